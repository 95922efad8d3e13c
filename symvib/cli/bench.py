"""The ``symvib bench`` command: its parser and :func:`bench_main` (the jobs are in :mod:`symvib.checks.bench`)."""
from __future__ import annotations

import argparse
import os
import sys

from symvib.cli.common import EXIT_BAD_INPUT

__all__ = ["BENCH_OUT", "build_bench_parser", "bench_main"]


class _BenchParser(argparse.ArgumentParser):
    """The parser of ``symvib bench``: its errors are one line (exit status 2), not a usage block."""

    def error(self, message):
        print(f"symvib bench: error: {message}", file=sys.stderr)
        raise SystemExit(EXIT_BAD_INPUT)


#: Default output folder of ``symvib bench`` (relative to the current directory).
BENCH_OUT = "symvib-bench"


def build_bench_parser() -> argparse.ArgumentParser:
    """The options of ``symvib bench`` (jobs in :mod:`symvib.checks.bench`)."""
    from symvib.checks.accuracy import ACCURACY_REFERENCE_NAME
    from symvib.checks.bench.paper_references import REFERENCE_NAME
    from symvib.checks.bench.scenes import RANDOM_SCENES
    from symvib.checks.bench.settings import PEER_BUDGET

    parser = _BenchParser(prog="symvib bench", description="work-precision charts and the stability suite")
    sub = parser.add_subparsers(dest="job", required=True)
    p = sub.add_parser("work-precision", help="error against CPU time on the paper scenes; wrong-sequence counts")
    p.add_argument("--out", default=BENCH_OUT, help=f"output folder (default: {BENCH_OUT})")
    p.add_argument("--quick", action="store_true", help="a small run (2 scenes, few settings, 20 random scenes)")
    p.add_argument("--random", type=int, default=None, help=f"random scenes (default {RANDOM_SCENES})")
    p.add_argument("--workers", type=int, default=1, help="processes for the random scenes (default 1)")
    p.add_argument("--budget", type=float, default=PEER_BUDGET, help="CPU seconds per peer run")
    p = sub.add_parser("stability", help="every method on every stability case, outcomes classified")
    p.add_argument("--out", default=BENCH_OUT, help=f"output folder (default: {BENCH_OUT})")
    p.add_argument("--quick", action="store_true", help="five of the cases")
    p.add_argument("--workers", type=int, default=1, help="processes (default 1)")
    p.add_argument("--budget", type=float, default=PEER_BUDGET, help="CPU seconds per peer run")
    p = sub.add_parser("reference", help="recompute the 30-digit time references of the paper scenes")
    p.add_argument("--write", action="store_true", help=f"store them in OUT/{REFERENCE_NAME}")
    p.add_argument("--out", default=BENCH_OUT,
                   help=f"folder of --write (default: {BENCH_OUT}; symvib/checks/data updates the shipped file)")
    p = sub.add_parser("accuracy-reference",
                       help="recompute the random scenes of the accuracy test and their references (minutes), "
                            "and compare them with the shipped ones")
    p.add_argument("--write", action="store_true", help=f"store them in OUT/{ACCURACY_REFERENCE_NAME}")
    p.add_argument("--out", default=BENCH_OUT,
                   help=f"folder of --write (default: {BENCH_OUT}; symvib/checks/data updates the shipped file)")
    p.add_argument("--workers", type=int, default=1, help="processes (default 1)")
    return parser


def bench_main(argv) -> int:
    """``symvib bench``: returns an exit status (2 for bad options)."""
    from pathlib import Path

    from symvib.checks.bench.paper_references import references
    from symvib.checks.bench.stability_job import stability
    from symvib.checks.bench.work_precision_job import work_precision
    from symvib.paths import check_output_dir

    try:
        args = build_bench_parser().parse_args(argv)
    except SystemExit as exc:
        return int(exc.code or 0)
    if getattr(args, "workers", 1) < 1 or getattr(args, "workers", 1) > os.cpu_count():
        print(f"symvib bench: error: --workers: must be between 1 and {os.cpu_count()}", file=sys.stderr)
        return EXIT_BAD_INPUT
    if getattr(args, "budget", 1.0) <= 0 or (getattr(args, "random", None) or 0) < 0:
        print("symvib bench: error: --budget and --random must be positive", file=sys.stderr)
        return EXIT_BAD_INPUT
    if args.job not in ("reference", "accuracy-reference") or args.write:
        check_output_dir(args.out, "--out folder")
    if args.job == "work-precision":
        work_precision(Path(args.out), quick=args.quick, n_random=args.random, workers=args.workers,
                       budget=args.budget)
    elif args.job == "stability":
        stability(Path(args.out), quick=args.quick, workers=args.workers, budget=args.budget)
    elif args.job == "accuracy-reference":
        from symvib.checks.accuracy import regenerate

        differs = regenerate(Path(args.out) if args.write else None, workers=args.workers)
        return 1 if differs and not args.write else 0
    else:
        references(Path(args.out) if args.write else None)
    return 0
