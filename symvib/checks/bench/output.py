"""What the benchmarks write in their output folder: JSON caches and CSV tables.

Every file goes through :mod:`symvib.safeio` (the folder checked, the file replaced
whole).  A cache file (:func:`load_json`, :func:`store_json`) holds references
computed on demand, keyed by scene (:func:`symvib.checks.bench.scenes.scene_key`);
:func:`write_csv` writes a table of rows, floats to six digits.

Examples
--------
>>> import tempfile
>>> from pathlib import Path
>>> with tempfile.TemporaryDirectory() as d:
...     store_json(Path(d) / "cache.json", {"a": 1})
...     store_json(Path(d) / "cache.json", {"b": 2})
...     load_json(Path(d) / "cache.json"), load_json(Path(d) / "missing.json")
({'a': 1, 'b': 2}, {})
"""
from __future__ import annotations

import csv
import io
import json
from pathlib import Path

from symvib import safeio

__all__ = ["OUT_FOLDER", "CACHE_FOLDER", "load_json", "store_json", "write_csv"]

#: What the output folder is called in the messages of symvib.safeio.
OUT_FOLDER = "bench folder"
#: What a cache file's folder is called in those messages.
CACHE_FOLDER = "bench cache folder"


def load_json(path: Path | None) -> dict:
    """A cache file written by the benchmarks, or ``{}`` when there is none (or it is unreadable).

    Parameters
    ----------
    path : pathlib.Path or None
        The cache file; None reads nothing.

    Returns
    -------
    dict
        The file's JSON, or ``{}``.
    """
    if path is None:
        return {}
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}


def store_json(path: Path, entries: dict, **dump) -> None:
    """Merge ``entries`` into the JSON cache file ``path`` (created with its folder).

    Parameters
    ----------
    path : pathlib.Path
        The cache file.
    entries : dict
        Keys and values to add (a key already there is replaced).
    **dump
        Options of :func:`json.dumps` (``indent``); the keys are always sorted.
    """
    data = load_json(path)
    data.update(entries)
    safeio.write_file(path, json.dumps(data, sort_keys=True, **dump) + "\n", what=CACHE_FOLDER)


def write_csv(path: Path, rows) -> None:
    """Write ``rows`` (dicts with the same keys, the first row's give the columns) as a CSV table.

    Parameters
    ----------
    path : pathlib.Path
        The file, in the output folder.
    rows : list of dict
        The rows; floats are written to six significant digits.  No rows writes no file.
    """
    if not rows:
        return
    text = io.StringIO(newline="")
    w = csv.DictWriter(text, fieldnames=list(rows[0]))
    w.writeheader()
    for r in rows:
        w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})
    safeio.write_file(path, text.getvalue(), what=OUT_FOLDER)
