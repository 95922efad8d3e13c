"""Samples of a run with flights (physics.md, "Flight and landing", Samples, dense output and figures).

A unilateral run that lifts off (:mod:`symvib.numeric.flights`) is a sequence of pieces:
the engine's sliding stretches (:class:`~symvib.numeric.flights.Slide`), flights
(:class:`~symvib.numeric.flights.Arc`) and bouncing-ball accumulations
(:class:`~symvib.numeric.flights.Accumulated`).  Its samples (:class:`FlightSamples`) are

* on a sliding stretch, the samples the driver takes of any run (the engine's Gauss nodes of
  every motion interval, :func:`symvib.numeric.driver.simulate`), shifted by the stretch's start
  time and by the friction work, impact and landing losses before it;
* on a flight, as many points as a sliding interval gets (``samples_per_interval`` and one, at
  least; fewer where a long run keeps one piece per interval), evenly spaced in time on its parabola
  (:func:`arc_points`): ``x, z, vx, vz`` in closed form, ``q``, ``qdot``, ``v`` and ``s`` NaN
  (the particle is off the curve: it has no coordinate on it), ``F_N = F_mu = P_mu = 0``,
  ``E = Ek + Ep`` with ``Ek = m (vx^2 + vz^2) / 2``;
* an accumulation is not sampled (as a limiter's Zeno series is not): the samples jump over its
  time, from the landing before it to the sliding after it.

So ``E + W_mu + W_impacts + W_landing = E0`` at every sample.  The columns are those of
:class:`symvib.numeric.events.Samples` and ``vx``, ``vz`` (the velocity, m/s, on the curve
``qdot (x', z')``), ``W_landing`` (the landing losses since the start, J) and ``flight`` (the
flight's number from 0, -1 while sliding).

Examples
--------
>>> from symvib import simulate
>>> from symvib.numeric.scene import scene_from_dict
>>> scene = scene_from_dict({"curve": {"shape": "circle"}, "parameters": {"R": 0.5},
...     "physics": {"mu": 0.05, "restitution": 1, "contact": "unilateral", "restitution_curve": 0.5},
...     "initial": {"q": 0, "qdot": 8}})
>>> S = simulate(scene, backend="python").samples
>>> bool(abs(S.E + S.W_mu + S.W_impacts + S.W_landing - S.E[0]).max() < 1e-12 * S.E[0])
True
>>> int(S.flight.max()) + 1, bool(np.isnan(S.q[S.flight == 0]).all())     # 17 flights, off the curve
(17, True)
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from symvib.numeric.events import Samples
from symvib.numeric.flight import path
from symvib.numeric.flights import Accumulated, Arc, Slide
from symvib.numeric.layout import SceneRow
from symvib.numeric.quadrature import rule
from symvib.numeric.scenerow import scene_row

__all__ = ["FlightSamples", "Sampling", "samples", "arc_points", "arc_length", "parabola_length",
           "ARC_NODES", "ARC_PANEL"]

#: Gauss-Legendre nodes per panel of the arc length ``Integral h dq`` between two points of the curve.
ARC_NODES = 16
#: Panel width of that quadrature, a share of the run's length scale in ``q`` (the curve turns by
#: at most about this many radians over a panel: 16 nodes integrate it to rounding).
ARC_PANEL = 0.125


@dataclass(frozen=True)
class FlightSamples(Samples):
    """:class:`~symvib.numeric.events.Samples` of a run with flights (physics.md, "Flight and landing"),
    with ``vx``, ``vz`` [m/s] the velocity, ``W_landing`` [J] the landing losses since the start and
    ``flight`` the number of the flight a sample lies on (from 0; -1 on the curve).  In flight ``q``,
    ``qdot``, ``v`` and ``s`` are NaN, ``F_N``, ``F_mu``, ``P_mu`` and ``branch`` 0."""

    vx: np.ndarray
    vz: np.ndarray
    W_landing: np.ndarray
    flight: np.ndarray


class Sampling(NamedTuple):
    """How the driver samples a run (:func:`symvib.numeric.driver.simulate` builds it): ``stretch(row,
    intervals, n_intervals, pieces)`` the samples of an engine run's logged intervals (``(Samples,
    None)`` or ``(None, message)``), ``pieces_of(n_intervals)`` the pieces per interval (``(pieces,
    None)``, or ``(None, message)`` where there would be too many samples; a flight counts as an
    interval), and ``per_piece`` the points a piece of an interval gives (a flight gets ``pieces
    per_piece + 1`` points)."""

    stretch: object
    pieces_of: object
    per_piece: int


def parabola_length(t, vx, vz, g):
    """The length of the ballistic path from its launch with ``(vx, vz)`` to times ``t`` (closed form:
    ``Integral sqrt(vx^2 + u^2) du / g`` over ``u`` from ``vz - g t`` to ``vz``).

    Examples
    --------
    >>> float(parabola_length(2.0, 3.0, 4.0, 0.0))          # a straight line at 5 m/s
    10.0
    >>> round(float(parabola_length(1.0, 0.0, 0.0, 2.0)), 12)   # dropped: g t^2 / 2
    1.0
    """
    t = np.asarray(t, dtype=float)
    if g == 0.0:
        return math.hypot(vx, vz) * t
    a = abs(vx)

    def F(u):   # an antiderivative of sqrt(a^2 + u^2)
        if a == 0.0:
            return 0.5 * u * np.abs(u)
        return 0.5 * (u * np.hypot(a, u) + a * a * np.arcsinh(u / a))

    return (F(vz) - F(vz - g * t)) / g


def arc_length(mod, cp, qa, qb, scale):
    """``Integral_qa^qb h dq`` (signed): Gauss-Legendre on panels of :data:`ARC_PANEL` length scales."""
    if qa == qb:
        return 0.0
    n = max(1, int(math.ceil(abs(qb - qa) / (ARC_PANEL * scale))))
    r = rule(ARC_NODES)
    edges = np.linspace(qa, qb, n + 1)
    half = 0.5 * np.diff(edges)
    nodes = (edges[:-1] + half)[:, None] + half[:, None] * np.asarray(r.x)[None, :]
    h = np.broadcast_to(mod.h(nodes, *cp), nodes.shape)
    return float(np.sum(half * (h @ np.asarray(r.weights))))


def arc_points(arc: Arc, count: int, g: float):
    """``(t, x, z, vx, vz)`` at ``count`` times evenly spaced over the flight ``arc`` (both ends)."""
    tau = np.linspace(0.0, arc.T, max(int(count), 2))
    x, z, vx, vz = path(tau, arc.x0, arc.z0, arc.vx, arc.vz, g)
    return arc.t0 + tau, x, z, np.broadcast_to(vx, tau.shape).astype(float), vz


def samples(scene, mod, cp, pieces, sampling: Sampling, scale: float):
    """The samples of a run with flights (module docstring): ``(FlightSamples, None)``, or ``(None,
    message)`` where a stretch's sampling failed or there would be too many samples.

    Parameters
    ----------
    scene : Scene
    mod : module
        The curve's kernels; ``cp`` their parameter values.
    pieces : sequence
        The run's log (:func:`symvib.numeric.flights.follow`): :class:`~symvib.numeric.flights.Slide`,
        :class:`~symvib.numeric.flights.Arc` and :class:`~symvib.numeric.flights.Accumulated`, in time order.
    sampling : Sampling
    scale : float
        The run's length scale in ``q`` (the arc-length quadrature's panels).
    """
    n_intervals = sum(int(p.out.n_intervals) for p in pieces if isinstance(p, Slide))
    n_arcs = sum(isinstance(p, Arc) for p in pieces)
    per_interval, message = sampling.pieces_of(n_intervals + n_arcs)
    if message is not None:
        return None, message
    m, g = scene.m, scene.g
    parts = []
    interval = flight = 0
    travelled = 0.0
    s_at, q_at = 0.0, float(scene.q0)   # the arc-length coordinate s at q_at
    for p in pieces:
        if isinstance(p, Slide):
            row = scene_row(scene)
            row[SceneRow.q0], row[SceneRow.qdot0] = p.q, p.qdot
            S, message = sampling.stretch(row, p.out.intervals, int(p.out.n_intervals), per_interval)
            if message is not None:
                return None, message
            if not len(S.t):
                continue
            s_at, q_at = s_at + arc_length(mod, cp, q_at, p.q, scale), p.q
            cols = {name: np.array(getattr(S, name)) for name in Samples.__dataclass_fields__}
            cols["t"] += p.t0
            cols["interval"] += interval
            cols["s"] += s_at
            cols["path"] += travelled
            cols["W_mu"] += p.W_friction
            cols["W_impacts"] += p.W_impacts
            n = len(S.t)
            dx, dz = (np.broadcast_to(k(S.q, *cp), S.q.shape) for k in (mod.dx, mod.dz))
            cols.update(vx=S.qdot * dx, vz=S.qdot * dz, W_landing=np.full(n, p.W_landing),
                        flight=np.full(n, -1))
            interval = int(cols["interval"][-1]) + 1
            travelled = float(cols["path"][-1])
            parts.append(cols)
        elif isinstance(p, Arc):
            t, x, z, vx, vz = arc_points(p, per_interval * sampling.per_piece + 1, g)
            n = len(t)
            nan, zero = np.full(n, np.nan), np.zeros(n)
            Ek = 0.5 * m * (vx * vx + vz * vz)
            Ep = m * g * z
            parts.append({"t": t, "q": nan, "qdot": nan, "F_N": zero, "P_mu": zero, "Ek": Ek, "Ep": Ep,
                          "E": Ek + Ep, "interval": np.full(n, interval), "branch": np.zeros(n, dtype=int),
                          "x": x, "z": z, "s": nan, "path": travelled + parabola_length(t - p.t0, p.vx, p.vz, g),
                          "v": nan, "F_mu": zero, "W_mu": np.full(n, p.W_friction),
                          "W_impacts": np.full(n, p.W_impacts), "vx": vx, "vz": vz,
                          "W_landing": np.full(n, p.W_landing), "flight": np.full(n, flight)})
            interval, flight = interval + 1, flight + 1
            travelled = float(parts[-1]["path"][-1])
        elif isinstance(p, Accumulated):   # not sampled: along the curve from its start to its end
            travelled += abs(arc_length(mod, cp, p.q0, p.q1, scale))
    ints = ("interval", "branch", "flight")
    if not parts:
        return FlightSamples(**{k: np.zeros(0, dtype=int if k in ints else float)
                                for k in FlightSamples.__dataclass_fields__}), None
    out = {k: np.concatenate([np.asarray(c[k], dtype=int if k in ints else float) for c in parts])
           for k in FlightSamples.__dataclass_fields__}
    return FlightSamples(**out), None
