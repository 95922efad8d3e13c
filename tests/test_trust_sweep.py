"""Trust (issue 13), sweep lane: scenes round-trip, user curves sweep, sweep data never mixes,
sizes are checked before memory is spent, bad folders and files end in one-line errors."""
import json
import math

import numpy as np
import pytest

from symvib import simulate, sweep
from symvib.cli import sweep_main as main
from symvib.cli.common import EXIT_RUN_FAILED
from symvib.numeric.scene import SceneError, scene_from_dict
from symvib.shapes import CATALOGUE

#: The README's own user curve (a graph z = f(x)).
BOWL = {
    "name": "bowl-scene",
    "curve": {"name": "bowl", "z": "R - sqrt(R**2 - x**2)", "domain": ["-R", "R"]},
    "parameters": {"R": 0.5},
    "physics": {"alpha0": 0.05, "restitution": 0.8},
    "limiters": {"left": -0.2, "right": 0.35},
    "initial": {"q": 0.1, "qdot": 3.0},
}
#: A parametric user curve x(q), z(q), with h and alpha given and a parameter assumption.
WHEEL = {
    "curve": {"name": "wheel", "x": "R*sin(t)", "z": "R*(1 - cos(t))", "q": "t", "h": "R", "alpha": "t",
              "domain": ["-pi", "pi"], "q_scale": "1", "params": {"R": "positive"}},
    "parameters": {"R": 0.5},
    "physics": {"mu": 0.1, "restitution": 1.0, "g": 9.0, "m": 2.0},
    "limiters": {"right": "pi/4"},
    "initial": {"q": 0.0, "qdot": 4.0},
    "run": {"t_max": 50.0, "max_events": 500},
}
#: A graph in a coordinate of its own name, no limiters, default domain.
SLOPE = {"curve": {"z": "c*u**4", "q": "u"}, "parameters": {"c": 2.0},
         "physics": {"mu": 0.0, "restitution": 0.5}, "initial": {"q": 0.3, "qdot": 0.0}}


def _catalogue_scene(name):
    sh = CATALOGUE[name]
    return {"curve": {"shape": name}, "parameters": dict(sh.defaults),
            "physics": {"alpha0": 0.05, "restitution": 0.8}, "initial": {"q": 0.0, "qdot": 1.0}}


SCENES = {**{f"catalogue-{n}": _catalogue_scene(n) for n in CATALOGUE},
          "graph-bowl": BOWL, "parametric-wheel": WHEEL, "graph-own-coordinate": SLOPE}


# --------------------------------------------------------------------- class 5: Scene.to_dict round-trips

@pytest.mark.parametrize("key", sorted(SCENES))
def test_to_dict_round_trips_every_curve_kind(key):
    s = scene_from_dict(SCENES[key])
    data = s.to_dict()
    again = scene_from_dict(data)
    assert again == s
    assert again.shape == s.shape and again.shape.kind == s.shape.kind
    assert again.alpha0 == s.alpha0          # compare=False on Scene: checked by hand
    assert again.name == s.name
    via_json = scene_from_dict(json.loads(json.dumps(data)))   # what a manifest and a Dask task carry
    assert via_json == s and via_json.alpha0 == s.alpha0
    assert "kind" not in data["curve"]


def test_to_dict_writes_mu_when_no_friction_angle_was_given():
    s = scene_from_dict(WHEEL)
    assert s.to_dict()["physics"]["mu"] == 0.1 and "alpha0" not in s.to_dict()["physics"]
    t = scene_from_dict(BOWL).replace(mu=0.3)      # mu replaced: the old angle no longer holds
    assert t.alpha0 is None and scene_from_dict(t.to_dict()).mu == 0.3
    u = scene_from_dict(WHEEL).replace(alpha0=0.2)
    assert u.to_dict()["physics"] == {"g": 9.0, "m": 2.0, "alpha0": 0.2, "restitution": 1.0, "contact": "bilateral"}


def test_to_dict_writes_contact_only_where_the_scene_has_one():
    s = scene_from_dict(BOWL)
    assert ("contact" in s.to_dict()["physics"]) == (getattr(s, "contact", None) is not None)


# --------------------------------------------------------------------- class 5: user curves sweep

@pytest.fixture
def bowl():
    return scene_from_dict(BOWL)


def test_user_curve_sweeps_through_the_api_like_the_driver(bowl, tmp_path):
    res = sweep(bowl, {"qdot": "1:4:3", "R": "0.5,0.6"}, log_events=16, out=tmp_path / "bowl")
    assert res.count == 6 and res.spec.scene == bowl
    for row in range(res.count):
        one = bowl.replace(qdot0=float(res["initial.qdot"][row]), params={"R": float(res["parameters.R"][row])})
        ref = simulate(one, samples=False)
        assert int(res["events"][row]) == len(ref.events)
        assert res.status_names()[row] == ref.status.value
        assert res["t_final"][row] == pytest.approx(ref.t_final, rel=1e-12, abs=1e-12)
    assert (res["impacts"] > 0).any()


def test_user_curve_sweeps_through_the_cli(tmp_path, capsys):
    scene = tmp_path / "bowl.toml"
    scene.write_text('name = "bowl-scene"\n[curve]\nname = "bowl"\nz = "R - sqrt(R**2 - x**2)"\n'
                     'domain = ["-R", "R"]\n[parameters]\nR = 0.5\n[physics]\nalpha0 = 0.05\nrestitution = 0.8\n'
                     '[limiters]\nleft = -0.2\nright = 0.35\n[initial]\nq = 0.1\nqdot = 3.0\n')
    out = tmp_path / "out"
    assert main([str(scene), "--vary", "qdot=1:4:4", "--vary", "mu=0.01,0.1", "-o", str(out), "--quiet"]) == 0
    text = capsys.readouterr().out
    assert "sweep of 8 scenes of bowl-scene" in text and "0 reused" in text
    assert main([str(scene), "--vary", "qdot=1:4:4", "--vary", "mu=0.01,0.1", "-o", str(out), "--quiet"]) == 0
    assert "0 chunk(s) computed, 1 reused" in capsys.readouterr().out


# --------------------------------------------------------------------- class 6: sizes before memory

import os  # noqa: E402
import socket  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import tracemalloc  # noqa: E402
from pathlib import Path  # noqa: E402

from symvib.cli.common import EXIT_FAILED_SCENES  # noqa: E402
from symvib.numeric.sweep import FORMAT, MAX_LIST_VALUES, SweepError, WriterLock, load_sweep, make_spec, sweep_id  # noqa: E402
from symvib.numeric.sweep import lock as lock_mod  # noqa: E402
from symvib.numeric.sweep import result as result_mod  # noqa: E402
from symvib.numeric.sweep import runner as runner_mod  # noqa: E402
from symvib.numeric.sweep.axes import linspace_at as _linspace_at  # noqa: E402

PARABOLA = {"curve": {"shape": "parabola"}, "parameters": {"p": 1.0},
            "physics": {"g": 9.81, "m": 0.2, "mu": 0.05, "restitution": 0.8},
            "limiters": {"left": "-pi/6", "right": "pi/4"}, "initial": {"q": 0.0, "qdot": 7.0}}
#: Bytes a definition may cost while it is checked (an axis of 10**9 values once cost 14 GB).
SMALL = 2_000_000


def parabola():
    return scene_from_dict(PARABOLA)


@pytest.mark.parametrize("start, stop, count", [
    (3.0, 12.0, 400), (0.01, 0.2, 250), (-math.pi / 3, -math.pi / 12, 10), (0.0, 1.0, 2), (1.0, 1.0, 5),
    (2.5, 2.5, 1), (12.0, 3.0, 7), (5e-324, 1e-323, 9), (-1e300, 1e300, 11), (0.1, 0.7, 1000),
])
def test_grid_values_are_numpy_linspace_bit_for_bit(start, stop, count):
    ref = np.linspace(start, stop, count) if count > 1 else np.array([start])
    idx = np.arange(count)
    assert np.array_equal(_linspace_at(start, stop, count, idx), ref)
    assert np.array_equal(_linspace_at(start, stop, count, idx[::-3]), ref[::-3])


@pytest.mark.parametrize("vary, kwargs, field", [
    ({"qdot": "3:12:1000000000"}, {}, "vary.qdot"),                       # the issue's 14 GB tuple
    ({"qdot": "3:12:100000", "mu": "0.01:0.2:100000"}, {}, "vary"),       # 10**10 scenes
    ({"qdot": "3:12:4"}, {"log_events": 100_000_000}, "log_events"),      # the issue's 16 GB event log
    ({"qdot": "3:12:4096"}, {"log_events": 1_000_000}, "chunk"),          # a chunk's log: 196 GB
    ({"qdot": "3:12:4096"}, {"log_events": 6000}, "chunk"),               # 1.18 GB > MAX_CHUNK_BYTES
    ({"qdot": "3:12:4"}, {"log_events": 10**7}, "log_events"),            # > MAX_LOG_EVENTS
    ({"qdot": "3:12:1000000"}, {"log_events": 1000, "chunk": 1000}, "log_events"),   # 48 GB in all
    ({"qdot": "3:12:10000000"}, {"chunk": 1}, "chunk"),                   # 10**7 chunk files
    ({"qdot": "3:12:4"}, {"nodes": 1}, "nodes"),
    ({"qdot": "3:12:4"}, {"nodes": 65}, "nodes"),
    ({"qdot": "3:12:4"}, {"nodes": True}, "nodes"),
    ({"qdot": "3:12:4"}, {"chunk": 2.5}, "chunk"),
    ({"qdot": "3:12:4"}, {"seed": -1}, "seed"),
    ({"qdot": "3:12"}, {"random": 10**12}, "random"),
    ({"k": ",".join(["0.5"] * (MAX_LIST_VALUES + 1))}, {}, "vary.k"),
    ({"k": [0.5] * (MAX_LIST_VALUES + 1)}, {}, "vary.k"),
    ({"max_events": "1e19"}, {}, "run.max_events"),                        # overflows int64 in the core
    ({"max_events": "2.5"}, {}, "run.max_events"),
])
def test_sizes_are_checked_before_memory_is_spent(vary, kwargs, field):
    tracemalloc.start()
    try:
        with pytest.raises(SceneError) as info:
            make_spec(parabola(), vary, **kwargs)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert info.value.field == field and "\n" not in str(info.value)
    assert peak < SMALL + 40 * MAX_LIST_VALUES   # a listed axis's own text is the only size paid


def test_a_large_grid_costs_three_numbers_until_its_chunks_run():
    tracemalloc.start()
    try:
        spec = make_spec(parabola(), {"qdot": "3:12:100000000"})
        text = json.dumps(spec.to_dict())
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < SMALL and len(text) < 10_000 and spec.count == 10**8
    rows, (values,) = spec.rows(spec.chunks - 1)
    assert rows[-1] == 10**8 - 1 and values[-1] == 12.0
    assert np.allclose(values, 3.0 + rows * (9.0 / (10**8 - 1)), rtol=1e-15, atol=0)


def test_cli_refuses_sizes_before_creating_the_folder(tmp_path, capsys):
    out = tmp_path / "never"
    assert main(["paper-parabola", "--vary", "qdot=3:12:1000000000", "-o", str(out), "--quiet"]) == 2
    assert main(["paper-parabola", "--vary", "qdot=3:12:4", "--log-events", "100000000", "-o", str(out)]) == 2
    assert main(["paper-parabola", "--vary", "qdot=3:12:4", "--nodes", "100", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 3 and "vary.qdot" in err[0] and "log_events" in err[1] and "nodes" in err[2]
    assert not out.exists()


# --------------------------------------------------------------------- classes 4 and 7: storage

VARY = {"qdot": "3:12:4", "mu": "0.01:0.2:3"}
CHUNK = 5


def _written(tmp_path, name="sw", vary=VARY, **kw):
    out = tmp_path / name
    sweep(parabola(), vary, chunk=CHUNK, out=out, **kw)
    return out


def _chunk(out, i):
    return out / "chunks" / f"chunk-{i:06d}.npz"


def _rewrite(path, **changes):
    """Rewrite a chunk file with some columns changed (None removes one)."""
    with np.load(path) as data:
        cols = {k: data[k] for k in data.files}
    for k, v in changes.items():
        if v is None:
            cols.pop(k)
        else:
            cols[k] = v(cols) if callable(v) else v
    with open(path, "wb") as fh:
        np.savez(fh, **cols)


def _lying_header(path):
    """A chunk whose impacts member declares 10**12 rows (8 TB) and holds none."""
    import io
    import zipfile

    with np.load(path) as data:
        cols = {k: data[k] for k in data.files}
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, {"descr": "<i8", "fortran_order": False, "shape": (10**12,)})
    with zipfile.ZipFile(path, "w") as z:
        for k, v in cols.items():
            if k == "impacts":
                z.writestr("impacts.npy", buf.getvalue())
            else:
                member = io.BytesIO()
                np.save(member, v)
                z.writestr(f"{k}.npy", member.getvalue())


def test_manifest_and_every_chunk_carry_the_sweep_identity(tmp_path):
    out = _written(tmp_path)
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["format"] == FORMAT == "symvib-sweep/2"
    assert manifest["sweep_id"] == sweep_id(manifest["definition"]) == sweep_id(
        make_spec(parabola(), VARY, chunk=CHUNK).to_dict())
    assert manifest["definition"]["axes"][0] == {"key": "qdot", "field": "initial.qdot", "start": 3.0,
                                                 "stop": 12.0, "count": 4}
    for i in range(manifest["chunks"]):
        with np.load(_chunk(out, i)) as data:
            assert str(data["sweep_id"]) == manifest["sweep_id"]
    assert not (out / "sweep.lock").exists()       # released
    other = make_spec(parabola(), {"qdot": "3:12:4", "mu": "0.01:0.2:4"}, chunk=CHUNK).to_dict()
    assert sweep_id(other) != manifest["sweep_id"]


#: Ways a chunk file goes bad: name -> (how, what the error says).
BAD_CHUNKS = {
    "truncated": (lambda p, other: p.write_bytes(p.read_bytes()[: p.stat().st_size // 2]), "truncated"),
    "empty": (lambda p, other: p.write_bytes(b""), "truncated"),
    "garbage": (lambda p, other: p.write_bytes(b"PK\x03\x04" + bytes(range(256)) * 4), "truncated"),
    "foreign": (lambda p, other: p.write_bytes(other.read_bytes()), "another sweep"),
    "no identity": (lambda p, other: _rewrite(p, sweep_id=None), "no sweep identity"),
    "identity of bytes": (lambda p, other: _rewrite(p, sweep_id=np.frombuffer(b"x" * 32, dtype=np.uint8)),
                          "column sweep_id"),
    "identity too long": (lambda p, other: _rewrite(p, sweep_id=np.array("x" * 10**6)), "column sweep_id"),
    "float32 row": (lambda p, other: _rewrite(p, row=lambda c: c["row"].astype(np.float32)), "column row"),
    "short column": (lambda p, other: _rewrite(p, impacts=lambda c: c["impacts"][:-1]), "column impacts"),
    "extra column": (lambda p, other: _rewrite(p, extra=np.zeros(5)), "columns"),
    "missing column": (lambda p, other: _rewrite(p, zeno_ratio=None), "columns"),
    "other rows": (lambda p, other: _rewrite(p, row=lambda c: c["row"] + 5), "rows"),
    "other values": (lambda p, other: _rewrite(p, **{"physics.mu": lambda c: c["physics.mu"] * 2}), "varied"),
    "status out of range": (lambda p, other: _rewrite(p, status=lambda c: c["status"] + 99), "status"),
    "pickled object": (lambda p, other: _rewrite(p, impacts=np.array([object()] * 5, dtype=object)),
                       "column impacts"),
    "lying header": (lambda p, other: _lying_header(p), "column impacts is int64[1000000000000]"),
    "a directory": (lambda p, other: (p.unlink(), p.mkdir()), "truncated or unreadable"),
}


def _refused_load(out):
    """The SweepError of ``load_sweep(out)`` and the peak memory it took to refuse."""
    tracemalloc.start()
    try:
        with pytest.raises(SweepError) as info:
            load_sweep(out)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    return info, peak


@pytest.mark.parametrize("how", sorted(BAD_CHUNKS))
def test_a_bad_chunk_is_refused_on_load_and_recomputed_on_resume(tmp_path, how):
    mem = sweep(parabola(), VARY, chunk=CHUNK)
    out = _written(tmp_path)
    other = _written(tmp_path, "other", vary={"qdot": "3:12:4", "mu": "0.01:0.3:3"})
    spoil, says = BAD_CHUNKS[how]
    spoil(_chunk(out, 1), _chunk(other, 1))
    info, peak = _refused_load(out)
    assert info.value.field == str(_chunk(out, 1)) and says in info.value.reason and peak < SMALL
    assert "\n" not in str(info.value)
    if how == "a directory":
        _chunk(out, 1).rmdir()       # a folder in place of a chunk: not removed for the user
        mem_again = sweep(parabola(), VARY, chunk=CHUNK, out=out)
        assert mem_again.computed == (1,)
        return
    again = sweep(parabola(), VARY, chunk=CHUNK, out=out)
    assert again.discarded == (1,) and again.computed == (1,) and again.reused == (0, 2)
    for name in mem.columns:
        assert np.array_equal(again[name], mem[name])


def _manifest_of(out):
    return json.loads((out / "manifest.json").read_text())


#: Bad manifests: name -> (the text written, a phrase of the error).
BAD_MANIFESTS = {
    "empty list": ("[]", "JSON object"),
    "not json": ("format = 'toml?'", "not a JSON manifest"),
    "empty": ("", "not a JSON manifest"),
    "deep nesting": ("[" * 200_000 + "]" * 200_000, "not a JSON manifest"),
    "not utf-8": (b"\xff\xfe{}", "not a JSON manifest"),
    "a number": ("3", "JSON object"),
    "no format": ('{"definition": {}}', "unknown format"),
    "old format": ('{"format": "symvib-sweep/1", "definition": {}}', "symvib-sweep/1"),
    "definition a number": (lambda m: m | {"definition": 3}, "definition: must be a table"),
    "no sweep id": (lambda m: {k: v for k, v in m.items() if k != "sweep_id"}, "sweep_id"),
    "edited": (lambda m: m | {"definition": m["definition"] | {"seed": 5}}, "sweep_id"),
    "unknown key": (lambda m: m | {"definition": m["definition"] | {"extra": 1}}, "definition.extra"),
    "huge log": (lambda m: m | {"definition": m["definition"] | {"log_events": 10**8}}, "definition.log_events"),
    "huge axis": (lambda m: _axis0(m, count=10**12), "definition.axes[0].count"),
    "axis count text": (lambda m: _axis0(m, count="4"), "definition.axes[0].count"),
    "axis nan": (lambda m: _axis0(m, start=float("nan")), "non-finite number NaN"),
    "infinity": (lambda m: m | {"definition": m["definition"] | {"seed": float("inf")}}, "non-finite number"),
    "axis kinds mixed": (lambda m: _axis0(m, low=1.0), "definition.axes[0]"),
    "axis field": (lambda m: _axis0(m, field="physics.evil"), "definition.axes[0].field"),
    "count lies": (lambda m: m | {"definition": m["definition"] | {"count": 11}}, "definition.count"),
    "mode": (lambda m: m | {"definition": m["definition"] | {"mode": "random"}}, "definition.mode"),
    "scene": (lambda m: m | {"definition": m["definition"] | {"scene": {"curve": 1}}}, "definition.scene"),
    "nodes": (lambda m: m | {"definition": m["definition"] | {"nodes": 1000}}, "definition.nodes"),
}


def _axis0(m, **changes):
    d = json.loads(json.dumps(m["definition"]))
    d["axes"][0].update(changes)
    return m | {"definition": d}


def _spoil_manifest(out, how):
    text = BAD_MANIFESTS[how][0]
    path = out / "manifest.json"
    if callable(text):
        m = text(_manifest_of(out))
        if "sweep_id" in m and m.get("definition") != _manifest_of(out)["definition"] and how != "edited":
            try:
                m["sweep_id"] = sweep_id(m["definition"])    # a consistent but hostile manifest
            except ValueError:
                pass                                         # NaN: no identity can be made of it
        text = json.dumps(m)
    path.write_bytes(text if isinstance(text, bytes) else text.encode())


@pytest.mark.parametrize("how", sorted(BAD_MANIFESTS))
def test_a_bad_manifest_is_a_one_line_error_and_overwrite_replaces_it(tmp_path, how, capsys):
    out = _written(tmp_path)
    _spoil_manifest(out, how)
    info, peak = _refused_load(out)
    assert "manifest.json" in info.value.field and BAD_MANIFESTS[how][1] in str(info.value)
    assert "\n" not in str(info.value) and peak < 50 * SMALL
    with pytest.raises(SweepError, match="--overwrite"):
        sweep(parabola(), VARY, chunk=CHUNK, out=out)
    args = ["paper-parabola", "--vary", "qdot=3:12:4", "-o", str(out), "--quiet"]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "manifest.json" in err
    assert main(args + ["--overwrite"]) == 0
    assert load_sweep(out).count == 4


def test_incomplete_sweep_is_a_sweep_error_naming_the_folder(tmp_path):
    out = _written(tmp_path)
    _chunk(out, 2).unlink()
    with pytest.raises(SweepError, match="incomplete: 1 of 3 chunks missing") as info:
        load_sweep(out)
    assert info.value.field == str(out)
    with pytest.raises(SweepError, match="no sweep here"):
        load_sweep(tmp_path / "nothing")


# --------------------------------------------------------------------- class 7: output paths

def _file(tmp_path):
    p = tmp_path / "a-file"
    p.write_text("x")
    return p


def _folder_with(tmp, name, entry, kind):
    folder = tmp / name
    folder.mkdir()
    if kind == "link":
        (tmp / "elsewhere").mkdir()
        (folder / entry).symlink_to(tmp / "elsewhere")
    else:
        (folder / entry).mkdir() if kind == "dir" else (folder / entry).write_text("x")
    return folder


OUT_PATHS = {
    "a file": (lambda tmp: _file(tmp), "not a folder"),
    "a device": (lambda tmp: Path("/dev/null"), "not a folder"),
    "below a file": (lambda tmp: _file(tmp) / "sub", "is a file"),
    "below a device": (lambda tmp: Path("/dev/null/sub"), "is a file"),
    "unwritable system folder": (lambda tmp: Path("/sys/symvib-sweep-out"), "cannot create the folder"),
    "chunks is a file": (lambda tmp: _folder_with(tmp, "o", "chunks", "file"), "not a folder"),
    "manifest is a folder": (lambda tmp: _folder_with(tmp, "m", "manifest.json", "dir"), "not a regular file"),
    "chunks is a symbolic link": (lambda tmp: _folder_with(tmp, "s", "chunks", "link"), "symbolic link"),
    "not a path": (lambda tmp: 5, "must be a folder path"),
    "NUL in the name": (lambda tmp: str(tmp / "a\0b"), "not a usable folder name"),
}


@pytest.mark.parametrize("how", sorted(OUT_PATHS))
def test_unusable_output_paths_are_one_line_errors(tmp_path, how, capsys):
    make, says = OUT_PATHS[how]
    out = make(tmp_path)
    with pytest.raises(SweepError) as info:
        sweep(parabola(), {"qdot": "3:12:2"}, out=out)
    assert says in str(info.value) and "\n" not in str(info.value)
    if not isinstance(out, (str, Path)):
        return                                   # the command line passes text only
    assert main(["paper-parabola", "--vary", "qdot=3:12:2", "-o", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and says in err


@pytest.mark.skipif(hasattr(os, "geteuid") and os.geteuid() == 0, reason="root may write any folder")
def test_a_read_only_folder_is_refused(tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    try:
        with pytest.raises(SweepError, match="not writable|cannot create"):
            sweep(parabola(), {"qdot": "3:12:2"}, out=ro / "out")
    finally:
        ro.chmod(0o700)


# --------------------------------------------------------------------- class 4: one writer per folder

def _dead_pid():
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def _lock(out, **fields):
    out.mkdir(parents=True, exist_ok=True)
    data = {"pid": os.getpid(), "host": socket.gethostname(), "nonce": "n" * 32, "since": "now"} | fields
    (out / WriterLock.NAME).write_text(json.dumps(data))


def _snapshot(out):
    return {p.relative_to(out): p.read_bytes() for p in sorted(out.rglob("*")) if p.is_file()}


def test_a_held_lock_stops_a_second_writer_even_with_overwrite(tmp_path, capsys):
    out = _written(tmp_path)
    _lock(out)                                   # this (live) process holds it
    before = _snapshot(out)
    other = {"qdot": "3:12:4", "mu": "0.01:0.3:3"}
    with pytest.raises(SweepError, match=r"another sweep writes .* \(pid \d+ on .*\)") as info:
        sweep(parabola(), other, chunk=CHUNK, out=out, overwrite=True)
    assert info.value.field == "out" and "\n" not in str(info.value)
    assert main(["paper-parabola", "--vary", "qdot=3:12:4", "-o", str(out), "--overwrite", "--quiet"]) == 2
    assert "another sweep writes" in capsys.readouterr().err
    assert _snapshot(out) == before              # nothing of the folder touched
    assert load_sweep(out).spec.to_dict() == make_spec(parabola(), VARY, chunk=CHUNK).to_dict()


@pytest.mark.parametrize("holder, taken", [
    ({"pid": "dead"}, True),                     # a killed sweep on this host
    ({"host": "elsewhere.example"}, False),      # cannot tell: another machine's sweep
    ({"pid": "dead", "host": "elsewhere.example"}, False),
    ({"pid": 1}, False),                         # alive (init)
    ({"pid": -5}, False),
    ({"pid": 2**80}, False),
    ({"pid": True}, False),
])
def test_stale_locks_of_dead_local_writers_are_taken_over(tmp_path, holder, taken):
    out = tmp_path / "sw"
    if holder.get("pid") == "dead":
        holder = holder | {"pid": _dead_pid()}
    _lock(out, **holder)
    if taken:
        res = sweep(parabola(), VARY, chunk=CHUNK, out=out)
        assert res.count == 12 and not (out / WriterLock.NAME).exists()
    else:
        with pytest.raises(SweepError, match="another sweep writes"):
            sweep(parabola(), VARY, chunk=CHUNK, out=out)


def test_an_empty_lock_is_stale_only_after_its_grace_time(tmp_path):
    out = tmp_path / "sw"
    out.mkdir()
    lock = out / WriterLock.NAME
    lock.write_bytes(b"")
    with pytest.raises(SweepError, match="lock file being written"):
        sweep(parabola(), VARY, chunk=CHUNK, out=out)
    old = time.time() - 2 * lock_mod.LOCK_GRACE
    os.utime(lock, (old, old))
    assert sweep(parabola(), VARY, chunk=CHUNK, out=out).count == 12


def test_writer_lock_excludes_verifies_and_releases_only_its_own(tmp_path):
    a = WriterLock(tmp_path).acquire()
    with pytest.raises(SweepError, match="another sweep writes"):
        WriterLock(tmp_path).acquire()
    a.verify()
    (tmp_path / WriterLock.NAME).write_text(json.dumps({"pid": 1, "host": "h", "nonce": "other"}))
    with pytest.raises(SweepError, match="lost the lock"):
        a.verify()
    a.release()                                  # not ours any more: left in place
    assert (tmp_path / WriterLock.NAME).exists()


def test_a_writer_that_loses_its_lock_stops_before_writing_another_chunk(tmp_path, monkeypatch):
    out = tmp_path / "sw"
    real = runner_mod.run_chunk
    calls = []

    def run_chunk(definition, index, backend="auto"):
        calls.append(index)
        if index == 1:   # another writer takes the folder over while chunk 1 computes
            (out / WriterLock.NAME).write_text(json.dumps({"pid": 1, "host": "h", "nonce": "thief"}))
        return real(definition, index, backend)

    monkeypatch.setattr(runner_mod, "run_chunk", run_chunk)
    with pytest.raises(SweepError, match="lost the lock"):
        sweep(parabola(), VARY, chunk=CHUNK, out=out)
    assert calls == [0, 1] and sorted(p.name for p in (out / "chunks").iterdir()) == ["chunk-000000.npz"]


#: Seconds the first writer of the race test waits before each chunk (75 chunks: the second
#: writer surely comes while it writes).
SLOW_CHUNK = 0.05


@pytest.mark.slow
def test_the_issues_race_two_processes_one_folder(tmp_path, capsys):
    """A sweep restarted with --overwrite while another writes the folder: refused, nothing mixed."""
    out = tmp_path / "race"
    first = ["paper-parabola", "--vary", "qdot=3:12:12", "--vary", "mu=0.01:0.2:25", "--chunk", "4",
             "-o", str(out), "--backend", "python", "--quiet"]
    env = dict(os.environ, SYMVIB_BACKEND="python")
    slow_writer = ("import sys, time\nimport symvib.cli as cli\nimport symvib.numeric.sweep.runner as s\n"
                   "real = s.run_chunk\n"
                   "s.run_chunk = lambda *a, **k: (time.sleep(SLOW_CHUNK), real(*a, **k))[1]\n"
                   "sys.exit(cli.sweep_main(sys.argv[1:]))\n").replace("SLOW_CHUNK", repr(SLOW_CHUNK))
    proc = subprocess.Popen([sys.executable, "-c", slow_writer, *first], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and proc.poll() is None and not _chunk(out, 0).exists():
            time.sleep(0.01)
        assert proc.poll() is None, "the first sweep must still be running"
        second = ["paper-parabola", "--vary", "qdot=3:12:12", "--vary", "mu=0.01:0.3:25", "--chunk", "4",
                  "-o", str(out), "--overwrite", "--quiet"]
        assert main(second) == 2
        assert "another sweep writes" in capsys.readouterr().err
    finally:
        stdout, stderr = proc.communicate(timeout=300)
    assert proc.returncode == 0, stderr
    res = load_sweep(out)                        # every chunk checked against the first sweep's identity
    assert res.spec.axes[1].stop == 0.2 and np.array_equal(res["row"], np.arange(300))
    assert main(second) == 0                     # once the first is done, --overwrite replaces it
    assert load_sweep(out).spec.axes[1].stop == 0.3


# --------------------------------------------------------------------- sweep files

@pytest.mark.parametrize("text, field", [
    ('scene = "paper-parabola"\nvary = 3\n', "vary"),
    ('scene = "paper-parabola"\nvary = [1, 2]\n', "vary"),
    ('scene = 5\n[vary]\nqdot = "3:12:2"\n', "scene"),
    ('scene = ""\n[vary]\nqdot = "3:12:2"\n', "scene"),
    ('scene = "paper-parabola"\nout = 5\n[vary]\nqdot = "3:12:2"\n', "out"),
    ('scene = "paper-parabola"\nchunk = "4"\n[vary]\nqdot = "3:12:2"\n', "chunk"),
    ('scene = "paper-parabola"\nrandom = true\n[vary]\nqdot = "3:12"\n', "random"),
    ('scene = "paper-parabola"\nseed = 1.5\n[vary]\nqdot = "3:12:2"\n', "seed"),
    ('scene = "paper-parabola"\nlog_events = 100000000\n[vary]\nqdot = "3:12:2"\n', "log_events"),
    ('scene = "paper-parabola"\n[vary]\nqdot = [[1, 2], [3, 4]]\n', "vary.qdot"),
    ('scene = "paper-parabola"\n[vary]\nqdot = 1979-05-27\n', "vary.qdot"),
    ('scene = "paper-parabola"\n[vary.qdot]\nstart = 3\nstop = 12\ncount = 1000000000\n', "vary.qdot"),
    # the session's new surfaces: sensitivity columns and static friction
    ('scene = "paper-parabola"\nsensitivities = 5\n[vary]\nqdot = "6,7"\n', "sensitivities"),
    ('scene = "paper-parabola"\nsensitivities = ["mu", 1]\n[vary]\nqdot = "6,7"\n', "sensitivities"),
    ('scene = "paper-parabola"\nsensitivities = "nu"\n[vary]\nqdot = "6,7"\n', "sensitivities: 'nu'"),
    ('scene = "paper-parabola"\nsensitivities = "__import__(\'os\')"\n[vary]\nqdot = "6,7"\n', "sensitivities"),
    ('scene = "paper-parabola"\n[vary]\nmu_s = "nan,0.3"\n', "vary.mu_s"),
    ('scene = "paper-parabola"\n[vary]\nmu_s = [0.2, "x"]\n', "vary.mu_s: name 'x'"),
    ('scene = "paper-parabola"\n[vary]\nmu_s = "-0.1,0.3"\n', "physics.mu_s: static friction coefficient must be >= 0"),
    ('scene = "paper-parabola"\n[vary]\nmu_s = "0.01,0.3"\n', "physics.mu_s: static friction coefficient 0.01"),
    ('scene = "paper-parabola"\n[vary]\nalpha0_s = "0.2,2.0"\n', "physics.alpha0_s: friction angle must be in"),
    ('scene = "paper-parabola"\n[vary]\nmu_s = "0.2,0.3"\nalpha0_s = "0.2,0.3"\n', "vary: vary mu_s or alpha0_s"),
    ('scene = "paper-parabola"\n[vary.mu_s]\nlow = 0.2\nhigh = 0.3\n', "vary.mu_s: a table of start, stop"),
    ('scene = "paper-parabola"\n[vary.mu_s]\nstart = 0.2\n', "'stop' is missing"),
])
def test_hostile_sweep_files_are_one_line_errors(tmp_path, capsys, text, field):
    sw = tmp_path / "sweep.toml"
    sw.write_text(text)
    assert main(["--file", str(sw), "-o", str(tmp_path / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and field in err and "Traceback" not in err


@pytest.mark.parametrize("text, extra, prefix", [
    ('scene = "paper-parabola"\n[vary]\nqdot = "abc"\n', [], "sweep.toml:vary.qdot: name 'abc'"),
    ('scene = "paper-parabola"\nseed = -1\nrandom = 3\n[vary]\nqdot = "3:12"\n', [], "sweep.toml:seed: "),
    # the command line's value is the command line's: no file name before it
    ('scene = "paper-parabola"\n[vary]\nqdot = "3:12:2"\n', ["--vary", "qdot=abc"], "error: vary.qdot: name 'abc'"),
    ('scene = "paper-parabola"\nseed = 1\nrandom = 3\n[vary]\nqdot = "3:12"\n', ["--seed", "-2"], "error: seed: "),
])
def test_a_bad_value_in_a_sweep_file_names_the_file(tmp_path, capsys, text, extra, prefix):
    sw = tmp_path / "sweep.toml"
    sw.write_text(text)
    assert main(["--file", str(sw), "-o", str(tmp_path / "out"), "--quiet", *extra]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and prefix in err, err


def test_a_directory_as_sweep_file_is_a_one_line_error(tmp_path, capsys):
    assert main(["--file", str(tmp_path), "-o", str(tmp_path / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(tmp_path) in err


# --------------------------------------------------------------------- class 3 in sweeps: failed rows

def test_cli_exits_nonzero_when_scenes_failed(tmp_path, capsys, monkeypatch):
    """Rows of an error status (the driver's ERROR_CODES) make the sweep exit 3 (as `symvib run`) in one line; here the
    'arrested' code stands in for one, so the test does not depend on which inputs overflow."""
    from symvib.numeric.layout import STATUSES

    args = ["paper-parabola", "--vary", "qdot=3:12:3", "-o", str(tmp_path / "o"), "--quiet"]
    assert main(args) == 0
    monkeypatch.setattr(result_mod, "ERROR_CODES", (STATUSES.index("arrested"),))
    capsys.readouterr()
    assert main(args) == EXIT_FAILED_SCENES == EXIT_RUN_FAILED
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "3 of 3 scenes failed (arrested; first: row 0)" in err
    assert load_sweep(tmp_path / "o").failed.all()


def test_the_issues_overflow_inputs_fail_a_sweep(tmp_path, capsys):
    """qdot = 1e200 and mu = 1e60 (issue 13, class 3) in a sweep: exit 3, never exit 0 with inf/NaN rows.
    A ``--vary`` text beyond 1e100 is refused as bad input (exit 2); a scene file's float is not."""
    assert main(["paper-parabola", "--vary", "qdot=1e200,7", "-o", str(tmp_path / "x"), "--quiet"]) == 2
    assert "vary.qdot" in capsys.readouterr().err
    scene = tmp_path / "s.toml"
    scene.write_text('name = "overflow"\n[curve]\nshape = "parabola"\n[parameters]\np = 1\n'
                     '[physics]\nalpha0 = 0.05\nrestitution = 0.8\n[limiters]\nleft = "-pi/6"\n'
                     'right = "pi/4"\n[initial]\nq = 0\nqdot = 1e200\n', encoding="utf-8")
    for args, failed in (([str(scene), "--vary", "k=0.6,0.8"], [True, True]),
                         (["paper-parabola", "--vary", "mu=0.05,1e60"], [False, True])):
        out = tmp_path / f"o{len(failed)}{failed[0]}"
        assert main([*args, "-o", str(out), "--quiet"]) == EXIT_FAILED_SCENES
        assert "scenes failed" in capsys.readouterr().err
        res = load_sweep(out)
        assert list(res.failed) == failed
        ok = ~res.failed
        for name in ("t_final", "q_final", "E0", "E_final", "friction_work", "impact_loss"):
            assert np.isfinite(res[name][ok]).all()


# --------------------------------------------------------------------- static friction in sweeps

@pytest.mark.parametrize("base, vary, field, text", [
    ({"mu_s": 0.1}, {"mu": "0.05,0.2"}, "physics.mu_s", "is below the kinetic mu = 0.2"),
    ({"mu_s": 0.1}, {"alpha0": "0.05,0.2"}, "physics.mu_s", "is below the kinetic mu = 0.2027"),
    ({}, {"mu_s": "-0.1,0.3"}, "physics.mu_s", "must be >= 0"),
    ({}, {"alpha0_s": "0.2,2.0"}, "physics.alpha0_s", "[0, pi/2)"),
    ({}, {"mu_s": "0.2,0.3", "alpha0_s": "0.2,0.3"}, "vary", "not both"),
    ({}, {"mu_s": "nan,0.3"}, "vary.mu_s", "not allowed"),
])
def test_rows_of_bad_static_friction_are_refused_naming_the_field_and_row(base, vary, field, text):
    from symvib.numeric.scene import resolve_scene
    from symvib.numeric.sweep import sweep as sweep_scene

    with pytest.raises(SceneError) as info:
        sweep_scene(resolve_scene("paper-parabola").replace(**base), vary, backend="python")
    assert info.value.field == field and text in str(info.value), str(info.value)
    assert "\n" not in str(info.value)
