"""Careless input read as meant, or refused in one line naming the field (issue 29, 12): byte-order
marks, a field varied twice, the row a sweep's error names, the list of sweepable fields, angle units
on an angle-valued curve parameter.
"""
from importlib.resources import files

import numpy as np
import pytest

from symvib.cli import main, sweep_main
from symvib.numeric.scene import SceneError, angle_parameters, load_scene, resolve_scene, scene_from_dict
from symvib.numeric.sweep import make_spec
from symvib.paths import UserPathError, read_user_toml
from symvib.shapes import Shape

BOM = "\ufeff"
PARABOLA = (files("symvib") / "scenes" / "paper-parabola.toml").read_text(encoding="utf-8")


def one_line(capsys, *words):
    err = capsys.readouterr().err
    return err.count("\n") == 1 and "Traceback" not in err and all(w in err for w in words)


# --------------------------------------------------------------------- byte-order marks

@pytest.mark.parametrize("text", [BOM + PARABOLA, BOM + PARABOLA.replace("\n", "\r\n"),
                                  BOM + "# a comment first\n" + PARABOLA])
def test_a_scene_file_with_a_byte_order_mark_reads(tmp_path, text, capsys):
    path = tmp_path / "scene.toml"
    path.write_bytes(text.encode("utf-8"))
    assert load_scene(path).name == "paper-parabola"
    assert main(["run", str(path), "--backend", "python"]) == 0


def test_a_sweep_file_with_a_byte_order_mark_reads(tmp_path):
    path = tmp_path / "sweep.toml"
    path.write_bytes((BOM + 'scene = "paper-parabola"\nchunk = 2\n[vary]\nqdot = "3:12:3"\n').encode("utf-8"))
    assert sweep_main(["--file", str(path), "-o", str(tmp_path / "out"), "--quiet", "--backend", "python"]) == 0


@pytest.mark.parametrize("text", [BOM + BOM + PARABOLA, BOM + "name = \n"])
def test_what_follows_the_mark_is_still_checked(tmp_path, text):
    path = tmp_path / "bad.toml"
    path.write_bytes(text.encode("utf-8"))
    with pytest.raises(UserPathError, match="not valid TOML") as info:
        read_user_toml(path, "scene file")
    assert str(path) in str(info.value) and "\n" not in str(info.value)


# --------------------------------------------------------------------- a field varied twice

@pytest.mark.parametrize("first, second, field", [
    ("qdot=1:2:3", "qdot=4", "qdot"),
    ("mu=0.1,0.2", "mu=0.3", "mu"),
    ("qdot=3:12:3", " qdot =4", "qdot"),
    ("k=0.5", "k=0.5", "k"),
])
def test_a_field_given_twice_on_the_command_line_is_refused_naming_it(tmp_path, capsys, first, second, field):
    args = ["paper-parabola", "--vary", first, "--vary", second, "-o", str(tmp_path / "out"), "--quiet"]
    assert sweep_main(args) == 2
    assert one_line(capsys, f"--vary {field}", "twice")
    assert not (tmp_path / "out").exists()


def test_two_spellings_of_one_field_are_still_refused(tmp_path, capsys):
    args = ["paper-parabola", "--vary", "qdot=3,4", "--vary", "qdot0=5", "-o", str(tmp_path / "out"), "--quiet"]
    assert sweep_main(args) == 2 and one_line(capsys, "initial.qdot", "twice")


# --------------------------------------------------------------------- the row an error names

@pytest.mark.parametrize("vary, row", [
    ({"k": "0.5,0.6,1.5"}, 2),
    ({"k": "1.5,0.6,0.5"}, 0),
    ({"qdot": "3,4,5", "k": "0.5,1.5"}, 1),        # row = index of qdot * 2 + index of k: (0, 1) first
    ({"k": "0.5,1.5", "qdot": "3,4,5"}, 3),        # (1, 0): row 3
    ({"k": "0.5:1.5:11"}, 10),
])
def test_a_bad_grid_value_is_named_by_its_row_in_the_sweep(vary, row):
    with pytest.raises(SceneError, match="physics.restitution") as info:
        make_spec(resolve_scene("paper-parabola"), vary)
    assert f"(sweep row {row})" in str(info.value) and "of its chunk" not in str(info.value)


def test_a_bad_row_of_a_later_chunk_is_named_by_its_sweep_row():
    spec = make_spec(resolve_scene("paper-parabola"), {"k": "0.2:0.9:8"}, chunk=3)
    values = [np.array([0.5, 1.5, 0.7])]
    with pytest.raises(SceneError, match=r"\(sweep row 7\)"):
        spec.scalars(values, rows=np.array([6, 7, 8]))


def test_a_bad_random_corner_is_named_by_its_values():
    with pytest.raises(SceneError, match=r"varied values physics.restitution = 1.5"):
        make_spec(resolve_scene("paper-parabola"), {"k": "0.5:1.5"}, random=10)


# --------------------------------------------------------------------- the list of sweepable fields

@pytest.mark.parametrize("shape, names", [("parabola-x", ("x", "xdot", "x0", "xdot0")),
                                          ("circle", ("phi", "phidot", "phi0", "phidot0")),
                                          ("catenary", ("x", "xdot"))])
def test_the_list_of_fields_names_every_accepted_spelling(shape, names):
    from symvib.shapes import CATALOGUE

    scene = scene_from_dict({"curve": {"shape": shape}, "parameters": dict(CATALOGUE[shape].defaults),
                             "physics": {"mu": 0.1, "restitution": 0.8}, "initial": {"q": 0.1, "qdot": 1.0}})
    for name in names:                             # every spelling is accepted ...
        make_spec(scene, {name: "0.1,0.2"})
    with pytest.raises(SceneError) as info:
        make_spec(scene, {"nonsense": "1,2"})
    listed = str(info.value).split("use one of ", 1)[1].split(" (or", 1)[0].split(", ")
    assert set(names) <= set(listed)               # ... and listed


# --------------------------------------------------------------------- angle units on curve parameters

RAMP = {"name": "ramp", "z": "x*tan(beta) + x**2/2", "q": "x", "params": {"beta": "real"}}
REST = {"physics": {"mu": 0.1, "restitution": 0.8}, "initial": {"q": 0.5, "qdot": 0.0}, "limiters": {"left": -1.0}}


@pytest.mark.parametrize("text, value", [("17 deg", np.radians(17.0)), ("0.3 rad", 0.3), ("-5 deg", np.radians(-5.0)),
                                         ("pi/18 rad", np.pi / 18)])
def test_an_angle_valued_curve_parameter_takes_angle_units(text, value):
    scene = scene_from_dict({"curve": RAMP, "parameters": {"beta": text}, **REST})
    assert scene.param_values[0] == pytest.approx(value, rel=1e-15)


@pytest.mark.parametrize("curve, angles", [
    ({"z": "x*tan(beta)", "q": "x", "params": {"beta": "real"}}, {"beta"}),
    ({"z": "c*x**2 + sin(x - beta)", "q": "x", "params": {"c": "positive", "beta": "real"}}, {"beta"}),
    ({"z": "c*sin(c*x)", "q": "x", "params": {"c": "positive"}}, set()),       # c outside sin too: a length
    ({"x": "R*sin(t)", "z": "R*(1 - cos(t))", "q": "t", "params": {"R": "positive"}, "alpha": "t + g0"}, set()),
    ({"x": "cos(t + a)", "z": "sin(t + a)", "q": "t", "params": {"a": "real"}}, {"a"}),
])
def test_which_parameters_are_angles(curve, angles):
    kind = "parametric" if "x" in curve else "graph"
    assert set(angle_parameters(Shape(name="c", kind=kind, **curve))) == angles


@pytest.mark.parametrize("unit", ["deg", "rad"])
def test_a_length_parameter_with_an_angle_unit_is_a_clear_error(unit):
    curve = {"name": "bowl", "z": "x**2/(2*p)", "q": "x", "params": {"p": "positive"}}
    with pytest.raises(SceneError, match=r"^parameters\.p: takes no unit") as info:
        scene_from_dict({"curve": curve, "parameters": {"p": f"2 {unit}"}, **REST})
    assert "only inside cos, sin, tan" in str(info.value) and "\n" not in str(info.value)
