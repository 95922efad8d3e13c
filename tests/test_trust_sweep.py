"""Trust (issue 13), sweep lane: scenes round-trip, user curves sweep, sweep data never mixes,
sizes are checked before memory is spent, bad folders and files end in one-line errors."""
import json
import math

import numpy as np
import pytest

from symvib.driver import simulate
from symvib.scene import SceneError, scene_from_dict
from symvib.shapes import CATALOGUE
from symvib.sweep import main, sweep

#: The README's own user curve (a graph z = f(x)).
BOWL = {
    "name": "bowl-scene",
    "curve": {"name": "bowl", "z": "R - sqrt(R**2 - x**2)", "domain": ["-R", "R"]},
    "parameters": {"R": 0.5},
    "physics": {"alpha0": 0.05, "restitution": 0.8},
    "limiters": {"left": -0.2, "right": 0.35},
    "initial": {"q": 0.1, "qdot": 3.0},
}
#: A parametric user curve x(q), z(q), with h and alpha given and a parameter assumption.
WHEEL = {
    "curve": {"name": "wheel", "x": "R*sin(t)", "z": "R*(1 - cos(t))", "q": "t", "h": "R", "alpha": "t",
              "domain": ["-pi", "pi"], "q_scale": "1", "params": {"R": "positive"}},
    "parameters": {"R": 0.5},
    "physics": {"mu": 0.1, "restitution": 1.0, "g": 9.0, "m": 2.0},
    "limiters": {"right": "pi/4"},
    "initial": {"q": 0.0, "qdot": 4.0},
    "run": {"t_max": 50.0, "max_events": 500},
}
#: A graph in a coordinate of its own name, no limiters, default domain.
SLOPE = {"curve": {"z": "c*u**4", "q": "u"}, "parameters": {"c": 2.0},
         "physics": {"mu": 0.0, "restitution": 0.5}, "initial": {"q": 0.3, "qdot": 0.0}}


def _catalogue_scene(name):
    sh = CATALOGUE[name]
    return {"curve": {"shape": name}, "parameters": dict(sh.defaults),
            "physics": {"alpha0": 0.05, "restitution": 0.8}, "initial": {"q": 0.0, "qdot": 1.0}}


SCENES = {**{f"catalogue-{n}": _catalogue_scene(n) for n in CATALOGUE},
          "graph-bowl": BOWL, "parametric-wheel": WHEEL, "graph-own-coordinate": SLOPE}


# --------------------------------------------------------------------- class 5: Scene.to_dict round-trips

@pytest.mark.parametrize("key", sorted(SCENES))
def test_to_dict_round_trips_every_curve_kind(key):
    s = scene_from_dict(SCENES[key])
    data = s.to_dict()
    again = scene_from_dict(data)
    assert again == s
    assert again.shape == s.shape and again.shape.kind == s.shape.kind
    assert again.alpha0 == s.alpha0          # compare=False on Scene: checked by hand
    assert again.name == s.name
    via_json = scene_from_dict(json.loads(json.dumps(data)))   # what a manifest and a Dask task carry
    assert via_json == s and via_json.alpha0 == s.alpha0
    assert "kind" not in data["curve"]


def test_to_dict_writes_mu_when_no_friction_angle_was_given():
    s = scene_from_dict(WHEEL)
    assert s.to_dict()["physics"]["mu"] == 0.1 and "alpha0" not in s.to_dict()["physics"]
    t = scene_from_dict(BOWL).replace(mu=0.3)      # mu replaced: the old angle no longer holds
    assert t.alpha0 is None and scene_from_dict(t.to_dict()).mu == 0.3
    u = scene_from_dict(WHEEL).replace(alpha0=0.2)
    assert u.to_dict()["physics"] == {"g": 9.0, "m": 2.0, "alpha0": 0.2, "restitution": 1.0}


def test_to_dict_writes_contact_only_where_the_scene_has_one():
    s = scene_from_dict(BOWL)
    assert ("contact" in s.to_dict()["physics"]) == (getattr(s, "contact", None) is not None)


# --------------------------------------------------------------------- class 5: user curves sweep

@pytest.fixture
def bowl():
    return scene_from_dict(BOWL)


def test_user_curve_sweeps_through_the_api_like_the_driver(bowl, tmp_path):
    res = sweep(bowl, {"qdot": "1:4:3", "R": "0.5,0.6"}, log_events=16, out=tmp_path / "bowl")
    assert res.count == 6 and res.spec.scene == bowl
    for row in range(res.count):
        one = bowl.replace(qdot0=float(res["initial.qdot"][row]), params={"R": float(res["parameters.R"][row])})
        ref = simulate(one, samples=False)
        assert int(res["events"][row]) == len(ref.events)
        assert res.status_names()[row] == ref.status.value
        assert res["t_final"][row] == pytest.approx(ref.t_final, rel=1e-12, abs=1e-12)
    assert (res["impacts"] > 0).any()


def test_user_curve_sweeps_through_the_cli(tmp_path, capsys):
    scene = tmp_path / "bowl.toml"
    scene.write_text('name = "bowl-scene"\n[curve]\nname = "bowl"\nz = "R - sqrt(R**2 - x**2)"\n'
                     'domain = ["-R", "R"]\n[parameters]\nR = 0.5\n[physics]\nalpha0 = 0.05\nrestitution = 0.8\n'
                     '[limiters]\nleft = -0.2\nright = 0.35\n[initial]\nq = 0.1\nqdot = 3.0\n')
    out = tmp_path / "out"
    assert main([str(scene), "--vary", "qdot=1:4:4", "--vary", "mu=0.01,0.1", "-o", str(out), "--quiet"]) == 0
    text = capsys.readouterr().out
    assert "sweep of 8 scenes of bowl-scene" in text and "0 reused" in text
    assert main([str(scene), "--vary", "qdot=1:4:4", "--vary", "mu=0.01,0.1", "-o", str(out), "--quiet"]) == 0
    assert "0 chunk(s) computed, 1 reused" in capsys.readouterr().out
