"""A sweep's columns as labelled data: an xarray Dataset, a pandas DataFrame (extra ``symvib[xarray]``).

:func:`dataset` gives a grid sweep one dimension and coordinate per varied
field, named readably (``qdot0``, ``mu``, a curve parameter's name: see
:mod:`symvib.numeric.sweep.labels`), and a random sweep the dimension ``row``
with the varied fields as coordinates along it.  Every summary column
(:data:`symvib.numeric.layout.SUMMARY_COLUMNS`), the flight columns of a sweep of
unilateral scenes (:mod:`symvib.numeric.sweep.flights`), the sensitivity columns when
asked, the derived ``impact_share`` and, when events were logged, ``event_log`` are
data variables carrying ``units`` (SI), ``long_name`` and ``latex``; ``status`` holds the codes, named
by its ``flag_meanings`` (CF convention).  The Dataset's attributes name the
sweep (:func:`dataset_attrs`).  :func:`dataframe` is the same as one row per
scene, ``status`` as a categorical of the status names.

The columns may be NumPy arrays (:meth:`symvib.numeric.sweep.result.SweepResult.to_xarray`)
or Dask arrays (:func:`symvib.numeric.sweep.labelled.open_sweep`); the form
written to a Zarr store is :func:`dataset` with ``store=True``
(:mod:`symvib.numeric.sweep.zarrstore`).  xarray, pandas, zarr and dask are
the extra :data:`EXTRA`, imported by :func:`require` when first used.

Examples
--------
>>> from symvib.numeric.scene import resolve_scene
>>> from symvib.numeric.sweep import sweep
>>> res = sweep(resolve_scene("paper-parabola"), {"qdot": "3:12:4", "mu": "0.05,0.1"}, backend="python")
>>> ds = dataset(res.spec, res.columns, res.sweep_id)
>>> dict(ds.sizes), ds["mu"].attrs["long_name"], ds["impact_share"].attrs["units"]
({'qdot0': 4, 'mu': 2}, 'friction coefficient', '1')
>>> dict(dataset(res.spec, res.columns, res.sweep_id, store=True).sizes)   # the form written to Zarr
{'row': 8}
>>> dataframe(res.spec, res.columns, res.sweep_id)["status"].dtype.name
'category'
"""
from __future__ import annotations

import importlib
import json

import numpy as np

from symvib import __version__
from symvib.numeric.layout import EVENT_COLUMNS, STATUSES, SUMMARY_COLUMNS
from symvib.numeric.sweep.flights import column_names as flight_columns
from symvib.numeric.sweep.labels import COLUMN_LABELS, column_attrs, field_attrs
from symvib.numeric.sweep.limits import EVENT_WIDTH
from symvib.numeric.sweep.schema import FORMAT, impact_share, variable_names
from symvib.numeric.sweep.sensitivity_columns import column_attrs as sensitivity_attrs
from symvib.numeric.sweep.sensitivity_columns import column_names as sensitivity_columns

__all__ = ["EXTRA", "ROW_ATTRS", "require", "dataset", "dataframe", "dataset_attrs", "status_attrs",
           "event_log_attrs"]

#: The pyproject extra that installs xarray, pandas, zarr and dask.
EXTRA = "xarray"
#: Attributes of the row number (a random sweep's dimension).
ROW_ATTRS = {"long_name": "scene number (row of the sweep)", "units": "1"}


def require(module: str, what: str):
    """Import ``module`` or raise an ImportError naming the extra that installs it.

    The extra's packages are imported here, when first used, never at module level: a sweep
    runs, stores ``.npz`` chunks and loads them without them.
    """
    try:
        return importlib.import_module(module)
    except ImportError:
        raise ImportError(f"{what} needs {module.split('.')[0]}: pip install \"symvib[{EXTRA}]\"") from None


def dataset_attrs(spec, ident: str) -> dict:
    """The Dataset attributes naming the sweep: identity, definition (JSON), layout, curve."""
    return {"title": f"symvib sweep of {spec.scene.name}", "sweep_id": ident, "sweep_format": FORMAT,
            "mode": spec.mode, "count": spec.count, "chunk": spec.chunk, "seed": spec.seed,
            "nodes": spec.nodes, "log_events": spec.log_events, "curve": spec.scene.shape.name,
            "coordinate": spec.scene.shape.q, "definition": json.dumps(spec.to_dict(), sort_keys=True),
            "symvib_version": __version__}


def status_attrs(scene) -> dict:
    return column_attrs(scene, "status") | {"flag_values": list(range(len(STATUSES))),
                                            "flag_meanings": " ".join(STATUSES)}


def event_log_attrs() -> dict:
    return {"long_name": "the first logged events of each scene (kind code, t, q, qdot_before, qdot_after, "
                         "energy); rows past the scene's events are not events",
            "columns": " ".join(EVENT_COLUMNS), "units": "mixed: 1, s, {q}, {q}/s, {q}/s, J"}


def dataset(spec, columns: dict, ident: str, *, store: bool = False):
    """The labelled Dataset of a sweep's ``columns`` (NumPy or Dask arrays in row order).

    ``store`` is the form written to Zarr: a table (dimension ``row``) without the
    ``row`` index, the event column names or the derived ``impact_share``.
    """
    xr = require("xarray", "a labelled sweep")
    scene = spec.scene
    names = variable_names(spec)
    coords = {}
    if spec.mode == "grid" and not store:
        dims, shape = tuple(names[a.field] for a in spec.axes), spec.shape
        for a in spec.axes:
            coords[names[a.field]] = (names[a.field], a.at(np.arange(a.size)), field_attrs(scene, a.field))
    else:
        dims, shape = ("row",), (spec.count,)
        if not store:
            coords["row"] = ("row", columns["row"], ROW_ATTRS)
        for a in spec.axes:
            coords[names[a.field]] = ("row", columns[a.field], field_attrs(scene, a.field))
    data = {}
    for name in SUMMARY_COLUMNS:
        attrs = status_attrs(scene) if name == "status" else column_attrs(scene, name)
        data[name] = (dims, columns[name].reshape(shape), attrs)
    for name in flight_columns(scene):
        data[name] = (dims, columns[name].reshape(shape), column_attrs(scene, name))
    for name in sensitivity_columns(spec.sensitivities, scene):
        data[name] = (dims, columns[name].reshape(shape), sensitivity_attrs(scene, name, COLUMN_LABELS))
    if spec.log_events:
        log = columns["event_log"].reshape(shape + (spec.log_events, EVENT_WIDTH))
        attrs = event_log_attrs()
        attrs["units"] = attrs["units"].format(q=scene.shape.unit)
        data["event_log"] = (dims + ("event", "event_column"), log, attrs)
        if not store:
            coords["event_column"] = ("event_column", list(EVENT_COLUMNS))
    ds = xr.Dataset(data, coords, attrs=dataset_attrs(spec, ident))
    if not store:
        ds["impact_share"] = impact_share(ds["friction_work"], ds["impact_loss"])
        ds["impact_share"].attrs = column_attrs(scene, "impact_share")
    return ds


def dataframe(spec, columns: dict, ident: str):
    """One row per scene (index ``row``): the varied fields, the summary columns, ``impact_share``.

    Named as :func:`dataset` names them; ``status`` is a categorical of the
    status names; ``DataFrame.attrs`` holds ``sweep_id``, ``units`` and ``long_names``.
    """
    pd = require("pandas", "a sweep as a DataFrame")
    scene = spec.scene
    names = variable_names(spec)
    data, attrs = {}, {}
    for a in spec.axes:
        data[names[a.field]] = np.asarray(columns[a.field])
        attrs[names[a.field]] = field_attrs(scene, a.field)
    for name in SUMMARY_COLUMNS + tuple(flight_columns(scene)):
        data[name] = np.asarray(columns[name])
        attrs[name] = column_attrs(scene, name)
    for name in sensitivity_columns(spec.sensitivities, scene):
        data[name] = np.asarray(columns[name])
        attrs[name] = sensitivity_attrs(scene, name, COLUMN_LABELS)
    data["status"] = pd.Categorical.from_codes(data["status"], categories=list(STATUSES))
    data["impact_share"] = impact_share(data["friction_work"], data["impact_loss"])
    attrs["impact_share"] = column_attrs(scene, "impact_share")
    df = pd.DataFrame(data, index=pd.RangeIndex(spec.count, name="row"))
    df.attrs = {"sweep_id": ident, "units": {k: v["units"] for k, v in attrs.items()},
                "long_names": {k: v["long_name"] for k, v in attrs.items()}}
    return df
