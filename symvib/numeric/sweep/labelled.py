"""A sweep as labelled data: an xarray Dataset, a pandas DataFrame, a folder opened lazily.

:func:`to_xarray` gives a grid sweep one dimension and coordinate per varied
field, named readably (``qdot0``, ``mu``, a curve parameter's name: see
:mod:`symvib.numeric.sweep.labels`), and a random sweep the dimension ``row``
with the varied fields as coordinates along it.  Every summary column
(:data:`symvib.numeric.layout.SUMMARY_COLUMNS`), the derived ``impact_share``
and, when events were logged, ``event_log`` are data variables carrying
``units`` (SI), ``long_name`` and ``latex``; ``status`` holds the codes, named
by its ``flag_meanings`` (CF convention).  The Dataset's attributes name the
sweep: ``sweep_id`` (the identity of :func:`symvib.numeric.sweep.store.sweep_id`),
its definition (JSON) and layout.  :func:`to_dataframe` is the same as one
row per scene, ``status`` as a categorical of the status names.

:func:`open_sweep` opens a sweep folder (either storage) as one Dask-backed
Dataset without reading its chunks: each chunk is read, and checked as
:func:`~symvib.numeric.sweep.store.load_sweep` checks it, when a computation
first needs it.

xarray, pandas, zarr and dask are the extra ``symvib[xarray]``, imported
when first used.

Examples
--------
>>> from symvib.numeric.scene import resolve_scene
>>> from symvib.numeric.sweep import sweep
>>> res = sweep(resolve_scene("paper-parabola"), {"qdot": "3:12:4", "mu": "0.05,0.1"}, backend="python")
>>> ds = res.to_xarray()
>>> dict(ds.sizes), ds["qdot0"].attrs["units"], ds["impacts"].shape
({'qdot0': 4, 'mu': 2}, 'rad/s', (4, 2))
>>> ds.attrs["sweep_id"] == res.sweep_id
True
>>> list(res.to_dataframe().columns[:4])
['qdot0', 'mu', 'status', 'events']
"""
from __future__ import annotations

import importlib
import json
from pathlib import Path

import numpy as np

from symvib import __version__
from symvib.numeric.layout import EVENT_COLUMNS, STATUSES, SUMMARY_COLUMNS
from symvib.numeric.sweep.labels import column_attrs, field_attrs
from symvib.numeric.sweep.limits import EVENT_WIDTH
from symvib.numeric.sweep.schema import FORMAT, column_dtype, column_tail, impact_share, variable_names

__all__ = ["EXTRA", "require", "variable_names", "dataset", "dataframe", "dataset_attrs", "open_sweep",
           "impact_share"]

#: The pyproject extra that installs xarray, pandas, zarr and dask.
EXTRA = "xarray"
#: Attributes of the row number (a random sweep's dimension).
ROW_ATTRS = {"long_name": "scene number (row of the sweep)", "units": "1"}


def require(module: str, what: str):
    """Import ``module`` or raise an ImportError naming the extra that installs it."""
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
    for name in SUMMARY_COLUMNS:
        data[name] = np.asarray(columns[name])
        attrs[name] = column_attrs(scene, name)
    data["status"] = pd.Categorical.from_codes(data["status"], categories=list(STATUSES))
    data["impact_share"] = impact_share(data["friction_work"], data["impact_loss"])
    attrs["impact_share"] = column_attrs(scene, "impact_share")
    df = pd.DataFrame(data, index=pd.RangeIndex(spec.count, name="row"))
    df.attrs = {"sweep_id": ident, "units": {k: v["units"] for k, v in attrs.items()},
                "long_names": {k: v["long_name"] for k, v in attrs.items()}}
    return df


class _ChunkReader:
    """Reads chunk ``index`` of a sweep folder, checked (the task of one block of :func:`open_sweep`)."""

    def __init__(self, out, manifest, spec, ident):
        self.out, self.manifest, self.spec, self.ident = out, manifest, spec, ident
        self.read = None

    def __call__(self, index: int) -> dict:
        from symvib.numeric.sweep.store import reader

        if self.read is None:    # opened once per process (a Zarr store's metadata)
            self.read = reader(self.out, self.manifest, self.spec, self.ident)
        return self.read(index)


def open_sweep(out):
    """Open the sweep folder ``out`` lazily as one Dask-backed Dataset (grid or table, as :func:`dataset`).

    The manifest is read and checked now (its identity, the storage's, and
    that no chunk is missing); each chunk is read and checked (identity, sizes,
    rows, content) when a computation first needs it, so a bad chunk raises
    :class:`~symvib.numeric.sweep.limits.SweepError` naming its file then.
    ``open_sweep(out).compute()`` equals ``load_sweep(out).to_xarray()``.
    """
    from symvib.numeric.sweep.store import missing_chunks, read_manifest, reader

    dask = require("dask", "opening a sweep folder lazily")
    da = require("dask.array", "opening a sweep folder lazily")
    out = Path(out)
    manifest, spec, ident = read_manifest(out)
    missing_chunks(out, manifest, spec)
    reader(out, manifest, spec, ident)          # the storage is checked now (a Zarr store's identity)
    read = _ChunkReader(out, manifest, spec, ident)
    token = f"symvib-sweep-{ident[:12]}"
    pieces = {name: [] for name in variable_names(spec)}
    for i in range(spec.chunks):
        part = dask.delayed(read, name=f"{token}-reader")(i, dask_key_name=f"{token}-chunk-{i}")
        n = len(spec.rows(i)[0])
        for name in pieces:
            pieces[name].append(da.from_delayed(part[name], shape=(n,) + column_tail(spec, name),
                                                dtype=column_dtype(name)))
    columns = {name: da.concatenate(p) for name, p in pieces.items()}
    columns["row"] = da.arange(spec.count, dtype=np.int64, chunks=spec.chunk)
    return dataset(spec, columns, ident)
