r"""The format of a generated kernel module: what it may contain and how it is sealed.

A generated module (written by :mod:`symvib.codegen.generate`, loaded by
:mod:`symvib.numeric.kernels`) is sealed by its first line, ``# symvib
generated ...; body sha256: <hex>`` (:data:`DIGEST_PREFIX`), and a curve's
module records its inputs' hash as ``INPUT_HASH = '<hex>'``.  Its text may hold
only what a generator writes (:func:`verify_text`: a whitelist of syntax,
:data:`ALLOWED_NODES`, :data:`SAFE_BUILTINS`, :data:`NUMPY_ATTRIBUTES`, ...), and
a curve's module must provide every kernel of :data:`KERNEL_INTERFACE` with the
declared arguments (:func:`check_interface`).  :func:`check_text` checks all of
it.  The generator checks what it writes and the loader what it reads against
this one module, which imports neither SymPy nor NumPy at import (NumPy only
when a text is verified, to tell its ufuncs).

Examples
--------
>>> import hashlib
>>> body = "'''A tiny module.'''\nimport math\n\ndef f(q):\n    return math.sin(q)\n"
>>> text = DIGEST_PREFIX + hashlib.sha256(body.encode()).hexdigest() + "\n" + body
>>> check_text(text, "tiny.py")          # sealed and whitelisted: passes silently
>>> try:
...     check_text(text.replace("math.sin", "math.cos"), "tiny.py")
... except KernelError as err:
...     print(err)
tiny.py: body digest mismatch (edited, truncated or damaged)
>>> try:
...     verify_text(body.replace("math.sin(q)", "open(q)"), "tiny.py")
... except KernelError as err:
...     print(err)
tiny.py: line 5: the name 'open' ('open') is not allowed in a generated module; regenerate it
"""
from __future__ import annotations

import builtins
import hashlib
import re

__all__ = ["KernelError", "DIGEST_PREFIX", "KERNEL_INTERFACE", "ALLOWED_NODES", "MODULE_STATEMENTS",
           "ALLOWED_IMPORTS", "SAFE_BUILTINS", "NUMPY_ATTRIBUTES", "VALUE_ATTRIBUTES", "ALLOWED_KEYWORDS",
           "MODULE_CALL", "LOOP_ITERATORS", "verify_text", "check_interface", "check_text"]


class KernelError(RuntimeError):
    """A kernel module is missing or does not match its inputs."""


#: First line of every generated module up to its body's SHA-256 (kernel modules; the
#: Gauss-Legendre table has its own prefix, :data:`symvib.codegen.gauss.TABLE_PREFIX`).
DIGEST_PREFIX = "# symvib generated kernel module; body sha256: "
_DIGEST_LINE = re.compile(r"# symvib generated [^\n]*; body sha256: ([0-9a-f]{64})")
_INPUT_HASH_LINE = re.compile(r"^INPUT_HASH = '([0-9a-f]{64})'$", re.M)

#: Statement and expression nodes a generated module may contain (:func:`verify_text`).  No
#: conditional (``IfExp``, ``If``) and no comparison (``Compare``): the generator decides every
#: ``Piecewise`` symbolically (:func:`symvib.symbolic.branches.generic_branch`) and writes none.
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
    "zeros", "sum", "amax", "amin", "float64", "reshape",
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

#: The kernels a curve's module provides the engine (:func:`check_interface`; the engine's
#: :class:`symvib.numeric.engine.state.Kernels` lists the same names in order): engine name ->
#: (function of the generated module, arguments before the curve's parameters, number of floats returned).
KERNEL_INTERFACE = {
    "F_p": ("F_p_scalar", ("q", "mu"), 1),
    "F_m": ("F_m_scalar", ("q", "mu"), 1),
    "dF_p": ("dF_p_scalar", ("q", "mu"), 1),
    "dF_m": ("dF_m_scalar", ("q", "mu"), 1),
    "ddF_p": ("ddF_p_scalar", ("q", "mu"), 1),
    "ddF_m": ("ddF_m_scalar", ("q", "mu"), 1),
    "node_p": ("node_p_scalar", ("q", "mu"), 5),
    "node_m": ("node_m_scalar", ("q", "mu"), 5),
    "z": ("z_scalar", ("q",), 1),
    "h": ("h_scalar", ("q",), 1),
    "dx": ("dx_scalar", ("q",), 1),
    "dz": ("dz_scalar", ("q",), 1),
    "alpha": ("alpha_scalar", ("q",), 1),
    "kappa": ("kappa_scalar", ("q",), 1),
    "N_w": ("N_w_scalar", ("q", "w", "g"), 1),
    "q_scale": ("q_scale_scalar", (), 1),
    "domain": ("domain", (), 2),
}


def verify_text(text: str, origin) -> None:
    """Check the text of a generated module before it is imported or executed.

    The text must parse, and every node of its syntax tree must be one a
    generator writes: definitions, assignments, arithmetic, calls of the
    module's own functions, of :data:`SAFE_BUILTINS`, of :mod:`math` and of
    NumPy's ufuncs and :data:`NUMPY_ATTRIBUTES`; docstrings as the only bare
    expressions; ``import math`` / ``import numpy`` as the only imports; no
    name or attribute starting with ``__``.  This whitelist keeps a module that
    was edited or generated wrong from running code; the digest
    (:func:`check_text`) tells that it changed.

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
    :data:`KERNEL_INTERFACE`, the function taking the
    declared leading arguments followed by the curve's parameters (its ``PARAMS``).

    Raises
    ------
    KernelError
        Naming ``origin`` and the first kernel missing or with other arguments.
    """
    import ast

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
