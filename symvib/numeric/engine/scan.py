"""Where the next event is: the map of the curve and the search along the motion.

Within one motion interval the branch ``s`` is fixed and the phase trajectory
(physics.md, eq. 2) ``G(q) = C - 2 g F_s(q)`` holds in closed form.  Walking in
the direction of motion over pieces on which ``G`` is monotone (split where
``F_s' = 0``: the critical points, found by a lazy scan in steps over which the
tangent turns by at most ``CRIT_TURN``, and at most ``CRIT_STEP`` of the curve's
length scale, :func:`curve_scale`), the limiter ahead is hit iff ``G`` stays positive up
to it; otherwise the first root of ``G`` is the turning point.  Where the normal
force may change sign (outside the region where ``kappa >= 0`` and ``x' > 0``),
its first zero ends the interval first (:func:`locate`).

Examples
--------
>>> End.TURN.name, Region.safe_hi.value
('TURN', 7)
"""
from __future__ import annotations

import enum
import math

import numpy as np

from symvib.numeric.engine.anchor import anchored_G, root_anchored
from symvib.numeric.engine.laws import EPS, Fs
from symvib.numeric.engine.roots import ROOT_MAXITER, illinois_point, illinois_update, root_G

__all__ = ["End", "Region", "scratch", "map_new", "map_arrays", "map_start", "room", "grown_roots", "locate",
           "curve_scale", "branch_cut", "next_cut", "turn_angle", "CRIT_STEP", "CRIT_TURN", "WINDOW", "CHUNK",
           "DIP_ITER", "SCALE_POINTS", "SCALE_TURN"]

#: Search window where no limiter bounds the motion, in units of q_scale.
WINDOW = 2.0
#: Longest step of the critical-point scan (F_s' = 0), in units of q_scale.
CRIT_STEP = 1 / 32
#: Largest turn of the tangent between two points of the scan (rad): F_s' changes sign where the
#: tangent crosses the cone edge, so a pair of critical points hides between two scan points only
#: where the tangent overshoots the edge by less than about this.
CRIT_TURN = 1 / 32
#: Lattice steps scanned ahead of the particle at a time.
CHUNK = 16
#: Golden-section steps of the search for a dip of the normal force below 0 around a local
#: minimum of its scanned values (the bracket shrinks to 0.618**40 = 4e-9 of two node spacings).
DIP_ITER = 40
#: The golden ratio's conjugate, (sqrt(5) - 1) / 2.
GOLDEN = 0.6180339887498949
#: Distance, relative to max(1, |end|), kept inside a finite domain end by the scan.
EDGE_RTOL = 1e-12
#: Stand-in for a positive value of N that is 0 at the start of an interval.
N_FLOOR = 1e-300
#: Points at which :func:`curve_scale` samples how fast the tangent turns.
SCALE_POINTS = 9
#: The run's length scale is at most the distance in q over which the tangent turns by this (rad).
SCALE_TURN = 1.0
#: Initial capacity of the list of critical points per branch.  The scan never grows the array: it
#: stops where a row is full and says so (:func:`room`, ``End.ROOM``), and the one function that owns
#: the array (the run) grows it (:func:`grown_roots`); so no function of the scan allocates or returns
#: an array, and they run without reference counts (:data:`symvib.numeric.engine.bind.NO_REFCOUNT`).
ROOTS_CAPACITY = 8
#: Rows of the array of special points: the critical points of the branches s = +1 and s = -1,
#: and the branch cuts of the tangent angle (:data:`CUT_ROW`).
ROOT_ROWS = 3
#: The row of the points where the kernels' tangent angle jumps by 2 pi (``atan2`` of a parametric
#: curve whose tangent points along -x): each is stored as the last double before the jump.
CUT_ROW = 2
#: Bisection steps that bring a branch cut's bracket down to two neighbouring doubles.
CUT_BISECT = 80
#: The closed form ``G = C - 2 g F_s`` is trusted at a turning point or an interval's end while
#: its rounding, ``NOISE_ROUNDS eps (|C| + 2 g |F_s|)``, is below ``CANCEL_RTOL`` of the ``G`` that
#: decides there (the bracket's start, the end's value); else the interval is searched again
#: with ``G`` carried from its start (:func:`symvib.numeric.engine.anchor.anchored_G`).
CANCEL_RTOL = 1e-11
NOISE_ROUNDS = 8.0


class End(enum.IntEnum):
    """How a motion interval found by :func:`locate` ends."""

    LIMIT = 0  # at a limiter: an impact
    TURN = 1  # at a root of G: a turning point
    NSIGN = 2  # at a zero of the normal force
    PASS = 3  # at the end of the search window: the motion goes on
    EDGE = 4  # at an end of the curve's regular domain
    CUT = 5  # at a branch cut of the tangent angle: the motion goes on from the other side
    ROOM = 6  # not found: the array of special points is full (grow it, :func:`grown_roots`, and locate again)


class Region(enum.IntEnum):
    """Entries of the scanned region (a float array, mutated in place): its ends, ``z' +- mu x'``
    at the ends, the part where ``N > 0`` surely (``kappa >= 0`` and ``x' > 0``) and whether that
    part is still open at each end, the tangent's turning rate over the last step at each end, the
    domain pulled :data:`EDGE_RTOL` inside its ends, and ``x'`` at the ends."""

    x_lo = 0
    x_hi = 1
    fp_lo = 2
    fm_lo = 3
    fp_hi = 4
    fm_hi = 5
    safe_lo = 6
    safe_hi = 7
    safe_lo_open = 8
    safe_hi_open = 9
    turn_lo = 10
    turn_hi = 11
    lo_in = 12
    hi_in = 13
    dx_lo = 14
    dx_hi = 15


#: Entries of the region array.
REGION_SIZE = len(Region)
#: The entries' indices as plain ints (numpy indexes faster with an int than with an IntEnum).
(X_LO, X_HI, FP_LO, FM_LO, FP_HI, FM_HI, SAFE_LO, SAFE_HI, SAFE_LO_OPEN, SAFE_HI_OPEN, TURN_LO, TURN_HI, LO_IN,
 HI_IN, DX_LO, DX_HI) = (int(r) for r in Region)


def crit_f(x, p):
    """z' + s mu x' at x, p = (s, mu, K, cp): the sign of F_s' = exp(2 s mu alpha) (z' + s mu x')."""
    s, mu, K, cp = p
    return K.dz(x, *cp) + s * mu * K.dx(x, *cp)


def root_crit(p, a, b, fa, fb):
    """Root of crit_f between a and b (values fa, fb of opposite signs)."""
    if fa == 0.0:
        return a
    for _ in range(ROOT_MAXITER):
        x = illinois_point(a, b, fa, fb)
        a, b, fa, fb, done = illinois_update(a, b, fa, fb, x, crit_f(x, p))
        if done:
            break
    return b


def root_normal(p, a, b, fa, fb):
    """Root of normal_on between a and b (values fa, fb of opposite signs)."""
    for _ in range(ROOT_MAXITER):
        x = illinois_point(a, b, fa, fb)
        a, b, fa, fb, done = illinois_update(a, b, fa, fb, x, normal_on(x, p))
        if done:
            break
    return b


def is_safe(x, K, cp):
    """Whether ``N > 0`` surely at ``x`` for ``w >= 0``: ``kappa >= 0`` and ``x' > 0``."""
    return K.kappa(x, *cp) >= 0.0 and K.dx(x, *cp) > 0.0

def scratch(rows, n):
    """``rows`` scratch rows of ``n`` floats (the plain-Python engine takes lists:
    :func:`symvib.numeric.engine.plain.scratch`)."""
    return np.empty((rows, n))


def curve_scale(K, cp, q0, lo, hi, has_left, left, has_right, right, hint):
    """The length scale of a run, in units of ``q``: the curve's declared ``q_scale`` (``hint``) at
    most, and no more than the distance over which the tangent turns by :data:`SCALE_TURN` rad
    anywhere on the stretch the run can reach first (between the limiters, or
    ``WINDOW`` hints around ``q0``; sampled at :data:`SCALE_POINTS` points), nor the limiters' span.

    The quadrature panels, the search window, the scan's longest step and the reach of
    the cone-edge expansion are fractions of it, so a curve of any size is resolved alike
    (physics.md, "Accuracy").
    """
    a = left if has_left else q0 - WINDOW * hint
    b = right if has_right else q0 + WINDOW * hint
    a = max(a, lo + EDGE_RTOL * max(1.0, abs(lo)))
    b = min(b, hi - EDGE_RTOL * max(1.0, abs(hi)))
    scale = hint
    if has_left and has_right and right > left:
        scale = min(scale, right - left)
    if not b > a:
        return scale
    turn = 0.0
    for i in range(SCALE_POINTS):
        turn = max(turn, turn_rate(a + (b - a) * (i + 0.5) / SCALE_POINTS, K, cp))
    if turn * scale > SCALE_TURN:
        scale = SCALE_TURN / turn
    return scale


def turn_rate(x, K, cp):
    """``|alpha'(x)| = |kappa h|``: how fast the tangent turns per unit of ``q`` (0 where not finite)."""
    r = abs(K.kappa(x, *cp) * K.h(x, *cp))
    return r if math.isfinite(r) else 0.0


def scan_step(turn, step):
    """The next scan step from a point where the tangent turns at ``turn``: at most ``step``, and
    short enough that the tangent turns by at most :data:`CRIT_TURN` (physics.md, "Accuracy")."""
    return step if turn * step <= CRIT_TURN else CRIT_TURN / turn


def map_new(q0, lo, hi, mu, K, cp, step):
    """The scanned region (:class:`Region`) and critical points at the start ``q0`` (scan steps at
    most ``step``, :func:`scan_step`): ``(region, roots, count)``."""
    region, roots, count = map_arrays()
    map_start(region, roots, count, q0, lo, hi, mu, K, cp, step)
    return region, roots, count


def map_arrays():
    """Arrays for a scanned region and its critical points, ``(region, roots, count)``, to be set by
    :func:`map_start` (a sweep reuses them from scene to scene)."""
    return scratch(1, REGION_SIZE)[0], np.empty((ROOT_ROWS, ROOTS_CAPACITY)), np.zeros(ROOT_ROWS, dtype=np.int64)


def map_start(region, roots, count, q0, lo, hi, mu, K, cp, step):
    """Set ``region``, ``roots`` and ``count`` (:func:`map_arrays`) to the scanned region and critical
    points at the start ``q0`` (:func:`map_new`)."""
    lo_in = lo + EDGE_RTOL * max(1.0, abs(lo)) if math.isfinite(lo) else -math.inf
    hi_in = hi - EDGE_RTOL * max(1.0, abs(hi)) if math.isfinite(hi) else math.inf
    x0 = min(max(q0, lo_in), hi_in)
    region[X_LO] = x0
    region[X_HI] = x0
    zp, xp = K.dz(x0, *cp), K.dx(x0, *cp)
    region[FP_LO] = region[FP_HI] = zp + mu * xp
    region[FM_LO] = region[FM_HI] = zp - mu * xp
    safe = is_safe(x0, K, cp) and is_safe(q0, K, cp)
    region[SAFE_LO] = region[SAFE_HI] = x0
    region[SAFE_LO_OPEN] = region[SAFE_HI_OPEN] = 1.0 if safe else 0.0
    if not safe:
        region[SAFE_LO] = region[SAFE_HI] = q0
    region[TURN_LO] = region[TURN_HI] = 0.0
    region[DX_LO] = region[DX_HI] = xp
    region[LO_IN] = lo_in
    region[HI_IN] = hi_in
    for b in range(ROOT_ROWS):
        count[b] = 0
    if region[FP_LO] == 0.0:
        add_root(roots, count, 0, x0)
    if region[FM_LO] == 0.0:
        add_root(roots, count, 1, x0)


def room(roots, count):
    """Whether every row of the special points has a free place (a scan step adds at most one a row)."""
    for b in range(ROOT_ROWS):
        if count[b] >= roots.shape[1]:
            return False
    return True


def grown_roots(roots, count):
    """The special points in an array of twice the capacity (the scan stopped where a row was full)."""
    new = np.empty((ROOT_ROWS, 2 * roots.shape[1]))
    for i in range(ROOT_ROWS):
        for j in range(count[i]):
            new[i, j] = roots[i, j]  # element by element: see timing.grown
    return new


def add_root(roots, count, b, r):
    """Append the critical point ``r`` of branch row ``b`` (the scan makes :func:`room` first)."""
    if count[b] < roots.shape[1]:
        roots[b, count[b]] = r
        count[b] += 1

def crossing(roots, count, row, x_old, x_new, f_old, f_new, mu, K, cp):
    """Record the root of F_s' between two scanned points where :func:`changes_sign`
    (at the new one, if exactly 0)."""
    if f_new == 0.0:
        add_root(roots, count, row, x_new)
    else:
        s = 1 if row == 0 else -1
        add_root(roots, count, row, root_crit((s, mu, K, cp), x_old, x_new, f_old, f_new))

def changes_sign(f_old, f_new):
    """Whether F_s' has a root between two scanned points with values f_old, f_new (or at the
    new one): a root at the old one is recorded already."""
    return f_new == 0.0 or (f_old != 0.0 and (f_old > 0.0) != (f_new > 0.0))

def map_extend(region, roots, count, target, mu, K, cp, step):
    """Scan outward until target is covered (or the domain ends, or a row of ``roots`` is full:
    then not :func:`room`)."""
    if target > region[X_HI]:
        extend_side(region, roots, count, target, mu, K, cp, step, 1.0)
    elif target < region[X_LO]:
        extend_side(region, roots, count, target, mu, K, cp, step, -1.0)

def turn_angle(cross, dot):
    """The angle between two tangents from their cross and dot products, ``|atan2(cross, dot)|``; where
    it is at most 45 degrees (the scan's steps turn by about :data:`CRIT_TURN`) its tangent
    ``|cross| / dot`` instead, which exceeds it by a factor of about ``1 + theta^2 / 3`` (at most
    ``4 / pi``): the scan's steps come out shorter by that, never longer, and ``atan2`` had been
    2 % of a sweep's time.

    >>> round(turn_angle(1 / 32, 1.0) / math.atan(1 / 32) - 1, 6), turn_angle(1.0, -1.0), turn_angle(0.0, 0.0)
    (0.000325, 2.356194490192345, 0.0)
    """
    if 0.0 < dot < math.inf and abs(cross) <= dot:
        return abs(cross) / dot
    return abs(math.atan2(cross, dot))


def extend_side(region, roots, count, target, mu, K, cp, step, up):
    """Scan up (``up = 1``) or down (``up = -1``) until target is covered (or the domain ends), in
    steps over which the tangent turns by at most about :data:`CRIT_TURN` (:func:`scan_step`, the
    rate of the step before; a step that turned more than twice that is taken again, shorter).

    The turn of a step is the angle between the tangents ``(x', z')`` at its ends; where the
    tangent passes through ``-x`` the kernels' ``alpha`` may jump (:func:`branch_cut`)."""
    if up > 0.0:
        ix, ifp, ifm, isafe, iopen, iturn, iedge, idx = X_HI, FP_HI, FM_HI, SAFE_HI, SAFE_HI_OPEN, TURN_HI, HI_IN, \
            DX_HI
    else:
        ix, ifp, ifm, isafe, iopen, iturn, iedge, idx = X_LO, FP_LO, FM_LO, SAFE_LO, SAFE_LO_OPEN, TURN_LO, LO_IN, \
            DX_LO
    x_old, edge, xp_old = region[ix], region[iedge], region[idx]
    fp_old, fm_old, turn, safe_open = region[ifp], region[ifm], region[iturn], region[iopen] != 0.0
    zp_old = 0.5 * (fp_old + fm_old)
    while (target - x_old) * up > 0.0 and (x_old - edge) * up < 0.0 and room(roots, count):
        h = scan_step(turn, step)
        while True:
            x = x_old + up * h
            if (x - edge) * up > 0.0:
                x = edge
            zp, xp = K.dz(x, *cp), K.dx(x, *cp)
            turned = turn_angle(xp_old * zp - zp_old * xp, xp_old * xp + zp_old * zp)
            dx = abs(x - x_old)
            turn = turned / dx if math.isfinite(turned) and dx > 0.0 else 0.0
            if turned <= 2.0 * CRIT_TURN or dx <= EDGE_RTOL * max(1.0, abs(x)) or turn == 0.0:
                break
            h = CRIT_TURN / turn
        fp, fm = zp + mu * xp, zp - mu * xp
        if not (fp * fp_old > 0.0 and fm * fm_old > 0.0):
            # Both signs kept (the common case) records nothing: else a closer look.
            if changes_sign(fp_old, fp):
                crossing(roots, count, 0, x_old, x, fp_old, fp, mu, K, cp)
            if changes_sign(fm_old, fm):
                crossing(roots, count, 1, x_old, x, fm_old, fm, mu, K, cp)
        if xp < 0.0 and zp * zp_old <= 0.0:
            # z' changed sign with the tangent along -x: where atan2's angle jumps, if it does.
            branch_cut(roots, count, min(x_old, x), max(x_old, x), K, cp)
        if safe_open:
            if xp > 0.0 and K.kappa(x, *cp) >= 0.0:
                region[isafe] = x
            else:
                safe_open = False
        x_old, fp_old, fm_old, xp_old, zp_old = x, fp, fm, xp, zp
    region[ix], region[ifp], region[ifm], region[iturn], region[idx] = x_old, fp_old, fm_old, turn, xp_old
    region[iopen] = 1.0 if safe_open else 0.0

def branch_cut(roots, count, a, b, K, cp):
    """Record where the kernels' tangent angle jumps by more than pi between ``a < b`` (if it does),
    as the last double before the jump (bisection on ``alpha`` down to neighbouring doubles).

    A parametric curve's ``alpha = atan2(z', x')`` jumps by ``2 pi`` where its tangent turns
    through ``-x``; the factor ``exp(2 s mu alpha)`` of eq. 2 must not, so a motion interval
    ends there and the next begins on the other side (physics.md, "Accuracy").
    """
    fa, fb = K.alpha(a, *cp), K.alpha(b, *cp)
    if not abs(fb - fa) > math.pi:
        return
    for _ in range(CUT_BISECT):
        m = 0.0 if a < 0.0 < b else 0.5 * (a + b)
        if not a < m < b:
            break
        fm = K.alpha(m, *cp)
        if abs(fm - fa) > math.pi:
            b, fb = m, fm
        else:
            a, fa = m, fm
    if b == 0.0 or a == 0.0:
        # A jump at q = 0 (a loop's lowest point): halving only approaches it, over a thousand binades.
        below = np.nextafter(0.0, -1.0)
        a = below if abs(K.alpha(below, *cp) - K.alpha(0.0, *cp)) > math.pi else 0.0
    for i in range(count[CUT_ROW]):
        if roots[CUT_ROW, i] == a:
            return
    add_root(roots, count, CUT_ROW, a)


def next_cut(roots, count, a, b, sigma):
    """The nearest branch cut strictly between ``a`` and ``b`` in direction ``sigma`` (nan if none):
    the double the motion stops at before the jump (the stored one moving up, the next one down)."""
    best = math.nan
    for i in range(count[CUT_ROW]):
        c = roots[CUT_ROW, i]
        if sigma < 0:
            # (+ 0.0: -0.0 is +0.0; the kernels' atan2 takes the sign of a zero z' for a branch)
            c = np.nextafter(c, math.inf) + 0.0
        if (a < c < b or b < c < a) and (math.isnan(best) or abs(c - a) < abs(best - a)):
            best = c
    return best


def next_crit(roots, count, s, a, b, sigma):
    """The known critical point of branch s nearest a strictly between a and b (nan if none)."""
    row = 0 if s > 0 else 1
    best = math.nan
    for i in range(count[row]):
        r = roots[row, i]
        if sigma > 0:
            if a < r < b and (math.isnan(best) or r < best):
                best = r
        else:
            if b < r < a and (math.isnan(best) or r > best):
                best = r
    return best

def normal_on(x, p):
    """The normal force per unit mass at x on the current branch, times its expected sign.

    p = (s, C, nsgn, g, g2, mu, K, cp).
    """
    s, C, nsgn, g, g2, mu, K, cp = p
    G = C - g2 * Fs(s, x, mu, K, cp)
    w = math.exp(-2.0 * s * mu * K.alpha(x, *cp)) * max(G, 0.0)
    return nsgn * K.N_w(x, w, g, *cp)

def dip_below(pn, a, b):
    """A point of (a, b) where normal_on < 0, by a golden-section search for a minimum (nan if none)."""
    c = b - GOLDEN * (b - a)
    d = a + GOLDEN * (b - a)
    fc = normal_on(c, pn)
    fd = normal_on(d, pn)
    for _ in range(DIP_ITER):
        if fc < 0.0:
            return c, fc
        if fd < 0.0:
            return d, fd
        if fc < fd:
            b, d, fd = d, c, fc
            c = b - GOLDEN * (b - a)
            fc = normal_on(c, pn)
        else:
            a, c, fc = c, d, fd
            d = a + GOLDEN * (b - a)
            fd = normal_on(d, pn)
    return math.nan, 0.0

def walk(q, sigma, s, Ga, C, bound, kind, S, K, cp, region, roots, count, Xa, Wa):
    """Walk from ``q`` towards ``bound`` over the pieces on which ``G`` is monotone: the first
    root of ``G`` (a turning point), else ``bound`` (of ``kind``).  Returns ``(qe, Ge, kind)``; kind
    ``End.ROOM`` (at ``q``) when the special points filled their array first.

    ``G`` at the pieces' ends is the closed form ``C - 2 g F_s``, until its rounding is too
    large for the ``G`` that decides a turning point or the end (:data:`CANCEL_RTOL`):
    from there on it is carried from ``q``, where it is exact
    (:func:`~symvib.numeric.engine.anchor.anchored_G`), and a turning point is found on
    that form (:func:`~symvib.numeric.engine.anchor.root_anchored`).
    """
    g2 = 2.0 * S.g
    mu = S.mu
    step = CRIT_STEP * S.scale
    a, Gq = q, Ga
    anchored = False
    while True:
        # Scan at most CHUNK longest steps ahead of a; between a and the scanned edge
        # the known critical points are all there are, so G is monotone between them.
        ahead = a + sigma * CHUNK * step
        target = min(ahead, bound) if sigma > 0 else max(ahead, bound)
        map_extend(region, roots, count, target, mu, K, cp, step)
        if not room(roots, count):
            return q, Ga, End.ROOM
        edge = min(region[X_HI], bound) if sigma > 0 else max(region[X_LO], bound)
        cut = next_cut(roots, count, a, edge, sigma)
        if not math.isnan(cut):
            bound, kind, edge = cut, End.CUT, cut
        c = next_crit(roots, count, s, a, edge, sigma)
        b = edge if math.isnan(c) else c
        if b == a:
            b = bound  # the domain ends here: nothing left to scan
        if anchored:
            Gb = anchored_G(b, a, Gq, s, S, K, cp, Xa, Wa, roots, count)
        else:
            Fb = Fs(s, b, mu, K, cp)
            Gb = C - g2 * Fb
            if (Gb <= 0.0 or b == bound) and NOISE_ROUNDS * EPS * (abs(C) + g2 * abs(Fb)) > CANCEL_RTOL * max(Gq, Gb):
                anchored = True
                if a != q:
                    Gq = anchored_G(a, q, Ga, s, S, K, cp, Xa, Wa, roots, count)
                Gb = anchored_G(b, a, Gq, s, S, K, cp, Xa, Wa, roots, count)
        if math.isnan(Gb):
            Gb = -math.inf
        if Gb <= 0.0:
            # A non-finite G at a domain end stands in as -1 (the finder bisects there).
            Gb = Gb if math.isfinite(Gb) else -1.0
            if not anchored:
                return root_G(s, C, a, b, Gq, Gb, g2, mu, K, cp), 0.0, End.TURN
            if Gq <= 0.0:
                return a, 0.0, End.TURN
            # The closed form's root, then the anchored form's from there.
            Fa = C - g2 * Fs(s, a, mu, K, cp)
            Fb = C - g2 * Fs(s, b, mu, K, cp)
            x = root_G(s, C, a, b, Fa, Fb, g2, mu, K, cp) if Fa > 0.0 >= Fb else math.nan
            qe, Ge = root_anchored(a, Gq, b, Gb, x, s, S, K, cp, Xa, Wa, roots, count)
            return qe, Ge, End.TURN
        if b == bound:
            return bound, Gb, kind
        a, Gq = b, Gb

def locate(q, sigma, s, Ga, S, K, cp, region, roots, count, X, Xa, Wa):
    """The end of the motion interval that starts at ``q`` moving ``sigma`` on branch ``s``
    with ``G(q) = Ga``, for the scene constants ``S`` (:class:`~symvib.numeric.engine.state.Setup`).

    Returns ``(end, qe, Ge)``: how it ends (:class:`End`), where, and ``G`` there; ``End.ROOM``
    when the array of special points ``roots`` is full (:func:`grown_roots`, then locate again).
    The normal force is scanned at the nodes ``X`` (``Rules.Xw``) where it may change sign, and
    ``G`` carried from the start with the rule ``Xa, Wa`` (``Rules.Xp, Rules.Wp``) where the
    closed form cancels (:data:`CANCEL_RTOL`).
    """
    g, mu, left, right, lo, hi, scale = S.g, S.mu, S.left, S.right, S.lo, S.hi, S.scale
    has_left, has_right = S.has_left, S.has_right
    g2 = 2.0 * g
    C = Ga + g2 * Fs(s, q, mu, K, cp)
    if sigma > 0 and has_right:
        bound, kind = right, End.LIMIT
    elif sigma < 0 and has_left:
        bound, kind = left, End.LIMIT
    else:
        edge = hi if sigma > 0 else lo
        window = q + sigma * WINDOW * scale
        if math.isfinite(edge) and (edge - window) * sigma <= 0.0:
            bound, kind = edge, End.EDGE
        else:
            bound, kind = window, End.PASS
    qe, Ge, kind_out = walk(q, sigma, s, Ga, C, bound, kind, S, K, cp, region, roots, count, Xa, Wa)
    if kind_out == End.ROOM:
        return kind_out, qe, Ge
    # An earlier zero of N on [q, qe] ends the interval there instead.
    safe_lo = region[SAFE_LO]
    safe_hi = region[SAFE_HI]
    if safe_lo <= min(q, qe) and max(q, qe) <= safe_hi:
        return kind_out, qe, Ge
    # N is scanned at the Gauss nodes and at qe (its sign can change after the last node);
    # around a local minimum of the scanned values a golden-section search looks for a
    # dip below 0 between nodes.  The start counts as positive (N may be 0 there, just
    # after a sign change).
    nsgn = 1.0 if s * sigma > 0 else -1.0
    pn = (s, C, nsgn, g, g2, mu, K, cp)
    before, fbefore = q, max(normal_on(q, pn), N_FLOOR)
    prev, fprev = q, N_FLOOR
    n = len(X)
    for j in range(n + 1):
        x = q + (qe - q) * 0.5 * (X[j] + 1.0) if j < n else qe
        fx = normal_on(x, pn)
        if fx < 0.0:
            r = root_normal(pn, prev, x, fprev, fx)
            return End.NSIGN, r, C - g2 * Fs(s, r, mu, K, cp)
        if j > 0 and fprev <= fbefore and fprev <= fx:
            xd, fd = dip_below(pn, before, x)
            if not math.isnan(xd):
                r = root_normal(pn, before, xd, fbefore, fd)
                return End.NSIGN, r, C - g2 * Fs(s, r, mu, K, cp)
        before, fbefore = prev, max(fprev, N_FLOOR)
        prev, fprev = x, fx
    return kind_out, qe, Ge

