"""A verdict on the engine against the independent reference, over random scenes.

:func:`compare` gives a :class:`Verdict` of an engine result against a
:class:`~symvib.checks.arclength.ReferenceRun` (see :data:`VERDICTS`),
:func:`reference_for` the reference of a scene, and :func:`check_scenes` runs a
list of scenes (:func:`symvib.checks.randomscenes.random_scenes`) on the engine
and summarises them (:class:`Report`: verdicts per category, the distribution
of the largest event-time difference per scene, the worst cases).

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
>>> from symvib.numeric.scene import scene_from_dict
>>> scene = {"curve": {"shape": "parabola-x"}, "parameters": {"p": 1.0},
...          "physics": {"mu": 0.2, "restitution": 0.5}, "limiters": {"right": 0.5},
...          "initial": {"q": 0.0, "qdot": 3.0}, "run": {"max_events": 4}}
>>> import symvib
>>> v = compare(symvib.simulate(scene), reference_for(scene).run)
>>> v.verdict, v.max_dt < 1e-12
('agree', True)
"""
from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field

import numpy as np

from symvib.checks.arclength import CONE_RTOL, curve_frame, reference_run, scene_scales
from symvib.checks.randomscenes import CATEGORIES, QUOTAS, TRACKS, RandomScene, random_scenes
from symvib.numeric.scene import scene_from_dict

__all__ = ["Verdict", "Reference", "Record", "Report", "VERDICTS", "DT_BINS", "TIME_TOL", "reference_for",
           "compare", "check_scene", "check_scenes", "time_tolerance",
           # the random scenes, for convenience (symvib.checks.randomscenes)
           "CATEGORIES", "QUOTAS", "TRACKS", "RandomScene", "random_scenes"]

#: Verdicts, best first.  ``agree``: the same events, every time within the tolerance;
#: ``flagged``: not so, but the engine says so (``success`` False, an error status, the
#: events' ``t_err`` covers the difference, or it raised); ``ambiguous``: the first difference
#: is a decision both answers can defend within rounding (a grazing impact, the cone edge,
#: a decision on which the double-precision reference's own two runs split);
#: ``reference_failed``: the reference could not decide; ``silent_miss``: anything else.
VERDICTS = ("agree", "flagged", "ambiguous", "reference_failed", "silent_miss")
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
_TRUNCATED = ("t_max", "max_events")
_TURNS = ("reversal", "arrest")


# --- the reference --------------------------------------------------------------------------------
def time_tolerance(scene) -> float:
    """``TIME_TOL`` seconds, relative to the scene's time scale where it exceeds 1 s."""
    return TIME_TOL * max(1.0, scene_scales(scene)[2])


@dataclass(frozen=True)
class Reference:
    """The reference of a scene: the run, and what its double-precision pair said of itself.

    ``spread`` is the largest time difference of the two DOP853 runs over their common
    events and their final states at ``t_max`` (``inf`` where their events differ),
    ``split_at`` the index of their first differing event (None if none).
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
    elif a.status == b.status == "t_max" and split_at is None and len(a.events) == len(b.events):
        spread = max(spread, _final_dt(scene, b.q_final, a))
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


def _final_dt(scene, q, reference) -> float:
    """The distance from ``q`` to the reference's final position at ``t_max``, as the time the
    reference takes to cover it: ``ds / max(|v|, sqrt(g ds))`` (from rest, ``ds`` takes ``sqrt(2 ds / a)``)."""
    h = curve_frame(scene)(reference.q_final)[0]
    ds = h * abs(q - reference.q_final)
    speed = h * abs(reference.qdot_final)
    return 0.0 if ds == 0 else ds / max(speed, math.sqrt(scene.g * ds))


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
    Simultaneous events (within the tolerance) may come in either order.  Where both stop at
    ``t_max`` after the same events, the final positions are compared too, as the time the
    reference takes to go from one to the other.
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
        if not body or any(e[0] not in ("impact", "reversal") or e[0] == "impact" and e[2] != q_lim for e in bounces) \
                or not (ends_at_rest or bounces and reference.status in _TRUNCATED):
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
    elif result.status.value == reference.status == "t_max":
        # Both stopped at t_max after the same events: their final positions, as a time.
        dts.append(_final_dt(scene, result.q_final, reference))
    max_dt = max(dts, default=math.nan)
    late = [j for j, dt in enumerate(dts) if not dt <= tol]
    if not late:
        return Verdict("agree", max_dt)
    j = late[0]
    event = sym[j] if j < len(sym) else ("the state at t_max",)
    detail = f"event {j} ({event[0]}): |t - t_ref| = {dts[j]:.3g} s > {tol:.3g} s"
    if bad:
        return Verdict("flagged", max_dt, j, f"engine status {result.status.value}; " + detail)
    if all(m < len(sym) and sym[m][5] is not None and dts[m] <= sym[m][5] + FLAG_SLACK for m in late):
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
    many spawned processes (``simulate`` must then pickle: a module-level function or None).
    """
    if workers > 1:
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        records = []
        with ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn")) as pool:
            for record in pool.map(check_scene, scenes, [simulate] * len(scenes)):
                records.append(record)
                if progress is not None:
                    progress(record)
        return Report(tuple(records))
    records = []
    for rs in scenes:
        record = check_scene(rs, simulate)
        records.append(record)
        if progress is not None:
            progress(record)
    return Report(tuple(records))
