"""An independent reference: the equation of motion integrated in time along the arc.

:func:`reference_run` is written from ``docs/physics.md`` alone and shares no
numerics with the engine: no generated kernels, no :mod:`symvib.symbolic.derive`,
no phase trajectory ``F_sigma``.  It differentiates the curve's ``x(q)``,
``z(q)`` itself (SymPy, then ``lambdify``) and integrates, in time, the state
``(q, v)`` with ``v = h qdot`` the signed speed along the curve
(physics.md, "Equation of motion (paper eq. 1)"):

    dq/dt = v / h,
    dv/dt = -g sin(alpha) - sigma mu |N|,    N = kappa v**2 + g cos(alpha),

with ``h sin(alpha) = z'``, ``h cos(alpha) = x'``, ``kappa = (x' z'' - z' x'') / h**3``
(physics.md, "Geometry").  Within a segment the direction ``sigma`` and the sign
of ``N`` are fixed (so the right-hand side is smooth), and a segment ends at the
first terminal event: the limiter ahead (an impact), ``v = 0`` (a turning point),
``N = 0`` (``normal_sign_change``; it is a kink of the right-hand side, so the
integration restarts there), the end of the declared domain, or ``t_max``.  The
laws at events are physics.md's ("Events"): impact ``v -> -k v``; at a point at
rest, rest on a limiter that gravity pushes into, else arrest iff
``|sin alpha| <= mu_s |cos alpha| (1 + CONE_RTOL) + CONE_ATOL`` (``mu_s``: the static friction), else a reversal
downhill.  A start at rest that slides records no event (as the engine does); a
start on a limiter moving into it is an impact at ``t = 0``.  A Zeno accumulation
is not summed: the bounces go on until ``max_events`` (the comparison,
:mod:`symvib.checks.accuracy`, handles it).  Unilateral contact ends with
``left_curve`` where ``N`` reaches 0 (or is negative at the start or after an impact).

Two quadratures of the same event loop:

``"DOP853"`` (default)
    :func:`scipy.integrate.solve_ivp` (DOP853, ``rtol = 1e-13``, ``atol`` scaled to
    each segment's speed), restarted at every event, on the offset ``q - q_start``
    so that the coordinate keeps its digits on short motions.  Double precision:
    where the answer is ill-conditioned (a speed that nearly vanishes inside an
    interval, a start next to the cone edge) its error grows beyond ``rtol``.
``"GBS"``
    Gragg-Bulirsch-Stoer extrapolation (modified midpoint rule, Aitken-Neville in
    ``H**2``) in mpmath at ``digits`` digits (30 by default), events located by a
    safeguarded Newton iteration on the length of a fresh step.  Slow (milliseconds
    per step), for the scenes double precision cannot resolve.

Examples
--------
>>> from symvib.numeric.scene import scene_from_dict
>>> s = scene_from_dict({"curve": {"z": "c*x"}, "parameters": {"c": 0.5},
...                      "physics": {"mu": 0.1, "restitution": 0.8}, "limiters": {"left": 0.0},
...                      "initial": {"q": 1.0, "qdot": 0.0}, "run": {"max_events": 3}})
>>> run = reference_run(s)
>>> run.status, [(e[0], round(e[1], 9)) for e in run.events]
('max_events', [('impact', 0.798188571), ('reversal', 1.223889142), ('impact', 1.745263734)])
"""
from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass
from functools import lru_cache

import mpmath

__all__ = ["ReferenceRun", "reference_run", "scene_scales", "curve_frame", "CONE_RTOL", "CONE_ATOL", "RTOL", "METHODS"]

#: Relative tolerance of the arrest test at the cone edge (physics.md, "Events" 2).
CONE_RTOL = 1e-9
#: Absolute slack of the arrest test: a few rounding errors of a sine of order 1 (the engine's).
CONE_ATOL = 4.0 * 2.220446049250313e-16
#: Relative tolerance of the DOP853 quadrature.
RTOL = 1e-13
#: Absolute tolerances of DOP853 relative to each segment's own scales (speed, its distance).
ATOL_REL = 1e-16
#: Longest step as a fraction of the scene's time scale (keeps double crossings of an event function apart).
MAX_STEP_FRACTION = 0.125
#: The run's domain ends this many ``q_scale`` inside a finite end of the declared domain (physics.md, "Events" 4).
DOMAIN_INSET = 1e-12
#: Default CPU-time budget of one run, in seconds.
BUDGET_SECONDS = 60.0
#: Right-hand-side calls between two checks of the CPU-time budget.
BUDGET_CHECK_CALLS = 256
#: Most right-hand-side calls of one DOP853 segment: beyond them the steps have collapsed (a
#: right-hand side whose rounding noise exceeds the tolerance, next to the cone edge).
MAX_SEGMENT_CALLS = 100_000
#: Tolerances of the location of a limiter crossed within a DOP853 step (relative to T, and to t).
ROOT_XTOL, ROOT_RTOL = 1e-18, 4 * 2.220446049250313e-16
#: The quadratures :func:`reference_run` offers.
METHODS = ("DOP853", "GBS")
#: GBS: digits of the mpmath arithmetic, and of the step's acceptance below them.
GBS_DIGITS = 30
GBS_GUARD_DIGITS = 5
#: GBS: substep numbers of the modified midpoint rule (rows of the extrapolation tableau).
GBS_SEQUENCE = (2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24)
#: GBS: largest growth of a step, and the safety factor of the next step's estimate.
GBS_GROWTH, GBS_SAFETY = 4, 0.8
#: GBS: first step as a fraction of the scene's time scale, and the factor of a rejected step.
GBS_FIRST_STEP, GBS_REJECT = 0.02, 0.25
#: GBS: iterations of the event location, and the step of its finite-difference derivative along
#: the flow, ``10**(-digits * GBS_FD_EXPONENT) T`` (its error is the square of that, relative).
GBS_ROOT_ITERATIONS, GBS_FD_EXPONENT = 80, 1 / 3


class _Budget(RuntimeError):
    """The run spent its CPU-time budget."""


@dataclass(frozen=True)
class ReferenceRun:
    """The outcome of :func:`reference_run`.

    Attributes
    ----------
    status : str
        A status name of the engine (``"arrested"``, ``"resting_on_limiter"``, ``"t_max"``,
        ``"max_events"``, ``"left_curve"``, ``"left_domain"``) or ``"failed"`` (the quadrature
        failed or the CPU-time budget was spent; ``message`` says which).
    events : tuple
        ``(kind, t, q, qdot_before, qdot_after)`` tuples of floats, kinds named as the engine's.
    message : str
    method : str
    v_start : tuple
        For each event, ``|v|`` at the start of the motion segment that ended at it (the
        speed scale the event was computed from; 0 for events without a segment).
    t_final, q_final, qdot_final : float
    rhs_calls : int
    """

    status: str
    events: tuple
    message: str
    method: str
    v_start: tuple = ()
    t_final: float = 0.0
    q_final: float = 0.0
    qdot_final: float = 0.0
    rhs_calls: int = 0

    @property
    def failed(self) -> bool:
        return self.status == "failed"


# --- the curve ------------------------------------------------------------------------------------
@lru_cache(maxsize=64)
def _lambdified(shape_key, module: str):
    """``(frame(q, *p) -> (x', z', x'', z''), domain(*p) -> (lo, hi), q_scale(*p))``."""
    import sympy as sp

    curve = shape_key.curve()
    q, params = curve.q, list(curve.params)
    xp, zp = sp.diff(curve.x, q), sp.diff(curve.z, q)
    # A DiracDelta is the second derivative of an Abs at its kink, a point of measure zero.
    exprs = [e.replace(sp.DiracDelta, lambda *a: sp.S.Zero) for e in (xp, zp, sp.diff(xp, q), sp.diff(zp, q))]
    frame = sp.lambdify([q, *params], exprs, modules=module, cse=True)
    domain = sp.lambdify(params, list(curve.domain), modules="mpmath")
    scale = sp.lambdify(params, curve.q_scale, modules="mpmath")
    return frame, domain, scale


class _Hashable:
    """A shape keyed by its defining data (a Shape holds dicts, so it does not hash)."""

    def __init__(self, shape):
        self.shape = shape
        self.key = json.dumps(shape.source(), sort_keys=True)

    def curve(self):
        return self.shape.curve()

    def __hash__(self):
        return hash(self.key)

    def __eq__(self, other):
        return isinstance(other, _Hashable) and other.key == self.key


class _Physics:
    """The scene's curve and constants at one precision (floats, or mpf at ``digits``)."""

    def __init__(self, scene, digits=None):
        self.mp = digits is not None
        key = _Hashable(scene.shape)
        self._frame, domain, scale = _lambdified(key, "mpmath" if self.mp else "math")
        num = mpmath.mpf if self.mp else float
        self.num = num
        self.sqrt = mpmath.sqrt if self.mp else math.sqrt
        self.cp = tuple(num(v) for v in scene.param_values)
        self.g, self.mu, self.k = num(scene.g), num(scene.mu), num(scene.k)
        self.mu_s = num(scene.mu_static)   # the rest test's (static) friction
        self.left = None if scene.left is None else num(scene.left)
        self.right = None if scene.right is None else num(scene.right)
        with mpmath.workdps(30):
            lo, hi = (mpmath.mpf(v) for v in domain(*scene.param_values))
            self.q_scale = abs(float(scale(*scene.param_values)))
        inset = DOMAIN_INSET * self.q_scale
        self.lo = None if not mpmath.isfinite(lo) else num(float(lo) + inset)
        self.hi = None if not mpmath.isfinite(hi) else num(float(hi) - inset)
        self.unilateral = scene.contact == "unilateral"
        self.calls = 0

    def frame(self, q):
        """``(h, sin alpha, cos alpha, kappa)`` at ``q``."""
        xp, zp, xpp, zpp = self._frame(q, *self.cp)
        h = self.sqrt(xp * xp + zp * zp)
        return h, zp / h, xp / h, (xp * zpp - zp * xpp) / (h * h * h)

    def rates(self, q, v, sigma, nsign):
        """``(dq/dt, dv/dt)`` on the branch of direction ``sigma`` and normal-force sign ``nsign``."""
        self.calls += 1
        xp, zp, xpp, zpp = self._frame(q, *self.cp)
        h2 = xp * xp + zp * zp
        inv = 1 / self.sqrt(h2)
        # kappa v^2 + g cos(alpha) = ((x' z'' - z' x'') v^2 / h^2 + g x') / h
        normal = ((xp * zpp - zp * xpp) * v * v / h2 + self.g * xp) * inv
        return v * inv, -self.g * zp * inv - (sigma * nsign) * self.mu * normal

    def normal(self, q, v):
        """``N = kappa v**2 + g cos(alpha)`` per unit mass."""
        _, _, cos, kappa = self.frame(q)
        return kappa * v * v + self.g * cos

    def nsign(self, q, v):
        """The sign of ``N``; where it is 0, the sign of ``x'`` (the side gravity pulls to)."""
        n = self.normal(q, v)
        if n == 0:
            n = self.frame(q)[2]
        return 1 if n >= 0 else -1

    def rest(self, q, side):
        """The rest test (physics.md, "Events" 2): ``(what, direction)``, what in
        ``"rest_on_limiter"``, ``"arrest"``, ``"slide"``."""
        _, sin, cos, _ = self.frame(q)
        if side != 0 and -sin * side > 0:
            return "rest_on_limiter", 0
        if abs(sin) <= self.mu_s * abs(cos) * (1 + CONE_RTOL) + CONE_ATOL:
            return "arrest", 0
        return "slide", (1 if -sin > 0 else -1)

    def side(self, q):
        """+1 on the right limiter, -1 on the left one, 0 elsewhere."""
        if self.right is not None and q == self.right:
            return 1
        if self.left is not None and q == self.left:
            return -1
        return 0

    def ahead(self, sigma):
        """``(kind, q)`` of the limiter and the domain end ahead in direction ``sigma``."""
        out = []
        lim, end = (self.right, self.hi) if sigma > 0 else (self.left, self.lo)
        if lim is not None:
            out.append(("limiter", lim))
        if end is not None and (lim is None or sigma * (end - lim) < 0):
            out.append(("domain", end))
        return out


def curve_frame(scene, digits: int | None = None):
    """A function ``q -> (h, sin alpha, cos alpha, kappa)`` of the scene's curve (floats, or mpf:
    call it within ``mpmath.workdps(digits)``).

    Examples
    --------
    >>> from symvib.numeric.scene import scene_from_dict
    >>> s = scene_from_dict({"curve": {"z": "x**2/2"}, "physics": {"mu": 0, "restitution": 1},
    ...                      "initial": {"q": 0, "qdot": 1}})
    >>> [round(x, 6) for x in curve_frame(s)(1.0)]
    [1.414214, 0.707107, 0.707107, 0.353553]
    """
    return _Physics(scene, digits).frame


def scene_scales(scene) -> tuple:
    """``(L, V, T)``: a length (m), a speed (m/s) and a time (s) characteristic of a scene.

    ``L`` is the metric at the start times the span of ``q`` the limiters leave
    (twice the distance to the one limiter, or ``q_scale`` without any), ``V`` the
    larger of the start speed and ``sqrt(g L)``, ``T = L / V``.

    Examples
    --------
    >>> from symvib.numeric.scene import scene_from_dict
    >>> s = scene_from_dict({"curve": {"shape": "circle"}, "parameters": {"R": 0.5},
    ...                      "physics": {"mu": 0, "restitution": 1}, "limiters": {"left": -1, "right": 1},
    ...                      "initial": {"q": 0, "qdot": 0}})
    >>> [round(x, 4) for x in scene_scales(s)]
    [1.0, 3.1321, 0.3193]
    """
    P = _Physics(scene)
    h = P.frame(scene.q0)[0]
    if scene.left is not None and scene.right is not None:
        span = scene.right - scene.left
    elif scene.left is not None or scene.right is not None:
        span = 2 * abs(scene.q0 - (scene.left if scene.left is not None else scene.right))
    else:
        span = P.q_scale
    L = h * span if span > 0 else h
    V = max(abs(h * scene.qdot0), math.sqrt(scene.g * L))
    return L, V, L / V


# --- segments -------------------------------------------------------------------------------------
def _two_sum(a, b):
    """``(s, e)`` with ``s = fl(a + b)`` and ``a + b = s + e`` exactly (Knuth)."""
    s = a + b
    bb = s - a
    return s, (a - (s - bb)) + (b - bb)


def _segment_dop853(P, t0, q0, dq0, v0, sigma, nsign, t_end, T, deadline, rtol):
    """Integrate one segment from ``(t0, q0 + dq0, v0)``: ``(kind, t, q, dq, v)``, kind in ``"limiter"``,
    ``"domain"``, ``"turn"``, ``"normal"``, ``"t_max"``.

    The position is ``q + dq`` (a float and its residual): the state integrated is the offset
    from ``q0``, so that a bounce of a billionth of the limiter's coordinate keeps its digits.
    """
    from scipy.integrate import solve_ivp

    first = P.calls

    def fun(t, y):
        if P.calls % BUDGET_CHECK_CALLS == 0:
            if time.process_time() > deadline:
                raise _Budget("CPU-time budget spent")
            if P.calls - first > MAX_SEGMENT_CALLS:
                raise RuntimeError(f"DOP853: more than {MAX_SEGMENT_CALLS} calls in one segment (steps collapsed)")
        return P.rates(q0 + y[0], y[1], sigma, nsign)

    a0 = fun(0.0, (dq0, v0))[1]
    v_scale = max(abs(v0), abs(a0) * T)
    h0 = P.frame(q0)[0]
    atol = [ATOL_REL * v_scale * T / h0, ATOL_REL * v_scale]
    events, kinds = [], []
    for kind, qe in P.ahead(sigma):
        ev = (lambda d: lambda t, y: y[0] - d)(qe - q0)
        ev.terminal, ev.direction = True, sigma
        events.append(ev)
        kinds.append((kind, qe))
    turn = lambda t, y: y[1]  # noqa: E731
    turn.terminal, turn.direction = True, -sigma
    normal = lambda t, y: P.normal(q0 + y[0], y[1])  # noqa: E731
    normal.terminal, normal.direction = True, -nsign
    events += [turn, normal]
    kinds += [("turn", None), ("normal", None)]
    sol = solve_ivp(fun, (0.0, t_end - t0), [dq0, v0], method="DOP853", rtol=rtol, atol=atol, events=events,
                    max_step=MAX_STEP_FRACTION * T, dense_output=True)
    if sol.status == -1:
        raise RuntimeError(f"DOP853: {sol.message}")
    hits = [(float(te[0]), i) for i, te in enumerate(sol.t_events) if len(te)]
    if not hits:
        return ("t_max", t_end, *_two_sum(q0, float(sol.y[0, -1])), float(sol.y[1, -1]))
    tau, i = min(hits)
    kind, qe = kinds[i]
    dq, v = (float(x) for x in sol.y_events[i][0])
    if kind == "turn":
        # A grazing approach may cross a limiter and come back within one step: the turn is then past it.
        for kind_, qe_ in P.ahead(sigma):
            if sigma * (dq - (qe_ - q0)) > 0:
                from scipy.optimize import brentq

                tau = brentq(lambda s: sol.sol(s)[0] - (qe_ - q0), 0.0, tau, xtol=ROOT_XTOL * T, rtol=ROOT_RTOL)
                return kind_, t0 + tau, qe_, 0.0, float(sol.sol(tau)[1])
    q, dq = (qe, 0.0) if qe is not None else _two_sum(q0, dq)
    return kind, t0 + tau, q, dq, (0.0 if kind == "turn" else v)


def _gbs_step(P, y, H, sigma, nsign, scales, tol):
    """One extrapolated step of length ``H`` from ``y``: ``(y_new or None if not converged, next H)``.

    The next step is the one that would meet ``tol`` at the least work per unit time
    over the rows computed (each row's error taken as the difference of its two last
    extrapolations, of order ``2 j + 1``).
    """
    f = lambda z: P.rates(z[0], z[1], sigma, nsign)  # noqa: E731
    f0 = f(y)
    table, best, work = [], None, 1
    for j, n in enumerate(GBS_SEQUENCE):
        hs = H / n
        z0, z1 = y, (y[0] + hs * f0[0], y[1] + hs * f0[1])
        for _ in range(n - 1):
            fz = f(z1)
            z0, z1 = z1, (z0[0] + 2 * hs * fz[0], z0[1] + 2 * hs * fz[1])
        fz = f(z1)
        work += n
        row = [((z0[0] + z1[0] + hs * fz[0]) / 2, (z0[1] + z1[1] + hs * fz[1]) / 2)]
        for k in range(1, j + 1):
            r = mpmath.mpf(n) ** 2 / mpmath.mpf(GBS_SEQUENCE[j - k]) ** 2 - 1
            prev, low = row[k - 1], table[j - 1][k - 1]
            row.append((prev[0] + (prev[0] - low[0]) / r, prev[1] + (prev[1] - low[1]) / r))
        table.append(row)
        if j == 0:
            continue
        err = max(abs(row[j][i] - row[j - 1][i]) / (abs(row[j][i]) + scales[i]) for i in (0, 1))
        h_j = H * GBS_GROWTH if err == 0 else min(H * GBS_GROWTH,
                                                   GBS_SAFETY * H * (tol / err) ** (mpmath.mpf(1) / (2 * j + 1)))
        if best is None or work / h_j < best[0]:
            best = (work / h_j, h_j)
        if j >= 2 and err <= tol:
            return row[j], best[1]
    return None, min(best[1], H * GBS_REJECT)


def _advance(P, y, H, sigma, nsign, scales, tol, deadline):
    """``y`` after a time ``H`` (substeps as needed)."""
    done, step = mpmath.mpf(0), H
    while done < H:
        step = min(step, H - done)
        new, h_next = _gbs_step(P, y, step, sigma, nsign, scales, tol)
        if time.process_time() > deadline:
            raise _Budget("CPU-time budget spent")
        if new is None:
            step = h_next
            continue
        y, done = new, done + step
    return y


def _segment_gbs(P, t0, q0, dq0, v0, sigma, nsign, t_end, T, deadline, digits):
    """As :func:`_segment_dop853`, by Gragg-Bulirsch-Stoer extrapolation at ``digits`` digits
    (``q`` an mpf, ``dq`` 0)."""
    tol = mpmath.mpf(10) ** (GBS_GUARD_DIGITS - digits)
    t, y = mpmath.mpf(t0), (mpmath.mpf(q0) + dq0, mpmath.mpf(v0))
    a0 = P.rates(y[0], y[1], sigma, nsign)[1]
    v_scale = max(abs(y[1]), abs(a0) * T)
    scales = (v_scale * T / P.frame(y[0])[0], v_scale)
    funcs = [(kind, (lambda e: lambda z: z[0] - e)(qe), sigma, qe) for kind, qe in P.ahead(sigma)]
    funcs += [("turn", lambda z: z[1], -sigma, None), ("normal", lambda z: P.normal(z[0], z[1]), -nsign, None)]
    H = GBS_FIRST_STEP * T
    hmax = MAX_STEP_FRACTION * T
    before = [fn(y) for _, fn, _, _ in funcs]
    while True:
        if time.process_time() > deadline:
            raise _Budget("CPU-time budget spent")
        H = min(H, t_end - t, hmax)
        new, h_next = _gbs_step(P, y, H, sigma, nsign, scales, tol)
        if new is None:
            H = h_next
            continue
        after = [fn(new) for _, fn, _, _ in funcs]
        found = []
        for (kind, fn, d, qe), g0, g1 in zip(funcs, before, after):
            if (d > 0 and g0 <= 0 <= g1 and g1 != g0) or (d < 0 and g0 >= 0 >= g1 and g1 != g0):
                tau, z = _locate(P, y, H, fn, g0, g1, sigma, nsign, scales, tol, deadline, T)
                found.append((tau, kind, qe, z))
        if found:
            tau, kind, qe, z = min(found, key=lambda x: x[0])
            if kind == "turn":
                # A grazing approach may cross a limiter and come back within one step.
                for (kind_, fn, _, qe_), g0 in zip(funcs, before):
                    if qe_ is not None and fn(z) * sigma > 0:
                        tau, z = _locate(P, y, tau, fn, g0, fn(z), sigma, nsign, scales, tol, deadline, T)
                        kind, qe = kind_, qe_
                        break
            q = qe if qe is not None else z[0]
            return kind, t + tau, q, 0, (mpmath.mpf(0) if kind == "turn" else z[1])
        if t + H >= t_end:
            return "t_max", t_end, new[0], 0, new[1]
        t, y, before = t + H, new, after
        H = h_next


def _locate(P, y, H, fn, g0, g1, sigma, nsign, scales, tol, deadline, T):
    """The time ``tau`` in ``(0, H]`` where ``fn`` of the state reaches 0, and the state there
    (Newton on ``tau`` with a finite-difference derivative along the flow, kept in its bracket)."""
    lo, hi, glo = mpmath.mpf(0), H, g0
    tau = H * g0 / (g0 - g1)
    eps = mpmath.mpf(10) ** (-mpmath.mp.dps * GBS_FD_EXPONENT) * T
    z = None
    for _ in range(GBS_ROOT_ITERATIONS):
        z = _advance(P, y, tau, sigma, nsign, scales, tol, deadline)
        gz = fn(z)
        if gz == 0:
            return tau, z
        if (gz > 0) == (glo > 0):
            lo, glo = tau, gz
        else:
            hi = tau
        dq, dv = P.rates(z[0], z[1], sigma, nsign)
        slope = (fn((z[0] + eps * dq, z[1] + eps * dv)) - fn((z[0] - eps * dq, z[1] - eps * dv))) / (2 * eps)
        step = -gz / slope if slope != 0 else mpmath.inf
        new = tau + step
        if not (lo < new < hi):
            new = (lo + hi) / 2
        if abs(new - tau) <= tol * T or hi - lo <= tol * T:
            tau = new
            break
        tau = new
    z = _advance(P, y, tau, sigma, nsign, scales, tol, deadline)
    return tau, z


# --- the event loop -------------------------------------------------------------------------------
def reference_run(scene, method: str = "DOP853", *, rtol: float = RTOL, digits: int = GBS_DIGITS,
                  budget: float = BUDGET_SECONDS, max_events: int | None = None,
                  t_max: float | None = None) -> ReferenceRun:
    """Simulate ``scene`` by time integration of eq. 1 (see the module docstring).

    Parameters
    ----------
    scene : symvib.numeric.scene.Scene
    method : {"DOP853", "GBS"}
        Double-precision DOP853, or 30-digit extrapolation (:data:`METHODS`).
    rtol : float
        Relative tolerance of DOP853.
    digits : int
        Digits of the GBS arithmetic.
    budget : float
        CPU seconds; a run that spends them ends ``"failed"``.
    max_events, t_max : optional
        Bounds replacing the scene's.

    Returns
    -------
    ReferenceRun
    """
    if method not in METHODS:
        raise ValueError(f"method: one of {METHODS}, got {method!r}")
    max_events = scene.max_events if max_events is None else max_events
    t_max = scene.t_max if t_max is None else t_max
    deadline = time.process_time() + budget
    if method == "GBS":
        with mpmath.workdps(digits):
            return _run(scene, _Physics(scene, digits), method, max_events, t_max, deadline,
                        lambda *a: _segment_gbs(*a, digits))
    return _run(scene, _Physics(scene), method, max_events, t_max, deadline, lambda *a: _segment_dop853(*a, rtol))


def _run(scene, P, method, max_events, t_max, deadline, segment):
    T = P.num(scene_scales(scene)[2])
    events, v_start = [], []
    num = P.num
    t, q, dq = num(0), num(scene.q0), 0
    v = P.frame(q)[0] * num(scene.qdot0)
    status, message = None, ""

    def put(kind, t, q, before, after, v0=0.0):
        events.append((kind, float(t), float(q), float(before), float(after)))
        v_start.append(abs(float(v0)))

    def at_rest(q, side, v0=0.0):
        nonlocal status
        what, direction = P.rest(q, side)
        if what != "slide":
            put(what, t, q, 0.0, 0.0, v0)
            status = "arrested" if what == "arrest" else "resting_on_limiter"
        return direction

    sigma = 0 if v == 0 else (1 if v > 0 else -1)
    side = P.side(q)
    pending = sigma != 0 and side == sigma
    flipped, v_seg = None, v
    try:
        if P.unilateral and P.normal(q, v) < 0:
            qd = v / P.frame(q)[0]
            put("left_curve", t, q, qd, qd)
            status = "left_curve"
        elif sigma == 0:
            sigma = at_rest(q, side)
        while status is None:
            if pending:
                pending = False
                qd = v / P.frame(q)[0]
                put("impact", t, q, qd, -P.k * qd, v_seg)
                side, v, sigma = sigma, -P.k * v, -sigma
                if v == 0:
                    sigma = at_rest(q, side)
                    if status is not None:
                        break
            if len(events) >= max_events:
                status = "max_events"
                break
            if t >= t_max:
                status = "t_max"
                break
            nsign = flipped if flipped is not None else P.nsign(q, v)
            flipped = None
            if P.unilateral and nsign < 0:
                qd = v / P.frame(q)[0]
                put("left_curve", t, q, qd, qd)
                status = "left_curve"
                break
            v_seg = v
            kind, t, q, dq, v = segment(P, t, q, dq, v, sigma, nsign, num(t_max), T, deadline)
            if not all(math.isfinite(float(x)) for x in (t, q, v)):
                raise FloatingPointError("the state stopped being finite")
            if kind == "t_max":
                status = "t_max"
            elif kind == "domain":
                status = "left_domain"
            elif kind == "limiter":
                pending = True
            elif kind == "normal":
                qd = v / P.frame(q)[0]
                if P.unilateral:
                    put("left_curve", t, q, qd, qd, v_seg)
                    status = "left_curve"
                else:
                    put("normal_sign_change", t, q, qd, qd, v_seg)
                    flipped = -nsign
            else:
                sigma = at_rest(q, P.side(q) if dq == 0 else 0, v_seg)
                if status is None:
                    put("reversal", t, q, 0.0, 0.0, v_seg)
    except (_Budget, RuntimeError, FloatingPointError, ZeroDivisionError, ValueError, OverflowError) as exc:
        status, message = "failed", f"{type(exc).__name__}: {exc}"
    qd_final = float(v / P.frame(q)[0]) if status != "failed" else float("nan")
    return ReferenceRun(status, tuple(events), message, method, tuple(v_start), float(t), float(q), qd_final,
                        P.calls)
