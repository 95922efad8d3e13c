"""Engine functions compiled without reference counting never hand an array to their caller.

numba's ``_nrt=False`` (:data:`symvib.numeric.engine.bind.NO_REFCOUNT`) drops the
reference counts of the arrays a function receives: safe while the caller owns them
for the whole call, a use after free if the function returned an array (its new owner
would release a reference it never got).  The engine is compiled afresh in a child
process (an empty numba cache: a cached entry point would not compile its callees).
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
    import json, os, sys, tempfile
    os.environ["NUMBA_CACHE_DIR"] = tempfile.mkdtemp()
    os.environ["SYMVIB_CACHE"] = tempfile.mkdtemp()
    from numba.core import types
    from symvib.numeric.engine.bind import NO_REFCOUNT, bind
    from symvib.numeric.kernels import load
    from symvib.numeric.scene import scene_from_dict
    from symvib import simulate
    scene = scene_from_dict({"curve": {"shape": "parabola"}, "parameters": {"p": 1.0},
                             "physics": {"mu": 0.05, "restitution": 0.8},
                             "limiters": {"left": -0.5, "right": 0.7},
                             "initial": {"q": 0.0, "qdot": 6.0}, "run": {"t_max": 0.4}})
    simulate(scene, backend="numba")
    engine = load(scene.shape)._symvib_specialized_engine

    def arrays(t):
        if isinstance(t, types.Array):
            return [str(t)]
        return [a for x in getattr(t, "types", ()) for a in arrays(x)]

    out = {}
    for name in NO_REFCOUNT:
        nrt = engine[name].targetoptions.get("_nrt", True)
        out[name] = [{"nrt": nrt, "returns": arrays(cres.signature.return_type)}
                     for cres in engine[name].overloads.values()]
    print(json.dumps(out))
""")


def test_functions_without_reference_counts_return_no_array():
    done = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    compiled = json.loads(done.stdout.strip().splitlines()[-1])
    # quad and panel run on every interval: they must have been compiled, hence checked.
    assert compiled["quad"] and compiled["panel"]
    for name, overloads in compiled.items():
        for cres in overloads:
            assert cres["nrt"] is False, f"{name} was compiled with reference counting"
            assert cres["returns"] == [], f"{name} returns an array: {cres['returns']}"
