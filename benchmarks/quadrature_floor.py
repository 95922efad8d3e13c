"""How far can the time quadrature's work per event fall at the engine's accuracy?  Two measurements.

Run from the project folder (numba for part 1)::

    python benchmarks/quadrature_floor.py [--scenes 3000] [--intervals 200] [--nodes 16] [--repeat 5]

Issue 28's sweep targets ask for the compiled loop about twice as fast at unchanged accuracy.
About half of a sweep's time is the time quadrature (``panel``, its ``sincos`` and ``quad``:
docs/benchmarks.md, "Where a sweep's event goes").  This script measures the two ways that work
could shrink:

1. **Smaller rules.** The benchmark's sweep (the paper parabola, ``--scenes`` scenes of the
   100 x 100 grid of ``phidot0`` x ``mu``, ``k = 0.8``, as ``sweep_duel.py``) on one thread with
   16, 12, 10 and 8 nodes per panel at the default tolerance: best thread time of
   ``--repeat``, and whether every scene's event count and final state agree with 16 nodes'.
2. **One panel per interval.** Each interval is now two halves, each anchored at its end,
   each at least one panel.  The plain engine runs ``--intervals`` random scenes of the
   same grid; for every interval between two limiters across the valley (``G`` rising
   inward at both ends, far from 0: most of the grid's intervals) the script integrates the
   time in one panel of ``--nodes`` Gauss-Legendre nodes over the whole interval, in the
   variable ``theta`` of ``q = c - R cos theta`` with ``c -+ R`` the two (virtual) roots of
   ``G`` beyond the ends, found by Newton's method on the closed form (the substitution
   that makes the time of a harmonic swing exact).  It compares that and the engine's time
   with a reference: the same integral in ``q`` by panels of 30 nodes graded geometrically towards
   both ends (down to ``2^-40`` of the interval), ``G`` from its
   closed form (no code of the engine's quadrature; intervals where that closed form misses the
   far end's ``G``, a near-stop's rounding, are left out); and counts the panels the engine took.

What it showed on this machine is in docs/benchmarks.md, "The time quadrature's floor".
"""
from __future__ import annotations

import argparse
import collections
import math
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from symvib.numeric import driver  # noqa: E402
from symvib.numeric.engine import plain  # noqa: E402
from symvib.numeric.scene import load_scene  # noqa: E402

#: The reference's composite rule in ``q``: panels graded geometrically (ratio 2) from the middle towards
#: both ends, down to ``2^-REF_LEVELS`` of the interval, of ``REF_NODES`` nodes each (a virtual root
#: beyond an end at a distance above the smallest panel is then at least a panel's width from each).
REF_LEVELS, REF_NODES = 40, 30
#: Newton steps for each virtual root of ``G``, at most (``--root-steps``).
ROOT_STEPS = 30
#: The engine's accuracy the one-panel rule must meet: relative error of an interval's time.
TARGET = 1e-13
#: The reference needs ``G``'s closed form, which rounds to ``eps |C|``: an interval whose far end it misses
#: by more than this (``G`` of rounding size, a near-stop) has no reference and is left out.
CLOSED_FORM_RTOL = 1e-12
#: An interval's ends count as "far from 0" where ``G`` exceeds this share of the larger end's.
FAR = 1e-9


def grid(scene, scenes: int):
    """The benchmark's rows and parameters (``sweep_duel.GRID``)."""
    rows = np.array([driver.scene_row(scene.replace(qdot0=float(a), mu=float(b), k=0.8))
                     for a in np.linspace(3, 12, 100) for b in np.linspace(0.01, 0.2, 100)])
    params = np.array([scene.param_values] * len(rows))
    pick = np.random.default_rng(0).permutation(len(rows))[:scenes]
    return rows[pick], params[pick]


def rules_part(scene, scenes: int, repeat: int) -> None:
    import numba

    numba.set_num_threads(1)
    fn = driver.sweep_function(scene, "numba")
    rows, params = grid(scene, scenes)
    results = {}
    print(f"1. The sweep's rules: {scenes} scenes, one thread, best thread time of {repeat}")
    for nodes in (16, 12, 10, 8):
        fn(rows[:10], params[:10], nodes, 0)
        best = math.inf
        for _ in range(repeat):
            start = time.thread_time()
            out, _ = fn(rows, params, nodes, 0)
            best = min(best, time.thread_time() - start)
        results[nodes] = (out, best)
    base, t16 = results[16]
    for nodes, (out, best) in results.items():
        same = bool(np.array_equal(out[:, :2], base[:, :2]))
        final = np.nanmax(np.abs(out[:, 5] - base[:, 5]) / np.abs(base[:, 5]))
        print(f"   {nodes:2d} nodes: {best:.4f} s ({best / t16:.2f} x 16 nodes'), {int(out[:, 1].sum())} events, "
              f"statuses and event counts as 16 nodes': {same}, final times within {final:.1e}")


def captured_intervals(scene, scenes: int):
    """Every interval's ``quad`` call of the plain engine on ``scenes`` random grid scenes, with its
    result and the panels it evaluated."""
    fns = plain.plain_functions()
    space = fns["quad"].__globals__
    quad, panel = space["quad"], space["panel"]
    seen, current = [], [0, 0]

    def counting_panel(*args):
        current[0] += 1
        current[1] += len(args[12])   # (the rule's nodes, Xr)
        return panel(*args)

    def capturing_quad(qa, qb, Ga, Gb, s, sigma, S, K, cp, *rest):
        current[:] = [0, 0]
        out = quad(qa, qb, Ga, Gb, s, sigma, S, K, cp, *rest)
        seen.append((qa, qb, Ga, Gb, s, S, K, cp, out[0], current[0], current[1]))
        return out

    space["panel"] = counting_panel
    fns["interval"].__globals__["quad"] = capturing_quad
    try:
        rng = np.random.default_rng(0)
        for a, b in rng.uniform([3.0, 0.01], [12.0, 0.2], size=(scenes, 2)):
            driver.simulate(scene.replace(qdot0=float(a), mu=float(b), k=0.8), backend="python", samples=False)
    finally:
        space["panel"] = panel
        fns["interval"].__globals__["quad"] = quad
    return seen, fns


def whole_interval_part(scene, scenes: int, nodes: int, root_steps: int) -> None:
    seen, fns = captured_intervals(scene, scenes)
    Fs, dFs = fns["Fs"], fns["dFs"]
    x, w = np.polynomial.legendre.leggauss(nodes)
    xr, wr = np.polynomial.legendre.leggauss(REF_NODES)
    errors = collections.defaultdict(list)
    panels = collections.Counter()
    for qa, qb, Ga, Gb, s, S, K, cp, T, taken, evaluated in seen:
        panels["all"] += taken
        panels["intervals"] += 1
        panels["nodes"] += evaluated
        top = max(Ga, Gb)
        if top <= 0.0 or min(Ga, Gb) < FAR * top:
            continue
        mu, g = S.mu, S.g
        lo, hi = min(qa, qb), max(qa, qb)
        G_lo, G_hi = (Ga, Gb) if qa < qb else (Gb, Ga)
        F_lo = Fs(s, lo, mu, K, cp)

        def G(q):
            return G_lo - 2.0 * g * (Fs(s, q, mu, K, cp) - F_lo)

        def dG(q):
            return -2.0 * g * dFs(s, q, mu, K, cp)

        if not (dG(lo) > 0.0 > dG(hi)):
            continue   # not across a valley
        if abs(G(hi) / G_hi - 1.0) > CLOSED_FORM_RTOL:
            errors["closed form off"].append(0.0)   # (G of rounding size: no reference here)
            continue
        roots, steps = [], 0
        for end, G_end in ((lo, G_lo), (hi, G_hi)):
            q = end - G_end / dG(end)
            for _ in range(root_steps):
                try:
                    step = G(q) / dG(q)
                except (ArithmeticError, ValueError):   # (no root: Newton ran off into a pole)
                    step = math.nan
                if not math.isfinite(step):
                    q = math.nan
                    break
                q -= step
                steps += 1
                if abs(step) <= 4e-16 * abs(q):
                    break
            roots.append(q)
        q1, q2 = roots
        if not (q1 < lo and hi < q2):
            errors["no two roots beyond the ends"].append(0.0)
            continue
        panels["valley"] += taken
        panels["root steps"] += steps
        panels["valley nodes"] += evaluated
        panels["valley intervals"] += 1

        def dt(q):
            node = K.node_p(q, mu, *cp) if s > 0 else K.node_m(q, mu, *cp)
            return node[1] * node[2] / math.sqrt(G(q))

        c, R = 0.5 * (q1 + q2), 0.5 * (q2 - q1)
        t1, t2 = math.acos((c - lo) / R), math.acos((c - hi) / R)
        theta = t1 + 0.5 * (t2 - t1) * (x + 1.0)
        one = 0.5 * (t2 - t1) * sum(wj * dt(c - R * math.cos(tj)) * R * math.sin(tj) for tj, wj in zip(theta, w))
        ref = 0.0
        graded = [lo + (hi - lo) * 0.5 ** k for k in range(REF_LEVELS, 0, -1)]
        edges = [lo, *graded, *[hi - (g_ - lo) for g_ in reversed(graded[:-1])], hi]   # (the middle once)
        for a, b in zip(edges[:-1], edges[1:]):
            ref += 0.5 * (b - a) * sum(wj * dt(a + 0.5 * (b - a) * (xj + 1.0)) for xj, wj in zip(xr, wr))
        errors["one panel"].append(abs(one / ref - 1.0))
        errors["engine"].append(abs(T / ref - 1.0))
    n_valley = panels["valley intervals"]
    print(f"2. One panel per interval: {panels['intervals']} intervals of {scenes} scenes; {n_valley} across a valley "
          f"({len(errors['no two roots beyond the ends'])} more without two roots beyond the ends, "
          f"{len(errors['closed form off'])} where G's closed form misses its end by over {CLOSED_FORM_RTOL:.0e})")
    print(f"   the engine's panels: {panels['all'] / panels['intervals']:.2f} an interval, "
          f"{panels['valley'] / max(n_valley, 1):.2f} an interval across a valley (floor: 2, one a half)")
    saved = panels["valley nodes"] - nodes * n_valley - 2 * panels["root steps"]
    print(f"   node evaluations: {panels['nodes'] / panels['intervals']:.1f} an interval, "
          f"{panels['valley nodes'] / max(n_valley, 1):.1f} an interval across a valley; one panel there instead "
          f"would take {nodes} and {2 * panels['root steps'] / max(n_valley, 1):.1f} calls of F_s and F_s' for the "
          f"two roots: {saved / panels['intervals']:+.1f} kernel calls an interval in all")
    for name in ("engine", "one panel"):
        e = np.array(errors[name])
        if len(e):
            p50, p90, p99 = np.percentile(e, [50, 90, 99])
            print(f"   {name:9s} against the reference: median {p50:.1e}, 90 % {p90:.1e}, 99 % {p99:.1e}, "
                  f"max {e.max():.1e}; within {TARGET:.0e}: {np.mean(e <= TARGET):.1%}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scenes", type=int, default=3000, help="sweep scenes of part 1 (0: skip it)")
    ap.add_argument("--intervals", type=int, default=200, help="plain-engine scenes of part 2 (0: skip it)")
    ap.add_argument("--nodes", type=int, default=16, help="nodes of part 2's one panel")
    ap.add_argument("--root-steps", type=int, default=ROOT_STEPS, help="Newton steps for each root, at most")
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    scene = load_scene(ROOT / "symvib" / "scenes" / "paper-parabola.toml")
    if args.scenes:
        rules_part(scene, args.scenes, args.repeat)
    if args.intervals:
        whole_interval_part(scene, args.intervals, args.nodes, args.root_steps)


if __name__ == "__main__":
    main()
