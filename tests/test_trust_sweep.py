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


# --------------------------------------------------------------------- class 6: sizes before memory

import os  # noqa: E402
import socket  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import tracemalloc  # noqa: E402
from pathlib import Path  # noqa: E402

from symvib import sweep as sweep_mod  # noqa: E402
from symvib.sweep import (FORMAT, MAX_LIST_VALUES, SweepError, WriterLock, load_sweep, make_spec,  # noqa: E402
                          sweep_id, _linspace_at)

PARABOLA = {"curve": {"shape": "parabola"}, "parameters": {"p": 1.0},
            "physics": {"g": 9.81, "m": 0.2, "mu": 0.05, "restitution": 0.8},
            "limiters": {"left": "-pi/6", "right": "pi/4"}, "initial": {"q": 0.0, "qdot": 7.0}}
#: Bytes a definition may cost while it is checked (an axis of 10**9 values once cost 14 GB).
SMALL = 2_000_000


def parabola():
    return scene_from_dict(PARABOLA)


@pytest.mark.parametrize("start, stop, count", [
    (3.0, 12.0, 400), (0.01, 0.2, 250), (-math.pi / 3, -math.pi / 12, 10), (0.0, 1.0, 2), (1.0, 1.0, 5),
    (2.5, 2.5, 1), (12.0, 3.0, 7), (5e-324, 1e-323, 9), (-1e300, 1e300, 11), (0.1, 0.7, 1000),
])
def test_grid_values_are_numpy_linspace_bit_for_bit(start, stop, count):
    ref = np.linspace(start, stop, count) if count > 1 else np.array([start])
    idx = np.arange(count)
    assert np.array_equal(_linspace_at(start, stop, count, idx), ref)
    assert np.array_equal(_linspace_at(start, stop, count, idx[::-3]), ref[::-3])


@pytest.mark.parametrize("vary, kwargs, field", [
    ({"qdot": "3:12:1000000000"}, {}, "vary.qdot"),                       # the 14 GB tuple
    ({"qdot": "3:12:100000", "mu": "0.01:0.2:100000"}, {}, "vary"),       # 10**10 scenes
    ({"qdot": "3:12:4"}, {"log_events": 100_000_000}, "log_events"),      # the 16 GB event log
    ({"qdot": "3:12:4096"}, {"log_events": 1_000_000}, "chunk"),          # a chunk's log: 196 GB
    ({"qdot": "3:12:4096"}, {"log_events": 6000}, "chunk"),               # 1.18 GB > MAX_CHUNK_BYTES
    ({"qdot": "3:12:4"}, {"log_events": 10**7}, "log_events"),            # > MAX_LOG_EVENTS
    ({"qdot": "3:12:1000000"}, {"log_events": 1000, "chunk": 1000}, "log_events"),   # 48 GB in all
    ({"qdot": "3:12:10000000"}, {"chunk": 1}, "chunk"),                   # 10**7 chunk files
    ({"qdot": "3:12:4"}, {"nodes": 1}, "nodes"),
    ({"qdot": "3:12:4"}, {"nodes": 65}, "nodes"),
    ({"qdot": "3:12:4"}, {"nodes": True}, "nodes"),
    ({"qdot": "3:12:4"}, {"chunk": 2.5}, "chunk"),
    ({"qdot": "3:12:4"}, {"seed": -1}, "seed"),
    ({"qdot": "3:12"}, {"random": 10**12}, "random"),
    ({"k": ",".join(["0.5"] * (MAX_LIST_VALUES + 1))}, {}, "vary.k"),
    ({"k": [0.5] * (MAX_LIST_VALUES + 1)}, {}, "vary.k"),
    ({"max_events": "1e19"}, {}, "run.max_events"),                        # overflows int64 in the core
    ({"max_events": "2.5"}, {}, "run.max_events"),
])
def test_sizes_are_checked_before_memory_is_spent(vary, kwargs, field):
    tracemalloc.start()
    try:
        with pytest.raises(SceneError) as info:
            make_spec(parabola(), vary, **kwargs)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert info.value.field == field and "\n" not in str(info.value)
    assert peak < SMALL + 40 * MAX_LIST_VALUES   # a listed axis's own text is the only size paid


def test_a_large_grid_costs_three_numbers_until_its_chunks_run():
    tracemalloc.start()
    try:
        spec = make_spec(parabola(), {"qdot": "3:12:100000000"})
        text = json.dumps(spec.to_dict())
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < SMALL and len(text) < 10_000 and spec.count == 10**8
    rows, (values,) = spec.rows(spec.chunks - 1)
    assert rows[-1] == 10**8 - 1 and values[-1] == 12.0
    assert np.allclose(values, 3.0 + rows * (9.0 / (10**8 - 1)), rtol=1e-15, atol=0)


def test_cli_refuses_sizes_before_creating_the_folder(tmp_path, capsys):
    out = tmp_path / "never"
    assert main(["paper-parabola", "--vary", "qdot=3:12:1000000000", "-o", str(out), "--quiet"]) == 2
    assert main(["paper-parabola", "--vary", "qdot=3:12:4", "--log-events", "100000000", "-o", str(out)]) == 2
    assert main(["paper-parabola", "--vary", "qdot=3:12:4", "--nodes", "100", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 3 and "vary.qdot" in err[0] and "log_events" in err[1] and "nodes" in err[2]
    assert not out.exists()
