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
from symvib.numeric.engine.scan import CRIT_STEP, End, curve_scale, grown_roots, locate, map_new, scratch
from symvib.numeric.engine.state import Outcome, Setup, Zeno
from symvib.numeric.engine.timing import (
    EPS,
    NONE,
    QUAD_BUDGET,
    QUAD_NEGATIVE,
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

__all__ = ["run", "params_of", "setup_of", "run_scale", "setup_scaled", "same_scale", "simulate_scene",
           "sample_scene", "sweep_scenes", "sweep_block", "sweep_arrays"]

#: Rows the event log starts with (it doubles when full).
EVENT_LOG_START = 64
#: Rows the interval log starts with (it doubles when full).
INTERVAL_LOG_START = 64
#: Spare event rows beyond ``max_events`` (the events of the last step).
EVENT_LOG_SPARE = 4
#: Columns of the event log, the interval log and the sweep summary.
EVENT_WIDTH, INTERVAL_WIDTH, SUMMARY_WIDTH = len(EVENT_COLUMNS), len(INTERVAL_COLUMNS), len(SUMMARY_COLUMNS)
#: An interval whose estimated time error exceeds this many times the tolerance of the time at its
#: end (``rtol (t + T) + atol``: the event times' promise) ends the run ``tolerance_not_met``: the
#: quadrature aims at the tolerance, and a miss this large is not rounding of the estimate but an
#: integral it could not resolve, or ``G`` lost to cancellation (physics.md, "Accuracy").
TOLERANCE_FACTOR = 100.0
#: Column indices as plain ints (numpy indexes faster with an int than with an IntEnum).
E_KIND, E_T, E_Q, E_BEFORE, E_AFTER, E_ENERGY, E_TERR = (int(c) for c in EventColumn)
I_QA, I_QB, I_GA, I_GB, I_S, I_SIGMA, I_T0, I_T, I_W, I_TERR = (int(c) for c in IntervalColumn)


def put_event(events, ne, kind, t, q, before, after, e, t_err):
    """Append an event (columns :class:`~symvib.numeric.layout.EventColumn`); the log doubles when full."""
    if ne == events.shape[0]:
        events = grown(events, ne, 2 * events.shape[0])
    events[ne, E_KIND] = kind.value
    events[ne, E_T] = t
    events[ne, E_Q] = q
    events[ne, E_BEFORE] = before
    events[ne, E_AFTER] = after
    events[ne, E_ENERGY] = e
    events[ne, E_TERR] = t_err
    return events, ne + 1


def put_interval(ivs, ni, qa, qb, Ga, Gb, s, sigma, t0, T, Wi, T_err):
    """Append a motion interval (columns :class:`~symvib.numeric.layout.IntervalColumn`)."""
    if ni == ivs.shape[0]:
        ivs = grown(ivs, ni, 2 * ivs.shape[0])
    ivs[ni, I_QA] = qa
    ivs[ni, I_QB] = qb
    ivs[ni, I_GA] = Ga
    ivs[ni, I_GB] = Gb
    ivs[ni, I_S] = s
    ivs[ni, I_SIGMA] = sigma
    ivs[ni, I_T0] = t0
    ivs[ni, I_T] = T
    ivs[ni, I_W] = Wi
    ivs[ni, I_TERR] = T_err
    return ivs, ni + 1


def run(S, K, cp, R, q0, qdot0, t_max, max_events, keep_intervals):
    """Simulate one scene from ``(q0, qdot0)`` until a rest, ``t_max`` or ``max_events``.

    ``S``: the scene's constants (:class:`~symvib.numeric.engine.state.Setup`); with
    ``S.unilateral`` the curve only pushes along its normal, so where ``N`` reaches 0
    (or is negative at the start of an interval) the run ends with ``LEFT_CURVE``
    (physics.md, "Events").  Returns an :class:`~symvib.numeric.engine.state.Outcome`.
    """
    g, m, mu, k, scale = S.g, S.m, S.mu, S.k, S.scale
    region, roots, count = map_new(q0, S.lo, S.hi, mu, K, cp, CRIT_STEP * scale)
    X = R.Xw
    work = scratch(1, WORK_ROWS * max(len(X), len(R.Xp)))[0]
    dummy = np.empty((1, 4))
    events = np.zeros((min(max_events + EVENT_LOG_SPARE, EVENT_LOG_START), EVENT_WIDTH))
    ne = 0
    ivs = np.zeros((INTERVAL_LOG_START if keep_intervals else 1, INTERVAL_WIDTH))
    ni = 0
    t = 0.0
    Wf = 0.0
    Wimp = 0.0
    t_err = 0.0
    q_bad = math.nan
    # The time from a turning point to the double before it that the next interval starts on.
    tail_next = 0.0
    zeno = Zeno(0.0, 0.0, 0.0, 0.0)
    status = StatusCode.RUNNING
    q = q0
    w = (K.h(q, *cp) * qdot0) ** 2
    # At rest also when w underflows to 0 (qdot0 = 1e-300): the rest test decides.
    sigma = 0 if qdot0 == 0.0 or w == 0.0 else (1 if qdot0 > 0.0 else -1)
    E0 = energy(q, w, m, g, K, cp)
    flip = False
    nsign = 1
    side = side_at(q, S.has_left, S.left, S.has_right, S.right)
    pending_impact = sigma != 0 and side == sigma
    if not (math.isfinite(E0) and finite_state(t, q, w, Wf, Wimp)):
        status = StatusCode.NON_FINITE  # e.g. qdot0 = 1e200: w = inf from the start
    elif S.unilateral and K.N_w(q, w, g, *cp) < 0.0:
        # Unilateral contact and N < 0 at the start: the particle leaves the curve at once.
        events, ne = put_event(events, ne, EventCode.LEFT_CURVE, t, q, qdot0, qdot0, E0, t_err)
        status = StatusCode.LEFT_CURVE
    elif sigma == 0:
        what, direction = rest(q, side, mu, K, cp)
        if what != SLIDE:
            code, status = rest_outcome(what)
            events, ne = put_event(events, ne, code, t, q, 0.0, 0.0, energy(q, 0.0, m, g, K, cp), t_err)
        sigma = direction
    while status == StatusCode.RUNNING:
        if S.deadline > 0.0 and clock() > S.deadline:
            status = StatusCode.WALL_TIME_LIMIT  # (the plain engine only: the compiled one has no clock)
            break
        if not finite_state(t, q, w, Wf, Wimp):
            status = StatusCode.NON_FINITE  # overflow: stop at once rather than run max_events impacts at inf
            break
        if pending_impact:
            # An impact at q with squared speed w moving sigma.
            pending_impact = False
            qd = qdot_of(q, w, sigma, K, cp)
            qd_after, w_after, loss = impact(qd, w, k, m)
            Wimp += loss
            events, ne = put_event(events, ne, EventCode.IMPACT, t, q, qd, qd_after, energy(q, w_after, m, g, K, cp),
                                   t_err)
            side = int(sigma)
            w_before = w
            w = w_after
            sigma = -sigma
            if w == 0.0:
                what, direction = rest(q, side, mu, K, cp)
                if what != SLIDE:
                    code, status = rest_outcome(what)
                    events, ne = put_event(events, ne, code, t, q, 0.0, 0.0, energy(q, 0.0, m, g, K, cp), t_err)
                    break
                sigma = direction
            else:
                applies, ratio, remaining, w_imp, w_fric = zeno_series(q, w_before, sigma, g, mu, k, m, scale, K, cp)
                if applies:
                    Wimp += w_imp
                    Wf += w_fric
                    simulated = 0
                    for j in range(ne - 1, -1, -1):
                        if int(events[j, E_KIND]) == EventCode.IMPACT and events[j, E_Q] == q:
                            simulated += 1
                        elif int(events[j, E_KIND]) != EventCode.REVERSAL:
                            break
                    t += remaining
                    t_err += 4.0 * EPS * remaining
                    zeno = Zeno(ratio, float(simulated), remaining, float(side))
                    events, ne = put_event(events, ne, EventCode.REST_ON_LIMITER, t, q, 0.0, 0.0,
                                           energy(q, 0.0, m, g, K, cp), t_err)
                    w = 0.0
                    status = StatusCode.RESTING_ON_LIMITER
                    break
            if ne >= max_events:
                status = StatusCode.MAX_EVENTS
                break
        if ne >= max_events:
            status = StatusCode.MAX_EVENTS
            break
        if flip:
            nsign = -nsign
        else:
            nsign = nsign_of(q, w, g, K, cp)
        flip = False
        if S.unilateral and nsign < 0:
            # N < 0 here (at the start, or after an impact): the particle is not held.
            events, ne = put_event(events, ne, EventCode.LEFT_CURVE, t, q, qdot_of(q, w, sigma, K, cp),
                                   qdot_of(q, w, sigma, K, cp), energy(q, w, m, g, K, cp), t_err)
            status = StatusCode.LEFT_CURVE
            break
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
        Ga = w * math.exp(2.0 * s * mu * K.alpha(q, *cp))
        end, qb, Gb = locate(q, sigma, s, Ga, S, K, cp, region, roots, count, X, R.Xp, R.Wp)
        while end == End.ROOM:
            roots = grown_roots(roots, count)
            end, qb, Gb = locate(q, sigma, s, Ga, S, K, cp, region, roots, count, X, R.Xp, R.Wp)
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
        if flag == QUAD_BUDGET or not Te <= TOLERANCE_FACTOR * (R.rtol * (t + T) + R.atol):
            # The interval's time could not be brought within its tolerance: stop at its start.
            status = StatusCode.TOLERANCE_NOT_MET
            q_bad = qb
            break
        if t + T > t_max:
            # Stop inside this interval where t reaches t_max.
            target = t_max - t
            C = Ga + 2.0 * g * Fs(s, q, mu, K, cp)
            pt = (q, Ga, C, s, sigma, S, K, cp, R, work, dummy, target, roots, count)
            qe = root_time(pt, q, qb, -target, T - target)
            Ge = max(C - 2.0 * g * Fs(s, qe, mu, K, cp), 0.0)
            Tq, Wq, Tqe, _, _, _, _, _ = quad(q, qe, Ga, Ge, s, sigma, S, K, cp, R, work, NONE, dummy, 0,
                                              roots, count)
            if keep_intervals:
                ivs, ni = put_interval(ivs, ni, q, qe, Ga, Ge, s, sigma, t, Tq, Wq, Tqe)
            Wf += m * Wq
            t = t_max
            t_err += Tqe
            q = qe
            w = math.exp(-2.0 * s * mu * K.alpha(qe, *cp)) * Ge
            status = StatusCode.T_MAX
            break
        wb = math.exp(-2.0 * s * mu * K.alpha(qb, *cp)) * Gb
        if keep_intervals:
            ivs, ni = put_interval(ivs, ni, q, qb, Ga, Gb, s, sigma, t, T, Wi, Te)
        t += T
        t_err += Te
        Wf += m * Wi
        if end == End.TURN:
            side = side_at(qb, S.has_left, S.left, S.has_right, S.right)
            what, direction = rest(qb, side, mu, K, cp)
            q, w = qb, 0.0
            code = EventCode.REVERSAL
            if what != SLIDE:
                code, status = rest_outcome(what)
            else:
                sigma = direction
                if Gb > 0.0:
                    # The turning point lies a fraction of an ulp beyond qb: the particle passes qb
                    # again, with the G of its new branch over that stretch, after tail_next.
                    s_out = sigma * nsign_of(qb, 0.0, g, K, cp)
                    G_out = turn_departure(qb, Gb, s, s_out, S, K, cp, roots, count)
                    w = G_out * math.exp(-2.0 * s_out * mu * K.alpha(qb, *cp))
                    tail_next = tail_time(qb, G_out, s_out, S, K, cp, roots, count)
            events, ne = put_event(events, ne, code, t, qb, 0.0, 0.0, energy(qb, 0.0, m, g, K, cp), t_err)
        elif end == End.LIMIT:
            q, w = qb, wb
            pending_impact = True
        elif end == End.NSIGN and S.unilateral:
            qd = qdot_of(qb, wb, sigma, K, cp)
            events, ne = put_event(events, ne, EventCode.LEFT_CURVE, t, qb, qd, qd, energy(qb, wb, m, g, K, cp),
                                   t_err)
            q, w = qb, wb
            status = StatusCode.LEFT_CURVE
        elif end == End.NSIGN:
            qd = qdot_of(qb, wb, sigma, K, cp)
            events, ne = put_event(events, ne, EventCode.NORMAL_SIGN_CHANGE, t, qb, qd, qd,
                                   energy(qb, wb, m, g, K, cp), t_err)
            q, w = qb, wb
            flip = True
        elif end == End.PASS:
            q, w = qb, wb
        elif end == End.CUT:
            # The tangent angle's branch cut: go on from the first double beyond it, where the
            # kernels' alpha is the other branch's (w is continuous; one ulp of motion is not timed).
            q, w = np.nextafter(qb, qb + sigma), wb
        else:
            q, w = qb, wb
            status = StatusCode.LEFT_DOMAIN
    if (status == StatusCode.MAX_EVENTS or status == StatusCode.WALL_TIME_LIMIT) and w == 0.0:
        sigma = 0
    if not finite_state(t, q, w, Wf, Wimp):
        status = StatusCode.NON_FINITE  # e.g. mu = 1e65: an arrest reached at t = nan
    qdot_final = qdot_of(q, w, sigma, K, cp) if sigma != 0 else 0.0
    return Outcome(status.value, ne, events, ni, ivs, t, q, qdot_final, Wf, Wimp, E0, energy(q, w, m, g, K, cp),
                   zeno, scale, t_err, q_bad)


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
                 row[SceneRow.unilateral] != 0.0, row[SceneRow.deadline])


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
    for i in range(start, stop):
        cp = params_of(cp_rows[i], cp_rows.shape[1])
        row = rows[i]
        # The curve's length scale is sampled once for a run of scenes that share it.
        if i == start or not same_scale(rows, cp_rows, i):
            scale = run_scale(row, K, cp)
        S = setup_scaled(row, K, cp, scale)
        o = run(S, K, cp, R, row[SceneRow.q0], row[SceneRow.qdot0], row[SceneRow.t_max],
                int(row[SceneRow.max_events]), False)
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
