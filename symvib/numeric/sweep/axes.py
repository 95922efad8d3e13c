"""The fields a sweep can vary and its axes: one varied field's values, from ``--vary`` text.

A field is named with the scene file's own keys (``qdot``, ``q``, ``mu``,
``alpha0``, ``mu_s``, ``alpha0_s``, ``restitution``, ``g``, ``m``, ``left``, ``right``, ``t_max``,
``max_events``, a curve parameter such as ``p``, or the dotted form
``initial.qdot``, ``parameters.p``); its values are a grid ``start:stop:count``
(ends included), a list ``a,b,c``, or a random range ``start:stop``
(:func:`parse_axis`).  An :class:`Axis` stores a grid as its three numbers and
computes values per chunk (:meth:`Axis.at`).

Examples
--------
>>> from symvib.numeric.scene import resolve_scene
>>> base = resolve_scene("paper-parabola")
>>> canonical_field(base, "qdot"), canonical_field(base, "p")
('initial.qdot', 'parameters.p')
>>> a = parse_axis(base, "qdot", "3:12:4", random=False)
>>> a.size, a.values
(4, (3.0, 6.0, 9.0, 12.0))
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from symvib import expr as _expr
from symvib.numeric.layout import SceneRow
from symvib.numeric.scene import Scene, SceneError
from symvib.numeric.sweep import limits
from symvib.numeric.sweep.limits import SweepError

__all__ = ["FIELDS", "Axis", "canonical_field", "parse_axis", "linspace_at"]

#: Scene fields a sweep can vary: canonical name -> its column of the scene row
#: (:class:`symvib.numeric.layout.SceneRow`; ``alpha0`` is stored as ``mu = tan(alpha0)``,
#: ``alpha0_s`` as ``mu_s``; a scene without ``mu_s`` has its rows' ``mu_s`` follow ``mu``).
FIELDS = {
    "initial.q": SceneRow.q0, "initial.qdot": SceneRow.qdot0, "physics.mu": SceneRow.mu,
    "physics.alpha0": SceneRow.mu, "physics.mu_s": SceneRow.mu_s, "physics.alpha0_s": SceneRow.mu_s,
    "physics.restitution": SceneRow.k, "physics.g": SceneRow.g,
    "physics.m": SceneRow.m, "limiters.left": SceneRow.left, "limiters.right": SceneRow.right,
    "run.t_max": SceneRow.t_max, "run.max_events": SceneRow.max_events,
}
#: Short names of the fields (as on the command line) -> canonical names.
_SHORT = {"q": "initial.q", "qdot": "initial.qdot", "q0": "initial.q", "qdot0": "initial.qdot",
          "mu": "physics.mu", "alpha0": "physics.alpha0", "mu_s": "physics.mu_s", "alpha0_s": "physics.alpha0_s",
          "restitution": "physics.restitution",
          "k": "physics.restitution", "g": "physics.g", "m": "physics.m", "left": "limiters.left",
          "right": "limiters.right", "t_max": "run.t_max", "max_events": "run.max_events"}


def canonical_field(scene: Scene, key: str) -> str:
    """The dotted scene-file name of a sweepable ``key`` (``"qdot"`` -> ``"initial.qdot"``).

    Curve parameters are ``parameters.NAME``; the coordinate's own name works
    for the initial state too (``phidot`` for ``qdot`` on the paper's curves).
    """
    key = key.strip()
    params = [n for n, _ in scene.params]
    if key in FIELDS or key.startswith("parameters.") and key.split(".", 1)[1] in params:
        return key
    if key in params:
        return f"parameters.{key}"
    q = scene.shape.q
    aliases = {q: "initial.q", f"{q}0": "initial.q", f"{q}dot": "initial.qdot", f"{q}dot0": "initial.qdot"}
    if key in _SHORT:
        return _SHORT[key]
    if key in aliases:
        return aliases[key]
    known = sorted(set(_SHORT) | set(params) | set(aliases))
    raise SceneError(f"vary.{key}", f"not a sweepable field of this scene; use one of {', '.join(known)} "
                                    f"(or a dotted scene-file name such as initial.qdot)")


def linspace_at(start: float, stop: float, count: int, index) -> np.ndarray:
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
        return linspace_at(self.start, self.stop, self.count, index)

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
    def from_dict(cls, data, label: str) -> Axis:
        """An axis from a manifest's definition (types and sizes checked; ``label`` names it)."""
        if not isinstance(data, dict) or not isinstance(data.get("key"), str) \
                or not isinstance(data.get("field"), str):
            raise SweepError(label, "must be a table with text 'key' and 'field'")
        kinds = [k for k in (("values",), ("start", "stop", "count"), ("low", "high")) if k[0] in data]
        if len(kinds) != 1 or set(data) != {"key", "field", *kinds[0]}:
            raise SweepError(label, "must hold values, or start, stop and count, or low and high")
        if "values" in data:
            items = data["values"]
            if not isinstance(items, list) or not 1 <= len(items) <= limits.MAX_LIST_VALUES:
                raise SweepError(f"{label}.values", f"must be a list of 1 to {limits.MAX_LIST_VALUES} numbers")
            return cls(data["key"], data["field"], items=tuple(_real(v, f"{label}.values") for v in items))
        if "count" in data:
            count = data["count"]
            if isinstance(count, bool) or not isinstance(count, int) or not 1 <= count <= limits.MAX_SCENES:
                raise SweepError(f"{label}.count", f"must be an integer in [1, {limits.MAX_SCENES}], got {count!r}")
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


def parse_axis(scene: Scene, key: str, spec, random: bool) -> Axis:
    """An :class:`Axis` from ``"start:stop:count"``, ``"start:stop"``, ``"a,b,c"`` or a sequence.

    Sizes are checked before anything of that size is built: a count beyond
    :data:`~symvib.numeric.sweep.limits.MAX_SCENES`, or more than
    :data:`~symvib.numeric.sweep.limits.MAX_LIST_VALUES` listed values, is refused.
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
        keys = set(map(str, spec))
        if not {"start", "stop"} <= keys <= {"start", "stop", "count"}:
            wrong = sorted(keys - {"start", "stop", "count"}) or sorted({"start", "stop"} - keys)
            raise SceneError(label, f"a table of start, stop (and count for a grid); {wrong[0]!r:.40} is "
                                    f"{'unknown' if wrong[0] in keys else 'missing'}")
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
        if count > limits.MAX_SCENES:
            raise SceneError(label, f"count {count} is more scenes than a sweep may hold ({limits.MAX_SCENES}, "
                                    f"symvib.numeric.sweep.limits.MAX_SCENES)")
        start, stop = num(parts[0]), num(parts[1])
        return Axis(key, fld, start=start, stop=stop, count=count)
    if random:
        raise SceneError(label, "a random sweep takes a range start:stop, not a list of values")
    if isinstance(spec, str):
        if spec.count(",") >= limits.MAX_LIST_VALUES:
            raise SceneError(label, f"more than {limits.MAX_LIST_VALUES} listed values "
                                    "(symvib.numeric.sweep.limits.MAX_LIST_VALUES); "
                                    f"use start:stop:count")
        items = spec.split(",")
    else:
        items = np.atleast_1d(spec)
        if items.ndim != 1 or items.size > limits.MAX_LIST_VALUES:
            raise SceneError(label, f"must be a flat list of at most {limits.MAX_LIST_VALUES} values "
                                    f"(symvib.numeric.sweep.limits.MAX_LIST_VALUES); use start:stop:count")
        items = list(items)
    if not len(items) or items == [""]:
        raise SceneError(label, "no values given")
    return Axis(key, fld, items=tuple(num(v) for v in items))


