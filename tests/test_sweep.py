"""Sweeps: definitions, equality with the single-scene driver, chunked output, resume, Dask, maps."""
import hashlib
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from symvib import simulate, sweep
from symvib.cli import sweep_main as main
from symvib.numeric.scene import SceneError, scene_from_dict
from symvib.numeric.scene import resolve_scene as _resolve_scene
from symvib.numeric.sweep import FORMAT, Progress, load_sweep, make_spec, run_chunk

PARABOLA = {"curve": {"shape": "parabola"}, "parameters": {"p": 1.0},
            "physics": {"g": 9.81, "m": 0.2, "mu": 0.05, "restitution": 0.8},
            "limiters": {"left": "-pi/6", "right": "pi/4"}, "initial": {"q": 0.0, "qdot": 7.0}}


def base(**changes):
    return scene_from_dict(PARABOLA).replace(**changes)


def single(spec_scene, fields: dict):
    """The scene of one sweep row, built through Scene.replace (validated as any scene)."""
    changes, params = {}, {}
    attr = {"initial.q": "q0", "initial.qdot": "qdot0", "physics.mu": "mu", "physics.restitution": "k",
            "limiters.left": "left", "limiters.right": "right", "physics.g": "g", "physics.m": "m",
            "physics.mu_s": "mu_s", "physics.alpha0_s": "alpha0_s"}
    for fld, v in fields.items():
        if fld.startswith("parameters."):
            params[fld.split(".", 1)[1]] = float(v)
        elif fld == "physics.alpha0":
            changes["alpha0"] = float(v)
        else:
            changes[attr[fld]] = float(v)
    if params:
        changes["params"] = params
    return spec_scene.replace(**changes)


def assert_same_as_driver(res, rows):
    """Each row's logged events equal the single-scene driver's: kinds, and t, q to 1e-12."""
    varied = [a.field for a in res.spec.axes]
    for row in rows:
        scene = single(res.spec.scene, {f: res[f][row] for f in varied})
        ref = simulate(scene, samples=False)
        got = res.events(row)
        assert int(res["events"][row]) == len(ref.events)
        assert [e[0] for e in got] == [e.kind.value for e in ref.events[:len(got)]]
        for e, r in zip(got, ref.events):
            assert abs(e[1] - r.t) <= 1e-12 * max(1.0, abs(r.t))
            assert abs(e[2] - r.q) <= 1e-12
        assert res.status_names()[row] == ref.status.value
        assert res["t_final"][row] == pytest.approx(ref.t_final, rel=1e-12, abs=1e-12)
        assert res["impact_loss"][row] == pytest.approx(ref.energy_budget.impact_loss, rel=1e-12, abs=1e-15)


# --------------------------------------------------------------------- definitions

def test_grid_axes_order_and_expressions():
    spec = make_spec(base(), {"qdot": "3:12:4", "left": "-pi/3:-pi/12:3", "k": "0.5,1"})
    assert spec.shape == (4, 3, 2) and spec.count == 24
    rows, values = spec.rows(0)
    # first axis slowest (C order), ends included, expressions evaluated
    assert values[0][0] == 3.0 and values[0][-1] == 12.0
    lefts = spec.axes[1].values
    assert lefts[0] == pytest.approx(-math.pi / 3) and lefts[-1] == pytest.approx(-math.pi / 12)
    assert list(values[1][:6]) == [lefts[0], lefts[0], lefts[1], lefts[1], lefts[2], lefts[2]]
    assert list(values[2][:4]) == [0.5, 1.0, 0.5, 1.0]
    assert list(values[0][:7]) == [3.0] * 6 + [6.0]


def test_random_rows_are_reproducible_and_in_range():
    spec = make_spec(base(), {"mu": "0.01:0.2", "qdot": "3:12"}, random=50, seed=7, chunk=16)
    assert spec.chunks == 4
    a = spec.rows(2)[1]
    b = make_spec(base(), {"mu": "0.01:0.2", "qdot": "3:12"}, random=50, seed=7, chunk=16).rows(2)[1]
    assert all(np.array_equal(x, y) for x, y in zip(a, b))
    c = make_spec(base(), {"mu": "0.01:0.2", "qdot": "3:12"}, random=50, seed=8, chunk=16).rows(2)[1]
    assert not np.array_equal(a[0], c[0])
    assert (a[0] >= 0.01).all() and (a[0] <= 0.2).all() and len(spec.rows(3)[0]) == 2


@pytest.mark.parametrize("vary, kwargs, field", [
    ({"foo": "1:2:3"}, {}, "vary.foo"),
    ({"k": "0.5:1.2:3"}, {}, "physics.restitution"),
    ({"mu": "-0.1:0.1:3"}, {}, "physics.mu"),
    ({"left": "-0.5:0.9:3"}, {}, "limiters"),
    ({"q": "-1:0:3"}, {}, "initial.q"),
    ({"qdot": "1:2"}, {}, "vary.qdot"),
    ({"qdot": "1:2:3"}, {"random": 5}, "vary.qdot"),
    ({"qdot": "1:2:x"}, {}, "vary.qdot"),
    ({"qdot": "1:2:0"}, {}, "vary.qdot"),
    ({"mu": "0.1,0.2", "alpha0": "0.1,0.2"}, {}, "vary"),
    ({"qdot": "__import__('os').system('true'):2:3"}, {}, "vary.qdot"),
    ({"p": "0:1:3"}, {}, "parameters.p"),
    ({"alpha0": "0:2:3"}, {}, "physics.alpha0"),
    ({"mu_s": "0.1,0.2", "alpha0_s": "0.1,0.2"}, {}, "vary"),
    ({"mu_s": "0:0.2:3"}, {}, "physics.mu_s"),          # 0 is below the kinetic mu = 0.05
    ({"alpha0_s": "0.1:2:3"}, {}, "physics.alpha0_s"),
    ({}, {}, "vary"),
    ({"qdot": "1:2:3"}, {"chunk": 0}, "chunk"),
])
def test_bad_definitions_name_the_field(vary, kwargs, field):
    with pytest.raises(SceneError) as info:
        make_spec(base(), vary, **kwargs)
    assert info.value.field == field


#: One bad value per checked field: (section, key, value as a scene file gives it, vary key, vary value).
SAME_ERROR = [
    ("physics", "restitution", 1.5, "restitution", "1.5"),
    ("physics", "mu", -0.1, "mu", "-0.1"),
    ("physics", "alpha0", 2.0, "alpha0", "2.0"),
    ("physics", "g", -2.0, "g", "-2.0"),
    ("physics", "m", 0.0, "m", "0.0"),
    ("initial", "q", 1.0, "q", "1.0"),
    ("initial", "q", -1.0, "q", "-1.0"),
    ("limiters", "right", -0.6, "right", "-0.6"),
    ("run", "t_max", -1.0, "t_max", "-1.0"),
    ("run", "max_events", 0, "max_events", "0"),
    ("parameters", "p", -1.0, "p", "-1.0"),
    ("physics", "mu_s", -0.1, "mu_s", "-0.1"),
    ("physics", "mu_s", 0.01, "mu_s", "0.01"),
    ("physics", "alpha0_s", 2.0, "alpha0_s", "2.0"),
]


@pytest.mark.parametrize("section, key, value, vary, text", SAME_ERROR)
def test_a_sweep_and_a_scene_file_give_the_same_error_for_the_same_bad_value(section, key, value, vary, text):
    """One set of checks (scene.CHECKS): the sweep's message is the scene file's, with the row appended."""
    data = {k: dict(v) for k, v in PARABOLA.items()}
    if key == "alpha0":
        del data["physics"]["mu"]
    data.setdefault(section, {})[key] = value
    with pytest.raises(SceneError) as from_file:
        scene_from_dict(data)
    with pytest.raises(SceneError) as from_sweep:
        make_spec(base(), {vary: f"{text},{text}"})
    assert from_sweep.value.field == from_file.value.field
    assert str(from_sweep.value) == f"{from_file.value} (sweep row 0)"


def test_cli_bad_input_exits_2(capsys):
    assert main(["paper-parabola", "--vary", "restitution=0:2:3", "-o", "unused"]) == 2
    assert "physics.restitution" in capsys.readouterr().err
    assert main(["no-such-scene", "--vary", "qdot=1:2:2", "-o", "unused"]) == 2
    assert main(["paper-parabola", "--vary", "qdot", "-o", "unused"]) == 2


# --------------------------------------------------------------------- against the driver

def test_sweep_equals_single_scene_driver_on_random_rows():
    scene = base()
    res = sweep(scene, {"qdot": "-12:12", "mu": "0:0.2", "restitution": "0:1", "left": "-0.9:-0.2",
                        "q": "-0.2:0.3", "p": "0.5:2"}, random=40, seed=3, chunk=16, log_events=64)
    assert res.count == 40 and (res["events"] > 64).any()  # some logs are truncated: compared as far as kept
    rng = np.random.default_rng(0)
    assert_same_as_driver(res, rng.choice(40, size=12, replace=False))


def test_alpha0_axis_matches_tan():
    res = sweep(base(), {"alpha0": "0.02,0.1"}, log_events=32)
    assert np.allclose(res["physics.alpha0"], [0.02, 0.1])
    assert_same_as_driver(res, [0, 1])


def test_static_friction_axes_equal_the_driver_and_mu_s_follows_a_varied_mu():
    # mu_s above every mu: arrests and reversals decided by it, row for row as the driver does.
    res = sweep(base(), {"mu": "0:0.1", "mu_s": "0.1:0.6", "qdot": "3:9"}, random=12, seed=5, log_events=300)
    assert_same_as_driver(res, range(12))
    angle = sweep(base(), {"alpha0_s": "0.06,0.3"}, log_events=300)
    assert np.allclose(angle["physics.alpha0_s"], [0.06, 0.3])
    assert_same_as_driver(angle, [0, 1])
    # no mu_s in the scene: each row's mu_s is its mu (as Scene.replace(mu=...) gives)
    follows = sweep(base(), {"mu": "0.01,0.3"}, log_events=300)
    assert_same_as_driver(follows, [0, 1])


def test_energy_columns_balance():
    res = sweep(base(), {"qdot": "3:12:5", "mu": "0.01:0.2:4"})
    lost = res["friction_work"] + res["impact_loss"]
    assert np.allclose(res["E0"] - res["E_final"], lost, rtol=1e-12, atol=1e-14)
    share = res.impact_share
    assert ((share >= 0) & (share <= 1)).all()
    assert set(res.status_names()) == {"arrested"}


def test_catenary_sweeps_through_its_numeric_representation():
    """The catenary has no closed-form F_sigma: its kernels integrate numerically."""
    cat = scene_from_dict({"curve": {"shape": "catenary"}, "parameters": {"a": 1.0},
                           "physics": {"mu": 0.1, "restitution": 0.8}, "limiters": {"left": -0.8, "right": 0.6},
                           "initial": {"q": 0.0, "qdot": 4.0}})
    res = sweep(cat, {"qdot": "2:8:3", "mu": "0.05,0.15"}, log_events=32)
    assert_same_as_driver(res, range(res.count))
    assert (res["impacts"] > 0).any()


# --------------------------------------------------------------------- storage and resume

def test_chunks_on_disk_load_and_resume(tmp_path):
    vary = {"qdot": "3:12:6", "mu": "0.01:0.2:3"}
    mem = sweep(base(), vary, chunk=5)
    out = tmp_path / "sw"
    first = sweep(base(), vary, chunk=5, out=out)
    assert first.computed == (0, 1, 2, 3) and first.reused == ()
    manifest = (out / "manifest.json").read_text()
    assert FORMAT in manifest
    with np.load(out / "chunks" / "chunk-000001.npz") as data:   # plain NumPy reads a chunk
        assert list(data["row"]) == [5, 6, 7, 8, 9]
    for name in mem.columns:
        assert np.array_equal(first[name], mem[name])
    (out / "chunks" / "chunk-000002.npz").unlink()
    (out / "chunks" / "chunk-000003.12345.tmp.npz").write_bytes(b"partial")
    again = sweep(base(), vary, chunk=5, out=out)
    assert again.computed == (2,) and again.reused == (0, 1, 3)
    assert not list((out / "chunks").glob("*.tmp.npz"))
    for name in mem.columns:
        assert np.array_equal(again[name], mem[name])
    with pytest.raises(SceneError, match="different sweep"):
        sweep(base(), {"qdot": "3:12:7"}, chunk=5, out=out)
    (out / "chunks" / "chunk-000000.npz").unlink()
    with pytest.raises(ValueError, match="incomplete"):
        load_sweep(out)


def _complete_chunks(folder):
    """Chunk files written in full (a chunk is written as chunk-N.<pid>.tmp.npz, then renamed)."""
    return sorted(p for p in Path(folder).glob("chunk-*.npz") if not p.name.endswith(".tmp.npz"))


def _files(folder):
    out = {}
    for p in _complete_chunks(folder):
        st = p.stat()
        out[p.name] = (st.st_ino, st.st_mtime_ns, hashlib.sha256(p.read_bytes()).hexdigest())
    return out


def test_killed_sweep_resumes_without_loss_or_duplicates(tmp_path, capsys):
    out = tmp_path / "killed"
    args = ["paper-parabola", "--vary", "qdot=3:12:12", "--vary", "mu=0.01:0.2:25", "--vary", "k=0.8",
            "--chunk", "4", "--log-events", "8", "-o", str(out), "--backend", "python", "--quiet"]
    env = dict(os.environ, SYMVIB_BACKEND="python")
    proc = subprocess.Popen([sys.executable, "-m", "symvib.cli", "sweep", *args], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and len(_complete_chunks(out / "chunks")) < 3:
        if proc.poll() is not None:
            break
        time.sleep(0.01)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    before = _files(out / "chunks")
    assert 3 <= len(before) < 75, "the sweep must be killed midway"
    assert main(args) == 0
    assert f"{75 - len(before)} chunk(s) computed, {len(before)} reused" in capsys.readouterr().out
    after = _files(out / "chunks")
    assert len(after) == 75
    for name, stamp in before.items():    # nothing recomputed or rewritten
        assert after[name] == stamp
    res = load_sweep(out)
    assert np.array_equal(res["row"], np.arange(300))    # every row once, in order
    mem = sweep(_resolve_scene("paper-parabola"), {"qdot": "3:12:12", "mu": "0.01:0.2:25", "k": "0.8"},
                chunk=4, log_events=8)
    for name in mem.columns:
        assert np.array_equal(res[name], mem[name])


# --------------------------------------------------------------------- progress and maps

class _Stream:
    def __init__(self):
        self.text = ""

    def write(self, s):
        self.text += s

    def flush(self):
        pass


def test_progress_bar_reports_rate_and_time_left():
    stream = _Stream()
    bar = Progress(1000, stream=stream)
    time.sleep(0.01)
    bar.update(250, final=True)
    assert "250/1000" in stream.text and "scenes/s" in stream.text and "left" in stream.text
    assert "25.0%" in stream.text


def test_maps_are_png_files(tmp_path):
    from symvib.numeric.sweepmaps import MAPS, sweep_maps

    grid = sweep(base(), {"qdot": "3:12:4", "mu": "0.01:0.2:3", "k": "0.8,1"})
    rand = sweep(base(), {"qdot": "3:12", "mu": "0.01:0.2"}, random=20)
    line = sweep(base(), {"qdot": "3:12:4"})
    for res, folder in ((grid, "g"), (rand, "r"), (line, "l")):
        paths = sweep_maps(res, tmp_path / folder)
        assert [p.stem for p in paths] == list(MAPS)
        for p in paths:
            data = p.read_bytes()
            assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000


def test_cli_sweep_file_and_plot(tmp_path, capsys):
    scene = tmp_path / "scene.toml"
    scene.write_text('[curve]\nshape = "circle"\n[parameters]\nR = 1\n[physics]\nmu = 0.1\nrestitution = 0.8\n'
                     '[limiters]\nleft = "-pi/3"\nright = "pi/4"\n[initial]\nq = 0\nqdot = 3.8\n')
    sw = tmp_path / "sweep.toml"
    sw.write_text('scene = "scene.toml"\nchunk = 4\n[vary]\nqdot = "2:6:3"\nrestitution = "0.5:1:3"\n')
    out = tmp_path / "out"
    assert main(["--file", str(sw), "-o", str(out), "--plot", "--quiet"]) == 0
    text = capsys.readouterr().out
    assert "sweep of 9 scenes" in text and (out / "maps" / "impacts.png").exists()
    assert load_sweep(out).spec.scene.shape.name == "circle"


# --------------------------------------------------------------------- Dask

def test_dask_local_cluster_gives_the_in_process_results(tmp_path):
    distributed = pytest.importorskip("dask.distributed")
    vary = {"qdot": "3:12:5", "mu": "0.01:0.2:4", "k": "0.8"}
    mem = sweep(base(), vary, chunk=3, log_events=8)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        res = sweep(base(), vary, chunk=3, log_events=8, out=tmp_path / "dask", scheduler=client)
        by_address = sweep(base(), vary, chunk=3, log_events=8, out=tmp_path / "dask2",
                           scheduler=cluster.scheduler_address)
    assert len(res.computed) == 7 and len(by_address.computed) == 7
    for name in mem.columns:
        assert np.array_equal(res[name], mem[name])
        assert np.array_equal(by_address[name], mem[name])


def test_run_chunk_is_a_pure_function_of_its_definition():
    spec = make_spec(base(), {"qdot": "3:12:5"}, chunk=2)
    a = run_chunk(spec.to_dict(), 1)
    b = run_chunk(spec.to_dict(), 1)
    assert list(a["row"]) == [2, 3]
    for name in a:
        assert np.array_equal(a[name], b[name])


@pytest.mark.parametrize("backend, noted", [("python", True), ("auto", False)])
def test_a_sweep_on_the_slow_path_says_so_before_it_starts(backend, noted, tmp_path, capsys, monkeypatch):
    from symvib.cli import main as cli_main
    from symvib.numeric import driver

    if backend == "auto" and not driver.backend_available("numba"):
        pytest.skip("the auto backend is the plain one without numba")
    monkeypatch.delenv("SYMVIB_BACKEND", raising=False)
    args = ["sweep", "paper-parabola", "--vary", "qdot=6:7:2", "-o", str(tmp_path / "o"), "--backend", backend]
    assert cli_main(args) == 0
    err = capsys.readouterr().err
    assert ("plain-Python engine" in err and 'pip install numba' in err) is noted
