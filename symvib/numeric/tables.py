"""A run's results as tables: pandas DataFrames of the events and the samples, and their units.

pandas is an optional dependency (``pip install "symvib[pandas]"``), imported
only when a table is asked for; everything else here is plain NumPy.  A result
is read by its attributes (``events``, ``samples``, ``scene``): this module
stands below :mod:`symvib.numeric.events`, whose ``Result`` methods
(``events_frame``, ``samples_frame``, ``to_pandas``, the units of ``to_dict``)
call it.

Columns and dtypes (``frame.attrs["units"]`` maps every column to its unit):

* :func:`events_frame`, one row per event (index ``event``, from 0): ``kind``
  (a pandas ``Categorical`` whose categories are every event kind's name, in
  the order of :class:`symvib.numeric.layout.EventCode`), ``t``, ``t_err`` (the
  estimated error of ``t``, s), ``q``, ``qdot_before``, ``qdot_after``, ``energy``
  (``float64``) and ``detail`` (``object``, text; empty for most events);
* :func:`samples_frame`, one row per sample (index ``sample``): every field of
  :class:`symvib.numeric.events.Samples`, in its order (``t``, ``q``, ``qdot``,
  ``F_N``, ``P_mu``, ``Ek``, ``Ep``, ``E``, ... as ``float64``; ``interval`` and
  ``branch`` as ``int64``); a field added to ``Samples`` becomes a column.

Units (SI) come from the scene's table :data:`symvib.numeric.scene.FIELD_UNITS`:
``q`` has the unit of the coordinate (``rad`` or ``m``), ``qdot`` that per second.

Examples
--------
>>> from symvib.shapes import shape
>>> units = quantity_units(shape("circle"))
>>> units["t"], units["q"], units["qdot"], units["E"], units["F_N"]
('s', 'rad', 'rad/s', 'J', 'N')
"""
from __future__ import annotations

import dataclasses

import numpy as np

from symvib.numeric.layout import EVENT_KINDS
from symvib.numeric.scene import DRAG_FIELDS, FIELD_UNITS, FLIGHT_FIELDS, STATIC_FRICTION_FIELDS, field_unit

__all__ = ["events_frame", "samples_frame", "to_pandas", "quantity_units", "result_units", "require_pandas",
           "QUANTITY_UNITS"]

#: Units of the quantities of a result (events, samples, final state, energy budget); ``"[q]"`` is
#: the coordinate's unit.  Time, position and velocity are the scene's own fields' units.
QUANTITY_UNITS = {
    "t": FIELD_UNITS["run.t_max"],
    "q": FIELD_UNITS["initial.q"],
    "qdot": FIELD_UNITS["initial.qdot"],
    "qdot_before": FIELD_UNITS["initial.qdot"],
    "qdot_after": FIELD_UNITS["initial.qdot"],
    "t_err": FIELD_UNITS["run.t_max"],
    "kind": None,
    "detail": None,
    "energy": "J",
    "x": "m",
    "z": "m",
    "s": "m",
    "path": "m",
    "v": "m/s",
    "F_N": "N",
    "F_mu": "N",
    "P_mu": "W",
    "W_mu": "J",
    "W_impacts": "J",
    "W_drag": "J",
    "W_landing": "J",
    "vx": "m/s",
    "vz": "m/s",
    "flight": "1",
    "Ek": "J",
    "Ep": "J",
    "E": "J",
    "interval": "1",
    "branch": "1",
}
#: Units of a result's energy budget (:class:`symvib.numeric.events.EnergyBudget`).
BUDGET_UNITS = {"initial": "J", "final": "J", "friction_work": "J", "impact_loss": "J", "residual": "J"}


def require_pandas():
    """The ``pandas`` module, or an ImportError that names the extra to install."""
    try:
        import pandas
    except ImportError:
        raise ImportError('results as DataFrames need pandas: pip install "symvib[pandas]" '
                          "(or pip install pandas)") from None
    return pandas


def quantity_units(shape) -> dict:
    """:data:`QUANTITY_UNITS` for a curve: ``"[q]"`` replaced by the coordinate's unit."""
    return {k: None if u is None else u.replace("[q]", shape.unit) for k, u in QUANTITY_UNITS.items()}


def result_units(result, *, samples: bool = False) -> dict:
    """The ``"units"`` entry of :meth:`symvib.numeric.events.Result.to_dict`: the unit of
    every number of the JSON, nested as the JSON is, and of every scene field (the static
    friction's only where the scene gives it: :data:`~symvib.numeric.scene.STATIC_FRICTION_FIELDS`; the
    drag's only where the scene has drag: :data:`~symvib.numeric.scene.DRAG_FIELDS`)."""
    shape = result.scene.shape
    units = quantity_units(shape)
    out = {"t_final": units["t"], "q_final": units["q"], "qdot_final": units["qdot"],
           "events": {k: units[k] for k in ("t", "t_err", "q", "qdot_before", "qdot_after", "energy")},
           "energy_budget": dict(BUDGET_UNITS)}
    if result.energy_budget.drag_work is not None:   # (a run with air drag: physics.md, "Air drag")
        out["energy_budget"]["drag_work"] = "J"
    if result.energy_budget.landing_loss is not None:
        out["energy_budget"]["landing_loss"] = "J"
    if samples and result.samples is not None:
        out["samples"] = {name: units.get(name) for name in _sample_fields(result.samples)}
    scene_units = {}
    for name in FIELD_UNITS:
        if name == "parameters.*":
            for p in shape.params:
                scene_units[f"parameters.{p}"] = field_unit(f"parameters.{p}", shape)
        elif name in STATIC_FRICTION_FIELDS and result.scene.mu_s is None:
            continue
        elif name in DRAG_FIELDS and not getattr(result.scene, "drag", 0.0):
            continue
        elif name in FLIGHT_FIELDS and result.scene.contact != "unilateral":
            continue
        elif not name.startswith("curve.") or not shape.in_catalogue:
            scene_units[name] = field_unit(name, shape)
    out["scene"] = scene_units
    return out


def _sample_fields(samples) -> list:
    return [f.name for f in dataclasses.fields(samples)]


#: Columns of :func:`events_frame`: the fields of an :class:`~symvib.numeric.events.Event` (checked
#: where it is defined), the estimated error of the time beside the time.
EVENT_FRAME_COLUMNS = ("kind", "t", "t_err", "q", "qdot_before", "qdot_after", "energy", "detail")


def events_frame(result):
    """The events of ``result`` as a DataFrame (columns in the module docstring)."""
    pd = require_pandas()
    events = result.events
    columns = {}
    for name in EVENT_FRAME_COLUMNS:
        values = [getattr(e, name) for e in events]
        if name == "kind":
            columns[name] = pd.Categorical([v.value for v in values], categories=list(EVENT_KINDS))
        elif name == "detail":
            columns[name] = pd.Series(values, dtype=object)
        else:
            columns[name] = np.asarray(values, dtype=np.float64)
    frame = pd.DataFrame(columns)
    frame.index.name = "event"
    units = quantity_units(result.scene.shape)
    frame.attrs["units"] = {k: units.get(k) for k in frame.columns}
    frame.attrs["scene"] = result.scene.name
    return frame


def samples_frame(result):
    """The samples of ``result`` as a DataFrame, one column per field of ``Samples``.

    Raises
    ------
    ValueError
        When the run kept no samples (``simulate(..., samples=False)``) or sampling failed.
    """
    pd = require_pandas()
    samples = result.require_samples()
    columns = {}
    for name in _sample_fields(samples):
        values = np.asarray(getattr(samples, name))
        kind = values.dtype.kind
        if kind in "iu":
            values = values.astype(np.int64)
        elif kind == "f":
            values = values.astype(np.float64)
        columns[name] = values
    frame = pd.DataFrame(columns)
    frame.index.name = "sample"
    units = quantity_units(result.scene.shape)
    frame.attrs["units"] = {k: units.get(k) for k in frame.columns}
    frame.attrs["scene"] = result.scene.name
    return frame


def to_pandas(result):
    """``(events_frame(result), samples_frame(result))``."""
    return events_frame(result), samples_frame(result)
