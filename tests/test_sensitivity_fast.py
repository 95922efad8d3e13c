"""The fast path of exact sensitivities (symvib/numeric/sensitivity_batch.py, ``through=``) against the
full one: the batched time quadratures equal each interval's own refinement, and a truncated table
equals the full table on the events it keeps (physics.md, "Sensitivities")."""
import warnings

import numpy as np
import pytest

import symvib
from symvib.numeric.scene import resolve_scene, scene_from_dict
from symvib.numeric.sensitivity import PARAMETERS, interval_tangents, sensitivities
from symvib.numeric.sweep import sweep

#: Agreement of the fast path with the full one, relative to each column's largest entry (rounding only:
#: the same Gauss levels, nodes and refinement decisions).
SAME = 1e-12
PAPER = [(name, k) for name in ("paper-parabola", "paper-cycloid", "paper-circle-7", "paper-circle-3.8")
         for k in (1.0, 0.8)]
FLIGHTS = {"curve": {"shape": "circle"}, "parameters": {"R": 1.0},      # lift-offs, bounces, an accumulation
           "physics": {"mu": 0.1, "restitution": 0.8, "contact": "unilateral", "restitution_curve": 0.3},
           "initial": {"q": 0.0, "qdot": 7.0}}
USER = {"curve": {"name": "sens-fast-hump", "z": "a*(1 - cos(x/b))"}, "parameters": {"a": 0.3, "b": 0.2},
        "physics": {"mu": 0.05, "restitution": 0.7}, "limiters": {"left": -1.5, "right": 1.5},
        "initial": {"q": 0.0, "qdot": 4.0}}


def _run(scene):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return symvib.simulate(scene)


def _wrt(scene):
    return [p for p in PARAMETERS if not (p in ("left", "right") and getattr(scene, p) is None)] + \
        [name for name, _ in scene.params]


def _assert_same(fast, full, rows):
    for a, b in zip(fast, full):
        scale = np.nanmax(np.abs(b[rows]), axis=0, initial=0.0) + 1e-300
        assert np.array_equal(np.isnan(a[rows]), np.isnan(b[rows]))
        assert np.all(np.nan_to_num(np.abs(a[rows] - b[rows])) <= SAME * scale), (a[rows] - b[rows]) / scale


@pytest.mark.parametrize("scene", [resolve_scene(n).replace(k=k) for n, k in PAPER]
                         + [scene_from_dict(USER), scene_from_dict(FLIGHTS)],
                         ids=[f"{n}-k{k}" for n, k in PAPER] + ["user-hump", "flights"])
def test_batched_time_derivatives_equal_each_interval_s_own_refinement(scene):
    tangents = interval_tangents(_run(scene), _wrt(scene))
    assert tangents.legs
    for leg in tangents.legs:     # (the per-interval quadrature, Interval.dT, is the reference)
        own, batched = leg.interval.dT(), leg.Dt_e - leg.Dt_a
        scale = np.max(np.abs(own)) + 1e-300
        assert np.all(np.abs(batched - own) <= SAME * scale), (batched - own) / scale


@pytest.mark.parametrize("scene", [resolve_scene(n).replace(k=k) for n, k in PAPER]
                         + [scene_from_dict(USER), scene_from_dict(FLIGHTS)],
                         ids=[f"{n}-k{k}" for n, k in PAPER] + ["user-hump", "flights"])
def test_a_truncated_table_equals_the_full_one_on_its_events(scene):
    res = _run(scene)
    full = sensitivities(res, _wrt(scene))
    n = len(res.events)
    for through in sorted({0, n // 2, n - 2}):
        if through < 0:
            continue
        part = sensitivities(res, _wrt(scene), through=through)
        keep = slice(0, through + 1)
        _assert_same((part.t, part.q, part.v_before, part.v_after), (full.t, full.q, full.v_before, full.v_after),
                     keep)
        assert part.reasons[keep] == full.reasons[keep]
        assert all(r.startswith("not asked for") for r in part.reasons[through + 1:])
        assert np.all(np.isnan(part.t[through + 1:])) and np.all(np.isnan(part.final["t_final"]))
    last = sensitivities(res, _wrt(scene), through=n + 5)       # beyond the end: the full table
    _assert_same((last.t, last.q), (full.t, full.q), slice(None))
    assert np.array_equal(last.final["t_final"], full.final["t_final"], equal_nan=True)


@pytest.mark.parametrize("through", [-1, 1.5, True, "3"])
def test_a_bad_through_is_refused_naming_it(through):
    with pytest.raises(ValueError, match="through: "):
        sensitivities(_run(resolve_scene("paper-parabola")), ("mu",), through=through)


@pytest.mark.parametrize("name, wrt", [("paper-parabola", ("p", "mu")), ("paper-cycloid", ("parameters.R", "k")),
                                       ("paper-circle-7", ("R", "qdot0"))])
def test_sweep_columns_of_curve_parameters_are_result_sensitivities(name, wrt):
    base = resolve_scene(name).replace(k=0.8)
    res = sweep(base, {"qdot": f"{base.qdot0}:{base.qdot0 * 1.02}:2"}, backend="python", sensitivities=wrt)
    for row in range(2):
        final = _run(base.replace(qdot0=float(res["initial.qdot"][row]))).sensitivities(wrt=wrt).final
        for quantity, values in final.items():
            for j, p in enumerate(wrt):
                assert res[f"d_{quantity}_d_{p}"][row] == pytest.approx(values[j], rel=1e-12, abs=1e-15), (quantity, p)
    assert np.all(res["sensitivity_reason"] == 0)


def test_the_option_s_text_names_curve_parameters_and_refuses_an_ambiguous_one():
    from symvib.numeric.scene import SceneError
    from symvib.numeric.sweep import make_spec

    spec = make_spec(resolve_scene("paper-parabola"), {"qdot": "6:7:2"}, sensitivities="mu,parameters.p")
    assert spec.sensitivities == ("mu", "parameters.p")
    ambiguous = scene_from_dict({"curve": {"name": "sens-fast-k", "z": "k*x**2"}, "parameters": {"k": 0.5},
                                 "physics": {"mu": 0.05, "restitution": 0.8}, "limiters": {"right": 0.5},
                                 "initial": {"q": 0.0, "qdot": 1.0}})
    with pytest.raises(SceneError, match="sensitivities: 'k' is ambiguous"):
        make_spec(ambiguous, {"qdot": "1:2:2"}, sensitivities="k")
    with pytest.raises(SceneError, match="sensitivities: 'q': give distinct names from mu, k, .*, right, p"):
        make_spec(resolve_scene("paper-parabola"), {"qdot": "6:7:2"}, sensitivities="q")


@pytest.mark.parametrize("scene", [resolve_scene("paper-parabola").replace(k=0.8), scene_from_dict(USER)],
                         ids=["paper-parabola-k0.8", "user-hump"])
def test_early_samples_are_differentiated_as_among_later_ones(scene):
    from symvib.numeric.sample_sensitivity import sample_sensitivities

    res = _run(scene)
    t_end = res.events[-1].t
    early = np.linspace(0.01, 0.3, 7) * t_end
    alone = sample_sensitivities(res, early, _wrt(scene), "xz")      # differentiated up to those samples only
    among = sample_sensitivities(res, np.concatenate([early, [0.9 * t_end]]), _wrt(scene), "xz")
    assert alone.reasons == among.reasons[:len(early)]
    a, b = alone.derivatives, among.derivatives[:len(early)]
    assert np.array_equal(np.isnan(a), np.isnan(b))
    assert np.all(np.nan_to_num(np.abs(a - b)) <= SAME * (np.nanmax(np.abs(b), axis=0) + 1e-300))


@pytest.mark.parametrize("scene", [resolve_scene(n).replace(k=0.8) for n in ("paper-parabola", "paper-circle-3.8")]
                         + [scene_from_dict(USER)], ids=["paper-parabola", "paper-circle-3.8", "user-hump"])
def test_the_difference_of_f_gives_what_the_integral_of_its_derivative_does(scene, monkeypatch):
    # f(q) - f(q_c) away from the ends is F_s' itself, not the integral of F_s'': the same time derivatives
    # as integrating everywhere (DIFFERENCE_RTOL = 0 never switches), within the levels' own agreement
    # (RTOL: a short swing between two turning points, paper-circle-3.8's arrest, differs by 1.3e-11).
    from symvib.numeric import sensitivity, sensitivity_batch

    monkeypatch.setattr(sensitivity, "quadratures_for", lambda *args, **_: None)     # (NumPy's levels)
    res = _run(scene)
    switching = interval_tangents(res, _wrt(scene)).sensitivities
    monkeypatch.setattr(sensitivity_batch, "DIFFERENCE_RTOL", 0.0)
    integrating = interval_tangents(res, _wrt(scene)).sensitivities
    for a, b in ((switching.t, integrating.t), (switching.q, integrating.q), (switching.v_after, integrating.v_after)):
        scale = np.nanmax(np.abs(b), axis=0, initial=0.0) + 1e-300
        assert np.array_equal(np.isnan(a), np.isnan(b))
        assert np.all(np.nan_to_num(np.abs(a - b)) <= sensitivity_batch.RTOL * scale), (a - b) / scale
    assert np.any(np.abs(switching.t - integrating.t) > 0)      # (the switch was taken)


def test_the_difference_of_f_is_taken_only_where_it_rises_above_its_rounding():
    from symvib.numeric.sensitivity_batch import DIFFERENCE_RTOL, EPS, NEAR_END, switched

    x = np.array([0.2 * NEAR_END, 0.5 * NEAR_END, NEAR_END, 2 * NEAR_END, 0.3, 0.5])
    f_c = 2.0
    rising = f_c + np.array([1e-3, 1e-2, 0.05, 0.1, 0.3, 0.0])      # (back at f_c at the last node)
    assert switched(x, rising, f_c).tolist() == [False, False, True, True, True, True]
    tiny = f_c + 1e4 * EPS * x                 # an interval of a few ulps: the difference is rounding
    assert not switched(x, tiny, f_c).any()
    edge = f_c + 4 * EPS / DIFFERENCE_RTOL * np.array([0.0, 0.0, 0.5, 1.5, 1.5, 1.5])
    assert switched(x, edge, f_c).tolist() == [False, False, False, True, True, True]
    rows = switched(x, np.vstack([rising, tiny]), np.array([f_c, f_c]))     # (one row per interval)
    assert rows[0].tolist() == switched(x, rising, f_c).tolist() and not rows[1].any()
