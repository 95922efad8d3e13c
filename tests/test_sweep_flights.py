"""Sweeps of unilateral scenes follow flights (docs/sweeps.md, "Flights"; physics.md, "Flight and landing").

Every row of a seeded random sweep of unilateral scenes, on the circle run fast enough to lift off
and on a bowl (the double well of tests/flight_reference.py), equals ``simulate`` of its scene:
status, event kinds and count, final time, state and energies, its logged events; the flight
columns are ``Result.stats["flights"]``, ``["landings"]`` and the budget's landing loss.  The
chunked folder (``.npz`` and Zarr), a Dask cluster and the command line give the same rows and
write the columns; the compiled engine gives the plain one's rows (slow: it compiles the circle);
a bilateral sweep has no flight columns.
"""
import json
import math

import numpy as np
import pytest

from symvib import simulate, sweep
from symvib.cli import sweep_main
from symvib.numeric.events import EventKind
from symvib.numeric.layout import EVENT_KINDS, STATUSES, SUMMARY_COLUMNS
from symvib.numeric.scene import scene_from_dict
from symvib.numeric.sweep import load_sweep, open_sweep
from symvib.numeric.sweep.flights import COLUMNS
from symvib.numeric.sweep.schema import column_names

G = 9.81
#: Seeds of the random sweeps (one per curve).
SEED_CIRCLE, SEED_BOWL, SEED_LIMITED = 20261127, 27, 5
#: Random rows per sweep (the issue asks for at least 20 scenes on at least 2 curves).
ROWS = 12
#: Events logged per row: every event of these short runs.
LOG = 160
#: Agreement of a row with simulate on the same backend: bit for bit (the same code runs both).
SAME = 0.0
#: Agreement of the compiled engine's rows with the plain engine's (relative, or absolute below 1):
#: they differ in the last bits (symvib.numeric.engine.plain sums in another order).
BACKENDS = 1e-12


def circle(e=0.4, **run):
    """The circle, unilateral, started at its bottom: fast enough, it lifts off above the horizontal
    diameter, flies across and lands (and bounces with ``restitution_curve = e``)."""
    return scene_from_dict({"name": "flying-circle", "curve": {"shape": "circle"}, "parameters": {"R": 0.5},
                            "physics": {"g": G, "mu": 0.05, "restitution": 1.0, "contact": "unilateral",
                                        "restitution_curve": e},
                            "initial": {"q": 0.0, "qdot": 8.0}, "run": {"t_max": 3.0, "max_events": 150, **run}})


def limited_circle(e=0.4):
    """:func:`circle` between limiters: some runs bounce off them, some arrest, some fly across the right
    one's normal line (status ``crossed_limiter``)."""
    return circle(e, t_max=5.0).replace(left=-1.0, right=2.4)


def bowl(e=0.0):
    """The double well ``z = a x^4 - b x^2`` (tests/flight_reference.py) started at the bottom of its
    right well towards the hump at ``x = 0``: fast enough, it flies off the hump into the other well."""
    a, b = 1.0, 0.5
    return scene_from_dict({"name": "flying-bowl", "curve": {"z": "a*x**4 - b*x**2", "name": "flight-well"},
                            "parameters": {"a": a, "b": b},
                            "physics": {"g": G, "mu": 0.05, "restitution": 1.0, "contact": "unilateral",
                                        "restitution_curve": e},
                            "initial": {"q": math.sqrt(b / (2 * a)), "qdot": -4.0},
                            "run": {"t_max": 3.0, "max_events": 150}})


def row_scene(res, i):
    """The scene of row ``i`` of the sweep ``res``, built by ``Scene.replace`` from its varied values."""
    changes, params = {}, {}
    for axis in res.spec.axes:
        value = float(res[axis.field][i])
        if axis.field.startswith("parameters."):
            params[axis.field.split(".", 1)[1]] = value
        else:
            changes[{"initial.qdot": "qdot0", "physics.mu": "mu", "initial.q": "q0"}[axis.field]] = value
    if params:
        changes["params"] = params
    return res.spec.scene.replace(**changes)


def close(a, b, tol=SAME):
    """``a == b`` (both NaN included), or within ``tol`` relative (absolute below 1)."""
    return a == b or (math.isnan(a) and math.isnan(b)) or abs(a - b) <= tol * max(1.0, abs(a), abs(b))


def assert_row_is_the_result(res, i, r, tol=SAME):
    """Row ``i`` of ``res`` against the Result ``r`` of its scene: status, counts, final state, energies,
    flight columns and logged events (bit for bit at ``tol = 0``)."""
    where = (res.spec.scene.name, i, r.status.value)
    assert STATUSES[int(res["status"][i])] == r.status.value, where
    assert int(res["events"][i]) == len(r.events), where
    for column, kind in (("impacts", EventKind.IMPACT), ("reversals", EventKind.REVERSAL),
                         ("normal_sign_changes", EventKind.NORMAL_SIGN_CHANGE)):
        assert int(res[column][i]) == r.count(kind), (where, column)
    b = r.energy_budget
    for column, value in (("t_final", r.t_final), ("q_final", r.q_final), ("qdot_final", r.qdot_final),
                          ("friction_work", b.friction_work), ("impact_loss", b.impact_loss), ("E0", b.initial),
                          ("E_final", b.final), ("t_err", r.stats["t_err"]),
                          ("zeno_ratio", r.zeno.ratio if r.zeno else 0.0),
                          ("landing_loss", b.landing_loss or 0.0)):
        assert close(float(res[column][i]), float(value), tol), (where, column, float(res[column][i]), value)
    assert int(res["flights"][i]) == r.stats.get("flights", 0), where
    assert int(res["landings"][i]) == r.stats.get("landings", 0), where
    logged = res.events(i)
    assert [e[0] for e in logged] == [e.kind.value for e in r.events][:LOG], where
    for got, e in zip(logged, r.events):
        assert all(close(x, y, tol) for x, y in zip(got[1:], (e.t, e.q, e.qdot_before, e.qdot_after, e.energy))), \
            (where, got, e)


@pytest.mark.parametrize("make, vary, seed", [
    (circle, {"qdot": "4:10", "mu": "0.02:0.12", "R": "0.4:0.8"}, SEED_CIRCLE),
    (bowl, {"qdot": "-6:-2.5", "mu": "0.01:0.15", "a": "0.8:1.2"}, SEED_BOWL),
    (limited_circle, {"qdot": "6:10.5", "mu": "0.02:0.12"}, SEED_LIMITED),
], ids=["circle", "bowl", "circle-limiters"])
@pytest.mark.parametrize("e", [0.0, 0.4])
def test_every_row_of_a_random_unilateral_sweep_is_simulates_result(make, vary, seed, e):
    res = sweep(make(e), vary, random=ROWS, seed=seed, chunk=5, log_events=LOG, backend="python")
    flew = 0
    for i in range(res.count):
        r = simulate(row_scene(res, i), backend="python", samples=False)
        assert_row_is_the_result(res, i, r)
        flew += r.count(EventKind.LIFT_OFF) > 0
    assert STATUSES.index("left_curve") not in res["status"]
    assert flew >= ROWS // 3, flew                    # the sets fly (and some rows do not)


def test_flight_counts_are_the_results_stats_and_landing_events():
    res = sweep(circle(), {"qdot": "3,8,8.5,9"}, log_events=LOG, backend="python")
    for i in range(res.count):
        r = simulate(row_scene(res, i), backend="python", samples=False)
        assert (int(res["flights"][i]), int(res["landings"][i])) == (r.stats.get("flights", 0),
                                                                      r.stats.get("landings", 0))
        kinds = [k for k, *_ in res.events(i)]
        assert kinds.count("lift_off") == r.count(EventKind.LIFT_OFF)
        assert kinds.count("landing") == r.count(EventKind.LANDING) >= int(res["landings"][i])
    assert res["flights"][0] == res["landings"][0] == 0 and res["landing_loss"][0] == 0.0   # (it stays on)
    assert np.all(res["flights"][1:] > 0) and np.all(res["landing_loss"][1:] > 0)
    assert res["flights"].dtype == res["landings"].dtype == np.int64 and res["landing_loss"].dtype == np.float64
    lifted = res["event_log"][1, 0]
    assert EVENT_KINDS[int(lifted[0])] == "lift_off"


def test_a_bilateral_sweep_has_no_flight_columns():
    scene = circle().replace(contact="bilateral")
    res = sweep(scene, {"qdot": "3,8"}, log_events=4, backend="python")
    expected = ["row", "initial.qdot", *SUMMARY_COLUMNS, "event_log"]
    assert column_names(res.spec) == expected and list(res.columns) == expected
    assert not set(COLUMNS) & set(res.to_xarray().data_vars)
    assert not set(COLUMNS) & set(res.to_dataframe().columns)


def test_the_folder_gives_the_in_memory_rows_and_holds_the_columns(tmp_path):
    vary = {"qdot": "3:9:5", "mu": "0.03,0.08"}
    mem = sweep(circle(), vary, log_events=LOG, backend="python")
    assert list(mem.columns)[-4:] == [*COLUMNS, "event_log"]
    for storage in ("npz", "zarr"):
        out = tmp_path / storage
        disk = sweep(circle(), vary, chunk=3, log_events=LOG, out=out, storage=storage, backend="python")
        again = load_sweep(out)
        for name in mem.columns:
            assert np.array_equal(disk[name], mem[name]) and np.array_equal(again[name], mem[name]), (storage, name)
        manifest = json.loads((out / "manifest.json").read_text())
        assert manifest["columns"] == column_names(mem.spec)
        lazy = open_sweep(out).compute()
        assert lazy["landings"].attrs["units"] == "1" and lazy["landing_loss"].attrs["units"] == "J"
        assert np.array_equal(lazy["flights"].values, mem.grid("flights"))
    first = np.load(tmp_path / "npz" / "chunks" / "chunk-000000.npz")
    assert set(COLUMNS) <= set(first.files)


def test_a_dask_cluster_follows_the_flights_as_this_process_does(tmp_path):
    distributed = pytest.importorskip("dask.distributed")
    vary = {"qdot": "3,8,8.5,9"}
    mem = sweep(circle(), vary, chunk=2, log_events=LOG, backend="python")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        res = sweep(circle(), vary, chunk=2, log_events=LOG, out=tmp_path / "dask", scheduler=client,
                    backend="python")
    for name in mem.columns:
        assert np.array_equal(res[name], mem[name]), name
    assert res["flights"][0] == 0 and np.all(res["flights"][1:] > 0)


def test_a_chunk_without_the_flight_columns_is_computed_again(tmp_path):
    # A unilateral sweep's folder written before sweeps followed flights (its rows end left_curve and
    # it has no flight columns) is resumed: such a chunk is refused and computed again.
    out = tmp_path / "old"
    vary = {"qdot": "8,9"}
    sweep(circle(), vary, out=out, backend="python")
    path = out / "chunks" / "chunk-000000.npz"
    with np.load(path) as data:
        old = {name: data[name] for name in data.files if name not in COLUMNS}
    np.savez(path, **old)
    res = sweep(circle(), vary, out=out, backend="python")
    assert res.discarded == (0,) and np.all(res["flights"] > 0)


def test_the_cli_writes_the_flight_columns(tmp_path, capsys):
    scene = tmp_path / "scene.toml"
    scene.write_text('[curve]\nshape = "circle"\n[parameters]\nR = 0.5\n'
                     '[physics]\nmu = 0.05\nrestitution = 1\ncontact = "unilateral"\nrestitution_curve = 0.4\n'
                     '[initial]\nq = 0\nqdot = 8\n[run]\nt_max = 3\nmax_events = 150\n')
    out = tmp_path / "out"
    code = sweep_main([str(scene), "--vary", "qdot=3,8", "--vary", "mu=0.05,0.1", "-o", str(out), "--quiet",
                       "--backend", "python", "--plot"])
    assert code == 0
    text = capsys.readouterr().out
    assert "flights" in text and "landings" in text
    res = load_sweep(out)
    assert set(COLUMNS) <= set(res.columns) and res["flights"][0] == 0 and res["flights"][-1] > 0
    assert (out / "maps" / "flights.png").exists()


@pytest.mark.slow
def test_the_compiled_engine_gives_the_plain_engines_rows(tmp_path):
    # backend="numba" (the circle's sweep and single-scene engines compiled, cached): the rows are
    # simulate's on that backend, and the plain engine's within the last bits; the folder's the same.
    vary = {"qdot": "4:10", "mu": "0.02:0.12"}
    compiled = sweep(circle(), vary, random=8, seed=3, chunk=3, log_events=LOG, backend="numba")
    plain = sweep(circle(), vary, random=8, seed=3, chunk=3, log_events=LOG, backend="python")
    disk = sweep(circle(), vary, random=8, seed=3, chunk=3, log_events=LOG, out=tmp_path / "o", backend="numba")
    for i in range(compiled.count):
        assert_row_is_the_result(compiled, i, simulate(row_scene(compiled, i), backend="numba", samples=False))
        assert_row_is_the_result(plain, i, simulate(row_scene(plain, i), backend="numba", samples=False),
                                 tol=BACKENDS)
    for name in compiled.columns:
        assert np.array_equal(disk[name], compiled[name]), name
