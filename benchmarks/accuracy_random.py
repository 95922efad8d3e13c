"""symvib's engine on seeded random scenes against the independent reference (symvib.checks.accuracy).

Run from the project folder (needs SciPy)::

    python benchmarks/accuracy_random.py [--fresh] [--seed S] [--n N] [--curves circle,parabola,...]
                                         [--csv verdicts.csv] [--worst 5] [--workers 2]

By default it takes the scenes of ``tests/test_accuracy_random.py`` and their
references as stored in ``symvib/checks/data/accuracy_reference.json``
(:func:`symvib.checks.accuracy.stored_references`: seed 20261125, 200 scenes;
``--curves`` keeps those on the curves named) and only runs
``symvib.simulate(scene)`` with its defaults on each: a few seconds.  ``--fresh``
draws ``--n`` scenes of ``--seed`` instead
(:func:`symvib.checks.accuracy.random_scenes`: generic, near-stop, near-edge,
looping and rescaled scenes on the curves of :data:`~symvib.checks.accuracy.TRACKS`)
and computes their references: the near-stop scenes bisect their start speed
against the reference, and the ill-conditioned ones take the 30-digit reference,
so expect a few seconds per scene (about ten minutes for 200 on two cores).
Another seed or count needs ``--fresh``.  ``symvib bench accuracy-reference
--write --out symvib/checks/data`` regenerates the stored file.

It prints the verdicts per category, the distribution of the largest event-time
difference per scene, and the worst silent misses as scene dicts (JSON, ready for
``symvib.simulate``) with both event lists.  ``--csv`` writes one row per scene.
"""
from __future__ import annotations

import argparse
import csv
import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from symvib.checks.accuracy import (  # noqa: E402
    TRACKS,
    check_scenes,
    random_scenes,
    stale,
    stored_references,
)

#: Seed and number of scenes of ``--fresh`` by default.
FRESH_SEED, FRESH_SCENES = 0, 200


def _scenes(args):
    """``(scenes, references, time scales, what)``: the stored ones, or fresh ones (references None)."""
    curves = [c.strip() for c in args.curves.split(",") if c.strip()] or None
    if args.fresh:
        seed = FRESH_SEED if args.seed is None else args.seed
        n = FRESH_SCENES if args.n is None else args.n
        return random_scenes(seed, n, curves, workers=args.workers), None, None, f"seed {seed}, fresh references"
    stored = stored_references()
    seed, n = stored.header["seed"], stored.header["count"]
    if (args.seed, args.n) != (None, None) and (args.seed, args.n) != (seed, n):
        raise SystemExit(f"accuracy_random: the stored references are of seed {seed}, {n} scenes; "
                         f"another seed or count needs --fresh (it computes the references: minutes)")
    for why in stale(stored):
        print(f"warning: the stored references are stale ({why}); regenerate them: "
              f"{stored.header['regenerate']}", file=sys.stderr)
    keep = [i for i, s in enumerate(stored.scenes) if curves is None or s.curve in curves]
    pick = lambda xs: [xs[i] for i in keep]  # noqa: E731
    return pick(stored.scenes), pick(stored.references), pick(stored.time_scales), f"seed {seed}, stored references"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fresh", action="store_true",
                    help="draw the scenes and compute their references (default: the stored ones)")
    ap.add_argument("--seed", type=int, default=None, help=f"seed (--fresh; default {FRESH_SEED})")
    ap.add_argument("--n", type=int, default=None, help=f"scenes (--fresh; default {FRESH_SCENES})")
    ap.add_argument("--curves", default="", help=f"comma-separated, of: {', '.join(TRACKS)} "
                    "(default: every curve not tagged numeric)")
    ap.add_argument("--csv", default="", help="write one row per scene here")
    ap.add_argument("--worst", type=int, default=5, help="silent misses to print in full")
    ap.add_argument("--workers", type=int, default=1, help="processes checking scenes")
    ap.add_argument("--quiet", action="store_true", help="no line per scene")
    args = ap.parse_args(argv)
    start = time.perf_counter()
    scenes, references, time_scales, what = _scenes(args)
    drawn = time.perf_counter() - start

    def progress(r):
        if not args.quiet:
            print(f"{r.scene.index:>4} {r.scene.category:<10} {r.scene.curve:<18} {r.verdict.verdict:<16} "
                  f"{r.verdict.max_dt:10.3g} {r.reference_method:<6} {r.seconds:6.1f} s", flush=True)

    report = check_scenes(scenes, progress=progress, workers=args.workers, references=references,
                          time_scales=time_scales)
    print(f"\nsymvib.simulate against the reference: {what}, {len(scenes)} scenes on "
          f"{len({s.curve for s in scenes})} curves (drawn or read in {drawn:.0f} s, checked in "
          f"{time.perf_counter() - start - drawn:.0f} s wall)\n")
    print(report.table())
    misses = report.counts()["silent_miss"]
    if misses:
        print(f"\nworst silent misses ({min(args.worst, misses)} of {misses}):")
        print(report.describe("silent_miss", args.worst))
    if args.csv:
        with open(args.csv, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["index", "category", "curve", "verdict", "max_dt", "first", "engine_status",
                        "reference_status", "reference_method", "seconds", "note", "detail", "scene"])
            for r in report.records:
                w.writerow([r.scene.index, r.scene.category, r.scene.curve, r.verdict.verdict, r.verdict.max_dt,
                            r.verdict.first, r.engine_status, r.reference_status, r.reference_method,
                            round(r.seconds, 2), r.scene.note,
                            r.verdict.detail, json.dumps(r.scene.scene)])
    return 0


if __name__ == "__main__":
    sys.exit(main())
