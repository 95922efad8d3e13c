"""Flight and landing on a unilateral curve (docs/physics.md, "Flight and landing").

Closed forms: the flight and its landing on a flat floor and on a straight slope, the
landing law (sticking and sliding), bouncing-ball accumulations on a flat floor and on a
slope (time and state after them); the energy lost equals the budget's landing column;
hostile values of ``physics.restitution_curve``; and, slow, seeded random unilateral scenes
on three curves against an independent integrator written from physics.md
(tests/flight_reference.py: solve_ivp on the sliding equations, the flight in closed form,
its landing by a dense scan of an explicit signed function and brentq).
"""
import json
import math
import random

import pytest
from flight_reference import CURVES, reference_run

from symvib import simulate
from symvib.numeric.events import EventKind, Status
from symvib.numeric.flight import (
    ACCUMULATION_W,
    LANDED,
    Stretch,
    accumulation,
    landing,
    landing_law,
    limiter_crossing,
)
from symvib.numeric.flights import fly
from symvib.numeric.scene import SceneError, scene_from_dict
from symvib.prepare import prepare

G = 9.81
#: Relative agreement asked of a closed form (a few rounding errors of the sums).
CLOSED = 1e-12
#: Agreement of event times with the independent integrator, s (the issue's 1e-9).
TIME_TOL = 1e-9
#: The energy budget closes to this share of E0 (the issue's 1e-12).
BUDGET_TOL = 1e-12
#: Seeded random scenes against the reference (the issue asks for at least 50 on at least 3 curves).
N_RANDOM, SEED = 54, 20261127


def line_scene(slope, e=0.5, mu=0.2, qdot=0.0, **run):
    """A straight line ``z = s x`` (``s = 0``: a flat floor), unilateral."""
    return scene_from_dict({"name": "line", "curve": {"z": "s*x", "name": "flight-line", "params": {"s": "real"}},
                            "parameters": {"s": slope},
                            "physics": {"g": G, "mu": mu, "restitution": 1.0, "contact": "unilateral",
                                        "restitution_curve": e},
                            "initial": {"q": 0.0, "qdot": qdot}, "run": run})


def line_stretch(slope):
    scene = line_scene(slope)
    mod = prepare(scene).kernels
    return scene, mod, Stretch(mod, (slope,), -50.0, 50.0, 1.0, 0.0)


# --- the flight and its landing in closed form ----------------------------------------------------


@pytest.mark.parametrize("vx,vz,height", [(1.5, 2.0, 0.7), (-0.3, 0.0, 2.0), (0.0, 4.0, 0.0 + 1e-3)])
def test_landing_on_a_flat_floor_is_the_root_of_the_parabola(vx, vz, height):
    _, _, st = line_stretch(0.0)
    ld = landing(st, 0.0, height, vx, vz, G, vz if height == 0 else 0.0, 1.0)
    t = (vz + math.sqrt(vz * vz + 2 * G * height)) / G
    assert ld.kind == LANDED
    assert ld.t == pytest.approx(t, rel=CLOSED) and ld.q == pytest.approx(vx * t, rel=CLOSED, abs=1e-14)


@pytest.mark.parametrize("slope,u,v", [(0.3, 1.0, 0.5), (-0.5, 0.2, -2.0), (0.7, 2.0, 0.0)])
def test_a_bounce_on_a_straight_slope_lasts_2u_over_g_cos_alpha(slope, u, v):
    # From the line's point with normal speed u and tangential v: T = 2 u / (g cos alpha), and it
    # lands v T - g sin alpha T^2 / 2 further along the line.
    _, _, st = line_stretch(slope)
    c, s = 1 / math.hypot(1, slope), slope / math.hypot(1, slope)
    vx, vz = v * c - u * s, v * s + u * c
    ld = landing(st, 0.0, 0.0, vx, vz, G, u, 1.0)
    T = 2 * u / (G * c)
    along = v * T - G * s * T * T / 2
    assert ld.kind == LANDED and ld.t == pytest.approx(T, rel=CLOSED)
    assert ld.q == pytest.approx(along * c, rel=1e-11)


def test_a_path_that_grazes_the_floor_from_above_is_not_a_landing_until_it_crosses():
    # A path whose apex is 1e-9 m above a floor at z = 0 ... no: a path launched upwards from 1e-9 m
    # must not land at its start; it lands where the parabola crosses z = 0.
    _, _, st = line_stretch(0.0)
    ld = landing(st, 0.0, 1e-9, 0.5, 1.0, G, 0.0, 1.0)
    assert ld.t == pytest.approx((1.0 + math.sqrt(1.0 + 2 * G * 1e-9)) / G, rel=CLOSED)


def test_a_limiter_line_is_crossed_where_the_quadratic_says():
    # A wall x = 1 (the normal line of a flat floor at q = 1): a path from (0, 1) with vx = 2 reaches it at 0.5 s.
    assert limiter_crossing(10.0, 0.0, 1.0, 2.0, 0.0, G, 1.0, 0.0, 1.0, 0.0, 1) == pytest.approx(0.5)
    assert limiter_crossing(0.4, 0.0, 1.0, 2.0, 0.0, G, 1.0, 0.0, 1.0, 0.0, 1) == math.inf   # lands first
    assert limiter_crossing(10.0, 0.0, 1.0, 2.0, 0.0, G, -1.0, 0.0, 1.0, 0.0, -1) == math.inf  # moving away


# --- the landing law ------------------------------------------------------------------------------


@pytest.mark.parametrize("e", [0.0, 0.4, 1.0])
def test_landing_law_sticks_within_the_cone_and_slides_with_the_bounded_impulse(e):
    mu = 0.3
    stick = landing_law(0.2, -2.0, 1.0, 0.0, e, mu)            # |v| = 0.2 <= mu (1 + e) 2
    assert stick.stick and stick.v_after == 0.0 and stick.u_after == pytest.approx(2.0 * e)
    slide = landing_law(3.0, -2.0, 1.0, 0.0, e, mu)            # |v| = 3 > mu (1 + e) 2
    assert not slide.stick and slide.v_after == pytest.approx(3.0 - mu * (1 + e) * 2.0)
    for law, (vx, vz) in ((stick, (0.2, -2.0)), (slide, (3.0, -2.0))):
        assert law.loss == pytest.approx(0.5 * (vx * vx + vz * vz - law.u_after ** 2 - law.v_after ** 2))
        assert law.loss >= 0.0
    # On a slope the same in the slope's frame: a velocity along the normal only, no tangential part.
    c, s = math.cos(0.4), math.sin(0.4)
    normal = landing_law(2.0 * s, -2.0 * c, c, s, e, mu)
    assert normal.u_before == pytest.approx(-2.0) and normal.v_before == pytest.approx(0.0, abs=1e-15)
    assert normal.u_after == pytest.approx(2.0 * e)


def test_energy_lost_at_landings_is_the_budgets_landing_column():
    # A drop onto a flat floor (fly: the flights of a run, from a launch 1 m up): every landing's
    # loss is m (|V-|^2 - |V+|^2) / 2, and they add to W_landing.
    scene, mod, st = line_stretch(0.0)
    scene = scene.replace(restitution_curve=0.6)
    flown = fly(scene, mod, (0.0,), st, 0.0, 0.0, 1.0, 0.8, 0.0, 0.0, 1.0, 0)
    v_end = flown.slide[2]
    E0 = scene.m * G * 1.0 + scene.m * 0.8 ** 2 / 2
    assert flown.W_landing == pytest.approx(E0 - scene.m * v_end ** 2 / 2, rel=1e-13)


# --- bouncing-ball accumulations ------------------------------------------------------------------


@pytest.mark.parametrize("e,mu,vx", [(0.5, 0.2, 0.0), (0.7, 0.05, 3.0), (0.3, 0.4, 0.5)])
def test_bouncing_ball_on_a_flat_floor_accumulates_as_the_closed_form_says(e, mu, vx):
    # Dropped from H with vx: first landing at sqrt(2 H / g) with speed v1 = sqrt(2 g H); then
    # bounces of 2 e^k v1 / g; each landing takes mu (1 + e) e^k v1 of the tangential speed
    # (or all of it: it sticks).  Time and place of the accumulation, and the speed after it.
    H = 0.8
    scene, mod, st = line_stretch(0.0)
    scene = scene.replace(restitution_curve=e, mu=mu)
    flown = fly(scene, mod, (0.0,), st, 0.0, 0.0, H, vx, 0.0, 0.0, 1.0, 0)
    v1 = math.sqrt(2 * G * H)
    t, x, v = math.sqrt(2 * H / G), vx * math.sqrt(2 * H / G), vx
    for k in range(400):
        u = e ** k * v1                          # incoming normal speed of landing k
        v = max(v - mu * (1 + e) * u, 0.0)       # it sticks once the cone holds it
        T = 2 * e ** (k + 1) * v1 / G
        t, x = t + T, x + v * T
    t_acc, q_acc, qdot_acc = flown.slide
    assert flown.stop is None
    assert t_acc == pytest.approx(math.sqrt(2 * H / G) + 2 * e * v1 / (G * (1 - e)), rel=CLOSED)
    assert t_acc == pytest.approx(t, rel=CLOSED)
    assert q_acc == pytest.approx(x, rel=CLOSED, abs=1e-15) and qdot_acc == pytest.approx(v, rel=1e-9, abs=1e-15)
    assert flown.events[-1].kind is EventKind.LANDING and "accumulation" in flown.events[-1].detail
    # the series was summed once the bounces were below the threshold, not before
    assert (e ** flown.landings * v1) ** 2 < ACCUMULATION_W * G * 1.0 <= (e ** (flown.landings - 1) * v1) ** 2


@pytest.mark.parametrize("slope,e,mu,v", [(0.1, 0.5, 0.3, 0.0), (0.25, 0.6, 0.1, -1.0), (0.25, 0.6, 0.1, 2.0)])
def test_bouncing_ball_on_a_slope_accumulates_as_the_closed_form_says(slope, e, mu, v):
    # From the line's point with normal speed u and tangential v.  In the slope's frame every
    # bounce is exact: T_k = 2 u_k / (g cos a), the tangential speed changes by -g sin a T_k in
    # flight and by the landing law at each landing.  The sum of the series (here term by term,
    # 400 bounces) against the engine's bounces and its closed-form tail.
    u = 0.9
    scene, mod, st = line_stretch(slope)
    scene = scene.replace(restitution_curve=e, mu=mu)
    c, s = 1 / math.hypot(1, slope), slope / math.hypot(1, slope)
    flown = fly(scene, mod, (slope,), st, 0.0, 0.0, 0.0, v * c - u * s, v * s + u * c, u, 1.0, 0)
    t, along, uk, vk = 0.0, 0.0, u, v
    for _ in range(400):
        T = 2 * uk / (G * c)
        t, along = t + T, along + vk * T - G * s * T * T / 2
        v_land = vk - G * s * T
        jt = mu * (1 + e) * uk
        vk = 0.0 if abs(v_land) <= jt else v_land - math.copysign(jt, v_land)
        uk *= e
    t_acc, q_acc, qdot_acc = flown.slide
    # (1e-10: the last bounces simulated one by one land with normal speeds near sqrt(1e-10 g L), and
    # their landing times carry the rounding of the positions, eps |x|, over that speed)
    assert t_acc == pytest.approx(2 * u / (G * c * (1 - e)), rel=1e-10) and t_acc == pytest.approx(t, rel=1e-10)
    assert q_acc == pytest.approx(along * c, rel=1e-10, abs=1e-15)
    assert qdot_acc == pytest.approx(vk * c, rel=1e-9, abs=1e-14)   # q = x: qdot = v / h = v cos a


def test_accumulation_regimes_in_closed_form():
    # Stuck: 2 |tan a| <= mu (1 + e), v = 0: creeps by 2 u^2 tan a / (g cos a (1 - e^2)).
    a, e, mu, u = 0.1, 0.5, 0.5, 1e-3
    acc = accumulation(u, 0.0, G * math.sin(a), G * math.cos(a), e, mu)
    assert acc.stuck and acc.bounces == 0 and acc.v_after == 0.0
    assert acc.time == pytest.approx(2 * u / (G * math.cos(a) * (1 - e)), rel=CLOSED)
    assert acc.ds == pytest.approx(-2 * u * u * math.tan(a) / (G * math.cos(a) * (1 - e * e)), rel=CLOSED)
    # Drifting: v_inf = v + c u / (1 - e), c = -2 tan a - sigma mu (1 + e).
    v = 1.0
    acc = accumulation(u, v, G * math.sin(a), G * math.cos(a), e, 0.1)
    c = -2 * math.tan(a) - 0.1 * (1 + e)
    assert not acc.stuck and acc.v_after == pytest.approx(v + c * u / (1 - e), rel=CLOSED)


def test_a_bouncing_ball_run_end_to_end_closes_its_budget_and_arrests():
    # The circle run fast: it lifts off, lands and bounces with e = 0.5 until the series is summed,
    # slides and arrests; the budget (with its landing column) closes.
    scene = scene_from_dict({"curve": {"shape": "circle"}, "parameters": {"R": 0.5},
                             "physics": {"g": G, "mu": 0.05, "restitution": 1.0, "contact": "unilateral",
                                         "restitution_curve": 0.5}, "initial": {"q": 0.0, "qdot": 8.0}})
    r = simulate(scene, backend="python")
    kinds = [e.kind for e in r.events]
    assert kinds[0] is EventKind.LIFT_OFF and kinds.count(EventKind.LANDING) > 5
    assert r.status is Status.ARRESTED and r.success
    b = r.energy_budget
    assert b.landing_loss > 0 and b.relative_residual < BUDGET_TOL
    data = json.loads(r.to_json())
    assert data["energy_budget"]["landing_loss"] == b.landing_loss and data["units"]["energy_budget"]["landing_loss"]
    assert {"lift_off", "landing"} <= {e["kind"] for e in data["events"]}
    assert "landing loss" in r.event_table()
    S = r.samples   # (its samples: tests/test_flight_samples.py)
    flown = [e for e in r.events if e.kind is EventKind.LANDING and "accumulation" not in e.detail]
    assert S.flight.max() + 1 == len(flown) and r.error is None   # (the summed bounces are not sampled)
    # a bilateral run's budget and JSON are as they were: no landing column
    plain = simulate(scene.replace(contact="bilateral"), backend="python", samples=False)
    assert plain.energy_budget.landing_loss is None and "landing_loss" not in plain.to_dict()["energy_budget"]


# --- the scene field ------------------------------------------------------------------------------


@pytest.mark.parametrize("value", [float("nan"), -1, 2, "half", float("inf"), True])
def test_hostile_restitution_curve_is_refused_naming_the_field(value):
    data = {"curve": {"shape": "circle"}, "parameters": {"R": 0.5},
            "physics": {"mu": 0.05, "restitution": 1.0, "contact": "unilateral", "restitution_curve": value},
            "initial": {"q": 0.0, "qdot": 1.0}}
    with pytest.raises(SceneError) as err:
        scene_from_dict(data)
    assert err.value.field == "physics.restitution_curve"


def test_restitution_curve_round_trips_and_defaults_to_zero():
    base = {"curve": {"shape": "circle"}, "parameters": {"R": 0.5},
            "physics": {"mu": 0.05, "restitution": 1.0, "contact": "unilateral"}, "initial": {"q": 0.0, "qdot": 1.0}}
    s = scene_from_dict(base)
    assert s.restitution_curve == 0.0 and "restitution_curve" not in s.to_dict()["physics"]
    t = s.replace(restitution_curve=0.25)
    assert scene_from_dict(t.to_dict()) == t and t.to_dict()["physics"]["restitution_curve"] == 0.25


def test_a_flight_across_a_limiters_line_ends_the_run_with_its_status():
    # The circle with a limiter near its top: the lifted particle's flight crosses the limiter's
    # normal line (a radius) before it lands; the run stops there, at the time the line's
    # quadratic gives, with its energy (the flight's) in the budget.
    R, right = 0.5, 3.0
    scene = scene_from_dict({"curve": {"shape": "circle"}, "parameters": {"R": R},
                             "physics": {"g": G, "mu": 0.0, "restitution": 1.0, "contact": "unilateral"},
                             "limiters": {"left": -0.3, "right": right}, "initial": {"q": 0.0, "qdot": 8.5}})
    r = simulate(scene, backend="python")
    assert r.events[-1].kind is EventKind.LIFT_OFF
    assert r.status is Status.CROSSED_LIMITER and "right limiter" in r.message and r.success
    lift = r.events[-1]
    phi, v = lift.q, lift.qdot_before * R
    x0, z0, vx, vz = R * math.sin(phi), R * (1 - math.cos(phi)), v * math.cos(phi), v * math.sin(phi)
    # the radius through the limiter's point: (P(t) - C) x (direction of the radius) = 0
    dx, dz = math.sin(right), -math.cos(right)
    def cross(t):
        return (x0 + vx * t) * dz - (z0 + vz * t - G * t * t / 2 - R) * dx
    from scipy.optimize import brentq
    t_cross = brentq(cross, 1e-9, 1.0, xtol=1e-16)
    assert r.t_final == pytest.approx(lift.t + t_cross, abs=1e-12)
    assert r.energy_budget.relative_residual < BUDGET_TOL


# --- against the independent integrator -----------------------------------------------------------


def random_scene(rng, i):
    """Scene ``i`` of the seeded random set: a curve of :data:`CURVES`, parameters, friction,
    restitution of landings and a start fast enough to lift off (most of the time)."""
    name = sorted(CURVES)[i % len(CURVES)]
    mu = rng.choice([0.0, rng.uniform(0.0, 0.15)])
    e = rng.choice([0.0, rng.uniform(0.05, 0.6)])
    if name == "circle":
        R = rng.uniform(0.3, 1.0)
        params, q0 = {"R": R}, 0.0
        qdot0 = math.sqrt(G * R * rng.uniform(2.6, 4.6)) / R
    elif name == "sine":
        a, b = rng.uniform(0.1, 0.3), rng.uniform(0.2, 0.5)
        params, q0 = {"a": a, "b": b}, 0.0
        qdot0 = math.sqrt(4 * G * a + G * b * b / a * rng.uniform(1.2, 3.0)) * rng.choice([-1, 1])
    else:
        a, b = rng.uniform(0.5, 2.0), rng.uniform(0.3, 1.0)
        params, q0 = {"a": a, "b": b}, math.sqrt(b / (2 * a))
        depth = b * b / (4 * a)
        qdot0 = -math.sqrt(2 * G * depth + G / (2 * b) * rng.uniform(1.2, 3.0))
    physics = {"g": G, "mu": mu, "restitution": 1.0, "contact": "unilateral", "restitution_curve": e}
    return scene_from_dict({"name": f"flight-{i}", "curve": CURVES[name].curve, "parameters": params,
                            "physics": physics, "initial": {"q": q0, "qdot": qdot0},
                            "run": {"t_max": 6.0, "max_events": 200}}), name


@pytest.mark.slow
def test_random_unilateral_scenes_agree_with_an_independent_integrator():
    rng = random.Random(SEED)
    lifted = {name: 0 for name in CURVES}
    bounced = 0
    for i in range(N_RANDOM):
        scene, name = random_scene(rng, i)
        r = simulate(scene, backend="python")
        assert r.success, (i, r.status, r.message)
        assert r.energy_budget.relative_residual < BUDGET_TOL, (i, r.energy_budget)
        ref = reference_run(scene, CURVES[name], r.stats.get("scale"))
        got = [(e.kind.value, e.t) for e in r.events]
        assert [k for k, _ in got] == [k for k, _ in ref.events], (i, name, got, ref.events)
        worst = max((abs(a[1] - b[1]) for a, b in zip(got, ref.events)), default=0.0)
        assert worst < TIME_TOL, (i, name, worst)
        assert r.status.value == ref.status, (i, r.status, ref.status)
        if r.count(EventKind.LIFT_OFF):
            lifted[name] += 1
        bounced += any("normal velocity" in e.detail and "-> 0 " not in e.detail for e in r.events
                       if e.kind is EventKind.LANDING and scene.restitution_curve > 0)
    assert all(n >= 10 for n in lifted.values()), lifted
    assert bounced >= 10


@pytest.mark.slow
def test_the_compiled_engine_flies_as_the_plain_one():
    # backend="numba": the compiled engine slides, the flights run between its runs as on the plain one.
    scene = scene_from_dict({"curve": {"shape": "circle"}, "parameters": {"R": 0.5},
                             "physics": {"g": G, "mu": 0.05, "restitution": 1.0, "contact": "unilateral",
                                         "restitution_curve": 0.5}, "initial": {"q": 0.0, "qdot": 8.0}})
    a, b = simulate(scene, backend="python"), simulate(scene, backend="numba")
    assert b.stats["backend"] == "numba" and a.status is b.status is Status.ARRESTED
    assert [e.kind for e in a.events] == [e.kind for e in b.events]
    assert max(abs(x.t - y.t) for x, y in zip(a.events, b.events)) < 1e-12
