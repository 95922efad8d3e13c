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

**Stored references.** The references of the scenes of
``tests/test_accuracy_random.py`` (seed :data:`STORED_SEED`,
:data:`STORED_SCENES` scenes) take about ten minutes on two cores (the
near-stop speeds are bisected against the reference); they ship in
``symvib/checks/data/accuracy_reference.json`` (:data:`ACCURACY_REFERENCE_NAME`),
one scene per line with its reference and time scale, under a header that
identifies them: the seed and count, fingerprints of the generating and the
reference code (:func:`generator_hash`, :func:`reference_hash`) and the
reference's settings (:func:`reference_settings`).  :func:`stored_references`
reads them, :func:`stale` says what no longer matches the code, and
:func:`compute_references` / :func:`write_references` regenerate them
(``symvib bench accuracy-reference --write --out symvib/checks/data``).

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

import ast
import hashlib
import inspect
import json
import math
import textwrap
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from symvib.checks import arclength, randomscenes
from symvib.checks.arclength import CONE_RTOL, ReferenceRun, curve_frame, reference_run, scene_scales
from symvib.checks.randomscenes import CATEGORIES, QUOTAS, TRACKS, RandomScene, random_scenes
from symvib.checks.shipped import shipped
from symvib.numeric.scene import scene_from_dict

__all__ = ["Verdict", "Reference", "Record", "Report", "VERDICTS", "DT_BINS", "TIME_TOL", "reference_for",
           "compare", "check_scene", "check_scenes", "time_tolerance",
           # the stored references
           "StoredReferences", "ACCURACY_REFERENCE_NAME", "STORED_SEED", "STORED_SCENES", "STORE_FORMAT",
           "code_hash", "generator_hash", "reference_hash", "reference_settings", "compute_references",
           "write_references", "read_references", "stored_references", "stale", "reference_differences",
           "stored_differences", "regenerate", "STORED_TOL",
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
#: The cone edge: ``|tan alpha| / mu_s`` within this of ``1 + CONE_RTOL`` at the turning point.
CONE_BAND = 1e-10
#: A time difference within an event's ``t_err`` plus this counts as flagged.
FLAG_SLACK = 1e-12
#: Events the reference runs beyond ``max_events`` (it keeps bouncing where the engine sums a Zeno series).
ZENO_EXTRA_EVENTS = 4
#: Ulps by which the reference's second run moves the start, and that run's relative tolerance.
PERTURB_ULPS, PERTURBED_RTOL = 4, 1e-12
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
    b = reference_run(_perturbed(scene), rtol=PERTURBED_RTOL, max_events=extra, budget=DOP853_BUDGET)
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
            mu_s = scene.mu_static   # the rest test's cone (physics.md, "Events" 2)
            ratio = abs(s) / (mu_s * abs(c)) if mu_s * c != 0 else math.inf
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
    status = result.status.value
    lift = next((i for i, e in enumerate(sym) if e[0] == "lift_off"), None)
    if lift is not None:
        # The reference does not fly (physics.md, "Flight and landing"): up to the lift-off, its left_curve.
        sym, status = sym[:lift] + [("left_curve", *sym[lift][1:])], "left_curve"
    ref = list(reference.events)
    zeno = result.zeno is not None and bool(sym) and sym[-1][0] == "rest_on_limiter"
    body = sym[:-1] if zeno else sym
    dts = []

    def mismatch(i, why):
        dt = max(dts, default=math.nan)
        a = body[i] if i < len(body) else f"end ({status})"
        b = ref[i] if i < len(ref) else f"end ({reference.status})"
        detail = f"event {i}: engine {a}, reference {b}; {why}"
        if bad:
            return Verdict("flagged", dt, i, f"engine status {status}; " + detail, True)
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
        if not (status == "max_events" or (status == "t_max" and late)):
            return mismatch(len(body), "the engine stopped first")
    elif status != reference.status and not {status, reference.status} & set(_TRUNCATED):
        return mismatch(n, "the statuses differ")
    elif status == reference.status == "t_max":
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
        return Verdict("flagged", max_dt, j, f"engine status {status}; " + detail)
    if all(m < len(sym) and sym[m][5] is not None and dts[m] <= sym[m][5] + FLAG_SLACK for m in late):
        return Verdict("flagged", max_dt, j, "within the events' t_err; " + detail)
    return Verdict("silent_miss", max_dt, j, detail)


# --- running scenes -------------------------------------------------------------------------------
#: Digits of event times in :meth:`Report.describe`, and the reference events it shows beyond the engine's.
EVENT_DIGITS, SHOWN_EXTRA_EVENTS = 17, 2


def _event_lines(events) -> str:
    return "\n".join(f"      {e[0]:<19} t = {e[1]:.{EVENT_DIGITS}g}  q = {e[2]:.{EVENT_DIGITS}g}  "
                     f"qdot_before = {e[3]:.6g}" for e in events) or "      (none)"


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


def check_scene(rs: RandomScene, simulate=None, reference: Reference | None = None,
                time_scale: float | None = None) -> Record:
    """Run one scene on the engine and judge it against the reference.

    Parameters
    ----------
    rs : RandomScene
    simulate : callable, optional
        ``simulate(scene) -> Result`` (default ``symvib.simulate`` with its defaults).
    reference : Reference, optional
        The scene's reference (default :func:`reference_for`, computed; a stored one:
        :func:`stored_references`).
    time_scale : float, optional
        The scene's ``T`` (:func:`~symvib.checks.arclength.scene_scales`), which sets the
        tolerance (:func:`time_tolerance`; default: computed).
    """
    if simulate is None:
        from symvib import simulate
    start = time.process_time()
    scene = scene_from_dict(rs.scene)
    ref = reference_for(rs.scene) if reference is None else reference
    tol = None if time_scale is None else TIME_TOL * max(1.0, time_scale)
    try:
        result = simulate(scene)
    except Exception as exc:  # noqa: BLE001 - an engine that raises has said it cannot
        verdict = Verdict("flagged", math.nan, 0, f"the engine raised {type(exc).__name__}: {exc}")
        return Record(rs, verdict, (), "raised", ref.run.events, ref.run.status, ref.run.method,
                      time.process_time() - start)
    verdict = compare(result, ref.run, scene=scene, tol=tol, split_at=ref.split_at)
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

    def describe(self, verdict: str = "silent_miss", n: int = 5) -> str:
        """The worst ``n`` records of ``verdict`` (:meth:`worst`) in full: the scene as JSON (ready for
        ``symvib.simulate``), the verdict's detail and both event lists ("" when there are none)."""
        lines = []
        for r in self.worst(verdict, n):
            v = r.verdict
            shown = r.reference_events[:len(r.engine_events) + SHOWN_EXTRA_EVENTS]
            lines += [f"- scene {r.scene.index} ({r.scene.category}, {r.scene.curve}; {r.scene.note})",
                      f"  max |t - t_ref| = {v.max_dt:.3g} s; {v.detail}",
                      f"  scene = {json.dumps(r.scene.scene)}",
                      f"  engine ({r.engine_status}):", _event_lines(r.engine_events),
                      f"  reference {r.reference_method} ({r.reference_status}):", _event_lines(shown)]
        return "\n".join(lines)

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


def check_scenes(scenes, simulate=None, progress=None, workers: int = 1, references=None,
                 time_scales=None) -> Report:
    """Check every scene (:func:`check_scene`) and return the :class:`Report`.

    ``progress(record)`` is called after each scene; ``workers > 1`` checks them in that
    many spawned processes (``simulate`` must then pickle: a module-level function or None).
    ``references`` and ``time_scales`` (sequences as long as ``scenes``, e.g. of
    :func:`stored_references`) replace computing them.
    """
    n = len(scenes)
    tasks = list(zip(scenes, [simulate] * n, references or [None] * n, time_scales or [None] * n))
    records = []
    if workers > 1:
        from symvib.children import worker_pool

        with worker_pool(workers, "spawn") as pool:
            for record in pool.map(check_scene, *zip(*tasks)):
                records.append(record)
                if progress is not None:
                    progress(record)
        return Report(tuple(records))
    for task in tasks:
        record = check_scene(*task)
        records.append(record)
        if progress is not None:
            progress(record)
    return Report(tuple(records))


# --- stored references ----------------------------------------------------------------------------
#: The stored references (package data, ``symvib/checks/data``), the version of their layout, and the
#: seed and number of the scenes they hold (those of ``tests/test_accuracy_random.py``).
ACCURACY_REFERENCE_NAME = "accuracy_reference.json"
STORE_FORMAT = 1
STORED_SEED, STORED_SCENES = 20261125, 200
#: The command that regenerates the shipped file (from a checkout).
REGENERATE = f"symvib bench accuracy-reference --write --out symvib/checks/data  # writes {ACCURACY_REFERENCE_NAME}"
#: Hex digits of the code fingerprints.
HASH_DIGITS = 16
#: A recomputed reference agrees with the stored one within this: event times in s (relative to
#: ``T`` where ``T > 1 s``), positions relative to the run's largest ``|q|``.
STORED_TOL = 1e-12


def code_hash(*objects) -> str:
    """A fingerprint of the code of modules, classes or functions.

    The source of each (:func:`inspect.getsource`) without its docstrings, comment lines
    and blank lines, so that documenting the code does not change it; anything else does.

    Examples
    --------
    >>> from symvib.checks import randomscenes
    >>> code_hash(randomscenes) == generator_hash(), len(code_hash(randomscenes))
    (True, 16)
    """
    digest = hashlib.sha256()
    for obj in objects:
        source = textwrap.dedent(inspect.getsource(obj))
        docstrings = set()
        for node in ast.walk(ast.parse(source)):
            body = getattr(node, "body", None)
            if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and body \
                    and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant) \
                    and isinstance(body[0].value.value, str):
                docstrings.update(range(body[0].lineno, body[0].end_lineno + 1))
        for number, line in enumerate(source.splitlines(), 1):
            text = line.rstrip()
            if number not in docstrings and text.strip() and not text.lstrip().startswith("#"):
                digest.update(text.encode() + b"\n")
    return digest.hexdigest()[:HASH_DIGITS]


def generator_hash() -> str:
    """The fingerprint (:func:`code_hash`) of the code that draws the scenes (:mod:`symvib.checks.randomscenes`)."""
    return code_hash(randomscenes)


def reference_hash() -> str:
    """The fingerprint (:func:`code_hash`) of the code of the references: :mod:`symvib.checks.arclength`
    (it also bisects the near-stop speeds) and :func:`reference_for` with its helpers."""
    return code_hash(arclength, reference_for, _perturbed, _same, _final_dt)


def reference_settings() -> dict:
    """The settings of :func:`reference_for` (and of :func:`~symvib.checks.arclength.reference_run`)."""
    return {"rtol": arclength.RTOL, "perturbed_rtol": PERTURBED_RTOL, "perturb_ulps": PERTURB_ULPS,
            "ref_tol_fraction": REF_TOL_FRACTION, "time_tol": TIME_TOL, "zeno_extra_events": ZENO_EXTRA_EVENTS,
            "gbs_digits": arclength.GBS_DIGITS, "gbs_guard_digits": arclength.GBS_GUARD_DIGITS,
            "cone_rtol": arclength.CONE_RTOL, "cone_atol": arclength.CONE_ATOL,
            "dop853_budget": DOP853_BUDGET, "gbs_budget": GBS_BUDGET}


@dataclass(frozen=True)
class StoredReferences:
    """Scenes with their references, as :func:`read_references` reads them.

    Attributes
    ----------
    header : dict
        What identifies them: ``format``, ``seed``, ``count``, ``curves``, ``generator_hash``,
        ``reference_hash``, ``reference_settings`` (and, for information, ``made_with``).
    scenes : tuple of RandomScene
    references : tuple of Reference
    time_scales : tuple of float
        Each scene's ``T`` (:func:`~symvib.checks.arclength.scene_scales`).
    """

    header: dict
    scenes: tuple
    references: tuple
    time_scales: tuple


def _num(x) -> float:
    """A stored number: a float, or the string of a non-finite one (JSON has none)."""
    return float(x)


def _plain(x):
    """``x`` with non-finite floats as their strings (``"inf"``, ``"nan"``), for strict JSON."""
    if isinstance(x, float) and not math.isfinite(x):
        return repr(x)
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    if isinstance(x, dict):
        return {k: _plain(v) for k, v in x.items()}
    return x


def _entry(rs: RandomScene) -> dict:
    """One stored scene: the scene, its time scale and its reference (computed)."""
    ref = reference_for(rs.scene)
    run = ref.run
    return _plain({"index": rs.index, "category": rs.category, "curve": rs.curve, "note": rs.note,
                   "T": scene_scales(scene_from_dict(rs.scene))[2], "scene": rs.scene,
                   "reference": {"method": run.method, "status": run.status, "message": run.message,
                                 "spread": ref.spread, "split_at": ref.split_at, "t_final": run.t_final,
                                 "q_final": run.q_final, "qdot_final": run.qdot_final, "rhs_calls": run.rhs_calls,
                                 "v_start": list(run.v_start), "events": [list(e) for e in run.events]}})


def _decode(entry: dict) -> tuple:
    """``(RandomScene, Reference, T)`` of a stored scene."""
    r = entry["reference"]
    events = tuple((e[0], *(_num(x) for x in e[1:])) for e in r["events"])
    run = ReferenceRun(r["status"], events, r["message"], r["method"], tuple(_num(v) for v in r["v_start"]),
                       _num(r["t_final"]), _num(r["q_final"]), _num(r["qdot_final"]), int(r["rhs_calls"]))
    rs = RandomScene(entry["index"], entry["category"], entry["curve"], entry["scene"], entry["note"])
    return rs, Reference(run, _num(r["spread"]), r["split_at"]), _num(entry["T"])


def _made_with() -> dict:
    import platform

    import mpmath
    import scipy

    return {"python": platform.python_version(), "numpy": np.__version__, "scipy": scipy.__version__,
            "mpmath": mpmath.__version__}


def compute_references(seed: int = STORED_SEED, n: int = STORED_SCENES, curves=None, workers: int = 1,
                       log=None) -> dict:
    """Draw ``n`` scenes of ``seed`` (:func:`random_scenes`) and compute their references.

    Parameters
    ----------
    seed, n : int
    curves : sequence of str, optional
        As :func:`random_scenes` (default: every curve not tagged ``numeric``).
    workers : int
        Processes (spawned) drawing the scenes and computing the references.
    log : callable, optional
        ``log(str)`` after each scene.

    Returns
    -------
    dict
        The content of the stored file (:func:`write_references`): a header and ``scenes``.
    """
    names = list(curves) if curves else [t.name for t in TRACKS.values() if not t.numeric]
    # The fingerprints first: the source is read from the files when they are taken.
    header = {"format": STORE_FORMAT, "seed": seed, "count": n, "curves": names,
              "generator_hash": generator_hash(), "reference_hash": reference_hash(),
              "reference_settings": reference_settings(), "made_with": _made_with(), "regenerate": REGENERATE}
    scenes = random_scenes(seed, n, names, workers=workers)
    entries = []
    if workers > 1:
        from symvib.children import worker_pool

        with worker_pool(workers, "spawn") as pool:
            entries = list(pool.map(_entry, scenes))
    else:
        entries = [_entry(rs) for rs in scenes]
    if log is not None:
        for e in entries:
            r = e["reference"]
            log(f"{e['index']:>4} {e['category']:<10} {e['curve']:<18} {r['method']:<6} {r['status']:<18} "
                f"{len(r['events']):>3} events")
    return {**header, "scenes": entries}


def write_references(path, data: dict) -> Path:
    """Write :func:`compute_references`'s ``data`` to ``path`` (a file, or a folder that receives
    :data:`ACCURACY_REFERENCE_NAME`): the header, then one scene per line (floats as ``repr``)."""
    path = Path(path)
    if path.is_dir() or not path.suffix:
        path = path / ACCURACY_REFERENCE_NAME
    header = {k: v for k, v in data.items() if k != "scenes"}
    lines = [f" {json.dumps(k)}: {json.dumps(v, allow_nan=False)}," for k, v in header.items()]
    scenes = ",\n".join("  " + json.dumps(e, allow_nan=False, separators=(",", ":")) for e in data["scenes"])
    text = "{\n" + "\n".join(lines) + '\n "scenes": [\n' + scenes + "\n ]\n}\n"
    assert json.loads(text) == json.loads(json.dumps(data)), "the stored text must read back as the data"
    from symvib import safeio

    return safeio.write_file(path, text, what="reference folder")


def read_references(data: dict | str | Path) -> StoredReferences:
    """The :class:`StoredReferences` of a file's content (a dict) or of a file."""
    if not isinstance(data, dict):
        data = json.loads(Path(data).read_text(encoding="utf-8"))
    decoded = [_decode(e) for e in data["scenes"]]
    header = {k: v for k, v in data.items() if k != "scenes"}
    return StoredReferences(header, *(tuple(x) for x in zip(*decoded))) if decoded else \
        StoredReferences(header, (), (), ())


def stored_references() -> StoredReferences:
    """The shipped references (``symvib/checks/data/accuracy_reference.json``, package data)."""
    return read_references(shipped(ACCURACY_REFERENCE_NAME))


def stale(stored: StoredReferences) -> list:
    """What no longer matches the code in ``stored``'s header (the format, the fingerprints of the generating
    and the reference code, the reference's settings), one string each; ``[]`` when it is current."""
    h = stored.header
    now = {"format": STORE_FORMAT, "generator_hash": generator_hash(), "reference_hash": reference_hash(),
           "reference_settings": reference_settings()}
    return [f"{k}: stored {h.get(k)!r}, now {v!r}" for k, v in now.items() if h.get(k) != v]


def reference_differences(a: Reference, b: Reference, tol: float) -> str:
    """How two references of a scene differ, or ``""`` where they agree.

    They agree in method, status, where their double-precision pair split, the kinds of their
    events, every event time within ``tol`` (s) and every event position (and the final one)
    within ``tol`` relative to the largest ``|q|`` of ``a``'s run.
    """
    x, y = a.run, b.run
    for what in ("method", "status"):
        if getattr(x, what) != getattr(y, what):
            return f"{what}: {getattr(x, what)} against {getattr(y, what)}"
    if a.split_at != b.split_at:
        return f"split_at: {a.split_at} against {b.split_at}"
    if [e[0] for e in x.events] != [e[0] for e in y.events]:
        return f"event kinds: {[e[0] for e in x.events]} against {[e[0] for e in y.events]}"
    q_scale = max([abs(e[2]) for e in x.events] + [abs(x.q_final), math.ulp(1.0)])
    for i, (e, f) in enumerate(zip(x.events, y.events)):
        if not (abs(e[1] - f[1]) <= tol and abs(e[2] - f[2]) <= tol * q_scale):
            return f"event {i} ({e[0]}): t {e[1]!r} against {f[1]!r}, q {e[2]!r} against {f[2]!r}"
    if x.status == "t_max" and not abs(x.q_final - y.q_final) <= tol * q_scale:
        return f"final q at t_max: {x.q_final!r} against {y.q_final!r}"
    return ""


def stored_differences(fresh: StoredReferences, stored: StoredReferences, indices=None) -> list:
    """Where ``fresh`` (recomputed) and ``stored`` references differ, one string each (``[]``: none).

    Compares the scenes (as dicts), their time scales and their references
    (:func:`reference_differences`, to :data:`STORED_TOL`) of the scenes ``indices`` of
    ``stored`` (default all), which ``fresh`` holds in that order.
    """
    indices = range(len(stored.scenes)) if indices is None else list(indices)
    if len(fresh.scenes) != len(indices):
        return [f"{len(fresh.scenes)} scenes recomputed, {len(indices)} to compare"]
    out = []
    for j, i in enumerate(indices):
        rs, ref, T = stored.scenes[i], stored.references[i], stored.time_scales[i]
        where = f"scene {rs.index} ({rs.category}, {rs.curve})"
        if fresh.scenes[j].scene != rs.scene:
            out.append(f"{where}: the scene differs")
            continue
        if fresh.time_scales[j] != T:
            out.append(f"{where}: T {fresh.time_scales[j]!r} against {T!r}")
        why = reference_differences(ref, fresh.references[j], STORED_TOL * max(1.0, T))
        if why:
            out.append(f"{where}: {why}")
    return out


def regenerate(out=None, *, seed: int = STORED_SEED, n: int = STORED_SCENES, workers: int = 1, log=print) -> list:
    """``symvib bench accuracy-reference``: recompute the stored scenes and references, compare them.

    Parameters
    ----------
    out : pathlib.Path, optional
        A folder whose :data:`ACCURACY_REFERENCE_NAME` receives them (``symvib/checks/data`` in a
        checkout updates the shipped file); None stores nothing.
    seed, n : int
        The scenes (default: those of the shipped file, :data:`STORED_SEED`, :data:`STORED_SCENES`).
    workers : int
        Processes.
    log : callable

    Returns
    -------
    list of str
        Where they differ from the shipped ones: what is :func:`stale` in the shipped file's
        header, then the seed and count if they differ, else :func:`stored_differences`.
    """
    start = time.perf_counter()
    data = compute_references(seed, n, workers=workers, log=log)
    log(f"{len(data['scenes'])} scenes of seed {seed} in {time.perf_counter() - start:.0f} s wall")
    try:
        shipped = stored_references()
    except FileNotFoundError as exc:
        diffs = [str(exc)]
    else:
        diffs = stale(shipped)
        was = (shipped.header.get("seed"), shipped.header.get("count"))
        if was != (seed, n):
            diffs.append(f"the shipped references are of seed {was[0]}, {was[1]} scenes; these of seed {seed}, "
                         f"{n} scenes")
        else:
            diffs += stored_differences(read_references(data), shipped)
    log("\n".join(diffs) if diffs else "the same as the shipped references")
    if out is not None:
        log(f"wrote {write_references(out, data)}")
    return diffs
