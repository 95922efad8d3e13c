"""Parameters from measured event times: least squares with the exact Jacobian (physics.md, "Sensitivities").

A researcher who records the impacts of the paper's device (a microphone, an
accelerometer) or tracks the particle on video has event times, sometimes their
positions, and wants ``mu``, ``k``, the initial speed or the limiters with error
bars.  :func:`fit` runs the scene, matches its events to the observed ones,
differentiates the matched times exactly (:mod:`symvib.numeric.sensitivity`) and
takes Levenberg-Marquardt steps (Moré's scaling, bounds kept by projection)
until the parameters stop moving.

**Matching.** Observed events are matched in order to the model's events of the
kinds the data name (all kinds when the data name none), as long as the kinds
agree.  An observed event the model does not make (it stops, or reverses where
the data bounce, earlier) keeps its place in the residual vector with a fixed
residual, the span of the observed times (positions: of the observed positions
about ``q0``), and no derivative: a step that makes the event again lowers the
cost, so the fit is drawn to parameters that make every observed event, while
the matched ones give the direction.  The result's ``matched`` says how many
were matched at the end, and its message names a shortfall.  Extra model events
are not compared.  An event without derivatives (physics.md, "Sensitivities")
is left out of the steps, and the result says so.

**Samples.** Observed positions at sample times (:class:`ObservedSamples`: ``q``, ``x, z``
or the arc length ``s``, from video tracking) are compared with the model's position at the
same times (its dense output), every sample in place; their Jacobian is the exact derivative
of the position at a fixed time (:mod:`symvib.numeric.sample_sensitivity`).  A sample whose
position has no derivative (after an event without one) is left out of the steps, and the
result says so; a sample after the end of a run that does not come to rest is refused.

**Errors.** ``weights`` are ``1 / sigma`` of each observation; without them the
covariance is scaled by the residual variance (``cost / (m - n)``, as SciPy's
``curve_fit`` with ``absolute_sigma=False``).  Parameters the data do not
separate (a near-singular Jacobian, ``|correlation| > 1 - 1e-6``) are named in
the status ``not_identified``.  With weights, a minimum whose ``chi^2 / (m - n)``
exceeds :data:`POOR_FIT` is no answer: the status ``poor_fit`` says so (least squares
from a distant start can settle in a local minimum, which the continuation avoids
but cannot rule out).

Examples
--------
>>> from symvib.numeric.scene import resolve_scene
>>> from symvib.numeric.driver import simulate
>>> truth = resolve_scene("paper-parabola").replace(mu=0.03, k=0.8)
>>> times = [e.t for e in simulate(truth, samples=False).events if e.kind.value == "impact"][:6]
>>> start = truth.replace(mu=0.05, k=0.7)
>>> result = fit(start, observed_events(times, kinds=["impact"] * 6), free=("mu", "k"))
>>> result.status, round(result.estimates["mu"], 9), round(result.estimates["k"], 9)
('converged', 0.03, 0.8)
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from symvib.numeric.events import EventKind
from symvib.numeric.fit_data import (
                                     Observed,
                                     ObservedSamples,
                                     observed_events,
                                     observed_samples,
                                     read_events,
                                     read_observations,
                                     read_samples,
)
from symvib.numeric.sample_sensitivity import sample_positions, sample_sensitivities
from symvib.numeric.scene import Scene
from symvib.numeric.sensitivity import PARAMETERS, sensitivities
from symvib.numeric.sensitivity_curve import parameter_value, resolve_wrt, with_parameters

__all__ = ["fit", "observed_events", "observed_samples", "read_events", "read_samples", "read_observations",
           "FitResult", "Observed", "ObservedSamples", "STATUSES", "POOR_FIT"]

#: Outcomes of a fit.
STATUSES = {
    "converged": "the parameters stopped moving (relative step below xtol)",
    "not_identified": "converged, but the data do not separate some parameters (see message)",
    "max_iterations": "the iteration bound was reached before the parameters settled",
    "no_error_estimate": "converged; as many observations as parameters, so no error estimate without weights",
    "incomplete": "stopped where the model does not make every observed event (see message); try another start",
    "no_events": "the model makes none of the observed events at the start; give another start",
    "runs_failed": "stopped: the run of every trial step from here failed (see message); try another start or bounds",
    "poor_fit": ("converged to a minimum whose residuals are far larger than the weights' sigmas (see message): a "
                 "local minimum (try another start) or data the model cannot make"),
}
#: A converged fit with weights ``1 / sigma`` whose ``chi^2 / (m - n)`` exceeds this has status ``poor_fit``
#: (the residuals about 3 times their sigmas or more; with the right model and sigmas it is about 1,
#: above 10 with probability 0.2 % at one degree of freedom and far less at more).
POOR_FIT = 10.0
#: Largest ``|correlation|`` of two estimates that still counts as separated.
IDENTIFIED = 1 - 1e-6
#: Steps of ``lambda`` (Levenberg-Marquardt) up and down, and its range (above the top no step is
#: left to try: the cost is at a minimum to rounding).
LAMBDA_UP, LAMBDA_DOWN = 10.0, 0.3
LAMBDA_MIN, LAMBDA_MAX = 1e-12, 1e16
#: Relative step that ends a stage of the continuation before the last (the last uses ``xtol``).
STAGE_XTOL = 1e-5
#: Events per free parameter fitted in the continuation's first stage (:func:`_stages`).
FIRST_STAGE = 2


@dataclass(frozen=True)
class FitResult:
    """The outcome of :func:`fit` (immutable).

    Attributes
    ----------
    status : str
        A key of :data:`STATUSES`; ``message`` says more.
    scene : Scene
        The start scene with the estimates.
    free : tuple of str
    estimates, stderr : dict
        Parameter -> value, standard error.
    covariance, correlation : ndarray
        In the order of ``free``.
    residuals : ndarray
        Model minus observed, unweighted: times in s, then positions (events); or each coordinate
        at every sample, ``x`` then ``z`` (samples).
    matched : int
        Observed events matched to model events (the others were compared with the final time);
        for samples, their number.
    iterations : int
    cost : float
        Half the weighted sum of squared residuals.
    data : str
        ``"events"``, or the coordinates of a sampled trajectory (``"q"``, ``"xz"``, ``"s"``).
    """

    status: str
    message: str
    scene: Scene
    free: tuple
    estimates: dict
    stderr: dict
    covariance: np.ndarray
    correlation: np.ndarray
    residuals: np.ndarray
    matched: int
    iterations: int
    cost: float
    history: tuple = field(default=(), repr=False)
    data: str = "events"

    def summary(self) -> str:
        """Estimates with standard errors, the correlation, the status (plain text)."""
        lines = [f"fit: {self.status} after {self.iterations} iterations ({self.message})",
                 (f"matched {self.matched} of {len(self.residuals)} observations" if self.data == "events" else
                  f"{self.matched} samples of {self.data}, {len(self.residuals)} observations") +
                 f"; cost {self.cost:.6g}"]
        for name in self.free:
            lines.append(f"  {name:6s} = {self.estimates[name]:.10g} +- {self.stderr[name]:.3g}")
        if len(self.free) > 1:
            lines.append("correlation:")
            for name, row in zip(self.free, self.correlation):
                lines.append(f"  {name:6s} " + " ".join(f"{v:+.4f}" for v in row))
        return "\n".join(lines)

    def plot(self, path=None):
        """The residuals against the observation number (a Matplotlib figure; written to ``path`` if
        given)."""
        import matplotlib

        if path is not None:
            matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6, 3.2))
        n = len(self.residuals)
        ax.axhline(0.0, color="0.6", lw=0.8)
        scale, unit = {"events": (1e3, "ms"), "q": (1.0, "q")}.get(self.data, (1e3, "mm"))
        ax.plot(np.arange(1, n + 1), self.residuals * scale, "o", ms=4)
        ax.set_xlabel("observation" if self.data == "events" else f"sample ({', '.join(self.data)})")
        ax.set_ylabel(f"model - observed ({unit})")
        ax.set_title(", ".join(f"{k} = {self.estimates[k]:.5g} ± {self.stderr[k]:.2g}" for k in self.free),
                     fontsize=9)
        fig.tight_layout()
        if path is not None:
            from symvib import safeio

            with safeio.replacing_file(path, what="residual figure") as fh:   # never through a link there
                fig.savefig(fh, format="png", dpi=120)
            plt.close(fig)
        return fig


def _at(scene: Scene, free) -> dict:
    """The scene's values of the free parameters (scene or curve parameters), by their names."""
    return {t[0]: parameter_value(scene, t) for t in resolve_wrt(scene, free, "free")}


def _default_bounds(scene: Scene, name: str, kind: str = "scene") -> tuple:
    if kind == "curve":     # (a value the curve does not allow is refused by the scene: the step fails)
        return (-math.inf, math.inf)
    left = scene.left if scene.left is not None else -math.inf
    right = scene.right if scene.right is not None else math.inf
    mu_top = math.inf if scene.mu_s is None else scene.mu_s   # a given static friction bounds mu (mu <= mu_s)
    return {"mu": (0.0, mu_top), "k": (0.0, 1.0), "qdot0": (-math.inf, math.inf),
            "q0": (left, right), "left": (-math.inf, scene.q0), "right": (scene.q0, math.inf)}[name]


#: Event kinds by their names (the observed events' kinds).
_KINDS = {kind.value: kind for kind in EventKind}


def _matching(observed) -> tuple:
    """What matching reads of ``observed`` events besides the model's (the same at every trial point, so
    computed once a fit stage): the kinds as :class:`EventKind` members (or ``None``), the kinds the
    model's events are picked by, and the fixed residual of an unmatched time."""
    # (the kinds as EventKind members: a tuple's `in` finds a member by identity, without the enum's value)
    kinds = [_KINDS[v] for v in observed.kinds] if observed.kinds is not None else None
    wanted = tuple(_KINDS[v] for v in set(observed.kinds)) if kinds else None   # (str hashes are kept)
    span_t = max(float(observed.t[-1] - observed.t[0]), float(observed.t[-1]), 1e-300)
    return kinds, wanted, span_t


def _model(scene, observed, free, run, matching=None):
    """Residuals (model - observed, unweighted), how many events matched, and a function that gives
    their Jacobian and which rows have one (the exact sensitivities cost more than the run: a
    Levenberg-Marquardt step asks for them only once a trial is accepted).  ``matching`` is
    :func:`_matching` of ``observed`` (computed here when not given)."""
    result = run(scene)
    if result.status.is_error:
        raise ValueError(f"scene: the run at {_at(scene, free)} failed "
                         f"({result.status.value}): {result.message}")
    events = result.events
    kinds, wanted, span_t = matching or _matching(observed)
    if wanted:
        index = [i for i, e in enumerate(events) if e.kind in wanted]
    else:
        index = list(range(len(events)))
    n_obs = len(observed.t)
    matched = min(n_obs, len(index))
    if kinds is not None:
        made = [events[i].kind for i in index[:matched]]
        if made != kinds[:matched]:     # (members compare by identity first: the first that differs ends it)
            matched = next(j for j, (a, b) in enumerate(zip(made, kinds)) if a is not b)
    rows = index[:matched]
    r = np.full(n_obs if observed.q is None else 2 * n_obs, span_t)
    r[:matched] = [events[i].t for i in rows]
    r[:matched] -= observed.t[:matched]
    if observed.q is not None:
        span_q = max(float(np.max(np.abs(observed.q - scene.q0))), 1e-300)
        r[n_obs:] = span_q
        r[n_obs:n_obs + matched] = [events[i].q for i in rows]
        r[n_obs:n_obs + matched] -= observed.q[:matched]

    def jacobian():
        # (the events after the last matched one are not differentiated: no row needs them)
        sens = sensitivities(result, wrt=free, through=index[matched - 1] if matched else 0, compile=True)
        columns = [sens.t] if observed.q is None else [sens.t, sens.q]
        J = np.zeros((len(columns), n_obs, len(free)))
        for block, values in zip(J, columns):
            block[:matched] = values[rows]
        usable = np.isfinite(J).all(axis=2)       # (the rows past the matched ones are 0: usable)
        if not usable.all():
            J[~usable] = 0.0
        return J.reshape(-1, len(free)), usable.ravel()

    return r, matched, jacobian


def _sample_model(scene, observed, free, run, matching=None):
    """As :func:`_model` for a sampled trajectory: the model's coordinates at the sample times minus the
    observed ones (column by column: ``x`` then ``z``), every sample matched."""
    result = run(scene)
    if result.status.is_error:
        raise ValueError(f"scene: the run at {_at(scene, free)} failed "
                         f"({result.status.value}): {result.message}")
    if observed.t[-1] > result.dense.t_max:
        raise ValueError(f"observed.t: the last sample ({float(observed.t[-1])!r} s) comes after the run's end "
                         f"({result.dense.t_max:g} s, status {result.status.value}) at "
                         f"{_at(scene, free)}")
    r = (sample_positions(result, observed.t, observed.coordinates) - observed.values).T.ravel()

    def jacobian():
        D = sample_sensitivities(result, observed.t, free, observed.coordinates,
                                 compile=True).derivatives  # (n, columns, P)
        J = np.concatenate([D[:, j, :] for j in range(D.shape[1])])
        usable = np.all(np.isfinite(J), axis=1)
        J[~usable] = 0.0
        return J, usable

    return r, len(observed.t), jacobian


def fit(scene: Scene, observed: Observed | ObservedSamples, free=("mu", "k"), *, bounds=None, weights=None,
        max_iterations=50, xtol=1e-10, run=None) -> FitResult:
    """Fit the ``free`` parameters of ``scene`` to ``observed`` events or samples (least squares, exact Jacobian).

    Parameters
    ----------
    scene : Scene
        The start: its values of the free parameters are the first guess, the others fixed.
    observed : Observed or ObservedSamples
        Events (:func:`observed_events`, :func:`read_events`) or a sampled trajectory
        (:func:`observed_samples`, :func:`read_samples`); :func:`read_observations` reads either.
    free : sequence of str
        Names from :data:`symvib.numeric.sensitivity.PARAMETERS` or of the curve's parameters
        (``p``, or ``parameters.p``: :func:`symvib.numeric.sensitivity_curve.resolve_wrt`).
    bounds : dict, optional
        Parameter -> ``(low, high)``; default: the physical ranges (``mu >= 0``, and ``mu <= mu_s``
        where the scene gives static friction, ``0 <= k <= 1``, ``q0`` between the limiters, a
        limiter on its side of ``q0``); given bounds lie within those (the scene is refused
        beyond them).  An estimate on a bound is named in the message.
    weights : array, optional
        ``1 / sigma`` of each observation (times, then positions; for samples each coordinate at
        every sample, ``x`` then ``z``).
    run : callable, optional
        ``scene -> Result`` (default :func:`symvib.numeric.driver.simulate`, keeping its intervals
        only for samples: their positions come from its dense output).

    Raises
    ------
    ValueError
        Naming ``free`` (unknown, repeated, a missing limiter, more parameters than
        observations), ``observed.kind`` (a kind the scene cannot make), ``observed.t`` (a sample
        after the end of the start's run), ``weights`` (not one positive finite number per
        observation), ``bounds`` (not a dict of parameter -> ``(low, high)``, ``low <= high``,
        within the physical ranges), ``max_iterations`` (not a whole number >= 1), ``xtol`` (not positive and finite),
        ``observed`` (not events or samples) or ``scene`` (not a Scene, or a run that failed).
    """
    from symvib.numeric.driver import simulate

    if not isinstance(scene, Scene):
        raise ValueError(f"scene: a Scene (symvib.load_scene), got {type(scene).__name__}")
    if not isinstance(observed, (Observed, ObservedSamples)):
        raise ValueError(f"observed: events (observed_events, read_events) or samples (observed_samples, "
                         f"read_samples), got {type(observed).__name__}")
    if isinstance(free, str) or not hasattr(free, "__iter__"):
        raise ValueError(f"free: a sequence of names from {', '.join(PARAMETERS)} (such as ('mu', 'k')), "
                         f"got {free!r:.80}")
    if isinstance(max_iterations, bool) or not isinstance(max_iterations, (int, np.integer)) or max_iterations < 1:
        raise ValueError(f"max_iterations: a whole number of at least 1, got {max_iterations!r:.80}")
    if not isinstance(xtol, (int, float, np.number)) or not (0 < xtol < math.inf):
        raise ValueError(f"xtol: a positive finite number, got {xtol!r:.80}")
    free = tuple(free)
    curve_names = tuple(n for n, _ in scene.params)
    names = bool(free) and all(isinstance(p, str) for p in free)
    for side in ("left", "right"):
        if names and side in free and getattr(scene, side) is None and side not in curve_names:
            raise ValueError(f"free: the scene has no {side} limiter to fit")
    try:
        targets = resolve_wrt(scene, free, "free") if names else None
    except ValueError as err:
        if "ambiguous" in str(err):
            raise
        targets = None
    if targets is None:
        raise ValueError(f"free: {free!r} must be distinct names from {', '.join(PARAMETERS + curve_names)}")
    samples = isinstance(observed, ObservedSamples)
    m = observed.count
    if m < len(free):
        raise ValueError(f"free: {len(free)} parameters from {m} observations; give at least as many observations "
                         "as free parameters")
    if not samples and observed.kinds and ("impact" in observed.kinds or "rest_on_limiter" in observed.kinds) \
            and scene.left is None and scene.right is None:
        raise ValueError("observed.kind: impacts observed, but the scene has no limiter to make them")
    flying = sorted({"lift_off", "landing"} & set(observed.kinds or ())) if not samples else []
    if flying and scene.contact != "unilateral":
        raise ValueError(f"observed.kind: {' and '.join(flying)} observed, but the scene's contact is bilateral "
                         "(a bead on a wire never flies); set physics.contact = \"unilateral\"")
    try:
        w = np.ones(m) if weights is None else np.asarray(weights, dtype=float).ravel()
    except (TypeError, ValueError):
        raise ValueError(f"weights: one positive finite 1/sigma per observation ({m}), got {weights!r:.80}") from None
    if len(w) != m or not np.all(np.isfinite(w)) or np.any(w <= 0):
        raise ValueError(f"weights: one positive finite 1/sigma per observation ({m}), got {len(w)}")
    given = _check_bounds(bounds, free)
    defaults = {t[0]: _default_bounds(scene, t[2], t[1]) for t in targets}
    for name in set(given) & set(free):     # beyond them the scene is refused: steps there would just fail
        (low, high), (d_low, d_high) = given[name], defaults[name]
        if low < d_low or high > d_high:
            raise ValueError(f"bounds.{name}: ({low:g}, {high:g}) reaches beyond the values the scene allows, "
                             f"[{d_low:g}, {d_high:g}] (mu <= mu_s, k <= 1, q0 between the limiters)")
    bounds = {name: given.get(name, defaults[name]) for name in free}
    problem = _Problem(scene, free, targets, run or (lambda s: simulate(s, samples=samples)),
                       *(np.array([bounds[n][i] for n in free]) for i in (0, 1)), weights is not None,
                       _sample_model if samples else _model)
    x = np.array([parameter_value(scene, t) for t in targets], dtype=float)
    if np.any(x < problem.lo) or np.any(x > problem.hi):
        raise ValueError(f"scene: the start {dict(zip(free, x))} is outside the bounds {bounds}")
    n_obs = len(observed.t)
    total, history = 0, []
    for n in _stages(n_obs, len(free)):
        part = observed.head(n)
        part_w = np.concatenate([w[j * n_obs:j * n_obs + n] for j in range(m // n_obs)])
        # (a stage before the last only needs to land near its minimum: the next one refines it)
        result = _levenberg_marquardt(problem, part, part_w, x, xtol if n == n_obs else STAGE_XTOL, max_iterations,
                                      final=n == n_obs)
        total += result.iterations
        history += list(result.history)
        x = np.array([result.estimates[name] for name in free])
        if result.status == "no_events":
            return result
    return dataclasses.replace(result, iterations=total, history=tuple(history),
                               data=observed.coordinates if samples else "events")


def _check_bounds(bounds, free=()) -> dict:
    """The given ``bounds`` as ``name -> (low, high)`` floats, or an error naming ``bounds`` (a name
    from :data:`PARAMETERS` or ``free``)."""
    if bounds is None:
        return {}
    if not isinstance(bounds, dict):
        raise ValueError(f"bounds: a dict of parameter -> (low, high), got {type(bounds).__name__}")
    checked = {}
    for name, pair in bounds.items():
        if name not in PARAMETERS and name not in free:
            raise ValueError(f"bounds: {name!r} is not a parameter ({', '.join(dict.fromkeys(PARAMETERS + free))})")
        try:
            low, high = (float(v) for v in pair)
        except (TypeError, ValueError):
            raise ValueError(f"bounds.{name}: a pair (low, high) of numbers, got {pair!r:.80}") from None
        if math.isnan(low) or math.isnan(high) or low > high:
            raise ValueError(f"bounds.{name}: low <= high, neither NaN (infinite for none), got {pair!r:.80}")
        checked[name] = (low, high)
    return checked


def _stages(n_obs: int, n_free: int) -> list:
    """How many observed events each stage of the continuation fits: the first events depend least
    on how far the start is from the answer, so fit them first, then twice as many, ..., then all
    (a fit of every event from a distant start can stop where the model's later events are matched
    to the wrong observed ones).  The first stage fits :data:`FIRST_STAGE` times as many events as
    free parameters: with exactly as many, its minimum is a root (every residual 0), which takes
    Levenberg-Marquardt many short steps and which the next stage moves away from anyway.

    >>> _stages(20, 4), _stages(3, 2), _stages(40, 2)
    ([8, 16, 20], [3], [4, 8, 16, 32, 40])
    """
    stages, n = [], min(n_obs, max(FIRST_STAGE * n_free, 2))
    while n < n_obs:
        stages.append(n)
        n *= 2
    return stages + [n_obs]


@dataclass(frozen=True)
class _Problem:
    """What a fit holds fixed: the start scene, the free parameters, the forward run, the bounds."""

    scene: Scene
    free: tuple
    targets: tuple
    run: object
    lo: np.ndarray
    hi: np.ndarray
    absolute: bool
    model: object
    scenes: list = field(default_factory=list, compare=False, repr=False)

    def at(self, values) -> Scene:
        """The scene with the free parameters ``values`` (the last two remembered: a stage ends and the next
        starts where the last step was taken)."""
        key = np.asarray(values, dtype=float).tobytes()
        for known, scene in self.scenes:
            if known == key:
                return scene
        scene = with_parameters(self.scene, self.targets, values)
        self.scenes[:] = [(key, scene), *self.scenes[:1]]
        return scene


def _levenberg_marquardt(problem: _Problem, observed: Observed, w, x, xtol: float, max_iterations: int,
                         final: bool = True) -> FitResult:
    """Levenberg-Marquardt from ``x`` (Moré's column scaling, bounds by projection): a trial that
    lowers the cost is taken and ``lambda`` falls, else ``lambda`` rises; it stops when the relative
    step is below ``xtol`` or no step lowers the cost (a minimum, to rounding).  A stage before the
    last (not ``final``) reads only the estimates, the status and the history of the result: the
    Jacobian at a last step that ends it on ``xtol`` is not computed (its covariance is that of the
    step before)."""
    free, lo, hi = problem.free, problem.lo, problem.hi
    matching = _matching(observed) if problem.model is _model else None
    r, matched, jacobian = problem.model(problem.at(x), observed, free, problem.run, matching)
    J, usable = jacobian()
    if matched == 0:
        return _result("no_events", STATUSES["no_events"], problem.at(x), free, x, J, r, w, problem.absolute,
                       matched, 0, ())
    cost = 0.5 * float(np.sum((w * r) ** 2))
    lam, history, status = 1e-3, [(x.copy(), cost)], "max_iterations"
    iterations, eye, w_col = 0, np.eye(len(x)), w[:, None]
    while iterations < max_iterations:
        iterations += 1
        A = w_col * J
        scale = np.maximum(np.sqrt((A * A).sum(axis=0)), 1e-300)     # (np.linalg.norm(A, axis=0)'s arithmetic)
        # The damped normal equations in Moré's scaled variables y = scale * step: (A_s^T A_s + lambda I) y =
        # -A_s^T (w r), A_s = A / scale (unit columns), the same for every lambda.
        A /= scale
        H, minus_g = A.T @ A, -(A.T @ (w * r))
        ran, failure = False, ""
        while True:
            step = _damped_step(H, eye, lam, minus_g) / scale
            trial = np.minimum(np.maximum(x + step, lo), hi)     # (np.clip's result, without its overhead)
            try:
                r_new, m_new, jacobian_new = problem.model(problem.at(trial), observed, free, problem.run, matching)
                wr = w * r_new
                new_cost = 0.5 * float((wr * wr).sum())     # (np.sum((w * r) ** 2)'s arithmetic)
                ran = ran or bool((trial != x).any())
            except ValueError as err:               # a run that failed there: as if the cost rose
                new_cost, failure = math.inf, str(err)
            if new_cost <= cost:
                break
            if not failure and _settled(trial, x, xtol):
                break       # (a step within xtol that does not lower the cost: a larger lambda only shortens it)
            lam *= LAMBDA_UP
            if lam > LAMBDA_MAX:
                break
        # No step lowers the cost: a minimum; unless every step away from x failed to run (a step
        # damped to nothing then "succeeds" at x itself): the fit is stuck, not converged.
        stuck = not ran and bool(failure)
        if new_cost > cost or (stuck and np.array_equal(trial, x)):
            status = "runs_failed" if stuck else "converged"
            break
        settled = _settled(trial, x, xtol)
        if final or not settled:
            J, usable = jacobian_new()
        x, r, matched, cost = trial, r_new, m_new, new_cost
        lam = max(lam * LAMBDA_DOWN, LAMBDA_MIN)
        history.append((x.copy(), cost))
        if settled:
            status = "converged"
            break
    if matched < len(observed.t):
        status = "incomplete"
    message = STATUSES[status]
    if status == "runs_failed":
        message += f"; the last: {failure}"
    if not np.all(usable):
        message += f"; {int(np.sum(~usable))} observation(s) without derivatives left out of the steps"
    if matched < len(observed.t):
        message += f"; the model makes only {matched} of the {len(observed.t)} observed events in their order and kinds"
    for name, v, low, high in zip(free, x, lo, hi):
        if v in (low, high):     # (the data may want it beyond: a minimum on the bound is not theirs)
            message += f"; {name} = {v:g} is at its bound ({'low' if v == low else 'high'})"
    return _result(status, message, problem.at(x), free, x, J, r, w, problem.absolute, matched, iterations,
                   tuple(history))


def _settled(trial, x, xtol) -> bool:
    """Whether the step from ``x`` to ``trial`` is within ``xtol`` of ``x`` in every parameter (relative)."""
    return bool((np.abs(trial - x) <= xtol * (np.abs(x) + xtol)).all())


def _damped_step(H, eye, lam, minus_g):
    """The solution of ``(H + lam I) y = -g`` (``H`` the scaled Gauss-Newton matrix, positive semidefinite):
    by ``solve`` where the matrix is regular, else the least-squares solution (a zero column)."""
    M = H + lam * eye
    try:
        y = np.linalg.solve(M, minus_g)
        if np.isfinite(y).all():
            return y
    except np.linalg.LinAlgError:
        pass
    return np.linalg.lstsq(M, minus_g, rcond=None)[0]


def _result(status, message, scene, free, x, J, r, w, absolute, matched, iterations, history) -> FitResult:
    """The result at ``x``: covariance ``(A^T A)^-1`` of the weighted Jacobian ``A``, scaled by the
    residual variance unless the weights are ``1 / sigma`` (``absolute``)."""
    A = w[:, None] * J
    m, n = A.shape
    cost = 0.5 * float(np.sum((w * r) ** 2))
    try:
        inverse = np.linalg.inv(A.T @ A)
    except np.linalg.LinAlgError:
        inverse = np.full((n, n), np.inf)
    variance = 1.0 if absolute else (2 * cost / (m - n) if m > n else math.nan)
    cov = inverse * variance
    se = np.sqrt(np.abs(np.diag(cov)))
    with np.errstate(invalid="ignore", divide="ignore"):
        # from (A^T A)^-1 itself: the correlation needs no estimate of the noise
        d = np.sqrt(np.abs(np.diag(inverse)))
        corr = inverse / np.outer(d, d)
    if status == "converged" and absolute and m > n and 2 * cost / (m - n) > POOR_FIT:
        status = "poor_fit"
        message = (f"{STATUSES['poor_fit']}; chi^2 / (m - n) = {2 * cost / (m - n):.3g} with the weights as "
                   f"1/sigma (about 1 for a model that makes the data)") + message[len(STATUSES["converged"]):]
    if status == "converged" and n > 1:
        pairs = [(free[i], free[j], corr[i, j]) for i in range(n) for j in range(i + 1, n)
                 if not abs(corr[i, j]) <= IDENTIFIED]
        if not np.all(np.isfinite(inverse)):
            pairs = pairs or [(free[0], free[-1], math.nan)]
        if pairs:
            status = "not_identified"
            a, b, c = pairs[0]
            message = (f"{STATUSES['not_identified']}: {a} and {b} correlate at {c:+.7f}; the data fix a "
                       f"combination of them, not each (observe more events, or fix one)") + message[len(
                           STATUSES["converged"]):]
    if status == "converged" and m == n and not absolute:
        status, message = "no_error_estimate", STATUSES["no_error_estimate"] + message[len(STATUSES["converged"]):]
    return FitResult(status, message, scene, free, dict(zip(free, map(float, x))), dict(zip(free, map(float, se))),
                     cov, corr, r, matched, iterations, cost, history)
