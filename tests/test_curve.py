"""Curves: geometry of every catalogue shape against numeric differentiation; bad input."""
import mpmath
import numpy as np
import pytest
import sympy as sp

from symvib.shapes import CATALOGUE, shape
from symvib.symbolic import angle, branches, identity
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


Q = sp.Symbol("q", real=True)
A = sp.Symbol("a", real=True)


@pytest.mark.parametrize("expr, want", [
    (sp.Piecewise((4 * sp.sin(Q), sp.Eq(sp.cos(Q), 0)), (3 * sp.sin(Q), True)), 3 * sp.sin(Q)),
    (sp.Piecewise((Q, sp.Ne(Q, 0)), (1, True)), Q),
    (sp.Piecewise((1, sp.Eq(Q, 0) & (Q > 1)), (Q, True)), Q),
    (sp.Piecewise((1, sp.Eq(Q, 0) | sp.Eq(A, 0)), (Q, True)), Q),
    (sp.Piecewise((sp.exp(A * Q) / A, sp.Ne(A, 0)), (Q, True)), sp.exp(A * Q) / A),
    (sp.Piecewise((2 * Q, sp.Eq(sp.sin(Q)**2 + sp.cos(Q)**2 - 1, 0, evaluate=False)), (Q, True)), 2 * Q),
    (sp.cos(Q) + sp.Piecewise((0, sp.Eq(Q, 0)), (Q, True)) ** 2, sp.cos(Q) + Q**2),
    (2 * sp.DiracDelta(Q) + Q, Q),
    (sp.diff(sp.Abs(Q) ** 3, Q, 2), 6 * sp.Abs(Q)),
])
def test_generic_branch_drops_branches_on_sets_of_measure_zero(expr, want):
    got = branches.generic_branch(expr)
    assert not got.has(sp.Piecewise, sp.DiracDelta)
    for q in (-1.3, -0.2, 0.7, 2.1):
        values = {Q: q, A: 0.8}
        assert float(got.subs(values)) == pytest.approx(float(want.subs(values)), rel=1e-14)


@pytest.mark.parametrize("expr", [
    sp.Piecewise((Q, Q > 0), (0, True)),
    sp.Piecewise((1, sp.Eq(Q, 0)), (Q, Q < 1), (2, True)),
    sp.Piecewise((1, sp.Eq(Q, 0) | (Q > 1)), (Q, True)),
])
def test_generic_branch_refuses_inequalities_naming_the_field(expr):
    with pytest.raises(branches.CurveError, match=r"^kernel dh: .*Piecewise .*hint \(curve.h / curve.alpha\)"):
        branches.generic_branch(expr, "kernel dh")


def test_generic_branch_refuses_a_piecewise_defined_on_a_null_set_only():
    with pytest.raises(branches.CurveError, match="measure zero"):
        branches.generic_branch(sp.Piecewise((1, sp.Eq(Q, 0)), (2, sp.Eq(Q, 1))))


def test_the_paper_parabola_in_expressions_has_a_geometry_without_piecewise():
    c = cv.parametric("tan(phi)", "tan(phi)**2/2", q="phi")
    for e in (c.hp, c.alphap, c.kappa):
        assert not e.has(sp.Piecewise, sp.DiracDelta)


# --- a continuous tangent angle (physics.md, "Geometry") ------------------------------------
@pytest.mark.parametrize("x, z, q, domain, want", [
    ("R*sin(q)", "R*(1 - cos(q))", "q", None, "q"),                       # alpha' = 1 integrated
    ("R*sin(t)", "-R*cos(t)", "t", None, "t"),
    ("R*(phi + sin(phi))", "R*(1 - cos(phi))", "phi", ("-pi", "pi"), "phi/2"),
    ("p*tan(phi)", "p*tan(phi)**2/2", "phi", ("-pi/2", "pi/2"), "phi"),
    ("sin(q)*sqrt(tan(q)**2 + 1)", "tan(q)**2/2", "q", ("-pi/2", "pi/2"), "q"),   # Abs(cos q) > 0 there
])
def test_a_parametric_curve_gets_its_continuous_tangent_angle(x, z, q, domain, want):
    c = cv.parametric(x, z, q=q, domain=domain)
    assert not c.alpha_cut
    assert sp.simplify(c.alpha - sp.sympify(want, locals={q: c.q})) == 0


def test_the_ellipse_gets_a_continuous_rotated_form_and_not_atan_of_tan():
    c = cv.parametric("a*sin(q)", "b*(1 - cos(q))")
    assert not c.alpha_cut and not c.alpha.has(sp.atan2)
    f = sp.lambdify([c.q, *c.params], c.alpha)
    qs = np.linspace(-10.0, 10.0, 20001)
    values = f(qs, 0.5, 0.3)
    assert np.max(np.abs(np.diff(values))) < 0.01          # continuous: no jump of pi or 2 pi
    turned = np.unwrap(np.arctan2(0.3 * np.sin(qs), 0.5 * np.cos(qs)))   # the tangent, loop after loop
    np.testing.assert_allclose(values - values[10000], turned - turned[10000], atol=1e-12)
    a, b = c.params
    assert angle.angle_jump(sp.atan(b * sp.tan(c.q) / a), c, c.default_values()) is not None   # off by pi
    jump = angle.angle_jump(sp.atan2(b * sp.sin(c.q), a * sp.cos(c.q)), c, c.default_values())
    assert np.cos(jump) == pytest.approx(-1.0, abs=1e-9)       # 2 pi where the tangent points along -x


def test_a_curve_without_a_continuous_closed_form_keeps_atan2_and_says_so():
    # A prolate trochoid: continuous forms exist for a > 1 and for a < 1, but not one for every a.
    c = cv.parametric("q - a*sin(q)", "a*(1 - cos(q))")
    assert c.alpha_cut and c.alpha.has(sp.atan2)
    assert not cv.graph("x**2").alpha_cut and not cv.parametric("q**3 + q", "q**2").alpha_cut


def test_a_hint_that_jumps_is_refused():
    message = r"hint alpha = atan2\(sin\(q\), cos\(q\)\) jumps at q = -?[\d.]+ \(parameters = 1\), where"
    with pytest.raises(branches.CurveError, match=message):
        cv.parametric("R*sin(q)", "R*(1 - cos(q))", alpha="atan2(sin(q), cos(q))", h="R")


def test_the_kernel_module_says_whether_alpha_has_a_branch_cut():
    from symvib.codegen.kernel_text import module_text
    from symvib.symbolic.derive import derive

    for x, z, cut in (("q - a*sin(q)", "a*(1 - cos(q))", True), ("R*sin(q)", "R*(1 - cos(q))", False)):
        d = derive(cv.parametric(x, z), routes=())
        assert f"\nALPHA_CUT = {cut}\n" in module_text(d, {"x": x, "z": z})


def test_the_circle_across_its_top_is_not_arrested_at_pi():
    # With atan2 the tangent angle jumped by 2 pi at q = pi, so exp(-2 s mu alpha) did: a spurious
    # turning point and arrest there.  alpha = q now: it bounces between the limiters.
    from symvib import simulate
    from symvib.numeric.scene import scene_from_dict

    scene = scene_from_dict({"curve": {"x": "R*sin(q)", "z": "R*(1 - cos(q))"}, "parameters": {"R": 0.5},
                             "physics": {"mu": 0.05, "restitution": 0.8}, "limiters": {"left": 2.8, "right": 3.5},
                             "initial": {"q": 3.0, "qdot": 2.0}})
    result = simulate(scene, backend="python", samples=False)
    assert result.success and result.status.value == "resting_on_limiter"
    assert [e.kind.value for e in result.events[:3]] == ["impact", "impact", "reversal"]
    assert all(e.kind.value != "arrest" or abs(e.q - np.pi) > 0.1 for e in result.events)


def test_a_simplified_geometry_never_overflows_where_the_plain_derivative_does_not():
    # simplify() clears the Gaussian's denominators: alpha' became exp(x**2/b**2)/(... + b**4
    # exp(2 x**2/b**2)), inf/inf = nan beyond x**2/b**2 of about 355, where alpha' is 0.
    c = cv.graph("-a*exp(-x**2/b**2)", params={"a": "positive", "b": "positive"})
    a, b = c.params
    values = {a: 0.1, b: 0.05}
    for name in ("hp", "alphap", "kappa"):
        fn = sp.lambdify([c.q], getattr(c, name).subs(values), "numpy")
        with np.errstate(all="ignore"):
            far = np.array([fn(x) for x in (-1.5, -1.0, 1.0, 1.5)], dtype=float)
        assert np.all(np.isfinite(far)), (name, getattr(c, name))
        assert np.all(np.abs(far) < 1e-100), (name, far)
        # ... and nothing overflows on the way: a scalar kernel's math.exp raises where NumPy gives inf
        # (h' simplified to exp(-x^2/b^2) / sqrt(... + b^4 exp(2 x^2/b^2)): finite in NumPy, not in math).
        scalar = sp.lambdify([c.q], getattr(c, name).subs(values), "math")
        assert all(abs(scalar(x)) < 1e-100 for x in (-1.5, -1.0, 1.0, 1.5)), name
    # Where they are finite, the forms agree with the plain derivative (60 digits).
    raw = sp.diff(c.alpha, c.q)
    for x in (0.01, 0.04, 0.1):
        exact = raw.subs({**values, c.q: x}).evalf(60)
        assert abs(c.alphap.subs({**values, c.q: x}).evalf(60) - exact) <= 1e-50 * (1 + abs(exact))
    # A simplification that overflows nowhere is kept.
    q = c.q
    assert identity.tamed(sp.cos(q) ** 2, 1 - sp.sin(q) ** 2, c) == sp.cos(q) ** 2
