"""A sweep's result: its definition and one column per quantity, one row per scene.

:class:`SweepResult` is what :func:`symvib.numeric.sweep.runner.sweep` returns and
:func:`symvib.numeric.sweep.store.load_sweep` reads back: the row number, each
varied field, the summary columns (:data:`symvib.numeric.layout.SUMMARY_COLUMNS`)
and, when events were logged, ``event_log``; status and event codes are named
by :mod:`symvib.numeric.layout`.

Examples
--------
>>> from symvib.numeric.sweep import sweep
>>> from symvib.numeric.scene import resolve_scene
>>> res = sweep(resolve_scene("paper-parabola"), {"qdot": "3:12:3"}, log_events=2, backend="python")
>>> res.grid("impacts").shape, list(res.status_names()), bool(res.failed.any())
((3,), ['arrested', 'arrested', 'arrested'], False)
>>> res.events(0)[0][0]
'reversal'
>>> res.to_xarray()["impacts"].dims, res.to_dataframe().index.name
(('qdot0',), 'row')
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from symvib.numeric.layout import ERROR_CODES, EVENT_KINDS, STATUSES
from symvib.numeric.sweep.frames import dataframe, dataset
from symvib.numeric.sweep.schema import INTEGER_COLUMNS, impact_share, sweep_id

if TYPE_CHECKING:
    from symvib.numeric.sweep.spec import SweepSpec

__all__ = ["SweepResult", "INTEGER_COLUMNS", "join_chunks"]


@dataclass(frozen=True)
class SweepResult:
    """A sweep's definition and its per-scene columns (row order), read-only.

    Attributes
    ----------
    spec : SweepSpec
    columns : dict of str -> ndarray
        ``row``, each varied field, the :data:`symvib.numeric.layout.SUMMARY_COLUMNS`,
        ``flights``, ``landings`` and ``landing_loss`` for unilateral scenes
        (:mod:`~symvib.numeric.sweep.flights`),
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
        return np.asarray(STATUSES, dtype=object)[self.columns["status"]]

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
        return [(EVENT_KINDS[int(r[0])], *map(float, r[1:])) for r in self.columns["event_log"][row, :n]]

    @property
    def failed(self) -> np.ndarray:
        """Rows whose run failed (a status of :data:`symvib.numeric.layout.ERROR_CODES`: non-finite state, energy
        budget not closing): their numbers are not a result."""
        return np.isin(self.columns["status"], ERROR_CODES)

    @property
    def impact_share(self) -> np.ndarray:
        """Share of the energy lost to impacts, ``W_impacts / (W_friction + W_impacts)`` (NaN if none)."""
        return impact_share(self.columns["friction_work"], self.columns["impact_loss"])

    @property
    def sweep_id(self) -> str:
        """The sweep's identity (:func:`symvib.numeric.sweep.schema.sweep_id` of its definition)."""
        return sweep_id(self.spec.to_dict())

    def to_xarray(self):
        """The sweep as an ``xarray.Dataset`` (extra ``symvib[xarray]``).

        A grid sweep has one dimension and coordinate per varied field, named
        readably (``qdot0``, ``mu``; :mod:`symvib.numeric.sweep.labels`), so
        ``ds[name]`` equals :meth:`grid`; a random sweep has the dimension
        ``row`` and the varied fields as coordinates along it.  Data variables:
        the summary columns, the flight columns of a sweep of unilateral scenes
        (:mod:`~symvib.numeric.sweep.flights`), ``impact_share`` and ``event_log`` (if logged),
        each with ``units`` (SI), ``long_name`` and ``latex`` attributes; the
        Dataset's attributes hold ``sweep_id`` and the definition
        (:func:`symvib.numeric.sweep.frames.dataset`).
        """
        return dataset(self.spec, self.columns, self.sweep_id)

    def to_dataframe(self):
        """The sweep as a ``pandas.DataFrame``, one row per scene (index ``row``), columns named as in
        :meth:`to_xarray`, ``status`` a categorical of the status names (extra ``symvib[xarray]``)."""
        return dataframe(self.spec, self.columns, self.sweep_id)

    to_pandas = to_dataframe


def join_chunks(spec: SweepSpec, parts: list) -> dict:
    """The columns of a whole sweep from its chunks' (in row order; read-only arrays)."""
    columns = {}
    for name in parts[0]:
        columns[name] = np.concatenate([p[name] for p in parts])
        columns[name].flags.writeable = False
    if not np.array_equal(columns["row"], np.arange(spec.count)):
        raise ValueError("sweep chunks do not cover the rows exactly once")
    return columns
