"""symvib: vibro-impact dynamics of a heavy particle on rough curves.

Two wings meet only at the code generator:

* symbolic (SymPy): :mod:`symvib.curve`, :mod:`symvib.shapes`,
  :mod:`symvib.integrals`, :mod:`symvib.derive`, :mod:`symvib.audit`;
* numeric (NumPy only): generated kernels, the driver, sweeps.

``import symvib`` imports neither SymPy nor NumPy; the names below load their
module on first use.

>>> import symvib
>>> symvib.derive("circle").eom(+1)
Eq(mu*phidot**2 + phiddot + g*(mu*cos(phi) + sin(phi))/R, 0)
"""
from __future__ import annotations

import importlib
import sys
import types

__version__ = "0.1.0"

_LAZY = {
    "derive": "symvib.derive",
    "graph": "symvib.curve",
    "parametric": "symvib.curve",
    "shape": "symvib.shapes",
    "CATALOGUE": "symvib.shapes",
    "audit": "symvib.audit",
}

__all__ = sorted(_LAZY)


def __getattr__(name: str):
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'symvib' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_LAZY))


class _Package(types.ModuleType):
    """The package module, keeping ``derive`` and ``audit`` the functions.

    Importing a submodule binds it on its package (``symvib.derive = <module>``);
    where the submodule exports a function of its own name, the package binds
    that function instead, so ``from symvib import derive`` gives the function
    whichever modules were imported before. The modules stay importable as
    ``from symvib.derive import Derivation``.
    """

    def __setattr__(self, name, value):
        if (isinstance(value, types.ModuleType) and _LAZY.get(name) == value.__name__
                and hasattr(value, name)):
            value = getattr(value, name)
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package
