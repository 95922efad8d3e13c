"""Runs that end at once draw every figure (issue 29, item 10).

A start at rest inside the friction cone, at the bottom, against a limiter or at the top
of a circle ends with no motion and no samples; ``symvib run --plot`` raised IndexError in
``figures.force_diagram``.
"""
from __future__ import annotations

import math
import warnings

import matplotlib
import pytest

matplotlib.use("Agg")

from symvib import simulate
from symvib.cli import main
from symvib.numeric.figures import FIGURE_NAMES, run_figures
from symvib.numeric.scene import scene_from_dict

PARABOLA = ({"shape": "parabola"}, {"p": 1.0})
CIRCLE = ({"shape": "circle"}, {"R": 0.5})

#: name -> (curve, parameters, mu, limiters, q0, qdot0, run bounds)
STILL = {
    "rest-in-cone": (*PARABOLA, 0.3, {}, 0.01, 0.0, {}),
    "bottom": (*PARABOLA, 0.1, {}, 0.0, 0.0, {}),
    "bottom-frictionless": (*PARABOLA, 0.0, {}, 0.0, 0.0, {}),
    "on-limiter": (*PARABOLA, 0.01, {"left": 0.3}, 0.3, 0.0, {}),
    "top-of-circle": (*CIRCLE, 0.1, {}, math.pi, 0.0, {}),
    "tiny-t_max": (*PARABOLA, 0.1, {}, 0.2, 1.0, {"t_max": 1e-300}),
    "one-event": (*PARABOLA, 0.1, {"left": -0.5, "right": 0.5}, 0.2, 5.0, {"max_events": 1}),
}


def _scene(name):
    curve, params, mu, limiters, q0, qdot0, bounds = STILL[name]
    return scene_from_dict({"name": name, "curve": curve, "parameters": params,
                            "physics": {"mu": mu, "restitution": 0.8}, "limiters": limiters,
                            "initial": {"q": q0, "qdot": qdot0}, "run": bounds})


@pytest.mark.parametrize("name", STILL)
def test_every_figure_kind_draws_a_run_that_ends_at_once(name):
    result = simulate(_scene(name))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no "no artists with labels" either
        figures = run_figures(result)
    assert [n for n, _, _ in figures] == list(FIGURE_NAMES)
    for _, fig, _ in figures:
        fig.canvas.draw()


def test_runs_without_samples_are_among_them():
    """The family holds runs with no samples at all (the IndexError's cause)."""
    empty = [n for n in STILL if len(simulate(_scene(n)).samples.t) == 0]
    assert {"rest-in-cone", "bottom", "on-limiter", "top-of-circle"} <= set(empty)


@pytest.mark.parametrize("name", ("rest-in-cone", "on-limiter", "top-of-circle"))
def test_symvib_run_plot_writes_every_figure(tmp_path, capsys, name):
    path = tmp_path / "scene.toml"
    path.write_text(_toml(name), encoding="utf-8")
    assert main(["run", str(path), "--plot", str(tmp_path / "figs")]) == 0
    err = capsys.readouterr().err
    assert "Traceback" not in err and "Error" not in err
    assert len(list((tmp_path / "figs").glob("*.png"))) == len(FIGURE_NAMES)


def _toml(name) -> str:
    curve, params, mu, limiters, q0, qdot0, _ = STILL[name]
    lines = [f'name = "{name}"', "[curve]", f'shape = "{curve["shape"]}"', "[parameters]"]
    lines += [f"{k} = {v!r}" for k, v in params.items()]
    lines += ["[physics]", f"mu = {mu!r}", "restitution = 0.8", "[limiters]"]
    lines += [f"{k} = {v!r}" for k, v in limiters.items()]
    lines += ["[initial]", f"q = {q0!r}", f"qdot = {qdot0!r}"]
    return "\n".join(lines) + "\n"
