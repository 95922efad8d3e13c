"""The time quadrature of one interval (symvib.numeric.engine.timing.quad) against a 30-digit integral.

On the circle (``x = R sin q``, ``z = R (1 - cos q)``, ``alpha = q``, ``h = R``) the phase
trajectory of eq. 2 is ``G(q) = G(qa) - 2 g Integral_qa^q exp(2 s mu u) R (sin u + s mu cos u) du``
and the time ``Integral h exp(s mu q) / sqrt(G) dq`` (physics.md, "Time"): written here from those
formulas with mpmath, not from the kernels.  A turning point is where the engine stops on the
last double before the root, with ``G`` there of rounding size: the half anchored there must start
on the root with the weighted rule (one panel, not a cascade of halvings towards it) and still
give the time to the tolerance.
"""
from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest

from symvib.numeric.driver import rules, scene_row
from symvib.numeric.engine.bind import kernel_functions
from symvib.numeric.engine.plain import plain_functions, plain_rules
from symvib.numeric.engine.state import Kernels
from symvib.numeric.engine.timing import NONE, PANEL_COLUMNS, PANELS, QUAD_OK, WORK_ROWS, PanelColumn
from symvib.numeric.kernels import load
from symvib.numeric.scene import scene_from_dict

R, G_ACC, MU, QA = 0.5, 9.81, 0.1, 0.3


def circle_G(Ga, q):
    """``G(q)`` on branch ``s = +1`` from ``G(QA) = Ga`` (mpmath, 30 digits)."""
    mu = mpmath.mpf(MU)
    return Ga - 2 * G_ACC * mpmath.quad(lambda u: mpmath.exp(2 * mu * u) * R * (mpmath.sin(u) + mu * mpmath.cos(u)),
                                        [QA, q])


def turning_point(Ga):
    """The turning point ``q*`` (``G(q*) = 0``) and the last double before it with ``G`` there."""
    mpmath.mp.dps = 30
    q_star = mpmath.findroot(lambda q: circle_G(Ga, q), 1.2)
    qb = float(q_star)
    while circle_G(Ga, qb) < 0:
        qb = math.nextafter(qb, -math.inf)
    return q_star, qb, circle_G(Ga, qb)


def reference_time(Ga, qb):
    mu = mpmath.mpf(MU)
    return mpmath.quad(lambda q: R * mpmath.exp(mu * q) / mpmath.sqrt(circle_G(Ga, q)), [QA, (QA + qb) / 2, qb])


@pytest.fixture(scope="module")
def engine():
    scene = scene_from_dict({"curve": {"shape": "circle"}, "parameters": {"R": R},
                             "physics": {"g": G_ACC, "mu": MU, "restitution": 0.8},
                             "initial": {"q": QA, "qdot": 1.0}})
    fns = plain_functions()
    K = Kernels(*kernel_functions(load("circle")))
    cp = (R,)
    S = fns["setup_of"](scene_row(scene), K, cp)
    R_ = plain_rules(rules(16))
    return fns, K, cp, S, R_


def quad(engine, Ga, qb, Gb, mode=NONE):
    fns, K, cp, S, R_ = engine
    step = fns["CRIT_STEP"] * S.scale
    region, roots, count = fns["map_new"](QA, S.lo, S.hi, S.mu, K, cp, step)
    fns["map_extend"](region, roots, count, qb, S.mu, K, cp, step)
    n = max(len(R_.Xw), len(R_.Xp))
    out = np.zeros((2 * fns["MAX_PANELS"] + 2, PANEL_COLUMNS))
    res = fns["quad"](QA, qb, Ga, Gb, 1, 1, S, K, cp, R_, fns["scratch"](1, WORK_ROWS * n)[0], mode, out, 0,
                      roots, count)
    return res, out[:res[4]] if mode == PANELS else None


@pytest.mark.parametrize("Ga", [1.0, 3.0])
def test_a_turning_point_stopped_on_the_double_before_it_is_timed_from_one_weighted_panel(engine, Ga):
    q_star, qb, Gb = turning_point(Ga)
    assert 0 < Gb < 1e-13  # G of rounding size where the engine stops
    (T, _, err, flag, *_), _ = quad(engine, Ga, qb, float(Gb))
    assert flag == QUAD_OK
    want = reference_time(Ga, qb)
    assert abs(T - float(want)) <= 1e-13 * float(want)
    assert err <= 1e-11 * T
    # The half anchored at the turning point: one panel, on the root (r from 0), weighted.
    (_, _, _, _, rows, *_), panels = quad(engine, Ga, qb, float(Gb), PANELS)
    half = panels[panels[:, PanelColumn.half] == 1]
    assert len(half) == 1
    assert half[0, PanelColumn.r1] == 0.0 and half[0, PanelColumn.root] == 1.0
    # ... whose time starts on the root: the stretch from the root to the anchor comes first (<0).
    assert -1e-6 < half[0, PanelColumn.tau1] < 0.0


def test_the_time_to_a_turning_point_does_not_depend_on_the_double_it_is_stopped_at(engine):
    """Stopped on the root's double with G = 0, or one double before it with G of rounding size:
    the two times differ by the time over that ulp only (tail_time's linear model)."""
    Ga = 2.0
    q_star, qb, Gb = turning_point(Ga)
    T_before = quad(engine, Ga, qb, float(Gb))[0][0]
    T_on = quad(engine, Ga, qb, 0.0)[0][0]
    slope = 2 * G_ACC * math.exp(2 * MU * qb) * R * (math.sin(qb) + MU * math.cos(qb))
    ulp_time = 2 * R * math.exp(MU * qb) * math.sqrt(float(Gb)) / slope
    assert abs((T_on - T_before) - ulp_time) <= 1e-13 * T_on
