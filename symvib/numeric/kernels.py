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
import logging
import re
import sys
import warnings
from pathlib import Path

from symvib import cachetrust, provenance, safeio
from symvib.paths import UserPathError
from symvib.shapes import CATALOGUE, Shape

#: Progress of slow steps (a new curve's derivation): shown on a terminal by the command line.
_log = logging.getLogger(__name__)

__all__ = ["load", "load_generated", "generated_dir", "cache_dir", "check_text", "verify_text", "check_interface",
           "KernelError", "DIGEST_PREFIX"]

#: Environment variable naming the cache folder for user curves.
CACHE_ENV = cachetrust.CACHE_ENV
#: Largest module file read from the cache, in bytes (the largest generated module is about 100 kB).
MAX_MODULE_BYTES = 8 * 2**20


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
#: Keyword arguments a generated module passes (``numpy.asarray(q, dtype=float)``, ``numpy.sum(v, axis=...)``,
#: ``numpy.max(v, initial=0.0)``); no other (a ufunc's ``out=`` would write into an array it was given).
ALLOWED_KEYWORDS = frozenset({"dtype", "axis", "initial"})
#: The one call a module-level assignment may make: ``numpy.array(<a literal or a constant's name>)``
#: (the quadrature's nodes as arrays).  Every other module-level value is a literal, so importing a
#: module runs no loop and no function (nothing that could hang or change another module).
MODULE_CALL = ("numpy", "array")
#: Builtins a ``for`` loop of a generated function may iterate over (``range(panels)``, ``zip(X, W)``).
LOOP_ITERATORS = frozenset({"range", "zip"})


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
    # Items a module-level assignment fills (``RULES[3] = (...)``): checked by _check_module_assign.
    module_targets = {id(t) for n in tree.body if isinstance(n, ast.Assign) for t in n.targets
                      if isinstance(t, ast.Subscript)}
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
            a = node.args
            if a.defaults or a.kw_defaults or a.kwonlyargs or a.kwarg or a.posonlyargs:
                refuse(node, f"function {node.name!r} with defaults, keyword-only or ** arguments "
                             "(defaults run at import)")
        elif isinstance(node, (ast.Attribute, ast.Subscript, ast.Starred)) and not isinstance(node.ctx, ast.Load) \
                and id(node) not in module_targets:
            refuse(node, "assigning to " + ("an attribute" if isinstance(node, ast.Attribute)
                                            else "an item" if isinstance(node, ast.Subscript) else "a starred name"))
        elif isinstance(node, ast.keyword) and node.arg not in ALLOWED_KEYWORDS:
            refuse(node, f"the keyword argument {node.arg or '**'!r}")
        elif isinstance(node, ast.AugAssign) and not isinstance(node.target, ast.Name):
            refuse(node, "augmented assignment to something other than a local name")
        elif isinstance(node, ast.For) and not _plain_loop(node):
            refuse(node, "a loop other than over range(name) or zip(names)")
        elif isinstance(node, ast.comprehension) and not (
                isinstance(node.target, ast.Name) and isinstance(node.iter, ast.Name) and not node.ifs
                and not node.is_async):
            refuse(node.iter, "a comprehension other than over a name")
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
    for node in tree.body:   # what runs at import: literals only (after the names, which say more)
        if isinstance(node, ast.Assign):
            _check_module_assign(node, refuse)
    check_interface(tree, origin)


def _check_module_assign(node, refuse) -> None:
    """A module-level assignment: one name (or ``NAME[integer]``) bound to a literal or to
    ``numpy.array(literal or name)`` (:data:`MODULE_CALL`); nothing else runs at import."""
    import ast

    if len(node.targets) != 1:
        refuse(node, "a chained assignment at module level")
    target, value = node.targets[0], node.value
    if isinstance(target, ast.Subscript):
        if not (isinstance(target.value, ast.Name) and isinstance(target.slice, ast.Constant)
                and type(target.slice.value) is int):
            refuse(node, "a module-level item assignment other than NAME[integer]")
    elif not isinstance(target, ast.Name):
        refuse(node, "a module-level assignment to something other than a name")
    if isinstance(value, ast.Call):
        func = value.func
        called = (func.value.id, func.attr) if isinstance(func, ast.Attribute) and isinstance(func.value, ast.Name) \
            else None
        if called != MODULE_CALL or value.keywords or len(value.args) != 1 \
                or not (isinstance(value.args[0], ast.Name) or _is_literal(value.args[0])):
            refuse(node, "a call at module level (it would run at import)")
    elif not _is_literal(value):
        refuse(node, "a module-level value that is not a literal")


def _is_literal(node) -> bool:
    """Whether ``node`` is a plain literal (numbers, strings, None, tuples, lists, dicts of them)."""
    import ast

    try:
        ast.literal_eval(node)
    except (ValueError, TypeError, SyntaxError, MemoryError, RecursionError):
        return False
    return True


def _plain_loop(node) -> bool:
    """``for NAME in range(NAME)`` or ``for NAME, NAME in zip(NAME, NAME)`` (what the generator writes)."""
    import ast

    it = node.iter
    names = [node.target] if isinstance(node.target, ast.Name) else \
        node.target.elts if isinstance(node.target, ast.Tuple) else [None]
    return (not node.orelse and all(isinstance(n, ast.Name) for n in names)
            and isinstance(it, ast.Call) and isinstance(it.func, ast.Name) and it.func.id in LOOP_ITERATORS
            and not it.keywords and it.args and all(isinstance(a, ast.Name) for a in it.args))


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
    """Folder where user-curve modules are generated and cached: ``$SYMVIB_CACHE`` (default
    ``~/.cache/symvib/kernels``), created ``0700`` and used only while it is the user's alone
    (:func:`symvib.cachetrust.kernel_cache`; else a private temporary folder, with a warning)."""
    return cachetrust.kernel_cache()


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
    cachetrust.configure_numba()
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
    cachetrust.configure_numba()   # before any compiled function: numba reads only a checked folder
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
    folder = cache_dir()
    path = folder / f"{name}.py"
    key = f"symvib.generated.{name}"
    if key in sys.modules and getattr(sys.modules[key], "__file__", None) == str(path):
        return sys.modules[key]
    try:
        # Never through a link, and only a file that is the user's alone (symvib.safeio.read_bytes).
        raw = safeio.read_bytes(folder, path.name, max_bytes=MAX_MODULE_BYTES, what="kernel cache", private=True)
    except FileNotFoundError:
        raw = None
    except UserPathError as err:
        warnings.warn(f"{err}; regenerating it", stacklevel=3)
        raw = None
    if raw is not None:
        text = raw.decode("utf-8", errors="replace")
        try:
            check_text(text, path, want)
            return _exec(text, path, name)
        except KernelError as err:
            # Tampered, truncated or from a broken generator: made again below.
            warnings.warn(f"{err}; regenerating it", stacklevel=3)
    return _generate(curve, source, want, folder, name)


def _generate(curve: Shape, source: dict, want: str, folder: Path, name: str):
    """Generate a user curve's module: derived, checked and imported from its text, and only then
    written into the cache (whole, never through a link: :func:`symvib.safeio.write_text`); any
    failure leaves nothing in the cache."""
    from symvib.codegen import generate as codegen  # the bridge: imports SymPy, only for a curve not generated yet

    path = folder / f"{name}.py"
    _log.info("deriving the kernels of curve %r (first use; closed_form = %s), then caching them",
              curve.name, curve.closed_form)
    text = codegen.module_source(curve, source=source, closed_form=curve.closed_form, origin=path)
    check_text(text, path, want)
    try:
        module = _exec(text, path, name)
    except Exception as err:  # noqa: BLE001 - any failure of a fresh module is the generator's
        sys.modules.pop(f"symvib.generated.{name}", None)
        raise KernelError(f"{path}: the generated module does not import "
                          f"({type(err).__name__}: {err}); nothing was cached") from None
    try:
        safeio.remove_file(folder, path.name, links=True)   # a stale entry, or a link planted at its name
        safeio.write_text(folder, path.name, text, what="kernel cache", private=True)
    except OSError as err:   # a folder in its place, a full disk: the run goes on, uncached
        warnings.warn(f"{err}; the module is not cached", stacklevel=3)
    return module
