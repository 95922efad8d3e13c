"""Figures of a run: the scene, the forces, the phase portrait and the paper's energy analysis.

* :func:`scene_sketch` -- the curve in ``(x, z)`` with its limiters, the start
  point and the arc of relative equilibrium (paper figs. 2, 3, 5, 12, 19); a run
  with flights (physics.md, "Flight and landing") adds each flight's arc and its
  lift-off and landing;
* :func:`force_diagram` -- the forces on the particle at a sample, drawn on
  the curve (paper fig. 1 b);
* :func:`phase_portrait` -- ``(q, qdot)``, the two branches (``v > 0``,
  ``v < 0``) in two line styles, impacts as arrows on the limiter line,
  reversals and the final rest marked, the band ``|tan alpha| <= mu_s`` of
  relative equilibrium shaded (paper figs. 4, 6, 13, 20, 21; ``mu_s = mu`` unless the
  scene gives static friction);
* :func:`energy_vs_q` -- ``F_N``, ``P_mu``, ``Ek``, ``Ep`` or ``E`` against
  ``q``, one curve per motion interval with an arrow in its direction of motion
  (figs. 7-11, 14-18, 22-26);
* :func:`energy_vs_t` -- ``E(t)`` with the friction work and impact losses (and
  landing losses, drag work) stacked on it: they add up to ``E0`` at every sample
  (not in the paper);
* :func:`run_figures` / :func:`save_run_figures` -- all of them, with captions.

The figures against ``q`` draw a run's sliding only (in flight the particle has no
``q``: physics.md, "Flight and landing"); the sketch and the energy in time draw its flights too.

Every figure has axis labels with units in brackets, a title naming the paper's
figure it reproduces (when given) and a caption (:data:`CAPTIONS`).  Branches
differ by line style as well as colour, so the figures read in greyscale.

Files are drawn on backend-free :class:`matplotlib.figure.Figure` objects
(no screen needed, the caller's backend untouched); the single figures use
``pyplot`` only when no axes are given, on whatever backend the caller chose.
"""
from __future__ import annotations

import textwrap

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure
from matplotlib.transforms import blended_transform_factory

from symvib import safeio
from symvib.numeric.events import EventKind
from symvib.paths import UserPathError, check_output_dir, inside, safe_stem

__all__ = ["phase_portrait", "energy_vs_q", "energy_vs_t", "scene_sketch", "force_diagram", "run_figures",
           "save_run_figures", "equilibrium_arcs", "flight_arcs", "QUANTITIES", "CAPTIONS", "FIGURE_NAMES"]

#: Plotted quantities: label, unit.
QUANTITIES = {
    "F_N": ("normal force $F_N$", "N"),
    "P_mu": (r"friction power $P_\mu$", "W"),
    "Ek": ("kinetic energy $E_k$", "J"),
    "Ep": ("potential energy $E_p$", "J"),
    "E": ("total energy $E$", "J"),
}
#: Line style and colour of the branches v > 0 and v < 0 (style first: greyscale).
BRANCH_STYLES = {1: {"color": "tab:blue", "ls": "-"}, -1: {"color": "tab:orange", "ls": "--"}}
BRANCH_LABELS = {1: "branch $v > 0$ (upper sign)", -1: "branch $v < 0$ (lower sign)"}
#: Figure size in inches: the axes and a legend column on the right (legends never cover data).
FIGSIZE = (8.0, 4.4)
DPI = 130
#: Margins of the axes in figure fractions (the legend column on the right; the caption below
#: the bottom margin).
MARGINS = {"left": 0.09, "right": 0.66, "top": 0.87, "bottom": 0.1}
#: Legend placed outside the axes, on the right.
LEGEND_OUTSIDE = {"loc": "upper left", "bbox_to_anchor": (1.02, 1.0), "borderaxespad": 0.0, "fontsize": 8}
#: Colour and line of a limiter, and of an impact's jump.
LIMITER_STYLE = {"color": "0.35", "lw": 1.0, "ls": "-.", "zorder": 1}
IMPACT_COLOUR = "tab:red"
#: Line of a flight's arc in the sketch (physics.md, "Flight and landing" 2).
FLIGHT_STYLE = {"color": "tab:purple", "ls": (0, (4, 2)), "lw": 1.3}
#: Relative-equilibrium band: face colour and hatch.
BAND_STYLE = {"facecolor": "tab:green", "alpha": 0.15, "hatch": "...", "edgecolor": "tab:green", "lw": 0.0}
#: Points of the grid on which the band |tan alpha| <= mu_s and the sketch's curve are evaluated.
GRID_POINTS = 2001
#: Bisections that refine each edge of the band between two grid points.
EDGE_BISECTIONS = 50
#: Share of the visited range added on each side of a sketch.
SKETCH_MARGIN = 0.15
#: Length of the largest force arrow of a force plan, in units of the scene's extent.
FORCE_LENGTH = 0.35
#: Shortest force arrow, in units of the scene's extent (a longer one is drawn dotted).
MIN_ARROW = 0.08
#: Characters per line of a caption under a figure, and its font size.
CAPTION_WIDTH = 150
CAPTION_POINTS = 7
#: Figures of a run, in order (file name suffixes).
FIGURE_NAMES = ("sketch", "forces", "phase", *QUANTITIES, "energy-time")

#: Captions: what each figure shows and how to read it (the run's numbers are added).
CAPTIONS = {
    "sketch": "The scene: the curve z(x), its elongation limiters (bars across the curve), the start point with "
              "the direction of the initial velocity, the final rest, and (thick, green) the arc of relative "
              "equilibrium |tan alpha| <= mu where static friction can hold the particle.",
    "forces": "Force plan at the start: weight m g, normal force F_N along the normal n, friction force F_mu "
              "along the tangent against the velocity v; arrow lengths in proportion to the forces (a dotted "
              "arrow is enlarged to stay visible; the values are in the legend); alpha is the tangent angle.",
    "phase": "Phase portrait: solid = branch v > 0 (upper sign), dashed = branch v < 0 (lower sign); arrows on "
             "the dash-dot limiter lines = impact jumps qdot -> -k qdot; hatched band = relative equilibrium "
             "|tan alpha| <= mu (paper fig. 4), where a reversal ends in arrest.",
    "F_N": "Normal force along the path, one curve per motion interval (solid v > 0, dashed v < 0; the arrow "
           "gives the direction of motion); dash-dot lines = limiters.",
    "P_mu": "Friction power P_mu = -mu |F_N| |v| <= 0 along the path, one curve per motion interval (solid "
            "v > 0, dashed v < 0; arrows: direction of motion); it vanishes with the square root of the "
            "distance at a reversal.",
    "Ek": "Kinetic energy along the path, one curve per motion interval (solid v > 0, dashed v < 0; arrows: "
          "direction of motion); at k < 1 it drops at each impact.",
    "Ep": "Potential energy m g z(q): one curve for every branch (it depends on the position only), with the "
          "reversal and impact positions marked.",
    "E": "Total mechanical energy along the path: numbers give the order of the motion intervals in time, "
         "arrows the direction of motion (solid v > 0, dashed v < 0); it decreases along every interval.",
    "energy-time": "Energy budget in time: mechanical energy E, friction work W_mu and impact losses stacked; "
                   "their sum is E0 at every sample (the run's own quadrature of the friction work).",
}


def _coord(result):
    shape = result.scene.shape
    name = {"phi": r"\varphi", "theta": r"\theta"}.get(shape.q, shape.q)
    return name, shape.unit


def _title(result, what, paper=None):
    # A `$` of the scene's name would start mathtext (and an odd one fails to draw): escaped.
    name = result.scene.name.replace("$", r"\$")
    ref = f" - paper {paper}" if paper else ""
    static = "" if result.scene.mu_s is None else f", $\\mu_s$ = {result.scene.mu_s:.4g}"
    return f"{name}: {what}{ref}\n(k = {result.scene.k:g}, $\\mu$ = {result.scene.mu:.4g}{static})"


def _static_above_kinetic(result) -> bool:
    """Whether the scene's static friction ``mu_s`` exceeds its kinetic ``mu`` (the band is then
    ``|tan alpha| <= mu_s``, wider than the sliding cone)."""
    return result.scene.mu_static > result.scene.mu


def _band_label(result) -> str:
    """The legend of the relative-equilibrium band: ``mu_s`` where static friction exceeds ``mu``."""
    bound = r"\mu_s" if _static_above_kinetic(result) else r"\mu"
    return rf"relative equilibrium $|\tan\alpha| \leq {bound}$"


def _new_axes(ax):
    return ax or plt.subplots(figsize=FIGSIZE, dpi=DPI)[1]


def _kernels(result):
    from symvib.numeric.kernels import load

    return load(result.scene.shape), tuple(float(v) for v in result.scene.param_values)


#: Legend of the one point a run without motion draws (it ends where it starts).
STILL_LABEL = "start (the run ends where it starts: no motion)"


def _moved(result) -> bool:
    """Whether the run has samples of a motion (a run that ends at once, at rest, has none)."""
    return result.samples is not None and len(result.samples.t) > 0


def _start_values(result) -> dict:
    """``F_N, P_mu, Ek, Ep, E`` of the initial state (from the kernels; for a run without samples)."""
    mod, cp = _kernels(result)
    sc = result.scene
    _, _, v, normal, friction, _ = _forces_at(result, mod, cp, None)
    ek = 0.5 * sc.m * v * v
    ep = sc.m * sc.g * float(np.broadcast_to(mod.z(sc.q0, *cp), ()))
    return {"F_N": normal, "P_mu": friction * v, "Ek": ek, "Ep": ep, "E": ek + ep}


def _intervals(result):
    """``(selection, sign of v)`` of every motion interval of the samples on the curve (a flight's
    samples, without ``q``, are left out)."""
    S = result.samples
    if S is None or not len(S.t):
        return
    bounds = np.flatnonzero(np.diff(S.interval)) + 1
    for sl in np.split(np.arange(len(S.t)), bounds):
        if np.isnan(S.q[sl]).all():   # a flight (physics.md, "Flight and landing")
            continue
        v = S.v[sl]
        sign = 1 if np.nansum(v) >= 0 else -1
        yield sl, sign


def flight_arcs(result) -> list:
    """``(x, z)`` arrays of each flight of a run, from its samples (physics.md, "Flight and landing"
    2: the parabola in closed form); empty for a run without flights or samples."""
    S = result.samples
    flight = getattr(S, "flight", None)
    if flight is None:
        return []
    return [(S.x[flight == k], S.z[flight == k]) for k in np.unique(flight[flight >= 0]).tolist()]


#: Colour, marker and legend label of each event kind in the phase portrait.
EVENT_STYLES = {
    EventKind.IMPACT: ("k", "|", "impact"),
    EventKind.REVERSAL: ("tab:green", "o", "reversal"),
    EventKind.ARREST: ("tab:red", "*", "arrest"),
    EventKind.REST_ON_LIMITER: ("tab:red", "s", "rest on limiter"),
    EventKind.NORMAL_SIGN_CHANGE: ("tab:purple", "x", "$N$ changes sign"),
    EventKind.LEFT_CURVE: ("tab:brown", "v", "leaves the curve"),
    EventKind.LIFT_OFF: ("tab:brown", "^", "lift-off"),
    EventKind.LANDING: ("tab:orange", "v", "landing"),
}
#: Colour and marker of an event kind without a style of its own (labelled with its name).
DEFAULT_EVENT_STYLE = ("0.3", "D")


def event_style(kind) -> tuple:
    """``(colour, marker, label)`` of an event kind; a kind added to the vocabulary
    without a style is drawn with :data:`DEFAULT_EVENT_STYLE` and its name.

    >>> event_style(EventKind.REVERSAL)
    ('tab:green', 'o', 'reversal')
    """
    if kind in EVENT_STYLES:
        return EVENT_STYLES[kind]
    return (*DEFAULT_EVENT_STYLE, kind.value.replace("_", " "))


def equilibrium_arcs(result, lo: float, hi: float) -> list:
    """The ``q`` intervals within ``[lo, hi]`` where ``|tan alpha| <= mu_s`` (relative
    equilibrium, paper fig. 4: static friction can hold the particle; physics.md, "Events" 2,
    with ``mu_s = mu`` unless the scene gives static friction), on a grid of
    :data:`GRID_POINTS`.

    >>> from symvib.numeric.driver import simulate
    >>> from symvib.numeric.scene import resolve_scene
    >>> r = simulate(resolve_scene("paper-circle-7"), samples=False)
    >>> [(round(a, 3), round(b, 3)) for a, b in equilibrium_arcs(r, -1.0, 1.0)]  # |phi| <= alpha0 = 0.05
    [(-0.05, 0.05)]
    """
    mod, cp = _kernels(result)
    mu_s = result.scene.mu_static

    def held(x):  # |tan alpha| <= mu_s, written without a division
        alpha = np.broadcast_to(mod.alpha(x, *cp), np.shape(x))
        return np.abs(np.sin(alpha)) <= mu_s * np.abs(np.cos(alpha))

    q = np.linspace(lo, hi, GRID_POINTS)
    inside_band = held(q)
    edges = np.flatnonzero(np.diff(inside_band.astype(int)))
    # Each edge refined by bisection between its two grid points (to rounding).
    a, b = q[edges].copy(), q[edges + 1].copy()
    left_in = inside_band[edges]
    for _ in range(EDGE_BISECTIONS):
        mid = 0.5 * (a + b)
        same = held(mid) == left_in
        a, b = np.where(same, mid, a), np.where(same, b, mid)
    cut = 0.5 * (a + b)
    starts = ([lo] if inside_band[0] else []) + [float(c) for c, i in zip(cut, left_in) if not i]
    ends = [float(c) for c, i in zip(cut, left_in) if i] + ([hi] if inside_band[-1] else [])
    return [(float(x), float(y)) for x, y in zip(starts, ends)]


def _limiters(ax, result):
    """Dash-dot vertical lines at the limiters, labelled at the top of the axes."""
    trans = blended_transform_factory(ax.transData, ax.transAxes)
    for side in ("left", "right"):
        x = getattr(result.scene, side)
        if x is not None:
            ax.axvline(x, **LIMITER_STYLE)
            ax.text(x, 0.02, f"{side} limiter ", transform=trans, rotation=90, va="bottom",
                    ha="right" if side == "right" else "left", fontsize=7, color="0.25",
                    bbox={"boxstyle": "square,pad=0.1", "fc": "w", "ec": "none", "alpha": 0.7})


def _band(ax, result):
    lo, hi = ax.get_xlim()
    label = _band_label(result)
    for a, b in equilibrium_arcs(result, lo, hi):
        ax.axvspan(a, b, label=label, zorder=0, **BAND_STYLE)
        label = None
    ax.set_xlim(lo, hi)


def _direction_arrow(ax, x, y, style):
    """A small arrow at the middle of a curve, in the direction of its points' order."""
    if len(x) < 3:
        return
    i = len(x) // 2
    ax.annotate("", xy=(x[i + 1], y[i + 1]), xytext=(x[i - 1], y[i - 1]),
                arrowprops={"arrowstyle": "-|>", "color": style["color"], "lw": 1.0, "mutation_scale": 10})


def phase_portrait(result, ax=None, *, paper=None):
    """The phase portrait of a run in ``(q, qdot)``; ``paper`` names the paper's figure it reproduces."""
    ax = _new_axes(ax)
    S = result.samples
    q, unit = _coord(result)
    seen = set()
    for sel, sign in _intervals(result):
        label = None if sign in seen else BRANCH_LABELS[sign]
        seen.add(sign)
        ax.plot(S.q[sel], S.qdot[sel], lw=1.3, label=label, **BRANCH_STYLES[sign])
    marks = {}
    impact_label = "impact jump $\\dot q \\to -k \\dot q$"
    for e in result.events:
        marks.setdefault(e.kind, []).append(e)
        if e.kind is EventKind.IMPACT:
            ax.annotate("", xy=(e.q, e.qdot_after), xytext=(e.q, e.qdot_before), zorder=5,
                        arrowprops={"arrowstyle": "-|>", "color": IMPACT_COLOUR, "lw": 1.6, "mutation_scale": 12})
    if EventKind.IMPACT in marks:
        ax.plot([], [], color=IMPACT_COLOUR, lw=1.6, label=impact_label)
    for kind in EventKind:  # every kind of the vocabulary, in its order
        events = marks.get(kind)
        if events and kind is not EventKind.IMPACT:
            c, mk, label = event_style(kind)
            ax.plot([e.q for e in events], [e.qdot_before for e in events], mk, color=c, ms=7,
                    label=label, ls="none", zorder=6)
        elif events:
            c, mk, label = event_style(kind)
            ax.plot([e.q for e in events], [e.qdot_before for e in events], mk, color=c, ms=12,
                    label=label, ls="none", zorder=6)
    ax.plot([result.scene.q0], [result.scene.qdot0], ">", color="k", ms=7, ls="none", label="start", zorder=6)
    ax.axhline(0, color="0.8", lw=0.8)
    _limiters(ax, result)
    ax.plot([], [], **{k: v for k, v in LIMITER_STYLE.items() if k != "zorder"}, label="limiter")
    _band(ax, result)
    ax.set_xlabel(f"${q}$ [{unit}]")
    ax.set_ylabel(f"$\\dot{{{q}}}$ [{unit}/s]")
    ax.set_title(_title(result, "phase portrait", paper), fontsize=9)
    ax.legend(**LEGEND_OUTSIDE)
    ax.grid(alpha=0.3)
    return ax


def energy_vs_q(result, quantity: str, ax=None, *, paper=None):
    """One of ``F_N, P_mu, Ek, Ep, E`` against ``q``: one curve per motion interval with an arrow
    in its direction of motion (``E``: and its number in time order); ``Ep``, a function of
    the position alone, as one curve."""
    if quantity not in QUANTITIES:
        raise ValueError(f"quantity must be one of {', '.join(QUANTITIES)}, not {quantity!r}")
    ax = _new_axes(ax)
    S = result.samples
    q, unit = _coord(result)
    label, qunit = QUANTITIES[quantity]
    values = getattr(S, quantity)
    if not _moved(result):
        ax.plot([result.scene.q0], [_start_values(result)[quantity]], ">", color="k", ms=7, ls="none",
                label=STILL_LABEL)
    elif quantity == "Ep":
        on = np.flatnonzero(np.isfinite(S.q))   # (on the curve: in flight the particle has no q)
        order = on[np.argsort(S.q[on], kind="stable")]
        ax.plot(S.q[order], values[order], color="k", lw=1.3, label="$E_p = m g z$ (depends on the position only)")
        for kind in (EventKind.REVERSAL, EventKind.IMPACT, EventKind.ARREST):
            ev = [e for e in result.events if e.kind is kind]
            if ev:
                c, mk, lab = event_style(kind)
                qs = np.array([e.q for e in ev])
                ax.plot(qs, np.interp(qs, S.q[order], values[order]), mk, color=c, ms=7 if mk != "|" else 12,
                        ls="none", label=lab)
    else:
        seen = set()
        for number, (sel, sign) in enumerate(_intervals(result), 1):
            lab = None if sign in seen else BRANCH_LABELS[sign]
            seen.add(sign)
            style = BRANCH_STYLES[sign]
            ax.plot(S.q[sel], values[sel], lw=1.2, label=lab, **style)
            _direction_arrow(ax, S.q[sel], values[sel], style)
            if quantity == "E":
                i = sel[len(sel) // 2]
                ax.annotate(str(number), (S.q[i], values[i]), textcoords="offset points", xytext=(0, 5),
                            fontsize=7, ha="center", bbox={"boxstyle": "round,pad=0.1", "fc": "w", "ec": "none",
                                                            "alpha": 0.7})
        if quantity == "E":
            ax.plot([], [], ls="none", marker="$1$", color="k", label="interval number (time order)")
    _limiters(ax, result)
    ax.set_xlabel(f"${q}$ [{unit}]")
    ax.set_ylabel(f"{label} [{qunit}]")
    ax.set_title(_title(result, label, paper), fontsize=9)
    ax.legend(**LEGEND_OUTSIDE)
    ax.grid(alpha=0.3)
    return ax


def energy_vs_t(result, ax=None, *, paper=None):
    """``E(t)`` with the friction work and impact losses (and, with air drag, the drag work)
    stacked on it: they sum to ``E0`` at every sample (the samples' ``W_mu``, ``W_impacts`` and
    ``W_drag``, the energy budget's own terms; at an impact the state after it carries its loss)."""
    ax = _new_axes(ax)
    S = result.samples
    if not _moved(result):
        ax.plot([0.0], [_start_values(result)["E"]], ">", color="k", ms=7, ls="none", label=STILL_LABEL)
    layers, labels = [S.E, S.W_mu, S.W_impacts], ["mechanical energy $E$", r"friction work $W_\mu$",
                                                   "impact losses $W_k$"]
    colors = ["tab:blue", "tab:orange", "0.6"]
    if getattr(S, "W_drag", None) is not None:   # a run with air drag (physics.md, "Air drag")
        layers, labels, colors = layers + [S.W_drag], labels + ["drag work $W_d$"], colors + ["tab:green"]
    if getattr(S, "W_landing", None) is not None:   # a run with flights (physics.md, "Flight and landing")
        layers, labels, colors = layers + [S.W_landing], labels + ["landing losses $W_l$"], colors + ["tab:purple"]
    polys = ax.stackplot(S.t, *layers, labels=labels, colors=colors, alpha=0.75)
    for poly, hatch in zip(polys, ("", "//", "..", "\\\\", "xx")):
        poly.set_hatch(hatch)
    ax.axhline(result.energy_budget.initial, color="k", lw=0.8, ls="--", label="$E_0$")
    ax.set_xlabel("$t$ [s]")
    ax.set_ylabel("energy [J]")
    ax.set_title(_title(result, "energy budget", paper), fontsize=9)
    ax.legend(**LEGEND_OUTSIDE)
    ax.grid(alpha=0.3)
    return ax


def _sketch_range(result):
    """The ``q`` range a sketch shows: limiters and the visited positions, with a margin,
    inside the curve's regular domain."""
    mod, cp = _kernels(result)
    sc = result.scene
    qs = [sc.q0] + [e.q for e in result.events] + [v for v in (sc.left, sc.right) if v is not None]
    S = result.samples
    if S is not None and np.isfinite(S.q).any():   # (in flight q is NaN)
        qs += [float(np.nanmin(S.q)), float(np.nanmax(S.q))]
    lo, hi = min(qs), max(qs)
    pad = SKETCH_MARGIN * max(hi - lo, 1e-3)
    # (the run's own domain: a curve with a singular point inside its declared one is drawn up to it)
    dlo, dhi = (float(v) for v in result.stats.get("domain") or mod.domain(*cp))
    inset = 1e-6 * max(hi - lo, 1e-3)
    return max(lo - pad, dlo + inset), min(hi + pad, dhi - inset)


def _point(mod, cp, q):
    x = float(np.broadcast_to(mod.x(q, *cp), ()))
    z = float(np.broadcast_to(mod.z(q, *cp), ()))
    a = float(np.broadcast_to(mod.alpha(q, *cp), ()))
    return x, z, a


def _draw_curve(ax, result, mod, cp, lo, hi, **style):
    """The curve ``x(q), z(q)`` for ``lo <= q <= hi``; returns ``(q, x, z, span)``, ``span`` the
    drawing's size (for arrows and labels in proportion)."""
    q = np.linspace(lo, hi, GRID_POINTS)
    x = np.broadcast_to(mod.x(q, *cp), q.shape)
    z = np.broadcast_to(mod.z(q, *cp), q.shape)
    ax.plot(x, z, label=f"curve: {result.scene.shape.name}", **style)
    return q, x, z, max(np.ptp(x), np.ptp(z), 1e-9)


def scene_sketch(result, ax=None, *, paper=None):
    """The curve in the vertical plane with its limiters, the start point and direction, the
    final rest and the arc of relative equilibrium (paper figs. 2, 3, 5, 12, 19)."""
    ax = _new_axes(ax)
    mod, cp = _kernels(result)
    sc = result.scene
    lo, hi = _sketch_range(result)
    q, x, z, span = _draw_curve(ax, result, mod, cp, lo, hi, color="k", lw=1.4)
    label = _band_label(result)
    for a, b in equilibrium_arcs(result, lo, hi):
        sel = (q >= a) & (q <= b)
        ax.plot(x[sel], z[sel], color="tab:green", lw=5, alpha=0.6, solid_capstyle="butt", label=label)
        label = None
    qn, qu = _coord(result)
    for side in ("left", "right"):
        ql = getattr(sc, side)
        if ql is None:
            continue
        xl, zl, al = _point(mod, cp, ql)
        nx, nz = -np.sin(al), np.cos(al)
        d = 0.06 * span
        ax.plot([xl - d * nx, xl + d * nx], [zl - d * nz, zl + d * nz], color="0.2", lw=3, solid_capstyle="butt")
        ax.annotate(f"{side} limiter\n${qn}$ = {ql:.4g} {qu}", (xl + d * nx, zl + d * nz), fontsize=7,
                    xytext=(0, 4), textcoords="offset points", ha="center", va="bottom")
    x0, z0, a0 = _point(mod, cp, sc.q0)
    ax.plot([x0], [z0], "o", color="tab:blue", ms=7, label=f"start ${qn}_0$ = {sc.q0:.4g} {qu}", zorder=5)
    if sc.qdot0 != 0.0:
        sgn = np.sign(sc.qdot0) * np.sign(float(np.broadcast_to(mod.h(sc.q0, *cp), ())))
        L = 0.15 * span
        ax.annotate("", xy=(x0 + sgn * L * np.cos(a0), z0 + sgn * L * np.sin(a0)), xytext=(x0, z0), zorder=5,
                    arrowprops={"arrowstyle": "-|>", "color": "tab:blue", "lw": 1.5})
        ax.plot([], [], color="tab:blue", lw=1.5, label=f"initial velocity ($\\dot{{{qn}}}_0$ = {sc.qdot0:g} {qu}/s)")
    if result.events and result.events[-1].kind in (EventKind.ARREST, EventKind.REST_ON_LIMITER):
        xf, zf, _ = _point(mod, cp, result.q_final)
        ax.plot([xf], [zf], "*", color="tab:red", ms=11, ls="none", label="final rest", zorder=6)
    _flights(ax, result, mod, cp)
    # Gravity, beside the axes (under the legend), where it covers nothing.
    ax.annotate("", xy=(1.05, 0.05), xytext=(1.05, 0.3), xycoords="axes fraction", annotation_clip=False,
                arrowprops={"arrowstyle": "-|>", "color": "0.3"})
    ax.text(1.07, 0.17, "gravity $g$", transform=ax.transAxes, fontsize=8, va="center")
    return _plane_axes(ax, _title(result, "the scene", paper))


def _flights(ax, result, mod, cp):
    """A run's flight arcs and its lift-offs and landings (on the curve, at their ``q``) in the sketch."""
    label = "flight (parabola)"
    arcs = flight_arcs(result)
    for x, z in arcs:
        ax.plot(x, z, label=label, zorder=4, **FLIGHT_STYLE)
        label = None
    if arcs and result.samples.flight[-1] >= 0:   # the run stopped in flight (crossed_limiter, t_max, ...)
        ax.plot(arcs[-1][0][-1:], arcs[-1][1][-1:], "X", color=FLIGHT_STYLE["color"], ms=9, ls="none", zorder=6,
                label=f"end in flight ({result.status.value})")
    for kind in (EventKind.LIFT_OFF, EventKind.LANDING):
        qs = [e.q for e in result.events if e.kind is kind]
        if qs:
            c, mk, lab = event_style(kind)
            xs = np.broadcast_to(mod.x(np.array(qs), *cp), (len(qs),))
            zs = np.broadcast_to(mod.z(np.array(qs), *cp), (len(qs),))
            ax.plot(xs, zs, mk, color=c, ms=7, mec="k", mew=0.5, ls="none", label=f"{lab} ({len(qs)})", zorder=6)


def _plane_axes(ax, title: str):
    """Finish a drawing in the plane of the curve: equal scales, x and z in metres, title, legend beside."""
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("$x$ [m]")
    ax.set_ylabel("$z$ [m]")
    ax.set_title(title, fontsize=9)
    ax.legend(**LEGEND_OUTSIDE)
    ax.grid(alpha=0.3)
    return ax


def force_diagram(result, ax=None, *, paper=None, sample: int = 0):
    """The force plan (paper fig. 1 b) at a sample (default: the start), drawn on the curve:
    weight, normal force along ``n = (-sin alpha, cos alpha)``, friction force along the
    tangent against the velocity; lengths in proportion to the forces."""
    ax = _new_axes(ax)
    mod, cp = _kernels(result)
    sc = result.scene
    qs, ts, v, normal, friction, friction_label = _forces_at(result, mod, cp, sample)
    xs, zs, a = _point(mod, cp, qs)
    lo, hi = _sketch_range(result)
    _, _, _, span = _draw_curve(ax, result, mod, cp, lo, hi, color="0.4", lw=1.2)
    weight = sc.m * sc.g
    t_vec = np.array([np.cos(a), np.sin(a)])
    n_vec = np.array([-np.sin(a), np.cos(a)])
    forces = [
        ("weight $m g$", np.array([0.0, -weight]), "k", "-"),
        ("normal force $F_N$", normal * n_vec, "tab:blue", "-"),
        (friction_label, friction * t_vec, "tab:red", "-"),
    ]
    largest = max(float(np.hypot(*f)) for _, f, _, _ in forces)
    if not (np.isfinite(largest) and largest > 0.0):
        largest = 1.0  # g = 0 at rest: no force to draw in proportion
    unit = FORCE_LENGTH * span / largest  # metres per newton: the largest force is FORCE_LENGTH of the scene
    for label, f, colour, ls in forces:
        size = float(np.hypot(*f))
        scale, note = unit, ""
        if 0.0 < unit * size < MIN_ARROW * span:  # a small force (friction) stays visible
            scale, ls, note = MIN_ARROW * span / size, ":", "\n(dotted: arrow enlarged)"
        tip = (xs + scale * f[0], zs + scale * f[1])
        ax.annotate("", xy=tip, xytext=(xs, zs), zorder=5,
                    arrowprops={"arrowstyle": "-|>", "color": colour, "lw": 1.8, "ls": ls})
        ax.plot([tip[0]], [tip[1]], ls="none")  # the axes' limits include the arrow
        ax.plot([], [], color=colour, lw=1.8, ls=ls, label=f"{label} = {size:.4g} N{note}")
    if v != 0.0:
        L = 0.2 * span * np.sign(v)
        ax.annotate("", xy=(xs + L * t_vec[0], zs + L * t_vec[1]), xytext=(xs, zs), zorder=4,
                    arrowprops={"arrowstyle": "-|>", "color": "tab:green", "lw": 1.2, "ls": "--"})
        ax.plot([], [], color="tab:green", lw=1.2, ls="--", label=f"velocity $v$ = {v:.4g} m/s (direction)")
    ax.plot([xs - 0.25 * span, xs + 0.25 * span], [zs, zs], color="0.6", lw=0.8, ls=":")
    ax.plot([xs, xs + 0.25 * span * t_vec[0]], [zs, zs + 0.25 * span * t_vec[1]], color="0.6", lw=0.8, ls=":")
    ax.text(xs + 0.27 * span, zs, f"$\\alpha$ = {np.degrees(a):.3g} deg", fontsize=8, va="center")
    ax.plot([xs], [zs], "o", color="k", ms=6, zorder=6, label=f"particle at t = {ts:.3g} s")
    return _plane_axes(ax, _title(result, "force plan", paper))


def _forces_at(result, mod, cp, sample: int | None) -> tuple:
    """``(q, t, v, F_N, F_mu, friction label)`` at a sample, or at the start (``sample`` None, or a
    run without samples).

    A run that ends where it starts (at rest in the friction cone, on a limiter) has no
    samples: its forces are those of the initial state, the normal force ``m (kappa v**2 +
    g cos alpha)`` and, at rest, the static friction that holds the particle (``m g sin
    alpha`` along the tangent, at most ``mu_s |F_N|``: physics.md, "Events" 2).
    """
    S = result.samples
    if sample is not None and S is not None and -len(S.t) <= sample < len(S.t):
        return (float(S.q[sample]), float(S.t[sample]), float(S.v[sample]), float(S.F_N[sample]),
                float(S.F_mu[sample]), r"friction force $F_\mu$")
    sc = result.scene
    h = float(np.broadcast_to(mod.h(sc.q0, *cp), ()))
    kappa = float(np.broadcast_to(mod.kappa(sc.q0, *cp), ()))
    _, _, a = _point(mod, cp, sc.q0)
    v = h * sc.qdot0
    normal = sc.m * (kappa * v * v + sc.g * np.cos(a))
    if v != 0.0:
        return sc.q0, 0.0, v, normal, -np.sign(v) * sc.mu * abs(normal), r"friction force $F_\mu$"
    hold = sc.mu_static * abs(normal)   # static friction: mu_s (mu unless the scene gives it)
    static = float(np.clip(sc.m * sc.g * np.sin(a), -hold, hold))
    return sc.q0, 0.0, 0.0, normal, static, r"static friction $F_\mu$"


def _drawers():
    out = {"sketch": scene_sketch, "forces": force_diagram, "phase": phase_portrait}
    for k in QUANTITIES:
        out[k] = (lambda kk: lambda r, ax, paper=None: energy_vs_q(r, kk, ax, paper=paper))(k)
    out["energy-time"] = energy_vs_t
    return out


def caption(name: str, paper=None) -> str:
    """The caption of a figure kind (:data:`CAPTIONS`), with the paper's figure it reproduces."""
    text = CAPTIONS[name]
    return f"{text} Reproduces paper {paper}." if paper else text


def run_figures(result, *, only=None, paper=None) -> list:
    """The run's figures as ``(name, Figure, caption)``, names from :data:`FIGURE_NAMES`.

    ``only`` restricts them to some names; ``paper`` maps a name to the paper's
    figure it reproduces (``{"phase": "fig. 6"}``), shown in the title and caption.
    Each figure carries its caption under the axes.
    """
    paper = paper or {}
    out = []
    for name, draw in _drawers().items():
        if only is not None and name not in only:
            continue
        fig = Figure(figsize=FIGSIZE, dpi=DPI)
        ax = fig.subplots()
        draw(result, ax, paper=paper.get(name))
        text = caption(name, paper.get(name))
        if _static_above_kinetic(result):   # the band is static friction's, wider than the sliding cone
            text = text.replace("|tan alpha| <= mu ", "|tan alpha| <= mu_s (static friction) ")
        if name == "energy-time" and result.energy_budget.landing_loss is not None:   # landings' own layer
            text = text.replace("W_mu and impact losses stacked", "W_mu, impact losses and landing losses W_l stacked")
        if name == "sketch" and result.energy_budget.landing_loss is not None:   # a run with flights
            text += (" Dashed purple: the flights (parabolas, physics.md \"Flight and landing\"); triangles: "
                     "lift-offs and landings on the curve.")
        if name == "energy-time" and result.energy_budget.drag_work is not None:   # air drag's own layer
            text = text.replace("W_mu and impact losses", "W_mu, impact losses and drag work W_d").replace(
                "of the friction work", "of the friction and drag work")
        lines = textwrap.fill(text, CAPTION_WIDTH)
        fig.text(0.01, 0.01, lines, fontsize=CAPTION_POINTS, va="bottom", ha="left")
        height = (lines.count("\n") + 1) * CAPTION_POINTS * 1.35 / 72 / FIGSIZE[1] + 0.02
        # Fixed margins (tight_layout would lay every text out twice: most of the drawing time).
        fig.subplots_adjust(bottom=height + MARGINS["bottom"], **{k: v for k, v in MARGINS.items() if k != "bottom"})
        out.append((name, fig, text))
    return out


def save_run_figures(result, out_dir, *, prefix: str | None = None, only=None, paper=None) -> list:
    """Write the run's figures (:func:`run_figures`) as PNG; returns the paths.

    ``only`` restricts them to some names: ``"sketch"``, ``"forces"``, ``"phase"``,
    ``"F_N"``, ``"P_mu"``, ``"Ek"``, ``"Ep"``, ``"E"``, ``"energy-time"``.  File names
    start with ``safe_stem(prefix or scene name)`` (:func:`symvib.paths.safe_stem`): a
    name such as ``../../x`` or ``/abs/path`` writes inside ``out_dir`` and nowhere else.

    Raises
    ------
    symvib.paths.UserPathError
        When ``out_dir`` is a file or a device, or cannot be created.
    """
    check_output_dir(out_dir, "figure folder")
    out = safeio.check_root(out_dir, "figure folder")   # a real folder of the user's, not a link
    # File names from user text: a plain stem, and never outside ``out_dir`` (docs/trust.md).
    prefix = safe_stem(prefix or result.scene.name)
    paths = []
    for name, fig, _ in run_figures(result, only=only, paper=paper):
        path = out / f"{prefix}-{name}.png"
        if not inside(path, out):
            raise UserPathError(path, f"figure file name would leave the folder {out}")
        with safeio.replacing(out, path.name, what="figure folder") as fh:   # whole, never through a link
            fig.savefig(fh, format="png")
        paths.append(path)
    return paths
