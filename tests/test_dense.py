"""Dense output (symvib/numeric/dense.py): the state at any time and at any position.

Checked against the run's own events and against an independent 30-digit
reference that integrates eq. 1 in time (symvib/checks/reference_time.py).
"""
import math
import zlib

import numpy as np
import pytest

from symvib import simulate
from symvib.checks.bench.scenes import paper_scenes
from symvib.checks.reference_time import time_reference_states
from symvib.numeric.scene import scene_from_dict

#: The issue's bar: the dense output agrees with the 30-digit reference to 1e-12.
TOL = 1e-12
PAPER = dict(paper_scenes())


def run(scene):
    return simulate(scene, backend="python")


def incline(k=0.8, t_max=1000.0):
    """Gravity pushes into the left limiter outside the friction cone: a Zeno accumulation for k > 0."""
    return scene_from_dict({"curve": {"z": "c*x"}, "parameters": {"c": 0.5},
                            "physics": {"g": 9.81, "mu": 0.1, "restitution": k},
                            "limiters": {"left": 0}, "initial": {"q": 1.0, "qdot": 0.0}, "run": {"t_max": t_max}})


def random_times(result, n, seed):
    """``n`` random times over the run and a little past its end, plus times just around each reversal."""
    rng = np.random.default_rng(seed)
    times = rng.uniform(0.0, result.t_final * 1.05, n)
    near = [e.t + d for e in result.events if e.kind.value == "reversal" for d in (-1e-6, 1e-7)][:4]
    return np.sort(np.concatenate((times, near)))


def assert_matches_reference(scene, times):
    result = run(scene)
    q, qdot = result.state(times)
    ref = time_reference_states(scene, list(times), dps=30)
    for t, a, b, r in zip(times, q, qdot, ref):
        assert r is not None
        assert abs(a - float(r[0])) < TOL and abs(b - float(r[1])) < TOL, (t, a - float(r[0]), b - float(r[1]))


@pytest.mark.parametrize("label", sorted(PAPER))
def test_state_at_each_event_is_the_events_state(label):
    result = run(PAPER[label])
    times = np.array([e.t for e in result.events])
    q, qdot = result.state(times)
    for e, a, b in zip(result.events, q, qdot):
        after = [x for x in result.events if x.t == e.t][-1]  # right-continuous: after every event at e.t
        assert abs(a - after.q) <= TOL * max(1.0, abs(after.q))
        assert abs(b - after.qdot_after) <= TOL * max(1.0, abs(after.qdot_after)), (e, b)
    # and one event at a time, as plain floats
    e = result.events[0]
    assert result.state(e.t) == pytest.approx((e.q, e.qdot_after), abs=TOL)


def test_agrees_with_the_30_digit_reference_at_random_times():
    scene = PAPER["paper-circle-3.8 k=1"]
    assert_matches_reference(scene, random_times(run(scene), 6, seed=17))


@pytest.mark.slow
@pytest.mark.parametrize("label", sorted(PAPER))
def test_agrees_with_the_30_digit_reference_on_every_paper_scene(label):
    scene = PAPER[label]
    assert_matches_reference(scene, random_times(run(scene), 10, seed=zlib.crc32(label.encode())))


@pytest.mark.slow
def test_agrees_with_the_reference_on_a_curve_without_closed_form():
    # The catenary's F_sigma has no closed form: the dense output never needs it (G is rebuilt from G').
    scene = scene_from_dict({"curve": {"shape": "catenary"}, "parameters": {"a": 1.0},
                             "physics": {"mu": 0.1, "restitution": 0.8}, "limiters": {"left": -0.5, "right": 0.6},
                             "initial": {"q": 0.0, "qdot": 3.0}})
    assert_matches_reference(scene, random_times(run(scene), 8, seed=3))


def test_at_position_inverts_state():
    result = run(PAPER["paper-parabola k=0.8"])
    dense = result.dense
    for i in range(dense.n_intervals):
        iv = {k: v[i] for k, v in dense.intervals.items()}
        qs = np.linspace(iv["q_start"], iv["q_end"], 7)
        t, qdot = result.at(qs, interval=i)
        assert np.all((t >= iv["t_start"] - 1e-15) & (t <= iv["t_end"] + 1e-15))
        assert np.all(np.diff(t) > 0)  # a motion interval is monotone in q
        q2, qdot2 = result.state(t[1:-1])  # the ends are events (right-continuous there)
        assert np.max(np.abs(q2 - qs[1:-1])) < TOL
        assert np.max(np.abs(qdot2 - qdot[1:-1])) < TOL
        assert np.all(np.sign(qdot[1:-1]) == iv["direction"])


def test_at_position_first_passage_and_outside():
    result = run(PAPER["paper-parabola k=1"])
    e = result.events[0]  # the first impact, at the right limiter
    t, qdot = result.at(e.q)
    assert t == pytest.approx(e.t, abs=TOL) and qdot == pytest.approx(e.qdot_before, abs=TOL)
    t, qdot = result.at(np.array([2.0, result.scene.q0]))  # beyond the limiters: never reached
    assert math.isnan(t[0]) and math.isnan(qdot[0])
    assert t[1] == 0.0 and qdot[1] == pytest.approx(result.scene.qdot0, abs=TOL)
    with pytest.raises(ValueError, match="interval"):
        result.at(0.1, interval=10**6)


def test_shapes_and_solve_ivp_style_call():
    result = run(PAPER["paper-cycloid k=1"])
    grid = np.linspace(0.0, result.t_final, 12).reshape(3, 4)
    q, qdot = result.state(grid)
    assert q.shape == qdot.shape == (3, 4)
    y = result.sol(grid.ravel())
    assert y.shape == (2, 12) and np.array_equal(y[0], q.ravel()) and np.array_equal(y[1], qdot.ravel())
    assert result.sol(0.5).shape == (2,)
    assert result.sol(0.0) == pytest.approx([result.scene.q0, result.scene.qdot0], abs=TOL)


def test_after_arrest_the_particle_stays_and_outside_the_span_is_an_error():
    result = run(PAPER["paper-circle-7 k=0.8"])
    assert result.status.value == "arrested"
    q, qdot = result.state([result.t_final, result.t_final + 100.0])
    assert np.all(q == result.q_final) and np.all(qdot == 0.0)
    with pytest.raises(ValueError, match=r"^t: "):
        result.state(-1.0)
    with pytest.raises(ValueError, match=r"^t: "):
        result.state(math.nan)
    bounded = run(PAPER["paper-circle-7 k=1"].replace(t_max=0.5))
    assert bounded.status.value == "t_max"
    assert bounded.state(0.5) == (bounded.q_final, bounded.qdot_final)
    with pytest.raises(ValueError, match=r"t: the state is defined on \[0, 0.5\]"):
        bounded.state(0.6)


def test_zeno_tail_is_the_limiter_at_rest():
    result = run(incline(0.8))
    assert result.zeno is not None
    last = result.dense.intervals["t_end"][-1]
    assert last < result.t_final
    q, qdot = result.state(0.5 * (last + result.t_final))
    assert (q, qdot) == (0.0, 0.0)  # the left limiter, at rest


def test_a_run_without_intervals_says_how_to_get_them():
    result = simulate(PAPER["paper-cycloid k=1"], samples=False, backend="python")
    with pytest.raises(ValueError, match="samples=True"):
        result.state(0.1)
