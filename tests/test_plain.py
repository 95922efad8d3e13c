"""The plain-Python engine's primitives (symvib/numeric/engine/plain.py) against the engine's loop versions."""
from pathlib import Path

import numpy as np
import pytest

from symvib.numeric import driver
from symvib.numeric.engine import loop, plain, scan, timing
from symvib.numeric.engine.bind import bind, kernel_functions
from symvib.numeric.engine.state import Kernels
from symvib.numeric.kernels import load
from symvib.numeric.layout import Summary
from symvib.numeric.scene import load_scene

SCENES = Path(__file__).resolve().parents[1] / "symvib" / "scenes"


@pytest.mark.parametrize("nodes", [16, 5])
def test_cumulate_is_the_loop_versions_sum_to_rounding(nodes):
    R = driver.rules(nodes)
    rng = np.random.default_rng(7)
    for St in (R.Sw, R.SWw, R.Sp):
        n = St.shape[0]
        # Rows of one flat scratch array: the integrand at offset 2, the sums at offset n + 5.
        v = rng.normal(size=2 * n + 8) * 10.0 ** rng.integers(-5, 5, size=2 * n + 8)
        want = timing.cumulate(St, v.copy(), 2, n, v.copy(), n + 5)
        got = plain.cumulate(St, v.tolist(), 2, n, v.tolist(), n + 5)
        assert isinstance(got, list) and len(got) == len(v) and all(type(x) is float for x in got)
        # Only the n sums are written, the rest of the row is left as it was.
        assert got[:n + 5] == v[:n + 5].tolist() and got[2 * n + 5:] == v[2 * n + 5:].tolist()
        assert np.array_equal(want[:n + 5], v[:n + 5]) and np.array_equal(want[2 * n + 5:], v[2 * n + 5:])
        bound = np.abs(St[:n, :n]).T @ np.abs(v[2:n + 2])  # the sum's rounding scales with it
        exact = St[:n, :n].T @ v[2:n + 2]
        assert np.all(np.abs(want[n + 5:2 * n + 5] - exact) <= 8 * np.finfo(float).eps * bound)
        assert np.all(np.abs(np.array(got[n + 5:2 * n + 5]) - want[n + 5:2 * n + 5]) <= 8 * np.finfo(float).eps * bound)


def test_scratch_rows_have_the_loop_versions_shape_and_are_independent():
    rows = plain.scratch(3, 5)
    assert [len(r) for r in rows] == list(scan.scratch(3, 5).shape[1:]) * 3
    rows[0][1] = 2.5
    assert rows[1][1] == 0.0 and rows[2][1] == 0.0


def test_grown_copies_what_the_loop_version_copies():
    a = np.arange(12.0).reshape(4, 3)
    assert np.array_equal(plain.grown(a, 3, 6), timing.grown(a, 3, 6))


def test_plain_rules_hold_the_same_numbers():
    R = driver.rules(driver.NODES)
    P = plain.plain_rules(R)
    for a, b in zip(R, P):
        assert np.array_equal(a, np.asarray(b))
    assert isinstance(P.Xw, list) and isinstance(P.Wp, list)


def _engines(name, k=1.0):
    scene = load_scene(SCENES / f"{name}.toml").replace(k=k)
    mod = load(scene.shape)
    return scene, mod, Kernels(*kernel_functions(mod)), tuple(scene.param_values), driver.scene_row(scene)


@pytest.mark.parametrize("name,k", [("paper-parabola", 1.0), ("paper-circle-7", 0.8), ("paper-cycloid", 1.0)])
def test_plain_engine_gives_the_events_of_the_loop_engine(name, k):
    # The engine's own functions run as plain Python with NumPy arrays (the loop versions)
    # against the plain engine (the primitives): the cumulative sums differ in order only.
    scene, mod, K, cp, row = _engines(name, k)
    R = driver.rules(driver.NODES)
    a = loop.simulate_scene(K, cp, row, R, True)
    b = bind(mod, "python").simulate(cp, row, R, True)
    assert a.status == b.status and a.n_events == b.n_events > 0 and a.n_intervals == b.n_intervals
    np.testing.assert_allclose(b.events[:b.n_events], a.events[:a.n_events], rtol=1e-13, atol=1e-13)
    assert b.W_friction == pytest.approx(a.W_friction, rel=1e-13)
    sa, ia = loop.sample_scene(K, cp, row, R, a.intervals, a.n_intervals, 2)
    sb, ib = bind(mod, "python").samples(cp, row, R, b.intervals, b.n_intervals, 2)
    assert np.array_equal(ia, ib)
    np.testing.assert_allclose(sb, sa, rtol=1e-12, atol=1e-13)


def test_plain_engine_sweeps_as_it_simulates():
    scene, mod, K, cp, row = _engines("paper-parabola")
    R = driver.rules(driver.NODES)
    eng = bind(mod, "python")
    one = eng.simulate(cp, row, R, False)
    summary, logs = eng.sweep(row[None, :], np.array([cp]), R, 4)
    assert summary[0, Summary.events] == one.n_events and summary[0, Summary.t_final] == one.t
    assert np.array_equal(logs[0], one.events[:4])
