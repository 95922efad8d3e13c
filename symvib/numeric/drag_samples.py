"""Samples of a run with air drag (physics.md, "Air drag"): :class:`DragSamples`.

A drag run (:mod:`symvib.numeric.drag_run`) logs its motion intervals; their samples
are the points of the same walks that timed them (:func:`symvib.numeric.drag_phase.pieces`,
each panel's Gauss nodes and its end), with the time, the friction work, the drag work
and the arc length cumulative along each walk.  The columns are those of
:class:`symvib.numeric.events.Samples` and ``W_drag``, the drag work since the start
(J), so that ``E + W_mu + W_impacts + W_drag = E0`` at every sample.

Examples
--------
>>> import symvib
>>> S = symvib.simulate(symvib.load_scene("paper-cycloid").replace(drag=0.1)).samples
>>> bool(abs(S.E + S.W_mu + S.W_impacts + S.W_drag - S.E[0]).max() < 1e-12 * S.E[0])
True
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from symvib.numeric.drag_phase import pieces
from symvib.numeric.events import Samples
from symvib.numeric.run_samples import column

__all__ = ["DragSamples", "samples"]


@dataclass(frozen=True)
class DragSamples(Samples):
    """:class:`~symvib.numeric.events.Samples` of a run with air drag, with ``W_drag`` [J], the
    drag work since the start (the cumulative quadrature of ``c w ds`` the energy budget sums)."""

    W_drag: np.ndarray


def samples(run, scene, mod, cp) -> DragSamples:
    """The samples of the logged intervals of ``run`` (a :class:`symvib.numeric.drag_run.DragInterval`
    list, ``run.intervals``), in time order."""
    cols = {k: [] for k in ("t", "q", "w", "N", "Wf", "Wd", "Wimp", "path", "s", "sigma", "interval", "branch")}
    c = run.c
    s_arc = path = 0.0
    for i, iv in enumerate(run.intervals):
        t, Wf, Wd, path0 = iv.t0, iv.Wf0, iv.Wd0, path
        _point(cols, iv.t0, iv.qa, iv.wa, mod, cp, scene.g, iv.Wf0, iv.Wd0, iv.Wimp0, path, path0, s_arc, iv, i)
        parts = pieces(c, iv.qa, iv.qb, iv.sigma, iv.s, iv.wa, iv.end_root, run.rtol, profile=True)
        for wk, back, _, _ in parts:
            tc, wfc, wdc, arc = wk.profile
            if back:   # from the turning point at qb against the motion: the totals at qb minus these
                order = np.arange(len(wk.q) - 2, -1, -1)   # (its last point is the previous walk's end)
                T_end, Wf_end, Wd_end = t + wk.T, Wf + wk.Wf, Wd + wk.Wd
                path_end = path + arc[-1]
                _extend(cols, T_end - tc[order], wk.q[order], wk.w[order], wk.N[order], Wf_end - wfc[order],
                        Wd_end - wdc[order], path_end - arc[order], path0, iv, i, s_arc)
                t, Wf, Wd, path = T_end, Wf_end, Wd_end, path_end
            else:
                _extend(cols, t + tc, wk.q, wk.w, wk.N, Wf + wfc, Wd + wdc, path + arc, path0, iv, i, s_arc)
                t, Wf, Wd, path = t + wk.T, Wf + wk.Wf, Wd + wk.Wd, path + arc[-1]
        _point(cols, iv.t0 + iv.T, iv.qb, 0.0 if iv.end_root else cols["w"][-1], mod, cp, scene.g, Wf, Wd,
               iv.Wimp0, path, path0, s_arc, iv, i)
        s_arc += iv.sigma * (path - path0)
    if not cols["t"]:
        return DragSamples(**{k: np.zeros(0, dtype=int if k in ("interval", "branch") else float)
                              for k in DragSamples.__dataclass_fields__})
    a = {k: np.concatenate([np.atleast_1d(np.asarray(v, dtype=float)) for v in vals]) for k, vals in cols.items()}
    q, w, N, sigma = a["q"], a["w"], a["N"], a["sigma"]
    m, mu = scene.m, scene.mu
    speed = np.sqrt(np.maximum(w, 0.0))
    v = sigma * speed
    h = column(mod.h(q, *cp), q)
    z = column(mod.z(q, *cp), q)
    Ep = m * scene.g * z
    friction = mu * m * np.abs(N)
    return DragSamples(t=a["t"], q=q, qdot=v / h, F_N=m * N, P_mu=-friction * speed, Ek=0.5 * m * w, Ep=Ep,
                       E=0.5 * m * w + Ep, interval=a["interval"].astype(int), branch=a["branch"].astype(int),
                       x=column(mod.x(q, *cp), q), z=z, s=a["s"], path=a["path"], v=v, F_mu=-sigma * friction,
                       W_mu=m * a["Wf"], W_impacts=a["Wimp"], W_drag=m * a["Wd"])


def _extend(cols, t, q, w, N, Wf, Wd, path, path0, iv, i, s_arc):
    n = len(q)
    for key, value in (("t", t), ("q", q), ("w", w), ("N", N), ("Wf", Wf), ("Wd", Wd), ("path", path),
                       ("s", s_arc + iv.sigma * (np.asarray(path) - path0)), ("sigma", np.full(n, float(iv.sigma))),
                       ("interval", np.full(n, float(i))), ("branch", np.full(n, float(iv.s))),
                       ("Wimp", np.full(n, iv.Wimp0))):
        cols[key].append(np.asarray(value, dtype=float))


def _point(cols, t, q, w, mod, cp, g, Wf, Wd, Wimp, path, path0, s_arc, iv, i):
    """One point (an interval's start or end): ``N = kappa w + g cos alpha`` from the kernels."""
    w = float(np.atleast_1d(w)[-1]) if np.ndim(w) else float(w)
    h = float(np.asarray(mod.h(q, *cp)))
    N = float(np.asarray(mod.kappa(q, *cp))) * w + g * float(np.asarray(mod.dx(q, *cp))) / h
    _extend(cols, [t], [q], [w], [N], [Wf], [Wd], [path], path0, iv, i, s_arc)
