"""A sweep on disk: folder layout, manifest, chunk files, loading.

Layout of a sweep folder ``DIR``: ``DIR/manifest.json`` (the definition, its
identity :func:`sweep_id` and the names of columns and codes) and one
``DIR/chunks/chunk-NNNNNN.npz`` per chunk of rows, NumPy's own archive format
(``numpy.load`` reads it; :func:`load_sweep` joins the chunks into columns).
Every chunk carries the sweep's identity; it is written to a temporary name
and renamed, so it either exists complete or not at all.  Every file read is
checked (sizes, types, identity) before it is used: a chunk that is truncated
or another sweep's is refused with a one-line :class:`SweepError` naming it.
One writer at a time: :class:`symvib.numeric.sweep.lock.WriterLock`.

With ``storage="zarr"`` (``symvib sweep --format zarr``, extra ``symvib[xarray]``)
the chunks go into one Zarr store ``DIR/sweep.zarr`` instead, with a marker
``DIR/chunks/chunk-NNNNNN.json`` per written chunk
(:mod:`symvib.numeric.sweep.zarrstore`); the manifest's ``storage`` says which.

Examples
--------
>>> import tempfile
>>> from symvib.numeric.scene import resolve_scene
>>> from symvib.numeric.sweep import sweep
>>> out = tempfile.mkdtemp()
>>> _ = sweep(resolve_scene("paper-parabola"), {"qdot": "3:12:3"}, chunk=2, out=out, backend="python")
>>> sorted(chunk_files(Path(out)))
['chunk-000000.npz', 'chunk-000001.npz']
>>> res = load_sweep(out)
>>> res.count, res.spec.chunks, len(sweep_id(res.spec.to_dict()))
(3, 2, 32)
"""
from __future__ import annotations

import json
import os
import zipfile
import zlib
from pathlib import Path

import numpy as np

from symvib import __version__, safeio
from symvib.numeric.layout import EVENT_COLUMNS, EVENT_KINDS, STATUSES
from symvib.numeric.scene import SceneError
from symvib.numeric.sweep import limits, zarrstore
from symvib.numeric.sweep.limits import SweepError
from symvib.numeric.sweep.owned import CHUNK_NAME, FILES, STORE, remove_store, survey
from symvib.numeric.sweep.result import SweepResult, join_chunks
from symvib.numeric.sweep.schema import (
    FORMAT,
    OLD_FORMATS,
    bad_chunk,
    check_rows,
    column_dtype,
    column_names,
    column_tail,
    sweep_id,
)
from symvib.numeric.sweep.spec import SweepSpec
from symvib.numeric.sweep.zarrstore import marker_path
from symvib.paths import UserPathError

__all__ = ["FORMAT", "OLD_FORMATS", "STORAGES", "sweep_id", "load_sweep", "manifest", "read_manifest",
           "column_names", "chunk_path", "chunk_files", "write_chunk", "read_chunk", "check_rows", "check_out",
           "check_storage", "prepare", "reader", "missing_chunks"]

#: How the chunks are stored (manifest key ``storage``; a manifest without it is ``npz``):
#: NumPy ``.npz`` files (no extra dependency), or one Zarr store (extra ``symvib[xarray]``).
STORAGES = ("npz", "zarr")


def check_storage(storage) -> str:
    """``storage`` if it is one of :data:`STORAGES`, else a :class:`SweepError` naming the option."""
    if storage not in STORAGES:
        raise SweepError("storage", f"must be one of {', '.join(STORAGES)}, got {storage!r}")
    return storage


def manifest(spec: SweepSpec, ident: str, storage: str = "npz") -> dict:
    """The manifest of the sweep ``ident`` (written as ``manifest.json``): layout, identity, storage,
    definition, the names of columns and codes, the files symvib writes."""
    return {"format": FORMAT, "sweep_id": ident, "storage": storage, "definition": spec.to_dict(),
            "chunks": spec.chunks,
            "columns": column_names(spec),
            "status_names": list(STATUSES), "event_names": list(EVENT_KINDS),
            "event_log_columns": list(EVENT_COLUMNS),
            "files": FILES,
            "symvib_version": __version__}


def chunk_path(out: Path, index: int) -> Path:
    return out / "chunks" / f"chunk-{index:06d}.npz"


#: The Zarr store the running sweep writes, opened (and checked) by :func:`prepare`: ``(out, ident, ZarrChunks)``.
_zarr_writer: list = []


def write_chunk(out: Path, index: int, columns: dict, ident: str, storage: str = "npz") -> None:
    """Write a chunk with its sweep's identity: to a temporary name, then renamed (atomic); or into the
    Zarr store that :func:`prepare` opened, then marked."""
    if storage == "zarr":
        if not _zarr_writer or _zarr_writer[0][:2] != (Path(out), ident):
            raise SweepError(str(out), "the Zarr store was not prepared for this sweep")
        _zarr_writer[0][2].write(index, columns)
        return
    path = chunk_path(out, index)
    try:
        with safeio.replacing(out, f"chunks/{path.name}", what="sweep folder") as fh:
            np.savez(fh, sweep_id=np.array(ident), **columns)
    except OSError as exc:
        raise SweepError(str(path), f"cannot write the chunk: {exc}") from None


def read_chunk(path: Path, spec: SweepSpec, ident: str, index: int) -> dict:
    """The columns of chunk ``index``, checked against the sweep: identity, names, dtypes, shapes, rows.

    Raises
    ------
    SweepError
        Naming the chunk file: truncated or unreadable, made by another sweep,
        or columns that are not this sweep's.
    """
    rows, values = spec.rows(index)
    n = len(rows)
    expected = column_names(spec)
    try:
        with safeio.reading(path.parent, path.name) as fh:
            if os.fstat(fh.fileno()).st_size > spec.chunk_bytes() + limits.MAX_MANIFEST_BYTES:
                raise bad_chunk(path, "larger than a chunk of this sweep can be")
            data = np.load(fh, allow_pickle=False)
            columns = _chunk_columns(path, data, spec, ident, n, expected)
    except SweepError:
        raise
    except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile, zlib.error) as exc:
        raise bad_chunk(path, f"truncated or unreadable ({type(exc).__name__})") from None
    check_rows(path, spec, index, columns)
    return columns


def _chunk_columns(path: Path, data, spec: SweepSpec, ident: str, n: int, expected: list) -> dict:
    """The columns of an open ``.npz`` chunk, each header checked before its array is read."""
    with data:
        names = set(data.files)
        if "sweep_id" not in names:
            raise bad_chunk(path, "no sweep identity: not a chunk of this sweep")
        _check_header(path, data, "sweep_id", lambda d, sh: d.kind == "U" and sh == () and d.itemsize <= 4 * 64,
                      "a text")
        if str(data["sweep_id"]) != ident:
            raise bad_chunk(path, "made by another sweep (its sweep_id differs from the manifest's)")
        if names != set(expected) | {"sweep_id"}:
            raise bad_chunk(path, f"columns {sorted(names - {'sweep_id'})} are not this sweep's")
        columns = {}
        for name in expected:   # each header checked before its array is allocated
            want = column_dtype(name)
            shape = (n,) + column_tail(spec, name)
            _check_header(path, data, name, lambda d, sh: d == want and sh == shape,
                          f"{want}{list(shape)}")
            columns[name] = data[name]
    return columns


def _check_header(path: Path, data, name: str, ok, expected: str) -> None:
    """Check the ``.npy`` header of member ``name`` (dtype, shape) before its array is read."""
    with data.zip.open(f"{name}.npy") as fh:
        version = np.lib.format.read_magic(fh)
        read = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
        shape, fortran, dtype = read(fh)
    if fortran or dtype.hasobject or not ok(dtype, shape):
        raise bad_chunk(path, f"column {name} is {dtype}{list(shape)}, expected {expected}")


def check_out(out) -> Path:
    """Create and check the sweep folder ``out`` and its ``chunks``, or raise a one-line :class:`SweepError`.

    ``out`` must be a real folder of the user's (not a symbolic link); ``chunks``
    is reached without following a link (:func:`symvib.safeio.check_root`).
    """
    if not isinstance(out, (str, os.PathLike)):
        raise SweepError("out", f"must be a folder path, got {type(out).__name__}")
    out = Path(out)
    if not str(out) or "\0" in str(out):
        raise SweepError("out", f"not a usable folder name: {str(out)!r}")
    try:
        safeio.check_root(out, "sweep folder")
        safeio.make_folders(out, "chunks", what="sweep folder")
        kinds = safeio.entries(out)
    except OSError as exc:
        raise SweepError("out", str(exc)) from None
    if not os.access(out, os.W_OK | os.X_OK) or not os.access(out / "chunks", os.W_OK | os.X_OK):
        raise SweepError("out", f"folder {out} is not writable")
    if kinds.get("manifest.json", "file") != "file":
        raise SweepError(str(out / "manifest.json"), "is not a regular file")
    return out


def read_manifest(out: Path) -> tuple:
    """``(manifest, spec, sweep_id)`` of the sweep in ``out``, every part checked.

    Raises
    ------
    SweepError
        One line naming ``manifest.json``: missing, not a small regular file,
        not JSON, not an object, an old or unknown format, a definition that
        is not valid or not the one its ``sweep_id`` was made of.
    """
    path = out / "manifest.json"
    try:
        with safeio.reading(out, path.name) as fh:   # never through a link
            size = os.fstat(fh.fileno()).st_size
            if size > limits.MAX_MANIFEST_BYTES:
                raise SweepError(str(path), f"is {size} bytes, more than a manifest may hold "
                                            f"({limits.MAX_MANIFEST_BYTES})")
            raw = fh.read(size + 1)   # the size was checked: no buffer of the bound's size
        if len(raw) > limits.MAX_MANIFEST_BYTES:
            raise SweepError(str(path), f"is more than a manifest may hold ({limits.MAX_MANIFEST_BYTES} bytes)")
        manifest = json.loads(raw.decode("utf-8"), parse_constant=_no_constant)
    except SweepError:
        raise
    except FileNotFoundError:
        raise SweepError(str(out), "no sweep here (manifest.json missing)") from None
    except UserPathError as exc:
        if "does not exist" in exc.reason:
            raise SweepError(str(out), "no sweep here (manifest.json missing)") from None
        raise SweepError(str(path), exc.reason if exc.path == str(path) else str(exc)) from None
    except OSError as exc:
        raise SweepError(str(path), f"cannot read it: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise SweepError(str(path), "not a JSON manifest (not UTF-8 text)") from None
    except (ValueError, RecursionError) as exc:
        reason = exc.args[0] if isinstance(exc, ValueError) else "nested too deeply"
        raise SweepError(str(path), f"not a JSON manifest ({reason})") from None
    if not isinstance(manifest, dict):
        raise SweepError(str(path), f"must hold a JSON object, got {type(manifest).__name__}")
    fmt = manifest.get("format")
    if fmt in OLD_FORMATS:
        raise SweepError(str(path), f"written in the older layout {fmt}, whose chunks carry no sweep identity; "
                                    f"run the sweep again with --overwrite (layout {FORMAT})")
    if fmt != FORMAT:
        raise SweepError(str(path), f"unknown format {fmt!r}; expected {FORMAT}")
    definition = manifest.get("definition")
    try:
        spec = SweepSpec.from_dict(definition)
    except SceneError as exc:
        raise SweepError(str(path), f"{exc.field}: {exc.reason}") from None
    ident = sweep_id(definition)
    if manifest.get("sweep_id") != ident:
        raise SweepError(str(path), "sweep_id does not match the definition (the manifest was edited)")
    if manifest.setdefault("storage", "npz") not in STORAGES:
        raise SweepError(str(path), f"unknown storage {manifest['storage']!r}; expected one of {', '.join(STORAGES)}")
    return manifest, spec, ident


def _no_constant(name: str):
    """``json.loads`` hook: a manifest holds finite numbers only (no NaN or Infinity)."""
    raise ValueError(f"non-finite number {name}")


def chunk_files(out: Path) -> set:
    """Names in ``out/chunks`` (reached without following a link; each is checked when read)."""
    try:
        return set(safeio.entries(out, "chunks"))
    except OSError as exc:
        raise SweepError(str(Path(out) / "chunks"), str(exc)) from None


#: Entries of a folder named in a refusal (the rest are counted).
SHOWN_ENTRIES = 3


def prepare(out: Path, spec: SweepSpec, ident: str, overwrite: bool, storage: str = "npz") -> tuple:
    """Open ``out`` for the sweep ``ident`` stored as ``storage`` (the caller holds its lock).

    Returns ``(done, discarded)``: chunks complete and valid there, and chunks
    removed because they were truncated, unreadable or another sweep's.  A
    folder holding the same sweep in the other storage is refused (or, with
    ``overwrite``, replaced).

    Only what symvib provably wrote is ever deleted (:func:`symvib.numeric.sweep.owned.survey`):
    a new sweep in a folder holding anything else (someone's ``sweep.zarr``, a
    note among the chunks) is refused, and with ``overwrite`` written beside it,
    deleting only the previous sweep's files.
    """
    check_storage(storage)
    path = out / "manifest.json"
    old = old_storage = None
    if "manifest.json" in safeio.entries(out):
        try:
            old_manifest, _, old = read_manifest(out)
            old_storage = old_manifest["storage"]
        except SweepError as exc:
            if not overwrite:
                raise SweepError(exc.field, f"{exc.reason}; --overwrite replaces it with this sweep") from None
    if old is not None and old != ident and not overwrite:
        raise SweepError("out", f"{out} holds a different sweep; choose another folder or overwrite it")
    if old == ident and old_storage != storage and not overwrite:
        raise SweepError("out", f"{out} holds this sweep stored as {old_storage}; run it with --format "
                                f"{old_storage} (storage={old_storage!r}), or --overwrite to store it as {storage}")
    resume = old == ident and old_storage == storage
    found = survey(out, manifest_ours=old is not None, prove=not resume)
    held = found.unknown + [rel for rel in found.ours if rel != "sweep.lock"]
    if held and not resume and not overwrite:
        # A new sweep starts in an empty folder: whatever is here (even an earlier sweep's chunks
        # without their manifest) stays until the user says --overwrite.
        unknown = found.unknown or held
        shown = ", ".join(unknown[:SHOWN_ENTRIES])
        more = f" and {len(unknown) - SHOWN_ENTRIES} more" if len(unknown) > SHOWN_ENTRIES else ""
        kind = "files symvib did not write" if found.unknown else "another sweep's files"
        raise SweepError("out", f"{out} holds {kind} ({shown}{more}); choose another folder, or pass "
                                "--overwrite to replace symvib's own files (others are never deleted)")
    for rel in found.temporary:
        _remove(out, rel)   # a killed writer's partial file
    if not resume:
        for rel in found.ours:
            if rel.startswith(("chunks/", "maps/")):
                _remove(out, rel)
        if STORE in found.ours or (found.store and storage == "zarr"):
            remove_store(out)   # refused (nothing removed) unless provably symvib's
    files = chunk_files(out)
    if not resume:
        taken = sorted(n for n in files if CHUNK_NAME.fullmatch(n))
        if taken:   # not provably symvib's (no sweep identity in it): never replaced
            raise SweepError(str(out / "chunks" / taken[0]), "symvib cannot tell it wrote this file (no sweep "
                                                              "identity in it); remove it or choose another folder")
    chunks = _open_zarr(out, spec, ident, files) if storage == "zarr" else None
    text = json.dumps(manifest(spec, ident, storage), indent=1, allow_nan=False) + "\n"
    try:
        safeio.write_text(out, path.name, text, what="sweep folder")
    except OSError as exc:
        raise SweepError(str(path), f"cannot write the manifest: {exc}") from None
    done, discarded = [], []
    for i in range(spec.chunks):
        chunk = chunk_path(out, i) if chunks is None else marker_path(out, i)
        if chunk.name not in files:
            continue
        try:
            read_chunk(chunk, spec, ident, i) if chunks is None else chunks.read(i)
            done.append(i)
        except SweepError:
            _remove(out, f"chunks/{chunk.name}")   # this sweep's chunk name, in its own folder
            discarded.append(i)
    return done, discarded


def _remove(out: Path, rel: str) -> None:
    """Remove the file ``out/rel`` that symvib wrote (never through a link)."""
    try:
        safeio.remove_file(out, rel)
    except OSError as exc:
        raise SweepError(str(Path(out) / rel), f"cannot remove it: {exc}") from None


def _open_zarr(out: Path, spec: SweepSpec, ident: str, files: set):
    """The sweep's Zarr store for writing: the one there if it is this sweep's, else a new one (whose
    markers are removed from ``files``)."""
    _zarr_writer.clear()
    try:
        chunks = zarrstore.ZarrChunks(out, spec, ident, mode="r+")
    except SweepError:
        for name in [n for n in files if CHUNK_NAME.fullmatch(n) and n.endswith(".json")]:   # this sweep's markers
            _remove(out, f"chunks/{name}")
            files.discard(name)
        zarrstore.create(out, spec, ident)
        chunks = zarrstore.ZarrChunks(out, spec, ident, mode="r+")
    _zarr_writer.append((Path(out), ident, chunks))
    return chunks


def missing_chunks(out: Path, manifest: dict, spec: SweepSpec) -> None:
    """Raise :class:`SweepError` naming ``out`` if any chunk of the sweep is not there (incomplete)."""
    files = chunk_files(out)
    where = chunk_path if manifest["storage"] == "npz" else marker_path
    missing = [i for i in range(spec.chunks) if where(out, i).name not in files]
    if missing:
        raise SweepError(str(out), f"sweep is incomplete: {len(missing)} of {spec.chunks} chunks missing "
                                   f"(first: {missing[0]}); run the same sweep again to resume")


def reader(out: Path, manifest: dict, spec: SweepSpec, ident: str):
    """A function ``index -> columns`` reading the checked chunks of the sweep in ``out`` (either storage)."""
    if manifest["storage"] == "zarr":
        return zarrstore.ZarrChunks(out, spec, ident).read
    return lambda index: read_chunk(chunk_path(out, index), spec, ident, index)


def load_sweep(out) -> SweepResult:
    """Read a sweep folder (manifest and chunks, either storage) into a :class:`SweepResult`.

    Every chunk is checked against the manifest (:func:`read_chunk`: the
    sweep's identity, column names, dtypes, shapes and rows; a Zarr chunk:
    its marker's identity and the digests of its bytes).

    Raises
    ------
    SweepError
        One line naming the file: no or a bad manifest, missing chunks (the
        sweep is incomplete), a truncated chunk or one of another sweep.
    """
    out = Path(out)
    manifest_, spec, ident = read_manifest(out)
    missing_chunks(out, manifest_, spec)
    read = reader(out, manifest_, spec, ident)
    parts = [read(i) for i in range(spec.chunks)]
    return SweepResult(spec, join_chunks(spec, parts), out=str(out))
