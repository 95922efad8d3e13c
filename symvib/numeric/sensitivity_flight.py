"""The derivatives of flights and landings on a unilateral curve (physics.md, "Sensitivities" 10).

A run with flights (:mod:`symvib.numeric.flights`) lifts off where ``N`` reaches 0, flies on
the closed-form parabola of flight and lands where that parabola meets the curve; the landing
law then gives the velocity after it. Each step is a closed form or an implicit equation, so
its derivatives follow exactly, as the sliding intervals' do
(:mod:`symvib.numeric.sensitivity`):

* **Launch** at ``q_l`` with the signed speed ``v`` (``v = h qdot``): ``P0 = (x, z)(q_l)``,
  ``V0 = v T(q_l)``, ``T = (x', z') / h = (cos alpha, sin alpha)``, so
  ``DP0 = (x', z') Dq_l + (dx/dp, dz/dp)`` and ``DV0 = Dv T + v n Dalpha`` with
  ``n = (-sin alpha, cos alpha)`` and ``Dalpha = alpha' Dq + dalpha/dp``.
* **Landing** after a flight time ``tau``: ``(x, z)(q_L) = P0 + V0 tau - (0, g tau^2 / 2)``.
  Differentiated in ``(q_L, tau)``::

      [x'(q_L)  -V_x] [Dq_L]   [DX0 + DV0_x tau - dx/dp]
      [z'(q_L)  -V_z] [Dtau] = [DZ0 + DV0_z tau - dz/dp],      V = V0 - (0, g tau),

  whose determinant is ``-h u`` (``u = n . V``, the normal velocity): a tangential landing
  (``u = 0``) has no derivative.
* **Landing law** (physics.md, "Flight and landing" 4) with ``e = restitution_curve``:
  ``u = n . V``, ``v_t = T . V``, so ``Du = n . DV - v_t Dalpha`` and ``Dv_t = T . DV + u Dalpha``;
  ``u' = -e u``; sliding ``v' = v_t - sign(v_t) mu (1 + e) |u|`` (``Dv' = Dv_t - sign(v_t) (Dmu (1
  + e) |u| - mu (1 + e) Du)``); sticking ``v' = 0``. On the edge between them (``|v_t| = mu (1 +
  e) |u|``) the law switches: no derivative.
* A **bounce** (``u' > 0``) launches the next flight from the landing point with ``V' = u' n + v'
  T``; a landing without one resumes sliding with ``w = v'^2``. A bouncing-ball accumulation
  (infinitely many bounces summed) has no derivative, as the limiter's Zeno has none.

The landing loss ``m (u^2 + v_t^2 - u'^2 - v'^2) / 2`` is differentiated with them.

Examples
--------
>>> import numpy as np
>>> f = Flight(0.0, np.zeros(1), 0.0, 0.0, 1.0, 2.0, np.zeros(1), np.zeros(1), np.ones(1), np.zeros(1))
>>> f.at(0.5, 10.0)            # velocity after half a second with g = 10: (1, -3)
(1.0, -3.0)
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

__all__ = ["Flight", "Landed", "launch", "land", "TANGENTIAL_LANDING", "STICK_EDGE",
           "TANGENTIAL_LANDING_REASON", "STICK_EDGE_REASON", "ACCUMULATION_REASON", "landing_reason"]

#: ``|u|`` below this share of the speed ``|V|`` is a tangential landing (no derivative: the flight
#: time moves by more than ``1e8`` of its own change per unit of the data).
TANGENTIAL_LANDING = 1e-8
#: ``| |v_t| - mu (1 + e) |u| |`` below this share of ``|v_t| + mu (1 + e) |u|``: the landing is on the
#: edge between sticking and sliding.
STICK_EDGE = 1e-9
#: Why a tangential landing has no derivative.
TANGENTIAL_LANDING_REASON = ("a tangential landing (the parabola of flight touches the curve: its time has no "
                             "derivative); this event and the ones after it")
#: Why a landing on the edge between sticking and sliding has none.
STICK_EDGE_REASON = ("a landing on the edge between sticking and sliding (the landing law switches there); this "
                     "event and the ones after it")
#: Why a bouncing-ball accumulation has none.
ACCUMULATION_REASON = ("a bouncing-ball accumulation (infinitely many bounces summed); this event and the ones "
                       "after it")


class Flight(NamedTuple):
    """A flight launched at time ``t0`` from ``(X0, Z0)`` with velocity ``(Vx, Vz)``, and the
    tangents (shape ``(P,)``) of the launch time, point and velocity."""

    t0: float
    Dt0: np.ndarray
    X0: float
    Z0: float
    Vx: float
    Vz: float
    DX0: np.ndarray
    DZ0: np.ndarray
    DVx: np.ndarray
    DVz: np.ndarray

    def at(self, tau, g):
        """The velocity ``tau`` after the launch."""
        return self.Vx, self.Vz - g * tau


class Landed(NamedTuple):
    """The tangents of a landing: its time, position, tangential speed before and after and its
    loss; then either the next flight (a bounce) or where sliding resumes (``q, w`` and their
    tangents ``Dq, Dw``)."""

    Dt: np.ndarray
    Dq: np.ndarray
    Dv_before: np.ndarray
    Dv_after: np.ndarray
    D_loss: np.ndarray
    bounce: Flight | None
    q: float
    w: float
    Dw: np.ndarray


def _frame(c, q, Dq):
    """``(x, z, dx, dz, T, n, Dalpha, DP)`` at ``q`` moved by ``Dq``: the point, ``(x', z')``, the unit
    tangent and normal, and the tangents of the tangent angle and of the point (the curve's
    parameters included)."""
    x, z = float(c.x(q)), float(c.z(q))
    dx, dz = float(c.dx(q)), float(c.dz(q))
    h = math.hypot(dx, dz)
    T = np.array([dx / h, dz / h])
    n = np.array([-T[1], T[0]])
    Dalpha = float(c.dalpha(q)) * Dq + c.geometry_dp("alpha", q)[0]
    DP = np.outer(np.array([dx, dz]), Dq) + np.stack([c.geometry_dp("x", q)[0], c.geometry_dp("z", q)[0]])
    return x, z, dx, dz, T, n, Dalpha, DP


def launch(c, q, v, Dq, Dv, t, Dt) -> Flight:
    """The flight from a lift-off at ``q`` (time ``t``) with the signed speed ``v = h qdot``, and the
    tangents ``Dq``, ``Dv``, ``Dt`` of the lift-off (``c``: the run's
    :class:`~symvib.numeric.sensitivity_curve.CurveFunctions`)."""
    x, z, _, _, T, n, Dalpha, DP = _frame(c, q, Dq)
    DV = np.outer(T, Dv) + v * np.outer(n, Dalpha)
    return Flight(t, Dt, x, z, v * T[0], v * T[1], DP[0], DP[1], DV[0], DV[1])


def landing_reason(detail: str) -> str:
    """Why a landing event (its ``detail``) has no derivative, judged from its record alone: a
    tangential touch or a bouncing-ball accumulation; empty otherwise."""
    low = detail.lower()
    if "accumulation" in low:
        return ACCUMULATION_REASON
    if low.startswith("touch"):
        return TANGENTIAL_LANDING_REASON
    return ""


def land(c, scene, flight: Flight, t_land: float, q_land: float) -> Landed | str:
    """The tangents of the landing of ``flight`` at time ``t_land`` and position ``q_land`` (an event of
    the run), or the reason it has none (:data:`TANGENTIAL_LANDING_REASON`, :data:`STICK_EDGE_REASON`).

    Parameters
    ----------
    c : symvib.numeric.sensitivity_curve.CurveFunctions
        The curve, with the parameters of ``wrt``.
    scene : Scene
        The run's scene (``g``, ``mu``, ``restitution_curve``).
    flight : Flight
        The flight that lands.
    t_land, q_land : float
        The landing event's time and position.
    """
    g, mu, e = c.g, scene.mu, scene.restitution_curve
    tau = t_land - flight.t0
    Vx, Vz = flight.at(tau, g)
    x, z, dx, dz, T, n, Dalpha_fixed, DP_fixed = _frame(c, q_land, np.zeros_like(flight.DX0))
    u = -T[1] * Vx + T[0] * Vz
    v_t = T[0] * Vx + T[1] * Vz
    if not abs(u) > TANGENTIAL_LANDING * math.hypot(Vx, Vz):
        return TANGENTIAL_LANDING_REASON
    # The landing condition differentiated in (q_L, tau); DP_fixed holds (dx/dp, dz/dp) at fixed q.
    rhs_x = flight.DX0 + flight.DVx * tau - DP_fixed[0]
    rhs_z = flight.DZ0 + flight.DVz * tau - DP_fixed[1]
    det = -dx * Vz + dz * Vx
    Dq = (-Vz * rhs_x + Vx * rhs_z) / det
    Dtau = (-dz * rhs_x + dx * rhs_z) / det
    DVx, DVz = flight.DVx, flight.DVz - g * Dtau
    Dalpha = Dalpha_fixed + float(c.dalpha(q_land)) * Dq
    Du = n[0] * DVx + n[1] * DVz - v_t * Dalpha
    Dv_t = T[0] * DVx + T[1] * DVz + u * Dalpha
    # The landing law (symvib.numeric.flight.landing_law), u < 0 here.
    jn = (1.0 + e) * -u
    Djn = -(1.0 + e) * Du
    u_after, Du_after = -e * u, -e * Du
    Dmu = c.Dmu
    if abs(abs(v_t) - mu * jn) <= STICK_EDGE * (abs(v_t) + mu * jn):
        return STICK_EDGE_REASON
    if abs(v_t) <= mu * jn:
        v_after, Dv_after = 0.0, np.zeros_like(Dv_t)
    else:
        sign = math.copysign(1.0, v_t)
        v_after = v_t - sign * mu * jn
        Dv_after = Dv_t - sign * (Dmu * jn + mu * Djn)
    D_loss = c.m * (u * Du + v_t * Dv_t - u_after * Du_after - v_after * Dv_after)
    Dt = flight.Dt0 + Dtau
    bounce = None
    if u_after > 0.0:
        DP = np.outer(np.array([dx, dz]), Dq) + DP_fixed
        V = u_after * n + v_after * T
        DV = (np.outer(n, Du_after) + np.outer(T, Dv_after)
              + np.outer(u_after * -T + v_after * n, Dalpha))
        bounce = Flight(t_land, Dt, x, z, float(V[0]), float(V[1]), DP[0], DP[1], DV[0], DV[1])
    return Landed(Dt, Dq, Dv_t, Dv_after, D_loss, bounce, q_land, v_after * v_after, 2 * v_after * Dv_after)
