"""The engine's functions rebuilt over globals of a binding's choosing (both bindings use it).

The engine (:mod:`~symvib.numeric.engine.laws`, ``roots``, ``anchor``, ``scan``,
``timing``, ``loop``) is written once as plain functions.  A binding runs that
same code with some globals replaced: the plain engine
(:mod:`~symvib.numeric.engine.plain`) swaps in fast Python primitives, the
compiled one (:mod:`~symvib.numeric.engine.bind`) numba's static-length
``params_of`` and the curve's kernels.  :func:`rebound_functions` does that for
both, so neither binding imports the other to reach it.

Examples
--------
>>> fns = rebound_functions(ENGINE_MODULES, lambda name: name == "rest")
>>> sorted(fns), fns["rest"].__module__
(['rest'], 'symvib.numeric.engine.laws')
"""
from __future__ import annotations

import types

from symvib.numeric.engine import anchor, laws, loop, roots, scan, timing

__all__ = ["ENGINE_MODULES", "rebound_functions"]

#: The engine's modules, in import order.
ENGINE_MODULES = (laws, roots, anchor, scan, timing, loop)


def rebound_functions(modules, keep, make=None, names=None) -> dict:
    """The functions defined in ``modules`` whose names pass ``keep``, each rebuilt from its own
    code object by ``make(name, fn)`` (default: as it is), with a copy of its module's globals.

    In each copy, every such name is the rebuilt function (names must be unique across
    the modules), then ``names`` replace or add globals (numba's static-length
    ``params_of`` and the kernels; the plain engine's primitives).  No source text is
    pasted or executed: both backends run the engine's own code.
    """
    functions, spaces = {}, []
    for mod in modules:
        namespace = dict(vars(mod))
        spaces.append(namespace)
        for name, fn in vars(mod).items():
            if isinstance(fn, types.FunctionType) and fn.__module__ == mod.__name__ and keep(name):
                if name in functions:
                    raise RuntimeError(f"engine function {name!r} is defined twice ({mod.__name__})")
                new = types.FunctionType(fn.__code__, namespace, fn.__name__, fn.__defaults__, fn.__closure__)
                new.__qualname__, new.__module__, new.__doc__ = fn.__qualname__, fn.__module__, fn.__doc__
                functions[name] = make(name, new) if make else new
    for namespace in spaces:
        namespace.update(functions)
        namespace.update(names or {})
    return functions
