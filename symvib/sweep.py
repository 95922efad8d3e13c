"""Parameter sweeps: many scenes of one curve through the driver's core at once.

A sweep takes a base :class:`~symvib.scene.Scene` and varies some of its
fields, named with the scene file's own keys (``qdot``, ``q``, ``mu``,
``alpha0``, ``restitution``, ``g``, ``m``, ``left``, ``right``, ``t_max``,
``max_events``, a curve parameter such as ``p``, or the dotted form
``initial.qdot``, ``parameters.p``), over

* a grid: ``qdot=3:12:200`` (``start:stop:count``, ends included) or a list
  ``k=0.6,0.8,1``; the first axis varies slowest (C order), or
* random samples: ``--random N`` with ranges ``mu=0.01:0.2``, uniform, drawn
  from ``numpy.random.default_rng([seed, chunk])`` so a chunk's rows never
  depend on which process draws them.

Every scene runs the same compiled loop as :func:`symvib.driver.simulate`
(:func:`symvib.core.sweep`, parallel over scenes on the numba backend), so a
sweep's event sequences are the single-scene driver's.  Per scene it keeps the
columns :data:`symvib.core.SUMMARY` (status, event counts, final time and
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
>>> from symvib.scene import scene_from_dict
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
import sys
import time
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import core
from . import expr as _expr
from .scene import MAX_EVENTS, Scene, SceneError, load_scene, scene_from_dict

__all__ = ["SweepSpec", "SweepResult", "make_spec", "sweep", "load_sweep", "run_chunk", "main",
           "FORMAT", "DEFAULT_CHUNK"]

#: Identifier of the on-disk layout (manifest key ``format``).
FORMAT = "symvib-sweep/1"
#: Scenes per chunk: the unit of writing, resuming and distribution.
DEFAULT_CHUNK = 4096
#: Largest number of scenes a sweep may declare.
MAX_SCENES = 10**9
#: Seconds between progress-bar redraws.
PROGRESS_EVERY = 0.2
#: Chunks in flight per Dask worker.
DASK_INFLIGHT = 2

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


@dataclass(frozen=True)
class Axis:
    """One varied field: grid ``values``, or a random range ``[low, high]``."""

    key: str
    field: str
    values: tuple | None = None
    low: float | None = None
    high: float | None = None

    def to_dict(self) -> dict:
        return {"key": self.key, "field": self.field,
                **({"values": list(self.values)} if self.values is not None else {"low": self.low, "high": self.high})}


def _axis(scene: Scene, key: str, spec, random: bool) -> Axis:
    """An :class:`Axis` from ``"start:stop:count"``, ``"start:stop"``, ``"a,b,c"`` or a sequence."""
    fld = canonical_field(scene, key)
    label = f"vary.{key}"

    def num(text):
        if isinstance(text, (int, float)) and not isinstance(text, bool):
            if not math.isfinite(text):
                raise SceneError(label, f"must be finite, got {text}")
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
        start, stop = num(parts[0]), num(parts[1])
        values = np.linspace(start, stop, count) if count > 1 else np.array([start])
        return Axis(key, fld, values=tuple(float(v) for v in values))
    items = spec.split(",") if isinstance(spec, str) else list(np.atleast_1d(spec))
    if random:
        raise SceneError(label, "a random sweep takes a range start:stop, not a list of values")
    if not items or items == [""]:
        raise SceneError(label, "no values given")
    return Axis(key, fld, values=tuple(num(v) for v in items))


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
    nodes: int = 16

    @property
    def shape(self) -> tuple:
        """The grid's shape (one entry per axis); ``(count,)`` for random samples."""
        return tuple(len(a.values) for a in self.axes) if self.mode == "grid" else (self.count,)

    @property
    def chunks(self) -> int:
        return -(-self.count // self.chunk)

    def to_dict(self) -> dict:
        return {"scene": self.scene.to_dict(), "axes": [a.to_dict() for a in self.axes], "mode": self.mode,
                "count": self.count, "seed": self.seed, "chunk": self.chunk, "log_events": self.log_events,
                "nodes": self.nodes}

    @classmethod
    def from_dict(cls, data: dict) -> "SweepSpec":
        scene = scene_from_dict(data["scene"])
        axes = tuple(Axis(a["key"], a["field"], tuple(a["values"]) if "values" in a else None,
                          a.get("low"), a.get("high")) for a in data["axes"])
        return cls(scene, axes, data["mode"], int(data["count"]), int(data["seed"]), int(data["chunk"]),
                   int(data["log_events"]), int(data["nodes"]))

    def rows(self, index: int) -> tuple:
        """Row numbers and varied values (one array per axis) of chunk ``index``."""
        start = index * self.chunk
        stop = min(start + self.chunk, self.count)
        rows = np.arange(start, stop, dtype=np.int64)
        if self.mode == "grid":
            idx = np.unravel_index(rows, self.shape)
            return rows, [np.asarray(a.values)[i] for a, i in zip(self.axes, idx)]
        rng = np.random.default_rng([self.seed, index])
        u = rng.random((stop - start, len(self.axes)))
        return rows, [a.low + (a.high - a.low) * u[:, j] for j, a in enumerate(self.axes)]

    def scalars(self, values) -> tuple:
        """Rows of :data:`symvib.core.SCALARS` and of curve parameters for varied ``values``.

        Every row is validated as :class:`~symvib.scene.Scene` validates one
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
    """Vectorized :func:`symvib.scene._validate` over the rows of one chunk."""
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
    from .scene import _domain as scene_domain

    return scene_domain(scene.replace(params=dict(zip((n for n, _ in scene.params), (float(v) for v in values)))))


def make_spec(scene: Scene, vary: dict, *, random: int | None = None, seed: int = 0,
              chunk: int = DEFAULT_CHUNK, log_events: int = 0, nodes: int = 16) -> SweepSpec:
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
        Gauss-Legendre nodes per quadrature panel (as :func:`symvib.driver.simulate`).
    """
    if not isinstance(scene, Scene):
        raise SceneError("scene", f"must be a Scene, got {type(scene).__name__}")
    if not vary:
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
        count = math.prod(len(a.values) for a in axes)
    if count > MAX_SCENES:
        raise SceneError("vary", f"{count} scenes is more than a sweep may hold ({MAX_SCENES})")
    for label, value, least in (("chunk", chunk, 1), ("log_events", log_events, 0), ("seed", seed, 0),
                                ("nodes", nodes, 2)):
        if isinstance(value, bool) or not isinstance(value, int) or value < least:
            raise SceneError(label, f"must be an integer >= {least}, got {value!r}")
    spec = SweepSpec(scene, axes, "grid" if random is None else "random", count, seed, chunk, log_events, nodes)
    # Every corner of the box of varied values is a valid scene (the linear
    # constraints then hold inside it); each chunk is checked row by row too.
    corners = [(min(a.values), max(a.values)) if a.values is not None else (a.low, a.high) for a in axes]
    for corner in np.array(np.meshgrid(*corners, indexing="ij")).reshape(len(axes), -1).T:
        spec.scalars([np.array([v]) for v in corner])
    return spec


def run_chunk(definition: dict, index: int, backend: str = "auto") -> dict:
    """Compute chunk ``index`` of the sweep ``definition`` (:meth:`SweepSpec.to_dict`).

    A pure function of its arguments (it runs on Dask workers): returns the
    chunk's columns as a dict of arrays (``row``, the varied fields, the
    :data:`symvib.core.SUMMARY` columns, and ``event_log`` when asked).
    """
    spec = SweepSpec.from_dict(definition)
    rows, values = spec.rows(index)
    scal, cp = spec.scalars(values)
    fn = _sweep_function(spec.scene, backend)
    from .driver import _rule

    summary, logs = fn(scal, cp, _rule(spec.nodes), spec.log_events)
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


def _sweep_function(scene: Scene, backend: str):
    from . import driver
    from .kernels import load

    mod = load(scene.shape)
    return driver.guarded_sweep(driver.engine(mod.__file__, driver._resolve(backend))[2])


@dataclass(frozen=True)
class SweepResult:
    """A sweep's definition and its per-scene columns (row order), read-only.

    Attributes
    ----------
    spec : SweepSpec
    columns : dict of str -> ndarray
        ``row``, each varied field, the :data:`symvib.core.SUMMARY` columns,
        ``event_log`` (shape ``(count, log_events, 6)``: kind, t, q,
        qdot_before, qdot_after, energy) when events were logged.
    computed, reused : tuple of int
        Chunks computed by this call, and chunks found complete on disk.
    seconds : float
        Wall time of the computation.
    """

    spec: SweepSpec
    columns: dict
    computed: tuple = ()
    reused: tuple = ()
    seconds: float = 0.0
    out: str | None = field(default=None)

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


def _manifest(spec: SweepSpec) -> dict:
    from . import __version__

    return {"format": FORMAT, "definition": spec.to_dict(), "chunks": spec.chunks,
            "columns": ["row"] + [a.field for a in spec.axes] + list(core.SUMMARY)
            + (["event_log"] if spec.log_events else []),
            "status_names": list(core.STATUS_NAMES), "event_names": list(core.EVENT_NAMES),
            "event_log_columns": ["kind", "t", "q", "qdot_before", "qdot_after", "energy"],
            "symvib_version": __version__}


def _chunk_path(out: Path, index: int) -> Path:
    return out / "chunks" / f"chunk-{index:06d}.npz"


def _write_chunk(out: Path, index: int, columns: dict) -> None:
    path = _chunk_path(out, index)
    tmp = path.with_name(f"{path.stem}.{os.getpid()}.tmp.npz")
    np.savez(tmp, **columns)
    os.replace(tmp, path)


def _prepare(out: Path, spec: SweepSpec, overwrite: bool) -> list:
    """Create or reopen ``out``; the chunks already complete there."""
    manifest = _manifest(spec)
    path = out / "manifest.json"
    if path.exists():
        old = json.loads(path.read_text(encoding="utf-8"))
        if old.get("definition") != json.loads(json.dumps(manifest["definition"])) and not overwrite:
            raise SceneError("out", f"{out} holds a different sweep; choose another folder or overwrite it")
        if overwrite and old.get("definition") != json.loads(json.dumps(manifest["definition"])):
            for p in (out / "chunks").glob("chunk-*"):
                p.unlink()
    (out / "chunks").mkdir(parents=True, exist_ok=True)
    for stale in (out / "chunks").glob("*.tmp.npz"):
        stale.unlink()  # a killed writer's partial file
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(manifest, indent=1) + "\n", encoding="utf-8")
    os.replace(tmp, path)
    return [i for i in range(spec.chunks) if _chunk_path(out, i).exists()]


def sweep(scene: Scene, vary: dict, *, random: int | None = None, seed: int = 0, chunk: int = DEFAULT_CHUNK,
          log_events: int = 0, nodes: int = 16, out=None, overwrite: bool = False, scheduler=None,
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
        resumed (only missing chunks run).  Without it the sweep stays in memory.
    overwrite : bool
        Replace a *different* sweep found in ``out`` instead of refusing.
    scheduler : str or dask.distributed.Client, optional
        Run the chunks on this Dask cluster (extra ``symvib[dask]``).
    progress : bool
        Draw a progress bar on stderr.
    backend : {"auto", "numba", "python"}

    Returns
    -------
    SweepResult
    """
    spec = make_spec(scene, vary, random=random, seed=seed, chunk=chunk, log_events=log_events, nodes=nodes)
    definition = spec.to_dict()
    out = None if out is None else Path(out)
    done = _prepare(out, spec, overwrite) if out is not None else []
    todo = [i for i in range(spec.chunks) if i not in set(done)]
    store: dict = {}
    bar = Progress(spec.count, enabled=progress,
                   initial=sum(len(spec.rows(i)[0]) for i in done) if done else 0)
    start = time.perf_counter()

    def take(index, columns):
        if out is not None:
            _write_chunk(out, index, columns)
        else:
            store[index] = columns
        bar.update(len(columns["row"]))

    if scheduler is not None and todo:
        _run_dask(scheduler, definition, todo, backend, take)
    else:
        for index in todo:
            take(index, run_chunk(definition, index, backend))
    bar.update(0, final=True)
    seconds = time.perf_counter() - start
    if out is not None:
        result = load_sweep(out)
        return SweepResult(result.spec, result.columns, tuple(todo), tuple(done), seconds, str(out))
    return SweepResult(spec, _join(spec, [store[i] for i in range(spec.chunks)]), tuple(todo), (), seconds)


def _run_dask(scheduler, definition, todo, backend, take) -> None:
    try:
        from dask.distributed import Client, as_completed
    except ImportError:
        raise SceneError("scheduler", "running on a Dask cluster needs dask.distributed: "
                                      "pip install 'symvib[dask]'") from None
    client = scheduler if isinstance(scheduler, Client) else Client(scheduler)
    try:
        token = hashlib.sha256(json.dumps(definition, sort_keys=True).encode()).hexdigest()[:12]
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

    Raises ``ValueError`` naming the missing chunks if the sweep is incomplete.
    """
    out = Path(out)
    path = out / "manifest.json"
    if not path.exists():
        raise SceneError(str(out), "no sweep here (manifest.json missing)")
    manifest = json.loads(path.read_text(encoding="utf-8"))
    if manifest.get("format") != FORMAT:
        raise SceneError(str(path), f"unknown format {manifest.get('format')!r}; expected {FORMAT}")
    spec = SweepSpec.from_dict(manifest["definition"])
    missing = [i for i in range(spec.chunks) if not _chunk_path(out, i).exists()]
    if missing:
        raise ValueError(f"sweep in {out} is incomplete: {len(missing)} of {spec.chunks} chunks missing "
                         f"(first: {missing[0]}); run the same sweep again to resume")
    parts = []
    for i in range(spec.chunks):
        with np.load(_chunk_path(out, i)) as data:
            parts.append({name: data[name] for name in data.files})
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
    try:
        with path.open("rb") as fh:
            data = tomllib.load(fh)
    except FileNotFoundError:
        raise SceneError(str(path), "no such sweep file") from None
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(str(path), f"not valid TOML: {exc}") from None
    known = {"scene", "vary", "random", "seed", "chunk", "log_events", "nodes", "out"}
    for key in data:
        if key not in known:
            raise SceneError(f"{path.name}:{key}", f"unknown key; known: {', '.join(sorted(known))}")
    if "scene" in data:
        scene = Path(data["scene"])
        data["scene"] = str(scene if scene.is_absolute() or not (path.parent / scene).exists()
                            else path.parent / scene)
    return data


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
    except (SceneError, ValueError) as exc:
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
          f"{len(res.reused)} reused")
    print(f"  status: {status}; {events} events; {np.mean(res['impacts']):.3g} impacts per scene on average")
    failed = int(np.sum(np.isin(res["status"], core.ERROR_CODES)))
    if failed:
        print(f"  {failed} of {res.count} scenes failed (status "
              f"{' or '.join(core.STATUS_NAMES[c] for c in core.ERROR_CODES)}): their numbers are not results")
    if res.computed and res.seconds > 0:
        n = sum(len(res.spec.rows(i)[0]) for i in res.computed)
        print(f"  {n / res.seconds:,.0f} scenes/s over {res.seconds:.3g} s")
    if args.plot:
        from .sweepmaps import sweep_maps

        for path in sweep_maps(res, Path(out) / "maps"):
            print(f"wrote {path}")
    return 0
