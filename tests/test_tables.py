"""A Result as tables (symvib/numeric/tables.py), solve_ivp's names, and the examples of the
README's "Results as tables" and of docs/results.md."""
import dataclasses
import sys
from pathlib import Path

import numpy as np
import pytest
from readme_blocks import code_blocks, run_section

import symvib
from symvib import simulate
from symvib.numeric.events import EventKind, Samples
from symvib.numeric.layout import EVENT_KINDS, EventCode
from symvib.numeric.scene import resolve_scene

pd = pytest.importorskip("pandas")

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def result():
    return simulate(resolve_scene("paper-parabola"), backend="python")


def test_events_frame_columns_dtypes_and_values(result):
    frame = result.events_frame()
    assert list(frame.columns) == ["kind", "t", "t_err", "q", "qdot_before", "qdot_after", "energy", "detail"]
    assert isinstance(frame["kind"].dtype, pd.CategoricalDtype)
    assert list(frame["kind"].cat.categories) == list(EVENT_KINDS)
    for name in ("t", "t_err", "q", "qdot_before", "qdot_after", "energy"):
        assert frame[name].dtype == np.float64, name
        assert frame[name].tolist() == [getattr(e, name) for e in result.events]
    assert frame["detail"].dtype == object
    assert frame["kind"].tolist() == [e.kind.value for e in result.events]
    assert frame.index.name == "event" and len(frame) == len(result.events)
    assert (frame["kind"] == "impact").sum() == result.count(EventKind.IMPACT)
    assert frame.attrs["units"]["t"] == "s" and frame.attrs["units"]["q"] == "rad"
    assert frame.attrs["units"]["t_err"] == "s"


def test_samples_frame_follows_every_samples_field(result):
    frame = result.samples_frame()
    S = result.samples
    names = [f.name for f in dataclasses.fields(Samples)]
    assert list(frame.columns) == names
    for name in names:
        values = getattr(S, name)
        expected = np.int64 if values.dtype.kind in "iu" else np.float64
        assert frame[name].dtype == expected, name
        assert np.array_equal(frame[name].to_numpy(), values), name
    assert frame["interval"].dtype == np.int64 and frame["branch"].dtype == np.int64
    assert frame.index.name == "sample"
    assert all(frame.attrs["units"][n] for n in names), frame.attrs["units"]


def test_to_pandas_returns_both(result):
    events, samples = result.to_pandas()
    assert len(events) == len(result.events) and len(samples) == len(result.samples.t)


def test_a_run_of_one_event_keeps_the_dtypes():
    scene = resolve_scene("paper-parabola").replace(q0=0.0, qdot0=0.0)  # at rest at the bottom: one arrest
    frame = simulate(scene, backend="python").events_frame()
    assert frame["kind"].tolist() == ["arrest"] and frame["t"].dtype == np.float64


def test_missing_pandas_names_the_extra(result, monkeypatch):
    monkeypatch.setitem(sys.modules, "pandas", None)
    with pytest.raises(ImportError, match=r'symvib\[pandas\]'):
        result.events_frame()


def test_samples_frame_without_samples_says_how():
    r = simulate(resolve_scene("paper-cycloid"), samples=False, backend="python")
    with pytest.raises(ValueError, match="samples=True"):
        r.samples_frame()
    with pytest.raises(ValueError, match="samples=True"):
        r.t  # noqa: B018


def test_solve_ivp_names(result):
    S = result.samples
    assert np.array_equal(result.t, S.t)
    assert result.y.shape == (2, len(S.t))
    assert np.array_equal(result.y[0], S.q) and np.array_equal(result.y[1], S.qdot)
    assert len(result.t_events) == len(result.y_events) == len(EventCode)
    impacts = [e for e in result.events if e.kind is EventKind.IMPACT]
    assert result.t_events[EventCode.IMPACT].tolist() == [e.t for e in impacts]
    assert result.y_events[EventCode.IMPACT].shape == (len(impacts), 2)
    assert result.y_events[EventCode.IMPACT][:, 1].tolist() == [e.qdot_after for e in impacts]
    assert result.t_events[EventCode.LEFT_CURVE].shape == (0,)
    assert result.success and isinstance(result.message, str)


def test_readme_results_as_tables_runs(capsys):
    namespace = run_section("## Results as tables", "readme_results")
    out = capsys.readouterr().out
    events, result = namespace["events"], namespace["result"]
    counts = events.groupby("kind", observed=True).size()
    assert counts["impact"] == result.count(EventKind.IMPACT) == 10 and counts["reversal"] == 7
    assert "rad/s" in out
    assert namespace["q"].shape == (3,) and namespace["q"][2] == result.q_final  # t = 20 s: arrested
    assert namespace["y"].shape == (2, len(namespace["t_samples"]))
    assert abs(result.state(namespace["t"])[0] - 0.3) < 1e-12
    assert "0.052408 rad/s" in out  # tan(3 deg), and the unit of initial.qdot on a circle


def test_docs_results_side_by_side_runs(capsys):
    pytest.importorskip("scipy")
    blocks = code_blocks((ROOT / "docs" / "results.md").read_text(encoding="utf-8"))
    assert blocks
    namespace = {"__name__": "docs_results"}
    for block in blocks:
        exec(compile(block, "docs/results.md", "exec"), namespace)  # noqa: S102
    ivp, mine = namespace["ivp"], namespace["mine"]
    assert ivp.success and mine.shape == ivp.y.shape
    assert np.max(np.abs(mine - ivp.y)) < 1e-9  # DOP853 at rtol 1e-12 against the exact state
    assert "largest difference" in capsys.readouterr().out


def test_top_level_names_are_the_api():
    from symvib import api

    assert symvib.simulate is api.simulate and symvib.load_scene is api.load_scene and symvib.sweep is api.sweep
    scene = symvib.load_scene("paper-circle-3.8")
    assert symvib.load_scene(scene) is scene
    assert symvib.load_scene(ROOT / "symvib" / "scenes" / "paper-circle-3.8.toml") == scene
    assert symvib.simulate(scene, backend="python").events == simulate(scene, backend="python").events
    with pytest.raises(TypeError, match="load_scene"):
        symvib.load_scene(42)
