"""Load generated kernel modules (numeric wing: no SymPy).

* A catalogue shape's module comes from ``generated/`` (installed as
  ``symvib.generated``).
* A user curve (its defining data: the same fields as a
  :class:`~symvib.shapes.Shape`) is looked up by its input hash in the cache
  folder (``$SYMVIB_CACHE``, default ``~/.cache/symvib/kernels``); only when it
  is missing is the code generator imported, which imports SymPy, and the
  module is written there once.

Examples
--------
>>> k = load("circle")
>>> k.COORDINATE, k.PARAMS
('phi', ('R',))
>>> float(k.h(0.3, 0.5))
0.5
"""
from __future__ import annotations

import importlib.util
import os
import sys
import warnings
from pathlib import Path

from . import provenance
from .shapes import CATALOGUE, Shape

__all__ = ["load", "load_generated", "generated_dir", "cache_dir", "KernelError"]

#: Environment variable naming the cache folder for user curves.
CACHE_ENV = "SYMVIB_CACHE"


class KernelError(RuntimeError):
    """A kernel module is missing or does not match its inputs."""


def generated_dir() -> Path:
    """The folder of the catalogue's generated modules (installed or in the checkout)."""
    here = Path(__file__).resolve().parent
    for candidate in (here / "generated", here.parent / "generated"):
        if (candidate / "__init__.py").exists():
            return candidate
    raise KernelError("no generated/ folder found next to the symvib package; run `symvib generate`")


def cache_dir() -> Path:
    """Folder where user-curve modules are generated and cached."""
    root = os.environ.get(CACHE_ENV)
    return Path(root) if root else Path.home() / ".cache" / "symvib" / "kernels"


def _module_name(name: str) -> str:
    import re

    out = re.sub(r"\W", "_", name)
    return out if out[:1].isalpha() else "c_" + out


def _import(path: Path, name: str):
    key = f"symvib.generated.{name}"
    cached = sys.modules.get(key)
    if cached is not None and getattr(cached, "__file__", None) == str(path):
        return cached
    spec = importlib.util.spec_from_file_location(key, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    sys.modules[key] = module
    return module


def load_generated(name: str):
    """The module ``name`` of the generated folder (installed or in the checkout).

    Examples
    --------
    >>> sorted(load_generated("gauss_rules").RULES)[:3]
    [1, 2, 3]
    """
    path = generated_dir() / f"{name}.py"
    if not path.exists():
        raise KernelError(f"{path} is missing; run `symvib generate`")
    return _import(path, name)


def load(curve, *, check: bool = True):
    """The kernel module of ``curve``.

    Parameters
    ----------
    curve : str, Shape or dict
        A catalogue name, a :class:`~symvib.shapes.Shape`, or the defining data
        of a user curve (``kind``, ``z``, ``x``, ``q``, ``params``, ...).
    check : bool
        Warn when a catalogue module's input hash differs from the current one
        (the shape or the generator changed since it was generated).

    Returns
    -------
    module
        With the kernels listed in its ``SIGNATURES``.
    """
    if isinstance(curve, str):
        if curve not in CATALOGUE:
            raise KeyError(f"unknown shape {curve!r}; known shapes: {', '.join(sorted(CATALOGUE))}")
        curve = CATALOGUE[curve]
    if isinstance(curve, dict):
        curve = Shape(**curve)
    if not isinstance(curve, Shape):
        raise TypeError(f"load() needs a shape name, a Shape or its data, not {type(curve).__name__}")
    key = repr(curve.source())
    module = _LOADED.get(key)
    if module is not None:
        return module
    module = _load(curve, check)
    _LOADED[key] = module
    return module


#: Modules already loaded in this process, by their shape's defining data.
_LOADED: dict = {}


def _load(curve: Shape, check: bool):
    source = curve.source()
    want = provenance.input_hash(source)
    if CATALOGUE.get(curve.name) == curve:
        module = load_generated(_module_name(curve.module))
        path = module.__file__
        if check and module.INPUT_HASH != want:
            warnings.warn(f"{path} is stale (the shape or the generator changed); run `symvib generate`",
                          stacklevel=2)
        return module
    name = f"{_module_name(curve.module)}_{want[:16]}"
    path = cache_dir() / f"{name}.py"
    if not path.exists():
        from . import codegen  # the bridge: imports SymPy, only for a curve never generated before

        tmp = codegen.generate(curve, cache_dir(), name=name + ".tmp", source=source)
        tmp.replace(path)
    return _import(path, name)
