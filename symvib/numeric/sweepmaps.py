"""Maps of a sweep over two of its varied fields.

For each scene of a :class:`~symvib.numeric.sweep.SweepResult`: the number of
impacts, the arrest (or rest) time and position, and the share of the lost
energy that went into impacts, ``W_impacts / (W_friction + W_impacts)`` (and the
number of flights, for a sweep of unilateral scenes),
drawn over the first two varied fields that take more than one value: as an
image on a grid sweep (with more axes, at the first value of the others, said
in the title),
as coloured points on a random sweep, as a line over a one-field sweep.

Axes and colour bars are labelled with the quantity's name, symbol and SI
units (``initial speed $\\dot{\\varphi}_0$ [rad/s]``, ``friction coefficient
$\\mu$ [-]``: :mod:`symvib.numeric.sweep.labels`).  Maps are drawn on
backend-free :class:`matplotlib.figure.Figure` objects (no screen needed, the
caller's backend untouched).

Examples
--------
>>> from symvib.numeric.scene import scene_from_dict
>>> from symvib.numeric.sweep import sweep
>>> import tempfile
>>> base = scene_from_dict({"curve": {"shape": "parabola"}, "parameters": {"p": 1},
...     "physics": {"mu": 0.05, "restitution": 0.8}, "limiters": {"left": -0.5, "right": 0.7},
...     "initial": {"q": 0, "qdot": 7}})
>>> res = sweep(base, {"qdot": "3:12:3", "mu": "0.05:0.2:2"}, backend="python")
>>> [p.name for p in sweep_maps(res, tempfile.mkdtemp())]
['impacts.png', 't_final.png', 'q_final.png', 'impact_share.png']
"""
from __future__ import annotations

import matplotlib
import numpy as np
from matplotlib.figure import Figure

from symvib import safeio
from symvib.numeric.sweep.labels import axis_label, column_attrs, field_attrs, label, unit_text

__all__ = ["sweep_maps", "MAPS", "FLIGHT_MAPS"]

#: Mapped quantities: column (or SweepResult attribute) -> title (the colour bar's label, with the
#: symbol and units, is :func:`symvib.numeric.sweep.labels.column_attrs`').
MAPS = {
    "impacts": "number of impacts",
    "t_final": "arrest (or rest) time",
    "q_final": "arrest (or rest) position",
    "impact_share": "share of the energy lost to impacts",
}
#: Mapped too in a sweep of unilateral scenes, which has the flight columns
#: (:mod:`symvib.numeric.sweep.flights`).
FLIGHT_MAPS = {"flights": "number of flights"}
#: Quantities that are counts (drawn with one colour per value).
INTEGER_MAPS = ("impacts", "flights")
#: Quantities whose label leaves out the symbol (a formula too long for a colour bar).
NO_SYMBOL = ("impact_share",)
_TITLES = MAPS | FLIGHT_MAPS
FIGSIZE = (6.4, 4.8)
DPI = 120


def _values(res, name):
    return res.impact_share if name == "impact_share" else np.asarray(res[name], dtype=float)


def _value_label(scene, name):
    """``long name $symbol$ [units]`` of a mapped quantity (title text as the long name)."""
    return label(column_attrs(scene, name) | {"long_name": _TITLES[name]}, symbol=name not in NO_SYMBOL)


def _at(scene, axis):
    """``$\\mu$ = 0.05`` (with units unless a pure number): where a map holds a further axis."""
    attrs = field_attrs(scene, axis.field)
    unit = unit_text(attrs["units"])
    return f"{attrs['latex']} = {axis.first:g}" + (f" {unit}" if unit not in ("-", "") else "")


def _at_first(res, others):
    """Rows where every axis in ``others`` is at its first grid value (all rows if none)."""
    sel = np.ones(res.count, dtype=bool)
    for a in others:
        if a.grid:
            sel &= res[a.field] == a.first
    return sel


def sweep_maps(res, out_dir, *, names=None) -> list:
    """Write one PNG per quantity of ``names`` into ``out_dir``; returns the paths.

    ``names`` defaults to :data:`MAPS`, and :data:`FLIGHT_MAPS` after them for a sweep with
    flight columns (of unilateral scenes).

    ``out_dir`` is created if missing and must be a real folder of the user's (not a
    symbolic link); each map is written whole, never through a link (:mod:`symvib.safeio`).
    """
    out = safeio.check_root(out_dir, "maps folder")
    if names is None:
        names = tuple(MAPS) + (tuple(FLIGHT_MAPS) if "flights" in res.columns else ())
    spread = [a for a in res.spec.axes if not a.grid or a.size > 1] or list(res.spec.axes)
    shown = spread[:2]
    scene = res.spec.scene
    others = [a for a in res.spec.axes if a not in shown]
    note = " at " + ", ".join(_at(scene, a) for a in others) if others else ""
    paths = []
    for name in names:
        values = _values(res, name)
        fig = Figure(figsize=FIGSIZE, dpi=DPI)
        ax = fig.subplots()
        colour = {"cmap": "viridis"}
        if name in INTEGER_MAPS and np.all(np.isfinite(values)):
            top = int(values.max()) if values.size else 0
            # one colour per count, ticks on the integers
            colour = {"cmap": matplotlib.colormaps["viridis"].resampled(top + 1), "vmin": -0.5, "vmax": top + 0.5}
        if len(shown) == 1:
            x = res[shown[0].field]
            sel = _at_first(res, others)
            order = np.argsort(x[sel])
            ax.plot(x[sel][order], values[sel][order], ".-")
            ax.set_xlabel(axis_label(scene, shown[0].field))
            ax.set_ylabel(_value_label(scene, name))
        else:
            xf, yf = shown[0].field, shown[1].field
            if res.spec.mode == "grid":
                grid = values.reshape(res.spec.shape)
                index = tuple(slice(None) if a in shown else 0 for a in res.spec.axes)
                z = grid[index]
                xs, ys = np.asarray(shown[0].values), np.asarray(shown[1].values)
                mesh = ax.pcolormesh(xs, ys, z.T, shading="nearest", **colour)
            else:
                mesh = ax.scatter(res[xf], res[yf], c=values, s=8, **colour)
            bar = fig.colorbar(mesh, ax=ax)
            bar.set_label(_value_label(scene, name))
            ax.set_xlabel(axis_label(scene, xf))
            ax.set_ylabel(axis_label(scene, yf))
        varied = {a.field for a in res.spec.axes}
        fixed = "" if "physics.restitution" in varied else f", k = {scene.k:g}"
        fixed += "" if varied & {"physics.mu", "physics.alpha0"} else f", $\\mu$ = {scene.mu:.4g}"
        if scene.mu_s is not None and not varied & {"physics.mu_s", "physics.alpha0_s"}:
            fixed += f", $\\mu_s$ = {scene.mu_s:.4g}"
        ax.set_title(f"{scene.name}: {_TITLES[name]}{note}\n({res.count} scenes{fixed})", fontsize=10)
        fig.tight_layout()
        path = out / f"{name}.png"
        with safeio.replacing(out, path.name, what="maps folder") as fh:
            fig.savefig(fh, format="png")
        paths.append(path)
    return paths
