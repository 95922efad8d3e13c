"""The scan of critical points: a full array stops the scan and is grown by its owner, nothing is lost.

The scan (:mod:`symvib.numeric.engine.scan`) never allocates: where a row of the special
points is full it stops and says so (``room``), and the run grows the array
(``grown_roots``) and scans on.  Over many loops of the circle the recorded critical points
of ``F_s' = z' + s mu x'`` must be exactly the closed-form ones, ``q = -s atan(mu) + k pi``.
"""
import math

import numpy as np
import pytest

from symvib.numeric.engine.bind import kernel_functions
from symvib.numeric.engine.plain import plain_functions
from symvib.numeric.engine.scan import ROOTS_CAPACITY
from symvib.numeric.engine.state import Kernels
from symvib.numeric.kernels import load

R = 0.5
MU = 0.07


@pytest.fixture(scope="module")
def scan():
    fns = plain_functions()
    K = Kernels(*kernel_functions(load("circle")))
    return fns, K, (R,)


def scanned(fns, K, cp, target, step):
    region, roots, count = fns["map_new"](0.0, -math.inf, math.inf, MU, K, cp, step)
    grown = 0
    fns["map_extend"](region, roots, count, target, MU, K, cp, step)
    while not fns["room"](roots, count):
        roots = fns["grown_roots"](roots, count)
        grown += 1
        fns["map_extend"](region, roots, count, target, MU, K, cp, step)
    return region, roots, count, grown


@pytest.mark.parametrize("loops", [1, 6, 40])
def test_every_critical_point_of_many_loops_is_recorded_once(scan, loops):
    fns, K, cp = scan
    target = 2.0 * math.pi * loops
    region, roots, count, grown = scanned(fns, K, cp, target, fns["CRIT_STEP"])
    assert region[1] >= target  # the scan reached its target (x_hi)
    for row, s in ((0, 1.0), (1, -1.0)):
        want = [-s * math.atan(MU) + k * math.pi for k in range(-1, 2 * loops + 2)]
        want = [x for x in want if 0.0 < x <= region[1]]
        got = np.sort(roots[row, :count[row]])
        assert len(got) == len(want)
        assert np.allclose(got, want, rtol=0.0, atol=1e-12)
    if 2 * loops > ROOTS_CAPACITY:
        assert grown >= 1  # the growth path ran


def test_a_full_row_stops_the_scan_where_it_was(scan):
    fns, K, cp = scan
    step = fns["CRIT_STEP"]
    region, roots, count = fns["map_new"](0.0, -math.inf, math.inf, MU, K, cp, step)
    fns["map_extend"](region, roots, count, 2.0 * math.pi * 40, MU, K, cp, step)
    assert not fns["room"](roots, count)
    assert count[0] == ROOTS_CAPACITY or count[1] == ROOTS_CAPACITY
    # Stopped at the step that filled the row: no critical point beyond the scanned edge is missing.
    last = max(roots[0, count[0] - 1], roots[1, count[1] - 1])
    assert last <= region[1] < last + 2.0 * math.pi / 4
    grown = fns["grown_roots"](roots, count)
    assert grown.shape[1] == 2 * roots.shape[1]
    for row in range(roots.shape[0]):
        assert np.array_equal(grown[row, :count[row]], roots[row, :count[row]])


def test_the_turn_of_a_scan_step_is_never_below_the_angle_and_exact_beyond_45_degrees():
    """The scan's steps are sized by the angle between the tangents at their ends: its tangent where
    it is small (cheaper than atan2; a little more, so a step comes out shorter, never longer)."""
    from symvib.numeric.engine.scan import turn_angle

    rng = np.random.default_rng(3)
    for _ in range(20000):
        theta = rng.uniform(-math.pi, math.pi) * 10 ** rng.uniform(-6, 0)
        size = 10 ** rng.uniform(-8, 8)
        cross, dot = size * math.sin(theta), size * math.cos(theta)
        angle = abs(math.atan2(cross, dot))
        got = turn_angle(cross, dot)
        assert angle * (1 - 1e-15) <= got <= angle * 4 / math.pi * (1 + 1e-15) + 1e-300
        if angle > math.pi / 4 * (1 + 1e-12):
            assert got == angle
        if angle < 1 / 16:
            assert got <= angle * (1 + angle * angle / 3 * 1.01 + 1e-14)  # (and rounding)
    assert turn_angle(0.0, 0.0) == 0.0 and turn_angle(1.0, 0.0) == math.pi / 2
    assert math.isnan(turn_angle(math.nan, 1.0))
