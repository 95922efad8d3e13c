"""symvib's engine on seeded random scenes against the independent reference (symvib.checks.accuracy).

Run from the project folder (needs SciPy)::

    python benchmarks/accuracy_random.py [--seed 0] [--n 200] [--curves circle,parabola,...]
                                         [--csv verdicts.csv] [--worst 5] [--workers 2]

It draws ``--n`` scenes (:func:`symvib.checks.accuracy.random_scenes`: generic,
near-stop, near-edge, looping and rescaled scenes on the curves of
:data:`~symvib.checks.accuracy.TRACKS`), runs ``symvib.simulate(scene)`` with its
defaults and the reference on each, and prints the verdicts per category, the
distribution of the largest event-time difference per scene, and the worst silent
misses as scene dicts (JSON, ready for ``symvib.simulate``) with both event lists.
``--csv`` writes one row per scene.  The near-stop scenes bisect their start speed
against the reference, and the ill-conditioned ones take the 30-digit reference:
expect a few seconds per scene.
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

from symvib.checks.accuracy import TRACKS, check_scenes, random_scenes  # noqa: E402

#: Digits of event times in the printed event lists.
DIGITS = 17


def _events(events) -> str:
    return "\n".join(f"      {e[0]:<19} t = {e[1]:.{DIGITS}g}  q = {e[2]:.{DIGITS}g}  qdot_before = {e[3]:.6g}"
                     for e in events) or "      (none)"


def _worst(report, verdict, n):
    lines = []
    for r in report.worst(verdict, n):
        v = r.verdict
        shown = r.reference_events[:len(r.engine_events) + 2]
        lines += [f"- scene {r.scene.index} ({r.scene.category}, {r.scene.curve}; {r.scene.note})",
                  f"  max |t - t_ref| = {v.max_dt:.3g} s; {v.detail}",
                  f"  scene = {json.dumps(r.scene.scene)}",
                  f"  engine ({r.engine_status}):", _events(r.engine_events),
                  f"  reference {r.reference_method} ({r.reference_status}):", _events(shown)]
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--curves", default="", help=f"comma-separated, of: {', '.join(TRACKS)} "
                    "(default: every curve not tagged numeric)")
    ap.add_argument("--csv", default="", help="write one row per scene here")
    ap.add_argument("--worst", type=int, default=5, help="silent misses to print in full")
    ap.add_argument("--workers", type=int, default=1, help="processes checking scenes")
    ap.add_argument("--quiet", action="store_true", help="no line per scene")
    args = ap.parse_args(argv)
    curves = [c.strip() for c in args.curves.split(",") if c.strip()] or None
    start = time.perf_counter()
    scenes = random_scenes(args.seed, args.n, curves, workers=args.workers)
    drawn = time.perf_counter() - start

    def progress(r):
        if not args.quiet:
            print(f"{r.scene.index:>4} {r.scene.category:<10} {r.scene.curve:<18} {r.verdict.verdict:<16} "
                  f"{r.verdict.max_dt:10.3g} {r.reference_method:<6} {r.seconds:6.1f} s", flush=True)

    report = check_scenes(scenes, progress=progress, workers=args.workers)
    print(f"\nsymvib.simulate against the reference: seed {args.seed}, {len(scenes)} scenes on "
          f"{len({s.curve for s in scenes})} curves (drawn in {drawn:.0f} s, checked in "
          f"{time.perf_counter() - start - drawn:.0f} s wall)\n")
    print(report.table())
    worst = _worst(report, "silent_miss", args.worst)
    if worst:
        print(f"\nworst silent misses ({min(args.worst, report.counts()['silent_miss'])} of "
              f"{report.counts()['silent_miss']}):")
        print("\n".join(worst))
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
