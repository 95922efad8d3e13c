"""Derivatives of lift-offs, flights and landings on a unilateral curve (physics.md, "Sensitivities" 10).

The landing's implicit equations and the landing law against their closed forms on a flat floor,
and every differentiable event of runs with flights (bounces, repeated lift-offs, a landing that
slides on to an arrest) against a Richardson-extrapolated step study of central differences of the
engine's own runs, to 1e-7, as tests/test_sensitivity_jets.py does for the sliding events.
"""
import math
import random
import warnings

import numpy as np
import pytest
from test_flight import random_scene

from symvib import simulate
from symvib.numeric.events import EventKind
from symvib.numeric.scene import scene_from_dict
from symvib.numeric.sensitivity import sensitivities
from symvib.numeric.sensitivity_curve import parameter_value, resolve_wrt, with_parameters
from symvib.numeric.sensitivity_flight import (
    ACCUMULATION_REASON,
    STICK_EDGE_REASON,
    TANGENTIAL_LANDING_REASON,
    Flight,
    land,
)

TOL = 1e-7
#: Steps of the study: a share of the parameter's size, halved twice.
FIRST_STEP = 1e-4
#: The random scenes of tests/test_flight.py used here (its seed): a circle whose landing slides on to
#: an arrest, and a sine track that lifts off and lands again and again.
SEED = 5
G = 9.81

BOUNCES = {"curve": {"shape": "circle"}, "parameters": {"R": 1.0},
           "physics": {"mu": 0.1, "restitution": 0.8, "contact": "unilateral", "restitution_curve": 0.3},
           "initial": {"q": 0.0, "qdot": 7.0}}


def _observed(scene, n):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = simulate(scene, samples=False)
    if len(r.events) < n:
        return None
    b = r.energy_budget
    return (np.array([e.t for e in r.events[:n]]), np.array([e.q for e in r.events[:n]]),
            np.array([r.t_final, b.friction_work, b.landing_loss]))


def _step_study(scene, target, n):
    x = parameter_value(scene, target)
    size = max(abs(x), 0.1)
    estimates = []
    for d in (FIRST_STEP * size, FIRST_STEP * size / 2, FIRST_STEP * size / 4):
        plus = _observed(with_parameters(scene, [target], [x + d]), n)
        minus = _observed(with_parameters(scene, [target], [x - d]), n)
        estimates.append(None if plus is None or minus is None else [(a - b) / (2 * d) for a, b in zip(plus, minus)])
    return [[(4 * f - c) / 3 for c, f in zip(coarse, fine)]
            for coarse, fine in zip(estimates, estimates[1:]) if coarse is not None and fine is not None]


def assert_matches(scene, wrt, n_events=None, finals=False):
    """Every differentiable event's time and position (the first ``n_events``), and with ``finals`` the
    final time, friction work and landing loss, against the step study."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = simulate(scene)
    sens = sensitivities(res, wrt=wrt)
    n = len(res.events) if n_events is None else n_events
    good = [i for i in range(n) if not sens.reasons[i]]
    for j, target in enumerate(resolve_wrt(scene, wrt)):
        study = _step_study(scene, target, len(res.events))
        assert study, f"{target}: every perturbed run changed its events"
        for which, column in enumerate((sens.t[:, j], sens.q[:, j])):
            floor = max(1e-4 * np.max(np.abs(column[good])), 1e-5)
            for i in good:
                err = min(abs(est[which][i] - column[i]) for est in study)
                assert err <= TOL * max(abs(column[i]), floor), (target, "tq"[which], i, res.events[i].kind,
                                                                 column[i], [est[which][i] for est in study])
        if finals:
            for k, name in enumerate(("t_final", "friction_work", "landing_loss")):
                value = sens.final[name][j]
                err = min(abs(est[2][k] - value) for est in study)
                assert err <= TOL * max(abs(value), 1e-5), (target, name, value, [est[2][k] for est in study])
    return res, sens


def test_bounces_after_a_lift_off_match_a_step_study_until_their_accumulation():
    scene = scene_from_dict(BOUNCES)
    res, sens = assert_matches(scene, ("mu", "qdot0", "R"))
    kinds = [e.kind for e in res.events]
    assert kinds[0] is EventKind.LIFT_OFF and kinds.count(EventKind.LANDING) >= 10
    landed = [i for i, e in enumerate(res.events) if e.kind is EventKind.LANDING and not sens.reasons[i]]
    assert len(landed) >= 10 and np.all(np.isfinite(sens.t[landed]))
    last = len(landed) + 1
    assert "accumulation" in res.events[last].detail and sens.reasons[last] == ACCUMULATION_REASON
    assert all(sens.reasons[last + 1:]) and np.all(np.isnan(sens.t[last:]))


def test_a_landing_that_slides_on_to_an_arrest_has_exact_final_derivatives():
    scene, name = random_scene(random.Random(SEED), 0)
    assert name == "circle"
    res, sens = assert_matches(scene, ("qdot0", "q0", "mu", "R"), finals=True)
    assert [e.kind for e in res.events[:2]] == [EventKind.LIFT_OFF, EventKind.LANDING]
    assert res.status.value == "arrested" and not any(sens.reasons)
    assert set(sens.final) == {"t_final", "q_final", "friction_work", "impact_loss", "landing_loss"}


def test_repeated_lift_offs_and_landings_on_a_user_curve_match_a_step_study():
    rng = random.Random(SEED)
    random_scene(rng, 0)
    scene, name = random_scene(rng, 1)
    assert name == "sine"
    res, sens = assert_matches(scene, ("qdot0", "a"), n_events=8)
    assert [e.kind for e in res.events[:4]] == [EventKind.LIFT_OFF, EventKind.LANDING] * 2


def test_a_bilateral_run_has_no_landing_loss_column():
    res = simulate("paper-parabola")
    assert "landing_loss" not in sensitivities(res, wrt="mu").final


# --- the landing against its closed form on a flat floor -----------------------------------------


class _Floor:
    """``z = 0``, ``q = x``: what :func:`land` reads of a curve, with the parameters ``(vx, vz)``."""

    g, m, scale = G, 1.0, 1.0
    Dmu = np.zeros(2)

    def x(self, q):
        return np.asarray(q, dtype=float)

    def z(self, q):
        return np.zeros_like(np.asarray(q, dtype=float))

    def dx(self, q):
        return np.ones_like(np.asarray(q, dtype=float))

    def dz(self, q):
        return np.zeros_like(np.asarray(q, dtype=float))

    def dalpha(self, q):
        return np.zeros_like(np.asarray(q, dtype=float))

    def geometry_dp(self, what, q):
        return np.zeros((1, 2))


def _flight(vx, vz):
    z2 = np.zeros(2)
    return Flight(0.0, z2, 0.0, 0.0, vx, vz, z2, z2, np.array([1.0, 0.0]), np.array([0.0, 1.0]))


class _Scene:
    def __init__(self, mu, e):
        self.mu, self.restitution_curve = mu, e


@pytest.mark.parametrize("vx, vz, mu, e", [(1.5, 2.0, 0.1, 0.5), (-0.7, 3.0, 0.3, 0.0), (0.2, 1.0, 0.5, 0.4)])
def test_a_landing_on_a_flat_floor_moves_as_its_closed_form(vx, vz, mu, e):
    tau = 2 * vz / G                                   # z = vz t - g t^2 / 2 = 0
    got = land(_Floor(), _Scene(mu, e), _flight(vx, vz), tau, vx * tau)
    np.testing.assert_allclose(got.Dt, [0.0, 2 / G], atol=1e-15)
    np.testing.assert_allclose(got.Dq, [tau, 2 * vx / G], rtol=1e-14)
    np.testing.assert_allclose(got.Dv_before, [1.0, 0.0], atol=1e-15)      # v_t = vx
    jn = (1 + e) * vz
    if abs(vx) <= mu * jn:                                                 # sticks: v' = 0 whatever moves
        np.testing.assert_array_equal(got.Dv_after, [0.0, 0.0])
        assert got.w == 0.0
    else:
        np.testing.assert_allclose(got.Dv_after, [1.0, -math.copysign(mu * (1 + e), vx)], rtol=1e-14)
    # a bounce leaves with (v', e vz): its velocity's tangents
    if e > 0:
        np.testing.assert_allclose(got.bounce.DVz, [0.0, e], rtol=1e-14)
        np.testing.assert_allclose(got.bounce.DVx, got.Dv_after, rtol=1e-14)
    else:
        assert got.bounce is None


def test_a_tangential_landing_and_the_stick_edge_have_no_derivative():
    grazing = _flight(1.0, 1e-10)
    assert land(_Floor(), _Scene(0.1, 0.5), grazing, 2e-10 / G, 2e-10 / G) == TANGENTIAL_LANDING_REASON
    vz, e = 2.0, 0.5
    mu = 1.0 / ((1 + e) * vz)                          # |v_t| = mu (1 + e) |u| exactly
    tau = 2 * vz / G
    assert land(_Floor(), _Scene(mu, e), _flight(1.0, vz), tau, tau) == STICK_EDGE_REASON


# --- positions at fixed times in flight (a tracked video of a ball) ---------------------------------


def test_positions_in_flight_move_as_a_step_study_of_the_parabola_says():
    from symvib.numeric.sample_sensitivity import sample_positions, sample_sensitivities

    scene = scene_from_dict(BOUNCES)
    res = simulate(scene)
    lift, land1, land2 = (e.t for e in res.events[:3])
    times = np.array([0.5 * (lift + land1), land1 + 0.3 * (land2 - land1), 0.2 * lift])   # in, in, before
    sens = sample_sensitivities(res, times, wrt=("mu", "qdot0", "R"), coordinates="xz")
    assert sens.reasons == ("", "", "")
    np.testing.assert_allclose(sens.values[:2], np.column_stack(res.dense.position(times[:2])[:2]), rtol=1e-14)
    for j, target in enumerate(resolve_wrt(scene, ("mu", "qdot0", "R"))):
        x = parameter_value(scene, target)
        estimates = []
        for d in (FIRST_STEP * max(abs(x), 0.1) / 2 ** m for m in range(3)):
            plus = sample_positions(simulate(with_parameters(scene, [target], [x + d])), times, "xz")
            minus = sample_positions(simulate(with_parameters(scene, [target], [x - d])), times, "xz")
            estimates.append((plus - minus) / (2 * d))
        rich = [(4 * f - c) / 3 for c, f in zip(estimates, estimates[1:])]
        got = sens.derivatives[:, :, j]
        err = min(np.max(np.abs(r - got)) for r in rich)
        assert err <= TOL * max(np.max(np.abs(got)), 1e-3), (target, got, rich)
    q_in_flight = sample_sensitivities(res, times[:1], wrt="mu", coordinates="q")
    assert np.isnan(q_in_flight.values[0, 0]) and "in flight" in q_in_flight.reasons[0]
