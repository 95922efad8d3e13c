"""Random scenes nobody designed, and a verdict on the engine against an independent reference.

:func:`random_scenes` draws seeded scenes (a NumPy ``Generator`` per scene, so
scene ``i`` of a seed is the same whatever ``n``) on the curves of
:data:`TRACKS` (catalogue shapes and curves of :mod:`symvib.checks.corpus`), in
the categories of :data:`CATEGORIES` with the quotas of :data:`QUOTAS`:

``generic``
    random limiters (none, one, two), ``mu`` in ``[0, 0.6]`` (sometimes 0),
    ``k`` in ``[0, 1]`` (sometimes exactly 0 or 1), start anywhere between them;
``near-stop``
    the speed nearly vanishes: the start speed is bisected against the reference
    so that the particle barely passes a hump (the top of a loop, the crest of a
    double well) or barely reaches a limiter, with ``w_min / w0`` about
    ``1e-4 .. 1e-10``;
``near-edge``
    a start at rest a relative ``1e-9 .. 1e-5`` beyond the friction-cone edge
    ``|tan alpha| = mu``: it slides slowly and stops just past the edge;
``looping``
    full loops on the circle and the ellipse;
``scale``
    a generic scene with every length scaled by ``1e-6 .. 1e3`` (limiters,
    speeds and ``t_max`` scaled with it).

:func:`compare` gives a :class:`Verdict` of an engine result against a
:class:`~symvib.checks.arclength.ReferenceRun` (see :data:`VERDICTS`), and
:func:`check_scenes` runs a list of scenes and summarises (:class:`Report`).

**Tolerance.** Event times agree within :func:`time_tolerance`: ``1e-9 s``, or
``1e-9`` relative to the scene's time scale ``T = L / V``
(:func:`symvib.checks.arclength.scene_scales`) where ``T > 1 s`` (the huge
scenes).

**The reference** (:func:`reference_for`) is the DOP853 run of
:func:`~symvib.checks.arclength.reference_run` (``rtol = 1e-13``), run a second
time at ``rtol = 1e-12`` with the start speed (or, at rest, the start position)
moved by :data:`PERTURB_ULPS` ulps.  Where the two differ by more than a tenth
of the tolerance (the answer is ill-conditioned in double precision: a near
stop, the cone edge), or DOP853 failed, the 30-digit GBS run replaces it.  It
runs :data:`ZENO_EXTRA_EVENTS` events beyond the scene's ``max_events``, so that
it keeps bouncing where the engine summed a Zeno series.

Examples
--------
>>> scenes = random_scenes(seed=1, n=3, categories=("generic",))
>>> [s.category for s in scenes], len({s.curve for s in scenes})
(['generic', 'generic', 'generic'], 3)
"""
from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field

import numpy as np

from symvib.checks.arclength import CONE_RTOL, curve_frame, reference_run, scene_scales
from symvib.numeric.scene import scene_from_dict

__all__ = ["Track", "TRACKS", "RandomScene", "Verdict", "Record", "Report", "VERDICTS", "CATEGORIES", "QUOTAS",
           "DT_BINS", "random_scenes", "reference_for", "compare", "check_scene", "check_scenes",
           "time_tolerance", "TIME_TOL"]

#: Verdicts, best first.  ``agree``: the same events, every time within the tolerance;
#: ``flagged``: not so, but the engine says so (``success`` False, an error status, or the
#: event's ``t_err`` covers the difference, or it raised); ``ambiguous``: the first difference
#: is a decision both answers can defend within rounding (a grazing impact, the cone edge,
#: a decision on which the double-precision reference's own two runs split);
#: ``reference_failed``: the reference could not decide; ``silent_miss``: anything else.
VERDICTS = ("agree", "flagged", "ambiguous", "reference_failed", "silent_miss")
CATEGORIES = ("generic", "near-stop", "near-edge", "looping", "scale")
#: Share of each category in :func:`random_scenes`.
QUOTAS = {"generic": 0.35, "near-stop": 0.2, "near-edge": 0.15, "looping": 0.1, "scale": 0.2}
#: Event times agree within this many seconds (relative to ``T`` where ``T > 1 s``).
TIME_TOL = 1e-9
#: The reference must be this fraction of the tolerance sure of itself, or the GBS run decides.
REF_TOL_FRACTION = 0.1
#: A grazing impact: ``w`` at the impact below this fraction of the segment's ``v**2``.
GRAZE_RTOL = 1e-12
#: The cone edge: ``|tan alpha| / mu`` within this of ``1 + CONE_RTOL`` at the turning point.
CONE_BAND = 1e-10
#: A time difference within an event's ``t_err`` plus this counts as flagged.
FLAG_SLACK = 1e-12
#: Events the reference runs beyond ``max_events`` (it keeps bouncing where the engine sums a Zeno series).
ZENO_EXTRA_EVENTS = 4
#: Ulps by which the reference's second run moves the start.
PERTURB_ULPS = 4
#: CPU seconds of a DOP853 reference run, and of a GBS run.
DOP853_BUDGET, GBS_BUDGET = 60.0, 300.0
#: Upper bounds of the bins of ``max_dt`` in the summary (the last bin is ``>= 1e-3``).
DT_BINS = (1e-13, 1e-12, 1e-11, 1e-10, 1e-9, 1e-6, 1e-3)
#: Share of the near-stop scenes that pass a crest on a curve that has one (the others barely reach a limiter).
CREST_SHARE = 0.5
#: Events of a near-stop scene (the first ones matter; the 30-digit reference runs them all).
NEAR_STOP_EVENTS = 8
#: Bisection steps of a near-stop speed, and the doublings allowed to find a speed that passes.
BISECTIONS, DOUBLINGS = 60, 12
#: Grid steps of the search for the cone edge past a crest; draws of a climb to a limiter, and its
#: grid of slope checks; events a speed test may run to find its first decision.
EXIT_GRID, TRIES, CLIMB_GRID, DECISION_EVENTS = 400, 20, 16, 4
_TRUNCATED = ("t_max", "max_events")
_TURNS = ("reversal", "arrest")
_G = 9.81


# --- the curves -----------------------------------------------------------------------------------
@dataclass(frozen=True)
class Track:
    """A curve the random scenes use.

    Attributes
    ----------
    name : str
        A catalogue shape or a :mod:`symvib.checks.corpus` entry.
    curve, parameters : dict
        The scene's ``curve`` and ``parameters`` tables.
    span : (float, float)
        Where limiters and starts go (units of ``q``).
    bounded : bool
        The domain is bounded: every scene has both limiters.
    humps : tuple of (q_top, side, width)
        Crests to pass barely: start at ``q_top + side * (0.3 .. 0.9) * width`` towards it.
    edge : (float, float) or None
        An interval of ``q`` on which ``|tan alpha|`` grows (near-edge starts).
    loops : bool
    length : float
        A length of the curve (m).
    q_length : bool
        ``q`` is a length (a graph), not an angle.
    scalable : bool
        Every parameter is a length: the curve scales with them.
    numeric : bool
        The corpus tags it ``numeric`` (its first derivation takes up to a minute).
    """

    name: str
    curve: dict
    parameters: dict
    span: tuple
    bounded: bool = False
    humps: tuple = ()
    edge: tuple | None = None
    loops: bool = False
    length: float = 1.0
    q_length: bool = True
    scalable: bool = True
    numeric: bool = False


def _track(name, curve, parameters, span, **kw):
    return Track(name, curve, parameters, span, **kw)


_PI = math.pi
#: The curves of the random scenes.
TRACKS = {t.name: t for t in (
    _track("circle", {"shape": "circle"}, {"R": 0.5}, (-2.5, 2.5), humps=((_PI, -1, _PI), (-_PI, 1, _PI)),
           edge=(0.0, 1.4), loops=True, length=0.5, q_length=False),
    _track("parabola", {"shape": "parabola"}, {"p": 1.0}, (-1.3, 1.3), bounded=True, edge=(0.0, 1.3),
           q_length=False),
    _track("cycloid", {"shape": "cycloid"}, {"R": 0.5}, (-2.8, 2.8), bounded=True, edge=(0.0, 2.8), length=0.5,
           q_length=False),
    _track("parabola-x", {"shape": "parabola-x"}, {"p": 1.0}, (-1.5, 1.5), edge=(0.0, 1.5)),
    _track("ellipse", {"shape": "ellipse"}, {"a": 1.0, "b": 0.5}, (-1.4, 1.4), bounded=True, edge=(0.0, 1.4),
           length=0.5, q_length=False),
    _track("quartic", {"shape": "quartic"}, {"c": 1.0}, (-1.5, 1.5), edge=(0.0, 1.5)),
    _track("catenary", {"shape": "catenary"}, {"a": 1.0}, (-1.5, 1.5), edge=(0.0, 1.5)),
    _track("double-well", {"z": "a*((x/b)**2 - 1)**2"}, {"a": 0.05, "b": 0.4}, (-0.8, 0.8),
           humps=((0.0, -1, 0.4), (0.0, 1, 0.4)), length=0.4),
    _track("cubic", {"z": "x**3/3 - a**2*x"}, {"a": 0.5}, (-1.1, 1.1), humps=((-0.5, 1, 1.0),), length=0.5,
           scalable=False),
    _track("witch", {"z": "a*x**2/(x**2 + b**2)"}, {"a": 0.3, "b": 0.5}, (-1.2, 1.2), length=0.5),
    _track("tanh-step", {"z": "a*tanh(x/b)"}, {"a": 0.2, "b": 0.3}, (-0.6, 0.6), length=0.3),
    _track("log-cosh", {"z": "a*log(cosh(x/a))"}, {"a": 0.4}, (-1.2, 1.2), edge=(0.0, 1.2), length=0.4),
    _track("hyperbola-graph", {"z": "sqrt(x**2 + a**2) - a"}, {"a": 0.3}, (-1.4, 1.4), edge=(0.0, 1.4),
           length=0.3),
    _track("bowl", {"z": "R - sqrt(R**2 - x**2)", "domain": ["-R", "R"]}, {"R": 0.5}, (-0.45, 0.45),
           bounded=True, edge=(0.0, 0.45), length=0.5),
    _track("exponential-slope", {"z": "a*exp(x/a)"}, {"a": 0.5}, (-1.5, 0.8), edge=(-2.5, 0.5), length=0.5),
    _track("ellipse-loop", {"x": "a*sin(q)", "z": "b*(1 - cos(q))", "q": "q"}, {"a": 0.5, "b": 0.3}, (-2.5, 2.5),
           humps=((_PI, -1, _PI),), loops=True, length=0.4, q_length=False, numeric=True),
)}


@dataclass(frozen=True)
class RandomScene:
    """One random scene: its category, curve, the scene as a dict of tables, and how it was made."""

    index: int
    category: str
    curve: str
    scene: dict
    note: str = ""


# --- drawing scenes -------------------------------------------------------------------------------
def _base(track, mu, k, left, right, q0, qdot0, t_max, max_events):
    limiters = {k_: float(v) for k_, v in (("left", left), ("right", right)) if v is not None}
    return {"name": f"random-{track.name}", "curve": dict(track.curve), "parameters": dict(track.parameters),
            "physics": {"g": _G, "m": 1.0, "mu": float(mu), "restitution": float(k)}, "limiters": limiters,
            "initial": {"q": float(q0), "qdot": float(qdot0)}, "run": {"t_max": float(t_max),
                                                                     "max_events": int(max_events)}}


def _physics(rng, mu_max=0.6):
    mu = 0.0 if rng.random() < 0.15 else rng.uniform(0.0, mu_max)
    u = rng.random()
    k = 0.0 if u < 0.1 else 1.0 if u < 0.2 else rng.uniform(0.0, 1.0)
    return mu, k


def _time_scale(track):
    return math.sqrt(track.length / _G)


def _generic(rng, track, note="generic"):
    mu, k = _physics(rng)
    lo, hi = track.span
    nlim = 2 if track.bounded else int(rng.integers(0, 3))
    a, b = sorted(rng.uniform(lo, hi, 2))
    if nlim == 2:
        left, right = a, b
    elif nlim == 1:
        left, right = (a, None) if rng.random() < 0.5 else (None, b)
    else:
        left = right = None
    q0 = rng.uniform(left if left is not None else lo, right if right is not None else hi)
    if rng.random() < 0.05 and left is not None:
        q0 = left  # on a limiter
    speed = 0.0 if rng.random() < 0.15 else rng.uniform(0.0, 2.0) * math.sqrt(_G * track.length)
    h = curve_frame(scene_from_dict(_base(track, mu, k, left, right, q0, 1.0, 1.0, 1)))(q0)[0]
    qdot0 = rng.choice((-1.0, 1.0)) * speed / h
    T = _time_scale(track)
    return _base(track, mu, k, left, right, q0, qdot0, rng.uniform(3.0, 10.0) * T, 40), note


def _first_decision(scene):
    """``(first event that is not a normal-force sign change, or None; final q)`` of a short reference run."""
    s = scene_from_dict(scene)
    for m in range(1, DECISION_EVENTS + 1):
        run = reference_run(s, max_events=m, budget=DOP853_BUDGET)
        if run.events and run.events[-1][0] != "normal_sign_change" or run.status != "max_events":
            break
    return next((e for e in run.events if e[0] != "normal_sign_change"), None), run.q_final


def _bisect_speed(scene, passes, h, v_guess):
    """The smallest start speed (m/s) for which ``passes(first event)``, bracketed to ``BISECTIONS`` halvings."""
    sign = 1.0 if scene["initial"]["qdot"] >= 0 else -1.0

    def ok(v):
        scene["initial"]["qdot"] = sign * v / h
        return passes(*_first_decision(scene))

    lo, hi = 0.0, v_guess
    for _ in range(DOUBLINGS):
        if ok(hi):
            break
        lo, hi = hi, 2.0 * hi
    else:
        return None
    if ok(lo):
        return None
    for _ in range(BISECTIONS):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if ok(mid) else (mid, hi)
        if hi - lo <= 1e-15 * hi:
            break
    return hi


def _cone_exit(frame, top, direction, width, mu):
    """The first ``q`` past the crest ``top`` (moving ``direction``) where ``|tan alpha| > mu``, or None:
    from there on the particle speeds up, so it has passed (the slowest point is there)."""
    prev = top
    for j in range(1, EXIT_GRID + 1):
        q = top + direction * width * j / EXIT_GRID
        _, s, c, _ = frame(q)
        if abs(s) > mu * abs(c):
            a, b = prev, q
            for _ in range(BISECTIONS):
                m = 0.5 * (a + b)
                _, s, c, _ = frame(m)
                a, b = (a, m) if abs(s) > mu * abs(c) else (m, b)
            return b
        prev = q
    return None


def _near_stop(rng, track):
    ratio = 10.0 ** rng.uniform(-10.0, -4.0)
    mu = 0.0 if rng.random() < 0.3 else rng.uniform(0.0, 0.3)
    k = rng.uniform(0.0, 1.0)
    T = _time_scale(track)
    t_max = (4.0 + 1.5 * math.log(1.0 / ratio)) * T
    lo, hi = track.span
    frame = curve_frame(scene_from_dict(_base(track, mu, k, None, None, 0.5 * (lo + hi), 1.0, 1.0, 1)))
    if track.humps:
        top, side, width = track.humps[int(rng.integers(len(track.humps)))]
        exit_ = _cone_exit(frame, top, -side, width, mu)
        if exit_ is None:
            mu, exit_ = 0.0, top
        q0 = top + side * rng.uniform(0.3, 0.9) * width
        beyond = top - side * rng.uniform(0.2, 0.6) * width if rng.random() < 0.7 else None
        behind = q0 + side * rng.uniform(0.1, 0.3) * width if rng.random() < 0.5 else None
        left, right = (beyond, behind) if side > 0 else (behind, beyond)
        scene = _base(track, mu, k, left, right, q0, -side, t_max, NEAR_STOP_EVENTS)

        def passes(e, q_final):
            # Past the slowest point: an impact beyond, any event beyond it, or no event and beyond it at t_max.
            if e is None:
                return -side * (q_final - exit_) > 0
            return -side * (e[2] - exit_) > 0 or (e[0] == "impact" and -side * (e[2] - top) > 0)

        what = f"passes the crest q = {top:.6g} (slowest at q = {exit_:.6g})"
    else:
        width = hi - lo
        for _ in range(TRIES):
            q0, direction = rng.uniform(lo, hi), float(rng.choice((-1.0, 1.0)))
            lim = q0 + direction * rng.uniform(0.2, 0.6) * width
            # Climb towards the limiter: z rises all the way to it (no crest on the way).
            if lo <= lim <= hi and all(direction * frame(q0 + (lim - q0) * j / CLIMB_GRID)[1] > 0
                                       for j in range(CLIMB_GRID + 1)):
                break
        else:
            return _generic(rng, track, "generic (no climb to a limiter found)")
        behind = q0 - direction * rng.uniform(0.0, 1.0) * (q0 - lo if direction > 0 else hi - q0)
        behind = behind if track.bounded or rng.random() < 0.5 else None
        left, right = (behind, lim) if direction > 0 else (lim, behind)
        scene = _base(track, mu, k, left, right, q0, direction, t_max, NEAR_STOP_EVENTS)

        def passes(e, q_final):
            return e is not None and e[0] == "impact" and e[2] == lim

        what = f"barely reaches the limiter q = {lim:.6g}"
    h = curve_frame(scene_from_dict(scene))(scene["initial"]["q"])[0]
    v = _bisect_speed(scene, passes, h, 2.0 * math.sqrt(_G * track.length))
    if v is None:
        return _generic(rng, track, "generic (no near-stop found)")
    scene["initial"]["qdot"] = math.copysign(v * math.sqrt(1.0 + ratio) / h, scene["initial"]["qdot"])
    return scene, f"near-stop: {what}, w_min/w0 about {ratio:.1e}"


def _tan_root(frame, target, a, b):
    """``q`` in ``[a, b]`` where ``|tan alpha| = target`` (``|tan alpha|`` growing on it), to 40 digits."""
    import mpmath

    with mpmath.workdps(40):
        a, b = mpmath.mpf(a), mpmath.mpf(b)
        for _ in range(140):
            m = (a + b) / 2
            _, s, c, _ = frame(m)
            a, b = (m, b) if abs(s / c) < target else (a, m)
        return float((a + b) / 2)


def _near_edge(rng, track):
    import mpmath

    k = rng.uniform(0.0, 1.0)
    a, b = track.edge
    probe = _base(track, 0.0, k, None, None, a, 0.0, 1.0, 1)
    frame = curve_frame(scene_from_dict(probe), 40)
    with mpmath.workdps(40):
        tan_b = float(abs(frame(mpmath.mpf(b))[1] / frame(mpmath.mpf(b))[2]))
    mu = rng.uniform(0.1, 0.8) * min(tan_b, 0.75)
    delta = 10.0 ** rng.uniform(-9.0, -5.0)
    q0 = _tan_root(frame, mpmath.mpf(mu) * (1 + mpmath.mpf(delta)), a, b)
    lo, hi = track.span
    left, right = (lo, hi) if track.bounded else (None, None)
    T = _time_scale(track)
    return _base(track, mu, k, left, right, q0, 0.0, 12.0 * T, 10), \
        f"near-edge: at rest, |tan alpha| / mu - 1 about {delta:.1e}"


def _looping(rng, track):
    mu = 0.0 if rng.random() < 0.2 else rng.uniform(0.0, 0.25)
    k = rng.uniform(0.0, 1.0)
    q0 = rng.uniform(-0.5, 0.5)
    h = curve_frame(scene_from_dict(_base(track, mu, k, None, None, q0, 1.0, 1.0, 1)))(q0)[0]
    speed = math.sqrt(_G * track.length * rng.uniform(5.0, 14.0))
    T = _time_scale(track)
    return _base(track, mu, k, None, None, q0, rng.choice((-1.0, 1.0)) * speed / h, rng.uniform(3.0, 8.0) * T,
                 40), "looping"


def _scaled(rng, track):
    scene, _ = _generic(rng, track)
    lam = 10.0 ** rng.uniform(-6.0, 3.0)
    scene["parameters"] = {k: v * lam for k, v in scene["parameters"].items()}
    qs = lam if track.q_length else 1.0
    scene["limiters"] = {k: v * qs for k, v in scene["limiters"].items()}
    scene["initial"] = {"q": scene["initial"]["q"] * qs,
                        "qdot": scene["initial"]["qdot"] * math.sqrt(lam) * qs / lam}
    scene["run"]["t_max"] *= math.sqrt(lam)
    return scene, f"scale: lengths times {lam:.3g}"


_MAKERS = {"generic": _generic, "near-stop": _near_stop, "near-edge": _near_edge, "looping": _looping,
           "scale": _scaled}
_ELIGIBLE = {"generic": lambda t: True, "near-stop": lambda t: True, "near-edge": lambda t: t.edge is not None,
             "looping": lambda t: t.loops, "scale": lambda t: t.scalable}


def _counts(n, quotas, categories):
    """Scenes per category: the quotas' shares of ``n`` by largest remainders."""
    shares = {c: quotas.get(c, 0.0) for c in categories}
    total = sum(shares.values())
    exact = {c: n * s / total for c, s in shares.items()}
    out = {c: int(x) for c, x in exact.items()}
    for c in sorted(exact, key=lambda c: out[c] - exact[c])[:n - sum(out.values())]:
        out[c] += 1
    return out


def random_scenes(seed: int, n: int, curves=None, quotas=None, categories=CATEGORIES) -> tuple:
    """``n`` random scenes (:class:`RandomScene`), seeded.

    Parameters
    ----------
    seed : int
    n : int
    curves : sequence of str, optional
        Names of :data:`TRACKS` (default: every track not tagged ``numeric``).
    quotas : dict, optional
        Shares of the categories (default :data:`QUOTAS`).
    categories : sequence of str
        The categories drawn (of :data:`CATEGORIES`).

    Notes
    -----
    Scene ``j`` of a category takes its own generator, ``default_rng([seed, category, j])``,
    and the generic scenes take the curves in turn, so that every curve is used.  The
    near-stop scenes run the reference to bisect their speed (about a second each).
    """
    tracks = [TRACKS[c] for c in curves] if curves else [t for t in TRACKS.values() if not t.numeric]
    counts = _counts(n, QUOTAS if quotas is None else quotas, categories)
    out = []
    for ci, category in enumerate(CATEGORIES):
        pool = [t for t in tracks if _ELIGIBLE[category](t)] or tracks
        for j in range(counts.get(category, 0)):
            rng = np.random.default_rng([seed, ci, j])
            choices = pool
            if category == "near-stop":
                crest = rng.random() < CREST_SHARE
                choices = [t for t in pool if bool(t.humps) == crest] or pool
            track = choices[j % len(choices)] if category == "generic" else choices[int(rng.integers(len(choices)))]
            scene, note = _MAKERS[category](rng, track)
            out.append(RandomScene(len(out), category, track.name, scene, note))
    return tuple(out)


# --- the reference --------------------------------------------------------------------------------
def time_tolerance(scene) -> float:
    """``TIME_TOL`` seconds, relative to the scene's time scale where it exceeds 1 s."""
    return TIME_TOL * max(1.0, scene_scales(scene)[2])


@dataclass(frozen=True)
class Reference:
    """The reference of a scene: the run, and what its double-precision pair said of itself.

    ``spread`` is the largest time difference of the two DOP853 runs over their common
    events (``inf`` where their events differ), ``split_at`` the index of their first
    differing event (None if none).
    """

    run: object
    spread: float
    split_at: int | None


_REFERENCES: dict = {}


def _perturbed(scene):
    if scene.qdot0 != 0.0:
        return scene.replace(qdot0=scene.qdot0 * (1.0 + PERTURB_ULPS * 2.0 ** -52))
    q = scene.q0
    for _ in range(PERTURB_ULPS):
        q = math.nextafter(q, math.inf)
    if scene.right is not None and q > scene.right:
        q = scene.q0
    return scene.replace(q0=q)


def reference_for(scene_dict: dict) -> Reference:
    """The reference of a scene given as a dict (cached per process; see the module docstring)."""
    key = json.dumps(scene_dict, sort_keys=True)
    if key in _REFERENCES:
        return _REFERENCES[key]
    scene = scene_from_dict(scene_dict)
    extra = scene.max_events + ZENO_EXTRA_EVENTS
    a = reference_run(scene, max_events=extra, budget=DOP853_BUDGET)
    b = reference_run(_perturbed(scene), rtol=1e-12, max_events=extra, budget=DOP853_BUDGET)
    split_at, spread = None, 0.0
    for i, (x, y) in enumerate(zip(a.events, b.events)):
        if not _same(x, y):
            split_at, spread = i, math.inf
            break
        spread = max(spread, abs(x[1] - y[1]))
    if a.failed or b.failed:
        spread = math.inf
    run = a
    if not spread <= REF_TOL_FRACTION * time_tolerance(scene):
        run = reference_run(scene, "GBS", max_events=extra, budget=GBS_BUDGET)
    out = Reference(run, spread, split_at)
    _REFERENCES[key] = out
    return out


# --- the verdict ----------------------------------------------------------------------------------
@dataclass(frozen=True)
class Verdict:
    """The engine's run of a scene against the reference.

    Attributes
    ----------
    verdict : str
        One of :data:`VERDICTS`.
    max_dt : float
        Largest ``|t - t_ref|`` over the events both have, in s (``nan`` if none).
    first : int or None
        Index of the first differing event (kind, or time beyond the tolerance).
    detail : str
    sequence_differs : bool
        The first difference is in the event sequence, not in a time.
    """

    verdict: str
    max_dt: float
    first: int | None = None
    detail: str = ""
    sequence_differs: bool = False


def _same(a, b) -> bool:
    """Same kind (and for an impact the same limiter)."""
    if a[0] != b[0]:
        return False
    return a[0] != "impact" or (a[3] > 0) == (b[3] > 0)


def _zeno_remaining(scene, impact):
    """The time the remaining bounces after ``impact`` take (physics.md, "Events": Zeno accumulation),
    from the reference's state; None where the series does not apply."""
    q, before = impact[2], impact[3]
    h, sin, cos, _ = curve_frame(scene)(q)
    away = -1.0 if before > 0 else 1.0
    a_up = scene.g * (away * sin + scene.mu * abs(cos))
    a_down = scene.g * (away * sin - scene.mu * abs(cos))
    if not (a_down > 0 and scene.k > 0):
        return None
    ratio = scene.k * math.sqrt(a_down / a_up)
    if ratio >= 1:
        return None
    return scene.k * abs(before) * h * (1 / a_up + 1 / math.sqrt(a_up * a_down)) / (1 - ratio)


def _ambiguous(i, sym, ref, reference, scene, split_at) -> str:
    """Why the first sequence difference (at ``i``) is defensible either way, or ``""``."""
    a = sym[i] if i < len(sym) else None
    b = ref[i] if i < len(ref) else None
    kinds = {a[0] if a else None, b[0] if b else None}
    if split_at is not None and split_at <= i:
        return f"the double-precision reference's two runs split at event {split_at}: a decision within rounding"
    frame = curve_frame(scene)
    if "impact" in kinds and len(kinds - {"impact"}) == 1:
        e = a if a and a[0] == "impact" else b
        v_seg = reference.v_start[i] if i < len(reference.v_start) else 0.0
        w = (frame(e[2])[0] * e[3]) ** 2
        if w <= GRAZE_RTOL * max(v_seg ** 2, scene_scales(scene)[1] ** 2):
            return f"grazing impact: w = {w:.3g} at the limiter"
    if "arrest" in kinds:
        qs = [e[2] for e in (b, a) if e is not None and (e is b and e[0] in _TURNS or e[1] == 0.0)]
        for q in qs:
            _, s, c, _ = frame(q)
            ratio = abs(s) / (scene.mu * abs(c)) if scene.mu * c != 0 else math.inf
            if abs(ratio - 1.0 - CONE_RTOL) <= CONE_BAND:
                return f"cone edge: |tan alpha| / mu = 1 + {ratio - 1:.3g} at q = {q:.17g}"
    return ""


def compare(result, reference, *, scene=None, tol: float | None = None, split_at: int | None = None) -> Verdict:
    """The verdict on an engine ``result`` against a ``reference`` run (see :data:`VERDICTS`).

    Parameters
    ----------
    result : symvib.numeric.events.Result
    reference : symvib.checks.arclength.ReferenceRun
    scene : Scene, optional
        Default ``result.scene``.
    tol : float, optional
        Time tolerance in s (default :func:`time_tolerance`).
    split_at : int, optional
        Where the reference's double-precision pair split (:class:`Reference`).

    Notes
    -----
    Events are compared in order, as kinds (an impact with its limiter) and times,
    up to where both stop: a run that ends at ``t_max`` or ``max_events`` compares the
    events both have (an event of the other run within the tolerance of ``t_max``
    may be missing).  Where the engine summed a Zeno series, its simulated bounces
    are compared, the reference must go on bouncing at that limiter, and the time of
    the rest is compared with the reference's time of the last simulated impact plus the
    series of physics.md ("Events", Zeno accumulation) from the reference's speed there.
    Simultaneous events (within the tolerance) may come in either order.
    """
    scene = result.scene if scene is None else scene
    tol = time_tolerance(scene) if tol is None else tol
    if reference.failed:
        return Verdict("reference_failed", math.nan, None, f"reference: {reference.message}")
    bad = (not result.success) or result.status.is_error
    sym = [(e.kind.value, e.t, e.q, e.qdot_before, e.qdot_after, getattr(e, "t_err", None)) for e in result.events]
    ref = list(reference.events)
    zeno = result.zeno is not None and bool(sym) and sym[-1][0] == "rest_on_limiter"
    body = sym[:-1] if zeno else sym
    dts = []

    def mismatch(i, why):
        dt = max(dts, default=math.nan)
        a = body[i] if i < len(body) else f"end ({result.status.value})"
        b = ref[i] if i < len(ref) else f"end ({reference.status})"
        detail = f"event {i}: engine {a}, reference {b}; {why}"
        if bad:
            return Verdict("flagged", dt, i, f"engine status {result.status.value}; " + detail, True)
        amb = _ambiguous(i, body, ref, reference, scene, split_at)
        if amb:
            return Verdict("ambiguous", dt, i, amb + "; " + detail, True)
        return Verdict("silent_miss", dt, i, detail, True)

    n = min(len(body), len(ref))
    i = 0
    while i < n:
        if not _same(body[i], ref[i]):
            if i + 1 < n and _same(body[i], ref[i + 1]) and _same(body[i + 1], ref[i]) \
                    and abs(body[i][1] - body[i + 1][1]) <= tol and abs(ref[i][1] - ref[i + 1][1]) <= tol:
                ref[i], ref[i + 1] = ref[i + 1], ref[i]
            else:
                return mismatch(i, "the kinds differ")
        dts.append(abs(body[i][1] - ref[i][1]) if math.isfinite(body[i][1]) else math.inf)
        i += 1
    if zeno:
        # The reference keeps bouncing at that limiter (and may end at rest there once a bounce is
        # below the rounding of q); the rest comes after the series of physics.md from its last impact.
        extra = ref[len(body):]
        q_lim = sym[-1][2]
        ends_at_rest = bool(extra) and extra[-1][0] == "rest_on_limiter" and extra[-1][2] == q_lim
        bounces = extra[:len(extra) - ends_at_rest]
        if not body or not bounces or any(e[0] not in ("impact", "reversal") or e[0] == "impact" and e[2] != q_lim
                                          for e in bounces) or not (ends_at_rest or reference.status in _TRUNCATED):
            return mismatch(len(body), "the engine summed a Zeno series; the reference does not keep bouncing")
        remaining = _zeno_remaining(scene, ref[len(body) - 1])
        if remaining is None:
            return mismatch(len(body), "the engine summed a Zeno series where its law does not apply")
        dts.append(abs(sym[-1][1] - (ref[len(body) - 1][1] + remaining)))
    elif len(body) > len(ref):
        late = all(e[1] >= reference.t_final - tol for e in body[len(ref):])
        if not (reference.status in _TRUNCATED and late):
            return mismatch(len(ref), "the reference stopped first")
    elif len(ref) > len(body):
        late = all(e[1] >= scene.t_max - tol for e in ref[len(body):])
        if not (result.status.value == "max_events" or (result.status.value == "t_max" and late)):
            return mismatch(len(body), "the engine stopped first")
    elif result.status.value != reference.status and not {result.status.value, reference.status} & set(_TRUNCATED):
        return mismatch(n, "the statuses differ")
    max_dt = max(dts, default=math.nan)
    late = [j for j, dt in enumerate(dts) if not dt <= tol]
    if not late:
        return Verdict("agree", max_dt)
    j = late[0]
    event = sym[j] if j < len(sym) else None
    detail = f"event {j} ({event[0] if event else '?'}): |t - t_ref| = {dts[j]:.3g} s > {tol:.3g} s"
    if bad:
        return Verdict("flagged", max_dt, j, f"engine status {result.status.value}; " + detail)
    if all(sym[m][5] is not None and dts[m] <= sym[m][5] + FLAG_SLACK for m in late):
        return Verdict("flagged", max_dt, j, "within the events' t_err; " + detail)
    return Verdict("silent_miss", max_dt, j, detail)


# --- running scenes -------------------------------------------------------------------------------
@dataclass(frozen=True)
class Record:
    """One checked scene: the scene, the verdict, both event lists and the reference's method."""

    scene: RandomScene
    verdict: Verdict
    engine_events: tuple
    engine_status: str
    reference_events: tuple
    reference_status: str
    reference_method: str
    seconds: float = field(default=0.0, compare=False)


def check_scene(rs: RandomScene, simulate=None) -> Record:
    """Run one scene on the engine (``symvib.simulate`` by default) and judge it against the reference."""
    if simulate is None:
        from symvib import simulate
    start = time.process_time()
    scene = scene_from_dict(rs.scene)
    ref = reference_for(rs.scene)
    try:
        result = simulate(scene)
    except Exception as exc:  # noqa: BLE001 - an engine that raises has said it cannot
        verdict = Verdict("flagged", math.nan, 0, f"the engine raised {type(exc).__name__}: {exc}")
        return Record(rs, verdict, (), "raised", ref.run.events, ref.run.status, ref.run.method,
                      time.process_time() - start)
    verdict = compare(result, ref.run, scene=scene, split_at=ref.split_at)
    events = tuple((e.kind.value, e.t, e.q, e.qdot_before, e.qdot_after) for e in result.events)
    return Record(rs, verdict, events, result.status.value, ref.run.events, ref.run.status, ref.run.method,
                  time.process_time() - start)


@dataclass(frozen=True)
class Report:
    """The records of :func:`check_scenes`, and their summary."""

    records: tuple

    def counts(self) -> dict:
        """Scenes per verdict (every verdict, zeros included)."""
        return {v: sum(r.verdict.verdict == v for r in self.records) for v in VERDICTS}

    def by_category(self) -> dict:
        """``{category: {verdict: count}}``."""
        out = {c: dict.fromkeys(VERDICTS, 0) for c in CATEGORIES}
        for r in self.records:
            out.setdefault(r.scene.category, dict.fromkeys(VERDICTS, 0))[r.verdict.verdict] += 1
        return {c: v for c, v in out.items() if sum(v.values())}

    def dt_histogram(self) -> dict:
        """Scenes per bin of ``max_dt`` (labels ``"<1e-13"`` ... ``">=1e-03"``; ``"n/a"``: none compared)."""
        labels = [f"<{b:.0e}" for b in DT_BINS] + [f">={DT_BINS[-1]:.0e}", "n/a"]
        out = dict.fromkeys(labels, 0)
        for r in self.records:
            dt = r.verdict.max_dt
            if math.isnan(dt):
                out["n/a"] += 1
                continue
            j = next((j for j, b in enumerate(DT_BINS) if dt < b), len(DT_BINS))
            out[labels[j]] += 1
        return out

    def worst(self, verdict: str = "silent_miss", n: int = 5) -> list:
        """The ``n`` records of ``verdict`` with the largest ``max_dt`` (sequence differences first)."""
        rs = [r for r in self.records if r.verdict.verdict == verdict]
        return sorted(rs, key=lambda r: (not r.verdict.sequence_differs, -np.nan_to_num(r.verdict.max_dt)))[:n]

    def table(self) -> str:
        """The summary as text: verdicts per category, and the distribution of ``max_dt``."""
        cats = self.by_category()
        head = f"{'category':<12}" + "".join(f"{v:>18}" for v in VERDICTS) + f"{'total':>8}"
        lines = [head, "-" * len(head)]
        for c, counts in cats.items():
            lines.append(f"{c:<12}" + "".join(f"{counts[v]:>18}" for v in VERDICTS) + f"{sum(counts.values()):>8}")
        total = self.counts()
        lines.append(f"{'all':<12}" + "".join(f"{total[v]:>18}" for v in VERDICTS) + f"{len(self.records):>8}")
        seq = sum(r.verdict.sequence_differs for r in self.records)
        lines += ["", f"event sequences that differ: {seq}", "max |t - t_ref| per scene:"]
        lines += [f"  {k:>9}: {v}" for k, v in self.dt_histogram().items()]
        methods = {}
        for r in self.records:
            methods[r.reference_method] = methods.get(r.reference_method, 0) + 1
        lines.append("reference: " + ", ".join(f"{m} {c}" for m, c in sorted(methods.items())))
        return "\n".join(lines)


def check_scenes(scenes, simulate=None, progress=None, workers: int = 1) -> Report:
    """Check every scene (:func:`check_scene`) and return the :class:`Report`.

    ``progress(record)`` is called after each scene; ``workers > 1`` checks them in that
    many processes (``simulate`` must then pickle: a module-level function or None).
    """
    records = []
    if workers > 1:
        from concurrent.futures import ProcessPoolExecutor

        with ProcessPoolExecutor(workers) as pool:
            for record in pool.map(check_scene, scenes, [simulate] * len(scenes)):
                records.append(record)
                if progress is not None:
                    progress(record)
        return Report(tuple(records))
    for rs in scenes:
        record = check_scene(rs, simulate)
        records.append(record)
        if progress is not None:
            progress(record)
    return Report(tuple(records))
