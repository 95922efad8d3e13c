"""Eq. 1 from first principles with sympy.physics.mechanics, against ``derive`` for every catalogue curve.

The derivation here shares nothing with :mod:`symvib.symbolic.derive` but the curve's
``x(q)``, ``z(q)``: a point on the curve in an inertial frame, a particle, gravity,
the normal reaction ``N`` along the normal and Coulomb friction ``-mu |N| sign(v)``
along the tangent; Kane's method gives the motion along the curve (the normal
reaction does no work and drops out), Newton's law along the normal gives ``N``.
Both are compared with ``derive(curve).eom(sigma, normal_sign)`` at 30 digits at
random points, for ``sigma = +-1`` and both signs of ``N``; a friction force with the
wrong sign, or the wrong branch, is caught.  ``derivations/mechanics.ipynb`` shows
the same derivation step by step.
"""
from __future__ import annotations

import random
from functools import cache

import mpmath
import pytest
import sympy as sp
from sympy.physics import mechanics as me

from symvib.shapes import CATALOGUE
from symvib.symbolic.curve import sample_points
from symvib.symbolic.derive import derive
from symvib.symbolic.symbols import g, mu

#: Random points per comparison, and the working precision and relative tolerance there.
POINTS = 5
DIGITS = 30
TOLERANCE = mpmath.mpf("1e-24")
#: The branches: (sign of v, sign of N).
BRANCHES = [(s, n) for s in (1, -1) for n in (1, -1)]


def first_principles(curve, friction: int = -1):
    """``(qddot, N)`` of a particle on ``curve`` from Kane's method, in the curve's ``q``, ``qdot``.

    ``friction`` is the sign of the friction force relative to the velocity (-1: Coulomb,
    opposing it); the results hold the symbols ``sign_v`` and ``abs_N`` for ``sign(v)``
    and ``|N|`` (``N`` per unit mass along the normal ``n = (-sin alpha, cos alpha)``).
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
    r_q = P.pos_from(origin).diff(q, frame)              # dr/dq, along the tangent
    h = sp.sqrt(r_q.dot(r_q))
    tangent = r_q / h
    normal = (-r_q.dot(frame.z) * frame.x + r_q.dot(frame.x) * frame.z) / h
    force = (-mass * g * frame.z + mass * N * normal
             + friction * mu * mass * abs_N * sign_v * tangent)
    kane = me.KanesMethod(frame, q_ind=[q], u_ind=[u], kd_eqs=[q.diff(t) - u])
    fr, frstar = kane.kanes_equations([me.Particle("particle", P, mass)], [(P, force)])
    eq = (fr + frstar)[0]
    assert sp.simplify(eq.diff(N)) == 0, "the normal reaction must not enter Kane's equation"
    ud = u.diff(t)
    qddot = -eq.subs({ud: 0, N: 0}) / eq.diff(ud)   # linear in u'; N's coefficient is 0 (asserted)
    along_n = mass * P.acc(frame).subs(q.diff(t), u).dot(normal) - force.dot(normal)
    N_value = -along_n.subs(N, 0) / along_n.diff(N)  # Newton along the normal, linear in N
    assert sp.simplify(N_value.diff(abs_N)) == 0, "friction acts along the tangent only"
    assert sp.simplify(N_value.diff(ud)) == 0, "the tangential acceleration has no normal part"
    N_value = N_value.subs({ud: 0, abs_N: 0})       # u' and friction enter as multiples of t . n = 0
    assert not N_value.has(ud) and not qddot.has(ud)

    def back(e):  # the derivatives first, then the functions of time
        return me.msubs(e, {q.diff(t): curve.qdot, u: curve.qdot}).subs(q, curve.q)
    return back(qddot), back(N_value), sign_v, abs_N


@cache
def _derived(name):
    # eq. 1 does not depend on F_sigma: the numeric route stands in at once (no integration budgets).
    return derive(CATALOGUE[name].curve(), routes=())


def _agree(a, b, curve, seed: int = 0) -> bool:
    """``a == b`` at ``POINTS`` random points (``q``, ``qdot``, ``g``, ``mu``, parameters), 30 digits."""
    args = [curve.q, curve.qdot, g, mu, *curve.params]
    fa, fb = (sp.lambdify(args, e, "mpmath") for e in (a, b))
    rng = random.Random(seed)
    with mpmath.workdps(DIGITS):
        for qv in sample_points(curve, POINTS, seed=seed + 1):
            values = [qv, rng.uniform(-3, 3), rng.uniform(1, 20), rng.uniform(0.01, 0.5)]
            values += [rng.uniform(0.5, 2) for _ in curve.params]
            x, y = fa(*map(mpmath.mpf, values)), fb(*map(mpmath.mpf, values))
            if not abs(x - y) <= TOLERANCE * max(1, abs(x), abs(y)):
                return False
    return True


def _on_branch(expr, sign_v, abs_N, N, s, n):
    return expr.subs({sign_v: s, abs_N: n * N})


@pytest.mark.parametrize("name", sorted(CATALOGUE))
def test_kane_gives_eq1_for_every_branch(name):
    d = _derived(name)
    c = d.curve
    qddot, N, sign_v, abs_N = first_principles(c)
    for s, n in BRANCHES:
        eom = d.eom(s, n).lhs                       # qddot + A qdot^2 + B
        ours = -(eom - c.qddot)                     # qddot = -A qdot^2 - B
        assert _agree(_on_branch(qddot, sign_v, abs_N, N, s, n), ours, c), (name, s, n)


@pytest.mark.parametrize("name", sorted(CATALOGUE))
def test_normal_reaction_is_kappa_w_plus_g_cos_alpha(name):
    """Newton along the normal: N = kappa h^2 qdot^2 + g cos(alpha) (physics.md, eq. 1)."""
    c = _derived(name).curve
    _, N, _, _ = first_principles(c)
    assert _agree(N, c.kappa * c.h**2 * c.qdot**2 + g * sp.cos(c.alpha), c), name


@pytest.mark.parametrize("name", ["parabola", "circle", "catenary"])
def test_a_wrong_friction_or_branch_is_caught(name):
    d = _derived(name)
    c = d.curve
    qddot, N, sign_v, abs_N = first_principles(c, friction=+1)    # friction pushing the particle on
    for s, n in BRANCHES:
        ours = -(d.eom(s, n).lhs - c.qddot)
        assert not _agree(_on_branch(qddot, sign_v, abs_N, N, s, n), ours, c), (name, s, n)
    qddot, N, sign_v, abs_N = first_principles(c)
    ours = -(d.eom(1, 1).lhs - c.qddot)
    assert not _agree(_on_branch(qddot, sign_v, abs_N, N, -1, 1), ours, c)   # v < 0 is not the v > 0 branch
    assert not _agree(_on_branch(qddot, sign_v, abs_N, N, 1, -1), ours, c)   # nor is N < 0


def test_the_mechanics_notebook_asserts_every_catalogue_curve():
    import json
    from pathlib import Path

    path = Path(__file__).resolve().parent.parent / "derivations" / "mechanics.ipynb"
    source = "\n".join("".join(c["source"]) for c in json.loads(path.read_text(encoding="utf-8"))["cells"]
                       if c["cell_type"] == "code")
    for needed in ("KanesMethod", "dynamicsymbols", "ReferenceFrame", "Particle", "for name in CATALOGUE",
                   ".eom(", "assert "):
        assert needed in source, needed
