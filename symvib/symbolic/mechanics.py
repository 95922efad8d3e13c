"""Eq. (1) from first principles with ``sympy.physics.mechanics``, to check :func:`derive` against.

This derivation shares nothing with :mod:`symvib.symbolic.derive` but the curve's
``x(q)``, ``z(q)``: a point on the curve in an inertial frame, a particle,
gravity, the normal reaction ``N`` along the normal ``n = (-sin alpha, cos alpha)``
and Coulomb friction ``-mu |N| sign(v)`` along the tangent.  Kane's method gives the
motion along the curve (the normal reaction does no work and drops out); Newton's
law along the normal gives ``N`` (physics.md, "Equation of motion (paper eq. 1)":
``N = kappa w + g cos(alpha)`` per unit mass, ``w = v^2``).  :func:`check_eq1` compares the result with
``derive(curve).eom(sigma, sign_N)`` on all four branches at 30 digits at random points.
``derivations/mechanics.ipynb`` shows the same derivation step by step.

Examples
--------
>>> check_eq1("circle")
{(1, 1): True, (1, -1): True, (-1, 1): True, (-1, -1): True}
"""
from __future__ import annotations

import sympy as sp
from sympy.physics import mechanics as me

from symvib.symbolic.drag import gamma_drag
from symvib.symbolic.identity import numeric_zero
from symvib.symbolic.symbols import g, mu

__all__ = ["first_principles", "agrees", "on_branch", "check_eq1", "BRANCHES"]

#: Random points of a comparison, and the ranges its speed, gravity and friction are drawn from.
POINTS = 5
QDOT_RANGE, G_RANGE, MU_RANGE = (-3.0, 3.0), (1.0, 20.0), (0.01, 0.5)
#: Range of the drag ``gamma = c / m`` (1/length) drawn by a comparison with drag.
GAMMA_RANGE = (0.0, 2.0)
#: The branches of eq. (1): (sign of v, sign of N).
BRANCHES = ((1, 1), (1, -1), (-1, 1), (-1, -1))


def first_principles(curve, friction: int = -1, *, drag: bool = False):
    """``(qddot, N, sign_v, abs_N)`` of a particle on ``curve`` by Kane's method, in ``q``, ``qdot``.

    ``friction`` is the sign of the friction force relative to the velocity (-1: Coulomb,
    opposing it; +1 is wrong physics, for tests that must catch it).  ``drag`` adds the
    air drag ``-m gamma |v| v`` (physics.md, "Air drag"; ``gamma`` is
    :data:`~symvib.symbolic.drag.gamma_drag`).  ``qddot`` holds the
    symbols ``sign_v`` and ``abs_N`` for ``sign(v)`` and ``|N|`` (``N`` per unit mass,
    along ``n``); ``N`` is the normal reaction from Newton's law along the normal.
    """
    q, u = me.dynamicsymbols("q u")
    t = me.dynamicsymbols._t
    mass = sp.Symbol("m", positive=True)
    N, sign_v, abs_N = sp.symbols("N sign_v abs_N", real=True)
    frame = me.ReferenceFrame("I")                  # inertial: x horizontal, z up
    origin = me.Point("O")
    origin.set_vel(frame, 0)
    P = origin.locatenew("P", curve.x.subs(curve.q, q) * frame.x + curve.z.subs(curve.q, q) * frame.z)
    P.set_vel(frame, P.pos_from(origin).dt(frame).subs(q.diff(t), u))
    r_q = P.pos_from(origin).diff(q, frame)         # dr/dq, along the tangent
    h = sp.sqrt(r_q.dot(r_q))
    tangent = r_q / h
    normal = (-r_q.dot(frame.z) * frame.x + r_q.dot(frame.x) * frame.z) / h
    force = -mass * g * frame.z + mass * N * normal + friction * mu * mass * abs_N * sign_v * tangent
    if drag:
        velocity = P.vel(frame)
        force += -mass * gamma_drag * sign_v * velocity.dot(velocity) * tangent   # |v| v = sign(v) v^2 along t
    kane = me.KanesMethod(frame, q_ind=[q], u_ind=[u], kd_eqs=[q.diff(t) - u])
    fr, frstar = kane.kanes_equations([me.Particle("particle", P, mass)], [(P, force)])
    eq = (fr + frstar)[0]
    if sp.simplify(eq.diff(N)) != 0:
        raise AssertionError("the normal reaction must not enter Kane's equation")
    ud = u.diff(t)
    qddot = -eq.subs({ud: 0, N: 0}) / eq.diff(ud)   # linear in u'; N's coefficient is 0 (checked)
    along_n = mass * P.acc(frame).subs(q.diff(t), u).dot(normal) - force.dot(normal)
    N_value = -along_n.subs(N, 0) / along_n.diff(N)  # Newton along the normal, linear in N
    if any(sp.simplify(N_value.diff(along_t)) != 0 for along_t in (abs_N, ud, sign_v)):
        raise AssertionError("friction, drag and the tangential acceleration must not enter N")
    N_value = N_value.subs({ud: 0, abs_N: 0, sign_v: 0})   # they enter as multiples of t . n = 0

    def back(e):  # the derivatives first, then the functions of time
        return me.msubs(e, {q.diff(t): curve.qdot, u: curve.qdot}).subs(q, curve.q)

    return back(qddot), back(N_value), sign_v, abs_N


def agrees(a, b, curve, seed: int = 0) -> bool:
    """``a == b`` at :data:`POINTS` random points (``q``, ``qdot``, ``g``, ``mu``, ``gamma``,
    parameters), at 30 digits (:func:`symvib.symbolic.identity.numeric_zero`)."""
    extra = {curve.qdot: QDOT_RANGE, g: G_RANGE, mu: MU_RANGE, gamma_drag: GAMMA_RANGE}
    return numeric_zero(a - b, curve, extra=extra, points=POINTS, seed=seed + 1)


def on_branch(expr, sign_v, abs_N, N, s: int, n: int):
    """``expr`` of :func:`first_principles` on the branch ``sign(v) = s``, ``sign(N) = n``."""
    return expr.subs({sign_v: s, abs_N: n * N})


def check_eq1(curve, *, friction: int = -1, drag: bool = False) -> dict:
    """Whether Kane's eq. (1) equals ``derive(curve).eom(s, n)`` on each branch ``(s, n)``.

    ``curve``: a :class:`~symvib.symbolic.curve.Curve`, or the name of a catalogue shape.
    ``drag``: with air drag, against :func:`symvib.symbolic.drag.derive_drag`'s eq. 1.
    """
    from symvib.symbolic.derive import derive
    from symvib.symbolic.drag import derive_drag

    # eq. 1 does not need F_sigma or D: no integration budgets
    d = derive_drag(curve, seconds=0, arc_seconds=0) if drag else derive(curve, routes=())
    c = d.curve
    qddot, N, sign_v, abs_N = first_principles(c, friction, drag=drag)
    out = {}
    for s, n in BRANCHES:
        ours = -(d.eom(s, n).lhs - c.qddot)        # qddot = -A qdot^2 - B
        out[(s, n)] = agrees(on_branch(qddot, sign_v, abs_N, N, s, n), ours, c)
    return out
