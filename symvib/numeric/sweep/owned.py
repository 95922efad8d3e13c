"""What in a sweep folder symvib wrote, and may therefore delete.

A sweep folder holds only names symvib writes (:data:`FILES`, written into the
manifest as ``files``): ``manifest.json``, ``sweep.lock``,
``chunks/chunk-NNNNNN.npz`` (or ``.json`` markers of a Zarr sweep),
``sweep.zarr/``, ``maps/NAME.png`` and symvib's own temporary files.  A name is
not proof: a file counts as symvib's (:func:`survey`) only when its content or
the folder's manifest proves it:

* a chunk carries a sweep identity (a ``sweep_id`` member; a marker, a
  ``sweep_id`` key);
* a Zarr store carries a sweep identity in its group attributes and holds
  nothing but Zarr metadata and chunk keys (:func:`zarr_entry`);
* maps count when the folder's manifest is a valid symvib manifest;
* temporary files are named by :func:`symvib.safeio.replacing` (or by the
  versions before it: ``*.<pid>.tmp.npz``, ``manifest.json.tmp``).

Anything else is *unknown*: a sweep never deletes or replaces it, and a new
sweep refuses a folder holding unknown files unless ``--overwrite`` is given,
which then writes beside them (:func:`symvib.numeric.sweep.store.prepare`).

Examples
--------
>>> zarr_entry(("qdot0", "c", "0"), "file"), zarr_entry(("notes.txt",), "file")
(True, False)
"""
from __future__ import annotations

import json
import re
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

from symvib import safeio
from symvib.numeric.sweep.limits import SweepError
from symvib.numeric.sweep.schema import ID_DIGITS
from symvib.paths import UserPathError

__all__ = ["FILES", "STORE", "CHUNK_NAME", "Survey", "survey", "zarr_entry", "store_identity", "remove_store"]

#: The names symvib writes in a sweep folder (the manifest's ``files``; ``N`` is the chunk number).
FILES = {"manifest": "manifest.json", "lock": "sweep.lock", "chunks": "chunks/chunk-NNNNNN.npz",
         "markers": "chunks/chunk-NNNNNN.json", "store": "sweep.zarr", "maps": "maps/NAME.png"}
#: The Zarr store's name in a sweep folder.
STORE = "sweep.zarr"
#: Largest marker or Zarr metadata file read to prove it is symvib's, in bytes.
MAX_PROOF_BYTES = 2**20

#: A chunk file or marker of any sweep.
CHUNK_NAME = re.compile(r"chunk-\d{6}\.(npz|json)")
#: Temporary names of earlier versions: ``chunk-000001.1234.tmp.npz``, ``manifest.json.tmp``.
_OLD_TEMPORARY = re.compile(r"chunk-\d{6}\.\d+\.tmp\.(npz|json)|manifest\.json\.tmp")
_STALE_LOCK = re.compile(r"sweep\.lock\.stale-[0-9a-f]{32}")
_MAP = re.compile(r"[A-Za-z0-9_]+\.png")
_IDENT = re.compile(rf"[0-9a-f]{{{ID_DIGITS}}}")
#: Zarr metadata files (version 2 and 3) and chunk keys (``0``, ``0.0``; ``c`` of version 3's ``c/0``).
_ZARR_META = frozenset({"zarr.json", ".zgroup", ".zattrs", ".zmetadata", ".zarray"})
_ZARR_KEY = re.compile(r"c|\d+(\.\d+)*")
_ZARR_ARRAY = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.+-]*")


@dataclass
class Survey:
    """The entries of a sweep folder, sorted: ``ours`` (proven symvib's, as paths relative to the folder),
    ``temporary`` (symvib's temporary files) and ``unknown`` (everything else)."""

    ours: list = field(default_factory=list)
    temporary: list = field(default_factory=list)
    unknown: list = field(default_factory=list)
    store: bool = False


def _is_chunk(out: Path, rel: str) -> bool:
    """Whether ``out/rel`` carries a sweep identity (an ``.npz`` chunk's member, a marker's key)."""
    try:
        if rel.endswith(".npz"):
            with safeio.reading(out, rel) as fh, zipfile.ZipFile(fh) as z:
                return "sweep_id.npy" in z.namelist()
        marker = json.loads(safeio.read_bytes(out, rel, max_bytes=MAX_PROOF_BYTES))
        return isinstance(marker, dict) and bool(_IDENT.fullmatch(str(marker.get("sweep_id"))))
    except (OSError, ValueError, zipfile.BadZipFile, RecursionError):
        return False


def survey(out, *, manifest_ours: bool, prove: bool = True) -> Survey:
    """Sort the entries of the sweep folder ``out`` into symvib's, temporary and unknown.

    Parameters
    ----------
    out : Path
        The sweep folder (checked by the caller).
    manifest_ours : bool
        Whether ``out/manifest.json`` is a valid symvib manifest (then its maps count as symvib's).
    prove : bool
        Open every chunk file for its sweep identity (``False``: a resumed sweep, whose
        manifest lists its chunk names and which checks every chunk it reads anyway).

    Returns
    -------
    Survey
    """
    out = Path(out)
    found = Survey()
    for name, kind in sorted(safeio.entries(out).items()):
        if name in ("manifest.json", "sweep.lock") and kind == "file":
            if name == "sweep.lock" or manifest_ours:
                found.ours.append(name)
            else:
                found.unknown.append(name)
        elif (safeio.is_temporary(name) or _OLD_TEMPORARY.fullmatch(name) or _STALE_LOCK.fullmatch(name)) \
                and kind == "file":
            found.temporary.append(name)
        elif name == STORE and kind == "folder":
            found.store = True
            (found.ours if store_identity(out) else found.unknown).append(name)
        elif name in ("chunks", "maps") and kind == "folder":
            for entry, sub in sorted(safeio.entries(out, name).items()):
                rel = f"{name}/{entry}"
                if sub == "file" and (safeio.is_temporary(entry) or _OLD_TEMPORARY.fullmatch(entry)):
                    found.temporary.append(rel)
                elif sub == "file" and name == "chunks" and CHUNK_NAME.fullmatch(entry) and (
                        not prove or _is_chunk(out, rel)):
                    found.ours.append(rel)
                elif sub == "file" and name == "maps" and manifest_ours and _MAP.fullmatch(entry):
                    found.ours.append(rel)
                else:
                    found.unknown.append(rel)
        else:
            found.unknown.append(name)
    return found


def zarr_entry(parts: tuple, kind: str) -> bool:
    """Whether ``parts`` (a path below ``sweep.zarr``) is what Zarr writes for a sweep: metadata files,
    array folders and chunk keys, nothing else."""
    head, rest = parts[0], parts[1:]
    if not rest:
        return head in _ZARR_META if kind == "file" else bool(_ZARR_ARRAY.fullmatch(head)) and head not in _ZARR_META
    if len(rest) == 1 and kind == "file" and rest[0] in _ZARR_META:
        return True
    return all(_ZARR_KEY.fullmatch(p) for p in rest)


def store_identity(out) -> str | None:
    """The sweep identity in the group attributes of ``out/sweep.zarr`` (Zarr 3 or 2), or ``None``."""
    for name, attrs_of in (("zarr.json", lambda m: m.get("attributes")), (".zattrs", lambda m: m)):
        try:
            meta = json.loads(safeio.read_bytes(out, f"{STORE}/{name}", max_bytes=MAX_PROOF_BYTES))
        except (OSError, ValueError, RecursionError):
            continue
        attrs = attrs_of(meta) if isinstance(meta, dict) else None
        ident = attrs.get("sweep_id") if isinstance(attrs, dict) else None
        if isinstance(ident, str) and _IDENT.fullmatch(ident):
            return ident
    return None


def remove_store(out, field_name: str = "out") -> None:
    """Remove ``out/sweep.zarr`` if symvib provably wrote it (its identity and only Zarr's entries in it).

    Raises
    ------
    SweepError
        Naming the store when it cannot be proven symvib's (nothing is removed then).
    """
    where = Path(out) / STORE
    if STORE not in safeio.entries(out):
        return
    if store_identity(out) is None:
        raise SweepError(str(where), "symvib cannot tell it wrote this Zarr store (no sweep identity in it); "
                                     "remove it yourself or choose another folder")
    try:
        safeio.remove_tree(out, STORE, zarr_entry)
    except UserPathError as exc:
        raise SweepError(str(where), f"not removed: {exc}; remove it yourself or choose another folder") from None
