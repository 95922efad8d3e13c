"""Exact derivatives of a run's events with respect to its parameters (physics.md, "Sensitivities").

Every event of a run is defined by a closed-form condition on the phase trajectory
(paper eq. 2): an impact where the particle reaches a limiter, a turning point
where ``G(q) = C - 2 g F_s(q)`` vanishes, and so on.  So the derivatives of an
event's position, speeds and time with respect to ``mu``, ``k``, the initial
state and the limiters follow from the implicit function theorem, interval by
interval, with the jumps at impacts and reversals carried through; nothing is
differenced.  Within an interval on branch ``s`` that starts at ``(q_a, w_a)``,
with ``E(q) = exp(2 s mu alpha(q))`` and ``f = F_s' = E (z' + s mu x')``:

    G(q)  = w_a E(q_a) - 2 g Integral_{q_a}^{q} f du,          w(q) = G(q) / E(q),
    dG/dp = D(w_a E(q_a)) + 2 g f(q_a) Dq_a - 2 g Dmu Integral_{q_a}^{q} df/dmu du,

and at its end ``q_e``: a limiter, ``Dq_e = D(limiter)``; a turning point
(``G(q*) = 0``), ``Dq* = (dG/dp)(q*) / (2 g f(q*))``, and ``w`` stays 0.  The
time ``T = Integral h dq / sqrt(w)`` is differentiated on ``q = q_a + (q_e -
q_a) u`` at fixed ``u``; the total derivative of ``w`` along the interval
vanishes at an end where ``w = 0``, so the derivative's integrand has the same
inverse-square-root ends as ``T``'s, which ``u = (1 - cos theta) / 2`` removes
(Gauss-Legendre panels in ``theta``, refined until two levels agree).

An impact maps ``w -> k^2 w``; the impact loss and (by the energy budget) the
friction work follow.  Where an event is not differentiable the table says so
instead of a number: a turning point on the friction cone's edge (arrest or
reversal changes with the parameters: the rest test's cone, ``|tan alpha| = mu_s``), a
turning point on the sliding cone's edge ``|tan alpha| = mu`` where static friction
exceeds it (a double root of ``G``: its position has no derivative), a turning point on a limiter (grazing),
a Zeno accumulation, a start at rest for ``qdot0`` (its sign chooses the
direction), and a tangential zero of the normal force.  A sign change of the normal force
that crosses (:mod:`symvib.numeric.sensitivity_normal`) and the curve's own parameters
(:mod:`symvib.numeric.sensitivity_curve`) are differentiated with the curve's jets
(:mod:`symvib.numeric.jet_kernels`; physics.md, "Sensitivities" 8 and 9), read only then.
On a unilateral curve the lift-off, the flight and its landings follow in closed form
(:mod:`symvib.numeric.sensitivity_flight`; physics.md, "Sensitivities" 10); a tangential landing, one on
the edge between sticking and sliding, and a bouncing-ball accumulation have no derivative.

Examples
--------
>>> from symvib import simulate
>>> res = simulate("paper-parabola")
>>> sens = sensitivities(res, wrt=("mu", "qdot0"))
>>> sens.events[0].kind.value, round(float(sens.t[0, 1]), 6)   # d t / d qdot0: faster, earlier
('impact', -0.027878)
>>> round(float(sens.final["t_final"][0]), 3)                  # d t_arrest / d mu
139.592
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

# Kinds and statuses by their engine codes (symvib.numeric.layout, below the records of
# symvib.numeric.events, whose Result.sensitivities calls up into this module).
from symvib.kernelformat import KernelError
from symvib.numeric.layout import EventCode, StatusCode
from symvib.numeric.sensitivity_batch import (
    ACCEPT,
    INNER_NODES,
    INTEGRAL_RTOL,
    MAX_PANELS,
    NODES,
    RTOL,
    end_integrals,
    gauss,
    time_derivatives,
)
from symvib.numeric.sensitivity_curve import PARAMETERS, CurveFunctions, resolve_wrt
from symvib.numeric.sensitivity_flight import land, landing_reason, launch
from symvib.numeric.sensitivity_normal import TANGENTIAL_N_REASON, normal_sign_change_tangent
from symvib.numeric.sensitivity_table import Sensitivities

__all__ = ["sensitivities", "interval_tangents", "Sensitivities", "Tangents", "Leg", "PARAMETERS"]

#: Relative distance of ``|sin alpha|`` from ``mu_s |cos alpha|`` (or ``mu |cos alpha|``) below which a
#: turning point is on the edge of the static (or sliding) friction cone (the engine's rest test, with
#: ``mu_s``, decides there within ``1e-9``).
CONE_EDGE = 1e-7
#: Distance of a turning point from a limiter, in units of ``q_scale``, below which it grazes it.
GRAZING = 1e-9
#: Statuses whose final state has derivatives (the run ended on an event).
FINAL_STATUSES = (StatusCode.ARRESTED, StatusCode.RESTING_ON_LIMITER)


class _Interval:
    """One motion interval from ``(q_a, w_a)`` to ``q_e`` on branch ``s``, with the tangents of its start.

    ``G``, its total derivative along the interval and ``F_s'`` differences are integrals from an
    anchor, the start for ``u <= 1/2`` and the end beyond: next to a turning point ``G`` is a small
    difference of ``F_s`` values, and an integral of ``F_s'`` from the root keeps its relative
    accuracy where a difference of two ``F_s`` would not.
    """

    def __init__(self, curve, q_a, w_a, q_e, s, turning_end, Dq_a=None, Dw_a=None, Dmu=None, G_e=None,
                 I_p_e=None, ends=None):
        c = curve
        self.c, self.q_a, self.q_e, self.s, self.turning_end = c, q_a, q_e, s, turning_end
        self.w_a = w_a
        # (``ends``: the kernels at both ends, from a caller that evaluates them for many intervals at once)
        alpha_a, dalpha_a, f_a, f_e, F_a, F_e, alpha_e, dalpha_e = ends or (
            float(c.alpha(q_a)), float(c.dalpha(q_a)), float(c.f(s, q_a)), float(c.f(s, q_e)), c.F(s, q_a),
            c.F(s, q_e), c.alpha(np.array([q_e])), c.dalpha(np.array([q_e])))
        self.E_a = math.exp(2 * s * c.mu * alpha_a)
        self.G_a = w_a * self.E_a
        self.alpha_a, self.dalpha_a, self.f_a, self.f_e = alpha_a, dalpha_a, f_a, f_e
        if I_p_e is None:       # (given by a caller that integrates many intervals at once)
            I_p_e = self.integral(lambda q: c.df_dp(s, q), q_a, q_e - q_a) if c.f_depends else 0.0
        self.I_p_e = I_p_e
        if G_e is None:
            G_e = 0.0 if turning_end else self.G_a - 2 * c.g * float(F_e - F_a)
        self.G_e = G_e
        self.alpha_e, self.dalpha_e, self.E_e = alpha_e, dalpha_e, np.exp(2 * s * c.mu * alpha_e)
        if Dq_a is not None:
            self.set_start(Dq_a, Dw_a, Dmu)

    def set_start(self, Dq_a, Dw_a, Dmu):
        """The start's tangents ``Dq_a``, ``Dw_a`` (and ``Dmu``): the total derivative of ``G`` there."""
        c, s = self.c, self.s
        self.Dq_a, self.Dw_a, self.Dmu = Dq_a, Dw_a, Dmu
        # total derivative of G at the start: D(w_a E(q_a)), alpha's own derivative in a curve parameter too
        self.DG_a = Dw_a * self.E_a + self.G_a * 2 * s * (self.alpha_a * Dmu + c.mu * self.dalpha_a * Dq_a
                                                            + c.mu * c.geometry_dp("alpha", self.q_a)[0])
        # dG/dp at fixed q, the part that does not depend on q: (dG/dp)(q) = A - 2 g I_p(q), with
        # I_p(q) = Integral_{q_a}^{q} dF_s'/dp (mu and the curve's parameters)
        self.A = self.DG_a + 2 * c.g * self.f_a * Dq_a

    def end_state(self):
        """``w`` at the end and its total derivative there (shape (P,)): :meth:`along` at ``u = 1``, where
        every integral from the end is empty."""
        c, s = self.c, self.s
        W = (self.DG_e - self.G_e * 2 * s * (np.outer(self.alpha_e, self.Dmu) + c.mu * self.dalpha_e[:, None]
                                             * self.Dq_e[None, :] + c.mu * c.geometry_dp("alpha", self.q_e)))
        return float((self.G_e / self.E_e)[0]), (W / self.E_e[:, None])[0]

    def dG_fixed_q_end(self):
        """``dG/dp`` at fixed ``q = q_e``."""
        return self.A - 2 * self.c.g * self.I_p_e

    def set_end(self, Dq_e):
        """The end's tangent ``Dq_e``; the total derivative of ``G`` there (0 at a turning point)."""
        self.Dq_e = Dq_e
        self.DG_e = np.zeros_like(Dq_e) if self.turning_end else \
            self.dG_fixed_q_end() - 2 * self.c.g * self.f_e * Dq_e

    @staticmethod
    def cumulative(fn, anchor, D, x_sorted):
        """``Integral_{anchor}^{anchor + D x} fn(q) dq`` at offsets ``x_sorted`` (ascending, from 0): a
        fixed Gauss rule between neighbours, summed.  Integrated in the offset, whose differences
        keep their relative accuracy next to the anchor where differences of ``q`` would not."""
        x, w = gauss(INNER_NODES)
        ends = np.concatenate(([0.0], x_sorted))
        a, b = ends[:-1], ends[1:]
        mid, half = (a + b) / 2, (b - a) / 2
        nodes = anchor + D * (mid[:, None] + half[:, None] * x[None, :])
        vals = np.asarray(fn(nodes.ravel()))
        vals = vals.reshape(nodes.shape + vals.shape[1:])          # (pieces, nodes[, parameters])
        sums = np.moveaxis(vals, 1, -1) @ w
        return D * np.cumsum(half.reshape((-1,) + (1,) * (sums.ndim - 1)) * sums, axis=0)

    @classmethod
    def integral(cls, fn, anchor, D):
        """``Integral_{anchor}^{anchor + D} fn(q) dq``: :meth:`cumulative` over 8, 16, ... equal pieces
        until two agree to rounding (``INTEGRAL_RTOL`` of the integral of ``|fn|``); ``fn`` may give
        one column per parameter (then each column to its own magnitude)."""
        pieces, previous = 8, None
        while pieces <= MAX_PANELS * NODES:
            x = np.arange(1, pieces + 1) / pieces
            current = cls.cumulative(fn, anchor, D, x)[-1]
            magnitude = abs(cls.cumulative(lambda v: np.abs(fn(v)), anchor, D, x)[-1])
            if previous is not None and np.all(np.abs(current - previous)
                                               <= INTEGRAL_RTOL * np.maximum(magnitude, 1e-300)):
                return current
            previous, pieces = current, 2 * pieces
        return previous

    def along(self, u, d=None):
        """``w`` and its total derivative ``W = D[w(q(u))]`` at the nodes ``u`` (any order; ``d = 1 - u``,
        given exactly where the caller has it), each from its nearer anchor."""
        c, s = self.c, self.s
        d = 1.0 - u if d is None else d
        delta = self.q_e - self.q_a
        q = np.where(u <= 0.5, self.q_a + delta * u, self.q_e - delta * d)
        Dq = np.outer(1 - u, self.Dq_a) + np.outer(u, self.Dq_e)
        G = np.empty_like(u)
        DG = np.empty((len(u), len(self.Dq_a)))
        for from_start in (True, False):
            pick = np.flatnonzero(u <= 0.5) if from_start else np.flatnonzero(u > 0.5)
            if not len(pick):
                continue
            offset = u[pick] if from_start else d[pick]
            order = pick[np.argsort(offset)]
            x = np.sort(offset)
            q_c, D, G_c, DG_c, f_c = ((self.q_a, delta, self.G_a, self.DG_a, self.f_a) if from_start
                                      else (self.q_e, -delta, self.G_e, self.DG_e, self.f_e))
            int_f = self.cumulative(lambda v: c.f(s, v), q_c, D, x)
            int_df = self.cumulative(lambda v: c.df(s, v), q_c, D, x)          # f(q) - f(q_c)
            G[order] = G_c - 2 * c.g * int_f
            # Dq(u) - Dq(anchor): u (Dq_e - Dq_a) from the start, -(1 - u) (Dq_e - Dq_a) from the end
            step = np.outer(x if from_start else -x, self.Dq_e - self.Dq_a)
            dg = DG_c - 2 * c.g * (int_df[:, None] * Dq[order] + f_c * step)
            if c.f_depends:
                dg -= 2 * c.g * self.cumulative(lambda v: c.df_dp(s, v), q_c, D, x)
            DG[order] = dg
        alpha, dalpha = c.alpha(q), c.dalpha(q)
        E = np.exp(2 * s * c.mu * alpha)
        W = (DG - G[:, None] * 2 * s * (np.outer(alpha, self.Dmu) + c.mu * dalpha[:, None] * Dq
                                        + c.mu * c.geometry_dp("alpha", q))) / E[:, None]
        return G / E, W, q, Dq

    def dT(self):
        """Derivative of the interval's duration (shape (P,)), or None when the refinement fails."""
        c = self.c
        delta = self.q_e - self.q_a
        sigma = 1.0 if delta > 0 else -1.0
        length = abs(delta)
        d_delta = self.Dq_e - self.Dq_a
        x, wts = gauss(NODES)

        def integral(panels):
            edges = np.linspace(0.0, math.pi, panels + 1)
            a, b = edges[:-1], edges[1:]
            theta = (((a + b) / 2)[:, None] + ((b - a) / 2)[:, None] * x[None, :]).ravel()
            weights = (((b - a) / 2)[:, None] * wts[None, :]).ravel() * np.sin(theta) / 2
            u, d = np.sin(theta / 2) ** 2, np.cos(theta / 2) ** 2      # u and 1 - u, each to its last bit
            w, W, q, Dq = self.along(u, d)
            h, dh = c.h(q), c.dh(q)
            root = np.sqrt(w)
            # h at fixed u moves with q(u) and, for a curve parameter, with the parameter itself
            J = ((dh[:, None] * Dq * length + (h * sigma)[:, None] * d_delta[None, :]
                  + c.geometry_dp("h", q) * length) / root[:, None]
                 - 0.5 * (h * length)[:, None] * W / (w * root)[:, None])
            return weights @ J, weights @ np.abs(J)

        # Differences of two levels relative to the integral of |integrand|: a column that is 0
        # (a parameter the interval does not see), or a small difference of two large terms (a
        # short swing between two turning points), converges to rounding noise, not to 0.  Next to
        # the roots the rounding grows as panels shrink, so the level whose difference from the
        # one before is smallest is kept once no level reaches RTOL, if it is within ACCEPT.
        panels = 2
        previous, _ = integral(panels)
        best, best_gap = None, math.inf
        while panels < MAX_PANELS:
            panels *= 2
            current, magnitude = integral(panels)
            if not np.all(np.isfinite(current)):
                return None
            gap = float(np.max(np.abs(current - previous) / np.maximum(magnitude, 1e-300)))
            if gap <= RTOL:
                return current
            if gap < best_gap:
                best, best_gap = previous, gap
            previous = current
        return best if best_gap <= ACCEPT else None

    def position_tangent(self, q, qdot, Dt_a, Dt_e):
        """``Dq`` at fixed time of the point ``q`` inside the interval (``qdot`` its speed there, ``Dt_a``,
        ``Dt_e`` the tangents of the start and end times), or None when the time quadrature fails.

        The time from the nearer end to ``q`` is the duration of a piece of the interval whose ends
        move with that end's tangent (fixed distance ``xi`` from it): ``t = t_c +- tau(xi; p)``, so at
        fixed ``t``, ``Dq = Dq_c - qdot (Dt_c +- D tau)`` (physics.md, "Sensitivities" 7).  Next to a
        turning point the piece starts or ends on it, and ``D tau`` stays finite where the derivative
        of ``t(q)`` at fixed ``q`` (``-Dq / qdot``) would not.
        """
        c, s = self.c, self.s
        from_start = abs(q - self.q_a) <= abs(q - self.q_e)
        q_c, Dq_c, Dt_c = (self.q_a, self.Dq_a, Dt_a) if from_start else (self.q_e, self.Dq_e, Dt_e)
        if q == q_c:
            return Dq_c - qdot * Dt_c
        G, Dw = self.point(q, Dq_c, from_start)
        if from_start:
            piece = _Interval(c, self.q_a, self.w_a, q, s, False, self.Dq_a, self.Dw_a, self.Dmu, G_e=G)
        else:
            w = G / math.exp(2 * s * c.mu * float(c.alpha(q)))
            piece = _Interval(c, q, w, self.q_e, s, self.turning_end, self.Dq_e, Dw, self.Dmu, G_e=self.G_e)
        piece.set_end(Dq_c)
        dtau = piece.dT()
        if dtau is None:
            return None
        return Dq_c - qdot * (Dt_c + dtau if from_start else Dt_c - dtau)

    def point(self, q, Dq, from_start):
        """``G(q)`` and the total derivative of ``w`` at ``q`` moving with tangent ``Dq``, integrated from
        the start (``from_start``) or the end: ``G(q) = G_c - 2 g Integral_{q_c}^{q} f`` and
        ``DG = DG_c - 2 g (f(q) Dq - f(q_c) Dq_c + Integral_{q_c}^{q} dF_s'/dp)``."""
        c, s = self.c, self.s
        q_c, G_c, DG_c, f_c, Dq_c = ((self.q_a, self.G_a, self.DG_a, self.f_a, self.Dq_a) if from_start
                                     else (self.q_e, self.G_e, self.DG_e, self.f_e, self.Dq_e))
        G = G_c - 2 * c.g * self.integral(lambda v: c.f(s, v), q_c, q - q_c)
        DG = DG_c - 2 * c.g * (float(c.f(s, q)) * Dq - f_c * Dq_c)
        if c.f_depends:
            DG = DG - 2 * c.g * self.integral(lambda v: c.df_dp(s, v), q_c, q - q_c)
        alpha, dalpha = float(c.alpha(q)), float(c.dalpha(q))
        E = math.exp(2 * s * c.mu * alpha)
        return G, (DG - G * 2 * s * (alpha * self.Dmu + c.mu * dalpha * Dq + c.mu * c.geometry_dp("alpha", q)[0])) / E


def sensitivities(result, wrt=PARAMETERS, *, prepared=None, through=None) -> Sensitivities:
    """Derivatives of ``result``'s events and final state with respect to ``wrt``.

    Parameters and errors as :func:`interval_tangents`, whose ``sensitivities`` this is.

    Returns
    -------
    Sensitivities
        The record (:mod:`symvib.numeric.sensitivity_table`).
    """
    return interval_tangents(result, wrt, prepared=prepared, through=through).sensitivities


@dataclass(frozen=True)
class Leg:
    """One motion interval of a differentiated run, from event time ``t_a`` (0 for the start) to
    ``t_e``, with the tangents ``Dt_a``, ``Dt_e`` of those times (shape (parameters,)); its
    :meth:`position_tangent` differentiates a position inside it at fixed time."""

    interval: object
    t_a: float
    t_e: float
    Dt_a: np.ndarray
    Dt_e: np.ndarray

    def position_tangent(self, q, qdot):
        """``Dq`` at fixed time of the point ``q`` (speed ``qdot``) inside the leg, or None."""
        return self.interval.position_tangent(q, qdot, self.Dt_a, self.Dt_e)


@dataclass(frozen=True)
class Tangents:
    """A differentiated run: its :class:`Sensitivities` and the :class:`Leg` of every motion interval up
    to the first event without derivatives (in time order)."""

    sensitivities: Sensitivities
    legs: tuple


def interval_tangents(result, wrt=PARAMETERS, *, prepared=None, jets=None, through=None) -> Tangents:
    """Derivatives of ``result``'s events and final state with respect to ``wrt``, and its intervals.

    Parameters
    ----------
    result : symvib.numeric.events.Result
        A run of :func:`symvib.simulate` (its scene and events are read; nothing runs again).
    wrt : str or sequence of str
        Names from :data:`PARAMETERS` (``left``/``right`` only where the scene has that limiter) or
        of the curve's parameters (:func:`symvib.numeric.sensitivity_curve.resolve_wrt`: a name that is
        both is refused, ``parameters.<name>`` is the curve's); one name alone is one parameter.
    prepared : Prepared, optional
        The scene's prepared curve (default: :func:`symvib.numeric.prepared.prepared_of`).
    jets : module, optional
        The curve's jets module (default: :func:`symvib.numeric.jet_kernels.load_jets`, read only when a
        sign change of ``N`` or a curve parameter needs it).
    through : int, optional
        The index of the last event to differentiate (default: all): the later events' rows are NaN,
        their reason says they were not asked for, and so is the final state unless it is the last
        event.  The events up to it are the same numbers as without it (a fit that matches the
        first events asks for those only).

    Returns
    -------
    Tangents

    Raises
    ------
    ValueError
        Naming ``wrt`` for an unknown, repeated or ambiguous parameter or a missing limiter, and
        ``result`` for a failed run (its numbers are not a result), ``through`` for a negative or
        not whole index.

    Notes
    -----
    Four passes: the run's path in scalars (each interval's ends, branch and ``w``); the integrals
    of ``dF_s'/dp`` over every interval at once; the tangents of positions and speeds, event by
    event; the time derivatives of every interval at once
    (:mod:`symvib.numeric.sensitivity_batch`).  Only the first and third are loops over events.
    """
    from symvib.numeric.prepared import prepared_of

    scene = result.scene
    targets = resolve_wrt(scene, wrt)
    wrt = tuple(t[0] for t in targets)
    if result.status.is_error:
        raise ValueError(f"result: the run failed ({result.status.value}); its events have no derivatives")
    if getattr(scene, "drag", 0.0):
        raise ValueError("result: a run with air drag (physics.drag) has no sensitivities yet: the derivatives of "
                         "physics.md, \"Sensitivities\" are those of the drag-free phase trajectory")
    kernels = (prepared or prepared_of(scene)).kernels
    if jets is None:
        from symvib.numeric.jet_kernels import load_jets

        jets = lambda: load_jets(scene.shape)  # noqa: E731 - loaded only if needed
    c = CurveFunctions(kernels, scene, targets, jets)
    P = len(wrt)
    unit = {name: np.zeros(P) for name in PARAMETERS}
    for j, (_, kind, p) in enumerate(targets):
        if kind == "scene":
            unit[p] = np.eye(P)[j]
    Dmu, Dk = unit["mu"], unit["k"]
    limiter_D = {scene.left: unit["left"], scene.right: unit["right"]}

    q_a, qdot0 = scene.q0, scene.qdot0
    h0, dh0 = float(c.h(q_a)), float(c.dh(q_a))
    w_a = h0 ** 2 * qdot0 ** 2
    Dq_a = unit["q0"].copy()
    Dw_a = (2 * h0 ** 2 * qdot0 * unit["qdot0"] + 2 * h0 * dh0 * qdot0 ** 2 * unit["q0"]
            + 2 * h0 * qdot0 ** 2 * c.geometry_dp("h", q_a)[0])
    notes = {}
    if qdot0 == 0 and "qdot0" in [t[2] for t in targets if t[1] == "scene"]:
        notes[next(t[0] for t in targets if t[1:] == ("scene", "qdot0"))] = \
            "the run starts at rest: the sign of qdot0 chooses the direction (no derivative)"
    DE0 = c.m * (Dw_a / 2 + c.g * (float(c.dz(q_a)) * Dq_a + c.geometry_dp("z", q_a)[0]))

    n = len(result.events)
    last = n - 1 if through is None else _checked_through(through, n)
    events = result.events
    path = _Path(q_a, w_a, Dq_a, Dw_a, np.zeros(P), 0.0, tuple(np.full((n, P), np.nan) for _ in range(4)), [],
                 np.zeros(P), np.zeros(P))
    units = (Dmu, Dk, limiter_D)
    i, broken, first, flight = 0, "", None, None
    while i <= last and not broken:
        ev = events[i]
        if ev.kind.code != EventCode.LANDING:       # sliding, up to a lift-off or a landing
            i, broken, first, flight = _slide(c, scene, events, i, last, path, units)
            continue
        broken = _not_differentiable(ev, scene, c, EventCode.LANDING)   # physics.md, "Sensitivities" 10
        landed = broken or land(c, scene, flight, ev.t, ev.q)
        if isinstance(landed, str):
            broken, first = landed, i
            break
        for column, value in zip(path.table, (landed.Dt, landed.Dq, landed.Dv_before, landed.Dv_after)):
            column[i] = value
        path.D_landing_loss += landed.D_loss
        flight = landed.bounce
        if flight is None:              # sliding resumes from the landing point
            path.q, path.w, path.Dq, path.Dw = landed.q, landed.w, landed.Dq, landed.Dw
            path.Dt, path.t = landed.Dt, ev.t
        i += 1
    T, Q, VB, VA = path.table
    reasons = [""] * (first if broken else last + 1)
    if broken:
        reasons += _reasons_after(events[first:last + 1], first, broken, scene, c, path.q)
    reasons += [f"not asked for: after event {last} (through={last})"] * (n - 1 - last)
    final_names = ("t_final", "q_final", "friction_work", "impact_loss") + (
        ("landing_loss",) if scene.contact == "unilateral" else ())
    final = {name: np.full(P, np.nan) for name in final_names}
    if not broken and n and last == n - 1 and result.status.code in FINAL_STATUSES:
        q_f = events[-1].q
        DE_final = c.m * (path.Dw / 2 + c.g * (float(c.dz(q_f)) * path.Dq + c.geometry_dp("z", q_f)[0]))
        final.update(t_final=T[-1].copy(), q_final=Q[-1].copy(), impact_loss=path.D_impact_loss,
                     friction_work=DE0 - DE_final - path.D_impact_loss - path.D_landing_loss)
        if "landing_loss" in final:
            final["landing_loss"] = path.D_landing_loss
    for name in notes:
        j = wrt.index(name)
        for column in (T, Q, VB, VA, *final.values()):
            column[..., j] = np.nan
    sens = Sensitivities(wrt, tuple(events), T, Q, VB, VA, tuple(reasons), final, notes)
    return Tangents(sens, tuple(path.legs))


@dataclass
class _Path:
    """Where the differentiation of a run is: the particle's position and ``w`` after the last event
    differentiated and their tangents, that event's time and time tangent, the table's columns
    ``(T, Q, VB, VA)`` so far, the legs, and the tangents of the impact and landing losses."""

    q: float
    w: float
    Dq: np.ndarray
    Dw: np.ndarray
    Dt: np.ndarray
    t: float
    table: tuple
    legs: list
    D_impact_loss: np.ndarray
    D_landing_loss: np.ndarray


def _slide(c, scene, events, start, last, path, units):
    """Differentiate the sliding events from ``start`` on, up to a lift-off (included), a landing (not
    included) or ``last``, in four passes (:func:`interval_tangents`), advancing ``path``.

    Returns the next event's index, why the derivatives end (empty if they go on), the index of the
    first event without them, and the flight launched at a lift-off (or None).
    """
    Dmu, Dk, limiter_D = units
    T, Q, VB, VA = path.table
    P = len(Dmu)
    # 1. the run's path, event by event, in scalars: each interval's ends, branch and w before and after
    plan, first, broken = _plan(events, start, last, scene, c, path.q, path.w)
    # 2. the integrals of dF_s'/dp over whole intervals, all at once (they need no tangent)
    if c.f_depends:
        for s, group in _by_branch([p[4] for p in plan]):
            q0s, D = np.array([iv.q_a for iv in group]), np.array([iv.q_e - iv.q_a for iv in group])
            for iv, I_p_e in zip(group, end_integrals(c, s, q0s, D, MAX_PANELS * NODES)):
                iv.I_p_e = I_p_e
    # 3. the tangents of the events' positions and speeds, event by event (no quadrature left)
    Dq_a, Dw_a, lift = path.Dq, path.Dw, None
    D_impact_loss = np.zeros(P)
    for j, (i, ev, kind, turning, iv, w_minus) in enumerate(plan):
        if iv is None:                      # no motion in between (a rest test at the start)
            Dq_e, Dw_minus = Dq_a.copy(), Dw_a.copy()
        else:
            iv.set_start(Dq_a, Dw_a, Dmu)
            if turning:
                Dq_e = iv.dG_fixed_q_end() / (2 * c.g * iv.f_e)
            elif kind in (EventCode.NORMAL_SIGN_CHANGE, EventCode.LIFT_OFF):
                try:
                    Dq_e = normal_sign_change_tangent(c, iv)
                except KernelError as err:     # (a user curve's jets not generated where this runs)
                    Dq_e, why = None, f"the curve's jets (kappa') are not available here: {err}"
                else:
                    why = TANGENTIAL_N_REASON
                if Dq_e is None:
                    plan, first, broken = plan[:j], i, why
                    break
            else:
                Dq_e = limiter_D.get(ev.q, np.zeros(P)) if kind in (EventCode.IMPACT, EventCode.REST_ON_LIMITER) \
                    else np.zeros(P)
            iv.set_end(Dq_e)
            Dw_minus = np.zeros(P) if turning else iv.end_state()[1]
        sigma_in = 1.0 if ev.qdot_before >= 0 else -1.0
        v_minus = sigma_in * math.sqrt(max(w_minus, 0.0))
        Dv_minus = sigma_in * Dw_minus / (2 * math.sqrt(w_minus)) if w_minus > 0 else np.zeros(P)
        if kind == EventCode.IMPACT:
            k = scene.k
            Dw_plus = 2 * k * Dk * w_minus + k * k * Dw_minus
            Dv_plus = -(Dk * v_minus + k * Dv_minus)
            D_impact_loss = D_impact_loss + c.m / 2 * (-2 * k * Dk * w_minus + (1 - k * k) * Dw_minus)
        else:   # a turning point, or a sign change of N: w goes on (the branch flips with N)
            Dw_plus, Dv_plus = Dw_minus, (np.zeros(P) if turning else Dv_minus)
        Q[i], VB[i], VA[i] = Dq_e, Dv_minus, Dv_plus
        Dq_a, Dw_a = Dq_e, Dw_plus
        if kind == EventCode.LIFT_OFF:
            lift = (ev.q, v_minus, Dq_e, Dv_plus)
    # 4. the time derivatives of all intervals at once; the first that fails ends the derivatives
    dT = np.zeros((len(plan), P))
    for lo in range(0, len(plan), CHUNK):      # (in chunks: none computed after one that fails)
        rows = [lo + r for r, p in enumerate(plan[lo:lo + CHUNK]) if p[4] is not None]
        if rows:
            ends = {name: np.array([getattr(plan[r][4], name) for r in rows]) for name in BATCH_FIELDS}
            dT[rows] = time_derivatives(c, ends)
        if not np.all(np.isfinite(dT[lo:lo + CHUNK])):
            break
    failed = np.flatnonzero(~np.all(np.isfinite(dT), axis=1))
    if len(failed):
        j = int(failed[0])
        plan, first, broken = plan[:j], plan[j][0], "the time derivative's quadrature did not converge"
    if broken and first is not None:       # (the rows pass 3 wrote past the first event without derivatives)
        for column in (Q, VB, VA):
            column[first:last + 1] = np.nan
    for j, (i, ev, _, _, iv, _) in enumerate(plan):
        Dt_e = path.Dt + dT[j]
        T[i] = Dt_e
        if iv is not None:
            path.legs.append(Leg(iv, path.t, ev.t, path.Dt, Dt_e))
        path.q, path.Dt, path.t = ev.q, Dt_e, ev.t
    if plan:      # (past the first event without derivatives, only path.q is read: the reasons')
        _, _, kind, _, _, w_minus = plan[-1]
        path.w = scene.k * scene.k * w_minus if kind == EventCode.IMPACT else w_minus
        path.Dq, path.Dw, path.D_impact_loss = Dq_a, Dw_a, path.D_impact_loss + D_impact_loss
    flight = None
    if lift is not None and not broken and plan and plan[-1][2] == EventCode.LIFT_OFF:
        flight = launch(c, lift[0], lift[1], lift[2], lift[3], path.t, path.Dt)
    return (plan[-1][0] + 1 if plan else start), broken, first, flight


#: Intervals whose time derivatives are computed at once (a chunk after one that fails is not computed).
CHUNK = 64
#: The arrays of each interval that :func:`symvib.numeric.sensitivity_batch.time_derivatives` reads.
BATCH_FIELDS = ("s", "q_a", "q_e", "G_a", "G_e", "f_a", "f_e", "Dq_a", "Dq_e", "DG_a", "DG_e")


def _checked_through(through, n: int) -> int:
    """The index of the last event to differentiate: ``through`` within the run's events."""
    if isinstance(through, bool) or not isinstance(through, (int, np.integer)) or through < 0:
        raise ValueError(f"through: the index of an event (a whole number >= 0), got {through!r:.80}")
    return min(int(through), n - 1)


def _by_branch(intervals):
    """``(s, intervals on branch s)`` for each branch that has some."""
    for s in (1, -1):
        group = [iv for iv in intervals if iv is not None and iv.s == s]
        if group:
            yield s, group


def _plan(events, start, last, scene, c, q_a, w_a):
    """The differentiable sliding events from ``start`` (the particle at ``q_a`` with ``w_a``) to a
    lift-off (included), a landing (not included) or ``last``, each ``(index, event, kind code,
    turning, interval or None, w before it)``; and the first event without derivatives (its index,
    or None) and why."""
    plan = []
    stop = start
    while stop < last and events[stop].kind.code not in (EventCode.LIFT_OFF, EventCode.LANDING):
        stop += 1
    if events[stop].kind.code == EventCode.LANDING:
        stop -= 1
    segment = events[start:stop + 1]
    # the kernels at every event and every interval's middle, each called once for all of them
    at = np.array([q_a] + [ev.q for ev in segment])
    middle = at[:-1] + (at[1:] - at[:-1]) / 2
    alpha, dalpha, alpha_mid = c.alpha(at), c.dalpha(at), c.alpha(middle)
    F, f, F_mid = ({s: fn(s, x) for s in (1, -1)} for fn, x in ((c.F, at), (c.f, at), (c.F, middle)))
    for j, ev in enumerate(segment):
        i, kind = start + j, ev.kind.code
        own = _not_differentiable(ev, scene, c, kind, moved=ev.q != q_a)
        if own:
            return plan, i, own
        turning = kind in (EventCode.REVERSAL, EventCode.ARREST)
        if ev.q == q_a:                      # no motion in between (a rest test at the start)
            iv, w_minus = None, w_a
        else:
            sigma = 1 if ev.q > q_a else -1
            s = _branch(c, w_a, sigma, middle[j], (alpha[j], alpha_mid[j], F[sigma][j], F_mid[sigma][j]))
            ends = (float(alpha[j]), float(dalpha[j]), float(f[s][j]), float(f[s][j + 1]), F[s][j], F[s][j + 1],
                    alpha[j + 1:j + 2], dalpha[j + 1:j + 2])
            iv = _Interval(c, q_a, w_a, ev.q, s, turning, I_p_e=0.0, ends=ends)
            w_minus = 0.0 if turning else float((iv.G_e / iv.E_e)[0])
        plan.append((i, ev, kind, turning, iv, w_minus))
        q_a, w_a = ev.q, (scene.k * scene.k * w_minus if kind == EventCode.IMPACT else w_minus)
    return plan, None, ""


def _reasons_after(events, first, why, scene, c, q_a) -> list:
    """The reasons of the events from the first without derivatives on (index ``first``, reason ``why``; the
    particle was at ``q_a`` before it): each later one's own, else that it follows ``first``."""
    out = [why]
    for ev in events[1:]:
        own = _not_differentiable(ev, scene, c, ev.kind.code, moved=ev.q != q_a)
        out.append(own or f"follows event {first}, which has no derivatives ({why})")
    return out


def _branch(c, w_a, sigma, mid_q, values) -> int:
    """The branch ``s = sigma sign(N)`` of an interval (no sign change of ``N`` inside: the engine
    ends an interval there), from ``N`` at its middle ``mid_q`` on the branch that assumes ``N > 0``
    (``values``: ``alpha`` at its start and middle, ``F_sigma`` at its start and middle)."""
    alpha_a, alpha_mid, F_a, F_mid = values
    G_a = w_a * math.exp(2 * sigma * c.mu * float(alpha_a))
    G_mid = G_a - 2 * c.g * float(F_mid - F_a)
    w_mid = G_mid / math.exp(2 * sigma * c.mu * float(alpha_mid))
    return sigma if c.N(mid_q, w_mid) >= 0 else -sigma


def _on_cone_edge(alpha: float, mu: float) -> bool:
    """Whether ``|tan alpha|`` is within :data:`CONE_EDGE` (relative) of the friction coefficient ``mu``."""
    edge = abs(abs(math.sin(alpha)) - mu * abs(math.cos(alpha)))
    return edge <= CONE_EDGE * max(abs(math.sin(alpha)), mu * abs(math.cos(alpha)), 1e-300)


def _not_differentiable(ev, scene, c, kind, *, moved: bool = True) -> str:
    """Why event ``ev`` has no derivatives (empty when it has); ``moved``: the particle moved to it
    (a turning point of ``G``, not a rest test where it already was)."""
    if kind == EventCode.LEFT_CURVE:
        return "the particle leaves the curve"
    if kind == EventCode.LANDING:
        return landing_reason(ev.detail)
    if ev.detail and "zeno" in ev.detail.lower():
        return "a Zeno accumulation of impacts (infinitely many events); this event and the ones after it"
    if kind in (EventCode.REVERSAL, EventCode.ARREST):
        a = float(c.alpha(ev.q))
        if _on_cone_edge(a, scene.mu_static):   # the rest test's (static) cone: the decision flips there
            return "a turning point on the edge of the friction cone (arrest or reversal changes with the parameters)"
        if moved and scene.mu_static != scene.mu and _on_cone_edge(a, scene.mu):
            return ("a turning point on the edge of the sliding friction cone |tan alpha| = mu (a double root of "
                    "the phase trajectory: its position has no derivative)")
        for limiter in (scene.left, scene.right):
            if limiter is not None and abs(ev.q - limiter) <= GRAZING * c.scale:
                return "a turning point on a limiter (grazing)"
    return ""
