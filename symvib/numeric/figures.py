"""Figures of a run: the phase portrait and the paper's energy analysis.

* :func:`phase_portrait` -- ``(q, qdot)`` with the two branches (``v > 0``,
  ``v < 0``) in two colours, impacts as dashed jumps, reversals and the final
  rest marked (paper figs. 6, 13, 20, 21);
* :func:`energy_vs_q` -- ``F_N``, ``P_mu``, ``Ek``, ``Ep`` or ``E`` against
  ``q``, one curve per interval (figs. 7-11, 14-18, 22-26);
* :func:`energy_vs_t` -- ``E(t)`` with the friction work and impact losses
  stacked on it, which must add up to ``E0`` (not in the paper);
* :func:`save_run_figures` -- all of them as PNG files.

Files are drawn on backend-free :class:`matplotlib.figure.Figure` objects
(no screen needed, the caller's backend untouched); the single figures use
``pyplot`` only when no axes are given, on whatever backend the caller chose.
"""
from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from symvib.numeric.engine.laws import impact
from symvib.numeric.events import EventKind
from symvib.paths import UserPathError, check_output_dir, inside, safe_stem

__all__ = ["phase_portrait", "energy_vs_q", "energy_vs_t", "save_run_figures", "QUANTITIES"]

#: Plotted quantities: label, unit.
QUANTITIES = {
    "F_N": ("normal force $F_N$", "N"),
    "P_mu": (r"friction power $P_\mu$", "W"),
    "Ek": ("kinetic energy $E_k$", "J"),
    "Ep": ("potential energy $E_p$", "J"),
    "E": ("total energy $E$", "J"),
}
#: Colours of the branches v > 0 and v < 0.
BRANCH_COLOURS = {1: "tab:blue", -1: "tab:orange"}
#: Figure size in inches (the report shows figures about 16 cm wide).
FIGSIZE = (6.4, 4.2)
DPI = 130


def _coord(result):
    shape = result.scene.shape
    name = {"phi": r"\varphi", "theta": r"\theta"}.get(shape.q, shape.q)
    return name, shape.unit


def _title(result, what):
    # A `$` of the scene's name would start mathtext (and an odd one fails to draw): escaped.
    name = result.scene.name.replace("$", r"\$")
    return f"{name}: {what} (k = {result.scene.k:g}, $\\mu$ = {result.scene.mu:.4g})"


def _intervals(result):
    S = result.samples
    if S is None or not len(S.t):
        return
    for i in np.unique(S.interval):
        sel = S.interval == i
        sign = 1 if np.nanmean(S.qdot[sel]) >= 0 else -1
        yield sel, sign


#: Colour, marker and legend label of each event kind in the phase portrait.
EVENT_STYLES = {
    EventKind.IMPACT: ("k", "|", "impact"),
    EventKind.REVERSAL: ("tab:green", "o", "reversal"),
    EventKind.ARREST: ("tab:red", "*", "arrest"),
    EventKind.REST_ON_LIMITER: ("tab:red", "s", "rest on limiter"),
    EventKind.NORMAL_SIGN_CHANGE: ("tab:purple", "x", "$N$ changes sign"),
    EventKind.LEFT_CURVE: ("tab:brown", "v", "leaves the curve"),
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


def phase_portrait(result, ax=None):
    """The phase portrait of a run in ``(q, qdot)``."""
    ax = ax or plt.subplots(figsize=FIGSIZE, dpi=DPI)[1]
    S = result.samples
    q, unit = _coord(result)
    seen = set()
    for sel, sign in _intervals(result):
        label = None
        if sign not in seen:
            label = ("branch $v > 0$ (upper sign)" if sign > 0 else "branch $v < 0$ (lower sign)")
            seen.add(sign)
        ax.plot(S.q[sel], S.qdot[sel], color=BRANCH_COLOURS[sign], lw=1.3, label=label)
    marks = {}
    for e in result.events:
        marks.setdefault(e.kind, []).append(e)
        if e.kind is EventKind.IMPACT:
            ax.plot([e.q, e.q], [e.qdot_before, e.qdot_after], "k--", lw=0.8)
    for kind in EventKind:  # every kind of the vocabulary, in its order
        events = marks.get(kind)
        if events:
            c, mk, label = event_style(kind)
            ax.plot([e.q for e in events], [e.qdot_before for e in events], mk, color=c, ms=7 if mk != "|" else 12,
                    label=label, ls="none")
    for side in ("left", "right"):
        x = getattr(result.scene, side)
        if x is not None:
            ax.axvline(x, color="0.5", lw=2, alpha=0.5)
    ax.axhline(0, color="0.8", lw=0.8)
    ax.set_xlabel(f"${q}$ [{unit}]")
    ax.set_ylabel(f"$\\dot{{{q}}}$ [{unit}/s]")
    ax.set_title(_title(result, "phase portrait"), fontsize=10)
    ax.legend(fontsize=8, loc="best")
    ax.grid(alpha=0.3)
    return ax


def energy_vs_q(result, quantity: str, ax=None):
    """One of ``F_N, P_mu, Ek, Ep, E`` against ``q``, one curve per interval."""
    if quantity not in QUANTITIES:
        raise ValueError(f"quantity must be one of {', '.join(QUANTITIES)}, not {quantity!r}")
    ax = ax or plt.subplots(figsize=FIGSIZE, dpi=DPI)[1]
    S = result.samples
    q, unit = _coord(result)
    label, qunit = QUANTITIES[quantity]
    values = getattr(S, quantity)
    seen = set()
    for sel, sign in _intervals(result):
        lab = None if sign in seen else (f"$v {'>' if sign > 0 else '<'} 0$")
        seen.add(sign)
        ax.plot(S.q[sel], values[sel], color=BRANCH_COLOURS[sign], lw=1.2, label=lab)
    ax.set_xlabel(f"${q}$ [{unit}]")
    ax.set_ylabel(f"{label} [{qunit}]")
    ax.set_title(_title(result, label), fontsize=10)
    ax.legend(fontsize=8, title="branch", title_fontsize=8)
    ax.grid(alpha=0.3)
    return ax


def energy_vs_t(result, ax=None):
    """``E(t)`` with the friction work and impact losses stacked on it (they sum to ``E0``)."""
    ax = ax or plt.subplots(figsize=FIGSIZE, dpi=DPI)[1]
    S = result.samples
    order = np.argsort(S.t, kind="stable")
    t, E = S.t[order], S.E[order]
    P = S.P_mu[order]
    # Friction work: integral of -P_mu dt (trapezoid on the samples, for display only).
    Wf = np.concatenate(([0.0], np.cumsum(-0.5 * (P[1:] + P[:-1]) * np.diff(t))))
    loss = np.zeros_like(t)
    for e in result.events:
        if e.kind is EventKind.IMPACT:
            _, _, jump = impact(e.qdot_before, (e.qdot_before * _h(result, e.q)) ** 2, result.scene.k,
                                result.scene.m)
            loss[t >= e.t] += jump
    ax.stackplot(t, E, Wf, loss, labels=["mechanical energy $E$", "friction work", "impact losses"],
                 colors=["tab:blue", "tab:orange", "tab:gray"], alpha=0.75)
    ax.axhline(result.energy_budget.initial, color="k", lw=0.8, ls="--", label="$E_0$")
    ax.set_xlabel("$t$ [s]")
    ax.set_ylabel("energy [J]")
    ax.set_title(_title(result, "energy budget"), fontsize=10)
    ax.legend(fontsize=8, loc="lower left")
    ax.grid(alpha=0.3)
    return ax


def _h(result, q):
    from symvib.numeric.kernels import load

    return float(load(result.scene.shape).h_scalar(q, *result.scene.param_values))


def save_run_figures(result, out_dir, *, prefix: str | None = None, only=None) -> list:
    """Write the phase portrait, the five energy figures and E(t) as PNG; returns the paths.

    ``only`` restricts them to some names: ``"phase"``, ``"F_N"``, ``"P_mu"``,
    ``"Ek"``, ``"Ep"``, ``"E"``, ``"energy-time"``.  File names start with
    ``safe_stem(prefix or scene name)`` (:func:`symvib.paths.safe_stem`): a name
    such as ``../../x`` or ``/abs/path`` writes inside ``out_dir`` and nowhere else.

    Raises
    ------
    symvib.paths.UserPathError
        When ``out_dir`` is a file or a device, or cannot be created.
    """
    out = check_output_dir(out_dir, "figure folder")
    out.mkdir(parents=True, exist_ok=True)
    # File names from user text: a plain stem, and never outside ``out_dir`` (docs: README "Trust").
    prefix = safe_stem(prefix or result.scene.name)
    paths = []
    figures = [("phase", phase_portrait)] + [(k, (lambda kk: lambda r, ax: energy_vs_q(r, kk, ax))(k))
                                             for k in QUANTITIES] + [("energy-time", energy_vs_t)]
    for name, draw in figures:
        if only is not None and name not in only:
            continue
        fig = Figure(figsize=FIGSIZE, dpi=DPI)
        ax = fig.subplots()
        draw(result, ax)
        fig.tight_layout()
        path = out / f"{prefix}-{name}.png"
        if not inside(path, out):
            raise UserPathError(path, f"figure file name would leave the folder {out}")
        fig.savefig(path)
        paths.append(path)
    return paths
