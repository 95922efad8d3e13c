"""The interactive explorer's drawing: change ``mu``, ``k``, ``qdot0`` or a limiter, run, redraw.

A run of a paper scene takes milliseconds on the plain-Python engine, so a notebook
can redraw the phase portrait and the energy budget while a slider moves
(``derivations/explorer.ipynb``, with ipywidgets).  The functions here are plain:
:func:`explore` runs the changed scene and draws one figure, :func:`slider_ranges`
proposes the sliders' ranges, and :func:`phase_grid` draws the static grid the
notebook shows where ipywidgets is not installed.

Examples
--------
>>> from symvib.numeric.scene import scene_from_dict
>>> scene = scene_from_dict({"curve": {"shape": "circle"}, "parameters": {"R": 0.5},
...     "physics": {"mu": 0.1, "restitution": 0.8}, "limiters": {"right": 0.6},
...     "initial": {"q": 0, "qdot": 5}})
>>> result, fig = explore(scene, mu=0.3, k=0.5)
>>> result.scene.mu, result.scene.k, result.status.value
(0.3, 0.5, 'arrested')
>>> sorted(slider_ranges(scene))
['k', 'mu', 'qdot0', 'right']
"""
from __future__ import annotations

from matplotlib.figure import Figure

from symvib.numeric import figures
from symvib.numeric.driver import simulate
from symvib.numeric.events import EventKind

__all__ = ["explore", "changed_scene", "slider_ranges", "phase_grid", "FIELDS"]

#: What the explorer varies: argument name -> Scene field.
FIELDS = {"mu": "mu", "k": "k", "qdot0": "qdot0", "left": "left", "right": "right"}
#: Figure size (inches) of :func:`explore` and of one panel of :func:`phase_grid`.
FIGSIZE = (12.0, 4.2)
PANEL_SIZE = (4.2, 3.4)
DPI = 90
#: Slider steps: this share of the slider's range.
STEP_SHARE = 1e-3
#: A limiter's slider reaches this multiple of its distance from the start beyond the scene's value.
LIMITER_REACH = 1.0
#: Largest friction coefficient a slider offers at least.
MU_REACH = 0.5


def changed_scene(scene, **changes):
    """``scene`` with the explorer's fields changed (None: unchanged); errors name the field."""
    unknown = set(changes) - set(FIELDS)
    if unknown:
        raise ValueError(f"{sorted(unknown)[0]}: the explorer varies {', '.join(FIELDS)}")
    return scene.replace(**{FIELDS[k]: float(v) for k, v in changes.items() if v is not None})


def explore(scene, *, mu=None, k=None, qdot0=None, left=None, right=None, fig=None, backend: str = "auto"):
    """Run ``scene`` with the given changes and draw its phase portrait and energy budget.

    Parameters
    ----------
    scene : Scene
    mu, k, qdot0, left, right : float, optional
        New friction coefficient, restitution, initial speed ``qdot0`` and limiter
        positions (None keeps the scene's).
    fig : matplotlib.figure.Figure, optional
        Drawn into (cleared first), so a slider redraws one figure; a new one by default.
    backend : str
        Of :func:`symvib.numeric.driver.simulate` (``"auto"`` never waits for a compiler).

    Returns
    -------
    (Result or None, Figure)
        The run (None when the changed scene is invalid: the figure then shows why).
    """
    fig = fig if fig is not None else Figure(figsize=FIGSIZE, dpi=DPI)
    fig.clf()
    try:
        result = simulate(changed_scene(scene, mu=mu, k=k, qdot0=qdot0, left=left, right=right), backend=backend)
    except ValueError as exc:  # SceneError and friends: say so in the figure, keep the sliders alive
        fig.text(0.5, 0.5, f"no run: {exc}", ha="center", va="center", wrap=True, color="tab:red")
        return None, fig
    ax_phase, ax_energy = fig.subplots(1, 2)
    if result.samples is None:
        ax_phase.text(0.5, 0.5, f"{result.status.value}: {result.message}", ha="center", transform=ax_phase.transAxes)
        return result, fig
    figures.phase_portrait(result, ax=ax_phase)
    figures.energy_vs_t(result, ax=ax_energy)
    impacts = result.count(EventKind.IMPACT)
    fig.suptitle(f"{result.status.value} at t = {result.t_final:.4g} s: {len(result.events)} events, "
                 f"{impacts} of them impacts", fontsize=10)
    fig.tight_layout()
    return result, fig


def slider_ranges(scene) -> dict:
    """``{name: (low, high, step, value)}`` for the explorer's sliders, around the scene's values.

    ``mu`` from 0 to at least :data:`MU_REACH`, ``k`` from 0 to 1, ``qdot0`` from
    ``-2 |qdot0|`` to ``2 |qdot0|``, and each limiter the scene has from the start
    ``q0`` out to :data:`LIMITER_REACH` times its distance beyond it.
    """
    def entry(lo, hi, value):
        return (float(lo), float(hi), float((hi - lo) * STEP_SHARE), float(value))

    speed = max(abs(scene.qdot0), 1.0)
    out = {"mu": entry(0.0, max(MU_REACH, 2 * scene.mu), scene.mu), "k": entry(0.0, 1.0, scene.k),
           "qdot0": entry(-2 * speed, 2 * speed, scene.qdot0)}
    for side in ("left", "right"):
        q_lim = getattr(scene, side)
        if q_lim is not None:
            gap = abs(q_lim - scene.q0)
            near, far = scene.q0 + (q_lim - scene.q0) * 0.05, q_lim + (q_lim - scene.q0) * LIMITER_REACH
            out[side] = entry(min(near, far), max(near, far), q_lim) if gap > 0 else entry(q_lim, q_lim, q_lim)
    return out


def phase_grid(scene, field: str, values, *, backend: str = "auto") -> Figure:
    """Phase portraits of ``scene`` with one explorer field set to each of ``values``, side by side."""
    if field not in FIELDS:
        raise ValueError(f"field: the explorer varies {', '.join(FIELDS)}, not {field!r}")
    values = list(values)
    if not values:
        raise ValueError("values: give at least one value")
    fig = Figure(figsize=(PANEL_SIZE[0] * len(values), PANEL_SIZE[1]), dpi=DPI)
    for ax, value in zip(fig.subplots(1, len(values), squeeze=False)[0], values):
        result = simulate(changed_scene(scene, **{field: value}), backend=backend)
        figures.phase_portrait(result, ax=ax)
        ax.set_title(f"{field} = {value:g}: {result.status.value}, {len(result.events)} events", fontsize=9)
        ax.legend().set_visible(False)
    fig.tight_layout()
    return fig
