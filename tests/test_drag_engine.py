"""Air drag in the engine (physics.md, "Air drag"; symvib.numeric.drag_run, symvib.numeric.drag_phase).

Event kinds, times and positions on the paper's scenes with a drag coefficient that matters
(``gamma = c / m`` of 0.1 to 1 per metre) against an independent 30-digit time integration of
eq. 1 with drag (tests/drag_reference.py, written from physics.md), the energy budget with its
drag work, a drag of 0 that leaves every run as it was, and the field's checks.
"""
import json
import math

import numpy as np
import pytest
from drag_reference import reference_events

import symvib
from symvib.numeric.drag_run import NO_DENSE, ZENO_DRAG
from symvib.numeric.scene import SceneError, load_scene, packaged_scene, scene_from_dict

#: Agreement asked of event times (s) against the reference, and of positions (in q).
T_AGREE, Q_AGREE = 1e-9, 1e-9
#: Energy budget closure asked of a drag run, relative to E0.
BUDGET_AGREE = 1e-12
PAPER = ("paper-parabola", "paper-cycloid", "paper-circle-7")


def _compare(result, reference):
    assert [e.kind.value for e in result.events[:len(reference)]] == [k for k, _, _ in reference]
    for e, (_, t, q) in zip(result.events, reference):
        assert abs(e.t - float(t)) <= T_AGREE, (e, float(t))
        assert abs(e.q - float(q)) <= Q_AGREE, (e, float(q))


def test_first_events_of_the_circle_with_drag_against_a_30_digit_integration():
    scene = packaged_scene("paper-circle-7").replace(drag=0.1)   # gamma = 0.5 / m
    result = symvib.simulate(scene)
    reference = reference_events(scene, 3)
    _compare(result, reference)
    # the comparison sees the drag: without it the second event is elsewhere
    plain = symvib.simulate(packaged_scene("paper-circle-7"))
    assert abs(plain.events[1].t - float(reference[1][1])) > 1e-3


@pytest.mark.slow
@pytest.mark.parametrize("name", PAPER)
@pytest.mark.parametrize("k", [1.0, 0.8])
@pytest.mark.parametrize("drag", [0.02, 0.1])
def test_paper_scenes_with_drag_against_a_30_digit_integration(name, k, drag):
    scene = packaged_scene(name).replace(drag=drag, k=k)
    result = symvib.simulate(scene)
    assert result.success and result.zeno is None
    reference = reference_events(scene, len(result.events))
    assert len(reference) == len(result.events)
    _compare(result, reference)
    assert (result.status.value == "arrested") == (reference[-1][0] == "arrest")


@pytest.mark.slow
@pytest.mark.parametrize("contact, kind", [("bilateral", "normal_sign_change"), ("unilateral", "left_curve")])
def test_normal_force_zero_with_drag_against_a_30_digit_integration(contact, kind):
    """The circle run fast above its horizontal diameter: N changes sign (a bead: the branch flips),
    or a particle inside the loop leaves it, with drag."""
    scene = scene_from_dict({"curve": {"shape": "circle"}, "parameters": {"R": 0.5},
                             "physics": {"mu": 0.05, "restitution": 0.8, "drag": 0.05, "m": 0.2,
                                         "contact": contact},
                             "limiters": {"right": 2.5}, "initial": {"q": 0.0, "qdot": 9.0}})
    result = symvib.simulate(scene)
    assert kind in [e.kind.value for e in result.events]
    n = [e.kind.value for e in result.events].index(kind) + 1
    _compare(result, reference_events(scene, n))


@pytest.mark.parametrize("name", PAPER)
@pytest.mark.parametrize("k", [1.0, 0.8])
def test_energy_budget_with_drag_closes(name, k):
    scene = packaged_scene(name).replace(drag=0.1, k=k)
    result = symvib.simulate(scene, samples=False)
    b = result.energy_budget
    assert result.success and b.drag_work > 0.01 * b.initial   # the drag takes a visible share
    assert abs(b.initial - b.final - b.friction_work - b.impact_loss - b.drag_work) <= BUDGET_AGREE * b.initial
    assert abs(b.residual) <= BUDGET_AGREE * b.initial
    data = json.loads(result.to_json())
    assert data["energy_budget"]["drag_work"] == b.drag_work and data["units"]["energy_budget"]["drag_work"] == "J"
    assert "drag work" in result.event_table()


def test_a_budget_that_misses_its_drag_work_does_not_close():
    """The check can fail: the drag work is a term of its own, not absorbed elsewhere."""
    result = symvib.simulate(packaged_scene("paper-cycloid").replace(drag=0.1), samples=False)
    b = result.energy_budget
    assert abs(b.initial - b.final - b.friction_work - b.impact_loss) > 1e3 * BUDGET_AGREE * b.initial


@pytest.mark.parametrize("name", PAPER)
def test_a_vanishing_drag_runs_as_the_engine(name):
    """The drag path is code of its own: at c = 1e-13 kg/m its events are the engine's without drag."""
    plain = symvib.simulate(packaged_scene(name), samples=False)
    tiny = symvib.simulate(packaged_scene(name).replace(drag=1e-13), samples=False)
    assert tiny.stats["drag"] and "drag" not in plain.stats
    assert [e.kind for e in tiny.events] == [e.kind for e in plain.events]
    for a, b in zip(tiny.events, plain.events):
        assert abs(a.t - b.t) <= 1e-10 and abs(a.q - b.q) <= 1e-10
    assert tiny.status == plain.status


@pytest.mark.parametrize("backend", ["python", "auto"])
def test_zero_drag_is_the_engine_bit_for_bit(backend):
    scene = packaged_scene("paper-parabola")
    given = scene_from_dict({**scene.to_dict(), "physics": {**scene.to_dict()["physics"], "drag": 0}})
    assert given == scene and given.drag == 0.0 and "drag" not in scene.to_dict()["physics"]
    a, b = symvib.simulate(scene, backend=backend), symvib.simulate(given.replace(drag=0.0), backend=backend)
    assert a.events == b.events and a.energy_budget == b.energy_budget and a.energy_budget.drag_work is None
    assert a.to_json() == b.to_json() and "drag" not in a.to_json()
    assert repr(a.energy_budget).count("drag") == 0


def test_drag_runs_on_every_backend_and_sweeps_refuse_it():
    scene = packaged_scene("paper-cycloid").replace(drag=0.05)
    a, b = symvib.simulate(scene, backend="python"), symvib.simulate(scene, backend="numba")
    assert a.events == b.events and b.stats["backend"] == "python" and "drag" in b.stats["drag"]
    with pytest.raises(SceneError, match="physics.drag: .*sweeps do not run scenes with air drag"):
        symvib.sweep(scene, {"qdot": "3:12:2"}, backend="python")
    with pytest.raises(ValueError, match="backend"):
        symvib.simulate(scene, backend="fortran")


def test_a_drag_run_says_it_has_no_dense_output_or_sensitivities():
    result = symvib.simulate(packaged_scene("paper-cycloid").replace(drag=0.05))
    with pytest.raises(ValueError, match="dense output: the dense output .* is not computed for a run with air drag"):
        result.state(0.1)
    assert NO_DENSE in str(pytest.raises(ValueError, result.at, 0.0).value)
    with pytest.raises(ValueError, match="air drag"):
        result.sensitivities(("mu",))


@pytest.mark.parametrize("name", PAPER)
def test_samples_of_a_drag_run_carry_the_drag_work_and_close_the_budget(name):
    result = symvib.simulate(packaged_scene(name).replace(drag=0.1, k=0.8))
    S, b = result.samples, result.energy_budget
    assert result.error is None and len(S.t) > 100 and bool(np.all(np.diff(S.t) >= 0))
    assert np.abs(S.E + S.W_mu + S.W_impacts + S.W_drag - b.initial).max() <= BUDGET_AGREE * b.initial
    assert S.W_drag[-1] == pytest.approx(b.drag_work, rel=1e-13) and S.W_mu[-1] == pytest.approx(b.friction_work,
                                                                                                   rel=1e-13)
    # each interval ends at its event, and passes it to the next at the same time
    for i, e in enumerate(e for e in result.events if e.kind.value != "arrest"):
        assert S.t[S.interval == i][-1] == pytest.approx(e.t, abs=1e-15) and S.q[S.interval == i][-1] == e.q
    # the speed's sign is the direction of motion, and the arc length follows q (here h > 0)
    assert np.all(np.sign(S.v[S.qdot != 0]) == np.sign(S.qdot[S.qdot != 0]))
    assert bool(np.all(np.diff(S.s)[np.diff(S.q) > 0] >= 0)) and bool(np.all(np.diff(S.s)[np.diff(S.q) < 0] <= 0))
    frame = result.samples_frame()
    assert frame.attrs["units"]["W_drag"] == "J" and "W_drag" in json.loads(result.to_json(samples=True))["samples"]


def test_the_energy_figure_of_a_drag_run_stacks_the_drag_work():
    from symvib.numeric.figures import run_figures

    result = symvib.simulate(packaged_scene("paper-cycloid").replace(drag=0.1))
    [(name, fig, text)] = run_figures(result, only=("energy-time",))
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert "drag work $W_d$" in labels and "drag work W_d" in text
    [(_, plain, plain_text)] = run_figures(symvib.simulate(packaged_scene("paper-cycloid")), only=("energy-time",))
    assert not any("drag" in t.get_text() for t in plain.axes[0].get_legend().get_texts())
    assert "drag" not in plain_text


def test_t_max_inside_an_interval_with_drag():
    scene = packaged_scene("paper-circle-7").replace(drag=0.1)
    full = symvib.simulate(scene, samples=False)
    t_max = 0.5 * (full.events[1].t + full.events[2].t)
    cut = symvib.simulate(scene.replace(t_max=t_max), samples=False)
    assert cut.status.value == "t_max" and cut.t_final == t_max and cut.events == full.events[:2]
    assert full.events[1].q < cut.q_final < full.events[2].q or full.events[2].q < cut.q_final < full.events[1].q
    assert cut.energy_budget.relative_residual <= BUDGET_AGREE


def test_zeno_accumulation_with_drag_is_summed_with_its_bound_stated():
    """Bounces against a limiter that gravity pushes the particle into: summed once the drag's share
    of a bounce is below ZENO_DRAG, with the drag-free local model (physics.md, "Air drag")."""
    scene = scene_from_dict({"curve": {"shape": "circle"}, "parameters": {"R": 0.5},
                             "physics": {"mu": 0.05, "restitution": 0.5, "drag": 0.1, "m": 0.2},
                             "limiters": {"left": 0.3}, "initial": {"q": 0.9, "qdot": 0.0}})
    result = symvib.simulate(scene, samples=False)
    assert result.status.value == "resting_on_limiter" and result.zeno is not None
    assert "drag-free local model" in result.events[-1].detail
    assert result.energy_budget.relative_residual <= BUDGET_AGREE
    # the series: ratio and time of the drag-free local model at the limiter (circle: alpha = q, h = R)
    g, mu, k, R, q = 9.81, 0.05, 0.5, 0.5, 0.3
    a_up, a_down = g * (math.sin(q) + mu * math.cos(q)), g * (math.sin(q) - mu * math.cos(q))
    ratio = k * math.sqrt(a_down / a_up)
    assert result.zeno.ratio == pytest.approx(ratio, rel=1e-12)
    last = [e for e in result.events if e.kind.value == "impact"][-1]
    v = abs(last.qdot_after) * R
    remaining = v * (1 / a_up + 1 / math.sqrt(a_up * a_down)) / (1 - ratio)
    assert result.t_final - last.t == pytest.approx(remaining, rel=1e-9) == result.zeno.remaining_time
    # summed only once the drag's share of a bounce (gamma times its length) is below the bound
    assert (0.1 / 0.2) * v ** 2 / (2 * a_up) <= ZENO_DRAG


@pytest.mark.parametrize("value, match", [
    (float("nan"), "physics.drag: must be finite, got nan"),
    (-0.1, "physics.drag: the drag coefficient c .* must be >= 0, got -0.1"),
    (float("inf"), "physics.drag: must be finite"),
    ("0.1", "physics.drag: must be a number"),
    (True, "physics.drag: must be a number"),
    (None, "physics.drag: must be a number"),
])
def test_replace_refuses_a_bad_drag_naming_the_field(value, match):
    with pytest.raises(SceneError, match=match):
        packaged_scene("paper-parabola").replace(drag=value)


@pytest.mark.parametrize("text, match", [
    ('"nan"', "physics.drag"), ("-0.5", "physics.drag: the drag coefficient"), ('"abc"', "physics.drag"),
    ('"0.1 kg"', "physics.drag"), ("inf", "physics.drag"), ("[1, 2]", "physics.drag"), ("true", "physics.drag"),
    ('"1e400"', "physics.drag"), ('"__import__(\'os\')"', "physics.drag"),
])
def test_a_hostile_drag_in_a_scene_file_names_the_field(tmp_path, text, match):
    path = tmp_path / "scene.toml"
    path.write_text('[curve]\nshape = "circle"\n[parameters]\nR = 0.5\n'
                    f'[physics]\nmu = 0.05\nrestitution = 1\ndrag = {text}\n[initial]\nq = 0\nqdot = 3\n')
    with pytest.raises(SceneError, match=match):
        load_scene(path)


def test_a_scene_file_reads_the_drag_and_the_scene_round_trips(tmp_path):
    path = tmp_path / "scene.toml"
    path.write_text('[curve]\nshape = "circle"\n[parameters]\nR = 0.5\n'
                    '[physics]\nmu = 0.05\nrestitution = 1\nm = 0.2\ndrag = "0.02 kg/m"\n'
                    '[initial]\nq = 0\nqdot = 3\n')
    scene = load_scene(path)
    assert scene.drag == 0.02 and scene.to_dict()["physics"]["drag"] == 0.02
    assert scene_from_dict(scene.to_dict()) == scene and scene.replace(drag=0.0) != scene
    result = symvib.simulate(scene, samples=False)
    assert result.to_dict()["units"]["scene"]["physics.drag"] == "kg/m"


@pytest.mark.parametrize("qdot", [1e200, 1e160])
def test_an_overflowing_drag_run_ends_non_finite(qdot):
    result = symvib.simulate(packaged_scene("paper-circle-7").replace(drag=0.1, qdot0=qdot))
    assert result.status.value == "non_finite" and not result.success


def test_a_user_curve_runs_with_drag_and_closes_its_budget():
    scene = scene_from_dict({"curve": {"name": "bowl", "z": "R - sqrt(R**2 - x**2)", "domain": ["-R", "R"]},
                             "parameters": {"R": 0.5}, "physics": {"alpha0": 0.05, "restitution": 0.8, "drag": 0.05},
                             "limiters": {"left": -0.2, "right": 0.35}, "initial": {"q": 0.1, "qdot": 3.0}})
    result = symvib.simulate(scene)
    assert result.success and result.status.value == "arrested"
    assert result.energy_budget.relative_residual <= BUDGET_AGREE and result.energy_budget.drag_work > 0
