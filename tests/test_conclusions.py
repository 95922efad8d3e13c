"""The paper's conclusions: every quote verbatim in the seed, every number recomputed independently.

The numbers of :mod:`symvib.paper.conclusions` come from the generated closed-form
phase trajectories sampled between events.  Here each motion interval is
integrated again from the state after its first event with SciPy's
``solve_ivp`` on the equation of motion of docs/physics.md, written out from
the curve's geometry (SymPy, lambdified; no generated kernel, no driver), and
the forces and energies are computed from their definitions.
"""
import math
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

from symvib.paper import conclusions as conc
from symvib.paper.seed import SEED_FILE
from symvib.shapes import shape

scipy_integrate = pytest.importorskip("scipy.integrate")

SEED = (Path(__file__).resolve().parents[1] / "docs" / "seed" / SEED_FILE).read_text(encoding="utf-8")
#: Tolerances of the ODE integration and of the comparison of maxima and ranges (sampling differs).
RTOL, ATOL = 1e-11, 1e-13
MATCH = 1e-3
#: Points of the dense ODE output per interval.
ODE_POINTS = 1500


@pytest.fixture(scope="module")
def runs():
    return conc.paper_runs()


@pytest.fixture(scope="module")
def claims(runs):
    return {c.key: c for c in conc.conclusions(runs)}


def _geometry(name):
    """NumPy functions x, z, h, h', alpha, kappa of the curve, from its SymPy definition."""
    c = shape(name).curve()
    args = [c.q, *c.params]
    return {k: sp.lambdify(args, getattr(c, k), "numpy") for k in ("z", "h", "hp", "alpha", "kappa")}


def _ode_interval(scene, geo, iv):
    """The interval integrated with solve_ivp: t, q, qdot, F_N, P_mu, Ek, Ep, E (docs/physics.md)."""
    cp = tuple(scene.param_values)
    s = 1 if iv.q1 > iv.q0 else -1  # sign of v; N > 0 checked below, so the branch is s
    g, m, mu = scene.g, scene.m, scene.mu

    def rhs(t, y):
        q, qd = y
        h, hp, a, k = geo["h"](q, *cp), geo["hp"](q, *cp), geo["alpha"](q, *cp), geo["kappa"](q, *cp)
        return [qd, -(hp + s * mu * k * h**2) * qd**2 / h - g * (math.sin(a) + s * mu * math.cos(a)) / h]

    t = np.linspace(iv.t0, iv.t1, ODE_POINTS)
    sol = scipy_integrate.solve_ivp(rhs, (iv.t0, iv.t1), [iv.q0, iv.qdot0], t_eval=t, rtol=RTOL, atol=ATOL,
                                    method="DOP853")
    q, qd = sol.y
    h, a, k = (np.broadcast_to(geo[n](q, *cp), q.shape) for n in ("h", "alpha", "kappa"))
    v2 = h**2 * qd**2
    F_N = m * (k * v2 + g * np.cos(a))
    assert np.all(F_N > 0)
    Ek, Ep = m * v2 / 2, m * g * np.broadcast_to(geo["z"](q, *cp), q.shape)
    return {"t": t, "q": q, "qdot": qd, "F_N": F_N, "P_mu": -mu * np.abs(F_N) * h * np.abs(qd), "Ek": Ek,
            "Ep": Ep, "E": Ek + Ep}


@pytest.fixture(scope="module")
def ode(runs):
    out = {}
    for name, r in runs.items():
        geo = _geometry(r.scene.shape.name)
        out[name] = [(iv, _ode_interval(r.scene, geo, iv)) for iv in conc.intervals(r)]
    return out


def test_every_quote_is_verbatim_in_the_seed():
    assert len(conc.CLAIM_KEYS) >= 10
    for c in conc.CLAIM_KEYS:
        assert SEED.count(c.quote) >= 1, c.key


def test_every_claim_has_a_verdict_and_numbers(claims):
    assert list(claims) == [c.key for c in conc.CLAIM_KEYS]
    for c in claims.values():
        assert c.verdict in ("true", "false", "partly") and any(ch.isdigit() for ch in c.numbers), c.key


def test_intervals_follow_the_events(runs, ode):
    for name, r in runs.items():
        ivs = [iv for iv, _ in ode[name]]
        assert [iv.end for iv in ivs] == [e.kind.value for e in r.events]
        assert ivs[-1].t1 == r.events[-1].t and ivs[0].t0 == 0.0
        for iv, d in ode[name]:
            # The integration lands on the next event's position, and its energy on the event's energy.
            assert d["q"][-1] == pytest.approx(iv.q1, abs=1e-7)
            assert d["E"][-1] == pytest.approx(r.events[iv.index].energy, rel=1e-7, abs=1e-9)
            # Energy balance along the interval: E(t0) - E(t1) is the friction work.
            work = -float(np.sum((d["P_mu"][1:] + d["P_mu"][:-1]) / 2 * np.diff(d["t"])))
            assert d["E"][0] - d["E"][-1] == pytest.approx(work, rel=1e-4, abs=1e-9)


def test_normal_force_ranges(claims, ode):
    got = claims["normal-force"].data["ranges"]
    for name, parts in ode.items():
        lo = min(d["F_N"].min() for _, d in parts)
        hi = max(d["F_N"].max() for _, d in parts)
        assert got[name] == pytest.approx((lo, hi), rel=MATCH)
        assert hi - lo > 0.1 * hi  # it changes its value: the claim is false
    assert claims["normal-force"].verdict == "false"


def test_elastic_impacts_keep_the_speed(runs, claims):
    impacts = [e for r in runs.values() for e in r.events if e.kind.value == "impact"]
    assert len(impacts) == claims["elastic-impact"].data["impacts"] > 0
    assert all(abs(e.qdot_after) == pytest.approx(abs(e.qdot_before), rel=1e-12) for e in impacts)
    assert claims["elastic-impact"].verdict == "true"


def test_speed_is_zero_at_reversals(ode, claims):
    for parts in ode.values():
        for iv, d in parts:
            if iv.end in ("reversal", "arrest"):
                assert abs(d["qdot"][-1]) < 1e-4 * np.abs(d["qdot"]).max()
    assert claims["reversal-speed"].verdict == "true"


def test_normal_force_is_a_local_minimum_at_reversals(ode, claims):
    count = 0
    for parts in ode.values():
        for (a, da), (_, db) in zip(parts, parts[1:]):
            if a.end != "reversal":
                continue
            count += 1
            near = ODE_POINTS // 10
            assert da["F_N"][-1] < min(da["F_N"][-near:-1].min(), db["F_N"][1:near].min())
            assert np.sign(da["qdot"][ODE_POINTS // 2]) == -np.sign(db["qdot"][ODE_POINTS // 2])
    assert count == len(claims["reversal-minimum"].data["margins"])
    assert claims["reversal-minimum"].verdict == "true" and claims["friction-direction"].verdict == "true"


def test_friction_power_is_never_positive(ode, claims):
    top = max(d["P_mu"].max() for parts in ode.values() for _, d in parts)
    assert top <= 0 and claims["power-sign"].verdict == "true"
    low = min(d["P_mu"].min() for parts in ode.values() for _, d in parts)
    assert claims["power-sign"].data["low"] == pytest.approx(low, rel=MATCH)


@pytest.mark.parametrize("key, quantity", [("power-maximum", "P_mu"), ("kinetic-maximum", "Ek")])
def test_maxima_per_interval(ode, claims, key, quantity):
    claim = claims[key]
    falls = True
    for name, parts in ode.items():
        maxima = [float(np.abs(d[quantity]).max()) for _, d in parts]
        assert claim.data["maxima"][name] == pytest.approx(maxima, rel=MATCH)
        falls &= all(b < a for a, b in zip(maxima, maxima[1:]))
    assert claim.verdict == ("true" if falls else "partly" if claim.data["rises"] else "false")


def test_impacts_leave_the_potential_energy(ode, claims):
    for parts in ode.values():
        for (a, da), (_, db) in zip(parts, parts[1:]):
            if a.end == "impact":
                assert da["Ep"][-1] == pytest.approx(db["Ep"][0], rel=1e-9)
    assert claims["potential-impact"].verdict == "true"


def test_total_energy_decreases(runs, ode, claims):
    for name, parts in ode.items():
        energies = [runs[name].energy_budget.initial] + [e.energy for e in runs[name].events]
        assert all(b < a for a, b in zip(energies, energies[1:]))
        for _, d in parts:
            assert np.all(np.diff(d["E"]) <= 1e-12 * energies[0])
    assert claims["total-energy"].verdict == "true"


def test_several_impacts_condition(runs, claims):
    rows = claims["several-impacts"].data["rows"]
    for name, row in rows.items():
        scene = runs[name].scene
        g, (R,), delta = scene.g, scene.param_values, scene.right
        lo = math.sqrt(2 * g / R * (1 - math.cos(delta)))
        hi = math.sqrt(4 * g / R - 2 * g / R * (1 - math.cos(delta)))
        assert row["bounds"] == pytest.approx((lo, hi), rel=1e-14)
        assert scene.q0 < delta and lo < scene.qdot0 < hi  # both paper scenes satisfy the condition ...
    # ... yet the first has a single impact: the condition is not sufficient.
    assert sum(e.kind.value == "impact" for e in runs["paper-circle-3.8"].events) == 1
    assert rows["paper-circle-3.8"]["scan"][7.0] < 2 and not rows["paper-circle-3.8"]["sufficient"]
    sufficient = all(r["sufficient"] for r in rows.values())
    necessary = all(r["necessary"] for r in rows.values())
    assert claims["several-impacts"].verdict == ("true" if sufficient and necessary else
                                                 "partly" if sufficient or necessary else "false")


def test_lower_friction_more_impacts(runs, claims):
    def count(name, kind):
        return sum(e.kind.value == kind for e in runs[name].events)

    low, high = runs["paper-circle-7"].scene, runs["paper-circle-3.8"].scene
    assert low.mu < high.mu and low.qdot0 > high.qdot0
    more = count("paper-circle-7", "impact") > count("paper-circle-3.8", "impact") and \
        count("paper-circle-7", "reversal") > count("paper-circle-3.8", "reversal")
    assert claims["lower-friction"].verdict == ("true" if more else "false")
