"""The stability suite: symvib's driver is right on every case; the classifier sorts runs as it says."""
import math

import pytest

from symvib import simulate
from symvib.checks import stability as st
from symvib.checks.reference import phase_reference
from symvib.checks.reference_time import time_reference

#: Cases whose right outcome takes more than a few seconds to compute.
SLOW_CASES = {"thousands", "zeno-parabola"}
NAMES = [c.name for c in st.cases()]


def test_catalogue_covers_the_issue():
    assert {"grazing", "cone-edge", "zeno", "plastic-stay", "plastic-slide", "mu-to-0", "elastic-long",
            "large-friction", "thousands", "cycloid-cusp", "normal-sign", "looping"} <= set(NAMES)
    assert len(NAMES) == len(set(NAMES))
    for c in st.cases():
        assert c.derivation and c.title


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow) if n in SLOW_CASES else n for n in NAMES])
def test_driver_is_correct_on_every_case(name):
    c = st.case(name)
    exp = st.expected(name)
    result = simulate(c.scene, samples=False)
    assert st.classify(exp, result.status.value, result.events) == st.CORRECT
    assert result.energy_budget.relative_residual < 1e-10


def test_zeno_accumulation_time_is_the_geometric_series():
    """The driver's accumulation time on the incline is the closed-form geometric sum."""
    c = st.case("zeno")
    result = simulate(c.scene, samples=False)
    assert result.zeno is not None
    assert result.t_final == pytest.approx(st.expected("zeno").final_time, abs=1e-12)


# --- the truths, checked against the references ------------------------------------------------------
def test_incline_closed_form_against_the_time_reference():
    c = st.case("plastic-stay")
    exp = st.expected("plastic-stay")
    ref = time_reference(c.scene)
    assert [e.kind for e in ref] == ["impact", "rest_on_limiter"]
    assert abs(float(ref[0].t) - exp.times[0]) < 1e-15


def test_frictionless_generator_against_the_phase_reference():
    scene = st.case("mu-to-0").scene.replace(mu=0.0, max_events=8)
    ours = st.frictionless_events(scene, 8)
    ref = phase_reference(scene, max_events=8)
    assert st.labels(ours) == st.labels([(e.kind, e.t, e.q, e.qdot_before) for e in ref])
    for a, r in zip(ours, ref):
        assert abs(a[1] - float(r.t)) < 1e-12 and abs(a[2] - float(r.q)) < 1e-12


# --- the classifier -----------------------------------------------------------------------------------
EXP = st.Expected(labels=("impact+", "reversal", "arrest"), status="arrested", times=(1.0, 2.0, 3.0),
                  positions=(0.5, -0.1, 0.02), tol=1e-6)
GOOD = [("impact", 1.0, 0.5, 2.0), ("reversal", 2.0, -0.1, 0.0), ("arrest", 3.0, 0.02, 0.0)]


def test_classify_correct_and_inaccurate():
    assert st.classify(EXP, "arrested", GOOD) == st.CORRECT
    late = [GOOD[0], ("reversal", 2.0 + 1e-4, -0.1, 0.0), GOOD[2]]
    assert st.classify(EXP, "arrested", late) == st.INACCURATE


def test_classify_missed_impact():
    # Turned back just before the limiter instead of hitting it (a grazing impact missed).
    assert st.classify(EXP, "arrested", [("reversal", 0.99, 0.4999, 0.0), ("arrest", 2.5, 0.02, 0.0)]) \
        == st.MISSED_IMPACT


def test_classify_wrong_arrest():
    early = [GOOD[0], ("arrest", 2.0, -0.1, 0.0)]
    assert st.classify(EXP, "arrested", early) == st.WRONG_ARREST
    late = GOOD[:2] + [("reversal", 3.0, 0.02, 0.0), ("arrest", 3.5, 0.01, 0.0)]
    assert st.classify(EXP, "arrested", late) == st.WRONG_ARREST


def test_classify_wrong_sequence_nan_and_did_not_finish():
    wrong_side = [("impact", 1.0, -0.5, -2.0), GOOD[1], GOOD[2]]
    assert st.classify(EXP, "arrested", wrong_side) == st.WRONG_SEQUENCE
    assert st.classify(EXP, "failed", [GOOD[0], ("reversal", math.nan, math.nan, 0.0)]) == st.NAN
    assert st.classify(EXP, "failed", GOOD[:1], "non-finite state") == st.NAN
    assert st.classify(EXP, "failed", GOOD[:1], "PeerBudget: CPU-time budget of 20 s spent") == st.DID_NOT_FINISH
    assert st.classify(EXP, "max_events", GOOD[:2]) == st.DID_NOT_FINISH


def test_classify_zeno_accepts_any_number_of_bounces():
    exp = st.Expected(labels=("impact-", "rest_on_limiter"), status="resting_on_limiter", times=(1.0,),
                      positions=(0.0,), final_time=3.0, zeno=True, tol=1e-9)
    bounces = [("impact", 1.0, 0.0, -1.0)]
    for i in range(5):
        bounces += [("reversal", 1.5 + i * 0.1, 0.1, 0.0), ("impact", 1.6 + i * 0.1, 0.0, -0.1)]
    assert st.classify(exp, "resting_on_limiter", bounces + [("rest_on_limiter", 3.0, 0.0, 0.0)]) == st.CORRECT
    assert st.classify(exp, "resting_on_limiter", bounces + [("rest_on_limiter", 2.9, 0.0, 0.0)]) == st.INACCURATE
    assert st.classify(exp, "max_events", bounces) == st.DID_NOT_FINISH
    assert st.classify(exp, "arrested", bounces[:2] + [("arrest", 1.5, 0.1, 0.0)]) == st.WRONG_ARREST
