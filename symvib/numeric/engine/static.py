"""The kernels of one curve as a compile-time constant of the compiled engine (imports numba).

An engine specialized to a curve (:func:`symvib.numeric.engine.bind.bind`)
receives its kernels as ``K``, as the plain engine does, but ``K``'s numba type
is :class:`StaticKernelsType`: its fields are the kernels' dispatcher types, so
``K.F_p(q, mu, *cp)`` resolves at compile time (numba inlines the kernel) and
``K`` itself carries no data at run time.  The type is named by the curve's
module and input hash, and its constant holds no address, so numba can cache
the compiled engine on disk (a tuple of dispatchers as a constant could not be).

Examples
--------
>>> t = StaticKernelsType("demo", ())
>>> t.name
'StaticKernels(demo)'
"""
from __future__ import annotations

from numba.core import cgutils, types
from numba.core.extending import lower_getattr_generic, models, register_model, typeof_impl
from numba.core.imputils import lower_constant
from numba.core.typing.templates import AttributeTemplate, infer_getattr

__all__ = ["StaticKernelsType", "StaticKernels"]


class StaticKernelsType(types.Type):
    """numba type of a curve's kernels fixed at compile time (``fields``: name -> dispatcher type)."""

    def __init__(self, tag: str, fields: tuple):
        self.tag = tag
        self.fields = dict(fields)
        super().__init__(name=f"StaticKernels({tag})")

    @property
    def key(self):
        return self.tag


class StaticKernels:
    """A curve's compiled kernels (a :class:`~symvib.numeric.engine.state.Kernels` of
    dispatchers) with the numba type that fixes them at compile time."""

    def __init__(self, tag: str, kernels):
        self.kernels = kernels
        self.numba_type = StaticKernelsType(
            tag, tuple((name, types.Dispatcher(d)) for name, d in zip(kernels._fields, kernels)))


@typeof_impl.register(StaticKernels)
def _typeof_static(val, c):
    return val.numba_type


register_model(StaticKernelsType)(models.OpaqueModel)


@lower_constant(StaticKernelsType)
def _constant_static(context, builder, typ, pyval):
    return cgutils.get_null_value(context.get_value_type(typ))


@infer_getattr
class _StaticKernelsAttributes(AttributeTemplate):
    key = StaticKernelsType

    def generic_resolve(self, typ, attr):
        return typ.fields.get(attr)


@lower_getattr_generic(StaticKernelsType)
def _getattr_static(context, builder, typ, value, attr):
    return cgutils.get_null_value(context.get_value_type(typ.fields[attr]))
