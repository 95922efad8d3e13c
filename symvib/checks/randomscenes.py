"""Random scenes nobody designed: seeded, on many curves, in categories that find weak spots.

:func:`random_scenes` draws seeded scenes (a NumPy ``Generator`` per scene, so
scene ``j`` of a category is the same whatever ``n``) on the curves of
:data:`TRACKS` (catalogue shapes and curves of :mod:`symvib.checks.corpus`), in
the categories of :data:`CATEGORIES` with the quotas of :data:`QUOTAS`:

``generic``
    random limiters (none, one, two), ``mu`` in ``[0, 0.6]`` (sometimes 0),
    ``k`` in ``[0, 1]`` (sometimes exactly 0 or 1), start anywhere between them
    (now and then on a limiter, at rest, or with unilateral contact);
``near-stop``
    the speed nearly vanishes: the start speed is bisected against the reference
    (:func:`symvib.checks.arclength.reference_run`) so that the particle barely
    passes a crest (the top of a loop, the crest of a double well; with friction
    the slowest point is past the crest, where ``|tan alpha|`` exceeds ``mu``
    again) or barely reaches a limiter it climbs to, with ``w_min / w0`` about
    ``1e-4 .. 1e-10``;
``near-edge``
    a start at rest a relative ``1e-9 .. 1e-5`` beyond the friction-cone edge
    ``|tan alpha| = mu``: it slides slowly and stops just past the edge;
``looping``
    full loops on the circle (and the ellipse, a curve tagged ``numeric``);
``scale``
    a generic scene with every length scaled by ``1e-6 .. 1e3`` (limiters,
    speeds and ``t_max`` scaled with it).

Each :class:`RandomScene` carries its scene as a dict of tables
(:func:`symvib.numeric.scene.scene_from_dict`, ``symvib.simulate``) and a note
of how it was made.  :mod:`symvib.checks.accuracy` judges the engine on them.

Examples
--------
>>> scenes = random_scenes(seed=1, n=3, categories=("generic",))
>>> [s.category for s in scenes], len({s.curve for s in scenes})
(['generic', 'generic', 'generic'], 3)
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from symvib.checks.arclength import curve_frame, reference_run
from symvib.numeric.scene import scene_from_dict

__all__ = ["Track", "TRACKS", "RandomScene", "CATEGORIES", "QUOTAS", "random_scenes"]

#: The categories of random scenes.
CATEGORIES = ("generic", "near-stop", "near-edge", "looping", "scale")
#: Share of each category in :func:`random_scenes`.
QUOTAS = {"generic": 0.35, "near-stop": 0.2, "near-edge": 0.15, "looping": 0.1, "scale": 0.2}
#: Generic scenes: the largest mu, the shares with mu = 0, with k = 0 (and as many with k = 1), at
#: rest, on a limiter and with unilateral contact (physics.md, "Assumptions"); the start speed in
#: units of sqrt(g L), t_max in units of the time scale sqrt(L / g), and the event bound.
MU_MAX, MU_ZERO_SHARE, K_EXACT_SHARE = 0.6, 0.15, 0.1
AT_REST_SHARE, ON_LIMITER_SHARE, UNILATERAL_SHARE = 0.15, 0.05, 0.1
SPEED_RANGE, T_MAX_RANGE, GENERIC_EVENTS = (0.0, 2.0), (3.0, 10.0), 40
#: Near-stop scenes: the range of log10(w_min / w0), the largest mu, the share with mu = 0, where
#: the start is (a fraction of the crest's width, or of the span to a limiter), and t_max
#: ``(a + b ln(w0 / w_min)) T`` (the time through a near stop grows as the logarithm).
RATIO_RANGE, NEAR_STOP_MU_MAX, NEAR_STOP_MU_ZERO = (-10.0, -4.0), 0.3, 0.3
CREST_START, CLIMB_START, NEAR_STOP_T_MAX = (0.3, 0.9), (0.2, 0.6), (4.0, 1.5)
#: Near-stop limiters: beyond the crest (a share of the scenes, at a fraction of its width past it)
#: and behind the start (a share, at a fraction of the width).
BEYOND_SHARE, BEYOND_RANGE, BEHIND_SHARE, BEHIND_RANGE = 0.7, (0.2, 0.6), 0.5, (0.1, 0.3)
#: Near-edge scenes: the range of log10(|tan alpha| / mu - 1) at the start, mu as a fraction of the
#: largest slope on the edge interval (and at most NEAR_EDGE_MU_MAX), t_max in T and the event bound.
DELTA_RANGE, NEAR_EDGE_MU, NEAR_EDGE_MU_MAX = (-9.0, -5.0), (0.1, 0.8), 0.75
NEAR_EDGE_T_MAX, NEAR_EDGE_EVENTS = 12.0, 10
#: Looping scenes: the largest mu, the share with mu = 0, the start within +-LOOP_START, the start
#: speed squared in units of g L, t_max in T, and the event bound.
LOOP_MU_MAX, LOOP_MU_ZERO, LOOP_START = 0.25, 0.2, 0.5
LOOP_SPEED2, LOOP_T_MAX, LOOP_EVENTS = (5.0, 14.0), (3.0, 8.0), 40
#: Scaled scenes: the range of log10 of the length factor.
SCALE_RANGE = (-6.0, 3.0)
#: Digits and bisection steps of the start on the cone edge.
EDGE_DIGITS, EDGE_BISECTIONS = 40, 140
#: Share of the near-stop scenes that pass a crest on a curve that has one (the others barely reach a limiter).
CREST_SHARE = 0.5
#: Events of a near-stop scene (the first ones matter; the 30-digit reference runs them all).
NEAR_STOP_EVENTS = 8
#: Bisection steps of a near-stop speed, and the doublings allowed to find a speed that passes.
BISECTIONS, DOUBLINGS = 60, 12
#: Grid steps of the search for the cone edge past a crest; draws of a climb to a limiter, and its
#: grid of slope checks; events a speed test may run to find its first decision.
EXIT_GRID, TRIES, CLIMB_GRID, DECISION_EVENTS = 400, 20, 16, 4
#: CPU seconds of a reference run of the speed bisection, and its relative resolution.
BISECT_BUDGET, BISECT_RTOL = 60.0, 1e-15
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


def _physics(rng):
    mu = 0.0 if rng.random() < MU_ZERO_SHARE else rng.uniform(0.0, MU_MAX)
    u = rng.random()
    k = 0.0 if u < K_EXACT_SHARE else 1.0 if u < 2 * K_EXACT_SHARE else rng.uniform(0.0, 1.0)
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
    if rng.random() < ON_LIMITER_SHARE and left is not None:
        q0 = left  # on a limiter
    speed = 0.0 if rng.random() < AT_REST_SHARE else rng.uniform(*SPEED_RANGE) * math.sqrt(_G * track.length)
    h = curve_frame(scene_from_dict(_base(track, mu, k, left, right, q0, 1.0, 1.0, 1)))(q0)[0]
    qdot0 = rng.choice((-1.0, 1.0)) * speed / h
    T = _time_scale(track)
    scene = _base(track, mu, k, left, right, q0, qdot0, rng.uniform(*T_MAX_RANGE) * T, GENERIC_EVENTS)
    if rng.random() < UNILATERAL_SHARE:
        scene["physics"]["contact"] = "unilateral"
        note += ", unilateral contact"
    return scene, note


def _first_decision(scene):
    """``(first event that is not a normal-force sign change, or None; final q)`` of a short reference run."""
    s = scene_from_dict(scene)
    for m in range(1, DECISION_EVENTS + 1):
        run = reference_run(s, max_events=m, budget=BISECT_BUDGET)
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
        if hi - lo <= BISECT_RTOL * hi:
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
    ratio = 10.0 ** rng.uniform(*RATIO_RANGE)
    mu = 0.0 if rng.random() < NEAR_STOP_MU_ZERO else rng.uniform(0.0, NEAR_STOP_MU_MAX)
    k = rng.uniform(0.0, 1.0)
    T = _time_scale(track)
    t_max = (NEAR_STOP_T_MAX[0] + NEAR_STOP_T_MAX[1] * math.log(1.0 / ratio)) * T
    lo, hi = track.span
    frame = curve_frame(scene_from_dict(_base(track, mu, k, None, None, 0.5 * (lo + hi), 1.0, 1.0, 1)))
    if track.humps:
        top, side, width = track.humps[int(rng.integers(len(track.humps)))]
        exit_ = _cone_exit(frame, top, -side, width, mu)
        if exit_ is None:
            mu, exit_ = 0.0, top
        q0 = top + side * rng.uniform(*CREST_START) * width
        beyond = top - side * rng.uniform(*BEYOND_RANGE) * width if rng.random() < BEYOND_SHARE else None
        behind = q0 + side * rng.uniform(*BEHIND_RANGE) * width if rng.random() < BEHIND_SHARE else None
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
            lim = q0 + direction * rng.uniform(*CLIMB_START) * width
            # Climb towards the limiter: z rises all the way to it (no crest on the way).
            if lo <= lim <= hi and all(direction * frame(q0 + (lim - q0) * j / CLIMB_GRID)[1] > 0
                                       for j in range(CLIMB_GRID + 1)):
                break
        else:
            return _generic(rng, track, "generic (no climb to a limiter found)")
        behind = q0 - direction * rng.uniform(0.0, 1.0) * (q0 - lo if direction > 0 else hi - q0)
        behind = behind if track.bounded or rng.random() < BEHIND_SHARE else None
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

    with mpmath.workdps(EDGE_DIGITS):
        a, b = mpmath.mpf(a), mpmath.mpf(b)
        for _ in range(EDGE_BISECTIONS):
            m = (a + b) / 2
            _, s, c, _ = frame(m)
            a, b = (m, b) if abs(s / c) < target else (a, m)
        return float((a + b) / 2)


def _near_edge(rng, track):
    import mpmath

    k = rng.uniform(0.0, 1.0)
    a, b = track.edge
    probe = _base(track, 0.0, k, None, None, a, 0.0, 1.0, 1)
    frame = curve_frame(scene_from_dict(probe), EDGE_DIGITS)
    with mpmath.workdps(EDGE_DIGITS):
        tan_b = float(abs(frame(mpmath.mpf(b))[1] / frame(mpmath.mpf(b))[2]))
    mu = rng.uniform(*NEAR_EDGE_MU) * min(tan_b, NEAR_EDGE_MU_MAX)
    delta = 10.0 ** rng.uniform(*DELTA_RANGE)
    q0 = _tan_root(frame, mpmath.mpf(mu) * (1 + mpmath.mpf(delta)), a, b)
    lo, hi = track.span
    left, right = (lo, hi) if track.bounded else (None, None)
    T = _time_scale(track)
    return _base(track, mu, k, left, right, q0, 0.0, NEAR_EDGE_T_MAX * T, NEAR_EDGE_EVENTS), \
        f"near-edge: at rest, |tan alpha| / mu - 1 about {delta:.1e}"


def _looping(rng, track):
    mu = 0.0 if rng.random() < LOOP_MU_ZERO else rng.uniform(0.0, LOOP_MU_MAX)
    k = rng.uniform(0.0, 1.0)
    q0 = rng.uniform(-LOOP_START, LOOP_START)
    h = curve_frame(scene_from_dict(_base(track, mu, k, None, None, q0, 1.0, 1.0, 1)))(q0)[0]
    speed = math.sqrt(_G * track.length * rng.uniform(*LOOP_SPEED2))
    T = _time_scale(track)
    return _base(track, mu, k, None, None, q0, rng.choice((-1.0, 1.0)) * speed / h, rng.uniform(*LOOP_T_MAX) * T,
                 LOOP_EVENTS), "looping"


def _scaled(rng, track):
    scene, _ = _generic(rng, track)
    lam = 10.0 ** rng.uniform(*SCALE_RANGE)
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


def _draw(seed, ci, j, names):
    """Scene ``j`` of category ``CATEGORIES[ci]`` on the tracks ``names``: ``(category, curve, scene, note)``."""
    category = CATEGORIES[ci]
    tracks = [TRACKS[c] for c in names]
    pool = [t for t in tracks if _ELIGIBLE[category](t)] or tracks
    rng = np.random.default_rng([seed, ci, j])
    if category == "near-stop":
        crest = rng.random() < CREST_SHARE
        pool = [t for t in pool if bool(t.humps) == crest] or pool
    track = pool[j % len(pool)] if category == "generic" else pool[int(rng.integers(len(pool)))]
    scene, note = _MAKERS[category](rng, track)
    return category, track.name, scene, note


def random_scenes(seed: int, n: int, curves=None, quotas=None, categories=CATEGORIES, workers: int = 1) -> tuple:
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
    workers : int
        Processes drawing scenes (the same scenes whatever their number).

    Notes
    -----
    Scene ``j`` of a category takes its own generator, ``default_rng([seed, category index, j])``,
    and the generic scenes take the curves in turn, so that every curve is used.  The
    near-stop scenes run the reference to bisect their speed (a second or two each).
    """
    names = list(curves) if curves else [t.name for t in TRACKS.values() if not t.numeric]
    counts = _counts(n, QUOTAS if quotas is None else quotas, categories)
    tasks = [(seed, ci, j, names) for ci, c in enumerate(CATEGORIES) for j in range(counts.get(c, 0))]
    drawn = _map(_draw, tasks, workers)
    return tuple(RandomScene(i, *d) for i, d in enumerate(drawn))


def _map(fn, tasks, workers):
    """``[fn(*task) for task in tasks]``, in ``workers`` processes (spawned: safe after threads) when above 1."""
    if workers <= 1:
        return [fn(*task) for task in tasks]
    from symvib.children import worker_pool

    with worker_pool(workers, "spawn") as pool:
        return list(pool.map(fn, *zip(*tasks)))
