"""The driver against an independent mpmath reference, its energy budget, and the hard cases."""
import dataclasses
import math
from pathlib import Path

import mpmath
import pytest

from symvib import simulate
from symvib.checks.reference import phase_reference
from symvib.numeric.events import EventKind, Status
from symvib.numeric.scene import load_scene, scene_from_dict

SCENES = Path(__file__).resolve().parents[1] / "symvib" / "scenes"
#: Required agreement of event times and positions with the 30-digit reference.
EVENT_TOL = 1e-12
#: Required energy-budget residual, relative to the initial energy.
BUDGET_TOL = 1e-12


def scene(shape="parabola", params=None, physics=None, limiters=None, initial=None, run=None):
    data = {
        "curve": {"shape": shape},
        "parameters": params or {"p": 1.0},
        "physics": {"g": 9.81, "m": 0.2, "alpha0": 0.05, "restitution": 0.8, **(physics or {})},
        "limiters": {"left": "-pi/6", "right": "pi/4"} if limiters is None else limiters,
        "initial": initial or {"q": 0.0, "qdot": 7.0},
    }
    if "mu" in data["physics"]:
        data["physics"].pop("alpha0")
    if run:
        data["run"] = run
    return scene_from_dict(data)


def assert_matches_reference(result, ref, tol=EVENT_TOL):
    n = len(ref)
    assert [e.kind.value for e in result.events[:n]] == [e.kind for e in ref]
    for e, r in zip(result.events, ref):
        assert abs(e.t - float(r.t)) < tol, (e, r)
        assert abs(e.q - float(r.q)) < tol, (e, r)
        assert abs(e.qdot_before - float(r.qdot_before)) < tol * max(1.0, abs(float(r.qdot_before))), (e, r)


@pytest.mark.parametrize("name", ["paper-parabola", "paper-cycloid", "paper-circle-3.8", "paper-circle-7"])
@pytest.mark.parametrize("k", [1.0, 0.8])
def test_paper_scenes_match_reference(name, k):
    s = load_scene(SCENES / f"{name}.toml").replace(k=k)
    result = simulate(s)
    ref = phase_reference(s)
    assert len(result.events) == len(ref)
    assert_matches_reference(result, ref)
    assert result.status is Status.ARRESTED
    assert result.energy_budget.relative_residual < BUDGET_TOL


@pytest.mark.slow
def test_the_reference_without_closed_forms_finds_a_swing_shorter_than_its_grid_step():
    """Under load the reference's derivation may spend its route budgets and integrate F_s' instead
    (seen once in a full run: 100,000 reversals against the engine's 4 events). paper-circle-3.8 at
    k = 0.8 reverses at phi = 0.1428 and swings back less than a grid step before it stops: from
    rest, G(q) = 0 exactly, and the bracket's start was taken for the next turning point, again and
    again. Without closed forms it must give the engine's events as the closed-form reference does."""
    from symvib.symbolic.derive import derive

    s = load_scene(SCENES / "paper-circle-3.8.toml").replace(k=0.8)
    ref = phase_reference(s, max_events=10, derive=lambda curve, seconds: derive(curve, seconds=seconds, routes=()))
    assert [e.kind for e in ref] == ["impact", "reversal", "reversal", "arrest"]
    assert_matches_reference(simulate(s), ref)


def test_result_is_immutable_and_serializable():
    result = simulate(load_scene(SCENES / "paper-parabola.toml"))
    with pytest.raises(dataclasses.FrozenInstanceError):
        result.status = Status.T_MAX  # type: ignore[misc]
    with pytest.raises(ValueError):
        result.samples.t[0] = 1.0
    data = result.to_dict()
    assert data["status"] == "arrested"
    assert set(data["events"][0]) >= {"kind", "t", "q", "qdot_before", "qdot_after", "energy"}
    assert set(data["energy_budget"]) == {"initial", "final", "friction_work", "impact_loss", "residual"}
    table = result.event_table("phi")
    assert "impact" in table and "status: arrested" in table


def test_samples_follow_the_energy_balance():
    """Along every interval dE = P_mu dt: the sampled E and the integral of P_mu agree."""
    result = simulate(load_scene(SCENES / "paper-circle-7.toml"))
    S = result.samples
    assert (S.P_mu <= 0).all()
    for i in range(int(S.interval.max()) + 1):
        sel = S.interval == i
        t, E, P = S.t[sel], S.E[sel], S.P_mu[sel]
        work = float(sum(0.5 * (P[1:] + P[:-1]) * (t[1:] - t[:-1])))
        assert E[-1] - E[0] == pytest.approx(work, rel=2e-3, abs=1e-6)


# --- hard cases ----------------------------------------------------------------------------------
def grazing_qdot0(eps, p=1.0, g=9.81, alpha0=0.05, q_lim=math.pi / 4):
    """Initial phidot on the paper parabola for which w at the right limiter is eps (closed form, 40 digits)."""
    with mpmath.workdps(40):
        mu = mpmath.tan(mpmath.mpf(alpha0))
        F = lambda x: p * mpmath.exp(2 * mu * x) / (2 * mpmath.cos(x) ** 2)  # noqa: E731
        ql = mpmath.pi / 4 if q_lim == math.pi / 4 else mpmath.mpf(q_lim)
        C = eps * mpmath.exp(2 * mu * ql) + 2 * g * F(ql)
        w0 = C - 2 * g * F(0)
        return float(mpmath.sqrt(w0) / p)


@pytest.mark.parametrize("eps", [1e-9, -1e-9, 1e-14])
def test_grazing_impact_matches_reference_within_its_conditioning(eps):
    """Near grazing the problem is ill-conditioned: w at the limiter is a small difference
    of O(w0) terms, so one ulp of the initial velocity moves event times by ~1e-11.
    The driver must agree with the 30-digit reference within the spread the reference
    itself shows for a 4-ulp change of the initial velocity (plus EVENT_TOL)."""
    qdot0 = grazing_qdot0(eps)
    s = scene(initial={"q": 0.0, "qdot": qdot0})
    result = simulate(s)
    assert result.events[0].kind is (EventKind.IMPACT if eps > 0 else EventKind.REVERSAL)
    ref = phase_reference(s, max_events=4)
    spread = [0.0] * len(ref)
    vspread = [0.0] * len(ref)
    for f in (1 - 4 * 2.0**-52, 1 + 4 * 2.0**-52):
        other = phase_reference(s.replace(qdot0=qdot0 * f), max_events=4)
        for i, (a, b) in enumerate(zip(ref, other)):
            spread[i] = max(spread[i], abs(float(a.t - b.t)), abs(float(a.q - b.q)))
            vspread[i] = max(vspread[i], abs(float(a.qdot_before - b.qdot_before)))
    assert [e.kind.value for e in result.events[:4]] == [e.kind for e in ref]
    for e, r, sp, vs in zip(result.events, ref, spread, vspread):
        assert abs(e.t - float(r.t)) < EVENT_TOL + sp, (e, r, sp)
        assert abs(e.q - float(r.q)) < EVENT_TOL + sp
        assert abs(e.qdot_before - float(r.qdot_before)) < EVENT_TOL * max(1, abs(e.qdot_before)) + vs
    assert result.energy_budget.relative_residual < BUDGET_TOL


def test_grazing_is_continuous_across_the_threshold():
    runs = [simulate(scene(initial={"q": 0.0, "qdot": grazing_qdot0(e)})) for e in (1e-12, -1e-12)]
    a, b = runs
    assert a.events[0].kind is EventKind.IMPACT and b.events[0].kind is EventKind.REVERSAL
    # The next event and everything after move by O(sqrt(eps)) only.
    for ea, eb in zip(a.events[1:4], b.events[1:4]):
        assert ea.kind is eb.kind
        assert abs(ea.t - eb.t) < 1e-5 and abs(ea.q - eb.q) < 1e-5


def test_turning_point_on_the_friction_cone_edge_arrests():
    """Started so that the turning point is exactly where tan(alpha) = mu: arrest there."""
    alpha0 = 0.05
    with mpmath.workdps(40):
        mu = mpmath.tan(mpmath.mpf(alpha0))
        edge = mpmath.atan(mu)
        F = lambda x: mpmath.exp(2 * mu * x) / (2 * mpmath.cos(x) ** 2)  # noqa: E731
        qdot0 = float(mpmath.sqrt(2 * mpmath.mpf(9.81) * (F(edge) - F(0))))
    result = simulate(scene(initial={"q": 0.0, "qdot": qdot0}))
    assert [e.kind for e in result.events] == [EventKind.ARREST]
    assert result.q_final == pytest.approx(alpha0, abs=1e-12)
    # At rest exactly on the edge, and just outside it.
    assert simulate(scene(initial={"q": alpha0, "qdot": 0.0})).status is Status.ARRESTED
    outside = simulate(scene(initial={"q": alpha0 * (1 + 1e-6), "qdot": 0.0}))
    assert outside.events[0].kind is EventKind.REVERSAL or outside.events[0].kind is EventKind.ARREST
    assert outside.q_final == pytest.approx(alpha0, abs=1e-3)


def zeno_scene(k):
    return scene(physics={"restitution": k}, limiters={"right": -0.3}, initial={"q": -0.6, "qdot": 0.0})


@pytest.mark.parametrize("k", [0.8, 1.0])
def test_zeno_accumulation_is_summed(k):
    s = zeno_scene(k)
    result = simulate(s)
    assert result.status is Status.RESTING_ON_LIMITER
    assert result.events[-1].kind is EventKind.REST_ON_LIMITER and result.zeno is not None
    # Limit ratio of bounce times from the local slope (alpha = phi on this parabola).
    mu, g, a = s.mu, s.g, 0.3
    a_up, a_down = g * (math.sin(a) + mu * math.cos(a)), g * (math.sin(a) - mu * math.cos(a))
    assert result.zeno.ratio == pytest.approx(k * math.sqrt(a_down / a_up), rel=1e-12)
    impacts = [e.t for e in result.events if e.kind is EventKind.IMPACT]
    d = [t1 - t0 for t0, t1 in zip(impacts, impacts[1:])]
    assert d[-1] / d[-2] == pytest.approx(result.zeno.ratio, rel=1e-4)
    assert result.energy_budget.relative_residual < BUDGET_TOL
    assert result.energy_budget.final == pytest.approx(s.m * s.g * (1 / math.cos(-0.3) ** 2 - 1) / 2, rel=1e-12)


def test_zeno_accumulation_time_against_reference():
    """The reference's bounces, extrapolated by their own geometric ratio, end where the driver says."""
    s = zeno_scene(0.8)
    result = simulate(s)
    ref = phase_reference(s, max_events=40)
    # Later bounces have w ~ 1e-7 of the first: like grazing, their times are conditioned
    # by the rounding of w (see the grazing test), so the first 16 events are held to 1e-12.
    assert_matches_reference(result, ref[:16])
    t = [float(e.t) for e in ref if e.kind == "impact"]
    d1, d2 = t[-1] - t[-2], t[-2] - t[-3]
    r = d1 / d2
    t_inf = t[-1] + d1 * r / (1 - r)
    assert result.t_final == pytest.approx(t_inf, abs=1e-7)


def test_plastic_impacts_stay_or_slide_away():
    stay = simulate(scene(physics={"restitution": 0.0}, limiters={"right": -0.3}, initial={"q": -0.6, "qdot": 0.0}))
    assert [e.kind for e in stay.events] == [EventKind.IMPACT, EventKind.REST_ON_LIMITER]
    assert stay.events[0].qdot_after == 0.0 and stay.status is Status.RESTING_ON_LIMITER
    slide_scene = scene(physics={"restitution": 0.0})
    slide = simulate(slide_scene)
    assert slide.events[0].kind is EventKind.IMPACT and slide.events[1].kind is EventKind.IMPACT
    assert slide.status is Status.ARRESTED
    assert_matches_reference(slide, phase_reference(slide_scene))


def test_frictionless_elastic_never_stops():
    s = scene(physics={"mu": 0.0, "restitution": 1.0}, run={"t_max": 60.0})
    result = simulate(s)
    assert result.status is Status.T_MAX and result.t_final == 60.0
    assert result.energy_budget.final == pytest.approx(result.energy_budget.initial, rel=1e-12)
    bounded = simulate(s.replace(max_events=50, t_max=1e6))
    assert bounded.status is Status.MAX_EVENTS and len(bounded.events) == 50


def test_t_max_inside_an_interval_keeps_the_budget():
    s = load_scene(SCENES / "paper-parabola.toml").replace(t_max=0.3)
    result = simulate(s)
    assert result.status is Status.T_MAX and result.t_final == 0.3
    assert result.energy_budget.relative_residual < BUDGET_TOL
    full = simulate(s.replace(t_max=1000.0))
    assert full.events[0].t < 0.3 < full.events[1].t
    assert -math.pi / 6 < result.q_final < math.pi / 4


def test_initial_states():
    at_rest_inside = simulate(scene(initial={"q": 0.04, "qdot": 0.0}))
    assert [(e.kind, e.t) for e in at_rest_inside.events] == [(EventKind.ARREST, 0.0)]
    at_rest_outside = simulate(scene(initial={"q": 0.5, "qdot": 0.0}))
    assert at_rest_outside.events[0].kind is EventKind.REVERSAL and at_rest_outside.events[0].t > 0
    into_limiter = scene(initial={"q": "pi/4", "qdot": 1.0})
    r = simulate(into_limiter)
    assert r.events[0].kind is EventKind.IMPACT and r.events[0].t == 0.0
    assert_matches_reference(r, phase_reference(into_limiter))
    pushed = simulate(scene(limiters={"right": -0.3}, initial={"q": -0.3, "qdot": 0.0}))
    assert [e.kind for e in pushed.events] == [EventKind.REST_ON_LIMITER]


def test_normal_force_changes_sign_above_the_diameter():
    s = scene("circle", {"R": 0.5}, {"restitution": 1.0}, limiters={}, initial={"q": 0.0, "qdot": 8.5})
    result = simulate(s)
    assert result.count(EventKind.NORMAL_SIGN_CHANGE) >= 2
    assert_matches_reference(result, phase_reference(s))
    assert result.energy_budget.relative_residual < BUDGET_TOL


def test_looping_circle_without_limiters():
    s = scene("circle", {"R": 0.5}, {"alpha0": 0.02, "restitution": 1.0}, limiters={}, initial={"q": 0.0, "qdot": 11.0})
    result = simulate(s)
    assert result.events[4].q > 4 * math.pi  # two full turns before the first reversal
    assert_matches_reference(result, phase_reference(s, max_events=12))
    assert result.status is Status.ARRESTED


def test_limiter_next_to_the_cycloid_cusp():
    s = scene("cycloid", {"R": 0.05}, {"restitution": 0.9}, limiters={"left": "-pi/6", "right": "pi - 0.01"},
              initial={"q": 0.0, "qdot": 30.0})
    result = simulate(s)
    assert result.events[0].q == pytest.approx(math.pi - 0.01) and abs(result.events[0].qdot_before) > 1000
    assert_matches_reference(result, phase_reference(s))
    reach = simulate(s.replace(right=None, left=-math.pi / 6, qdot0=60.0))
    assert reach.status is Status.LEFT_DOMAIN


def test_thousands_of_impacts_keep_the_budget():
    s = scene(physics={"mu": 1e-5, "restitution": 0.9999}, run={"max_events": 3000})
    result = simulate(s, samples=False)
    assert result.status is Status.MAX_EVENTS and result.count(EventKind.IMPACT) == 3000
    assert result.energy_budget.relative_residual < BUDGET_TOL
    times = [e.t for e in result.events]
    assert all(t1 > t0 for t0, t1 in zip(times, times[1:]))


@pytest.mark.slow
def test_numeric_route_curve_matches_reference():
    s = scene("catenary", {"a": 1.0}, limiters={"left": -0.8, "right": 1.0}, initial={"q": 0.0, "qdot": 4.0})
    result = simulate(s)
    assert_matches_reference(result, phase_reference(s, max_events=2))
    assert result.energy_budget.relative_residual < BUDGET_TOL


def test_a_single_run_never_waits_for_a_compiler(tmp_path, monkeypatch):
    # "auto" takes the compiled engine only where it is on disk already; an explicit
    # backend and $SYMVIB_BACKEND are obeyed (issue 15).
    from symvib.numeric import driver
    from symvib.numeric.engine.bind import compiled_marker
    from symvib.numeric.kernels import load

    monkeypatch.setenv("SYMVIB_CACHE", str(tmp_path))
    monkeypatch.delenv("SYMVIB_BACKEND", raising=False)
    shape = load_scene(SCENES / "paper-parabola.toml").shape
    assert driver.run_backend(shape, "auto") == "python"
    assert driver.run_backend(shape, "python") == "python"
    monkeypatch.setenv("SYMVIB_BACKEND", "python")
    assert driver.run_backend(shape, "auto") == "python"
    if driver.backend_available("numba"):
        monkeypatch.delenv("SYMVIB_BACKEND")
        marker = compiled_marker(load(shape), "simulate_bound")
        assert marker.parent.parent == tmp_path
        marker.parent.mkdir(parents=True)
        marker.touch()  # as the first numba run leaves it
        assert driver.run_backend(shape, "auto") == "numba"
        assert driver.run_backend(shape, "numba") == "numba"
    result = simulate(load_scene(SCENES / "paper-parabola.toml"), backend="python", samples=False)
    assert result.stats["backend"] == "python"


def test_samples_are_computed_on_first_use_and_once():
    # simulate() costs its events; the samples come when asked (issue 15), and are the same
    # as computed at once.
    scene = load_scene(SCENES / "paper-circle-7.toml")
    result = simulate(scene, backend="python")
    assert "samples" not in result._memo
    first = result.samples
    assert result._memo["samples"] is first and result.samples is first
    assert len(first.t) > 0 and result.error is None
    assert simulate(scene, backend="python", samples=False).samples is None
    again = simulate(scene, backend="python").to_dict(samples=True)["samples"]
    assert again["t"] == first.t.tolist()
