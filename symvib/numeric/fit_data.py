"""Observations a fit reads: event times, or positions sampled along the trajectory, checked.

Two kinds of data, each an immutable record whose constructor checks it:

* :class:`Observed` (:func:`observed_events`): event times, ascending, with optional kinds and
  positions (a microphone, an accelerometer);
* :class:`ObservedSamples` (:func:`observed_samples`): the position at sample times (video
  tracking), as the coordinate ``q``, the point ``x, z`` or the arc length ``s`` from the initial
  position (:data:`symvib.numeric.sample_sensitivity.COORDINATES`).

A CSV file is read as text with :mod:`csv` (nothing is evaluated), its kind told by its
columns (:func:`read_observations`): ``t`` with ``q``, ``x, z`` or ``s`` and no ``kind`` is a
sampled trajectory; ``t`` with an optional ``kind`` (and then optional ``q``) are events.
Errors name the file and the row, or the field.

Examples
--------
>>> obs = observed_samples([0.1, 0.2, 0.3], x=[0.5, 0.6, 0.7], z=[0.1, 0.2, 0.2])
>>> obs.coordinates, obs.values.shape, obs.count
('xz', (3, 2), 6)
>>> observed_samples([0.2, 0.1], q=[0.0, 0.1])
Traceback (most recent call last):
...
ValueError: observed.t: the times must be ascending (time 2, 0.1, comes before time 1, 0.2)
"""
from __future__ import annotations

import csv
from dataclasses import dataclass

import numpy as np

from symvib.numeric.events import EventKind

__all__ = ["Observed", "ObservedSamples", "observed_events", "observed_samples", "read_events", "read_samples",
           "read_observations", "CSV_COLUMNS", "SAMPLE_COLUMNS"]

#: Columns a file of observed events may have.
CSV_COLUMNS = ("t", "kind", "q")
#: Column sets of a file of samples (besides ``t``) -> the coordinates they give.
SAMPLE_COLUMNS = {("q",): "q", ("x", "z"): "xz", ("s",): "s"}
#: Most columns a data file has (``t, kind, q`` or ``t, x, z``).
MAX_COLUMNS = 3


@dataclass(frozen=True)
class Observed:
    """Observed events: times (ascending), optional kinds and positions."""

    t: np.ndarray
    kinds: tuple | None = None
    q: np.ndarray | None = None

    @property
    def count(self) -> int:
        """Number of observations (times, and positions when given)."""
        return len(self.t) * (1 if self.q is None else 2)

    def head(self, n: int) -> Observed:
        """The first ``n`` events."""
        return Observed(self.t[:n], self.kinds[:n] if self.kinds else None, self.q[:n] if self.q is not None else None)


@dataclass(frozen=True)
class ObservedSamples:
    """Observed positions at sample times (ascending, from 0).

    Attributes
    ----------
    t : ndarray, shape (n,)
    coordinates : str
        ``"q"``, ``"xz"`` or ``"s"``.
    values : ndarray, shape (n, 1) or (n, 2)
        One column per coordinate (``x`` then ``z``).
    """

    t: np.ndarray
    coordinates: str
    values: np.ndarray

    @property
    def count(self) -> int:
        """Number of observations: one per sample and coordinate."""
        return self.values.size

    def head(self, n: int) -> ObservedSamples:
        """The first ``n`` samples."""
        return ObservedSamples(self.t[:n], self.coordinates, self.values[:n])


def _show(value, limit: int = 80) -> str:
    """``repr(value)``, cut to about ``limit`` characters (a cell or a header of a hostile file may be long)."""
    text = repr(value)
    return text if len(text) <= limit else text[:limit] + "..."


def _floats(values, name: str) -> np.ndarray:
    """``values`` as a flat float array, or an error naming ``observed.<name>``."""
    try:
        return np.asarray(values, dtype=float).ravel()
    except (TypeError, ValueError):
        raise ValueError(f"observed.{name}: give numbers (a sequence of floats), got {values!r:.80}") from None


def _check_times(t, what: str) -> np.ndarray:
    t = _floats(t, "t")
    if not len(t):
        raise ValueError(f"observed.t: no {what}")
    if not np.all(np.isfinite(t)):
        raise ValueError(f"observed.t: time {int(np.flatnonzero(~np.isfinite(t))[0]) + 1} is not a finite number")
    if np.any(np.diff(t) < 0):
        bad = int(np.flatnonzero(np.diff(t) < 0)[0])
        raise ValueError(f"observed.t: the times must be ascending (time {bad + 2}, {float(t[bad + 1])!r}, "
                         f"comes before time {bad + 1}, {float(t[bad])!r})")
    return t


def observed_events(t, kinds=None, q=None) -> Observed:
    """Check and hold observed events.

    Raises
    ------
    ValueError
        Naming ``observed.t`` (not finite, not ascending, empty), ``observed.kind`` (not an
        event kind), ``observed.q`` (not finite, or not one per time).
    """
    t = _check_times(t, "event times")
    if kinds is not None:
        if isinstance(kinds, str):
            raise ValueError(f"observed.kind: one kind per time (a list such as [{kinds!r:.40}]), not a string")
        kinds = tuple(str(k).strip().lower() for k in kinds)
        valid = {k.value for k in EventKind}
        for i, k in enumerate(kinds):
            if k not in valid:
                raise ValueError(f"observed.kind: event {i + 1} is {_show(k)}, not one of {', '.join(sorted(valid))}")
        if len(kinds) != len(t):
            raise ValueError(f"observed.kind: {len(kinds)} kinds for {len(t)} times")
    if q is not None:
        q = _floats(q, "q")
        if len(q) != len(t) or not np.all(np.isfinite(q)):
            raise ValueError("observed.q: one finite position per time")
    return Observed(t, kinds, q)


def observed_samples(t, *, q=None, x=None, z=None, s=None) -> ObservedSamples:
    """Check and hold a sampled trajectory: times with ``q``, or ``x`` and ``z``, or ``s``.

    Raises
    ------
    ValueError
        Naming ``observed.t`` (not finite, not ascending, negative, empty) or the coordinate
        (missing, not finite, not one per time, or two kinds given).
    """
    t = _check_times(t, "sample times")
    if t[0] < 0:
        raise ValueError(f"observed.t: sample 1 is at {float(t[0])!r} s, before the run starts (t = 0)")
    given = tuple(name for name, v in (("q", q), ("x", x), ("z", z), ("s", s)) if v is not None)
    if given not in SAMPLE_COLUMNS:
        raise ValueError(f"observed: give q, or x and z, or s with the times (got {', '.join(given) or 'none'})")
    values = []
    for name, v in (("q", q), ("x", x), ("z", z), ("s", s)):
        if v is None:
            continue
        v = _floats(v, name)
        if len(v) != len(t):
            raise ValueError(f"observed.{name}: {len(v)} values for {len(t)} times")
        if not np.all(np.isfinite(v)):
            raise ValueError(f"observed.{name}: sample {int(np.flatnonzero(~np.isfinite(v))[0]) + 1} is not a "
                             "finite number")
        values.append(v)
    return ObservedSamples(t, SAMPLE_COLUMNS[given], np.stack(values, axis=1))


def _read_columns(path, what: str) -> tuple:
    """The header (lower case) and the columns of a CSV file, numbers as floats (``kind`` as text)."""
    from symvib.paths import read_user_file

    text = read_user_file(path, what=what).removeprefix("\ufeff")   # a byte-order mark (spreadsheet export)
    reader = csv.reader(text.splitlines(), strict=True)
    try:
        rows = list(reader)
    except csv.Error as exc:     # a stray or unclosed quote, a cell beyond the module's field limit
        raise ValueError(f"{path}: row {reader.line_num}: not comma-separated values ({exc})") from None
    if not rows:
        raise ValueError(f"{path}: empty; give a header row (events: t[, kind][, q]; samples: t with q, x,z or s)")
    header = [h.strip().lower() for h in rows[0]]
    if len(header) > MAX_COLUMNS:     # (before any work per column: a header of 100,000 names)
        raise ValueError(f"{path}: header {_show(rows[0])} has {len(header)} columns; a data file has at most "
                         f"{MAX_COLUMNS} (events: t, kind, q; samples: t with q, x and z, or s)")
    twice = sorted({h for h in header if header.count(h) > 1})
    if twice:
        raise ValueError(f"{path}: header {_show(rows[0])} names column {_show(twice[0])} twice")
    if len(header) == 1 and any(sep in header[0] for sep in ";\t"):
        raise ValueError(f"{path}: header {_show(rows[0])}: separate the columns by commas, not semicolons or tabs")
    if "" in header:
        raise ValueError(f"{path}: header {_show(rows[0])}: column {header.index('') + 1} has no name")
    columns = {h: [] for h in header}
    for number, row in enumerate(rows[1:], start=2):
        if not any(cell.strip() for cell in row):
            continue
        if len(row) != len(header):
            raise ValueError(f"{path}: row {number} has {len(row)} cells for {len(header)} columns")
        for h, cell in zip(header, row):
            if h == "kind":
                columns[h].append(cell)
                continue
            try:
                if not cell.isascii() or "_" in cell:     # float() reads "1_0" as 10 and other scripts' digits
                    raise ValueError
                value = float(cell)
            except ValueError:
                raise ValueError(f"{path}: row {number}, column {h}: {_show(cell)} is not a number") from None
            if not np.isfinite(value):
                raise ValueError(f"{path}: row {number}, column {h}: {_show(cell.strip())} is not a finite number")
            columns[h].append(value)
    return rows[0], header, columns


def read_events(path) -> Observed:
    """Observed events from a CSV file with a header: ``t`` (s), optional ``kind`` and ``q``."""
    return _events(path, *_read_columns(path, "events file"))


def read_samples(path) -> ObservedSamples:
    """A sampled trajectory from a CSV file with a header: ``t`` (s) and ``q``, or ``x, z`` (m), or ``s`` (m)."""
    return _samples(path, *_read_columns(path, "samples file"))


def read_observations(path):
    """Events or samples from a CSV file (read once), told by its columns: ``t`` with ``q``, ``x, z`` or
    ``s`` and no ``kind`` is a sampled trajectory (:func:`read_samples`), else events (:func:`read_events`)."""
    raw, header, columns = _read_columns(path, "data file")
    rest = tuple(sorted(h for h in header if h != "t"))
    return (_samples if rest in SAMPLE_COLUMNS else _events)(path, raw, header, columns)


def _events(path, raw, header, columns) -> Observed:
    unknown = [h for h in header if h not in CSV_COLUMNS]
    if "t" not in header or unknown:
        raise ValueError(f"{path}: header {_show(raw)}: needs a column t and only {', '.join(CSV_COLUMNS)} (events), "
                         "or t with q, x and z, or s (a sampled trajectory)")
    try:
        return observed_events(columns["t"], columns.get("kind"), columns.get("q"))
    except ValueError as exc:
        raise ValueError(f"{path}: {exc} (data rows counted from 1 after the header)") from None


def _samples(path, raw, header, columns) -> ObservedSamples:
    rest = tuple(sorted(h for h in header if h != "t"))
    if "t" not in header or rest not in SAMPLE_COLUMNS:
        raise ValueError(f"{path}: header {_show(raw)}: a sampled trajectory needs t and q, or t, x, z, or t, s")
    try:
        return observed_samples(columns["t"], **{h: columns[h] for h in rest})
    except ValueError as exc:
        raise ValueError(f"{path}: {exc} (data rows counted from 1 after the header)") from None
