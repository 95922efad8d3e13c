"""The event loop of one scene, and its entry points for one scene and for a sweep.

A run alternates motion intervals and events (physics.md, "Events"): from the
current state, :func:`~symvib.numeric.engine.scan.locate` finds where the
interval ends, :func:`~symvib.numeric.engine.timing.quad` how long it takes and
the friction work on it, and the end decides what happens: an impact at a
limiter (:func:`~symvib.numeric.engine.laws.impact`, perhaps the start of a Zeno
series), a turning point (the rest test
:func:`~symvib.numeric.engine.laws.rest`: arrest, rest on a limiter or reversal),
a zero of the normal force (the branch flips, or a unilateral contact ends), or
the end of the search window (the motion goes on).

Entry points (what the driver calls, compiled by numba or run as plain Python
by :mod:`symvib.numeric.engine.bind`): :func:`simulate_scene`,
:func:`sample_scene`, :func:`sweep_scenes` and its part :func:`sweep_block`.  Each takes the kernels ``K``
(a :class:`~symvib.numeric.engine.state.Kernels`, or its numba structure
:class:`~symvib.numeric.engine.compiled.KernelsType`: the same field names),
the curve's parameter values and the scene as a row of floats
(:class:`~symvib.numeric.layout.SceneRow`).

Examples
--------
>>> EVENT_LOG_START, INTERVAL_LOG_START
(64, 64)
"""
from __future__ import annotations

import math

import numpy as np

from symvib.numeric.engine.anchor import anchored_G, root_anchored
from symvib.numeric.engine.laws import (
    SLIDE,
    Fs,
    energy,
    finite_state,
    impact,
    nsign_of,
    qdot_of,
    rest,
    rest_outcome,
    side_at,
    zeno_series,
)
from symvib.numeric.engine.scan import CRIT_STEP, End, curve_scale, grown_roots, locate, map_arrays, map_start, scratch
from symvib.numeric.engine.state import NO_EVENT, Event, Interval, Outcome, RunArrays, RunState, Setup, Zeno
from symvib.numeric.engine.timing import (
    EPS,
    NONE,
    QUAD_BUDGET,
    QUAD_NEGATIVE,
    QUAD_OK,
    WORK_ROWS,
    grown,
    quad,
    root_time,
    samples,
    tail_time,
    turn_departure,
)
from symvib.numeric.layout import (
    EVENT_COLUMNS,
    INTERVAL_COLUMNS,
    SUMMARY_COLUMNS,
    EventCode,
    EventColumn,
    IntervalColumn,
    SceneRow,
    StatusCode,
    Summary,
)

__all__ = ["run", "run_on", "run_arrays", "start", "with_status", "checked", "impact_step", "after_impact",
           "impacts_at", "depart", "interval", "within_tolerance", "stop_at_t_max", "arrive", "turning_point", "finish",
           "RUN_STEPS", "params_of", "setup_of", "run_scale", "setup_scaled", "same_scale", "simulate_scene",
           "sample_scene", "sweep_scenes", "sweep_block", "sweep_arrays"]

#: Rows the event log starts with (it doubles when full).
EVENT_LOG_START = 64
#: Rows the interval log starts with (it doubles when full).
INTERVAL_LOG_START = 64
#: Spare event rows beyond ``max_events`` (the events of the last step).
EVENT_LOG_SPARE = 4
#: Most events one pass of :func:`run_on`'s loop logs (an impact, then a rest or the next
#: interval's end): the log grows before a pass that could fill it.
EVENTS_PER_PASS = 2
#: Columns of the event log, the interval log and the sweep summary.
EVENT_WIDTH, INTERVAL_WIDTH, SUMMARY_WIDTH = len(EVENT_COLUMNS), len(INTERVAL_COLUMNS), len(SUMMARY_COLUMNS)
#: An interval whose estimated time error exceeds this many times the tolerance of the time at its
#: end (``rtol (t + T) + atol``: the event times' promise) ends the run ``tolerance_not_met``: the
#: quadrature aims at the tolerance, and a miss this large is not rounding of the estimate but an
#: integral it could not resolve, or ``G`` lost to cancellation (physics.md, "Accuracy").
TOLERANCE_FACTOR = 100.0
#: The steps of :func:`run` that take and give numbers only: the compiled engine inlines them into
#: ``run`` (:mod:`~symvib.numeric.engine.bind`), where their state stays in registers.  The steps that
#: take the run's arrays (:func:`interval`, :func:`turning_point`, :func:`stop_at_t_max`,
#: :func:`impacts_at`) are calls compiled without reference counting instead: an array passed
#: to an inlined function is counted (atomically) on the way in and out.
RUN_STEPS = ("start", "with_status", "checked", "impact_step", "after_impact", "depart", "within_tolerance",
             "arrive", "finish")
#: Column indices as plain ints (numpy indexes faster with an int than with an IntEnum).
E_KIND, E_T, E_Q, E_BEFORE, E_AFTER, E_ENERGY, E_TERR = (int(c) for c in EventColumn)
I_QA, I_QB, I_GA, I_GB, I_S, I_SIGMA, I_T0, I_T, I_W, I_TERR = (int(c) for c in IntervalColumn)


def put_event(events, ne, ev):
    """Write the event ``ev`` (an :class:`~symvib.numeric.engine.state.Event`; columns
    :class:`~symvib.numeric.layout.EventColumn`) into row ``ne`` of the log; returns ``ne + 1``
    (the caller grows the log: this call neither allocates nor returns an array)."""
    events[ne, E_KIND] = ev.kind
    events[ne, E_T] = ev.t
    events[ne, E_Q] = ev.q
    events[ne, E_BEFORE] = ev.before
    events[ne, E_AFTER] = ev.after
    events[ne, E_ENERGY] = ev.energy
    events[ne, E_TERR] = ev.t_err
    return ne + 1


def put_interval(ivs, ni, iv, t0):
    """Write the motion interval ``iv`` (an :class:`~symvib.numeric.engine.state.Interval`) that
    starts at ``t0`` into row ``ni`` of the log (columns :class:`~symvib.numeric.layout.IntervalColumn`);
    returns ``ni + 1`` (the caller grows the log)."""
    ivs[ni, I_QA] = iv.qa
    ivs[ni, I_QB] = iv.qb
    ivs[ni, I_GA] = iv.Ga
    ivs[ni, I_GB] = iv.Gb
    ivs[ni, I_S] = iv.s
    ivs[ni, I_SIGMA] = iv.sigma
    ivs[ni, I_T0] = t0
    ivs[ni, I_T] = iv.T
    ivs[ni, I_W] = iv.W
    ivs[ni, I_TERR] = iv.T_err
    return ni + 1


def run(S, K, cp, R, q0, qdot0, t_max, max_events, keep_intervals):
    """Simulate one scene from ``(q0, qdot0)`` until a rest, ``t_max`` or ``max_events``
    (:func:`run_on` on arrays of its own).  Returns an :class:`~symvib.numeric.engine.state.Outcome`."""
    A = run_arrays(R, min(max_events + EVENT_LOG_SPARE, EVENT_LOG_START),
                   INTERVAL_LOG_START if keep_intervals else 1)
    return run_on(S, K, cp, R, q0, qdot0, t_max, max_events, keep_intervals, A)


def run_arrays(R, event_rows, interval_rows):
    """The arrays a run works in (:class:`~symvib.numeric.engine.state.RunArrays`), with logs of
    ``event_rows`` events and ``interval_rows`` intervals (each grows when full): a sweep allocates
    them once per block of scenes, not once per scene."""
    region, roots, count = map_arrays()
    return RunArrays(np.zeros((event_rows, EVENT_WIDTH)), np.zeros((interval_rows, INTERVAL_WIDTH)), region, roots,
                     count, scratch(1, WORK_ROWS * max(len(R.Xw), len(R.Xp)))[0], np.empty((1, 4)))


def run_on(S, K, cp, R, q0, qdot0, t_max, max_events, keep_intervals, A):
    """Simulate one scene from ``(q0, qdot0)`` until a rest, ``t_max`` or ``max_events``, in the
    arrays ``A`` (:class:`~symvib.numeric.engine.state.RunArrays`, from :func:`run_arrays`; their
    contents on entry do not matter).

    ``S``: the scene's constants (:class:`~symvib.numeric.engine.state.Setup`); with
    ``S.unilateral`` the curve only pushes along its normal, so where ``N`` reaches 0
    (or is negative at the start of an interval) the run ends with ``LEFT_CURVE``
    (physics.md, "Events").  Returns an :class:`~symvib.numeric.engine.state.Outcome`.

    The run is a loop over named steps, in the order of physics.md's "Events", on one
    state ``x`` (:class:`~symvib.numeric.engine.state.RunState`): :func:`start`; then, until
    the status is no longer ``RUNNING``, :func:`checked` (deadline, overflow), at a limiter
    :func:`impact_step` (event 1) and :func:`after_impact` (a plastic impact's rest test, or
    a Zeno series summed), :func:`depart` (the branch and the start of the next interval),
    :func:`interval` (its end and time: physics.md, "Time"), :func:`stop_at_t_max` inside it,
    else :func:`arrive` at its end (an impact next, ``N = 0`` (event 3), the domain's end
    (event 4)) and at a turning point :func:`turning_point` (event 2, the rest test); last
    :func:`finish`.  Each step returns the new state and at most one
    :class:`~symvib.numeric.engine.state.Event` (numbers only), which the loop logs.  Compiled,
    the split costs nothing: the steps on numbers alone (:data:`RUN_STEPS`) are inlined, and
    those that read the run's arrays are calls without reference counting.
    """
    events, ivs, region, roots, count, work, dummy = A
    map_start(region, roots, count, q0, S.lo, S.hi, S.mu, K, cp, CRIT_STEP * S.scale)
    ne = 0
    ni = 0
    zeno = Zeno(0.0, 0.0, 0.0, 0.0)
    q_bad = math.nan
    x, E0, ev = start(S, K, cp, q0, qdot0)
    if ev.kind != NO_EVENT:
        ne = put_event(events, ne, ev)
    s = 0
    again = False  # the interval from x on the branch s is to be asked for again (its roots were full)
    while x.status == StatusCode.RUNNING:
        # The arrays grow here, outside the loop of passes: numba counts the references of an
        # array a loop rebinds on every pass of that loop.
        if ne + EVENTS_PER_PASS > events.shape[0]:
            events = grown(events, ne, 2 * events.shape[0])
        if keep_intervals and ni == ivs.shape[0]:
            ivs = grown(ivs, ni, 2 * ivs.shape[0])
        if again:
            roots = grown_roots(roots, count)
        while x.status == StatusCode.RUNNING:
            if ne + EVENTS_PER_PASS > events.shape[0] or (keep_intervals and ni == ivs.shape[0]):
                break  # (to grow the logs)
            if not again:
                x = checked(x, S)
                if x.status != StatusCode.RUNNING:
                    break
                if x.impact_next:
                    w_before = x.w
                    x, ev = impact_step(x, S, K, cp)
                    ne = put_event(events, ne, ev)
                    x, ev, series, ratio, remaining = after_impact(x, w_before, S, K, cp)
                    if ev.kind != NO_EVENT:
                        if series:  # a Zeno series, after the impacts simulated at this limiter
                            zeno = Zeno(ratio, float(impacts_at(events, ne, x.q)), remaining, float(x.side))
                        ne = put_event(events, ne, ev)
                        break
                if ne >= max_events:
                    x = with_status(x, StatusCode.MAX_EVENTS)
                    break
                x, ev, s = depart(x, S, K, cp, t_max)
                if ev.kind != NO_EVENT:
                    ne = put_event(events, ne, ev)
                    break
            iv = interval(x, s, S, K, cp, R, region, roots, count, work, dummy)
            again = iv.end == End.ROOM
            if again:
                break  # (to grow the roots)
            if not within_tolerance(x, iv, R.rtol, R.atol):
                # The interval's time could not be brought within its tolerance: stop at its start.
                x = with_status(x, StatusCode.TOLERANCE_NOT_MET)
                q_bad = iv.qb
                break
            t0 = x.t
            if t0 + iv.T > t_max:
                x, iv = stop_at_t_max(x, iv, t_max, S, K, cp, R, work, dummy, roots, count)
            else:
                x, ev = arrive(x, iv, S, K, cp)
                if iv.end == End.TURN:
                    x, ev = turning_point(x, iv, S, K, cp, roots, count)
                if ev.kind != NO_EVENT:
                    ne = put_event(events, ne, ev)
            if keep_intervals:
                ni = put_interval(ivs, ni, iv, t0)
    x, qdot, E = finish(x, S, K, cp)
    return Outcome(x.status.value, ne, events, ni, ivs, x.t, x.q, qdot, x.W_friction, x.W_impacts, E0, E, zeno,
                   S.scale, x.t_err, q_bad)


def start(S, K, cp, q0, qdot0):
    """The state at the start, its energy ``E0`` and its event (a start at rest: the rest test).

    A start on a limiter moving into it is an impact next; ``qdot0`` with ``w`` of
    ``inf`` ends the run ``NON_FINITE`` at once; a unilateral contact with ``N < 0``
    ``LEFT_CURVE``.  Returns ``(x, E0, event)``.
    """
    t = 0.0
    t_err = 0.0
    w = (K.h(q0, *cp) * qdot0) ** 2
    # At rest also when w underflows to 0 (qdot0 = 1e-300): the rest test decides.
    sigma = 0 if qdot0 == 0.0 or w == 0.0 else (1 if qdot0 > 0.0 else -1)
    E0 = energy(q0, w, S.m, S.g, K, cp)
    side = side_at(q0, S.has_left, S.left, S.has_right, S.right)
    impact_next = sigma != 0 and side == sigma
    status = StatusCode.RUNNING
    ev = Event(NO_EVENT, t, q0, 0.0, 0.0, 0.0, t_err)
    if not (math.isfinite(E0) and finite_state(t, q0, w, 0.0, 0.0)):
        status = StatusCode.NON_FINITE  # e.g. qdot0 = 1e200: w = inf from the start
    elif S.unilateral and K.N_w(q0, w, S.g, *cp) < 0.0:
        # Unilateral contact and N < 0 at the start: the particle leaves the curve at once.
        ev = Event(EventCode.LEFT_CURVE.value, t, q0, qdot0, qdot0, E0, t_err)
        status = StatusCode.LEFT_CURVE
    elif sigma == 0:
        what, direction = rest(q0, side, S.mu_s, K, cp)
        if what != SLIDE:
            code, status = rest_outcome(what)
            ev = Event(code.value, t, q0, 0.0, 0.0, energy(q0, 0.0, S.m, S.g, K, cp), t_err)
        sigma = direction
    return RunState(t, q0, w, sigma, side, 1, False, impact_next, 0.0, 0.0, 0.0, t_err, status), E0, ev


def with_status(x, status):
    """The state ``x`` with the status ``status``."""
    return RunState(x.t, x.q, x.w, x.sigma, x.side, x.nsign, x.flip, x.impact_next, x.tail_next, x.W_friction,
                    x.W_impacts, x.t_err, status)


def checked(x, S):
    """``x``, ended ``WALL_TIME_LIMIT`` past the plain engine's deadline, or ``NON_FINITE`` on an
    overflow (stop at once rather than run ``max_events`` impacts at ``inf``)."""
    if S.deadline > 0.0 and clock() > S.deadline:
        return with_status(x, StatusCode.WALL_TIME_LIMIT)  # (the plain engine only: the compiled one has no clock)
    if not finite_state(x.t, x.q, x.w, x.W_friction, x.W_impacts):
        return with_status(x, StatusCode.NON_FINITE)
    return x


def impact_step(x, S, K, cp):
    """The impact at the limiter ``x.q`` reached with ``w = x.w`` moving ``x.sigma`` (physics.md,
    "Events" 1, :func:`~symvib.numeric.engine.laws.impact`): ``qdot -> -k qdot``, so ``w -> k^2 w``,
    the direction flips and ``(1 - k^2) m w / 2`` is lost.  Returns ``(x, event)``."""
    qd = qdot_of(x.q, x.w, x.sigma, K, cp)
    qd_after, w_after, loss = impact(qd, x.w, S.k, S.m)
    ev = Event(EventCode.IMPACT.value, x.t, x.q, qd, qd_after, energy(x.q, w_after, S.m, S.g, K, cp), x.t_err)
    return RunState(x.t, x.q, w_after, -x.sigma, int(x.sigma), x.nsign, x.flip, False, x.tail_next, x.W_friction,
                    x.W_impacts + loss, x.t_err, x.status), ev


def after_impact(x, w_before, S, K, cp):
    """After an impact (``w_before`` the squared speed before it): at rest (``k = 0``) the rest
    test (:func:`~symvib.numeric.engine.laws.rest`) says whether the particle stays on the limiter or
    slides off; else, where the bounces form a Zeno series (physics.md, "Events"), its infinitely many
    bounces are summed and the particle rests on the limiter.

    Returns ``(x, event, series, ratio, remaining)``: the event of a rest (or none), whether a
    series was summed, its ratio and its time.
    """
    q, side = x.q, x.side
    if x.w == 0.0:
        what, direction = rest(q, side, S.mu_s, K, cp)
        if what != SLIDE:
            code, status = rest_outcome(what)
            ev = Event(code.value, x.t, q, 0.0, 0.0, energy(q, 0.0, S.m, S.g, K, cp), x.t_err)
            return with_status(x, status), ev, False, 0.0, 0.0
        slides = RunState(x.t, q, x.w, direction, side, x.nsign, x.flip, x.impact_next, x.tail_next, x.W_friction,
                          x.W_impacts, x.t_err, x.status)
        return slides, Event(NO_EVENT, x.t, q, 0.0, 0.0, 0.0, x.t_err), False, 0.0, 0.0
    applies, ratio, remaining, w_imp, w_fric = zeno_series(q, w_before, x.sigma, S.g, S.mu, S.k, S.m, S.scale, K, cp)
    if not applies:
        return x, Event(NO_EVENT, x.t, q, 0.0, 0.0, 0.0, x.t_err), False, 0.0, 0.0
    t = x.t + remaining
    t_err = x.t_err + 4.0 * EPS * remaining
    ev = Event(EventCode.REST_ON_LIMITER.value, t, q, 0.0, 0.0, energy(q, 0.0, S.m, S.g, K, cp), t_err)
    return RunState(t, q, 0.0, x.sigma, side, x.nsign, x.flip, x.impact_next, x.tail_next, x.W_friction + w_fric,
                    x.W_impacts + w_imp, t_err, StatusCode.RESTING_ON_LIMITER), ev, True, ratio, remaining


def impacts_at(events, ne, q):
    """The impacts at ``q`` that end the log's first ``ne`` events (reversals between them
    skipped): the bounces simulated before a Zeno series."""
    simulated = 0
    for j in range(ne - 1, -1, -1):
        if int(events[j, E_KIND]) == EventCode.IMPACT and events[j, E_Q] == q:
            simulated += 1
        elif int(events[j, E_KIND]) != EventCode.REVERSAL:
            break
    return simulated


def depart(x, S, K, cp, t_max):
    """The start of the next motion interval: the normal force's sign (flipped after ``N = 0``,
    physics.md, "Events" 3; a unilateral contact with ``N < 0`` leaves the curve), the branch ``s
    = sigma sign(N)``, one double past the tangent angle's branch cut, and the time from a turning
    point to the double the interval starts on.  Returns ``(x, event, s)``."""
    t, q, w, sigma, t_err, tail_next = x.t, x.q, x.w, x.sigma, x.t_err, x.tail_next
    nsign = -x.nsign if x.flip else nsign_of(q, w, S.g, K, cp)
    if S.unilateral and nsign < 0:
        # N < 0 here (at the start, or after an impact): the particle is not held.
        qd = qdot_of(q, w, sigma, K, cp)
        ev = Event(EventCode.LEFT_CURVE.value, t, q, qd, qd, energy(q, w, S.m, S.g, K, cp), t_err)
        return RunState(t, q, w, sigma, x.side, nsign, False, x.impact_next, tail_next, x.W_friction, x.W_impacts,
                        t_err, StatusCode.LEFT_CURVE), ev, 0
    s = sigma * nsign
    q_next = np.nextafter(q, q + sigma)
    if abs(K.alpha(q_next, *cp) - K.alpha(q, *cp)) > math.pi:
        # q is on the tangent angle's branch cut (a start, an impact or a turn there): go on
        # from the first double beyond it, on the branch the motion is on (as at End.CUT).
        q = q_next
    if tail_next > 0.0:
        t = min(t + tail_next, t_max)  # from the turning point, past the double it was stopped on, to q
        t_err += 4.0 * EPS * tail_next
        tail_next = 0.0
    return RunState(t, q, w, sigma, x.side, nsign, False, x.impact_next, tail_next, x.W_friction, x.W_impacts, t_err,
                    x.status), Event(NO_EVENT, t, q, 0.0, 0.0, 0.0, t_err), s


def interval(x, s, S, K, cp, R, region, roots, count, work, dummy):
    """The motion interval from ``x`` on the branch ``s``: where it ends
    (:func:`~symvib.numeric.engine.scan.locate`: a limiter, a turning point, ``N = 0``, the search
    window's or the domain's end) and its time and friction work
    (:func:`~symvib.numeric.engine.timing.quad`; physics.md, "Time"); an
    :class:`~symvib.numeric.engine.state.Interval`, whose ``end`` is ``End.ROOM`` when ``roots`` is
    full (grow it and ask again).  A turning point the search stepped over (``G < 0`` at a node:
    a narrow dip of ``G``) is found and the interval ends there."""
    q, sigma = x.q, x.sigma
    Ga = x.w * math.exp(2.0 * s * S.mu * K.alpha(q, *cp))
    end, qb, Gb = locate(q, sigma, s, Ga, S, K, cp, region, roots, count, R.Xw, R.Xp, R.Wp)
    if end == End.ROOM:
        return Interval(q, qb, Ga, Gb, s, sigma, end, 0.0, 0.0, 0.0, QUAD_OK)
    T, Wi, Te, flag, _, q_ok, G_ok, q_neg = quad(q, qb, Ga, Gb, s, sigma, S, K, cp, R, work, NONE, dummy, 0,
                                                 roots, count)
    if flag == QUAD_NEGATIVE:
        # G < 0 inside: a turning point the search stepped over (a narrow dip of G).
        G_neg = anchored_G(q_neg, q_ok, G_ok, s, S, K, cp, R.Xp, R.Wp, roots, count)
        if G_neg < 0.0 < G_ok:
            qb, Gb = root_anchored(q_ok, G_ok, q_neg, G_neg, math.nan, s, S, K, cp, R.Xp, R.Wp, roots, count)
            end = End.TURN
            T, Wi, Te, flag, _, _, _, _ = quad(q, qb, Ga, Gb, s, sigma, S, K, cp, R, work, NONE, dummy, 0,
                                               roots, count)
        if flag == QUAD_NEGATIVE:
            flag = QUAD_BUDGET
    if end == End.TURN and Gb > 0.0:
        T += tail_time(qb, Gb, s, S, K, cp, roots, count)  # to the root, past the double it stops on
    return Interval(q, qb, Ga, Gb, s, sigma, end, T, Wi, Te, flag)


def within_tolerance(x, iv, rtol, atol):
    """Whether the interval's time is within its tolerance (the rules' ``rtol, atol``): the quadrature's
    budget was enough and its estimated error at most :data:`TOLERANCE_FACTOR` times the tolerance of
    the time at its end.  (Numbers, not the rules: their arrays passed to this inlined step would be
    reference-counted on every interval.)"""
    return iv.flag != QUAD_BUDGET and iv.T_err <= TOLERANCE_FACTOR * (rtol * (x.t + iv.T) + atol)


def stop_at_t_max(x, iv, t_max, S, K, cp, R, work, dummy, roots, count):
    """The state where ``t`` reaches ``t_max`` inside the interval ``iv`` (status ``T_MAX``), and the
    part of ``iv`` before it: the point is where the time from the interval's start is ``t_max - t``
    (:func:`~symvib.numeric.engine.timing.root_time`).  Returns ``(x, interval)``."""
    g, mu = S.g, S.mu
    q, Ga, s, sigma = iv.qa, iv.Ga, iv.s, iv.sigma
    target = t_max - x.t
    C = Ga + 2.0 * g * Fs(s, q, mu, K, cp)
    pt = (q, Ga, C, s, sigma, S, K, cp, R, work, dummy, target, roots, count)
    qe = root_time(pt, q, iv.qb, -target, iv.T - target)
    Ge = max(C - 2.0 * g * Fs(s, qe, mu, K, cp), 0.0)
    Tq, Wq, Tqe, flag, _, _, _, _ = quad(q, qe, Ga, Ge, s, sigma, S, K, cp, R, work, NONE, dummy, 0, roots, count)
    w = math.exp(-2.0 * s * mu * K.alpha(qe, *cp)) * Ge
    return (RunState(t_max, qe, w, sigma, x.side, x.nsign, x.flip, x.impact_next, x.tail_next,
                     x.W_friction + S.m * Wq, x.W_impacts, x.t_err + Tqe, StatusCode.T_MAX),
            Interval(q, qe, Ga, Ge, s, sigma, iv.end, Tq, Wq, Tqe, flag))


def arrive(x, iv, S, K, cp):
    """The state at the end of the interval ``iv``: its time and friction work added, and what its
    end makes of the motion: at a limiter an impact next (physics.md, "Events" 1), at ``N = 0`` the
    branch flips or a unilateral contact ends (3), the search window's end goes on, a branch cut of
    the tangent angle goes on from the first double beyond it, the domain's end ends the run (4).
    A turning point (2) is :func:`turning_point`'s.  Returns ``(x, event)``."""
    t = x.t + iv.T
    t_err = x.t_err + iv.T_err
    Wf = x.W_friction + S.m * iv.W
    qb, sigma, end = iv.qb, x.sigma, iv.end
    ev = Event(NO_EVENT, t, qb, 0.0, 0.0, 0.0, t_err)
    if end == End.TURN:
        return RunState(t, qb, 0.0, sigma, x.side, x.nsign, x.flip, x.impact_next, x.tail_next, Wf, x.W_impacts,
                        t_err, x.status), ev
    wb = math.exp(-2.0 * iv.s * S.mu * K.alpha(qb, *cp)) * iv.Gb
    q, impact_next, flip, status = qb, x.impact_next, x.flip, x.status
    if end == End.LIMIT:
        impact_next = True
    elif end == End.NSIGN:
        qd = qdot_of(qb, wb, sigma, K, cp)
        if S.unilateral:
            ev = Event(EventCode.LEFT_CURVE.value, t, qb, qd, qd, energy(qb, wb, S.m, S.g, K, cp), t_err)
            status = StatusCode.LEFT_CURVE
        else:
            ev = Event(EventCode.NORMAL_SIGN_CHANGE.value, t, qb, qd, qd, energy(qb, wb, S.m, S.g, K, cp), t_err)
            flip = True
    elif end == End.CUT:
        # The tangent angle's branch cut: go on from the first double beyond it, where the
        # kernels' alpha is the other branch's (w is continuous; one ulp of motion is not timed).
        q = np.nextafter(qb, qb + sigma)
    elif end != End.PASS:
        status = StatusCode.LEFT_DOMAIN
    return RunState(t, q, wb, sigma, x.side, x.nsign, flip, impact_next, x.tail_next, Wf, x.W_impacts, t_err,
                    status), ev


def turning_point(x, iv, S, K, cp, roots, count):
    """At the turning point that ends the interval ``iv`` (the state ``x`` there at rest, physics.md,
    "Events" 2): the rest test (:func:`~symvib.numeric.engine.laws.rest`) says arrest, rest on a
    limiter, or reversal; a reversal leaves on the branch of its new direction, from the double
    before the turning point (``G > 0`` there: the particle passes it again after ``tail_next``).
    Returns ``(x, event)``."""
    qb, Gb, s = iv.qb, iv.Gb, iv.s
    side = side_at(qb, S.has_left, S.left, S.has_right, S.right)
    what, direction = rest(qb, side, S.mu_s, K, cp)
    ev = Event(EventCode.REVERSAL.value, x.t, qb, 0.0, 0.0, energy(qb, 0.0, S.m, S.g, K, cp), x.t_err)
    if what != SLIDE:
        code, status = rest_outcome(what)
        ev = Event(code.value, x.t, qb, 0.0, 0.0, ev.energy, x.t_err)
        return RunState(x.t, qb, 0.0, x.sigma, side, x.nsign, x.flip, x.impact_next, x.tail_next, x.W_friction,
                        x.W_impacts, x.t_err, status), ev
    sigma = direction
    w = 0.0
    tail_next = x.tail_next
    if Gb > 0.0:
        # The turning point lies a fraction of an ulp beyond qb: the particle passes qb
        # again, with the G of its new branch over that stretch, after tail_next.
        s_out = sigma * nsign_of(qb, 0.0, S.g, K, cp)
        G_out = turn_departure(qb, Gb, s, s_out, S, K, cp, roots, count)
        w = G_out * math.exp(-2.0 * s_out * S.mu * K.alpha(qb, *cp))
        tail_next = tail_time(qb, G_out, s_out, S, K, cp, roots, count)
    return RunState(x.t, qb, w, sigma, side, x.nsign, x.flip, x.impact_next, tail_next, x.W_friction, x.W_impacts,
                    x.t_err, x.status), ev


def finish(x, S, K, cp):
    """The final state: at rest when ``max_events`` or the deadline stopped it with ``w = 0``,
    ``NON_FINITE`` when a number overflowed (e.g. ``mu = 1e65``: an arrest reached at ``t = nan``).
    Returns ``(x, qdot, E)``: the state, its speed ``qdot`` and its energy."""
    sigma, status = x.sigma, x.status
    if (status == StatusCode.MAX_EVENTS or status == StatusCode.WALL_TIME_LIMIT) and x.w == 0.0:
        sigma = 0
    if not finite_state(x.t, x.q, x.w, x.W_friction, x.W_impacts):
        status = StatusCode.NON_FINITE
    qdot = qdot_of(x.q, x.w, sigma, K, cp) if sigma != 0 else 0.0
    return (RunState(x.t, x.q, x.w, sigma, x.side, x.nsign, x.flip, x.impact_next, x.tail_next, x.W_friction,
                     x.W_impacts, x.t_err, status), qdot, energy(x.q, x.w, S.m, S.g, K, cp))


def clock():
    """The wall clock (s) a run's deadline (:attr:`~symvib.numeric.engine.state.Setup.deadline`) is
    read on.  The compiled engine has none (this 0 never passes a deadline): it runs the largest
    ``max_events`` in minutes; the plain engine takes ``time.monotonic``
    (:data:`symvib.numeric.engine.plain.PRIMITIVES`), where 100,000 events take about a minute."""
    return 0.0


def params_of(row, n):
    """The first ``n`` values of a parameter row as the tuple the kernels take (``*cp``).

    :mod:`symvib.numeric.engine.bind` gives the compiled engine a version with ``n``
    fixed at compile time (numba builds tuples of a static length only).
    """
    return tuple(row[:n])


def setup_of(row, K, cp):
    """The scene constants (:class:`~symvib.numeric.engine.state.Setup`) of a scene row, with the
    length scale of the run taken from the curve (:func:`~symvib.numeric.engine.scan.curve_scale`)."""
    return setup_scaled(row, K, cp, run_scale(row, K, cp))


def run_scale(row, K, cp):
    """The length scale of the run of a scene row (:func:`~symvib.numeric.engine.scan.curve_scale`)."""
    lo, hi = K.domain(*cp)
    return curve_scale(K, cp, row[SceneRow.q0], lo, hi, row[SceneRow.has_left] != 0.0, row[SceneRow.left],
                       row[SceneRow.has_right] != 0.0, row[SceneRow.right], K.q_scale(*cp))


def setup_scaled(row, K, cp, scale):
    """:func:`setup_of` with the run's length scale given."""
    lo, hi = K.domain(*cp)
    return Setup(row[SceneRow.g], row[SceneRow.m], row[SceneRow.mu], row[SceneRow.k], row[SceneRow.has_left] != 0.0,
                 row[SceneRow.left], row[SceneRow.has_right] != 0.0, row[SceneRow.right], lo, hi, scale,
                 row[SceneRow.unilateral] != 0.0, row[SceneRow.deadline], row[SceneRow.mu_s])


def same_scale(rows, cp_rows, i):
    """Whether scene ``i`` of a sweep has the length scale of scene ``i - 1``: the same curve
    parameters and limiters (and start, where a limiter is missing: :func:`run_scale`)."""
    # (elements, not row views: a view counts a reference to the array all threads share)
    for c in (SceneRow.has_left, SceneRow.left, SceneRow.has_right, SceneRow.right):
        if rows[i, c] != rows[i - 1, c]:
            return False
    if (rows[i, SceneRow.has_left] == 0.0 or rows[i, SceneRow.has_right] == 0.0) and \
            rows[i, SceneRow.q0] != rows[i - 1, SceneRow.q0]:
        return False
    for c in range(cp_rows.shape[1]):
        if cp_rows[i, c] != cp_rows[i - 1, c]:
            return False
    return True


def simulate_scene(K, cp, row, R, keep):
    """Entry point: run the scene ``row`` (keeping its intervals when ``keep``); an Outcome."""
    S = setup_of(row, K, cp)
    return run(S, K, cp, R, row[SceneRow.q0], row[SceneRow.qdot0], row[SceneRow.t_max],
               int(row[SceneRow.max_events]), keep)


def sample_scene(K, cp, row, R, ivs, ni, pieces):
    """Entry point: samples of the logged intervals of a run of ``row``, each cut into ``pieces``
    (columns :class:`~symvib.numeric.engine.timing.SampleColumn`), and their motion-interval index."""
    return samples(ivs, ni, setup_of(row, K, cp), K, cp, R, pieces)


def sweep_scenes(K, rows, cp_rows, R, max_log):
    """Entry point: run many scenes of one curve (rows of :class:`~symvib.numeric.layout.SceneRow`
    values and of parameter values).

    Returns the per-scene summary (columns :class:`~symvib.numeric.layout.Summary`) and,
    when ``max_log > 0``, the first ``max_log`` events of each scene.  The compiled
    engine runs :func:`sweep_block` on threads instead
    (:func:`symvib.numeric.engine.bind.threaded_sweep`).
    """
    out, logs = sweep_arrays(rows.shape[0], max_log)
    sweep_block(K, rows, cp_rows, R, max_log, out, logs, 0, rows.shape[0])
    return out, logs


def sweep_arrays(n, max_log):
    """The summary and event-log arrays of a sweep of ``n`` scenes (zeros)."""
    return np.zeros((n, SUMMARY_WIDTH)), np.zeros((n, max(max_log, 1), EVENT_WIDTH))


def sweep_block(K, rows, cp_rows, R, max_log, out, logs, start, stop):
    """Entry point: scenes ``start`` to ``stop - 1`` of a sweep, their summaries into ``out``
    and their first ``max_log`` events into ``logs`` (see :func:`sweep_scenes`)."""
    scale = 0.0
    A = run_arrays(R, EVENT_LOG_START, 1)   # (reused by every scene of the block)
    for i in range(start, stop):
        cp = params_of(cp_rows[i], cp_rows.shape[1])
        row = rows[i]
        # The curve's length scale is sampled once for a run of scenes that share it.
        if i == start or not same_scale(rows, cp_rows, i):
            scale = run_scale(row, K, cp)
        S = setup_scaled(row, K, cp, scale)
        o = run_on(S, K, cp, R, row[SceneRow.q0], row[SceneRow.qdot0], row[SceneRow.t_max],
                   int(row[SceneRow.max_events]), False, A)
        impacts = 0
        reversals = 0
        flips = 0
        for j in range(o.n_events):
            kind = int(o.events[j, EventColumn.kind])
            if kind == EventCode.IMPACT:
                impacts += 1
            elif kind == EventCode.REVERSAL:
                reversals += 1
            elif kind == EventCode.NORMAL_SIGN_CHANGE:
                flips += 1
            if j < max_log:
                for c in range(EVENT_WIDTH):
                    logs[i, j, c] = o.events[j, c]
        out[i, Summary.status] = o.status
        out[i, Summary.events] = o.n_events
        out[i, Summary.impacts] = impacts
        out[i, Summary.reversals] = reversals
        out[i, Summary.normal_sign_changes] = flips
        out[i, Summary.t_final] = o.t
        out[i, Summary.q_final] = o.q
        out[i, Summary.qdot_final] = o.qdot
        out[i, Summary.friction_work] = o.W_friction
        out[i, Summary.impact_loss] = o.W_impacts
        out[i, Summary.E0] = o.E0
        out[i, Summary.E_final] = o.E_final
        out[i, Summary.zeno_ratio] = o.zeno.ratio
        out[i, Summary.t_err] = o.t_err


#: The kernels of the curve a compiled engine is specialized to: a global of the entries
#: below, which :mod:`symvib.numeric.engine.bind` sets in each curve's compiled copy (so
#: numba inlines the kernels and caches the copy on disk under the curve's name).
BOUND_KERNELS = None


def simulate_bound(cp, row, R, keep):
    """:func:`simulate_scene` with the bound curve's kernels."""
    return simulate_scene(BOUND_KERNELS, cp, row, R, keep)


def sample_bound(cp, row, R, ivs, ni, pieces):
    """:func:`sample_scene` with the bound curve's kernels."""
    return sample_scene(BOUND_KERNELS, cp, row, R, ivs, ni, pieces)


def sweep_bound(rows, cp_rows, R, max_log, out, logs, start, stop):
    """:func:`sweep_block` with the bound curve's kernels."""
    sweep_block(BOUND_KERNELS, rows, cp_rows, R, max_log, out, logs, start, stop)
