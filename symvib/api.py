"""The package's top-level functions: ``symvib.load_scene``, ``symvib.simulate``, ``symvib.sweep``.

Each takes a scene in any form a user has at hand: a :class:`~symvib.numeric.scene.Scene`,
the path of a scene file, the name of a packaged scene (``"paper-parabola"``)
or a dict of a scene file's tables, and hands it to the numeric wing
(:func:`symvib.numeric.driver.simulate`, :func:`symvib.numeric.sweep.sweep`) with its
curve prepared (:func:`symvib.prepare.prepare`).
``symvib.derive`` is the symbolic wing's :func:`symvib.symbolic.derive.derive`.

This module imports nothing heavy: the driver and the sweep are imported when
called, and none of them imports SymPy for a curve already prepared (a catalogue
shape, or a user curve whose kernels and singular points are on record); a new
user curve is derived and searched with SymPy once (:mod:`symvib.prepare`).

Examples
--------
>>> import symvib
>>> result = symvib.simulate("paper-circle-3.8", backend="python")
>>> result.status.value, result.success
('arrested', True)
>>> scene = symvib.load_scene({"curve": {"shape": "circle"}, "parameters": {"R": 0.5},
...     "physics": {"alpha0": "3 deg", "restitution": 1}, "initial": {"q": "10 deg", "qdot": 2}})
>>> round(scene.q0, 12), round(scene.mu, 9)
(0.174532925199, 0.052407779)
"""
from __future__ import annotations

from pathlib import Path

__all__ = ["load_scene", "simulate", "sweep"]


def load_scene(source, *, name: str | None = None):
    """A validated :class:`~symvib.numeric.scene.Scene` from ``source``.

    Parameters
    ----------
    source : Scene, str, os.PathLike or dict
        A scene (returned as it is), the path of a scene TOML file, the name of a
        packaged scene (``"paper-parabola"``; :func:`symvib.numeric.scene.resolve_scene`),
        or the scene file's tables as a dict (:func:`symvib.numeric.scene.scene_from_dict`).
    name : str, optional
        The scene's name, for a dict without one.

    Raises
    ------
    SceneError
        Naming the field (or the file) that is wrong.
    TypeError
        When ``source`` is none of these.
    """
    from symvib.numeric import scene as _scene

    if isinstance(source, _scene.Scene):
        return source
    if isinstance(source, dict):
        return _scene.scene_from_dict(source, name=name)
    if isinstance(source, Path):
        return _scene.load_scene(source)
    if isinstance(source, str):
        return _scene.resolve_scene(source)
    raise TypeError(f"load_scene: a Scene, a path, a packaged scene's name or a dict, got {type(source).__name__}")


def simulate(scene, **options):
    """Simulate a scene given in any form :func:`load_scene` takes; ``options`` are
    :func:`symvib.numeric.driver.simulate`'s (``nodes``, ``samples``, ``backend``).

    Returns
    -------
    Result
        Status, events, samples, dense output (``result.state(t)``), tables
        (``result.events_frame()``) and energy budget.
    """
    from symvib.numeric.driver import simulate as _simulate
    from symvib.prepare import prepare

    scene = load_scene(scene)
    if options.get("prepared") is None:
        options["prepared"] = prepare(scene)
    return _simulate(scene, **options)


def sweep(scene, vary: dict, **options):
    """Sweep a scene given in any form :func:`load_scene` takes over the ``vary`` fields;
    ``options`` are :func:`symvib.numeric.sweep.sweep`'s (``random``, ``out``, ``backend``, ...)."""
    from symvib.numeric.sweep import sweep as _sweep
    from symvib.prepare import prepare

    scene = load_scene(scene)
    if options.get("prepared") is None:
        options["prepared"] = prepare(scene)
    return _sweep(scene, vary, **options)


def fit(scene, observed, free=("mu", "k"), **options):
    """Fit the ``free`` parameters of a scene (any form :func:`load_scene` takes; its values are the
    start) to observed events or a sampled trajectory: a CSV file (events ``t[, kind][, q]``, or
    samples ``t`` with ``q``, ``x, z`` or ``s``: :func:`symvib.numeric.fit_data.read_observations`),
    a list of impact times, a dict of samples (``{"t": ..., "x": ..., "z": ...}``), or
    :func:`symvib.numeric.fit.observed_events` / :func:`symvib.numeric.fit.observed_samples`; ``options``
    are :func:`symvib.numeric.fit.fit`'s (``bounds``, ``weights``).

    Returns
    -------
    FitResult
        Estimates, standard errors, covariance and correlation, residuals, a status.
    """
    from pathlib import Path

    from symvib.numeric.driver import simulate as _simulate
    from symvib.numeric.fit import Observed, ObservedSamples, observed_events, observed_samples, read_observations
    from symvib.numeric.fit import fit as _fit
    from symvib.prepare import prepare

    scene = load_scene(scene)
    if isinstance(observed, (str, Path)):
        observed = read_observations(observed)
    elif isinstance(observed, dict):
        if "t" not in observed or not set(observed) <= {"t", "q", "x", "z", "s"}:
            raise ValueError(f"observed: a dict of samples has the keys t with q, or x and z, or s; got "
                             f"{', '.join(map(repr, observed)) or 'none'}")
        observed = observed_samples(**observed)
    elif not isinstance(observed, (Observed, ObservedSamples)):
        if not hasattr(observed, "__iter__") or isinstance(observed, bytes):
            raise ValueError(f"observed: a CSV file, a list of impact times, a dict of samples or observed "
                             f"events or samples, got {type(observed).__name__}")
        times = list(observed)
        observed = observed_events(times, kinds=["impact"] * len(times))   # what a microphone hears
    prepared = prepare(scene)
    samples = isinstance(observed, ObservedSamples)
    # (a free curve parameter changes the curve: each of its values is prepared, once)
    return _fit(scene, observed, free, run=lambda s: _simulate(
        s, samples=samples, prepared=prepared if s.params == scene.params else prepare(s)), **options)

