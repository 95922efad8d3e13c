"""Dense output of a run with flights: the state at any time (physics.md, "Flight and landing",
Samples, dense output and figures).

A run with flights is a sequence of pieces (:func:`symvib.numeric.flights.follow`):

* a sliding stretch: the state from its own :class:`~symvib.numeric.dense.DenseOutput` (the
  engine's interval log of that stretch, exact from the phase trajectory, paper eq. 2), its time
  shifted by the stretch's start;
* a flight: the ballistic parabola in closed form; the particle is off the curve, so ``q`` and
  ``qdot`` are NaN there (as in the samples), and :meth:`FlightDense.position` gives ``x, z, vx, vz``;
* a bouncing-ball accumulation summed on the tangent line: ``q`` moves linearly in time from its start
  to its end, ``qdot`` the mean (the bounces are below ``1e-10`` of the run's length scale high;
  the local model's mean motion differs from a linear one by about that over ``(1 - e)^2``).

The state is right-continuous: at a lift-off it is already in flight (NaN ``q``), at a landing the
state after it.  Past the last piece it is the run's final state (at rest for a run that came to
rest; the last landing's where ``t_max`` fell inside an accumulation).

Examples
--------
>>> from symvib import simulate
>>> from symvib.numeric.scene import scene_from_dict
>>> scene = scene_from_dict({"curve": {"shape": "circle"}, "parameters": {"R": 0.5},
...     "physics": {"mu": 0.05, "restitution": 1, "contact": "unilateral"}, "initial": {"q": 0, "qdot": 8}})
>>> r = simulate(scene, backend="python")        # lifts off, flies, lands (restitution_curve 0) and slides
>>> lift, land = r.events[0], r.events[1]
>>> r.dense.in_flight([lift.t - 1e-3, 0.5 * (lift.t + land.t), land.t]).tolist()
[False, True, False]
>>> q, qdot = r.state(land.t)                    # the state just after the first landing
>>> bool(abs(q - land.q) < 1e-12 and abs(qdot - land.qdot_after) < 1e-12)
True
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from symvib.numeric.dense import DenseOutput, checked_times
from symvib.numeric.flight import path
from symvib.numeric.flight_pieces import Arc, Slide
from symvib.numeric.layout import StatusCode

__all__ = ["FlightDense", "SLIDING", "FLYING", "ACCUMULATING"]

#: Kinds of the pieces of a run with flights.
SLIDING, FLYING, ACCUMULATING = 0, 1, 2
#: Statuses after which the particle stays at rest forever.
_RESTING = ("arrested", "resting_on_limiter")


class _Stretch(NamedTuple):
    """What :class:`~symvib.numeric.dense.DenseOutput` reads of a result, for one sliding stretch."""

    scene: object
    status: object
    t_final: float
    q_final: float
    qdot_final: float


class _Status(NamedTuple):
    value: str


class _StartedAt:
    """The run's scene started at ``(q0, qdot0)``, unvalidated (a stretch starts where a landing put
    the particle, which the scene's checks of a start need not accept): what a stretch's
    :class:`~symvib.numeric.dense.DenseOutput` reads of it (the engine's row, ``g``, ``mu``)."""

    def __init__(self, scene, q0, qdot0):
        self._scene, self.q0, self.qdot0 = scene, float(q0), float(qdot0)

    def __getattr__(self, name):
        return getattr(self._scene, name)


class FlightDense:
    """The state of a run with flights at any time (:meth:`state`, ``__call__``, :meth:`position`,
    :meth:`in_flight`) and, on the curve, at any position (:meth:`at`).

    Built by :attr:`symvib.numeric.events.Result.dense` (module docstring).

    Parameters
    ----------
    result : Result
        The run.
    mod : module
        The curve's kernels; ``params`` their parameter values.
    rules : Rules
        The rules and tolerances the run used.
    pieces : sequence
        The run's log: :class:`~symvib.numeric.flights.Slide`, :class:`~symvib.numeric.flights.Arc`,
        :class:`~symvib.numeric.flights.Accumulated`, in time order.
    """

    def __init__(self, result, *, mod, params, rules, pieces):
        self.result = result
        self._K, self._cp = mod, tuple(float(v) for v in params)
        scene = result.scene
        self._g = float(scene.g)
        self._pieces = list(pieces)
        self._denses: dict = {}
        self._rules = rules
        start, end, kind = [], [], []
        slides = [i for i, p in enumerate(self._pieces) if isinstance(p, Slide)]
        self._last_slide = slides[-1] if slides else -1
        for p in self._pieces:
            if isinstance(p, Slide):
                start.append(p.t0)
                end.append(p.t0 + float(p.out.t))
                kind.append(SLIDING)
            else:
                start.append(p.t0)
                end.append(p.t0 + p.T)
                kind.append(FLYING if isinstance(p, Arc) else ACCUMULATING)
        self._start, self._end, self._kind = np.array(start), np.array(end), np.array(kind)
        #: Time span where the state is defined; ``t_max`` is infinite for a run that came to rest.
        self.t_min = 0.0
        self.t_max = math.inf if result.status.value in _RESTING else float(result.t_final)

    # -- the pieces ----------------------------------------------------------------------------------

    def _dense(self, i: int) -> DenseOutput:
        """The dense output of sliding stretch ``i`` (a piece), built once."""
        d = self._denses.get(i)
        if d is None:
            p = self._pieces[i]
            out = p.out
            scene = _StartedAt(self.result.scene, p.q, p.qdot)
            if i == self._last_slide and int(out.status) != StatusCode.LEFT_CURVE:
                status = self.result.status
            else:
                status = _Status("left_curve")
            fake = _Stretch(scene, status, float(out.t), float(out.q), float(out.qdot))
            d = DenseOutput(fake, self._K, self._cp, out.intervals[:out.n_intervals], self._rules)
            self._denses[i] = d
        return d

    def _where(self, flat):
        """The piece of each time (-1 before the first, or past the last piece's end: the final state)."""
        i = np.searchsorted(self._start, flat, side="right") - 1
        past = (i < 0) | (flat > self._end[np.maximum(i, 0)])
        return np.where(past, -1, i)

    def _checked(self, t):
        return checked_times(t, self.t_min, self.t_max, self.result.status.value)

    # -- the state -----------------------------------------------------------------------------------

    @property
    def n_pieces(self) -> int:
        """Number of pieces: sliding stretches, flights and accumulations."""
        return len(self._pieces)

    @property
    def flights(self) -> dict:
        """The flights as columns: ``t_start``, ``t_end``, ``x0``, ``z0``, ``vx0``, ``vz0`` (the launch)."""
        arcs = [p for p in self._pieces if isinstance(p, Arc)]
        return {"t_start": np.array([a.t0 for a in arcs]), "t_end": np.array([a.t0 + a.T for a in arcs]),
                "x0": np.array([a.x0 for a in arcs]), "z0": np.array([a.z0 for a in arcs]),
                "vx0": np.array([a.vx for a in arcs]), "vz0": np.array([a.vz for a in arcs])}

    @property
    def intervals(self) -> dict:
        """The sliding motion intervals of every stretch, in time order, as
        :attr:`symvib.numeric.dense.DenseOutput.intervals` (times from the run's start); flights are in
        :attr:`flights`.  :meth:`at` numbers them so."""
        parts = [(self._pieces[i].t0, self._dense(i).intervals) for i in np.flatnonzero(self._kind == SLIDING)]
        keys = ("t_start", "t_end", "q_start", "q_end", "branch", "direction")
        if not parts:
            return {k: np.zeros(0) for k in keys}
        return {k: np.concatenate([d[k] + (t0 if k.startswith("t_") else 0) for t0, d in parts]) for k in keys}

    @property
    def n_intervals(self) -> int:
        """Number of sliding motion intervals (:attr:`intervals`)."""
        return sum(self._dense(i).n_intervals for i in np.flatnonzero(self._kind == SLIDING))

    def __call__(self, t) -> np.ndarray:
        """``[q, qdot]`` at ``t``: shape ``(2,)`` for a number, ``(2, n)`` for ``n`` times (NaN in flight)."""
        q, qdot = self.state(t)
        return np.array([q, qdot], dtype=float)

    def in_flight(self, t) -> np.ndarray:
        """Whether the particle flies at time(s) ``t`` (right-continuous: at a lift-off, yes; at a landing, no)."""
        times, flat = self._checked(t)
        i = self._where(flat)
        return ((i >= 0) & (self._kind[np.maximum(i, 0)] == FLYING)).reshape(times.shape)

    def state(self, t):
        """``(q, qdot)`` at time(s) ``t`` (a number or an array; the results have its shape); NaN in flight.

        Raises
        ------
        ValueError
            Naming ``t`` when a time is not finite or outside ``[t_min, t_max]``.
        """
        times, flat = self._checked(t)
        q = np.full(flat.shape, float(self.result.q_final))
        qdot = np.full(flat.shape, float(self.result.qdot_final))
        which = self._where(flat)
        for i in np.unique(which[which >= 0]).tolist():
            sel = np.flatnonzero(which == i)
            p, kind = self._pieces[i], self._kind[i]
            if kind == SLIDING:
                local = np.minimum(flat[sel] - p.t0, float(p.out.t))
                q[sel], qdot[sel] = self._dense(i).state(np.maximum(local, 0.0))
            elif kind == FLYING:
                q[sel], qdot[sel] = np.nan, np.nan
            else:   # an accumulation: its mean motion
                share = (flat[sel] - p.t0) / p.T if p.T > 0.0 else np.ones(len(sel))
                q[sel] = p.q0 + share * (p.q1 - p.q0)
                qdot[sel] = np.where(share >= 1.0, p.qdot1, (p.q1 - p.q0) / p.T if p.T > 0.0 else p.qdot1)
        if times.ndim == 0:
            return float(q[0]), float(qdot[0])
        return q.reshape(times.shape), qdot.reshape(times.shape)

    def position(self, t):
        """``(x, z, vx, vz)`` at time(s) ``t``: on the curve from ``(q, qdot)`` and the kernels
        (``(vx, vz) = qdot (x', z')``), in flight from the parabola (physics.md, "Flight and landing" 2)."""
        times, flat = self._checked(t)
        q, qdot = self.state(flat)
        K, cp = self._K, self._cp
        on = np.isfinite(q)
        qs = np.where(on, q, 0.0)
        x = np.array(np.broadcast_to(K.x(qs, *cp), qs.shape), dtype=float)
        z = np.array(np.broadcast_to(K.z(qs, *cp), qs.shape), dtype=float)
        vx = qdot * np.broadcast_to(K.dx(qs, *cp), qs.shape)
        vz = qdot * np.broadcast_to(K.dz(qs, *cp), qs.shape)
        which = self._where(flat)
        for i in np.unique(which[(which >= 0) & ~on]).tolist():
            sel = np.flatnonzero(which == i)
            a = self._pieces[i]
            x[sel], z[sel], vx[sel], vz[sel] = path(flat[sel] - a.t0, a.x0, a.z0, a.vx, a.vz, self._g)
        shape = times.shape
        if times.ndim == 0:
            return float(x[0]), float(z[0]), float(vx[0]), float(vz[0])
        return x.reshape(shape), z.reshape(shape), vx.reshape(shape), vz.reshape(shape)

    def at(self, q, interval=None):
        """``(t, qdot)`` where the particle slides through position(s) ``q``: on sliding interval
        ``interval`` (numbered as :attr:`intervals`), or at its first passage on the curve (a flight
        over ``q`` does not pass it); NaN where ``q`` is never reached on the curve."""
        qs = np.asarray(q, dtype=float)
        flat = qs.reshape(-1)
        t = np.full(flat.shape, np.nan)
        qdot = np.full(flat.shape, np.nan)
        offset = 0
        for i in np.flatnonzero(self._kind == SLIDING).tolist():
            d, t0 = self._dense(i), self._pieces[i].t0
            n = d.n_intervals
            if interval is None:
                todo = np.flatnonzero(np.isnan(t))
                if todo.size and n:
                    ti, vi = d.at(flat[todo])
                    t[todo], qdot[todo] = ti + t0, vi
            elif offset <= _index(interval, self.n_intervals) < offset + n:
                ti, vi = d.at(flat, int(interval) - offset)
                t, qdot = ti + t0, vi
            offset += n
        if qs.ndim == 0:
            return float(t[0]), float(qdot[0])
        return t.reshape(qs.shape), qdot.reshape(qs.shape)


def _index(interval, n: int) -> int:
    """``interval`` checked: an integer in ``[0, n)``."""
    if isinstance(interval, bool) or not isinstance(interval, (int, np.integer)) or not 0 <= interval < n:
        raise ValueError(f"interval: must be an integer in [0, {n}) (the run's sliding intervals), got {interval!r}")
    return int(interval)
