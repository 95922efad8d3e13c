"""The benchmark's jobs shared out over worker processes (``--workers``).

The random scenes' references and sequence counts and the stability runs are
independent jobs: :func:`map_workers` runs them in this process or in a pool of
workers that may start the symbolic derivation's budgeted child processes.  The
timings of the work-precision diagram never run in a worker.

Examples
--------
>>> map_workers(abs, [-1, 2, -3], workers=1)
[1, 2, 3]
"""
from __future__ import annotations

__all__ = ["map_workers"]


def map_workers(fn, items, workers: int) -> list:
    """``[fn(x) for x in items]``, over ``workers`` processes when more than one.

    The workers are not daemonic (:func:`symvib.symbolic.budget.worker_pool`), so the
    symbolic derivation may start its budgeted child processes there.

    Parameters
    ----------
    fn : callable
        A module-level function (it is pickled to the workers).
    items : iterable
        Its arguments, one call each.
    workers : int
        Processes; 1 or fewer runs every call here.

    Returns
    -------
    list
        The results, in the order of ``items``.
    """
    if workers <= 1:
        return [fn(x) for x in items]
    from symvib.symbolic.budget import worker_pool

    with worker_pool(workers) as ex:
        return list(ex.map(fn, items, chunksize=1))
