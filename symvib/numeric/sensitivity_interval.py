"""One motion interval of a differentiated run, one at a time (physics.md, "Sensitivities" 2, 5 and 7).

:class:`Interval` holds an interval from ``(q_a, w_a)`` to ``q_e`` on branch ``s`` with the
tangents of its ends, and differentiates what lies inside it: ``w`` and its total derivative at
any ``u`` (:meth:`Interval.along`), the duration (:meth:`Interval.dT`, refined level by level on
its own: the reference that :mod:`symvib.numeric.sensitivity_batch` evaluates for all intervals
at once) and a position at fixed time (:meth:`Interval.position_tangent`, for sampled
trajectories).  :func:`symvib.numeric.sensitivity.interval_tangents` builds them; its legs carry
them.
"""
from __future__ import annotations

import math

import numpy as np

from symvib.numeric.sensitivity_batch import (
    ACCEPT,
    FIRST_PANELS,
    INNER_NODES,
    INTEGRAL_RTOL,
    MAX_PANELS,
    NODES,
    RTOL,
    gauss,
    switched,
)

__all__ = ["Interval"]


class Interval:
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

    @classmethod
    def of_scalars(cls, curve, row, turning_end):
        """The interval whose scalars :func:`symvib.numeric.sensitivity._plan` computed (``row``: ``s, E_a, G_a,
        alpha_a, alpha'_a, f_a, f_e, G_e, alpha_e, alpha'_e, E_e, q_a, q_e, w_a``; the same numbers as
        :meth:`__init__` from the kernels at both ends), its integral of ``dF_s'/dp`` 0 until set."""
        self = cls.__new__(cls)
        (s, self.E_a, self.G_a, self.alpha_a, self.dalpha_a, self.f_a, self.f_e, self.G_e, alpha_e, dalpha_e, E_e,
         self.q_a, self.q_e, self.w_a) = row
        self.c, self.s, self.turning_end, self.I_p_e = curve, s, turning_end, 0.0
        self.alpha_e, self.dalpha_e, self.E_e = np.array([alpha_e]), np.array([dalpha_e]), np.array([E_e])
        return self

    def set_start(self, Dq_a, Dw_a, Dmu):
        """The start's tangents ``Dq_a``, ``Dw_a`` (and ``Dmu``): the total derivative of ``G`` there."""
        c, s = self.c, self.s
        self.Dq_a, self.Dw_a, self.Dmu = Dq_a, Dw_a, Dmu
        # total derivative of G at the start: D(w_a E(q_a)), alpha's own derivative in a curve parameter too
        moved = self.alpha_a * Dmu + c.mu * self.dalpha_a * Dq_a
        if c.has_curve_parameters:      # (else alpha's own derivative is 0: nothing to add)
            moved = moved + c.mu * c.geometry_dp("alpha", self.q_a)[0]
        self.DG_a = Dw_a * self.E_a + self.G_a * 2 * s * moved
        # dG/dp at fixed q, the part that does not depend on q: (dG/dp)(q) = A - 2 g I_p(q), with
        # I_p(q) = Integral_{q_a}^{q} dF_s'/dp (mu and the curve's parameters)
        self.A = self.DG_a + 2 * c.g * self.f_a * Dq_a

    def end_state(self):
        """``w`` at the end and its total derivative there (shape (P,)): :meth:`along` at ``u = 1``, where
        every integral from the end is empty."""
        c, s = self.c, self.s
        E_e = self.E_e[0]
        moved = self.alpha_e[0] * self.Dmu + c.mu * self.dalpha_e[0] * self.Dq_e
        if c.has_curve_parameters:      # (else alpha's own derivative is 0: nothing to add)
            moved = moved + c.mu * c.geometry_dp("alpha", self.q_e)[0]
        return float(self.G_e / E_e), (self.DG_e - self.G_e * 2 * s * moved) / E_e

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
            f_q = c.f(s, q[order])                                  # f(q) - f(q_c): integrated, or
            int_df = np.where(switched(x, f_q, f_c), f_q - f_c,     # that difference (switched)
                              self.cumulative(lambda v: c.df(s, v), q_c, D, x))
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
        panels = FIRST_PANELS
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
            piece = Interval(c, self.q_a, self.w_a, q, s, False, self.Dq_a, self.Dw_a, self.Dmu, G_e=G)
        else:
            w = G / math.exp(2 * s * c.mu * float(c.alpha(q)))
            piece = Interval(c, q, w, self.q_e, s, self.turning_end, self.Dq_e, Dw, self.Dmu, G_e=self.G_e)
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
