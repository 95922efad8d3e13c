"""Exact sensitivities on seeded random scenes against a step study of central differences.

Run from the project folder::

    python benchmarks/sensitivity_random.py [--seed 1] [--n 40] [--categories generic,scale,near-edge,near-stop]

The scenes are :func:`symvib.checks.randomscenes.random_scenes`' (user curves and catalogue shapes,
random friction, restitution, limiters and starts; rescaled ones from 1e-6 m to 1e3 m; near-edge
and near-stop starts), run to their ``t_max`` or event bound.  For each, ``result.sensitivities``
of the event times and positions with respect to ``mu``, ``k``, ``qdot0``, ``q0`` and the limiters
(those the scene has) is compared, event by event up to the last event every perturbed run still
shares, with central differences of the engine's own runs (at ``rtol = 1e-14``) and their Richardson extrapolations over
steps from 1e-3 to 1e-9 of the parameter's scale, a factor 4 apart (``tests/test_sensitivity.py``
does the same from 1e-3 to 1.6e-5): a derivative agrees when one of the estimates is within
``--tol`` (1e-7) of it, relative to its size or to its column's largest
entry where it is about 0.

Verdicts per scene: ``agree`` (every compared derivative), ``said`` (some events have no
derivative and the table says why, the others agree), ``no study`` (every perturbed run changed
the events, nothing to compare), ``run <status>`` (the run itself failed, for example
``tolerance_not_met`` at a near-stop, and says so: no derivatives), ``DISAGREE`` (a derivative given
as a number that no estimate matches: a silent error).  The worst disagreements are printed as scene dicts.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from symvib import simulate  # noqa: E402
from symvib.checks.randomscenes import random_scenes  # noqa: E402
from symvib.numeric.prepared import prepared_of  # noqa: E402
from symvib.numeric.scene import scene_from_dict  # noqa: E402

#: Agreement asked of a derivative (relative); the step study's first step (of a scale), its steps
#: and their ratio: from 1e-3 to 1e-9 of the scale, for next to a near-stop the differences reach the
#: derivative only at steps of 1e-7 or less (``t`` grows like ``1/sqrt(w_min)``).
TOL, FIRST_STEP, STEPS, STEP_RATIO = 1e-7, 1e-3, 11, 4.0
#: Tolerance of the perturbed runs (the engine's tightest): their rounding over the smallest steps.
FD_RTOL = 1e-14
#: Events compared at most per scene (the first ones: later events of a long run move chaotically).
MAX_COMPARED = 12


def _observed(scene, n):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = simulate(scene, samples=False, rtol=FD_RTOL)
    kinds = [e.kind.value for e in r.events[:n]]
    return kinds, np.array([e.t for e in r.events[:n]]), np.array([e.q for e in r.events[:n]])


def _study(scene, name, kinds, n, scale):
    """Richardson-extrapolated central differences of the first ``n`` event times and positions in ``name``."""
    x = getattr(scene, name)
    steps = [FIRST_STEP * scale / STEP_RATIO ** j for j in range(STEPS)]

    def central(d):
        try:
            plus, minus = _observed(scene.replace(**{name: x + d}), n), _observed(scene.replace(**{name: x - d}), n)
        except Exception:          # a perturbed start outside the limiters, k above 1: no estimate there
            return None
        if plus[0] != kinds or minus[0] != kinds:
            return None
        return (plus[1] - minus[1]) / (2 * d), (plus[2] - minus[2]) / (2 * d)

    D = [central(d) for d in steps]
    r2 = STEP_RATIO ** 2        # (Richardson: the h^2 term of two steps STEP_RATIO apart)
    return [tuple((r2 * f - c) / (r2 - 1) for c, f in zip(a, b)) for a, b in zip(D, D[1:])
            if a is not None and b is not None] + [d for d in D if d is not None]


def check(scene, tol=TOL):
    """``(verdict, compared, worst)`` for one scene (:mod:`module docstring <sensitivity_random>`)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = simulate(scene, samples=False)
    wrt = [p for p in ("mu", "k", "qdot0", "q0", "left", "right") if not (
        p in ("left", "right") and getattr(scene, p) is None) and not (p == "k" and scene.k in (0.0, 1.0))
        and not (p == "qdot0" and scene.qdot0 == 0.0) and not (p == "mu" and scene.mu == 0.0)]
    if res.status.is_error:      # (its events have no derivatives, and the status says why)
        return f"run {res.status.value}", 0, 0.0
    if not res.events or not wrt:
        return "no study", 0, 0.0
    sens = res.sensitivities(wrt=wrt)
    n = min(len(res.events), MAX_COMPARED)
    kinds = [e.kind.value for e in res.events[:n]]
    said = any(sens.reasons[:n])
    L = float(prepared_of(scene).kernels.q_scale_scalar(*scene.param_values))     # (the curve's length in q)
    compared, worst, studied = 0, 0.0, False
    for j, name in enumerate(wrt):
        scale = {"mu": max(scene.mu, 0.01), "k": 0.1, "qdot0": max(abs(scene.qdot0), 0.1)}.get(name, L)
        study = _study(scene, name, kinds, n, scale)
        if not study:
            continue
        studied = True
        for which, exact in enumerate((sens.t[:n, j], sens.q[:n, j])):
            finite = np.isfinite(exact)
            if not finite.any():
                continue
            floor = max(1e-4 * np.max(np.abs(exact[finite])), 1e-5 * L)
            for i in np.flatnonzero(finite):
                err = min(abs(est[which][i] - exact[i]) for est in study)
                rel = err / max(abs(exact[i]), floor)
                worst = max(worst, rel)
                compared += 1
    if not studied:
        return "no study", 0, 0.0
    if worst > tol:
        return "DISAGREE", compared, worst
    return ("said" if said else "agree"), compared, worst


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--n", type=int, default=40)
    ap.add_argument("--categories", default="generic,scale,near-edge,near-stop")
    ap.add_argument("--tol", type=float, default=TOL)
    ap.add_argument("--worst", type=int, default=3)
    args = ap.parse_args(argv)
    categories = tuple(c.strip() for c in args.categories.split(",") if c.strip())
    drawn = random_scenes(args.seed, args.n, categories=categories)
    start = time.perf_counter()
    verdicts, bad = {}, []
    for r in drawn:
        scene = scene_from_dict(r.scene)
        try:
            verdict, compared, worst = check(scene, args.tol)
        except Exception as err:      # reported, not hidden: a scene the check itself cannot run
            verdict, compared, worst = f"error: {type(err).__name__}", 0, math.nan
        verdicts.setdefault((r.category, verdict), 0)
        verdicts[(r.category, verdict)] += 1
        if verdict == "DISAGREE":
            bad.append((worst, r))
        print(f"{r.index:4d} {r.category:10s} {r.curve:18s} {verdict:9s} {compared:4d} derivatives, worst {worst:.1e}",
              flush=True)
    print(f"# seed {args.seed}, {len(drawn)} scenes, {time.perf_counter() - start:.0f} s")
    for (category, verdict), count in sorted(verdicts.items()):
        print(f"{category:10s} {verdict:12s} {count}")
    for worst, r in sorted(bad, key=lambda b: -b[0])[:args.worst]:
        print(f"# worst {worst:.1e}: {json.dumps(r.scene)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
