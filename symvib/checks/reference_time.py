"""A time-stepping reference at high precision: eq. 1 integrated in time with mpmath.

:func:`time_reference` shares no numerics with the driver (no closed-form
phase trajectory, no quadrature in ``q``) nor with
:func:`symvib.checks.reference.phase_reference`: it integrates the equation of
motion (paper eq. 1) on the branch ``s = sigma * sign(N)`` fixed per segment,

    qddot = -A_s(q) qdot**2 - B_s(q),
    A_s = h'/h + s mu alpha',   B_s = g (z' + s mu x') / h**2,

with ``A_s``, ``B_s`` from the SymPy derivation (:func:`symvib.symbolic.derive.coefficients`)
evaluated by ``lambdify(..., "mpmath")`` at ``dps`` digits.  The integrator is
Gragg-Bulirsch-Stoer extrapolation (modified midpoint rule, step numbers
``2, 4, 6, ...``, Aitken-Neville in ``H**2``): its order grows until the
extrapolation tableau agrees to ``10**-(dps - GUARD_DIGITS)`` relative, so the
steps are long and the result is accurate to about ``dps - GUARD_DIGITS``
digits.  Events have their own location: after a step, the event functions

* limiter ahead: ``sigma (q - q_lim)``,
* turning point: ``-sigma qdot``,
* normal force: ``-sign(N) N(q, qdot)``, ``N = kappa h**2 qdot**2 + g x'/h``,

are checked at its end; the earliest one that became ``>= 0`` is located by
an Illinois iteration on the length of a fresh extrapolated step from the
step's start, so an event is as accurate as a step.  At events the physics is
physics.md's (impact ``qdot -> -k qdot``; at rest: arrest when
``|tan alpha| <= mu_s``, the static friction, rest on a limiter that gravity pushes into, else slide
downhill).

It is slow (about 10 ms per step at 30 digits); results used by the
benchmarks ship in ``symvib/checks/data/time_reference.json`` (see
:mod:`symvib.checks.bench.paper_references`, ``symvib bench reference``).

Examples
--------
>>> from symvib.numeric.scene import scene_from_dict
>>> s = scene_from_dict({"curve": {"shape": "circle"}, "parameters": {"R": 0.5},
...     "physics": {"mu": 3, "restitution": 1}, "limiters": {"right": "pi/4"},
...     "initial": {"q": "pi/12", "qdot": 3.8}})
>>> [(e.kind, round(float(e.q), 9)) for e in time_reference(s, dps=20)]
[('arrest', 0.350089206)]
"""
from __future__ import annotations

import time

import mpmath
import sympy as sp

from symvib.checks.reference import RefEvent
from symvib.symbolic.derive import coefficients
from symvib.symbolic.symbols import g as g_sym
from symvib.symbolic.symbols import mu as mu_sym
from symvib.symbolic.symbols import sigma as sigma_sym

__all__ = ["time_reference", "time_reference_states", "TimeReferenceBudget", "GUARD_DIGITS"]

#: Digits kept as guard: steps are accepted at ``10**-(dps - GUARD_DIGITS)``.
GUARD_DIGITS = 4
#: Columns of the extrapolation tableau (order up to ``2 * LEVELS``).
LEVELS = 12
#: Longest step, in seconds (keeps double crossings of an event function out of one step).
MAX_STEP = 0.02
#: First step, in seconds.
FIRST_STEP = 1e-3
#: Iterations of the event location.
ROOT_ITERATIONS = 200
#: Default budget of one run, in seconds of CPU time.
BUDGET_SECONDS = 600.0
#: Deepest halving of a probe's step (:func:`time_reference_states`) before it is given up.
ADVANCE_DEPTH = 30
#: Relative tolerance of the arrest test (the driver's and the peers').
CONE_RTOL = 1e-9


class TimeReferenceBudget(RuntimeError):
    """The time reference ran out of its budget (steps or CPU seconds)."""


class _Model:
    def __init__(self, scene):
        c = scene.shape.curve()
        self.curve = c
        vals = {p: sp.Float(repr(v), 40) for p, v in zip(c.params, scene.param_values)}
        vals[g_sym] = sp.Float(repr(scene.g), 40)
        vals[mu_sym] = sp.Float(repr(scene.mu), 40)
        A, B = coefficients(c.xp, c.zp, c.h, c.hp, c.alphap)
        lam = lambda e: sp.lambdify(c.q, sp.sympify(e).subs(vals), "mpmath")  # noqa: E731
        self.AB = {s: sp.lambdify(c.q, [A.subs(sigma_sym, s).subs(vals), B.subs(sigma_sym, s).subs(vals)],
                                  "mpmath", cse=True) for s in (1, -1)}
        self.h, self.xp, self.zp, self.kappa = lam(c.h), lam(c.xp), lam(c.zp), lam(c.kappa)
        self.g = mpmath.mpf(repr(scene.g))
        self.mu = mpmath.mpf(repr(scene.mu))
        self.mu_s = mpmath.mpf(repr(scene.mu_static))   # the rest test's (static) friction

    def N(self, q, v):
        h = self.h(q)
        return self.kappa(q) * h * h * v * v + self.g * self.xp(q) / h


def _gbs_step(f, y0, H, tol):
    """One Gragg-Bulirsch-Stoer step of length ``H``: ``(y1, converged)``."""
    prev = None
    for j in range(1, LEVELS + 1):
        n = 2 * j
        h = H / n
        z0 = list(y0)
        d = f(z0)
        z1 = [a + h * b for a, b in zip(z0, d)]
        for _ in range(n - 1):
            d = f(z1)
            z0, z1 = z1, [a + 2 * h * b for a, b in zip(z0, d)]
        d = f(z1)
        T = [[(a + b + h * c) / 2 for a, b, c in zip(z0, z1, d)]]
        for k in range(1, j):
            ratio = mpmath.mpf(n) ** 2 / mpmath.mpf(2 * (j - k)) ** 2 - 1
            T.append([a + (a - b) / ratio for a, b in zip(T[k - 1], prev[k - 1])])
        if j > 2:
            err = max(abs(a - b) for a, b in zip(T[-1], T[-2]))
            scale = max(max(abs(a) for a in T[-1]), mpmath.mpf(1))
            if err <= tol * scale:
                return T[-1], j
        prev = T
    return prev[-1], None


def time_reference(scene, *, dps: int = 30, max_events: int | None = None, budget: float = BUDGET_SECONDS,
                   max_step: float = MAX_STEP) -> list:
    """Events of ``scene`` by time integration of eq. 1 at ``dps`` digits.

    Parameters
    ----------
    scene : Scene
    dps : int
        Working digits; events are accurate to about ``dps - GUARD_DIGITS`` digits.
    max_events : int, optional
        Stop after this many events (default ``scene.max_events``); a Zeno
        accumulation is not summed, so cap it.
    budget : float
        CPU seconds before :class:`TimeReferenceBudget` is raised.
    max_step : float
        Longest step in seconds.

    Returns
    -------
    list of RefEvent
        ``kind`` is ``"impact"``, ``"reversal"``, ``"arrest"``, ``"rest_on_limiter"`` or
        ``"normal_sign_change"``; stops at arrest, rest, ``max_events`` or ``scene.t_max``.
    """
    return _run(scene, dps, max_events, budget, max_step, ())[0]


def time_reference_states(scene, times, *, dps: int = 30, max_events: int | None = None,
                          budget: float = BUDGET_SECONDS, max_step: float = MAX_STEP) -> list:
    """The state ``(q, qdot)`` at each of ``times``, by the same time integration as :func:`time_reference`.

    Each state is a fresh extrapolated step from the last accepted step (or event)
    before it, so it is as accurate as an event (about ``dps - GUARD_DIGITS``
    digits); at an event's time it is the state after the event, after an arrest or
    a rest the rest state.  The reference of the dense output
    (:mod:`symvib.numeric.dense`).

    Returns
    -------
    list of (mpf, mpf) or None
        In the order of ``times``; None for a time past the end of a run that did
        not come to rest (``t_max``, ``max_events``).

    Examples
    --------
    >>> from symvib.numeric.scene import scene_from_dict
    >>> s = scene_from_dict({"curve": {"z": "c*x"}, "parameters": {"c": 0.5},
    ...     "physics": {"mu": 0, "restitution": 1}, "initial": {"q": 0, "qdot": 1}})
    >>> q, qdot = time_reference_states(s, [0.1], dps=20, max_events=1)[0]   # qdot = 1 - g sin a cos a t
    >>> round(float(qdot), 12) == round(1 - 9.81 * 0.4 * 0.1, 12)
    True
    """
    return _run(scene, dps, max_events, budget, max_step, times)[1]


def _advance(f, y, H, tol, depth=0):
    """``y`` advanced by ``H`` with extrapolated steps (halved until they converge)."""
    if H == 0:
        return list(y)
    y1, level = _gbs_step(f, y, H, tol)
    if level is not None:
        return y1
    if depth > ADVANCE_DEPTH:
        raise TimeReferenceBudget("time_reference: a probe step did not converge")
    return _advance(f, _advance(f, y, H / 2, tol, depth + 1), H / 2, tol, depth + 1)


def _run(scene, dps, max_events, budget, max_step, times):
    """Events and the states at ``times`` (:func:`time_reference`, :func:`time_reference_states`)."""
    max_events = scene.max_events if max_events is None else max_events
    start_cpu = time.process_time()
    with mpmath.workdps(dps):
        M = _Model(scene)
        mp = mpmath.mpf
        tol = mp(10) ** (-(dps - GUARD_DIGITS))
        k = mp(repr(scene.k))
        left = None if scene.left is None else mp(repr(scene.left))
        right = None if scene.right is None else mp(repr(scene.right))
        t_max = mp(repr(scene.t_max))
        q, v, t = mp(repr(scene.q0)), mp(repr(scene.qdot0)), mp(0)
        events = []
        targets = [mp(repr(float(x))) for x in times]
        order = sorted(range(len(targets)), key=lambda j: targets[j])
        states = [None] * len(targets)
        done = [0]  # probes recorded, in time order

        def record(f, y, t0, upto, inclusive=False):
            """The states of the probes at t0 <= time < upto (<= upto if inclusive), from y at t0."""
            while done[0] < len(order):
                j = order[done[0]]
                if targets[j] > upto or (targets[j] == upto and not inclusive):
                    return
                if targets[j] >= t0:
                    states[j] = tuple(_advance(f, y, targets[j] - t0, tol))
                done[0] += 1

        def at_rest(x):
            """The states of the remaining probes: at rest at x."""
            for j in order[done[0]:]:
                states[j] = (x, mp(0))
            done[0] = len(order)

        def at_limiter(x):
            return 1 if right is not None and x == right else -1 if left is not None and x == left else 0

        def rest(x):
            h = M.h(x)
            sin, cos = M.zp(x) / h, M.xp(x) / h
            side = at_limiter(x)
            if side and -sin * side > 0:
                return "rest_on_limiter", 0
            if abs(sin) <= M.mu_s * abs(cos) * (1 + mp(CONE_RTOL)):
                return "arrest", 0
            return "slide", 1 if -sin > 0 else -1

        sigma = 0 if v == 0 else (1 if v > 0 else -1)
        if sigma == 0:
            what, sigma = rest(q)
            if what != "slide":
                at_rest(q)
                return [RefEvent(what, t, q, mp(0), mp(0))], states
        elif at_limiter(q) == sigma:
            events.append(RefEvent("impact", t, q, v, -k * v))
            v, sigma = -k * v, -sigma
            if v == 0:
                what, sigma = rest(q)
                if what != "slide":
                    events.append(RefEvent(what, t, q, mp(0), mp(0)))
                    at_rest(q)
                    return events, states
        nsign = None
        H = mp(FIRST_STEP)
        H_max = mp(max_step)
        while len(events) < max_events:
            if nsign is None:
                n0 = M.N(q, v)
                nsign = 1 if n0 > 0 else -1 if n0 < 0 else (1 if M.xp(q) >= 0 else -1)
            s = sigma * nsign
            AB = M.AB[s]

            def f(y, AB=AB):
                A, B = AB(y[0])
                return [y[1], -A * y[1] ** 2 - B]

            bound = right if sigma > 0 else left
            sg, ns = sigma, nsign
            checks = [("reversal", lambda y: -sg * y[1]), ("normal_sign_change", lambda y: -ns * M.N(y[0], y[1]))]
            if bound is not None:
                checks.insert(0, ("impact", lambda y, b=bound: sg * (y[0] - b)))
            y = [q, v]
            found = None
            while found is None:
                if time.process_time() - start_cpu > budget:
                    raise TimeReferenceBudget(f"time_reference: budget of {budget:g} s spent at t = {float(t):.6g}")
                H = min(H, H_max)
                last = t + H >= t_max
                if last:
                    H = t_max - t
                y1, level = _gbs_step(f, y, H, tol)
                if level is None:
                    H /= 2
                    if H < mp(10) ** (-dps):
                        raise TimeReferenceBudget("time_reference: step size underflow")
                    continue
                hit = [(kind, fn) for kind, fn in checks if fn(y1) >= 0]
                if hit:
                    best = None
                    for kind, fn in hit:
                        hr = _locate(lambda h, fn=fn: fn(_gbs_step(f, y, h, tol)[0]), fn(y), fn(y1), H, tol)
                        if best is None or hr < best[1]:
                            best = (kind, hr)
                    kind, hr = best
                    y_ev = _gbs_step(f, y, hr, tol)[0]
                    found = (kind, t + hr, y_ev)
                    record(f, y, t, t + hr)
                    break
                record(f, y, t, t + H, inclusive=last)
                t += H
                y = y1
                if last:
                    return events, states
                if level <= LEVELS // 2:
                    H *= mp(3) / 2
                elif level >= LEVELS - 1:
                    H *= mp(2) / 3
            kind, t, (qb, vb) = found
            if kind == "impact":
                qb = bound
                events.append(RefEvent("impact", t, qb, vb, -k * vb))
                q, v, sigma, nsign = qb, -k * vb, -sigma, None
                if v == 0:
                    what, sigma = rest(q)
                    if what != "slide":
                        events.append(RefEvent(what, t, q, mp(0), mp(0)))
                        at_rest(q)
                        break
                continue
            if kind == "normal_sign_change":
                events.append(RefEvent(kind, t, qb, vb, vb))
                q, v, nsign = qb, vb, -nsign
                continue
            what, direction = rest(qb)
            if what != "slide":
                events.append(RefEvent(what, t, qb, mp(0), mp(0)))
                at_rest(qb)
                break
            events.append(RefEvent("reversal", t, qb, mp(0), mp(0)))
            q, v, sigma, nsign = qb, mp(0), direction, None
        return events, states


def _locate(phi, fa, fb, H, tol):
    """Illinois iteration for the root of ``phi`` on ``[0, H]`` (``phi(0) = fa <= 0 <= phi(H) = fb``)."""
    a, b = mpmath.mpf(0), H
    side = 0
    c_prev = None
    for _ in range(ROOT_ITERATIONS):
        c = b - fb * (b - a) / (fb - fa) if fb != fa else (a + b) / 2
        if not a < c < b:
            c = (a + b) / 2
        fc = phi(c)
        if fc == 0:
            return c
        if fc > 0:
            b, fb = c, fc
            if side == 1:
                fa /= 2
            side = 1
        else:
            a, fa = c, fc
            if side == -1:
                fb /= 2
            side = -1
        if c_prev is not None and abs(c - c_prev) <= tol * H * mpmath.mpf("1e-3"):
            return c
        c_prev = c
    raise TimeReferenceBudget("time_reference: event location did not converge")
