"""A sweep's chunks in one Zarr store (``symvib sweep --format zarr``), checked like the ``.npz`` chunks.

Layout: ``OUT/sweep.zarr`` is a Zarr group that ``xarray.open_zarr`` opens in
one call: one array per column, named as :func:`symvib.numeric.sweep.frames.dataset`
names them (``qdot0``, ``mu``, ``impacts``, ...), along the dimension ``row``,
with their ``units``, ``long_name`` and ``latex`` and the sweep's identity
(``sweep_id``) in the group's attributes.  A Zarr chunk of every array is one
sweep chunk, so each sweep chunk writes whole Zarr chunks of its own (no two
writers ever share one).  The store is created (metadata only) before the
first chunk runs.

Written chunks are marked: after chunk ``i``'s region is written,
``OUT/chunks/chunk-NNNNNN.json`` records the sweep's identity, the chunk
number and the SHA-256 of every column's bytes (written under a temporary
name and renamed).  A chunk counts as written only when its marker is there
and holds this sweep's identity and the digests of what the store holds: a
chunk whose write was interrupted (no marker), whose files were truncated or
replaced by another sweep's (digests differ), or whose marker is another
sweep's, is computed again on resume and refused on load.

Examples
--------
>>> import tempfile, xarray
>>> from symvib.numeric.scene import resolve_scene
>>> from symvib.numeric.sweep import sweep
>>> out = tempfile.mkdtemp()
>>> res = sweep(resolve_scene("paper-parabola"), {"qdot": "3:12:3"}, chunk=2, out=out, storage="zarr",
...             backend="python")
>>> ds = xarray.open_zarr(f"{out}/sweep.zarr")
>>> dict(ds.sizes), ds.attrs["sweep_id"] == res.sweep_id, ds["qdot0"].values.tolist()
({'row': 3}, True, [3.0, 7.5, 12.0])
"""
from __future__ import annotations

import hashlib
import json
import os
import warnings
from pathlib import Path

import numpy as np

from symvib import safeio
from symvib.numeric.sweep.frames import dataset, require
from symvib.numeric.sweep.limits import SweepError
from symvib.numeric.sweep.owned import STORE, remove_store
from symvib.numeric.sweep.schema import bad_chunk, check_rows, column_dtype, column_tail, variable_names
from symvib.paths import UserPathError

__all__ = ["STORE", "MAX_MARKER_BYTES", "store_path", "marker_path", "create", "remove", "ZarrChunks", "digests"]

#: Largest chunk marker read, in bytes (a marker holds one digest per column).
MAX_MARKER_BYTES = 2**16


def store_path(out: Path) -> Path:
    return Path(out) / STORE


def marker_path(out: Path, index: int) -> Path:
    return Path(out) / "chunks" / f"chunk-{index:06d}.json"


def _zarr():
    return require("zarr", "a sweep stored as Zarr")


def digests(columns: dict) -> dict:
    """SHA-256 of every column's bytes (C order, little-endian), by column name."""
    out = {}
    for name, values in columns.items():
        arr = np.ascontiguousarray(values)
        arr = arr.astype(arr.dtype.newbyteorder("<"), copy=False)
        out[name] = hashlib.sha256(arr.tobytes()).hexdigest()
    return out


def remove(out: Path) -> None:
    """Remove the Zarr store of ``out`` if symvib provably wrote it (:func:`symvib.numeric.sweep.owned.remove_store`:
    its sweep identity, and nothing in it but Zarr's own entries); else a :class:`SweepError` naming it."""
    remove_store(out)


def create(out: Path, spec, ident: str) -> None:
    """Create the empty store of the sweep (its arrays' metadata, attributes and identity; no data)."""
    da = require("dask.array", "a sweep stored as Zarr")
    remove(out)
    lazy = {}
    for column in variable_names(spec):
        shape = (spec.count,) + column_tail(spec, column)
        lazy[column] = da.zeros(shape, dtype=column_dtype(column), chunks=shape)
    ds = dataset(spec, lazy, ident, store=True)
    ds.attrs["columns"] = json.dumps({c: n for c, n in variable_names(spec).items() if c != "row"})
    encoding = {name: {"chunks": (spec.chunk,) + var.shape[1:]} for name, var in ds.data_vars.items()}
    encoding.update({name: {"chunks": (spec.chunk,)} for name in ds.coords})
    with warnings.catch_warnings():
        # zarr 3: consolidated metadata is not yet part of the v3 specification (xarray reads it).
        warnings.filterwarnings("ignore", message=".*[Cc]onsolidated metadata.*")
        try:
            # "w-": a store is never replaced by Zarr itself (remove() above proved what it deletes).
            ds.to_zarr(store_path(out), mode="w-", compute=False, consolidated=True, encoding=encoding)
        except OSError as exc:
            raise SweepError(str(store_path(out)), f"cannot create the Zarr store: {exc.strerror or exc}") from None


class ZarrChunks:
    """The chunks of one sweep's Zarr store: checked against the sweep on opening, read and written by number.

    Parameters
    ----------
    out : Path
        The sweep folder.
    spec : SweepSpec
    ident : str
        The sweep's identity (:func:`~symvib.numeric.sweep.schema.sweep_id`).
    mode : {"r", "r+"}

    Raises
    ------
    SweepError
        Naming the store: missing, not a Zarr group, another sweep's, or arrays
        that are not this sweep's (names, dtypes, shapes, chunks).
    """

    def __init__(self, out: Path, spec, ident: str, mode: str = "r"):
        zarr = _zarr()
        self.out, self.spec, self.ident = Path(out), spec, ident
        path = store_path(out)
        if path.is_symlink() or not path.is_dir():
            raise bad_chunk(path, "no Zarr store here (missing, or not a folder)")
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                self.group = zarr.open_group(str(path), mode=mode)
            attrs = dict(self.group.attrs)
            arrays = {name: self.group[name] for name in self.group.array_keys()}
        except Exception as exc:  # noqa: BLE001 - zarr raises many kinds on a spoiled store
            raise SweepError(str(path), f"not a readable Zarr store ({type(exc).__name__})") from None
        if attrs.get("sweep_id") != ident:
            raise SweepError(str(path), "made by another sweep (its sweep_id differs from the manifest's)")
        self.names = {c: n for c, n in variable_names(spec).items() if c != "row"}
        if set(arrays) != set(self.names.values()):
            raise SweepError(str(path), f"arrays {sorted(arrays)} are not this sweep's")
        for column, name in self.names.items():
            arr = arrays[name]
            tail = column_tail(spec, column)
            dtype = column_dtype(column)
            if arr.dtype != dtype or tuple(arr.shape) != (spec.count,) + tail \
                    or tuple(arr.chunks) != (spec.chunk,) + tail:
                raise SweepError(str(path), f"array {name} is {arr.dtype}{list(arr.shape)} in chunks "
                                            f"{list(arr.chunks)}, expected {dtype}{[spec.count, *tail]} in chunks "
                                            f"{[spec.chunk, *tail]}")
        self.arrays = arrays

    def _marker(self, index: int) -> dict:
        path = marker_path(self.out, index)
        try:
            raw = safeio.read_bytes(self.out, f"chunks/{path.name}", max_bytes=MAX_MARKER_BYTES)
            marker = json.loads(raw.decode("utf-8"))
        except UserPathError as exc:
            raise SweepError(str(path), f"{exc.reason}; run the same sweep again to recompute the chunk") from None
        except (OSError, UnicodeDecodeError, ValueError, RecursionError) as exc:
            raise SweepError(str(path), f"not a chunk marker ({type(exc).__name__}); run the same sweep again "
                                        "to recompute the chunk") from None
        ok = isinstance(marker, dict) and marker.get("sweep_id") == self.ident \
            and isinstance(marker.get("sha256"), dict)
        if not ok or type(marker.get("chunk")) is not int or marker["chunk"] != index:
            raise bad_chunk(path, "made by another sweep, or not the marker of this chunk")
        return marker

    def read(self, index: int) -> dict:
        """The columns of chunk ``index`` (as :func:`~symvib.numeric.sweep.store.read_chunk` returns them), checked:
        its marker is this sweep's and the store holds the bytes it was written with."""
        marker = self._marker(index)
        rows = self.spec.rows(index)[0]
        start, stop = (int(rows[0]), int(rows[-1]) + 1) if len(rows) else (0, 0)
        columns = {"row": rows}
        where = f"{store_path(self.out)} (chunk {index})"
        try:
            for column, name in self.names.items():
                columns[column] = np.asarray(self.arrays[name][start:stop])
        except Exception as exc:  # noqa: BLE001 - a truncated or foreign Zarr chunk fails in the codec
            raise bad_chunk(where, f"truncated or unreadable ({type(exc).__name__})") from None
        if digests(columns) != marker["sha256"]:
            raise bad_chunk(where, "its data are not what this sweep wrote (truncated, edited or another sweep's)")
        check_rows(where, self.spec, index, columns)
        return columns

    def _refuse_links(self, index: int) -> None:
        """Before Zarr writes chunk ``index`` (it opens files by name): no link at the store, an array's
        folder, its ``c`` folder or the chunk's key (version 3's ``c/N``, version 2's ``N`` or ``N.0.0``)."""
        store = store_path(self.out)
        for name in self.names.values():
            for rel in ("", name, f"{name}/c", f"{name}/c/{index}", f"{name}/{index}", f"{name}/{index}.0.0"):
                path = store / rel if rel else store
                if os.path.islink(path):
                    raise SweepError(str(path), "is a symbolic link; symvib never writes through one (remove it, "
                                                "or run the sweep into another folder)")

    def write(self, index: int, columns: dict) -> None:
        """Write chunk ``index``: unmark it, write its region of every array, then mark it (atomic rename)."""
        path = marker_path(self.out, index)
        try:
            safeio.remove_file(self.out, f"chunks/{path.name}")
        except OSError as exc:
            raise SweepError(str(path), f"cannot remove it: {exc}") from None
        rows = columns["row"]
        start, stop = int(rows[0]), int(rows[-1]) + 1
        self._refuse_links(index)
        try:
            for column, name in self.names.items():
                self.arrays[name][start:stop] = columns[column]
            text = json.dumps({"sweep_id": self.ident, "chunk": index, "rows": [start, stop],
                               "sha256": digests(columns)})
            safeio.write_text(self.out, f"chunks/{path.name}", text, what="sweep folder")
        except OSError as exc:
            raise SweepError(str(store_path(self.out)), f"cannot write chunk {index}: {exc.strerror or exc}") \
                from None
