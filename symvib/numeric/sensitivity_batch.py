"""The quadratures of exact sensitivities, for every interval of a run at once (physics.md, "Sensitivities" 2, 5).

Given the tangents at both ends of each motion interval, its time derivative (item 5) is an
integral in ``theta`` whose integrand needs ``G``, ``f(q) - f(q_c)`` and ``Integral dF_s'/dp``
from the nearer end ``q_c``: none of it depends on another interval.  So the Gauss-Legendre
levels of :mod:`symvib.numeric.sensitivity` (``NODES`` nodes a panel, doubled until two levels
agree) are evaluated here for all intervals in one NumPy pass (each kernel called once per
branch): the kernels take arrays, the nodes of a level are the same ``u`` for every interval, and
only the intervals that have not converged go on to the next level.  Each interval gets the same levels, nodes and
arithmetic as one at a time (:meth:`symvib.numeric.sensitivity_interval.Interval.dT`, kept as the
reference), so the two agree to rounding.

The same holds for the integral of ``dF_s'/dp`` over a whole interval (item 2, the ``dG/dp`` of
its end): :func:`end_integrals` refines the piece counts interval by interval, in one pass.

Examples
--------
>>> import numpy as np
>>> x = np.array([0.25, 1.0])
>>> vals = cumulative(lambda q: 3 * q ** 2, np.array([0.0, 1.0]), np.array([1.0, -1.0]), x)
>>> np.round(vals, 12).tolist()                 # Integral_0^{x} 3q^2 and Integral_1^{1 - x} 3q^2
[[0.015625, 1.0], [-0.578125, -1.0]]
"""
from __future__ import annotations

import math
from functools import cache

import numpy as np

__all__ = ["NODES", "RTOL", "ACCEPT", "MAX_PANELS", "FIRST_PANELS", "INNER_NODES", "NEAR_END",
           "DIFFERENCE_RTOL", "EPS", "switched", "INTEGRAL_RTOL", "gauss", "theta_level",
           "cumulative", "end_integrals", "time_derivatives"]

#: Gauss-Legendre nodes per panel of the time derivative's integral in ``theta``.
NODES = 20
#: Agreement of two refinement levels (relative to the integral of the integrand's magnitude) that ends
#: the refinement of a time derivative: far below what the derivatives of event times computed to
#: 1e-12 can mean, and above the rounding of the integrand next to a turning point.
RTOL = 1e-10
#: The largest such difference a time derivative is kept with when no level reaches ``RTOL``.
ACCEPT = 1e-8
#: Most panels a time derivative may take (then its entries are NaN and the reason says why).
MAX_PANELS = 256
#: Panels of a time derivative's first level (then 2, 4, ...): on the paper's scenes four intervals in
#: five reach ``RTOL`` between one panel and two, and the others cost one panel more than from two.
FIRST_PANELS = 1
#: Nodes of the fixed rule that integrates ``F_s'``, ``F_s''`` and ``df/dmu`` between neighbouring nodes.
INNER_NODES = 8
#: Where ``f(q) - f(q_c)`` (item 5 of physics.md's "Sensitivities") is that difference of ``F_s'`` itself
#: instead of the integral of ``F_s''`` from the nearer end ``q_c``: from the first node at least
#: ``NEAR_END`` of the interval's length from ``q_c`` whose difference is at least ``1 / DIFFERENCE_RTOL``
#: times its rounding (``eps (|f(q)| + |f(q_c)|)``), and at every node beyond it.  Closer to the end,
#: where ``G`` and ``W`` vanish together at a turning point and the integrand's ``W / w^(3/2)`` magnifies
#: an absolute error, and on an interval too short for the difference to rise above its rounding, the
#: Gauss rule between neighbouring nodes keeps the relative accuracy.
NEAR_END = 0.05
DIFFERENCE_RTOL = 1e-12
#: Rounding unit of a double.
EPS = float(np.finfo(float).eps)
#: Agreement of two piece counts that ends the integral of ``df/dmu`` over a whole interval.
INTEGRAL_RTOL = 1e-14
#: Finest level (panels) of :func:`time_derivatives` evaluated for many intervals at once.
BATCH_PANELS = 16
#: Fewest pieces of :func:`end_integrals`' first level.
FIRST_PIECES = 8


def switched(x, f, f_c):
    """Which of a half's nodes (offsets ``x`` from the anchor, ascending along the last axis) take
    ``f(q) - f(q_c)`` as that difference (``f``: ``F_s'`` at them, ``f_c``: at the anchor): the first
    that :data:`NEAR_END` and :data:`DIFFERENCE_RTOL` allow and all after it.

    >>> switched(np.array([0.01, 0.1, 0.2]), np.array([1.0, 1.1, 1.0 + 1e-16]), 1.0).tolist()
    [False, True, True]
    """
    f_c = np.asarray(f_c)[..., None] if np.ndim(f_c) else f_c
    ok = (x >= NEAR_END) & (np.abs(f - f_c) * DIFFERENCE_RTOL >= EPS * (np.abs(f) + np.abs(f_c)))
    return np.logical_or.accumulate(ok, axis=-1)


@cache
def gauss(n):
    """Gauss-Legendre nodes and weights on ``[-1, 1]`` (computed once per ``n``, read-only)."""
    x, w = np.polynomial.legendre.leggauss(n)
    x.setflags(write=False)
    w.setflags(write=False)
    return x, w


@cache
def theta_level(panels):
    """The nodes ``u``, ``1 - u`` (each to its last bit) and weights of ``panels`` Gauss panels in ``theta``
    on ``[0, pi]``, ``u = (1 - cos theta) / 2`` (the weights carry ``du/dtheta``)."""
    x, wts = gauss(NODES)
    edges = np.linspace(0.0, math.pi, panels + 1)
    a, b = edges[:-1], edges[1:]
    theta = (((a + b) / 2)[:, None] + ((b - a) / 2)[:, None] * x[None, :]).ravel()
    weights = (((b - a) / 2)[:, None] * wts[None, :]).ravel() * np.sin(theta) / 2
    u, d = np.sin(theta / 2) ** 2, np.cos(theta / 2) ** 2
    start = np.flatnonzero(u <= 0.5)
    end = np.flatnonzero(u > 0.5)
    end = end[np.argsort(d[end], kind="stable")]
    for v in (u, d, weights, start, end):
        v.setflags(write=False)
    return u, d, weights, start, end


def _pieces(x_sorted):
    """Middles and half-widths of the pieces between ``0`` and the ascending offsets ``x_sorted``."""
    ends = np.concatenate(([0.0], x_sorted))
    a, b = ends[:-1], ends[1:]
    return (a + b) / 2, (b - a) / 2


def cumulative(fns, anchor, D, x_sorted, magnitude=False):
    """``Integral_{anchor}^{anchor + D x} fn(q) dq`` for each interval (``anchor``, ``D``: shape (M,)) at the
    offsets ``x_sorted`` (ascending, from 0), for every ``fn`` of ``fns`` at the same nodes: a fixed
    Gauss rule between neighbours, summed (in the offset, whose differences keep their relative
    accuracy next to the anchor).

    Returns one array of shape ``(M, len(x_sorted)[, columns])`` per function (one alone for a single
    callable), and with ``magnitude`` the integrals of ``|fn|`` too.
    """
    single = callable(fns)
    fns = (fns,) if single else tuple(fns)
    nodes, half = _nodes(anchor, D, x_sorted)
    flat = nodes.ravel()
    out = []
    for fn in fns:
        vals = np.asarray(fn(flat))
        for v in ((vals, np.abs(vals)) if magnitude else (vals,)):
            out.append(_summed(v.reshape(nodes.shape + v.shape[1:]), D, half))
    return out[0] if single and not magnitude else out


def _nodes(anchor, D, x_sorted):
    """The inner Gauss nodes of :func:`cumulative` (shape (M, pieces, INNER_NODES)) and the pieces' half-widths."""
    x, _ = gauss(INNER_NODES)
    mid, half = _pieces(x_sorted)
    return anchor[:, None, None] + D[:, None, None] * (mid[:, None] + half[:, None] * x[None, :])[None], half


def _summed(v, D, half):
    """The cumulative sums of :func:`cumulative` from the values ``v`` at its nodes (shape (M, pieces, nodes[,
    columns]))."""
    _, w = gauss(INNER_NODES)
    if v.ndim == 3:              # (one column: the nodes are the last axis already)
        return D[:, None] * np.cumsum(half[None, :] * (v @ w), axis=1)
    sums = np.moveaxis(v, 2, -1) @ w
    shape = (1, -1) + (1,) * (sums.ndim - 2)
    return D.reshape((-1,) + (1,) * (sums.ndim - 1)) * np.cumsum(half.reshape(shape) * sums, axis=1)


def end_integrals(c, s, anchor, D, max_pieces):
    """``Integral_{anchor}^{anchor + D} dF_s'/dp dq`` of each interval (shape (M, P)): :func:`cumulative`
    over 8, 16, ... equal pieces until two agree to ``INTEGRAL_RTOL`` of the integral of ``|dF_s'/dp|``,
    column by column, each interval to its own count (the last count tried where none agree).  Without
    curve parameters only ``mu``'s column is integrated (the others are 0).  ``c.quadratures``, where
    set, evaluates the same levels compiled (:mod:`symvib.numeric.sensitivity_compiled`)."""
    if getattr(c, "quadratures", None) is not None:
        return c.quadratures.end_integrals(c, s, anchor, D, max_pieces)
    factors = c.df_dp_factors(s)
    fn = factors[0] if factors else (lambda v: c.df_dp(s, v))
    M = len(anchor)
    result, previous = None, None
    active = np.arange(M)
    pieces = FIRST_PIECES
    while pieces <= max_pieces and len(active):
        x = np.arange(1, pieces + 1) / pieces
        current, magnitude = (v[:, -1] for v in cumulative(fn, anchor[active], D[active], x, magnitude=True))
        magnitude = np.abs(magnitude)
        if result is None:
            result = np.empty((M,) + current.shape[1:])
        if previous is not None:
            agree = np.all((np.abs(current - previous) <= INTEGRAL_RTOL * np.maximum(magnitude, 1e-300))
                           .reshape(len(active), -1), axis=1)
            result[active[agree]] = current[agree]
            active, previous = active[~agree], current[~agree]
        else:
            previous = current
        pieces *= 2
    if len(active):
        result[active] = previous
    return result[:, None] * factors[1] if factors else result


def time_derivatives(c, ends):
    """Derivatives of the durations of intervals (shape (M, P), the intervals in time order, on either
    branch); a row is NaN where the refinement fails (a non-finite level, or no two levels within
    ``ACCEPT``), and so is every row after the first that fails past ``BATCH_PANELS`` (not computed:
    the derivatives end at the first failure).

    ``ends`` holds arrays over the intervals: the branch ``s`` (+-1), ``q_a``, ``q_e``, ``G_a``, ``G_e``,
    ``f_a``, ``f_e`` (M,)
    and the tangents ``Dq_a``, ``Dq_e``, ``DG_a``, ``DG_e`` (M, P); ``c`` is the
    :class:`~symvib.numeric.sensitivity_curve.CurveFunctions` of the run.  The levels up to
    ``BATCH_PANELS`` panels are evaluated for all unconverged intervals at once, the finer ones
    interval by interval (few need them, and none after one that fails).  ``c.quadratures``, where set,
    evaluates the same levels compiled (:mod:`symvib.numeric.sensitivity_compiled`).
    """
    if getattr(c, "quadratures", None) is not None:
        return c.quadratures.time_derivatives(c, ends)
    M, P = ends["Dq_a"].shape
    out = np.full((M, P), np.nan)
    if M == 0:
        return out
    state = _Refinement(M, P, _level(c, ends, np.arange(M), FIRST_PANELS)[0])
    active, panels = np.arange(M), FIRST_PANELS
    while panels < min(BATCH_PANELS, MAX_PANELS) and len(active):
        panels *= 2
        active = state.step(out, active, *_level(c, ends, active, panels))
    for r in active:                     # (in time order)
        rows, level = np.array([r]), panels
        while level < MAX_PANELS and len(rows):
            level *= 2
            rows = state.step(out, rows, *_level(c, ends, rows, level))
        if len(rows) and state.best_gap[r] <= ACCEPT:
            out[r] = state.best[r]
        if not np.all(np.isfinite(out[r])):
            break
    return out


class _Refinement:
    """The levels of :func:`time_derivatives` so far: each interval's last level, and its best pair
    of consecutive levels (the earlier of the two, and their relative difference)."""

    def __init__(self, M, P, first):
        self.previous = first
        self.best, self.best_gap = np.full((M, P), np.nan), np.full(M, math.inf)

    def step(self, out, rows, current, magnitude):
        """Take a new level of the intervals ``rows``: the converged ones go to ``out``; the ones still
        refining are returned (a non-finite level ends an interval's refinement: it fails)."""
        previous = self.previous[rows]
        finite = np.all(np.isfinite(current), axis=1)
        gap = np.max(np.abs(current - previous) / np.maximum(magnitude, 1e-300), axis=1)
        converged = finite & (gap <= RTOL)
        out[rows[converged]] = current[converged]
        better = finite & ~converged & (gap < self.best_gap[rows])
        self.best[rows[better]], self.best_gap[rows[better]] = previous[better], gap[better]
        self.best_gap[rows[~finite]] = math.inf
        self.previous[rows] = current
        return rows[finite & ~converged]


def _level(c, ends, rows, panels):
    """The integral of the time derivative's integrand and of its magnitude on ``panels`` panels, for the
    intervals ``rows`` of ``ends`` (shape (len(rows), P) each)."""
    u, d, weights, start, end = theta_level(panels)
    e = {k: v[rows] for k, v in ends.items()}
    q_a, q_e = e["q_a"], e["q_e"]
    delta = q_e - q_a
    Dq_a, Dq_e = e["Dq_a"], e["Dq_e"]
    n, (M, P) = len(u), Dq_a.shape
    q = np.where(u <= 0.5, q_a[:, None] + delta[:, None] * u, q_e[:, None] - delta[:, None] * d)
    Dq = (1 - u)[None, :, None] * Dq_a[:, None, :] + u[None, :, None] * Dq_e[:, None, :]
    G = np.empty((M, n))
    DG = np.empty((M, n, P))
    s = e["s"]
    fns = [c.f, c.df]
    factors = c.df_dp_factors(1) if c.f_depends else None     # (its columns are the same on both branches)
    if c.f_depends:
        fns.append(c.df_dmu if factors else c.df_dp)
    halves = [(from_start, order) for from_start, order in ((True, start), (False, end)) if len(order)]
    inner = []
    for from_start, order in halves:
        x = u[order] if from_start else d[order]
        inner.append(_nodes(q_a if from_start else q_e, delta if from_start else -delta, x))
    values = [_on_branches(fn, s, [nodes for nodes, _ in inner]) for fn in fns]
    at_nodes = _on_branches(c.f, s, [q[:, order, None] for _, order in halves])
    for h, ((from_start, order), (_, half)) in enumerate(zip(halves, inner)):
        x = u[order] if from_start else d[order]
        q_c, D, G_c, DG_c, f_c = ((q_a, delta, e["G_a"], e["DG_a"], e["f_a"]) if from_start
                                  else (q_e, -delta, e["G_e"], e["DG_e"], e["f_e"]))
        int_f, int_df, *int_dp = (_summed(v[h], D, half) for v in values)
        f_q = at_nodes[h][:, :, 0]
        int_df = np.where(switched(x, f_q, f_c), f_q - f_c[:, None], int_df)     # (f(q) - f(q_c): switched)
        G[:, order] = G_c[:, None] - 2 * c.g * int_f
        step = (x if from_start else -x)[None, :, None] * (Dq_e - Dq_a)[:, None, :]
        dg = DG_c[:, None, :] - 2 * c.g * (int_df[:, :, None] * Dq[:, order] + f_c[:, None, None] * step)
        if int_dp:
            dg -= 2 * c.g * (int_dp[0][:, :, None] * factors[1] if factors else int_dp[0])
        DG[:, order] = dg
    flat = q.ravel()
    alpha, dalpha = c.alpha(flat).reshape(M, n), c.dalpha(flat).reshape(M, n)
    E = np.exp(2 * s[:, None] * c.mu * alpha)
    W = (DG - G[:, :, None] * 2 * s[:, None, None] * (alpha[:, :, None] * c.Dmu + c.mu * dalpha[:, :, None] * Dq
                                      + c.mu * c.geometry_dp("alpha", flat).reshape(M, n, P))) / E[:, :, None]
    w = G / E
    length = np.abs(delta)
    sigma = np.where(delta > 0, 1.0, -1.0)
    h, dh = c.h(flat).reshape(M, n), c.dh(flat).reshape(M, n)
    root = np.sqrt(w)
    J = ((dh[:, :, None] * Dq * length[:, None, None] + (h * sigma[:, None])[:, :, None] * (Dq_e - Dq_a)[:, None, :]
          + c.geometry_dp("h", flat).reshape(M, n, P) * length[:, None, None]) / root[:, :, None]
         - 0.5 * (h * length[:, None])[:, :, None] * W / (w * root)[:, :, None])
    return np.einsum("n,mnp->mp", weights, J), np.einsum("n,mnp->mp", weights, np.abs(J))


def _on_branches(fn, s, parts):
    """``fn(sign, q)`` at the nodes ``parts`` (one array of shape (M, pieces, nodes) per half of the
    intervals), each interval's on its branch ``s`` (M,): one call per branch for all halves."""
    if np.all(s == s[0]):        # (one branch: no rows to pick)
        values = np.asarray(fn(int(s[0]), np.concatenate([p.ravel() for p in parts])))
        cuts = np.cumsum([p.size for p in parts])[:-1]
        return [v.reshape(p.shape + values.shape[1:]) for v, p in zip(np.split(values, cuts), parts)]
    out = [None] * len(parts)
    for sign in (1, -1):
        rows = np.flatnonzero(s == sign)
        if not len(rows):
            continue
        values = np.asarray(fn(sign, np.concatenate([p[rows].ravel() for p in parts])))
        cut = 0
        for h, p in enumerate(parts):
            size = len(rows) * p.shape[1] * p.shape[2]
            if out[h] is None:
                out[h] = np.empty(p.shape + values.shape[1:])
            out[h][rows] = values[cut:cut + size].reshape((len(rows),) + p.shape[1:] + values.shape[1:])
            cut += size
    return out
