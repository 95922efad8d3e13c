"""Derivatives of a run's position at fixed times (symvib/numeric/sample_sensitivity.py).

Held against a Richardson step study of central differences of the engine's own dense output
(its state at the same times after a perturbed run), to 1e-7 relative, on the paper's parabola
and a user curve with two limiters, in ``q``, ``x, z`` and the arc length ``s``; samples away
from events (where ``q(t)`` has a kink, or a jump of acceleration, that a difference straddles).
"""
import math
import warnings

import numpy as np
import pytest

from symvib import simulate
from symvib.numeric.sample_sensitivity import arc_length, sample_positions, sample_sensitivities
from symvib.numeric.scene import resolve_scene, scene_from_dict

TOL = 1e-7
HALVINGS = 5
FIRST_STEP = 1e-4
#: Samples keep this fraction of their interval's duration away from its ends.
MARGIN = 0.1
BOWL = {"curve": {"name": "samples-bowl", "z": "R - sqrt(R**2 - x**2)", "domain": ["-R", "R"]},
        "parameters": {"R": 0.5}, "physics": {"alpha0": 0.05, "restitution": 0.8},
        "limiters": {"left": -0.2, "right": 0.35}, "initial": {"q": 0.1, "qdot": 3.0}}


def run(scene):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return simulate(scene)


def inner_times(result, per_interval=3, intervals=8):
    """Sample times inside the first motion intervals, ``MARGIN`` of each away from its ends."""
    ends = [0.0] + [e.t for e in result.events]
    out = []
    for a, b in list(zip(ends, ends[1:]))[:intervals]:
        if b - a > 1e-3:
            out += list(a + (b - a) * np.linspace(MARGIN, 1 - MARGIN, per_interval))
    return np.array(out)


def assert_matches_step_study(scene, times, wrt, coordinates):
    exact = sample_sensitivities(run(scene), times, wrt=wrt, coordinates=coordinates)
    assert not any(exact.reasons), exact.reasons
    for j, name in enumerate(wrt):
        x = getattr(scene, name)
        steps = [FIRST_STEP * max(abs(x), 0.1) / 2 ** i for i in range(HALVINGS + 1)]
        central = [(sample_positions(run(scene.replace(**{name: x + d})), times, coordinates)
                    - sample_positions(run(scene.replace(**{name: x - d})), times, coordinates)) / (2 * d)
                   for d in steps]
        study = [(4 * fine - coarse) / 3 for coarse, fine in zip(central, central[1:])]
        a = exact.derivatives[:, :, j]
        floor = max(1e-4 * float(np.max(np.abs(a))), 1e-5)
        err = np.min([np.abs(est - a) for est in study], axis=0)
        worst = np.unravel_index(np.argmax(err / np.maximum(np.abs(a), floor)), a.shape)
        assert np.all(err <= TOL * np.maximum(np.abs(a), floor)), (name, coordinates, worst, a[worst],
                                                                  [est[worst] for est in study])
    return exact


def test_the_paper_parabola_s_positions_at_fixed_times_match_a_step_study():
    scene = resolve_scene("paper-parabola").replace(k=0.8)
    times = inner_times(run(scene))
    assert len(times) >= 20
    assert_matches_step_study(scene, times, ("mu", "k", "qdot0", "q0", "left", "right"), "q")


@pytest.mark.parametrize("coordinates", ["q", "xz", "s"])
def test_a_user_curve_with_two_limiters_matches_a_step_study_in_every_coordinate(coordinates):
    scene = scene_from_dict(BOWL)
    times = inner_times(run(scene), per_interval=2, intervals=6)
    assert_matches_step_study(scene, times, ("mu", "k", "qdot0", "q0", "right"), coordinates)


def test_next_to_a_turning_point_the_derivative_stays_finite_and_tends_to_the_turning_point_s():
    # At fixed t the position moves as the turning point does, plus O(t - t*): no 1/qdot blow-up.
    scene = resolve_scene("paper-parabola").replace(k=0.8)
    res = run(scene)
    i = next(i for i, e in enumerate(res.events) if e.kind.value == "reversal")
    turn = res.events[i]
    at_turn = res.sensitivities(wrt=("mu", "k", "qdot0")).q[i]
    gaps = np.array([1e-3, 1e-5, 1e-7])
    for side in (-1, 1):
        D = sample_sensitivities(res, turn.t + side * gaps, wrt=("mu", "k", "qdot0")).derivatives[:, 0, :]
        assert np.all(np.isfinite(D))
        distance = np.max(np.abs(D - at_turn), axis=1)
        assert np.all(distance <= 1e3 * gaps * np.max(np.abs(at_turn))), (side, distance)
        assert distance[-1] < 1e-3 * distance[0]           # O(t - t*): 1e4 times closer, not 1e2


def test_after_the_arrest_the_position_s_derivative_is_the_arrest_s():
    res = run(resolve_scene("paper-parabola").replace(k=0.8))
    sens = res.sensitivities(wrt=("mu", "k"))
    D = sample_sensitivities(res, [res.t_final, res.t_final + 5.0], wrt=("mu", "k")).derivatives[:, 0, :]
    assert np.array_equal(D[1], sens.final["q_final"])
    assert np.allclose(D[0], sens.final["q_final"], rtol=1e-9)


def test_samples_after_a_zeno_accumulation_say_why_they_have_no_derivative():
    scene = scene_from_dict({"curve": {"shape": "parabola"}, "parameters": {"p": 1.0},
                             "physics": {"alpha0": 0.05, "restitution": 0.8}, "limiters": {"right": -0.3},
                             "initial": {"q": -0.6, "qdot": 0.5}})
    res = run(scene)
    sens = res.sensitivities(wrt=("mu",))
    first = next(i for i, why in enumerate(sens.reasons) if why)
    before = res.events[first - 1].t
    out = sample_sensitivities(res, [before / 2, res.t_final + 1.0], wrt=("mu",))
    assert out.reasons[0] == "" and np.isfinite(out.derivatives[0]).all()
    assert "Zeno" in out.reasons[1] and np.isnan(out.derivatives[1]).all()


def test_the_arc_length_is_the_samples_own_s_column():
    # The samples' s is the engine's cumulative quadrature of h dq from the start: independent.
    res = run(scene_from_dict(BOWL))
    samples = res.samples
    pick = slice(0, len(samples.t), max(1, len(samples.t) // 40))
    s = sample_positions(res, samples.t[pick], "s")[:, 0]
    assert np.allclose(s, samples.s[pick], rtol=1e-10, atol=1e-12)
    assert arc_length(np.cos, 0.0, math.pi / 2) == pytest.approx(1.0, rel=1e-14)


@pytest.mark.parametrize("t, match", [([float("nan")], "t: sample 1"), ([-0.1], "t: sample 1"),
                                      ([0.1, 1e9], "t: sample 2 .* time span")])
def test_a_time_outside_the_run_is_refused_naming_t(t, match):
    res = simulate(resolve_scene("paper-parabola").replace(t_max=1.0))      # stopped by t_max at 1 s
    assert res.status.value == "t_max"
    with pytest.raises(ValueError, match=match):
        sample_sensitivities(res, t, wrt=("mu",))


def test_unknown_coordinates_are_refused():
    with pytest.raises(ValueError, match="coordinates: 'y'"):
        sample_sensitivities(simulate("paper-parabola"), [0.1], coordinates="y")


@pytest.mark.parametrize("function", [sample_sensitivities, sample_positions])
@pytest.mark.parametrize("kwargs, match", [
    ({"coordinates": "y"}, "coordinates: 'y' is not one of q, xz, s"),        # sample_positions gave q's values
    ({"coordinates": ["q"]}, r"coordinates: \['q'\] is not one of"),
    ({"coordinates": None}, "coordinates: None is not one of"),
    ({"t": "abc"}, "t: sample times in seconds"),
    ({"t": [0.1, "x"]}, "t: sample times in seconds"),
    ({"t": [1j]}, "t: sample times in seconds"),
    ({"t": [float("nan")]}, "t: .*nan"),
    ({"t": [-5.0]}, "t: .*-5.0"),
    ({"result": None}, "result: a run of symvib.simulate, got NoneType"),
    ({"result": "paper-parabola"}, "result: a run of symvib.simulate, got str"),
])
def test_hostile_samples_requests_are_refused_naming_the_argument(function, kwargs, match):
    args = {"result": simulate(resolve_scene("paper-parabola").replace(t_max=1.0)), "t": [0.1],
            "coordinates": "q"} | kwargs
    with pytest.raises(ValueError, match=match):
        function(args.pop("result"), args.pop("t"), coordinates=args.pop("coordinates"))


def test_a_run_without_intervals_is_refused_naming_the_dense_output():
    res = simulate("paper-parabola", samples=False)
    for function in (sample_sensitivities, sample_positions):
        with pytest.raises(ValueError, match="dense output: this run kept no intervals"):
            function(res, [0.1])


def test_samples_inside_the_interval_a_run_stopped_in_say_why():
    res = simulate(resolve_scene("paper-parabola").replace(t_max=1.0))
    last = res.events[-1].t
    out = sample_sensitivities(res, [last / 2, (last + 1.0) / 2], wrt=("mu",))
    assert out.reasons[0] == "" and "status t_max" in out.reasons[1] and np.isnan(out.derivatives[1]).all()


def test_a_sample_at_an_impact_s_time_has_no_derivative_and_says_why():
    # q(t) has a kink there: the derivative at fixed time jumps from DL - v_before Dt to DL - v_after Dt.
    res = run(resolve_scene("paper-parabola").replace(k=0.8))
    impact = res.events[0]
    out = sample_sensitivities(res, [impact.t * (1 - 1e-6), impact.t, impact.t * (1 + 1e-6)], wrt=("mu", "k"))
    assert out.reasons[0] == "" and out.reasons[2] == ""
    assert "kink" in out.reasons[1] and np.isnan(out.derivatives[1]).all()
    assert not np.allclose(out.derivatives[0], out.derivatives[2], rtol=1e-2)     # the jump
