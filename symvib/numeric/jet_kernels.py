"""Load a curve's jets module, the derivatives exact sensitivities need beyond its kernels (numeric wing: no SymPy).

The jets module of a curve (:mod:`symvib.codegen.jets`: ``kappa'`` and the derivatives with respect to
the curve's parameters; physics.md, "Sensitivities" 8 and 9) is loaded only when a run is
differentiated and needs it (a sign change of ``N``, or a curve parameter in ``wrt``): a plain run
never reads it.

* A catalogue shape's comes from ``generated/jets/`` (written by ``symvib generate``).
* A user curve's is looked up by its jets hash (:func:`symvib.provenance.jets_hash`) in the kernel
  cache (``$SYMVIB_CACHE``), beside the curve's kernels; when it is missing, the generator
  registered by the prepare step (:func:`register_generator`, called by :mod:`symvib.prepare`,
  which the numeric wing never imports) makes its text, which is checked, executed, then cached.

Like a kernel module, its text is checked before it runs (:func:`symvib.kernelformat.check_text`:
its body digest, its ``INPUT_HASH``, the whitelist of a generated module).

Examples
--------
>>> j = load_jets("parabola")
>>> j.PARAM_JETS, j.JET3
({'p': 0}, ('d3x', 'd3z', 'dkappa'))
"""
from __future__ import annotations

from symvib import provenance
from symvib.kernelformat import KernelError, check_text
from symvib.numeric import kernels as _kernels
from symvib.shapes import CATALOGUE, Shape

__all__ = ["load_jets", "register_generator", "JETS_FOLDER", "JETS_SUFFIX"]

#: Folder of the catalogue's jets modules inside ``generated/`` (as :data:`symvib.codegen.jets.JETS_FOLDER`).
JETS_FOLDER = "jets"
#: What a user curve's jets module adds to its kernel module's cache name.
JETS_SUFFIX = "_jets"

#: ``generate(shape, source, origin) -> str``: the text of a user curve's jets module (set by the
#: prepare step, above both wings).
_GENERATOR = []
#: Jets modules loaded in this process, by shape data (and a user curve's cache folder).
_LOADED: dict = {}


def register_generator(generate) -> None:
    """Make ``generate(shape, source, origin) -> str`` the maker of missing user-curve jets modules
    (:mod:`symvib.prepare` registers the code generator's when it is imported)."""
    _GENERATOR[:] = [generate]


def load_jets(curve, *, generate=None):
    """The jets module of ``curve`` (a catalogue name, a :class:`~symvib.shapes.Shape` or its data).

    Parameters
    ----------
    curve : str, Shape or dict
    generate : callable, optional
        As :func:`symvib.numeric.kernels.load`'s; default: the registered one (:func:`register_generator`).

    Raises
    ------
    KernelError
        A catalogue module missing, edited or stale (run ``symvib generate``); a user curve's
        missing with no generator to make it.
    """
    import os

    if isinstance(curve, str):
        if curve not in CATALOGUE:
            raise KeyError(f"unknown shape {curve!r}; known shapes: {', '.join(sorted(CATALOGUE))}")
        curve = CATALOGUE[curve]
    if isinstance(curve, dict):
        curve = Shape(**curve)
    key = repr(curve.source()) if curve.in_catalogue else (repr(curve.source()),
                                                            os.environ.get(_kernels.CACHE_ENV))
    module = _LOADED.get(key)
    if module is None:
        module = _LOADED[key] = _load(curve, generate or (_GENERATOR[0] if _GENERATOR else None))
    return module


def _load(curve: Shape, generate):
    source = curve.source()
    want = provenance.jets_hash(source)
    stem = _kernels.module_name(curve.module)
    if curve.in_catalogue:
        path = _kernels.generated_dir() / JETS_FOLDER / f"{stem}.py"
        if not path.exists():
            raise KernelError(f"{path} is missing; run `symvib generate`")
        text = path.read_text(encoding="utf-8")
        try:
            check_text(text, path, want)
        except KernelError as err:
            raise KernelError(f"{err}; run `symvib generate`") from None
        return _kernels._exec(text, path, f"jets_{stem}")     # the text checked, not a second read
    name = f"{stem}_{want[:16]}{JETS_SUFFIX}"
    folder = _kernels.cache_dir()
    path = folder / f"{name}.py"
    module = _kernels.read_cached(folder, name, want)
    if module is not None:
        return module
    if generate is None:
        raise KernelError(f"curve {curve.name!r} has no generated jets in {folder} (symvib.prepare.load_jets "
                          "generates them)")
    return _kernels.cache_generated(generate(curve, source, path), folder, name, want, "jets module")
