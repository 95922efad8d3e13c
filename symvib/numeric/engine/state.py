"""Named state of the engine, and the kernel interface it needs, declared once.

The engine's functions pass named tuples, not positional ones: numba compiles
named tuples (heterogeneous, with arrays and functions as fields), and plain
Python reads them as any tuple.

:data:`KERNEL_INTERFACE` is the contract between the code generator and the
engine: for each kernel the engine calls, the function of a generated module
that provides it and the arguments that come before the curve's parameters.
It is declared with the rest of a generated module's format in
:mod:`symvib.kernelformat` and named here too.
:func:`symvib.codegen.generate.generate` checks every module it writes
against it, and :func:`symvib.numeric.kernels.load` every module it loads.

Examples
--------
>>> KERNEL_INTERFACE["F_p"]
('F_p_scalar', ('q', 'mu'), 1)
>>> Kernels._fields[:6]
('F_p', 'F_m', 'dF_p', 'dF_m', 'ddF_p', 'ddF_m')
"""
from __future__ import annotations

from typing import NamedTuple

from symvib.kernelformat import KERNEL_INTERFACE  # declared with the format of a generated module

__all__ = ["KERNEL_INTERFACE", "Kernels", "Setup", "Rules", "Outcome", "Zeno", "RunState", "RunArrays", "Interval",
           "Event", "NO_EVENT"]


class Kernels(NamedTuple):
    """The curve's kernels as the engine calls them (fields: :data:`KERNEL_INTERFACE`).

    Each takes its leading arguments and then the curve's parameter values
    (``*cp``).  ``node_s`` returns ``(F_s', h, exp(s mu alpha), kappa, cos alpha)``
    at once, for the time quadrature; ``domain`` the open interval of ``q``.
    """

    F_p: object
    F_m: object
    dF_p: object
    dF_m: object
    ddF_p: object
    ddF_m: object
    node_p: object
    node_m: object
    z: object
    h: object
    dx: object
    dz: object
    alpha: object
    kappa: object
    N_w: object
    q_scale: object
    domain: object


assert Kernels._fields == tuple(KERNEL_INTERFACE), "Kernels must list KERNEL_INTERFACE in order"


class Setup(NamedTuple):
    """One scene's constants: gravity, mass, friction, restitution, limiters, the curve's
    regular domain ``(lo, hi)``, its length scale ``scale`` (``q_scale``), its contact, the
    plain engine's wall-clock deadline (``time.monotonic()`` seconds, 0: none) and the static
    friction coefficient ``mu_s >= mu`` of the rest test (physics.md, "Events" 2; sliding
    uses ``mu``)."""

    g: float
    m: float
    mu: float
    k: float
    has_left: bool
    left: float
    has_right: bool
    right: float
    lo: float
    hi: float
    scale: float
    unilateral: bool
    deadline: float
    mu_s: float


class Rules(NamedTuple):
    """Gauss-Legendre rules and tolerances of the time quadrature (:func:`symvib.numeric.driver.rules`).

    ``Xw, Ww, Sw, SWw``: nodes, weights and the transposed cumulative and weighted
    cumulative matrices of the rule for panels that start on a root; ``Xp, Wp, Sp``:
    nodes, weights and transposed cumulative matrix of the rule for every other panel;
    ``Tw, Tp``: the four rows (one after the other in one array) that give the four highest
    Legendre coefficients of an integrand from its values at the nodes of each rule (the error estimate of a panel,
    :func:`symvib.numeric.engine.timing.tail_error`); ``rtol, atol``: the tolerance a
    motion interval's time aims at (relative to its duration; seconds).
    """

    Xw: object
    Ww: object
    Sw: object
    SWw: object
    Xp: object
    Wp: object
    Sp: object
    Tw: object
    Tp: object
    rtol: float
    atol: float


class Zeno(NamedTuple):
    """A Zeno accumulation summed as a geometric series (physics.md, "Events" 3):
    the ratio of successive bounce speeds, the impacts simulated before it, the
    time the series takes and the limiter's side (+1 right, -1 left); all 0 if none."""

    ratio: float
    simulated: float
    remaining: float
    side: float


class RunState(NamedTuple):
    """The state of a run between two of its steps (:func:`symvib.numeric.engine.loop.run`; physics.md,
    "Events"): only numbers, so that the compiled steps keep it in registers.

    ``t, q, w``: time, coordinate and squared speed ``v^2``; ``sigma``: the direction of motion
    (+1, -1; 0 at rest); ``side``: the limiter at ``q`` (+1 right, -1 left, 0 none); ``nsign``: the
    sign of the normal force on the branch of the last interval; ``flip``: that interval ended where
    ``N = 0`` and the branch flips; ``impact_next``: the particle is on a limiter moving into it;
    ``tail_next``: the time from a turning point to the double next to it that the next interval
    starts on (physics.md, "Accuracy"); ``W_friction, W_impacts``: the energy lost so far;
    ``t_err``: the estimated error of ``t`` (s); ``status``: a
    :class:`~symvib.numeric.layout.StatusCode`, ``RUNNING`` until the run ends.
    """

    t: float
    q: float
    w: float
    sigma: int
    side: int
    nsign: int
    flip: bool
    impact_next: bool
    tail_next: float
    W_friction: float
    W_impacts: float
    t_err: float
    status: object


class RunArrays(NamedTuple):
    """The arrays a run writes (:func:`symvib.numeric.engine.loop.run_on`), allocated once and reused
    run after run by a sweep: the event log and the interval log (rows of
    :class:`~symvib.numeric.layout.EventColumn` and :class:`~symvib.numeric.layout.IntervalColumn`
    values; they grow when full), the scanned region, its critical points and their count per row
    (:func:`~symvib.numeric.engine.scan.map_arrays`), the time quadrature's flat scratch array
    (:data:`~symvib.numeric.engine.timing.WORK_ROWS` rows of the larger rule's length) and its
    unused output (one row)."""

    events: object
    intervals: object
    region: object
    roots: object
    count: object
    work: object
    dummy: object


class Interval(NamedTuple):
    """A motion interval (physics.md, "Events", "Time"): from ``qa`` to ``qb`` on the branch ``s``
    moving ``sigma``, with ``G = w exp(2 s mu alpha)`` at its ends, how it ends
    (:class:`~symvib.numeric.engine.scan.End`), its time ``T``, friction work ``W`` per unit mass,
    the estimated error ``T_err`` of ``T`` and the quadrature's flag
    (:data:`~symvib.numeric.engine.timing.QUAD_OK`, ...)."""

    qa: float
    qb: float
    Ga: float
    Gb: float
    s: int
    sigma: int
    end: object
    T: float
    W: float
    T_err: float
    flag: int


class Event(NamedTuple):
    """One row of the event log (columns :class:`~symvib.numeric.layout.EventColumn`) as a step
    returns it: ``kind`` an :class:`~symvib.numeric.layout.EventCode` value, or :data:`NO_EVENT`."""

    kind: int
    t: float
    q: float
    before: float
    after: float
    energy: float
    t_err: float


#: The ``kind`` of an :class:`Event` a step returns when nothing happened.
NO_EVENT = -1


class Outcome(NamedTuple):
    """What a run returns: status code, the event log (``n_events`` rows, columns
    :class:`~symvib.numeric.layout.EventColumn`), the interval log (``n_intervals``
    rows, columns :class:`~symvib.numeric.layout.IntervalColumn`), the final state,
    the energy sums, the Zeno summary, the length scale the run used, the estimated error
    of the final time (s; physics.md, "Time") and, for a run that ended
    ``tolerance_not_met``, the far end of the interval whose time missed its tolerance
    (``nan`` otherwise: the run stopped at its start, ``q``)."""

    status: int
    n_events: int
    events: object
    n_intervals: int
    intervals: object
    t: float
    q: float
    qdot: float
    W_friction: float
    W_impacts: float
    E0: float
    E_final: float
    zeno: Zeno
    scale: float
    t_err: float
    q_bad: float
