"""An independent reference for runs with air drag: eq. 1 with drag integrated in time at 30 digits.

Written from docs/physics.md ("Equation of motion", "Air drag", "Events") alone: the curve's
``x(q)``, ``z(q)`` are differentiated by SymPy here, and on each branch ``(sigma, n)``

    qddot = -(h'/h + s mu alpha' + sigma gamma h) qdot^2 - g (z' + s mu x') / h^2,   s = sigma n,

is integrated in 30-digit arithmetic (mpmath) by the implicit 3-stage Gauss-Legendre
Runge-Kutta method (order 6; stages solved by fixed-point iteration to 1e-28) with steps of
:data:`STEP` seconds: its truncation error is below 1e-14 s on the event times of the tests'
scenes (halving the step moves none by more).  Events are sign changes after a step, placed
by bisecting the length of one step from the step's start to :data:`BISECT` seconds:
``qdot = 0`` (a turning point: the rest test with ``mu_s``, else the particle slides down the
slope), a limiter reached (``qdot -> -k qdot``), ``N = kappa w + g cos alpha = 0`` (the branch
flips).  Nothing of the engine, its kernels or its quadratures is used.
"""
from __future__ import annotations

import mpmath
import sympy as sp

#: Digits of the reference.
DIGITS = 30
#: Step (s) of the integrator, at the end of which the event functions are looked at.
STEP = "0.002"
#: Width (s) to which an event's time is bisected.
BISECT = "1e-16"
#: Fixed-point iterations of a step's stages stop when they change by less than this.
STAGE_TOL = "1e-28"


def gauss_legendre_step(f, t, y, dt):
    """One step of the 3-stage Gauss-Legendre method (order 6) of ``y' = f(t, y)`` from ``(t, y)``."""
    r = mpmath.sqrt(15)
    c = [mpmath.mpf(1) / 2 - r / 10, mpmath.mpf(1) / 2, mpmath.mpf(1) / 2 + r / 10]
    A = [[mpmath.mpf(5) / 36, mpmath.mpf(2) / 9 - r / 15, mpmath.mpf(5) / 36 - r / 30],
         [mpmath.mpf(5) / 36 + r / 24, mpmath.mpf(2) / 9, mpmath.mpf(5) / 36 - r / 24],
         [mpmath.mpf(5) / 36 + r / 30, mpmath.mpf(2) / 9 + r / 15, mpmath.mpf(5) / 36]]
    b = [mpmath.mpf(5) / 18, mpmath.mpf(4) / 9, mpmath.mpf(5) / 18]
    tol = mpmath.mpf(STAGE_TOL)
    k = [f(t, y)] * 3
    for _ in range(60):
        new = [f(t + c[i] * dt, [y[m] + dt * sum(A[i][j] * k[j][m] for j in range(3)) for m in range(2)])
               for i in range(3)]
        change = max(abs(new[i][m] - k[i][m]) for i in range(3) for m in range(2))
        k = new
        if change * abs(dt) < tol:
            break
    return [y[m] + dt * sum(b[i] * k[i][m] for i in range(3)) for m in range(2)]


def curve_functions(shape, params: dict):
    """mpmath functions ``(x', z', x'', z'')`` of ``q`` for a shape (its ``x``, ``z`` and coordinate)."""
    src = shape.source()
    q = sp.Symbol(src.get("q") or "x", real=True)
    names = {n: sp.Symbol(n, positive=True) for n in params}
    local = {**names, q.name: q}
    x = sp.sympify(src["x"], locals=local) if src.get("x") else q
    z = sp.sympify(src["z"], locals=local)
    values = {names[n]: sp.Rational(str(v)) if isinstance(v, str) else sp.nsimplify(v) for n, v in params.items()}
    out = []
    for expr in (sp.diff(x, q), sp.diff(z, q), sp.diff(x, q, 2), sp.diff(z, q, 2)):
        out.append(sp.lambdify(q, expr.subs(values), "mpmath"))
    return tuple(out)


def reference_events(scene, n_events: int, t_end: float = 30.0):
    """The first ``n_events`` events of ``scene`` (a :class:`symvib.numeric.scene.Scene` with drag)
    as ``[(kind, t, q)]`` in mpmath numbers, kinds as the engine names them."""
    with mpmath.workdps(DIGITS):
        return _events(scene, n_events, mpmath.mpf(t_end))


def _events(scene, n_events, t_end):
    mpf = mpmath.mpf
    xp, zp, xpp, zpp = curve_functions(scene.shape, dict(scene.params))
    g, mu, k = mpf(scene.g), mpf(scene.mu), mpf(scene.k)
    mu_s = mpf(scene.mu_static)
    gamma = mpf(scene.drag) / mpf(scene.m)
    left = None if scene.left is None else mpf(scene.left)
    right = None if scene.right is None else mpf(scene.right)

    def geometry(q):
        a, b, c, d = xp(q), zp(q), xpp(q), zpp(q)
        h = mpmath.sqrt(a * a + b * b)
        return a, b, h, (a * c + b * d) / h, (a * d - b * c) / (h * h)

    def normal(q, qd):
        a, b, h, dh, dalpha = geometry(q)
        return (dalpha / h) * (h * qd) ** 2 + g * a / h

    def rhs(sigma, s):
        def f(t, y):
            q, qd = y
            a, b, h, dh, dalpha = geometry(q)
            return [qd, -(dh / h + s * mu * dalpha + sigma * gamma * h) * qd ** 2 - g * (b + s * mu * a) / h ** 2]
        return f

    t, q, qd = mpf(0), mpf(scene.q0), mpf(scene.qdot0)
    sigma = 1 if qd > 0 else -1
    n = 1 if normal(q, qd) > 0 else -1
    events = []
    if qd == 0:
        raise ValueError("the reference starts in motion")
    while len(events) < n_events and t < t_end:
        f = rhs(sigma, sigma * n)

        def checks(y, only=None, sigma=sigma, n=n):
            qq, vv = y
            out = {"turn": lambda: sigma * vv, "nsign": lambda: n * normal(qq, vv)}
            if sigma > 0 and right is not None:
                out["impact"] = lambda: right - qq
            if sigma < 0 and left is not None:
                out["impact"] = lambda: qq - left
            if only is not None:
                return out[only]()
            return {name: fn() for name, fn in out.items()}

        step, y = mpf(STEP), [q, qd]
        while True:
            y_next = gauss_legendre_step(f, t, y, step)
            hits = [name for name, v in checks(y_next).items() if v <= 0]
            if hits:
                break
            t, y = t + step, y_next
        best = None
        for name in hits:
            lo, hi = mpf(0), step
            while hi - lo > mpf(BISECT):
                mid = (lo + hi) / 2
                if checks(gauss_legendre_step(f, t, y, mid), name) > 0:
                    lo = mid
                else:
                    hi = mid
            if best is None or hi < best[1]:
                best = (name, hi)
        name, tau = best
        q, qd = gauss_legendre_step(f, t, y, tau)
        t = t + tau
        if name == "impact":
            q = right if sigma > 0 else left
            events.append(("impact", t, q))
            qd = -k * qd
            sigma = -sigma
        elif name == "nsign":
            if scene.contact == "unilateral":   # the particle leaves the curve: the run ends
                events.append(("left_curve", t, q))
                return events
            events.append(("normal_sign_change", t, q))
            n = -n
        else:
            qd = mpf(0)
            a_, b_, h, _, _ = geometry(q)
            sin, cos = b_ / h, a_ / h
            if abs(sin) <= mu_s * abs(cos):
                events.append(("arrest", t, q))
                return events
            events.append(("reversal", t, q))
            sigma = 1 if -sin > 0 else -1
            n = 1 if normal(q, qd) > 0 else -1
    return events
