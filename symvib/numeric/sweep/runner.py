"""Running a sweep: its chunks in this process or on a Dask cluster, resumed from a folder.

Every scene runs the same compiled loop as :func:`symvib.numeric.driver.simulate`
(:func:`symvib.numeric.driver.sweep_function`, parallel over scenes on the
numba backend), so a sweep's event sequences are the single-scene driver's.
:func:`run_chunk` computes one chunk from the definition alone (a pure
function: it is the Dask task); :func:`sweep` validates the definition, takes
the folder's lock, keeps the chunks already written and computes the missing
ones, in order here or ``DASK_INFLIGHT`` per worker on a cluster.

Examples
--------
>>> from symvib.numeric.scene import resolve_scene
>>> spec = make_spec(resolve_scene("paper-parabola"), {"qdot": "3:12:4"}, chunk=3)
>>> columns = run_chunk(spec.to_dict(), 1, backend="python")
>>> columns["row"].tolist(), columns["initial.qdot"].tolist(), columns["status"].dtype.name
([3], [12.0], 'int64')
"""
from __future__ import annotations

import math
import sys
import time

import numpy as np

from symvib.numeric.driver import sweep_function
from symvib.numeric.layout import Summary
from symvib.numeric.prepared import prepared_of
from symvib.numeric.scene import Scene, SceneError
from symvib.numeric.sweep import flights, limits, sensitivity_columns
from symvib.numeric.sweep.limits import SweepError
from symvib.numeric.sweep.lock import WriterLock
from symvib.numeric.sweep.progress import Progress
from symvib.numeric.sweep.result import INTEGER_COLUMNS, SweepResult, join_chunks
from symvib.numeric.sweep.spec import SweepSpec, make_spec
from symvib.numeric.sweep.store import check_out, check_storage, load_sweep, prepare, sweep_id, write_chunk

__all__ = ["sweep", "run_chunk", "DASK_INFLIGHT"]

#: Chunks in flight per Dask worker.
DASK_INFLIGHT = 2


def run_chunk(definition: dict, index: int, backend: str = "auto") -> dict:
    """Compute chunk ``index`` of the sweep ``definition`` (:meth:`SweepSpec.to_dict`).

    A pure function of its arguments (it runs on Dask workers): returns the
    chunk's columns as a dict of arrays (``row``, the varied fields, the
    :data:`symvib.numeric.layout.SUMMARY_COLUMNS`, the flight columns of a unilateral scene, whose
    rows that lift off fly on: :mod:`~symvib.numeric.sweep.flights`, the sensitivity columns and
    ``event_log`` when asked).
    """
    spec = SweepSpec.from_dict(definition)
    if isinstance(index, bool) or not isinstance(index, (int, np.integer)) or not 0 <= index < spec.chunks:
        raise SweepError("chunk", f"index must be an integer in [0, {spec.chunks}), got {index!r}")
    rows, values = spec.rows(int(index))
    scene_rows, param_rows = spec.scalars(values, rows)
    summary, logs = sweep_function(spec.scene, backend)(scene_rows, param_rows, spec.nodes, spec.log_events)
    out = {"row": rows}
    for axis, v in zip(spec.axes, values):
        out[axis.field] = np.asarray(v, dtype=float)
    for column in Summary:
        values_ = summary[:, column]
        out[column.name] = values_.astype(np.int64) if column.name in INTEGER_COLUMNS else values_
    log = logs[:, :spec.log_events] if spec.log_events else None
    if flights.unilateral(spec.scene):   # rows that lifted off fly on (physics.md, "Flight and landing")
        out.update(flights.follow_rows(spec, values, out, log, backend))
    if spec.sensitivities:
        out.update(sensitivity_columns.compute(spec, values, out["status"], backend))
    if log is not None:
        out["event_log"] = log
    return out



def _end_text(v: float) -> str:
    """A domain end as a scene file writes it (exact: the shortest repr of the double)."""
    return ("oo" if v > 0 else "-oo") if math.isinf(v) else repr(float(v))


def _refuse_singular_domain(scene: Scene, prepared=None) -> None:
    """Refuse a user curve with a singular point inside its declared domain.

    :func:`symvib.numeric.driver.simulate` runs such a scene on the regular interval
    around ``initial.q`` (:class:`~symvib.numeric.prepared.Prepared`, from the prepare
    step's record); a sweep runs one kernel module for all its rows, so it asks for
    that domain to be declared instead of integrating across the point.  A catalogue
    shape is regular on its domain.  Rows that vary the curve's parameters are not
    re-checked one by one; their energy budget is (``energy_budget_mismatch``).
    """
    prep = prepared_of(scene) if prepared is None else prepared
    if prep.domain.narrowed:
        lo, hi = _end_text(prep.domain.lo), _end_text(prep.domain.hi)
        raise SceneError("curve.domain", f"curve '{scene.shape.name}' has a singular point inside its domain; "
                                         f"a sweep needs a regular one: declare domain = [\"{lo}\", \"{hi}\"] "
                                         f"(the regular interval around initial.q) or narrower")


def sweep(scene: Scene, vary: dict, *, random: int | None = None, seed: int = 0, chunk: int = limits.DEFAULT_CHUNK,
          log_events: int = 0, nodes: int = limits.DEFAULT_NODES, out=None, overwrite: bool = False, scheduler=None,
          progress: bool = False, backend: str = "auto", storage: str = "npz", prepared=None,
          sensitivities=()) -> SweepResult:
    """Run ``scene`` for every combination (or random sample) of the ``vary`` fields.

    Parameters
    ----------
    scene : Scene
        Base scene.
    vary : dict
        Field key -> grid axis or random range (see :func:`~symvib.numeric.sweep.spec.make_spec`).
    random, seed, chunk, log_events, nodes
        See :func:`~symvib.numeric.sweep.spec.make_spec`.
    out : path, optional
        Folder for the manifest and chunk files; an existing sweep there is
        resumed (only missing chunks run; chunks that are truncated or carry
        another sweep's identity are computed again).  Without it the sweep
        stays in memory.  The folder is locked (:class:`WriterLock`) while the
        sweep writes it.
    overwrite : bool
        Replace a *different* sweep (or an unreadable manifest) found in ``out``
        instead of refusing.
    scheduler : str or dask.distributed.Client, optional
        Run the chunks on this Dask cluster (extra ``symvib[dask]``).
    progress : bool
        Draw a progress bar on stderr.
    backend : {"auto", "numba", "python"}
    storage : {"npz", "zarr"}
        How ``out`` stores the chunks: NumPy ``.npz`` files, or one Zarr store
        that ``xarray.open_zarr`` opens (extra ``symvib[xarray]``;
        :mod:`~symvib.numeric.sweep.zarrstore`).
    prepared : Prepared, optional
        The base scene's prepared curve (:func:`symvib.prepare.prepare`, which ``symvib.sweep``
        calls); default: what is on disk (:func:`~symvib.numeric.prepared.prepared_of`).
    sensitivities : sequence of str, optional
        Add the final state's derivatives with respect to these parameters
        (:mod:`~symvib.numeric.sweep.sensitivity_columns`): each scene run again by the
        single-scene driver and differentiated, a slower path (its cost per scene:
        ``benchmarks/bench_fit.py --sweep``).

    Returns
    -------
    SweepResult

    Raises
    ------
    SceneError
        A bad definition (naming the field or option); :class:`SweepError` for
        an unusable folder, a folder another sweep writes, or a chunk that
        cannot be written.
    """
    check_storage(storage)
    _refuse_singular_domain(scene, prepared)
    spec = make_spec(scene, vary, random=random, seed=seed, chunk=chunk, log_events=log_events, nodes=nodes,
                     sensitivities=sensitivities)
    definition = spec.to_dict()
    ident = sweep_id(definition)
    if out is None:
        return _run(spec, definition, ident, None, None, [], [], scheduler, progress, backend)
    out = check_out(out)
    lock = WriterLock(out).acquire()
    try:
        done, discarded = prepare(out, spec, ident, overwrite, storage)
        return _run(spec, definition, ident, out, lock, done, discarded, scheduler, progress, backend, storage)
    finally:
        lock.release()


def _say_slow_path(backend: str) -> None:
    """Before a sweep on the plain-Python engine computes: say so, and the remedy (one line, stderr)."""
    from symvib.numeric.backends import resolve_backend

    if resolve_backend(backend) == "python":
        why = "as asked" if backend == "python" else "numba is not installed"
        print(f"symvib sweep: note: the plain-Python engine runs this sweep ({why}); it is 50 to 200 times "
              "slower than the compiled one (benchmarks/bench_sweep.py): pip install numba (symvib's dependency) "
              "restores it",
              file=sys.stderr, flush=True)


def _run(spec, definition, ident, out, lock, done, discarded, scheduler, progress, backend,
         storage="npz") -> SweepResult:
    """Compute the chunks not in ``done``: into ``out`` (under ``lock``), or in memory."""
    finished = set(done)
    todo = [i for i in range(spec.chunks) if i not in finished]
    store: dict = {}
    if progress and todo:
        _say_slow_path(backend)
    bar = Progress(spec.count, enabled=progress,
                   initial=sum(len(spec.rows(i)[0]) for i in done) if done else 0)
    start = time.perf_counter()

    def take(index, columns):
        if out is not None:
            lock.verify()
            write_chunk(out, index, columns, ident, storage)
        else:
            store[index] = columns
        bar.update(len(columns["row"]))

    if scheduler is not None and todo:
        _run_dask(scheduler, definition, ident, todo, backend, take)
    else:
        for index in todo:
            take(index, run_chunk(definition, index, backend))
    bar.update(0, final=True)
    seconds = time.perf_counter() - start
    if out is not None:
        result = load_sweep(out)
        if sweep_id(result.spec.to_dict()) != ident:
            raise SweepError("out", f"{out} holds another sweep than the one just written")
        return SweepResult(result.spec, result.columns, tuple(todo), tuple(done), seconds, str(out),
                           tuple(discarded))
    return SweepResult(spec, join_chunks(spec, [store[i] for i in range(spec.chunks)]), tuple(todo), (), seconds)


def _run_dask(scheduler, definition, ident, todo, backend, take) -> None:
    try:
        from dask.distributed import Client, as_completed
    except ImportError:
        raise SceneError("scheduler", "running on a Dask cluster needs dask.distributed: "
                                      "pip install 'symvib[dask]'") from None
    client = scheduler if isinstance(scheduler, Client) else Client(scheduler)
    try:
        token = ident[:12]
        workers = max(1, len(client.scheduler_info().get("workers", {})))
        pending = list(todo)
        running = as_completed()

        def submit():
            index = pending.pop(0)
            running.add(client.submit(run_chunk, definition, index, backend, key=f"symvib-sweep-{token}-{index}",
                                      pure=False))

        for _ in range(min(len(pending), DASK_INFLIGHT * workers)):
            submit()
        for future in running:
            index = int(future.key.rsplit("-", 1)[1])
            take(index, future.result())
            future.release()
            if pending:
                submit()
    finally:
        if client is not scheduler:
            client.close()


