"""F_sigma routes: closed forms checked by numeric differentiation, budgets, mu -> 0."""
import math
import time

import mpmath
import pytest
import sympy as sp

from symvib.shapes import shape
from symvib.symbolic import budget, integrals
from symvib.symbolic.integrals import antiderivative, frictionless_gap, regularize
from symvib.symbolic.symbols import mu

CLOSED = ["parabola", "parabola-x", "cycloid", "circle"]


@pytest.mark.parametrize("name", CLOSED)
@pytest.mark.parametrize("s", [1, -1])
def test_closed_form_differentiates_back_numerically(name, s):
    """d/dq of the closed form (mpmath finite differences, 30 digits) equals the integrand."""
    c = shape(name).curve()
    F = antiderivative(c, s)
    assert F.closed and F.verification in ("symbolic", "numeric")
    values = {p: sp.Rational(3, 4) for p in c.params}
    values[mu] = sp.Rational(7, 100)
    Fn = sp.lambdify(c.q, F.expr.subs(values), "mpmath")
    fn = sp.lambdify(c.q, integrals.integrand(c, s).subs(values), "mpmath")
    with mpmath.workdps(30):
        for q in c.sample_points(5, seed=9):
            assert mpmath.diff(Fn, q) == pytest.approx(fn(q), rel=1e-20, abs=1e-22)


def test_paper_antiderivatives_by_hand():
    """Closed forms derived by hand (physics.md) equal SymPy's up to a constant."""
    R = sp.Symbol("R", positive=True)
    p = sp.Symbol("p", positive=True)
    phi = sp.Symbol("phi", real=True)
    hand = {
        "parabola": p * sp.exp(2 * mu * phi) / (2 * sp.cos(phi) ** 2),
        "circle": R * sp.exp(2 * mu * phi) * (3 * mu * sp.sin(phi) - (1 - 2 * mu**2) * sp.cos(phi)) / (1 + 4 * mu**2),
        "cycloid": R * sp.exp(mu * phi) * ((2 * mu * sp.sin(phi) - (1 - mu**2) * sp.cos(phi)) / (1 + mu**2) + 1),
    }
    for name, expected in hand.items():
        got = antiderivative(shape(name).curve(), 1).expr
        assert sp.simplify(sp.diff(got - expected, phi)) == 0, name


def test_catenary_falls_back_to_numeric_route_with_provenance():
    c = shape("catenary").curve()
    F = antiderivative(c, 1, seconds=0.5)
    assert F.route == "numeric" and not F.closed
    assert [a.route for a in F.attempts] == list(integrals.ROUTES)
    assert all(a.outcome.startswith(("timeout", "no closed form", "error")) for a in F.attempts)
    # The numeric representation is usable: its derivative is the integrand.
    assert sp.simplify(sp.diff(F.expr, c.q) - F.integrand) == 0
    values = {c.params[0]: 1, mu: sp.Rational(1, 10)}
    with mpmath.workdps(20):
        val = sp.N(F.expr.subs(values).subs(c.q, 1), 20)
        ref = mpmath.quad(sp.lambdify(c.q, F.integrand.subs(values), "mpmath"), [0, 1])
        assert val == pytest.approx(ref, rel=1e-15)


def _sleep_forever():
    while True:
        time.sleep(1)


def test_budget_kills_a_job_that_never_ends():
    outcome = budget.run(_sleep_forever, (), seconds=0.3)
    assert outcome.status == "timeout" and outcome.value is None


def test_budget_reports_errors():
    outcome = budget.run(math.sqrt, (-1.0,), seconds=10)
    assert outcome.status == "error" and "ValueError" in outcome.value


def _hyper_arc_length():
    x = sp.Symbol("x", real=True)
    return sp.integrate(sp.sqrt(1 + 16 * x**6), x)   # a hyper(...) whose srepr SymPy cannot rebuild


def test_budget_reports_a_result_that_does_not_rebuild_as_an_error():
    """SymPy's ``srepr`` of ``hyper`` does not round-trip: the step fails cleanly (its fallback takes over)."""
    with pytest.raises((TypeError, ValueError)):
        sp.sympify(sp.srepr(_hyper_arc_length()))
    outcome = budget.run(_hyper_arc_length, (), seconds=60)
    assert outcome.status == "error" and "srepr" in outcome.value


def test_regularize_removes_constant_pole():
    t = sp.Symbol("t", real=True)
    F, regular = regularize(sp.exp(mu * t) / mu + sp.sin(t), t)
    assert not regular
    assert sp.limit(F, mu, 0) == t + sp.sin(t)
    assert sp.simplify(sp.diff(F, t) - sp.diff(sp.exp(mu * t) / mu + sp.sin(t), t)) == 0
    assert regularize(sp.exp(mu * t) * sp.cos(t), t) == (sp.exp(mu * t) * sp.cos(t), True)


@pytest.mark.parametrize("name", CLOSED)
def test_frictionless_limit_is_energy_conservation(name):
    """At mu = 1e-12 the closed form gives F(q) - F(q0) = z(q) - z(q0) in double precision."""
    c = shape(name).curve()
    values = {p: v for p, v in zip(c.params, shape(name).defaults.values())}
    for s in (1, -1):
        F = antiderivative(c, s)
        assert F.mu_regular
        assert frictionless_gap(F, c, values) < 1e-9


def test_bad_branch_and_route():
    c = shape("circle").curve()
    with pytest.raises(ValueError, match="branch"):
        antiderivative(c, 0)
    with pytest.raises(ValueError, match="unknown route"):
        antiderivative(c, 1, routes=("magic",))


@pytest.mark.parametrize("routes", [integrals.ROUTES, ()], ids=["closed", "numeric"])
def test_one_integrand_on_two_half_infinite_domains_keeps_each_reference_point(routes):
    """The cache shares symbolic work between curves, never the domain's reference point
    (CI once saw Q_REF = 1.3 for a domain (-oo, -0.3) after a run on (0.3, oo))."""
    from symvib.symbolic.curve import graph

    right = graph("x**2", domain=("3/10", "oo"))
    left = graph("x**2", domain=("-oo", "-3/10"))
    F_right = antiderivative(right, 1, seconds=0.5, routes=routes)
    F_left = antiderivative(left, 1, seconds=0.5, routes=routes)
    assert F_right.q_ref == sp.Rational(13, 10) and F_left.q_ref == -sp.Rational(13, 10)
    if not routes:  # the numeric form integrates from its own reference point
        assert F_left.expr.limits[0][1] == -sp.Rational(13, 10)
        assert sp.simplify(sp.diff(F_left.expr, left.q) - F_left.integrand) == 0


def test_jobs_started_together_each_keep_their_own_budget_from_their_start():
    """budget.start / finish: the branches' routes run side by side; a job's budget counts from
    its start, so waiting for another job first does not lengthen it."""
    quick = budget.start(time.sleep, (0.2,), seconds=5.0)
    slow = budget.start(time.sleep, (30.0,), seconds=1.0)
    time.sleep(1.2)  # (the slow job's budget is spent while the parent waits elsewhere)
    assert budget.finish(slow).status == "timeout"
    done = budget.finish(quick)
    assert done.status == "ok" and done.value is None
    assert not slow.proc.is_alive() and not quick.proc.is_alive()


def test_both_branches_at_once_find_what_each_finds_alone():
    """antiderivatives (both branches, routes side by side) against antiderivative branch by branch:
    the same closed form, route and attempts (routes and verdicts) on each branch."""
    curve = shape("cycloid").curve()
    integrals._CACHE.clear()
    together = integrals.antiderivatives(curve)
    integrals._CACHE.clear()
    for s in (1, -1):
        alone = antiderivative(curve, s)
        assert sp.simplify(together[s].expr - alone.expr) == 0
        assert together[s].route == alone.route and together[s].verification == alone.verification
        assert [(a.route, a.outcome) for a in together[s].attempts] == [(a.route, a.outcome) for a in alone.attempts]


def _wrong_sympy_job(f: str, q: str):
    """The sympy route's closed form, made wrong by a term whose derivative is small but not zero."""
    F = integrals._job_sympy(f, q)
    var = integrals._find(sp.sympify(f), q)
    return F + mu**2 * var**3 / 10**6


def test_a_wrong_closed_form_is_rejected_by_the_numeric_check(monkeypatch):
    """Under closed_form "auto" a closed form is checked numerically only (no symbolic substitution):
    a wrong one (derivative off by 3e-6 mu**2 q**2) is still rejected and the numeric route stands in,
    while the right one passes, verified "numeric"."""
    from symvib.symbolic.curve import graph

    c = graph("a*x**2/2")
    monkeypatch.setattr(integrals, "_CACHE", {})
    right = integrals.antiderivatives(c, routes=("sympy",), seconds=20.0, total=20.0, check="numeric")
    assert all(F.route == "sympy" and F.verification == "numeric" for F in right.values())
    monkeypatch.setattr(integrals, "_CACHE", {})
    monkeypatch.setattr(integrals, "_route_job", lambda route, f, curve, s: (_wrong_sympy_job,
                                                                            (sp.srepr(f), curve.q.name)))
    wrong = integrals.antiderivatives(c, routes=("sympy",), seconds=20.0, total=20.0, check="numeric")
    for F in wrong.values():
        assert F.route == "numeric"
        assert [a.outcome for a in F.attempts] == ["rejected: derivative check failed"]


def test_an_unknown_check_names_the_option():
    with pytest.raises(ValueError, match="check: 'maybe'"):
        integrals.antiderivatives(shape("circle").curve(), check="maybe")
