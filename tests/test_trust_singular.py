"""Issue 13 (Trust), singular curves: poles, cusps and branch points are never integrated across.

A run of a user curve uses the regular interval around ``initial.q``
(:mod:`symvib.symbolic.singular`); a singular ``initial.q`` or a limiter beyond a
singular point is a one-line :class:`SceneError` naming the field.
"""
from __future__ import annotations

import math

import pytest

from symvib.numeric.scene import SceneError, scene_from_dict
from symvib.prepare import prepare
from symvib.shapes import CATALOGUE
from symvib.symbolic.curve import graph, parametric
from symvib.symbolic.singular import regular_interval

INF = math.inf
#: Agreement of a located singular point with the exact one (bisection to adjacent doubles).
POINT_TOL = 1e-7


def _scene(z, q0, qdot=1.0, params=None, limiters=None, mu=0.1, t_max=20.0):
    data = {"curve": {"z": z}, "physics": {"mu": mu, "restitution": 0.8},
            "initial": {"q": q0, "qdot": qdot}, "run": {"t_max": t_max}}
    if params:
        data["curve"]["params"] = list(params)
        data["parameters"] = dict(params)
    if limiters:
        data["limiters"] = limiters
    return scene_from_dict(data)


# (z, parameters, q0, expected regular interval); the hostile curves of the issue (classes 3 and 7) and more.
INTERVALS = [
    ("x**2 + 1/(x - 0.3)", {}, 0.5, (0.3, INF)),
    ("x**2 + 1/(x - 0.3)", {}, 0.1, (-INF, 0.3)),
    ("x**2 + 1/(x - a)", {"a": 0.3}, 0.5, (0.3, INF)),
    ("x**2 + 1/(x - a)", {"a": 0.7}, 0.5, (-INF, 0.7)),
    ("-1/x", {}, 0.5, (0.0, INF)),
    ("-1/x", {}, -0.5, (-INF, 0.0)),
    ("1/x**2", {}, 0.5, (0.0, INF)),
    ("sqrt(x)", {}, 0.5, (0.0, INF)),
    ("sqrt(1 - x**2)", {}, 0.5, (-1.0, 1.0)),
    ("x**x", {}, 0.5, (0.0, INF)),
    ("acosh(x)", {}, 1.5, (1.0, INF)),
    ("log(x)", {}, 0.5, (0.0, INF)),
    ("1/sin(x)", {}, 1.0, (0.0, math.pi)),
    ("tan(x)", {}, 0.2, (-math.pi / 2, math.pi / 2)),
    ("x**(2/3)", {}, 0.5, (0.0, INF)),
    ("x**2/2", {}, 0.5, (-INF, INF)),
    ("cosh(x)", {}, 0.5, (-INF, INF)),
]


def _close(got, want):
    return got == want if math.isinf(want) else abs(got - want) <= POINT_TOL * max(1.0, abs(want))


@pytest.mark.parametrize("z, params, q0, want", INTERVALS, ids=[f"{z}@{q0}" for z, _, q0, _ in INTERVALS])
def test_regular_interval_of_hostile_curves(z, params, q0, want):
    c = graph(z, params=list(params) or None)
    r = regular_interval(c, params, q0, (-INF, INF))
    assert not r.at_start
    assert _close(r.lo, want[0]) and _close(r.hi, want[1]), (r, want)
    # Conservative: the interval never reaches over the singular point.
    assert want[0] <= r.lo and r.hi <= want[1]
    if math.isfinite(want[0]):
        assert r.lo_reason
    if math.isfinite(want[1]):
        assert r.hi_reason


#: (z, parameters, q0, regular interval, reason of the finite end): an Abs or sign whose argument
#: changes sign is a corner where the slope jumps, and a regular point where only a higher
#: derivative does.
CORNERS = [
    ("abs(x)", {}, 0.5, (0.0, INF), "z' is discontinuous (a corner)"),
    ("abs(x)", {}, -0.5, (-INF, 0.0), "z' is discontinuous (a corner)"),
    ("sqrt(x**2)", {}, 0.5, (0.0, INF), "z' is discontinuous (a corner)"),      # SymPy: Abs(x)
    ("abs(x - a) + x**2", {"a": 0.3}, 0.5, (0.3, INF), "z' is discontinuous (a corner)"),
    ("abs(sin(x))", {}, 1.0, (0.0, math.pi), "z' is discontinuous (a corner)"),
    ("abs(x)**3", {}, 0.5, (-INF, INF), ""),                                   # z'' jumps only
    ("x*abs(x)", {}, 0.5, (-INF, INF), ""),                                    # slope continuous
    ("abs(x)*x**2 + abs(x - 1)**3", {}, 0.5, (-INF, INF), ""),
    ("x**2 + abs(x)**3", {}, -0.5, (-INF, INF), ""),
]


@pytest.mark.parametrize("z, params, q0, want, reason", CORNERS, ids=[f"{c[0]}@{c[2]}" for c in CORNERS])
def test_corners_bound_the_interval_and_smooth_abs_does_not(z, params, q0, want, reason):
    c = graph(z, params=list(params) or None)
    r = regular_interval(c, params, q0, (-INF, INF))
    assert _close(r.lo, want[0]) and _close(r.hi, want[1]), r
    assert want[0] <= r.lo and r.hi <= want[1]
    assert reason in (r.lo_reason, r.hi_reason)


@pytest.mark.parametrize("x, z, want, reason", [
    ("q + abs(q)", "q", (0.0, INF), "x' is discontinuous (a corner)"),   # the speed h jumps
    ("q", "abs(q)", (0.0, INF), "z' is discontinuous (a corner)"),
    ("q**3 + abs(q)**3", "q", (-INF, INF), ""),                           # x' continuous (0) at 0
])
def test_corners_of_parametric_curves(x, z, want, reason):
    r = regular_interval(parametric(x, z), {}, 0.5, (-INF, INF))
    assert _close(r.lo, want[0]) and _close(r.hi, want[1]), r
    assert reason in (r.lo_reason, r.hi_reason)


def test_a_corner_is_a_singular_initial_position_and_bounds_the_limiters():
    with pytest.raises(SceneError, match="initial.q.*z' is discontinuous"):
        prepare(_scene("abs(x)", 0.0))
    with pytest.raises(SceneError, match="limiters.left.*beyond a singular point"):
        prepare(_scene("abs(x) + x**2", 0.5, limiters={"left": -0.2}))


@pytest.mark.parametrize("x, z, q0, want", [
    ("phi + sin(phi)", "1 - cos(phi)", 0.5, (-math.pi, math.pi)),          # cycloid: cusps at +-pi
    ("cos(q)**3", "sin(q)**3", 0.5, (0.0, math.pi / 2)),                   # astroid: cusps at k pi/2
    ("q**3", "q**2", 0.5, (0.0, INF)),                                     # semicubical cusp at 0
])
def test_cusps_of_parametric_curves_bound_the_interval(x, z, q0, want):
    c = parametric(x, z, q="phi" if "phi" in x else "q")
    r = regular_interval(c, {}, q0, (-INF, INF))
    assert _close(r.lo, want[0]) and _close(r.hi, want[1]), r
    assert want[0] <= r.lo and r.hi <= want[1]


@pytest.mark.parametrize("z, q0, params", [
    ("x**2 + 1/(x - 0.3)", 0.3, {}),
    ("x**2 + 1/(x - a)", 0.7, {"a": 0.7}),
    ("acosh(x)", 0.5, {}),          # z not real left of 1
    ("sqrt(1 - x**2)", 1.5, {}),
    ("log(x)", -1.0, {}),
    ("-1/x", 0.0, {}),
])
def test_singular_initial_position_is_a_scene_error(z, q0, params):
    scene = _scene(z, q0, params=params)
    with pytest.raises(SceneError) as err:
        prepare(scene)
    assert err.value.field == "initial.q"
    assert "singular point" in str(err.value) and "\n" not in str(err.value)


@pytest.mark.parametrize("z, q0, limiters, field", [
    ("x**2 + 1/(x - 0.3)", 0.5, {"left": 0.1}, "limiters.left"),
    ("x**2 + 1/(x - 0.3)", 0.1, {"right": 0.5}, "limiters.right"),
    ("x**2 + 1/(x - 0.3)", 0.1, {"right": 0.3}, "limiters.right"),  # on the pole itself
    ("sqrt(1 - x**2)", 0.5, {"left": -0.5, "right": 1.2}, "limiters.right"),
    ("log(x)", 0.5, {"left": -0.1}, "limiters.left"),
])
def test_limiter_beyond_a_singular_point_is_a_scene_error(z, q0, limiters, field):
    scene = _scene(z, q0, limiters=limiters)
    with pytest.raises(SceneError) as err:
        prepare(scene)
    assert err.value.field == field
    assert "beyond a singular point" in str(err.value)


def test_limiters_inside_the_regular_interval_are_accepted():
    scene = _scene("x**2 + 1/(x - 0.3)", 0.5, limiters={"left": 0.35, "right": 2.0})
    run = prepare(scene).domain
    assert run.lo > 0.3 and run.hi == INF and run.narrowed


def test_regular_user_curve_keeps_its_module():
    """No singular point in the domain: the run uses the curve's module as it is (same events)."""
    from symvib.numeric.kernels import load

    scene = _scene("x**2/(2*p)", 0.5, params={"p": 1.0})
    p = prepare(scene)
    assert p.kernels is load(scene.shape) and not p.domain.narrowed and p.ends == (None, None)


def test_narrowed_domain_stays_inside_the_pole():
    run = prepare(_scene("x**2 + 1/(x - a)", 0.5, params={"a": 0.3})).domain
    assert 0.3 < run.lo < 0.3 + 1e-9
    assert run.scale <= 0.2 + 1e-12  # panels no wider than the distance to the pole
    assert run.lo < run.q_ref < 0.5 + 1e-9   # a numeric F_sigma is integrated from inside the interval


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(CATALOGUE))
def test_catalogue_shapes_are_regular_on_their_domains(name):
    """The driver skips the search for catalogue shapes: each is regular on its declared domain."""
    sh = CATALOGUE[name]
    c = sh.curve()
    values = dict(sh.defaults)
    lo, hi = (float(e.subs({p: values[p.name] for p in c.params})) for e in c.domain)
    q0 = 0.0 if lo < 0.0 < hi else 0.5 * (lo + hi)
    r = regular_interval(c, values, q0, (lo, hi))
    assert (r.lo, r.hi) == (lo, hi), r


def _reference_reversals(a, mu, g, x0, xd0, n):
    """Turning points of paper eq. 1 on z = x^2 + 1/(x - a), by scipy's solve_ivp (independent of symvib)."""
    from scipy.integrate import solve_ivp

    def zp(x):
        return 2 * x - 1 / (x - a) ** 2

    def rhs(sigma):
        def f(t, y):
            x, xd = y
            d1, d2 = zp(x), 2 + 2 / (x - a) ** 3
            h = math.sqrt(1 + d1 * d1)
            normal = d2 / h**3 * (h * xd) ** 2 + g / h
            dv = -g * d1 / h - mu * sigma * abs(normal)
            return [xd, (dv - d1 * d2 / h * xd * xd) / h]
        return f

    t, out, sigma = 0.0, [], 1 if xd0 > 0 else -1
    while len(out) < n:
        def turn(t, y):
            return y[1]
        turn.terminal, turn.direction = True, -sigma
        sol = solve_ivp(rhs(sigma), (t, t + 50), [x0, xd0], events=turn, rtol=1e-12, atol=1e-12, method="DOP853")
        t, x0, xd0 = sol.t_events[0][0], sol.y_events[0][0][0], 0.0
        out.append((t, x0))
        if abs(zp(x0)) <= mu:
            break
        sigma = -1 if zp(x0) > 0 else 1
    return out


@pytest.mark.slow
def test_pole_example_gives_the_reversals_of_an_independent_integration():
    """Issue 13, class 3: z = x^2 + 1/(x - 0.3) ran to t_max with 0 events; it has reversals."""
    from symvib import simulate

    scene = _scene("x**2 + 1/(x - 0.3)", 0.5, qdot=1.0, mu=0.1)
    result = simulate(scene, samples=False)
    assert result.status.value == "arrested"
    assert result.energy_budget.relative_residual < 1e-9
    ref = _reference_reversals(0.3, 0.1, 9.81, 0.5, 1.0, len(result.events))
    assert len(ref) == len(result.events) >= 10
    for event, (t, x) in zip(result.events, ref):
        assert event.kind.value in ("reversal", "arrest")
        assert abs(event.q - x) < 1e-9
        assert abs(event.t - t) < 1e-8 * max(1.0, t)


@pytest.mark.slow
@pytest.mark.parametrize("z, q0", [("-1/x", 0.5), ("sqrt(x)", 0.5), ("sqrt(1 - x**2)", 0.5), ("x**x", 0.5),
                                   ("acosh(x)", 1.5), ("log(x)", 0.5)])
def test_crashing_curves_run_without_a_traceback(z, q0):
    """Issue 13, class 7: each crashed (ZeroDivisionError, complex ordering); now it runs in its
    regular interval and, when it reaches a singular point, ends there with status
    reached_singular_point (success False), its message naming the point; never a success that
    does not close."""
    from symvib import simulate

    scene = _scene(z, q0)
    run = prepare(scene).domain
    result = simulate(scene, samples=False)
    lo, hi = run.lo, run.hi
    assert lo < result.q_final < hi or result.q_final in (lo, hi)
    assert result.status.value in ("reached_singular_point", "arrested", "t_max")
    assert math.isfinite(result.t_final)
    if result.status.value == "reached_singular_point":
        assert not result.success and "singular point x = " in result.message
    if result.success:
        assert result.energy_budget.relative_residual < 1e-9


@pytest.mark.parametrize("z", ["cos(1000000*x)/1000000", "1e-6*cos(x/1e-6)"])
def test_a_curve_that_oscillates_a_million_times_has_no_singular_point(z):
    """Thousands of sign changes of kappa on the scan grid are bisected together (one at a time
    took minutes); none is a pole, and the scan still finds the poles of INTERVALS."""
    from symvib.symbolic.singular import corners

    c = graph(z)
    assert corners(c) == ()
    r = regular_interval(c, {}, 0.0, (-INF, INF))
    assert (r.lo, r.hi, r.at_start) == (-INF, INF, "")


# (z, q0, qdot0, the pole it falls into): z -> -oo there, so the particle runs into it.
POLES = [("x**2 + 1/(x - 0.3)", 0.0, 1.0, 0.3), ("x**2 + 1/(x - 0.3)", 0.0, -0.5, 0.3),
         ("-1/(x - 1)**2", 0.0, 0.5, 1.0), ("x**2 - 1/(x + 0.5)", 0.0, -1.0, -0.5)]


@pytest.mark.parametrize("z, q0, qdot, pole", POLES)
def test_a_run_into_a_pole_ends_reached_singular_point_naming_it(z, q0, qdot, pole):
    """It ended energy_budget_mismatch (E = -3440 J) or tolerance_not_met, which name no point."""
    from symvib import simulate

    result = simulate(_scene(z, q0, qdot=qdot, t_max=5.0), samples=False, backend="python")
    assert result.status.value == "reached_singular_point" and not result.success
    assert f"singular point x = {pole:.12g} " in result.message and "z is not finite" in result.message
    assert (result.q_final - pole) * (q0 - pole) > 0  # stopped on its side of the point
    # The events before it are right: the same events as a run that stops at the last of them.
    if result.events:
        last = result.events[-1].t
        before = simulate(_scene(z, q0, qdot=qdot, t_max=last), samples=False, backend="python")
        assert [(e.kind, e.t, e.q) for e in before.events] == [(e.kind, e.t, e.q) for e in result.events]


def test_a_pole_that_repels_is_no_end():
    """z -> +oo at the pole: the particle turns before it, and the run is a success."""
    from symvib import simulate

    result = simulate(_scene("x**2 - 1/(x - 0.3)", 0.0, qdot=3.0, t_max=5.0), samples=False, backend="python")
    assert result.status.value == "t_max" and result.success
    assert result.q_final < 0.3


def test_the_turning_point_next_to_a_pole_is_where_an_independent_integrator_puts_it():
    # F_s' grows as 1/(x - 0.3)^2: G carried from an anchor (its closed form cancels at the turning
    # point) by fixed panels was off by 2.6e-11 in q and 2.9e-9 s in t; its panels are checked now.
    pytest.importorskip("scipy")
    from symvib import simulate
    from symvib.checks.accuracy import reference_for

    data = {"curve": {"z": "x**2 - 1/(x - 0.3)"}, "physics": {"mu": 0.1, "restitution": 0.8},
            "initial": {"q": 0.0, "qdot": 3.0}, "run": {"t_max": 5.0}}
    kind, t_ref, q_ref = reference_for(data).run.events[0][:3]
    for backend in ("python", "numba"):
        first = simulate(scene_from_dict(data), samples=False, backend=backend).events[0]
        assert first.kind.value == kind == "reversal"
        assert abs(first.t - t_ref) <= 1e-12 * t_ref and abs(first.q - q_ref) <= 1e-13, (backend, first)


def test_a_sweep_refuses_a_user_curve_with_a_singular_point_in_its_domain(tmp_path):
    """A sweep runs one kernel module for all rows: it names the regular domain to declare
    instead of integrating across the pole (simulate narrows; a sweep once bypassed that)."""
    from symvib import sweep

    scene = _scene("x**2 + 1/(x - 0.3)", 0.5)
    with pytest.raises(SceneError, match=r"curve\.domain.*singular point.*declare domain = \[\"0\.3") as info:
        sweep(scene, {"qdot": [1.0, 2.0]}, out=tmp_path / "out")
    assert "\n" not in str(info.value)
    assert not (tmp_path / "out").exists()
    import dataclasses
    import re

    from symvib.numeric.sweep.runner import _refuse_singular_domain

    lo, hi = re.search(r'domain = \["([^"]+)", "([^"]+)"\]', str(info.value)).groups()
    assert 0.3 < float(lo) < 0.3 + 1e-9 and hi == "oo"
    declared = scene.replace(shape=dataclasses.replace(scene.shape, domain=(lo, hi)))
    _refuse_singular_domain(declared, prepare(declared))  # accepted


@pytest.mark.parametrize("length", [1.0, 1e-3, 1e-6, 1e-9])
def test_a_smooth_minimum_of_h_far_below_the_scan_grid_is_not_a_cusp(length):
    # A graph's h = sqrt(1 + z'^2) >= 1 has no cusp; at micrometres the grid (q_scale = 1) sees h a
    # million times its minimum next to each minimum, which was taken for a cusp (initial.q refused).
    c = graph("a*((x/b)**2 - 1)**2", params=("a", "b"))
    r = regular_interval(c, {"a": 0.125 * length, "b": length}, -0.7 * length, (-INF, INF))
    assert (r.lo, r.hi) == (-INF, INF), r


@pytest.mark.parametrize("length", [1e3, 1.0, 1e-3, 1e-6, 1e-9])
def test_a_cusp_at_a_small_length_scale_still_bounds_the_interval(length):
    # At 1e-6 and 1e-9 the cusp's piece, measured against h at the grid's neighbours (h ~ q**2/L**2
    # there, millions of times its size near the cusp), swallowed the start at 0.5 L.
    c = parametric("q**3/L**2", "q**2/L", params=("L",))      # the semicubical cusp at 0, at length L
    r = regular_interval(c, {"L": length}, 0.5 * length, (-INF, INF))
    assert 0.0 <= r.lo <= 1e-2 * length and r.hi == INF and r.lo_reason == "h is zero (a cusp)", r
