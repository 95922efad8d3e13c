"""Inner engine functions compiled to optimized LLVM IR only: turned into machine code once,
inside the entry point that calls them (imports numba).

numba finalizes the code library of every function it compiles: it links in the libraries of
the functions it calls, runs the full module optimization (``-O3``) over the lot and emits
machine code for it.  For the engine's call tree (about 90 functions, ``simulate_bound`` ->
``run`` -> ``run_on`` -> ``interval`` -> ``quad`` -> ``panel`` ...) every caller thus compiles
again the code of all its callees: the machine-code emitter saw about six times the code of the
entry point, 3-4 s of a 23 s compile of the parabola's ``simulate`` entry (docs/benchmarks.md,
"The engine's compile").

An inner function (compiled without Python and C wrappers: only compiled code calls it, never
Python) needs no machine code of its own: its library serves only to be linked into its callers.
:func:`lazy` marks such a function; its library is then finalized without it (linked and
optimized as before, not added to numba's execution engine), and the entry point that calls it
emits the whole tree once, as it did anyway.  The entry points, the kernels, and every function
numba compiles for anyone else in the process are finalized as before.  Where numba's internals
are not what this module expects, or the numba release is not one it was tested with
(:data:`TESTED_NUMBA`), :func:`install` does nothing (the compile is then as slow as before, not
wrong).

The optimization is kept: skipping it too (the entry point optimizing the whole tree once) saved
about 3 s more of the compile, but LLVM then inlined and optimized differently and the sweep ran
6 % slower (``benchmarks/sweep_duel.py``: 0.939).  With it, the entry point's module is the one
numba built before, and so is its code (the same events, bit for bit:
``benchmarks/event_snapshot.py``).

Examples
--------
>>> def f(x):
...     return x
>>> lazy(f) is f, f._symvib_lazy_library
(True, True)
"""
from __future__ import annotations

import threading

__all__ = ["lazy", "install", "installed", "TESTED_NUMBA"]

#: Attribute of a Python function whose numba library is finalized by linking alone.
MARK = "_symvib_lazy_library"
#: Attribute of such a numba code library.
LIBRARY_MARK = "_symvib_lazy"

#: numba releases (major, minor) whose internals these patches were written against and tested with
#: (``tests/test_engine_compile.py``, ``benchmarks/event_snapshot.py``); with any other release
#: :func:`install` leaves numba alone: a private method may keep its name and change its meaning.
TESTED_NUMBA = ((0, 68),)

_LOCK = threading.Lock()
_STATE = {"installed": None}


def lazy(fn):
    """Mark ``fn`` (a Python function to be compiled by numba without Python and C wrappers) so that
    its code library is only linked, never optimized or compiled to machine code on its own."""
    setattr(fn, MARK, True)
    return fn


def installed() -> bool:
    """Whether the patches are in place (numba's internals as expected)."""
    return bool(_STATE["installed"])


def install() -> bool:
    """Install the patches of numba's lowering and code library (once; idempotent).  Returns
    whether they are in place."""
    with _LOCK:
        if _STATE["installed"] is None:
            try:
                _STATE["installed"] = _install()
            except Exception:   # noqa: BLE001 - another numba: compile as numba does
                _STATE["installed"] = False
        return _STATE["installed"]


def _release(version: str) -> tuple:
    """``(major, minor)`` of a version string (``"0.68.1"`` -> ``(0, 68)``); ``()`` when unreadable."""
    try:
        return tuple(int(part) for part in version.split(".")[:2])
    except ValueError:
        return ()


def _install() -> bool:
    import numba

    if _release(numba.__version__) not in TESTED_NUMBA:
        return False
    from numba.core import codegen, typed_passes
    from numba.core.compiler_lock import require_global_compiler_lock

    lowering = typed_passes.BaseNativeLowering
    library_class = codegen.CPUCodeLibrary
    jit_codegen = codegen.JITCPUCodegen
    needed = ((library_class, ("finalize", "_get_module_for_linking", "_finalize_dynamic_globals",
                               "_verify_declare_only_symbols", "_raise_if_finalized")),
              (lowering, ("run_pass",)), (jit_codegen, ("set_env",)))
    if not all(hasattr(owner, name) for owner, names in needed for name in names):
        return False

    run_pass = lowering.run_pass

    def lazy_run_pass(self, state):
        fn = getattr(state.func_id, "func", None)
        flags = state.flags
        if getattr(fn, MARK, False) and flags.no_cpython_wrapper and flags.no_cfunc_wrapper:
            if state.library is None:   # (what the pass does itself, done first to mark the library)
                state.library = state.targetctx.codegen().create_library(state.func_id.func_qualname)
                state.library.enable_object_caching()
            setattr(state.library, LIBRARY_MARK, True)
        return run_pass(self, state)

    finalize = library_class.finalize

    def lazy_finalize(self):
        if not getattr(self, LIBRARY_MARK, False):
            return finalize(self)
        # numba's finalize without the execution engine: link and optimize, emit no machine code
        require_global_compiler_lock()
        self._raise_if_finalized()
        seen = set()
        for library in self._linking_libraries:
            if library not in seen:
                self._reload_init.update(library._reload_init)
                seen.add(library)
                self._final_module.link_in(library._get_module_for_linking(), preserve=True)
        self._optimize_final_module()
        self._finalize_dynamic_globals()
        self._verify_declare_only_symbols()
        self._finalized = True

    set_env = jit_codegen.set_env

    def lazy_set_env(self, env_name, env):
        # A linked-only library is not in the execution engine: no environment to point at (as for
        # the inner functions of an entry point loaded from numba's disk cache).
        if not self._engine.get_global_value_address(env_name):
            return None
        return set_env(self, env_name, env)

    lowering.run_pass = lazy_run_pass
    library_class.finalize = lazy_finalize
    jit_codegen.set_env = lazy_set_env
    return True
