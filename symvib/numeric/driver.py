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

import importlib.util
import math
import os
import time
from contextlib import contextmanager, nullcontext
from functools import lru_cache, partial

import numpy as np

from symvib.numeric import tiered
from symvib.numeric.engine import bind
from symvib.numeric.engine.state import Rules
from symvib.numeric.events import EnergyBudget, Event, Result, Samples, Status, ZenoInfo, kind_of, status_of
from symvib.numeric.kernels import load
from symvib.numeric.layout import EventCode, EventColumn, SceneRow, StatusCode, Summary
from symvib.numeric.prepared import Prepared, prepared_of
from symvib.numeric.quadrature import rule
from symvib.numeric.scenerow import scene_row
from symvib.numeric.trusted import BUDGET_RTOL, checked_status
from symvib.shapes import Shape

__all__ = ["simulate", "NODES", "MAX_F_PANELS", "check_panels", "quiet_compiler",
           "RTOL", "ATOL", "check_tolerances", "SAMPLES_PER_INTERVAL", "SAMPLE_BUDGET",
           "sample_pieces",
           "backend_available", "resolve_backend", "run_backend", "checked_status", "compile_by_running",
           "guarded_sweep", "check_wall_time", "DEFAULT_WALL_TIME",
           "BUDGET_RTOL", "scene_row", "sweep_function", "rules"]

#: Gauss-Legendre nodes per quadrature panel (a panel's accuracy; the tolerance decides how many panels).
NODES = 16
#: Default relative tolerance of the time of every motion interval (physics.md, "Accuracy"): the
#: quadrature refines its panels until each one's estimated error is below ``rtol`` of its time
#: (plus its share of ``atol``), so an event's time is within about ``rtol`` of the time elapsed.
RTOL = 1e-12
#: Default absolute tolerance of the time of a motion interval, seconds.
ATOL = 0.0
#: Smallest rtol a run may ask for: a few rounding errors of a sum of quadrature terms.
MIN_RTOL = 1e-14
#: Samples per motion interval (at least) by default: smooth curves of F_N and P_mu.
SAMPLES_PER_INTERVAL = 96
#: Most samples per motion interval a run may ask for (memory: 80 bytes per sample).
MAX_SAMPLES_PER_INTERVAL = 100_000
#: Samples a run keeps by default at most at :data:`SAMPLES_PER_INTERVAL` (above, one piece per
#: interval): 1e6 samples are about 150 MB and a second to compute.
SAMPLE_BUDGET = 1_000_000
#: Most samples a run computes (about 1.5 GB); a run that would pass it gets no samples and says why.
MAX_SAMPLES = 10_000_000
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
#: Environment variable that forces a backend ("numba" or "python").
BACKEND_ENV = "SYMVIB_BACKEND"
#: (kernels, bound engine) by the identity of the kernels (a module, or a prepared view) and the backend.
_BOUND: dict = {}
#: Kernels (by identity) whose compiled engine has run in this process: it compiles nothing more.
_RAN_COMPILED: dict = {}
#: Kernels whose compiled entry :func:`run_backend` found on disk, by (identity, entry, kernel cache).
_ON_DISK: dict = {}


def backend_available(name: str) -> bool:
    """Whether a backend can run here (``"python"`` always can)."""
    if name == "python":
        return True
    if name == "numba":
        # Found, not imported: importing numba takes a few tenths of a second a plain run does not need.
        return importlib.util.find_spec("numba") is not None
    raise ValueError(f"unknown backend {name!r}; use 'numba', 'python' or 'auto'")


def resolve_backend(backend: str) -> str:
    """The backend a run uses: ``"numba"`` or ``"python"`` (``"auto"``: numba when installed,
    unless ``$SYMVIB_BACKEND`` says otherwise)."""
    backend = os.environ.get(BACKEND_ENV, backend) if backend == "auto" else backend
    if backend == "auto":
        return "numba" if backend_available("numba") else "python"
    if not backend_available(backend):
        raise ValueError(f"backend {backend!r} is not available here (pip install numba: symvib depends on it; "
                         "where numba cannot be installed the plain engine runs)")
    return backend


def _kernels(curve):
    """The kernel module of ``curve``: a module (or a prepared view) as it is, a shape's from disk."""
    return load(curve) if isinstance(curve, (Shape, str)) else curve


def bound_engine(curve, backend: str = "auto"):
    """``(kernel module, engine)`` of a curve's kernels (a module, a prepared view, or a shape whose
    module is on disk) on a backend (:func:`symvib.numeric.engine.bind`), cached."""
    mod = _kernels(curve)
    entry = _BOUND.get((id(mod), backend))
    if entry is None or entry[0] is not mod or backend == "auto" and os.environ.get(BACKEND_ENV):
        entry = (mod, bind(mod, resolve_backend(backend)))
        _BOUND[(id(mod), backend)] = entry
    return entry


def run_backend(curve, backend: str = "auto", entry: str = "simulate_bound") -> str:
    """The backend one run of ``shape`` takes: a single scene never waits for a compiler.

    ``"auto"`` is numba only where the curve's compiled ``entry`` (``"simulate_bound"``
    for a run, ``"sample_bound"`` for its samples) is already on disk (compiled by an
    earlier ``backend="numba"`` run; :func:`symvib.numeric.engine.bind.is_compiled`),
    and the plain-Python engine otherwise (milliseconds per paper scene, where a
    first compilation takes seconds: docs/benchmarks.md, "The driver and first
    calls").  ``$SYMVIB_BACKEND`` and an explicit backend are obeyed.  Sweeps compile (:func:`sweep_function`).
    A process that runs a curve's plain engine many times compiles it in a child process and
    then takes it (:mod:`symvib.numeric.tiered`).
    """
    if backend != "auto" or os.environ.get(BACKEND_ENV):
        return resolve_backend(backend)
    if not backend_available("numba"):
        return "python"
    from symvib.numeric.engine.bind import is_compiled

    mod = _kernels(curve)
    if entry == "simulate_bound":   # a background compile started by this process decides (tiered.ready)
        compiled = tiered.ready(mod)
        if compiled is not None:
            return "numba" if compiled else "python"
    # Found on disk once, taken without asking the disk again (the cache folder's trust check and
    # the marker cost as much as a compiled run); by the kernel cache folder, which a test may change.
    key = (id(mod), entry, os.environ.get("SYMVIB_CACHE"))
    if _ON_DISK.get(key) is mod:
        return "numba"
    if not is_compiled(mod, entry):
        return "python"
    _ON_DISK[key] = mod
    return "numba"


#: Entries of the compiled engine whose disk-cache markers :func:`quiet_compiler` removes.
COMPILED_ENTRIES = ("simulate_bound", "sample_bound")
#: What numba says when it compiles a function it cannot store in its disk cache.
UNCACHEABLE = "cannot cache"


@contextmanager
def quiet_compiler(mod, backend: str):
    """No NumbaWarning reaches the user; a curve whose engine numba cannot cache is not taken by ``auto`` again.

    numba warns (NumbaWarning blocks on stderr) when it compiles a function it cannot
    store on disk; such an engine compiles anew in every process (10.9 s against 1.1 s
    for the plain engine), so the markers that make ``auto`` take it
    (:func:`symvib.numeric.engine.bind.is_compiled`) are removed: later runs take the
    plain engine, silently.  The run at hand has paid the compilation and uses it.
    """
    if backend != "numba":
        yield
        return
    import warnings

    from numba.core.errors import NumbaWarning

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", NumbaWarning)
        yield
    if any(UNCACHEABLE in str(w.message).lower() for w in caught if issubclass(w.category, NumbaWarning)):
        from symvib.numeric.engine.bind import compiled_marker

        for entry in COMPILED_ENTRIES:
            compiled_marker(mod, entry).unlink(missing_ok=True)
    for w in caught:  # the others (not numba's) as they were
        if not issubclass(w.category, NumbaWarning):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)


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
            if not _math_error(exc):
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
        if not _math_error(exc):
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
            sampling = Sampling(partial(_stretch_samples, partial(_sample_engine, mod, requested, backend), cp, R,
                                        scene, mod), partial(_sample_plan, spi, nodes, samples_per_interval is None),
                                2 * plain_nodes(nodes) + 1)
        try:
            return result_with_flights(scene, prep, mod, eng, cp, row, R, out, backend, sampling)
        except (ArithmeticError, ValueError) as exc:
            if not _math_error(exc):
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
        pieces, too_many = _sample_plan(spi, nodes, samples_per_interval is None, int(out.n_intervals))
        if too_many:
            sampler = partial(_no_samples, too_many)
        else:
            sampler = partial(_lazy_samples, partial(_sample_engine, mod, requested, backend), cp, row,
                              out.intervals, out.n_intervals, R, scene, mod, pieces)
        interpolant = partial(_dense, mod, cp, out.intervals[:out.n_intervals], R)
    stats = {"intervals": int(out.n_intervals) if samples else None, "backend": backend, "t_err": float(out.t_err),
             "domain": (prep.domain.lo, prep.domain.hi)}   # the run's (narrowed next to a singular point)
    if status == StatusCode.TOLERANCE_NOT_MET:
        stats["accuracy"] = (
            f"error: the time of the motion interval from {scene.shape.q} = {float(out.q):.12g} to "
            f"{float(out.q_bad):.12g} (starting at t = {float(out.t):.12g} s) could not be brought within its "
            f"tolerance (rtol {rtol:g}, atol {atol:g} s); the run stopped at its start. Remedies: a looser "
            f"tolerance (simulate(scene, rtol=...), symvib run --rtol), or more nodes per panel (nodes=...)")
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


def compile_by_running(mod, cp, row, R, samples):
    """Compile ``mod``'s engine by running it once on a run's arguments (a background compile's
    job, :mod:`symvib.numeric.tiered`): numba compiles at the first call and writes its disk cache;
    a cache it cannot write removes the marker (:func:`quiet_compiler`)."""
    mod, eng = bound_engine(mod, "numba")
    with quiet_compiler(mod, "numba"):
        return eng.simulate(cp, row, R, samples)


def _dense(mod, cp, ivs, R, result):
    """The dense output of ``result`` (:class:`symvib.numeric.dense.DenseOutput`) from its interval log."""
    from symvib.numeric.dense import DenseOutput

    return DenseOutput(result, mod, cp, ivs, R)


def _sample_plan(spi: int, nodes: int, default: bool, n_intervals: int):
    """``(pieces, None)``: the pieces each of ``n_intervals`` logged intervals is sampled in (one where
    the default ``spi`` would pass :data:`SAMPLE_BUDGET`), or ``(None, message)`` where the samples
    would pass :data:`MAX_SAMPLES`."""
    pieces = sample_pieces(spi, nodes)
    if default and n_intervals * spi > SAMPLE_BUDGET:
        pieces = 1
    wanted = n_intervals * pieces * (2 * plain_nodes(nodes) + 1)
    if wanted > MAX_SAMPLES:
        return None, (f"samples: {n_intervals:,} intervals at samples_per_interval {spi} would give about "
                      f"{wanted:,} samples, more than {MAX_SAMPLES:,}; ask for fewer (samples_per_interval) or a "
                      "shorter run (run.max_events)")
    return pieces, None


def _stretch_samples(engine_of, cp, R, scene, mod, row, ivs, ni, pieces):
    """The samples of one sliding stretch of a run with flights (``row`` its start): as
    :func:`_lazy_samples` (:class:`symvib.numeric.flight_samples.Sampling`)."""
    return _lazy_samples(engine_of, cp, row, ivs, ni, R, scene, mod, pieces)


def _no_samples(message):
    """``(None, message)``: a run whose samples would be too many (:data:`MAX_SAMPLES`)."""
    return None, message


def _sample_engine(mod, requested: str, backend: str):
    """The engine that computes the samples of a run on ``backend`` (asked for as ``requested``).

    The run's own, except where ``"auto"`` took the compiled engine and its samples
    entry is not compiled yet: the plain engine then computes the samples from the
    run's interval log (the same quadrature; a run never waits for a compiler).
    """
    if backend == "numba" and requested == "auto":
        backend = run_backend(mod, requested, "sample_bound")
    return bound_engine(mod, backend)[1]


def _lazy_samples(engine_of, cp, row, ivs, ni, R, scene, mod, pieces):
    """``(samples, None)``, or ``(None, message)`` where the plain-Python engine overflowed;
    ``engine_of()`` gives the engine (:func:`_sample_engine`)."""
    eng = engine_of()
    try:
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"), quiet_compiler(mod, "numba"):
            return _samples(eng, cp, row, ivs, ni, R, scene, mod, pieces), None
    except (ArithmeticError, ValueError) as exc:
        if not _math_error(exc):
            raise
        return None, f"{type(exc).__name__}: {exc}"


#: Messages of the exceptions Python's ``math`` raises where compiled code returns inf or NaN.
_MATH_MESSAGES = ("math range error", "math domain error", "float division by zero", "division by zero",
                  "Numerical result out of range", "float modulo", "integer division or modulo by zero")


def _math_error(exc: BaseException) -> bool:
    """Whether ``exc`` is a floating-point failure of the plain-Python engine (not a bug)."""
    if isinstance(exc, ArithmeticError):
        return True  # OverflowError, ZeroDivisionError, FloatingPointError
    return isinstance(exc, ValueError) and any(m in str(exc) for m in _MATH_MESSAGES)


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
            if not _math_error(exc):
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


def plain_nodes(nodes: int) -> int:
    """Nodes of a panel that does not start on a root, for ``nodes`` on one that does.

    A panel that starts on a turning point (in the variable ``r``, ``q = q* -+ r^2``)
    has the interval's other end, possibly another turning point, at ``r = sqrt(L)``
    while it spans ``[0, sqrt(L/2)]``: the Bernstein ellipse of that branch point has
    ``rho = 3.4``, and ``nodes`` Gauss points leave an error of about ``rho^(-2 nodes)``.
    Every other panel is at least 2.6 of its half-widths from the nearest
    (virtual) root (3 for a panel in ``q``, 2.66 for the last of a graded run in
    ``r``), so ``rho >= 5.1`` and ``3/4`` of the nodes reach the same error
    (16 -> 12: ``5.1^-24 = 1e-17`` against ``3.4^-32 = 1e-17``).
    ``tests/test_quadrature.py`` checks 29 turning points against the
    30-digit reference to 2e-14 at 16 and at 32 nodes.

    Examples
    --------
    >>> plain_nodes(16), plain_nodes(12), plain_nodes(2)
    (12, 9, 2)
    """
    return max(1, -(-3 * nodes // 4))


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


def tail_rows(x, weights) -> np.ndarray:
    """Rows ``E_k`` with ``E_k @ f = a_k``, the Legendre coefficient of degree ``k`` of the interpolant
    of ``f`` at the Gauss-Legendre nodes ``x``, for ``k = n-1, n-2, n-3, n-4`` (``a_k = (2k + 1)/2
    sum_j w_j P_k(x_j) f_j``, exact for the interpolant by the rule's exactness to degree ``2n - 1``);
    degrees below 0 give zero rows.

    Examples
    --------
    >>> from symvib.numeric.quadrature import rule
    >>> r = rule(6)
    >>> E = tail_rows(r.x, r.weights)
    >>> bool(abs(E[0] @ r.x ** 5 - 8 / 63) < 1e-15)        # x^5 = (8/63) P_5 + lower degrees
    True
    """
    n = len(x)
    out = np.zeros((4, n))
    for row in range(4):
        k = n - 1 - row
        if k >= 0:
            unit = np.zeros(k + 1)
            unit[k] = 1.0
            out[row] = (2 * k + 1) / 2 * np.asarray(weights) * np.polynomial.legendre.legval(np.asarray(x), unit)
    return out


def sample_pieces(samples_per_interval: int, nodes: int) -> int:
    """Pieces each logged interval is cut into so that a motion interval has at least
    ``samples_per_interval`` samples (a piece gives at least two plain panels' nodes and its end).

    Examples
    --------
    >>> sample_pieces(SAMPLES_PER_INTERVAL, NODES), sample_pieces(1, NODES), sample_pieces(1000, NODES)
    (4, 1, 40)
    """
    per_piece = 2 * plain_nodes(nodes) + 1
    return max(1, -(-int(samples_per_interval) // per_piece))


def _samples(eng, cp, row, ivs, ni, R, scene, mod, pieces: int = 1) -> Samples:
    """The samples of the logged intervals (:func:`symvib.numeric.engine.timing.samples`), in time
    order, with the derived columns of :class:`Samples`.

    Linear in the number of intervals: one stable sort by (interval, time).
    """
    from symvib.numeric.engine.timing import SampleColumn as C

    nodes, index = eng.samples(cp, row, R, np.ascontiguousarray(ivs), ni, pieces)
    if not len(index):
        return Samples.empty()
    order = np.lexsort((nodes[:, C.t], index))  # stable: ties keep the engine's order
    nodes, index = nodes[order], index[order]
    t, q, w, N = nodes[:, C.t], nodes[:, C.q], nodes[:, C.w], nodes[:, C.N]
    sigma = nodes[:, C.sigma]
    m, mu = scene.m, scene.mu
    speed = np.sqrt(np.maximum(w, 0.0))
    v = sigma * speed
    z = _column(mod.z(q, *cp), q)
    Ep = m * scene.g * z
    friction = mu * m * np.abs(N)  # |F_mu|
    return Samples(t=t, q=q, qdot=v / mod.h(q, *cp), F_N=m * N, P_mu=-friction * speed,
                   Ek=0.5 * m * w, Ep=Ep, E=0.5 * m * w + Ep, interval=index.astype(int),
                   branch=nodes[:, C.branch].astype(int), x=_column(mod.x(q, *cp), q), z=z,
                   s=nodes[:, C.s].copy(), path=nodes[:, C.path].copy(), v=v, F_mu=-sigma * friction,
                   W_mu=m * nodes[:, C.W], W_impacts=m * nodes[:, C.W_impacts])


def _column(values, like) -> np.ndarray:
    """A kernel's values as a float array of ``like``'s shape (a constant kernel returns a scalar)."""
    return np.array(np.broadcast_to(values, like.shape), dtype=float)
