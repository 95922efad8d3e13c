"""The kernels as a numba structure, for the compiled engine (imports numba).

:class:`KernelsType` is a numba ``StructRef`` with one first-class function
field per kernel of :data:`~symvib.numeric.engine.state.KERNEL_INTERFACE`
(the fields of :class:`~symvib.numeric.engine.state.Kernels`), so the engine's
code ``K.F_p(q, mu, *cp)`` reads the same on both backends.  A call of the
compiled engine passes one pointer to the structure: the kernels' function
pointers are taken once per curve (:func:`kernels_box`), not at every call, and
the engine compiled for the type is cached on disk like any numba function.
"""
from __future__ import annotations

from functools import cache

import numba
from numba import types as nt
from numba.experimental import structref

from symvib.numeric.engine.state import Kernels

__all__ = ["KernelsType", "KernelsBox", "kernels_type", "kernels_box"]


@structref.register
class KernelsType(nt.StructRef):
    """numba type of the kernel structure (fields: :data:`KERNEL_INTERFACE`)."""

    def preprocess_fields(self, fields):
        return tuple((name, nt.unliteral(t)) for name, t in fields)


class KernelsBox(structref.StructRefProxy):
    """A curve's compiled kernels as one numba structure."""


structref.define_proxy(KernelsBox, KernelsType, list(Kernels._fields))


def kernels_type(signatures: dict) -> KernelsType:
    """The structure's type for the kernels' signatures (by field name)."""
    return KernelsType([(name, nt.FunctionType(signatures[name])) for name in Kernels._fields])


@cache
def _maker(signatures_key: tuple):
    signatures = dict(signatures_key)

    def make(F_p, F_m, dF_p, dF_m, ddF_p, ddF_m, node_p, node_m, z, h, dx, dz, alpha, kappa, N_w, q_scale, domain):
        return KernelsBox(F_p, F_m, dF_p, dF_m, ddF_p, ddF_m, node_p, node_m, z, h, dx, dz, alpha, kappa, N_w,
                          q_scale, domain)

    # The maker names the fields of the interface, in their order (a new kernel is added here too).
    if make.__code__.co_varnames[:make.__code__.co_argcount] != Kernels._fields:
        raise RuntimeError(f"compiled.make takes {make.__code__.co_varnames}, the interface is {Kernels._fields}")

    argtypes = tuple(nt.FunctionType(signatures[name]) for name in Kernels._fields)
    return numba.njit(argtypes, cache=True)(make)


def kernels_box(dispatchers: tuple, signatures: dict) -> KernelsBox:
    """The compiled kernels (in :class:`Kernels` field order) as one structure."""
    return _maker(tuple(signatures.items()))(*dispatchers)
