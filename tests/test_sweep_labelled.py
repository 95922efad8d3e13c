"""Sweeps as labelled data (issue 17): to_xarray / to_dataframe, Zarr sweep folders opened lazily, map labels."""
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from readme_blocks import DOCS, run_section

from symvib import sweep
from symvib.cli import sweep_main as main
from symvib.numeric.layout import EVENT_COLUMNS, STATUSES, SUMMARY_COLUMNS
from symvib.numeric.scene import scene_from_dict
from symvib.numeric.sweep import SweepError, load_sweep, open_sweep, sweep_id

xr = pytest.importorskip("xarray")
pd = pytest.importorskip("pandas")
pytest.importorskip("zarr")
pytest.importorskip("dask.array")

ROOT = Path(__file__).resolve().parents[1]
PARABOLA = {"curve": {"shape": "parabola"}, "parameters": {"p": 1.0},
            "physics": {"g": 9.81, "m": 0.2, "mu": 0.05, "restitution": 0.8},
            "limiters": {"left": "-pi/6", "right": "pi/4"}, "initial": {"q": 0.0, "qdot": 7.0}}
CATENARY = {"curve": {"shape": "catenary"}, "parameters": {"a": 1.0}, "physics": {"mu": 0.1, "restitution": 0.7},
            "limiters": {"left": -0.6, "right": 0.5}, "initial": {"q": 0.0, "qdot": 3.0}}
#: A three-axis grid with a curve parameter; chunks of 5 rows straddle the grid's lines.
VARY = {"qdot": "3:12:4", "mu": "0.01:0.2:3", "p": "0.8,1.2"}
CHUNK = 5
#: Readable names of the VARY fields, in order.
NAMES = ("qdot0", "mu", "p")


def parabola():
    return scene_from_dict(PARABOLA)


@pytest.fixture(scope="module")
def grid():
    return sweep(parabola(), VARY, chunk=CHUNK, log_events=4)


# --------------------------------------------------------------------- to_xarray, to_dataframe

def test_to_xarray_round_trips_a_grid_sweep(grid):
    ds = grid.to_xarray()
    assert tuple(ds["impacts"].dims) == NAMES and dict(ds.sizes)["qdot0"] == 4
    for axis, name in zip(grid.spec.axes, NAMES):        # coordinates are the axes' values
        assert np.array_equal(ds[name].values, np.asarray(axis.values))
        assert ds[name].attrs["field"] == axis.field
    for column in SUMMARY_COLUMNS:                        # every summary column, equal to grid()
        assert ds[column].dtype == grid[column].dtype
        assert np.array_equal(ds[column].values, grid.grid(column), equal_nan=True)
    assert np.array_equal(ds["event_log"].values, grid.grid("event_log"))
    assert list(ds["event_column"].values) == list(EVENT_COLUMNS)
    assert np.array_equal(ds["impact_share"].values, grid.impact_share.reshape(grid.spec.shape), equal_nan=True)
    # one scene looked up by its coordinates is that row of the flat columns
    row = 17
    at = {name: grid[a.field][row] for a, name in zip(grid.spec.axes, NAMES)}
    assert int(ds["impacts"].sel(at)) == grid["impacts"][row]
    assert ds.attrs["sweep_id"] == sweep_id(grid.spec.to_dict()) == grid.sweep_id
    assert ds["status"].attrs["flag_meanings"].split() == list(STATUSES)


def test_every_variable_has_units_long_name_and_a_symbol(grid):
    ds = grid.to_xarray()
    for name, var in ds.variables.items():
        if name in ("event_column", "event_log", "status"):
            continue
        assert {"units", "long_name", "latex"} <= set(var.attrs), name
        assert re.fullmatch(r"\$[^$]+\$", var.attrs["latex"]), name
    units = {name: ds[name].attrs["units"] for name in ds.variables if "units" in ds[name].attrs}
    # SI, by the physics: the parabola's coordinate is an angle; energies in joules
    assert units["qdot0"] == "rad/s" and units["mu"] == "1" and units["p"] == "m"
    assert units["t_final"] == "s" and units["q_final"] == "rad"
    assert {units[c] for c in ("friction_work", "impact_loss", "E0", "E_final")} == {"J"}
    assert {units[c] for c in ("events", "impacts", "reversals", "normal_sign_changes")} == {"1"}
    cat = sweep(scene_from_dict(CATENARY), {"qdot": "2:4:2", "left": "-0.7,-0.6"}).to_xarray()
    assert cat["qdot0"].attrs["units"] == "m/s" and cat["left"].attrs["units"] == "m"   # a graph: x in metres
    assert cat["q_final"].attrs["units"] == "m"


def test_a_random_sweep_has_rows_with_the_varied_fields_as_coordinates():
    res = sweep(parabola(), {"qdot": "3:12", "mu": "0.01:0.2"}, random=23, seed=4, chunk=7)
    ds = res.to_xarray()
    assert tuple(ds["impacts"].dims) == ("row",) and np.array_equal(ds["row"].values, np.arange(23))
    assert set(ds.coords) == {"row", "qdot0", "mu"}
    assert np.array_equal(ds["qdot0"].values, res["initial.qdot"])
    for column in SUMMARY_COLUMNS:
        assert np.array_equal(ds[column].values, res[column], equal_nan=True)
    with pytest.raises(ValueError, match="no grid"):
        res.grid("impacts")


@pytest.mark.parametrize("random", [None, 19])
def test_to_dataframe_columns_dtypes_and_values(grid, random):
    res = grid if random is None else sweep(parabola(), {"qdot": "3:12", "mu": "0.01:0.2"}, random=random)
    df = res.to_dataframe()
    names = [n for n in NAMES if n in df.columns] if random is None else ["qdot0", "mu"]
    assert list(df.columns) == names + list(SUMMARY_COLUMNS) + ["impact_share"]
    assert df.index.name == "row" and np.array_equal(df.index.to_numpy(), np.arange(res.count))
    assert isinstance(df["status"].dtype, pd.CategoricalDtype)
    assert list(df["status"].cat.categories) == list(STATUSES)
    assert np.array_equal(df["status"].astype(str).to_numpy(), res.status_names().astype(str))
    for column in SUMMARY_COLUMNS:
        if column != "status":
            assert df[column].dtype == res[column].dtype == (np.int64 if column in (
                "events", "impacts", "reversals", "normal_sign_changes") else np.float64)
            assert np.array_equal(df[column].to_numpy(), res[column], equal_nan=True)
    for axis, name in zip(res.spec.axes, names):
        assert df[name].dtype == np.float64 and np.array_equal(df[name].to_numpy(), res[axis.field])
    assert df.attrs["sweep_id"] == res.sweep_id and df.attrs["units"]["t_final"] == "s"
    assert res.to_pandas().equals(df)


def test_without_the_extra_the_error_names_it(grid, monkeypatch):
    monkeypatch.setitem(sys.modules, "xarray", None)
    monkeypatch.setitem(sys.modules, "pandas", None)
    with pytest.raises(ImportError, match=r'pip install "symvib\[xarray\]"'):
        grid.to_xarray()
    with pytest.raises(ImportError, match=r'pip install "symvib\[xarray\]"'):
        grid.to_dataframe()


# --------------------------------------------------------------------- Zarr on disk, opened lazily

def _zarr_sweep(tmp_path, name="z", vary=VARY, **kw):
    out = tmp_path / name
    return out, sweep(parabola(), vary, chunk=CHUNK, log_events=4, out=out, storage="zarr", **kw)


def test_a_zarr_sweep_folder_opens_lazily_as_one_dataset_equal_to_the_in_memory_result(grid, tmp_path):
    out, res = _zarr_sweep(tmp_path)
    assert (out / "sweep.zarr").is_dir() and not list((out / "chunks").glob("*.npz"))
    for name in grid.columns:                              # load_sweep reads back the same columns
        assert np.array_equal(res[name], grid[name], equal_nan=True)
    lazy = open_sweep(out)
    assert lazy["impacts"].chunks is not None              # Dask-backed: nothing read yet
    xr.testing.assert_identical(lazy.compute(), grid.to_xarray())
    raw = xr.open_zarr(out / "sweep.zarr")                 # xarray alone, one call: dimension row
    assert raw["impacts"].chunks is not None and raw.attrs["sweep_id"] == grid.sweep_id
    assert raw["impacts"].chunks[0][0] == CHUNK            # a Zarr chunk is a sweep chunk
    assert np.array_equal(raw["qdot0"].values, grid["initial.qdot"])
    for column in SUMMARY_COLUMNS:
        assert raw[column].dtype == grid[column].dtype
        assert np.array_equal(raw[column].values, grid[column], equal_nan=True)


def test_an_npz_sweep_folder_opens_lazily_too(grid, tmp_path):
    sweep(parabola(), VARY, chunk=CHUNK, log_events=4, out=tmp_path / "n")
    lazy = open_sweep(tmp_path / "n")
    assert lazy["t_final"].chunks is not None
    xr.testing.assert_identical(lazy.compute(), grid.to_xarray())
    (tmp_path / "n" / "chunks" / "chunk-000002.npz").write_bytes(b"PK")   # spoiled after opening:
    with pytest.raises(SweepError, match="chunk-000002.npz: truncated"):  # refused when it is read
        lazy["t_final"].compute()


def _zarr_files(store, index):
    """The Zarr chunk files of sweep chunk ``index``, one per array (keys ``c/i/...`` in Zarr 3, ``i.0.0`` in 2)."""
    files = []
    for array in sorted(p for p in store.iterdir() if p.is_dir()):
        for p in array.rglob("*"):
            parts = p.relative_to(array).parts
            parts = parts[1:] if parts[0] == "c" else parts
            if p.is_file() and parts and parts[0].split(".")[0] == str(index) and not p.name.startswith((".z", "z")):
                files.append(p)
    return files


#: Ways a Zarr chunk goes bad: name -> (spoil(out, other, index), what load_sweep says, marker kept?).
SPOILED = {
    "write interrupted before the marker": (lambda out, other, i: (out / "chunks" / f"chunk-{i:06d}.json").unlink(),
                                            "incomplete", False),
    "truncated data file": (lambda out, other, i: [p.write_bytes(p.read_bytes()[:5]) for p in
                                                   _zarr_files(out / "sweep.zarr", i)], "chunk", True),
    "another sweep's data": (lambda out, other, i: [shutil.copyfile(q, p) for p, q in zip(
        _zarr_files(out / "sweep.zarr", i), _zarr_files(other / "sweep.zarr", i))], "not what this sweep wrote", True),
    "another sweep's marker": (lambda out, other, i: shutil.copyfile(
        other / "chunks" / f"chunk-{i:06d}.json", out / "chunks" / f"chunk-{i:06d}.json"), "another sweep", True),
}


@pytest.mark.parametrize("how", sorted(SPOILED))
def test_a_spoiled_zarr_chunk_is_refused_and_recomputed_on_resume(grid, tmp_path, how):
    out, _ = _zarr_sweep(tmp_path)
    other, _ = _zarr_sweep(tmp_path, "other", vary={"qdot": "3:12:4", "mu": "0.01:0.3:3", "p": "0.8,1.2"})
    spoil, says, marked = SPOILED[how]
    spoil(out, other, 2)
    with pytest.raises(SweepError, match=says) as info:
        load_sweep(out)
    assert "\n" not in str(info.value)
    again = sweep(parabola(), VARY, chunk=CHUNK, log_events=4, out=out, storage="zarr")
    assert again.computed == (2,) and again.discarded == ((2,) if marked else ())
    assert again.reused == tuple(i for i in range(again.spec.chunks) if i != 2)
    for name in grid.columns:
        assert np.array_equal(again[name], grid[name], equal_nan=True)
    xr.testing.assert_identical(open_sweep(out).compute(), grid.to_xarray())


def test_a_foreign_zarr_store_is_replaced_and_its_identity_checked_on_load(grid, tmp_path):
    out, _ = _zarr_sweep(tmp_path)
    other, _ = _zarr_sweep(tmp_path, "other", vary={"qdot": "3:12:4", "mu": "0.01:0.3:3", "p": "0.8,1.2"})
    shutil.rmtree(out / "sweep.zarr")
    shutil.copytree(other / "sweep.zarr", out / "sweep.zarr")
    with pytest.raises(SweepError, match="another sweep") as info:
        load_sweep(out)
    assert info.value.field.endswith("sweep.zarr")
    with pytest.raises(SweepError, match="another sweep"):
        open_sweep(out)
    again = sweep(parabola(), VARY, chunk=CHUNK, log_events=4, out=out, storage="zarr")
    assert len(again.computed) == again.spec.chunks and again.reused == ()
    for name in grid.columns:
        assert np.array_equal(again[name], grid[name], equal_nan=True)


def test_the_same_sweep_in_the_other_storage_is_refused_unless_overwritten(tmp_path):
    out = tmp_path / "s"
    sweep(parabola(), VARY, chunk=CHUNK, out=out)
    with pytest.raises(SweepError, match="stored as npz"):
        sweep(parabola(), VARY, chunk=CHUNK, out=out, storage="zarr")
    res = sweep(parabola(), VARY, chunk=CHUNK, out=out, storage="zarr", overwrite=True)
    assert len(res.computed) == res.spec.chunks and not list((out / "chunks").glob("*.npz"))
    back = sweep(parabola(), VARY, chunk=CHUNK, out=out, overwrite=True)    # and back to npz
    assert not (out / "sweep.zarr").exists() and load_sweep(out).count == back.count
    with pytest.raises(SweepError, match="storage: must be one of npz, zarr"):
        sweep(parabola(), VARY, out=tmp_path / "x", storage="parquet")


def _markers(folder):
    return sorted(p for p in Path(folder).glob("chunk-*.json") if not p.name.endswith(".tmp.json"))


def test_a_killed_zarr_sweep_resumes_and_keeps_its_identity(tmp_path, capsys):
    out = tmp_path / "killed"
    args = ["paper-parabola", "--vary", "qdot=3:12:12", "--vary", "mu=0.01:0.2:25", "--vary", "k=0.8",
            "--chunk", "4", "--log-events", "8", "-o", str(out), "--backend", "python", "--quiet", "--format", "zarr"]
    env = dict(os.environ, SYMVIB_BACKEND="python")
    proc = subprocess.Popen([sys.executable, "-m", "symvib.cli", "sweep", *args], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and len(_markers(out / "chunks")) < 3:
        if proc.poll() is not None:
            break
        time.sleep(0.01)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    before = {p.name: p.read_bytes() for p in _markers(out / "chunks")}
    assert 3 <= len(before) < 75, "the sweep must be killed midway"
    assert main(args) == 0
    assert f"{75 - len(before)} chunk(s) computed, {len(before)} reused" in capsys.readouterr().out
    assert all((out / "chunks" / name).read_bytes() == data for name, data in before.items())
    mem = sweep(_paper(), {"qdot": "3:12:12", "mu": "0.01:0.2:25", "k": "0.8"}, chunk=4, log_events=8)
    xr.testing.assert_identical(open_sweep(out).compute(), mem.to_xarray())


def _paper():
    from symvib.numeric.scene import resolve_scene

    return resolve_scene("paper-parabola")


def test_cli_format_zarr_and_a_bad_format_in_a_sweep_file(tmp_path, capsys):
    out = tmp_path / "cli"
    assert main(["paper-parabola", "--vary", "qdot=3:12:3", "-o", str(out), "--format", "zarr", "--quiet"]) == 0
    assert xr.open_zarr(out / "sweep.zarr")["impacts"].shape == (3,)
    sw = tmp_path / "sweep.toml"
    sw.write_text('scene = "paper-parabola"\nformat = "hdf5"\n[vary]\nqdot = "3:12:3"\n')
    capsys.readouterr()
    assert main(["--file", str(sw), "-o", str(tmp_path / "bad"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "storage" in err and "hdf5" in err


# --------------------------------------------------------------------- maps

def test_maps_label_axes_with_names_symbols_and_units(tmp_path, monkeypatch):
    from matplotlib.figure import Figure

    from symvib.numeric.sweepmaps import sweep_maps

    labels = []
    save = Figure.savefig

    def spy(fig, *args, **kwargs):
        ax = fig.axes[0]
        labels.append((ax.get_xlabel(), ax.get_ylabel(), fig.axes[1].get_ylabel() if len(fig.axes) > 1 else ""))
        return save(fig, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", spy)
    sweep_maps(sweep(parabola(), {"qdot": "3:12:3", "mu": "0.01:0.2:2"}), tmp_path)
    text = " ".join(" ".join(t) for t in labels)
    assert "initial." not in text and "physics." not in text          # no dotted scene-file names
    assert all(x.startswith("initial speed") and x.endswith("[rad/s]") and "\\dot" in x for x, _, _ in labels)
    assert all(y.startswith("friction coefficient") and y.endswith("[-]") for _, y, _ in labels)
    assert any(bar.startswith("arrest (or rest) time") and bar.endswith("[s]") for _, _, bar in labels)


# ------------------------------------------------------------ docs/sweeps.md

def test_docs_labelled_sweep_example_runs(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    namespace = run_section("## Sweeps as labelled data", "docs_labelled_sweep", DOCS / "sweeps.md")
    ds, lazy, res = namespace["ds"], namespace["lazy"], namespace["res"]
    assert tuple(ds["impacts"].dims) == ("qdot0", "mu")
    xr.testing.assert_identical(lazy.compute(), ds)
    assert np.array_equal(ds["impacts"].values, res.grid("impacts"))
