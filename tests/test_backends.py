"""The compiled (numba) core gives the events of the plain-Python core."""
from pathlib import Path

import pytest

from symvib.numeric.driver import backend_available, simulate
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
    from symvib.numeric import driver
    from symvib.numeric.engine.bind import is_compiled
    from symvib.numeric.kernels import load

    monkeypatch.setenv("SYMVIB_CACHE", str(tmp_path))
    monkeypatch.delenv("SYMVIB_BACKEND", raising=False)
    monkeypatch.setattr(driver, "_BOUND", {})  # engines bound under another cache folder
    scene = load_scene(SCENES / "paper-circle-7.toml")
    assert simulate(scene, samples=False).stats["backend"] == "python"
    assert not is_compiled(load(scene.shape))
    first = simulate(scene, samples=False, backend="numba")
    assert is_compiled(load(scene.shape))
    again = simulate(scene, samples=False)
    assert again.stats["backend"] == "numba" and again.events == first.events
