"""Where the next event is: the map of the curve and the search along the motion.

Within one motion interval the branch ``s`` is fixed and the phase trajectory
(physics.md, eq. 2) ``G(q) = C - 2 g F_s(q)`` holds in closed form.  Walking in
the direction of motion over pieces on which ``G`` is monotone (split where
``F_s' = 0``: the critical points, found by a lazy scan of a lattice of
``CRIT_STEP * q_scale``), the limiter ahead is hit iff ``G`` stays positive up
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

from symvib.numeric.engine.laws import Fs
from symvib.numeric.engine.roots import ROOT_MAXITER, illinois_point, illinois_update, root_G

__all__ = ["End", "Region", "scratch", "map_new", "locate", "CRIT_STEP", "WINDOW", "CHUNK", "DIP_ITER"]

#: Search window where no limiter bounds the motion, in units of q_scale.
WINDOW = 2.0
#: Spacing of the critical-point scan (F_s' = 0), in units of q_scale: a bump of the
#: curve narrower than this may hide a pair of critical points.
CRIT_STEP = 1 / 32
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
#: Initial capacity of the list of critical points per branch.
ROOTS_CAPACITY = 8


class End(enum.IntEnum):
    """How a motion interval found by :func:`locate` ends."""

    LIMIT = 0  # at a limiter: an impact
    TURN = 1  # at a root of G: a turning point
    NSIGN = 2  # at a zero of the normal force
    PASS = 3  # at the end of the search window: the motion goes on
    EDGE = 4  # at an end of the curve's regular domain


class Region(enum.IntEnum):
    """Entries of the scanned region of the lattice (a float array, mutated in place):
    its ends, ``z' +- mu x'`` at the ends, the part where ``N > 0`` surely (``kappa >= 0``
    and ``x' > 0``) and whether that part is still open at each end, the lattice
    indices of the ends, and the domain pulled :data:`EDGE_RTOL` inside its ends."""

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
    k_lo = 10
    k_hi = 11
    lo_in = 12
    hi_in = 13


#: Entries of the region array.
REGION_SIZE = len(Region)
#: The entries' indices as plain ints (numpy indexes faster with an int than with an IntEnum).
(X_LO, X_HI, FP_LO, FM_LO, FP_HI, FM_HI, SAFE_LO, SAFE_HI, SAFE_LO_OPEN, SAFE_HI_OPEN, K_LO, K_HI, LO_IN,
 HI_IN) = (int(r) for r in Region)


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


def map_new(q0, lo, hi, mu, K, cp, step):
    """The scanned region (:class:`Region`) and critical points at the start ``q0``."""
    region = scratch(1, REGION_SIZE)[0]
    lo_in = lo + EDGE_RTOL * max(1.0, abs(lo)) if math.isfinite(lo) else -math.inf
    hi_in = hi - EDGE_RTOL * max(1.0, abs(hi)) if math.isfinite(hi) else math.inf
    k0 = math.floor(q0 / step)
    x0 = min(max(k0 * step, lo_in), hi_in)
    region[X_LO] = x0
    region[X_HI] = x0
    zp, xp = K.dz(x0, *cp), K.dx(x0, *cp)
    region[FP_LO] = region[FP_HI] = zp + mu * xp
    region[FM_LO] = region[FM_HI] = zp - mu * xp
    safe = xp > 0.0 and K.kappa(x0, *cp) >= 0.0 and is_safe(q0, K, cp)
    region[SAFE_LO] = region[SAFE_HI] = x0
    region[SAFE_LO_OPEN] = region[SAFE_HI_OPEN] = 1.0 if safe else 0.0
    if not safe:
        region[SAFE_LO] = region[SAFE_HI] = q0
    region[K_LO] = region[K_HI] = k0
    region[LO_IN] = lo_in
    region[HI_IN] = hi_in
    roots = np.empty((2, ROOTS_CAPACITY))
    count = np.zeros(2, dtype=np.int64)
    if region[FP_LO] == 0.0:
        roots = add_root(roots, count, 0, x0)
    if region[FM_LO] == 0.0:
        roots = add_root(roots, count, 1, x0)
    return region, roots, count

def add_root(roots, count, b, r):
    """Append the critical point ``r`` of branch row ``b`` (grows the array when full)."""
    if count[b] == roots.shape[1]:
        new = np.empty((2, 2 * roots.shape[1]))
        for i in range(2):
            for j in range(roots.shape[1]):
                new[i, j] = roots[i, j]  # element by element: see timing.grown
        roots = new
    roots[b, count[b]] = r
    count[b] += 1
    return roots

def crossing(roots, count, row, x_old, x_new, f_old, f_new, mu, K, cp):
    """Record the root of F_s' between two scanned points where :func:`changes_sign`
    (at the new one, if exactly 0)."""
    if f_new == 0.0:
        return add_root(roots, count, row, x_new)
    s = 1 if row == 0 else -1
    return add_root(roots, count, row, root_crit((s, mu, K, cp), x_old, x_new, f_old, f_new))

def changes_sign(f_old, f_new):
    """Whether F_s' has a root between two scanned points with values f_old, f_new (or at the
    new one): a root at the old one is recorded already."""
    return f_new == 0.0 or (f_old != 0.0 and (f_old > 0.0) != (f_new > 0.0))

def map_extend(region, roots, count, target, mu, K, cp, step):
    """Scan the lattice outward until target is covered (or the domain ends)."""
    if target > region[X_HI]:
        return extend_side(region, roots, count, target, mu, K, cp, step, 1.0)
    if target < region[X_LO]:
        return extend_side(region, roots, count, target, mu, K, cp, step, -1.0)
    return roots

def extend_side(region, roots, count, target, mu, K, cp, step, up):
    """Scan the lattice up (``up = 1``) or down (``up = -1``) until target is covered (or the domain ends)."""
    if up > 0.0:
        ix, ifp, ifm, isafe, iopen, ik, iedge = X_HI, FP_HI, FM_HI, SAFE_HI, SAFE_HI_OPEN, K_HI, HI_IN
    else:
        ix, ifp, ifm, isafe, iopen, ik, iedge = X_LO, FP_LO, FM_LO, SAFE_LO, SAFE_LO_OPEN, K_LO, LO_IN
    x_old, edge = region[ix], region[iedge]
    fp_old, fm_old, k, safe_open = region[ifp], region[ifm], region[ik], region[iopen] != 0.0
    while (target - x_old) * up > 0.0 and (x_old - edge) * up < 0.0:
        k += up
        x = k * step
        if (x - edge) * up > 0.0:
            x = edge
        zp, xp = K.dz(x, *cp), K.dx(x, *cp)
        fp, fm = zp + mu * xp, zp - mu * xp
        if not (fp * fp_old > 0.0 and fm * fm_old > 0.0):
            # Both signs kept (the common case) records nothing: else a closer look.
            if changes_sign(fp_old, fp):
                roots = crossing(roots, count, 0, x_old, x, fp_old, fp, mu, K, cp)
            if changes_sign(fm_old, fm):
                roots = crossing(roots, count, 1, x_old, x, fm_old, fm, mu, K, cp)
        if safe_open:
            if xp > 0.0 and K.kappa(x, *cp) >= 0.0:
                region[isafe] = x
            else:
                safe_open = False
        x_old, fp_old, fm_old = x, fp, fm
    region[ix], region[ifp], region[ifm], region[ik] = x_old, fp_old, fm_old, k
    region[iopen] = 1.0 if safe_open else 0.0
    return roots

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

def locate(q, sigma, s, Ga, S, K, cp, region, roots, count, X):
    """The end of the motion interval that starts at ``q`` moving ``sigma`` on branch ``s``
    with ``G(q) = Ga``, for the scene constants ``S`` (:class:`~symvib.numeric.engine.state.Setup`).

    Returns ``(end, qe, Ge, roots)``: how it ends (:class:`End`), where, ``G`` there,
    and the (possibly grown) array of critical points.  ``X`` are the Gauss nodes at
    which the normal force is scanned where it may change sign.
    """
    g, mu, left, right, lo, hi, scale = S.g, S.mu, S.left, S.right, S.lo, S.hi, S.scale
    has_left, has_right = S.has_left, S.has_right
    g2 = 2.0 * g
    step = CRIT_STEP * scale
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
    a, Gq = q, Ga
    qe, Ge, kind_out = bound, 0.0, kind
    while True:
        # Scan at most CHUNK lattice steps ahead of a; between a and the scanned edge
        # the known critical points are all there are, so G is monotone between them.
        ahead = a + sigma * CHUNK * step
        target = min(ahead, bound) if sigma > 0 else max(ahead, bound)
        roots = map_extend(region, roots, count, target, mu, K, cp, step)
        edge = min(region[X_HI], bound) if sigma > 0 else max(region[X_LO], bound)
        c = next_crit(roots, count, s, a, edge, sigma)
        b = edge if math.isnan(c) else c
        if b == a:
            b = bound  # the domain ends here: nothing left to scan
        Gb = C - g2 * Fs(s, b, mu, K, cp)
        if math.isnan(Gb):
            Gb = -math.inf
        if Gb <= 0.0:
            # A non-finite G at a domain end stands in as -1 (the finder bisects there).
            qe = root_G(s, C, a, b, Gq, Gb if math.isfinite(Gb) else -1.0, g2, mu, K, cp)
            Ge, kind_out = 0.0, End.TURN
            break
        if b == bound:
            qe, Ge, kind_out = bound, Gb, kind
            break
        a, Gq = b, Gb
    # An earlier zero of N on [q, qe] ends the interval there instead.
    safe_lo = region[SAFE_LO]
    safe_hi = region[SAFE_HI]
    if safe_lo <= min(q, qe) and max(q, qe) <= safe_hi:
        return kind_out, qe, Ge, roots
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
            return End.NSIGN, r, C - g2 * Fs(s, r, mu, K, cp), roots
        if j > 0 and fprev <= fbefore and fprev <= fx:
            xd, fd = dip_below(pn, before, x)
            if not math.isnan(xd):
                r = root_normal(pn, before, xd, fbefore, fd)
                return End.NSIGN, r, C - g2 * Fs(s, r, mu, K, cp), roots
        before, fbefore = prev, max(fprev, N_FLOOR)
        prev, fprev = x, fx
    return kind_out, qe, Ge, roots

