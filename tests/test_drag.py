"""Quadratic air drag in the symbolic wing (symvib.symbolic.drag; physics.md, "Air drag").

Eq. 2 with drag substituted back into eq. 1 with drag, eq. 1 with drag against Kane's
method with a drag force, and the phase trajectory against a 30-digit time integration
of Kane's equation (mpmath's Taylor integrator), which shares nothing with the derivation
but the curve.
"""
import mpmath
import pytest
import sympy as sp

from symvib.symbolic.curve import graph
from symvib.symbolic.derive import derive
from symvib.symbolic.drag import BRANCHES, derive_drag, gamma_drag
from symvib.symbolic.mechanics import agrees, check_eq1, first_principles, on_branch
from symvib.symbolic.symbols import g, mu

SHAPES = ("parabola", "cycloid", "circle")
#: Digits of the time-integration references, and the agreement asked of them.
DIGITS, AGREEMENT = 30, mpmath.mpf("1e-22")
#: Gravity as an exact number (the references simplify Kane's equation with it).
G_EXACT = sp.Rational(981, 100)


@pytest.fixture(scope="module")
def quartic():
    return graph("a*x**4", params={"a": "positive"}, name="quartic-user")


@pytest.mark.parametrize("name", SHAPES)
def test_phase_trajectory_with_drag_satisfies_eq1(name):
    assert derive_drag(name, seconds=0).check() == {key: "symbolic" for key in BRANCHES}


def test_phase_trajectory_with_drag_satisfies_eq1_on_a_user_graph(quartic):
    assert set(derive_drag(quartic, seconds=0).check().values()) <= {"symbolic", "numeric"}


@pytest.mark.parametrize("name", SHAPES)
def test_eq1_with_drag_is_kanes(name):
    assert check_eq1(name, drag=True) == {key: True for key in BRANCHES}


def test_kane_tells_a_missing_or_reversed_drag():
    """The comparison can fail: eq. 1 without drag, or with the drag's sign reversed, is not Kane's."""
    d, plain = derive_drag("circle", seconds=0), derive("circle", routes=())
    c = d.curve
    qddot, N, sign_v, abs_N = first_principles(c, drag=True)
    for s, n in BRANCHES:
        kane = on_branch(qddot, sign_v, abs_N, N, s, n)
        assert agrees(kane, -(d.eom(s, n).lhs - c.qddot), c)
        assert not agrees(kane, -(plain.eom(s, n).lhs - c.qddot), c)
        reversed_ = d.eom(s, n).lhs.subs(gamma_drag, -gamma_drag)
        assert not agrees(kane, -(reversed_ - c.qddot), c)


@pytest.mark.parametrize("name", SHAPES)
def test_drag_vanishes_at_zero(name):
    d, plain = derive_drag(name, seconds=0), derive(name, routes=())
    for (s, n), br in d.branches.items():
        ref = plain.branch(s, n)
        assert sp.simplify(br.A.subs(gamma_drag, 0) - ref.A) == 0
        assert sp.simplify(br.B.subs(gamma_drag, 0) - ref.B) == 0


#: A budget for the circle's closed form that a loaded machine does not spend (it takes about 1 s idle).
CIRCLE_SECONDS = 120


def test_circle_has_a_closed_form_and_it_is_checked():
    d = derive_drag("circle", seconds=CIRCLE_SECONDS)
    assert d.arc_length == d.curve.params[0] * d.curve.q
    for br in d.branches.values():
        assert br.D is not None
        assert sp.simplify(sp.diff(br.D, d.curve.q) - br.integrand) == 0


def test_a_curve_parameter_may_not_take_the_drag_symbol():
    curve = graph("gamma_drag*x**2", params={"gamma_drag": "positive"}, name="clash")
    with pytest.raises(ValueError, match="gamma_drag"):
        derive_drag(curve, seconds=0)


def _kane_rhs(c, s, n, values):
    """Kane's ``qddot(q, qdot)`` on a branch with exact numbers for every symbol, as an mpmath
    function (simplified first: the Taylor integrator evaluates it many times)."""
    qddot, N, sign_v, abs_N = first_principles(c, drag=True)
    expr = sp.simplify(on_branch(qddot, sign_v, abs_N, N, s, n).subs(values))
    return sp.lambdify((c.q, c.qdot), expr, modules="mpmath"), sp.lambdify((c.q, c.qdot), N.subs(values), "mpmath")


def _integrated(c, s, n, values, q0, qdot0, times):
    """``(q, qdot)`` at ``times`` from Kane's equation, integrated at :data:`DIGITS` digits."""
    rhs, normal = _kane_rhs(c, s, n, values)
    with mpmath.workdps(DIGITS):
        solution = mpmath.odefun(lambda t, y: [y[1], rhs(y[0], y[1])], 0, [mpmath.mpf(q0), mpmath.mpf(qdot0)])
        states = [solution(mpmath.mpf(t)) for t in times]
        for q, qdot in states:   # the branch holds along the stretch compared
            assert mpmath.sign(qdot) == s * n and mpmath.sign(normal(q, qdot)) == n
    return states


def _w_of(c, br, values, q0, qdot0, D):
    """``w(q)`` of eq. 2 with drag through ``(q0, qdot0)``, ``D`` a function of q (numbers)."""
    Phi = sp.lambdify(c.q, br.Phi.subs(values), "mpmath")
    h = sp.lambdify(c.q, c.h.subs(values), "mpmath")
    gv = mpmath.mpf(values[g].p) / values[g].q
    C_value = h(q0) ** 2 * qdot0**2 * mpmath.exp(Phi(q0)) + 2 * gv * D(q0)
    return lambda q: mpmath.exp(-Phi(q)) * (C_value - 2 * gv * D(q))


@pytest.mark.slow
def test_circle_closed_form_against_a_30_digit_time_integration():
    d = derive_drag("circle", seconds=CIRCLE_SECONDS)
    c = d.curve
    values = {c.params[0]: sp.Rational(1, 2), g: G_EXACT, mu: sp.Rational(1, 10),
              gamma_drag: sp.Rational(3, 10)}
    br = d.branches[(1, 1)]
    with mpmath.workdps(DIGITS):
        q0, qdot0 = mpmath.mpf("-0.4"), mpmath.mpf("5")
        D = sp.lambdify(c.q, br.D.subs(values), "mpmath")
        w = _w_of(c, br, values, q0, qdot0, D)
        without = {**values, gamma_drag: 0}
        w_without = _w_of(c, br, without, q0, qdot0, sp.lambdify(c.q, br.D.subs(without), "mpmath"))
        for q, qdot in _integrated(c, 1, 1, values, q0, qdot0, ("0.05", "0.1", "0.15")):
            v2 = (mpmath.mpf(1) / 2) ** 2 * qdot**2
            assert abs(v2 - w(q)) <= AGREEMENT * v2
            assert abs(v2 - w_without(q)) > 1e-3 * v2   # the comparison sees the drag


@pytest.mark.slow
def test_parabola_quadrature_against_a_30_digit_time_integration():
    """No closed form for ``D``: eq. 2 with ``D`` by a 30-digit quadrature, arc length in closed form."""
    d = derive_drag("parabola", seconds=0)
    c = d.curve
    assert not d.arc_length.has(sp.Integral)
    values = {c.params[0]: sp.Rational(1, 2), g: G_EXACT, mu: sp.Rational(1, 20),
              gamma_drag: sp.Rational(1, 2)}
    for sig in (1, -1):
        br = d.branches[(sig, 1)]
        f = sp.lambdify(c.q, br.integrand.subs(values), "mpmath")
        with mpmath.workdps(DIGITS):
            q0, qdot0 = mpmath.mpf(-0.3) * sig, mpmath.mpf(4) * sig
            w = _w_of(c, br, values, q0, qdot0, lambda q: mpmath.quad(f, [q0, q]))
            h = sp.lambdify(c.q, c.h.subs(values), "mpmath")
            for q, qdot in _integrated(c, sig, 1, values, q0, qdot0, ("0.04",)):
                v2 = h(q) ** 2 * qdot**2
                assert abs(v2 - w(q)) <= AGREEMENT * v2


@pytest.mark.parametrize("kwargs, match", [
    ({"seconds": "5"}, "seconds: a number of seconds in"), ({"seconds": float("nan")}, "seconds: .* got nan"),
    ({"seconds": -1}, "seconds: .* got -1"), ({"seconds": float("inf")}, "seconds: .* got inf"),
    ({"seconds": 1e300}, "seconds: .* got 1e"), ({"seconds": True}, "seconds: .* got True"),
    ({"seconds": None}, "seconds: .* got None"), ({"seconds": 1j}, "seconds: .* got 1j"),
    ({"arc_seconds": "x"}, "arc_seconds: a number of seconds in"), ({"arc_seconds": float("nan")}, "arc_seconds"),
    ({"arc_seconds": -0.5}, "arc_seconds: .* got -0.5"),
    ({"forms": "evil"}, "forms: 'evil' is not one of simplest, direct"), ({"forms": None}, "forms: None"),
])
def test_hostile_budgets_and_forms_are_refused_naming_the_argument(kwargs, match):
    with pytest.raises(ValueError, match=match):
        derive_drag("circle", **kwargs)


@pytest.mark.parametrize("curve, error, match", [
    ("nosuch", KeyError, "unknown shape 'nosuch'; known shapes: "), ("../../etc/passwd", KeyError, "unknown shape"),
    ("__import__('os')", KeyError, "unknown shape"), ("", KeyError, "unknown shape ''"),
    ("CIRCLE", KeyError, "unknown shape 'CIRCLE'"),
    (None, TypeError, "needs a Curve, a Shape or a shape name, not NoneType"), (5, TypeError, "not int"),
])
def test_a_curve_that_is_not_one_is_refused_naming_what_was_given(curve, error, match):
    with pytest.raises(error, match=match):
        derive_drag(curve, seconds=0, arc_seconds=0)


def test_numpy_budgets_are_accepted():
    import numpy as np

    d = derive_drag("circle", seconds=np.float64(0.0), arc_seconds=np.int64(0))
    assert str(d.arc_length) == "R*phi" and d.branches[(1, 1)].D is None
