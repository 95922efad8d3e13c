"""The independent reference (:mod:`symvib.checks.arclength`) meets closed forms of the mechanics."""
import math

import mpmath
import pytest

from symvib.checks.arclength import reference_run
from symvib.numeric.scene import scene_from_dict

pytest.importorskip("scipy")

G = 9.81
#: Agreement of event times with a closed form (s), both quadratures.
CLOSED_TOL = 1e-12


def _scene(curve, parameters, physics, limiters, q, qdot, **run):
    return scene_from_dict({"curve": curve, "parameters": parameters, "physics": {"g": G, **physics},
                            "limiters": limiters, "initial": {"q": q, "qdot": qdot},
                            "run": {"t_max": 100.0, "max_events": 100, **run}})


def _incline_events(c, mu, k, x0, n):
    """Closed form of a slide from rest down ``z = c x`` onto a limiter at ``x = 0``, and its bounces."""
    h = math.sqrt(1 + c * c)
    sin, cos = c / h, 1 / h
    down, up = G * (sin - mu * cos), G * (sin + mu * cos)
    t, dist, out = 0.0, x0 * h, []
    while len(out) < n:
        v = math.sqrt(2 * down * dist)
        t += v / down
        out.append(("impact", t, 0.0, -v / h))
        climb = k * v
        t += climb / up
        dist = climb * climb / (2 * up)
        out.append(("reversal", t, dist / h, 0.0))
    return out[:n]


@pytest.mark.parametrize("method", ["DOP853", "GBS"])
def test_incline_with_friction_matches_the_closed_form_bounces(method):
    c, mu, k, x0, n = 0.5, 0.1, 0.8, 1.0, 8
    s = _scene({"z": "c*x"}, {"c": c}, {"mu": mu, "restitution": k}, {"left": 0.0}, x0, 0.0, max_events=n)
    run = reference_run(s, method)
    want = _incline_events(c, mu, k, x0, n)
    assert run.status == "max_events"
    assert [e[0] for e in run.events] == [w[0] for w in want]
    for e, w in zip(run.events, want):
        assert e[1] == pytest.approx(w[1], abs=CLOSED_TOL)
        assert e[2] == pytest.approx(w[2], abs=CLOSED_TOL)
        assert e[3] == pytest.approx(w[3], rel=CLOSED_TOL)
    assert all(e[4] == pytest.approx(-k * e[3]) for e in run.events if e[0] == "impact")


@pytest.mark.parametrize("method", ["DOP853", "GBS"])
def test_frictionless_pendulum_reverses_at_half_periods(method):
    R, phi0 = 0.5, 1.2
    s = _scene({"shape": "circle"}, {"R": R}, {"mu": 0.0, "restitution": 1.0}, {}, phi0, 0.0, max_events=4)
    run = reference_run(s, method)
    half = 2 * math.sqrt(R / G) * float(mpmath.ellipk(math.sin(phi0 / 2) ** 2))
    assert [e[0] for e in run.events] == ["reversal"] * 4
    for j, e in enumerate(run.events, 1):
        assert e[1] == pytest.approx(j * half, abs=CLOSED_TOL)
        assert e[2] == pytest.approx(phi0 if j % 2 == 0 else -phi0, abs=1e-12)


def test_energy_is_conserved_without_friction_over_many_impacts():
    p, v0 = 1.0, 3.0
    s = _scene({"shape": "parabola-x"}, {"p": p}, {"mu": 0.0, "restitution": 1.0}, {"left": -0.5, "right": 0.7},
               0.0, v0, max_events=60)
    run = reference_run(s)
    assert run.status == "max_events" and {e[0] for e in run.events} == {"impact"}
    for e in run.events:
        x = e[2]
        speed = abs(e[3]) * math.sqrt(1 + (x / p) ** 2)
        assert speed == pytest.approx(math.sqrt(v0 * v0 - 2 * G * x * x / (2 * p)), rel=1e-11)


def test_a_start_at_rest_within_the_cone_edge_is_an_arrest_at_once():
    mu = 0.3
    s = _scene({"shape": "parabola-x"}, {"p": 1.0}, {"mu": mu, "restitution": 0.5}, {}, mu * (1 + 5e-10), 0.0)
    run = reference_run(s)
    assert run.status == "arrested" and run.events == (("arrest", 0.0, s.q0, 0.0, 0.0),)


def test_a_start_just_outside_the_cone_edge_stops_after_half_a_period_mirrored():
    # Near the edge x_e = mu p of z = x^2 / (2 p) the slide is harmonic, omega^2 = g cos^2(alpha_e) / p.
    mu, p, delta = 0.3, 1.0, 1e-6
    s = _scene({"shape": "parabola-x"}, {"p": p}, {"mu": mu, "restitution": 0.5}, {}, mu * p * (1 + delta), 0.0,
               t_max=5.0)
    omega = math.sqrt(G / (p * (1 + mu * mu)))
    run = reference_run(s, "GBS")
    assert run.status == "arrested" and [e[0] for e in run.events] == ["arrest"]
    _, t, x, _, _ = run.events[0]
    assert t == pytest.approx(math.pi / omega, rel=10 * delta)
    assert (mu * p - x) == pytest.approx(s.q0 - mu * p, rel=10 * delta)


def test_the_double_precision_reference_fails_loudly_next_to_the_cone_edge():
    # Its right-hand side is rounding noise there (a ~ 1e-9 g): DOP853's steps collapse, and it says so.
    mu, p = 0.3, 1.0
    s = _scene({"shape": "parabola-x"}, {"p": p}, {"mu": mu, "restitution": 0.5}, {}, mu * p * (1 + 4e-9), 0.0,
               t_max=5.0)
    run = reference_run(s, budget=20.0)
    assert run.status == "failed" and "collapsed" in run.message


def test_gbs_times_a_loop_whose_speed_at_the_top_nearly_vanishes_as_the_energy_integral_does():
    # Frictionless circle: w = v0^2 - 2 g R (1 - cos phi), t(phi) = Integral R dphi / sqrt(w), with
    # w_top / v0^2 = 1e-8 (the double-precision reference is off by microseconds here).
    R, ratio, right = 0.5, 1e-8, 4.0
    v0 = math.sqrt(4 * G * R * (1 + ratio))
    s = _scene({"shape": "circle"}, {"R": R}, {"mu": 0.0, "restitution": 0.5}, {"right": right}, 0.0, v0 / R,
               max_events=3, t_max=20.0)
    run = reference_run(s, "GBS")
    with mpmath.workdps(30):
        w = lambda phi: mpmath.mpf(v0) ** 2 - 2 * G * R * (1 - mpmath.cos(phi))  # noqa: E731
        t_impact = mpmath.quad(lambda phi: R / mpmath.sqrt(w(phi)), [0, mpmath.pi, right])
    assert [e[0] for e in run.events] == ["normal_sign_change", "normal_sign_change", "impact"]
    assert run.events[2][1] == pytest.approx(float(t_impact), abs=CLOSED_TOL)


def test_unilateral_contact_leaves_the_circle_where_the_normal_force_vanishes():
    R, v0 = 0.5, 4.0
    s = scene_from_dict({"curve": {"shape": "circle"}, "parameters": {"R": R},
                         "physics": {"g": G, "mu": 0.0, "restitution": 1.0, "contact": "unilateral"},
                         "initial": {"q": 0.0, "qdot": v0 / R}})
    run = reference_run(s)
    # w = v0^2 - 2 g R (1 - cos phi) and N = w / R + g cos phi = 0.
    phi = math.acos((2 * G - v0 * v0 / R) / (3 * G))
    assert run.status == "left_curve" and [e[0] for e in run.events] == ["left_curve"]
    assert run.events[0][2] == pytest.approx(phi, abs=1e-11)


def test_gbs_and_dop853_agree_on_a_generic_scene_with_friction_and_a_sign_change_of_n():
    s = _scene({"shape": "circle"}, {"R": 0.5}, {"mu": 0.1, "restitution": 0.7}, {"right": 4.0}, 0.0, 11.0,
               max_events=6)
    a, b = reference_run(s), reference_run(s, "GBS")
    assert [e[0] for e in a.events] == [e[0] for e in b.events]
    assert "normal_sign_change" in [e[0] for e in a.events] and "impact" in [e[0] for e in a.events]
    assert max(abs(x[1] - y[1]) for x, y in zip(a.events, b.events)) < 1e-11


def test_a_grazing_approach_finds_the_impact_even_when_one_step_crosses_the_limiter_twice():
    # The limiter sits 1e-10 (relative) below the top of the climb: a DOP853 step spans it.
    p, v0 = 1.0, 2.0
    top = math.sqrt(2 * p * v0 * v0 / (2 * G))   # x where w reaches 0 without friction
    s = _scene({"shape": "parabola-x"}, {"p": p}, {"mu": 0.0, "restitution": 0.5}, {"right": top * (1 - 1e-10)},
               0.0, v0, max_events=1)
    for method in ("DOP853", "GBS"):
        run = reference_run(s, method)
        assert run.events[0][0] == "impact", method


def test_a_start_on_a_limiter_moving_into_it_is_an_impact_at_once_and_zeno_bounces_go_on():
    s = _scene({"z": "c*x"}, {"c": 0.5}, {"mu": 0.1, "restitution": 0.5}, {"left": 0.0}, 0.0, -1.0, max_events=30)
    run = reference_run(s)
    assert run.events[0][:3] == ("impact", 0.0, 0.0)
    kinds = [e[0] for e in run.events]
    assert set(kinds) <= {"impact", "reversal", "rest_on_limiter"} and kinds.count("impact") >= 10
    times = [e[1] for e in run.events]
    assert times == sorted(times)


def test_a_run_that_spends_its_budget_ends_failed():
    s = _scene({"shape": "circle"}, {"R": 0.5}, {"mu": 0.0, "restitution": 1.0}, {}, 0.0, 20.0, t_max=1e4,
               max_events=10**6)
    run = reference_run(s, budget=0.2)
    assert run.status == "failed" and "budget" in run.message
