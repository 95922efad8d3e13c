"""A run's samples: the logged motion intervals cut into pieces and evaluated at Gauss nodes
(physics.md, "Time": the nodes of the time quadrature), computed on first use of ``Result.samples``.

:func:`simulate <symvib.numeric.driver.simulate>` keeps what the samples need (the interval
log) and hands :func:`lazy_samples` to the result; the samples are computed by the engine the
run took, or by the plain one where ``"auto"`` took the compiled engine and its samples entry
is not compiled yet (:func:`sample_engine`: a run never waits for a compiler).  A run's
samples are capped (:data:`SAMPLE_BUDGET`, :data:`MAX_SAMPLES`), and a run that would pass the
cap gets none and says why (:func:`sample_plan`).

Examples
--------
>>> sample_pieces(SAMPLES_PER_INTERVAL, 16), sample_plan(96, 16, True, 10)
(4, (4, None))
"""
from __future__ import annotations

import numpy as np

from symvib.numeric.backends import bound_engine, quiet_compiler, run_backend
from symvib.numeric.events import Samples
from symvib.numeric.quadrature import plain_nodes
from symvib.numeric.trusted import math_error

__all__ = ["SAMPLES_PER_INTERVAL", "MAX_SAMPLES_PER_INTERVAL", "SAMPLE_BUDGET", "MAX_SAMPLES", "sample_pieces",
           "sample_plan", "sample_engine", "lazy_samples", "stretch_samples", "no_samples", "samples_of",
           "dense_output", "column"]

#: Samples per motion interval (at least) by default: smooth curves of F_N and P_mu.
SAMPLES_PER_INTERVAL = 96
#: Most samples per motion interval a run may ask for (memory: 80 bytes per sample).
MAX_SAMPLES_PER_INTERVAL = 100_000
#: Samples a run keeps by default at most at :data:`SAMPLES_PER_INTERVAL` (above, one piece per
#: interval): 1e6 samples are about 150 MB and a second to compute.
SAMPLE_BUDGET = 1_000_000
#: Most samples a run computes (about 1.5 GB); a run that would pass it gets no samples and says why.
MAX_SAMPLES = 10_000_000


def dense_output(mod, cp, ivs, R, result):
    """The dense output of ``result`` (:class:`symvib.numeric.dense.DenseOutput`) from its interval log."""
    from symvib.numeric.dense import DenseOutput

    return DenseOutput(result, mod, cp, ivs, R)


def sample_plan(spi: int, nodes: int, default: bool, n_intervals: int):
    """``(pieces, None)``: the pieces each of ``n_intervals`` logged intervals is sampled in (one where
    the default ``spi`` would pass :data:`SAMPLE_BUDGET`), or ``(None, message)`` where the samples
    would pass :data:`MAX_SAMPLES`."""
    pieces = sample_pieces(spi, nodes)
    if default and n_intervals * spi > SAMPLE_BUDGET:
        pieces = 1
    wanted = n_intervals * pieces * (2 * plain_nodes(nodes) + 1)
    if wanted > MAX_SAMPLES:
        return None, (f"samples: {n_intervals:,} intervals at samples_per_interval {spi} would give about "
                      f"{wanted:,} samples, more than {MAX_SAMPLES:,}; ask for fewer (samples_per_interval) or a "
                      "shorter run (run.max_events)")
    return pieces, None


def stretch_samples(engine_of, cp, R, scene, mod, row, ivs, ni, pieces):
    """The samples of one sliding stretch of a run with flights (``row`` its start): as
    :func:`lazy_samples` (:class:`symvib.numeric.flight_samples.Sampling`)."""
    return lazy_samples(engine_of, cp, row, ivs, ni, R, scene, mod, pieces)


def no_samples(message):
    """``(None, message)``: a run whose samples would be too many (:data:`MAX_SAMPLES`)."""
    return None, message


def sample_engine(mod, requested: str, backend: str):
    """The engine that computes the samples of a run on ``backend`` (asked for as ``requested``).

    The run's own, except where ``"auto"`` took the compiled engine and its samples
    entry is not compiled yet: the plain engine then computes the samples from the
    run's interval log (the same quadrature; a run never waits for a compiler).
    """
    if backend == "numba" and requested == "auto":
        backend = run_backend(mod, requested, "sample_bound")
    return bound_engine(mod, backend)[1]


def lazy_samples(engine_of, cp, row, ivs, ni, R, scene, mod, pieces):
    """``(samples, None)``, or ``(None, message)`` where the plain-Python engine overflowed;
    ``engine_of()`` gives the engine (:func:`sample_engine`)."""
    eng = engine_of()
    try:
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"), quiet_compiler(mod, "numba"):
            return samples_of(eng, cp, row, ivs, ni, R, scene, mod, pieces), None
    except (ArithmeticError, ValueError) as exc:
        if not math_error(exc):
            raise
        return None, f"{type(exc).__name__}: {exc}"


def sample_pieces(samples_per_interval: int, nodes: int) -> int:
    """Pieces each logged interval is cut into so that a motion interval has at least
    ``samples_per_interval`` samples (a piece gives at least two plain panels' nodes and its end).

    Examples
    --------
    >>> sample_pieces(SAMPLES_PER_INTERVAL, 16), sample_pieces(1, 16), sample_pieces(1000, 16)   # (16: driver.NODES)
    (4, 1, 40)
    """
    per_piece = 2 * plain_nodes(nodes) + 1
    return max(1, -(-int(samples_per_interval) // per_piece))


def samples_of(eng, cp, row, ivs, ni, R, scene, mod, pieces: int = 1) -> Samples:
    """The samples of the logged intervals (:func:`symvib.numeric.engine.timing.samples`), in time
    order, with the derived columns of :class:`Samples`.

    Linear in the number of intervals: one stable sort by (interval, time).
    """
    from symvib.numeric.engine.timing import SampleColumn as C

    nodes, index = eng.samples(cp, row, R, np.ascontiguousarray(ivs), ni, pieces)
    if not len(index):
        return Samples.empty()
    order = np.lexsort((nodes[:, C.t], index))  # stable: ties keep the engine's order
    nodes, index = nodes[order], index[order]
    t, q, w, N = nodes[:, C.t], nodes[:, C.q], nodes[:, C.w], nodes[:, C.N]
    sigma = nodes[:, C.sigma]
    m, mu = scene.m, scene.mu
    speed = np.sqrt(np.maximum(w, 0.0))
    v = sigma * speed
    z = column(mod.z(q, *cp), q)
    Ep = m * scene.g * z
    friction = mu * m * np.abs(N)  # |F_mu|
    return Samples(t=t, q=q, qdot=v / mod.h(q, *cp), F_N=m * N, P_mu=-friction * speed,
                   Ek=0.5 * m * w, Ep=Ep, E=0.5 * m * w + Ep, interval=index.astype(int),
                   branch=nodes[:, C.branch].astype(int), x=column(mod.x(q, *cp), q), z=z,
                   s=nodes[:, C.s].copy(), path=nodes[:, C.path].copy(), v=v, F_mu=-sigma * friction,
                   W_mu=m * nodes[:, C.W], W_impacts=m * nodes[:, C.W_impacts])


def column(values, like) -> np.ndarray:
    """A kernel's values as a float array of ``like``'s shape (a constant kernel returns a scalar)."""
    return np.array(np.broadcast_to(values, like.shape), dtype=float)
