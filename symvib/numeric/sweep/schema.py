"""A sweep's columns: their names and kinds, the layout's identity, and the check of a chunk's rows.

What every module that holds a sweep's columns shares, and the bottom of them:
the result (:mod:`~symvib.numeric.sweep.result`), the chunk files
(:mod:`~symvib.numeric.sweep.store`), the Zarr store
(:mod:`~symvib.numeric.sweep.zarrstore`) and the labelled data
(:mod:`~symvib.numeric.sweep.frames`, :mod:`~symvib.numeric.sweep.labelled`)
import it, and it imports none of them, nor the definition: a ``spec`` here is
any :class:`~symvib.numeric.sweep.spec.SweepSpec`, read by its ``axes``,
``log_events``, ``scene`` and ``rows``.

* The columns (:func:`column_names`), one row per scene: ``row`` (the scene's
  number in the sweep), each varied field by its dotted name (``initial.qdot``),
  the summary columns :data:`symvib.numeric.layout.SUMMARY_COLUMNS`, the flight
  columns of a sweep of unilateral scenes (:data:`symvib.numeric.sweep.flights.COLUMNS`)
  and, when events are logged, ``event_log``.  As labelled data and in a Zarr store a
  varied field is named readably (:func:`variable_names`: ``qdot0``).
* Their kinds: ``row`` and :data:`INTEGER_COLUMNS` (codes and counts) are
  ``int64``, the others ``float64`` (:func:`column_dtype`); ``event_log`` holds
  ``log_events`` events of :data:`~symvib.numeric.sweep.limits.EVENT_WIDTH`
  values per row, the others one value (:func:`column_tail`).
* The derived column ``impact_share`` (:func:`impact_share`).
* The layout :data:`FORMAT` and a sweep's identity :func:`sweep_id`, written in
  the manifest, in every chunk and in a Zarr store.
* :func:`check_rows`: a chunk read back holds the rows of its number, with
  status codes in range (:func:`bad_chunk` is the refusal).

Examples
--------
>>> from symvib.numeric.scene import resolve_scene
>>> from symvib.numeric.sweep.spec import make_spec
>>> spec = make_spec(resolve_scene("paper-parabola"), {"qdot": "3:12:3"}, log_events=2)
>>> column_names(spec)[:3], column_names(spec)[-1], variable_names(spec)["initial.qdot"]
(['row', 'initial.qdot', 'status'], 'event_log', 'qdot0')
>>> column_dtype("impacts"), column_dtype("t_final"), column_tail(spec, "event_log")
(dtype('int64'), dtype('float64'), (2, 7))
>>> len(sweep_id(spec.to_dict())) == ID_DIGITS
True
"""
from __future__ import annotations

import hashlib
import json

import numpy as np

from symvib.numeric.layout import STATUSES, SUMMARY_COLUMNS, Summary
from symvib.numeric.sweep import flights
from symvib.numeric.sweep.labels import axis_name
from symvib.numeric.sweep.limits import EVENT_WIDTH, SweepError
from symvib.numeric.sweep.sensitivity_columns import REASON_COLUMN
from symvib.numeric.sweep.sensitivity_columns import column_names as sensitivity_columns

__all__ = ["FORMAT", "OLD_FORMATS", "ID_DIGITS", "INTEGER_COLUMNS", "sweep_id", "column_names", "column_dtype",
           "column_tail", "variable_names", "impact_share", "bad_chunk", "check_rows"]

#: Identifier of the on-disk layout (manifest key ``format``).  Version 2 added the
#: sweep identity (``sweep_id``) to the manifest and to every chunk.
FORMAT = "symvib-sweep/2"
#: Layouts this version recognizes but does not read (their chunks carry no sweep identity).
OLD_FORMATS = ("symvib-sweep/1",)
#: Hex digits of the sweep identity (a SHA-256 of the format and definition).
ID_DIGITS = 32
#: Summary columns stored as integers (codes and counts); the others are float64.
INTEGER_COLUMNS = tuple(SUMMARY_COLUMNS[c] for c in (Summary.status, Summary.events, Summary.impacts,
                                                      Summary.reversals, Summary.normal_sign_changes))


def sweep_id(definition: dict) -> str:
    """The identity of a sweep: a hash of the layout :data:`FORMAT` and its definition.

    Written in the manifest and in every chunk; a chunk is used only by the
    sweep of the same identity (the definition's canonical JSON, so a
    definition read back from a manifest has the identity it was written with).
    """
    text = json.dumps({"format": FORMAT, "definition": definition}, sort_keys=True, separators=(",", ":"),
                      allow_nan=False)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:ID_DIGITS]


def column_names(spec) -> list:
    """The sweep's columns in their order: ``row``, the varied fields, the summary columns, the flight
    columns (a unilateral scene's: :mod:`~symvib.numeric.sweep.flights`), the sensitivity columns (when
    asked: :mod:`~symvib.numeric.sweep.sensitivity_columns`), ``event_log``."""
    return (["row"] + [a.field for a in spec.axes] + list(SUMMARY_COLUMNS) + flights.column_names(spec.scene)
            + sensitivity_columns(getattr(spec, "sensitivities", ()), spec.scene)
            + (["event_log"] if spec.log_events else []))


def column_dtype(name: str) -> np.dtype:
    """The dtype of column ``name``: ``int64`` for ``row``, :data:`INTEGER_COLUMNS` and the counts of
    flights and landings, else ``float64``."""
    integer = name in ("row", REASON_COLUMN) or name in INTEGER_COLUMNS or name in flights.INTEGER_COLUMNS
    return np.dtype(np.int64 if integer else np.float64)


def column_tail(spec, name: str) -> tuple:
    """The shape of one row of column ``name``: ``(log_events, EVENT_WIDTH)`` for ``event_log``, else ``()``."""
    return (spec.log_events, EVENT_WIDTH) if name == "event_log" else ()


def variable_names(spec) -> dict:
    """Column name (``initial.qdot``, ``impacts``, ...) -> variable name (``qdot0``, ``impacts``, ...)."""
    axes = {a.field for a in spec.axes}
    return {c: axis_name(spec.scene, c) if c in axes else c for c in column_names(spec)}


def impact_share(friction_work, impact_loss):
    """``W_impacts / (W_friction + W_impacts)``, NaN where nothing was lost (NumPy or xarray operands)."""
    total = friction_work + impact_loss
    if isinstance(total, np.ndarray):
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(total > 0, impact_loss / total, np.nan)
    return (impact_loss / total).where(total > 0)


def bad_chunk(where, reason: str) -> SweepError:
    """The refusal of a chunk (``where`` names its file): ``reason``, and how to recompute it."""
    return SweepError(str(where), f"{reason}; run the same sweep again to recompute it")


def check_rows(where, spec, index: int, columns: dict) -> None:
    """Refuse (naming ``where``) a chunk whose rows or varied values are not chunk ``index``'s, or whose
    status codes are out of range."""
    rows, values = spec.rows(index)
    if not np.array_equal(columns["row"], rows) or not all(
            np.array_equal(columns[a.field], v) for a, v in zip(spec.axes, values)):
        raise bad_chunk(where, f"rows or varied values are not those of chunk {index}")
    status = columns["status"]
    if status.size and (status.min() < 0 or status.max() >= len(STATUSES)):
        raise bad_chunk(where, "status codes out of range")
