"""CPU time per trajectory, and the first calls the timings leave out.

:func:`cpu_per_run` times a call by :func:`time.process_time` (one thread): the
cheapest of :data:`TIMING_BLOCKS` blocks of repeated calls, :data:`MIN_TIMING` CPU
seconds in all, so that load from other processes on a shared machine inflates it
less.  :func:`warm_up` makes symvib's driver compile (or load) each curve's code
before the timings and reports how long that first call took.

Examples
--------
>>> seconds, result = cpu_per_run(lambda: sum(range(100)), min_total=0.01)
>>> result, seconds < 0.01
(4950, True)
"""
from __future__ import annotations

import time

__all__ = ["MIN_TIMING", "TIMING_BLOCKS", "cpu_per_run", "warm_up"]

#: CPU seconds a timing is repeated for (at least one run), in TIMING_BLOCKS blocks.
MIN_TIMING = 0.25
TIMING_BLOCKS = 5


def cpu_per_run(fn, min_total: float = MIN_TIMING, blocks: int = TIMING_BLOCKS) -> tuple:
    """``(CPU seconds per call, last result)``.

    ``fn`` runs in ``blocks`` blocks of at least ``min_total / blocks`` CPU
    seconds each (one call at least); the cheapest block's mean is returned, so
    that load from other processes on a shared machine inflates it less.  A call
    longer than ``min_total`` runs once.
    """
    start = time.process_time()
    out = fn()
    first = time.process_time() - start
    if first >= min_total:
        return first, out
    best = first
    for _ in range(blocks):
        runs, total = 0, 0.0
        while runs == 0 or total < min_total / blocks:
            start = time.process_time()
            out = fn()
            total += time.process_time() - start
            runs += 1
        best = min(best, total / runs)
    return best, out


def warm_up(scenes, backend) -> dict:
    """Compile (or load) the driver for each curve once: the seconds of each curve's first call.

    Parameters
    ----------
    scenes : iterable of (str, symvib.numeric.scene.Scene)
        ``(label, scene)`` pairs; the first scene of each curve (``scene.shape.name``) runs.
    backend : str
        The driver's backend (:func:`symvib.checks.bench.settings.driver_backend`).

    Returns
    -------
    dict
        Curve name -> wall-clock seconds of its first call (compile or load included).
    """
    from symvib import simulate

    out = {}
    for _, scene in scenes:
        name = scene.shape.name
        if name not in out:
            start = time.perf_counter()
            simulate(scene, samples=False, backend=backend)
            out[name] = time.perf_counter() - start
    return out
