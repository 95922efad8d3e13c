"""Cost of the landing search of flights on a unilateral curve (docs/physics.md, "Flight and landing" 3).

Run from the project folder (another revision: its folder first on ``PYTHONPATH``)::

    python benchmarks/bench_landing.py [--repeat 3]

Three unilateral scenes: the paper's circle run fast (a lift-off, then bounces), a sine track that
lifts off again and again, and a Gaussian well whose flights start from a lift-off on its rim.  For
each: the run's status and flights, the signed distances the landing searches evaluated (a counter
around ``Stretch.nearest``), and the wall time of a run (best of ``--repeat``, the curve prepared
beforehand), with the time per flight.  A run that raises is reported with its exception.
"""
from __future__ import annotations

import argparse
import sys
import time
import warnings

SCENES = {
    "circle-bounces": {"curve": {"shape": "circle"}, "parameters": {"R": 1.0},
                       "physics": {"mu": 0.1, "restitution": 0.8, "contact": "unilateral",
                                   "restitution_curve": 0.3}, "initial": {"q": 0.0, "qdot": 7.0}},
    "sine-track": {"curve": {"z": "a*(1 - cos(x/b))", "name": "bench-landing-sine"},
                   "parameters": {"a": 0.1744, "b": 0.4605},
                   "physics": {"mu": 0.0, "restitution": 1.0, "contact": "unilateral"},
                   "initial": {"q": 0.0, "qdot": -5.4166}, "run": {"t_max": 6.0, "max_events": 200}},
    "gaussian-well": {"curve": {"z": "-a*exp(-x**2/b**2)", "name": "bench-landing-well"},
                      "parameters": {"a": 0.1449, "b": 0.1840},
                      "physics": {"mu": 0.2507, "restitution": 0.8, "contact": "unilateral",
                                  "restitution_curve": 0.3},
                      "initial": {"q": -0.2830, "qdot": 2.5785}, "run": {"t_max": 5.0, "max_events": 2000}},
}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    import symvib
    from symvib.numeric import flight
    from symvib.numeric.scene import scene_from_dict

    count = [0]
    nearest = flight.Stretch.nearest

    def counted(self, X, Z):
        count[0] += 1
        return nearest(self, X, Z)

    flight.Stretch.nearest = counted
    print(f"# landing search, symvib from {symvib.__file__}")
    print(f"{'scene':16s} {'status':18s} {'flights':>7s} {'distances':>10s} {'per flight':>10s} "
          f"{'run':>9s} {'per flight':>10s}")
    for name, data in SCENES.items():
        scene = scene_from_dict(data)
        try:
            symvib.simulate(scene, samples=False)            # (prepares a user curve outside the timing)
            best, result = float("inf"), None
            for _ in range(args.repeat):
                count[0] = 0
                t0 = time.perf_counter()
                result = symvib.simulate(scene, samples=False)
                best = min(best, time.perf_counter() - t0)
        except Exception as exc:   # noqa: BLE001 - an old revision may raise: report it
            print(f"{name:16s} raised {type(exc).__name__}: {exc} (after {count[0]} distances)")
            continue
        flights = max(int(result.stats.get("flights", 0)), 1)
        print(f"{name:16s} {result.status.value:18s} {flights:7d} {count[0]:10d} {count[0] / flights:10.0f} "
              f"{best * 1e3:7.1f} ms {best / flights * 1e3:7.2f} ms")
    return 0


if __name__ == "__main__":
    sys.exit(main())
