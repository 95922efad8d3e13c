"""The work-precision diagram: error against CPU time per trajectory, one line per method.

Log-log, the error axis reversed (more accurate to the right); a setting is drawn
only when its event sequence is right on every paper scene, errors below
:data:`ERROR_FLOOR` at the floor.  Written as ``work_precision.png`` by
:func:`symvib.checks.bench.work_precision_job.work_precision`.
"""
from __future__ import annotations

import math
from pathlib import Path

from symvib import safeio
from symvib.checks.bench.output import OUT_FOLDER

__all__ = ["ERROR_FLOOR", "STYLE", "FIGURE_SIZE", "FIGURE_DPI", "plot_work_precision"]

#: Smallest error drawn (errors below are plotted here).
ERROR_FLOOR = 1e-16
#: Colour and marker of each method's line.
STYLE = {"symvib": ("k", "o"), "RK45": ("tab:blue", "s"), "DOP853": ("tab:orange", "^"),
         "Radau": ("tab:green", "v"), "LSODA": ("tab:red", "D"), "RK4": ("tab:purple", "x")}
#: The figure's size in inches and its resolution.
FIGURE_SIZE = (6.4, 4.4)
FIGURE_DPI = 100


def plot_work_precision(path: Path, summary, backend) -> None:
    """Draw the work-precision diagram of ``summary`` into the PNG file ``path``.

    Parameters
    ----------
    path : pathlib.Path
        The PNG file, in the output folder.
    summary : list of dict
        One row per setting (``method``, ``error``, ``cpu`` in seconds); a row whose
        error is not finite (a wrong sequence somewhere) is not drawn.
    backend : str
        symvib's driver backend, named in the legend.
    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=FIGURE_SIZE, dpi=FIGURE_DPI)
    ax = fig.subplots()
    for method, (color, marker) in STYLE.items():
        pts = [(max(r["error"], ERROR_FLOOR), r["cpu"] * 1e3) for r in summary
               if r["method"] == method and math.isfinite(r["error"])]
        if not pts:
            continue
        name = f"symvib ({backend})" if method == "symvib" else method if method == "RK4" else f"solve_ivp {method}"
        ax.plot(*zip(*pts), marker=marker, color=color, label=name, ms=4, lw=1.2)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.invert_xaxis()
    ax.set_xlabel("max event-time / position error (vs 30-digit time reference)")
    ax.set_ylabel("CPU time per trajectory [ms]")
    ax.set_title("Work-precision, paper scenes (k = 1, 0.8)", fontsize=10)
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    with safeio.replacing(safeio.check_root(path.parent, OUT_FOLDER), path.name, what=OUT_FOLDER) as fh:
        fig.savefig(fh, format="png")
