"""First calls as a new user meets them: empty caches, fresh processes, wall time.

Run from the project folder, in the environment to measure (the main install
``pip install .``, numba included)::

    python benchmarks/bench_first_call.py [--sweep-scenes 200000] [--plain-scenes 2000] [--repeat N]

Every measurement runs the ``symvib`` command in a new process with its own
empty kernel cache (``$SYMVIB_CACHE``) and numba cache (``$NUMBA_CACHE_DIR``),
start-up included, and reports the wall time beside issue 15's target:

* ``symvib run`` of each paper scene (target <= 2 s each);
* the README's ``bowl`` curve, first run: derivation, generation and the run
  (target <= 10 s), and its first sweep (derivation, generation, compilation and
  20,000 scenes);
* the first run of the four curves of the corpus whose ``F_sigma`` the symbolic routes
  find late or never (``sine-track``, ``tilted-parabola``, ``tan-wall``, ``pole-well``),
  with each ``curve.closed_form`` of ``--closed-form`` (default ``auto``; issue 28's target
  <= 10 s each), its standard error on a pseudo-terminal so that the progress line shows,
  and when that line came (target <= 1 s); ``--repeat N`` runs each N times (each on empty
  caches) and prints every wall time and the median;
* the first sweep of ``--sweep-scenes`` scenes of the paper parabola, compilation
  included (target <= 15 s for 200,000);
* the main install's sweep speed (numba is a dependency): the same sweep again in a
  later process, which loads the compiled engine from disk (target >= 10,000 scenes/s);
* the plain-Python engine's sweep speed on ``--plain-scenes`` scenes (where numba is
  missing);
* ``--startup N``: the start-up of ``symvib sweep`` (issue 28's target < 0.7 s): a sweep of 4
  paper-parabola scenes in a fresh process whose caches hold the compiled engine, N times,
  alternated with two floors measured in the same run: a process that only imports NumPy,
  and one that loads a single cached numba function (numba's own import, target set-up,
  cache load and teardown); wall and CPU (user + system) medians;
* ``--prepared``: a user curve with a pole inside its domain (``x**2 + 1/(x - 0.3)``),
  its first run (derivation, singular points), the same run again in a new process with
  the caches of the first (issue 25's target <= 0.5 s, no SymPy), and a run from a start
  on the other side of the pole (one generated module for both).
"""
from __future__ import annotations

import argparse
import math
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENES = ("paper-parabola", "paper-cycloid", "paper-circle-3.8", "paper-circle-7")
#: Corpus curves whose closed form SymPy finds late (the tangent-angle route) or never.
NEW_CURVES = ("sine-track", "tilted-parabola", "tan-wall", "pole-well")
#: The README's own curve ("Your own curve"), as a scene file.
BOWL = """
[curve]
name = "bowl"
z = "R - sqrt(R**2 - x**2)"
domain = ["-R", "R"]

[parameters]
R = 0.5

[physics]
alpha0 = 0.05
restitution = 0.8

[limiters]
left = -0.2
right = 0.35

[initial]
q = 0.1
qdot = 3.0
"""


def timed(args: list, backend: str | None = None, caches: Path | None = None, codes=(0,)) -> tuple:
    """Wall time of ``symvib ARGS`` in a fresh process with empty caches (or the ``caches``
    folder of an earlier call), and its output (an exit code outside ``codes`` stops the benchmark)."""
    with tempfile.TemporaryDirectory() as tmp:
        folder = caches or Path(tmp)
        env = dict(os.environ, SYMVIB_CACHE=str(folder / "kernels"), NUMBA_CACHE_DIR=str(folder / "numba"))
        env.pop("SYMVIB_BACKEND", None)
        if backend:
            env["SYMVIB_BACKEND"] = backend
        start = time.perf_counter()
        out = subprocess.run([sys.executable, "-m", "symvib.cli", *args], capture_output=True, text=True, env=env,
                             cwd=tmp)
        wall = time.perf_counter() - start
    if out.returncode not in codes:
        raise SystemExit(f"symvib {' '.join(args)} failed ({out.returncode}):\n{out.stderr[-2000:]}")
    return wall, out.stdout + out.stderr


def timed_on_terminal(args: list) -> tuple:
    """``(wall, progress)`` of ``symvib ARGS`` in a fresh process with empty caches, its standard
    error on a pseudo-terminal (where the command line shows its progress lines): ``progress`` is
    the time from the start to the first line on it (``None`` when none came)."""
    import pty

    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, SYMVIB_CACHE=str(Path(tmp) / "kernels"), NUMBA_CACHE_DIR=str(Path(tmp) / "numba"))
        env.pop("SYMVIB_BACKEND", None)
        leader, follower = pty.openpty()
        first, chunks = [], []

        def read():
            while True:
                try:
                    data = os.read(leader, 4096)
                except OSError:   # the child closed the terminal
                    return
                if not data:
                    return
                if b"\n" in data and not first:
                    first.append(time.perf_counter())
                chunks.append(data)

        start = time.perf_counter()
        proc = subprocess.Popen([sys.executable, "-m", "symvib.cli", *args], stdout=subprocess.PIPE,
                                stderr=follower, env=env, cwd=tmp)
        os.close(follower)
        reader = threading.Thread(target=read, daemon=True)
        reader.start()
        proc.communicate()
        wall = time.perf_counter() - start
        reader.join(5.0)
        os.close(leader)
    if proc.returncode != 0:
        raise SystemExit(f"symvib {' '.join(args)} failed ({proc.returncode}):\n"
                         f"{b''.join(chunks).decode(errors='replace')[-2000:]}")
    return wall, (first[0] - start if first else None)


def new_curve_runs(choices: str, repeat: int) -> None:
    """Issue 28: the first run of each new curve, ``repeat`` times on empty caches, with its progress line."""
    from symvib.checks.corpus import entry

    for choice in choices.split(","):
        for name in NEW_CURVES:
            with tempfile.TemporaryDirectory() as tmp:
                path = Path(tmp) / f"{name}.toml"
                path.write_text(toml_text(entry(name).scene()), encoding="utf-8")
                runs = [timed_on_terminal(["run", str(path), "--closed-form", choice]) for _ in range(repeat)]
            walls = [w for w, _ in runs]
            lines = [p for _, p in runs if p is not None]
            shown = f"{statistics.median(lines):.2f}s" if len(lines) == len(runs) else "missing"
            each = f" (runs: {', '.join(f'{w:.2f}' for w in walls)}; progress line: " \
                   f"{', '.join(f'{p:.2f}' for p in lines)})" if repeat > 1 else ""
            print(f"{f'symvib run {name} (closed_form {choice})':48s} {statistics.median(walls):8.2f}s   "
                  f"<= 10 s (issue 28); first progress line {shown} (<= 1 s){each}")


def toml_text(tables: dict) -> str:
    """A scene's tables (strings, numbers, lists of them) as TOML text."""
    def value(v):
        if isinstance(v, str):
            return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
        if isinstance(v, list):
            return "[" + ", ".join(value(x) for x in v) + "]"
        return repr(v)

    lines = [f"{k} = {value(v)}" for k, v in tables.items() if not isinstance(v, dict)]
    for name, table in tables.items():
        if isinstance(table, dict) and table:
            lines += ["", f"[{name}]", *(f"{k} = {value(v)}" for k, v in table.items())]
    return "\n".join(lines) + "\n"


def grid(n: int) -> tuple:
    """``--vary`` options for about ``n`` scenes of the paper parabola (phidot0 x mu)."""
    a = max(2, round(math.sqrt(n * 5 / 4)))
    b = max(2, round(n / a))
    return ("--vary", f"qdot=3:12:{a}", "--vary", f"mu=0.01:0.2:{b}"), a * b


#: A user curve with a pole inside its declared domain, as a scene file (the start is set per run).
POLE = """
[curve]
name = "pole"
z = "x**2 + 1/(x - 0.3)"
closed_form = "never"

[physics]
mu = 0.1
restitution = 0.5

[initial]
q = {q0}
qdot = 0.0
"""


def prepared_runs() -> None:
    """Issue 25: a user curve prepared once, then run by later processes without SymPy."""
    with tempfile.TemporaryDirectory() as tmp:
        caches = Path(tmp) / "caches"
        right, left = Path(tmp) / "right.toml", Path(tmp) / "left.toml"
        right.write_text(POLE.format(q0=0.5), encoding="utf-8")
        left.write_text(POLE.format(q0=0.1), encoding="utf-8")
        wall, _ = timed(["run", str(right)], caches=caches)
        print(f"{'symvib run pole (first: derive, singular points)':48s} {wall:8.2f}s")
        walls = sorted(timed(["run", str(right)], caches=caches)[0] for _ in range(5))
        print(f"{'symvib run pole again (new process, median of 5)':48s} {walls[2]:8.2f}s   <= 0.5 s (issue 25)")
        # (from the left the particle slides into the pole: status reached_singular_point, exit code 3)
        wall, _ = timed(["run", str(left)], caches=caches, codes=(0, 3))
        modules = sorted(p.name for p in (caches / "kernels").glob("*.py"))
        print(f"{'symvib run pole, other side of the pole':48s} {wall:8.2f}s   "
              f"{len(modules)} generated module(s) for both starts: {', '.join(modules)}")


#: The numba floor of ``--startup``: one cached numba function loaded and called.
NUMBA_FLOOR = """
import numba, numpy as np
@numba.njit(cache=True)
def f(x):
    return np.sin(x).sum()
f(np.ones(3))
"""


def startup(n: int) -> None:
    """Issue 28: the start-up of ``symvib sweep`` against the floors of NumPy and numba, alternated."""
    import resource
    import statistics

    def child_cpu():
        usage = resource.getrusage(resource.RUSAGE_CHILDREN)
        return usage.ru_utime + usage.ru_stime

    with tempfile.TemporaryDirectory() as tmp:
        caches = Path(tmp) / "caches"
        (Path(tmp) / "floor.py").write_text(NUMBA_FLOOR, encoding="utf-8")
        env = dict(os.environ, SYMVIB_CACHE=str(caches / "kernels"), NUMBA_CACHE_DIR=str(caches / "numba"))
        env.pop("SYMVIB_BACKEND", None)
        sweep = [sys.executable, "-m", "symvib.cli", "sweep", "paper-parabola", "--vary", "qdot=3:12:4", "--quiet",
                 "-o"]
        cases = {"symvib sweep, 4 scenes (engine on disk)": lambda i: sweep + [str(Path(tmp) / f"s{i}")],
                 "floor: python -c 'import numpy'": lambda i: [sys.executable, "-c", "import numpy"],
                 "floor: one cached numba function": lambda i: [sys.executable, str(Path(tmp) / "floor.py")]}
        for make in cases.values():   # warm: compile the engine and the floor function into the caches
            subprocess.run(make("warm"), env=env, cwd=tmp, capture_output=True, check=True)
        walls = {k: [] for k in cases}
        cpus = {k: [] for k in cases}
        for i in range(n):
            for name, make in cases.items():
                cpu, start = child_cpu(), time.perf_counter()
                subprocess.run(make(i), env=env, cwd=tmp, capture_output=True, check=True)
                walls[name].append(time.perf_counter() - start)
                cpus[name].append(child_cpu() - cpu)
    for name in cases:
        print(f"{name:48s} {statistics.median(walls[name]):8.2f}s   CPU {statistics.median(cpus[name]):.2f} s"
              + ("   < 0.7 s (issue 28)" if name.startswith("symvib") else ""))


def first_sweeps(scenes: int) -> None:
    """The first sweep of ``scenes`` paper-grid scenes on empty caches (the engine compiled, or loaded
    from the engines compiled at install time unless ``$SYMVIB_INSTALLED_ENGINES=off``), then the same
    sweep in a later process on the caches of the first."""
    vary, n = grid(scenes)
    with tempfile.TemporaryDirectory() as tmp:
        caches = Path(tmp) / "caches"
        wall, _ = timed(["sweep", "paper-parabola", *vary, "-o", str(Path(tmp) / "s"), "--quiet"], caches=caches)
        print(f"{f'first sweep, {n:,} scenes (compile included)':48s} {wall:8.2f}s   <= 10 s for 200,000 "
              f"(installed engines: {os.environ.get('SYMVIB_INSTALLED_ENGINES', 'on')})")
        wall, _ = timed(["sweep", "paper-parabola", *vary, "-o", str(Path(tmp) / "s2"), "--quiet"], caches=caches)
        print(f"{f'the main install sweep, {n:,} scenes':48s} {wall:8.2f}s   {n / wall:,.0f} scenes/s "
              "(a later process: start-up and loading the compiled engine included; target >= 10,000 scenes/s)")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sweep-scenes", type=int, default=200_000)
    ap.add_argument("--plain-scenes", type=int, default=2_000)
    ap.add_argument("--closed-form", default="auto", help="curve.closed_form of the new curves (or a comma list)")
    ap.add_argument("--only-new-curves", action="store_true", help="time the new curves' first runs only")
    ap.add_argument("--prepared", action="store_true", help="time a prepared user curve's runs only (issue 25)")
    ap.add_argument("--startup", type=int, metavar="N", help="time the start-up of symvib sweep only, N rounds")
    ap.add_argument("--repeat", type=int, default=1, help="runs of each new curve (each on empty caches)")
    ap.add_argument("--only-sweep", action="store_true",
                    help="time the first sweep of --sweep-scenes scenes and the same sweep in a later process only")
    args = ap.parse_args(argv)
    try:
        import numba  # noqa: F401

        fast = True
    except ImportError:
        fast = False
    print(f"# first calls, empty caches, fresh processes; numba installed: {fast}")
    print(f"{'what':48s} {'wall':>9s}   target")
    if args.prepared:
        prepared_runs()
        return 0
    if args.startup:
        startup(args.startup)
        return 0
    if args.repeat < 1:
        raise SystemExit("--repeat: must be at least 1")
    if args.only_sweep:
        first_sweeps(args.sweep_scenes)
        return 0
    new_curve_runs(args.closed_form, args.repeat)
    if args.only_new_curves:
        return 0
    for name in SCENES:
        wall, _ = timed(["run", str(ROOT / "symvib" / "scenes" / f"{name}.toml")])
        print(f"{'symvib run ' + name:48s} {wall:8.2f}s   <= 2 s")
    with tempfile.TemporaryDirectory() as tmp:
        bowl = Path(tmp) / "bowl.toml"
        bowl.write_text(BOWL, encoding="utf-8")
        wall, _ = timed(["run", str(bowl)])
        print(f"{'symvib run bowl.toml (derive, generate, run)':48s} {wall:8.2f}s   <= 10 s")
        wall, _ = timed(["sweep", str(bowl), "--vary", "qdot=1:4:200", "--vary", "restitution=0.5:0.9:100",
                         "-o", str(Path(tmp) / "bowl-sweep"), "--quiet"])
    print(f"{'first sweep of bowl.toml, 20,000 scenes':48s} {wall:8.2f}s   "
          "(derive, generate, compile, sweep; 35-43 s before the first scene before issue 15)")
    first_sweeps(args.sweep_scenes)
    vary, n = grid(args.plain_scenes)
    with tempfile.TemporaryDirectory() as tmp:
        wall, _ = timed(["sweep", "paper-parabola", *vary, "-o", str(Path(tmp) / "s"), "--quiet",
                         "--backend", "python"])
    print(f"{f'plain-Python sweep, {n:,} scenes':48s} {wall:8.2f}s   {n / wall:,.0f} scenes/s "
          "(start-up included; the engine where numba is missing)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
