"""The numeric wing's vocabulary, defined once: event kinds, status codes, row and column layouts.

The engine (:mod:`symvib.numeric.engine`) stores events, intervals and sweep
summaries in float arrays, because compiled code returns arrays; this module
says once what each code and each column means.  The typed records of
:mod:`symvib.numeric.events` (``EventKind``, ``Status``), the driver, the sweep's
tables, the figures and the JSON all derive their names from here.

Adding an event kind: a member of :class:`EventCode` (its name, lowercase, is
the kind's name everywhere), the code in the engine that raises it, and a line
in :data:`symvib.numeric.events.EVENT_DOCS`; ``tests/test_layout.py`` follows a
new kind through the JSON, the sweep tables and the figures.

Examples
--------
>>> EventCode.IMPACT == 0, EVENT_KINDS[EventCode.REVERSAL]
(True, 'reversal')
>>> STATUSES[StatusCode.ENERGY_BUDGET_MISMATCH]
'energy_budget_mismatch'
>>> SUMMARY_COLUMNS[Summary.t_final], SCENE_ROW[SceneRow.mu]
('t_final', 'mu')
"""
from __future__ import annotations

import enum

__all__ = ["EventCode", "StatusCode", "EventColumn", "IntervalColumn", "SceneRow", "Summary",
           "EVENT_KINDS", "STATUSES", "ERROR_CODES", "EVENT_COLUMNS", "INTERVAL_COLUMNS", "SCENE_ROW",
           "SUMMARY_COLUMNS", "names"]


class EventCode(enum.IntEnum):
    """What happened at an event (physics.md, "Events"); the name, lowercase, is the kind's name."""

    IMPACT = 0
    REVERSAL = 1
    ARREST = 2
    REST_ON_LIMITER = 3
    NORMAL_SIGN_CHANGE = 4
    LEFT_CURVE = 5
    #: Unilateral contact: the particle leaves the curve and flies (physics.md, "Flight and landing" 1).
    LIFT_OFF = 6
    #: The flying particle lands on the curve (physics.md, "Flight and landing" 4).
    LANDING = 7


class StatusCode(enum.IntEnum):
    """Why a run stopped; the name, lowercase, is the status's name.  ``RUNNING`` never ends a run."""

    RUNNING = 0
    ARRESTED = 1
    RESTING_ON_LIMITER = 2
    T_MAX = 3
    MAX_EVENTS = 4
    LEFT_DOMAIN = 5
    NON_FINITE = 6
    ENERGY_BUDGET_MISMATCH = 7
    LEFT_CURVE = 8
    TOLERANCE_NOT_MET = 9
    #: The plain engine's wall-clock deadline passed (``simulate(..., wall_time=...)``); the events
    #: before it are right, the run is unfinished.
    WALL_TIME_LIMIT = 10
    #: The particle reached a singular point of the curve (a pole, a cusp, a corner) that ends the
    #: regular interval it runs on; set by the driver where the engine reports ``LEFT_DOMAIN`` there.
    REACHED_SINGULAR_POINT = 11
    #: A flying particle crossed the normal line of a limiter before landing (physics.md, "Flight and
    #: landing" 6); set by :mod:`symvib.numeric.flights`, never by the engine.
    CROSSED_LIMITER = 12


class EventColumn(enum.IntEnum):
    """Columns of the engine's event log (one row per event); ``t_err`` is the estimated error
    of ``t`` (s), the sum of the error estimates of the intervals before the event."""

    kind = 0
    t = 1
    q = 2
    qdot_before = 3
    qdot_after = 4
    energy = 5
    t_err = 6


class IntervalColumn(enum.IntEnum):
    """Columns of the engine's interval log: the ends, ``G`` at the ends, the branch ``s``,
    the direction ``sigma``, the start time, the duration, the friction work per unit mass and
    the estimated error of the duration."""

    qa = 0
    qb = 1
    Ga = 2
    Gb = 3
    s = 4
    sigma = 5
    t0 = 6
    T = 7
    W_friction = 8
    T_err = 9


class SceneRow(enum.IntEnum):
    """One scene as a row of floats (booleans 0/1): what the compiled engine takes per scene."""

    g = 0
    m = 1
    mu = 2
    k = 3
    has_left = 4
    left = 5
    has_right = 6
    right = 7
    q0 = 8
    qdot0 = 9
    t_max = 10
    max_events = 11
    unilateral = 12
    #: The plain engine's deadline (``time.monotonic()`` seconds; 0: none).  The compiled engine
    #: has no clock and ignores it.
    deadline = 13
    #: The static friction coefficient of the rest test (physics.md, "Events" 2); ``mu`` when the
    #: scene gives none.
    mu_s = 14


class Summary(enum.IntEnum):
    """Columns of a sweep's per-scene summary (status and counts stored as floats)."""

    status = 0
    events = 1
    impacts = 2
    reversals = 3
    normal_sign_changes = 4
    t_final = 5
    q_final = 6
    qdot_final = 7
    friction_work = 8
    impact_loss = 9
    E0 = 10
    E_final = 11
    zeno_ratio = 12
    t_err = 13


def names(codes: type[enum.IntEnum], *, lower: bool = False) -> tuple:
    """The members' names in code order (lowercase where ``lower``)."""
    out = tuple(c.name for c in sorted(codes))
    assert [int(c) for c in sorted(codes)] == list(range(len(out))), f"{codes.__name__}: codes must be 0..n-1"
    return tuple(n.lower() for n in out) if lower else out


#: Names of the event kinds, indexed by :class:`EventCode`.
EVENT_KINDS = names(EventCode, lower=True)
#: Names of the statuses, indexed by :class:`StatusCode`.
STATUSES = names(StatusCode, lower=True)
#: Status codes of a failed run (its numbers are not a result).
ERROR_CODES = (StatusCode.NON_FINITE, StatusCode.ENERGY_BUDGET_MISMATCH, StatusCode.TOLERANCE_NOT_MET,
               StatusCode.REACHED_SINGULAR_POINT)
EVENT_COLUMNS = names(EventColumn)
INTERVAL_COLUMNS = names(IntervalColumn)
SCENE_ROW = names(SceneRow)
SUMMARY_COLUMNS = names(Summary)
