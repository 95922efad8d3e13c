"""Peer methods for comparison: time-stepping integrators with event location.

Both integrate the equation of motion (eq. 1) in time from the generated
kernels (``qddot_p``/``qddot_m``), with the branch fixed per segment and the
same physics at events as the driver (impact ``v -> -k v``; at rest: arrest
when ``|tan alpha| <= mu_s`` (static friction), rest on a limiter that gravity pushes into, else
slide downhill):

* :func:`solve_ivp_events` -- :func:`scipy.integrate.solve_ivp` (RK45,
  DOP853, Radau, LSODA, ...), restarted at every event, with terminal events
  for the limiters, the turning point (``qdot = 0``) and, where it can change
  sign, the normal force;
* :func:`rk4_events` -- classical fixed-step RK4, the event located by
  bisection on the step's cubic Hermite interpolant.

SciPy is needed only here (the ``bench`` extra).  Both return the same
:class:`PeerRun` record; ``status`` is one of the driver's status values or
``"failed"``.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from symvib.numeric.kernels import load

__all__ = ["PeerRun", "PeerBudget", "solve_ivp_events", "rk4_events"]

#: Relative tolerance of the arrest test (same as the driver's).
CONE_RTOL = 1e-9
#: Bisection steps of the RK4 event location.
BISECT = 60
#: Right-hand-side calls between two checks of a run's CPU-time budget.
BUDGET_CHECK_CALLS = 256


class PeerBudget(RuntimeError):
    """A peer run spent its CPU-time budget (``budget=`` seconds): it did not finish."""


@dataclass(frozen=True)
class PeerRun:
    """Events found by a peer method: ``(kind, t, q, qdot_before, qdot_after)`` tuples."""

    method: str
    status: str
    events: tuple
    seconds: float
    steps: int = 0
    message: str = ""
    rhs_calls: int = field(default=0)


class _Physics:
    def __init__(self, scene, budget=None):
        self.scene = scene
        self.deadline = None if budget is None else time.process_time() + budget
        self.budget = budget
        self.mod = load(scene.shape)
        self.cp = scene.param_values
        self.g, self.mu, self.k = scene.g, scene.mu, scene.k
        self.mu_s = scene.mu_static   # the rest test's (static) friction
        self.qdd = {1: self.mod.qddot_p_scalar, -1: self.mod.qddot_m_scalar}
        self.calls = 0

    def h(self, q):
        return self.mod.h_scalar(q, *self.cp)

    def N(self, q, qdot):
        h = self.h(q)
        return self.mod.N_w_scalar(q, (h * qdot) ** 2, self.g, *self.cp)

    def rhs(self, s):
        f, g, mu, cp = self.qdd[s], self.g, self.mu, self.cp

        def rhs(t, y):
            self.calls += 1
            if self.deadline is not None and self.calls % BUDGET_CHECK_CALLS == 0 \
                    and time.process_time() > self.deadline:
                raise PeerBudget(f"CPU-time budget of {self.budget:g} s spent")
            return [y[1], f(y[0], y[1], g, mu, *cp)]

        return rhs

    def rest(self, q, side):
        h = self.h(q)
        sin = self.mod.dz_scalar(q, *self.cp) / h
        cos = self.mod.dx_scalar(q, *self.cp) / h
        if side and -sin * side > 0:
            return "rest_on_limiter", 0
        if abs(sin) <= self.mu_s * abs(cos) * (1 + CONE_RTOL) + 4e-16:
            return "arrest", 0
        return "slide", 1 if -sin > 0 else -1


def _segments(scene, step_segment, method_name, budget=None):
    """The event loop shared by the peers: ``step_segment(y0, t0, s, sigma)`` integrates one segment.

    With ``budget`` (CPU seconds) a run that spends it stops with status
    ``"failed"`` and a :class:`PeerBudget` message.
    """
    P = _Physics(scene, budget)
    start = time.perf_counter()
    q, qdot = scene.q0, scene.qdot0
    t = 0.0
    events = []
    steps = 0
    left, right = scene.left, scene.right
    side = 1 if right is not None and q == right else -1 if left is not None and q == left else 0
    sigma = 0 if qdot == 0 else (1 if qdot > 0 else -1)
    status = None
    # After an N = 0 event the next segment takes the other sign of N: at the
    # restart point N is zero to rounding, and its computed sign may still be
    # the old one, which would find the same event again at zero distance.
    flipped = None
    if sigma == 0:
        what, sigma = P.rest(q, side)
        if what != "slide":
            events.append((what, t, q, 0.0, 0.0))
            status = "arrested" if what == "arrest" else "resting_on_limiter"
    elif side == sigma:
        events.append(("impact", t, q, qdot, -scene.k * qdot))
        qdot, sigma = -scene.k * qdot, -sigma
        if qdot == 0:
            what, sigma = P.rest(q, side)
            if what != "slide":
                events.append((what, t, q, 0.0, 0.0))
                status = "arrested" if what == "arrest" else "resting_on_limiter"
    while status is None:
        if len(events) >= scene.max_events:
            status = "max_events"
            break
        if flipped is not None:
            nsign, flipped = flipped, None
        else:
            n0 = P.N(q, qdot)
            nsign = 1 if n0 > 0 else -1 if n0 < 0 else 1
        s = sigma * nsign
        try:
            kind, tb, qb, qdb, nsteps = step_segment(P, (q, qdot), t, s, sigma, nsign)
        except Exception as exc:  # noqa: BLE001 - a failing peer is an outcome to report
            return PeerRun(method_name, "failed", tuple(events), time.perf_counter() - start, steps,
                           f"{type(exc).__name__}: {exc}", P.calls)
        steps += nsteps
        if not (math.isfinite(tb) and math.isfinite(qb) and math.isfinite(qdb)):
            return PeerRun(method_name, "failed", tuple(events), time.perf_counter() - start, steps,
                           "non-finite state", P.calls)
        t = tb
        if kind == "t_max":
            status = "t_max"
            break
        if kind == "impact":
            events.append(("impact", t, qb, qdb, -scene.k * qdb))
            q, qdot, sigma = qb, -scene.k * qdb, -sigma
            if qdot == 0:
                what, sigma = P.rest(q, 1 if qb == right else -1)
                if what != "slide":
                    events.append((what, t, q, 0.0, 0.0))
                    status = "arrested" if what == "arrest" else "resting_on_limiter"
            continue
        if kind == "normal_sign_change":
            events.append(("normal_sign_change", t, qb, qdb, qdb))
            q, qdot, flipped = qb, qdb, -nsign
            continue
        what, direction = P.rest(qb, 0)
        if what != "slide":
            events.append((what, t, qb, 0.0, 0.0))
            status = "arrested" if what == "arrest" else "resting_on_limiter"
        else:
            events.append(("reversal", t, qb, 0.0, 0.0))
            q, qdot, sigma = qb, 0.0, direction
    return PeerRun(method_name, status, tuple(events), time.perf_counter() - start, steps, "", P.calls)


def solve_ivp_events(scene, method: str = "DOP853", rtol: float = 1e-10, atol: float | None = None,
                     max_step: float = math.inf, budget: float | None = None) -> PeerRun:
    """Integrate ``scene`` with :func:`scipy.integrate.solve_ivp`, restarted at every event.

    ``budget`` (CPU seconds, optional) bounds the run (status ``"failed"``, :class:`PeerBudget`).
    """
    from scipy.integrate import solve_ivp

    atol = rtol * 1e-2 if atol is None else atol

    def segment(P, y0, t0, s, sigma, nsign):
        right, left = scene.right, scene.left
        events = []
        kinds = []
        if right is not None and sigma > 0:
            ev = lambda t, y: y[0] - right  # noqa: E731
            ev.terminal, ev.direction = True, 1
            events.append(ev)
            kinds.append("impact")
        if left is not None and sigma < 0:
            ev = lambda t, y: y[0] - left  # noqa: E731
            ev.terminal, ev.direction = True, -1
            events.append(ev)
            kinds.append("impact")
        turn = lambda t, y: y[1]  # noqa: E731
        turn.terminal, turn.direction = True, -sigma
        events.append(turn)
        kinds.append("reversal")
        normal = lambda t, y: P.N(y[0], y[1])  # noqa: E731
        normal.terminal, normal.direction = True, -nsign
        events.append(normal)
        kinds.append("normal_sign_change")
        sol = solve_ivp(P.rhs(s), (t0, scene.t_max), list(y0), method=method, rtol=rtol, atol=atol,
                        events=events, max_step=max_step)
        if sol.status == -1:
            raise RuntimeError(sol.message)
        nsteps = len(sol.t)
        for ev_t, ev_y, kind in zip(sol.t_events, sol.y_events, kinds):
            if len(ev_t):
                q, qd = ev_y[0]
                if kind == "impact":
                    q = right if sigma > 0 else left
                if kind == "reversal":
                    qd = 0.0
                return kind, float(ev_t[0]), float(q), float(qd), nsteps
        return "t_max", scene.t_max, float(sol.y[0, -1]), float(sol.y[1, -1]), nsteps

    return _segments(scene, segment, f"solve_ivp {method} rtol={rtol:g}", budget)


def rk4_events(scene, dt: float, budget: float | None = None) -> PeerRun:
    """Classical RK4 with a fixed step ``dt``; events by bisection on the Hermite interpolant.

    ``budget`` (CPU seconds, optional) bounds the run (status ``"failed"``, :class:`PeerBudget`).
    """

    def segment(P, y0, t0, s, sigma, nsign):
        f = P.rhs(s)
        right, left = scene.right, scene.left
        q, v = y0
        t = t0
        nsteps = 0
        a = f(t, (q, v))[1]

        def crossings(q0, v0, a0, q1, v1, a1, h):
            # Event functions on the cubic Hermite interpolant of the step.
            def state(th):
                t2, t3 = th * th, th * th * th
                h00, h10, h01, h11 = 2 * t3 - 3 * t2 + 1, t3 - 2 * t2 + th, -2 * t3 + 3 * t2, t3 - t2
                qq = h00 * q0 + h10 * h * v0 + h01 * q1 + h11 * h * v1
                vv = h00 * v0 + h10 * h * a0 + h01 * v1 + h11 * h * a1
                return qq, vv

            tests = []
            if right is not None and sigma > 0:
                tests.append(("impact", lambda th: state(th)[0] - right))
            if left is not None and sigma < 0:
                tests.append(("impact", lambda th: left - state(th)[0]))
            tests.append(("reversal", lambda th: -sigma * state(th)[1]))
            tests.append(("normal_sign_change", lambda th: -nsign * P.N(*state(th))))
            best = None
            for kind, fn in tests:
                if fn(1.0) >= 0 and fn(0.0) < 0:
                    lo, hi = 0.0, 1.0
                    for _ in range(BISECT):
                        mid = 0.5 * (lo + hi)
                        if fn(mid) >= 0:
                            hi = mid
                        else:
                            lo = mid
                    if best is None or hi < best[1]:
                        best = (kind, hi, state(hi))
            return best

        while t < scene.t_max:
            h = min(dt, scene.t_max - t)
            k1 = (v, a)
            k2 = f(t, (q + 0.5 * h * k1[0], v + 0.5 * h * k1[1]))
            k3 = f(t, (q + 0.5 * h * k2[0], v + 0.5 * h * k2[1]))
            k4 = f(t, (q + h * k3[0], v + h * k3[1]))
            q1 = q + h * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0]) / 6
            v1 = v + h * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1]) / 6
            a1 = f(t + h, (q1, v1))[1]
            nsteps += 1
            hit = crossings(q, v, a, q1, v1, a1, h)
            if hit is not None:
                kind, th, (qe, ve) = hit
                if kind == "impact":
                    qe = right if sigma > 0 else left
                if kind == "reversal":
                    ve = 0.0
                return kind, t + th * h, qe, ve, nsteps
            q, v, a, t = q1, v1, a1, t + h
            if not (math.isfinite(q) and math.isfinite(v)):
                return "t_max", t, q, v, nsteps
        return "t_max", scene.t_max, q, v, nsteps

    return _segments(scene, segment, f"RK4 dt={dt:g}", budget)


def event_errors(events, reference) -> tuple:
    """(same sequence?, max |dt|, max |dq|) of peer events against reference events."""
    n = min(len(events), len(reference))
    same = len(events) >= len(reference) and all(
        e[0] == (r.kind if hasattr(r, "kind") and isinstance(r.kind, str) else r.kind.value)
        for e, r in zip(events, reference))
    dt = max((abs(e[1] - float(r.t)) for e, r in zip(events[:n], reference[:n])), default=np.inf)
    dq = max((abs(e[2] - float(r.q)) for e, r in zip(events[:n], reference[:n])), default=np.inf)
    return same, dt, dq
