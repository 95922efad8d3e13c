"""Safe parsing of user expressions (numbers and curve formulas).

Every expression that reaches symvib from a file or the command line goes
through :func:`parse`.  It never calls :func:`eval`: the text is parsed by
:mod:`ast` and accepted only if every node is on a short whitelist (numbers,
the declared symbols, ``+ - * / **``, unary minus and calls of a fixed set of
mathematical functions).  The result is a small immutable tree of tuples that
the numeric wing evaluates with :mod:`math` (:func:`evaluate`, :func:`number`)
and the symbolic wing converts to SymPy (``symvib.symbolic.curve.to_sympy``).

This module imports neither SymPy nor NumPy.

Examples
--------
>>> number("pi/4", field="limiters.right")
0.7853981633974483
>>> tree = parse("R*(1 - cos(phi))", symbols=("R", "phi"), field="curve.z")
>>> sorted(tree.symbols)
['R', 'phi']
>>> evaluate(tree, {"R": 2.0, "phi": 0.0})
0.0
>>> parse("__import__('os').system('true')", field="curve.z")
Traceback (most recent call last):
...
symvib.expr.ExpressionError: curve.z: attribute access ('.system') is not allowed (known symbols: none; functions: ...
"""
from __future__ import annotations

import ast
import hashlib
import math
import re
from dataclasses import dataclass

__all__ = [
    "ExpressionError",
    "Parsed",
    "FUNCTIONS",
    "CONSTANTS",
    "parse",
    "evaluate",
    "number",
    "free_names",
]

#: Longest accepted expression text, in characters.
MAX_LENGTH = 1000
#: Deepest accepted nesting of the expression tree.
MAX_DEPTH = 40
#: Largest number of tree nodes.
MAX_NODES = 400
#: Largest absolute value of a constant exponent (``x**64`` is accepted, ``x**65`` is not).
MAX_EXPONENT = 64
#: Largest product of the constant exponents of nested powers, over the whole expression
#: (``(x**8)**8`` is accepted, ``((9**64)**64)**64`` is not: SymPy would build a huge integer).
MAX_EXPONENT_PRODUCT = MAX_EXPONENT
#: Longest accepted integer literal, in digits.
MAX_INT_DIGITS = 30
#: Largest magnitude of a constant (a literal, or a part of the expression without symbols,
#: folded in floats): beyond it an expression is a mistake or an attack, not a curve.
MAX_CONSTANT = 1e100
#: Most unary signs (``-``, ``+``, ``~``) in one expression text.
MAX_UNARY = MAX_DEPTH

#: Functions allowed in expressions: name -> (number of arguments, math implementation).
FUNCTIONS: dict[str, tuple[int, object]] = {
    "sin": (1, math.sin),
    "cos": (1, math.cos),
    "tan": (1, math.tan),
    "asin": (1, math.asin),
    "acos": (1, math.acos),
    "atan": (1, math.atan),
    "atan2": (2, math.atan2),
    "sinh": (1, math.sinh),
    "cosh": (1, math.cosh),
    "tanh": (1, math.tanh),
    "asinh": (1, math.asinh),
    "acosh": (1, math.acosh),
    "atanh": (1, math.atanh),
    "exp": (1, math.exp),
    "log": (1, math.log),
    "sqrt": (1, math.sqrt),
    "abs": (1, abs),
}

#: Named constants allowed in expressions.
CONSTANTS: dict[str, float] = {"pi": math.pi, "e": math.e}

_BINOPS = {ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.Div: "/", ast.Pow: "**"}
_UNARY = {ast.USub: "neg", ast.UAdd: "pos"}


class ExpressionError(ValueError):
    """An expression was rejected; the message starts with the field it came from."""

    def __init__(self, field: str, reason: str):
        self.field = field
        self.reason = reason
        super().__init__(f"{field}: {reason}")


@dataclass(frozen=True)
class Parsed:
    """A validated expression.

    Attributes
    ----------
    text : str
        The expression as given.
    tree : tuple
        Nested tuples: ``("num", "0.5")``, ``("sym", "R")``, ``("const", "pi")``,
        ``("bin", "+", a, b)``, ``("neg", a)``, ``("call", "sin", a, ...)``.
    symbols : frozenset of str
        The declared symbols the expression uses.
    """

    text: str
    tree: tuple
    symbols: frozenset

    @property
    def canonical(self) -> str:
        """A whitespace-independent text of the tree (stable across runs)."""
        return _canonical(self.tree)

    @property
    def digest(self) -> str:
        """SHA-256 of :attr:`canonical`."""
        return hashlib.sha256(self.canonical.encode()).hexdigest()


def _canonical(node: tuple) -> str:
    kind = node[0]
    if kind in ("num", "sym", "const"):
        return node[1]
    if kind == "bin":
        return f"({_canonical(node[2])}{node[1]}{_canonical(node[3])})"
    if kind == "neg":
        return f"(-{_canonical(node[1])})"
    return f"{node[1]}(" + ",".join(_canonical(a) for a in node[2:]) + ")"


def _describe(symbols) -> str:
    known = "any name" if symbols is None else ", ".join(sorted(symbols)) or "none"
    return f"(known symbols: {known}; functions: {', '.join(sorted(FUNCTIONS))}; constants: pi, e)"


def parse(text: str, symbols=(), *, field: str = "expression") -> Parsed:
    """Parse ``text`` into a validated expression tree.

    Parameters
    ----------
    text : str
        The expression, in Python syntax (``**`` for powers).
    symbols : iterable of str, or ANY_NAME
        Names the expression may use besides functions and constants
        (:data:`ANY_NAME`: any identifier not starting with ``_``).
    field : str
        Where the text came from (``"curve.z"``); starts every error message.

    Returns
    -------
    Parsed

    Raises
    ------
    ExpressionError
        On anything that is not a plain arithmetic expression of the allowed
        names: attribute access, subscripts, lambdas, comprehensions, strings,
        keyword arguments, unknown names, text longer than ``MAX_LENGTH`` or
        nested deeper than ``MAX_DEPTH`` (checked on the text, before the Python
        parser runs, so no RecursionError or MemoryError escapes), integer
        literals longer than ``MAX_INT_DIGITS``, a constant part (folded in
        floats) beyond ``MAX_CONSTANT`` or dividing by zero, a constant exponent
        beyond ``MAX_EXPONENT``, or nested powers whose exponents multiply to more
        than ``MAX_EXPONENT_PRODUCT`` (``((9**64)**64)**64`` would make SymPy
        build an integer of millions of digits).
    """
    allowed = None if symbols is ANY_NAME else frozenset(symbols)
    text = _precheck(text, field)
    try:
        module = ast.parse(text.strip(), mode="eval")
    except SyntaxError as exc:
        hint = " (use ** for powers, not ^)" if "^" in text else ""
        raise ExpressionError(field, f"not a valid expression: {exc.msg}{hint}") from None
    except (RecursionError, MemoryError, ValueError):
        raise ExpressionError(field, "expression too complex to parse") from None
    counter = [0]
    used: set[str] = set()
    tree = _convert(module.body, allowed, field, counter, used, 0, text)
    weight = _power_weight(tree)
    if weight > MAX_EXPONENT_PRODUCT:
        raise ExpressionError(field, f"nested powers raise to a total exponent of {weight:g}; "
                                     f"at most {MAX_EXPONENT_PRODUCT} is accepted")
    return Parsed(text=text, tree=tree, symbols=frozenset(used))


#: Pass as ``symbols`` to :func:`parse` to accept every name that is not a function or constant.
ANY_NAME = object()


def _precheck(text, field: str) -> str:
    """Checks of the raw text before the (recursive) Python parser sees it: type, length,
    nesting of brackets and the number of unary signs, so that no RecursionError or
    MemoryError can escape the parser."""
    if not isinstance(text, str):
        if isinstance(text, bool) or not isinstance(text, (int, float)):
            raise ExpressionError(field, f"expected a number or an expression string, got {type(text).__name__}")
        if isinstance(text, int) and len(str(abs(text))) > MAX_INT_DIGITS:
            raise ExpressionError(field, f"integer longer than {MAX_INT_DIGITS} digits")
        if isinstance(text, float) and not math.isfinite(text):
            raise ExpressionError(field, f"number is not finite, got {text}")
        text = repr(text)
    if len(text) > MAX_LENGTH:
        raise ExpressionError(field, f"expression is {len(text)} characters long; at most {MAX_LENGTH} are accepted")
    if not text.strip():
        raise ExpressionError(field, "empty expression")
    depth = 0
    for ch in text:
        depth += ch in "([{"
        depth -= ch in ")]}"
        if depth > MAX_DEPTH:
            raise ExpressionError(field, f"expression nested deeper than {MAX_DEPTH} levels")
    if re.search(rf"(?:[-+~]\s*){{{MAX_UNARY + 2}}}", text):
        raise ExpressionError(field, f"expression nested deeper than {MAX_UNARY} levels "
                                     f"(more than {MAX_UNARY} signs in a row)")
    return text


def free_names(text, *, field: str = "expression") -> frozenset:
    """The names an expression uses besides functions and constants (parsed safely).

    >>> sorted(free_names("R*(1 - cos(phi)) + pi", field="curve.z"))
    ['R', 'phi']
    """
    return parse(text, ANY_NAME, field=field).symbols


def _power_weight(node: tuple) -> float:
    """The largest product of constant exponents along nested powers in ``node``."""
    kind = node[0]
    if kind == "bin":
        base, exponent = _power_weight(node[2]), _power_weight(node[3])
        if node[1] == "**":
            value = _constant_value(node[3])
            base *= 1.0 if value is None else max(abs(value), 1.0)
        return max(base, exponent)
    if kind in ("neg", "call"):
        return max((_power_weight(a) for a in node[1 if kind == "neg" else 2:]), default=1.0)
    return 1.0


def _convert(node, allowed, field, counter, used, depth, text):
    counter[0] += 1
    if counter[0] > MAX_NODES:
        raise ExpressionError(field, f"expression has more than {MAX_NODES} parts")
    if depth > MAX_DEPTH:
        raise ExpressionError(field, f"expression nested deeper than {MAX_DEPTH} levels")
    rec = lambda n: _convert(n, allowed, field, counter, used, depth + 1, text)  # noqa: E731
    if isinstance(node, ast.Constant):
        value = node.value
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ExpressionError(field, f"only numbers are allowed as constants, got {value!r}")
        if isinstance(value, int) and len(str(abs(value))) > MAX_INT_DIGITS:
            raise ExpressionError(field, f"integer literal longer than {MAX_INT_DIGITS} digits")
        if isinstance(value, float) and not math.isfinite(value):
            raise ExpressionError(field, "number is not finite")
        if abs(value) > MAX_CONSTANT:
            raise ExpressionError(field, f"number {float(value):g} is larger than {MAX_CONSTANT:g} in magnitude")
        literal = ast.get_source_segment(text.strip(), node) or repr(value)
        return ("num", literal.replace("_", ""))
    if isinstance(node, ast.Name):
        name = node.id
        if allowed is None and name not in FUNCTIONS and name not in CONSTANTS:
            if not name.isidentifier() or name.startswith("_"):
                raise ExpressionError(field, f"name {name!r} is not allowed (names may not start with _)")
            used.add(name)
            return ("sym", name)
        if allowed is not None and name in allowed:
            used.add(name)
            return ("sym", name)
        if name in CONSTANTS:
            return ("const", name)
        if name in FUNCTIONS:
            raise ExpressionError(field, f"function '{name}' must be called, as {name}(...)")
        raise ExpressionError(field, f"name '{name}' is not allowed {_describe(allowed)}")
    if isinstance(node, ast.BinOp):
        op = _BINOPS.get(type(node.op))
        if op is None:
            hint = " (use ** for powers)" if isinstance(node.op, ast.BitXor) else ""
            raise ExpressionError(field, f"operator {type(node.op).__name__} is not allowed{hint}")
        left, right = rec(node.left), rec(node.right)
        if op == "**":
            _check_exponent(right, field)
        return _folded(("bin", op, left, right), field)
    if isinstance(node, ast.UnaryOp):
        kind = _UNARY.get(type(node.op))
        if kind is None:
            raise ExpressionError(field, f"operator {type(node.op).__name__} is not allowed")
        operand = rec(node.operand)
        return operand if kind == "pos" else _folded(("neg", operand), field)
    if isinstance(node, ast.Call):
        if isinstance(node.func, ast.Attribute):
            raise ExpressionError(field, f"attribute access ('.{node.func.attr}') is not allowed {_describe(allowed)}")
        if not isinstance(node.func, ast.Name) or node.func.id not in FUNCTIONS:
            what = node.func.id if isinstance(node.func, ast.Name) else type(node.func).__name__
            raise ExpressionError(field, f"call of '{what}' is not allowed {_describe(allowed)}")
        if node.keywords:
            raise ExpressionError(field, "keyword arguments are not allowed")
        name = node.func.id
        arity = FUNCTIONS[name][0]
        if len(node.args) != arity or any(isinstance(a, ast.Starred) for a in node.args):
            raise ExpressionError(field, f"{name}() takes {arity} argument{'s' * (arity > 1)}")
        return _folded(("call", name, *(rec(a) for a in node.args)), field)
    raise ExpressionError(field, f"syntax not allowed in an expression: {type(node).__name__}")


def _constant_value(node):
    """Value of a constant subtree in floats (``inf`` on overflow), or None when it holds a
    symbol; a division by zero or a function outside its domain raises :class:`ArithmeticError`
    or :class:`ValueError`."""
    kind = node[0]
    if kind == "num":
        return float(node[1])
    if kind == "const":
        return CONSTANTS[node[1]]
    if kind == "sym":
        return None
    args = [_constant_value(a) for a in (node[1:] if kind == "neg" else node[2:] if kind == "bin" else node[2:])]
    if any(a is None for a in args):
        return None
    try:
        if kind == "neg":
            return -args[0]
        if kind == "bin":
            return _apply(node[1], *args)
        return float(FUNCTIONS[node[1]][1](*args))
    except OverflowError:
        return math.inf


def _folded(node: tuple, field: str) -> tuple:
    """``node``, after checking that a constant part of it is a finite number within MAX_CONSTANT."""
    try:
        value = _constant_value(node)
    except ZeroDivisionError:
        raise ExpressionError(field, f"division by zero in the constant {_canonical(node)}") from None
    except ValueError:
        raise ExpressionError(field, f"the constant {_canonical(node)} is not a real number "
                                     f"(a function outside its domain)") from None
    if node[0] == "bin" and node[1] == "/" and _constant_value(node[3]) == 0:
        raise ExpressionError(field, f"division by the constant {_short(_canonical(node[3]))}, which is zero")
    if value is not None and not abs(value) <= MAX_CONSTANT:
        raise ExpressionError(field, f"the constant {_short(_canonical(node))} is larger than {MAX_CONSTANT:g} "
                                     f"in magnitude")
    return node


def _short(text: str, limit: int = 60) -> str:
    return text if len(text) <= limit else text[:limit - 3] + "..."


def _check_exponent(node, field):
    value = _constant_value(node)
    if value is not None and (not math.isfinite(value) or abs(value) > MAX_EXPONENT):
        raise ExpressionError(field, f"constant exponent {value:g} is larger than {MAX_EXPONENT} in magnitude")


def _apply(op, a, b):
    if op == "+":
        return a + b
    if op == "-":
        return a - b
    if op == "*":
        return a * b
    if op == "/":
        return a / b
    return math.pow(a, b)


def evaluate(parsed: Parsed, values=None, *, field: str | None = None) -> float:
    """Evaluate a parsed expression in double precision with :mod:`math`.

    Parameters
    ----------
    parsed : Parsed
    values : mapping of str to float
        Values of the symbols the expression uses.
    field : str, optional
        Name for error messages (defaults to the one the text was parsed under).

    Raises
    ------
    ExpressionError
        When a symbol has no value, or the value is not finite
        (overflow, division by zero, a function outside its domain).
    """
    values = dict(values or {})
    name = field or "expression"
    missing = sorted(parsed.symbols - set(values))
    if missing:
        raise ExpressionError(name, f"no value for symbol(s) {', '.join(missing)}")

    def ev(node):
        kind = node[0]
        if kind == "num":
            return float(node[1])
        if kind == "const":
            return CONSTANTS[node[1]]
        if kind == "sym":
            return float(values[node[1]])
        if kind == "neg":
            return -ev(node[1])
        if kind == "bin":
            return _apply(node[1], ev(node[2]), ev(node[3]))
        return FUNCTIONS[node[1]][1](*(ev(a) for a in node[2:]))

    try:
        result = float(ev(parsed.tree))
    except (OverflowError, ZeroDivisionError, ValueError) as exc:
        raise ExpressionError(name, f"cannot evaluate '{parsed.text}': {exc}") from None
    if not math.isfinite(result):
        raise ExpressionError(name, f"'{parsed.text}' evaluates to {result}, not a finite number")
    return result


def number(text, *, field: str, symbols=None) -> float:
    """Parse and evaluate a number written as a constant expression.

    ``symbols`` optionally maps names to values that may appear
    (for example the curve parameters in a limiter position).

    >>> number("tan(0.05)", field="physics.mu")
    0.05004170837553879
    """
    symbols = dict(symbols or {})
    parsed = parse(text, symbols=tuple(symbols), field=field)
    return evaluate(parsed, symbols, field=field)
