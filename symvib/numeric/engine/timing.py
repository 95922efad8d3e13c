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

import numpy as np

from symvib.numeric.engine.laws import Fs, dFs, node
from symvib.numeric.engine.roots import ROOT_MAXITER, illinois_point, illinois_update
from symvib.numeric.layout import IntervalColumn

__all__ = ["quad", "root_time", "samples", "PANEL_Q", "ROOT_RATIO", "WORK_ROWS"]

#: Widest quadrature panel, in units of the curve's q_scale.
PANEL_Q = 1.0
#: A half-interval uses the root substitution when its anchor's (virtual) root
#: is closer than ROOT_RATIO times the half's length.
ROOT_RATIO = 1.0
#: Smallest positive double, used to keep 1/sqrt(G) finite at a node on a root.
TINY = np.finfo(float).tiny
#: Rows of the quadrature's scratch array (node values and the cumulative sums).
WORK_ROWS = 10
#: Columns of a sample: t, q, w, N.
SAMPLE_COLUMNS = 4
#: Nodes per interval a sample buffer grows by at least, times the rule's nodes.
SAMPLE_GROWTH = 200


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
    gam, dGdr, qn, dqdr, ft = work[0], work[1], work[2], work[3], work[4]
    hn, exn, kn, cn, acc = work[5], work[6], work[7], work[8], work[9]
    T = 0.0
    Wf = 0.0
    half_b = o
    for kh in range(2):
        if kh == 0:
            e, d, Ge = qa, float(sigma), Ga
        else:
            e, d, Ge = qb, -float(sigma), Gb
            half_b = o
        gamma = -d * g2 * dFs(s, e, mu, K, cp)
        root = Ge == 0.0 or (gamma > 0.0 and Ge < ROOT_RATIO * gamma * half)
        Gstart = Ge
        tau0 = 0.0
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
                    X, Wt, St = Xw, Ww, Sw
                else:
                    X, Wt, St = Xp, Wtp, Sp
                n = X.shape[0]
                for j in range(n):
                    r = r1 + hw * (X[j] + 1.0)
                    if root:
                        xi = r * r - delta
                        dq = 2.0 * r
                    else:
                        xi = r
                        dq = 1.0
                    qj = e + d * xi
                    qn[j] = qj
                    dqdr[j] = dq
                    dF, hh, ex, ka, co = node(s, qj, mu, K, cp)
                    hn[j], exn[j], kn[j], cn[j] = hh, ex, ka, co
                    gam[j] = -g2 * dF * d
                    dGdr[j] = gam[j] * dq
                total = 0.0
                for j in range(n):
                    total += Wt[j] * dGdr[j]
                total *= hw
                Tp = 0.0
                Wp = 0.0
                # acc = S @ dGdr (or SW @ gam next to a root), summed over i in order for every
                # node j at once: the inner loop runs along a row of the transposed matrix.
                for j in range(n):
                    acc[j] = 0.0
                if weighted:
                    scale_acc = 2.0 * hw * hw
                    for i in range(n):
                        gi = gam[i]
                        for j in range(n):
                            acc[j] += SWw[i, j] * gi
                else:
                    scale_acc = hw
                    for i in range(n):
                        di = dGdr[i]
                        for j in range(n):
                            acc[j] += St[i, j] * di
                for j in range(n):
                    G = max(Gstart + acc[j] * scale_acc, TINY)
                    hh = hn[j]
                    ex = exn[j]
                    f = hh * dqdr[j] * ex / math.sqrt(G)
                    ft[j] = f
                    w = G / (ex * ex)
                    N = kn[j] * w + g * cn[j]
                    Tp += Wt[j] * f
                    Wp += Wt[j] * mu * abs(N) * hh * dqdr[j]
                    if keep:
                        out[o + j, 1] = qn[j]
                        out[o + j, 2] = w
                        out[o + j, 3] = N
                if keep:
                    for j in range(n):
                        acc[j] = 0.0
                    for i in range(n):
                        fi = ft[i]
                        for j in range(n):
                            acc[j] += St[i, j] * fi
                    for j in range(n):
                        out[o + j, 0] = tau0 + hw * acc[j]
                    o += n
                Tp *= hw
                Wp *= hw
                tau0 += Tp
                T += Tp
                Wf += Wp
                Gstart += total
            if seg_b >= r_hi:
                break
            seg_a = seg_b
    if keep:
        for j in range(half_b, o):
            out[j, 0] = T - out[j, 0]
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



def samples(ivs, ni, S, K, cp, R):
    """Node samples (columns t, q, w, N) of the logged intervals, interval by interval,
    and the index of the interval of each sample; the cost grows linearly with ``ni``."""
    n = max(R.Xw.shape[0], R.Xp.shape[0])
    work = np.empty((WORK_ROWS, n))
    # Upper bound of the nodes per interval: panels are few; grow when needed.
    cap = max(ni * 8 * n, 16)
    out = np.zeros((cap, SAMPLE_COLUMNS))
    index = np.zeros(cap, dtype=np.int64)
    o = 0
    for i in range(ni):
        t0 = ivs[i, IntervalColumn.t0]
        need = o + SAMPLE_GROWTH * n
        if need > cap:
            cap = 2 * need
            new = np.zeros((cap, SAMPLE_COLUMNS))
            new[:o] = out[:o]
            out = new
            newi = np.zeros(cap, dtype=np.int64)
            newi[:o] = index[:o]
            index = newi
        start = o
        _, _, o = quad(ivs[i, IntervalColumn.qa], ivs[i, IntervalColumn.qb], ivs[i, IntervalColumn.Ga],
                       ivs[i, IntervalColumn.Gb], int(ivs[i, IntervalColumn.s]), int(ivs[i, IntervalColumn.sigma]),
                       S, K, cp, R, work, True, out, o)
        for j in range(start, o):
            out[j, 0] += t0
            index[j] = i
    return out[:o], index[:o]
