"""The reference files shipped with the package, in ``symvib/checks/data``.

The benchmarks and the accuracy test compare with references computed once and
shipped as package data (installed by pyproject's ``[tool.setuptools.package-data]``,
read with :mod:`importlib.resources`, so they are found in a wheel as in a checkout):

* ``time_reference.json``: the 30-digit time references of the paper scenes
  (:mod:`symvib.checks.bench.paper_references`);
* ``random_truth.json``: the event sequences of the benchmark's random scenes
  (:mod:`symvib.checks.bench.sequences`);
* ``accuracy_reference.json``: the random scenes of the accuracy test and their
  references (:mod:`symvib.checks.accuracy`).

Nothing writes here at run time: a reference missing from these files is computed
and cached in the output folder of the job that needs it.

Examples
--------
>>> all("events" in entry for entry in shipped("time_reference.json").values())
True
"""
from __future__ import annotations

import json
from importlib.resources import files

__all__ = ["DATA_PACKAGE", "DATA_FOLDER", "shipped"]

#: Package and folder of the shipped references (package data, read with importlib.resources).
DATA_PACKAGE = "symvib.checks"
DATA_FOLDER = "data"


def shipped(name: str) -> dict:
    """A reference file shipped with the package (``symvib/checks/data/NAME``), as a dict.

    Parameters
    ----------
    name : str
        The file's name in the data folder (``time_reference.json``, ``random_truth.json``,
        ``accuracy_reference.json``).

    Returns
    -------
    dict
        The file's JSON.

    Raises
    ------
    FileNotFoundError
        When the installed package lacks the file (the message names it).
    """
    resource = files(DATA_PACKAGE) / DATA_FOLDER / name
    try:
        text = resource.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise FileNotFoundError(f"{DATA_PACKAGE.replace('.', '/')}/{DATA_FOLDER}/{name}: shipped reference "
                                f"missing from the installed package (reinstall symvib)") from None
    return json.loads(text)
