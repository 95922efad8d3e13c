"""High-precision references that share no code with the driver (mpmath).

:func:`phase_reference` follows the same physics as the driver but none of
its numerics: the phase trajectory is evaluated from the SymPy closed form
(or an mpmath quadrature of ``F_s'``) at ``dps`` digits, events are
bracketed on a grid and refined with ``mpmath.findroot``, and interval times
are tanh-sinh quadratures (``mpmath.quad``) of ``h / sqrt(w)``, which treat
the inverse square root at turning points natively.  It is slow (tens of
milliseconds per event) and meant for tests and benchmarks.

Examples
--------
>>> from symvib.numeric.scene import scene_from_dict
>>> s = scene_from_dict({"curve": {"shape": "circle"}, "parameters": {"R": 0.5},
...     "physics": {"mu": 3, "restitution": 1}, "limiters": {"right": "pi/4"},
...     "initial": {"q": "pi/12", "qdot": 3.8}})
>>> [(e.kind, round(float(e.q), 9)) for e in phase_reference(s)]
[('arrest', 0.350089206)]
"""
from __future__ import annotations

from dataclasses import dataclass

import mpmath
import sympy as sp

from symvib.symbolic.derive import derive as derive_curve
from symvib.symbolic.symbols import g as g_sym
from symvib.symbolic.symbols import mu as mu_sym

__all__ = ["RefEvent", "phase_reference"]

#: Grid steps used to bracket the first event ahead.
GRID = 400
#: Search window in units of q_scale where no limiter bounds the motion.
WINDOW = 2


@dataclass(frozen=True)
class RefEvent:
    """An event of the reference (mpmath numbers)."""

    kind: str
    t: object
    q: object
    qdot_before: object
    qdot_after: object


#: Budget (seconds) of each closed-form route when the reference derives a curve.
ROUTE_SECONDS = 2.0
#: Halvings of :func:`_inner_bracket` towards a start from rest, at most (2^-200 of a grid step:
#: below the 30 digits of a position).
INNER_HALVINGS = 200


def _inner_bracket(G, q, x):
    """``(a, b)`` with ``G(a) > 0 >= G(b)`` in ``(q, x]``, where ``G(q) = 0`` (a start from rest) and
    ``G(x) <= 0``: halving towards ``q`` until ``G`` is positive; ``(None, None)`` when it is not
    within :data:`INNER_HALVINGS` halvings (the motion cannot start)."""
    b, a = x, q + (x - q) / 2
    for _ in range(INNER_HALVINGS):
        if G(a) > 0:
            return a, b
        b, a = a, q + (a - q) / 2
    return None, None


class _Model:
    def __init__(self, scene, dps, derive=derive_curve):
        self.dps = dps
        d = derive(scene.shape.curve(), seconds=ROUTE_SECONDS)
        c = d.curve
        with mpmath.workdps(dps):
            vals = {p: sp.Float(repr(v), dps) for p, v in zip(c.params, scene.param_values)}
            vals[g_sym] = sp.Float(repr(scene.g), dps)
            vals[mu_sym] = sp.Float(repr(scene.mu), dps)
        lam = lambda e: sp.lambdify(c.q, sp.sympify(e).subs(vals), "mpmath")  # noqa: E731
        self.h, self.alpha, self.z = lam(c.h), lam(c.alpha), lam(c.z)
        self.xp, self.zp, self.kappa = lam(c.xp), lam(c.zp), lam(c.kappa)
        self.F, self.dF, self.closed = {}, {}, {}
        for s, br in d.branches.items():
            self.dF[s] = lam(br.F.integrand)
            self.closed[s] = br.F.closed
            if br.F.closed:
                self.F[s] = lam(br.F.expr)
        self.g = mpmath.mpf(repr(scene.g))
        self.mu = mpmath.mpf(repr(scene.mu))
        self.mu_s = mpmath.mpf(repr(scene.mu_static))   # the rest test's (static) friction
        self.scale = float(c.q_scale.subs(vals))

    def N(self, q, w):
        return self.kappa(q) * w + self.g * self.xp(q) / self.h(q)

    def G(self, s, q0, G0, grid):
        """``G(x) = C - 2 g F_s(x)`` with ``G(q0) = G0``.

        Closed form when there is one; otherwise ``G0 - 2 g Integral_{q0}^{x} F_s'``
        by tanh-sinh quadrature from the nearest point of ``grid`` (values cached
        along it), so that every quadrature is short.
        """
        if self.closed[s]:
            C = G0 + 2 * self.g * self.F[s](q0)
            return lambda x: C - 2 * self.g * self.F[s](x)
        f = self.dF[s]
        cache = {0: G0}
        pts = [q0] + list(grid)

        def value_at(i):
            if i not in cache:
                cache[i] = value_at(i - 1) - 2 * self.g * mpmath.quad(f, [pts[i - 1], pts[i]])
            return cache[i]

        direction = 1 if pts[-1] >= q0 else -1

        def G(x):
            i = 0
            while i + 1 < len(pts) and (pts[i + 1] - x) * direction <= 0:
                i += 1
            return value_at(i) - 2 * self.g * mpmath.quad(f, [pts[i], x])

        return G


def phase_reference(scene, *, dps: int = 30, max_events: int | None = None, derive=derive_curve) -> list:
    """Events of ``scene`` computed at ``dps`` digits (see the module docstring).

    Stops at arrest, rest, ``max_events`` events, or ``scene.t_max``; a Zeno
    accumulation is not summed (cap it with ``max_events``).

    Parameters
    ----------
    scene : symvib.numeric.scene.Scene
    dps : int
        Working precision, decimal digits.
    max_events : int, optional
        Event cap (default: the scene's ``max_events``).
    derive : callable, optional
        ``derive(curve, seconds=...)`` returning the curve's
        :class:`~symvib.symbolic.derive.Derivation` (default
        :func:`symvib.symbolic.derive.derive`).  A caller that runs many scenes
        on few curves passes a memoized one (``symvib bench``).

    Returns
    -------
    list of RefEvent
    """
    max_events = scene.max_events if max_events is None else max_events
    with mpmath.workdps(dps):
        M = _Model(scene, dps, derive)
        mp = mpmath.mpf
        q = mp(repr(scene.q0))
        w = (M.h(q) * mp(repr(scene.qdot0))) ** 2
        sigma = 0 if scene.qdot0 == 0 else (1 if scene.qdot0 > 0 else -1)
        k = mp(repr(scene.k))
        left = None if scene.left is None else mp(repr(scene.left))
        right = None if scene.right is None else mp(repr(scene.right))
        t = mp(0)
        events = []

        def at_limiter(x):
            return 1 if right is not None and x == right else -1 if left is not None and x == left else 0

        def rest(x):
            sin, cos = M.zp(x) / M.h(x), M.xp(x) / M.h(x)
            side = at_limiter(x)
            if side and -sin * side > 0:
                return "rest_on_limiter", 0
            if abs(sin) <= M.mu_s * abs(cos) * (1 + mp("1e-9")):
                return "arrest", 0
            return "slide", 1 if -sin > 0 else -1

        def vel(x, w_, s_):
            return s_ * mpmath.sqrt(max(w_, 0)) / M.h(x)

        if sigma == 0:
            what, sigma = rest(q)
            if what != "slide":
                return [RefEvent(what, t, q, mp(0), mp(0))]
        elif at_limiter(q) == sigma:
            events.append(RefEvent("impact", t, q, vel(q, w, sigma), -k * vel(q, w, sigma)))
            w, sigma = k * k * w, -sigma
        nsign = 1 if M.N(q, w) >= 0 else -1
        flip = False
        while len(events) < max_events:
            if not flip:
                n0 = M.N(q, w)
                nsign = 1 if n0 > 0 else -1 if n0 < 0 else (1 if M.xp(q) >= 0 else -1)
            flip = False
            s = sigma * nsign
            bound = right if sigma > 0 else left
            kind = "impact"
            if bound is None:
                bound, kind = q + sigma * WINDOW * M.scale, "pass"
            grid = [q + (bound - q) * mp(i) / GRID for i in range(1, GRID + 1)]
            G = M.G(s, q, w * mpmath.exp(2 * s * M.mu * M.alpha(q)), grid)
            Nn = lambda x: nsign * M.N(x, mpmath.exp(-2 * s * M.mu * M.alpha(x)) * max(G(x), 0))  # noqa: E731
            # Bracket the first zero of G or N on a grid, then refine.
            prev = q
            found = None
            for x in grid:
                if G(x) <= 0:
                    if prev == q and w == 0:
                        # From rest (a reversal), the next turning point may lie before the first
                        # grid point, and the bracket's end q is a root itself: halve towards q.
                        prev, x = _inner_bracket(G, q, x)
                    found = ("reversal", prev, x) if prev is not None else ("stuck", q, q)
                    break
                if Nn(x) < 0:
                    found = ("normal_sign_change", prev, x)
                    break
                prev = x
            if found is None:
                qb = bound
            elif found[0] == "stuck":   # G <= 0 on both sides of q: no motion from rest (the cone's edge)
                events.append(RefEvent("arrest", t, q, mp(0), mp(0)))
                break
            else:
                what, a, b = found
                f = G if what == "reversal" else Nn
                qb = mpmath.findroot(f, (a, b), solver="anderson")
                kind = what
            wb = max(mpmath.exp(-2 * s * M.mu * M.alpha(qb)) * G(qb), mp(0)) if kind != "reversal" else mp(0)
            def integrand(x):
                # tanh-sinh puts nodes within rounding of a turning point, where
                # G rounds to 0; their weight is negligible.
                Gx = G(x)
                return M.h(x) * mpmath.exp(s * M.mu * M.alpha(x)) / mpmath.sqrt(Gx) if Gx > 0 else mp(0)

            pts = [q + (qb - q) * mp(j) / 4 for j in range(5)]
            dt = abs(mpmath.quad(integrand, pts))
            if t + dt > scene.t_max:
                break
            t += dt
            if kind == "pass":
                q, w = qb, wb
                continue
            if kind == "normal_sign_change":
                v = vel(qb, wb, sigma)
                events.append(RefEvent(kind, t, qb, v, v))
                q, w, nsign, flip = qb, wb, -nsign, True
                continue
            if kind == "impact":
                v = vel(qb, wb, sigma)
                events.append(RefEvent("impact", t, qb, v, -k * v))
                q, w, sigma = qb, k * k * wb, -sigma
                if w == 0:
                    what, sigma = rest(q)
                    if what != "slide":
                        events.append(RefEvent(what, t, q, mp(0), mp(0)))
                        break
                continue
            what, direction = rest(qb)
            if what != "slide":
                events.append(RefEvent(what, t, qb, mp(0), mp(0)))
                break
            events.append(RefEvent("reversal", t, qb, mp(0), mp(0)))
            q, w, sigma = qb, mp(0), direction
        return events
