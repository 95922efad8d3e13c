"""symvib bench: options, ratio, random scenes, peer budgets, shipped data, and (slow) the quick runs end to end."""
import csv
import importlib.util
from fnmatch import fnmatch
from importlib.resources import files
from pathlib import Path

import pytest
import tomllib

import symvib
from symvib.checks.bench.output import load_json
from symvib.checks.bench.paper_references import REFERENCE_NAME, reference_events
from symvib.checks.bench.scenes import RANDOM_MAX_EVENTS, paper_scenes, random_scenes, scene_key
from symvib.checks.bench.sequences import RANDOM_TRUTH_NAME
from symvib.checks.bench.work_precision_job import ratio_at_equal_accuracy
from symvib.checks.peers import solve_ivp_events
from symvib.checks.shipped import DATA_FOLDER, DATA_PACKAGE, shipped
from symvib.cli import main

#: The peers are scipy's integrators (the optional extra "bench"): their tests skip without it.
needs_scipy = pytest.mark.skipif(importlib.util.find_spec("scipy") is None, reason="needs the optional scipy")

ROOT = Path(__file__).resolve().parents[1]
DATA = files(DATA_PACKAGE) / DATA_FOLDER


def _package_state() -> dict:
    """Every data file of the installed package folder (what bench could write: not its Python
    sources, which an editable checkout may change meanwhile) with its size and modification time."""
    package = Path(symvib.__file__).resolve().parent
    return {p: (p.stat().st_size, p.stat().st_mtime_ns) for p in package.rglob("*")
            if p.is_file() and p.suffix not in (".py", ".pyc")}


def test_the_package_hands_on_the_names_of_the_old_module():
    """``symvib/checks/bench.py`` became the package ``symvib/checks/bench/``: every name it had
    still imports from ``symvib.checks.bench``, the same object as in its module."""
    from symvib.checks import bench
    from symvib.checks.bench.stability_job import stability
    from symvib.checks.bench.work_precision_job import work_precision

    assert (bench.shipped is shipped and bench.paper_scenes is paper_scenes and bench.work_precision is work_precision
            and bench.stability is stability and bench.REFERENCE_NAME == REFERENCE_NAME)
    assert all(hasattr(bench, name) for name in bench.__all__)


def test_bad_options_exit_2_with_one_line(capsys):
    assert main(["bench", "work-precision", "--workers", "0"]) == 2
    assert main(["bench", "no-such-job"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and all(line.startswith("symvib bench: error:") for line in err)


def test_out_that_is_a_file_is_refused_before_any_work(tmp_path, capsys):
    (tmp_path / "f").write_text("x", encoding="utf-8")
    assert main(["bench", "stability", "--out", str(tmp_path / "f")]) == 2
    assert "--out folder" in capsys.readouterr().err


def test_shipped_references_are_package_data():
    """The references ship inside the package (importlib.resources) and pyproject installs them."""
    assert shipped(REFERENCE_NAME) and shipped(RANDOM_TRUTH_NAME)
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    patterns = config["tool"]["setuptools"]["package-data"][DATA_PACKAGE]
    for name in (REFERENCE_NAME, RANDOM_TRUTH_NAME):
        assert (DATA / name).is_file()
        assert any(fnmatch(f"{DATA_FOLDER}/{name}", p) for p in patterns), name
    with pytest.raises(FileNotFoundError, match="symvib/checks/data/no-such.json"):
        shipped("no-such.json")


def test_a_computed_reference_goes_to_the_named_cache(tmp_path):
    """Recomputed references are stored in the file named, merged, never in the package."""
    label, scene = paper_scenes()[5]  # paper-circle-3.8 k=0.8: four events, under a second
    cache = tmp_path / "out" / REFERENCE_NAME
    before = _package_state()
    fresh = reference_events(scene, label=label, cached=False, cache=cache)
    stored = load_json(cache)
    assert list(stored) == [scene_key(scene)] and stored[scene_key(scene)]["scene"] == label
    assert reference_events(scene, cache=cache) == fresh
    assert _package_state() == before


def test_ratio_at_equal_accuracy():
    rows = [{"method": "symvib", "label": "s4", "wrong": 0, "error": 1e-5, "cpu": 1e-5},
            {"method": "symvib", "label": "s16", "wrong": 0, "error": 1e-13, "cpu": 2e-5},
            {"method": "DOP853", "label": "d7", "wrong": 0, "error": 1e-7, "cpu": 4e-3},
            {"method": "RK45", "label": "r10", "wrong": 1, "error": 1e-11, "cpu": 1e-3}]
    assert ratio_at_equal_accuracy(rows, 1e-6) == ("d7", 4e-3, "s16", 2e-5, pytest.approx(200))
    assert ratio_at_equal_accuracy(rows, 1e-10) is None  # r10 has a wrong sequence


def test_random_scenes_are_reproducible_and_capped():
    a, b = random_scenes(12), random_scenes(12)
    assert [scene_key(s) for s in a] == [scene_key(s) for s in b]
    assert {s.shape.name for s in a} == {"parabola", "circle"}
    for s in a:
        assert s.max_events == RANDOM_MAX_EVENTS
        assert (s.left is None or s.left < s.q0) and (s.right is None or s.q0 < s.right)


@needs_scipy
def test_peer_budget_stops_a_run():
    _, scene = paper_scenes()[0]
    run = solve_ivp_events(scene, "Radau", 1e-12, budget=0.0)
    assert run.status == "failed" and "budget" in run.message


@needs_scipy
@pytest.mark.slow
def test_quick_work_precision_run(tmp_path):
    before = _package_state()
    assert main(["bench", "work-precision", "--quick", "--out", str(tmp_path), "--random", "6"]) == 0
    assert _package_state() == before, "symvib bench wrote inside the package"
    for name in ("work_precision.png", "work_precision.csv", "work_precision_runs.csv", "wrong_sequences.csv",
                 "summary.md"):
        assert (tmp_path / name).stat().st_size > 0
    rows = list(csv.DictReader(open(tmp_path / "work_precision.csv", encoding="utf-8")))
    best = [r for r in rows if r["label"] == "symvib nodes=16"][0]
    assert int(best["wrong"]) == 0 and float(best["error"]) < 1e-12
    seq = list(csv.DictReader(open(tmp_path / "wrong_sequences.csv", encoding="utf-8")))
    ours = [r for r in seq if r["method"] == "symvib"][0]
    assert int(ours["wrong"]) == 0 and int(ours["failed"]) == 0


@needs_scipy
@pytest.mark.slow
def test_quick_stability_run(tmp_path):
    assert main(["bench", "stability", "--quick", "--out", str(tmp_path), "--budget", "5"]) == 0
    rows = list(csv.DictReader(open(tmp_path / "stability.csv", encoding="utf-8")))
    ours = [r for r in rows if r["method"].startswith("symvib")]
    assert ours and all(r["outcome"] == "correct" for r in ours)
    assert "| case |" in (tmp_path / "stability.md").read_text(encoding="utf-8")


@needs_scipy
def test_peers_cross_a_normal_force_zero_once():
    """A restarted peer takes the other sign of N after an N = 0 event (not the same event again)."""
    from symvib.checks import stability as st

    c = st.case("normal-sign")
    run = solve_ivp_events(c.scene, "RK45", 1e-8)
    assert st.labels(run.events) == st.expected("normal-sign").labels
