"""Sensitivity columns of a sweep (symvib/numeric/sweep/sensitivity_columns.py): the single-scene
derivatives per row, a finite difference across neighbouring rows, NaN with a reason code."""
import json
import random
import subprocess
import sys

import numpy as np
import pytest

import symvib
from symvib.numeric.scene import SceneError, resolve_scene, scene_from_dict
from symvib.numeric.sensitivity_flight import ACCUMULATION_REASON, STICK_EDGE_REASON, TANGENTIAL_LANDING_REASON
from symvib.numeric.sweep import load_sweep, make_spec, sweep
from symvib.numeric.sweep.sensitivity_columns import (
    FLIGHT_QUANTITIES,
    OTHER_REASON,
    QUANTITIES,
    REASONS,
    column_names,
    reason_code,
)

BASE = resolve_scene("paper-parabola").replace(k=0.8)
WRT = ("mu", "k", "qdot0")


def test_the_columns_are_the_single_scene_sensitivities_of_each_row():
    res = sweep(BASE, {"qdot": "6:8:3", "mu": "0.04,0.06"}, backend="python", sensitivities=WRT)
    assert [c for c in res.columns if c.startswith("d_")] == column_names(WRT)[:-1]
    for row in (0, 3, 5):
        scene = BASE.replace(qdot0=float(res["initial.qdot"][row]), mu=float(res["physics.mu"][row]))
        final = symvib.simulate(scene).sensitivities(wrt=WRT).final
        for quantity in QUANTITIES:
            for j, p in enumerate(WRT):
                assert res[f"d_{quantity}_d_{p}"][row] == pytest.approx(final[quantity][j], rel=1e-12, abs=1e-15)
    assert np.all(res["sensitivity_reason"] == 0)


def test_a_difference_across_neighbouring_scenes_agrees_to_the_step_s_order():
    # t_final(qdot0) on rows 7 + h * (-2, -1, 0, 1, 2): central differences with steps h and 2h differ
    # from the middle row's exact derivative by O(h^2), so the error of 2h is about 4 times that of h.
    h = 2e-3
    res = sweep(BASE, {"qdot": f"{7 - 2 * h}:{7 + 2 * h}:5"}, backend="python", sensitivities=("qdot0",))
    assert len(set(res["events"].tolist())) == 1                 # one event sequence across the rows
    for quantity in ("t_final", "q_final", "friction_work"):
        y, exact = res[quantity], res[f"d_{quantity}_d_qdot0"][2]
        err_h = abs((y[3] - y[1]) / (2 * h) - exact)
        err_2h = abs((y[4] - y[0]) / (4 * h) - exact)
        assert err_2h <= 1e-3 * abs(exact) and 2.5 < err_2h / err_h < 6.5, (quantity, exact, err_h, err_2h)


def test_rows_without_derivatives_are_nan_and_say_why():
    zeno = scene_from_dict({"curve": {"shape": "parabola"}, "parameters": {"p": 1.0},
                            "physics": {"alpha0": 0.05, "restitution": 0.8}, "limiters": {"right": -0.3},
                            "initial": {"q": -0.6, "qdot": 0.5}})
    res = sweep(zeno, {"t_max": "0.5,100"}, backend="python", sensitivities=("mu", "qdot0"))
    stopped, accumulated = 0, 1
    assert REASONS[res["sensitivity_reason"][stopped]].startswith("the run did not end at rest")
    # the bounces shrink onto the limiter: the first event without derivatives grazes it, then the series
    first = next(why for why in symvib.simulate(zeno).sensitivities(wrt=("mu",)).reasons if why)
    assert "grazing" in first and "grazing" in REASONS[res["sensitivity_reason"][accumulated]]
    assert np.all(np.isnan(res["d_t_final_d_mu"])) and np.all(np.isnan(res["d_q_final_d_qdot0"]))
    at_rest = sweep(BASE.replace(qdot0=0.0, q0=0.5), {"mu": "0.05,0.06"}, backend="python",
                    sensitivities=("mu", "qdot0"))
    assert np.all(np.isfinite(at_rest["d_t_final_d_mu"])) and np.all(np.isnan(at_rest["d_t_final_d_qdot0"]))
    assert "starts at rest" in REASONS[at_rest["sensitivity_reason"][0]]


@pytest.mark.parametrize("wrt, match", [(("nu",), "sensitivities: 'nu'"), (("mu", "mu"), "distinct"),
                                        ("mu,left", "no left limiter"), (5, r"give parameter names .* got 5"),
                                        (1.5, "give parameter names"), ([1], "sensitivities: 1: give distinct"),
                                        (b"mu", "sensitivities: 109"), ("mu;k", "'mu;k': give distinct"),
                                        ("mu,,mu", "distinct"), ("MU", "'MU'"), ("\u03bc", "sensitivities: '\u03bc'"),
                                        ("mu_s", "'mu_s'"), ("__import__('os').system('true')", "give distinct")])
def test_bad_sensitivity_names_are_refused_naming_the_option(wrt, match):
    scene = resolve_scene("paper-circle-3.8")          # no left limiter
    with pytest.raises(SceneError, match=match):
        make_spec(scene, {"qdot": "3:4:2"}, sensitivities=wrt)


@pytest.mark.parametrize("storage", ["npz", "zarr"])
def test_a_sweep_without_them_keeps_its_definition_and_a_folder_keeps_them(tmp_path, storage):
    if storage == "zarr":
        pytest.importorskip("zarr")
        pytest.importorskip("xarray")
    plain = make_spec(BASE, {"qdot": "3:4:2"})
    assert "sensitivities" not in plain.to_dict()
    out = tmp_path / "sw"
    first = sweep(BASE, {"qdot": "6,7"}, backend="python", sensitivities=("k",), out=out, storage=storage)
    again = load_sweep(out)
    assert again.spec.sensitivities == ("k",)
    assert np.array_equal(again["d_t_final_d_k"], first["d_t_final_d_k"])
    assert again["sensitivity_reason"].dtype == np.int64
    manifest = json.loads((out / "manifest.json").read_text(encoding="utf-8"))
    assert manifest["definition"]["sensitivities"] == ["k"]
    if storage == "zarr":
        from symvib.numeric.sweep import open_sweep

        ds = open_sweep(out)
        assert np.array_equal(ds["d_q_final_d_k"].values, first["d_q_final_d_k"])
        assert ds["d_t_final_d_k"].attrs["long_name"] == "derivative of t_final with respect to k"


def test_symvib_sweep_sensitivities_on_the_command_line(tmp_path):
    out = tmp_path / "cli"
    run = subprocess.run([sys.executable, "-m", "symvib.cli", "sweep", "paper-parabola", "--vary", "qdot=6,7",
                          "--sensitivities", "mu,k", "--backend", "python", "--quiet", "-o", str(out)],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    res = load_sweep(out)
    assert {"d_t_final_d_mu", "d_impact_loss_d_k", "sensitivity_reason"} <= set(res.columns)
    bad = subprocess.run([sys.executable, "-m", "symvib.cli", "sweep", "paper-parabola", "--vary", "qdot=6,7",
                          "--sensitivities", "mu,nu", "-o", str(tmp_path / "bad")],
                         capture_output=True, text=True, timeout=600)
    assert bad.returncode == 2 and "sensitivities" in bad.stderr


@pytest.mark.parametrize("value, match", [("mu", "must be a list"), (["nu"], "'nu'"), ([1], "must be a list")])
def test_a_definition_with_bad_sensitivities_is_refused_naming_the_key(value, match):
    from symvib.numeric.sweep import SweepError, SweepSpec

    definition = make_spec(BASE, {"qdot": "3:4:2"}, sensitivities=("mu",)).to_dict()
    definition["sensitivities"] = value
    with pytest.raises(SweepError, match=f"definition.sensitivities.*{match}"):
        SweepSpec.from_dict(definition)


@pytest.mark.parametrize("axis, values, base", [("mu_s", "0.2,0.3", BASE), ("physics.mu_s", "0.1,0.25", BASE),
                                                ("alpha0_s", "0.2,0.3", BASE.replace(mu_s=0.3))])
def test_a_sweep_of_static_friction_has_each_row_s_single_scene_sensitivities(axis, values, base):
    res = sweep(base, {axis: values}, backend="python", sensitivities=("mu", "k"))
    field = "physics." + axis.split(".")[-1]
    for row in range(2):
        scene = base.replace(**{field.split(".")[1]: float(res[field][row])})
        final = symvib.simulate(scene).sensitivities(wrt=("mu", "k")).final
        assert res["d_t_final_d_mu"][row] == pytest.approx(final["t_final"][0], rel=1e-12)
        assert res["d_q_final_d_k"][row] == pytest.approx(final["q_final"][1], rel=1e-12, abs=1e-15)


def test_every_sweepable_field_has_a_scene_attribute_for_the_sensitivity_rows():
    from symvib.numeric.sweep.axes import FIELDS
    from symvib.numeric.sweep.sensitivity_columns import SCENE_ATTRIBUTES

    assert set(FIELDS) == set(SCENE_ATTRIBUTES)


# --- a sweep of unilateral scenes: the landing loss's derivatives, and why flights have none ---------

def test_a_unilateral_sweep_differentiates_the_landing_loss_as_the_single_scene_does():
    from test_flight import random_scene

    scene, name = random_scene(random.Random(5), 0)     # a circle: lifts off, lands, slides on to an arrest
    assert name == "circle"
    res = sweep(scene, {"qdot": f"{scene.qdot0 * 0.999},{scene.qdot0}"}, backend="python", sensitivities=("mu", "q0"))
    assert column_names(("mu", "q0"), scene)[-3:] == ["d_landing_loss_d_mu", "d_landing_loss_d_q0",
                                                      "sensitivity_reason"]
    assert [c for c in res.columns if c.startswith("d_")] == column_names(("mu", "q0"), scene)[:-1]
    for row in (0, 1):
        assert res["landings"][row] >= 1 and res["landing_loss"][row] > 0
        final = symvib.simulate(scene.replace(qdot0=float(res["initial.qdot"][row]))).sensitivities(
            wrt=("mu", "q0")).final
        for quantity in QUANTITIES + FLIGHT_QUANTITIES:
            for j, p in enumerate(("mu", "q0")):
                assert res[f"d_{quantity}_d_{p}"][row] == pytest.approx(final[quantity][j], rel=1e-12, abs=1e-15)
    assert np.all(np.isfinite(res["d_landing_loss_d_mu"])) and np.all(res["sensitivity_reason"] == 0)
    assert "d_landing_loss_d_mu" not in column_names(("mu",), BASE)       # (a bilateral sweep has none)


def test_a_bouncing_ball_accumulation_has_its_own_reason_code_in_a_sweep():
    bounces = scene_from_dict({"curve": {"shape": "circle"}, "parameters": {"R": 1.0},
                               "physics": {"mu": 0.1, "restitution": 0.8, "contact": "unilateral",
                                           "restitution_curve": 0.3},
                               "initial": {"q": 0.0, "qdot": 7.0}})
    res = sweep(bounces, {"qdot": "7"}, backend="python", sensitivities=("mu",))
    assert REASONS[res["sensitivity_reason"][0]] == "a bouncing-ball accumulation"
    assert np.isnan(res["d_landing_loss_d_mu"][0])


@pytest.mark.parametrize("reason, code", [
    (TANGENTIAL_LANDING_REASON, 11), (STICK_EDGE_REASON, 12), (ACCUMULATION_REASON, 13),
    ("a Zeno accumulation of impacts (infinitely many events)", 4), ("something new", OTHER_REASON)])
def test_each_flight_reason_has_its_code_and_old_codes_keep_their_meaning(reason, code):
    assert reason_code(reason) == code
    assert REASONS[OTHER_REASON].startswith("another reason") and REASONS[9].endswith("no derivative in qdot0")
