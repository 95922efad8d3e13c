"""Seeded random scenes: the engine is right (to 1e-9 s against the independent reference) or says it is not.

The verdicts themselves are tested on hand-made results first (:func:`symvib.checks.accuracy.compare`).
"""
import math
import os
from types import SimpleNamespace
from typing import NamedTuple

import pytest

from symvib.checks.accuracy import (
    CATEGORIES,
    TIME_TOL,
    check_scenes,
    compare,
    random_scenes,
)
from symvib.checks.arclength import ReferenceRun, curve_frame, reference_run
from symvib.numeric.events import EventKind, Status
from symvib.numeric.scene import scene_from_dict

pytest.importorskip("scipy")

#: The harness's scenes: how many, on how many curves at least, and the seed.
N_SCENES, MIN_CURVES, SEED = 200, 10, 20261125
#: Processes the slow test draws and checks scenes in (the verdicts do not depend on it).
WORKERS = min(4, os.cpu_count() or 1)

INCLINE = {"curve": {"z": "c*x"}, "parameters": {"c": 0.5}, "physics": {"mu": 0.1, "restitution": 0.8},
           "limiters": {"left": 0.0, "right": 2.0}, "initial": {"q": 1.0, "qdot": 0.0},
           "run": {"t_max": 20.0, "max_events": 60}}


class _Event(NamedTuple):
    kind: EventKind
    t: float
    q: float
    qdot_before: float
    qdot_after: float
    t_err: float | None = None


def _result(scene, events, status="max_events", zeno=None):
    status = Status(status)
    return SimpleNamespace(scene=scene, status=status, success=not status.is_error, zeno=zeno,
                           events=tuple(_Event(EventKind(e[0]), *e[1:]) for e in events))


def _reference(events, status="max_events", v_start=None):
    return ReferenceRun(status, tuple(events), "", "DOP853", tuple(v_start or [1.0] * len(events)))


@pytest.fixture(scope="module")
def incline():
    return scene_from_dict(INCLINE)


REF = [("impact", 0.798188571017626, 0.0, -2.505673562138532, 2.004538849710826),
       ("reversal", 1.2238891422270268, 0.4266666666666669, 0.0, 0.0),
       ("impact", 1.7452637335642103, 0.0, -1.6366991171256866, 1.3093592937005494)]


def test_the_same_events_agree(incline):
    v = compare(_result(incline, REF), _reference(REF), scene=incline)
    assert v.verdict == "agree" and v.max_dt == 0.0


def test_a_late_event_is_a_silent_miss_unless_the_engine_says_so(incline):
    late = [REF[0], (REF[1][0], REF[1][1] + 1e-6, *REF[1][2:]), REF[2]]
    assert compare(_result(incline, late), _reference(REF), scene=incline).verdict == "silent_miss"
    failed = _result(incline, late, status="energy_budget_mismatch")
    assert compare(failed, _reference(REF), scene=incline).verdict == "flagged"
    covered = [REF[0], (*late[1], 2e-6), REF[2]]
    assert compare(_result(incline, covered), _reference(REF), scene=incline).verdict == "flagged"
    uncovered = [REF[0], (*late[1], 1e-7), REF[2]]
    assert compare(_result(incline, uncovered), _reference(REF), scene=incline).verdict == "silent_miss"


def test_within_the_tolerance_is_agreement(incline):
    close = [REF[0], (REF[1][0], REF[1][1] + 0.5 * TIME_TOL, *REF[1][2:]), REF[2]]
    v = compare(_result(incline, close), _reference(REF), scene=incline)
    assert v.verdict == "agree" and v.max_dt == pytest.approx(0.5 * TIME_TOL, rel=1e-3)


def test_a_missed_impact_is_a_silent_miss_but_a_grazing_one_is_ambiguous(incline):
    swapped = [("reversal", REF[0][1], 1e-3, 0.0, 0.0), *REF[1:]]
    assert compare(_result(incline, swapped), _reference(REF), scene=incline).verdict == "silent_miss"
    grazing = [("impact", REF[0][1], 0.0, -1e-7, 8e-8), *REF[1:]]
    v = compare(_result(incline, swapped), _reference(grazing, v_start=[3.0, 3.0, 3.0]), scene=incline)
    assert v.verdict == "ambiguous" and "grazing" in v.detail


def test_arrest_against_reversal_at_the_cone_edge_is_ambiguous():
    mu = 0.3
    scene = scene_from_dict({"curve": {"shape": "parabola-x"}, "parameters": {"p": 1.0},
                             "physics": {"mu": mu, "restitution": 0.5}, "initial": {"q": 0.0, "qdot": 1.0}})
    edge = mu * (1 + 1e-9)  # tan alpha = x / p: the arrest test's own edge
    ref = [("reversal", 0.5, edge, 0.0, 0.0)]
    assert compare(_result(scene, [("arrest", 0.5, edge, 0.0, 0.0)], "arrested"), _reference(ref, "max_events"),
                   scene=scene).verdict == "ambiguous"
    inside = [("reversal", 0.5, 0.9 * mu, 0.0, 0.0)]
    assert compare(_result(scene, [("arrest", 0.5, 0.9 * mu, 0.0, 0.0)], "arrested"),
                   _reference(inside, "max_events"), scene=scene).verdict == "silent_miss"


def test_runs_cut_by_t_max_compare_the_events_both_have(incline):
    scene = incline.replace(t_max=1.5)
    ref = [*REF[:2], ("impact", 1.5 + 1e-3, 0.0, -1.0, 0.8)]
    assert compare(_result(scene, REF[:2], "t_max"), _reference(ref, "max_events"), scene=scene).verdict == "agree"
    early = [*REF[:2], ("impact", 1.4, 0.0, -1.0, 0.8)]
    assert compare(_result(scene, REF[:2], "t_max"), _reference(early, "max_events"),
                   scene=scene).verdict == "silent_miss"


def test_runs_that_both_reach_t_max_compare_where_they_are(incline):
    scene = incline.replace(t_max=1.5)
    ref = ReferenceRun("t_max", tuple(REF[:2]), "", "DOP853", (1.0, 1.0), 1.5, 0.3, -1.0)
    for dq, verdict in ((0.0, "agree"), (1e-12, "agree"), (1e-6, "silent_miss")):
        result = _result(scene, REF[:2], "t_max")
        result.q_final, result.qdot_final = 0.3 + dq, -1.0
        assert compare(result, ref, scene=scene).verdict == verdict, dq


def test_a_failed_reference_decides_nothing(incline):
    run = ReferenceRun("failed", (), "budget", "GBS")
    assert compare(_result(incline, REF), run, scene=incline).verdict == "reference_failed"


def test_the_engine_zeno_series_agrees_with_the_reference_bouncing_on(incline):
    import symvib

    scene = incline.replace(right=None)
    result = symvib.simulate(scene)
    assert result.zeno is not None and result.events[-1].kind is EventKind.REST_ON_LIMITER
    run = reference_run(scene, max_events=scene.max_events + 40)
    v = compare(result, run, scene=scene)
    assert v.verdict == "agree", v.detail
    assert v.max_dt < 1e-11


def test_random_scenes_are_seeded_and_spread_over_curves_and_categories():
    kw = dict(seed=7, n=30, quotas={"generic": 2, "near-edge": 1, "looping": 1, "scale": 1},
              categories=("generic", "near-edge", "looping", "scale"))
    a, b = random_scenes(**kw), random_scenes(**kw)
    assert a == b and len(a) == 30
    assert {s.category for s in a} == {"generic", "near-edge", "looping", "scale"}
    assert len({s.curve for s in a if s.category == "generic"}) >= MIN_CURVES
    for s in a:
        scene = scene_from_dict(s.scene)
        assert scene.t_max > 0 and scene.max_events > 0
        if s.category == "near-edge":
            # At rest just outside the friction cone: 1 < |tan alpha| / mu < 1 + 1e-5 (plus rounding).
            _, sin, cos, _ = curve_frame(scene)(scene.q0)
            assert scene.qdot0 == 0.0 and 1.0 < abs(sin / cos) / scene.mu < 1.0 + 1.1e-5


@pytest.mark.slow
def test_random_scenes_are_right_or_flagged():
    # Every seeded random scene: the engine's event kinds and times agree with the independent
    # reference to 1e-9 s, or the engine says it is not accurate; never a silent miss.
    scenes = random_scenes(SEED, N_SCENES, workers=WORKERS)
    assert len(scenes) == N_SCENES and len({s.curve for s in scenes}) >= MIN_CURVES
    assert {s.category for s in scenes} == set(CATEGORIES)
    report = check_scenes(scenes, workers=WORKERS)
    counts = report.counts()
    misses = [f"{r.scene.index} {r.scene.category} {r.scene.curve}: {r.verdict.detail}"
              for r in report.records if r.verdict.verdict == "silent_miss"]
    assert counts["agree"] > N_SCENES // 2, report.table()
    assert not misses, f"{len(misses)} silent misses:\n" + "\n".join(misses[:20]) + "\n" + report.table()
    assert math.isfinite(max(r.verdict.max_dt for r in report.records if r.verdict.verdict == "agree"))
