"""Every file symvib writes or deletes: never through a symbolic link, never outside the folder named,
never a file symvib cannot prove it wrote (symvib.safeio, symvib.numeric.sweep.owned; docs/trust.md).

Each family keeps several hostile inputs; each test asserts what an attacker wanted untouched is
untouched (the target's bytes, an empty folder elsewhere) and that a refusal is one line naming the file.
"""
import json
import os
from pathlib import Path

import pytest

from symvib import safeio, sweep
from symvib.cli import main, sweep_main
from symvib.numeric.scene import resolve_scene
from symvib.numeric.sweep import load_sweep
from symvib.numeric.sweep.limits import SweepError
from symvib.paths import UserPathError

SECRET = b"someone else's data\n"
VARY = {"qdot": "3:12:3"}
ARGS = ["paper-parabola", "--vary", "qdot=3:12:3", "--chunk", "2", "--quiet", "--backend", "python"]


def parabola():
    return resolve_scene("paper-parabola")


@pytest.fixture
def elsewhere(tmp_path):
    """A folder outside the one symvib is told to write, with a file an attacker wants overwritten."""
    folder = tmp_path / "elsewhere"
    folder.mkdir()
    (folder / "target").write_bytes(SECRET)
    return folder


def untouched(elsewhere):
    """The folder elsewhere holds exactly its one file, unchanged."""
    return sorted(p.name for p in elsewhere.iterdir()) == ["target"] and (elsewhere / "target").read_bytes() == SECRET


def one_line_error(capsys, *words):
    err = capsys.readouterr().err
    return err.count("\n") == 1 and "Traceback" not in err and all(w in err for w in words)


# --------------------------------------------------------------------- safeio itself

#: Links planted below a root folder: (where, points to the target file or the folder elsewhere).
PLANTED = {
    "link at the final name": ("report.md", "target"),
    "link at a folder on the way": ("maps", "folder"),
    "link at a deeper folder": ("a/b", "folder"),
    "dangling link at the final name": ("report.md", "missing"),
}


@pytest.mark.parametrize("how", sorted(PLANTED))
def test_a_write_never_follows_a_planted_link(tmp_path, elsewhere, how):
    root = tmp_path / "out"
    root.mkdir()
    where, to = PLANTED[how]
    link = root / where
    link.parent.mkdir(parents=True, exist_ok=True)
    link.symlink_to(elsewhere if to == "folder" else elsewhere / to)
    name = "report.md" if where == "report.md" else f"{where}/report.md"
    with pytest.raises(UserPathError, match="symbolic link") as info:
        safeio.write_text(root, name, "x")
    assert "\n" not in str(info.value) and untouched(elsewhere)
    assert link.is_symlink()                    # the link itself is left as it was


def test_old_temporary_names_planted_as_links_are_never_written_through(tmp_path, elsewhere):
    """The versions before safeio wrote predictable temporary names (pid, ``.tmp``, ``.part``)."""
    root = tmp_path / "out"
    root.mkdir()
    for name in (f"report.md.{os.getpid()}.part", "report.md.tmp", f"report.{os.getpid()}.tmp.md", ".report.md.tmp"):
        (root / name).symlink_to(elsewhere / "target")
    for _ in range(5):
        safeio.write_text(root, "report.md", "mine\n")
    assert (root / "report.md").read_text() == "mine\n" and not (root / "report.md").is_symlink()
    assert untouched(elsewhere)


@pytest.mark.parametrize("make", ["link", "file", "device"])
def test_a_root_that_is_not_a_real_folder_is_refused(tmp_path, elsewhere, make):
    root = tmp_path / "root"
    if make == "link":
        root.symlink_to(elsewhere)
    elif make == "file":
        root.write_text("x")
    else:
        root = Path("/dev/null")
    with pytest.raises(UserPathError) as info:
        safeio.check_root(root, "plot folder")
    assert "plot folder" in str(info.value) and "\n" not in str(info.value) and untouched(elsewhere)


def test_a_root_owned_by_another_user_is_refused(tmp_path, monkeypatch):
    root = tmp_path / "theirs"
    root.mkdir()
    monkeypatch.setattr(os, "geteuid", lambda: os.stat(root).st_uid + 1)   # as if another user owned it
    with pytest.raises(UserPathError, match=r"owned by another user \(uid \d+\)"):
        safeio.check_root(root, "output folder")
    with pytest.raises(UserPathError, match="owned by another user"):
        safeio.write_text(root, "x.txt", "x")
    assert list(root.iterdir()) == []


def test_a_failed_write_leaves_neither_the_file_nor_a_temporary(tmp_path):
    root = tmp_path / "out"
    root.mkdir()
    (root / "kept.txt").write_text("old")
    with pytest.raises(RuntimeError), safeio.replacing(root, "kept.txt") as fh:
        fh.write(b"half")
        raise RuntimeError("the writer failed")
    assert sorted(p.name for p in root.iterdir()) == ["kept.txt"] and (root / "kept.txt").read_text() == "old"


@pytest.mark.parametrize("relpath", ["../x", "/abs/x", "a/../../x", "a/\0b"])
def test_relative_paths_cannot_leave_the_root(tmp_path, relpath):
    with pytest.raises(UserPathError, match="not a plain path"):
        safeio.write_text(tmp_path, relpath, "x")


def test_remove_file_removes_regular_files_only(tmp_path, elsewhere):
    (tmp_path / "link").symlink_to(elsewhere / "target")
    (tmp_path / "folder").mkdir()
    for name in ("link", "folder"):
        with pytest.raises(UserPathError, match="not a regular file"):
            safeio.remove_file(tmp_path, name)
    assert safeio.remove_file(tmp_path, "missing") is False
    assert untouched(elsewhere) and (tmp_path / "folder").is_dir()


def test_remove_tree_removes_nothing_unless_every_entry_is_accepted(tmp_path, elsewhere):
    tree = tmp_path / "tree"
    (tree / "a").mkdir(parents=True)
    (tree / "a" / "0").write_text("0")
    (tree / "a" / "notes.txt").write_text("mine")
    with pytest.raises(UserPathError, match="notes.txt"):
        safeio.remove_tree(tmp_path, "tree", lambda parts, kind: parts[-1] != "notes.txt")
    assert (tree / "a" / "0").exists() and (tree / "a" / "notes.txt").exists()
    (tree / "a" / "notes.txt").unlink()
    (tree / "a" / "1").symlink_to(elsewhere / "target")          # a link is never accepted
    with pytest.raises(UserPathError):
        safeio.remove_tree(tmp_path, "tree", lambda parts, kind: True)
    (tree / "a" / "1").unlink()
    safeio.remove_tree(tmp_path, "tree", lambda parts, kind: True)
    assert not tree.exists() and untouched(elsewhere)


# --------------------------------------------------------------------- sweep folders: links (issue 29, 1)

def _sweep_out(tmp_path, plant):
    out = tmp_path / "out"
    (out / "chunks").mkdir(parents=True)
    plant(out)
    return out


#: Links planted in a sweep folder, and a word of the one-line refusal.
SWEEP_LINKS = {
    "manifest.json is a link": (lambda out, e: (out / "manifest.json").symlink_to(e / "target"), "manifest.json"),
    "the old manifest temporary is a link": (lambda out, e: (out / "manifest.json.tmp").symlink_to(e / "target"),
                                             "manifest.json.tmp"),
    "a chunk is a link": (lambda out, e: (out / "chunks" / "chunk-000000.npz").symlink_to(e / "target"),
                          "chunk-000000.npz"),
    "an old chunk temporary is a link": (lambda out, e: (out / "chunks" / f"chunk-000000.{os.getpid()}.tmp.npz")
                                         .symlink_to(e / "target"), "tmp.npz"),
    "the lock is a link": (lambda out, e: (out / "sweep.lock").symlink_to(e / "target"), "sweep.lock"),
    "sweep.zarr is a link": (lambda out, e: (out / "sweep.zarr").symlink_to(e), "sweep.zarr"),
}


@pytest.mark.parametrize("how", sorted(SWEEP_LINKS))
@pytest.mark.parametrize("overwrite", [False, True], ids=["plain", "overwrite"])
def test_links_planted_in_a_sweep_folder_are_never_written_through(tmp_path, elsewhere, capsys, how, overwrite):
    plant, word = SWEEP_LINKS[how]
    out = _sweep_out(tmp_path, lambda o: plant(o, elsewhere))
    code = sweep_main(ARGS + ["-o", str(out)] + (["--overwrite"] if overwrite else []))
    err = capsys.readouterr().err
    assert untouched(elsewhere)
    if code == 0:                                # written beside the link (--overwrite), never through it
        assert overwrite and load_sweep(out).count == 3
    else:
        assert code == 2 and err.count("\n") == 1 and word in err and "Traceback" not in err


def test_maps_as_a_link_is_refused_before_any_work(tmp_path, elsewhere, capsys):
    out = tmp_path / "out"
    out.mkdir()
    (out / "maps").symlink_to(elsewhere)
    assert sweep_main(ARGS + ["-o", str(out), "--plot"]) == 2
    assert one_line_error(capsys, "maps", "symbolic link")
    assert untouched(elsewhere) and not (out / "manifest.json").exists()


def test_maps_made_a_link_after_the_check_are_not_written_through(tmp_path, elsewhere):
    from symvib.numeric.sweepmaps import sweep_maps

    res = sweep(parabola(), VARY, chunk=2, out=tmp_path / "out", backend="python")
    (tmp_path / "out" / "maps").symlink_to(elsewhere)
    with pytest.raises(UserPathError, match="symbolic link"):
        sweep_maps(res, tmp_path / "out" / "maps")
    assert untouched(elsewhere)


def test_the_sweep_folder_itself_as_a_link_is_refused(tmp_path, elsewhere, capsys):
    (tmp_path / "out").symlink_to(elsewhere)
    assert sweep_main(ARGS + ["-o", str(tmp_path / "out")]) == 2
    assert one_line_error(capsys, "symbolic link") and untouched(elsewhere)


def test_the_files_of_a_sweep_are_written_whole_and_private_to_its_folder(tmp_path):
    out = tmp_path / "out"
    sweep(parabola(), VARY, chunk=2, out=out, backend="python")
    names = sorted(str(p.relative_to(out)) for p in out.rglob("*"))
    assert names == ["chunks", "chunks/chunk-000000.npz", "chunks/chunk-000001.npz", "manifest.json"]
    assert json.loads((out / "manifest.json").read_text())["files"]["chunks"] == "chunks/chunk-NNNNNN.npz"


# --------------------------------------------------------------------- sweep files name no folder elsewhere (3)

def _sweep_file(tmp_path, out_text):
    folder = tmp_path / "defs"
    folder.mkdir(exist_ok=True)
    path = folder / "sweep.toml"
    path.write_text(f'scene = "paper-parabola"\nchunk = 2\nout = {json.dumps(out_text)}\n[vary]\nqdot = "3:12:3"\n')
    return path


@pytest.mark.parametrize("out_text", ["ABS", "../elsewhere-out", "sub/../../x", ".", "LINK/out"])
def test_a_sweep_file_cannot_send_results_out_of_its_folder(tmp_path, elsewhere, capsys, monkeypatch, out_text):
    monkeypatch.chdir(tmp_path)
    if out_text == "ABS":
        out_text = str(elsewhere / "out")
    path = _sweep_file(tmp_path, out_text)
    (path.parent / "LINK").symlink_to(elsewhere)
    assert sweep_main(["--file", str(path), "--quiet", "--backend", "python"]) == 2
    assert one_line_error(capsys, "sweep.toml:out", "-o OUT")
    assert untouched(elsewhere) and not (tmp_path / "elsewhere-out").exists() and not (tmp_path / "x").exists()


def test_a_sweep_files_out_is_relative_to_its_folder_and_the_command_line_may_go_anywhere(tmp_path, monkeypatch,
                                                                                           capsys):
    monkeypatch.chdir(tmp_path)
    path = _sweep_file(tmp_path, "results")
    assert sweep_main(["--file", str(path), "--quiet", "--backend", "python"]) == 0
    assert load_sweep(path.parent / "results").count == 3 and not (tmp_path / "results").exists()
    assert sweep_main(["--file", str(path), "-o", str(tmp_path / "chosen"), "--quiet", "--backend", "python"]) == 0
    assert load_sweep(tmp_path / "chosen").count == 3


# --------------------------------------------------------------------- deletion: only what symvib wrote (4)

def _foreign_store(out, ident=None, extra=None):
    store = out / "sweep.zarr"
    (store / "impacts" / "c").mkdir(parents=True)
    meta = {"zarr_format": 3, "node_type": "group", "attributes": {"sweep_id": ident} if ident else {"mine": 1}}
    (store / "zarr.json").write_text(json.dumps(meta))
    (store / "impacts" / "zarr.json").write_text("{}")
    (store / "impacts" / "c" / "0").write_bytes(SECRET)
    if extra:
        (store / extra).write_bytes(SECRET)
    return store


def _snapshot(folder):
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


#: Folders holding what symvib did not write: each must survive a sweep into them, --overwrite or not.
FOREIGN = {
    "the issue's zarr store and chunk notes": lambda out: (_foreign_store(out),
                                                           (out / "chunks" / "chunk-notes.txt").write_bytes(SECRET)),
    "notes beside the chunks": lambda out: (out / "notes.txt").write_bytes(SECRET),
    "a chunk without a sweep identity": lambda out: (out / "chunks" / "chunk-000005.npz").write_bytes(SECRET),
    "a folder of the user's": lambda out: ((out / "data").mkdir(), (out / "data" / "x.csv").write_bytes(SECRET)),
    "a map without a manifest": lambda out: ((out / "maps").mkdir(), (out / "maps" / "impacts.png")
                                             .write_bytes(SECRET)),
}


@pytest.mark.parametrize("how", sorted(FOREIGN))
def test_a_folder_holding_others_files_is_refused_and_nothing_is_deleted(tmp_path, capsys, how):
    out = tmp_path / "out"
    (out / "chunks").mkdir(parents=True)
    FOREIGN[how](out)
    before = _snapshot(out)
    assert sweep_main(ARGS + ["-o", str(out)]) == 2
    assert one_line_error(capsys, "did not write", "--overwrite")
    assert _snapshot(out) == before and not (out / "manifest.json").exists()
    with pytest.raises(SweepError, match="did not write"):
        sweep(parabola(), VARY, chunk=2, out=out, backend="python")
    assert _snapshot(out) == before


@pytest.mark.parametrize("how", sorted(FOREIGN))
def test_overwrite_writes_beside_others_files_and_deletes_none(tmp_path, capsys, how):
    out = tmp_path / "out"
    (out / "chunks").mkdir(parents=True)
    FOREIGN[how](out)
    before = _snapshot(out)
    code = sweep_main(ARGS + ["-o", str(out), "--overwrite"])
    after = _snapshot(out)
    assert all(after.get(name) == data for name, data in before.items())     # every file kept, unchanged
    if how == "a chunk without a sweep identity":
        assert code == 2 and one_line_error(capsys, "chunk-000005.npz", "cannot tell")   # a name the sweep writes
    else:
        assert code == 0 and load_sweep(out).count == 3


def test_a_foreign_zarr_store_is_never_replaced_by_a_zarr_sweep(tmp_path, capsys):
    pytest.importorskip("zarr")
    pytest.importorskip("xarray")
    out = tmp_path / "out"
    out.mkdir()
    _foreign_store(out)
    before = _snapshot(out)
    assert sweep_main(ARGS + ["-o", str(out), "--overwrite", "--format", "zarr"]) == 2
    assert one_line_error(capsys, "sweep.zarr", "cannot tell")
    assert _snapshot(out) == before


def test_a_symvib_zarr_store_with_a_foreign_file_in_it_is_not_removed(tmp_path, capsys):
    pytest.importorskip("zarr")
    pytest.importorskip("xarray")
    out = tmp_path / "out"
    assert sweep_main(ARGS + ["-o", str(out), "--format", "zarr"]) == 0
    (out / "sweep.zarr" / "impacts" / "notes.txt").write_bytes(SECRET)
    capsys.readouterr()
    assert sweep_main(ARGS + ["-o", str(out), "--overwrite", "--format", "zarr", "--seed", "3",
                        "--vary", "mu=0.1,0.2"]) == 2
    assert one_line_error(capsys, "notes.txt")
    assert (out / "sweep.zarr" / "impacts" / "notes.txt").read_bytes() == SECRET


def test_overwrite_replaces_symvibs_own_sweep_and_keeps_the_users_files(tmp_path):
    out = tmp_path / "out"
    sweep(parabola(), {"qdot": "3:12:6"}, chunk=2, out=out, backend="python")
    (out / "notes.txt").write_bytes(SECRET)
    (out / "chunks" / "chunk-notes.txt").write_bytes(SECRET)
    with pytest.raises(SweepError, match="different sweep"):
        sweep(parabola(), VARY, chunk=2, out=out, backend="python")
    res = sweep(parabola(), VARY, chunk=2, out=out, overwrite=True, backend="python")
    assert res.count == 3 and sorted(p.name for p in (out / "chunks").iterdir()) == [
        "chunk-000000.npz", "chunk-000001.npz", "chunk-notes.txt"]              # the old sweep's chunk 2 is gone
    assert (out / "notes.txt").read_bytes() == SECRET and (out / "chunks" / "chunk-notes.txt").read_bytes() == SECRET


def test_resuming_a_sweep_keeps_the_users_files(tmp_path):
    out = tmp_path / "out"
    sweep(parabola(), VARY, chunk=2, out=out, backend="python")
    (out / "notes.txt").write_bytes(SECRET)
    (out / "chunks" / "chunk-000001.npz").unlink()
    res = sweep(parabola(), VARY, chunk=2, out=out, backend="python")
    assert res.computed == (1,) and (out / "notes.txt").read_bytes() == SECRET


# --------------------------------------------------------------------- single output files and folders

@pytest.fixture
def scene_file(tmp_path):
    from importlib.resources import files

    path = tmp_path / "scene.toml"
    path.write_text((files("symvib") / "scenes" / "paper-parabola.toml").read_text(encoding="utf-8"))
    return path


@pytest.mark.parametrize("option", ["--json", "--plot", "--animate"])
def test_run_outputs_that_are_links_are_refused_before_the_run(tmp_path, elsewhere, capsys, scene_file, option):
    link = tmp_path / ("out.gif" if option == "--animate" else "out")
    link.symlink_to(elsewhere if option == "--plot" else elsewhere / "target")
    assert main(["run", str(scene_file), option, str(link), "--backend", "python"]) == 2
    assert one_line_error(capsys, "symbolic link") and untouched(elsewhere)


def test_run_json_replaces_the_file_whole(tmp_path, scene_file, capsys):
    target = tmp_path / "run.json"
    target.write_text("old")
    (tmp_path / f"run.json.{os.getpid()}.tmp").symlink_to(tmp_path / "victim")
    assert main(["run", str(scene_file), "--json", str(target), "--backend", "python"]) == 0
    assert json.loads(target.read_text())["success"] is True and not (tmp_path / "victim").exists()


def test_figures_never_write_through_a_link_at_a_figure_name(tmp_path, elsewhere):
    from symvib import simulate
    from symvib.numeric.figures import save_run_figures

    result = simulate(parabola(), backend="python")
    out = tmp_path / "figs"
    out.mkdir()
    (out / "paper-parabola-phase.png").symlink_to(elsewhere / "target")
    with pytest.raises(UserPathError, match="symbolic link|would leave the folder"):
        save_run_figures(result, out, only=("phase",))
    assert untouched(elsewhere)


def test_the_errata_writer_never_writes_through_a_link(tmp_path, elsewhere, monkeypatch):
    from symvib.paper import errata

    monkeypatch.setattr(errata, "errata_document", lambda verdicts: "# errata")
    link = tmp_path / "errata.md"
    link.symlink_to(elsewhere / "target")
    with pytest.raises(UserPathError, match="symbolic link"):
        errata.write_errata(link, verdicts=())
    assert untouched(elsewhere)
    assert errata.write_errata(tmp_path / "real.md", verdicts=()).read_text() == "# errata\n"


@pytest.mark.parametrize("where", ["impacts/c/1", "impacts/c", "impacts"])
def test_zarr_never_writes_a_chunk_through_a_link_in_the_store(tmp_path, elsewhere, where):
    pytest.importorskip("zarr")
    pytest.importorskip("xarray")
    out = tmp_path / "out"
    sweep(parabola(), VARY, chunk=2, out=out, storage="zarr", backend="python")
    (out / "chunks" / "chunk-000001.json").unlink()          # chunk 1 is computed again on resume
    planted = out / "sweep.zarr" / where
    planted.rename(planted.with_name(planted.name + ".moved"))
    planted.symlink_to(elsewhere / "target" if where.endswith("/1") else elsewhere)
    with pytest.raises(SweepError, match="symbolic link"):
        sweep(parabola(), VARY, chunk=2, out=out, storage="zarr", backend="python")
    assert untouched(elsewhere)
