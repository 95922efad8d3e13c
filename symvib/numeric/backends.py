"""Which engine runs a scene, and the engines bound to a curve's kernels (physics.md, "Events").

A run takes the compiled engine (numba) where the curve's engine is compiled on disk already, and
the plain-Python engine otherwise: a single scene never waits for a compiler
(:func:`run_backend`); a loop of plain runs compiles the curve in the background
(:mod:`symvib.numeric.tiered`).  :func:`bound_engine` binds a curve's kernels to a backend once
per process (:func:`symvib.numeric.engine.bind.bind`); :func:`quiet_compiler` keeps numba's
warnings from the user and drops an engine numba cannot cache.

Examples
--------
>>> resolve_backend("python"), backend_available("python")
('python', True)
>>> mod, engine = bound_engine("parabola", "python")
>>> mod.NAME, sorted(engine._fields)
('parabola', ['samples', 'simulate', 'sweep'])
"""
from __future__ import annotations

import importlib.util
import os
from contextlib import contextmanager

from symvib.numeric import tiered
from symvib.numeric.engine import bind
from symvib.numeric.kernels import load
from symvib.shapes import Shape

__all__ = ["BACKEND_ENV", "COMPILED_ENTRIES", "UNCACHEABLE", "backend_available", "resolve_backend",
           "kernels_of", "bound_engine", "run_backend", "quiet_compiler", "compile_by_running"]

#: Environment variable that forces a backend ("numba" or "python").
BACKEND_ENV = "SYMVIB_BACKEND"
#: (kernels, bound engine) by the identity of the kernels (a module, or a prepared view) and the backend.
_BOUND: dict = {}
#: Kernels whose compiled entry :func:`run_backend` found on disk, by (identity, entry, kernel cache).
_ON_DISK: dict = {}




def backend_available(name: str) -> bool:
    """Whether a backend can run here (``"python"`` always can)."""
    if name == "python":
        return True
    if name == "numba":
        # Found, not imported: importing numba takes a few tenths of a second a plain run does not need.
        return importlib.util.find_spec("numba") is not None
    raise ValueError(f"unknown backend {name!r}; use 'numba', 'python' or 'auto'")


def resolve_backend(backend: str) -> str:
    """The backend a run uses: ``"numba"`` or ``"python"`` (``"auto"``: numba when installed,
    unless ``$SYMVIB_BACKEND`` says otherwise)."""
    backend = os.environ.get(BACKEND_ENV, backend) if backend == "auto" else backend
    if backend == "auto":
        return "numba" if backend_available("numba") else "python"
    if not backend_available(backend):
        raise ValueError(f"backend {backend!r} is not available here (pip install numba: symvib depends on it; "
                         "where numba cannot be installed the plain engine runs)")
    return backend


def kernels_of(curve):
    """The kernel module of ``curve``: a module (or a prepared view) as it is, a shape's from disk."""
    return load(curve) if isinstance(curve, (Shape, str)) else curve


def bound_engine(curve, backend: str = "auto"):
    """``(kernel module, engine)`` of a curve's kernels (a module, a prepared view, or a shape whose
    module is on disk) on a backend (:func:`symvib.numeric.engine.bind`), cached."""
    mod = kernels_of(curve)
    entry = _BOUND.get((id(mod), backend))
    if entry is None or entry[0] is not mod or backend == "auto" and os.environ.get(BACKEND_ENV):
        entry = (mod, bind(mod, resolve_backend(backend)))
        _BOUND[(id(mod), backend)] = entry
    return entry


def run_backend(curve, backend: str = "auto", entry: str = "simulate_bound") -> str:
    """The backend one run of ``shape`` takes: a single scene never waits for a compiler.

    ``"auto"`` is numba only where the curve's compiled ``entry`` (``"simulate_bound"``
    for a run, ``"sample_bound"`` for its samples) is already on disk (compiled by an
    earlier ``backend="numba"`` run; :func:`symvib.numeric.engine.bind.is_compiled`),
    and the plain-Python engine otherwise (milliseconds per paper scene, where a
    first compilation takes seconds: docs/benchmarks.md, "The driver and first
    calls").  ``$SYMVIB_BACKEND`` and an explicit backend are obeyed.  Sweeps compile (:func:`sweep_function`).
    A process that runs a curve's plain engine many times compiles it in a child process and
    then takes it (:mod:`symvib.numeric.tiered`).
    """
    if backend != "auto" or os.environ.get(BACKEND_ENV):
        return resolve_backend(backend)
    if not backend_available("numba"):
        return "python"
    from symvib.numeric.engine.bind import is_compiled

    mod = kernels_of(curve)
    if entry == "simulate_bound":   # a background compile started by this process decides (tiered.ready)
        compiled = tiered.ready(mod)
        if compiled is not None:
            return "numba" if compiled else "python"
    # Found on disk once, taken without asking the disk again (the cache folder's trust check and
    # the marker cost as much as a compiled run); by the kernel cache folder, which a test may change.
    key = (id(mod), entry, os.environ.get("SYMVIB_CACHE"))
    if _ON_DISK.get(key) is mod:
        return "numba"
    if not is_compiled(mod, entry):
        return "python"
    _ON_DISK[key] = mod
    return "numba"


#: Entries of the compiled engine whose disk-cache markers :func:`quiet_compiler` removes.
COMPILED_ENTRIES = ("simulate_bound", "sample_bound")
#: What numba says when it compiles a function it cannot store in its disk cache.
UNCACHEABLE = "cannot cache"


@contextmanager
def quiet_compiler(mod, backend: str):
    """No NumbaWarning reaches the user; a curve whose engine numba cannot cache is not taken by ``auto`` again.

    numba warns (NumbaWarning blocks on stderr) when it compiles a function it cannot
    store on disk; such an engine compiles anew in every process (10.9 s against 1.1 s
    for the plain engine), so the markers that make ``auto`` take it
    (:func:`symvib.numeric.engine.bind.is_compiled`) are removed: later runs take the
    plain engine, silently.  The run at hand has paid the compilation and uses it.
    """
    if backend != "numba":
        yield
        return
    import warnings

    from numba.core.errors import NumbaWarning

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", NumbaWarning)
        yield
    if any(UNCACHEABLE in str(w.message).lower() for w in caught if issubclass(w.category, NumbaWarning)):
        from symvib.numeric.engine.bind import compiled_marker

        for entry in COMPILED_ENTRIES:
            compiled_marker(mod, entry).unlink(missing_ok=True)
    for w in caught:  # the others (not numba's) as they were
        if not issubclass(w.category, NumbaWarning):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)


def compile_by_running(mod, cp, row, R, samples):
    """Compile ``mod``'s engine by running it once on a run's arguments (a background compile's
    job, :mod:`symvib.numeric.tiered`): numba compiles at the first call and writes its disk cache;
    a cache it cannot write removes the marker (:func:`quiet_compiler`)."""
    mod, eng = bound_engine(mod, "numba")
    with quiet_compiler(mod, "numba"):
        return eng.simulate(cp, row, R, samples)
