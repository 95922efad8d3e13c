"""The pieces of a run with flights, in time order (physics.md, "Flight and landing"): sliding
stretches, flights and bouncing-ball accumulations.

:func:`symvib.numeric.flights.follow` logs them as it runs; the samples
(:mod:`symvib.numeric.flight_samples`) and the dense output (:mod:`symvib.numeric.flight_dense`)
read them. Records only, so that those modules and :mod:`symvib.numeric.flights` import this one
and not each other.

Examples
--------
>>> Arc(0.5, 0.2, 0.0, 0.0, 1.0, 2.0, 0.0, 0.0, 0.0).T
0.2
"""
from __future__ import annotations

from typing import NamedTuple

__all__ = ["Slide", "Arc", "Accumulated"]


class Slide(NamedTuple):
    """A sliding stretch of a run with flights (its log, for the samples and the dense output): the
    engine's outcome ``out`` of a run from ``(q, qdot)`` that starts at time ``t0`` (the outcome's times
    count from 0), and the friction work, impact and landing losses before it (J)."""

    t0: float
    q: float
    qdot: float
    out: object
    W_friction: float
    W_impacts: float
    W_landing: float


class Arc(NamedTuple):
    """A flight (physics.md, "Flight and landing" 2): launched at time ``t0`` from ``(x0, z0)`` with
    velocity ``(vx, vz)``, flying for ``T`` s (to its landing, or to where the run stopped in it), and
    the friction work, impact and landing losses before it (J)."""

    t0: float
    T: float
    x0: float
    z0: float
    vx: float
    vz: float
    W_friction: float
    W_impacts: float
    W_landing: float


class Accumulated(NamedTuple):
    """A bouncing-ball accumulation summed on the tangent line (physics.md, "Flight and landing"):
    from time ``t0`` for ``T`` s, from ``(q0, qdot0)`` (the landing that started it) to ``(q1, qdot1)``,
    with the losses before it (J; its own loss is in the next record's ``W_landing``)."""

    t0: float
    T: float
    q0: float
    qdot0: float
    q1: float
    qdot1: float
    W_friction: float
    W_impacts: float
    W_landing: float
