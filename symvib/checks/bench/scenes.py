"""The scenes the benchmarks run: the paper scenes, random scenes, and a scene's fingerprint.

:func:`paper_scenes` are the paper's scenes (:data:`symvib.shapes.PAPER_SCENES`)
at the restitutions :data:`RESTITUTIONS`, the scenes of the work-precision
diagram.  :func:`random_scenes` draws the parabola and circle scenes of the
wrong-sequence counts (:mod:`symvib.checks.bench.sequences`) from
:class:`random.Random`: the same seed gives the same scenes, whose truths ship in
``symvib/checks/data/random_truth.json``.  They are not the scenes of
:mod:`symvib.checks.randomscenes`, which the accuracy test draws on many curves in
categories of its own.  :func:`scene_key` fingerprints a scene for the reference
files (shipped and cached).

Examples
--------
>>> [label for label, _ in paper_scenes(quick=True)]
['paper-parabola k=0.8', 'paper-circle-3.8 k=1']
>>> a, b = random_scenes(3), random_scenes(3)
>>> [scene_key(s) for s in a] == [scene_key(s) for s in b], a[0].max_events == RANDOM_MAX_EVENTS
(True, True)
"""
from __future__ import annotations

import hashlib
import json
import random
from importlib.resources import files

from symvib.shapes import PAPER_SCENES

__all__ = ["RESTITUTIONS", "RANDOM_SCENES", "QUICK_RANDOM", "RANDOM_MAX_EVENTS", "RANDOM_SEED", "KEY_DIGITS",
           "paper_scenes", "random_scenes", "scene_key"]

#: The restitutions each paper scene (:data:`symvib.shapes.PAPER_SCENES`) of the work-precision diagram runs with.
RESTITUTIONS = (1.0, 0.8)
#: Random scenes (default run, --quick run) and their event cap.
RANDOM_SCENES = 200
QUICK_RANDOM = 20
RANDOM_MAX_EVENTS = 30
RANDOM_SEED = 2026
#: Hex digits of a scene's fingerprint.
KEY_DIGITS = 16


def paper_scenes(quick: bool = False) -> list:
    """``(label, scene)`` of the paper scenes with k = 1 and 0.8 (quick: two of them)."""
    from symvib.numeric.scene import load_scene

    out = []
    for name in PAPER_SCENES:
        for k in RESTITUTIONS:
            scene = load_scene(files("symvib") / "scenes" / f"{name}.toml").replace(k=k)
            out.append((f"{name} k={k:g}", scene))
    if quick:
        out = [out[1], out[4]]  # parabola k=0.8, circle-3.8 k=1
    return out


def scene_key(scene) -> str:
    """A fingerprint of everything that determines a scene's events."""
    data = [scene.shape.name, scene.shape.source() if hasattr(scene.shape, "source") else None,
            [repr(v) for v in scene.param_values], repr(scene.g), repr(scene.mu), repr(scene.k), repr(scene.left),
            repr(scene.right), repr(scene.q0), repr(scene.qdot0), repr(scene.t_max), scene.max_events]
    return hashlib.sha256(json.dumps(data, sort_keys=True, default=str).encode()).hexdigest()[:KEY_DIGITS]


def random_scenes(n: int, seed: int = RANDOM_SEED) -> list:
    """``n`` random paper-parabola / circle scenes (random ``qdot0``, ``mu``, ``k``, limiters), capped events."""
    from symvib.numeric.scene import scene_from_dict

    rng = random.Random(seed)
    out = []
    for i in range(n):
        circle = rng.random() < 0.5
        left = -rng.uniform(0.15, 1.0) if rng.random() < 0.85 else None
        right = rng.uniform(0.15, 1.0) if rng.random() < 0.85 else None
        lo = -0.9 * (1.0 if left is None else -left)
        hi = 0.9 * (1.0 if right is None else right)
        data = {"name": f"random-{seed}-{i}",
                "curve": {"shape": "circle" if circle else "parabola"},
                "parameters": {"R": 0.5} if circle else {"p": 1.0},
                "physics": {"g": 9.81, "m": 0.2, "mu": round(rng.uniform(0.01, 0.4), 6),
                            "restitution": 1.0 if rng.random() < 0.15 else round(rng.uniform(0.0, 1.0), 6)},
                "limiters": {k: v for k, v in (("left", left), ("right", right)) if v is not None},
                "initial": {"q": round(rng.uniform(lo, hi), 6), "qdot": round(rng.uniform(-9.0, 9.0), 6)},
                "run": {"t_max": 60.0, "max_events": RANDOM_MAX_EVENTS}}
        out.append(scene_from_dict(data))
    return out
