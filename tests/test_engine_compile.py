"""How the compiled engine is compiled: inner functions emit no machine code of their own, and the
arguments of :data:`symvib.numeric.engine.bind.NOT_LITERAL` get one specialization.

Both only make the compile cheaper (docs/benchmarks.md, "The engine's compile"); that the compiled
engine's events are the plain one's is ``tests/test_backends.py``'s.  The engine is compiled afresh
in a child process (an empty numba cache: a cached entry point would not compile its callees).
"""
import json
import subprocess
import sys
import textwrap

import pytest

from symvib.numeric.backends import backend_available

pytestmark = [pytest.mark.slow,
              pytest.mark.skipif(not backend_available("numba"), reason="numba is not installed")]

PROBE = textwrap.dedent("""
    import json, os, tempfile
    os.environ["NUMBA_CACHE_DIR"] = tempfile.mkdtemp()
    os.environ["SYMVIB_CACHE"] = tempfile.mkdtemp()
    from numba.core import types
    from symvib import simulate
    from symvib.numeric.engine import lazylink
    from symvib.numeric.engine.bind import BOUND_ENTRIES, NOT_LITERAL
    from symvib.numeric.kernels import load
    from symvib.numeric.scene import scene_from_dict
    scene = scene_from_dict({"curve": {"shape": "parabola"}, "parameters": {"p": 1.0},
                             "physics": {"mu": 0.05, "restitution": 0.8},
                             "limiters": {"left": -0.5, "right": 0.7},
                             "initial": {"q": 0.0, "qdot": 6.0}, "run": {"t_max": 0.4}})
    result = simulate(scene, backend="numba")
    engine = load(scene.shape)._symvib_specialized_engine

    def linked_only(dispatcher):
        return [bool(getattr(cres.library, lazylink.LIBRARY_MARK, False)) for cres in dispatcher.overloads.values()]

    print(json.dumps({
        "installed": lazylink.installed(),
        "events": len(result.events),
        "entries": {name: linked_only(engine[name]) for name in BOUND_ENTRIES if engine[name].overloads},
        "inner": {name: linked_only(engine[name]) for name in ("run_on", "quad", "panel", "locate")},
        "specializations": {name: [[str(a) for a in sig] for sig in engine[name].overloads]
                            for name in NOT_LITERAL if engine[name].overloads},
    }))
""")


@pytest.fixture(scope="module")
def probe():
    done = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def _tested_numba() -> bool:
    import numba

    from symvib.numeric.engine import lazylink

    return lazylink._release(numba.__version__) in lazylink.TESTED_NUMBA


def test_the_patches_stay_out_of_an_untested_numba(monkeypatch):
    import numba

    from symvib.numeric.engine import lazylink

    monkeypatch.setattr(numba, "__version__", "99.1.0")
    assert lazylink._install() is False
    assert lazylink._release("0.68.1") == (0, 68) and lazylink._release("dev") == ()


def test_inner_functions_are_linked_only_and_entries_compiled(probe):
    if not _tested_numba():
        pytest.skip("lazylink is not installed on a numba release it was not tested with")
    assert probe["installed"], "lazylink did not install on this numba"
    assert probe["events"] > 0
    assert probe["entries"] == {"simulate_bound": [False]}
    for name, marks in probe["inner"].items():
        assert marks and all(marks), f"{name}'s library was compiled to machine code"


def test_arguments_not_literal_give_one_specialization(probe):
    assert probe["specializations"]["panel"], "panel was not compiled"
    for name, sigs in probe["specializations"].items():
        assert len(sigs) == 1, f"{name} has {len(sigs)} specializations: {sigs}"
