"""A sweep as labelled data: an xarray Dataset, a pandas DataFrame, a folder opened lazily.

A sweep in memory (:class:`~symvib.numeric.sweep.result.SweepResult`) becomes
labelled data by its ``to_xarray`` and ``to_dataframe``, which are
:func:`dataset` and :func:`dataframe` of :mod:`symvib.numeric.sweep.frames`
(re-exported here): a grid sweep has one dimension and coordinate per varied
field, named readably (``qdot0``, ``mu``, a curve parameter's name: see
:mod:`symvib.numeric.sweep.labels`), a random sweep the dimension ``row``;
every column carries ``units`` (SI), ``long_name`` and ``latex``, and the
Dataset's attributes name the sweep: ``sweep_id`` (the identity of
:func:`symvib.numeric.sweep.schema.sweep_id`), its definition (JSON) and layout.

:func:`open_sweep` opens a sweep folder (either storage) as one Dask-backed
Dataset without reading its chunks: each chunk is read, and checked as
:func:`~symvib.numeric.sweep.store.load_sweep` checks it, when a computation
first needs it.  It stands above the folder's reader
(:mod:`symvib.numeric.sweep.store`), which the Dataset's builders stand below.

xarray, pandas, zarr and dask are the extra ``symvib[xarray]``, imported
when first used (:func:`require`).

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

from pathlib import Path

import numpy as np

from symvib.numeric.sweep.frames import (
    EXTRA,
    ROW_ATTRS,
    dataframe,
    dataset,
    dataset_attrs,
    event_log_attrs,
    require,
    status_attrs,
)
from symvib.numeric.sweep.schema import column_dtype, column_tail, impact_share, variable_names
from symvib.numeric.sweep.store import missing_chunks, read_manifest, reader

__all__ = ["EXTRA", "require", "variable_names", "dataset", "dataframe", "dataset_attrs", "open_sweep",
           "impact_share", "ROW_ATTRS", "status_attrs", "event_log_attrs"]


class _ChunkReader:
    """Reads chunk ``index`` of a sweep folder, checked (the task of one block of :func:`open_sweep`)."""

    def __init__(self, out, manifest, spec, ident):
        self.out, self.manifest, self.spec, self.ident = out, manifest, spec, ident
        self.read = None

    def __call__(self, index: int) -> dict:
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
