"""The sweep definition: a base scene, the axes it varies, grid or random, chunking (validated).

:func:`make_spec` checks a definition given in Python values (the command
line, :mod:`symvib.cli.sweep`, passes its options here); :meth:`SweepSpec.from_dict`
checks one read from a manifest or received by a Dask worker; both refuse a
sweep beyond :mod:`symvib.numeric.sweep.limits` before anything of its size is
built.  :meth:`SweepSpec.rows` gives a chunk's row numbers and varied values.

Examples
--------
>>> from symvib.numeric.scene import resolve_scene
>>> spec = make_spec(resolve_scene("paper-parabola"), {"qdot": "3:12:4", "mu": [0.05, 0.1]}, chunk=3)
>>> spec.count, spec.shape, spec.chunks
(8, (4, 2), 3)
>>> rows, (qdot, mu) = spec.rows(1)
>>> rows.tolist(), qdot.tolist(), mu.tolist()
([3, 4, 5], [6.0, 9.0, 9.0], [0.1, 0.05, 0.1])
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from symvib.numeric.layout import SUMMARY_COLUMNS
from symvib.numeric.scene import Scene, SceneError, scene_from_dict
from symvib.numeric.sweep import limits
from symvib.numeric.sweep.axes import Axis, canonical_field, parse_axis
from symvib.numeric.sweep.flights import column_names as flight_columns
from symvib.numeric.sweep.limits import EVENT_WIDTH, ITEM, SweepError
from symvib.numeric.sweep.rows import scene_rows
from symvib.numeric.sweep.sensitivity_columns import check_wrt
from symvib.numeric.sweep.sensitivity_columns import column_names as sensitivity_columns

__all__ = ["SweepSpec", "make_spec", "check_sizes"]


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
    chunk: int = limits.DEFAULT_CHUNK
    log_events: int = 0
    nodes: int = limits.DEFAULT_NODES
    sensitivities: tuple = ()

    @property
    def shape(self) -> tuple:
        """The grid's shape (one entry per axis); ``(count,)`` for random samples."""
        return tuple(a.size for a in self.axes) if self.mode == "grid" else (self.count,)

    @property
    def chunks(self) -> int:
        return -(-self.count // self.chunk)

    def to_dict(self) -> dict:
        out = {"scene": self.scene.to_dict(), "axes": [a.to_dict() for a in self.axes], "mode": self.mode,
               "count": self.count, "seed": self.seed, "chunk": self.chunk, "log_events": self.log_events,
               "nodes": self.nodes}
        if self.sensitivities:     # (only then: a sweep without them keeps its identity)
            out["sensitivities"] = list(self.sensitivities)
        return out

    @classmethod
    def from_dict(cls, data: dict) -> SweepSpec:
        """The spec of a definition (:meth:`to_dict`), checked as :func:`make_spec` checks one.

        A definition comes from a manifest or a Dask task: every type and size
        is checked (:func:`check_sizes`) before anything is allocated.

        Raises
        ------
        SweepError
            Naming the key of the definition (``definition.axes[0].count``).
        """
        label = "definition"
        if not isinstance(data, dict):
            raise SweepError(label, f"must be a table, got {type(data).__name__}")
        keys = {"scene", "axes", "mode", "count", "seed", "chunk", "log_events", "nodes"}
        if set(data) - {"sensitivities"} != keys:
            wrong = sorted((set(data) - {"sensitivities"}) ^ keys)[0]
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
        wrt = data.get("sensitivities", [])
        if not isinstance(wrt, list) or not all(isinstance(p, str) for p in wrt):
            raise SweepError(f"{label}.sensitivities", f"must be a list of parameter names, got {wrt!r}")
        try:
            wrt = check_wrt(scene, wrt, axes)
        except SceneError as exc:
            raise SweepError(f"{label}.sensitivities", exc.reason) from None
        spec = cls(scene, axes, data["mode"], **ints, sensitivities=wrt)
        check_sizes(spec, prefix=f"{label}.")
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
        """Bytes of the columns of one full chunk (row, varied fields, summary, flights, sensitivities,
        event log)."""
        per_row = (1 + len(self.axes) + len(SUMMARY_COLUMNS) + len(flight_columns(self.scene))
                   + len(sensitivity_columns(self.sensitivities, self.scene)) + EVENT_WIDTH * self.log_events) * ITEM
        return min(self.chunk, self.count) * per_row

    def scalars(self, values, rows=None) -> tuple:
        """Scene rows (:class:`symvib.numeric.layout.SceneRow`) and curve-parameter rows for varied ``values``.

        Every row is checked as :class:`~symvib.numeric.scene.Scene` checks one
        scene (:func:`symvib.numeric.sweep.rows.scene_rows`); a bad row raises
        :class:`SceneError` naming the field and the row (its number in the sweep,
        from ``rows``, else its varied values).
        """
        return scene_rows(self.scene, self.axes, values, rows)


def make_spec(scene: Scene, vary: dict, *, random: int | None = None, seed: int = 0,
              chunk: int = limits.DEFAULT_CHUNK, log_events: int = 0, nodes: int = limits.DEFAULT_NODES,
              sensitivities=()) -> SweepSpec:
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
        in :data:`~symvib.numeric.sweep.limits.NODES_RANGE`.
    sensitivities : sequence of str or str
        Parameters (:data:`symvib.numeric.sensitivity.PARAMETERS`) whose derivatives of the final
        state to add as columns (:mod:`~symvib.numeric.sweep.sensitivity_columns`; a slower path).

    Raises
    ------
    SceneError
        Naming the field or option; sizes (:func:`check_sizes`) are checked
        before anything of that size is built.
    """
    if not isinstance(scene, Scene):
        raise SceneError("scene", f"must be a Scene, got {type(scene).__name__}")
    if not isinstance(vary, dict) or not vary:
        raise SceneError("vary", "nothing to vary: give at least one field, e.g. qdot=3:12:200")
    axes = tuple(parse_axis(scene, key, value, random is not None) for key, value in vary.items())
    fields = [a.field for a in axes]
    for fld in set(fields):
        if fields.count(fld) > 1:
            raise SceneError(f"vary.{fld}", "varied twice")
    if "physics.mu" in fields and "physics.alpha0" in fields:
        raise SceneError("vary", "vary mu or alpha0 (mu = tan(alpha0)), not both")
    if "physics.mu_s" in fields and "physics.alpha0_s" in fields:
        raise SceneError("vary", "vary mu_s or alpha0_s (mu_s = tan(alpha0_s)), not both")
    if random is not None:
        if isinstance(random, bool) or not isinstance(random, int) or random < 1:
            raise SceneError("random", f"number of samples must be a positive integer, got {random!r}")
        count = random
    else:
        count = math.prod(a.size for a in axes)   # Python integers: no overflow
    wrt = check_wrt(scene, sensitivities, axes)
    spec = SweepSpec(scene, axes, "grid" if random is None else "random", count, seed, chunk, log_events, nodes, wrt)
    check_sizes(spec)
    # Every corner of the box of varied values is a valid scene (the linear
    # constraints then hold inside it); each chunk is checked row by row too.
    if spec.mode == "grid":   # a corner is a grid point: an error names its row in the sweep
        for index in itertools.product(*[sorted({_end(a, min), _end(a, max)}) for a in axes]):
            row = np.ravel_multi_index(index, spec.shape)
            spec.scalars([a.at(np.array([i])) for a, i in zip(axes, index)], rows=np.array([row]))
        return spec
    corners = [a.bounds for a in axes]
    for corner in np.array(np.meshgrid(*corners, indexing="ij")).reshape(len(axes), -1).T:
        spec.scalars([np.array([v]) for v in corner])
    return spec


def _end(axis, which) -> int:
    """The grid position of an axis's smallest (``which=min``) or largest (``max``) value."""
    if axis.items is not None:
        return axis.items.index(which(axis.items))
    return 0 if which(axis.start, axis.stop) == axis.start else axis.count - 1


def check_sizes(spec: SweepSpec, prefix: str = "") -> None:
    """Refuse, before anything is allocated, a sweep beyond the module's bounds.

    Bounds: :data:`MAX_SCENES`, :data:`MAX_CHUNKS`, :data:`MAX_LOG_EVENTS`,
    :data:`MAX_CHUNK_BYTES`, :data:`MAX_EVENT_LOG_BYTES`, :data:`NODES_RANGE`
    (module constants: assign them to change a bound).  Errors name the option.
    """
    for label, value, least in (("chunk", spec.chunk, 1), ("log_events", spec.log_events, 0),
                                ("seed", spec.seed, 0), ("nodes", spec.nodes, limits.NODES_RANGE[0])):
        if isinstance(value, bool) or not isinstance(value, int) or value < least:
            raise SceneError(prefix + label, f"must be an integer >= {least}, got {value!r}")
    if spec.nodes > limits.NODES_RANGE[1]:
        lo, hi = limits.NODES_RANGE
        raise SceneError(prefix + "nodes", f"must be in [{lo}, {hi}], got {spec.nodes}")
    if isinstance(spec.count, bool) or not isinstance(spec.count, int) or spec.count < 1:
        raise SceneError(prefix + "count", f"must be a positive integer, got {spec.count!r}")
    if spec.mode == "grid" and spec.count != math.prod(a.size for a in spec.axes):
        raise SceneError(prefix + "count", f"{spec.count} is not the product of the axes' sizes")
    if spec.count > limits.MAX_SCENES:
        sizes = " x ".join(f"{a.key} {a.size}" for a in spec.axes) if spec.mode == "grid" else "--random"
        raise SceneError(prefix + ("vary" if spec.mode == "grid" else "random"),
                         f"{spec.count} scenes ({sizes}) is more than a sweep may hold ({limits.MAX_SCENES}, "
                         f"symvib.numeric.sweep.limits.MAX_SCENES)")
    if spec.chunks > limits.MAX_CHUNKS:
        raise SceneError(prefix + "chunk", f"{spec.chunk} scenes per chunk makes {spec.chunks} chunk files, more "
                                           f"than {limits.MAX_CHUNKS} (symvib.numeric.sweep.limits.MAX_CHUNKS): "
                                           "choose a larger --chunk")
    if spec.log_events > limits.MAX_LOG_EVENTS:
        raise SceneError(prefix + "log_events", f"{spec.log_events} events per scene is more than "
                                                f"{limits.MAX_LOG_EVENTS} (symvib.numeric.sweep.limits.MAX_LOG_EVENTS)")
    if spec.chunk_bytes() > limits.MAX_CHUNK_BYTES:
        raise SceneError(prefix + "chunk", f"a chunk of {min(spec.chunk, spec.count)} scenes with --log-events "
                                           f"{spec.log_events} takes {spec.chunk_bytes()} bytes, more than "
                                           f"{limits.MAX_CHUNK_BYTES} (symvib.numeric.sweep.limits.MAX_CHUNK_BYTES): "
                                           "choose a smaller "
                                           f"--chunk or --log-events")
    log_bytes = spec.count * spec.log_events * EVENT_WIDTH * ITEM
    if log_bytes > limits.MAX_EVENT_LOG_BYTES:
        raise SceneError(prefix + "log_events", f"{spec.count} scenes x {spec.log_events} logged events take "
                                                f"{log_bytes} bytes, more than {limits.MAX_EVENT_LOG_BYTES} "
                                                f"(symvib.numeric.sweep.limits.MAX_EVENT_LOG_BYTES): log fewer events")


