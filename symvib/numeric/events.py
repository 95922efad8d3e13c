"""Typed, immutable records of a simulation: status, events, energy budget, result.

Like SciPy's ``OdeResult`` messages or diffrax's result codes, the outcome of
a run is an explicit :class:`Status`, and each event a typed :class:`Event`.

Examples
--------
>>> Status.ARRESTED.value, EventKind.IMPACT.value
('arrested', 'impact')
>>> status_of(StatusCode.ENERGY_BUDGET_MISMATCH), kind_of(1)
(<Status.ENERGY_BUDGET_MISMATCH: 'energy_budget_mismatch'>, <EventKind.REVERSAL: 'reversal'>)
"""
from __future__ import annotations

import enum
import json
import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from symvib.numeric import tables
from symvib.numeric.layout import ERROR_CODES, EventCode, StatusCode

__all__ = ["Status", "EventKind", "Event", "EnergyBudget", "Samples", "ZenoInfo", "Result", "MESSAGES",
           "ERROR_STATUSES", "json_safe", "status_of", "kind_of"]


def _named(name: str, codes, doc: str, *, skip=()) -> type[enum.Enum]:
    """A str-valued enum of the codes' names (lowercase values), in code order."""
    members = [(c.name, c.name.lower()) for c in sorted(codes) if c not in skip]
    out = enum.Enum(name, members, module=__name__)
    out.__doc__ = doc
    return out


#: Why a run stopped (names and codes: :class:`symvib.numeric.layout.StatusCode`).
Status = _named("Status", StatusCode, "Why a run stopped.", skip=(StatusCode.RUNNING,))
Status.is_error = property(lambda self: self in ERROR_STATUSES,
                           doc="Whether a run that stopped so failed (its numbers are not a result).")
Status.code = property(lambda self: StatusCode[self.name], doc="The engine's code of this status.")
#: What happened at an event (names and codes: :class:`symvib.numeric.layout.EventCode`).
EventKind = _named("EventKind", EventCode, "What happened at an event.")
EventKind.code = property(lambda self: EventCode[self.name], doc="The engine's code of this kind.")

#: Statuses of a failed run: the state stopped being finite, the energy budget does not close, or a
#: time could not be computed within its tolerance.
ERROR_STATUSES = tuple(Status[StatusCode(c).name] for c in ERROR_CODES)

#: One sentence per status, for reports (a status without one is an error at import).
MESSAGES = {
    Status.ARRESTED: "friction holds the particle at rest (|tan alpha| <= mu)",
    Status.RESTING_ON_LIMITER: "the particle rests against a limiter that gravity pushes it into",
    Status.T_MAX: "the time bound t_max was reached",
    Status.MAX_EVENTS: "the event bound max_events was reached",
    Status.LEFT_DOMAIN: "the particle reached an end of the curve's regular domain (a singular point)",
    Status.LEFT_CURVE: "the normal force reached 0 and the particle left the curve (unilateral contact; simulate() "
                       "and a sweep follow its flight, a run with air drag does not)",
    Status.NON_FINITE: "error: the state stopped being finite (overflow); the numbers are not a result",
    Status.ENERGY_BUDGET_MISMATCH: "error: the energy budget does not close; the numbers are not a result",
    Status.TOLERANCE_NOT_MET: "error: the time of a motion interval could not be brought within its tolerance "
                              "(rtol, atol); the run stopped at the start of that interval",
    Status.WALL_TIME_LIMIT: "the plain engine's wall-clock limit (wall_time) was reached; the events before it "
                            "are right, the run is unfinished",
    Status.CROSSED_LIMITER: "a flying particle crossed the normal line of a limiter before landing (unilateral "
                            "contact); the model has no impact of a flying particle on a limiter",
    Status.REACHED_SINGULAR_POINT: "error: the particle reached a singular point of the curve (a pole, a cusp or a "
                                   "corner), where the model ends; the events before it are right",
}
assert set(MESSAGES) == set(Status), "every status needs a message in MESSAGES"


#: Statuses and event kinds indexed by their engine codes (lookups of a run's every event).
_STATUS_BY_CODE = tuple(Status[c.name] if c != StatusCode.RUNNING else None for c in sorted(StatusCode))
_KIND_BY_CODE = tuple(EventKind[c.name] for c in sorted(EventCode))


def status_of(code) -> Status:
    """The :class:`Status` of an engine status code."""
    status = _STATUS_BY_CODE[int(code)]
    if status is None:
        raise ValueError("status code RUNNING never ends a run")
    return status


def kind_of(code) -> EventKind:
    """The :class:`EventKind` of an engine event code."""
    return _KIND_BY_CODE[int(code)]


class Event(NamedTuple):
    """One event (an immutable named tuple).

    Attributes
    ----------
    kind : EventKind
    t, q : float
        Time and position.
    qdot_before, qdot_after : float
        Generalized velocity just before and after (``-k`` times it at an impact).
    energy : float
        Total mechanical energy just after the event.
    detail : str
        Extra facts (a Zeno accumulation, a plastic impact).
    t_err : float
        Estimated error of ``t`` (s): the sum of the error estimates of the time
        quadratures of the motion intervals before the event (physics.md, "Accuracy").
    """

    kind: EventKind
    t: float
    q: float
    qdot_before: float
    qdot_after: float
    energy: float
    detail: str = ""
    t_err: float = 0.0

    def to_dict(self) -> dict:
        """JSON-ready fields."""
        out = {"kind": self.kind.value, "t": self.t, "t_err": self.t_err, "q": self.q,
               "qdot_before": self.qdot_before, "qdot_after": self.qdot_after, "energy": self.energy}
        if self.detail:
            out["detail"] = self.detail
        return out


assert set(tables.EVENT_FRAME_COLUMNS) == set(Event._fields), "every field of an Event needs its column"


@dataclass(frozen=True)
class EnergyBudget:
    """``E0 - E_final = W_friction + W_impacts (+ W_drag)``, with the residual of that balance
    (physics.md, "Energies").

    ``friction_work`` is the integral of ``mu |F_N|`` along the path (a
    quadrature independent of the closed-form ``w(q)``), ``impact_loss`` the
    sum of ``(1 - k^2) m w / 2`` over impacts, ``drag_work`` the integral of the
    drag force ``c w`` along the path (the drag path's own quadrature of ``gamma w
    h dq`` times ``m``); None for a scene without drag, whose budget, JSON and
    tables are as they were before drag existed.
    """

    initial: float
    final: float
    friction_work: float
    impact_loss: float
    #: The optional columns are keyword-only: a fifth positional number cannot land in the wrong one.
    drag_work: float | None = field(default=None, kw_only=True)
    #: ``W_landing``: the energy lost at landings (physics.md, "Flight and landing"); None for a run
    #: that never left the curve (its budget and JSON are what they were).
    landing_loss: float | None = field(default=None, kw_only=True)

    def __repr__(self) -> str:
        """As the dataclass writes it; ``drag_work`` and ``landing_loss`` only where there is one (a run
        without drag or flights reads as it did before they existed: ``benchmarks/event_snapshot.py``
        records this)."""
        names = ("initial", "final", "friction_work", "impact_loss") + tuple(
            name for name in ("drag_work", "landing_loss") if getattr(self, name) is not None)
        return f"EnergyBudget({', '.join(f'{n}={getattr(self, n)!r}' for n in names)})"

    @property
    def residual(self) -> float:
        out = self.initial - self.final - self.friction_work - self.impact_loss
        for extra in (self.drag_work, self.landing_loss):
            if extra is not None:
                out -= extra
        return out

    @property
    def relative_residual(self) -> float:
        """Residual relative to the initial energy (or to the dissipated energy if E0 is 0)."""
        lost = (abs(self.friction_work) + abs(self.impact_loss) + abs(self.drag_work or 0.0)
                + abs(self.landing_loss or 0.0))
        scale = max(abs(self.initial), lost, math.ulp(1.0))
        return abs(self.residual) / scale

    def to_dict(self) -> dict:
        out = {"initial": self.initial, "final": self.final, "friction_work": self.friction_work,
               "impact_loss": self.impact_loss, "residual": self.residual}
        if self.drag_work is not None:
            out["drag_work"] = self.drag_work
        if self.landing_loss is not None:
            out["landing_loss"] = self.landing_loss
        return out


@dataclass(frozen=True)
class ZenoInfo:
    """An accumulation of impacts at a limiter, summed as a geometric series.

    ``ratio`` is the limit ratio of successive bounce times,
    ``k sqrt(a_down / a_up)`` with the decelerations up and down the local
    slope; ``simulated`` impacts were computed event by event before the
    remaining infinitely many were summed (``remaining_time``).
    """

    limiter: str
    ratio: float
    simulated: int
    remaining_time: float
    accumulation_time: float


@dataclass(frozen=True)
class Samples:
    """Samples of every motion interval, in time order (read-only arrays of one length).

    ``interval`` numbers the motion intervals between events (0, 1, ...; an
    interval ends at each event that changes the motion); ``branch`` is
    ``s = sigma sign(N)``.  Each interval has its start and end point; at an
    impact the end of one interval holds the state before it and the start of
    the next the state after it, at the same ``t``.  SI units with the scene's
    ``m`` and ``g``:

    ``t`` [s]; ``q``, ``qdot`` (the coordinate's unit, per s); ``x``, ``z`` [m];
    ``s`` [m] the arc-length coordinate from the initial position (increasing
    with ``q``), ``path`` [m] the distance travelled (quadratures of ``h dq``);
    ``v = h qdot`` [m/s]; ``F_N`` [N] the normal force; ``F_mu`` [N] the
    friction force along the tangent (against ``v``); ``P_mu = F_mu v <= 0`` [W];
    ``Ek``, ``Ep``, ``E`` [J]; ``W_mu`` [J] the friction work since the start
    (the cumulative quadrature of ``mu |F_N| ds`` that the energy budget sums);
    ``W_impacts`` [J] the impact losses since the start.  So
    ``E + W_mu + W_impacts = E0`` at every sample (before a Zeno series, whose
    infinitely many bounces are summed at the end, not sampled).
    """

    t: np.ndarray
    q: np.ndarray
    qdot: np.ndarray
    F_N: np.ndarray
    P_mu: np.ndarray
    Ek: np.ndarray
    Ep: np.ndarray
    E: np.ndarray
    interval: np.ndarray
    branch: np.ndarray
    x: np.ndarray
    z: np.ndarray
    s: np.ndarray
    path: np.ndarray
    v: np.ndarray
    F_mu: np.ndarray
    W_mu: np.ndarray
    W_impacts: np.ndarray

    def __post_init__(self):
        for name in self.__dataclass_fields__:
            getattr(self, name).setflags(write=False)

    @classmethod
    def empty(cls) -> Samples:
        """Samples of a run without motion intervals."""
        ints = ("interval", "branch")
        return cls(**{k: np.zeros(0, dtype=int if k in ints else float) for k in cls.__dataclass_fields__})


@dataclass(frozen=True)
class Result:
    """The outcome of :func:`symvib.numeric.driver.simulate` (immutable).

    Names a ``scipy.integrate.solve_ivp`` user knows (docs/results.md sets them
    side by side): :attr:`t` and :attr:`y` (the samples' times and ``[q, qdot]``),
    :attr:`t_events` and :attr:`y_events`, :attr:`sol` (dense output),
    :attr:`success`, :attr:`message` and :attr:`status` (a :class:`Status`, not
    an int).  Tables: :meth:`events_frame`, :meth:`samples_frame`,
    :meth:`to_pandas` (pandas, the extra ``symvib[pandas]``).  The state at any
    time or position, exact from the phase trajectory: :meth:`state`, :meth:`at`
    (:mod:`symvib.numeric.dense`).
    """

    scene: object
    status: Status
    events: tuple
    energy_budget: EnergyBudget
    t_final: float
    q_final: float
    qdot_final: float
    zeno: ZenoInfo | None = None
    stats: dict = field(default_factory=dict, compare=False)
    #: Computes the samples on first use of :attr:`samples`: a function returning
    #: ``(Samples or None, error message or None)``; None for a run without samples.
    sampler: object = field(default=None, repr=False, compare=False)
    #: Builds the dense output on first use: a function of this result returning a
    #: :class:`symvib.numeric.dense.DenseOutput`; None for a run without its intervals.
    interpolant: object = field(default=None, repr=False, compare=False)
    _memo: dict = field(default_factory=dict, repr=False, compare=False)

    @property
    def samples(self) -> Samples | None:
        """Node samples of every motion interval, computed on first use (the run itself
        costs only its events); None when the run kept none or sampling failed
        (:attr:`error` says why)."""
        if "samples" not in self._memo:
            samples, error = self.sampler() if self.sampler is not None else (None, None)
            self._memo["samples"], self._memo["error"] = samples, error
        return self._memo["samples"]

    @property
    def error(self) -> str | None:
        """Why the run or its sampling failed on the plain-Python engine (an overflow), if it did."""
        return self.stats.get("error") or self._memo.get("error")

    @property
    def message(self) -> str:
        """One sentence on why the run stopped (:data:`MESSAGES`), with the interval and the remedy
        for a run that ended ``tolerance_not_met``, the point for ``reached_singular_point`` and the
        time reached for ``wall_time_limit``."""
        return self.stats.get("accuracy") or self.stats.get("stopped") or MESSAGES[self.status]

    @property
    def success(self) -> bool:
        """False when the run failed (:attr:`Status.is_error`), like ``solve_ivp``'s ``success``."""
        return not self.status.is_error

    def count(self, kind: EventKind) -> int:
        return sum(e.kind is kind for e in self.events)

    # -- solve_ivp's names --------------------------------------------------------------------------

    def require_samples(self) -> Samples:
        """:attr:`samples`, or a ValueError that says why there are none."""
        samples = self.samples
        if samples is None:
            raise ValueError("samples: this run has none (simulate(scene, samples=True), the default, keeps them"
                             + (f"; sampling failed: {self.error}" if self.error else "") + ")")
        return samples

    @property
    def t(self) -> np.ndarray:
        """Times of the samples (``samples.t``): each interval's start, Gauss nodes and end,
        so an event's time appears twice (the end of one interval, the start of the next)."""
        return self.require_samples().t

    @property
    def y(self) -> np.ndarray:
        """``[q, qdot]`` at the times :attr:`t`, shape ``(2, len(t))`` like ``solve_ivp``'s ``y``;
        at an event's time the first of the two columns holds the state before it, the second after."""
        samples = self.require_samples()
        return np.vstack((samples.q, samples.qdot))

    @property
    def t_events(self) -> list:
        """Times of the events, one array per event kind in :class:`EventCode` order
        (``result.t_events[EventCode.IMPACT]``), like ``solve_ivp``'s one per event function."""
        return [np.array([e.t for e in self.events if e.kind.code == code], dtype=float)
                for code in sorted(EventCode)]

    @property
    def y_events(self) -> list:
        """``[q, qdot]`` after each event, one array of shape ``(n, 2)`` per kind (as :attr:`t_events`)."""
        return [np.array([(e.q, e.qdot_after) for e in self.events if e.kind.code == code],
                         dtype=float).reshape(-1, 2) for code in sorted(EventCode)]

    # -- dense output -------------------------------------------------------------------------------

    @property
    def dense(self):
        """The dense output (:class:`symvib.numeric.dense.DenseOutput`), built on first use.

        Raises
        ------
        ValueError
            For a run without its intervals (``samples=False``) or one that failed.
        """
        if "dense" not in self._memo:
            if self.interpolant is None:
                raise ValueError("dense output: this run kept no intervals (simulate(scene, samples=True), the "
                                 "default, keeps them; a run with status non_finite has none)")
            self._memo["dense"] = self.interpolant(self)
        return self._memo["dense"]

    @property
    def sol(self):
        """The dense output as ``solve_ivp``'s ``sol``: ``result.sol(t)`` is ``[q, qdot]`` at ``t``."""
        return self.dense

    def state(self, t):
        """``(q, qdot)`` at time(s) ``t``, exact from the phase trajectory (paper eq. 2;
        :meth:`symvib.numeric.dense.DenseOutput.state`); right-continuous at impacts."""
        return self.dense.state(t)

    def at(self, q, interval=None):
        """``(t, qdot)`` where the particle is at ``q``: on motion interval ``interval``, or at its
        first passage (:meth:`symvib.numeric.dense.DenseOutput.at`)."""
        return self.dense.at(q, interval)

    # -- tables -------------------------------------------------------------------------------------

    def events_frame(self):
        """The events as a pandas DataFrame (columns and dtypes: :mod:`symvib.numeric.tables`)."""
        return tables.events_frame(self)

    def samples_frame(self):
        """The samples as a pandas DataFrame, one column per field of :class:`Samples`."""
        return tables.samples_frame(self)

    def sensitivities(self, wrt=("mu", "k", "qdot0", "q0", "left", "right"), **options):
        """Exact derivatives of the events and the final state with respect to ``wrt``
        (:func:`symvib.numeric.sensitivity.sensitivities`; physics.md, "Sensitivities")."""
        from symvib.numeric.sensitivity import sensitivities

        return sensitivities(self, wrt, **options)

    def to_pandas(self):
        """``(events_frame(), samples_frame())``."""
        return tables.to_pandas(self)

    def to_dict(self, *, samples: bool = False) -> dict:
        """JSON-ready data: status, events, energy budget (and samples if asked), and ``"units"``:
        the SI unit of every number, nested as the data (:func:`symvib.numeric.tables.result_units`,
        from :data:`symvib.numeric.scene.FIELD_UNITS`)."""
        out = {
            "scene": getattr(self.scene, "name", ""),
            "status": self.status.value,
            "success": self.success,
            "message": self.message,
            "t_final": self.t_final,
            "q_final": self.q_final,
            "qdot_final": self.qdot_final,
            "events": [e.to_dict() for e in self.events],
            "energy_budget": self.energy_budget.to_dict(),
        }
        kept = self.samples if samples else None
        if self.error:
            out["error"] = self.error
        if self.zeno is not None:
            out["zeno"] = {k: getattr(self.zeno, k) for k in self.zeno.__dataclass_fields__}
        if kept is not None:
            out["samples"] = {k: getattr(kept, k).tolist() for k in kept.__dataclass_fields__}
        out["units"] = tables.result_units(self, samples=kept is not None)
        return out

    def to_json(self, **kwargs) -> str:
        """Strict JSON of :meth:`to_dict`: a non-finite number is written ``null``."""
        return json.dumps(json_safe(self.to_dict(**kwargs)), indent=2, allow_nan=False)

    def event_table(self, coordinate: str = "q") -> str:
        """A readable table of the events and a summary."""
        qd = coordinate + "dot"
        head = (f"{'#':>5} {'kind':<19} {'t [s]':>18} {coordinate:>14} {qd + ' before':>14} {qd + ' after':>14} "
                f"{'E [J]':>14}")
        lines = [head, "-" * len(head)]
        for i, e in enumerate(self.events, 1):
            lines.append(f"{i:>5} {e.kind.value:<19} {e.t:>18.12f} {e.q:>14.9f} {e.qdot_before:>14.8f} "
                         f"{e.qdot_after:>14.8f} {e.energy:>14.9f}")
        b = self.energy_budget
        lines += [
            "",
            f"status: {self.status.value} ({self.message}) at t = {self.t_final:.12g} s, "
            f"{coordinate} = {self.q_final:.12g}",
            f"events: {len(self.events)} ({self.count(EventKind.IMPACT)} impacts, "
            f"{self.count(EventKind.REVERSAL)} reversals)",
            f"energy: initial {b.initial:.12g} J, final {b.final:.12g} J, friction work {b.friction_work:.12g} J, "
            f"impact loss {b.impact_loss:.12g} J, "
            + ("" if b.drag_work is None else f"drag work {b.drag_work:.12g} J, ")
            + (f"landing loss {b.landing_loss:.12g} J, " if b.landing_loss is not None else "")
            + f"residual {b.residual:.3g} J ({b.relative_residual:.2g} relative)",
        ]
        if self.zeno is not None:
            z = self.zeno
            lines.append(f"Zeno accumulation at the {z.limiter} limiter: ratio {z.ratio:.9g}, {z.simulated} "
                         f"impacts simulated, remaining time {z.remaining_time:.3g} s summed")
        return "\n".join(lines)


def json_safe(value):
    """``value`` with every non-finite float (NaN, +-inf, also NumPy's) replaced by ``None``.

    JSON has no NaN or Infinity (``json.dumps`` writes them as non-standard
    tokens that strict readers refuse), so they become ``null``.

    Examples
    --------
    >>> json_safe({"E": float("inf"), "q": [1.0, float("nan")], "n": 3})
    {'E': None, 'q': [1.0, None], 'n': 3}
    """
    if isinstance(value, dict):
        return {k: json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    if isinstance(value, np.ndarray):
        return json_safe(value.tolist())
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, np.integer):
        return int(value)
    return value
