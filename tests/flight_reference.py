"""An independent integrator of unilateral runs with flights, written from docs/physics.md alone.

Not from the engine, its kernels or :mod:`symvib.numeric.flight`: each curve is written out
by hand here (``x, z`` and their first two derivatives); sliding is ``dv/dt = -g sin(alpha) -
mu sigma N`` ("Equation of motion") integrated by scipy's DOP853 in time with its events
``N = 0`` (lift-off) and ``v = 0`` (a turning point, where the rest test of "Events" 2 says
arrest or reversal); a flight is the closed-form parabola and its landing the first sign change
of an explicit signed function (the height above a graph, ``R - |P - centre|`` inside the
circle) found by a dense scan in growing windows and brentq; the landing law, the bounce and
the bouncing-ball accumulation are those of "Flight and landing".
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

#: DOP853 tolerances (relative; absolute in the coordinate's units).
RTOL, ATOL = 1e-13, 1e-14
#: Rest test slack (physics.md, "Events" 2: within a relative 1e-9, the cone edge).
CONE_RTOL = 1e-9
#: Samples per scanned window of a flight, and the first window (s) of a lift-off.
SCAN, FIRST_WINDOW = 4000, 0.02
#: A scanned value counts as off the curve above this (m): a lift-off's start is a graze.
SEPARATED = 1e-10
#: The accumulation threshold of physics.md: u^2 < 1e-10 g L.
ACC_W = 1e-10


@dataclass(frozen=True)
class Curve:
    """A curve by hand: ``curve`` (the scene's [curve] table), ``f(q, p) -> (x, z, x', z', x'', z'')``,
    the signed height of a point above it (``side(X, Z, p)``, > 0 on the particle's side) and the
    ``q`` of a point on it (``q_of(X, Z, p, near)``)."""

    curve: dict
    f: object
    side: object
    q_of: object


def _circle(q, p):
    R = p["R"]
    s, c = math.sin(q), math.cos(q)
    return R * s, R * (1 - c), R * c, R * s, -R * s, R * c


def _circle_q(X, Z, p, near):
    phi = math.atan2(X, p["R"] - Z)
    return phi + 2 * math.pi * round((near - phi) / (2 * math.pi))


def _sine(q, p):
    a, b = p["a"], p["b"]
    return q, a * (1 - math.cos(q / b)), 1.0, a / b * math.sin(q / b), 0.0, a / b / b * math.cos(q / b)


def _well(q, p):
    a, b = p["a"], p["b"]
    return q, a * q ** 4 - b * q * q, 1.0, 4 * a * q ** 3 - 2 * b * q, 0.0, 12 * a * q * q - 2 * b


CURVES = {
    "circle": Curve({"shape": "circle"}, _circle,
                    lambda X, Z, p: p["R"] - np.hypot(X, Z - p["R"]), _circle_q),
    "sine": Curve({"z": "a*(1 - cos(x/b))", "name": "flight-sine"}, _sine,
                  lambda X, Z, p: Z - p["a"] * (1 - np.cos(X / p["b"])), lambda X, Z, p, near: X),
    "well": Curve({"z": "a*x**4 - b*x**2", "name": "flight-well"}, _well,
                  lambda X, Z, p: Z - (p["a"] * X ** 4 - p["b"] * X * X), lambda X, Z, p, near: X),
}


@dataclass
class Run:
    events: list = field(default_factory=list)   # (kind, t)
    status: str = ""


def reference_run(scene, curve: Curve, scale: float | None) -> Run:
    """The events (kind, time) and the status of ``scene`` (unilateral, no limiters) by this integrator;
    ``scale`` is the run's length scale in ``q`` (the accumulation's threshold, physics.md)."""
    p, g, mu, e = scene.param_dict, scene.g, scene.mu, scene.restitution_curve
    mu_s = scene.mu_static
    run = Run()

    def geo(q):
        x, z, dx, dz, ddx, ddz = curve.f(q, p)
        h = math.hypot(dx, dz)
        return x, z, dx, dz, h, (dx * ddx + dz * ddz) / h, (dx * ddz - dz * ddx) / h ** 3

    def normal(q, qd):   # N = kappa w + g cos(alpha)
        _, _, dx, _, h, _, kappa = geo(q)
        return kappa * (h * qd) ** 2 + g * dx / h

    def full():
        if len(run.events) >= scene.max_events:
            run.status = "max_events"
            return True
        return False

    def slide(t, q, qd):
        """Slide from (t, q, qd): ('lift', t, q, qd) or None (the run ended)."""
        while True:
            if full():
                return None
            if normal(q, qd) < 0:
                run.events.append(("lift_off", t))
                return t, q, qd
            if qd == 0.0:
                _, _, dx, dz, h, _, _ = geo(q)
                if abs(dz) <= mu_s * abs(dx) * (1 + CONE_RTOL):
                    run.events.append(("arrest", t))
                    run.status = "arrested"
                    return None
                sigma = -1.0 if dz > 0 else 1.0
            else:
                sigma = 1.0 if qd > 0 else -1.0

            def rhs(_, y, sigma=sigma):
                q_, qd_ = y
                _, _, dx, dz, h, dh, kappa = geo(q_)
                N = kappa * (h * qd_) ** 2 + g * dx / h
                dv = -g * dz / h - mu * sigma * N
                return [qd_, (dv - dh * qd_ * qd_) / h]

            def turn(_, y, sigma=sigma):
                return sigma * y[1]

            def lift(_, y):
                return normal(y[0], y[1])

            turn.terminal = lift.terminal = True
            turn.direction = lift.direction = -1
            sol = solve_ivp(rhs, (t, scene.t_max), [q, qd], method="DOP853", rtol=RTOL, atol=ATOL,
                            events=(turn, lift))
            if sol.status == 0:
                run.status = "t_max"
                return None
            if len(sol.t_events[1]):
                t, (q, qd) = sol.t_events[1][0], sol.y_events[1][0]
                run.events.append(("lift_off", t))
                return t, q, qd
            t, q = sol.t_events[0][0], sol.y_events[0][0][0]
            qd = 0.0
            _, _, dx, dz, h, _, _ = geo(q)
            if abs(dz) <= mu_s * abs(dx) * (1 + CONE_RTOL):
                run.events.append(("arrest", t))
                run.status = "arrested"
                return None
            run.events.append(("reversal", t))

    def landing_time(X0, Z0, VX, VZ, u):
        """First t > 0 where the path crosses to the curve's other side."""
        def F(t):
            return curve.side(X0 + VX * t, Z0 + VZ * t - g * t * t / 2, p)

        lo, width = 0.0, max(8 * u / g, FIRST_WINDOW if u == 0 else 0.0)
        seen = u > 0
        while True:
            ts = np.linspace(lo, lo + width, SCAN + 1)[1:]
            vals = F(ts)
            for k, v in enumerate(vals):
                if v > SEPARATED:
                    seen = True
                elif seen and v < 0:
                    a = ts[k - 1] if k else lo
                    return brentq(F, a, ts[k], xtol=1e-16, rtol=1e-15, maxiter=200)
            lo, width = lo + width, 2 * width
            if lo > scene.t_max + 10:
                raise RuntimeError("no landing")

    t, q, qd = 0.0, scene.q0, scene.qdot0
    while True:
        lifted = slide(t, q, qd)
        if lifted is None:
            return run
        t, q, qd = lifted
        x, z, dx, dz, h, _, _ = geo(q)
        length = scale * h
        X0, Z0, VX, VZ, u, near = x, z, qd * dx, qd * dz, 0.0, q
        while True:   # flights and bounces
            if full():
                return run
            T = landing_time(X0, Z0, VX, VZ, u)
            if t + T > scene.t_max:
                run.status = "t_max"
                return run
            t += T
            X, Z = X0 + VX * T, Z0 + VZ * T - g * T * T / 2
            vx, vz = VX, VZ - g * T
            qL = curve.q_of(X, Z, p, near)
            xL, zL, dx, dz, h, _, kappa = geo(qL)
            tx, tz = dx / h, dz / h
            un, vt = -tz * vx + tx * vz, tx * vx + tz * vz   # normal (<= 0), tangential
            u_in = min(un, 0.0)
            jn = (1 + e) * -u_in
            u_out = -e * u_in
            v_out = 0.0 if abs(vt) <= mu * jn else vt - math.copysign(mu * jn, vt)
            run.events.append(("landing", t))
            a_n = g * tx + kappa * v_out * v_out
            if u_out > 0 and e < 1 and a_n > 0 and u_out * u_out < ACC_W * g * length:
                dt, ds, v_inf = _accumulation(u_out, v_out, g * tz, a_n, e, mu)
                t += dt
                run.events.append(("landing", t))
                q = qL + ds / h
                qd = v_inf / geo(q)[4]
                break
            if u_out > 0:
                X0, Z0 = xL, zL
                VX, VZ = -tz * u_out + tx * v_out, tx * u_out + tz * v_out
                u, near = u_out, qL
                continue
            q, qd = qL, v_out / h
            break


def _accumulation(u, v, a_t, a_n, e, mu):
    """physics.md, "Flight and landing", Bouncing-ball accumulation: ``(time, ds, v_inf)``."""
    tau, r, f = 2 / a_n, a_t / a_n, mu * (1 + e)
    time = ds = 0.0
    while True:
        if v == 0 and 2 * abs(r) <= f:
            return (time + tau * u / (1 - e), ds - a_t * tau * tau * u * u / (2 * (1 - e * e)), 0.0)
        v_land = v - 2 * r * u
        if v_land != 0:
            sigma = math.copysign(1.0, v_land)
            c = -2 * r - sigma * f
            v_inf = v + c * u / (1 - e)
            if sigma * v_land > f * u and sigma * v_inf > 0:
                return (time + tau * u / (1 - e),
                        ds + tau * u * (v / (1 - e) + c * u * e / ((1 - e) * (1 - e * e)))
                        - a_t * tau * tau * u * u / (2 * (1 - e * e)), v_inf)
        T = tau * u
        time, ds = time + T, ds + v * T - a_t * T * T / 2
        v = 0.0 if abs(v_land) <= f * u else v_land - math.copysign(f * u, v_land)
        u *= e
