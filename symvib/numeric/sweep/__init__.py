"""Parameter sweeps: many scenes of one curve through the driver's engine at once.

A sweep takes a base :class:`~symvib.numeric.scene.Scene` and varies some of its
fields, named with the scene file's own keys (``qdot``, ``q``, ``mu``,
``alpha0``, ``restitution``, ``g``, ``m``, ``left``, ``right``, ``t_max``,
``max_events``, a curve parameter such as ``p``, or the dotted form
``initial.qdot``, ``parameters.p``), over

* a grid: ``qdot=3:12:200`` (``start:stop:count``, ends included) or a list
  ``k=0.6,0.8,1``; the first axis varies slowest (C order), or
* random samples: ``random=N`` with ranges ``mu=0.01:0.2``, uniform, drawn
  from ``numpy.random.default_rng([seed, chunk])`` so a chunk's rows never
  depend on which process draws them.

Every scene runs the same compiled loop as :func:`symvib.numeric.driver.simulate`,
so a sweep's event sequences are the single-scene driver's (a unilateral scene's row that
lifts off is followed on as ``simulate`` follows it: :mod:`~symvib.numeric.sweep.flights`).  Per scene it keeps
the columns :data:`symvib.numeric.layout.SUMMARY_COLUMNS` (status, event counts,
final time and position, friction work, impact loss, energies) and, with
``log_events=L``, the first ``L`` events; with ``sensitivities=("mu", "k")`` the final
state's derivatives (a slower path: each scene run again by the driver).  Given ``out=DIR`` the sweep is
written to a folder of chunk files and resumed from it; given ``scheduler``
(a ``dask.distributed`` address or ``Client``, extra ``symvib[dask]``), the
chunks run on that cluster.  The command line ``symvib sweep`` is
:func:`symvib.cli.sweep_main`.

The modules, one concept each:

* :mod:`~symvib.numeric.sweep.limits` - bounds, defaults and :class:`SweepError`;
* :mod:`~symvib.numeric.sweep.axes` - the fields a sweep can vary, ``--vary`` values;
* :mod:`~symvib.numeric.sweep.spec` - the definition (:func:`make_spec`, :class:`SweepSpec`);
* :mod:`~symvib.numeric.sweep.rows` - a chunk's scene rows, checked by the scene's own checks;
* :mod:`~symvib.numeric.sweep.labels` - readable names, units (SI), LaTeX symbols of the columns;
* :mod:`~symvib.numeric.sweep.flights` - the rows of unilateral scenes followed past their lift-off
  (physics.md, "Flight and landing"), and their columns ``flights``, ``landings``, ``landing_loss``;
* :mod:`~symvib.numeric.sweep.sensitivity_columns` - the opt-in columns of the final state's exact
  derivatives (``sensitivities=("mu", "k")``), computed per scene by the driver;
* :mod:`~symvib.numeric.sweep.schema` - the columns' names and kinds, the layout :data:`FORMAT`,
  :func:`sweep_id`, the check of a chunk's rows: what the result, the stores and the labelled data share;
* :mod:`~symvib.numeric.sweep.frames` - the columns as an xarray Dataset or a pandas DataFrame;
* :mod:`~symvib.numeric.sweep.result` - :class:`SweepResult` (``to_xarray``, ``to_dataframe``);
* :mod:`~symvib.numeric.sweep.zarrstore` - the chunks in one Zarr store (``storage="zarr"``);
* :mod:`~symvib.numeric.sweep.store` - folder, manifest, chunk files, :func:`load_sweep`;
* :mod:`~symvib.numeric.sweep.labelled` - :func:`open_sweep` (a folder as a lazy Dataset);
* :mod:`~symvib.numeric.sweep.lock` - the one writer of a folder (:class:`WriterLock`);
* :mod:`~symvib.numeric.sweep.progress` - the progress bar;
* :mod:`~symvib.numeric.sweep.runner` - :func:`sweep`, :func:`run_chunk` (locally or on Dask).

The bounds are read from :mod:`symvib.numeric.sweep.limits` when they are
checked: assign them there to change one.

Examples
--------
>>> from symvib.numeric.scene import scene_from_dict
>>> base = scene_from_dict({"curve": {"shape": "parabola"}, "parameters": {"p": 1},
...     "physics": {"g": 9.81, "m": 0.2, "mu": 0.05, "restitution": 0.8},
...     "limiters": {"left": "-pi/6", "right": "pi/4"}, "initial": {"q": 0, "qdot": 7}})
>>> res = sweep(base, {"qdot": "3:12:4", "mu": [0.05, 0.1]}, backend="python")
>>> res.count, res.grid("impacts").shape
(8, (4, 2))
>>> set(res.status_names())
{'arrested'}
"""
from __future__ import annotations

from symvib.numeric.sweep.labelled import open_sweep
from symvib.numeric.sweep.limits import (
                                         DEFAULT_CHUNK,
                                         DEFAULT_NODES,
                                         MAX_CHUNK_BYTES,
                                         MAX_CHUNKS,
                                         MAX_EVENT_LOG_BYTES,
                                         MAX_LIST_VALUES,
                                         MAX_LOG_EVENTS,
                                         MAX_MANIFEST_BYTES,
                                         MAX_SCENES,
                                         NODES_RANGE,
                                         SweepError,
)
from symvib.numeric.sweep.lock import LOCK_GRACE, WriterLock
from symvib.numeric.sweep.progress import Progress
from symvib.numeric.sweep.result import SweepResult
from symvib.numeric.sweep.runner import run_chunk, sweep
from symvib.numeric.sweep.schema import FORMAT, sweep_id
from symvib.numeric.sweep.spec import SweepSpec, make_spec
from symvib.numeric.sweep.store import STORAGES, load_sweep

__all__ = ["SweepSpec", "SweepResult", "SweepError", "WriterLock", "Progress", "make_spec", "sweep", "load_sweep",
           "open_sweep", "STORAGES",
           "run_chunk", "sweep_id", "FORMAT", "DEFAULT_CHUNK", "DEFAULT_NODES", "MAX_SCENES", "MAX_CHUNKS",
           "MAX_LIST_VALUES", "MAX_LOG_EVENTS", "MAX_CHUNK_BYTES", "MAX_EVENT_LOG_BYTES", "MAX_MANIFEST_BYTES",
           "NODES_RANGE", "LOCK_GRACE"]
