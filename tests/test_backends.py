"""The compiled (numba) core gives the events of the plain-Python core."""
from pathlib import Path

import numpy as np
import pytest

from symvib.numeric.backends import backend_available
from symvib.numeric.driver import simulate
from symvib.numeric.scene import load_scene, scene_from_dict

SCENES = Path(__file__).resolve().parents[1] / "symvib" / "scenes"

pytestmark = [pytest.mark.slow,
              pytest.mark.skipif(not backend_available("numba"), reason="numba is not installed")]


def scenes():
    out = [load_scene(SCENES / f"{n}.toml").replace(k=k) for n in ("paper-parabola", "paper-cycloid",
                                                                 "paper-circle-3.8", "paper-circle-7")
           for k in (1.0, 0.8)]
    base = {"curve": {"shape": "parabola"}, "parameters": {"p": 1.0},
            "physics": {"alpha0": 0.05, "restitution": 0.8}, "initial": {"q": -0.6, "qdot": 0.0}}
    out.append(scene_from_dict({**base, "limiters": {"right": -0.3}}))  # Zeno
    out.append(scene_from_dict({"curve": {"shape": "circle"}, "parameters": {"R": 0.5},
                                "physics": {"alpha0": 0.02, "restitution": 1.0},
                                "initial": {"q": 0.0, "qdot": 11.0}}))  # loops, N changes sign
    return out


@pytest.mark.parametrize("scene", scenes(), ids=lambda s: f"{s.name}-k{s.k}")
def test_numba_matches_python(scene):
    a = simulate(scene, backend="python")
    b = simulate(scene, backend="numba")
    assert a.status is b.status
    assert [e.kind for e in a.events] == [e.kind for e in b.events]
    for x, y in zip(a.events, b.events):
        assert x.t == pytest.approx(y.t, abs=1e-13) and x.q == pytest.approx(y.q, abs=1e-13)
    assert a.energy_budget.friction_work == pytest.approx(b.energy_budget.friction_work, rel=1e-12)
    assert len(a.samples.t) == len(b.samples.t)


def test_unknown_backend():
    with pytest.raises(ValueError, match="unknown backend"):
        backend_available("cuda")


@pytest.mark.slow  # compiles the shared engine (about 40 s)
def test_the_shared_engine_gives_the_events_of_the_specialized_one():
    # bind(..., shared=True): the engine compiled once per number of parameters, the kernels
    # as first-class functions; the same floating-point operations, so the same events.
    from symvib.numeric import driver
    from symvib.numeric.engine import bind
    from symvib.numeric.kernels import load
    from symvib.numeric.scene import resolve_scene

    for name in ("paper-parabola", "paper-circle-7"):
        scene = resolve_scene(name)
        mod = load(scene.shape)
        row, cp, R = driver.scene_row(scene), tuple(scene.param_values), driver.rules(driver.NODES)
        a = bind(mod, "numba").simulate(cp, row, R, False)
        b = bind(mod, "numba", shared=True).simulate(cp, row, R, False)
        assert a.status == b.status and a.n_events == b.n_events > 0
        assert a.events[:a.n_events].tobytes() == b.events[:b.n_events].tobytes()


def test_the_first_numba_run_leaves_its_marker_and_auto_then_takes_it(tmp_path, monkeypatch):
    from symvib.numeric import backends
    from symvib.numeric.engine.bind import is_compiled
    from symvib.numeric.kernels import load

    monkeypatch.setenv("SYMVIB_CACHE", str(tmp_path))
    monkeypatch.delenv("SYMVIB_BACKEND", raising=False)
    monkeypatch.setattr(backends, "_BOUND", {})  # engines bound under another cache folder
    scene = load_scene(SCENES / "paper-circle-7.toml")
    assert simulate(scene, samples=False).stats["backend"] == "python"
    assert not is_compiled(load(scene.shape))
    first = simulate(scene, samples=False, backend="numba")
    assert is_compiled(load(scene.shape))
    again = simulate(scene, samples=False)
    assert again.stats["backend"] == "numba" and again.events == first.events
    # The samples have a compiled entry of their own: until it is on disk, an "auto" run's
    # samples come from the plain engine, from the compiled run's interval log.
    mod = load(scene.shape)
    auto, plain = simulate(scene), simulate(scene, backend="python")
    assert auto.stats["backend"] == "numba"
    assert np.allclose(auto.samples.t, plain.samples.t, rtol=0, atol=1e-12)
    assert not is_compiled(mod, "sample_bound")
    compiled = simulate(scene, backend="numba")
    assert np.allclose(compiled.samples.qdot, plain.samples.qdot, rtol=1e-12, atol=1e-12)
    assert is_compiled(mod, "sample_bound")


def test_the_threaded_sweep_runs_every_scene_once_in_blocks_and_raises_a_block_s_error(monkeypatch):
    # threaded_sweep: threads take guided blocks (a quarter of what is left per thread, at
    # least SWEEP_GRAIN scenes) until none is left; an error in a thread reaches the caller.
    import threading

    import numba

    from symvib.numeric.driver import NODES, rules
    from symvib.numeric.engine.bind import SWEEP_GRAIN, threaded_sweep
    from symvib.numeric.layout import Summary

    calls, threads_seen, rules_seen = [], set(), {}

    def block(rows, cp_rows, R, max_log, out, logs, start, stop):
        calls.append((start, stop))
        threads_seen.add(threading.get_ident())
        rules_seen.setdefault(threading.get_ident(), set()).add(id(R.Xw))
        out[start:stop, Summary.events] += rows[start:stop, 0]

    n = 1000
    rows = np.arange(n, dtype=float).reshape(n, 1)
    threads = numba.get_num_threads()
    numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
    try:
        R = rules(NODES)
        out, logs = threaded_sweep(block)(rows, rows, R, 3)
    finally:
        numba.set_num_threads(threads)
    assert np.array_equal(out[:, Summary.events], rows[:, 0])  # each scene once
    assert logs.shape == (n, 3, logs.shape[2])
    spans = sorted(calls)
    assert spans[0][0] == 0 and spans[-1][1] == n
    assert all(a[1] == b[0] for a, b in zip(spans, spans[1:]))
    assert all(stop - start >= SWEEP_GRAIN for start, stop in spans[:-1])
    assert max(stop - start for start, stop in spans) < n  # more than one block
    assert len(threads_seen) >= 1
    # Each thread one copy of the rules of its own (reference counts are not shared between cores).
    assert all(len(ids) == 1 for ids in rules_seen.values())
    mine = [next(iter(ids)) for ids in rules_seen.values()]
    assert len(set(mine)) == len(mine) and (len(mine) == 1 or id(R.Xw) not in mine)

    def failing(rows, cp_rows, R, max_log, out, logs, start, stop):
        raise ZeroDivisionError("in a block")

    with pytest.raises(ZeroDivisionError, match="in a block"):
        threaded_sweep(failing)(rows, rows, R, 0)


def test_a_numeric_F_sigma_kernel_is_cached_on_disk_like_the_others(tmp_path, monkeypatch):
    """numba caches a compiled function only when it holds no function passed as a value; a
    numeric ``F_sigma`` calls ``F_sigma'`` by name, so its compiled kernels (and the engine that
    inlines them) are found on disk by the next process, as a closed form's are."""
    pytest.importorskip("numba")
    import warnings
    from pathlib import Path

    import numba
    from numba.core.errors import NumbaWarning

    from symvib.numeric.engine.bind import compiled_kernels
    from symvib.prepare import load_kernels

    monkeypatch.setenv("SYMVIB_CACHE", str(tmp_path))
    mod = load_kernels({"name": "bowl-numeric", "kind": "graph", "q": "x", "z": "R - sqrt(R**2 - x**2)",
                        "domain": ["-R", "R"], "params": {"R": "positive"}, "closed_form": "never"})
    assert set(mod.F_ROUTES.values()) == {"numeric"}
    with warnings.catch_warnings():
        warnings.simplefilter("error", NumbaWarning)   # "Cannot cache ... dynamic globals" fails here
        kernels = compiled_kernels(mod, len(mod.PARAMS))
    assert kernels[0](0.1, 0.05, 0.5) == mod.F_p_scalar(0.1, 0.05, 0.5)   # the same arithmetic
    stem = Path(mod.__file__).stem
    saved = {p.name.split("-")[0] for p in Path(numba.config.CACHE_DIR).rglob(f"{stem}.F_*_scalar-*.nbi")}
    assert saved == {f"{stem}.F_p_scalar", f"{stem}.F_m_scalar"}
