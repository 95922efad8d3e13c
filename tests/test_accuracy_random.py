"""Seeded random scenes: the engine is right (to 1e-9 s against the independent reference) or says it is not.

The verdicts themselves are tested on hand-made results first (:func:`symvib.checks.accuracy.compare`).
The scenes of the harness and their references are stored (``symvib/checks/data/accuracy_reference.json``,
:func:`symvib.checks.accuracy.stored_references`): the harness runs only the engine on them; cheap tests
check that the file is intact and current, a slow one recomputes a few of its references.
"""
import math
import random
from pathlib import Path
from types import SimpleNamespace
from typing import NamedTuple

import pytest

from symvib import simulate
from symvib.checks.accuracy import (
    ACCURACY_REFERENCE_NAME,
    CATEGORIES,
    STORED_SCENES,
    STORED_SEED,
    TIME_TOL,
    StoredReferences,
    check_scenes,
    code_hash,
    compare,
    random_scenes,
    read_references,
    reference_for,
    regenerate,
    stale,
    stored_differences,
    stored_references,
    write_references,
)
from symvib.checks.arclength import ReferenceRun, curve_frame, reference_run, scene_scales
from symvib.checks.shipped import shipped
from symvib.cli.bench import build_bench_parser
from symvib.numeric.events import EventKind, Status
from symvib.numeric.scene import scene_from_dict

pytest.importorskip("scipy")

#: The package's data folder (the shipped file, in this checkout).
ROOT_DATA = Path(__file__).resolve().parents[1] / "symvib" / "checks" / "data"

#: The harness's scenes: how many, on how many curves at least, and the seed (the stored ones).
N_SCENES, MIN_CURVES, SEED = 200, 10, 20261125
#: Silent misses (and flagged scenes) printed in full when the harness fails.
WORST = 5
#: Generic scenes regenerated from the seed by the cheap check of the stored file (no bisection).
REGENERATED = 6
#: The slow check of the stored references: the seed of its choice, how many double-precision and
#: 30-digit references it recomputes, and the largest right-hand-side calls of a scene it picks (the
#: cheaper ones, so that it takes a minute or so).
SUBSET_SEED, SUBSET_DOP853, SUBSET_GBS = 1, 4, 1
SUBSET_MAX_CALLS = {"DOP853": 20_000, "GBS": 20_000}

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


@pytest.fixture(scope="module")
def stored():
    return stored_references()


def test_the_stored_references_are_the_harness_scenes_and_current(stored):
    # The file holds the scenes of this seed and count, made by the code as it is now; if not,
    # regenerate it (the command is in its header and in the message).
    assert (STORED_SEED, STORED_SCENES) == (SEED, N_SCENES)
    assert (stored.header["seed"], stored.header["count"]) == (SEED, N_SCENES)
    assert not stale(stored), f"stale ({stale(stored)}): regenerate with {stored.header['regenerate']}"
    assert [s.index for s in stored.scenes] == list(range(N_SCENES))
    assert len(stored.references) == len(stored.time_scales) == N_SCENES
    assert {s.category for s in stored.scenes} == set(CATEGORIES)
    assert len({s.curve for s in stored.scenes}) >= MIN_CURVES
    for rs, ref, T in zip(stored.scenes, stored.references, stored.time_scales):
        times = [e[1] for e in ref.run.events]
        assert ref.run.method in ("DOP853", "GBS") and times == sorted(times) and 0 < T < math.inf, rs.index


def test_the_stored_generic_scenes_regenerate_from_the_seed_with_their_time_scales(stored):
    # Generic scenes need no bisection: the first few come back identical from the seed.
    generic = [s for s in stored.scenes if s.category == "generic"]
    assert random_scenes(SEED, REGENERATED, stored.header["curves"], categories=("generic",)) \
        == tuple(generic[:REGENERATED])
    for rs, T in zip(stored.scenes, stored.time_scales):
        assert scene_scales(scene_from_dict(rs.scene))[2] == T, rs.index


def test_the_stored_file_is_what_the_writer_writes(stored, tmp_path):
    # Byte for byte (one scene per line, floats as repr), and it reads back as the same references.
    data = shipped(ACCURACY_REFERENCE_NAME)
    path = write_references(tmp_path, data)
    assert path.name == ACCURACY_REFERENCE_NAME
    assert path.read_text(encoding="utf-8") == (ROOT_DATA / ACCURACY_REFERENCE_NAME).read_text(encoding="utf-8")
    again = read_references(path)
    assert again.scenes == stored.scenes and again.time_scales == stored.time_scales
    assert stored_differences(again, stored) == []
    assert len(path.read_text(encoding="utf-8").splitlines()) > N_SCENES


def test_a_changed_header_or_code_is_stale(stored):
    header = {**stored.header, "generator_hash": "0" * 16}
    assert [w.split(":")[0] for w in stale(StoredReferences(header, (), (), ()))] == ["generator_hash"]
    settings = {**stored.header["reference_settings"], "rtol": 1e-10}
    header = {**stored.header, "reference_settings": settings}
    assert [w.split(":")[0] for w in stale(StoredReferences(header, (), (), ()))] == ["reference_settings"]

    class A:
        def f(x):
            """Twice x."""
            # doubled
            return 2 * x

    class B:
        def f(x):
            return 2 * x  # the fingerprint keeps this comment, on a line of code

    class C:
        def f(x):
            return 3 * x  # the fingerprint keeps this comment, on a line of code

    assert code_hash(A.f) != code_hash(B.f) != code_hash(C.f)

    class D:
        def f(x):
            """Twice x, documented otherwise."""

            return 2 * x  # the fingerprint keeps this comment, on a line of code

    assert code_hash(D.f) == code_hash(B.f)


def test_a_differing_reference_is_reported(stored):
    i = next(j for j, ref in enumerate(stored.references) if len(ref.run.events) >= 2)
    ref = stored.references[i]
    events = list(ref.run.events)
    events[1] = (events[1][0], events[1][1] + 1e-9, *events[1][2:])
    moved = type(ref)(type(ref.run)(**{**ref.run.__dict__, "events": tuple(events)}), ref.spread, ref.split_at)
    fresh = StoredReferences({}, (stored.scenes[i],), (moved,), (stored.time_scales[i],))
    diffs = stored_differences(fresh, stored, [i])
    assert len(diffs) == 1 and "event 1" in diffs[0], diffs
    assert stored_differences(StoredReferences({}, (stored.scenes[i],), (ref,), (stored.time_scales[i],)),
                              stored, [i]) == []


def test_regeneration_writes_the_scenes_it_computes(stored, tmp_path):
    # One scene of the seed (a generic one, the first stored): the same scene and reference as stored.
    diffs = regenerate(tmp_path, seed=SEED, n=1, log=lambda *a: None)
    assert any("1 scenes" in d for d in diffs)
    fresh = read_references(tmp_path / ACCURACY_REFERENCE_NAME)
    assert fresh.header["seed"] == SEED and fresh.header["count"] == 1 and not stale(fresh)
    assert stored_differences(fresh, stored, [0]) == []
    args = build_bench_parser().parse_args(["accuracy-reference", "--write", "--out", str(tmp_path),
                                            "--workers", "2"])
    assert (args.job, args.write, args.out, args.workers) == ("accuracy-reference", True, str(tmp_path), 2)


def test_random_scenes_are_right_or_flagged(stored):
    # Every seeded random scene: the engine's event kinds and times agree with the independent
    # (stored) reference to 1e-9 s, or the engine says it is not accurate; never a silent miss.
    # On the plain-Python engine (the compiled one runs the same code, tests/test_backends.py; it
    # would compile an engine per curve, minutes): about 25 s.
    report = check_scenes(stored.scenes, simulate=lambda scene: simulate(scene, backend="python"),
                          references=stored.references, time_scales=stored.time_scales)
    counts = report.counts()
    assert len(report.records) == N_SCENES
    assert counts["agree"] > N_SCENES // 2, report.table()
    assert counts["silent_miss"] == 0, \
        f"{counts['silent_miss']} silent misses; the worst:\n{report.describe('silent_miss', WORST)}\n" \
        f"{report.table()}"
    assert math.isfinite(max(r.verdict.max_dt for r in report.records if r.verdict.verdict == "agree"))


def _subset(stored) -> list:
    """Indices of the scenes whose references the slow check recomputes (seeded; cheap ones)."""
    rng = random.Random(SUBSET_SEED)
    out = []
    for method, count in (("DOP853", SUBSET_DOP853), ("GBS", SUBSET_GBS)):
        pool = [i for i, ref in enumerate(stored.references)
                if ref.run.method == method and ref.run.rhs_calls <= SUBSET_MAX_CALLS[method]]
        out += sorted(rng.sample(pool, count))
    return out


@pytest.mark.slow
def test_a_subset_of_the_stored_references_recomputes_to_1e_12(stored):
    # The stored references themselves, against the reference computed again (DOP853 pair, and
    # the 30-digit run where they disagree): the same events, times to 1e-12 s.
    picks = _subset(stored)
    assert len(picks) == SUBSET_DOP853 + SUBSET_GBS
    assert stored.references[picks[-1]].run.method == "GBS"
    scenes = tuple(stored.scenes[i] for i in picks)
    fresh = StoredReferences({}, scenes, tuple(reference_for(s.scene) for s in scenes),
                             tuple(stored.time_scales[i] for i in picks))
    assert stored_differences(fresh, stored, picks) == []
