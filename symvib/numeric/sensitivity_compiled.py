"""The quadratures of exact sensitivities compiled by numba with the curve's kernels (physics.md,
"Sensitivities" 2, 5): the binding, and its cache on disk.

:func:`symvib.numeric.sensitivity_batch.time_derivatives` and
:func:`~symvib.numeric.sensitivity_batch.end_integrals` evaluate their Gauss levels with NumPy, for
all intervals of a run at once; on the paper's scenes that is a dozen intervals of 40-320 nodes a
level, where NumPy's cost per call outweighs the arithmetic.  The same levels are one compiled
loop per interval (:mod:`symvib.numeric.sensitivity_kernels`, the same numbers to rounding), the
curve's scalar kernels inlined as in the compiled engine (:mod:`symvib.numeric.engine.bind`: a
compile-time constant, :mod:`symvib.numeric.engine.static`); here they are compiled per curve
(:func:`quadratures`), cached on disk under the curve's module and input hash, and called as the
NumPy ones are (:class:`Quadratures`).  The NumPy path stays the reference and the path of every
other run: :func:`quadratures_for` gives the compiled one only for a run of the compiled engine
(whose user has waited for a compiler already), without curve parameters in ``wrt`` (then
``dF_s'/dp = dF_s'/dmu Dmu``), for a curve module on disk.

Examples
--------
>>> MARKED
('time_derivatives_kernel', 'end_integrals_kernel', 'slide_kernel', 'event_tangents')
"""
from __future__ import annotations

import hashlib
from functools import cache
from pathlib import Path

import numpy as np

from symvib.numeric import sensitivity_kernels
from symvib.numeric.sensitivity_batch import (
    ACCEPT,
    FIRST_PANELS,
    FIRST_PIECES,
    INNER_NODES,
    INTEGRAL_RTOL,
    MAX_PANELS,
    NODES,
    RTOL,
    gauss,
    theta_level,
)
from symvib.numeric.sensitivity_kernels import (
    BATCH_LEVELS,
    COMPILED,
    ENTRIES,
    LEVELS,
    SensitivityKernels,
    event_tangents_kernel,
)

__all__ = ["Quadratures", "quadratures_for", "quadratures", "level_tables", "MARKED", "compiled_marker",
           "compiled_on_disk", "event_tangents"]


@cache
def level_tables():
    """The ``theta`` levels of :func:`symvib.numeric.sensitivity_batch.theta_level` (1, 2, 4, ...,
    ``MAX_PANELS`` panels) as flat arrays: ``u``, ``1 - u``, weights, each level's nodes in the order
    they are integrated (the start's half by ``u``, then the end's by ``1 - u``: indices within the
    level), the number of the start's, and each level's first node."""
    parts = [theta_level(FIRST_PANELS << k) for k in range(LEVELS)]
    U = np.concatenate([p[0] for p in parts])
    Dd = np.concatenate([p[1] for p in parts])
    Wt = np.concatenate([p[2] for p in parts])
    order = np.concatenate([np.concatenate((p[3], p[4])) for p in parts]).astype(np.int64)
    n_start = np.array([len(p[3]) for p in parts], dtype=np.int64)
    offsets = np.concatenate(([0], np.cumsum([len(p[0]) for p in parts]))).astype(np.int64)
    xg, wg = (np.ascontiguousarray(v) for v in gauss(INNER_NODES))
    return U, Dd, Wt, order, n_start, offsets, xg, wg


class Quadratures:
    """A curve's compiled quadratures, called as the NumPy ones are (``c``: the run's
    :class:`~symvib.numeric.sensitivity_curve.CurveFunctions`, without curve parameters)."""

    def __init__(self, entries, cp):
        self._entries, self._cp = entries, tuple(float(v) for v in cp)

    def time_derivatives(self, c, ends):
        """:func:`symvib.numeric.sensitivity_batch.time_derivatives` (the same arguments and result)."""
        scalars = np.column_stack(
            [np.asarray(ends[name], dtype=float) for name in ("s", "q_a", "q_e", "G_a", "G_e", "f_a", "f_e")])
        return self.time_derivatives_arrays(c, scalars, np.stack([ends[name] for name in ("Dq_a", "Dq_e", "DG_a",
                                                                                           "DG_e")]))

    def time_derivatives_arrays(self, c, scalars, tangents):
        """:meth:`time_derivatives` of the intervals ``scalars`` (shape (M, 7): ``s, q_a, q_e, G_a, G_e, f_a,
        f_e``) with the tangents ``tangents`` (shape (4, M, P): ``Dq_a, Dq_e, DG_a, DG_e``)."""
        return self._entries["time_derivatives_kernel"](
            np.ascontiguousarray(scalars, dtype=float), np.ascontiguousarray(tangents, dtype=float), float(c.mu),
            float(c.g), np.ascontiguousarray(c.Dmu, dtype=float), bool(c.f_depends), self._cp, *level_tables(),
            BATCH_LEVELS, LEVELS, RTOL, ACCEPT)

    def slide(self, c, codes, q_at, at_values, w_a0, k, m, sigma_in, limiter, Dmu, Dk, Dq_a0, Dw_a0, chunk):
        """:func:`slide_kernel` for the run's curve ``c``."""
        return self._entries["slide_kernel"](
            codes, q_at, at_values, float(w_a0), float(k), float(c.mu), float(c.g), float(m), self._cp, sigma_in,
            limiter, np.array(Dmu, dtype=float), np.array(Dk, dtype=float), Dq_a0, Dw_a0, bool(c.f_depends),
            FIRST_PIECES, int(MAX_PANELS * NODES), INTEGRAL_RTOL, *level_tables(), BATCH_LEVELS, LEVELS, RTOL, ACCEPT,
            int(chunk))

    def end_integrals(self, c, s, anchor, D, max_pieces):
        """:func:`symvib.numeric.sensitivity_batch.end_integrals` (the same arguments and result)."""
        _, _, _, _, _, _, xg, wg = level_tables()
        values = self._entries["end_integrals_kernel"](
            float(s), np.ascontiguousarray(anchor, dtype=float), np.ascontiguousarray(D, dtype=float),
            FIRST_PIECES, int(max_pieces), float(c.mu), self._cp, xg, wg, INTEGRAL_RTOL)
        return values[:, None] * c.Dmu


def quadratures_for(result, kernels, c, *, compile: bool = False):
    """The compiled :class:`Quadratures` a differentiated run takes, or None (the NumPy path).

    Only for a run of the compiled engine (``result.stats["backend"] == "numba"``: a run of the plain
    engine never waits for a compiler), without curve parameters in ``wrt``, with numba installed and
    the curve's module on disk (a prepared view of it is compiled per process only: not worth it for
    the quadratures); and only where they are compiled already (in this process, or on disk:
    :func:`compiled_on_disk`) unless ``compile`` (a caller that differentiates many runs, a fit or a
    sweep's columns, for which the compile of a few seconds pays): one call never waits for it.
    """
    if result.stats.get("backend") != "numba" or c.has_curve_parameters or not getattr(kernels, "__file__", None):
        return None
    if not _numba_installed():
        return None
    if not (compile or getattr(kernels, "_symvib_sensitivity_quadratures", None) is not None
            or compiled_on_disk(kernels)):
        return None
    return Quadratures(quadratures(kernels), c._cp)


@cache
def _numba_installed() -> bool:
    """Whether numba can be imported (asked once per process)."""
    import importlib.util

    return importlib.util.find_spec("numba") is not None


#: The compiled functions whose disk-cache markers :func:`compiled_on_disk` asks for.
MARKED = (*ENTRIES, "event_tangents")


def compiled_marker(module, entry: str) -> Path:
    """The file that says ``entry`` (of :data:`MARKED`) is in numba's disk cache for ``module``'s curve
    (:func:`event_tangents`, which calls no kernel: for every curve)."""
    from symvib.numeric.engine.bind import curve_tag
    from symvib.numeric.kernels import cache_dir

    owner = "all" if entry == "event_tangents" else curve_tag(module)
    return cache_dir() / "engines" / f"compiled-sensitivity-{_digest()}-{owner}-{entry}"


def compiled_on_disk(module) -> bool:
    """Whether every compiled quadrature of ``module``'s curve was compiled before (and so loads from
    numba's disk cache in a new process instead of compiling)."""
    return all(compiled_marker(module, entry).exists() for entry in MARKED)



def _digest() -> str:
    """SHA-256 (hex, 20 digits) of the sources the compiled quadratures are built from (this module, the
    compiled functions', the static kernels' type, the batch module's constants), for flushing a stale
    disk cache."""
    import symvib.numeric.engine.static as static
    import symvib.numeric.sensitivity_batch as batch

    digest = hashlib.sha256()
    for origin in (__file__, sensitivity_kernels.__file__, static.__file__, batch.__file__):
        digest.update(Path(origin).read_bytes())
    return digest.hexdigest()[:20]


def quadratures(module) -> dict:
    """The compiled entry points (:data:`ENTRIES`) of a curve module's quadratures (compiled on first
    call and cached on disk under the module's name and input hash; kept on the module in this process)."""
    cached = getattr(module, "_symvib_sensitivity_quadratures", None)
    if cached is not None:
        return cached
    from symvib.numeric.engine.bind import (
        ERRORS,
        INNER,
        compiled_functions,
        compiled_kernels,
        curve_tag,
        flush_if_stale,
        kernel_signatures,
        marking,
    )
    from symvib.numeric.engine.static import StaticKernels
    from symvib.numeric.kernels import cache_dir

    ncp = len(module.PARAMS)
    engine_kernels = dict(zip(kernel_signatures(ncp), compiled_kernels(module, ncp)))
    extra = compiled_functions([module], lambda n: n.endswith("_scalar"),
                                options={n: {"cache": True, **ERRORS} for n in ("dalpha_scalar", "dh_scalar")},
                                default=ERRORS)
    geometry = kernel_signatures(ncp)["h"]
    for name in ("dalpha_scalar", "dh_scalar"):
        extra[name].compile(geometry)
    kernels = SensitivityKernels(
        **{name: engine_kernels[name] for name in ("dF_p", "dF_m", "ddF_p", "ddF_m", "alpha", "h", "dx", "dz")},
        dalpha=extra["dalpha_scalar"], dh=extra["dh_scalar"], N=engine_kernels["N_w"])
    tag = curve_tag(module)
    options = {name: {"cache": True, **ERRORS} for name in ENTRIES}
    compiled = compiled_functions([sensitivity_kernels], lambda n: n in COMPILED,
                                   names={"SK": StaticKernels(f"{tag}_sensitivity", kernels)}, options=options,
                                   default=INNER, qualnames={name: f"{name}__{tag}" for name in ENTRIES})
    compiled = {name: compiled[name] for name in ENTRIES}
    flush_if_stale(compiled.values(), cache_dir() / "engines" / f"sensitivity-{_digest()}-{tag}")
    compiled = {name: marking(fn, compiled_marker(module, name)) for name, fn in compiled.items()}
    if not compiled_on_disk(module):
        _compile_all(compiled, ncp)
    module._symvib_sensitivity_quadratures = compiled
    return compiled


def _compile_all(compiled, ncp: int) -> None:
    """Compile every entry of ``compiled`` (and :func:`event_tangents`) by a call on no interval, with the types
    of a real call: a run's sensitivities use :func:`slide_kernel`, a run with an event that needs the curve's jets
    the others, and a later process takes the compiled path only where all are on disk (:func:`compiled_on_disk`)."""
    cp, Dmu = (1.0,) * ncp, np.zeros(1)
    tables = level_tables()
    compiled["time_derivatives_kernel"](np.zeros((0, 7)), np.zeros((4, 0, 1)), 0.0, 1.0, Dmu, True, cp, *tables,
                                        BATCH_LEVELS, LEVELS, RTOL, ACCEPT)
    compiled["end_integrals_kernel"](1.0, np.zeros(0), np.zeros(0), FIRST_PIECES, int(MAX_PANELS * NODES), 0.0, cp,
                                     tables[6], tables[7], INTEGRAL_RTOL)
    compiled["slide_kernel"](np.zeros(0, dtype=np.int64), np.zeros(1), np.zeros((8, 1)), 0.0, 1.0, 0.0, 1.0, 1.0, cp,
                             np.zeros(0), np.zeros((0, 1)), Dmu, Dmu, Dmu, Dmu, True, FIRST_PIECES,
                             int(MAX_PANELS * NODES), INTEGRAL_RTOL, *tables, BATCH_LEVELS, LEVELS, RTOL, ACCEPT, 64)
    no = np.zeros(0, dtype=np.bool_)
    event_tangents()(no, no, no, np.zeros(0), np.zeros(0), np.zeros((0, 13)), np.zeros((0, 1)), np.zeros((0, 1)),
                     0.0, 1.0, 1.0, 1.0, Dmu, Dmu, Dmu, Dmu)


@cache
def event_tangents():
    """:func:`event_tangents_kernel` compiled (it calls no kernel of the curve: one compiled function for all
    curves, cached on disk)."""
    import numba

    from symvib.numeric.engine.bind import ERRORS, marking

    return marking(numba.njit(cache=True, **ERRORS)(event_tangents_kernel), compiled_marker(None, "event_tangents"))
