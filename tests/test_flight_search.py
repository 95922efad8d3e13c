"""The landing search on curves nobody designed (docs/physics.md, "Flight and landing" 3 and 6).

A Gaussian well ``-a exp(-x^2/b^2)`` on unilateral contact: a flight that starts at a lift-off
separates as ``t^3`` (``N`` crosses 0), which the Lipschitz and second-derivative tests resolve only
with millions of distances (a run took 93 s and then raised); the cubic test settles it in a few.
Far out its generated kernels overflow (``exp(x^2/b^2)`` in ``h'``): the searched stretch ends there
and a flight that gets past it leaves it with a status that says why, not an exception.
"""
import math

import pytest

import symvib
from symvib.numeric import flight
from symvib.numeric.events import EventKind
from symvib.numeric.flight import _cubic_clear
from symvib.numeric.scene import scene_from_dict

WELL = {"curve": {"z": "-a*exp(-x**2/b**2)", "name": "gauss-well"}, "parameters": {"a": 0.1449, "b": 0.1840},
        "physics": {"mu": 0.2507, "restitution": 0.8, "contact": "unilateral", "restitution_curve": 0.3},
        "initial": {"q": -0.2830, "qdot": 2.5785}, "run": {"t_max": 5.0, "max_events": 2000}}
#: Fast enough to fly out of the well and land on its flat tail near x = 2.95 m (where the kernels
#: once overflowed: SymPy's simplified curvature held exp(2 x^2/b^2); symbolic.identity.tamed).
OUT_OF_THE_WELL = {**WELL, "parameters": {"a": 0.1077, "b": 0.1875}, "initial": {"q": 0.2713, "qdot": 8.1019}}
#: A well of the same depth and width whose kernels overflow in every form SymPy gives them (a
#: hyperbolic secant of x^2/b^2: sums of exp(+-x^2/b^2) in every derivative), beyond about 1.45 m.
OVERFLOWING_WELL = {**OUT_OF_THE_WELL, "curve": {"z": "-2*a/(exp(x**2/b**2) + exp(-x**2/b**2))",
                                                 "name": "sech-well"}}
#: A search this short resolved the well's flights (before the cubic test, 200,000 were not enough).
FEW = 3000


def _scene(d):
    return scene_from_dict(d)


def test_a_flight_from_a_lift_off_is_searched_in_few_distances(monkeypatch):
    monkeypatch.setattr(flight, "MAX_EVALUATIONS", FEW)
    r = symvib.simulate(_scene(WELL), samples=False)
    kinds = [e.kind for e in r.events]
    assert r.status.value == "arrested", r.message
    assert kinds[0] is EventKind.LIFT_OFF and kinds.count(EventKind.LANDING) >= 5
    assert r.energy_budget.relative_residual < 1e-12


def test_a_landing_search_out_of_distances_ends_the_run_with_a_status(monkeypatch):
    monkeypatch.setattr(flight, "MAX_EVALUATIONS", 3)
    r = symvib.simulate(_scene(WELL), samples=False)
    assert r.status.value == "tolerance_not_met" and not r.success
    assert "landing search took more than 3 distances" in r.message


def test_a_flight_past_where_the_kernels_overflow_leaves_the_stretch_saying_why():
    r = symvib.simulate(_scene(OVERFLOWING_WELL), samples=False)
    assert r.status.value == "left_domain", r.message
    assert "kernels are not finite" in r.message
    assert [e.kind for e in r.events] == [EventKind.LIFT_OFF]


def test_a_flight_out_of_a_well_lands_where_the_ballistic_parabola_meets_the_curve():
    # The free flight x = x0 + vx t, z = z0 + vz t - g t^2/2 meets z = -a exp(-x^2/b^2): its root at 30
    # digits (mpmath), independent of the engine's landing search.
    import mpmath as mp

    r = symvib.simulate(_scene(OUT_OF_THE_WELL), samples=False)
    lift, land = r.events[0], r.events[1]
    assert (lift.kind, land.kind) == (EventKind.LIFT_OFF, EventKind.LANDING), r.events[:2]
    with mp.workdps(30):
        a, b, g = (mp.mpf(str(v)) for v in (0.1077, 0.1875, 9.81))
        z = lambda x: -a * mp.exp(-x**2 / b**2)    # noqa: E731
        x0, vx = mp.mpf(str(lift.q)), mp.mpf(str(lift.qdot_after))
        vz = mp.diff(z, x0) * vx
        t = mp.findroot(lambda t: z(x0) + vz * t - g * t**2 / 2 - z(x0 + vx * t), mp.mpf(land.t - lift.t))
        assert abs(float(t) - (land.t - lift.t)) <= 1e-13 and abs(float(x0 + vx * t) - land.q) <= 1e-13
    assert r.status.value == "arrested" and r.energy_budget.relative_residual < 1e-12, r.message


def test_the_plain_engine_sets_up_a_curve_whose_kernels_overflow_far_out():
    # Python's math raises where compiled code gives inf: the run's length scale samples the curve
    # far from the start (exp(x^2/b^2) overflows there); before, the plain run ended non_finite at once.
    well = {**WELL, "physics": {"mu": 0.1457, "restitution": 0.8}, "parameters": {"a": 0.1845, "b": 0.1043},
            "initial": {"q": -0.1971, "qdot": 1.0}}
    r = symvib.simulate(_scene(well), samples=False, backend="python", rtol=1e-10)
    assert r.status.value == "arrested", r.message
    assert EventKind.NORMAL_SIGN_CHANGE in [e.kind for e in r.events]


@pytest.mark.parametrize("d, d1, d2, J, span, clear", [
    (1.0, 0.0, 0.0, 6.0, 0.99, True),          # 1 - s^3 > 0 before s = 1
    (1.0, 0.0, 0.0, 6.0, 1.01, False),
    (1.0, -3.0, 4.0, 0.0, 10.0, False),        # 1 - 3 s + 2 s^2 dips to -1/8 at s = 3/4
    (1.0, -2.0, 4.0, 0.0, 10.0, True),         # 1 - 2 s + 2 s^2 stays above 1/2
    (1e-12, 3e-12, 6e-12, 30e-12, 1.0, True),  # t^3-like growth from a lift-off, J within bounds
    (1.0, 0.0, 0.0, math.inf, 0.1, False),     # no bound: never clear
    (0.0, 1.0, 0.0, 0.0, 1.0, False),          # not above the curve at the end
])
def test_the_cubic_lower_bound_is_positive_exactly_where_it_should_be(d, d1, d2, J, span, clear):
    assert _cubic_clear(d, d1, d2, J, span) is clear


#: A double well whose wall is steep far out: a bounce near its rim skims the rising wall.
STEEP_WALL = {"curve": {"z": "a*x**4 - b*x**2", "name": "steep-wall"}, "parameters": {"a": 0.25216, "b": 0.11956},
              "physics": {"mu": 0.07775, "restitution": 0.61306, "contact": "unilateral",
                          "restitution_curve": 0.75277},
              "initial": {"q": -0.26470, "qdot": 10.92}, "run": {"t_max": 5.0, "max_events": 3000}}


def test_the_nearest_point_is_never_taken_on_a_far_branch_of_the_curve():
    # The stretch reaches 60 length scales, where the quartic's samples are far apart: the global
    # longest segment let a far branch of the curve (the other side of the well) count as about as
    # near as the wall beside the particle, the signed distance jumped, and the search took that
    # jump for a landing 3.5 m off the curve (the budget then missed by 7 %).
    r = symvib.simulate(_scene(STEEP_WALL), samples=False)
    assert r.status.value == "t_max", r.message
    assert r.energy_budget.relative_residual < 1e-12
    stretch = flight.Stretch(*_stretch_args(r))
    for e in r.events:
        if e.kind is EventKind.LANDING:
            x, z, _, _ = stretch.point(e.q)
            q, d = stretch.nearest(x, z)
            assert abs(d) < 1e-9 and q == pytest.approx(e.q, abs=1e-9)


def _stretch_args(r):
    """A stretch over the run's searched span (as :func:`symvib.numeric.flights.searched_stretch` takes it)."""
    from symvib.numeric.flights import searched_stretch
    from symvib.numeric.prepared import prepared_of

    scene = r.scene
    prep = prepared_of(scene)
    scale = r.stats["scale"]
    qa, qb = searched_stretch(scene.q0, scene, prep.domain.lo, prep.domain.hi, scale)
    return prep.kernels, tuple(scene.param_values), qa, qb, scale, scene.q0
