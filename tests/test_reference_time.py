"""The time-stepping mpmath reference: closed forms, the phase reference, its cache and its budget."""
import math

import mpmath
import pytest

from symvib.checks.bench.paper_references import REFERENCE_NAME, reference_events
from symvib.checks.bench.scenes import paper_scenes, scene_key
from symvib.checks.reference import phase_reference
from symvib.checks.reference_time import TimeReferenceBudget, time_reference
from symvib.checks.shipped import shipped
from symvib.numeric.scene import scene_from_dict


def incline(k=0.0):
    return scene_from_dict({"curve": {"z": "c*x"}, "parameters": {"c": 0.5},
                            "physics": {"g": 9.81, "mu": 0.1, "restitution": k},
                            "limiters": {"left": 0}, "initial": {"q": 1.0, "qdot": 0.0}})


def test_uniform_acceleration_on_an_incline_to_25_digits():
    """Down an incline: t1 = sqrt(2 L / a_d), a_d = g (sin a - mu cos a), L = x0 / cos a."""
    ref = time_reference(incline(), dps=30)
    assert [e.kind for e in ref] == ["impact", "rest_on_limiter"]
    with mpmath.workdps(40):
        a = mpmath.atan(mpmath.mpf("0.5"))
        ad = mpmath.mpf("9.81") * (mpmath.sin(a) - mpmath.mpf("0.1") * mpmath.cos(a))
        t1 = mpmath.sqrt(2 / mpmath.cos(a) / ad)
        assert abs(ref[0].t - t1) < mpmath.mpf("1e-25")
        assert abs(ref[0].qdot_before + mpmath.sqrt(2 * ad / mpmath.cos(a)) * mpmath.cos(a)) < mpmath.mpf("1e-24")


def test_budget_is_enforced():
    with pytest.raises(TimeReferenceBudget):
        time_reference(incline(0.8), budget=0.0)


@pytest.mark.slow
@pytest.mark.parametrize("name,k", [("paper-cycloid", 1.0), ("paper-circle-3.8", 1.0)])
def test_agrees_with_the_phase_reference_to_1e_20(name, k):
    """Two independent references (time stepping vs quadrature in q) agree to 1e-20.

    The phase reference runs at 45 digits: its reversal times lose about half
    its digits (a 1/sqrt quadrature across a root known to the working precision).
    """
    scene = dict(paper_scenes())[f"{name} k={k:g}"]
    a = time_reference(scene, dps=30)
    b = phase_reference(scene, dps=45)
    assert [e.kind for e in a] == [e.kind for e in b]
    for x, y in zip(a, b):
        assert abs(x.t - y.t) < 1e-20 and abs(x.q - y.q) < 1e-20 and abs(x.qdot_before - y.qdot_before) < 1e-20


def test_cached_references_are_current():
    """The shipped references hold every paper scene, and one of them recomputes to the same digits."""
    data = shipped(REFERENCE_NAME)
    scenes = paper_scenes()
    assert all(scene_key(s) in data for _, s in scenes)
    label, scene = scenes[5]  # paper-circle-3.8 k=0.8: four events, under a second
    cached = reference_events(scene)
    fresh = reference_events(scene, cached=False)
    assert [e[0] for e in cached] == [e[0] for e in fresh]
    assert all(math.isclose(a[1], b[1], abs_tol=1e-15) and a[2] == pytest.approx(b[2], abs=1e-15)
               for a, b in zip(cached, fresh))
