"""Binding a curve's kernels to the engine: plain Python, or compiled by numba.

The engine (:mod:`~symvib.numeric.engine.laws`, ``roots``, ``anchor``, ``scan``, ``timing``,
``loop``) is written once, as plain Python functions that receive the curve's
kernels as an argument (a :class:`~symvib.numeric.engine.state.Kernels` tuple);
no source text is pasted or executed.

* ``python``: the engine's functions as they are, the kernels the generated
  module's ``*_scalar`` functions.
* ``numba`` (default): the engine specialized to the curve.  The kernels are
  compiled with their signatures from
  :data:`~symvib.numeric.engine.state.KERNEL_INTERFACE` and reach the engine as
  a compile-time constant (:mod:`~symvib.numeric.engine.static`), so numba
  inlines them; the compiled entry points are named after the curve's module
  and input hash and cached on disk.
* ``numba`` with ``shared=True``: the engine compiled once per number of curve
  parameters, with the kernels as first-class functions in one numba structure
  (:mod:`~symvib.numeric.engine.compiled`); a new curve costs its kernels only.

Either way every engine function is compiled from its own code object with its
calls bound to its compiled siblings (:func:`compiled_functions`).

The binding's contract
----------------------
What a kernel set must provide to the engine, and what the engine promises (an
implementer of a new kernel source, or of a new binding, reads this list):

1. **The module.** A kernel set is a module with one function per entry of
   :data:`~symvib.numeric.engine.state.KERNEL_INTERFACE`, named as the entry says
   (``F_p_scalar``, ..., ``domain``), and ``PARAMS``, the names of the curve's
   parameters (``ncp = len(PARAMS)``).  ``__file__``, ``__name__`` and ``INPUT_HASH``
   name its compiled engine on disk; a module without a file (a prepared view) is
   compiled for its process only.
2. **Argument order.** Every kernel takes its leading arguments (the entry's second
   field: ``(q, mu)`` for ``F_s, dF_s, ddF_s, node_s``; ``(q,)`` for the geometry;
   ``(q, w, g)`` for ``N_w``; none for ``q_scale`` and ``domain``) and then the ``ncp``
   parameter values, each a separate positional float (the engine calls ``K.F_p(q, mu, *cp)``).
3. **Dtypes.** Every argument is a float64; a kernel returns a float64, or a tuple of as
   many float64 as the entry's third field: ``node_s`` gives ``(F_s', h, exp(s mu alpha),
   kappa, cos alpha)`` at once, ``domain`` the open interval ``(lo, hi)`` of ``q``.
4. **Scalar code only.** A kernel calls only ``math`` and the module's own ``*_scalar``
   functions (numba compiles it in nopython mode with its signature from (2)-(3), the
   error model ``numpy``: a division by zero gives ``inf`` or ``nan``, never an
   exception); it keeps no state, so the engine may call it in any order, any number
   of times, from several threads.
5. **Accuracy.** Inside ``domain`` every kernel is finite and agrees with its
   expression to a few rounding errors; ``F_s`` is the antiderivative of ``dF_s``
   (the engine takes differences of it and rebuilds ``G`` from ``dF_s``), ``ddF_s``
   its derivative.  Outside ``domain`` nothing is asked.
6. **What the engine receives per call.** The curve's parameters as a tuple of
   ``ncp`` float64 (``cp``), a scene as a C-contiguous float64 row of
   :class:`~symvib.numeric.layout.SceneRow` values, the rules ``R``
   (:class:`~symvib.numeric.engine.state.Rules`: C-contiguous float64 vectors ``Xw,
   Ww, Xp, Wp, Tw, Tp``, matrices ``Sw, SWw, Sp``, floats ``rtol, atol``); a sweep
   C-contiguous float64 matrices of scene rows and parameter rows (one row per scene).
7. **What the engine promises.** :class:`Engine`'s three calls:
   ``simulate(cp, row, R, keep)`` returns an :class:`~symvib.numeric.engine.state.Outcome`
   (events in :class:`~symvib.numeric.layout.EventColumn` columns; the motion
   intervals too when ``keep``); ``samples(cp, row, R, intervals, n, pieces)`` the
   samples (:class:`~symvib.numeric.engine.timing.SampleColumn`) and their interval
   index; ``sweep(rows, cp_rows, R, max_log)`` the summary
   (:class:`~symvib.numeric.layout.Summary`) and each scene's first ``max_log``
   events.  It writes none of its arguments, keeps no reference to them after the
   call.  Every binding runs the same engine code (the plain one sums the
   cumulative integrals in another order, which changes the last bits:
   :mod:`~symvib.numeric.engine.plain`).

Examples
--------
>>> from symvib.numeric.kernels import load
>>> from symvib.shapes import shape
>>> engine = bind(load(shape("parabola")), "python")
>>> sorted(engine._fields)
['samples', 'simulate', 'sweep']
"""
from __future__ import annotations

import hashlib
import inspect
from functools import cache, partial
from pathlib import Path
from typing import NamedTuple

from symvib.numeric.engine import loop, timing
from symvib.numeric.engine.plain import plain_entries
from symvib.numeric.engine.rebind import ENGINE_MODULES, rebound_functions
from symvib.numeric.engine.state import KERNEL_INTERFACE, Kernels, Rules
from symvib.numeric.kernels import curve_tag

__all__ = ["Engine", "bind", "kernel_functions", "is_compiled", "compiled_marker", "threaded_sweep", "guided_blocks",
           "own_rules", "rebound_functions", "compiled_functions", "compiled_kernels", "kernel_signatures",
           "flush_if_stale", "curve_tag", "marking", "ENGINE_MODULES", "ENTRY_POINTS", "NO_REFCOUNT", "ERRORS", "INNER"]

#: Entry points compiled with explicit signatures (and cached on disk).
ENTRY_POINTS = ("simulate_scene", "sample_scene", "sweep_block")


class Engine(NamedTuple):
    """The engine bound to one curve's kernels.

    ``simulate(cp, row, R, keep) -> Outcome``; ``samples(cp, row, R, intervals, n, pieces)
    -> (samples, index)``; ``sweep(rows, cp_rows, R, max_log) -> (summary, logs)``
    (see :mod:`symvib.numeric.engine.loop`).
    """

    simulate: object
    samples: object
    sweep: object


def kernel_functions(module) -> tuple:
    """The generated module's functions in :data:`KERNEL_INTERFACE` order."""
    return tuple(getattr(module, name) for name, _, _ in KERNEL_INTERFACE.values())


def bind(module, backend: str, *, shared: bool = False) -> Engine:
    """The engine bound to the kernels of a generated ``module`` on ``backend``.

    On numba, the default is an engine specialized to the curve (its kernels
    inlined; compiled on first use and cached on disk under the curve's module
    and input hash; the kernels first, then the entry point, a second entry
    point costing less in the same process).  ``shared=True`` takes the engine
    compiled once per number of curve parameters, with the kernels as
    first-class functions (a new curve then costs its kernels only; runs are
    slower).  Compile times and the runs' speed: docs/benchmarks.md.
    """
    if backend == "python":
        return Engine(*plain_entries(Kernels(*kernel_functions(module))))
    if backend != "numba":
        raise ValueError(f"unknown backend {backend!r}; use 'numba' or 'python'")
    ncp = len(module.PARAMS)
    # (a prepared view's kernels take *cp, which the shared engine's explicit signatures do not
    # describe: a view is always bound to an engine of its own)
    if not shared or not _cacheable(module):
        entries = _specialized_engine(module, ncp)
        if not _cacheable(module):   # compiled in this process only: never marked compiled
            return Engine(entries["simulate_bound"], entries["sample_bound"], threaded_sweep(entries["sweep_bound"]))
        return Engine(marking(entries["simulate_bound"], compiled_marker(module, "simulate_bound")),
                      marking(entries["sample_bound"], compiled_marker(module, "sample_bound")),
                      threaded_sweep(entries["sweep_bound"]))
    from symvib.numeric.engine.compiled import kernels_box

    k = kernels_box(compiled_kernels(module, ncp), kernel_signatures(ncp))
    entries = _compiled_engine(ncp)
    return Engine(partial(entries["simulate_scene"], k), partial(entries["sample_scene"], k),
                  threaded_sweep(partial(entries["sweep_block"], k)))


# --- numba ------------------------------------------------------------------------
#: Fewest scenes a thread of a sweep takes at a time (numba backend).
SWEEP_GRAIN = 16
#: A thread takes this share of the scenes left per thread at a time (guided scheduling:
#: large blocks first, small ones at the end, so the threads finish together).
SWEEP_SHARE = 4
#: Small engine functions of the hot loops that take arrays, inlined where they are called (numba
#: counts a reference of every array an ordinary call passes, atomically).
HOT_INLINE = ("cumulate", "next_crit", "next_cut", "crit_near", "dF_best")
#: Engine functions that neither allocate nor return an array, compiled without reference counting
#: (numba's ``_nrt=False``): the arrays they receive stay owned by their caller, which outlives the
#: call.  Reference counts had been a third of a sweep's time (``benchmarks/profile_sweep.py``;
#: docs/benchmarks.md, "Cost of error control").  ``tests/test_engine_refcount.py`` checks that none
#: of them returns an array (a returned array would be freed under its new owner).
NO_REFCOUNT = ("panel", "quad", "interval", "turning_point", "stop_at_t_max", "impacts_at", "anchored_G",
               "root_anchored", "tail_time", "turn_departure", "time_excess", "root_time", "locate", "walk",
               "map_extend", "extend_side", "crossing", "branch_cut", "add_root", "room", "map_start", "put_event",
               "put_interval")
#: Arguments of engine functions that some call sites pass as a constant (``0``, ``False``) and
#: others as a variable: numba compiles a specialization for each literal constant (``panel`` twice,
#: ``add_root`` three times ...).  These are typed as variables at every call (they choose no code
#: path by their type; ``mode`` and the sweep's ``keep_intervals`` stay literal: those prune code).
NOT_LITERAL = {"panel": ("o",), "tail_error": ("cautious",), "grown": ("n",), "put_event": ("ne",),
               "put_interval": ("ni",), "add_root": ("b",), "crossing": ("row",), "scratch": ("rows", "n"),
               "run_arrays": ("event_rows", "interval_rows")}
#: numba's error model of the compiled engine and kernels: a division by zero gives inf or NaN (as
#: numpy does; the run then ends ``non_finite``), not a Python exception, so no division carries a
#: test and a branch to raise it (a few per cent of a sweep's time; docs/benchmarks.md).
ERRORS = {"error_model": "numpy"}
#: numba options of an engine function only compiled code calls: no Python or C wrapper
#: to build (about 2.5 s of the parabola engine's compile).
INNER = {"no_cpython_wrapper": True, "no_cfunc_wrapper": True, **ERRORS}


def kernel_signatures(ncp: int) -> dict:
    """numba signatures of the kernels (by engine name) for ``ncp`` curve parameters."""
    from numba import types as nt

    f64 = nt.float64
    out = {}
    for name, (_, leading, returns) in KERNEL_INTERFACE.items():
        result = f64 if returns == 1 else nt.UniTuple(f64, returns)
        out[name] = result(*([f64] * (len(leading) + ncp)))
    return out


def compiled_functions(modules, keep, *, names=None, options=None, default=None, qualnames=None) -> dict:
    """numba dispatchers of the functions defined in ``modules`` whose names pass ``keep``
    (:func:`rebound_functions`, their calls bound to their compiled siblings).

    ``options`` (name -> ``numba.njit`` options; ``default`` for the others) and
    ``qualnames`` (name -> the name numba's disk cache files it under) apply per
    function.  Dispatchers are lazy (compiled on first call, or by the caller with a
    signature).
    """
    import numba

    from symvib.numeric.engine import lazylink

    options, qualnames = options or {}, qualnames or {}
    linked_only = lazylink.install()

    def make(name, fn):
        fn.__qualname__ = qualnames.get(name, fn.__qualname__)
        opts = options.get(name, default or {})
        if linked_only and _inner(opts):
            # only compiled code calls it: its code is optimized and emitted inside its entry point
            lazylink.lazy(fn)
        dispatcher = numba.njit(**opts)(fn)
        if name in NOT_LITERAL:
            _typed_as_variables(dispatcher, NOT_LITERAL[name])
        return dispatcher

    return rebound_functions(modules, keep, make, names)


def _typed_as_variables(dispatcher, names) -> None:
    """Let ``dispatcher``'s compiled callers pass its arguments ``names`` as variables of their type
    (``int64``, ``bool``), never as the literal constant a call site may give them: one compiled
    specialization for every call, not one per constant (:data:`NOT_LITERAL`)."""
    from numba.core import types

    params = list(inspect.signature(dispatcher.py_func).parameters)
    which = frozenset(params.index(name) for name in names)
    get_call_template = dispatcher.get_call_template

    def unliteral_call_template(args, kws):
        return get_call_template(tuple(types.unliteral(a) if i in which else a for i, a in enumerate(args)), kws)

    dispatcher.get_call_template = unliteral_call_template


def _inner(options: dict) -> bool:
    """Whether numba options make an inner function (no Python or C wrapper, not cached): its code
    library is linked into its callers only (:mod:`~symvib.numeric.engine.lazylink`)."""
    return bool(options.get("no_cpython_wrapper") and options.get("no_cfunc_wrapper") and not options.get("cache"))


def _cacheable(module) -> bool:
    """Whether numba may cache a module's compiled kernels and engine on disk: not for a prepared
    view of a module on a narrowed domain (:func:`symvib.numeric.prepared.kernel_view`, no file),
    whose run's numbers are compile-time constants that numba's cache does not key on."""
    return bool(getattr(module, "__file__", None))


def compiled_kernels(module, ncp: int) -> tuple:
    """The module's interface kernels compiled with their signatures (cached per module)."""
    cached = getattr(module, "_symvib_compiled_kernels", None)
    if cached is not None:
        return cached
    sigs = kernel_signatures(ncp)
    wanted = {fname for fname, _, _ in KERNEL_INTERFACE.values()}
    # Every function the interface kernels may call: the module's float-only functions.
    cache = _cacheable(module)
    compiled = compiled_functions([module], lambda n: n.endswith("_scalar") or n in wanted,
                                   options={f: {"cache": cache, **ERRORS} for f in wanted}, default=ERRORS)
    if cache:   # an engine compiled at install time holds them too (engine/installed.py)
        from symvib.numeric.engine import installed

        for fname in wanted:
            installed.attach(compiled[fname], module)
    out = []
    for name, (fname, _, _) in KERNEL_INTERFACE.items():
        dispatcher = compiled[fname]
        if not dispatcher.py_func.__code__.co_flags & inspect.CO_VARARGS:   # (a view's take *cp: compiled
            dispatcher.compile(sigs[name])                                     # at their first call)
        out.append(dispatcher)
    module._symvib_compiled_kernels = tuple(out)
    return module._symvib_compiled_kernels


@cache
def engine_digest() -> str:
    """SHA-256 (hex, 20 digits) of the engine's source files and compile options, for cache invalidation
    (read once)."""
    import importlib.util

    digest = hashlib.sha256()
    # (the layout too: its codes and columns are compile-time constants of the engine; and the
    # kernel interface, declared in kernelformat).  Found, not imported: the compiled binding
    # imports numba, which a plain run asking "is it compiled?" does not need.
    names = ("symvib.numeric.engine.state", "symvib.numeric.engine.compiled", "symvib.numeric.engine.lazylink",
             "symvib.numeric.layout", "symvib.kernelformat")
    for origin in (*(mod.__file__ for mod in ENGINE_MODULES), *(importlib.util.find_spec(n).origin for n in names)):
        digest.update(Path(origin).read_bytes())
    # (and the compile options, which numba's cache does not key on either)
    digest.update(repr((INNER, HOT_INLINE, loop.RUN_STEPS, timing.QUAD_STEPS, NO_REFCOUNT, NOT_LITERAL)).encode())
    return digest.hexdigest()[:20]


@cache
def _params_of(ncp: int):
    """``loop.params_of`` for the compiled engine: ``ncp`` is fixed at compile time
    (numba builds tuples of a static length only)."""
    import numba
    from numba.np.unsafe.ndarray import to_fixed_tuple

    from symvib.numeric.engine import lazylink

    def params_of(row, n):
        return to_fixed_tuple(row, ncp)

    if lazylink.install():
        lazylink.lazy(params_of)
    return numba.njit(**INNER)(params_of)


def flush_if_stale(dispatchers, marker: Path) -> None:
    """Empty the disk cache of ``dispatchers`` unless ``marker`` (named by :func:`engine_digest`)
    exists, then leave it: numba checks only an entry point's own file, not the modules it calls."""
    if not marker.exists():
        for dispatcher in dispatchers:
            dispatcher._cache.flush()
        marker.parent.mkdir(parents=True, exist_ok=True)
        marker.touch()


@cache
def _compiled_engine(ncp: int) -> dict:
    """The engine's entry points compiled for ``ncp`` curve parameters.

    numba's cache checks the file of each entry point only, not the modules it
    calls; so the cache is flushed once whenever :func:`engine_digest` changes.
    """
    from numba import types as nt

    from symvib.numeric.engine.compiled import kernels_type
    from symvib.numeric.kernels import cache_dir

    f64 = nt.float64
    k_type = kernels_type(kernel_signatures(ncp))
    cp_type = nt.Tuple([f64] * ncp)
    vec, mat = f64[::1], f64[:, ::1]
    rules_type = nt.NamedTuple([vec, vec, mat, mat, vec, vec, mat, vec, vec, f64, f64], Rules)

    options = {name: {"cache": True, **ERRORS} for name in ENTRY_POINTS}
    options["sweep_block"] = {"cache": True, "nogil": True, **ERRORS}
    # (not NO_REFCOUNT here: the kernels' structure is itself reference counted)
    compiled = compiled_functions(ENGINE_MODULES, lambda n: not n.endswith("_bound") and n != "params_of",
                                   names={"params_of": _params_of(ncp)}, options=options, default=INNER)
    flush_if_stale([compiled[name] for name in ENTRY_POINTS], cache_dir() / "engines" / f"engine-{engine_digest()}")
    signatures = {
        "simulate_scene": (k_type, cp_type, vec, rules_type, nt.boolean),
        "sample_scene": (k_type, cp_type, vec, rules_type, mat, nt.int64, nt.int64),
        # rows, parameter rows, rules, max_log, summary, event logs, first and last + 1 scene
        "sweep_block": (k_type, mat, mat, rules_type, nt.int64, mat, f64[:, :, ::1], nt.int64, nt.int64),
    }
    for name, sig in signatures.items():
        compiled[name].compile(sig)
        # Locked to its signature: a call with the kernels' dispatchers converts them to
        # function pointers instead of compiling a specialization (slow, not cacheable).
        compiled[name].disable_compile()
    return compiled


#: Entry points of an engine specialized to one curve (:func:`_specialized_engine`).
BOUND_ENTRIES = ("simulate_bound", "sample_bound", "sweep_bound")


def compiled_marker(module, entry: str) -> Path:
    """The file that says a curve's compiled ``entry`` is in numba's disk cache (for this engine)."""
    from symvib.numeric.kernels import cache_dir

    return cache_dir() / "engines" / f"compiled-{engine_digest()}-{curve_tag(module)}-{entry}"


def is_compiled(module, entry: str = "simulate_bound") -> bool:
    """Whether the curve's compiled ``entry`` was compiled before (and so loads from disk, not compiles):
    into the user's cache (its marker), or at install time (:func:`symvib.numeric.engine.installed.has`)."""
    if compiled_marker(module, entry).exists():
        return True
    from symvib.numeric.engine import installed

    return installed.has(module, entry)


def marking(fn, marker: Path):
    """``fn`` that leaves ``marker`` after its first call (numba has compiled and cached it then);
    not after a call that loaded an engine compiled at install time (the user's cache does not hold it)."""
    done = [marker.exists()]

    def call(*args):
        out = fn(*args)
        if not done[0]:
            from symvib.numeric.engine.installed import from_installed

            if not from_installed(fn):
                marker.parent.mkdir(parents=True, exist_ok=True)
                marker.touch()
            done[0] = True
        return out

    call.__wrapped__ = fn
    return call


def _specialized_engine(module, ncp: int) -> dict:
    """The engine compiled for one curve's kernels (cached per module in this process).

    Each engine function is compiled from its own code with its calls bound to its
    compiled siblings and the global ``BOUND_KERNELS`` set to the curve's compiled
    kernels as a compile-time constant (:mod:`~symvib.numeric.engine.static`), so
    numba inlines them.  The entry points get a name of their own per
    curve (module name and input hash): numba's disk cache is keyed by that name and
    the argument types, so each curve's compiled engine is found again by later
    processes, and a regenerated module (a new input hash) is compiled anew.
    """
    cached = getattr(module, "_symvib_specialized_engine", None)
    if cached is not None:
        return cached
    from symvib.numeric.engine.static import StaticKernels
    from symvib.numeric.kernels import cache_dir

    tag = curve_tag(module)
    cache = _cacheable(module)
    options = {name: {"cache": cache, **ERRORS} for name in BOUND_ENTRIES}
    # Threads of Python over blocks of scenes (threaded_sweep), not numba's parallel loop (prange):
    # that costs about 3 s more of compile (the parfor passes) for the same sweep speed.
    options["sweep_bound"] = {"cache": cache, "nogil": True, **ERRORS}
    options.update({name: {"inline": "always", **INNER}
                    for name in ("simulate_scene", "sample_scene", "sweep_block", *HOT_INLINE, *loop.RUN_STEPS,
                                 *timing.QUAD_STEPS)})
    options.update({name: {"_nrt": False, **INNER} for name in NO_REFCOUNT})
    names = {"params_of": _params_of(ncp),
             "BOUND_KERNELS": StaticKernels(tag, Kernels(*compiled_kernels(module, ncp)))}
    compiled = compiled_functions(ENGINE_MODULES, lambda n: n != "params_of", names=names, options=options,
                                   default=INNER,
                                   qualnames={name: f"{name}__{tag}" for name in BOUND_ENTRIES})
    if cache:   # read an engine compiled at install time first (engine/installed.py)
        from symvib.numeric.engine import installed

        for name in BOUND_ENTRIES:
            installed.attach(compiled[name], module)
    flush_if_stale([compiled[name] for name in BOUND_ENTRIES],
                    cache_dir() / "engines" / f"engine-{engine_digest()}-{tag}")
    module._symvib_specialized_engine = compiled
    return compiled


def guided_blocks(n: int, threads: int):
    """``(start, stop)`` of the blocks a sweep of ``n`` scenes on ``threads`` threads takes, in order:
    :data:`SWEEP_SHARE`-th of the scenes left per thread, at least :data:`SWEEP_GRAIN`."""
    start = 0
    while start < n:
        stop = min(n, start + max(SWEEP_GRAIN, (n - start) // (SWEEP_SHARE * threads)))
        yield start, stop
        start = stop


def own_rules(R: Rules) -> Rules:
    """A copy of the rules ``R`` whose arrays share nothing with ``R``'s (for one thread of a sweep)."""
    import numpy as np

    return Rules(*(np.array(v, copy=True) if isinstance(v, np.ndarray) else v for v in R))


def threaded_sweep(block):
    """A sweep ``(rows, cp_rows, R, max_log) -> (summary, logs)`` that runs the compiled
    ``block(rows, cp_rows, R, max_log, out, logs, start, stop)`` (which releases the GIL)
    on ``numba.get_num_threads()`` threads.

    Each thread takes the next of the :func:`guided_blocks` (the scenes of a grid differ in
    cost: a row of fast scenes makes many events, so fixed shares would leave a thread idle).
    """
    import threading
    from concurrent.futures import ThreadPoolExecutor

    import numba

    def sweep(rows, cp_rows, R, max_log):
        n = rows.shape[0]
        out, logs = loop.sweep_arrays(n, max_log)
        threads = max(1, min(numba.get_num_threads(), -(-n // SWEEP_GRAIN)))
        own = threading.local()

        def run(span):
            # Each thread its own copy of the rules: the compiled engine counts references to
            # them atomically, and two cores counting on one array's count take turns.
            if not hasattr(own, "R"):
                own.R = R if threads == 1 else own_rules(R)
            block(rows, cp_rows, own.R, max_log, out, logs, *span)

        if threads == 1:
            for span in guided_blocks(n, 1):
                run(span)
        else:
            with ThreadPoolExecutor(threads) as pool:
                for _ in pool.map(run, guided_blocks(n, threads)):  # re-raises a block's error
                    pass
        return out, logs

    sweep.__wrapped__ = block
    return sweep
