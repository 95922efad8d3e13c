"""The phase trajectory with quadratic air drag, by quadrature (physics.md, "Air drag").

On a motion interval with direction ``sigma``, normal-force sign ``n`` and branch
``s = sigma n``, eq. 2 with drag is linear in ``w = v^2``:

    w(q) = exp(-Phi) [C - 2 g D(q)],   Phi = 2 s mu alpha + 2 sigma gamma S(q),
    S(q) = Integral h dq,   D(q) = Integral exp(Phi) (z' + s mu x') dq.

Neither ``S`` nor ``D`` has a closed form in general, so this module computes both
by Gauss-Legendre panels from the curve's generated kernels (``x'``, ``z'``, ``h``,
``alpha``, ``kappa``; no SymPy): a *walk* from an anchor point over a stretch of
``q`` in equal panels, every node of every panel at once (NumPy), with ``S`` and
``D`` cumulative (:attr:`symvib.numeric.quadrature.GaussRule.cumulative`) so that
``G = exp(Phi) w`` is known at every node.  ``Phi`` is measured from the anchor,
where it is 0, and only differences of ``alpha`` enter it (unwrapped across a
branch cut of the kernels' ``alpha``).

A walk from a turning point (``w = 0`` at the anchor) is taken in ``r``, ``q =
q_root + d L r^2``: there ``G`` grows like ``r^2``, the time's integrand ``h /
sqrt(w)`` times ``dq/dr`` is smooth, and ``G`` near the root keeps its relative
accuracy (its first panel integrates with the weighted cumulative matrix,
:attr:`~symvib.numeric.quadrature.GaussRule.cumulative_weighted`).  The time, the
friction work ``Integral mu |N| h dq`` and the drag work ``Integral gamma w h dq``
(both per unit mass) are sums over the same nodes; :func:`span` doubles the panels
until two counts agree on the time within ``rtol`` and returns the finer one
with the difference as its error estimate.

Examples
--------
>>> from symvib.numeric.kernels import load
>>> c = DragCurve.of(load("circle"), (0.5,), g=9.81, mu=0.0, gamma=0.0)
>>> T, Wf, Wd, w_end, err, ok = span(c, 0.0, 0.5, 1, 1, 4.0, False)
>>> bool(abs(w_end - (4.0 - 2 * 9.81 * 0.5 * (1 - math.cos(0.5)))) < 1e-13), ok   # energy conservation
(True, True)
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from symvib.numeric.quadrature import rule

__all__ = ["DragCurve", "Walk", "walk", "span", "pieces", "converged", "panels", "NODES", "PANEL", "MAX_PANELS",
           "DRAG_FOLD", "END_FOLD", "CHUNK_FOLD"]

#: Gauss-Legendre nodes per panel of a walk.
NODES = 16
#: Width of a walk's panels at first, a share of the run's length scale (``scan.curve_scale``).
PANEL = 0.125
#: Most panels :func:`span` doubles up to on one stretch; beyond, the time is not within its tolerance.
MAX_PANELS = 1 << 14
#: Most that ``2 gamma S`` grows over one panel (:meth:`DragCurve.panel`): half an e-fold of ``exp(Phi)``'s
#: drag factor per panel.
DRAG_FOLD = 0.5
#: How far (``2 gamma S``, e-folds of the drag factor) a walk back from a turning point that ends an
#: interval may go (:func:`span`): its ``G`` loses about ``exp(2 gamma S)`` of its relative accuracy.
END_FOLD = 1.0
#: E-folds of the drag factor after which a forward walk is anchored anew (:func:`span`).
CHUNK_FOLD = 64.0
#: Smallest relative tolerance :func:`span` asks of two panel counts' times (a few roundings of a sum).
FLOOR_RTOL = 1e-14


@dataclass(frozen=True)
class DragCurve:
    """A curve's kernels (vectorized and scalar) with a run's constants: ``g``, ``mu`` and
    ``gamma = c / m`` (physics.md, "Air drag")."""

    mod: object
    cp: tuple
    g: float
    mu: float
    gamma: float
    scale: float = 1.0
    cut: bool = False

    @classmethod
    def of(cls, mod, cp, *, g, mu, gamma, scale=1.0):
        return cls(mod, tuple(float(v) for v in cp), float(g), float(mu), float(gamma), float(scale),
                   bool(getattr(mod, "ALPHA_CUT", False)))

    def panel(self, q0: float) -> float:
        """The widest panel (in ``q``) of a walk from ``q0``: :data:`PANEL` of the length scale, and
        no more than the drag's e-folding share :data:`DRAG_FOLD` / (``gamma h``) (``exp(Phi)``
        then changes by at most ``e`` over a panel, which 16 nodes integrate to rounding)."""
        width = PANEL * self.scale
        if self.gamma > 0.0:
            h0 = abs(float(np.asarray(self.mod.h(q0, *self.cp), dtype=float)))
            if h0 > 0.0 and math.isfinite(h0):
                width = min(width, DRAG_FOLD / (self.gamma * h0))
        return width

    def local(self, q):
        """``(h, x', z', alpha, kappa)`` at the points ``q`` (arrays of ``q``'s shape)."""
        m, cp = self.mod, self.cp
        out = []
        for fn in (m.h, m.dx, m.dz, m.alpha, m.kappa):
            out.append(np.broadcast_to(np.asarray(fn(q, *cp), dtype=float), np.shape(q)))
        return out


@dataclass(frozen=True)
class Walk:
    """One walk: its points in the order walked (each panel's nodes, then its end), ``G`` and
    ``Phi`` there (from the anchor), ``w``, the normal force per unit mass ``N``, and the sums
    over the nodes: time, friction work and drag work per unit mass."""

    q: np.ndarray
    G: np.ndarray
    Phi: np.ndarray
    w: np.ndarray
    N: np.ndarray
    f: np.ndarray
    T: float
    Wf: float
    Wd: float
    #: With ``profile``: the time, friction work, drag work (per unit mass) and arc length from
    #: the anchor at every point (the samples of a run, :mod:`symvib.numeric.drag_samples`).
    profile: tuple | None = None


def walk(c: DragCurve, q0: float, d: int, length: float, sigma: int, s: int, G0: float, m: int,
         root: bool, nodes: int = NODES, profile: bool = False) -> Walk:
    """Walk ``length`` from ``q0`` in direction ``d`` in ``m`` panels (physics.md, "Air drag").

    ``sigma`` is the direction of motion and ``s`` the branch; ``d = sigma`` walks with the
    motion, ``d = -sigma`` against it (back from a turning point that ends an interval).
    ``G0`` is ``G = exp(Phi) w`` at ``q0`` (``Phi(q0) = 0``); ``root``: ``q0`` is a turning
    point (``G0 = 0``) and the walk is in ``r`` (``q = q0 + d length r^2``).

    With ``rho`` the distance walked, ``Phi = 2 s mu (alpha - alpha(q0)) + 2 sigma d gamma
    S(rho)`` and ``G = G0 - 2 g Integral_0^rho exp(Phi) d (z' + s mu x') drho'``.
    """
    R = rule(nodes)
    x = R.x
    k = np.arange(m, dtype=float)[:, None]
    u = np.concatenate(((k + (x[None, :] + 1.0) / 2.0) / m, (k + 1.0) / m), axis=1)   # (m, n + 1), last: end
    if root:
        rho = length * u * u
        jac = length * u[:, :-1] / m                 # drho/dx at the nodes
    else:
        rho = length * u
        jac = np.full((m, nodes), length / (2.0 * m))
    q = q0 + d * rho
    q[-1, -1] = q0 + d * length                      # the end exactly
    h, dx, dz, alpha, kappa = c.local(q)
    a0 = float(np.asarray(c.mod.alpha(q0, *c.cp), dtype=float))
    if c.cut:
        seq = np.unwrap(np.concatenate(([a0], alpha.ravel())))
        dalpha = (seq[1:] - a0).reshape(q.shape)
    else:
        dalpha = alpha - a0
    arc = _cumulative(R, h[:, :-1], jac, m, root, length)
    Phi = 2.0 * s * c.mu * dalpha + 2.0 * sigma * d * c.gamma * arc
    f = d * (dz + s * c.mu * dx)
    D = _cumulative(R, (np.exp(Phi) * f)[:, :-1], jac, m, root, length)
    G = G0 - 2.0 * c.g * D
    w = np.exp(-Phi) * G
    N = kappa * w + c.g * dx / h
    hn, wn, Nn, jn = h[:, :-1], w[:, :-1], N[:, :-1], jac
    with np.errstate(divide="ignore", invalid="ignore"):
        T = float(np.sum(R.weights * (hn / np.sqrt(wn)) * jn))
    Wf = float(np.sum(R.weights * c.mu * np.abs(Nn) * hn * jn))
    Wd = float(np.sum(R.weights * c.gamma * wn * hn * jn))
    cum = None
    if profile:
        with np.errstate(divide="ignore", invalid="ignore"):
            tc = _cumulative(R, hn / np.sqrt(wn), jac, m, root, length)
        cum = tuple(a.ravel() for a in (tc, _cumulative(R, c.mu * np.abs(Nn) * hn, jac, m, root, length),
                                        _cumulative(R, c.gamma * wn * hn, jac, m, root, length), arc))
    return Walk(q.ravel(), G.ravel(), Phi.ravel(), w.ravel(), N.ravel(), f.ravel(), T, Wf, Wd, cum)


def _cumulative(R, values, jac, m, root, length):
    """``Integral_0^rho values drho`` at every point of a walk's panels (nodes and ends), shape
    ``(m, n + 1)``: each panel's cumulative matrix, after the sum of the panels before it.  The
    first panel of a walk in ``r`` integrates ``values (x + 1)`` with the weighted matrix, which
    keeps the relative accuracy next to the root."""
    inner = (values * jac) @ R.cumulative.T
    totals = (values * jac) @ R.weights
    if root:
        first = values[0]
        inner[0] = length / (2.0 * m * m) * (R.cumulative_weighted @ first)
    before = np.concatenate(([0.0], np.cumsum(totals)[:-1]))
    ends = before + totals
    return np.concatenate((before[:, None] + inner, ends[:, None]), axis=1)


def panels(c: DragCurve, q0: float, length: float) -> int:
    """Panels of width at most :meth:`DragCurve.panel` over ``length`` from ``q0``."""
    return max(1, int(math.ceil(length / c.panel(q0))))


def converged(c, q0, d, length, sigma, s, G0, root, rtol, profile=False):
    """The walk of :func:`walk` with panels doubled until two counts agree on the time within
    ``rtol`` (and on the friction and drag work and the end's ``G`` to their rounding).

    Returns ``(walk, error, ok)``: the finer walk, the difference of the two times, and
    whether they agreed before :data:`MAX_PANELS`.
    """
    m = panels(c, q0, length)
    coarse = walk(c, q0, d, length, sigma, s, G0, m, root)
    tol = max(rtol, FLOOR_RTOL)
    while True:
        fine = walk(c, q0, d, length, sigma, s, G0, 2 * m, root, profile=profile)
        err = abs(fine.T - coarse.T)
        scale_w = abs(fine.Wf) + abs(fine.Wd) + abs(G0) + abs(fine.G[-1])
        if (err <= tol * fine.T and abs(fine.Wf - coarse.Wf) + abs(fine.Wd - coarse.Wd) <= tol * scale_w
                and abs(fine.G[-1] - coarse.G[-1]) <= tol * scale_w) or not math.isfinite(fine.T):
            return fine, err, math.isfinite(fine.T)
        m *= 2
        if 2 * m > MAX_PANELS:
            return fine, err, False
        coarse = fine


def span(c: DragCurve, qa: float, qe: float, sigma: int, s: int, wa: float, end_root: bool,
         rtol: float = 1e-12):
    """Time, friction work and drag work (per unit mass) from ``qa`` (squared speed ``wa``) to
    ``qe`` moving ``sigma`` on branch ``s``, and ``w`` at ``qe`` (physics.md, "Air drag", "Time").

    A turning point at either end (``wa == 0``, or ``end_root``) takes that half of the
    stretch walked in ``r`` from the root (anchored there: ``G = 0``), so the time's
    inverse square root is integrated without loss; the two halves meet at the midpoint.
    Walked back from a root at the end, ``G`` is a difference of terms that grow like
    ``exp(2 gamma S)``, so that walk is at most :data:`END_FOLD` e-folds of the drag
    long; the walk from the start (forward, where nothing cancels) takes the rest.

    Returns ``(T, W_friction, W_drag, w_end, T_err, ok)``.
    """
    length = abs(qe - qa)
    if length == 0.0:
        return 0.0, 0.0, 0.0, (0.0 if end_root else wa), 0.0, True
    T = Wf = Wd = err = 0.0
    ok = True
    w_end = wa
    for wk, back, e, good in pieces(c, qa, qe, sigma, s, wa, end_root, rtol):
        T, Wf, Wd, err, ok = T + wk.T, Wf + wk.Wf, Wd + wk.Wd, err + e, ok and good
        w_end = 0.0 if back else float(wk.w[-1])
    return T, Wf, Wd, w_end, err, ok


def pieces(c: DragCurve, qa: float, qe: float, sigma: int, s: int, wa: float, end_root: bool,
           rtol: float = 1e-12, profile: bool = False) -> list:
    """The walks :func:`span` sums, in the order of motion: ``[(walk, back, error, ok)]``, ``back``
    for the last one when it is walked back from a turning point at ``qe`` (its points then run
    from ``qe`` against the motion).  A first walk from a turning point at ``qa`` is in ``r``; the
    forward ones are anchored anew every :data:`CHUNK_FOLD` e-folds of the drag factor.
    """
    length = abs(qe - qa)
    out = []
    if length == 0.0:
        return out
    end_len = 0.0
    if end_root:
        # Walked back from the root, G is a difference of terms exp(2 gamma S) as large as itself:
        # that walk stays within END_FOLD e-folds of the root (forward walks do not cancel).
        end_len = 0.5 * length
        h_end = abs(float(np.asarray(c.mod.h(qe, *c.cp), dtype=float)))
        if c.gamma > 0.0 and h_end > 0.0:
            end_len = min(end_len, END_FOLD / (2.0 * c.gamma * h_end))
    qm = qe - sigma * end_len
    q, w = qa, wa
    if wa == 0.0:
        first_len = min(0.5 * length, abs(qm - qa))
        if c.gamma > 0.0:
            first_len = min(first_len, CHUNK_FOLD * c.panel(qa) / DRAG_FOLD)
        wk, err, ok = converged(c, qa, sigma, first_len, sigma, s, 0.0, True, rtol, profile)
        out.append((wk, False, err, ok))
        q, w = qa + sigma * first_len, float(wk.w[-1])
    while (qm - q) * sigma > 0.0:
        room = abs(qm - q)
        step = min(room, CHUNK_FOLD * c.panel(q) / DRAG_FOLD) if c.gamma > 0.0 else room
        last = step >= room
        wk, err, ok = converged(c, q, sigma, room if last else step, sigma, s, w, False, rtol, profile)
        out.append((wk, False, err, ok))
        if last or not ok:
            break
        q, w = q + sigma * step, float(wk.w[-1])
    if end_root:
        wk, err, ok = converged(c, qe, -sigma, end_len, sigma, s, 0.0, True, rtol, profile)
        out.append((wk, True, err, ok))
    return out
