"""Static friction ``mu_s >= mu``: the rest test decides with ``mu_s``, sliding keeps ``mu``
(physics.md, "Events" 2), on both engines and in a sweep.

Everything is held against a closed form written here from the equation of motion, not
against another run.  On the circle of radius ``R`` (``x = R sin phi``, ``z = R (1 - cos phi)``,
``h = R``, ``alpha = phi``, ``N = R phidot^2 + g cos phi > 0`` inside the lower half), sliding in
direction ``sigma`` obeys ``R phi'' = -g sin phi - sigma mu (R phi'^2 + g cos phi)``, so
``u = phidot^2`` solves ``du/dphi + 2 m u = -(2 g / R) (sin phi + m cos phi)`` with
``m = sigma mu``.  With ``a = 2 m``:

    u(phi) exp(a phi) = u0 exp(a phi0) - (2 g / R) (I(phi) - I(phi0)),
    I(phi) = exp(a phi) ((a sin phi - cos phi) + m (a cos phi + sin phi)) / (1 + a^2),

and a turning point is the root of ``u`` (found here at 30 digits with mpmath).  The rest test
there reads ``|tan alpha| = |tan phi|``.  Each case puts ``mu < |tan phi| `` and ``mu_s`` a
relative ``1e-6`` above or below ``|tan phi|``: far outside the test's ``1e-9`` tolerance, far
inside any threshold that is not ``mu_s`` itself.
"""
from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest

from symvib.numeric.driver import simulate
from symvib.numeric.scene import scene_from_dict
from symvib.numeric.sweep import sweep

R, G, MU = 0.5, 9.81, 0.1
#: Relative distance of mu_s from |tan alpha| at the point the rest test is made.
MARGIN = 1e-6
#: Agreement of an event's position with the closed form (the engine's turning points are exact
#: to a few ulps of the quadrature-free root of G; this leaves room for the root's conditioning).
Q_TOL = 1e-10
BACKENDS = ("python", pytest.param("numba", marks=pytest.mark.slow))


def circle(**physics):
    """The circle scene: ``R = 0.5``, ``mu = 0.1``; ``physics``, ``limiters`` and ``initial`` as given."""
    limiters = physics.pop("limiters", None)
    initial = physics.pop("initial", {"q": 0.0, "qdot": 2.5})
    data = {"curve": {"shape": "circle"}, "parameters": {"R": R},
            "physics": {"g": G, "mu": MU, "restitution": 1.0, **physics}, "initial": initial}
    if limiters:
        data["limiters"] = limiters
    return scene_from_dict(data)


def closed_form_turning_point(phi0, phidot0, sigma, guess, mu=MU):
    """The turning point of the slide from ``(phi0, phidot0)`` in direction ``sigma`` (module docstring)."""
    with mpmath.workdps(30):
        return float(turning_point_mp(phi0, phidot0, sigma, guess, mu))


def turning_point_mp(phi0, phidot0, sigma, guess, mu=MU):
    """:func:`closed_form_turning_point` as an mpmath number at the working precision."""
    m = sigma * mpmath.mpf(mu)
    a = 2 * m
    r, g = mpmath.mpf(R), mpmath.mpf(G)

    def I(phi):  # noqa: E743 - the antiderivative's name in the docstring
        return mpmath.exp(a * phi) * ((a * mpmath.sin(phi) - mpmath.cos(phi))
                                      + m * (a * mpmath.cos(phi) + mpmath.sin(phi))) / (1 + a * a)

    phi0 = mpmath.mpf(phi0)
    C = I(phi0) + r / (2 * g) * mpmath.mpf(phidot0) ** 2 * mpmath.exp(a * phi0)
    return mpmath.findroot(lambda p: I(p) - C, mpmath.mpf(guess))


#: The first turning point from phi = 0 at phidot = 2.5 rad/s, and |tan alpha| there (by hand).
PHI_T = closed_form_turning_point(0.0, 2.5, +1, 0.46)
TAN_T = abs(math.tan(PHI_T))


def kinds(result):
    return [e.kind.value for e in result.events]


def test_the_closed_form_turning_point_is_where_kinetic_friction_cannot_hold():
    # The cases below need mu < |tan alpha| at the turning point (else mu alone arrests).
    assert MU * (1 + 100 * MARGIN) < TAN_T < 1.0


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_turning_point_inside_the_static_cone_only_arrests_with_mu_s(backend):
    # mu < |tan alpha| <= mu_s: arrested there with mu_s ...
    held = simulate(circle(mu_s=TAN_T * (1 + MARGIN)), backend=backend)
    assert held.status.value == "arrested" and kinds(held) == ["arrest"]
    assert held.events[0].q == pytest.approx(PHI_T, abs=Q_TOL)
    # ... and slides on with mu_s = mu (the default), reversing there.
    default = simulate(circle(), backend=backend)
    assert kinds(default)[0] == "reversal" and default.events[0].q == pytest.approx(PHI_T, abs=Q_TOL)


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_turning_point_just_outside_the_static_cone_slides_on_with_mu(backend):
    # |tan alpha| just above mu_s: a reversal (a threshold above mu_s would arrest here) ...
    r = simulate(circle(mu_s=TAN_T * (1 - MARGIN)), backend=backend)
    assert kinds(r)[:2] == ["reversal", "arrest"]
    assert r.events[0].q == pytest.approx(PHI_T, abs=Q_TOL)
    # ... and the slide back is the kinetic one: its turning point is the closed form's with mu
    # (sliding with mu_s ~ |tan alpha| it would barely leave PHI_T), where |tan alpha| <= mu_s arrests it.
    phi_2 = closed_form_turning_point(PHI_T, 0.0, -1, -0.25)
    assert r.events[1].q == pytest.approx(phi_2, abs=Q_TOL)
    assert abs(math.tan(phi_2)) <= r.scene.mu_s


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_start_at_rest_is_held_by_mu_s_and_slides_just_outside_it(backend):
    phi0 = 0.5
    tan0 = math.tan(phi0)
    assert MU < tan0
    start = {"q": phi0, "qdot": 0.0}
    held = simulate(circle(mu_s=tan0 * (1 + MARGIN), initial=start), backend=backend)
    assert held.status.value == "arrested" and kinds(held) == ["arrest"] and held.t_final == 0.0
    # Just outside: it slides (with mu) to the turning point across the lowest point, where
    # |tan alpha| <= mu_s holds it; with mu_s = mu it reverses there instead.
    phi_2 = closed_form_turning_point(phi0, 0.0, -1, -0.3)
    assert MU < abs(math.tan(phi_2)) < tan0 * (1 - MARGIN)
    slides = simulate(circle(mu_s=tan0 * (1 - MARGIN), initial=start), backend=backend)
    assert kinds(slides) == ["arrest"] and slides.t_final > 0.0
    assert slides.events[0].q == pytest.approx(phi_2, abs=Q_TOL)
    default = simulate(circle(initial=start), backend=backend)
    assert kinds(default)[0] == "reversal" and default.events[0].q == pytest.approx(phi_2, abs=Q_TOL)


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_plastic_impact_rests_on_the_limiter_arrests_or_slides_by_mu_s(backend):
    # Right limiter at phi = 0.4 (reached: PHI_T is beyond it), k = 0: at rest there gravity pulls
    # away from it (downhill, to the left), so mu_s decides: |tan 0.4| = 0.4228 by hand.
    right = 0.4
    assert right < PHI_T
    tan_r = math.tan(right)
    plastic = {"restitution": 0.0, "limiters": {"right": right}}
    held = simulate(circle(mu_s=tan_r * (1 + MARGIN), **plastic), backend=backend)
    assert held.status.value == "arrested" and kinds(held) == ["impact", "arrest"]
    assert held.events[-1].q == right
    # Just outside: it slides off the limiter (with mu) to the closed form's turning point, where
    # |tan alpha| <= mu_s holds it (with mu_s = mu it reverses there).
    phi_2 = closed_form_turning_point(right, 0.0, -1, -0.2)
    assert MU < abs(math.tan(phi_2)) < tan_r * (1 - MARGIN)
    slides = simulate(circle(mu_s=tan_r * (1 - MARGIN), **plastic), backend=backend)
    assert kinds(slides) == ["impact", "arrest"] and slides.events[1].q == pytest.approx(phi_2, abs=Q_TOL)
    default = simulate(circle(**plastic), backend=backend)
    assert kinds(default)[:2] == ["impact", "reversal"] and default.events[1].q == pytest.approx(phi_2, abs=Q_TOL)
    # A limiter on the other side of the lowest point: gravity pushes into it, the particle rests
    # on it whatever mu_s (rest on a limiter comes before the friction cone).
    into = {"restitution": 0.0, "limiters": {"right": -0.3}, "initial": {"q": -0.8, "qdot": 1.0}}
    for mu_s in (None, 5.0):
        r = simulate(circle(**into, **({} if mu_s is None else {"mu_s": mu_s})), backend=backend)
        assert r.status.value == "resting_on_limiter" and kinds(r) == ["impact", "rest_on_limiter"]


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_sweep_over_mu_s_gives_the_statuses_and_events_of_the_driver(backend):
    base = circle()
    values = [MU, 0.3, TAN_T * (1 - MARGIN), TAN_T * (1 + MARGIN), 0.8]
    res = sweep(base, {"mu_s": values}, backend=backend, log_events=4)
    expected = [simulate(base.replace(mu_s=v), backend="python") for v in values]
    assert list(res.status_names()) == [r.status.value for r in expected]
    # Where mu_s holds the first turning point the run is one arrest; below it, it goes on.
    assert [res.events(i)[0][0] for i in range(len(values))] == ["reversal"] * 3 + ["arrest"] * 2
    assert [r.events[0].kind.value for r in expected] == ["reversal"] * 3 + ["arrest"] * 2
    assert np.array_equal(res["events"], [len(r.events) for r in expected])
    assert np.allclose(res["t_final"], [r.t_final for r in expected], rtol=1e-12, atol=0)


def test_a_sweep_over_mu_has_mu_s_follow_it_unless_the_scene_gives_mu_s():
    # No mu_s in the scene: mu_s = mu in every row (mu = 0.6 > |tan alpha| arrests at the turning point).
    follows = sweep(circle(), {"mu": [MU, 0.6]}, backend="python")
    assert list(follows.status_names()) == [simulate(circle(mu=v), backend="python").status.value for v in (MU, 0.6)]
    # A scene with mu_s = 0.7: rows whose mu exceeds it are refused, naming mu_s and the row.
    from symvib.numeric.scene import SceneError

    with pytest.raises(SceneError, match=r"physics\.mu_s: .*below the kinetic mu.*sweep row 1"):
        sweep(circle(mu_s=0.7), {"mu": [MU, 0.75]}, backend="python")


def test_the_mpmath_phase_reference_makes_the_same_rest_decisions_with_mu_s():
    # symvib.checks.reference: its own rest test (physics.md, "Events" 2) and 30-digit events
    from symvib.checks.reference import phase_reference

    for scene in (circle(mu_s=TAN_T * (1 + MARGIN)), circle(mu_s=TAN_T * (1 - MARGIN)),
                  circle(mu_s=0.45, restitution=0.0, limiters={"right": 0.4}),
                  circle(mu_s=0.55, initial={"q": 0.5, "qdot": 0.0}),      # tan 0.5 = 0.546: held at the start
                  circle(mu_s=0.54, initial={"q": 0.5, "qdot": 0.0})):     # slides
        ref = phase_reference(scene, max_events=4)
        got = simulate(scene, backend="python")
        assert [e.kind for e in ref] == kinds(got)[:len(ref)]
        for a, b in zip(ref, got.events):
            assert b.q == pytest.approx(float(a.q), abs=Q_TOL) and b.t == pytest.approx(float(a.t), rel=1e-9)
