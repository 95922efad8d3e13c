"""Times and friction work of a motion interval, by Gauss-Legendre quadrature.

``t = Integral h dq / sqrt(w)`` (physics.md, "Time").  Each interval is split at
its midpoint and each half is anchored at its outer end, where ``G`` is known
exactly (the state, or 0 at a turning point).  ``G`` at the Gauss nodes is
rebuilt from the anchor by integrating ``G' = -2 g F_s'`` with a cumulative
Gauss-Legendre matrix, so it keeps full relative accuracy where it is small;
near a (real or virtual) root at distance ``delta`` behind the anchor the
variable ``r = sqrt(xi)``, ``xi`` the distance from that root, removes the
inverse square root, with panels graded geometrically from ``sqrt(delta)``.

Examples
--------
>>> PANEL_Q, ROOT_RATIO, WORK_ROWS
(1.0, 1.0, 10)
"""
from __future__ import annotations

import math
from math import sqrt

import numpy as np

from symvib.numeric.engine.laws import Fs, dFs, node
from symvib.numeric.engine.roots import ROOT_MAXITER, illinois_point, illinois_update
from symvib.numeric.engine.scan import scratch
from symvib.numeric.layout import IntervalColumn

__all__ = ["quad", "cumulate", "root_time", "samples", "arc_length", "grown", "PANEL_Q", "ROOT_RATIO",
           "WORK_ROWS", "SampleColumn"]

#: Widest quadrature panel, in units of the curve's q_scale.
PANEL_Q = 1.0
#: A half-interval uses the root substitution when its anchor's (virtual) root
#: is closer than ROOT_RATIO times the half's length.
ROOT_RATIO = 1.0
#: Smallest positive double, used to keep 1/sqrt(G) finite at a node on a root.
TINY = np.finfo(float).tiny
#: Rows of the quadrature's scratch array (node values and the cumulative sums).
WORK_ROWS = 10


class SampleColumn:
    """Columns of the samples :func:`samples` returns (plain ints, for numba)."""

    t = 0  #: time [s]
    q = 1  #: coordinate
    w = 2  #: squared speed v^2
    N = 3  #: normal reaction per unit mass
    s = 4  #: arc-length coordinate from the initial position (increasing with q)
    path = 5  #: distance travelled since the start
    W = 6  #: friction work per unit mass since the start (the energy budget's quadrature)
    W_impacts = 7  #: impact losses per unit mass since the start (at an impact: counted after it)
    branch = 8  #: the branch s = sigma sign(N)
    sigma = 9  #: the direction of motion


#: Columns of a sample (:class:`SampleColumn`).
SAMPLE_COLUMNS = 1 + max(v for k, v in vars(SampleColumn).items() if not k.startswith("_"))
#: Nodes per quadrature piece a sample buffer grows by at least, times the rule's nodes.
SAMPLE_GROWTH = 200


def cumulate(St, v, n, acc):
    """``acc[j] = sum_i St[i, j] v[i]`` for ``j < n``, summed over ``i`` in order: a cumulative
    Gauss-Legendre integral at every node (``St`` the transposed matrix); returns ``acc``."""
    for j in range(n):
        acc[j] = 0.0
    for i in range(n):
        vi = v[i]
        for j in range(n):
            acc[j] += St[i, j] * vi
    return acc


def quad(qa, qb, Ga, Gb, s, sigma, S, K, cp, R, work, keep, out, o):
    """Time and friction work (per unit mass) of one interval; node samples into out[o:].

    ``R``: the rules (:class:`~symvib.numeric.engine.state.Rules`; see
    :func:`symvib.numeric.driver.plain_nodes`); ``S``: the scene constants
    (:class:`~symvib.numeric.engine.state.Setup`); ``work``: scratch rows
    (:data:`WORK_ROWS`).  Returns ``(T, W_friction / m, o)``.
    """
    Xw, Ww, Sw, SWw, Xp, Wtp, Sp = R.Xw, R.Ww, R.Sw, R.SWw, R.Xp, R.Wp, R.Sp
    g, mu, scale = S.g, S.mu, S.scale
    g2 = 2.0 * g
    L = abs(qb - qa)
    if L == 0.0:
        return 0.0, 0.0, o
    half = 0.5 * L
    maxq = PANEL_Q * scale
    # Per node: the integrand of G's cumulative integral, q, h dq/dr, exp(s mu alpha), kappa,
    # cos alpha, G's cumulative integral; with samples, the integrands of time, path and work.
    cum, qn, hd, exn, kn, cn, acc = work[0], work[1], work[2], work[3], work[4], work[5], work[6]
    ft, fp, fw = work[7], work[8], work[9]
    T = 0.0
    Wf = 0.0
    P = 0.0
    half_b = o
    for kh in range(2):
        if kh == 0:
            e, d, Ge = qa, float(sigma), Ga
        else:
            e, d, Ge = qb, -float(sigma), Gb
            half_b = o
        gd = -d * g2  # G' = gd F_s' along the half (d = +-1: gd F_s' is -2 g F_s' d exactly)
        gamma = gd * dFs(s, e, mu, K, cp)
        root = Ge == 0.0 or (gamma > 0.0 and Ge < ROOT_RATIO * gamma * half)
        Gstart = Ge
        tau0 = 0.0
        path0 = 0.0
        work0 = 0.0
        if root:
            delta = Ge / gamma if Ge > 0.0 else 0.0
            r_lo = math.sqrt(delta)
            r_hi = math.sqrt(delta + half)
        else:
            delta = 0.0
            r_lo = 0.0
            r_hi = half
        seg_a = r_lo
        while True:
            if (not root) or r_lo == 0.0 or 2.0 * seg_a >= r_hi:
                seg_b = r_hi
            else:
                seg_b = 2.0 * seg_a
            span = seg_b * seg_b - seg_a * seg_a if root else seg_b - seg_a
            parts = max(1, int(math.ceil(span / maxq)))
            step = (seg_b - seg_a) / parts
            for jp in range(parts):
                r1 = seg_a + jp * step
                r2 = seg_a + (jp + 1) * step if jp + 1 < parts else seg_b
                hw = 0.5 * (r2 - r1)
                weighted = root and r1 == 0.0
                if weighted:
                    X, Wt, St, St2 = Xw, Ww, Sw, SWw
                else:
                    X, Wt, St, St2 = Xp, Wtp, Sp, Sp
                n = len(X)
                total = 0.0
                for j in range(n):
                    r = r1 + hw * (X[j] + 1.0)
                    if root:
                        xi = r * r - delta
                        dq = 2.0 * r
                    else:
                        xi = r
                        dq = 1.0
                    qj = e + d * xi
                    # laws.node, called here directly (the plain engine's hottest call)
                    if s > 0:
                        dF, hh, ex, ka, co = K.node_p(qj, mu, *cp)
                    else:
                        dF, hh, ex, ka, co = K.node_m(qj, mu, *cp)
                    gj = gd * dF
                    dG = gj * dq
                    total += Wt[j] * dG
                    # The integrand of G's cumulative integral: gamma with the weight r next to a root.
                    cum[j] = gj if weighted else dG
                    hd[j] = hh * dq
                    exn[j] = ex
                    kn[j] = ka
                    cn[j] = co
                    if keep:
                        qn[j] = qj
                total *= hw
                Tp = 0.0
                Wp = 0.0
                Pp = 0.0
                # G at the nodes: the anchor plus the cumulative integral of dG/dr.
                acc = cumulate(St2, cum, n, acc)
                scale_acc = 2.0 * hw * hw if weighted else hw
                for j in range(n):
                    G = Gstart + acc[j] * scale_acc
                    if G < TINY:
                        G = TINY
                    ex = exn[j]
                    hdj = hd[j]
                    f = hdj * ex / sqrt(G)
                    w = G / (ex * ex)
                    N = kn[j] * w + g * cn[j]
                    wj = Wt[j]
                    Tp += wj * f
                    Wp += wj * mu * abs(N) * hdj
                    if keep:
                        ft[j] = f
                        fp[j] = hdj
                        fw[j] = mu * abs(N) * hdj
                        Pp += wj * fp[j]
                        out[o + j, 1] = qn[j]
                        out[o + j, 2] = w
                        out[o + j, 3] = N
                if keep:
                    # Time, path and friction work at every node: the same cumulative
                    # Gauss-Legendre integral as the interval's totals.
                    acc = cumulate(St, ft, n, acc)
                    for j in range(n):
                        out[o + j, 0] = tau0 + hw * acc[j]
                    acc = cumulate(St, fp, n, acc)
                    for j in range(n):
                        out[o + j, 4] = path0 + hw * acc[j]
                    acc = cumulate(St, fw, n, acc)
                    for j in range(n):
                        out[o + j, 5] = work0 + hw * acc[j]
                    o += n
                Tp *= hw
                Wp *= hw
                Pp *= hw
                tau0 += Tp
                path0 += Pp
                work0 += Wp
                T += Tp
                Wf += Wp
                P += Pp
                Gstart += total
            if seg_b >= r_hi:
                break
            seg_a = seg_b
    if keep:
        # The half anchored at qb was integrated from qb backwards.
        for j in range(half_b, o):
            out[j, 0] = T - out[j, 0]
            out[j, 4] = P - out[j, 4]
            out[j, 5] = Wf - out[j, 5]
    return T, Wf, o


def time_excess(x, p):
    """Time from the start of an interval to x, minus a target (for the t_max stop)."""
    q, Ga, C, s, sigma, S, K, cp, R, work, dummy, target = p
    Gx = max(C - 2.0 * S.g * Fs(s, x, S.mu, K, cp), 0.0)
    T, _, _ = quad(q, x, Ga, Gx, s, sigma, S, K, cp, R, work, False, dummy, 0)
    return T - target


def root_time(p, a, b, fa, fb):
    """Where time_excess vanishes between a and b (values fa, fb of opposite signs)."""
    for _ in range(ROOT_MAXITER):
        x = illinois_point(a, b, fa, fb)
        a, b, fa, fb, done = illinois_update(a, b, fa, fb, x, time_excess(x, p))
        if done:
            break
    return b


def arc_length(qa, qb, S, K, cp, R):
    """``Integral h dq`` from ``qa`` to ``qb`` (>= 0): Gauss-Legendre panels of at most
    ``PANEL_Q`` q_scale (``h`` is smooth on the regular domain, so this is exact to rounding)."""
    X, Wt = R.Xp, R.Wp
    L = abs(qb - qa)
    if L == 0.0:
        return 0.0
    parts = max(1, int(math.ceil(L / (PANEL_Q * S.scale))))
    step = (qb - qa) / parts
    total = 0.0
    for jp in range(parts):
        a = qa + jp * step
        for j in range(len(X)):
            total += Wt[j] * K.h(a + 0.5 * step * (X[j] + 1.0), *cp)
    return 0.5 * abs(step) * total


def grown(a, n, rows):
    """``a`` (2-d) with its first ``n`` rows copied into ``rows`` zeroed rows: a log that
    grows when full.  Element by element: numba compiles a slice copy with its
    broadcasting checks and their error messages, about a second of compile time."""
    new = np.zeros((rows, a.shape[1]))
    for i in range(n):
        for j in range(a.shape[1]):
            new[i, j] = a[i, j]
    return new


def put_sample(out, index, o, t, q, w, N, coord, path, Wf, Wimp, s, sigma, motion):
    """Write the sample at a piece's end into row ``o`` (columns :class:`SampleColumn`); returns ``o + 1``."""
    out[o, 0], out[o, 1], out[o, 2], out[o, 3] = t, q, w, N
    out[o, 4], out[o, 5], out[o, 6], out[o, 7] = coord, path, Wf, Wimp
    out[o, 8], out[o, 9] = s, sigma
    index[o] = motion
    return o + 1


def _state_at(q, G, s, S, K, cp):
    """``(w, N)`` at ``q`` from ``G = w exp(2 s mu alpha)`` (physics.md, eq. 2)."""
    _, _, ex, ka, co = node(s, q, S.mu, K, cp)
    w = G / (ex * ex)
    return w, ka * w + S.g * co


def samples(ivs, ni, S, K, cp, R, pieces):
    """Samples of the logged intervals (columns :class:`SampleColumn`) and the index of the
    motion interval of each; the cost grows linearly with ``ni``.

    Each logged interval is cut into ``pieces`` equal pieces in ``q``; each piece
    gives the Gauss nodes of :func:`quad` (graded in ``sqrt(distance)`` towards a
    turning point, where ``w`` has the square-root shape) and its end point, and a
    motion interval its start point.  Logged intervals that continue one another
    (the engine's search window ended, no event: same ``s`` and ``sigma``) share
    one motion interval, so the index counts the intervals between events.  Time,
    path and friction work are the cumulative quadratures of the run's own
    integrals; at an impact the start of the next interval carries the speed after
    it and the loss ``(1 - k^2) w / 2`` (per unit mass; physics.md, "Events" 1).
    Rows are in time order within each piece's half; the caller sorts by time.
    """
    n = max(len(R.Xw), len(R.Xp))
    work = scratch(WORK_ROWS, n)
    g, k = S.g, S.k
    cap = max(ni * pieces * 4 * n, 16)
    out = np.zeros((cap, SAMPLE_COLUMNS))
    index = np.zeros(cap, dtype=np.int64)
    o = 0
    motion = -1
    s_prev, sigma_prev, w_prev = 0, 0, 0.0
    coord, path, Wf, Wimp = 0.0, 0.0, 0.0, 0.0
    for i in range(ni):
        qa, qb = ivs[i, IntervalColumn.qa], ivs[i, IntervalColumn.qb]
        Ga, Gb = ivs[i, IntervalColumn.Ga], ivs[i, IntervalColumn.Gb]
        s, sigma = int(ivs[i, IntervalColumn.s]), int(ivs[i, IntervalColumn.sigma])
        t0, T, Wi = ivs[i, IntervalColumn.t0], ivs[i, IntervalColumn.T], ivs[i, IntervalColumn.W_friction]
        new = i == 0 or s != s_prev or sigma != sigma_prev
        if new:
            motion += 1
            if i > 0 and sigma != sigma_prev:
                Wimp += 0.5 * (1.0 - k * k) * w_prev  # an impact (0 at a reversal, where w = 0)
        C = Ga + 2.0 * g * Fs(s, qa, S.mu, K, cp)
        tp, Wp0 = t0, Wf
        G1 = Ga
        for jp in range(pieces):
            need = o + SAMPLE_GROWTH * n + 2
            if need > cap:
                cap = 2 * need
                out = grown(out, o, cap)
                new_index = np.zeros(cap, dtype=np.int64)
                for j in range(o):
                    new_index[j] = index[j]
                index = new_index
            last = jp + 1 == pieces
            q1 = qa + (qb - qa) * jp / pieces
            q2 = qb if last else qa + (qb - qa) * (jp + 1) / pieces
            G2 = Gb if last else max(C - 2.0 * g * Fs(s, q2, S.mu, K, cp), 0.0)
            if jp == 0 and new:
                w1, N1 = _state_at(q1, G1, s, S, K, cp)
                o = put_sample(out, index, o, tp, q1, w1, N1, coord, path, Wf, Wimp, s, sigma, motion)
            start = o
            Tq, Wq, o = quad(q1, q2, G1, G2, s, sigma, S, K, cp, R, work, True, out, o)
            for j in range(start, o):
                dp, dw = out[j, 4], out[j, 5]
                out[j, 0] += tp
                out[j, 4] = coord + sigma * dp
                out[j, 5] = path + dp
                out[j, 6] = Wf + dw
                out[j, 7] = Wimp
                out[j, 8], out[j, 9] = s, sigma
                index[j] = motion
            L = arc_length(q1, q2, S, K, cp, R)
            if last:  # the interval's end: its logged time and friction work
                tp, Wf = t0 + T, Wp0 + Wi
            else:
                tp, Wf = tp + Tq, Wf + Wq
            path += L
            coord += sigma * L
            w2, N2 = _state_at(q2, G2, s, S, K, cp)
            o = put_sample(out, index, o, tp, q2, w2, N2, coord, path, Wf, Wimp, s, sigma, motion)
            G1 = G2
            w_prev = w2
        s_prev, sigma_prev = s, sigma
    return out[:o], index[:o]
