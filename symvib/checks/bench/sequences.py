"""Wrong event sequences over random scenes: each setting against the phase reference.

Over :func:`~symvib.checks.bench.scenes.random_scenes`, every sequence setting
(:func:`~symvib.checks.bench.settings.sequence_settings`) runs every scene, and
its event sequence (:func:`symvib.checks.stability.labels`) is compared with the
scene's truth: that of :func:`symvib.checks.reference.phase_reference` at
:data:`RANDOM_DPS` digits.  Scenes whose reference needs more than
:data:`~symvib.checks.bench.scenes.RANDOM_MAX_EVENTS` events, or fails, are left
out and counted.  The truths ship in ``symvib/checks/data/random_truth.json``;
one missing there is computed and cached in the output folder under the same
name, :data:`RANDOM_TRUTH_NAME`.
"""
from __future__ import annotations

import time
from pathlib import Path

from symvib.checks.bench.output import load_json, store_json
from symvib.checks.bench.scenes import RANDOM_MAX_EVENTS, random_scenes, scene_key
from symvib.checks.bench.settings import run_setting
from symvib.checks.bench.workers import map_workers
from symvib.checks.shipped import shipped

__all__ = ["RANDOM_TRUTH_NAME", "RANDOM_DPS", "sequence_counts"]

#: Phase-reference event sequences of the random scenes: shipped, and the on-demand cache's name.
RANDOM_TRUTH_NAME = "random_truth.json"
#: Digits of the random scenes' phase reference.
RANDOM_DPS = 20


def sequence_counts(n, settings, workers, budget, backend, log, cache_file: Path) -> dict:
    """Wrong-sequence counts of each setting over ``n`` random scenes.

    Truths missing from the shipped :data:`RANDOM_TRUTH_NAME` and from ``cache_file``
    are computed (over the workers) and stored in ``cache_file``.

    Parameters
    ----------
    n : int
        Random scenes (:func:`~symvib.checks.bench.scenes.random_scenes`).
    settings : list of symvib.checks.bench.settings.Setting
        The settings that run them.
    workers : int
        Processes (:func:`~symvib.checks.bench.workers.map_workers`).
    budget : float
        CPU seconds of one peer run.
    backend : str
        symvib's driver backend.
    log : callable
        Where the progress lines go.
    cache_file : pathlib.Path
        The output folder's cache of truths.

    Returns
    -------
    dict
        ``rows`` (one per setting: ``method``, ``setting``, ``label``, ``scenes``, ``wrong``,
        ``failed``), ``usable`` (scenes counted) and ``left_out`` (scenes without a truth).
    """
    scenes = random_scenes(n)
    cache = {**shipped(RANDOM_TRUTH_NAME), **load_json(cache_file)}
    todo = [s for s in scenes if scene_key(s) not in cache]
    if todo:
        log(f"phase reference of {len(todo)} random scenes ({RANDOM_DPS} digits; cached in {cache_file})")
        truths = map_workers(_random_truth, todo, workers)
        new = {scene_key(s): tr for s, tr in zip(todo, truths)}
        cache.update(new)
        store_json(cache_file, new)
    usable = [(s, cache[scene_key(s)]["labels"]) for s in scenes if cache[scene_key(s)]["labels"] is not None]
    left_out = len(scenes) - len(usable)
    log(f"random scenes: {len(usable)} usable, {left_out} left out (more than {RANDOM_MAX_EVENTS} events, or the "
        f"reference failed)")
    tasks = [(s, tr, settings, budget, backend) for s, tr in usable]
    start = time.perf_counter()
    results = map_workers(_sequence_task, tasks, workers)
    rows = []
    for j, st in enumerate(settings):
        col = [r[j] for r in results]
        rows.append({"method": st.method, "setting": st.value, "label": st.label, "scenes": len(col),
                     "wrong": col.count("wrong"), "failed": col.count("failed")})
        log(f"  {st.label:22s} wrong sequence {col.count('wrong'):4d}/{len(col)}, failed/out of budget "
            f"{col.count('failed')}")
    log(f"  ({time.perf_counter() - start:.0f} s)")
    return {"rows": rows, "usable": len(usable), "left_out": left_out}


def _random_truth(scene):
    """Sequence labels of a random scene by the phase reference, or None (too many events, or it failed)."""
    from symvib.checks.reference import phase_reference
    from symvib.checks.stability import labels

    try:
        ref = phase_reference(scene, dps=RANDOM_DPS, max_events=RANDOM_MAX_EVENTS, derive=_shared_derive)
    except Exception as exc:  # noqa: BLE001 - a scene the reference cannot do is left out, and counted
        return {"labels": None, "why": f"{type(exc).__name__}"}
    if not ref or ref[-1].kind not in ("arrest", "rest_on_limiter"):
        return {"labels": None, "why": "needs more than the event cap"}
    rows = [(e.kind, float(e.t), float(e.q), float(e.qdot_before)) for e in ref]
    return {"labels": list(labels(rows)), "t": [r[1] for r in rows]}


def _sequence_task(args):
    """One random scene through every sequence setting (runs in a worker)."""
    scene, truth, settings, budget, backend = args
    from symvib.checks.stability import labels

    out = []
    for st in settings:
        try:
            status, events, _ = run_setting(st, scene, budget=budget, backend=backend)
        except Exception:  # noqa: BLE001 - a crash is a failure to count
            status, events = "failed", []
        if status == "failed":
            out.append("failed")
        else:
            out.append("ok" if list(labels(events)) == truth else "wrong")
    return out


_DERIVATIONS: dict = {}


def _shared_derive(curve, **kwargs):
    """:func:`symvib.symbolic.derive.derive`, memoized per process for the phase reference.

    :func:`symvib.checks.reference.phase_reference` derives the scene's curve on every
    call (a second or so, in budgeted child processes); the random scenes use
    two curves, so the derivation is memoized by the curve's expressions and
    the options (``_DERIVATIONS``) and passed as its ``derive``.
    """
    from symvib.symbolic.derive import derive

    key = (curve.name, str(curve.x), str(curve.z), str(curve.q), tuple(sorted(kwargs.items())))
    if key not in _DERIVATIONS:
        _DERIVATIONS[key] = derive(curve, **kwargs)
    return _DERIVATIONS[key]
