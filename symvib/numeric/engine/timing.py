"""Times and friction work of a motion interval, by adaptive Gauss-Legendre quadrature.

``t = Integral h dq / sqrt(w)`` (physics.md, "Time").  Each interval is split at
its midpoint and each half is anchored at its outer end, where ``G`` is known
exactly (the state, or 0 at a turning point).  ``G`` at the Gauss nodes is
rebuilt from the anchor by integrating ``G' = -2 g F_s'`` with a cumulative
Gauss-Legendre matrix, so it keeps full relative accuracy where it is small;
near a (real or virtual) root at distance ``delta`` behind the anchor the
variable ``r = sqrt(xi)``, ``xi`` the distance from that root, removes the
inverse square root, with panels graded geometrically from ``sqrt(delta)`` (grazing roots).

Error control (physics.md, "Accuracy"): every panel estimates the truncation error
of its time and of its increment of ``G`` from the four highest Legendre
coefficients of the integrands at its nodes (:func:`tail_error`), and the time's
sensitivity to an error in ``G``; a panel whose estimate exceeds the tolerance
(``R.rtol`` of its time, plus its share of ``R.atol``) is halved, the next one
doubles back.  The error of an interval is the sum over its panels of the
truncation estimates and of the propagated uncertainty of ``G`` (rounding of the
anchor and of every increment, bounded by the size of ``F_s'``'s terms), plus the
mismatch of the two halves at the midpoint.  :func:`quad` says when the budget of
panels was spent or a node found ``G < 0`` (a turning point the search missed).

Examples
--------
>>> PANEL_Q, ROOT_RATIO, WORK_ROWS, MAX_PANELS
(1.0, 1.0, 10, 400)
>>> tail_error(1e-3, 1e-3, 1e-3, 1e-3, 12, False, 0.0, 0.0) == 2e-3     # not decaying: the tail itself
True
>>> tail_error(1e-12, 0.0, 1e-8, 0.0, 12, False, 0.01, 0.0) < 1e-30      # decaying by 1e-2 a step: G's zero
True
>>> tail_error(1e-12, 0.0, 1e-8, 0.0, 12, False, 0.0, 0.0) > 1e-30       # ... or not: half the decay
True
"""
from __future__ import annotations

import math
from math import sqrt

import numpy as np

from symvib.numeric.engine.anchor import PANEL_Q, crit_near, dF_best
from symvib.numeric.engine.laws import EDGE_REACH, EDGE_SHARE, EPS, Fs, dF_edge, node
from symvib.numeric.engine.roots import ROOT_MAXITER, illinois_point, illinois_update
from symvib.numeric.engine.scan import ROOT_ROWS, scratch
from symvib.numeric.layout import IntervalColumn

__all__ = ["quad", "panel", "half_anchor", "panel_error", "record_panel", "midpoint_error", "QUAD_STEPS",
           "zero_ratio", "ellipse_ratio", "tail_time", "turn_departure", "PanelColumn",
           "PANEL_COLUMNS", "NONE",
           "SAMPLES", "PANELS",
           "tail_error", "cumulate", "root_time", "samples", "arc_length", "grown", "PANEL_Q", "ROOT_RATIO",
           "WORK_ROWS", "MAX_PANELS", "SampleColumn", "QUAD_OK", "QUAD_BUDGET", "QUAD_NEGATIVE"]

#: A half-interval uses the root substitution when its anchor's (virtual) root is
#: closer than ROOT_RATIO times the half's length.
ROOT_RATIO = 1.0
#: Panels are graded geometrically from ``r = sqrt(delta)`` only where that is at least this
#: fraction of the half's ``r`` span: a root closer than that is real and simple, and the
#: integrand is analytic in ``r`` far around it; error control refines whatever else needs it
#: (and a root within :data:`VIRTUAL_ROOT_RTOL`, a turning point stopped on the double before it,
#: is where the half starts).
ROOT_GRADE = 1e-3
#: A root half whose (virtual) root lies at most this many length scales behind its anchor starts
#: on the root with the weighted rule and takes the stretch to the anchor away in closed form (``G``
#: linear over it: exact to about this, relative): a turning point is stopped on the double before
#: it, where ``G`` is of rounding size, and the plain rule from there would halve its first panel
#: down towards the root.
VIRTUAL_ROOT_RTOL = 1e3 * EPS
#: Smallest positive double, used to keep 1/sqrt(G) finite at a node on a root.
TINY = np.finfo(float).tiny
#: Rows of the quadrature's scratch array, one after the other in one flat array of
#: ``WORK_ROWS * n`` floats (``n`` the nodes of a panel): per node the integrand of ``G``'s cumulative
#: integral, ``q``, ``h dq/dr``, ``exp(s mu alpha)``, ``kappa``, ``cos alpha``, the cumulative sums, and
#: with samples the integrands of time, path and friction work.  One flat array, not a tuple of row
#: views: the compiled engine counts a reference of every array it passes or unpacks (atomically),
#: which had cost a third of a sweep's time.
W_CUM, W_Q, W_HD, W_EX, W_KAPPA, W_COS, W_ACC, W_FT, W_FP, W_FW = range(10)
WORK_ROWS = 10
#: Most panels a half-interval may accept; with at most MAX_TRIES evaluated, including the
#: halved ones.  A half that needs more ends the run ``tolerance_not_met``.
MAX_PANELS = 400
MAX_TRIES = 4 * MAX_PANELS
#: Narrowest panel, relative to the size of its end in the quadrature variable: below it
#: a panel is not halved (its nodes would not be distinct doubles).
MIN_PANEL_RTOL = 1e3 * EPS
#: A ratio of successive Legendre coefficients at and above which the tail is taken as
#: not decaying (the integrand is not resolved on the panel).
UNRESOLVED = 0.5
#: A Legendre tail below this many rounding errors of its integrand's mean is rounding, not
#: truncation (:func:`tail_error`'s ``floor``).
ROUND_TAIL = 16.0
#: Factor on the extrapolated tail of a panel's error estimate (:func:`tail_error`).
ERROR_SAFETY = 2.0
#: The zero of G explains the decay of the coefficients while their own ratio is at most this many
#: times its ellipse's (:func:`tail_error`; on the paper's panels the two agree within 15 %).
GEOM_SLACK = 1.25
#: A node's G more negative than this many times its uncertainty is a root the search missed.
NEGATIVE_MARGIN = 8.0
#: What :func:`quad` writes to its ``out``: nothing, the samples at the nodes, or the panels it took.
NONE, SAMPLES, PANELS = 0, 1, 2
#: The steps of :func:`quad` besides :func:`panel`: the compiled engine inlines them into ``quad``
#: (:mod:`~symvib.numeric.engine.bind`; ``quad`` counts no references, so the arrays they take cost
#: nothing there either).
QUAD_STEPS = ("half_anchor", "panel_error", "record_panel", "midpoint_error")


class PanelColumn:
    """Columns of the rows :func:`quad` writes in mode :data:`PANELS` (one per accepted panel; plain
    ints, for numba): the half (0 anchored at the start, 1 at the end), the panel's ends in the
    quadrature variable ``r``, ``G`` and the time from the anchor at its ends, whether the half
    uses the root substitution, and its ``delta`` (``xi = r^2 - delta``)."""

    half = 0
    r1 = 1
    r2 = 2
    G1 = 3
    G2 = 4
    tau1 = 5
    tau2 = 6
    root = 7
    delta = 8


#: Columns of a row of :class:`PanelColumn`.
PANEL_COLUMNS = 9
#: :class:`PanelColumn` as module-level ints (numba takes them as compile-time constants).
P_HALF, P_R1, P_R2, P_G1, P_G2, P_TAU1, P_TAU2, P_ROOT, P_DELTA = (
    PanelColumn.half, PanelColumn.r1, PanelColumn.r2, PanelColumn.G1, PanelColumn.G2, PanelColumn.tau1,
    PanelColumn.tau2, PanelColumn.root, PanelColumn.delta)


#: What :func:`quad` reports: the tolerance was met (or the interval is done); the budget of
#: panels was spent first; a node found G < 0 (the interval's end is wrong).
QUAD_OK, QUAD_BUDGET, QUAD_NEGATIVE = 0, 1, 2


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
#: :class:`SampleColumn` as module-level ints (numba takes them as compile-time constants).
C_T, C_Q, C_W, C_N, C_S, C_PATH, C_WF, C_WIMP, C_BRANCH, C_SIGMA = (
    SampleColumn.t, SampleColumn.q, SampleColumn.w, SampleColumn.N, SampleColumn.s, SampleColumn.path,
    SampleColumn.W, SampleColumn.W_impacts, SampleColumn.branch, SampleColumn.sigma)
#: Panels a sample buffer grows by at least, times the rule's nodes (both halves of a piece).
SAMPLE_GROWTH = 2 * MAX_PANELS


def cumulate(St, v, vo, n, acc, ao):
    """``acc[ao + j] = sum_i St[i, j] v[vo + i]`` for ``j < n``, summed over ``i`` in order: a cumulative
    Gauss-Legendre integral at every node (``St`` the transposed matrix; ``v`` and ``acc`` flat rows of
    the quadrature's one scratch array, :data:`WORK_ROWS`); returns ``acc``."""
    for j in range(n):
        acc[ao + j] = 0.0
    for i in range(n):
        vi = v[vo + i]
        for j in range(n):
            acc[ao + j] += St[i, j] * vi
    return acc


def tail_error(c1, c2, c3, c4, n, cautious, r_geom, floor):
    """Error estimate of an ``n``-point Gauss-Legendre integral over ``[-1, 1]`` from the integrand's
    Legendre coefficients ``c1 = a_{n-1}, c2 = a_{n-2}, c3 = a_{n-3}, c4 = a_{n-4}``.

    The coefficients of an integrand analytic in a Bernstein ellipse ``rho`` decay as
    ``rho^-k``, and the rule errs by about ``rho^-2n``.  ``r_tail = 1/rho`` is estimated
    from the two pairs (pairs, so that an even or odd integrand, whose every other
    coefficient vanishes, is not taken for a resolved one); ``r_geom`` is ``1/rho`` of the
    nearest zero of ``G`` (the singularity of ``1/sqrt(G)``; :func:`zero_ratio`, 0 if not
    known; negative: trust the tail, for an integrand without that singularity, ``G'``).
    Where that zero explains the decay (``r_tail <= GEOM_SLACK r_geom``) the
    extrapolation is trusted: ``ERROR_SAFETY 2 t r^(n+1)``, ``r = max(r_tail, r_geom)``,
    ``t`` the larger of the last pair.  Otherwise, or with ``cautious``, the decay comes
    from something the nodes see less well (a singularity of the curve's kernels next to
    the panel: the coefficients of ``k ~ n`` are not yet in their asymptotic regime) and
    the estimate is ``2 t r_tail^(n/2 + 1)``: half the decay.  Over 4000 test integrands
    (near-stop peaks, virtual roots, poles of a kernel; ``python benchmarks/tail_estimate.py``)
    no estimate below ``1e-12`` or ``1e-13`` hid an error above it; below ``1e-10``, 2 of
    the 1325 kernel poles did (by at most 14 times), on the cautious rule.  A tail that
    does not decay (``r >= UNRESOLVED``) is its own estimate: ``2 t``.  A tail at or below ``floor``, the
    rounding of the integrand's values, is rounding (counted apart), not truncation: 0.
    """
    t1 = max(abs(c1), abs(c2))
    t2 = max(abs(c3), abs(c4))
    if t1 <= floor:
        return 0.0
    r = 1.0 if t2 == 0.0 else sqrt(t1 / t2)
    if cautious or 0.0 <= r_geom * GEOM_SLACK < r:
        if r >= UNRESOLVED:
            return 2.0 * t1
        return 2.0 * t1 * r ** (n // 2 + 1)
    r = max(r, r_geom)
    if r >= UNRESOLVED:
        return 2.0 * t1
    return ERROR_SAFETY * 2.0 * t1 * r ** (n + 1)


def ellipse_ratio(re, im):
    """``1/rho`` of the Bernstein ellipse of ``[-1, 1]`` through ``u = re + i im``: ``rho = a + sqrt(a^2 - 1)``,
    ``a = (|u - 1| + |u + 1|) / 2`` the semi-major axis (the ellipse's foci are -1 and 1).  In real
    arithmetic: the compiled engine's complex square root costs a ``hypot``, an ``atan2``, a ``cos``
    and a ``sin``, which had been a tenth of a sweep's time."""
    a = 0.5 * (sqrt((re - 1.0) * (re - 1.0) + im * im) + sqrt((re + 1.0) * (re + 1.0) + im * im))
    return 1.0 / (a + sqrt(max(a * a - 1.0, 0.0)))


def zero_ratio(x, G, G1, G2, c, hw):
    """``1/rho`` of the Bernstein ellipse (of the panel with centre ``c`` and half-width ``hw``) through
    the nearest zero of the quadratic ``G + G1 (z - x) + G2 (z - x)^2 / 2``: ``G``'s local model at the
    node ``x`` where it is smallest, whose zero is the singularity of the time's ``1/sqrt(G)``
    (:func:`ellipse_ratio`)."""
    if G2 != 0.0 and abs(G2) * hw > EPS * abs(G1):
        disc = G1 * G1 - 2.0 * G2 * G
        if disc >= 0.0:
            root = sqrt(disc)
            u1 = (x + (-G1 + root) / G2 - c) / hw
            u2 = (x + (-G1 - root) / G2 - c) / hw
            return max(ellipse_ratio(u1, 0.0), ellipse_ratio(u2, 0.0))
        # a complex pair x + (-G1 +- i sqrt(-disc)) / G2: both on one ellipse
        return ellipse_ratio((x - G1 / G2 - c) / hw, sqrt(-disc) / abs(G2) / hw)
    if G1 != 0.0:
        return ellipse_ratio((x - G / G1 - c) / hw, 0.0)
    return 0.0


def panel(r1, r2, Gstart, e, d, gd, s, root, delta, S, K, cp, Xr, Wr, Sr, Tr, work, mode, out, o, roots, count):
    """One panel ``[r1, r2]`` of a half-interval anchored at ``e`` (entered in direction ``d``),
    with ``G = Gstart`` at ``r1``: its nodes, ``G`` rebuilt at them, the integrals and their errors.

    ``r`` is the quadrature variable (``xi = r^2 - delta`` next to a root, ``xi = r``
    otherwise; ``q = e + d xi``); ``Xr, Wr, Sr, Tr`` are the nodes, weights, cumulative matrix and
    flattened tail rows of the Gauss-Legendre rule (a panel that starts on the root itself
    takes the weighted one), ``work`` the flat scratch array (rows :data:`WORK_ROWS`).
    In mode :data:`SAMPLES` the nodes' ``q, w, N`` go to ``out[o:]`` and the time, path and
    friction-work integrands to the last three rows.  Where ``F_s'`` at a node is small next
    to its terms and a critical point of ``roots`` is near, it is taken from there
    (:func:`~symvib.numeric.engine.laws.dF_edge`).

    Returns ``(dG, T, W, P, err_T, err_G, sens, round_G, G_min, q_min)``: the increment of
    ``G`` over the panel, its time, friction work per unit mass and path length, the
    truncation errors of the time and of ``dG`` (:func:`tail_error`), the time's
    sensitivity ``dT/dG`` to an offset of ``G`` (``Integral f / (2 G)``), a bound of the
    rounding of ``dG`` (``F_s'`` is a difference of terms as large as ``exp(2 s mu alpha)
    h (1 + mu)``, which near the cone edge is far above its value), and the smallest
    ``G`` at a node, with its ``q``.
    """
    g, mu = S.g, S.mu
    hw = 0.5 * (r2 - r1)
    weighted = root and r1 == 0.0
    n = len(Xr)
    cum, qn, hd, exn, kn, cn = W_CUM * n, W_Q * n, W_HD * n, W_EX * n, W_KAPPA * n, W_COS * n
    acc, ft, fp, fw = W_ACC * n, W_FT * n, W_FP * n, W_FW * n
    total = 0.0
    size = 0.0
    terms = 0.0
    a1, a2, a3, a4 = 0.0, 0.0, 0.0, 0.0
    for j in range(n):
        r = r1 + hw * (Xr[j] + 1.0)
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
        noise = ex * ex * hh * (1.0 + mu)
        if abs(dF) < EDGE_SHARE * noise:
            qc = crit_near(roots, count, s, qj, EDGE_REACH * S.scale)
            if qc == qc:
                dF = dF_edge(s, qc, (e - qc) + d * xi, mu, K, cp)
                noise = 8.0 * abs(dF)
        gj = gd * dF
        dG = gj * dq
        wj = Wr[j]
        total += wj * dG
        size += wj * abs(dG)
        terms += wj * noise * dq
        a1 += Tr[0 * n + j] * dG
        a2 += Tr[1 * n + j] * dG
        a3 += Tr[2 * n + j] * dG
        a4 += Tr[3 * n + j] * dG
        # The integrand of G's cumulative integral: gamma with the weight r next to a root.
        work[cum + j] = gj if weighted else dG
        work[hd + j] = hh * dq
        work[exn + j] = ex
        work[kn + j] = ka
        work[cn + j] = co
        work[qn + j] = qj
    total *= hw
    err_G = hw * tail_error(a1, a2, a3, a4, n, False, -1.0, ROUND_TAIL * EPS * (size + 2.0 * g * terms))
    round_G = EPS * hw * (4.0 * size + 2.0 * g * terms)
    # G at the nodes: the anchor plus the cumulative integral of dG/dr.
    cumulate(Sr, work, cum, n, work, acc)
    scale_acc = 2.0 * hw * hw if weighted else hw
    T = 0.0
    W = 0.0
    P = 0.0
    sens = 0.0
    G_min = math.inf
    q_min = e
    j_min = 0
    b1, b2, b3, b4 = 0.0, 0.0, 0.0, 0.0
    for j in range(n):
        G = Gstart + work[acc + j] * scale_acc
        if G < G_min:
            G_min = G
            q_min = work[qn + j]
            j_min = j
        if G < TINY:
            G = TINY
        ex = work[exn + j]
        hdj = work[hd + j]
        inv = 1.0 / sqrt(G)
        f = hdj * ex * inv
        w = G / (ex * ex)
        N = work[kn + j] * w + g * work[cn + j]
        wj = Wr[j]
        T += wj * f
        W += wj * mu * abs(N) * hdj
        sens += wj * f * inv * inv
        b1 += Tr[0 * n + j] * f
        b2 += Tr[1 * n + j] * f
        b3 += Tr[2 * n + j] * f
        b4 += Tr[3 * n + j] * f
        if mode == SAMPLES:
            work[ft + j] = f
            work[fp + j] = hdj
            work[fw + j] = mu * abs(N) * hdj
            P += wj * hdj
            out[o + j, C_Q] = work[qn + j]
            out[o + j, C_W] = w
            out[o + j, C_N] = N
    floor_T = ROUND_TAIL * EPS * T
    r_geom = 0.0
    if not weighted and max(abs(b1), abs(b2)) > floor_T:
        # (a tail at the rounding floor is 0 whatever the zero's ellipse: tail_error)
        # G's local model at its smallest node: value, slope and curvature in r (from the slopes
        # at the neighbouring nodes), for the zero that bounds the time integrand's analyticity.
        j0, j1 = max(j_min - 1, 0), min(j_min + 1, n - 1)
        x0, x1 = r1 + hw * (Xr[j0] + 1.0), r1 + hw * (Xr[j1] + 1.0)
        curv = (work[cum + j1] - work[cum + j0]) / (x1 - x0) if x1 > x0 else 0.0
        r_geom = zero_ratio(r1 + hw * (Xr[j_min] + 1.0), G_min, work[cum + j_min], curv, r1 + hw, hw)
    err_T = hw * tail_error(b1, b2, b3, b4, n, weighted, r_geom, floor_T)
    return total, hw * T, hw * W, hw * P, err_T, err_G, 0.5 * hw * sens, round_G, G_min, q_min


def quad(qa, qb, Ga, Gb, s, sigma, S, K, cp, R, work, mode, out, o, roots, count):
    """Time and friction work (per unit mass) of one interval, with an error estimate; in mode
    :data:`SAMPLES` the nodes' samples into ``out[o:]``, in mode :data:`PANELS` a row per
    accepted panel (columns :class:`PanelColumn`).

    ``R``: the rules and tolerances (:class:`~symvib.numeric.engine.state.Rules`; see
    :func:`symvib.numeric.driver.rules`); ``S``: the scene constants
    (:class:`~symvib.numeric.engine.state.Setup`); ``work``: the flat scratch array
    (:data:`WORK_ROWS` rows of the larger rule's nodes); ``roots, count``: the critical points known
    (:func:`~symvib.numeric.engine.scan.map_new`).  Returns ``(T, W_friction / m, err, flag, o, q_ok, G_ok, q_neg)``:
    the time, the friction work, the estimated error of the time (s), :data:`QUAD_OK`,
    :data:`QUAD_BUDGET` (a half needed more than :data:`MAX_PANELS` panels) or
    :data:`QUAD_NEGATIVE` (``G < 0`` at the node ``q_neg``, after ``G = G_ok > 0`` at
    ``q_ok``: a turning point lies between them), and the next free sample row.

    The steps (physics.md, "Time"): each half is anchored at its outer end
    (:func:`half_anchor`) and walked in panels of the quadrature variable from there
    (:func:`panel`); a panel whose error (:func:`panel_error`) exceeds its tolerance is
    halved, else accepted and recorded (:func:`record_panel`); where the halves meet, their
    disagreement on ``G`` is an error too (:func:`midpoint_error`).
    """
    scale = S.scale
    rtol, atol = R.rtol, R.atol
    L = abs(qb - qa)
    if L == 0.0:
        return 0.0, 0.0, 0.0, QUAD_OK, o, qa, Ga, qa
    half = 0.5 * L
    maxq = PANEL_Q * scale
    T = 0.0
    Wf = 0.0
    P = 0.0
    err = 0.0
    flag = QUAD_OK
    half_b = o
    G_mid_a = 0.0
    T_a = 0.0
    q_ok, G_ok, q_neg = qa, Ga, qa
    for kh in range(2):
        if kh == 1:
            half_b = o
        e, d, gd, Ge, root, delta, r_lo, r_hi, Gstart, tau0 = half_anchor(kh, qa, qb, Ga, Gb, s, sigma, half, S, K,
                                                                          cp, roots, count)
        T += tau0
        unsure = 4.0 * EPS * abs(Ge)  # the anchor's own rounding (0 on a root)
        path0 = 0.0
        work0 = 0.0
        sens_half = 0.0
        tries = 0
        accepted = 0
        seg_a = r_lo
        while True:
            if (not root) or r_lo < ROOT_GRADE * r_hi or 2.0 * seg_a >= r_hi:
                seg_b = r_hi
            else:
                seg_b = 2.0 * seg_a
            span = seg_b * seg_b - seg_a * seg_a if root else seg_b - seg_a
            parts = max(1, int(math.ceil(span / maxq)))
            step = (seg_b - seg_a) / parts
            r1 = seg_a
            width = step
            while r1 < seg_b:
                r2 = r1 + width
                if r2 >= seg_b or seg_b - r2 < 0.25 * width:
                    r2 = seg_b
                if root and r1 == 0.0:
                    dG, Tq, Wq, Pq, eT, eG, sens, rG, G_min, q_min = panel(
                        r1, r2, Gstart, e, d, gd, s, root, delta, S, K, cp, R.Xw, R.Ww, R.SWw, R.Tw, work, mode,
                        out, o, roots, count)
                else:
                    dG, Tq, Wq, Pq, eT, eG, sens, rG, G_min, q_min = panel(
                        r1, r2, Gstart, e, d, gd, s, root, delta, S, K, cp, R.Xp, R.Wp, R.Sp, R.Tp, work, mode,
                        out, o, roots, count)
                tries += 1
                tol, fixable, spread = panel_error(r1, r2, r_lo, r_hi, root, dG, Tq, eT, eG, sens, rG, unsure, rtol,
                                                   atol)
                narrow = (r2 - r1) <= MIN_PANEL_RTOL * max(abs(r1), abs(r2))
                if fixable > tol and not narrow and tries < MAX_TRIES and accepted < MAX_PANELS:
                    width = 0.5 * (r2 - r1)
                    continue
                if G_min < -NEGATIVE_MARGIN * (unsure + eG + rG) and flag == QUAD_OK:
                    # G < 0 at a node: the interval's end is past a turning point.
                    flag = QUAD_NEGATIVE
                    q_neg = q_min
                    if kh == 0:
                        x1 = max(r1 * r1 - delta, 0.0) if root else r1  # (a root before the anchor: 0)
                        q_ok, G_ok = e + d * x1, Gstart if x1 > 0.0 else Ge
                    else:
                        q_ok, G_ok = 0.5 * (qa + qb), G_mid_a
                    return T, Wf, err, flag, o, q_ok, G_ok, q_neg
                if fixable > tol:
                    flag = QUAD_BUDGET
                accepted += 1
                err += eT + spread
                unsure += eG + rG
                sens_half += sens
                o = record_panel(mode, out, o, kh, r1, r2, Gstart, dG, tau0, Tq, root, delta, path0, work0, R, work)
                tau0 += Tq
                path0 += Pq
                work0 += Wq
                T += Tq
                Wf += Wq
                P += Pq
                Gstart += dG
                width = min(2.0 * (r2 - r1), step)
                r1 = r2
            if seg_b >= r_hi:
                break
            seg_a = seg_b
        if kh == 0:
            G_mid_a = Gstart
            T_a = T
        else:
            err += midpoint_error(root, Gstart, G_mid_a, T, T_a, sens_half)
    if mode == SAMPLES:
        # The half anchored at qb was integrated from qb backwards.
        for j in range(half_b, o):
            out[j, C_T] = T - out[j, C_T]
            out[j, C_S] = P - out[j, C_S]
            out[j, C_PATH] = Wf - out[j, C_PATH]
    return T, Wf, err, flag, o, q_ok, G_ok, q_neg


def half_anchor(kh, qa, qb, Ga, Gb, s, sigma, half, S, K, cp, roots, count):
    """Where half ``kh`` of the interval ``[qa, qb]`` (0: from ``qa``, 1: from ``qb``) is anchored and
    in which variable it is integrated: ``(e, d, gd, Ge, root, delta, r_lo, r_hi, Gstart, tau0)``.

    The anchor ``e`` is the half's outer end, where ``G = Ge`` is known exactly; the half is walked
    in direction ``d`` from it, where ``G' = gd F_s'``.  Next to a (real or virtual) root of ``G``
    behind the anchor, at a distance ``delta`` (``G`` linear: ``Ge / gamma``), the variable is ``r =
    sqrt(xi + delta)`` (``root``), from ``r_lo`` to ``r_hi``; else ``r = xi`` from 0 to ``half``.  A
    root within :data:`VIRTUAL_ROOT_RTOL` (a turning point stopped on the double before it) is
    where the half starts instead, with ``G = Gstart = 0``, and the time of the stretch from it to
    the anchor, ``-tau0``, is taken away in closed form (:func:`tail_time`).
    """
    if kh == 0:
        e, d, Ge = qa, float(sigma), Ga
    else:
        e, d, Ge = qb, -float(sigma), Gb
    gd = -d * (2.0 * S.g)  # G' = gd F_s' along the half (d = +-1: gd F_s' is -2 g F_s' d exactly)
    gamma = gd * dF_best(s, e, 0.0, S, K, cp, roots, count)
    root = Ge == 0.0 or (gamma > 0.0 and Ge < ROOT_RATIO * gamma * half)
    Gstart = Ge
    tau0 = 0.0
    if root:
        delta = Ge / gamma if Ge > 0.0 else 0.0
        r_lo = math.sqrt(delta)
        r_hi = math.sqrt(delta + half)
        if 0.0 < delta <= VIRTUAL_ROOT_RTOL * S.scale:
            # G of rounding size (a turning point stopped on the double before it): the half
            # starts on the root itself with the weighted rule, and the time of the stretch from
            # the root to the anchor, where G is linear, is taken away in closed form.
            tau0 = -tail_time(e, Ge, s, S, K, cp, roots, count)
            r_lo = 0.0
            Gstart = 0.0
    else:
        delta = 0.0
        r_lo = 0.0
        r_hi = half
    return e, d, gd, Ge, root, delta, r_lo, r_hi, Gstart, tau0


def panel_error(r1, r2, r_lo, r_hi, root, dG, Tq, eT, eG, sens, rG, unsure, rtol, atol):
    """A panel's tolerance and errors (physics.md, "Accuracy"): ``(tol, fixable, spread)``.

    ``tol``: ``rtol`` of its time plus its share of ``atol``; ``fixable``: what halving it
    reduces, the truncation error of its time and the time's share of the truncation error of
    ``G``; ``spread``: the time's share of the uncertainty of ``G`` (the anchor's rounding and
    every increment's, ``unsure``, then this panel's), which halving does not reduce.
    """
    share = atol * (r2 - r1) / (r_hi - r_lo) if r_hi > r_lo else atol
    tol = rtol * Tq + share
    if root and r1 == 0.0:
        # From the root itself G is rebuilt as a multiple of the increment, so its errors
        # are relative: the time's is half of theirs (dT/T = -dG/(2G)).
        rel = 0.5 * Tq / abs(dG) if dG != 0.0 else 0.0
        return tol, eT + rel * eG, rel * (eG + rG)
    return tol, eT + sens * eG, sens * (unsure + eG + rG)


def record_panel(mode, out, o, kh, r1, r2, Gstart, dG, tau0, Tq, root, delta, path0, work0, R, work):
    """Write an accepted panel to ``out[o:]``: in mode :data:`PANELS` its row (columns
    :class:`PanelColumn`), in mode :data:`SAMPLES` the time, path and friction work from the
    half's anchor at its nodes (the same cumulative Gauss-Legendre integral as the interval's
    totals; :func:`panel` wrote the nodes' ``q, w, N``).  Returns the next free row."""
    if mode == PANELS:
        out[o, P_HALF], out[o, P_R1], out[o, P_R2] = kh, r1, r2
        out[o, P_G1], out[o, P_G2] = Gstart, Gstart + dG
        out[o, P_TAU1], out[o, P_TAU2] = tau0, tau0 + Tq
        out[o, P_ROOT], out[o, P_DELTA] = 1.0 if root else 0.0, delta
        return o + 1
    if mode == SAMPLES:
        weighted = root and r1 == 0.0
        St = R.Sw if weighted else R.Sp
        n = len(R.Xw) if weighted else len(R.Xp)
        hw = 0.5 * (r2 - r1)
        acc = W_ACC * n
        cumulate(St, work, W_FT * n, n, work, acc)
        for j in range(n):
            out[o + j, C_T] = tau0 + hw * work[acc + j]
        cumulate(St, work, W_FP * n, n, work, acc)
        for j in range(n):
            out[o + j, C_S] = path0 + hw * work[acc + j]  # (the path from the anchor, for now)
        cumulate(St, work, W_FW * n, n, work, acc)
        for j in range(n):
            out[o + j, C_PATH] = work0 + hw * work[acc + j]  # (the friction work, for now)
        return o + n
    return o


def midpoint_error(root, G_b, G_a, T, T_a, sens_half):
    """The error of the time from the halves' disagreement at the midpoint (``G_a`` from the first
    half, ``G_b`` from the second; ``T_a`` the time of the first, ``T`` of both): beyond their
    propagated uncertainties, it is an error of one of the anchors (or of the search).  Next to a
    root it moves the root (the time of the half scales as the root's distance, sqrt of ``G`` at
    the midpoint); elsewhere it is an offset of ``G`` over the half (``sens_half``: the half's
    ``dT/dG``)."""
    miss = abs(G_b - G_a)
    if root:
        G_mid = max(G_b, G_a)
        return 0.5 * (T - T_a) * miss / G_mid if G_mid > 0.0 else 0.0
    return sens_half * miss


def tail_time(q, G, s, S, K, cp, roots, count):
    """The time from ``q``, where ``G > 0`` is tiny, to the turning point just beyond it: ``2 h exp(s mu
    alpha) sqrt(G) / |G'|`` (``G`` linear over that stretch; ``G' = -2 g F_s'``).

    A turning point is stopped at on the last double before it
    (:func:`~symvib.numeric.engine.anchor.root_anchored`); where the motion is short (next to the
    cone edge, a bounce of 1e-13 at a limiter) the time over that last fraction of an ulp,
    ``2 sqrt(delta / |G'|)`` per unit of ``h exp(s mu alpha)``, is not negligible.
    """
    _, hh, ex, _, _ = node(s, q, S.mu, K, cp)
    slope = 2.0 * S.g * abs(dF_best(s, q, 0.0, S, K, cp, roots, count))
    return 2.0 * hh * ex * sqrt(G) / slope if slope > 0.0 else 0.0


def turn_departure(q, G, s, s_out, S, K, cp, roots, count):
    """``G`` of the branch ``s_out`` at ``q`` after a turning point a fraction of an ulp beyond it,
    where the branch ``s`` that arrived had ``G`` (both linear over that stretch): the particle
    passes ``q`` again with ``G_out = |G'_out| delta``, ``delta = G / |G'|`` (physics.md,
    "Accuracy").  The time from the turning point back to ``q`` is :func:`tail_time` of ``G_out``."""
    slope_in = abs(dF_best(s, q, 0.0, S, K, cp, roots, count))
    slope_out = abs(dF_best(s_out, q, 0.0, S, K, cp, roots, count))
    return G * slope_out / slope_in if slope_in > 0.0 else 0.0


def time_excess(x, p):
    """Time from the start of an interval to x, minus a target (for the t_max stop)."""
    q, Ga, C, s, sigma, S, K, cp, R, work, dummy, target, roots, count = p
    Gx = max(C - 2.0 * S.g * Fs(s, x, S.mu, K, cp), 0.0)
    T = quad(q, x, Ga, Gx, s, sigma, S, K, cp, R, work, NONE, dummy, 0, roots, count)[0]
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
    out[o, C_T], out[o, C_Q], out[o, C_W], out[o, C_N] = t, q, w, N
    out[o, C_S], out[o, C_PATH], out[o, C_WF], out[o, C_WIMP] = coord, path, Wf, Wimp
    out[o, C_BRANCH], out[o, C_SIGMA] = s, sigma
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
    work = scratch(1, WORK_ROWS * n)[0]
    g, k = S.g, S.k
    roots = np.empty((ROOT_ROWS, 1))  # no critical points known: F_s' from its kernel
    count = np.zeros(ROOT_ROWS, dtype=np.int64)
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
            Tq, Wq, _, _, o, _, _, _ = quad(q1, q2, G1, G2, s, sigma, S, K, cp, R, work, SAMPLES, out, o, roots, count)
            for j in range(start, o):
                # quad left the path and the friction work from the piece's start in the columns
                # s and path: now the arc-length coordinate, the path and the work since the start
                dp, dw = out[j, C_S], out[j, C_PATH]
                out[j, C_T] += tp
                out[j, C_S] = coord + sigma * dp
                out[j, C_PATH] = path + dp
                out[j, C_WF] = Wf + dw
                out[j, C_WIMP] = Wimp
                out[j, C_BRANCH], out[j, C_SIGMA] = s, sigma
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
