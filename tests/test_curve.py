"""Curves: geometry of every catalogue shape against numeric differentiation; bad input."""
import mpmath
import pytest
import sympy as sp

from symvib.shapes import CATALOGUE, shape
from symvib.symbolic import curve as cv


@pytest.mark.parametrize("name", sorted(CATALOGUE))
def test_geometry_matches_numeric_derivatives(name):
    """h, alpha, kappa against mpmath finite differences of x(q), z(q) alone."""
    c = shape(name).curve()
    values = {p: sp.Rational(str(v)) for p, v in zip(c.params, shape(name).defaults.values())}
    x = sp.lambdify(c.q, c.x.subs(values), "mpmath")
    z = sp.lambdify(c.q, c.z.subs(values), "mpmath")
    h = sp.lambdify(c.q, c.h.subs(values), "mpmath")
    alpha = sp.lambdify(c.q, c.alpha.subs(values), "mpmath")
    kappa = sp.lambdify(c.q, c.kappa.subs(values), "mpmath")
    with mpmath.workdps(30):
        for q in c.sample_points(4, seed=3):
            q = mpmath.mpf(q) * values.get(c.params[0], 1) if name in ("catenary", "quartic", "parabola-x") else q
            xp, zp = mpmath.diff(x, q), mpmath.diff(z, q)
            xpp, zpp = mpmath.diff(x, q, 2), mpmath.diff(z, q, 2)
            hn = mpmath.sqrt(xp**2 + zp**2)
            assert h(q) == pytest.approx(hn, rel=1e-20)
            assert hn * mpmath.sin(alpha(q)) == pytest.approx(zp, rel=1e-20, abs=1e-25)
            assert hn * mpmath.cos(alpha(q)) == pytest.approx(xp, rel=1e-20, abs=1e-25)
            assert kappa(q) == pytest.approx((xp * zpp - zp * xpp) / hn**3, rel=1e-18, abs=1e-25)


def test_paper_geometry_closed_forms():
    cyc = shape("cycloid").curve()
    R, phi = cyc.params[0], cyc.q
    assert sp.simplify(cyc.kappa - 1 / (4 * R * sp.cos(phi / 2))) == 0
    par = shape("parabola").curve()
    assert sp.simplify(par.kappa - sp.cos(par.q) ** 3 / par.params[0]) == 0
    assert shape("circle").curve().kappa == 1 / shape("circle").curve().params[0]


def test_graph_and_parametric_agree():
    g_ = cv.graph("x**2/(2*p)")
    assert g_.kind == "graph" and g_.q.name == "x" and g_.x == g_.q
    assert sp.simplify(g_.kappa - g_.params[0] ** 2 / (g_.params[0] ** 2 + g_.q**2) ** sp.Rational(3, 2)) == 0


def test_decimal_literals_are_exact():
    c = cv.graph("0.05*x**2")
    assert c.z == sp.Rational(1, 20) * c.q**2


@pytest.mark.parametrize("kwargs, message", [
    (dict(x="R*sin(t)", z="R*(1 - cos(t))", q="phi"), "neither x nor z depends on the coordinate 'phi'"),
    (dict(x="R", z="R*phi", q="phi"), "x = R does not depend on the coordinate"),
    (dict(x="sin(q)**2 + cos(q)**2", z="1", q="q"), "vanishes identically"),
    (dict(x="R*sin(phi)", z="R*(1 - cos(phi))", q="phi", params=["p"]), r"unknown parameter name\(s\) R"),
    (dict(x="g*sin(phi)", z="g*cos(phi)", q="phi"), "'g' in the curve is reserved"),
    (dict(x="R*sin(phi)", z="R*(1 - cos(phi))", q="mu"), "coordinate name 'mu' is reserved"),
    (dict(x="R*sin(phi)", z="R*(1 - cos(phi))", q="phi", alpha="2*phi"), "hint alpha"),
    (dict(x="R*sin(phi)", z="R*(1 - cos(phi))", q="phi", h="2*R"), "hint h"),
    (dict(x="R*sin(phi)", z="R*(1 - cos(phi))", q="phi", params={"R": "complex"}), "assumption"),
    (dict(x="R*sin(phi)", z="R*(1 - cos(phi))", q="phi", domain=("1", "-1")), "domain"),
    (dict(x="__import__('os')", z="phi", q="phi"), "curve.x: "),
])
def test_bad_curves_get_clear_errors(kwargs, message):
    with pytest.raises(ValueError, match=message):
        cv.parametric(**kwargs)


def test_bad_graph():
    with pytest.raises(ValueError, match="curve.z: "):
        cv.graph("x^2")
    with pytest.raises(ValueError, match="hint h"):
        cv.graph("x**2", domain=("-1", "1"), h="x")
