"""The animation (symvib.numeric.animation, ``symvib run --animate``) and the explorer's drawing.

The GIF is opened with Pillow and its frame count compared with ``round(fps * duration)``;
the interpolated state is exact at the events; bad paths and formats are refused before
anything is simulated; the example of docs/derivations.md, "Notebooks and animation", runs.
"""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from readme_blocks import DOCS, run_section

from symvib import simulate
from symvib.numeric import animation, explorer
from symvib.numeric.events import EventKind
from symvib.numeric.scene import load_scene, scene_from_dict
from symvib.paths import UserPathError

ROOT = Path(__file__).resolve().parents[1]
SCENE_FILE = ROOT / "symvib" / "scenes" / "paper-circle-3.8.toml"


def _scene():
    return scene_from_dict({"curve": {"shape": "parabola"}, "parameters": {"p": 1},
                            "physics": {"alpha0": 0.05, "restitution": 0.8},
                            "limiters": {"left": "-pi/6", "right": "pi/4"}, "initial": {"q": 0, "qdot": 7}})


@pytest.fixture(scope="module")
def result():
    return simulate(_scene(), backend="python")


def test_gif_has_the_expected_frames(result, tmp_path):
    fps, duration = 10, 1.2   # a GIF stores frame durations in hundredths of a second
    out = animation.animate(result, tmp_path / "run.gif", fps=fps, duration=duration)
    assert out == tmp_path / "run.gif" and out.stat().st_size > 0
    with Image.open(out) as gif:
        assert gif.format == "GIF"
        assert gif.n_frames == round(fps * duration)     # no frame dropped or merged
        assert gif.info["duration"] == round(1000 / fps)
        assert gif.size == (round(animation.FIGSIZE[0] * animation.DPI), round(animation.FIGSIZE[1] * animation.DPI))
        first = np.asarray(gif.convert("RGB"))
        gif.seek(gif.n_frames - 1)
        assert np.any(np.asarray(gif.convert("RGB")) != first)


def test_frame_times_span_the_run(result):
    times = animation.frame_times(result, fps=10, duration=2.0)
    assert len(times) == 20 and times[0] == 0.0 and times[-1] == result.t_final
    assert np.all(np.diff(times) > 0)
    lo, hi = animation.DEFAULT_DURATION_RANGE
    assert len(animation.frame_times(result)) == round(animation.DEFAULT_FPS * min(max(result.t_final, lo), hi))
    for kwargs, field in (({"fps": 0}, "fps"), ({"fps": "10"}, "fps"), ({"duration": -1.0}, "duration"),
                          ({"duration": float("nan")}, "duration"), ({"fps": 60, "duration": 60.0}, "duration")):
        with pytest.raises(ValueError, match=f"^{field}: "):
            animation.frame_times(result, **kwargs)


def test_states_are_exact_at_the_events_and_hold_the_final_state(result):
    times = np.array([e.t for e in result.events])
    q, qdot = animation.states(result, times)
    assert np.allclose(q, [e.q for e in result.events], rtol=0, atol=1e-12)
    after = [e.qdot_after for e in result.events]
    assert np.allclose(qdot[:-1], after[:-1], rtol=0, atol=1e-9)   # an impact time belongs to the rebound
    q_end, qdot_end = animation.states(result, [result.t_final + 1.0])
    assert q_end[0] == result.q_final and qdot_end[0] == result.qdot_final


def test_states_interpolate_between_the_nodes(result):
    """Hermite interpolation on every other node reproduces the nodes left out (a smooth motion)."""
    S = result.samples

    class Thinned:
        pass

    keep = np.ones(len(S.t), dtype=bool)
    inner = np.arange(len(S.t))
    keep[(inner % 2 == 1) & (np.r_[S.interval[1:] == S.interval[:-1], False])
         & (np.r_[False, S.interval[:-1] == S.interval[1:]])] = False
    thinned = Thinned()
    thinned.samples = type(S)(*(getattr(S, f)[keep].copy() for f in S.__dataclass_fields__))
    thinned.t_final, thinned.q_final, thinned.qdot_final = result.t_final, result.q_final, result.qdot_final
    q, qdot = animation.states(thinned, S.t[~keep])
    scale = np.ptp(S.q)
    assert np.max(np.abs(q - S.q[~keep])) < 1e-3 * scale
    assert np.max(np.abs(qdot - S.qdot[~keep])) < 2e-2 * np.ptp(S.qdot)


def test_bad_paths_and_formats_are_refused(result, tmp_path):
    with pytest.raises(ValueError, match=r"suffix must be one of \.gif"):
        animation.animate(result, tmp_path / "run.avi")
    with pytest.raises(UserPathError, match="is a directory"):
        animation.animate(result, tmp_path)
    with pytest.raises(UserPathError, match="does not exist"):
        animation.animate(result, tmp_path / "missing" / "run.gif")
    assert not list(tmp_path.iterdir())


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "symvib.cli", *map(str, args)], capture_output=True, text=True,
                          cwd=ROOT, env={"SYMVIB_BACKEND": "python", "PATH": "/usr/bin:/bin",
                                         "HOME": str(Path.home())})


def test_symvib_run_animate(tmp_path):
    out = _cli("run", SCENE_FILE, "--animate", tmp_path / "circle.gif")
    assert out.returncode == 0, out.stderr
    assert f"wrote {tmp_path / 'circle.gif'}" in out.stdout
    result = simulate(load_scene(SCENE_FILE), samples=False)
    lo, hi = animation.DEFAULT_DURATION_RANGE
    with Image.open(tmp_path / "circle.gif") as gif:
        assert gif.n_frames == round(animation.DEFAULT_FPS * min(max(result.t_final, lo), hi))


@pytest.mark.parametrize("target, message", [("run.avi", "suffix must be one of"), (".", "is a directory"),
                                             ("nowhere/run.gif", "does not exist")])
def test_symvib_run_animate_refuses_bad_paths(tmp_path, target, message):
    out = _cli("run", SCENE_FILE, "--animate", tmp_path / target)
    assert out.returncode == 2 and message in out.stderr and "--animate file" in out.stderr
    assert out.stderr.count("\n") == 1 and "event" not in out.stdout   # refused before the run


def test_docs_animation_example_runs(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    namespace = run_section("## Notebooks and animation", "docs_animation", DOCS / "derivations.md")
    with Image.open(tmp_path / "circle.gif") as gif:
        assert gif.n_frames == round(namespace["fps"] * namespace["duration"])
    assert namespace["result"].count(EventKind.IMPACT) >= 1
    assert "tg(alpha0)" in namespace["eq8"].text
    assert len(namespace["agree"]) == 4 and all(namespace["agree"].values())   # Kane = derive, every branch


# --- the explorer -------------------------------------------------------------------------------
def test_explore_runs_the_changed_scene_and_draws_it():
    scene = _scene()
    result, fig = explorer.explore(scene, mu=0.2, k=0.5, qdot0=-4.0)
    assert (result.scene.mu, result.scene.k, result.scene.qdot0) == (0.2, 0.5, -4.0)
    assert result.events == simulate(scene.replace(mu=0.2, k=0.5, qdot0=-4.0)).events
    assert len(fig.axes) == 2 and fig.axes[0].lines
    again, same = explorer.explore(scene, right=0.5, fig=fig)   # redraws into the same figure
    assert same is fig and len(fig.axes) == 2 and again.scene.right == 0.5


def test_explore_shows_an_invalid_scene_instead_of_raising():
    result, fig = explorer.explore(_scene(), k=1.5)
    assert result is None and "physics.restitution" in fig.texts[0].get_text()


def test_slider_ranges_hold_the_scene_values():
    scene = _scene()
    ranges = explorer.slider_ranges(scene)
    assert set(ranges) == {"mu", "k", "qdot0", "left", "right"}
    for name, (lo, hi, step, value) in ranges.items():
        assert lo <= value <= hi and 0 < step < hi - lo, name
    assert ranges["left"][1] < scene.q0 < ranges["right"][0]      # a limiter never crosses the start
    with pytest.raises(ValueError, match="^g: the explorer varies"):
        explorer.changed_scene(scene, g=3.0)


def test_phase_grid_draws_one_panel_per_value():
    fig = explorer.phase_grid(_scene(), "mu", [0.02, 0.1, 0.3])
    assert len(fig.axes) == 3 and all("mu = " in ax.get_title() for ax in fig.axes)
    with pytest.raises(ValueError, match="^field: "):
        explorer.phase_grid(_scene(), "g", [1.0])
