"""A unilateral run with flights: the engine's sliding stretches, and flights between them
(physics.md, "Flight and landing").

The engine (:mod:`symvib.numeric.engine`) ends a unilateral sliding stretch with
status ``left_curve`` where ``N`` reaches 0; :func:`follow` takes it from there:
the lift-off, the flight and its landing (:mod:`symvib.numeric.flight`), bounces
and their accumulation, and a new sliding stretch run by the engine from the
landing point, until the run stops.  The engine's loop is not touched: a
bilateral scene, and every run that never lifts off, is what it was.
"""
from __future__ import annotations

import math
from typing import NamedTuple

from symvib.numeric.events import Event, EventKind
from symvib.numeric.flight import (
    ACCUMULATION_W,
    HORIZON,
    LEFT_STRETCH,
    TOUCHED,
    LandingNotFound,
    Stretch,
    accumulation,
    landing,
    landing_law,
    limiter_crossing,
    path,
)
from symvib.numeric.flight_pieces import Accumulated, Arc, Slide
from symvib.numeric.layout import StatusCode

__all__ = ["Followed", "Flown", "Slide", "Arc", "Accumulated", "follow", "fly", "searched_stretch", "events_of",
           "result_with_flights"]


class Followed(NamedTuple):
    """A run with flights as :func:`follow` ends it: status code, events, final state and energy, the
    energy lost to friction, impacts and landings, the estimated error of ``t``, the last engine
    outcome and the time it started at (None and nan when the run ended in flight), a sentence on a
    stop in flight (or None), and the flights and landings counted."""

    status: int
    events: list
    t: float
    q: float
    qdot: float
    E_final: float
    W_friction: float
    W_impacts: float
    W_landing: float
    t_err: float
    last: object
    t_last: float
    stopped: str | None
    flights: int
    landings: int


def searched_stretch(q, scene, lo, hi, scale):
    """``(qa, qb)``: where a landing from a launch at ``q`` is searched (physics.md, "Flight and
    landing" 6): between the limiters, else to the domain's end, at most :data:`HORIZON` length scales away."""
    qa = scene.left if scene.left is not None else max(lo, q - HORIZON * scale)
    qb = scene.right if scene.right is not None else min(hi, q + HORIZON * scale)
    return float(qa), float(qb)


def _limiter_line(stretch, q):
    """``(x, z, tx, tz)``: the limiter's point and the curve's unit tangent there."""
    x, z, dx, dz = stretch.point(q)
    h = math.hypot(dx, dz)
    return x, z, dx / h, dz / h


class Flown(NamedTuple):
    """The end of a sequence of flights and bounces (:func:`fly`): the events it logged, the energy its
    landings lost, the flights and landings, and either where sliding resumes (``slide = (t, q,
    qdot)``) or how the run stopped in flight (``stop``, a :class:`Followed` without the sums before)."""

    events: list
    W_landing: float
    flights: int
    landings: int
    slide: tuple | None
    stop: object


def fly(scene, mod, cp, st, t, x0, z0, vx, vz, u, length, n_events, t_err=0.0, log=None):
    """Flights, landings and bounces from a launch at time ``t`` from ``(x0, z0)`` with velocity ``(vx,
    vz)`` and normal speed ``u`` (0 at a lift-off) over the stretch ``st`` (:class:`~symvib.numeric.flight.Stretch`),
    until sliding resumes or the run stops in flight (physics.md, "Flight and landing" 2-6 and the
    bouncing-ball accumulation); ``length`` is the run's length scale in metres, ``n_events`` the
    events logged before; ``log``, a list, receives an :class:`Arc` per flight and an :class:`Accumulated`
    per accumulation (their landing losses before them counted from this launch).  Returns a :class:`Flown`."""
    g, m, mu, e = scene.g, scene.m, scene.mu, scene.restitution_curve
    events, W_l, flights, landings = [], 0.0, 0, 0
    log = [] if log is None else log

    def stop(status, dt, msg):
        if dt > 0.0:
            log.append(Arc(t, dt, x0, z0, vx, vz, 0.0, 0.0, W_l))
        f = _in_flight(status, t, dt, st, x0, z0, vx, vz, g, m, events, 0.0, 0.0, W_l, t_err, flights, landings, msg)
        return Flown(events, W_l, flights, landings, None, f)

    while True:
        if n_events + len(events) >= scene.max_events:
            return stop(StatusCode.MAX_EVENTS, 0.0, None)
        flights += 1
        try:
            ld = landing(st, x0, z0, vx, vz, g, u, length)
        except LandingNotFound as exc:
            return stop(StatusCode.TOLERANCE_NOT_MET, 0.0,
                        f"{exc}, in the flight launched at t = {t:.12g} s from x = {x0:.12g} m, z = {z0:.12g} m "
                        "(physics.md, \"Flight and landing\" 3); the run stops at the launch")
        t_lim, where = math.inf, ""
        for side, qL in ((-1, scene.left), (1, scene.right)):
            if qL is not None:
                tc = limiter_crossing(ld.t, x0, z0, vx, vz, g, *_limiter_line(st, qL), side)
                if tc < t_lim:
                    t_lim, where = tc, ("left" if side < 0 else "right")
        if t + min(ld.t, t_lim) > scene.t_max:
            return stop(StatusCode.T_MAX, scene.t_max - t, None)
        if t_lim <= ld.t:
            return stop(StatusCode.CROSSED_LIMITER, t_lim,
                        f"the flying particle crossed the normal line of the {where} limiter at t = {t + t_lim:.12g} "
                        "s; the model has no impact of a flying particle on a limiter (physics.md, \"Flight and "
                        "landing\" 6)")
        if ld.kind == LEFT_STRETCH:
            cut = " (beyond it the curve's kernels are not finite)" if any(st.cut) else ""
            return stop(StatusCode.LEFT_DOMAIN, ld.t,
                        f"the flying particle left the searched stretch {scene.shape.q} in [{st.qa:.12g}, "
                        f"{st.qb:.12g}] of the curve{cut} without landing, at t = {t + ld.t:.12g} s (physics.md, "
                        "\"Flight and landing\" 6)")
        # The landing (physics.md, "Flight and landing" 4).
        xl, zl, dxl, dzl = st.point(ld.q)
        h = math.hypot(dxl, dzl)
        tx, tz = dxl / h, dzl / h
        _, _, vxl, vzl = path(ld.t, x0, z0, vx, vz, g)
        law = landing_law(vxl, vzl, tx, tz, e, mu)
        log.append(Arc(t, ld.t, x0, z0, vx, vz, 0.0, 0.0, W_l))
        t += ld.t
        landings += 1
        W_l += m * law.loss
        E_after = m * (0.5 * (law.u_after ** 2 + law.v_after ** 2) + g * zl)
        how = "touch" if ld.kind == TOUCHED else f"normal velocity {law.u_before:.9g} -> {law.u_after:.9g} m/s"
        events.append(Event(EventKind.LANDING, t, ld.q, law.v_before / h, law.v_after / h, E_after,
                            f"{how}; {'sticks' if law.stick else 'slides'}", t_err))
        a_n = g * tx + float(mod.kappa_scalar(ld.q, *cp)) * law.v_after ** 2   # N of sliding (eq. 1)
        if law.u_after > 0.0 and e < 1.0 and a_n > 0.0 and law.u_after ** 2 < ACCUMULATION_W * g * length:
            # Bouncing-ball accumulation, summed on the tangent line.
            acc = accumulation(law.u_after, law.v_after, g * tz, a_n, e, mu)
            if t + acc.time > scene.t_max:   # t_max falls inside the series: stopped at the landing before it
                f = Followed(int(StatusCode.T_MAX), events, scene.t_max, ld.q, law.v_after / h, E_after, 0.0, 0.0,
                             W_l, t_err, None, math.nan, "the time bound t_max was reached during a bouncing-ball "
                             "accumulation (its state is the last landing's)", flights, landings)
                return Flown(events, W_l, flights, landings, None, f)
            q_acc = ld.q + acc.ds / h
            h_acc = float(mod.h_scalar(q_acc, *cp))
            log.append(Accumulated(t, acc.time, ld.q, law.v_after / h, q_acc, acc.v_after / h_acc, 0.0, 0.0, W_l))
            t += acc.time
            E_acc = m * (0.5 * acc.v_after ** 2 + g * float(mod.z_scalar(q_acc, *cp)))
            W_l += E_after - E_acc
            flights += acc.bounces
            events.append(Event(EventKind.LANDING, t, q_acc, law.v_after / h, acc.v_after / h_acc, E_acc,
                                f"bouncing-ball accumulation: geometric series of bounces, ratio {e:.9g}"
                                f"{', every landing sticks' if acc.stuck else ''}", t_err))
            return Flown(events, W_l, flights, landings, (t, q_acc, acc.v_after / h_acc), None)
        if law.u_after > 0.0:   # a bounce: the next flight from the landing point
            x0, z0 = xl, zl
            st.q_near = ld.q
            vx, vz = law.u_after * -tz + law.v_after * tx, law.u_after * tx + law.v_after * tz
            u = law.u_after
        else:
            return Flown(events, W_l, flights, landings, (t, ld.q, law.v_after / h), None)


def follow(scene, mod, cp, lo, hi, first, run_segment, events_of, log=None):
    """Follow a unilateral run past its lift-offs (physics.md, "Flight and landing").

    Parameters
    ----------
    scene : Scene
    mod : module
        The curve's kernels; ``cp`` their parameter values; ``(lo, hi)`` the run's regular domain.
    first : Outcome
        The engine's first sliding stretch, which ended ``left_curve``.
    run_segment : callable
        ``run_segment(q0, qdot0, t_max, max_events)``: the engine's outcome of a sliding stretch
        from ``(q0, qdot0)`` (time from 0, at most ``t_max`` and ``max_events``).
    events_of : callable
        ``events_of(outcome, t0, t_err0)``: its events as :class:`~symvib.numeric.events.Event`,
        shifted by ``t0`` and ``t_err0``, a ``left_curve`` as ``lift_off``.
    log : list, optional
        Receives the run's pieces in time order: a :class:`Slide` per sliding stretch, an
        :class:`Arc` per flight, an :class:`Accumulated` per bouncing-ball accumulation.

    Returns
    -------
    Followed
    """
    scale = float(first.scale)
    out, t_off = first, 0.0
    events = list(events_of(first, 0.0, 0.0))
    W_f, W_i, W_l, t_err = float(first.W_friction), float(first.W_impacts), 0.0, float(first.t_err)
    flights = landings = 0
    stretches = {}
    log = [] if log is None else log
    log.append(Slide(0.0, float(scene.q0), float(scene.qdot0), first, 0.0, 0.0, 0.0))

    while True:
        # The lift-off that ended the sliding stretch `out`.
        q = float(out.q)
        qa, qb = searched_stretch(q, scene, lo, hi, scale)
        if (qa, qb) not in stretches or not stretches[(qa, qb)].qa <= q <= stretches[(qa, qb)].qb:
            stretches.clear()
            stretches[(qa, qb)] = Stretch(mod, cp, qa, qb, scale, q)
        st = stretches[(qa, qb)]
        st.q_near = q
        x0, z0, dx, dz = st.point(q)
        qd = float(out.qdot)
        pieces = []
        flown = fly(scene, mod, cp, st, t_off + float(out.t), x0, z0, qd * dx, qd * dz, 0.0,
                    scale * math.hypot(dx, dz), len(events), t_err, pieces)
        log += [p._replace(W_friction=W_f, W_impacts=W_i, W_landing=W_l + p.W_landing) for p in pieces]
        events += flown.events
        W_l += flown.W_landing
        flights += flown.flights
        landings += flown.landings
        if flown.stop is not None:
            f = flown.stop
            return f._replace(events=events, W_friction=W_f, W_impacts=W_i, W_landing=W_l, flights=flights,
                              landings=landings)
        t_off, q_s, qdot_s = flown.slide
        if len(events) >= scene.max_events:
            h = float(mod.h_scalar(q_s, *cp))
            E = scene.m * (0.5 * (qdot_s * h) ** 2 + scene.g * float(mod.z_scalar(q_s, *cp)))
            return Followed(int(StatusCode.MAX_EVENTS), events, t_off, q_s, qdot_s, E, W_f, W_i, W_l, t_err, None,
                            math.nan, None, flights, landings)
        # Sliding resumes from the landing point (the rest test at qdot = 0).
        out = run_segment(q_s, qdot_s, max(scene.t_max - t_off, 0.0), scene.max_events - len(events))
        log.append(Slide(t_off, q_s, qdot_s, out, W_f, W_i, W_l))
        events += events_of(out, t_off, t_err)
        W_f += float(out.W_friction)
        W_i += float(out.W_impacts)
        t_err += float(out.t_err)
        if int(out.status) != StatusCode.LEFT_CURVE:
            return Followed(int(out.status), events, t_off + float(out.t), float(out.q), float(out.qdot),
                            float(out.E_final), W_f, W_i, W_l, t_err, out, t_off, None, flights, landings)


def _in_flight(status, t, dt, st, x0, z0, vx, vz, g, m, events, W_f, W_i, W_l, t_err, flights, landings, msg):
    """The run stopped in flight ``dt`` after a launch at ``t``: the particle's energy there, and
    ``q``, ``qdot`` of the nearest point of the curve and the tangential velocity."""
    x, z, vxe, vze = path(dt, x0, z0, vx, vz, g)
    q, _ = st.nearest(x, z)
    _, _, dx, dz = st.point(q)
    h = math.hypot(dx, dz)
    E = m * (0.5 * (vxe * vxe + vze * vze) + g * z)
    qdot = (vxe * dx + vze * dz) / (h * h)
    if msg is None and status == StatusCode.T_MAX:
        msg = f"the time bound t_max was reached in flight, at x = {x:.12g} m, z = {z:.12g} m"
    return Followed(int(status), events, t + dt, q, qdot, E, W_f, W_i, W_l, t_err, None, math.nan, msg, flights,
                    landings)


def events_of(out, t0, t_err0, plastic):
    """The events of an engine outcome as :class:`~symvib.numeric.events.Event`, shifted by ``t0`` and
    ``t_err0``; a ``left_curve`` is the ``lift_off`` it is in a run with flights."""
    from symvib.numeric.events import kind_of

    found = []
    for r in out.events[:out.n_events].tolist():
        kind = kind_of(r[0])
        if kind is EventKind.LEFT_CURVE:
            kind = EventKind.LIFT_OFF
        detail = "plastic" if plastic and kind is EventKind.IMPACT else ""
        found.append(Event(kind, t0 + r[1], r[2], r[3], r[4], r[5], detail, t_err0 + r[6]))
    return found


def result_with_flights(scene, prep, mod, eng, cp, row, R, first, backend, sampling=None):
    """The :class:`~symvib.numeric.events.Result` of a unilateral run whose first sliding stretch
    ``first`` (an engine outcome) ended ``left_curve``: :func:`follow` on the engine ``eng`` of the
    curve's kernels ``mod`` (``row``, ``R``: the run's scene row and rules).  Called by
    :func:`symvib.numeric.driver.simulate`, with ``sampling``
    (:class:`~symvib.numeric.flight_samples.Sampling`) where the run keeps its samples: the sliding
    stretches then keep their intervals, and the result has samples
    (:func:`symvib.numeric.flight_samples.samples`) and a dense output
    (:class:`symvib.numeric.flight_dense.FlightDense`); physics.md, "Flight and landing", Samples."""
    from functools import partial

    import numpy as np

    from symvib.numeric.events import EnergyBudget, Result, ZenoInfo, status_of
    from symvib.numeric.layout import SceneRow
    from symvib.numeric.trusted import checked_status

    keep = sampling is not None

    def run_segment(q0, qdot0, t_max, max_events):
        r = np.array(row, dtype=float)
        r[SceneRow.q0], r[SceneRow.qdot0] = q0, qdot0
        r[SceneRow.t_max], r[SceneRow.max_events] = t_max, max_events
        return eng.simulate(cp, r, R, keep)

    plastic = scene.k == 0.0
    log = []
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):   # (the driver catches an overflow)
        f = follow(scene, mod, cp, prep.domain.lo, prep.domain.hi, first, run_segment,
                   lambda out, t0, te0: events_of(out, t0, te0, plastic), log)
    E0 = float(first.E0)
    status = checked_status(f.status, f.t, f.q, f.qdot, E0, f.E_final, f.W_friction, f.W_impacts + f.W_landing)
    events = list(f.events)
    zinfo = None
    if f.last is not None and f.last.zeno.ratio > 0.0:
        z = f.last.zeno
        zinfo = ZenoInfo("right" if z.side > 0 else "left", float(z.ratio), int(z.simulated), float(z.remaining),
                         f.t)
        events[-1] = events[-1]._replace(detail=f"Zeno accumulation: geometric series of bounces, ratio {z.ratio:.9g}")
    stats = {"intervals": None, "backend": backend, "t_err": f.t_err, "domain": (prep.domain.lo, prep.domain.hi),
             "flights": f.flights, "landings": f.landings, "scale": float(first.scale)}
    if f.stopped:
        stats["stopped"] = f.stopped
    sampler = interpolant = None
    if keep and status != StatusCode.NON_FINITE:
        from symvib.numeric.flight_dense import FlightDense
        from symvib.numeric.flight_samples import samples

        pieces = tuple(log)
        sampler = partial(samples, scene, mod, cp, pieces, sampling, float(first.scale))
        interpolant = partial(FlightDense, mod=mod, params=cp, rules=R, pieces=pieces)
    stats["intervals"] = sum(int(p.out.n_intervals) for p in log if isinstance(p, Slide)) if keep else None
    return Result(scene=scene, status=status_of(status), events=tuple(events), sampler=sampler,
                  interpolant=interpolant, energy_budget=EnergyBudget(E0, f.E_final, f.W_friction, f.W_impacts,
                                                            landing_loss=f.W_landing),
                  t_final=f.t, q_final=f.q, qdot_final=f.qdot, zeno=zinfo, stats=stats)
