"""The cost of a numeric ``F_sigma``: runs on the catalogue's numeric-route curves, plain and compiled.

A curve whose ``F_sigma`` has no closed form (catenary, ellipse, quartic; a user curve with
``closed_form = "never"``) integrates ``F_s'`` at every evaluation of ``F_sigma``
(:mod:`symvib.antiderivative`).  This times ``symvib.simulate`` of one scene per curve (the
event snapshot's catalogue scene: ``mu`` 0.05, ``k`` 0.8, limiters at -0.5 and 0.5, start 0.1 at
3 units of ``q`` per second; and the corpus's Gaussian well, ``b = 0.3``, ``q_scale`` 1) on the
plain engine and on numba (compiled before it is timed), and one call of ``F_+``'s scalar kernel
in plain Python.  Compare two revisions in one session::

    python benchmarks/compare_revisions.py BASE --bench benchmarks/bench_numeric_F.py --bench-from head \\
        --metric "catenary python: ([0-9.]+) ms" --metric "catenary numba: ([0-9.]+) ms" ...
"""
from __future__ import annotations

import argparse
import statistics
import time
import warnings


def scenes() -> dict:
    from symvib.checks.corpus import entry
    from symvib.shapes import CATALOGUE

    out = {}
    for name in ("catenary", "ellipse", "quartic"):
        out[name] = {"curve": {"shape": name}, "parameters": dict(CATALOGUE[name].defaults),
                     "physics": {"g": 9.81, "m": 0.2, "mu": 0.05, "restitution": 0.8},
                     "limiters": {"left": -0.5, "right": 0.5}, "initial": {"q": 0.1, "qdot": 3.0},
                     "run": {"max_events": 300}}
    gauss = entry("gaussian-well").scene()
    gauss["curve"]["closed_form"] = "never"
    out["gaussian-well"] = gauss
    return out


def timed(fn, repeat: int) -> float:
    """Median wall time of ``fn()`` in ms over ``repeat`` calls."""
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return 1e3 * statistics.median(times)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5, help="timed runs of the plain engine (numba: 4 times as many)")
    opts = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    import symvib
    from symvib.numeric.prepared import prepared_of
    from symvib.numeric.scene import scene_from_dict

    for name, scene in scenes().items():
        first = symvib.simulate(scene, backend="python", samples=False)     # (a user curve: prepared here)
        ms = timed(lambda s=scene: symvib.simulate(s, backend="python", samples=False), opts.repeat)
        print(f"{name} python: {ms:.3f} ms ({len(first.events)} events, {first.status.value})", flush=True)
        try:
            compiled = symvib.simulate(scene, backend="numba", samples=False)
        except Exception as exc:  # noqa: BLE001 - numba missing or failing: said, the rest still runs
            print(f"{name} numba: failed ({type(exc).__name__})")
        else:
            same = [e.kind for e in compiled.events] == [e.kind for e in first.events]
            ms = timed(lambda s=scene: symvib.simulate(s, backend="numba", samples=False), 4 * opts.repeat)
            print(f"{name} numba: {ms:.3f} ms ({'the same' if same else 'other'} events)", flush=True)
        resolved = scene_from_dict(scene)
        k = prepared_of(resolved).kernels
        cp = tuple(resolved.param_values)
        qs = (-0.45, -0.2, 0.05, 0.3, 0.48)
        us = timed(lambda: [k.F_p_scalar(q, 0.05, *cp) for q in qs], 20 * opts.repeat) * 1e3 / len(qs)
        print(f"{name} F_p_scalar: {us:.2f} us per call (plain Python)", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
