"""Exact event sensitivities (symvib/numeric/sensitivity.py) against a step study of central differences.

Every derivative must agree to 1e-7 (relative to its size, or to the largest derivative of its
column where it is about 0) with some Richardson-extrapolated central difference of the engine's
own runs, over steps halved six times: a wrong derivative matches none of them, and the study
finds the step where truncation and the runs' 1e-12 rounding balance (next to a slow impact the
differences converge only at small steps).
"""
import math
import warnings

import numpy as np
import pytest

from symvib import simulate
from symvib.numeric.events import EventKind
from symvib.numeric.scene import resolve_scene, scene_from_dict
from symvib.numeric.sensitivity import PARAMETERS, sensitivities

TOL = 1e-7
HALVINGS = 6
#: First step of each parameter's study, relative to its scale.
FIRST_STEP = 1e-3


def observed(scene, n_events):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = simulate(scene, samples=False)
    if len(r.events) < n_events:
        return None
    t = np.array([e.t for e in r.events[:n_events]])
    q = np.array([e.q for e in r.events[:n_events]])
    return t, q, r.energy_budget.friction_work


def step_study(scene, name, n_events):
    """Richardson-extrapolated central differences of (event times, event positions, friction
    work) with respect to ``name``, one estimate per step."""
    x = getattr(scene, name)
    scale = {"mu": max(scene.mu, 0.01), "k": 1.0, "qdot0": max(abs(scene.qdot0), 0.1)}.get(name, 1.0)
    if name in ("q0", "left", "right"):
        scale = float(simulate_scale(scene))
    steps = [FIRST_STEP * scale / 2 ** j for j in range(HALVINGS + 1)]

    def central(d):
        plus, minus = observed(scene.replace(**{name: x + d}), n_events), \
            observed(scene.replace(**{name: x - d}), n_events)
        if plus is None or minus is None:
            return None
        return [(a - b) / (2 * d) for a, b in zip(plus, minus)]

    D = [central(d) for d in steps]
    out = []
    for coarse, fine in zip(D, D[1:]):
        if coarse is not None and fine is not None:
            out.append([(4 * f - c) / 3 for c, f in zip(coarse, fine)])
    return out


def simulate_scale(scene):
    from symvib.numeric.prepared import prepared_of

    return prepared_of(scene).kernels.q_scale_scalar(*scene.param_values)


def assert_matches_step_study(scene, wrt=None):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = simulate(scene)
    if wrt is None:
        wrt = [p for p in PARAMETERS if not (p in ("left", "right") and getattr(scene, p) is None)
               and not (p == "k" and scene.k == 1.0) and not (p == "qdot0" and scene.qdot0 == 0)]
    sens = sensitivities(res, wrt=wrt)
    good = [i for i, why in enumerate(sens.reasons) if not why]
    assert good, sens.reasons
    n = good[-1] + 1
    compared = 0
    for j, name in enumerate(wrt):
        study = step_study(scene, name, n)
        assert study, f"{name}: every perturbed run changed its events"
        exact = [sens.t[:n, j], sens.q[:n, j]]
        final = not math.isnan(sens.final["friction_work"][j])
        for which, a in enumerate(exact):
            # where a derivative is about 0, the runs' rounding (1e-12 over steps down to 1.5e-5)
            # is what the differences show: compare to the column's size, at least 1e-5
            floor = max(1e-4 * np.max(np.abs(a)), 1e-5)
            for i in range(n):
                err = min(abs(est[which][i] - a[i]) for est in study)
                assert err <= TOL * max(abs(a[i]), floor), (name, ("t", "q")[which], i, a[i],
                                                             [est[which][i] for est in study])
                compared += 1
        if final:
            a = sens.final["friction_work"][j]
            err = min(abs(est[2] - a) for est in study)
            assert err <= TOL * max(abs(a), 1e-5), (name, "friction_work", a, [est[2] for est in study])
    assert compared > 0
    return sens


def test_the_paper_parabola_s_event_derivatives_match_a_step_study():
    sens = assert_matches_step_study(resolve_scene("paper-parabola").replace(k=0.8))
    assert not any(sens.reasons)
    assert np.all(np.isfinite(sens.final["t_final"]))


@pytest.mark.slow
@pytest.mark.parametrize("name", ["paper-parabola", "paper-cycloid", "paper-circle-3.8", "paper-circle-7"])
@pytest.mark.parametrize("k", [1.0, 0.8])
def test_every_paper_scene_s_event_derivatives_match_a_step_study(name, k):
    sens = assert_matches_step_study(resolve_scene(name).replace(k=k))
    assert not any(sens.reasons), sens.reasons


USER_SCENES = {
    "bowl, two limiters": {"curve": {"name": "sens-bowl", "z": "R - sqrt(R**2 - x**2)", "domain": ["-R", "R"]},
                           "parameters": {"R": 0.5}, "physics": {"alpha0": 0.05, "restitution": 0.8},
                           "limiters": {"left": -0.2, "right": 0.35}, "initial": {"q": 0.1, "qdot": 3.0}},
    "quartic well, one limiter": {"curve": {"name": "sens-quartic", "z": "x**2/2 + x**4/4"},
                                  "physics": {"mu": 0.1, "restitution": 0.7},
                                  "limiters": {"right": 0.5}, "initial": {"q": -0.8, "qdot": 0.5}},
    "sine track, numeric F_sigma": {"curve": {"name": "sens-sine", "z": "a*(1 - cos(x/b))", "closed_form": "never"},
                                    "parameters": {"a": 0.3, "b": 0.2}, "physics": {"mu": 0.08, "restitution": 0.6},
                                    "limiters": {"left": -0.25, "right": 0.3}, "initial": {"q": 0.0, "qdot": 2.0}},
    "tilted parabola, one limiter": {"curve": {"name": "sens-tilted", "z": "x**2/2 + c*x"},
                                     "parameters": {"c": 0.2}, "physics": {"mu": 0.05, "restitution": 0.9},
                                     "limiters": {"left": -0.6}, "initial": {"q": 0.4, "qdot": -1.5}},
    "parametric ellipse, two limiters": {"curve": {"name": "sens-ellipse", "q": "u", "x": "a*sin(u)",
                                                   "z": "-b*cos(u)", "domain": ["-pi/2", "pi/2"]},
                                         "parameters": {"a": 1.0, "b": 0.6},
                                         "physics": {"mu": 0.06, "restitution": 0.75},
                                         "limiters": {"left": -0.9, "right": 1.0},
                                         "initial": {"q": 0.2, "qdot": 2.5}},
}


@pytest.mark.slow
@pytest.mark.parametrize("label", sorted(USER_SCENES))
def test_user_curve_event_derivatives_match_a_step_study(label):
    sens = assert_matches_step_study(scene_from_dict(USER_SCENES[label]))
    assert not any(sens.reasons), sens.reasons


@pytest.mark.slow
def test_a_zeno_run_s_events_before_the_accumulation_match_and_the_accumulation_says_why():
    scene = scene_from_dict({"curve": {"shape": "parabola"}, "parameters": {"p": 1.0},
                             "physics": {"alpha0": 0.05, "restitution": 0.8}, "limiters": {"right": -0.3},
                             "initial": {"q": -0.6, "qdot": 0.5}})
    sens = assert_matches_step_study(scene, wrt=("mu", "k", "qdot0", "right"))
    assert "Zeno" in sens.reasons[-1]
    first = next(i for i, why in enumerate(sens.reasons) if why)
    assert first > 5 and all(sens.reasons[first:])
    assert np.all(np.isnan(sens.t[first:]))


@pytest.mark.slow
def test_a_run_with_sign_changes_of_n_matches_before_and_after_them():
    # (more of them, the curve's parameters and a tangential zero of N: tests/test_sensitivity_jets.py)
    scene = scene_from_dict({"curve": {"shape": "circle"}, "parameters": {"R": 0.5},
                             "physics": {"alpha0": 0.02, "restitution": 1.0}, "initial": {"q": 0.0, "qdot": 11.0},
                             "limiters": {"right": 2.5}})
    res = simulate(scene)
    kinds = [e.kind for e in res.events]
    assert EventKind.NORMAL_SIGN_CHANGE in kinds
    sens = assert_matches_step_study(scene, wrt=("mu", "qdot0"))
    assert not any(sens.reasons) and np.all(np.isfinite(sens.t))


def test_a_start_at_rest_has_no_derivative_in_qdot0_and_says_why():
    scene = resolve_scene("paper-parabola").replace(qdot0=0.0, q0=0.5)
    sens = sensitivities(simulate(scene), wrt=("mu", "qdot0"))
    assert "starts at rest" in sens.notes["qdot0"]
    assert np.all(np.isnan(sens.t[:, 1])) and np.all(np.isnan(sens.final["t_final"][1]))
    assert np.all(np.isfinite(sens.t[:, 0])) and not any(sens.reasons)
    assert_matches_step_study(scene, wrt=("mu", "q0", "left"))      # the other columns hold


@pytest.mark.parametrize("wrt, match", [(("nu",), "nu"), (("mu", "mu"), "distinct"), ((), "distinct")])
def test_unknown_or_repeated_parameters_are_refused_naming_wrt(wrt, match):
    res = simulate("paper-parabola")
    with pytest.raises(ValueError, match=f"wrt: .*{match}"):
        sensitivities(res, wrt=wrt)


@pytest.mark.parametrize("wrt, match", [(5, "got int"), (None, "got NoneType"), ((5,), "5"), ("m", "'m'")])
def test_parameters_that_are_not_names_are_refused_naming_wrt(wrt, match):
    res = simulate("paper-parabola")
    with pytest.raises(ValueError, match=f"wrt: .*{match}"):
        sensitivities(res, wrt=wrt)


def test_one_name_is_one_parameter_not_its_letters():
    res = simulate("paper-parabola")
    one, listed = sensitivities(res, wrt="mu"), sensitivities(res, wrt=("mu",))
    assert one.wrt == ("mu",) and np.array_equal(one.t, listed.t, equal_nan=True)


def test_a_missing_limiter_is_refused_naming_it():
    res = simulate(resolve_scene("paper-circle-3.8"))       # no left limiter
    with pytest.raises(ValueError, match="no left limiter"):
        res.sensitivities(wrt=("left",))


def test_the_long_table_has_one_row_per_event_and_parameter():
    res = simulate("paper-parabola")
    sens = res.sensitivities(wrt=("mu", "k"))
    rows = sens.rows()
    assert len(rows) == 2 * len(res.events)
    assert {r["wrt"] for r in rows} == {"mu", "k"}
    assert rows[0]["dt"] == sens.t[0, 0]
    # k = 1 here: the impacts' speeds after depend on k, their times not before the first impact
    assert sens.t[0, 1] == 0.0 and sens.v_after[0, 1] != 0.0


def test_the_labelled_table_has_an_event_and_a_parameter_dimension():
    xr = pytest.importorskip("xarray")
    res = simulate("paper-parabola")
    sens = res.sensitivities(wrt=("mu", "qdot0"))
    ds = sens.to_xarray()
    assert isinstance(ds, xr.Dataset) and dict(ds.sizes) == {"event": len(res.events), "wrt": 2}
    assert float(ds.dt.sel(wrt="qdot0").isel(event=0)) == sens.t[0, 1]
    assert float(ds.t_final.sel(wrt="mu")) == float(ds.dt.sel(wrt="mu").isel(event=-1))
    assert list(ds.kind.values[:2]) == ["impact", "impact"]
    pytest.importorskip("pandas")
    frame = sens.to_dataframe()
    assert len(frame) == 2 * len(res.events) and set(frame["wrt"]) == {"mu", "qdot0"}


def test_an_arrest_decided_by_mu_s_has_the_kinetic_derivatives_and_its_edge_has_none():
    # The circle of tests/test_engine_static_friction.py: its first turning point PHI_T (closed form)
    # has mu < |tan PHI_T| < mu_s, so mu_s arrests it; where it lies depends on mu only (sliding).
    from test_engine_static_friction import MU, PHI_T, TAN_T, circle, turning_point_mp

    scene = circle(mu_s=0.6)
    res = simulate(scene, backend="python")
    assert [e.kind for e in res.events] == [EventKind.ARREST] and res.events[0].q == pytest.approx(PHI_T, abs=1e-10)
    sens = assert_matches_step_study(scene, wrt=("mu", "qdot0"))
    assert not any(sens.reasons)
    # d PHI_T / d mu of the closed form (mpmath differentiates it; mu_s stays 0.6, it decides nothing)
    import mpmath

    with mpmath.workdps(30):
        dq_dmu = float(mpmath.diff(lambda m: turning_point_mp(0.0, 2.5, +1, PHI_T, mu=m), MU))
    assert sens.q[0, 0] == pytest.approx(dq_dmu, rel=1e-7)
    # mu_s on the edge |tan PHI_T|: arrest or reversal flips with the parameters, no derivative
    edge = sensitivities(simulate(circle(mu_s=TAN_T), backend="python"), wrt=("mu",))
    assert "edge of the friction cone" in edge.reasons[0] and np.all(np.isnan(edge.q))
