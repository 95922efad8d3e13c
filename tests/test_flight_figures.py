"""Figures and animation of a run with flights (docs/physics.md, "Flight and landing", Samples, dense
output and figures): the sketch draws each flight's arc (its line's data are the flight's samples)
and marks lift-offs and landings on the curve; the animation moves the particle along the
parabola, off the curve; every other figure draws a run with flights without failing.
"""
import math

import numpy as np
import pytest
from flight_reference import CURVES
from matplotlib.figure import Figure
from PIL import Image

from symvib import simulate
from symvib.numeric import figures
from symvib.numeric.animation import animate, positions, states
from symvib.numeric.events import EventKind
from symvib.numeric.scene import scene_from_dict

G = 9.81


@pytest.fixture(scope="module")
def bounce():
    """The paper's circle run fast: it lifts off, bounces with e = 0.5 (summed at last), slides, arrests."""
    scene = scene_from_dict({"name": "circle-bounce", "curve": {"shape": "circle"}, "parameters": {"R": 0.5},
                             "physics": {"g": G, "mu": 0.05, "restitution": 1.0, "contact": "unilateral",
                                         "restitution_curve": 0.5}, "initial": {"q": 0.0, "qdot": 8.0}})
    r = simulate(scene, backend="python")
    assert r.count(EventKind.LIFT_OFF) == 1 and r.samples.flight.max() > 3
    return r


def _lines(ax):
    return [(line.get_label(), np.asarray(line.get_xdata(), dtype=float), np.asarray(line.get_ydata(), dtype=float))
            for line in ax.get_lines()]


def test_the_sketch_draws_each_flight_arc_and_marks_lift_offs_and_landings(bounce):
    S = bounce.samples
    ax = Figure().subplots()
    figures.scene_sketch(bounce, ax)
    dashed = [line for line in ax.get_lines() if line.get_color() == figures.FLIGHT_STYLE["color"]]
    n = int(S.flight.max()) + 1
    assert len(dashed) == n
    for k, line in enumerate(dashed):
        assert np.array_equal(line.get_xdata(), S.x[S.flight == k]) and np.array_equal(line.get_ydata(),
                                                                                       S.z[S.flight == k])
    # the first arc is the parabola from the lift-off, off the curve (inside the circle) in between
    R = 0.5
    x, z = S.x[S.flight == 0], S.z[S.flight == 0]
    inside = R - np.hypot(x, z - R)
    assert inside[len(x) // 2] > 0.05 and abs(inside[0]) < 1e-12 and abs(inside[-1]) < 1e-9
    marks = {label: (xs, zs) for label, xs, zs in _lines(ax)}
    lift = [e for e in bounce.events if e.kind is EventKind.LIFT_OFF]
    land = [e for e in bounce.events if e.kind is EventKind.LANDING]
    xs, zs = marks[f"lift-off ({len(lift)})"]
    assert np.allclose(xs, [R * math.sin(e.q) for e in lift]) and np.allclose(zs, [R * (1 - math.cos(e.q))
                                                                                 for e in lift])
    xs, _ = marks[f"landing ({len(land)})"]
    assert np.allclose(xs, [R * math.sin(e.q) for e in land])
    labels = ax.get_legend_handles_labels()[1]
    assert "flight (parabola)" in labels


def test_every_figure_draws_a_run_with_flights(bounce, tmp_path):
    out = figures.run_figures(bounce)
    assert [name for name, _, _ in out] == list(figures.FIGURE_NAMES)
    for name, fig, caption in out:
        ax = fig.axes[0]
        assert ax.get_title() and ax.get_xlabel() and caption, name
    energy = dict((n, f) for n, f, _ in out)["energy-time"].axes[0]
    assert "landing losses $W_l$" in energy.get_legend_handles_labels()[1]
    caps = {n: c for n, _, c in out}
    assert "landing losses W_l" in caps["energy-time"] and "flights" in caps["sketch"]
    # the phase portrait draws the sliding only: every line's q is finite (in flight there is none)
    phase = dict((n, f) for n, f, _ in out)["phase"].axes[0]
    for label, xs, _ in _lines(phase):
        assert np.isfinite(xs).all(), label
    paths = figures.save_run_figures(bounce, tmp_path)
    assert len(paths) == len(figures.FIGURE_NAMES) and all(p.stat().st_size > 10_000 for p in paths)


def test_animation_states_in_flight_lie_on_the_parabola_off_the_curve(bounce):
    lift = next(e for e in bounce.events if e.kind is EventKind.LIFT_OFF)
    land = next(e for e in bounce.events if e.kind is EventKind.LANDING)
    t = np.linspace(lift.t, land.t, 41)[1:-1]
    x, z = positions(bounce, t)
    R, v = 0.5, lift.qdot_after * 0.5
    x0, z0 = R * math.sin(lift.q), R * (1 - math.cos(lift.q))
    vx, vz = v * math.cos(lift.q), v * math.sin(lift.q)
    tau = t - lift.t
    assert np.allclose(x, x0 + vx * tau, atol=1e-12) and np.allclose(z, z0 + vz * tau - G * tau ** 2 / 2, atol=1e-12)
    assert (CURVES["circle"].side(x, z, {"R": R}) > 1e-6).all()   # off the curve, inside the circle
    q, _ = states(bounce, t)
    assert np.isnan(q).all()
    # on the curve before the lift-off: the kernels' point of q(t)
    before = np.linspace(0.0, lift.t, 7)[:-1]
    x, z = positions(bounce, before)
    q, _ = states(bounce, before)
    assert np.allclose(x, R * np.sin(q), atol=1e-12) and np.allclose(z, R * (1 - np.cos(q)), atol=1e-12)


def test_the_animation_of_a_run_with_flights_is_written(bounce, tmp_path):
    path = animate(bounce, tmp_path / "flight.gif", fps=10, duration=1.0)
    with Image.open(path) as im:
        assert im.n_frames == 10


def test_a_run_stopped_in_flight_marks_where_it_stopped():
    scene = scene_from_dict({"name": "crossed", "curve": {"shape": "circle"}, "parameters": {"R": 0.5},
                             "physics": {"g": G, "mu": 0.0, "restitution": 1.0, "contact": "unilateral"},
                             "limiters": {"left": -0.3, "right": 3.0}, "initial": {"q": 0.0, "qdot": 8.5}})
    r = simulate(scene, backend="python")
    ax = Figure().subplots()
    figures.scene_sketch(r, ax)
    marks = {label: (xs, zs) for label, xs, zs in _lines(ax)}
    xs, zs = marks["end in flight (crossed_limiter)"]
    x, z, _, _ = r.dense.position(r.t_final)
    assert xs[0] == pytest.approx(x, abs=1e-12) and zs[0] == pytest.approx(z, abs=1e-12)
