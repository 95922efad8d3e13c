"""Parameter sweeps: many scenes of one curve through the driver's core at once.

A sweep takes a base :class:`~symvib.numeric.scene.Scene` and varies some of its
fields, named with the scene file's own keys (``qdot``, ``q``, ``mu``,
``alpha0``, ``restitution``, ``g``, ``m``, ``left``, ``right``, ``t_max``,
``max_events``, a curve parameter such as ``p``, or the dotted form
``initial.qdot``, ``parameters.p``), over

* a grid: ``qdot=3:12:200`` (``start:stop:count``, ends included) or a list
  ``k=0.6,0.8,1``; the first axis varies slowest (C order), or
* random samples: ``--random N`` with ranges ``mu=0.01:0.2``, uniform, drawn
  from ``numpy.random.default_rng([seed, chunk])`` so a chunk's rows never
  depend on which process draws them.

Every scene runs the same compiled loop as :func:`symvib.numeric.driver.simulate`
(:func:`symvib.numeric.engine.sweep`, parallel over scenes on the numba backend), so a
sweep's event sequences are the single-scene driver's.  Per scene it keeps the
columns :data:`symvib.numeric.engine.SUMMARY` (status, event counts, final time and
position, friction work, impact loss, energies) and, with ``log_events=L``,
the first ``L`` events.

Output (``out=DIR``): ``DIR/manifest.json`` (the sweep's definition) and one
``DIR/chunks/chunk-NNNNNN.npz`` per chunk of rows, NumPy's own archive format
(``numpy.load`` reads it, no extra dependency; :func:`load_sweep` joins the
chunks into columns).  Each chunk file is written to a temporary name and
renamed, so it either exists complete or not at all: a killed sweep restarted
with the same definition computes exactly the chunks that are missing.  Given
``scheduler`` (a ``dask.distributed`` address or ``Client``, extra
``symvib[dask]``), the chunks run on that cluster and are written here.

Examples
--------
>>> from symvib.numeric.scene import scene_from_dict
>>> base = scene_from_dict({"curve": {"shape": "parabola"}, "parameters": {"p": 1},
...     "physics": {"g": 9.81, "m": 0.2, "mu": 0.05, "restitution": 0.8},
...     "limiters": {"left": "-pi/6", "right": "pi/4"}, "initial": {"q": 0, "qdot": 7}})
>>> res = sweep(base, {"qdot": "3:12:4", "mu": [0.05, 0.1]}, backend="python")
>>> res.count, res.grid("impacts").shape
(8, (4, 2))
>>> set(res.status_names())
{'arrested'}
"""
from __future__ import annotations

import argparse
import hashlib
import json
import math
import os
import secrets
import socket
import sys
import time
import zipfile
import zlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from symvib.numeric import engine as core
from symvib import expr as _expr
from symvib.numeric.scene import MAX_EVENTS, Scene, SceneError, load_scene, scene_from_dict

__all__ = ["SweepSpec", "SweepResult", "SweepError", "WriterLock", "make_spec", "sweep", "load_sweep",
           "run_chunk", "sweep_id", "main", "FORMAT", "DEFAULT_CHUNK", "MAX_SCENES", "MAX_CHUNKS",
           "MAX_LIST_VALUES", "MAX_LOG_EVENTS", "MAX_CHUNK_BYTES", "MAX_EVENT_LOG_BYTES", "NODES_RANGE"]

#: Identifier of the on-disk layout (manifest key ``format``).  Version 2 added the
#: sweep identity (``sweep_id``) to the manifest and to every chunk.
FORMAT = "symvib-sweep/2"
#: Layouts this version recognizes but does not read (their chunks carry no sweep identity).
OLD_FORMATS = ("symvib-sweep/1",)
#: Scenes per chunk: the unit of writing, resuming and distribution.
DEFAULT_CHUNK = 4096
#: Default Gauss-Legendre nodes per quadrature panel (as :func:`symvib.numeric.driver.simulate`).
DEFAULT_NODES = 16
#: Allowed Gauss-Legendre nodes per panel, inclusive (``symvib.codegen.gauss`` tabulates rules up to this size).
NODES_RANGE = (2, 64)
#: Largest number of scenes a sweep may declare: its joined columns (about 130 bytes a
#: scene with two varied fields) are held in memory by :func:`load_sweep`.
MAX_SCENES = 10**8
#: Largest number of chunk files of a sweep (chunk files are numbered with six digits).
MAX_CHUNKS = 10**6
#: Largest number of values of one listed grid axis (``k=0.6,0.8,1``); a
#: ``start:stop:count`` axis is stored as its three numbers, whatever its count.
MAX_LIST_VALUES = 10**5
#: Largest number of events logged per scene (``--log-events``).
MAX_LOG_EVENTS = 10**6
#: Largest memory of one chunk's columns while it is computed, written or read, in bytes.
MAX_CHUNK_BYTES = 2**30
#: Largest event log of a whole sweep (scenes x ``log_events`` x 6 floats), in bytes:
#: :func:`load_sweep` joins it in memory.
MAX_EVENT_LOG_BYTES = 2**32
#: Largest manifest read, in bytes (listed axes of MAX_LIST_VALUES values fit many times).
MAX_MANIFEST_BYTES = 2**26
#: Seconds a lock file may stay empty (its writer between creating and filling it) before it counts as stale.
LOCK_GRACE = 10.0
#: Exit status of ``symvib sweep`` when some scenes failed (their rows are written, with their
#: status): the status of ``symvib run`` for a failed run, one code for one meaning.
EXIT_FAILED_SCENES = 3
#: Seconds between progress-bar redraws.
PROGRESS_EVERY = 0.2
#: Chunks in flight per Dask worker.
DASK_INFLIGHT = 2
#: Bytes of one float64 or int64 value.
_ITEM = 8
#: Values per logged event (kind, t, q, qdot_before, qdot_after, energy).
_EVENT_WIDTH = 6
#: Hex digits of the sweep identity (a SHA-256 of the format and definition).
_ID_DIGITS = 32


class SweepError(SceneError):
    """A sweep folder, manifest or chunk cannot be used; ``field`` names the file or the option."""


#: Scene fields a sweep can vary: canonical name -> (Scene attribute, column of core.SCALARS).
_FIELDS = {
    "initial.q": ("q0", 8), "initial.qdot": ("qdot0", 9), "physics.mu": ("mu", 2),
    "physics.alpha0": ("mu", 2), "physics.restitution": ("k", 3), "physics.g": ("g", 0),
    "physics.m": ("m", 1), "limiters.left": ("left", 5), "limiters.right": ("right", 7),
    "run.t_max": ("t_max", 10), "run.max_events": ("max_events", 11),
}
#: Scene-file names of the columns of core.SCALARS (for error messages).
_SCALAR_FIELDS = ("physics.g", "physics.m", "physics.mu", "physics.restitution", "limiters.left",
                  "limiters.left", "limiters.right", "limiters.right", "initial.q", "initial.qdot",
                  "run.t_max", "run.max_events", "physics.contact")
_SHORT = {"q": "initial.q", "qdot": "initial.qdot", "q0": "initial.q", "qdot0": "initial.qdot",
          "mu": "physics.mu", "alpha0": "physics.alpha0", "restitution": "physics.restitution",
          "k": "physics.restitution", "g": "physics.g", "m": "physics.m", "left": "limiters.left",
          "right": "limiters.right", "t_max": "run.t_max", "max_events": "run.max_events"}


def canonical_field(scene: Scene, key: str) -> str:
    """The dotted scene-file name of a sweepable ``key`` (``"qdot"`` -> ``"initial.qdot"``).

    Curve parameters are ``parameters.NAME``; the coordinate's own name works
    for the initial state too (``phidot`` for ``qdot`` on the paper's curves).
    """
    key = key.strip()
    params = [n for n, _ in scene.params]
    if key in _FIELDS or key.startswith("parameters.") and key.split(".", 1)[1] in params:
        return key
    if key in params:
        return f"parameters.{key}"
    q = scene.shape.q
    aliases = {q: "initial.q", f"{q}0": "initial.q", f"{q}dot": "initial.qdot", f"{q}dot0": "initial.qdot"}
    if key in _SHORT:
        return _SHORT[key]
    if key in aliases:
        return aliases[key]
    known = sorted(set(_SHORT) | set(params))
    raise SceneError(f"vary.{key}", f"not a sweepable field of this scene; use one of {', '.join(known)} "
                                    f"(or a dotted scene-file name such as initial.qdot)")


def _linspace_at(start: float, stop: float, count: int, index) -> np.ndarray:
    """Entries ``index`` of ``numpy.linspace(start, stop, count)``, bit for bit, without building it."""
    index = np.asarray(index, dtype=np.int64)
    if count == 1:
        return np.full(index.shape, float(start))
    div = count - 1
    delta = stop - start
    step = delta / div
    # numpy.linspace: arange * step + start (arange / div * delta when the step underflows to 0), last = stop
    y = index / div * delta + start if step == 0 else index * step + start
    return np.where(index == div, float(stop), y)


@dataclass(frozen=True)
class Axis:
    """One varied field: a grid ``start:stop:count`` (stored as those three
    numbers), listed grid values ``items``, or a random range ``[low, high]``.

    Values are computed per chunk (:meth:`at`), so an axis of any count costs
    three numbers until its chunk is run.
    """

    key: str
    field: str
    items: tuple | None = None
    start: float | None = None
    stop: float | None = None
    count: int | None = None
    low: float | None = None
    high: float | None = None

    @property
    def grid(self) -> bool:
        """Whether this is a grid axis (else a random range)."""
        return self.items is not None or self.count is not None

    @property
    def size(self) -> int | None:
        """Number of grid values (``None`` for a random range)."""
        if self.items is not None:
            return len(self.items)
        return self.count

    def at(self, index) -> np.ndarray:
        """Grid values at positions ``index`` (an integer array)."""
        if self.items is not None:
            return np.asarray(self.items, dtype=float)[np.asarray(index, dtype=np.int64)]
        return _linspace_at(self.start, self.stop, self.count, index)

    @property
    def first(self) -> float | None:
        """The first grid value (``None`` for a random range)."""
        return float(self.at(np.zeros(1, dtype=np.int64))[0]) if self.grid else None

    @property
    def values(self) -> tuple | None:
        """All grid values (built on demand: use :meth:`at` for large axes); ``None`` if random."""
        return tuple(float(v) for v in self.at(np.arange(self.size))) if self.grid else None

    @property
    def bounds(self) -> tuple:
        """Smallest and largest value the axis takes."""
        if self.items is not None:
            return min(self.items), max(self.items)
        if self.count is not None:
            return min(self.start, self.stop), max(self.start, self.stop)
        return self.low, self.high

    def to_dict(self) -> dict:
        head = {"key": self.key, "field": self.field}
        if self.items is not None:
            return head | {"values": list(self.items)}
        if self.count is not None:
            return head | {"start": self.start, "stop": self.stop, "count": self.count}
        return head | {"low": self.low, "high": self.high}

    @classmethod
    def from_dict(cls, data, label: str) -> "Axis":
        """An axis from a manifest's definition (types and sizes checked; ``label`` names it)."""
        if not isinstance(data, dict) or not isinstance(data.get("key"), str) \
                or not isinstance(data.get("field"), str):
            raise SweepError(label, "must be a table with text 'key' and 'field'")
        kinds = [k for k in (("values",), ("start", "stop", "count"), ("low", "high")) if k[0] in data]
        if len(kinds) != 1 or set(data) != {"key", "field", *kinds[0]}:
            raise SweepError(label, "must hold values, or start, stop and count, or low and high")
        if "values" in data:
            items = data["values"]
            if not isinstance(items, list) or not 1 <= len(items) <= MAX_LIST_VALUES:
                raise SweepError(f"{label}.values", f"must be a list of 1 to {MAX_LIST_VALUES} numbers")
            return cls(data["key"], data["field"], items=tuple(_real(v, f"{label}.values") for v in items))
        if "count" in data:
            count = data["count"]
            if isinstance(count, bool) or not isinstance(count, int) or not 1 <= count <= MAX_SCENES:
                raise SweepError(f"{label}.count", f"must be an integer in [1, {MAX_SCENES}], got {count!r}")
            return cls(data["key"], data["field"], start=_real(data["start"], f"{label}.start"),
                       stop=_real(data["stop"], f"{label}.stop"), count=count)
        low, high = _real(data["low"], f"{label}.low"), _real(data["high"], f"{label}.high")
        if not low <= high:
            raise SweepError(label, f"low must not exceed high, got {low!r} > {high!r}")
        return cls(data["key"], data["field"], low=low, high=high)


def _real(value, label: str) -> float:
    """A finite number from a manifest (JSON), else a :class:`SweepError` naming ``label``."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise SweepError(label, f"must be a finite number, got {value!r}")
    return float(value)


def _axis(scene: Scene, key: str, spec, random: bool) -> Axis:
    """An :class:`Axis` from ``"start:stop:count"``, ``"start:stop"``, ``"a,b,c"`` or a sequence.

    Sizes are checked before anything of that size is built: a count beyond
    :data:`MAX_SCENES`, or more than :data:`MAX_LIST_VALUES` listed values, is refused.
    """
    fld = canonical_field(scene, key)
    label = f"vary.{key}"

    def num(text):
        if isinstance(text, (int, float, np.integer, np.floating)) and not isinstance(text, (bool, np.bool_)):
            if not math.isfinite(text):
                raise SceneError(label, f"must be finite, got {float(text)}")
            return float(text)
        try:
            return _expr.number(str(text), field=label, symbols=dict(scene.params))
        except _expr.ExpressionError as exc:
            raise SceneError(label, exc.reason) from None

    if isinstance(spec, dict):
        spec = [spec.get("start"), spec.get("stop")] + ([spec["count"]] if "count" in spec else [])
        spec = ":".join(str(v) for v in spec)
    if isinstance(spec, str) and ":" in spec:
        parts = spec.split(":")
        if random:
            if len(parts) != 2:
                raise SceneError(label, f"a random sweep takes a range start:stop, got {spec!r}")
            low, high = num(parts[0]), num(parts[1])
            if not low <= high:
                raise SceneError(label, f"range start must not exceed stop, got {spec!r}")
            return Axis(key, fld, low=low, high=high)
        if len(parts) != 3:
            raise SceneError(label, f"a grid axis is start:stop:count, got {spec!r}")
        try:
            count = int(parts[2])
        except ValueError:
            raise SceneError(label, f"count must be an integer, got {parts[2]!r}") from None
        if count < 1:
            raise SceneError(label, f"count must be at least 1, got {count}")
        if count > MAX_SCENES:
            raise SceneError(label, f"count {count} is more scenes than a sweep may hold ({MAX_SCENES}, "
                                    f"symvib.numeric.sweep.MAX_SCENES)")
        start, stop = num(parts[0]), num(parts[1])
        return Axis(key, fld, start=start, stop=stop, count=count)
    if random:
        raise SceneError(label, "a random sweep takes a range start:stop, not a list of values")
    if isinstance(spec, str):
        if spec.count(",") >= MAX_LIST_VALUES:
            raise SceneError(label, f"more than {MAX_LIST_VALUES} listed values (symvib.numeric.sweep.MAX_LIST_VALUES); "
                                    f"use start:stop:count")
        items = spec.split(",")
    else:
        items = np.atleast_1d(spec)
        if items.ndim != 1 or items.size > MAX_LIST_VALUES:
            raise SceneError(label, f"must be a flat list of at most {MAX_LIST_VALUES} values "
                                    f"(symvib.numeric.sweep.MAX_LIST_VALUES); use start:stop:count")
        items = list(items)
    if not len(items) or items == [""]:
        raise SceneError(label, "no values given")
    return Axis(key, fld, items=tuple(num(v) for v in items))


@dataclass(frozen=True)
class SweepSpec:
    """What a sweep computes: base scene, axes, mode, size, chunking (validated).

    Build with :func:`make_spec`.  ``to_dict`` is the manifest's definition; two
    specs are the same sweep iff their dicts are equal.
    """

    scene: Scene
    axes: tuple
    mode: str
    count: int
    seed: int = 0
    chunk: int = DEFAULT_CHUNK
    log_events: int = 0
    nodes: int = DEFAULT_NODES

    @property
    def shape(self) -> tuple:
        """The grid's shape (one entry per axis); ``(count,)`` for random samples."""
        return tuple(a.size for a in self.axes) if self.mode == "grid" else (self.count,)

    @property
    def chunks(self) -> int:
        return -(-self.count // self.chunk)

    def to_dict(self) -> dict:
        return {"scene": self.scene.to_dict(), "axes": [a.to_dict() for a in self.axes], "mode": self.mode,
                "count": self.count, "seed": self.seed, "chunk": self.chunk, "log_events": self.log_events,
                "nodes": self.nodes}

    @classmethod
    def from_dict(cls, data: dict) -> "SweepSpec":
        """The spec of a definition (:meth:`to_dict`), checked as :func:`make_spec` checks one.

        A definition comes from a manifest or a Dask task: every type and size
        is checked (:func:`_check_sizes`) before anything is allocated.

        Raises
        ------
        SweepError
            Naming the key of the definition (``definition.axes[0].count``).
        """
        label = "definition"
        if not isinstance(data, dict):
            raise SweepError(label, f"must be a table, got {type(data).__name__}")
        keys = {"scene", "axes", "mode", "count", "seed", "chunk", "log_events", "nodes"}
        if set(data) != keys:
            wrong = sorted(set(data) ^ keys)[0]
            raise SweepError(f"{label}.{wrong}", "missing" if wrong in keys else "unknown key")
        try:
            scene = scene_from_dict(data["scene"])
        except SceneError as exc:
            raise SweepError(f"{label}.scene.{exc.field}", exc.reason) from None
        if not isinstance(data["axes"], list) or not data["axes"]:
            raise SweepError(f"{label}.axes", "must be a non-empty list")
        axes = tuple(Axis.from_dict(a, f"{label}.axes[{i}]") for i, a in enumerate(data["axes"]))
        for i, a in enumerate(axes):
            try:
                if canonical_field(scene, a.field) != a.field:
                    raise SceneError(a.field, "not canonical")
            except SceneError:
                raise SweepError(f"{label}.axes[{i}].field", f"{a.field!r} is not a sweepable field of the scene") \
                    from None
        ints = {}
        for key in ("count", "seed", "chunk", "log_events", "nodes"):
            value = data[key]
            if isinstance(value, bool) or not isinstance(value, int):
                raise SweepError(f"{label}.{key}", f"must be an integer, got {value!r}")
            ints[key] = value
        if data["mode"] not in ("grid", "random") or any(a.grid != (data["mode"] == "grid") for a in axes):
            raise SweepError(f"{label}.mode", "must be 'grid' (axes of values) or 'random' (axes of ranges)")
        spec = cls(scene, axes, data["mode"], **ints)
        _check_sizes(spec, prefix=f"{label}.")
        return spec

    def rows(self, index: int) -> tuple:
        """Row numbers and varied values (one array per axis) of chunk ``index``."""
        start = index * self.chunk
        stop = min(start + self.chunk, self.count)
        rows = np.arange(start, stop, dtype=np.int64)
        if self.mode == "grid":
            idx = np.unravel_index(rows, self.shape)
            return rows, [a.at(i) for a, i in zip(self.axes, idx)]
        rng = np.random.default_rng([self.seed, index])
        u = rng.random((stop - start, len(self.axes)))
        return rows, [a.low + (a.high - a.low) * u[:, j] for j, a in enumerate(self.axes)]

    def chunk_bytes(self) -> int:
        """Bytes of the columns of one full chunk (row, varied fields, summary, event log)."""
        per_row = (1 + len(self.axes) + len(core.SUMMARY) + _EVENT_WIDTH * self.log_events) * _ITEM
        return min(self.chunk, self.count) * per_row

    def scalars(self, values) -> tuple:
        """Rows of :data:`symvib.numeric.engine.SCALARS` and of curve parameters for varied ``values``.

        Every row is validated as :class:`~symvib.numeric.scene.Scene` validates one
        scene; a bad row raises :class:`SceneError` naming the field and the row.
        """
        s = self.scene
        n = len(values[0]) if values else 0
        base = np.array([s.g, s.m, s.mu, s.k, s.left is not None, 0.0 if s.left is None else s.left,
                         s.right is not None, 0.0 if s.right is None else s.right, s.q0, s.qdot0, s.t_max,
                         s.max_events, s.contact == "unilateral"], dtype=float)
        scal = np.repeat(base[None, :], n, axis=0)
        names = [name for name, _ in s.params]
        cp = np.repeat(np.array(s.param_values, dtype=float)[None, :], n, axis=0)
        for axis, v in zip(self.axes, values):
            v = np.asarray(v, dtype=float)
            if axis.field.startswith("parameters."):
                cp[:, names.index(axis.field.split(".", 1)[1])] = v
                continue
            col = _FIELDS[axis.field][1]
            if axis.field == "physics.alpha0":
                _require(v, (v >= 0) & (v < math.pi / 2), axis.field, "friction angle must be in [0, pi/2)")
                v = np.tan(v)
            if axis.field == "run.max_events":
                _require(v, v == np.round(v), axis.field, "must be an integer")
            scal[:, col] = v
            if axis.field in ("limiters.left", "limiters.right"):
                scal[:, col - 1] = 1.0
        _check_rows(self, scal, cp, names)
        return np.ascontiguousarray(scal), np.ascontiguousarray(cp)


def _require(values, ok, fld, reason):
    bad = np.flatnonzero(~ok)
    if bad.size:
        raise SceneError(fld, f"{reason}, got {np.asarray(values)[bad[0]].item()!r} (sweep row {bad[0]} of its chunk)")


def _check_rows(spec: SweepSpec, scal, cp, names) -> None:
    """Vectorized :func:`symvib.numeric.scene._validate` over the rows of one chunk."""
    g, m, mu, k, hl, left, hr, right, q0, qdot0, t_max, max_events, _unilateral = scal.T
    for label, v in zip(_SCALAR_FIELDS, scal.T):
        _require(v, np.isfinite(v), label, "must be finite")
    _require(g, g > 0, "physics.g", "must be positive")
    _require(m, m > 0, "physics.m", "must be positive")
    _require(mu, mu >= 0, "physics.mu", "friction coefficient must be >= 0")
    _require(k, (k >= 0) & (k <= 1), "physics.restitution", "must be in [0, 1]")
    _require(t_max, t_max > 0, "run.t_max", "must be positive")
    _require(max_events, max_events >= 1, "run.max_events", "must be a positive integer")
    over = np.flatnonzero(max_events > MAX_EVENTS)
    if over.size:
        raise SceneError("run.max_events", f"at most {MAX_EVENTS} (scene.MAX_EVENTS), got {float(max_events[over[0]]):g} "
                                           f"(sweep row {over[0]} of its chunk)")
    both = (hl != 0) & (hr != 0)
    _require(left, ~both | (left < right), "limiters", "left limiter must be left of the right one")
    _require(q0, (hl == 0) | (q0 >= left), "initial.q", "is left of the left limiter")
    _require(q0, (hr == 0) | (q0 <= right), "initial.q", "is right of the right limiter")
    kinds = spec.scene.shape.params
    for j, name in enumerate(names):
        _require(cp[:, j], np.isfinite(cp[:, j]), f"parameters.{name}", "must be finite")
        if kinds.get(name, "positive") == "positive":
            _require(cp[:, j], cp[:, j] > 0, f"parameters.{name}", "must be positive")
    if not any(a.field.startswith("parameters.") for a in spec.axes):
        lo, hi = _domain(spec.scene, spec.scene.param_values)
        for label, v, has in (("limiters.left", left, hl != 0), ("limiters.right", right, hr != 0),
                              ("initial.q", q0, np.ones_like(hl, dtype=bool))):
            _require(v, ~has | ((v > lo) & (v < hi)), label, f"is outside the curve's regular domain ({lo:.6g}, {hi:.6g})")
    else:
        for i in range(cp.shape[0]):
            lo, hi = _domain(spec.scene, tuple(cp[i]))
            for label, v, has in (("limiters.left", left[i], hl[i] != 0), ("limiters.right", right[i], hr[i] != 0),
                                  ("initial.q", q0[i], True)):
                if has and not lo < v < hi:
                    raise SceneError(label, f"{v!r} is outside the curve's regular domain ({lo:.6g}, {hi:.6g}) "
                                            f"(sweep row {i} of its chunk)")


def _domain(scene: Scene, values) -> tuple:
    from symvib.numeric.scene import declared_domain

    return declared_domain(scene.replace(params=dict(zip((n for n, _ in scene.params), (float(v) for v in values)))))


def make_spec(scene: Scene, vary: dict, *, random: int | None = None, seed: int = 0,
              chunk: int = DEFAULT_CHUNK, log_events: int = 0, nodes: int = DEFAULT_NODES) -> SweepSpec:
    """Validate a sweep definition.

    Parameters
    ----------
    scene : Scene
        The base scene; fields not varied keep its values.
    vary : dict
        Field key -> ``"start:stop:count"`` / ``"a,b,c"`` / sequence (grid), or
        ``"start:stop"`` (random).
    random : int, optional
        Number of random samples; ``None`` for a grid.
    seed, chunk, log_events : int
        Random seed, scenes per chunk, events kept per scene.
    nodes : int
        Gauss-Legendre nodes per quadrature panel (as :func:`symvib.numeric.driver.simulate`),
        in :data:`NODES_RANGE`.

    Raises
    ------
    SceneError
        Naming the field or option; sizes (:func:`_check_sizes`) are checked
        before anything of that size is built.
    """
    if not isinstance(scene, Scene):
        raise SceneError("scene", f"must be a Scene, got {type(scene).__name__}")
    if not isinstance(vary, dict) or not vary:
        raise SceneError("vary", "nothing to vary: give at least one field, e.g. qdot=3:12:200")
    axes = tuple(_axis(scene, key, value, random is not None) for key, value in vary.items())
    fields = [a.field for a in axes]
    for fld in set(fields):
        if fields.count(fld) > 1:
            raise SceneError(f"vary.{fld}", "varied twice")
    if "physics.mu" in fields and "physics.alpha0" in fields:
        raise SceneError("vary", "vary mu or alpha0 (mu = tan(alpha0)), not both")
    if random is not None:
        if isinstance(random, bool) or not isinstance(random, int) or random < 1:
            raise SceneError("random", f"number of samples must be a positive integer, got {random!r}")
        count = random
    else:
        count = math.prod(a.size for a in axes)   # Python integers: no overflow
    spec = SweepSpec(scene, axes, "grid" if random is None else "random", count, seed, chunk, log_events, nodes)
    _check_sizes(spec)
    # Every corner of the box of varied values is a valid scene (the linear
    # constraints then hold inside it); each chunk is checked row by row too.
    corners = [a.bounds for a in axes]
    for corner in np.array(np.meshgrid(*corners, indexing="ij")).reshape(len(axes), -1).T:
        spec.scalars([np.array([v]) for v in corner])
    return spec


def _check_sizes(spec: SweepSpec, prefix: str = "") -> None:
    """Refuse, before anything is allocated, a sweep beyond the module's bounds.

    Bounds: :data:`MAX_SCENES`, :data:`MAX_CHUNKS`, :data:`MAX_LOG_EVENTS`,
    :data:`MAX_CHUNK_BYTES`, :data:`MAX_EVENT_LOG_BYTES`, :data:`NODES_RANGE`
    (module constants: assign them to change a bound).  Errors name the option.
    """
    for label, value, least in (("chunk", spec.chunk, 1), ("log_events", spec.log_events, 0),
                                ("seed", spec.seed, 0), ("nodes", spec.nodes, NODES_RANGE[0])):
        if isinstance(value, bool) or not isinstance(value, int) or value < least:
            raise SceneError(prefix + label, f"must be an integer >= {least}, got {value!r}")
    if spec.nodes > NODES_RANGE[1]:
        raise SceneError(prefix + "nodes", f"must be in [{NODES_RANGE[0]}, {NODES_RANGE[1]}], got {spec.nodes}")
    if isinstance(spec.count, bool) or not isinstance(spec.count, int) or spec.count < 1:
        raise SceneError(prefix + "count", f"must be a positive integer, got {spec.count!r}")
    if spec.mode == "grid" and spec.count != math.prod(a.size for a in spec.axes):
        raise SceneError(prefix + "count", f"{spec.count} is not the product of the axes' sizes")
    if spec.count > MAX_SCENES:
        sizes = " x ".join(f"{a.key} {a.size}" for a in spec.axes) if spec.mode == "grid" else "--random"
        raise SceneError(prefix + ("vary" if spec.mode == "grid" else "random"),
                         f"{spec.count} scenes ({sizes}) is more than a sweep may hold ({MAX_SCENES}, "
                         f"symvib.numeric.sweep.MAX_SCENES)")
    if spec.chunks > MAX_CHUNKS:
        raise SceneError(prefix + "chunk", f"{spec.chunk} scenes per chunk makes {spec.chunks} chunk files, more "
                                           f"than {MAX_CHUNKS} (symvib.numeric.sweep.MAX_CHUNKS): choose a larger --chunk")
    if spec.log_events > MAX_LOG_EVENTS:
        raise SceneError(prefix + "log_events", f"{spec.log_events} events per scene is more than "
                                                f"{MAX_LOG_EVENTS} (symvib.numeric.sweep.MAX_LOG_EVENTS)")
    if spec.chunk_bytes() > MAX_CHUNK_BYTES:
        raise SceneError(prefix + "chunk", f"a chunk of {min(spec.chunk, spec.count)} scenes with --log-events "
                                           f"{spec.log_events} takes {spec.chunk_bytes()} bytes, more than "
                                           f"{MAX_CHUNK_BYTES} (symvib.numeric.sweep.MAX_CHUNK_BYTES): choose a smaller "
                                           f"--chunk or --log-events")
    log_bytes = spec.count * spec.log_events * _EVENT_WIDTH * _ITEM
    if log_bytes > MAX_EVENT_LOG_BYTES:
        raise SceneError(prefix + "log_events", f"{spec.count} scenes x {spec.log_events} logged events take "
                                                f"{log_bytes} bytes, more than {MAX_EVENT_LOG_BYTES} "
                                                f"(symvib.numeric.sweep.MAX_EVENT_LOG_BYTES): log fewer events")


def run_chunk(definition: dict, index: int, backend: str = "auto") -> dict:
    """Compute chunk ``index`` of the sweep ``definition`` (:meth:`SweepSpec.to_dict`).

    A pure function of its arguments (it runs on Dask workers): returns the
    chunk's columns as a dict of arrays (``row``, the varied fields, the
    :data:`symvib.numeric.engine.SUMMARY` columns, and ``event_log`` when asked).
    """
    spec = SweepSpec.from_dict(definition)
    if isinstance(index, bool) or not isinstance(index, (int, np.integer)) or not 0 <= index < spec.chunks:
        raise SweepError("chunk", f"index must be an integer in [0, {spec.chunks}), got {index!r}")
    rows, values = spec.rows(int(index))
    scal, cp = spec.scalars(values)
    from symvib.numeric.driver import sweep_function

    summary, logs = sweep_function(spec.scene, backend)(scal, cp, spec.nodes, spec.log_events)
    out = {"row": rows}
    for axis, v in zip(spec.axes, values):
        out[axis.field] = np.asarray(v, dtype=float)
    for j, name in enumerate(core.SUMMARY):
        col = summary[:, j]
        out[name] = col.astype(np.int64) if name in _INTEGER_COLUMNS else col
    if spec.log_events:
        out["event_log"] = logs[:, :spec.log_events]
    return out


_INTEGER_COLUMNS = ("status", "events", "impacts", "reversals", "normal_sign_changes")


@dataclass(frozen=True)
class SweepResult:
    """A sweep's definition and its per-scene columns (row order), read-only.

    Attributes
    ----------
    spec : SweepSpec
    columns : dict of str -> ndarray
        ``row``, each varied field, the :data:`symvib.numeric.engine.SUMMARY` columns,
        ``event_log`` (shape ``(count, log_events, 6)``: kind, t, q,
        qdot_before, qdot_after, energy) when events were logged.
    computed, reused : tuple of int
        Chunks computed by this call, and chunks found complete (and valid) on disk.
    seconds : float
        Wall time of the computation.
    out : str or None
        The sweep folder.
    discarded : tuple of int
        Chunks found on disk but truncated, unreadable or made by another sweep:
        removed and computed again (they are in ``computed`` too).
    """

    spec: SweepSpec
    columns: dict
    computed: tuple = ()
    reused: tuple = ()
    seconds: float = 0.0
    out: str | None = field(default=None)
    discarded: tuple = ()

    @property
    def count(self) -> int:
        return self.spec.count

    def __getitem__(self, name: str) -> np.ndarray:
        return self.columns[name]

    def status_names(self) -> np.ndarray:
        """Each scene's status as a string (``"arrested"``, ...)."""
        return np.asarray(core.STATUS_NAMES, dtype=object)[self.columns["status"]]

    def grid(self, name: str) -> np.ndarray:
        """Column ``name`` shaped as the grid (axes in the order declared)."""
        if self.spec.mode != "grid":
            raise ValueError("a random sweep has no grid; use the columns")
        return self.columns[name].reshape(self.spec.shape + self.columns[name].shape[1:])

    def events(self, row: int) -> list:
        """The logged events of scene ``row``: ``(kind, t, q, qdot_before, qdot_after, energy)``."""
        if "event_log" not in self.columns:
            raise ValueError("this sweep kept no event log (log_events = 0)")
        n = min(int(self.columns["events"][row]), self.spec.log_events)
        return [(core.EVENT_NAMES[int(r[0])], *map(float, r[1:])) for r in self.columns["event_log"][row, :n]]

    @property
    def failed(self) -> np.ndarray:
        """Rows whose run failed (a status of ``symvib.numeric.engine.ERROR_CODES``: non-finite state, energy
        budget not closing): their numbers are not a result."""
        return np.isin(self.columns["status"], core.ERROR_CODES)

    @property
    def impact_share(self) -> np.ndarray:
        """Share of the energy lost to impacts, ``W_impacts / (W_friction + W_impacts)`` (NaN if none)."""
        total = self.columns["friction_work"] + self.columns["impact_loss"]
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(total > 0, self.columns["impact_loss"] / total, np.nan)


class Progress:
    """A one-line progress bar on ``stream``: done/total, scenes per second, time left."""

    WIDTH = 30

    def __init__(self, total: int, *, stream=None, enabled: bool = True, initial: int = 0):
        self.total, self.done, self.start_done = total, initial, initial
        self.stream = sys.stderr if stream is None else stream
        self.enabled = enabled
        self.start = time.perf_counter()
        self.last = -math.inf

    def line(self) -> str:
        elapsed = time.perf_counter() - self.start
        rate = (self.done - self.start_done) / elapsed if elapsed > 0 else 0.0
        left = (self.total - self.done) / rate if rate > 0 else math.inf
        frac = self.done / self.total if self.total else 1.0
        bar = "#" * int(frac * self.WIDTH) + "." * (self.WIDTH - int(frac * self.WIDTH))
        eta = "--:--" if not math.isfinite(left) else time.strftime("%H:%M:%S", time.gmtime(left))
        return f"[{bar}] {frac:6.1%} {self.done}/{self.total} scenes, {rate:,.0f} scenes/s, {eta} left"

    def update(self, n: int, *, final: bool = False) -> None:
        self.done += n
        now = time.perf_counter()
        if not self.enabled or not final and now - self.last < PROGRESS_EVERY:
            return
        self.last = now
        tty = getattr(self.stream, "isatty", lambda: False)()
        self.stream.write(("\r" if tty else "") + self.line() + ("\n" if final or not tty else ""))
        self.stream.flush()


def sweep_id(definition: dict) -> str:
    """The identity of a sweep: a hash of the layout :data:`FORMAT` and its definition.

    Written in the manifest and in every chunk; a chunk is used only by the
    sweep of the same identity (the definition's canonical JSON, so a
    definition read back from a manifest has the identity it was written with).
    """
    text = json.dumps({"format": FORMAT, "definition": definition}, sort_keys=True, separators=(",", ":"),
                      allow_nan=False)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:_ID_DIGITS]


def _manifest(spec: SweepSpec, ident: str) -> dict:
    from symvib import __version__

    return {"format": FORMAT, "sweep_id": ident, "definition": spec.to_dict(), "chunks": spec.chunks,
            "columns": _column_names(spec),
            "status_names": list(core.STATUS_NAMES), "event_names": list(core.EVENT_NAMES),
            "event_log_columns": ["kind", "t", "q", "qdot_before", "qdot_after", "energy"],
            "symvib_version": __version__}


def _column_names(spec: SweepSpec) -> list:
    return ["row"] + [a.field for a in spec.axes] + list(core.SUMMARY) + (["event_log"] if spec.log_events else [])


def _chunk_path(out: Path, index: int) -> Path:
    return out / "chunks" / f"chunk-{index:06d}.npz"


def _write_chunk(out: Path, index: int, columns: dict, ident: str) -> None:
    """Write a chunk with its sweep's identity: to a temporary name, then renamed (atomic)."""
    path = _chunk_path(out, index)
    tmp = path.with_name(f"{path.stem}.{os.getpid()}.tmp.npz")
    try:
        np.savez(tmp, sweep_id=np.array(ident), **columns)
        os.replace(tmp, path)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise SweepError(str(path), f"cannot write the chunk: {exc.strerror or exc}") from None


def _bad_chunk(path: Path, reason: str) -> SweepError:
    return SweepError(str(path), f"{reason}; run the same sweep again to recompute it")


def _read_chunk(path: Path, spec: SweepSpec, ident: str, index: int) -> dict:
    """The columns of chunk ``index``, checked against the sweep: identity, names, dtypes, shapes, rows.

    Raises
    ------
    SweepError
        Naming the chunk file: truncated or unreadable, made by another sweep,
        or columns that are not this sweep's.
    """
    rows, values = spec.rows(index)
    n = len(rows)
    expected = _column_names(spec)
    try:
        if path.stat().st_size > spec.chunk_bytes() + MAX_MANIFEST_BYTES:
            raise _bad_chunk(path, "larger than a chunk of this sweep can be")
        with np.load(path, allow_pickle=False) as data:
            names = set(data.files)
            if "sweep_id" not in names:
                raise _bad_chunk(path, "no sweep identity: not a chunk of this sweep")
            _check_header(path, data, "sweep_id", lambda d, sh: d.kind == "U" and sh == () and d.itemsize <= 4 * 64,
                          "a text")
            if str(data["sweep_id"]) != ident:
                raise _bad_chunk(path, "made by another sweep (its sweep_id differs from the manifest's)")
            if names != set(expected) | {"sweep_id"}:
                raise _bad_chunk(path, f"columns {sorted(names - {'sweep_id'})} are not this sweep's")
            columns = {}
            for name in expected:   # each header checked before its array is allocated
                want = np.dtype(np.int64 if name == "row" or name in _INTEGER_COLUMNS else np.float64)
                shape = (n, spec.log_events, _EVENT_WIDTH) if name == "event_log" else (n,)
                _check_header(path, data, name, lambda d, sh: d == want and sh == shape,
                              f"{want}{list(shape)}")
                columns[name] = data[name]
    except SweepError:
        raise
    except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile, zlib.error) as exc:
        raise _bad_chunk(path, f"truncated or unreadable ({type(exc).__name__})") from None
    if not np.array_equal(columns["row"], rows) or not all(
            np.array_equal(columns[a.field], v) for a, v in zip(spec.axes, values)):
        raise _bad_chunk(path, f"rows or varied values are not those of chunk {index}")
    status = columns["status"]
    if status.size and (status.min() < 0 or status.max() >= len(core.STATUS_NAMES)):
        raise _bad_chunk(path, "status codes out of range")
    return columns


def _check_header(path: Path, data, name: str, ok, expected: str) -> None:
    """Check the ``.npy`` header of member ``name`` (dtype, shape) before its array is read."""
    with data.zip.open(f"{name}.npy") as fh:
        version = np.lib.format.read_magic(fh)
        read = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
        shape, fortran, dtype = read(fh)
    if fortran or dtype.hasobject or not ok(dtype, shape):
        raise _bad_chunk(path, f"column {name} is {dtype}{list(shape)}, expected {expected}")


class WriterLock:
    """The one writer of a sweep folder: ``FOLDER/sweep.lock``, created with ``O_CREAT | O_EXCL``.

    The lock file holds the writer's pid, host and a random nonce (JSON).  A
    lock whose pid is dead on this host (a killed sweep) is taken over; any
    other lock stops the second writer with a one-line :class:`SweepError`.
    The writer checks (:meth:`verify`) before each chunk it writes that the
    lock still holds its nonce, so even a lock taken over wrongly (a pid reused
    on another host sharing the folder) stops one writer instead of mixing two.
    """

    NAME = "sweep.lock"

    def __init__(self, folder):
        self.folder = Path(folder)
        self.path = self.folder / self.NAME
        self.nonce = secrets.token_hex(16)
        self.held = False

    def _text(self) -> str:
        return json.dumps({"pid": os.getpid(), "host": socket.gethostname(), "nonce": self.nonce,
                           "since": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())})

    def _holder(self):
        """The lock file's content as (raw bytes, parsed dict or None); ``None`` if there is no lock."""
        try:
            with open(self.path, "rb") as fh:
                raw = fh.read(4096)
        except FileNotFoundError:
            return None
        except OSError as exc:
            raise SweepError(str(self.path), f"cannot read the lock: {exc.strerror or exc}") from None
        try:
            data = json.loads(raw.decode("utf-8"))
        except (UnicodeDecodeError, ValueError):
            data = None
        return raw, data if isinstance(data, dict) else None

    def _stale(self, data) -> bool:
        if data is None:   # empty or garbled: its writer died between creating and filling it, or is filling it
            try:
                return time.time() - self.path.stat().st_mtime > LOCK_GRACE
            except FileNotFoundError:
                return True
        pid, host = data.get("pid"), data.get("host")
        if host != socket.gethostname() or isinstance(pid, bool) or not isinstance(pid, int) or pid <= 0:
            return False
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return True
        except (PermissionError, OverflowError):
            return False
        return False

    def acquire(self) -> "WriterLock":
        """Take the lock, or raise :class:`SweepError` naming the folder and the holder."""
        for _ in range(3):
            try:
                fd = os.open(self.path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            except FileExistsError:
                holder = self._holder()
                if holder is None:
                    continue   # released meanwhile
                raw, data = holder
                if not self._stale(data):
                    who = (f"pid {data.get('pid')} on {data.get('host')}, since {data.get('since')}"
                           if data else "lock file being written")
                    raise SweepError("out", f"another sweep writes {self.folder} ({who}); wait for it, or delete "
                                            f"{self.path} if that sweep is dead") from None
                self._take_over(raw)
                continue
            except OSError as exc:
                raise SweepError(str(self.path), f"cannot create the lock: {exc.strerror or exc}") from None
            try:
                os.write(fd, self._text().encode("utf-8"))
            finally:
                os.close(fd)
            self.held = True
            return self
        raise SweepError("out", f"could not take the lock {self.path}: other writers keep taking it")

    def _take_over(self, raw: bytes) -> None:
        """Remove a stale lock whose content is ``raw`` (and only that one)."""
        aside = self.path.with_name(f"{self.NAME}.stale-{self.nonce}")
        try:
            os.rename(self.path, aside)
        except FileNotFoundError:
            return
        try:
            if aside.read_bytes() != raw:   # another writer replaced the stale lock meanwhile: put it back
                try:
                    os.link(aside, self.path)
                except FileExistsError:
                    pass
        finally:
            aside.unlink(missing_ok=True)

    def verify(self) -> None:
        """Raise :class:`SweepError` unless the lock file still holds this writer's nonce."""
        holder = self._holder()
        if holder is None or holder[1] is None or holder[1].get("nonce") != self.nonce:
            raise SweepError("out", f"lost the lock {self.path}: another sweep took over {self.folder}; "
                                    f"this one stops")

    def release(self) -> None:
        """Remove the lock file if it is still this writer's."""
        if not self.held:
            return
        self.held = False
        holder = self._holder()
        if holder is not None and holder[1] is not None and holder[1].get("nonce") == self.nonce:
            self.path.unlink(missing_ok=True)


def _check_out(out) -> Path:
    """Create the sweep folder ``out`` (and its ``chunks``), or raise a one-line :class:`SweepError`."""
    if not isinstance(out, (str, os.PathLike)):
        raise SweepError("out", f"must be a folder path, got {type(out).__name__}")
    out = Path(out)
    if not str(out) or "\0" in str(out):
        raise SweepError("out", f"not a usable folder name: {str(out)!r}")
    for folder in (out, out / "chunks"):
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except FileExistsError:
            raise SweepError("out", f"{folder} exists and is not a folder (a file or a device)") from None
        except NotADirectoryError:
            raise SweepError("out", f"{folder}: a parent of it is a file, not a folder") from None
        except OSError as exc:
            raise SweepError("out", f"cannot create the folder {folder}: {exc.strerror or exc}") from None
        if not folder.is_dir() or folder.name == "chunks" and folder.is_symlink():
            raise SweepError("out", f"{folder} is not a folder (or a symbolic link, which could lead outside {out})")
        if not os.access(folder, os.W_OK | os.X_OK):
            raise SweepError("out", f"folder {folder} is not writable")
    manifest = out / "manifest.json"
    if manifest.exists() and not manifest.is_file():
        raise SweepError(str(manifest), "is not a regular file")
    return out


def _read_manifest(out: Path) -> tuple:
    """``(manifest, spec, sweep_id)`` of the sweep in ``out``, every part checked.

    Raises
    ------
    SweepError
        One line naming ``manifest.json``: missing, not a small regular file,
        not JSON, not an object, an old or unknown format, a definition that
        is not valid or not the one its ``sweep_id`` was made of.
    """
    path = out / "manifest.json"
    if not path.exists():
        raise SweepError(str(out), "no sweep here (manifest.json missing)")
    if not path.is_file():
        raise SweepError(str(path), "is not a regular file")
    try:
        size = path.stat().st_size
        if size > MAX_MANIFEST_BYTES:
            raise SweepError(str(path), f"is {size} bytes, more than a manifest may hold ({MAX_MANIFEST_BYTES})")
        with open(path, "rb") as fh:
            raw = fh.read(size + 1)   # the size was checked: no buffer of the bound's size
        if len(raw) > MAX_MANIFEST_BYTES:
            raise SweepError(str(path), f"is more than a manifest may hold ({MAX_MANIFEST_BYTES} bytes)")
        manifest = json.loads(raw.decode("utf-8"), parse_constant=_no_constant)
    except SweepError:
        raise
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
    return manifest, spec, ident


def _no_constant(name: str):
    """``json.loads`` hook: a manifest holds finite numbers only (no NaN or Infinity)."""
    raise ValueError(f"non-finite number {name}")


def _chunk_files(out: Path) -> set:
    try:
        return set(os.listdir(out / "chunks"))
    except (FileNotFoundError, NotADirectoryError):
        return set()


def _prepare(out: Path, spec: SweepSpec, ident: str, overwrite: bool) -> tuple:
    """Open ``out`` for the sweep ``ident`` (the caller holds its lock).

    Returns ``(done, discarded)``: chunks complete and valid there, and chunks
    removed because they were truncated, unreadable or another sweep's.
    """
    path = out / "manifest.json"
    old = None
    if path.exists():
        try:
            old = _read_manifest(out)[2]
        except SweepError as exc:
            if not overwrite:
                raise SweepError(exc.field, f"{exc.reason}; --overwrite replaces it with this sweep") from None
    if old is not None and old != ident and not overwrite:
        raise SweepError("out", f"{out} holds a different sweep; choose another folder or overwrite it")
    files = _chunk_files(out)
    if old != ident:
        for name in files:
            if name.startswith("chunk-"):
                (out / "chunks" / name).unlink(missing_ok=True)
        files = set()
    for name in files:
        if name.endswith(".tmp.npz"):
            (out / "chunks" / name).unlink(missing_ok=True)  # a killed writer's partial file
    tmp = path.with_suffix(".json.tmp")
    try:
        tmp.write_text(json.dumps(_manifest(spec, ident), indent=1, allow_nan=False) + "\n", encoding="utf-8")
        os.replace(tmp, path)
    except OSError as exc:
        raise SweepError(str(path), f"cannot write the manifest: {exc.strerror or exc}") from None
    done, discarded = [], []
    for i in range(spec.chunks):
        chunk = _chunk_path(out, i)
        if chunk.name not in files:
            continue
        try:
            _read_chunk(chunk, spec, ident, i)
            done.append(i)
        except SweepError:
            chunk.unlink(missing_ok=True)
            discarded.append(i)
    return done, discarded


def _refuse_singular_domain(scene: Scene) -> None:
    """Refuse a user curve with a singular point inside its declared domain.

    :func:`symvib.numeric.driver.simulate` narrows such a run's domain to the regular
    interval around ``initial.q`` (:func:`symvib.symbolic.singular.regular_shape`); a sweep
    runs one kernel module for all its rows, so it asks for that domain to be
    declared instead of integrating across the point.  A catalogue shape is
    regular on its domain.  Rows that vary the curve's parameters are not
    re-checked one by one; their energy budget is (``energy_budget_mismatch``).
    """
    if scene.shape.in_catalogue:
        return
    from symvib.symbolic.singular import regular_shape

    narrowed = regular_shape(scene)
    if narrowed is not scene.shape:
        lo, hi = narrowed.domain
        raise SceneError("curve.domain", f"curve '{scene.shape.name}' has a singular point inside its domain; "
                                         f"a sweep needs a regular one: declare domain = [\"{lo}\", \"{hi}\"] "
                                         f"(the regular interval around initial.q) or narrower")


def sweep(scene: Scene, vary: dict, *, random: int | None = None, seed: int = 0, chunk: int = DEFAULT_CHUNK,
          log_events: int = 0, nodes: int = DEFAULT_NODES, out=None, overwrite: bool = False, scheduler=None,
          progress: bool = False, backend: str = "auto") -> SweepResult:
    """Run ``scene`` for every combination (or random sample) of the ``vary`` fields.

    Parameters
    ----------
    scene : Scene
        Base scene.
    vary : dict
        Field key -> grid axis or random range (see :func:`make_spec`).
    random, seed, chunk, log_events, nodes
        See :func:`make_spec`.
    out : path, optional
        Folder for the manifest and chunk files; an existing sweep there is
        resumed (only missing chunks run; chunks that are truncated or carry
        another sweep's identity are computed again).  Without it the sweep
        stays in memory.  The folder is locked (:class:`WriterLock`) while the
        sweep writes it.
    overwrite : bool
        Replace a *different* sweep (or an unreadable manifest) found in ``out``
        instead of refusing.
    scheduler : str or dask.distributed.Client, optional
        Run the chunks on this Dask cluster (extra ``symvib[dask]``).
    progress : bool
        Draw a progress bar on stderr.
    backend : {"auto", "numba", "python"}

    Returns
    -------
    SweepResult

    Raises
    ------
    SceneError
        A bad definition (naming the field or option); :class:`SweepError` for
        an unusable folder, a folder another sweep writes, or a chunk that
        cannot be written.
    """
    _refuse_singular_domain(scene)
    spec = make_spec(scene, vary, random=random, seed=seed, chunk=chunk, log_events=log_events, nodes=nodes)
    definition = spec.to_dict()
    ident = sweep_id(definition)
    if out is None:
        return _run(spec, definition, ident, None, None, [], [], scheduler, progress, backend)
    out = _check_out(out)
    lock = WriterLock(out).acquire()
    try:
        done, discarded = _prepare(out, spec, ident, overwrite)
        return _run(spec, definition, ident, out, lock, done, discarded, scheduler, progress, backend)
    finally:
        lock.release()


def _run(spec, definition, ident, out, lock, done, discarded, scheduler, progress, backend) -> SweepResult:
    """Compute the chunks not in ``done``: into ``out`` (under ``lock``), or in memory."""
    finished = set(done)
    todo = [i for i in range(spec.chunks) if i not in finished]
    store: dict = {}
    bar = Progress(spec.count, enabled=progress,
                   initial=sum(len(spec.rows(i)[0]) for i in done) if done else 0)
    start = time.perf_counter()

    def take(index, columns):
        if out is not None:
            lock.verify()
            _write_chunk(out, index, columns, ident)
        else:
            store[index] = columns
        bar.update(len(columns["row"]))

    if scheduler is not None and todo:
        _run_dask(scheduler, definition, ident, todo, backend, take)
    else:
        for index in todo:
            take(index, run_chunk(definition, index, backend))
    bar.update(0, final=True)
    seconds = time.perf_counter() - start
    if out is not None:
        result = load_sweep(out)
        if sweep_id(result.spec.to_dict()) != ident:
            raise SweepError("out", f"{out} holds another sweep than the one just written")
        return SweepResult(result.spec, result.columns, tuple(todo), tuple(done), seconds, str(out),
                           tuple(discarded))
    return SweepResult(spec, _join(spec, [store[i] for i in range(spec.chunks)]), tuple(todo), (), seconds)


def _run_dask(scheduler, definition, ident, todo, backend, take) -> None:
    try:
        from dask.distributed import Client, as_completed
    except ImportError:
        raise SceneError("scheduler", "running on a Dask cluster needs dask.distributed: "
                                      "pip install 'symvib[dask]'") from None
    client = scheduler if isinstance(scheduler, Client) else Client(scheduler)
    try:
        token = ident[:12]
        workers = max(1, len(client.scheduler_info().get("workers", {})))
        pending = list(todo)
        running = as_completed()

        def submit():
            index = pending.pop(0)
            running.add(client.submit(run_chunk, definition, index, backend, key=f"symvib-sweep-{token}-{index}",
                                      pure=False))

        for _ in range(min(len(pending), DASK_INFLIGHT * workers)):
            submit()
        for future in running:
            index = int(future.key.rsplit("-", 1)[1])
            take(index, future.result())
            future.release()
            if pending:
                submit()
    finally:
        if client is not scheduler:
            client.close()


def _join(spec: SweepSpec, parts: list) -> dict:
    columns = {}
    for name in parts[0]:
        columns[name] = np.concatenate([p[name] for p in parts])
        columns[name].flags.writeable = False
    if not np.array_equal(columns["row"], np.arange(spec.count)):
        raise ValueError("sweep chunks do not cover the rows exactly once")
    return columns


def load_sweep(out) -> SweepResult:
    """Read a sweep folder (manifest and chunks) into a :class:`SweepResult`.

    Every chunk is checked against the manifest (:func:`_read_chunk`: the
    sweep's identity, column names, dtypes, shapes and rows).

    Raises
    ------
    SweepError
        One line naming the file: no or a bad manifest, missing chunks (the
        sweep is incomplete), a truncated chunk or one of another sweep.
    """
    out = Path(out)
    _, spec, ident = _read_manifest(out)
    files = _chunk_files(out)
    missing = [i for i in range(spec.chunks) if _chunk_path(out, i).name not in files]
    if missing:
        raise SweepError(str(out), f"sweep is incomplete: {len(missing)} of {spec.chunks} chunks missing "
                                   f"(first: {missing[0]}); run the same sweep again to resume")
    parts = [_read_chunk(_chunk_path(out, i), spec, ident, i) for i in range(spec.chunks)]
    return SweepResult(spec, _join(spec, parts), out=str(out))


# ----------------------------------------------------------------------------- command line

def _resolve_scene(text: str) -> Scene:
    path = Path(text)
    if path.exists() or text.endswith(".toml"):
        return load_scene(path)
    from importlib import resources

    packaged = resources.files("symvib") / "scenes" / f"{text}.toml"
    if not packaged.is_file():
        raise SceneError(text, "no such scene file (nor a packaged scene of that name)")
    with resources.as_file(packaged) as p:
        return load_scene(p)


def _sweep_file(path: Path) -> dict:
    """Read a sweep file as a scene file is read (:func:`symvib.paths.read_user_toml`:
    size cap, no device or folder, no TOML bomb), then check its keys."""
    from symvib.paths import read_user_toml

    data = read_user_toml(path, "sweep file")
    known = {"scene", "vary", "random", "seed", "chunk", "log_events", "nodes", "out"}
    for key in data:
        if key not in known:
            raise SceneError(f"{path.name}:{key}", f"unknown key; known: {', '.join(sorted(known))}")
    _check_sweep_file(data, path)
    if "scene" in data:
        scene = Path(data["scene"])
        data["scene"] = str(scene if scene.is_absolute() or not (path.parent / scene).exists()
                            else path.parent / scene)
    return data


#: Types of the keys of a sweep file (``vary`` is a table; integers are checked by :func:`make_spec`).
_SWEEP_FILE_TYPES = {"scene": str, "out": str, "vary": dict, "random": int, "seed": int, "chunk": int,
                     "log_events": int, "nodes": int}


def _check_sweep_file(data: dict, path: Path) -> None:
    """Refuse keys of the wrong type in a sweep file, naming the file and key."""
    for key, kind in _SWEEP_FILE_TYPES.items():
        if key in data and (not isinstance(data[key], kind) or isinstance(data[key], bool)):
            raise SceneError(f"{path.name}:{key}", f"must be {'a table' if kind is dict else kind.__name__}, "
                                                   f"got {type(data[key]).__name__}")
    for key in ("scene", "out"):
        if key in data and (not data[key] or "\0" in data[key]):
            raise SceneError(f"{path.name}:{key}", "must be a non-empty path")


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(
        prog="symvib sweep", description="Run a parameter sweep over scenes of one curve.",
        epilog="example: symvib sweep paper-parabola --vary qdot=3:12:200 --vary mu=0.01:0.2:100 -o OUT --plot")
    ap.add_argument("scene", nargs="?", help="scene TOML file (or a packaged scene name, e.g. paper-parabola)")
    ap.add_argument("--file", type=Path, help="sweep file (TOML: scene, [vary], random, seed, chunk, log_events, out)")
    ap.add_argument("--vary", action="append", default=[], metavar="KEY=SPEC",
                    help="start:stop:count (grid), a,b,c (values) or start:stop (with --random)")
    ap.add_argument("--random", type=int, metavar="N", help="N random samples instead of a grid")
    ap.add_argument("--seed", type=int)
    ap.add_argument("--chunk", type=int, help=f"scenes per chunk (default {DEFAULT_CHUNK})")
    ap.add_argument("--log-events", type=int, metavar="L", help="keep the first L events of every scene")
    ap.add_argument("--nodes", type=int, help="Gauss-Legendre nodes per quadrature panel (default 16)")
    ap.add_argument("-o", "--out", help="output folder (resumed if it holds the same sweep)")
    ap.add_argument("--overwrite", action="store_true", help="replace a different sweep in the output folder")
    ap.add_argument("--scheduler", metavar="ADDRESS", help="dask.distributed scheduler address (tcp://...)")
    ap.add_argument("--backend", default="auto", choices=("auto", "numba", "python"))
    ap.add_argument("--plot", action="store_true", help="write maps over the first two varied fields")
    ap.add_argument("--quiet", action="store_true", help="no progress bar")
    return ap


def main(argv=None) -> int:
    """``symvib sweep``: returns the exit status (2 on bad input)."""
    args = build_parser().parse_args(argv)
    try:
        return _main(args)
    except (SceneError, ValueError, OSError) as exc:
        print(f"symvib sweep: error: {exc}", file=sys.stderr)
        return 2


def _main(args) -> int:
    conf = _sweep_file(args.file) if args.file else {}
    scene_text = args.scene or conf.get("scene")
    if not scene_text:
        raise SceneError("scene", "give a scene file (or 'scene = ...' in the sweep file)")
    scene = _resolve_scene(str(scene_text))
    vary = dict(conf.get("vary", {}))
    for item in args.vary:
        if "=" not in item:
            raise SceneError("--vary", f"expected KEY=SPEC, got {item!r}")
        key, value = item.split("=", 1)
        vary[key.strip()] = value.strip()
    out = args.out or conf.get("out")
    if not out:
        raise SceneError("--out", "give an output folder (-o OUT)")

    def pick(name, default):
        value = getattr(args, name)
        return value if value is not None else conf.get(name, default)

    res = sweep(scene, vary, random=pick("random", None), seed=pick("seed", 0), chunk=pick("chunk", DEFAULT_CHUNK),
                log_events=pick("log_events", 0), nodes=pick("nodes", 16), out=out, overwrite=args.overwrite, scheduler=args.scheduler,
                progress=not args.quiet, backend=args.backend)
    names = res.status_names()
    status = ", ".join(f"{s}: {int(np.sum(names == s))}" for s in core.STATUS_NAMES if np.any(names == s))
    events = int(np.sum(res["events"]))
    print(f"sweep of {res.count} scenes of {scene.name} into {out}: {len(res.computed)} chunk(s) computed, "
          f"{len(res.reused)} reused" + (f" ({len(res.discarded)} found truncated or foreign)" if res.discarded else ""))
    print(f"  status: {status}; {events} events; {np.mean(res['impacts']):.3g} impacts per scene on average")
    if res.computed and res.seconds > 0:
        n = sum(len(res.spec.rows(i)[0]) for i in res.computed)
        print(f"  {n / res.seconds:,.0f} scenes/s over {res.seconds:.3g} s")
    if args.plot:
        from symvib.numeric.sweepmaps import sweep_maps

        for path in sweep_maps(res, Path(out) / "maps"):
            print(f"wrote {path}")
    failed = res.failed
    if failed.any():
        kinds = ", ".join(sorted(set(names[failed])))
        print(f"symvib sweep: error: {int(failed.sum())} of {res.count} scenes failed ({kinds}; first: row "
              f"{int(np.flatnonzero(failed)[0])}): their rows hold no result", file=sys.stderr)
        return EXIT_FAILED_SCENES
    return 0
