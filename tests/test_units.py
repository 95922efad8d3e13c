"""Units: every scene field's SI unit in one table, units in scene values, and in the JSON."""
import copy
import math
import re
from pathlib import Path

import pytest

from symvib import simulate
from symvib.numeric import scene as scene_mod
from symvib.numeric.scene import (
    DRAG_FIELDS,
    FIELD_UNITS,
    FLIGHT_FIELDS,
    STATIC_FRICTION_FIELDS,
    TEXT_FIELDS,
    SceneError,
    field_unit,
    load_scene,
    scene_from_dict,
    units_table,
)
from symvib.shapes import CATALOGUE

ROOT = Path(__file__).resolve().parents[1]

CIRCLE = {"curve": {"shape": "circle"}, "parameters": {"R": 0.5},
          "physics": {"alpha0": 0.05, "restitution": 1}, "limiters": {"right": "pi/4"},
          "initial": {"q": "pi/12", "qdot": 7}}
GRAPH = {"curve": {"shape": "catenary"}, "parameters": {"a": 1.0},
         "physics": {"mu": 0.1, "restitution": 0.8}, "limiters": {"left": -0.5},
         "initial": {"q": 0.0, "qdot": 3.0}}


def with_value(base, dotted, value):
    data = copy.deepcopy(base)
    section, key = dotted.split(".")
    data.setdefault(section, {})[key] = value
    return data


def every_field():
    """Every key a scene file may hold, as ``section.key`` (``parameters.*`` for the curve's symbols)."""
    out = set(scene_mod._TOP)
    for section, keys in scene_mod._SECTIONS.items():
        out |= {"parameters.*"} if keys is None else {f"{section}.{k}" for k in keys}
    return out


def test_every_scene_field_has_a_unit_or_is_text():
    fields = every_field()
    assert not set(FIELD_UNITS) & set(TEXT_FIELDS)
    assert fields == set(FIELD_UNITS) | set(TEXT_FIELDS), fields ^ (set(FIELD_UNITS) | set(TEXT_FIELDS))
    for name, unit in FIELD_UNITS.items():
        assert isinstance(unit, str) and unit, name


def test_field_units_resolve_the_coordinate():
    for sh in CATALOGUE.values():
        q_unit = "m" if sh.kind == "graph" else "rad"
        assert field_unit("initial.q", sh) == field_unit("limiters.left", sh) == q_unit
        assert field_unit("initial.qdot", sh) == f"{q_unit}/s"
        for p in sh.params:
            assert field_unit(f"parameters.{p}", sh) == "m"  # the catalogue's parameters are lengths
    user = scene_from_dict({"curve": {"z": "c*x"}, "parameters": {"c": 0.5}, "physics": {"mu": 0, "restitution": 1},
                            "initial": {"q": 0, "qdot": 1}}).shape
    assert field_unit("parameters.c", user) is None  # a slope: only the user knows


@pytest.mark.parametrize("dotted,value,attr,expected", [
    ("physics.alpha0", "3 deg", "mu", math.tan(3 * math.pi / 180)),
    ("physics.alpha0", "0.1 rad", "mu", math.tan(0.1)),
    ("physics.alpha0", "pi - 3", "mu", math.tan(math.pi - 3)),  # the paper circle's reading stays valid
    ("physics.alpha0", "90 - 87 deg", "mu", math.tan(3 * math.pi / 180)),
    ("limiters.right", "45 deg", "right", 45 * math.pi / 180),
    ("limiters.right", "pi/4 rad", "right", math.pi / 4),
    ("initial.q", "15 deg", "q0", 15 * math.pi / 180),
    ("initial.qdot", "360 deg/s", "qdot0", 2 * math.pi),
    ("initial.qdot", "7 rad/s", "qdot0", 7.0),
    ("run.t_max", "10 s", "t_max", 10.0),
    ("physics.m", "0.2 kg", "m", 0.2),
    ("physics.alpha0", "2 * pi / 100", "mu", math.tan(2 * math.pi / 100)),  # an expression, not "2 *" in "pi"
])
def test_units_in_values(dotted, value, attr, expected):
    scene = scene_from_dict(with_value(CIRCLE, dotted, value))
    assert getattr(scene, attr) == pytest.approx(expected, rel=1e-15)


def test_a_length_coordinate_takes_metres_not_degrees():
    assert scene_from_dict(with_value(GRAPH, "initial.q", "0.1 m")).q0 == 0.1
    with pytest.raises(SceneError, match=r"^initial\.q: unknown unit 'deg': this field is in m"):
        scene_from_dict(with_value(GRAPH, "initial.q", "3 deg"))


@pytest.mark.parametrize("dotted,value,message", [
    ("physics.alpha0", "3 degree", r"^physics\.alpha0: unknown unit 'degree'; this field is in rad and takes rad, deg"),
    ("initial.qdot", "3 deg", r"^initial\.qdot: unknown unit 'deg'; this field is in rad/s"),
    ("physics.restitution", "1 deg", r"^physics\.restitution: takes no unit \(a dimensionless number\)"),
    ("physics.g", "9.81 m", r"^physics\.g: takes no unit, got 'm': write the number in m/s\^2"),
    ("parameters.R", "5 deg", r"^parameters\.R: unknown unit 'deg': this field is in m"),
    ("run.t_max", "1 h", r"^run\.t_max: unknown unit 'h': this field is in s"),
])
def test_unit_errors_name_the_field(dotted, value, message):
    data = with_value(CIRCLE, dotted, value)
    with pytest.raises(SceneError, match=message):
        scene_from_dict(data)


def test_mu_takes_no_unit():
    data = with_value(CIRCLE, "physics.mu", "0.1 deg")
    del data["physics"]["alpha0"]
    with pytest.raises(SceneError, match=r"^physics\.mu: takes no unit"):
        scene_from_dict(data)


def test_the_schema_doc_holds_the_current_units_table_and_a_valid_scene(tmp_path):
    text = (ROOT / "docs" / "scenes.md").read_text(encoding="utf-8")
    assert units_table() in text, "docs/scenes.md: paste symvib.numeric.scene.units_table() between its markers"
    path = tmp_path / "scene.toml"
    path.write_text(re.search(r"```toml\n(.*?)```", text, re.S).group(1), encoding="utf-8")
    scene = load_scene(path)
    assert scene.shape.name == "parabola" and scene.right == pytest.approx(math.pi / 4)


def test_result_json_carries_the_units_of_the_table():
    scene = scene_from_dict(CIRCLE)
    data = simulate(scene, backend="python").to_dict(samples=True)
    units = data["units"]
    assert units["t_final"] == FIELD_UNITS["run.t_max"]
    assert units["q_final"] == field_unit("initial.q", scene.shape) == "rad"
    assert units["events"]["qdot_before"] == "rad/s"
    assert units["scene"]["physics.g"] == FIELD_UNITS["physics.g"]
    assert units["scene"]["parameters.R"] == "m"
    for name in FIELD_UNITS:  # every scene quantity (the curve's expressions of a catalogue shape aside)
        optional = STATIC_FRICTION_FIELDS + DRAG_FIELDS + FLIGHT_FIELDS
        if not name.startswith(("curve.", "parameters.")) and name not in optional:
            assert units["scene"][name] == field_unit(name, scene.shape)
    # the flights' fields only for a unilateral scene (a bilateral one: its JSON as before)
    assert not set(FLIGHT_FIELDS) & set(units["scene"])
    flying = simulate(scene.replace(contact="unilateral"), backend="python", samples=False).to_dict()["units"]
    assert {name: flying["scene"][name] for name in FLIGHT_FIELDS} == {"physics.restitution_curve": "1"}
    # static friction's units only where the scene gives it (a scene without it: its JSON as before)
    assert not set(STATIC_FRICTION_FIELDS) & set(units["scene"])
    static = simulate(scene.replace(mu_s=scene.mu + 0.1), backend="python", samples=False).to_dict()["units"]
    assert {name: static["scene"][name] for name in STATIC_FRICTION_FIELDS} == {"physics.mu_s": "1",
                                                                                "physics.alpha0_s": "rad"}
    # the drag's likewise, and the budget's drag work (physics.md, "Air drag")
    assert not set(DRAG_FIELDS) & set(units["scene"]) and "drag_work" not in units["energy_budget"]
    dragged = simulate(scene.replace(drag=0.05), samples=False).to_dict()
    assert dragged["units"]["scene"]["physics.drag"] == "kg/m" == FIELD_UNITS["physics.drag"]
    assert set(dragged["units"]["energy_budget"]) == set(dragged["energy_budget"]) >= {"drag_work"}
    # every number of the JSON has a unit: the events' columns, the samples' columns, the budget's entries
    assert set(units["events"]) == {k for e in data["events"] for k in e if k not in ("kind", "detail")}
    assert set(units["samples"]) == set(data["samples"])
    assert all(units["samples"][k] for k in data["samples"]), units["samples"]
    assert set(units["energy_budget"]) == set(data["energy_budget"])


@pytest.mark.parametrize("value", [
    "1" + " " * 5000 + "deg",        # the parser's length cap applies to the whole text
    "1 " * 20000 + "deg",
    "3 deg deg",
    "(1 deg)",
    "3 " + "x" * 100000,
    "3 deg/s/s",
])
def test_hostile_units_are_one_line_errors(value):
    with pytest.raises(SceneError) as info:
        scene_from_dict(with_value(CIRCLE, "physics.alpha0", value))
    assert str(info.value).startswith("physics.alpha0: ") and len(str(info.value)) < 400
