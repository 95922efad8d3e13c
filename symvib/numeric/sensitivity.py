"""Exact derivatives of a run's events with respect to its parameters (physics.md, "Sensitivities").

Every event of a run is defined by a closed-form condition on the phase trajectory
(paper eq. 2): an impact where the particle reaches a limiter, a turning point
where ``G(q) = C - 2 g F_s(q)`` vanishes, and so on.  So the derivatives of an
event's position, speeds and time with respect to ``mu``, ``k``, the initial
state and the limiters follow from the implicit function theorem, interval by
interval, with the jumps at impacts and reversals carried through; nothing is
differenced.  Within an interval on branch ``s`` that starts at ``(q_a, w_a)``,
with ``E(q) = exp(2 s mu alpha(q))`` and ``f = F_s' = E (z' + s mu x')``:

    G(q)  = w_a E(q_a) - 2 g Integral_{q_a}^{q} f du,          w(q) = G(q) / E(q),
    dG/dp = D(w_a E(q_a)) + 2 g f(q_a) Dq_a - 2 g Dmu Integral_{q_a}^{q} df/dmu du,

and at its end ``q_e``: a limiter, ``Dq_e = D(limiter)``; a turning point
(``G(q*) = 0``), ``Dq* = (dG/dp)(q*) / (2 g f(q*))``, and ``w`` stays 0.  The
time ``T = Integral h dq / sqrt(w)`` is differentiated on ``q = q_a + (q_e -
q_a) u`` at fixed ``u``; the total derivative of ``w`` along the interval
vanishes at an end where ``w = 0``, so the derivative's integrand has the same
inverse-square-root ends as ``T``'s, which ``u = (1 - cos theta) / 2`` removes
(Gauss-Legendre panels in ``theta``, refined until two levels agree).

An impact maps ``w -> k^2 w``; the impact loss and (by the energy budget) the
friction work follow.  Where an event is not differentiable the table says so
instead of a number: a turning point on the friction cone's edge (arrest or
reversal changes with the parameters: the rest test's cone, ``|tan alpha| = mu_s``), a
turning point on the sliding cone's edge ``|tan alpha| = mu`` where static friction
exceeds it (a double root of ``G``: its position has no derivative), a turning point on a limiter (grazing),
a Zeno accumulation, a start at rest for ``qdot0`` (its sign chooses the
direction), and a tangential zero of the normal force.  A sign change of the normal force
that crosses (:mod:`symvib.numeric.sensitivity_normal`) and the curve's own parameters
(:mod:`symvib.numeric.sensitivity_curve`) are differentiated with the curve's jets
(:mod:`symvib.numeric.jet_kernels`; physics.md, "Sensitivities" 8 and 9), read only then.
On a unilateral curve the lift-off, the flight and its landings follow in closed form
(:mod:`symvib.numeric.sensitivity_flight`; physics.md, "Sensitivities" 10); a tangential landing, one on
the edge between sticking and sliding, and a bouncing-ball accumulation have no derivative.

Examples
--------
>>> from symvib import simulate
>>> res = simulate("paper-parabola")
>>> sens = sensitivities(res, wrt=("mu", "qdot0"))
>>> sens.events[0].kind.value, round(float(sens.t[0, 1]), 6)   # d t / d qdot0: faster, earlier
('impact', -0.027878)
>>> round(float(sens.final["t_final"][0]), 3)                  # d t_arrest / d mu
139.592
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

# Kinds and statuses by their engine codes (symvib.numeric.layout, below the records of
# symvib.numeric.events, whose Result.sensitivities calls up into this module).
from symvib.kernelformat import KernelError
from symvib.numeric.layout import EventCode, StatusCode
from symvib.numeric.sensitivity_batch import MAX_PANELS, NODES, end_integrals, time_derivatives
from symvib.numeric.sensitivity_compiled import quadratures_for
from symvib.numeric.sensitivity_curve import PARAMETERS, CurveFunctions, resolve_wrt
from symvib.numeric.sensitivity_flight import land, landing_reason, launch
from symvib.numeric.sensitivity_interval import Interval
from symvib.numeric.sensitivity_normal import TANGENTIAL_N_REASON, normal_sign_change_tangent
from symvib.numeric.sensitivity_table import Sensitivities

__all__ = ["sensitivities", "interval_tangents", "Sensitivities", "Tangents", "Leg", "PARAMETERS"]

#: Relative distance of ``|sin alpha|`` from ``mu_s |cos alpha|`` (or ``mu |cos alpha|``) below which a
#: turning point is on the edge of the static (or sliding) friction cone (the engine's rest test, with
#: ``mu_s``, decides there within ``1e-9``).
CONE_EDGE = 1e-7
#: Distance of a turning point from a limiter, in units of ``q_scale``, below which it grazes it.
GRAZING = 1e-9
#: Statuses whose final state has derivatives (the run ended on an event).
FINAL_STATUSES = (StatusCode.ARRESTED, StatusCode.RESTING_ON_LIMITER)


def sensitivities(result, wrt=PARAMETERS, *, prepared=None, through=None, compile: bool = False) -> Sensitivities:
    """Derivatives of ``result``'s events and final state with respect to ``wrt``.

    Parameters and errors as :func:`interval_tangents`, whose ``sensitivities`` this is.

    Returns
    -------
    Sensitivities
        The record (:mod:`symvib.numeric.sensitivity_table`).
    """
    return interval_tangents(result, wrt, prepared=prepared, through=through, compile=compile,
                             legs=False).sensitivities


@dataclass(frozen=True)
class Leg:
    """One motion interval of a differentiated run, from event time ``t_a`` (0 for the start) to
    ``t_e``, with the tangents ``Dt_a``, ``Dt_e`` of those times (shape (parameters,)); its
    :meth:`position_tangent` differentiates a position inside it at fixed time."""

    interval: object
    t_a: float
    t_e: float
    Dt_a: np.ndarray
    Dt_e: np.ndarray

    def position_tangent(self, q, qdot):
        """``Dq`` at fixed time of the point ``q`` (speed ``qdot``) inside the leg, or None."""
        return self.interval.position_tangent(q, qdot, self.Dt_a, self.Dt_e)


@dataclass(frozen=True)
class Tangents:
    """A differentiated run: its :class:`Sensitivities` and the :class:`Leg` of every motion interval up
    to the first event without derivatives (in time order), and the flights launched before it
    (:class:`symvib.numeric.sensitivity_flight.Flight`, in time order; a unilateral curve's)."""

    sensitivities: Sensitivities
    legs: tuple
    flights: tuple = ()


def interval_tangents(result, wrt=PARAMETERS, *, prepared=None, jets=None, through=None,
                      compile: bool = False, legs: bool = True) -> Tangents:
    """Derivatives of ``result``'s events and final state with respect to ``wrt``, and its intervals.

    Parameters
    ----------
    result : symvib.numeric.events.Result
        A run of :func:`symvib.simulate` (its scene and events are read; nothing runs again).
    wrt : str or sequence of str
        Names from :data:`PARAMETERS` (``left``/``right`` only where the scene has that limiter) or
        of the curve's parameters (:func:`symvib.numeric.sensitivity_curve.resolve_wrt`: a name that is
        both is refused, ``parameters.<name>`` is the curve's); one name alone is one parameter.
    prepared : Prepared, optional
        The scene's prepared curve (default: :func:`symvib.numeric.prepared.prepared_of`).
    jets : module, optional
        The curve's jets module (default: :func:`symvib.numeric.jet_kernels.load_jets`, read only when a
        sign change of ``N`` or a curve parameter needs it).
    through : int, optional
        The index of the last event to differentiate (default: all): the later events' rows are NaN,
        their reason says they were not asked for, and so is the final state unless it is the last
        event.  The events up to it are the same numbers as without it (a fit that matches the
        first events asks for those only).
    compile : bool
        For a run of the compiled engine, compile the quadratures with the curve's kernels if they are
        not compiled yet (a few seconds, once per curve: :mod:`symvib.numeric.sensitivity_compiled`);
        the fit and a sweep's sensitivity columns ask for it.  Default: the compiled quadratures only
        where they are compiled already, else NumPy's (the same numbers to rounding).
    legs : bool
        Whether to build the legs (their :class:`~symvib.numeric.sensitivity_interval.Interval` records);
        without them the result's ``legs`` is empty and the compiled path builds no record per interval
        (:func:`sensitivities`, which returns the table only: the same numbers).

    Returns
    -------
    Tangents

    Raises
    ------
    ValueError
        Naming ``wrt`` for an unknown, repeated or ambiguous parameter or a missing limiter, and
        ``result`` for a failed run (its numbers are not a result), ``through`` for a negative or
        not whole index.

    Notes
    -----
    Four passes: the run's path in scalars (each interval's ends, branch and ``w``); the integrals
    of ``dF_s'/dp`` over every interval at once; the tangents of positions and speeds, event by
    event; the time derivatives of every interval at once
    (:mod:`symvib.numeric.sensitivity_batch`).  Only the first and third are loops over events.  For a
    run of the compiled engine (``result.stats["backend"] == "numba"``) without curve parameters in
    ``wrt``, the second and fourth are compiled with the curve's kernels, and where no event needs the
    curve's jets a sliding stretch's four passes are one compiled call
    (:mod:`symvib.numeric.sensitivity_compiled`: the same numbers to rounding as NumPy's, the Python
    passes' bit for bit; compiled once per curve, then read from numba's disk cache).
    """
    from symvib.numeric.prepared import kernels_of

    scene = result.scene
    targets, unit = _targets(scene, wrt)
    wrt = tuple(t[0] for t in targets)
    if result.status.is_error:
        raise ValueError(f"result: the run failed ({result.status.value}); its events have no derivatives")
    if getattr(scene, "drag", 0.0):
        raise ValueError("result: a run with air drag (physics.drag) has no sensitivities yet: the derivatives of "
                         "physics.md, \"Sensitivities\" are those of the drag-free phase trajectory")
    kernels = prepared.kernels if prepared else _kernels_of(scene, kernels_of)
    if jets is None:
        from symvib.numeric.jet_kernels import load_jets

        jets = lambda: load_jets(scene.shape)  # noqa: E731 - loaded only if needed
    c = CurveFunctions(kernels, scene, targets, jets)
    c.quadratures = quadratures_for(result, kernels, c, compile=compile)   # (compiled levels, where they may be)
    P = len(wrt)
    Dmu, Dk = unit["mu"], unit["k"]
    limiter_D = {scene.left: unit["left"], scene.right: unit["right"]}

    q_a, qdot0 = scene.q0, scene.qdot0
    h0, dh0, dz0 = _start_values(c, kernels, q_a)
    w_a = h0 ** 2 * qdot0 ** 2
    Dq_a = unit["q0"].copy()
    Dw_a = (2 * h0 ** 2 * qdot0 * unit["qdot0"] + 2 * h0 * dh0 * qdot0 ** 2 * unit["q0"]
            + 2 * h0 * qdot0 ** 2 * c.geometry_dp("h", q_a)[0])
    notes = {}
    if qdot0 == 0 and "qdot0" in [t[2] for t in targets if t[1] == "scene"]:
        notes[next(t[0] for t in targets if t[1:] == ("scene", "qdot0"))] = \
            "the run starts at rest: the sign of qdot0 chooses the direction (no derivative)"

    n = len(result.events)
    last = n - 1 if through is None else _checked_through(through, n)
    # (the final state's derivatives only where they are asked for: the start's energy only then)
    at_end = bool(n) and last == n - 1 and result.status.code in FINAL_STATUSES
    if at_end:
        DE0 = c.m * (Dw_a / 2 + c.g * (dz0 * Dq_a + c.geometry_dp("z", q_a)[0]))
    events = result.events
    path = _Path(q_a, w_a, Dq_a, Dw_a, np.zeros(P), 0.0, tuple(np.full((4, n, P), np.nan)), [], np.zeros(P),
                 np.zeros(P))
    units = (Dmu, Dk, limiter_D, legs)
    i, broken, first, flight = 0, "", None, None
    flights = []
    while i <= last and not broken:
        ev = events[i]
        if _code(ev.kind) != EventCode.LANDING:       # sliding, up to a lift-off or a landing
            i, broken, first, flight = _slide(c, scene, events, i, last, path, units)
            if flight is not None:
                flights.append(flight)
            continue
        broken = _not_differentiable(ev, scene, c, EventCode.LANDING)   # physics.md, "Sensitivities" 10
        landed = broken or land(c, scene, flight, ev.t, ev.q)
        if isinstance(landed, str):
            broken, first = landed, i
            break
        for column, value in zip(path.table, (landed.Dt, landed.Dq, landed.Dv_before, landed.Dv_after)):
            column[i] = value
        path.D_landing_loss += landed.D_loss
        flight = landed.bounce
        if flight is not None:
            flights.append(flight)
        if flight is None:              # sliding resumes from the landing point
            path.q, path.w, path.Dq, path.Dw = landed.q, landed.w, landed.Dq, landed.Dw
            path.Dt, path.t = landed.Dt, ev.t
        i += 1
    T, Q, VB, VA = path.table
    reasons = [""] * (first if broken else last + 1)
    if broken:
        reasons += _reasons_after(events[first:last + 1], first, broken, scene, c, path.q)
    reasons += [f"not asked for: after event {last} (through={last})"] * (n - 1 - last)
    final_names = ("t_final", "q_final", "friction_work", "impact_loss") + (
        ("landing_loss",) if scene.contact == "unilateral" else ())
    final = {name: np.full(P, np.nan) for name in final_names}
    if not broken and at_end:
        q_f = events[-1].q
        DE_final = c.m * (path.Dw / 2 + c.g * (float(c.dz(q_f)) * path.Dq + c.geometry_dp("z", q_f)[0]))
        final.update(t_final=T[-1].copy(), q_final=Q[-1].copy(), impact_loss=path.D_impact_loss,
                     friction_work=DE0 - DE_final - path.D_impact_loss - path.D_landing_loss)
        if "landing_loss" in final:
            final["landing_loss"] = path.D_landing_loss
    for name in notes:
        j = wrt.index(name)
        for column in (T, Q, VB, VA, *final.values()):
            column[..., j] = np.nan
    sens = Sensitivities(wrt, tuple(events), T, Q, VB, VA, tuple(reasons), final, notes)
    return Tangents(sens, tuple(path.legs), tuple(flights))


def _targets(scene, wrt):
    """:func:`~symvib.numeric.sensitivity_curve.resolve_wrt` ``(scene, wrt)`` and the unit tangent of each scene
    parameter (:data:`PARAMETERS` -> shape (P,), read-only; 0 for one not in ``wrt``), remembered by what they
    depend on: the names, the curve's parameter names and which limiters the scene has."""
    try:
        key = (wrt if isinstance(wrt, str) else tuple(wrt), tuple(n for n, _ in scene.params), scene.left is None,
               scene.right is None)
        known = _TARGETS.get(key)
    except TypeError:        # (names that are not hashable: resolve_wrt says what is wrong)
        key, known = None, None
    if known is not None:
        return known
    targets = resolve_wrt(scene, wrt if key is None else key[0])
    P = len(targets)
    unit = {name: np.zeros(P) for name in PARAMETERS}
    eye = np.eye(P)
    for j, (_, kind, p) in enumerate(targets):
        if kind == "scene":
            unit[p] = eye[j].copy()
    for v in unit.values():
        v.setflags(write=False)
    if key is not None and len(_TARGETS) < 256:
        _TARGETS[key] = (targets, unit)
    return targets, unit


#: What :func:`_targets` resolved, by its key.
_TARGETS = {}


def _start_values(c, kernels, q):
    """``h``, ``h'`` and ``z'`` at the start ``q`` (floats), remembered for the last few starts of a curve with
    its parameters (a fit's runs mostly start where the scene does)."""
    key = (id(kernels), q, c._cp)
    known = _STARTS.get(key)
    if known is None or known[0] is not kernels:
        known = (kernels, float(c.h(q)), float(c.dh(q)), float(c.dz(q)))
        if len(_STARTS) >= 16:
            _STARTS.clear()
        _STARTS[key] = known
    return known[1:]


#: :func:`_start_values` remembered: ``(id of the kernels, q, curve parameters) -> (kernels, h, h', z')``.
_STARTS = {}


def _kernels_of(scene, load):
    """``load(scene)`` (:func:`symvib.numeric.prepared.kernels_of`), remembered for the last catalogue shape (by
    identity: the scenes of a fit or a sweep share theirs; its module is the same for any of its scenes)."""
    shape = scene.shape
    if _LAST_KERNELS and _LAST_KERNELS[0] is shape:
        return _LAST_KERNELS[1]
    kernels = load(scene)
    if shape.in_catalogue:
        _LAST_KERNELS[:] = (shape, kernels)
    return kernels


#: The last catalogue shape :func:`_kernels_of` loaded, and its kernels.
_LAST_KERNELS = []


@dataclass
class _Path:
    """Where the differentiation of a run is: the particle's position and ``w`` after the last event
    differentiated and their tangents, that event's time and time tangent, the table's columns
    ``(T, Q, VB, VA)`` so far, the legs, and the tangents of the impact and landing losses."""

    q: float
    w: float
    Dq: np.ndarray
    Dw: np.ndarray
    Dt: np.ndarray
    t: float
    table: tuple
    legs: list
    D_impact_loss: np.ndarray
    D_landing_loss: np.ndarray


def _slide(c, scene, events, start, last, path, units):
    """Differentiate the sliding events from ``start`` on, up to a lift-off (included), a landing (not
    included) or ``last``, in four passes (:func:`interval_tangents`), advancing ``path``.

    Returns the next event's index, why the derivatives end (empty if they go on), the index of the
    first event without them, and the flight launched at a lift-off (or None).
    """
    Dmu, Dk, limiter_D, want_legs = units
    T, Q, VB, VA = path.table
    P = len(Dmu)
    segment_of = _segment(events, start, last, scene, c, path.q)
    _, codes, count, first, broken, _ = segment_of
    if c.quadratures is not None and count and not any(code in JETS_EVENTS for code in codes[:count]):
        return _slide_compiled(c, scene, segment_of, start, last, path, units)
    # 1. the run's path, event by event, in scalars: each interval's ends, branch and w before and after
    plan = _plan(segment_of, start, scene, c, path.q, path.w)
    intervals = [None if p[4] is None else Interval.of_scalars(c, p[4], p[3]) for p in plan]
    # 2. the integrals of dF_s'/dp over whole intervals, all at once (they need no tangent)
    I_p_e = np.zeros((len(plan), P))
    if c.f_depends:
        for s in (1, -1):
            group = [j for j, p in enumerate(plan) if p[4] is not None and p[4][0] == s]
            if group:
                q0s = np.array([plan[j][4][11] for j in group])
                D = np.array([plan[j][4][12] - plan[j][4][11] for j in group])
                I_p_e[group] = end_integrals(c, s, q0s, D, MAX_PANELS * NODES)
                for j in group:
                    intervals[j].I_p_e = I_p_e[j]
    # 3. the tangents of the events' positions and speeds, event by event (no quadrature left)
    Dq_a, Dw_a, lift = path.Dq, path.Dw, None
    D_impact_loss = np.zeros(P)
    for j, (i, ev, kind, turning, _, w_minus) in enumerate(plan):
        iv = intervals[j]
        if iv is None:                      # no motion in between (a rest test at the start)
            Dq_e, Dw_minus = Dq_a.copy(), Dw_a.copy()
        else:
            iv.set_start(Dq_a, Dw_a, Dmu)
            if turning:
                Dq_e = iv.dG_fixed_q_end() / (2 * c.g * iv.f_e)
            elif kind in (EventCode.NORMAL_SIGN_CHANGE, EventCode.LIFT_OFF):
                try:
                    Dq_e = normal_sign_change_tangent(c, iv)
                except KernelError as err:     # (a user curve's jets not generated where this runs)
                    Dq_e, why = None, f"the curve's jets (kappa') are not available here: {err}"
                else:
                    why = TANGENTIAL_N_REASON
                if Dq_e is None:
                    plan, first, broken = plan[:j], i, why
                    break
            else:
                Dq_e = limiter_D.get(ev.q, np.zeros(P)) if kind in (EventCode.IMPACT, EventCode.REST_ON_LIMITER) \
                    else np.zeros(P)
            iv.set_end(Dq_e)
            Dw_minus = np.zeros(P) if turning else iv.end_state()[1]
        sigma_in = 1.0 if ev.qdot_before >= 0 else -1.0
        v_minus = sigma_in * math.sqrt(max(w_minus, 0.0))
        Dv_minus = sigma_in * Dw_minus / (2 * math.sqrt(w_minus)) if w_minus > 0 else np.zeros(P)
        if kind == EventCode.IMPACT:
            k = scene.k
            Dw_plus = 2 * k * Dk * w_minus + k * k * Dw_minus
            Dv_plus = -(Dk * v_minus + k * Dv_minus)
            D_impact_loss = D_impact_loss + c.m / 2 * (-2 * k * Dk * w_minus + (1 - k * k) * Dw_minus)
        else:   # a turning point, or a sign change of N: w goes on (the branch flips with N)
            Dw_plus, Dv_plus = Dw_minus, (np.zeros(P) if turning else Dv_minus)
        Q[i], VB[i], VA[i] = Dq_e, Dv_minus, Dv_plus
        Dq_a, Dw_a = Dq_e, Dw_plus
        if kind == EventCode.LIFT_OFF:
            lift = (ev.q, v_minus, Dq_e, Dv_plus)
    # 4. the time derivatives of all intervals at once; the first that fails ends the derivatives
    dT = np.zeros((len(plan), P))
    for lo in range(0, len(plan), CHUNK):      # (in chunks: none computed after one that fails)
        rows = [lo + r for r, p in enumerate(plan[lo:lo + CHUNK]) if p[4] is not None]
        if rows:
            ends = {name: np.array([getattr(intervals[r], name) for r in rows]) for name in BATCH_FIELDS}
            dT[rows] = time_derivatives(c, ends)
        if not np.all(np.isfinite(dT[lo:lo + CHUNK])):
            break
    failed = np.flatnonzero(~np.all(np.isfinite(dT), axis=1))
    if len(failed):
        j = int(failed[0])
        plan, first, broken = plan[:j], plan[j][0], "the time derivative's quadrature did not converge"
    if broken and first is not None:       # (the rows pass 3 wrote past the first event without derivatives)
        for column in (Q, VB, VA):
            column[first:last + 1] = np.nan
    if plan:    # each event's time tangent: the one before plus its interval's (summed in time order)
        Dt = np.cumsum(np.vstack((path.Dt[None, :], dT[:len(plan)])), axis=0)
        T[[p[0] for p in plan]] = Dt[1:]
        if want_legs:
            t_a = [path.t] + [p[1].t for p in plan[:-1]]
            for j, (_, ev, _, _, _, _) in enumerate(plan):
                if intervals[j] is not None:
                    path.legs.append(Leg(intervals[j], t_a[j], ev.t, Dt[j], Dt[j + 1]))
        path.q, path.Dt, path.t = plan[-1][1].q, Dt[-1], plan[-1][1].t
    if plan:      # (past the first event without derivatives, only path.q is read: the reasons')
        _, _, kind, _, _, w_minus = plan[-1]
        path.w = scene.k * scene.k * w_minus if kind == EventCode.IMPACT else w_minus
        path.Dq, path.Dw, path.D_impact_loss = Dq_a, Dw_a, path.D_impact_loss + D_impact_loss
    flight = None
    if lift is not None and not broken and plan and plan[-1][2] == EventCode.LIFT_OFF:
        flight = launch(c, lift[0], lift[1], lift[2], lift[3], path.t, path.Dt)
    return (plan[-1][0] + 1 if plan else start), broken, first, flight


#: Intervals whose time derivatives are computed at once (a chunk after one that fails is not computed).
CHUNK = 64
#: Events whose tangent needs the curve's jets (:mod:`symvib.numeric.sensitivity_normal`): pass 3 of a
#: slide with one of them runs in Python.
JETS_EVENTS = (EventCode.NORMAL_SIGN_CHANGE, EventCode.LIFT_OFF)
#: Events that end on a limiter (their ``Dq`` is the limiter's).
LIMITER_EVENTS = (EventCode.IMPACT, EventCode.REST_ON_LIMITER)
#: The arrays of each interval that :func:`symvib.numeric.sensitivity_batch.time_derivatives` reads.
BATCH_FIELDS = ("s", "q_a", "q_e", "G_a", "G_e", "f_a", "f_e", "Dq_a", "Dq_e", "DG_a", "DG_e")


def _checked_through(through, n: int) -> int:
    """The index of the last event to differentiate: ``through`` within the run's events."""
    if isinstance(through, bool) or not isinstance(through, (int, np.integer)) or through < 0:
        raise ValueError(f"through: the index of an event (a whole number >= 0), got {through!r:.80}")
    return min(int(through), n - 1)


def _by_branch(intervals):
    """``(s, intervals on branch s)`` for each branch that has some."""
    for s in (1, -1):
        group = [iv for iv in intervals if iv is not None and iv.s == s]
        if group:
            yield s, group


def _segment(events, start, last, scene, c, q_a):
    """The sliding events from ``start`` (the particle at ``q_a``) to a lift-off (included), a landing (not
    included) or ``last``: their kind codes, how many of them have derivatives before the first without (its
    index or None, and why), and the kernels at the start, at every event and every interval's middle
    (``at``, ``middle``; each kernel called once for all of them: ``alpha`` at both, ``alpha'``, ``F_s`` at both,
    ``F_s'`` and ``E_s = exp(2 s mu alpha)`` at the events, NumPy's exp as :class:`Interval`'s)."""
    codes = []
    landing, lift_off, impact = EventCode.LANDING, EventCode.LIFT_OFF, EventCode.IMPACT
    for ev in events[start:last + 1]:
        kind = _code(ev.kind)
        if kind == landing:     # (a landing ends the slide before it, a lift-off with it)
            break
        codes.append(kind)
        if kind == lift_off:
            break
    segment = events[start:start + len(codes)]
    at = np.array([q_a] + [ev.q for ev in segment])
    middle = at[:-1] + (at[1:] - at[:-1]) / 2
    both = np.concatenate((at, middle))      # (alpha and F_s at both in one call each)
    alpha_at = c.alpha(both)
    n, first, broken, q_before = None, None, "", q_a
    for j, ev in enumerate(segment):
        kind = codes[j]
        # (an impact has derivatives unless it ends a Zeno accumulation, which its detail says)
        own = _not_differentiable(ev, scene, c, kind, moved=ev.q != q_before, alpha=alpha_at[j + 1]) \
            if kind != impact or ev.detail else ""
        if own:
            n, first, broken = j, start + j, own
            break
        q_before = ev.q
    n = len(segment) if n is None else n
    values = {"alpha": alpha_at, "dalpha": c.dalpha(at), "middle": middle,
              **{("E", s): np.exp(2 * s * c.mu * alpha_at[:len(at)]) for s in (1, -1)},
              **{("F", s): c.F(s, both) for s in (1, -1)}, **{("f", s): c.f(s, at) for s in (1, -1)}}
    return segment, codes, n, first, broken, values


def _plan(segment_of, start, scene, c, q_a, w_a):
    """The differentiable events of a :func:`_segment` ``segment_of`` (the particle at ``q_a`` with ``w_a``
    before them), each ``(index, event, kind code, turning, interval's scalars or None, w before it)``.  An
    interval's scalars are ``s, E_a, G_a, alpha_a, alpha'_a, f_a, f_e, G_e, alpha_e, alpha'_e, E_e, q_a, q_e,
    w_a`` (floats: what :class:`Interval` holds, :meth:`Interval.of_scalars`)."""
    segment, codes, count, _, _, values = segment_of
    n = len(segment) + 1
    # (as lists of floats, read one by one below: the same values, without NumPy's scalars)
    alpha, alpha_mid, middle = values["alpha"][:n].tolist(), values["alpha"][n:].tolist(), values["middle"].tolist()
    dalpha = values["dalpha"].tolist()
    E_at = {s: values["E", s].tolist() for s in (1, -1)}
    F = {s: values["F", s].tolist() for s in (1, -1)}
    f = {s: values["f", s].tolist() for s in (1, -1)}
    F, F_mid = {s: v[:n] for s, v in F.items()}, {s: v[n:] for s, v in F.items()}
    mu, g, k2 = c.mu, c.g, scene.k * scene.k
    plan = []
    for j, ev in enumerate(segment[:count]):
        i, kind = start + j, codes[j]
        q_e = ev.q
        turning = kind in TURNING_EVENTS
        if q_e == q_a:                      # no motion in between (a rest test at the start)
            row, w_minus = None, w_a
        else:
            sigma = 1 if q_e > q_a else -1
            s = _branch(c, w_a, sigma, middle[j], (alpha[j], alpha_mid[j], F[sigma][j], F_mid[sigma][j]))
            # (Interval's arithmetic: E_a by math.exp, G_e from the difference of F_s)
            E_a = math.exp(2 * s * mu * alpha[j])
            G_a = w_a * E_a
            G_e = 0.0 if turning else G_a - 2 * g * (F[s][j + 1] - F[s][j])
            E_e = E_at[s][j + 1]
            row = (s, E_a, G_a, alpha[j], dalpha[j], f[s][j], f[s][j + 1], G_e, alpha[j + 1], dalpha[j + 1], E_e,
                   q_a, q_e, w_a)
            w_minus = 0.0 if turning else G_e / E_e
        plan.append((i, ev, kind, turning, row, w_minus))
        q_a, w_a = q_e, (k2 * w_minus if kind == EventCode.IMPACT else w_minus)
    return plan


def _at_values(values, n, count) -> np.ndarray:
    """:func:`_segment`'s kernel values of its first ``count`` events (of ``n``) as the rows of
    :func:`symvib.numeric.sensitivity_kernels.slide_kernel`'s ``at_values`` (shape (8, 2 count + 1))."""
    out = np.zeros((8, 2 * count + 1))
    events, middles = slice(0, count + 1), slice(n + 1, n + 1 + count)
    for r, name in enumerate(("alpha", ("F", 1), ("F", -1))):
        out[(0, 2, 3)[r], :count + 1] = values[name][events]
        out[(0, 2, 3)[r], count + 1:] = values[name][middles]
    for r, name in zip((1, 4, 5, 6, 7), ("dalpha", ("f", 1), ("f", -1), ("E", 1), ("E", -1))):
        out[r, :count + 1] = values[name][events]
    return out


def _slide_compiled(c, scene, segment_of, start, last, path, units):
    """:func:`_slide` of ``segment_of`` (:func:`_segment`; no event of :data:`JETS_EVENTS` among its
    differentiable ones, no curve parameter) in one compiled call
    (:func:`symvib.numeric.sensitivity_kernels.slide_kernel`: the operations of :func:`_plan` and of the four
    passes, bit for bit)."""
    Dmu, Dk, limiter_D, want_legs = units
    T, Q, VB, VA = path.table
    segment, codes, n, first, broken, values = segment_of
    evs = segment[:n]
    limiter = np.zeros((n, len(Dmu)))
    for j, ev in enumerate(evs):
        if codes[j] in LIMITER_EVENTS:
            D = limiter_D.get(ev.q)
            if D is not None:       # (else the row stays 0)
                limiter[j] = D
    scalars, moving, w_minus, rows, tail, dT, I_p_e = c.quadratures.slide(
        c, np.array(codes[:n], dtype=np.int64), np.array([path.q] + [ev.q for ev in evs]),
        _at_values(values, len(segment), n), path.w, scene.k, c.m,
        np.array([1.0 if ev.qdot_before >= 0 else -1.0 for ev in evs]), limiter, Dmu, Dk,
        np.asarray(path.Dq, dtype=float), np.asarray(path.Dw, dtype=float), CHUNK)
    Q[start:start + n], VB[start:start + n], VA[start:start + n] = rows[4], rows[6], rows[7]
    finite = np.isfinite(dT).all(axis=1)
    count = n
    if not finite.all():
        count = int(np.flatnonzero(~finite)[0])
        first, broken = start + count, "the time derivative's quadrature did not converge"
    if broken and first is not None:       # (the rows written past the first event without derivatives)
        for column in (Q, VB, VA):
            column[first:last + 1] = np.nan
    if count:    # each event's time tangent: the one before plus its interval's (summed in time order)
        Dt = np.empty((count + 1, dT.shape[1]))
        Dt[0], Dt[1:] = path.Dt, dT[:count]
        np.cumsum(Dt, axis=0, out=Dt)
        T[start:start + count] = Dt[1:]
        if want_legs:
            t_a = [path.t] + [ev.t for ev in evs[:count - 1]]
            for j in range(count):
                if moving[j]:
                    row = scalars[j].tolist()
                    iv = Interval.of_scalars(c, (int(row[0]), *row[1:]), codes[j] in TURNING_EVENTS)
                    iv.I_p_e = I_p_e[j]
                    iv.Dq_a, iv.Dw_a, iv.Dmu, iv.DG_a, iv.A, iv.Dq_e, iv.DG_e = (
                        rows[0, j], rows[1, j], Dmu, rows[2, j], rows[3, j], rows[4, j], rows[5, j])
                    path.legs.append(Leg(iv, t_a[j], evs[j].t, Dt[j], Dt[j + 1]))
        path.q, path.Dt, path.t = evs[count - 1].q, Dt[-1], evs[count - 1].t
        w_last = float(w_minus[count - 1])
        path.w = scene.k * scene.k * w_last if codes[count - 1] == EventCode.IMPACT else w_last
        path.Dq, path.Dw, path.D_impact_loss = rows[4, -1], tail[1], path.D_impact_loss + tail[0]
    return start + count, broken, first, None


#: The engine's code of each event kind seen (``EventKind.code`` looks it up by name on every read), by the
#: kind's ``id`` (the members live as long as the process; an enum member's hash is a Python call).
_CODES = {}


def _code(kind) -> EventCode:
    """``kind.code``, looked up once per kind."""
    code = _CODES.get(id(kind))
    if code is None:
        code = _CODES[id(kind)] = kind.code
    return code

#: Events that end at a turning point of ``G``.
TURNING_EVENTS = (EventCode.REVERSAL, EventCode.ARREST)


def _reasons_after(events, first, why, scene, c, q_a) -> list:
    """The reasons of the events from the first without derivatives on (index ``first``, reason ``why``; the
    particle was at ``q_a`` before it): each later one's own, else that it follows ``first``."""
    out = [why]
    for ev in events[1:]:
        own = _not_differentiable(ev, scene, c, ev.kind.code, moved=ev.q != q_a)
        out.append(own or f"follows event {first}, which has no derivatives ({why})")
    return out


def _branch(c, w_a, sigma, mid_q, values) -> int:
    """The branch ``s = sigma sign(N)`` of an interval (no sign change of ``N`` inside: the engine
    ends an interval there), from ``N`` at its middle ``mid_q`` on the branch that assumes ``N > 0``
    (``values``: ``alpha`` at its start and middle, ``F_sigma`` at its start and middle)."""
    alpha_a, alpha_mid, F_a, F_mid = values
    G_a = w_a * math.exp(2 * sigma * c.mu * float(alpha_a))
    G_mid = G_a - 2 * c.g * float(F_mid - F_a)
    w_mid = G_mid / math.exp(2 * sigma * c.mu * float(alpha_mid))
    return sigma if c.N(mid_q, w_mid) >= 0 else -sigma


def _on_cone_edge(alpha: float, mu: float) -> bool:
    """Whether ``|tan alpha|`` is within :data:`CONE_EDGE` (relative) of the friction coefficient ``mu``."""
    edge = abs(abs(math.sin(alpha)) - mu * abs(math.cos(alpha)))
    return edge <= CONE_EDGE * max(abs(math.sin(alpha)), mu * abs(math.cos(alpha)), 1e-300)


def _not_differentiable(ev, scene, c, kind, *, moved: bool = True, alpha=None) -> str:
    """Why event ``ev`` has no derivatives (empty when it has); ``moved``: the particle moved to it
    (a turning point of ``G``, not a rest test where it already was); ``alpha``: the curve's ``alpha`` at
    it, if known."""
    if kind == EventCode.LEFT_CURVE:
        return "the particle leaves the curve"
    if kind == EventCode.LANDING:
        return landing_reason(ev.detail)
    if ev.detail and "zeno" in ev.detail.lower():
        return "a Zeno accumulation of impacts (infinitely many events); this event and the ones after it"
    if kind in (EventCode.REVERSAL, EventCode.ARREST):
        a = float(c.alpha(ev.q) if alpha is None else alpha)
        if _on_cone_edge(a, scene.mu_static):   # the rest test's (static) cone: the decision flips there
            return "a turning point on the edge of the friction cone (arrest or reversal changes with the parameters)"
        if moved and scene.mu_static != scene.mu and _on_cone_edge(a, scene.mu):
            return ("a turning point on the edge of the sliding friction cone |tan alpha| = mu (a double root of "
                    "the phase trajectory: its position has no derivative)")
        for limiter in (scene.left, scene.right):
            if limiter is not None and abs(ev.q - limiter) <= GRAZING * c.scale:
                return "a turning point on a limiter (grazing)"
    return ""
