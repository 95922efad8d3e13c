"""The thin event-driven driver: ``simulate(scene)`` (physics.md, "Events").

``simulate`` turns a scene into the engine's row of floats (:func:`scene_row`),
runs the engine bound to the curve's kernels (:mod:`symvib.numeric.engine`:
events found in ``q`` on the closed-form phase trajectory, :mod:`~.engine.scan`;
times and friction work by quadrature, :mod:`~.engine.timing`; the laws of
impact, rest and Zeno accumulation, :mod:`~.engine.laws`), and returns typed
records (:mod:`symvib.numeric.events`).

Hard cases the engine handles: grazing, a turning point on the cone edge
(arrest within ``laws.CONE_RTOL``), Zeno accumulation at a limiter (bounces
summed as a geometric series once below ``laws.ZENO_W``), plastic impacts,
``mu = 0`` with ``k = 1`` (bounded by ``t_max``/``max_events``), the normal
force changing sign (bilateral contact: the branch flips; ``physics.contact =
"unilateral"``: the particle lifts off, flies and lands, :mod:`symvib.numeric.flights`;
the sweep's compiled loop ends ``left_curve`` there and :mod:`symvib.numeric.sweep.flights`
follows the row on), and the ends of the curve's regular domain.

Every result is checked (:func:`checked_status`): a state that stops being
finite ends the run at once with status ``non_finite`` (on the plain-Python
backend, where ``math`` raises ``OverflowError`` instead, the message is kept
in ``stats["error"]``), and a run whose energy budget misses by more than
:data:`BUDGET_RTOL` ends ``energy_budget_mismatch``; ``Result.success`` is then
False and ``symvib run`` exits with status 3.

The engine runs compiled by numba (a main dependency) where it is compiled
already, and as plain Python otherwise; both give the same events.  A loop of
runs of one curve compiles it in the background (:mod:`symvib.numeric.tiered`).

Examples
--------
>>> from symvib.numeric.scene import scene_from_dict
>>> scene = scene_from_dict({"curve": {"shape": "parabola"}, "parameters": {"p": 1},
...     "physics": {"g": 9.81, "m": 0.2, "alpha0": 0.05, "restitution": 0.8},
...     "limiters": {"left": "-pi/6", "right": "pi/4"}, "initial": {"q": 0, "qdot": 7}})
>>> result = simulate(scene)
>>> result.status.value, result.events[0].kind.value
('arrested', 'impact')
>>> result.energy_budget.relative_residual < 1e-12
True
"""
from __future__ import annotations

import math
import time
from contextlib import nullcontext
from functools import lru_cache, partial

import numpy as np

from symvib.numeric import tiered
from symvib.numeric.backends import (
                                     BACKEND_ENV,
                                     backend_available,
                                     bound_engine,
                                     compile_by_running,
                                     quiet_compiler,
                                     resolve_backend,
                                     run_backend,
)
from symvib.numeric.engine.state import Rules
from symvib.numeric.events import EnergyBudget, Event, Result, Status, ZenoInfo, kind_of, status_of
from symvib.numeric.layout import EventCode, EventColumn, SceneRow, StatusCode, Summary
from symvib.numeric.prepared import Prepared, prepared_of
from symvib.numeric.quadrature import plain_nodes, rule, tail_rows
from symvib.numeric.run_samples import (
                                        MAX_SAMPLES_PER_INTERVAL,
                                        SAMPLE_BUDGET,
                                        SAMPLES_PER_INTERVAL,
                                        dense_output,
                                        lazy_samples,
                                        no_samples,
                                        sample_engine,
                                        sample_pieces,
                                        sample_plan,
                                        stretch_samples,
)
from symvib.numeric.scenerow import scene_row
from symvib.numeric.trusted import BUDGET_RTOL, checked_status, math_error

__all__ = ["simulate", "NODES", "MAX_F_PANELS", "check_panels", "quiet_compiler",
           "RTOL", "ATOL", "check_tolerances", "SAMPLES_PER_INTERVAL", "SAMPLE_BUDGET",
           "sample_pieces",
           "backend_available", "resolve_backend", "run_backend", "checked_status", "compile_by_running",
           "guarded_sweep", "check_wall_time", "DEFAULT_WALL_TIME", "BACKEND_ENV",
           "BUDGET_RTOL", "scene_row", "sweep_function", "rules"]

#: Gauss-Legendre nodes per quadrature panel (a panel's accuracy; the tolerance decides how many panels).
NODES = 16
#: Default relative tolerance of the time of every motion interval (physics.md, "Accuracy"): the
#: quadrature refines its panels until each one's estimated error is below ``rtol`` of its time
#: (plus its share of ``atol``), so an event's time is within about ``rtol`` of the time elapsed.
RTOL = 1e-12
#: Default absolute tolerance of the time of a motion interval, seconds.
ATOL = 0.0
#: An interval that missed its tolerance and spans less than this fraction of the curve's ``q_scale``
#: adds declaring ``q_scale`` to the remedies (:func:`_scale_remedy`).
SMALL_SPAN = 1e-3
#: Smallest rtol a run may ask for: a few rounding errors of a sum of quadrature terms.
MIN_RTOL = 1e-14
#: Most Gauss-Legendre panels one evaluation of a numeric ``F_sigma`` may take (``|q - Q_REF| / (PANEL
#: * q_scale)`` at the start and the limiters): a run evaluates it thousands of times, so a curve
#: whose ``q_scale`` is tiny against its span (``q_scale = "1e-7"``: 1e6-1e7 panels) is refused up front.
MAX_F_PANELS = 10_000
#: How close to an end of its regular interval a run that stopped there (``left_domain``, or
#: ``energy_budget_mismatch`` where the steps into a pole lose the budget) must be to have reached
#: the singular point beyond that end: a share of the distance from the start.
SINGULAR_REACH = 1e-3
#: ``symvib run``'s wall-clock limit of the plain engine (seconds; ``--wall-time``): a run on the
#: command line answers within a minute, or says how far it got (status ``wall_time_limit``).
DEFAULT_WALL_TIME = 40.0
#: The plain engine's time per event, about (seconds; the message of a run that reached its
#: ``wall_time``): 0.5 ms on the paper's parabola, 100 to 200 times the compiled engine's.
PLAIN_SECONDS_PER_EVENT = 5e-4
#: Kernels (by identity) whose compiled engine has run in this process: it compiles nothing more.
_RAN_COMPILED: dict = {}


def check_wall_time(wall_time, name: str = "wall_time") -> float | None:
    """``wall_time`` as a float (None, or 0: no limit), else a ValueError naming the field ``name``.

    Examples
    --------
    >>> check_wall_time(30), check_wall_time(None), check_wall_time(0)
    (30.0, None, None)
    >>> check_wall_time(float("nan"))
    Traceback (most recent call last):
    ...
    ValueError: wall_time must be a number of seconds >= 0 (0: no limit), not nan
    """
    if wall_time is None:
        return None
    ok = isinstance(wall_time, (int, float, np.integer, np.floating)) and not isinstance(wall_time, bool)
    if not ok or not math.isfinite(wall_time) or wall_time < 0:
        raise ValueError(f"{name} must be a number of seconds >= 0 (0: no limit), not {wall_time!r}")
    return float(wall_time) if wall_time > 0 else None


def _scale_remedy(scene, mod, cp, q_from: float, q_to: float) -> str:
    """A further remedy for an interval that missed its tolerance: where it is far shorter than the
    curve's ``q_scale``, the curve likely changes on a length its numeric kernels do not resolve
    (a numeric ``F_sigma``'s panels are fractions of ``q_scale``)."""
    try:
        scale = abs(float(mod.q_scale_scalar(*cp)))
    except (AttributeError, TypeError, ValueError, ArithmeticError):
        return ""
    span = abs(q_to - q_from)
    if not (math.isfinite(scale) and 0.0 < span < SMALL_SPAN * scale):
        return ""
    return (f"; or, since the interval spans {span:.3g} of {scene.shape.q} while the curve's q_scale is "
            f"{scale:.3g}, declare the length on which the curve changes as its q_scale (the scene's "
            f"[curve] q_scale, or curve.q_scale of a shape)")


def check_tolerances(rtol, atol) -> tuple:
    """``(rtol, atol)`` as floats if a run can aim at them, else a ValueError naming the field.

    Examples
    --------
    >>> check_tolerances(1e-10, 0)
    (1e-10, 0.0)
    >>> check_tolerances(0.0, 0.0)
    Traceback (most recent call last):
    ...
    ValueError: rtol must be a number in [1e-14, 1) (the relative tolerance of an interval's time), not 0.0
    """
    def number(value):
        ok = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)
        return float(value) if ok and math.isfinite(value) else None

    r, a = number(rtol), number(atol)
    if r is None or not MIN_RTOL <= r < 1.0:
        raise ValueError(f"rtol must be a number in [{MIN_RTOL:g}, 1) (the relative tolerance of an interval's "
                         f"time), not {rtol!r}")
    if a is None or a < 0.0:
        raise ValueError(f"atol must be a finite number >= 0 (seconds, the absolute tolerance of an interval's "
                         f"time), not {atol!r}")
    return r, a


def simulate(scene, *, nodes: int = NODES, samples: bool = True, backend: str = "auto",
             samples_per_interval: int | None = None, rtol: float = RTOL, atol: float = ATOL,
             wall_time: float | None = None, prepared: Prepared | None = None) -> Result:
    """Simulate ``scene`` event by event until arrest, rest, ``t_max`` or ``max_events``.

    Parameters
    ----------
    scene : Scene
    nodes : int
        Gauss-Legendre nodes per quadrature panel.
    samples : bool
        Keep what the samples need (the motion intervals); :attr:`Result.samples`
        computes them on first use, so a run costs its events only.
    backend : {"auto", "numba", "python"}
        (A scene with air drag, ``scene.drag > 0``, runs on the NumPy drag path whatever the
        backend: :mod:`symvib.numeric.drag_run`.)  ``"auto"``: the compiled engine where it is
        on disk already, else the plain one
        (:func:`run_backend`; a loop of runs compiles it in the background and then takes
        it, :mod:`symvib.numeric.tiered`; ``stats["backend"]`` says which ran); ``"numba"``
        compiles it on first use (once per curve; its time: docs/benchmarks.md, "The driver
        and first calls").
    samples_per_interval : int, optional
        Samples per motion interval, at least (each logged interval is cut into
        :func:`sample_pieces` equal pieces in ``q``, each with its Gauss nodes,
        which cluster in ``sqrt(distance)`` towards a turning point).  Costs
        nothing until :attr:`Result.samples` is read.  Default:
        :data:`SAMPLES_PER_INTERVAL`, or one piece per interval (about 25 samples)
        for a run whose samples would pass :data:`SAMPLE_BUDGET` that way (a run of
        100,000 events keeps 2.5 million samples, not 10 million).
    rtol, atol : float
        Tolerance of the time of every motion interval, relative to its duration and in
        seconds (physics.md, "Accuracy"): the quadrature refines its panels until its
        error estimate is below ``rtol T + atol``; each event carries the sum of the
        estimates before it (``Event.t_err``).  An interval whose estimate stays above
        100 times its tolerance (:data:`symvib.numeric.engine.loop.TOLERANCE_FACTOR`)
        ends the run with status ``tolerance_not_met`` (``success`` is False).
    wall_time : float, optional
        Seconds of computing the plain-Python engine may take (about
        :data:`PLAIN_SECONDS_PER_EVENT` per event): past them the run ends with status
        ``wall_time_limit``, its events so far right and its message naming the time reached.
        The compiled engine has no clock and ignores it (it runs the largest ``max_events``
        in minutes).  Default: no limit (``symvib run`` sets one: ``--wall-time``).
    prepared : Prepared, optional
        The curve's kernels and the run's regular domain (:func:`symvib.prepare.prepare`,
        which ``symvib.simulate`` calls).  Default: what is on disk
        (:func:`~symvib.numeric.prepared.prepared_of`): a catalogue shape always is, a user
        curve once prepared (else :class:`~symvib.numeric.prepared.NotPrepared`).

    Returns
    -------
    Result
        Status, events, samples and energy budget.
    """
    spi = SAMPLES_PER_INTERVAL if samples_per_interval is None else samples_per_interval
    if isinstance(spi, bool) or not isinstance(spi, (int, np.integer)) or not 1 <= spi <= MAX_SAMPLES_PER_INTERVAL:
        raise ValueError(f"samples_per_interval must be an integer from 1 to {MAX_SAMPLES_PER_INTERVAL}, "
                         f"not {spi!r}")
    rtol, atol = check_tolerances(rtol, atol)
    wall_time = check_wall_time(wall_time)
    prep = prepared_of(scene) if prepared is None else prepared
    if getattr(scene, "drag", 0.0):   # air drag: its own path, on every backend (physics.md, "Air drag")
        from symvib.numeric.drag_run import simulate_drag

        resolve_backend(backend)   # (an unknown backend is refused as for any scene)
        try:
            with np.errstate(over="ignore", invalid="ignore", divide="ignore"):   # the status says it
                return simulate_drag(scene, prep, rtol=rtol, atol=atol, wall_time=wall_time, samples=samples)
        except (ArithmeticError, ValueError) as exc:
            if not math_error(exc):
                raise
            return _non_finite(scene, exc)
    requested, backend = backend, run_backend(prep.kernels, backend)
    mod, eng = bound_engine(prep.kernels, backend)
    R = rules(nodes, rtol, atol)
    cp = tuple(float(v) for v in scene.param_values)
    check_panels(scene, mod, cp)
    row = scene_row(scene)
    if wall_time is not None and backend == "python":
        row[SceneRow.deadline] = time.monotonic() + wall_time
    started = time.perf_counter()
    # (a compiled engine that ran once in this process compiles nothing more: no warnings to catch)
    quiet = nullcontext() if _RAN_COMPILED.get(id(mod)) is mod else quiet_compiler(mod, backend)
    try:
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"), quiet:
            out = eng.simulate(cp, row, R, samples)  # the status says what overflowed
    except (ArithmeticError, ValueError) as exc:
        if not math_error(exc):
            raise
        return _non_finite(scene, exc)
    if backend == "numba":
        _RAN_COMPILED[id(mod)] = mod
    elif requested == "auto":   # a loop's plain runs compile the curve in the background
        tiered.ran(mod, time.perf_counter() - started, scene.shape.name,
                   partial(compile_by_running, mod, cp, row, R, samples))
    status = checked_status(out.status, out.t, out.q, out.qdot, out.E0, out.E_final, out.W_friction, out.W_impacts)
    if status == StatusCode.LEFT_CURVE and scene.contact == "unilateral":   # physics.md, "Flight and landing"
        from symvib.numeric.flight_samples import Sampling
        from symvib.numeric.flights import result_with_flights

        sampling = None
        if samples:   # each sliding stretch sampled as any run is (physics.md, "Flight and landing")
            sampling = Sampling(partial(stretch_samples, partial(sample_engine, mod, requested, backend), cp, R,
                                        scene, mod), partial(sample_plan, spi, nodes, samples_per_interval is None),
                                2 * plain_nodes(nodes) + 1)
        try:
            return result_with_flights(scene, prep, mod, eng, cp, row, R, out, backend, sampling)
        except (ArithmeticError, ValueError) as exc:
            if not math_error(exc):
                raise
            return _non_finite(scene, exc)
    # A run into a singular point (the end of a narrowed domain) ends left_domain there, or, where the
    # steps into a pole lose the budget or the interval into it cannot be timed, with those errors.
    singular, reached = None, {StatusCode.LEFT_DOMAIN: out.q, StatusCode.ENERGY_BUDGET_MISMATCH: out.q,
                               StatusCode.TOLERANCE_NOT_MET: out.q_bad}.get(status)
    if reached is not None and prep.domain.narrowed:
        singular = _singular_end(prep, scene, float(reached))
        if singular is not None:
            status = int(StatusCode.REACHED_SINGULAR_POINT)
    detail = "plastic" if scene.k == 0.0 else ""
    impact = int(EventCode.IMPACT)
    events = [Event(kind_of(r[0]), r[1], r[2], r[3], r[4], r[5], detail if r[0] == impact else "", r[6])
              for r in out.events[:out.n_events].tolist()]
    zeno = out.zeno
    zinfo = None
    if zeno.ratio > 0.0:
        zinfo = ZenoInfo("right" if zeno.side > 0 else "left", float(zeno.ratio), int(zeno.simulated),
                         float(zeno.remaining), float(out.t))
        events[-1] = events[-1]._replace(
            detail=f"Zeno accumulation: geometric series of bounces, ratio {zeno.ratio:.9g}")
    budget = EnergyBudget(float(out.E0), float(out.E_final), float(out.W_friction), float(out.W_impacts))
    sampler = interpolant = None
    if samples and status != StatusCode.NON_FINITE:
        pieces, too_many = sample_plan(spi, nodes, samples_per_interval is None, int(out.n_intervals))
        if too_many:
            sampler = partial(no_samples, too_many)
        else:
            sampler = partial(lazy_samples, partial(sample_engine, mod, requested, backend), cp, row,
                              out.intervals, out.n_intervals, R, scene, mod, pieces)
        interpolant = partial(dense_output, mod, cp, out.intervals[:out.n_intervals], R)
    stats = {"intervals": int(out.n_intervals) if samples else None, "backend": backend, "t_err": float(out.t_err),
             "domain": (prep.domain.lo, prep.domain.hi)}   # the run's (narrowed next to a singular point)
    if status == StatusCode.TOLERANCE_NOT_MET:
        stats["accuracy"] = (
            f"error: the time of the motion interval from {scene.shape.q} = {float(out.q):.12g} to "
            f"{float(out.q_bad):.12g} (starting at t = {float(out.t):.12g} s) could not be brought within its "
            f"tolerance (rtol {rtol:g}, atol {atol:g} s); the run stopped at its start. Remedies: a looser "
            f"tolerance (simulate(scene, rtol=...), symvib run --rtol), or more nodes per panel (nodes=...)"
            + _scale_remedy(scene, mod, cp, float(out.q), float(out.q_bad)))
    if status == StatusCode.WALL_TIME_LIMIT:
        stats["stopped"] = (
            f"the plain engine's wall-clock limit of {wall_time:g} s was reached at t = {float(out.t):.12g} s, "
            f"after {int(out.n_events):,} events (about {PLAIN_SECONDS_PER_EVENT * 1e3:g} ms each); those are "
            f"right, the run is unfinished. Remedies: a longer limit (simulate(scene, wall_time=...), symvib run "
            f"--wall-time SECONDS, 0 for none), or the compiled engine (backend='numba', --backend numba: it "
            f"compiles the curve once, then runs about 100 times faster)")
    elif singular is not None:
        point, reason = singular
        q = scene.shape.q
        if math.isnan(out.q_bad):  # it stopped at the end of its regular interval
            how = f"reached the singular point {q} = {point:.12g} of curve '{scene.shape.name}' ({reason}) at t = " \
                  f"{float(out.t):.12g} s"
        else:
            how = f"runs into the singular point {q} = {point:.12g} of curve '{scene.shape.name}' ({reason}) from " \
                  f"{q} = {float(out.q):.12g} at t = {float(out.t):.12g} s (the run stopped there: the time to " \
                  f"get there is not finite, or not within the tolerance)"
        stats["stopped"] = f"error: the particle {how}; the model ends at that point, the events before are right"
    return Result(scene=scene, status=status_of(status), events=tuple(events), sampler=sampler,
                  interpolant=interpolant,
                  energy_budget=budget, t_final=float(out.t), q_final=float(out.q), qdot_final=float(out.qdot),
                  zeno=zinfo, stats=stats)


def _non_finite(scene, exc: BaseException) -> Result:
    """The result of a run the plain-Python engine stopped by an overflow (status ``non_finite``).

    The compiled engine returns inf or NaN where Python's ``math`` raises, and
    ends the same run with the same status; the exception's text is kept in
    ``stats["error"]``.
    """
    nan = math.nan
    return Result(scene=scene, status=Status.NON_FINITE, events=(),
                  energy_budget=EnergyBudget(nan, nan, nan, nan), t_final=nan, q_final=nan, qdot_final=nan,
                  stats={"intervals": None, "error": f"{type(exc).__name__}: {exc}"})


def guarded_sweep(sweep_fn):
    """``sweep_fn`` (the engine's ``sweep``) with each scene's status checked as :func:`simulate` checks it.

    The summary's status column goes through :func:`checked_status`, so a
    scene whose state overflowed or whose energy budget does not close is
    ``non_finite`` / ``energy_budget_mismatch`` in a sweep too.  On the
    plain-Python backend an overflow raises: the scenes then run one at a time
    and the failing ones get status ``non_finite`` and NaN values.
    """
    def guarded(scal_rows, cp_rows, R, max_log):
        try:
            with np.errstate(over="ignore", invalid="ignore", divide="ignore"):  # the status says it
                out, logs = sweep_fn(scal_rows, cp_rows, R, max_log)
        except (ArithmeticError, ValueError) as exc:
            if not math_error(exc):
                raise
            if len(scal_rows) == 1:
                out = np.full((1, len(Summary)), np.nan)
                out[:, [Summary.status, Summary.events, Summary.impacts, Summary.reversals,
                        Summary.normal_sign_changes]] = [StatusCode.NON_FINITE, 0, 0, 0, 0]
                return out, np.zeros((1, max(max_log, 1), len(EventColumn)))
            parts = [guarded(scal_rows[i:i + 1], cp_rows[i:i + 1], R, max_log) for i in range(len(scal_rows))]
            return np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts])
        out[:, Summary.status] = checked_status(
            out[:, Summary.status], out[:, Summary.t_final], out[:, Summary.q_final], out[:, Summary.qdot_final],
            out[:, Summary.E0], out[:, Summary.E_final], out[:, Summary.friction_work], out[:, Summary.impact_loss])
        return out, logs

    guarded.__wrapped__ = sweep_fn
    return guarded


def sweep_function(scene, backend: str = "auto", *, rtol: float = RTOL, atol: float = ATOL):
    """The engine's checked sweep for the curve of ``scene``: a function
    ``(scene_rows, param_rows, nodes, max_log) -> (summary, logs)``, its times within
    ``rtol``/``atol`` (:func:`simulate`).

    ``scene_rows`` holds one :func:`scene_row` per scene, ``param_rows`` the
    curve's parameter values per scene; ``summary`` has the columns
    :class:`symvib.numeric.layout.Summary`, ``logs`` the first ``max_log`` events
    of each scene (columns :class:`symvib.numeric.layout.EventColumn`).  Statuses
    are checked as :func:`simulate` checks them (:func:`checked_status`).
    """
    rtol, atol = check_tolerances(rtol, atol)
    if getattr(scene, "drag", 0.0):
        from symvib.numeric.scene import SceneError

        raise SceneError("physics.drag", f"{scene.drag!r}: sweeps do not run scenes with air drag yet (the "
                                         "compiled engine has no drag); run them one by one with symvib.simulate, "
                                         "or sweep the scene with drag = 0")
    _, eng = bound_engine(scene.shape, backend)
    fn = guarded_sweep(eng.sweep)

    def run(scene_rows, param_rows, nodes, max_log):
        return fn(np.ascontiguousarray(scene_rows, dtype=float), np.ascontiguousarray(param_rows, dtype=float),
                  rules(nodes, rtol, atol), int(max_log))

    return run


def check_panels(scene, mod, cp) -> None:
    """Refuse a run whose numeric ``F_sigma`` would take more than :data:`MAX_F_PANELS` panels.

    Raises
    ------
    symvib.numeric.scene.SceneError
        Naming ``curve.q_scale`` and the bound.
    """
    if "numeric" not in getattr(mod, "F_ROUTES", {}).values():
        return
    from symvib.numeric.scene import SceneError

    width = mod.PANEL * float(mod.q_scale_scalar(*cp))
    reach = max(abs(v - mod.Q_REF) for v in (scene.q0, scene.left, scene.right) if v is not None)
    panels = reach / width if width > 0 else math.inf
    if not panels <= MAX_F_PANELS:
        raise SceneError("curve.q_scale", f"{float(mod.q_scale_scalar(*cp)):.3g} is too small for this run: "
                                          f"F_sigma has no closed form and one evaluation of its quadrature would "
                                          f"take {panels:.3g} panels of {mod.PANEL:g} q_scale, more than "
                                          f"{MAX_F_PANELS:,} (driver.MAX_F_PANELS); give a q_scale near the length "
                                          "on which the curve turns, or leave it out")


def _singular_end(prep: Prepared, scene, q: float):
    """``(point, reason)`` of the singular point that ends the regular interval a run of ``scene``
    stopped next to, at ``q`` (:attr:`Prepared.ends`); None elsewhere."""
    for end in prep.ends:
        if end is not None and abs(q - end[0]) <= SINGULAR_REACH * abs(end[0] - scene.q0):
            return end
    return None


@lru_cache(maxsize=8)
def rules(nodes: int, rtol: float = RTOL, atol: float = ATOL) -> Rules:
    """The quadrature rules and tolerances the engine takes (:class:`symvib.numeric.engine.state.Rules`;
    see :func:`symvib.numeric.engine.timing.quad`).

    For panels that start on a root: nodes, weights and both integration
    matrices, transposed; for the others: nodes, weights and the matrix of the
    :func:`plain_nodes` rule; for each rule the rows of :func:`tail_rows`, one after
    the other in one array (row ``k`` at ``[k n : (k + 1) n]``).
    """
    r, p = rule(nodes), rule(plain_nodes(nodes))
    # Fresh C-contiguous copies: the compiled engine's signature takes writable arrays.
    arrays = (np.array(a, dtype=float, order="C") for a in (
        r.x, r.weights, r.cumulative.T, r.cumulative_weighted.T, p.x, p.weights, p.cumulative.T,
        tail_rows(r.x, r.weights).ravel(), tail_rows(p.x, p.weights).ravel()))
    return Rules(*arrays, float(rtol), float(atol))
