"""The compiled quadratures of exact sensitivities (symvib/numeric/sensitivity_compiled.py) against the NumPy
ones (symvib/numeric/sensitivity_batch.py, the reference): the same levels and refinement decisions, so the
same derivatives to rounding, on the paper's scenes, user curves with one and two limiters, both branches
and a sign change of ``N``; and which runs take them (physics.md, "Sensitivities" 2, 5)."""
import warnings
from types import SimpleNamespace

import numpy as np
import pytest

import symvib
from symvib.numeric import sensitivity, sensitivity_batch, sensitivity_compiled
from symvib.numeric.layout import EventCode
from symvib.numeric.prepared import prepared_of
from symvib.numeric.scene import resolve_scene, scene_from_dict
from symvib.numeric.sensitivity import PARAMETERS, interval_tangents
from symvib.numeric.sensitivity_compiled import Quadratures, quadratures, quadratures_for
from symvib.numeric.sensitivity_curve import CurveFunctions, resolve_wrt

pytest.importorskip("numba")

#: Agreement of the compiled quadratures with NumPy's, relative to each column's largest entry (the same
#: nodes, levels and decisions; sums in another order, kernels from ``math`` instead of NumPy).
SAME = 1e-13
PAPER = [(name, k) for name in ("paper-parabola", "paper-cycloid", "paper-circle-7", "paper-circle-3.8")
         for k in (1.0, 0.8)]
HUMP = {"curve": {"name": "sens-compiled-hump", "z": "a*(1 - cos(x/b))"}, "parameters": {"a": 0.3, "b": 0.2},
        "physics": {"mu": 0.05, "restitution": 0.7}, "limiters": {"left": -1.5, "right": 1.5},
        "initial": {"q": 0.0, "qdot": 4.0}}
ONE_LIMITER = {**HUMP, "limiters": {"right": 0.3}, "initial": {"q": -0.2, "qdot": 3.0}}
CIRCLE_N = {"curve": {"shape": "circle"}, "parameters": {"R": 0.5},      # sign changes of N
            "physics": {"alpha0": 0.02, "restitution": 1.0}, "initial": {"q": 0.0, "qdot": 11.0},
            "limiters": {"right": 2.5}}
FLIGHTS = {"curve": {"shape": "circle"}, "parameters": {"R": 1.0},      # lift-offs, bounces, an accumulation
           "physics": {"mu": 0.1, "restitution": 0.8, "contact": "unilateral", "restitution_curve": 0.3},
           "initial": {"q": 0.0, "qdot": 7.0}}
SCENES = ([resolve_scene(n).replace(k=k) for n, k in PAPER]
          + [scene_from_dict(d) for d in (HUMP, ONE_LIMITER, CIRCLE_N, FLIGHTS)])
IDS = [f"{n}-k{k}" for n, k in PAPER] + ["user-two-limiters", "user-one-limiter", "circle-sign-change-of-N",
                                          "flights"]


def _run(scene):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return symvib.simulate(scene, backend="python", samples=False)


def _scene_wrt(scene):
    return [p for p in PARAMETERS if not (p in ("left", "right") and getattr(scene, p) is None)]


def _both(res, wrt, monkeypatch, **kwargs):
    """The tangents of ``res`` with the compiled quadratures and with NumPy's."""
    kernels = prepared_of(res.scene).kernels
    monkeypatch.setattr(sensitivity, "quadratures_for",
                        lambda result, k, c, **_: Quadratures(quadratures(kernels), c._cp))
    fast = interval_tangents(res, wrt, **kwargs)
    monkeypatch.setattr(sensitivity, "quadratures_for", lambda *args, **_: None)
    return fast, interval_tangents(res, wrt, **kwargs)


def _assert_same(a, b):
    if np.all(np.isnan(b)):
        assert np.all(np.isnan(a))
        return
    scale = np.nanmax(np.abs(b), axis=0, initial=0.0) + 1e-300
    assert np.array_equal(np.isnan(a), np.isnan(b))
    assert np.all(np.nan_to_num(np.abs(a - b)) <= SAME * scale), np.nanmax(np.abs(a - b) / scale)


@pytest.mark.parametrize("scene", SCENES, ids=IDS)
def test_the_compiled_quadratures_give_numpy_s_derivatives(scene, monkeypatch):
    res = _run(scene)
    fast, ref = _both(res, _scene_wrt(scene), monkeypatch)
    f, r = fast.sensitivities, ref.sensitivities
    assert r.reasons == f.reasons and np.any(np.isfinite(r.t))
    for a, b in ((f.t, r.t), (f.q, r.q), (f.v_before, r.v_before), (f.v_after, r.v_after)):
        _assert_same(a, b)
    for name in r.final:
        _assert_same(f.final[name], r.final[name])
    branches = {leg.interval.s for leg in ref.legs}
    assert len(fast.legs) == len(ref.legs) and branches <= {1, -1}


def test_the_scenes_cover_both_branches_and_a_sign_change_of_n():
    branches, kinds = set(), set()
    for scene in SCENES:
        res = _run(scene)
        kinds |= {e.kind.value for e in res.events}
        branches |= {leg.interval.s for leg in interval_tangents(res, ("mu",)).legs}
    assert branches == {1, -1} and "normal_sign_change" in kinds


def test_a_truncated_table_is_the_same_on_both_paths(monkeypatch):
    scene = resolve_scene("paper-parabola").replace(k=0.95, mu=0.01)
    res = _run(scene)
    fast, ref = _both(res, ("mu", "k", "qdot0", "right"), monkeypatch, through=20)
    _assert_same(fast.sensitivities.t, ref.sensitivities.t)
    assert np.all(np.isnan(ref.sensitivities.t[21:]))


@pytest.mark.parametrize("accept", [1.0, -1.0])
def test_failures_end_the_derivatives_alike(accept, monkeypatch):
    # No level converges (RTOL < 0): past BATCH_PANELS each interval keeps its best pair of levels
    # within ACCEPT (1: all do), or fails (< 0: the first does, and the derivatives end there).
    scene = resolve_scene("paper-circle-7")
    res = _run(scene)
    c = CurveFunctions(prepared_of(scene).kernels, scene, resolve_wrt(scene, ("mu", "k")))
    ends = _ends(res, ("mu", "k"))
    for module in (sensitivity_batch, sensitivity_compiled):
        monkeypatch.setattr(module, "RTOL", -1.0)
        monkeypatch.setattr(module, "ACCEPT", accept)
    ref = sensitivity_batch.time_derivatives(c, ends)
    c.quadratures = Quadratures(quadratures(prepared_of(scene).kernels), c._cp)
    fast = sensitivity_batch.time_derivatives(c, ends)
    assert len(ref) > 2 and np.all(np.isfinite(ref) if accept > 0 else np.isnan(ref))
    _assert_same(fast, ref)


def test_a_non_finite_level_fails_its_interval_only(monkeypatch):
    scene = resolve_scene("paper-parabola")
    res = _run(scene)
    c = CurveFunctions(prepared_of(scene).kernels, scene, resolve_wrt(scene, ("mu", "qdot0")))
    ends = _ends(res, ("mu", "qdot0"))
    ends["G_a"][1] = -1.0          # (w < 0 at the start: the integrand is NaN)
    with np.errstate(invalid="ignore"):
        ref = sensitivity_batch.time_derivatives(c, ends)
    c.quadratures = Quadratures(quadratures(prepared_of(scene).kernels), c._cp)
    fast = sensitivity_batch.time_derivatives(c, ends)
    _assert_same(fast, ref)
    assert np.all(np.isnan(ref[1])) and np.all(np.isfinite(np.delete(ref, 1, axis=0)))


def _ends(res, wrt):
    """The arrays :func:`time_derivatives` reads, of the run's intervals (their tangents from the run's legs)."""
    legs = interval_tangents(res, wrt).legs
    return {name: np.array([getattr(leg.interval, name) for leg in legs]) for name in sensitivity.BATCH_FIELDS}


def test_only_runs_of_the_compiled_engine_without_curve_parameters_take_them():
    scene = resolve_scene("paper-parabola")
    kernels = prepared_of(scene).kernels
    plain = CurveFunctions(kernels, scene, resolve_wrt(scene, ("mu", "k")))
    curve = CurveFunctions(kernels, scene, resolve_wrt(scene, ("mu", "p")))
    numba_run, plain_run = SimpleNamespace(stats={"backend": "numba"}), SimpleNamespace(stats={"backend": "python"})
    assert isinstance(quadratures_for(numba_run, kernels, plain, compile=True), Quadratures)
    assert quadratures_for(plain_run, kernels, plain, compile=True) is None   # a plain run never waits for one
    assert quadratures_for(numba_run, kernels, curve, compile=True) is None   # curve parameters: NumPy's path
    view = SimpleNamespace(PARAMS=kernels.PARAMS)                              # (a prepared view: no file)
    assert quadratures_for(numba_run, view, plain, compile=True) is None


def test_one_call_takes_them_only_where_they_are_compiled_and_a_fit_compiles_them(tmp_path, monkeypatch):
    monkeypatch.setenv("SYMVIB_CACHE", str(tmp_path))                    # (no markers of other runs)
    scene = resolve_scene("paper-parabola")
    c = CurveFunctions(prepared_of(scene).kernels, scene, resolve_wrt(scene, ("mu", "k")))
    fresh = SimpleNamespace(__file__="parabola.py", PARAMS=("p",), __name__="fresh", INPUT_HASH="0" * 64)
    monkeypatch.setattr(sensitivity_compiled, "quadratures", lambda module: {})      # (no compile here)
    numba_run = SimpleNamespace(stats={"backend": "numba"})
    assert not sensitivity_compiled.compiled_on_disk(fresh)
    assert quadratures_for(numba_run, fresh, c) is None                 # one call: NumPy's, no compile
    assert isinstance(quadratures_for(numba_run, fresh, c, compile=True), Quadratures)     # a fit's
    for entry in sensitivity_compiled.MARKED:                           # (what a first call leaves)
        marker = sensitivity_compiled.compiled_marker(fresh, entry)
        marker.parent.mkdir(parents=True, exist_ok=True)
        marker.touch()
    assert sensitivity_compiled.compiled_on_disk(fresh)
    assert isinstance(quadratures_for(numba_run, fresh, c), Quadratures)          # then one call takes them


def test_a_first_compiled_call_leaves_its_marker(tmp_path, monkeypatch):
    from symvib.numeric.engine.bind import marking

    monkeypatch.setenv("SYMVIB_CACHE", str(tmp_path))
    marker = tmp_path / "engines" / "m"
    calls = []
    marked = marking(lambda *a: calls.append(a) or 7, marker)
    assert not marker.exists() and marked(1, 2) == 7 and marker.exists() and calls == [(1, 2)]


@pytest.mark.parametrize("name", ["paper-parabola", "paper-circle-7"])
def test_the_compiled_pass_over_events_is_the_python_loop_bit_for_bit(name, monkeypatch):
    scene = resolve_scene(name).replace(k=0.8)
    res = _run(scene)
    kernels = prepared_of(scene).kernels
    wrt = _scene_wrt(scene)
    monkeypatch.setattr(sensitivity, "quadratures_for",
                        lambda result, k, c, **_: Quadratures(quadratures(kernels), c._cp))
    fast = interval_tangents(res, wrt)
    monkeypatch.setattr(sensitivity, "JETS_EVENTS", tuple(EventCode))     # (every event: the Python loop)
    slow = interval_tangents(res, wrt)
    f, s = fast.sensitivities, slow.sensitivities
    for a, b in ((f.t, s.t), (f.q, s.q), (f.v_before, s.v_before), (f.v_after, s.v_after), *(
            (f.final[k], s.final[k]) for k in s.final)):
        assert np.array_equal(a, b, equal_nan=True)
    assert len(fast.legs) == len(slow.legs) > 3
    for a, b in zip(fast.legs, slow.legs):
        for field in ("Dq_a", "Dw_a", "DG_a", "A", "Dq_e", "DG_e"):
            assert np.array_equal(getattr(a.interval, field), getattr(b.interval, field))
