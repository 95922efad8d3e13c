"""Run one benchmark at two git revisions, alternately, and report their ratio from the same run.

Usage, from the project folder (the benchmark script is taken from each revision)::

    python benchmarks/compare_revisions.py BASE [HEAD] --bench benchmarks/bench_sweep.py \\
        --args "--qdot 100 --mu 100 --sample 2 --repeat 3" \\
        --metric "numba, all threads: +([0-9,.]+) scenes/s" --rounds 3

``BASE`` (and ``HEAD``, default: the working tree) are checked out into
temporary git worktrees; each round runs the benchmark once per revision, in a
fresh process that imports that revision's ``symvib`` (an editable install of
the current checkout is bypassed; ``--bench-from head`` runs HEAD's script at both,
for a benchmark BASE does not have).  Each ``--metric`` (a regular expression
whose first group is a number) is read from every run; the report gives the
values per round, and the ratio HEAD / BASE of their medians.  Machines are
noisy: alternate rounds, never compare numbers from different runs.
"""
from __future__ import annotations

import argparse
import re
import shlex
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: Runs a script with the symvib of one folder first on the path, whatever is installed.
BOOTSTRAP = """
import runpy, sys
sys.meta_path[:] = [f for f in sys.meta_path if "editable" not in repr(f).lower()]
sys.path.insert(0, {folder!r})
import symvib
assert symvib.__file__.startswith({folder!r}), symvib.__file__
sys.argv = [{script!r}] + {args!r}
runpy.run_path({script!r}, run_name="__main__")
"""


def checkout(revision: str, where: Path) -> Path:
    """A worktree of ``revision`` in ``where`` (its generated/ made importable as symvib.generated)."""
    subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", "-q", str(where), revision], check=True)
    link = where / "symvib" / "generated"
    if not link.exists():
        link.symlink_to(where / "generated")
    return where


def run(folder: Path, bench: str, args: list, script_folder: Path | None = None) -> str:
    """The output of one benchmark run at ``folder`` (the script from ``script_folder``, default ``folder``)."""
    code = BOOTSTRAP.format(folder=str(folder), script=str((script_folder or folder) / bench), args=args)
    out = subprocess.run([sys.executable, "-W", "ignore", "-c", code], capture_output=True, text=True, cwd=folder)
    if out.returncode != 0:
        raise SystemExit(f"{folder}: the benchmark failed:\n{out.stderr[-3000:]}")
    return out.stdout


def number(pattern: str, text: str) -> float:
    match = re.search(pattern, text)
    if match is None:
        raise SystemExit(f"metric {pattern!r} not found in the output:\n{text[-2000:]}")
    return float(match.group(1).replace(",", ""))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("base")
    ap.add_argument("head", nargs="?", default=None, help="a revision (default: the working tree)")
    ap.add_argument("--bench", required=True, help="the benchmark script, relative to the project folder")
    ap.add_argument("--args", default="", help="its arguments, one string")
    ap.add_argument("--metric", action="append", required=True, help="regex; group 1 is the number")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--bench-from", choices=("each", "head"), default="each",
                    help="take the script from each revision (default) or HEAD's for both (a new benchmark)")
    opts = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        folders = {"base": checkout(opts.base, Path(tmp) / "base")}
        folders["head"] = checkout(opts.head, Path(tmp) / "head") if opts.head else ROOT
        try:
            values = {(side, m): [] for side in folders for m in opts.metric}
            for r in range(opts.rounds):
                for side, folder in folders.items():
                    text = run(folder, opts.bench, shlex.split(opts.args),
                               folders["head"] if opts.bench_from == "head" else None)
                    for m in opts.metric:
                        values[side, m].append(number(m, text))
                    print(f"round {r + 1} {side}: " + "; ".join(f"{values[side, m][-1]:g}" for m in opts.metric),
                          flush=True)
            for m in opts.metric:
                b, h = statistics.median(values["base", m]), statistics.median(values["head", m])
                print(f"{m!r}: base {b:g}, head {h:g}, head/base {h / b:.3f}")
        finally:
            for folder in folders.values():
                if folder != ROOT:
                    subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(folder)],
                                   check=False)
    return 0


if __name__ == "__main__":
    sys.exit(main())
