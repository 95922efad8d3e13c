"""Load generated kernel modules (numeric wing: no SymPy).

* A catalogue shape's module comes from ``generated/`` (installed as
  ``symvib.generated``).
* A user curve (its defining data: the same fields as a
  :class:`~symvib.shapes.Shape`) is looked up by its input hash in the cache
  folder (``$SYMVIB_CACHE``, default ``~/.cache/symvib/kernels``); only when it
  is missing is the code generator imported, which imports SymPy, and the
  module is written there once, atomically (checked and imported before it is
  renamed into place).

Before any module runs, its text is read once and checked (:func:`check_text`):
the body digest on its first line, the ``INPUT_HASH`` of the curve it is
loaded for, and a whitelist of syntax (:func:`verify_text`); then that same
text is executed.  A cached module that fails is regenerated; a module of
``generated/`` that fails is refused (run ``symvib generate``).  The digest
tells damage and edits; only the whitelist keeps code from running, since a
tamperer can recompute a digest.

Examples
--------
>>> k = load("circle")
>>> k.COORDINATE, k.PARAMS
('phi', ('R',))
>>> float(k.h(0.3, 0.5))
0.5
"""
from __future__ import annotations

import builtins
import hashlib
import importlib.util
import os
import re
import sys
import warnings
from pathlib import Path

from symvib import provenance
from symvib.shapes import CATALOGUE, Shape

__all__ = ["load", "load_generated", "generated_dir", "cache_dir", "check_text", "verify_text", "check_interface",
           "KernelError", "DIGEST_PREFIX"]

#: Environment variable naming the cache folder for user curves.
CACHE_ENV = "SYMVIB_CACHE"


class KernelError(RuntimeError):
    """A kernel module is missing or does not match its inputs."""


#: First line of every generated module up to its body's SHA-256 (kernel modules; the
#: Gauss-Legendre table has its own prefix, :data:`symvib.codegen.gauss.TABLE_PREFIX`).
DIGEST_PREFIX = "# symvib generated kernel module; body sha256: "
_DIGEST_LINE = re.compile(r"# symvib generated [^\n]*; body sha256: ([0-9a-f]{64})")
_INPUT_HASH_LINE = re.compile(r"^INPUT_HASH = '([0-9a-f]{64})'$", re.M)

#: Statement and expression nodes a generated module may contain (:func:`verify_text`).  No
#: conditional (``IfExp``, ``If``) and no comparison (``Compare``): the generator decides every
#: ``Piecewise`` symbolically (:func:`symvib.symbolic.curve.generic_branch`) and writes none.
ALLOWED_NODES = frozenset({
    "Module", "FunctionDef", "arguments", "arg", "Return", "Assign", "AugAssign", "For", "Expr", "Import",
    "alias", "BinOp", "UnaryOp", "Add", "Sub", "Mult", "Div", "Pow", "USub", "UAdd", "Call", "keyword",
    "Name", "Constant", "Tuple", "List", "Dict", "Subscript", "Slice", "Starred", "ListComp",
    "comprehension", "Attribute", "Load", "Store",
})
#: Statements allowed at module level (the others only run when a kernel is called).
MODULE_STATEMENTS = frozenset({"FunctionDef", "Assign", "Import", "Expr"})
#: Modules a generated module may import (``import math``, ``import numpy``, nothing else).
ALLOWED_IMPORTS = frozenset({"math", "numpy"})
#: Builtins a generated module may name; every other builtin (open, eval, __import__, ...) is refused.
SAFE_BUILTINS = frozenset({"float", "int", "abs", "max", "min", "range", "zip", "len", "round"})
#: NumPy attributes besides its ufuncs (which do arithmetic only) a generated module may use.
NUMPY_ATTRIBUTES = frozenset({
    "pi", "e", "inf", "nan", "arange", "array", "asarray", "broadcast", "broadcast_to", "max", "min", "ones",
    "zeros", "sum", "amax", "amin", "float64",
})
#: Attributes of values (arrays) a generated module may read.
VALUE_ATTRIBUTES = frozenset({"shape", "size"})


def verify_text(text: str, origin) -> None:
    """Check the text of a generated module before it is imported or executed.

    The text must parse, and every node of its syntax tree must be one a
    generator writes: definitions, assignments, arithmetic, calls of the
    module's own functions, of :data:`SAFE_BUILTINS`, of :mod:`math` and of
    NumPy's ufuncs and :data:`NUMPY_ATTRIBUTES`; docstrings as the only bare
    expressions; ``import math`` / ``import numpy`` as the only imports; no
    name or attribute starting with ``__``.  This whitelist keeps a module that
    was edited or generated wrong from running code; the digest
    (:func:`check_digest`) tells that it changed.

    Parameters
    ----------
    text : str
        The module's source.
    origin : str or Path
        The file (named in the error).

    Raises
    ------
    KernelError
        Naming ``origin``, the line and the first node not allowed.
    """
    import ast

    import numpy

    try:
        tree = ast.parse(text, filename=str(origin))
    except (SyntaxError, ValueError) as err:
        raise KernelError(f"{origin}: not valid Python ({err.msg if isinstance(err, SyntaxError) else err}, "
                          f"line {getattr(err, 'lineno', '?')}); regenerate it") from None

    def refuse(node, why):
        raise KernelError(f"{origin}: line {getattr(node, 'lineno', '?')}: {why} "
                          f"({ast.unparse(node)[:80]!r}) is not allowed in a generated module; regenerate it")

    for node in tree.body:
        kind = type(node).__name__
        if kind not in MODULE_STATEMENTS:
            refuse(node, f"a module-level {kind}")
    docstrings = {id(n.body[0]) for n in [tree, *ast.walk(tree)] if isinstance(n, (ast.Module, ast.FunctionDef))
                  and n.body and isinstance(n.body[0], ast.Expr)}
    for node in ast.walk(tree):
        kind = type(node).__name__
        if kind not in ALLOWED_NODES:
            refuse(node, f"a {kind} node")
        if isinstance(node, ast.Expr) and not (id(node) in docstrings and isinstance(node.value, ast.Constant)
                                               and isinstance(node.value.value, str)):
            refuse(node, "an expression statement other than a docstring")
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name not in ALLOWED_IMPORTS or alias.asname:
                    refuse(node, f"import of {alias.name!r}")
        elif isinstance(node, ast.FunctionDef):
            if node.decorator_list or node.returns or node.name.startswith("__"):
                refuse(node, f"function {node.name!r} with decorators, annotations or a dunder name")
        elif isinstance(node, ast.arg):
            if node.annotation is not None or node.arg.startswith("__") or node.arg in _FIXED_NAMES:
                refuse(node, f"argument {node.arg!r}")
        elif isinstance(node, ast.Name):
            if node.id.startswith("__") or hasattr(builtins, node.id) and node.id not in SAFE_BUILTINS:
                refuse(node, f"the name {node.id!r}")
            if not isinstance(node.ctx, ast.Load) and node.id in _FIXED_NAMES:
                refuse(node, f"assigning to {node.id!r}")
        elif isinstance(node, ast.Attribute) and not _attribute_allowed(node, numpy):
            refuse(node, f"the attribute {node.attr!r}")
    check_interface(tree, origin)


def check_interface(tree, origin) -> None:
    """Check that a curve's generated module provides the engine's kernels with the declared arguments.

    A curve's module (one that assigns ``PARAMS`` or defines any kernel; the
    Gauss-rule module does neither) must define, for every entry of
    :data:`symvib.numeric.engine.state.KERNEL_INTERFACE`, the function taking the
    declared leading arguments followed by the curve's parameters (its ``PARAMS``).

    Raises
    ------
    KernelError
        Naming ``origin`` and the first kernel missing or with other arguments.
    """
    import ast

    from symvib.numeric.engine.state import KERNEL_INTERFACE

    params, functions, has_params = None, {}, False
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            functions[node.name] = tuple(a.arg for a in node.args.args)
        elif isinstance(node, ast.Assign) and len(node.targets) == 1 and isinstance(node.targets[0], ast.Name):
            if node.targets[0].id == "PARAMS":
                has_params = True
                try:
                    params = tuple(ast.literal_eval(node.value))
                except ValueError:
                    params = None
    if not has_params and not {f for f, _, _ in KERNEL_INTERFACE.values()} & set(functions):
        return  # not a curve's module (the Gauss rules)
    if params is None or not all(isinstance(p, str) for p in params):
        raise KernelError(f"{origin}: no PARAMS tuple of parameter names; regenerate it")
    for engine_name, (function, leading, _) in KERNEL_INTERFACE.items():
        want = tuple(leading) + params
        if functions.get(function) != want:
            got = "missing" if function not in functions else f"takes {functions[function]}"
            raise KernelError(f"{origin}: kernel {function} (the engine's {engine_name}) must take {want}, "
                              f"{got}; regenerate it")


def check_text(text: str, origin, input_hash: str | None = None) -> None:
    """Check a generated module's text: its body digest, its inputs' hash, then :func:`verify_text`.

    Parameters
    ----------
    text : str
        The whole module, first line ``# symvib generated ...; body sha256: <hex>``.
    origin : str or Path
        The file (named in the error).
    input_hash : str, optional
        The ``INPUT_HASH`` the module must record (the curve it is loaded for).

    Raises
    ------
    KernelError
        When the digest does not match the body (edited, truncated, damaged), the
        input hash differs, or the whitelist refuses the text.
    """
    first, _, body = text.partition("\n")
    match = _DIGEST_LINE.fullmatch(first)
    if match is None:
        raise KernelError(f"{origin}: no body digest on the first line (not a generated module, or damaged)")
    if match.group(1) != hashlib.sha256(body.encode("utf-8", "surrogatepass")).hexdigest():
        raise KernelError(f"{origin}: body digest mismatch (edited, truncated or damaged)")
    if input_hash is not None:
        found = _INPUT_HASH_LINE.search(body)
        if found is None or found.group(1) != input_hash:
            raise KernelError(f"{origin}: made from other inputs (INPUT_HASH differs from the curve's)")
    verify_text(text, origin)


#: Names a generated module may use but never rebind.
_FIXED_NAMES = ALLOWED_IMPORTS | SAFE_BUILTINS


def _attribute_allowed(node, numpy) -> bool:
    """``math.<public name>``, ``numpy.<ufunc or NUMPY_ATTRIBUTES>``, or reading ``.shape``/``.size``."""
    import ast
    import math

    if node.attr.startswith("_"):
        return False
    base = node.value.id if isinstance(node.value, ast.Name) else None
    if base == "math":
        return hasattr(math, node.attr)
    if base == "numpy":
        return isinstance(getattr(numpy, node.attr, None), numpy.ufunc) or node.attr in NUMPY_ATTRIBUTES
    return node.attr in VALUE_ATTRIBUTES and isinstance(node.ctx, ast.Load)


def generated_dir() -> Path:
    """The folder of the catalogue's generated modules (installed or in the checkout)."""
    try:
        spec = importlib.util.find_spec("symvib.generated")
    except ImportError:
        spec = None
    locations = [Path(p) for p in (spec.submodule_search_locations or [])] if spec is not None else []
    # A source checkout imported from its folder (pytest's rootdir on sys.path): generated/
    # is beside the package, installed as symvib.generated by pyproject's package-dir.
    locations.append(Path(__file__).resolve().parents[2] / "generated")
    for candidate in locations:
        if (candidate / "__init__.py").exists():
            return candidate
    raise KernelError("no generated/ folder found next to the symvib package; run `symvib generate`")


def cache_dir() -> Path:
    """Folder where user-curve modules are generated and cached."""
    root = os.environ.get(CACHE_ENV)
    return Path(root) if root else Path.home() / ".cache" / "symvib" / "kernels"


def module_name(name: str) -> str:
    """A module (and cache file) name for a curve name: ASCII letters, digits and ``_`` only
    (:func:`symvib.paths.safe_stem`, so a hostile or very long name stays one short file
    name inside the cache folder, and distinct names stay distinct)."""
    import re

    from symvib.paths import safe_stem

    out = re.sub(r"[^A-Za-z0-9_]", "_", safe_stem(name))
    return out if out[:1].isalpha() else "c_" + out


def _import(path: Path, name: str, *, generated: bool = True):
    """Import the module ``name`` from ``path`` after :func:`check_text` of the text it executes.

    A module of ``generated/`` that fails the check is refused (run ``symvib
    generate``); for the others the error is left to the caller.
    """
    key = f"symvib.generated.{name}"
    cached = sys.modules.get(key)
    if cached is not None and getattr(cached, "__file__", None) == str(path):
        return cached
    text = path.read_text(encoding="utf-8")
    try:
        check_text(text, path)
    except KernelError as err:
        raise KernelError(f"{err}; run `symvib generate`" if generated else str(err)) from None
    return _exec(text, path, name)


def _exec(text: str, path: Path, name: str):
    """The module ``name`` made by executing ``text`` (already checked) as the file ``path``.

    What runs is the string that was checked, never a second read of the file.
    """
    key = f"symvib.generated.{name}"
    spec = importlib.util.spec_from_loader(key, loader=None, origin=str(path))
    module = importlib.util.module_from_spec(spec)
    module.__file__ = str(path)
    exec(compile(text, str(path), "exec"), module.__dict__)  # noqa: S102 - checked by the caller
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
    if curve.in_catalogue:
        module = load_generated(module_name(curve.module))
        path = module.__file__
        if check and module.INPUT_HASH != want:
            warnings.warn(f"{path} is stale (the shape or the generator changed); run `symvib generate`",
                          stacklevel=2)
        return module
    name = f"{module_name(curve.module)}_{want[:16]}"
    path = cache_dir() / f"{name}.py"
    key = f"symvib.generated.{name}"
    if key in sys.modules and getattr(sys.modules[key], "__file__", None) == str(path):
        return sys.modules[key]
    if path.exists():
        text = path.read_text(encoding="utf-8", errors="replace")
        try:
            check_text(text, path, want)
            return _exec(text, path, name)
        except KernelError as err:
            # Tampered, truncated or from a broken generator: made again below.
            warnings.warn(f"{err}; regenerating it", stacklevel=3)
            path.unlink(missing_ok=True)
    return _generate(curve, source, want, path, name)


def _generate(curve: Shape, source: dict, want: str, path: Path, name: str):
    """Generate a user curve's module atomically: into a temporary file, checked and
    imported from the text written, and only then renamed into the cache; any
    failure leaves nothing in the cache."""
    from symvib.codegen import generate as codegen  # the bridge: imports SymPy, only for a curve not generated yet

    tmp = None
    stem = f"{name}.{os.getpid()}.tmp"
    try:
        try:
            tmp = codegen.generate(curve, cache_dir(), name=stem, source=source)
        except KernelError as err:  # name the module the user asked for, not the temporary file
            raise KernelError(str(err).replace(str(cache_dir() / f"{stem}.py"), str(path))) from None
        text = tmp.read_text(encoding="utf-8")
        check_text(text, path, want)
        try:
            module = _exec(text, path, name)
        except Exception as err:  # noqa: BLE001 - any failure of a fresh module is the generator's
            sys.modules.pop(f"symvib.generated.{name}", None)
            raise KernelError(f"{path}: the generated module does not import "
                              f"({type(err).__name__}: {err}); nothing was cached") from None
        tmp.replace(path)
        tmp = None
        return module
    finally:
        if tmp is not None:
            tmp.unlink(missing_ok=True)
