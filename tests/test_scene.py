"""Scenes: loading, expressions, and a clear error naming the field for every bad input."""
import dataclasses
import math
from pathlib import Path

import pytest

from symvib.numeric.scene import Scene, SceneError, load_scene, resolve_scene, scene_from_dict

SCENES = Path(__file__).resolve().parents[1] / "symvib" / "scenes"


def base(**over):
    data = {
        "name": "t",
        "curve": {"shape": "parabola"},
        "parameters": {"p": 1.0},
        "physics": {"g": 9.81, "m": 0.2, "alpha0": 0.05, "restitution": 0.8},
        "limiters": {"left": "-pi/6", "right": "pi/4"},
        "initial": {"q": 0.0, "qdot": 7.0},
    }
    for key, value in over.items():
        section, _, field = key.partition("__")
        if field:
            if value is None:
                data[section].pop(field, None)
            else:
                data.setdefault(section, {})[field] = value
        elif value is None:
            data.pop(section, None)
        else:
            data[section] = value
    return data


def test_paper_scene_files_load():
    s = load_scene(SCENES / "paper-parabola.toml")
    assert s.shape.name == "parabola" and s.mu == pytest.approx(math.tan(0.05))
    assert s.left == pytest.approx(-math.pi / 6) and s.right == pytest.approx(math.pi / 4)
    c = load_scene(SCENES / "paper-circle-3.8.toml")
    assert c.mu == pytest.approx(abs(math.tan(3.0))) and c.left is None
    assert {p.stem for p in SCENES.glob("*.toml")} >= {"paper-parabola", "paper-cycloid", "paper-circle-3.8",
                                                       "paper-circle-7"}


def test_expressions_and_user_curves():
    s = scene_from_dict(base(physics__alpha0=None, physics__mu="tan(0.05)", limiters__right="asin(1/2)"))
    assert s.mu == pytest.approx(math.tan(0.05)) and s.right == pytest.approx(math.pi / 6)
    u = scene_from_dict(base(curve={"z": "x**2/(2*b)", "name": "bowl"}, parameters={"b": 2.0},
                             limiters={"left": -1, "right": "b/2"}))
    assert u.shape.kind == "graph" and u.shape.q == "x" and u.right == 1.0
    v = scene_from_dict(base(curve={"x": "R*sin(phi)", "z": "R*(1 - cos(phi))", "q": "phi"},
                             parameters={"R": 0.5}))
    assert v.shape.kind == "parametric" and v.param_dict == {"R": 0.5}


def test_replace_revalidates():
    s = scene_from_dict(base())
    assert s.replace(k=1.0).k == 1.0
    assert s.replace(params={"p": 2.0}).param_dict == {"p": 2.0}
    with pytest.raises(SceneError, match="physics.restitution"):
        s.replace(k=1.5)
    with pytest.raises(SceneError, match=r"parameters.R: not a parameter"):
        s.replace(params={"R": 1.0})



WITH_NUMBERS = [dict(mu=0.2), dict(k=0.3, qdot0=-2.0), dict(q0=0.1, left=-0.4, right=0.45), dict(mu=0.0, k=1.0),
                dict(mu=math.nan), dict(k=1.5), dict(k=-0.1), dict(mu=-0.1), dict(mu=0.9), dict(qdot0=math.inf),
                dict(q0=math.nan), dict(q0=0.6), dict(left=0.2), dict(right=-0.2), dict(right=math.nan),
                dict(left=-1e9), dict(right=1e9), dict(left=0.3, right=0.2)]


@pytest.mark.parametrize("changes", WITH_NUMBERS)
@pytest.mark.parametrize("mu_s", [None, 0.5])
def test_with_numbers_is_replace(changes, mu_s):
    """A fit's trial points: ``with_numbers`` makes the scene ``replace`` makes, or refuses it with the same error
    (the checks that read the changed numbers only)."""
    s = resolve_scene("paper-parabola").replace(left=-0.5, right=0.5, mu_s=mu_s)
    try:
        expected = s.replace(**changes)
    except SceneError as err:
        with pytest.raises(SceneError) as got:
            s.with_numbers(**changes)
        assert (got.value.field, str(got.value)) == (err.field, str(err))
        return
    new = s.with_numbers(**changes)
    assert new == expected and vars(new) == vars(expected) and new.alpha0 == expected.alpha0


def test_with_numbers_refuses_other_fields():
    s = resolve_scene("paper-parabola")
    with pytest.raises(TypeError, match="only mu"):
        s.with_numbers(g=9.0)
    with pytest.raises(SceneError, match="limiters.left"):
        s.replace(left=None).with_numbers(left=0.1)

@pytest.mark.parametrize("over, field, text", [
    (dict(physics__restitution=1.2), "physics.restitution", "must be in [0, 1]"),
    (dict(physics__restitution=-0.1), "physics.restitution", "must be in [0, 1]"),
    (dict(physics__restitution=None), "physics.restitution", "missing"),
    (dict(physics__alpha0=None, physics__mu=-0.1), "physics.mu", ">= 0"),
    (dict(physics__mu=0.1), "physics", "not both"),
    (dict(physics__alpha0=2.0), "physics.alpha0", "[0, pi/2)"),
    (dict(limiters__left="pi/4", limiters__right="-pi/6"), "limiters", "must be left of"),
    (dict(initial__q=1.0), "initial.q", "outside the limiters"),
    (dict(initial__q=-1.0), "initial.q", "outside the limiters"),
    (dict(limiters__right="2"), "limiters.right", "outside the curve's regular domain"),
    (dict(parameters={"p": 1.0, "R": 2.0}), "parameters.R", "unknown symbol"),
    (dict(parameters={}), "parameters.p", "missing"),
    (dict(parameters=None), "parameters", "missing section"),
    (dict(parameters={"p": -1.0}), "parameters.p", "must be positive"),
    (dict(initial__qdot=float("nan")), "initial.qdot", "finite"),
    (dict(physics__g=float("inf")), "physics.g", "finite"),
    (dict(physics__m=0), "physics.m", "must be positive"),
    (dict(initial__qdot="nan"), "initial.qdot", "not allowed"),
    (dict(initial=None), "initial", "missing section"),
    (dict(physics=None), "physics", "missing section"),
    (dict(curve=None), "curve", "missing section"),
    (dict(initial__qdot=None), "initial.qdot", "missing"),
    (dict(curve={"shape": "helix"}), "curve.shape", "unknown shape 'helix'"),
    (dict(curve={"shape": "parabola", "z": "x"}), "curve.z", "not both"),
    (dict(curve={"z": "x**2/(2*b)"}, parameters={"p": 1}), "parameters.p", "unknown symbol"),
    (dict(curve={"z": "__import__('os').system('true')"}), "curve.z", "not allowed"),
    (dict(physics__restitusion=0.5), "physics.restitusion", "unknown key"),
    (dict(extra={"a": 1}), "extra", "unknown section"),
    (dict(run={"t_max": -1}), "run.t_max", "must be positive"),
    (dict(run={"max_events": 0}), "run.max_events", "positive integer"),
    (dict(limiters__right="pi/4 +"), "limiters.right", "not a valid expression"),
    (dict(initial__q="p*"), "initial.q", "not a valid expression"),
    (dict(initial__q="x"), "initial.q", "name 'x' is not allowed"),
    (dict(initial__qdot=True), "initial.qdot", "must be a number"),
])
def test_bad_scenes_name_the_field(over, field, text):
    with pytest.raises(SceneError) as info:
        scene_from_dict(base(**over))
    assert info.value.field == field, str(info.value)
    assert text in str(info.value)


def test_bad_files(tmp_path):
    with pytest.raises(SceneError, match="no such file"):
        load_scene(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[curve\nshape = 1")
    with pytest.raises(SceneError, match="not valid TOML"):
        load_scene(bad)


def test_scene_is_immutable_and_round_trips():
    s = scene_from_dict(base())
    with pytest.raises(dataclasses.FrozenInstanceError):
        s.k = 0.5  # type: ignore[misc]
    again = scene_from_dict(s.to_dict())
    assert again == s
    assert isinstance(again, Scene)


# Static friction mu_s (physics.md, "Events" 2): default equal to mu, mu_s >= mu, errors naming the field.

@pytest.mark.parametrize("physics, field, text", [
    ({"mu_s": float("nan")}, "physics.mu_s", "finite"),
    ({"mu_s": "nan"}, "physics.mu_s", "not allowed"),
    ({"mu_s": float("inf")}, "physics.mu_s", "finite"),
    ({"mu_s": -0.1}, "physics.mu_s", "must be >= 0"),
    ({"mu_s": "fast"}, "physics.mu_s", "not allowed"),
    ({"mu_s": True}, "physics.mu_s", "must be a number"),
    ({"mu_s": [0.1]}, "physics.mu_s", "must be a number or an expression string"),
    ({"mu_s": 0.01}, "physics.mu_s", "not a Coulomb contact"),
    ({"mu_s": "3 deg"}, "physics.mu_s", "takes no unit"),
    ({"alpha0_s": 0.01}, "physics.mu_s", "below the kinetic mu"),
    ({"alpha0_s": 2.0}, "physics.alpha0_s", "[0, pi/2)"),
    ({"alpha0_s": -0.1}, "physics.alpha0_s", "[0, pi/2)"),
    ({"alpha0_s": "90 deg"}, "physics.alpha0_s", "[0, pi/2)"),
    ({"alpha0_s": "3 furlongs"}, "physics.alpha0_s", "unknown unit"),
    ({"mu_s": 0.1, "alpha0_s": 0.1}, "physics", "mu_s or alpha0_s"),
    ({"mu_s": 0.1, "alpha0_s": "atan(0.1)"}, "physics", "not both"),
    ({"mu_s": "oo"}, "physics.mu_s", "not allowed"),
    ({"mu_s": "__import__('os')"}, "physics.mu_s", "not allowed"),
    ({"mu_s": None}, "physics.mu_s", "must be a number or an expression string"),
    ({"mu_s": {"a": 1}}, "physics.mu_s", "must be a number or an expression string"),
    ({"mu_s": 10 ** 400}, "physics.mu_s", "number too large"),
    ({"mu_s": ""}, "physics.mu_s", "empty expression"),
    ({"mu_s": "\uff10.3"}, "physics.mu_s", "invalid character"),
    ({"mu_s": "1/0"}, "physics.mu_s", "division by zero"),
    ({"mu_s": "I"}, "physics.mu_s", "not allowed"),
    ({"mu_s": "p"}, "physics.mu_s", "not allowed"),
    ({"mu_s": 0}, "physics.mu_s", "below the kinetic mu"),
    ({"alpha0_s": float("nan")}, "physics.alpha0_s", "finite"),
    ({"alpha0_s": "pi/2"}, "physics.alpha0_s", "[0, pi/2)"),
    ({"alpha0_s": False}, "physics.alpha0_s", "must be a number"),
    ({"alpha0_s": "__import__('os')"}, "physics.alpha0_s", "not allowed"),
])
def test_bad_static_friction_names_the_field(physics, field, text):
    with pytest.raises(SceneError) as info:
        scene_from_dict(base(physics={"g": 9.81, "m": 0.2, "alpha0": 0.05, "restitution": 0.8, **physics}))
    assert info.value.field == field, str(info.value)
    assert text in str(info.value)


@pytest.mark.parametrize("changes, field, text", [
    ({"mu_s": float("nan")}, "physics.mu_s", "finite"),
    ({"mu_s": "0.3"}, "physics.mu_s", "must be a number, got '0.3'"),
    ({"mu_s": [0.2]}, "physics.mu_s", "must be a number"),
    ({"mu_s": 1j}, "physics.mu_s", "must be a number"),
    ({"alpha0_s": "0.3"}, "physics.alpha0_s", "must be a number"),
    ({"alpha0_s": -0.2}, "physics.alpha0_s", "[0, pi/2)"),
    ({"alpha0_s": float("nan")}, "physics.alpha0_s", "finite"),
    ({"mu_s": 0.3, "alpha0_s": 0.5}, "physics.alpha0_s", "give one of them"),
])
def test_bad_static_friction_through_replace_names_the_field(changes, field, text):
    with pytest.raises(SceneError) as info:
        scene_from_dict(base()).replace(**changes)
    assert info.value.field == field and text in str(info.value), str(info.value)


def test_a_new_kinetic_mu_above_a_given_static_one_is_refused_naming_mu_s():
    with pytest.raises(SceneError, match="below the kinetic mu = 0.5") as info:
        scene_from_dict(base()).replace(mu_s=0.3).replace(mu=0.5)
    assert info.value.field == "physics.mu_s"


def test_static_below_kinetic_says_why_and_what_to_change():
    s = scene_from_dict(base())
    with pytest.raises(SceneError) as info:
        s.replace(mu_s=0.02)
    message = str(info.value)
    assert info.value.field == "physics.mu_s"
    assert "0.02" in message and repr(s.mu) in message     # both numbers
    assert "give mu_s >= mu" in message and "leave mu_s out" in message


def test_static_friction_given_twice_through_the_api_must_agree():
    s = scene_from_dict(base())
    with pytest.raises(SceneError) as info:
        dataclasses.replace(s, mu_s=0.3, alpha0_s=0.1)     # tan(0.1) = 0.1003 is not 0.3
    assert info.value.field == "physics.alpha0_s" and "give one of them" in str(info.value)
    agree = dataclasses.replace(s, mu_s=math.tan(0.1), alpha0_s=0.1)
    assert agree.mu_s == math.tan(0.1)
    with pytest.raises(SceneError, match=r"physics\.mu_s: must be a number"):
        dataclasses.replace(s, mu_s="0.3", alpha0_s=0.1)


def test_mu_s_defaults_to_mu_and_follows_it():
    s = scene_from_dict(base())
    assert s.mu_s is None and s.mu_static == s.mu == math.tan(0.05)
    moved = s.replace(mu=0.2)                               # unset: still mu's
    assert moved.mu_s is None and moved.mu_static == 0.2
    given = s.replace(mu_s=0.3)
    assert given.mu_static == 0.3 and given.replace(mu=0.2).mu_static == 0.3   # given: its own
    with pytest.raises(SceneError, match=r"physics\.mu_s: .*below the kinetic mu"):
        given.replace(mu=0.4)
    angle = s.replace(alpha0_s=0.3)
    assert angle.mu_s == math.tan(0.3) and angle.replace(mu_s=0.5).alpha0_s is None


def test_a_scene_without_mu_s_writes_none_and_mu_s_round_trips():
    plain = scene_from_dict(base())
    assert "mu_s" not in plain.to_dict()["physics"] and "alpha0_s" not in plain.to_dict()["physics"]
    assert scene_from_dict(plain.to_dict()) == plain
    for physics, key in (({"mu_s": 0.08}, "mu_s"), ({"alpha0_s": "4 deg"}, "alpha0_s")):
        s = scene_from_dict(base(physics={"g": 9.81, "m": 0.2, "alpha0": 0.05, "restitution": 0.8, **physics}))
        data = s.to_dict()
        assert set(data["physics"]) & {"mu_s", "alpha0_s"} == {key}
        again = scene_from_dict(data)
        assert again == s and again.mu_static == s.mu_static and again.alpha0_s == s.alpha0_s
    assert scene_from_dict(base(physics__mu_s=0.08)) != plain   # a given mu_s is part of the scene
