"""Reading the paper's OCR text of an equation into SymPy, to check a transcription against it.

The seed of the project is the paper as OCR text with LaTeX formulas
(``../shared/seed/``; a copy ships in ``docs/seed/``).  :mod:`symvib.paper.audit`
stores beside each transcribed equation the seed's own text (an exact
substring of the seed file) and the OCR-noise differences it declares; this
module turns that text into a SymPy expression, so that a test can compare it
with the transcription and fail on any difference that is not declared.

The reading is in three steps:

1. :func:`layout` removes what is layout, not content, the same for every
   equation: the ``$$`` delimiters and the stray ``\\n`` of the OCR output
   between display blocks, ``\\left``/``\\right``/``\\bigg``, spacing commands,
   ``\\begin{cases}...\\end{cases}`` (the branch legend "za v > 0 / za v < 0":
   upper sign for ``v > 0``, the convention of the whole audit), the paper's
   ``tg`` for the tangent (read as ``\\tan``) and a multiplication sign or an
   equals sign repeated at a line break (printed at the end of one line and
   again at the start of the next; the OCR reads a line-end ``.`` for the
   ``·``);
2. the declared edits of the equation (:class:`Edit`, each with its reason)
   replace what the OCR got wrong; every edit must match;
3. :func:`parse` reads the result (a chain ``a = b = c``) into SymPy, one
   expression per side, with the symbols of a name table.

The parser knows the subset of LaTeX the paper's formulas use: sums with
``\\pm``/``\\mp`` (``pm`` times the term, ``-pm`` for ``\\mp``), implicit
products, ``\\cdot``, ``\\frac``, ``\\sqrt``, powers, ``e^{...}``, ``\\sin``,
``\\cos``, ``\\tan`` (with ``\\cos^3\\phi`` meaning ``cos(phi)**3``), ``\\dot``,
``\\ddot``, primes, subscripts, the groups ``()``, ``[]``, ``\\{\\}``,
``\\int ... dx`` and ``\\frac{d}{dx}``.  ``\\phi`` and ``\\varphi`` name the same
angle (the paper uses both), and a symbol's ``(\\phi)`` after it is the
function-argument notation ``\\dot\\phi_i^2(\\phi)``, not a factor.

Examples
--------
>>> import sympy as sp
>>> phi, mu, pm = sp.symbols("phi mu pm")
>>> read(r"\\dot{\\phi}^2 = \\cos^2 \\phi \\pm \\mu t g \\phi", (), {"phi": phi, "mu": mu, "pm": pm})
(mu*pm*tan(phi) + cos(phi)**2,)
"""
from __future__ import annotations

import re
from dataclasses import dataclass

import sympy as sp

__all__ = ["Edit", "SeedTexError", "layout", "apply_edits", "parse", "read"]


class SeedTexError(ValueError):
    """The seed text could not be read (unknown symbol, unbalanced group, edit that does not match)."""


@dataclass(frozen=True)
class Edit:
    """One declared difference between the seed's text and the transcription.

    ``seed`` is a fragment of the layout-normalised seed text (:func:`layout`),
    ``reading`` what the transcription reads instead, ``reason`` why this is
    OCR noise (or a reading of a garbled passage) and not what the paper says.
    """

    seed: str
    reading: str
    reason: str


#: Layout rules of step 1: (pattern, replacement, what it removes).  They apply to every equation.
LAYOUT_RULES = (
    (r"\.(?=\s*\n\$\$)", r" \\cdot ", "a line-end '.' ending a display block: the '·' of a line break"),
    (r"\\begin\{cases\}.*?\\end\{cases\}", " ", "the branch legend (upper sign for v > 0)"),
    (r"\$\$", " ", "display delimiters"),
    (r"\\n(?![A-Za-z])", " ", "stray '\\n' of the OCR output between blocks"),
    (r"\\(?:left|right|middle|bigg|Bigg|big|Big)(?![A-Za-z])", " ", "delimiter sizes"),
    (r"\\[,;!]|\\ ", " ", "spacing"),
    (r"\\tag\{[^}]*\}", " ", "equation numbers"),
    (r"(?<![A-Za-z\\])t\s*g(?![A-Za-z])", r"\\tan ", "tg, the paper's tangent"),
    (r"\s+", " ", "whitespace"),
    (r"\\cdot(?: \\cdot)+", r"\\cdot", "a multiplication sign repeated at a line break"),
    (r"=(?: =)+", "=", "an equals sign repeated at a line break"),
    (r"\+(?: \+)+", "+", "a plus sign repeated at a line break"),
)


def layout(text: str) -> str:
    """Step 1: the seed text without layout (:data:`LAYOUT_RULES`), one line."""
    for pattern, repl, _why in LAYOUT_RULES:
        text = re.sub(pattern, repl, text, flags=re.S)
    return text.strip()


def apply_edits(text: str, edits) -> str:
    """Step 2: apply the declared :class:`Edit` s to the layout-normalised ``text``; each must match once."""
    for e in edits:
        n = text.count(e.seed)
        if n != 1:
            raise SeedTexError(f"declared edit {e.seed!r} matches {n} times in the seed text (must be once)")
        text = text.replace(e.seed, e.reading)
    return text


_TOKEN = re.compile(r"\\[A-Za-z]+|\\[{}|]|dx(?![A-Za-z])|[0-9]+(?:\.[0-9]+)?|[A-Za-z]|'+|[-+=^_(){}\[\]/.,|]|\S")
_FUNCTIONS = {r"\sin": sp.sin, r"\cos": sp.cos, r"\tan": sp.tan}
_GREEK = {r"\phi": "phi", r"\varphi": "phi", r"\mu": "mu", r"\alpha": "alpha", r"\pi": "pi"}
_OPEN = {"(": ")", "[": "]", "{": "}", r"\{": r"\}"}
_SIGNS = ("+", "-", r"\pm", r"\mp")
_BREAK = {*_SIGNS, "=", ")", "]", "}", r"\}", "dx", ",", None}


class _Parser:
    def __init__(self, text: str, names: dict):
        self.toks = _TOKEN.findall(text)
        self.i = 0
        self.names = names

    # --- token helpers
    def peek(self, k: int = 0):
        j = self.i + k
        return self.toks[j] if j < len(self.toks) else None

    def take(self, want=None):
        tok = self.peek()
        if want is not None and tok != want:
            raise SeedTexError(f"expected {want!r} at token {self.i} ({self._here()}), found {tok!r}")
        self.i += 1
        return tok

    def _here(self) -> str:
        return " ".join(self.toks[max(0, self.i - 4):self.i + 4])

    def symbol(self, name: str):
        if name in self.names:
            return self.names[name]
        raise SeedTexError(f"unknown symbol {name!r} near {self._here()!r} (not in the equation's name table)")

    # --- grammar
    def chain(self) -> list:
        sides = [self.sum()]
        while self.peek() == "=":
            self.take()
            sides.append(self.sum())
        if self.peek() is not None:
            raise SeedTexError(f"unread text at {self._here()!r}")
        return sides

    def sum(self):
        terms = []
        while True:
            tok = self.peek()
            if tok in _SIGNS:
                self.take()
                sign = {"+": 1, "-": -1, r"\pm": self.symbol("pm"), r"\mp": -self.symbol("pm")}[tok]
            elif terms:
                break
            else:
                sign = 1
            if self.peek() in _BREAK:
                raise SeedTexError(f"empty term near {self._here()!r}")
            terms.append(sign * self.product())
            if self.peek() not in _SIGNS:
                break
        return sp.Add(*terms)

    def product(self):
        factors = []
        while self.peek() not in _BREAK:
            if self.peek() == r"\cdot":
                self.take()
            elif self.peek() == "/":
                self.take()
                factors.append(1 / self.power())
            else:
                factors.append(self.power())
        if not factors:
            raise SeedTexError(f"empty product near {self._here()!r}")
        return sp.Mul(*factors)

    def group_text_name(self) -> str:
        """The raw text of a subscript (one token or a braced group), for a symbol's name."""
        if self.peek() == "{":
            self.take("{")
            parts = []
            while self.peek() != "}":
                if self.peek() is None:
                    raise SeedTexError("unclosed subscript")
                parts.append(self.take())
            self.take("}")
            return "".join(parts)
        return self.take()

    def named(self, name: str):
        """The symbol ``name`` with the subscripts and primes that follow it (``C_i``, ``z''``)."""
        while True:
            tok = self.peek()
            if tok == "_":
                self.take()
                name = f"{name}_{self.group_text_name()}"
            elif tok is not None and tok.startswith("'"):
                name += self.take()
            else:
                break
        expr = self.symbol(name)
        # dot phi_i^2(phi): "(phi)" is the function-argument notation, not a factor.
        if name.startswith("dot ") and self.peek() == "^":
            self.take()
            expr = expr ** self.exponent()
        if name.startswith("dot ") and self.peek() == "(" and self.peek(2) == ")" \
                and self.peek(1) in (r"\phi", r"\varphi", "x"):
            self.i += 3
        return expr

    def power(self):
        base = self.atom()
        while self.peek() == "^":
            self.take()
            base = base ** self.exponent()
        return base

    def exponent(self):
        if self.peek() == "{":
            return self.braced()
        tok = self.take()
        if re.fullmatch(r"[0-9]+", tok or ""):
            return sp.Integer(tok)
        raise SeedTexError(f"unreadable exponent {tok!r}")

    def braced(self):
        self.take("{")
        e = self.sum()
        self.take("}")
        return e

    def atom(self):
        tok = self.take()
        if tok is None:
            raise SeedTexError("unexpected end of the text")
        if re.fullmatch(r"[0-9]+(?:\.[0-9]+)?", tok):
            return sp.Rational(tok)
        if tok in _OPEN:
            e = self.sum()
            self.take(_OPEN[tok])
            return e
        if tok in _FUNCTIONS:
            return self.function(_FUNCTIONS[tok])
        if tok == r"\frac":
            if self.toks[self.i:self.i + 6] == ["{", "d", "}", "{", "dx", "}"]:
                self.i += 6
                return sp.Derivative(self.power(), self.symbol("x")).doit()
            num = self.braced()
            return num / self.braced()
        if tok == r"\sqrt":
            return sp.sqrt(self.braced())
        if tok == r"\int":
            body = self.sum()
            self.take("dx")
            return sp.Integral(body, self.symbol("x"))
        if tok in (r"\dot", r"\ddot"):
            inner = self.group_text_name()
            return self.named(f"{tok[1:]} {_GREEK.get(inner, inner)}")
        if tok in _GREEK:
            return self.named(_GREEK[tok])
        if tok == "e" and self.peek() == "^":
            self.take("^")
            return sp.exp(self.exponent())
        if re.fullmatch(r"[A-Za-z]", tok):
            return self.named(tok)
        raise SeedTexError(f"unexpected {tok!r} near {self._here()!r}")

    def function(self, f):
        """``\\sin x``, ``\\sin(x + y)``, ``\\cos^3 x`` (= ``cos(x)**3``), ``\\cos\\frac{x}{2}``."""
        power = 1
        if self.peek() == "^":
            self.take()
            power = self.exponent()
        return f(self.atom()) ** power


def parse(text: str, names: dict) -> list:
    """Step 3: the sides of the equation chain ``text`` (layout-normalised), as SymPy expressions.

    ``names`` maps the names the text uses to SymPy objects: a letter
    (``"g"``), a Greek command without its backslash (``"phi"``, ``"mu"``;
    ``\\varphi`` is ``"phi"``), a subscripted name (``"alpha_0"``, ``"C_i"``,
    ``"F_{N,i}"`` written ``"F_N,i"``), a dotted one (``"dot phi"``, ``"ddot s"``),
    a primed one (``"z'"``); ``"pm"`` is the symbol of ``\\pm`` and ``"x"`` the
    variable of ``\\int ... dx``.  A side that is not needed may use names not
    in the table only if it is not parsed: use :func:`read` with ``sides``.
    """
    return _Parser(text, names).chain()


def _split_sides(text: str) -> list:
    depth, start, out = 0, 0, []
    for i, ch in enumerate(text):
        if ch in "([{":
            depth += 1
        elif ch in ")]}":
            depth -= 1
        elif ch == "=" and depth == 0:
            out.append(text[start:i])
            start = i + 1
    out.append(text[start:])
    return out


def read(seed_text: str, edits, names: dict, sides=(-1,)) -> tuple:
    """Steps 1-3 for the chosen ``sides`` of the chain (indices, ``-1`` the last): a tuple of expressions."""
    text = apply_edits(layout(seed_text), edits)
    parts = _split_sides(text)
    out = []
    for k in sides:
        try:
            out.append(parse(parts[k].strip(), names)[0])
        except IndexError:
            raise SeedTexError(f"the seed text has {len(parts)} sides, not side {k}") from None
    return tuple(out)
