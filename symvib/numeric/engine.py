"""The scalar core of the event-driven driver, written once for two engines.

Every function here uses only floats, small NumPy arrays and the generated
``*_scalar`` kernels, which it calls by their names (``F_p_scalar``,
``node_p_scalar``, ...).  :func:`symvib.numeric.driver.engine` appends this source to a
curve's generated kernel module, so the names resolve there, and runs the
whole as plain Python or, when the optional ``numba`` package is installed
(extra ``fast``), compiled by ``numba.njit(cache=True)`` (the combined file
lives in the kernel cache folder, so the compilation is reused by later
processes).  The algorithm is documented in :mod:`symvib.numeric.driver`; the numbers
of this module are its knobs.

Codes (integers, so that compiled code can return them):

* events: ``IMPACT, REVERSAL, ARREST, REST_ON_LIMITER, NORMAL_SIGN_CHANGE, LEFT_CURVE``;
* status: ``RUNNING, ARRESTED, RESTING, T_MAX, MAX_EVENTS, LEFT_DOMAIN, NON_FINITE,
  BUDGET_MISMATCH, LEFT_CURVE``.  The engine itself ends a run with ``NON_FINITE`` as soon
  as its state stops being finite; ``BUDGET_MISMATCH`` is set after the run by
  :func:`symvib.numeric.driver.checked_status` (the codes :data:`ERROR_CODES` are failures).
"""
import math

import numpy as np

__all__ = ["EVENT_NAMES", "STATUS_NAMES", "ERROR_CODES", "simulate", "samples", "sweep", "SUMMARY", "SCALARS"]

try:
    jit  # noqa: B018 - set by the combined engine module before this source
except NameError:  # imported on its own: plain Python

    def jit(fn):
        return fn

    pjit = jit
    prange = range

    def cp_tuple(row):
        return tuple(row)

IMPACT, REVERSAL, ARREST, REST_ON_LIMITER, NORMAL_SIGN_CHANGE = 0, 1, 2, 3, 4
LEFT_CURVE_EVENT = 5
RUNNING, ARRESTED, RESTING, T_MAX, MAX_EVENTS, LEFT_DOMAIN = 0, 1, 2, 3, 4, 5
NON_FINITE, BUDGET_MISMATCH, LEFT_CURVE = 6, 7, 8
#: Status codes of a failed run (its numbers are not a result).
ERROR_CODES = (NON_FINITE, BUDGET_MISMATCH)
EVENT_NAMES = ("impact", "reversal", "arrest", "rest_on_limiter", "normal_sign_change", "left_curve")
STATUS_NAMES = ("running", "arrested", "resting_on_limiter", "t_max", "max_events", "left_domain",
                "non_finite", "energy_budget_mismatch", "left_curve")
_LIMIT, _TURN, _NSIGN, _PASS, _EDGE = 0, 1, 2, 3, 4

#: Widest quadrature panel, in units of the curve's q_scale.
PANEL_Q = 1.0
#: A half-interval uses the root substitution when its anchor's (virtual) root
#: is closer than ROOT_RATIO times the half's length.
ROOT_RATIO = 1.0
#: Search window where no limiter bounds the motion, in units of q_scale.
WINDOW = 2.0
#: Spacing of the critical-point scan (F_s' = 0), in units of q_scale: a bump of the
#: curve narrower than this may hide a pair of critical points.
CRIT_STEP = 1 / 32
#: Relative tolerance of the arrest test |tan alpha| <= mu at a turning point.
CONE_RTOL = 1e-9
#: A Zeno accumulation is summed analytically once w at an impact is below
#: ZENO_W * g * (a length of the curve): the local model is then exact to rounding.
ZENO_W = 1e-10
#: Gauss points at which the normal force is sampled per interval where it may change sign.
N_SCAN = 32
#: Golden-section steps of the search for a dip of the normal force below 0 around a local
#: minimum of its scanned values (the bracket shrinks to 0.618**40 = 4e-9 of two node spacings).
DIP_ITER = 40
#: The golden ratio's conjugate, (sqrt(5) - 1) / 2.
GOLDEN = 0.6180339887498949
#: Relative bracket width at which root finders stop.
ROOT_RTOL = 4 * np.finfo(float).eps
#: Iterations after which a root finder stops (not reached on a bracketed monotone function).
ROOT_MAXITER = 200
#: Smallest positive double, used to keep 1/sqrt(G) finite at a node on a root.
TINY = np.finfo(float).tiny
#: Lattice steps scanned ahead of the particle at a time.
CHUNK = 16
#: Order of the scene scalars passed to the compiled ``simulate``.
SCALARS = ("g", "m", "mu", "k", "has_left", "left", "has_right", "right", "q0", "qdot0", "t_max", "max_events",
           "unilateral")
#: Rows of the quadrature's scratch array (node values and the cumulative sums).
WORK_ROWS = 10
#: Columns of the interval log: qa, qb, Ga, Gb, s, sigma, t0, T, Wf (per unit mass).
INTERVAL_COLUMNS = 9


@jit
def Fs(s, q, mu, cp):
    if s > 0:
        return F_p_scalar(q, mu, *cp)
    return F_m_scalar(q, mu, *cp)

@jit
def dFs(s, q, mu, cp):
    if s > 0:
        return dF_p_scalar(q, mu, *cp)
    return dF_m_scalar(q, mu, *cp)

@jit
def put_event(events, ne, kind, t, q, before, after, e):
    if ne == events.shape[0]:
        new = np.zeros((2 * events.shape[0], 6))
        new[:ne] = events[:ne]
        events = new
    events[ne, 0] = kind
    events[ne, 1] = t
    events[ne, 2] = q
    events[ne, 3] = before
    events[ne, 4] = after
    events[ne, 5] = e
    return events, ne + 1

@jit
def put_interval(ivs, ni, qa, qb, Ga, Gb, s, sigma, t0, T, Wi):
    if ni == ivs.shape[0]:
        new = np.zeros((2 * ivs.shape[0], INTERVAL_COLUMNS))
        new[:ni] = ivs[:ni]
        ivs = new
    ivs[ni, 0] = qa
    ivs[ni, 1] = qb
    ivs[ni, 2] = Ga
    ivs[ni, 3] = Gb
    ivs[ni, 4] = s
    ivs[ni, 5] = sigma
    ivs[ni, 6] = t0
    ivs[ni, 7] = T
    ivs[ni, 8] = Wi
    return ivs, ni + 1

@jit
def node(s, q, mu, cp):
    if s > 0:
        return node_p_scalar(q, mu, *cp)
    return node_m_scalar(q, mu, *cp)

@jit
def energy(q, w, m, g, cp):
    return m * (0.5 * w + g * z_scalar(q, *cp))

@jit
def qdot_of(q, w, sigma, cp):
    return sigma * math.sqrt(max(w, 0.0)) / h_scalar(q, *cp)

@jit
def finite_state(t, q, w, Wf, Wimp):
    """Whether the run's state and energy sums are all finite numbers."""
    return (math.isfinite(t) and math.isfinite(q) and math.isfinite(w) and math.isfinite(Wf)
            and math.isfinite(Wimp))

@jit
def nsign_of(q, w, g, cp):
    n = N_w_scalar(q, w, g, *cp)
    if n == 0.0:
        n = dx_scalar(q, *cp)
    return 1 if n >= 0.0 else -1

# --- root finders (inline functions: no function arguments, for numba) ---------
@jit
def root_G(s, C, a, b, Ga, Gb, g2, mu, cp):
    """rtsafe for G = C - 2 g F_s on [a, b] with G(a) > 0 >= G(b)."""
    if Gb == 0.0:
        return b
    lo, hi = b, a  # G(lo) < 0 < G(hi)
    x = a if Ga < -Gb else b
    fx = Ga if x == a else Gb
    dfx = -g2 * dFs(s, x, mu, cp)
    dx_old = abs(b - a)
    dxx = dx_old
    for _ in range(ROOT_MAXITER):
        tol = ROOT_RTOL * abs(x)
        ok = dfx != 0.0 and ((x - hi) * dfx - fx) * ((x - lo) * dfx - fx) < 0.0
        if (not ok) or abs(2.0 * fx) > abs(dx_old * dfx):
            dx_old = dxx
            dxx = 0.5 * (hi - lo)
            x = lo + dxx
        else:
            dx_old = dxx
            dxx = fx / dfx
            x = x - dxx
        if abs(dxx) <= tol or abs(hi - lo) <= tol:
            return x
        fx = C - g2 * Fs(s, x, mu, cp)
        if fx == 0.0:
            return x
        dfx = -g2 * dFs(s, x, mu, cp)
        if fx < 0.0:
            lo = x
        else:
            hi = x
    return x

@jit
def illinois_point(a, b, fa, fb):
    """Next point of the Illinois method (regula falsi, or bisection if that leaves the bracket)."""
    x = b - fb * (b - a) / (fb - fa)
    if not (min(a, b) < x < max(a, b)):
        x = 0.5 * (a + b)
    return x


@jit
def illinois_update(a, b, fa, fb, x, fx):
    """The bracket after evaluating f(x) = fx: halve the stale end's value (Illinois); done?"""
    if (fx > 0.0) == (fb > 0.0):
        fa = 0.5 * fa
    else:
        a, fa = b, fb
    b, fb = x, fx
    return a, b, fa, fb, fx == 0.0 or abs(b - a) <= ROOT_RTOL * abs(b) + 1e-300


@jit
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


@jit
def root_normal(p, a, b, fa, fb):
    """Root of normal_on between a and b (values fa, fb of opposite signs)."""
    for _ in range(ROOT_MAXITER):
        x = illinois_point(a, b, fa, fb)
        a, b, fa, fb, done = illinois_update(a, b, fa, fb, x, normal_on(x, p))
        if done:
            break
    return b


@jit
def root_time(p, a, b, fa, fb):
    """Where time_excess vanishes between a and b (values fa, fb of opposite signs)."""
    for _ in range(ROOT_MAXITER):
        x = illinois_point(a, b, fa, fb)
        a, b, fa, fb, done = illinois_update(a, b, fa, fb, x, time_excess(x, p))
        if done:
            break
    return b


@jit
def crit_f(x, p):
    """z' + s mu x' at x, p = (s, mu, cp): the sign of F_s' = exp(2 s mu alpha) (z' + s mu x')."""
    s, mu, cp = p
    return dz_scalar(x, *cp) + s * mu * dx_scalar(x, *cp)

# --- the map of the curve: critical points and where N > 0 surely, scanned lazily -----
# Lattice points x_k = k * step are scanned outward from the start as the particle
# travels; roots of F_s' between neighbours are refined and kept (few, unsorted).
# region: 0 x_lo, 1 x_hi, 2 fp_lo, 3 fm_lo, 4 fp_hi, 5 fm_hi, 6 safe_lo, 7 safe_hi,
#         8 safe_lo_open, 9 safe_hi_open, 10 k_lo, 11 k_hi, 12 lo_in, 13 hi_in
@jit
def is_safe(x, cp):
    return kappa_scalar(x, *cp) >= 0.0 and dx_scalar(x, *cp) > 0.0

@jit
def map_new(q0, lo, hi, mu, cp, step):
    region = np.empty(14)
    lo_in = lo + 1e-12 * max(1.0, abs(lo)) if math.isfinite(lo) else -math.inf
    hi_in = hi - 1e-12 * max(1.0, abs(hi)) if math.isfinite(hi) else math.inf
    k0 = math.floor(q0 / step)
    x0 = min(max(k0 * step, lo_in), hi_in)
    region[0] = x0
    region[1] = x0
    zp, xp = dz_scalar(x0, *cp), dx_scalar(x0, *cp)
    region[2] = region[4] = zp + mu * xp
    region[3] = region[5] = zp - mu * xp
    safe = xp > 0.0 and kappa_scalar(x0, *cp) >= 0.0 and is_safe(q0, cp)
    region[6] = region[7] = x0
    region[8] = region[9] = 1.0 if safe else 0.0
    if not safe:
        region[6] = region[7] = q0
    region[10] = region[11] = k0
    region[12] = lo_in
    region[13] = hi_in
    roots = np.empty((2, 8))
    count = np.zeros(2, dtype=np.int64)
    if region[2] == 0.0:
        roots = add_root(roots, count, 0, x0)
    if region[3] == 0.0:
        roots = add_root(roots, count, 1, x0)
    return region, roots, count

@jit
def add_root(roots, count, b, r):
    if count[b] == roots.shape[1]:
        new = np.empty((2, 2 * roots.shape[1]))
        new[:, :roots.shape[1]] = roots
        roots = new
    roots[b, count[b]] = r
    count[b] += 1
    return roots

@jit
def crossing(roots, count, row, x_old, x_new, f_old, f_new, mu, cp):
    """Record a root of F_s' between two scanned points (or at the new one, if exactly 0)."""
    if f_new == 0.0:
        return add_root(roots, count, row, x_new)
    if f_old != 0.0 and (f_old > 0.0) != (f_new > 0.0):
        s = 1 if row == 0 else -1
        return add_root(roots, count, row, root_crit((s, mu, cp), x_old, x_new, f_old, f_new))
    return roots

@jit
def map_extend(region, roots, count, target, mu, cp, step):
    """Scan the lattice outward until target is covered (or the domain ends)."""
    while target > region[1] and region[1] < region[13]:
        k = region[11] + 1.0
        x = min(k * step, region[13])
        zp, xp = dz_scalar(x, *cp), dx_scalar(x, *cp)
        fp, fm = zp + mu * xp, zp - mu * xp
        a = region[1]
        roots = crossing(roots, count, 0, a, x, region[4], fp, mu, cp)
        roots = crossing(roots, count, 1, a, x, region[5], fm, mu, cp)
        if region[9] != 0.0:
            if xp > 0.0 and kappa_scalar(x, *cp) >= 0.0:
                region[7] = x
            else:
                region[9] = 0.0
        region[1], region[4], region[5], region[11] = x, fp, fm, k
    while target < region[0] and region[0] > region[12]:
        k = region[10] - 1.0
        x = max(k * step, region[12])
        zp, xp = dz_scalar(x, *cp), dx_scalar(x, *cp)
        fp, fm = zp + mu * xp, zp - mu * xp
        b = region[0]
        roots = crossing(roots, count, 0, b, x, region[2], fp, mu, cp)
        roots = crossing(roots, count, 1, b, x, region[3], fm, mu, cp)
        if region[8] != 0.0:
            if xp > 0.0 and kappa_scalar(x, *cp) >= 0.0:
                region[6] = x
            else:
                region[8] = 0.0
        region[0], region[2], region[3], region[10] = x, fp, fm, k
    return roots

@jit
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

@jit
def normal_on(x, p):
    """The normal force per unit mass at x on the current branch, times its expected sign.

    p = (s, C, nsgn, g, g2, mu, cp).
    """
    s, C, nsgn, g, g2, mu, cp = p
    G = C - g2 * Fs(s, x, mu, cp)
    w = math.exp(-2.0 * s * mu * alpha_scalar(x, *cp)) * max(G, 0.0)
    return nsgn * N_w_scalar(x, w, g, *cp)

@jit
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

# --- event location -------------------------------------------------------------
@jit
def locate(q, sigma, s, Ga, P, region, roots, count, X):
    (g, m, mu, k, has_left, left, has_right, right, lo, hi, scale, cp) = P
    g2 = 2.0 * g
    step = CRIT_STEP * scale
    C = Ga + g2 * Fs(s, q, mu, cp)
    if sigma > 0 and has_right:
        bound, kind = right, _LIMIT
    elif sigma < 0 and has_left:
        bound, kind = left, _LIMIT
    else:
        edge = hi if sigma > 0 else lo
        window = q + sigma * WINDOW * scale
        if math.isfinite(edge) and (edge - window) * sigma <= 0.0:
            bound, kind = edge, _EDGE
        else:
            bound, kind = window, _PASS
    a, Gq = q, Ga
    qe, Ge, kind_out = bound, 0.0, kind
    while True:
        # Scan at most CHUNK lattice steps ahead of a; between a and the scanned edge
        # the known critical points are all there are, so G is monotone between them.
        ahead = a + sigma * CHUNK * step
        target = min(ahead, bound) if sigma > 0 else max(ahead, bound)
        roots = map_extend(region, roots, count, target, mu, cp, step)
        edge = min(region[1], bound) if sigma > 0 else max(region[0], bound)
        c = next_crit(roots, count, s, a, edge, sigma)
        b = edge if math.isnan(c) else c
        if b == a:
            b = bound  # the domain ends here: nothing left to scan
        Gb = C - g2 * Fs(s, b, mu, cp)
        if math.isnan(Gb):
            Gb = -math.inf
        if Gb <= 0.0:
            # A non-finite G at a domain end stands in as -1 (the finder bisects there).
            qe = root_G(s, C, a, b, Gq, Gb if math.isfinite(Gb) else -1.0, g2, mu, cp)
            Ge, kind_out = 0.0, _TURN
            break
        if b == bound:
            qe, Ge, kind_out = bound, Gb, kind
            break
        a, Gq = b, Gb
    # An earlier zero of N on [q, qe] ends the interval there instead.
    safe_lo = region[6]
    safe_hi = region[7]
    if safe_lo <= min(q, qe) and max(q, qe) <= safe_hi:
        return kind_out, qe, Ge, roots
    # N is scanned at the Gauss nodes and at qe (its sign can change after the last node);
    # around a local minimum of the scanned values a golden-section search looks for a
    # dip below 0 between nodes.  The start counts as positive (N may be 0 there, just
    # after a sign change).
    nsgn = 1.0 if s * sigma > 0 else -1.0
    pn = (s, C, nsgn, g, g2, mu, cp)
    before, fbefore = q, max(normal_on(q, pn), 1e-300)
    prev, fprev = q, 1e-300
    n = X.shape[0]
    for j in range(n + 1):
        x = q + (qe - q) * 0.5 * (X[j] + 1.0) if j < n else qe
        fx = normal_on(x, pn)
        if fx < 0.0:
            r = root_normal(pn, prev, x, fprev, fx)
            return _NSIGN, r, C - g2 * Fs(s, r, mu, cp), roots
        if j > 0 and fprev <= fbefore and fprev <= fx:
            xd, fd = dip_below(pn, before, x)
            if not math.isnan(xd):
                r = root_normal(pn, before, xd, fbefore, fd)
                return _NSIGN, r, C - g2 * Fs(s, r, mu, cp), roots
        before, fbefore = prev, max(fprev, 1e-300)
        prev, fprev = x, fx
    return kind_out, qe, Ge, roots

# --- time quadrature -------------------------------------------------------------
@jit
def quad(qa, qb, Ga, Gb, s, sigma, g, mu, scale, cp, R, work, keep, out, o):
    """Time and friction work (per unit mass) of one interval; node samples into out[o:].

    R = (x, w, S^T, SW^T) of the rule for panels that start on a root (weighted),
    then (x, w, S^T) of the rule for every other panel (see :func:`symvib.numeric.driver.plain_nodes`).
    """
    Xw, Ww, Sw, SWw, Xp, Wtp, Sp = R
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
        gamma = -d * g2 * dFs(s, e, mu, cp)
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
                    dF, hh, ex, ka, co = node(s, qj, mu, cp)
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

@jit
def time_excess(x, p):
    """Time from the start of an interval to x, minus a target (for the t_max stop)."""
    q, Ga, C, s, sigma, g, mu, scale, cp, R, work, dummy, target = p
    Gx = max(C - 2.0 * g * Fs(s, x, mu, cp), 0.0)
    T, _, _ = quad(q, x, Ga, Gx, s, sigma, g, mu, scale, cp, R, work, False, dummy, 0)
    return T - target


# --- rest and impacts ---------------------------------------------------------------
@jit
def rest(q, side, mu, cp):
    """At rest at q: (1 arrest | 2 rest on a limiter | 0 slide, direction)."""
    hh = h_scalar(q, *cp)
    sin = dz_scalar(q, *cp) / hh
    cos = dx_scalar(q, *cp) / hh
    pull = -sin
    if side != 0 and pull * side > 0.0:
        return 2, 0
    if abs(sin) <= mu * abs(cos) * (1.0 + CONE_RTOL) + 4.0 * 2.220446049250313e-16:
        return 1, 0
    return 0, (1 if pull > 0.0 else -1)

@jit
def run(P, R, q0, qdot0, t_max, max_events, keep_intervals, unilateral):
    """Simulate one scene.  Returns a tuple; see :func:`symvib.numeric.driver.simulate` for its use.

    ``unilateral``: the curve only pushes along its normal, so where N reaches 0 (or is
    negative at the start of an interval) the run ends with LEFT_CURVE (physics.md, "Events").
    """
    (g, m, mu, k, has_left, left, has_right, right, lo, hi, scale, cp) = P
    region, roots, count = map_new(q0, lo, hi, mu, cp, CRIT_STEP * scale)
    X = R[0]
    n = max(X.shape[0], R[4].shape[0])
    work = np.empty((WORK_ROWS, n))
    dummy = np.empty((1, 4))
    events = np.zeros((min(max_events + 4, 64), 6))
    ne = 0
    ivs = np.zeros((64 if keep_intervals else 1, INTERVAL_COLUMNS))
    ni = 0
    t = 0.0
    Wf = 0.0
    Wimp = 0.0
    zeno = np.zeros(4)  # ratio, simulated impacts, remaining time, side
    status = RUNNING
    q = q0
    w = (h_scalar(q, *cp) * qdot0) ** 2
    # At rest also when w underflows to 0 (qdot0 = 1e-300): the rest test decides.
    sigma = 0 if qdot0 == 0.0 or w == 0.0 else (1 if qdot0 > 0.0 else -1)
    E0 = energy(q, w, m, g, cp)
    flip = False
    nsign = 1
    side = 0
    if has_right and q == right:
        side = 1
    elif has_left and q == left:
        side = -1
    pending_impact = sigma != 0 and side == sigma
    if not (math.isfinite(E0) and finite_state(t, q, w, Wf, Wimp)):
        status = NON_FINITE  # e.g. qdot0 = 1e200: w = inf from the start
    elif unilateral and N_w_scalar(q, w, g, *cp) < 0.0:
        # Unilateral contact and N < 0 at the start: the particle leaves the curve at once.
        events, ne = put_event(events, ne, LEFT_CURVE_EVENT, t, q, qdot0, qdot0, E0)
        status = LEFT_CURVE
    elif sigma == 0:
        what, direction = rest(q, side, mu, cp)
        if what != 0:
            events, ne = put_event(events, ne, ARREST if what == 1 else REST_ON_LIMITER, t, q, 0.0, 0.0,
                           energy(q, 0.0, m, g, cp))
            status = ARRESTED if what == 1 else RESTING
        sigma = direction
    while status == RUNNING:
        if not finite_state(t, q, w, Wf, Wimp):
            status = NON_FINITE  # overflow: stop at once rather than run max_events impacts at inf
            break
        if pending_impact:
            # An impact at q with squared speed w moving sigma.
            pending_impact = False
            qd = qdot_of(q, w, sigma, cp)
            w_after = k * k * w
            Wimp += 0.5 * m * (1.0 - k * k) * w
            events, ne = put_event(events, ne, IMPACT, t, q, qd, -k * qd, energy(q, w_after, m, g, cp))
            side = int(sigma)
            w_before = w
            w = w_after
            sigma = -sigma
            if w == 0.0:
                what, direction = rest(q, side, mu, cp)
                if what != 0:
                    events, ne = put_event(events, ne, ARREST if what == 1 else REST_ON_LIMITER, t, q, 0.0, 0.0,
                                   energy(q, 0.0, m, g, cp))
                    status = ARRESTED if what == 1 else RESTING
                    break
                sigma = direction
            else:
                # Zeno: gravity pushes into the limiter, outside the cone, and the bounce is tiny.
                hh = h_scalar(q, *cp)
                sin = dz_scalar(q, *cp) / hh
                cos = dx_scalar(q, *cp) / hh
                away = float(sigma)
                a_up = g * (away * sin + mu * abs(cos))
                a_down = g * (away * sin - mu * abs(cos))
                if a_down > 0.0 and k > 0.0 and w_before < ZENO_W * g * hh * scale:
                    lam_w = k * k * a_down / a_up
                    if lam_w < 1.0:
                        ratio = math.sqrt(lam_w)
                        v_after = k * math.sqrt(w_before)
                        remaining = v_after * (1.0 / a_up + 1.0 / math.sqrt(a_up * a_down)) / (1.0 - ratio)
                        kinetic = 0.5 * m * k * k * w_before
                        w_imp = 0.5 * m * (1.0 - k * k) * lam_w * w_before / (1.0 - lam_w)
                        Wimp += w_imp
                        Wf += kinetic - w_imp
                        simulated = 0
                        for j in range(ne - 1, -1, -1):
                            if events[j, 0] == IMPACT and events[j, 2] == q:
                                simulated += 1
                            elif events[j, 0] != REVERSAL:
                                break
                        t += remaining
                        zeno[0], zeno[1], zeno[2], zeno[3] = ratio, simulated, remaining, side
                        events, ne = put_event(events, ne, REST_ON_LIMITER, t, q, 0.0, 0.0, energy(q, 0.0, m, g, cp))
                        w = 0.0
                        status = RESTING
                        break
            if ne >= max_events:
                status = MAX_EVENTS
                break
        if ne >= max_events:
            status = MAX_EVENTS
            break
        if flip:
            nsign = -nsign
        else:
            nsign = nsign_of(q, w, g, cp)
        flip = False
        if unilateral and nsign < 0:
            # N < 0 here (at the start, or after an impact): the particle is not held.
            events, ne = put_event(events, ne, LEFT_CURVE_EVENT, t, q, qdot_of(q, w, sigma, cp),
                                   qdot_of(q, w, sigma, cp), energy(q, w, m, g, cp))
            status = LEFT_CURVE
            break
        s = sigma * nsign
        Ga = w * math.exp(2.0 * s * mu * alpha_scalar(q, *cp))
        kind, qb, Gb, roots = locate(q, sigma, s, Ga, P, region, roots, count, X)
        T, Wi, _ = quad(q, qb, Ga, Gb, s, sigma, g, mu, scale, cp, R, work, False, dummy, 0)
        if t + T > t_max:
            # Stop inside this interval where t reaches t_max.
            target = t_max - t
            C = Ga + 2.0 * g * Fs(s, q, mu, cp)
            pt = (q, Ga, C, s, sigma, g, mu, scale, cp, R, work, dummy, target)
            qe = root_time(pt, q, qb, -target, T - target)
            Ge = max(C - 2.0 * g * Fs(s, qe, mu, cp), 0.0)
            Tq, Wq, _ = quad(q, qe, Ga, Ge, s, sigma, g, mu, scale, cp, R, work, False, dummy, 0)
            if keep_intervals:
                ivs, ni = put_interval(ivs, ni, q, qe, Ga, Ge, s, sigma, t, Tq, Wq)
            Wf += m * Wq
            t = t_max
            q = qe
            w = math.exp(-2.0 * s * mu * alpha_scalar(qe, *cp)) * Ge
            status = T_MAX
            break
        wb = math.exp(-2.0 * s * mu * alpha_scalar(qb, *cp)) * Gb
        if keep_intervals:
            ivs, ni = put_interval(ivs, ni, q, qb, Ga, Gb, s, sigma, t, T, Wi)
        t += T
        Wf += m * Wi
        if kind == _TURN:
            side = 0
            if has_right and qb == right:
                side = 1
            elif has_left and qb == left:
                side = -1
            what, direction = rest(qb, side, mu, cp)
            q, w = qb, 0.0
            code = REVERSAL
            if what == 1:
                code = ARREST
                status = ARRESTED
            elif what == 2:
                code = REST_ON_LIMITER
                status = RESTING
            else:
                sigma = direction
            events, ne = put_event(events, ne, code, t, qb, 0.0, 0.0, energy(qb, 0.0, m, g, cp))
        elif kind == _LIMIT:
            q, w = qb, wb
            pending_impact = True
        elif kind == _NSIGN and unilateral:
            qd = qdot_of(qb, wb, sigma, cp)
            events, ne = put_event(events, ne, LEFT_CURVE_EVENT, t, qb, qd, qd, energy(qb, wb, m, g, cp))
            q, w = qb, wb
            status = LEFT_CURVE
        elif kind == _NSIGN:
            qd = qdot_of(qb, wb, sigma, cp)
            events, ne = put_event(events, ne, NORMAL_SIGN_CHANGE, t, qb, qd, qd, energy(qb, wb, m, g, cp))
            q, w = qb, wb
            flip = True
        elif kind == _PASS:
            q, w = qb, wb
        else:
            q, w = qb, wb
            status = LEFT_DOMAIN
    if status == MAX_EVENTS and w == 0.0:
        sigma = 0
    if not finite_state(t, q, w, Wf, Wimp):
        status = NON_FINITE  # e.g. mu = 1e65: an arrest reached at t = nan
    return (status, ne, events, ni, ivs, t, q, w, sigma, Wf, Wimp, E0, zeno)

@jit
def samples(ivs, ni, g, mu, scale, cp, R):
    """Node samples (t, q, w, N) of the logged intervals, interval by interval."""
    n = max(R[0].shape[0], R[4].shape[0])
    work = np.empty((WORK_ROWS, n))
    # Upper bound of the nodes per interval: panels are few; grow when needed.
    cap = max(ni * 8 * n, 16)
    out = np.zeros((cap, 4))
    index = np.zeros(cap, dtype=np.int64)
    o = 0
    for i in range(ni):
        t0 = ivs[i, 6]
        need = o + 200 * n
        if need > cap:
            cap = 2 * need
            new = np.zeros((cap, 4))
            new[:o] = out[:o]
            out = new
            newi = np.zeros(cap, dtype=np.int64)
            newi[:o] = index[:o]
            index = newi
        start = o
        _, _, o = quad(ivs[i, 0], ivs[i, 1], ivs[i, 2], ivs[i, 3], int(ivs[i, 4]), int(ivs[i, 5]), g, mu, scale,
                       cp, R, work, True, out, o)
        for j in range(start, o):
            out[j, 0] += t0
            index[j] = i
    return out[:o], index[:o]

@jit
def simulate(scal, cp, R, keep):
    """Run one scene given as a float array (see :data:`SCALARS`) and its parameters."""
    g, m, mu, k = scal[0], scal[1], scal[2], scal[3]
    has_left, left, has_right, right = scal[4] != 0.0, scal[5], scal[6] != 0.0, scal[7]
    q0, qdot0, t_max, max_events = scal[8], scal[9], scal[10], int(scal[11])
    unilateral = scal[12] != 0.0
    lo, hi = domain(*cp)
    scale = q_scale_scalar(*cp)
    P = (g, m, mu, k, has_left, left, has_right, right, lo, hi, scale, cp)
    (status, ne, events, ni, ivs, t, q, w, sigma, Wf, Wimp, E0, zeno) = run(
        P, R, q0, qdot0, t_max, max_events, keep, unilateral)
    E_final = energy(q, w, m, g, cp)
    qdot_final = qdot_of(q, w, sigma, cp) if sigma != 0 else 0.0
    return (status, ne, events, ni, ivs, t, q, qdot_final, Wf, Wimp, E0, E_final, zeno, scale)


#: Columns of a sweep's per-scene summary.
SUMMARY = ("status", "events", "impacts", "reversals", "normal_sign_changes", "t_final", "q_final",
           "qdot_final", "friction_work", "impact_loss", "E0", "E_final", "zeno_ratio")


@pjit
def sweep(scal_rows, cp_rows, R, max_log):
    """Run many scenes of one curve (rows of :data:`SCALARS` values and of parameters).

    Returns the per-scene summary (columns :data:`SUMMARY`) and, when
    ``max_log > 0``, the first ``max_log`` events of each scene (kind, t, q,
    qdot_before, qdot_after, energy).  Scenes run in parallel threads on the
    numba backend (``prange``).
    """
    n = scal_rows.shape[0]
    out = np.zeros((n, len(SUMMARY)))
    logs = np.zeros((n, max(max_log, 1), 6))
    for i in prange(n):
        cp = cp_tuple(cp_rows[i])
        (status, ne, events, ni, ivs, t, q, qdot_final, Wf, Wimp, E0, E_final, zeno, scale) = simulate(
            scal_rows[i], cp, R, False)
        impacts = 0
        reversals = 0
        flips = 0
        for j in range(ne):
            kind = int(events[j, 0])
            if kind == IMPACT:
                impacts += 1
            elif kind == REVERSAL:
                reversals += 1
            elif kind == NORMAL_SIGN_CHANGE:
                flips += 1
            if j < max_log:
                for c in range(6):
                    logs[i, j, c] = events[j, c]
        out[i, 0] = status
        out[i, 1] = ne
        out[i, 2] = impacts
        out[i, 3] = reversals
        out[i, 4] = flips
        out[i, 5] = t
        out[i, 6] = q
        out[i, 7] = qdot_final
        out[i, 8] = Wf
        out[i, 9] = Wimp
        out[i, 10] = E0
        out[i, 11] = E_final
        out[i, 12] = zeno[0]
    return out, logs
