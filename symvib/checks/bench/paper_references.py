"""The time references of the paper scenes: shipped, cached in the output folder, or recomputed.

The work-precision diagram measures every run against the 30-digit time reference
(:func:`symvib.checks.reference_time.time_reference`) of its scene.  Those of the
paper scenes ship in ``symvib/checks/data/time_reference.json``
(:mod:`symvib.checks.shipped`), keyed by
:func:`~symvib.checks.bench.scenes.scene_key`; a scene missing there is computed
once and cached in the output folder under the same name, :data:`REFERENCE_NAME`.
:func:`references` is the job ``symvib bench reference``: it recomputes them all
(``--write --out symvib/checks/data`` in a checkout updates the shipped file).

Examples
--------
>>> label, scene = paper_scenes()[0]
>>> events = reference_events(scene)  # the shipped reference: nothing is computed
>>> label, events[0][0]
('paper-parabola k=1', 'impact')
"""
from __future__ import annotations

import time
from pathlib import Path

from symvib.checks.bench.output import load_json, store_json
from symvib.checks.bench.scenes import paper_scenes, scene_key
from symvib.checks.shipped import shipped

__all__ = ["REFERENCE_NAME", "REFERENCE_DPS", "STORED_DIGITS", "reference_events", "references"]

#: 30-digit time references of the paper scenes: shipped in the data folder, and the name of the
#: on-demand cache in an output folder (regenerate: ``symvib bench reference --write --out DIR``).
REFERENCE_NAME = "time_reference.json"
#: Digits of the time references, and the digits of each number stored.
REFERENCE_DPS = 30
STORED_DIGITS = 25


def reference_events(scene, *, label: str = "", cached: bool = True, cache: Path | None = None) -> list:
    """The time reference's events of ``scene`` as ``(kind, t, q, qdot_before)`` floats.

    Parameters
    ----------
    scene : symvib.numeric.scene.Scene
    label : str
        The scene's label in the cache file (default: its name).
    cached : bool
        Look the scene up (by :func:`~symvib.checks.bench.scenes.scene_key`) in the shipped
        references (:data:`REFERENCE_NAME`) and in ``cache`` first; False recomputes it.
    cache : pathlib.Path, optional
        A JSON file (in an output folder) where a computed reference is stored,
        merged with what the file holds; None stores nothing.

    Returns
    -------
    list of (str, float, float, float)
        The events in time order.
    """
    key = scene_key(scene)
    if cached:
        for data in (shipped(REFERENCE_NAME), load_json(cache)):
            if key in data:
                return [(e[0], float(e[1]), float(e[2]), float(e[3])) for e in data[key]["events"]]
    import mpmath

    from symvib.checks.reference_time import time_reference

    ref = time_reference(scene, dps=REFERENCE_DPS)
    rows = [(e.kind, mpmath.nstr(e.t, STORED_DIGITS), mpmath.nstr(e.q, STORED_DIGITS),
             mpmath.nstr(e.qdot_before, STORED_DIGITS)) for e in ref]
    if cache is not None:
        store_json(cache, {key: {"scene": label or scene.name, "dps": REFERENCE_DPS,
                                 "method": "symvib.checks.reference_time.time_reference", "events": rows}},
                   indent=1)
    return [(e[0], float(e[1]), float(e[2]), float(e[3])) for e in rows]


def references(out: Path | None = None, *, log=print) -> list:
    """Recompute the time reference of every paper scene (``symvib bench reference``).

    Parameters
    ----------
    out : pathlib.Path, optional
        Folder whose :data:`REFERENCE_NAME` receives them (merged with what it
        holds); None stores nothing.
    log : callable
        Where the progress lines go (default :func:`print`).

    Returns
    -------
    list of (str, list)
        ``(label, events)`` per paper scene.
    """
    cache = None if out is None else Path(out) / REFERENCE_NAME
    done = []
    for label, scene in paper_scenes():
        start = time.process_time()
        ev = reference_events(scene, label=label, cached=False, cache=cache)
        log(f"{label:24s} {len(ev):3d} events, {time.process_time() - start:.1f} s")
        done.append((label, ev))
    if cache is not None:
        log(f"wrote {cache}")
    return done
