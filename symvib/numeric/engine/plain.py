"""The plain-Python engine: the engine's own functions, with a few primitives made fast in Python.

The engine (:mod:`~symvib.numeric.engine.laws`, ``roots``, ``scan``, ``timing``,
``loop``) is written once, for numba, where indexing a NumPy array costs
nothing; run as plain Python, each ``a[i, j]`` costs about 100 ns.  Without numba
the engine's functions run as they are, rebound (:mod:`symvib.numeric.engine.rebind`, as
the compiled binding rebinds them for numba) to globals in which these primitives replace
their loop versions:

* :func:`scratch`: scratch rows as Python lists (indexing a list is several
  times faster than indexing an array);
* :func:`cumulate`: the cumulative Gauss-Legendre integral at every node, a
  matrix-vector product in NumPy instead of ``n^2`` indexed multiplications;
* :func:`grown`: a full log copied into a larger one by NumPy, not element by element;
* ``clock``: ``time.monotonic``, the wall clock a run's deadline is read on (the compiled
  engine's :func:`symvib.numeric.engine.loop.clock` has none);
* :func:`turn_rate`: 0 where a kernel overflows, as the compiled version gives 0 where it is
  not finite (Python's ``math`` raises ``OverflowError`` where compiled code returns ``inf``: a
  curve whose kernels overflow far from the start, ``exp(x^2/b^2)`` in a Gaussian's, would stop a
  plain run at its set-up that the compiled engine runs);

and :func:`plain_rules` gives the rules' nodes and weights as lists.  Each
computes what its loop version computes (``tests/test_plain.py``); the
cumulative sums only in another order, which changes the last bits.

Examples
--------
>>> cumulate(np.eye(2), [1.0, 2.0, 3.0], 1, 2, [0.0] * 3, 1)
[0.0, 2.0, 3.0]
>>> scratch(2, 3)
[[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]
"""
from __future__ import annotations

import math
import time
from functools import cache

import numpy as np

from symvib.numeric.engine.rebind import ENGINE_MODULES, rebound_functions
from symvib.numeric.engine.state import Rules

__all__ = ["scratch", "cumulate", "grown", "turn_rate", "plain_rules", "plain_entries", "plain_functions", "PRIMITIVES"]


def scratch(rows, n):
    """``rows`` scratch rows of ``n`` floats, as lists (:func:`symvib.numeric.engine.scan.scratch`)."""
    return [[0.0] * n for _ in range(rows)]


def cumulate(St, v, vo, n, acc, ao):
    """``acc[ao + j] = sum_i St[i, j] v[vo + i]`` for ``j < n``, by NumPy, into the list ``acc``
    (:func:`symvib.numeric.engine.timing.cumulate`); returns ``acc``."""
    acc[ao:ao + n] = np.dot(v[vo:vo + n], St).tolist()
    return acc


def grown(a, n, rows):
    """``a`` with its first ``n`` rows copied into ``rows`` zeroed rows (:func:`symvib.numeric.engine.timing.grown`)."""
    new = np.zeros((rows, a.shape[1]))
    new[:n] = a[:n]
    return new


def turn_rate(x, K, cp):
    """``|alpha'(x)| = |kappa h|`` (:func:`symvib.numeric.engine.scan.turn_rate`), 0 where it is not finite
    or a kernel overflows."""
    try:
        r = abs(K.kappa(x, *cp) * K.h(x, *cp))
    except (OverflowError, ZeroDivisionError, ValueError):
        return 0.0
    return r if math.isfinite(r) else 0.0


#: The primitives the plain-Python engine takes instead of the engine's loop versions.
PRIMITIVES = {"scratch": scratch, "cumulate": cumulate, "grown": grown, "clock": time.monotonic,
              "turn_rate": turn_rate}


def plain_rules(R: Rules) -> Rules:
    """The rules with their nodes, weights and error-estimate rows as lists (the integration matrices
    stay arrays, for :func:`cumulate`)."""
    return R._replace(Xw=R.Xw.tolist(), Ww=R.Ww.tolist(), Xp=R.Xp.tolist(), Wp=R.Wp.tolist(), Tw=R.Tw.tolist(),
                      Tp=R.Tp.tolist())


@cache
def _engine() -> dict:
    """The engine's functions with the plain primitives (built once;
    :func:`symvib.numeric.engine.rebind.rebound_functions`)."""
    return rebound_functions(ENGINE_MODULES, lambda name: True, names=PRIMITIVES)


def plain_functions() -> dict:
    """The plain engine's functions by name (as :func:`plain_entries` runs them), with the constants
    its callers need (``CRIT_STEP``, ``MAX_PANELS``): for the dense output, which integrates on
    the panels the engine's ``quad`` takes."""
    from symvib.numeric.engine.scan import CRIT_STEP
    from symvib.numeric.engine.timing import MAX_PANELS

    return {**_engine(), "scratch": scratch, "CRIT_STEP": CRIT_STEP, "MAX_PANELS": MAX_PANELS}


def plain_entries(K) -> tuple:
    """The entry points ``(simulate, samples, sweep)`` of :class:`symvib.numeric.engine.bind.Engine`
    bound to the kernels ``K``, taking the rules ``R`` as the compiled engine does."""
    fns = _engine()
    simulate_scene, sample_scene, sweep_scenes = fns["simulate_scene"], fns["sample_scene"], fns["sweep_scenes"]

    def simulate(cp, row, R, keep):
        return simulate_scene(K, cp, row, plain_rules(R), keep)

    def samples(cp, row, R, ivs, ni, pieces):
        return sample_scene(K, cp, row, plain_rules(R), ivs, ni, pieces)

    def sweep(rows, cp_rows, R, max_log):
        return sweep_scenes(K, rows, cp_rows, plain_rules(R), max_log)

    return simulate, samples, sweep
