"""Samples and dense output of a run with flights (docs/physics.md, "Flight and landing", Samples,
dense output and figures).

Flight samples against the parabola computed here from the lift-off event's state (the curve
written by hand in tests/flight_reference.py, not the kernels) and from the landing law applied
by hand at each bounce; sliding samples after a landing against a run started from the landing
state; the energy columns against the budget; the dense output in flight, on the curve and in a
bouncing-ball accumulation; the columns in flight (NaN ``q``, zero forces) and in the tables.
"""
import json
import math

import numpy as np
import pytest
from flight_reference import CURVES

from symvib import simulate
from symvib.numeric.events import EventKind, Status
from symvib.numeric.scene import scene_from_dict

G = 9.81
#: Agreement of a closed form evaluated here and by the run (a few roundings of the sums).
CLOSED = 1e-12
#: The energy columns close to this share of E0 (the issue's 1e-12).
BUDGET_TOL = 1e-12


def circle_scene(e=0.0, qdot=8.0, **extra):
    """The paper's circle (R = 0.5) run fast enough to lift off near its top, unilateral."""
    data = {"name": f"circle-e{e}", "curve": {"shape": "circle"}, "parameters": {"R": 0.5},
            "physics": {"g": G, "mu": 0.05, "restitution": 1.0, "contact": "unilateral", "restitution_curve": e},
            "initial": {"q": 0.0, "qdot": qdot}}
    data.update(extra)
    return scene_from_dict(data)


def sine_scene():
    """A sine track ``z = a (1 - cos(x / b))`` crossed fast: it lifts off a crest and bounces."""
    a, b = 0.2, 0.3
    return scene_from_dict({"name": "sine", "curve": CURVES["sine"].curve, "parameters": {"a": a, "b": b},
                            "physics": {"g": G, "mu": 0.05, "restitution": 1.0, "contact": "unilateral",
                                        "restitution_curve": 0.3},
                            "initial": {"q": 0.0, "qdot": math.sqrt(4 * G * a + 2 * G * b * b / a)},
                            "run": {"t_max": 3.0, "max_events": 200}})


@pytest.fixture(scope="module")
def runs():
    out = {"plastic": simulate(circle_scene(0.0), backend="python"),
           "bounce": simulate(circle_scene(0.5), backend="python"),
           "sine": simulate(sine_scene(), backend="python")}
    for r in out.values():
        assert r.count(EventKind.LIFT_OFF) and r.success, r.status
    return out


def by_hand(result):
    """``(curve, params)`` of tests/flight_reference.py for a run's curve."""
    name = "circle" if result.scene.shape.name == "circle" else "sine"
    return CURVES[name], result.scene.param_dict


def launch_from_lift_off(result, event):
    """``(x0, z0, vx, vz)`` at a lift-off, from the curve by hand: ``V = qdot (x', z')``."""
    curve, p = by_hand(result)
    x, z, dx, dz, _, _ = curve.f(event.q, p)
    return x, z, event.qdot_after * dx, event.qdot_after * dz


def bounce_by_hand(result, vx, vz, q):
    """The landing law of physics.md written out: the velocity after landing at ``q`` with ``(vx, vz)``."""
    curve, p = by_hand(result)
    _, _, dx, dz, _, _ = curve.f(q, p)
    h = math.hypot(dx, dz)
    tx, tz = dx / h, dz / h
    u, v = -tz * vx + tx * vz, tx * vx + tz * vz
    e, mu = result.scene.restitution_curve, result.scene.mu
    jn = (1 + e) * -min(u, 0.0)
    v_after = 0.0 if abs(v) <= mu * jn else v - math.copysign(mu * jn, v)
    u_after = -e * min(u, 0.0)
    return -tz * u_after + tx * v_after, tx * u_after + tz * v_after


# --- flights: the parabola --------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["plastic", "bounce", "sine"])
def test_flight_samples_are_the_parabola_launched_at_the_lift_off(runs, name):
    r = runs[name]
    S = r.samples
    lift = next(e for e in r.events if e.kind is EventKind.LIFT_OFF)
    landings = [e for e in r.events if e.kind is EventKind.LANDING and "accumulation" not in e.detail]
    x0, z0, vx, vz = launch_from_lift_off(r, lift)
    t0 = lift.t
    curve, p = by_hand(r)
    L = 0.5 if name != "sine" else 0.3
    for k in range(int(S.flight.max()) + 1):
        sel = S.flight == k
        t = S.t[sel]
        assert t[0] == pytest.approx(t0, abs=1e-14) and t[-1] == pytest.approx(landings[k].t, abs=1e-14)
        tau = t - t0
        assert np.allclose(S.x[sel], x0 + vx * tau, rtol=0, atol=CLOSED * L)
        assert np.allclose(S.z[sel], z0 + vz * tau - G * tau ** 2 / 2, rtol=0, atol=CLOSED * L)
        assert np.allclose(S.vx[sel], vx, rtol=0, atol=CLOSED * 10) and \
            np.allclose(S.vz[sel], vz - G * tau, rtol=0, atol=CLOSED * 10)
        assert abs(curve.side(S.x[sel][-1], S.z[sel][-1], p)) < 1e-9   # it ends on the curve: the landing
        # the next flight (a bounce) starts where this one lands, with the landing law's velocity
        x0, z0 = S.x[sel][-1], S.z[sel][-1]
        vx, vz = bounce_by_hand(r, S.vx[sel][-1], S.vz[sel][-1], landings[k].q)
        t0 = t[-1]


def test_flight_columns_have_no_curve_coordinate_and_no_contact_force(runs):
    S = runs["bounce"].samples
    fly = S.flight >= 0
    assert fly.any() and (~fly).any()
    for name in ("q", "qdot", "v", "s"):
        assert np.isnan(getattr(S, name)[fly]).all() and np.isfinite(getattr(S, name)[~fly]).all(), name
    assert (S.F_N[fly] == 0).all() and (S.F_mu[fly] == 0).all() and (S.P_mu[fly] == 0).all()
    assert (S.branch[fly] == 0).all() and (S.branch[~fly] != 0).all()
    m = runs["bounce"].scene.m
    assert np.allclose(S.Ek, 0.5 * m * (S.vx ** 2 + S.vz ** 2), rtol=1e-12, atol=1e-15)
    assert np.allclose(S.Ep, m * G * S.z, rtol=1e-12, atol=1e-15)
    # time order, one interval number per motion interval, the path grows
    assert (np.diff(S.t) >= 0).all() and (np.diff(S.interval) >= 0).all() and (np.diff(S.path) >= -1e-15).all()
    for k in np.unique(S.flight[fly]):
        assert len(np.unique(S.interval[S.flight == k])) == 1
    # on the circle the arc-length coordinate from the start is R (q - q0), across the flights too
    assert np.allclose(S.s[~fly], 0.5 * S.q[~fly], rtol=0, atol=1e-12)


def test_the_flights_path_is_the_parabolas_arc_length(runs):
    r = runs["plastic"]
    S = r.samples
    sel = S.flight == 0
    x, z = S.x[sel], S.z[sel]
    # the polygon through the dense points approaches the arc from below, to O(step^2)
    polygon = np.sum(np.hypot(np.diff(x), np.diff(z)))
    arc = S.path[sel][-1] - S.path[sel][0]
    assert polygon <= arc + 1e-12 and arc - polygon < 1e-4 * arc
    assert S.path[sel][0] == pytest.approx(S.path[np.flatnonzero(sel)[0] - 1], abs=1e-15)


@pytest.mark.parametrize("per_interval", [None, 10, 200])
def test_a_flight_has_as_many_samples_as_a_sliding_interval(per_interval):
    r = simulate(circle_scene(0.0), backend="python", samples_per_interval=per_interval)
    S = r.samples
    first = np.sum(S.interval == 0)   # the sliding up to the lift-off: one motion interval
    asked = (per_interval or 96) + 1
    assert np.sum(S.flight == 0) >= asked and first >= asked
    if per_interval != 10:   # (at 10, one piece of the engine's logged intervals: a few of them here)
        assert np.sum(S.flight == 0) == first


# --- sliding: as a run from the landing state --------------------------------------------------------


def test_sliding_after_a_landing_is_the_run_started_from_the_landing_state(runs):
    r = runs["plastic"]
    land = next(e for e in r.events if e.kind is EventKind.LANDING)
    again = simulate(r.scene.replace(q0=land.q, qdot0=land.qdot_after), backend="python")
    A, S = again.samples, r.samples
    after = (S.t >= land.t) & (S.flight < 0)
    assert after.sum() == len(A.t)
    assert np.allclose(S.t[after], land.t + A.t, rtol=0, atol=1e-14)
    for name in ("q", "qdot", "x", "z", "E", "F_N", "v"):
        assert np.allclose(getattr(S, name)[after], getattr(A, name), rtol=0, atol=1e-13), name
    b = r.energy_budget
    before = b.initial - A.E[0]   # what friction and the landing took before
    assert np.allclose(S.W_mu[after] + S.W_impacts[after] + S.W_landing[after], before + A.W_mu + A.W_impacts,
                       rtol=0, atol=BUDGET_TOL * b.initial)
    assert (S.W_landing[after] == b.landing_loss).all()
    assert [e.kind for e in again.events] == [e.kind for e in r.events if e.t > land.t]


@pytest.mark.parametrize("name", ["plastic", "bounce", "sine"])
def test_energy_columns_close_with_the_budget(runs, name):
    r = runs[name]
    S, b = r.samples, r.energy_budget
    total = S.E + S.W_mu + S.W_impacts + S.W_landing
    assert np.abs(total - b.initial).max() < BUDGET_TOL * b.initial
    for k in np.unique(S.flight[S.flight >= 0]):   # a flight conserves E
        E = S.E[S.flight == k]
        assert np.ptp(E) < BUDGET_TOL * b.initial
    if r.status is Status.ARRESTED:
        assert S.W_landing[-1] == b.landing_loss and S.E[-1] == pytest.approx(b.final, abs=BUDGET_TOL * b.initial)


# --- the dense output -------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["plastic", "bounce", "sine"])
def test_dense_output_in_flight_is_the_parabola_and_on_the_curve_the_samples(runs, name):
    r = runs[name]
    S, D = r.samples, r.dense
    fly = S.flight >= 0
    x, z, vx, vz = D.position(S.t[fly])
    # (at a landing time the state is the one after it: the flights' last samples are compared before)
    inner = np.r_[S.flight[fly][1:] == S.flight[fly][:-1], False] & np.r_[False, S.flight[fly][1:] ==
                                                                           S.flight[fly][:-1]]
    for got, want in ((x, S.x), (z, S.z), (vx, S.vx), (vz, S.vz)):
        assert np.allclose(got[inner], want[fly][inner], rtol=0, atol=1e-12)
    assert D.in_flight(S.t[fly][inner]).all() and np.isnan(D.state(S.t[fly][inner])[0]).all()
    # on the curve, inside the motion intervals (not at the events' times, which hold both sides)
    on = np.flatnonzero(~fly)
    t = S.t[on]
    single = np.r_[True, np.diff(t) > 0] & np.r_[np.diff(t) > 0, True] & (t < r.t_final)
    event_times = np.array([e.t for e in r.events])
    single &= np.min(np.abs(t[:, None] - event_times[None, :]), axis=1) > 1e-9
    q, qdot = D.state(t[single])
    assert np.allclose(q, S.q[on][single], rtol=0, atol=1e-11)
    assert np.allclose(qdot, S.qdot[on][single], rtol=1e-9, atol=1e-9)
    assert not D.in_flight(t[single]).any()


def test_dense_output_at_a_landing_is_the_state_after_it_and_rests_after_arrest(runs):
    r = runs["plastic"]
    land = next(e for e in r.events if e.kind is EventKind.LANDING)
    lift = next(e for e in r.events if e.kind is EventKind.LIFT_OFF)
    q, qdot = r.state(land.t)
    assert q == pytest.approx(land.q, abs=1e-12) and qdot == pytest.approx(land.qdot_after, abs=1e-12)
    q, qdot = r.state(lift.t - 1e-12)
    assert q == pytest.approx(lift.q, abs=1e-10)
    assert r.dense.in_flight(lift.t) and np.isnan(r.state(lift.t)[0])   # right-continuous: flying
    assert r.status is Status.ARRESTED and r.dense.t_max == math.inf
    assert r.state(r.t_final + 5.0) == (r.q_final, r.qdot_final)
    t, qd = r.at(0.3)   # first passage on the curve (the flight over q = 0.3 does not pass it)
    assert r.state(t)[0] == pytest.approx(0.3, abs=1e-12) and t < lift.t
    with pytest.raises(ValueError, match="t: the state is defined"):
        r.state(-1.0)
    with pytest.raises(ValueError, match="interval"):
        r.at(0.3, interval=r.dense.n_intervals)


def test_dense_output_in_a_bouncing_ball_accumulation_moves_from_its_start_to_its_end(runs):
    r = runs["bounce"]
    end = next(e for e in r.events if "accumulation" in e.detail)
    start = [e for e in r.events if e.t < end.t][-1]
    mid = 0.5 * (start.t + end.t)
    q, qdot = r.state(mid)
    assert min(start.q, end.q) < q < max(start.q, end.q) and not r.dense.in_flight(mid)
    assert r.state(end.t) == pytest.approx((end.q, end.qdot_after), abs=1e-12)


def test_a_run_stopped_in_flight_has_samples_and_a_state_to_its_end():
    # the circle with a limiter near its top: the flight crosses the limiter's line (tests/test_flight.py)
    scene = circle_scene(0.0, 8.5, limiters={"left": -0.3, "right": 3.0})
    r = simulate(scene.replace(mu=0.0), backend="python")
    assert r.status is Status.CROSSED_LIMITER
    S = r.samples
    assert S.flight[-1] == 0 and S.t[-1] == pytest.approx(r.t_final, abs=1e-14)
    lift = r.events[-1]
    x0, z0, vx, vz = launch_from_lift_off(r, lift)
    tau = r.t_final - lift.t
    x, z, _, _ = r.dense.position(r.t_final)
    assert x == pytest.approx(x0 + vx * tau, abs=1e-12) and z == pytest.approx(z0 + vz * tau - G * tau ** 2 / 2,
                                                                             abs=1e-12)
    assert r.dense.t_max == r.t_final


def test_without_samples_a_run_with_flights_has_neither_samples_nor_dense_output():
    r = simulate(circle_scene(0.5), backend="python", samples=False)
    assert r.samples is None and r.stats["intervals"] is None
    with pytest.raises(ValueError, match="kept no intervals"):
        _ = r.dense


# --- tables -----------------------------------------------------------------------------------------


def test_the_tables_and_json_carry_the_flight_columns_with_units(runs):
    pytest.importorskip("pandas")
    r = runs["bounce"]
    frame = r.samples_frame()
    for name, unit in (("W_landing", "J"), ("vx", "m/s"), ("vz", "m/s"), ("flight", "1"), ("q", "rad")):
        assert name in frame.columns and frame.attrs["units"][name] == unit
    data = json.loads(r.to_json(samples=True))
    assert data["samples"]["q"][int(np.flatnonzero(r.samples.flight >= 0)[0])] is None   # NaN in flight
    assert data["units"]["samples"]["W_landing"] == "J"


# --- many scenes, and the compiled engine (slow) ----------------------------------------------------


@pytest.mark.slow
def test_random_unilateral_scenes_have_samples_that_close_the_budget_and_a_state_everywhere():
    # the seeded random scenes of tests/test_flight.py (a bowl, the circle, a sine track)
    import random

    from test_flight import N_RANDOM, SEED, random_scene

    rng = random.Random(SEED)
    for i in range(N_RANDOM):
        scene, name = random_scene(rng, i)
        r = simulate(scene, backend="python")
        S, b = r.samples, r.energy_budget
        assert S is not None, (i, r.error)
        total = S.E + S.W_mu + S.W_impacts + getattr(S, "W_landing", 0.0)
        assert np.abs(total - b.initial).max() < BUDGET_TOL * b.initial, (i, name)
        assert (np.diff(S.t) >= 0).all(), (i, name)
        t = np.linspace(0.0, r.t_final, 64)
        if r.count(EventKind.LIFT_OFF):
            x, z, vx, vz = r.dense.position(t)
            assert np.isfinite(np.stack([x, z, vx, vz])).all(), (i, name)
            assert (np.isnan(r.state(t)[0]) == r.dense.in_flight(t)).all(), (i, name)


@pytest.mark.slow
def test_numba_samples_of_a_run_with_flights_equal_the_plain_ones():
    a = simulate(circle_scene(0.5), backend="python").samples
    b = simulate(circle_scene(0.5), backend="numba").samples
    assert len(a.t) == len(b.t) and np.array_equal(a.flight, b.flight)
    for name in ("t", "q", "qdot", "x", "z", "E", "W_mu", "W_landing"):
        assert np.allclose(getattr(a, name), getattr(b, name), rtol=1e-12, atol=1e-12, equal_nan=True), name
