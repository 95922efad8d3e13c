"""LaTeX formulas of the report as MathML, so that ``report.html`` reads offline.

Browsers render MathML natively (Firefox, and Chromium since version 109); no
script and no network are needed.  This converts the subset of TeX that the
report uses (what :func:`sympy.latex` writes, and the paper's transcriptions):
groups, ``^ _ '``, ``\\frac``, ``\\sqrt``, ``\\left ... \\right``, accents
(``\\dot``, ``\\ddot``, ``\\hat``, ``\\bar``, ``\\tilde``, ``\\vec``), ``\\text``,
``\\mathrm``, ``\\operatorname``, Greek letters, function names, common
operators and spaces, and ``cases``/``matrix`` environments.  Anything else
raises :class:`TexError`; :func:`to_mathml` then returns ``None`` and the
caller shows the TeX source.  Each formula keeps its TeX as an annotation.

Examples
--------
>>> m = tex_to_mathml(r"\\dot{\\varphi}^{2} = \\frac{C}{p}")
>>> m[:65]
'<math><semantics><mrow><msup><mover accent="true"><mi>φ</mi><mo>˙'
>>> "<mfrac><mi>C</mi><mi>p</mi></mfrac>" in m
True
>>> to_mathml(r"\\unknowncommand x") is None
True
"""
from __future__ import annotations

import html
import re

__all__ = ["tex_to_mathml", "to_mathml", "TexError"]

GREEK = {
    "alpha": "α", "beta": "β", "gamma": "γ", "delta": "δ", "epsilon": "ϵ", "varepsilon": "ε", "zeta": "ζ",
    "eta": "η", "theta": "θ", "vartheta": "ϑ", "iota": "ι", "kappa": "κ", "lambda": "λ", "mu": "μ", "nu": "ν",
    "xi": "ξ", "pi": "π", "rho": "ρ", "sigma": "σ", "tau": "τ", "upsilon": "υ", "phi": "ϕ", "varphi": "φ",
    "chi": "χ", "psi": "ψ", "omega": "ω",
    "Gamma": "Γ", "Delta": "Δ", "Theta": "Θ", "Lambda": "Λ", "Xi": "Ξ", "Pi": "Π", "Sigma": "Σ", "Phi": "Φ",
    "Psi": "Ψ", "Omega": "Ω",
}
#: MathML's function application (invisible), after a function name and its scripts.
_APPLY = "<mo>&#x2061;</mo>"
FUNCTIONS = {"sin", "cos", "tan", "cot", "sec", "csc", "exp", "log", "ln", "sinh", "cosh", "tanh", "arcsin",
             "arccos", "arctan", "sign", "max", "min", "tg", "ctg", "det", "lim"}
OPERATORS = {
    "pm": "±", "mp": "∓", "cdot": "⋅", "times": "×", "leq": "≤", "le": "≤", "geq": "≥", "ge": "≥", "neq": "≠",
    "ne": "≠", "approx": "≈", "to": "→", "rightarrow": "→", "Rightarrow": "⇒", "infty": "∞", "partial": "∂",
    "ldots": "…", "cdots": "⋯", "dots": "…", "int": "∫", "sum": "∑", "prod": "∏", "vert": "|", "lvert": "|",
    "rvert": "|", "mid": "|", "Vert": "‖", "equiv": "≡", "sim": "∼", "propto": "∝", "in": "∈", "cdotp": "⋅",
    "lbrace": "{", "rbrace": "}", "langle": "⟨", "rangle": "⟩", "circ": "∘", "nabla": "∇", "ell": "ℓ",
    "{": "{", "}": "}", "|": "‖", "%": "%", "_": "_", "#": "#", "&": "&",
}
SPACES = {",": "0.167em", ":": "0.222em", ";": "0.278em", " ": "0.25em", "quad": "1em", "qquad": "2em",
          "!": "0em"}
ACCENTS = {"dot": "˙", "ddot": "¨", "hat": "^", "bar": "¯", "tilde": "~", "vec": "→", "overline": "¯"}
TEXT_COMMANDS = {"text", "mathrm", "textrm", "mbox", "mathit", "mathbf", "textit", "textbf"}
#: Commands that only steer TeX's layout: drawn as nothing.
IGNORED = {"displaystyle", "limits", "nolimits"}
ENVIRONMENTS = {"cases", "matrix", "pmatrix", "bmatrix", "aligned", "array"}
_TOKEN = re.compile(r"\\([A-Za-z]+|.)|(\d+(?:\.\d+)?)|(\s+)|(.)", re.S)


class TexError(ValueError):
    """A formula outside the supported subset."""


def _tokens(tex: str) -> list:
    out = []
    for m in _TOKEN.finditer(tex):
        cmd, num, space, ch = m.groups()
        if space:
            out.append(("sp", " "))
            continue
        out.append(("cmd", cmd) if cmd is not None else ("num", num) if num is not None else ("ch", ch))
    return out


def _esc(s: str) -> str:
    return html.escape(s, quote=False)


class _Parser:
    def __init__(self, tex: str):
        self.toks = _tokens(tex)
        self.i = 0

    def peek(self):
        while self.i < len(self.toks) and self.toks[self.i][0] == "sp":
            self.i += 1
        return self.toks[self.i] if self.i < len(self.toks) else (None, None)

    def take(self):
        tok = self.peek()
        if tok[0] is None:
            raise TexError("unexpected end of formula")
        self.i += 1
        return tok

    def group(self) -> str:
        """One argument: a braced group or a single atom."""
        kind, val = self.peek()
        if kind == "ch" and val == "{":
            self.take()
            items = self.sequence(stop="}")
            self.take()
            return _row(items)
        return self.atom()

    def raw_group(self) -> str:
        """The text of a braced argument (for \\text and environment names)."""
        if self.take() != ("ch", "{"):
            raise TexError("expected {")
        depth, parts = 1, []
        while True:
            if self.i >= len(self.toks):
                raise TexError("missing }")
            kind, val = self.toks[self.i]
            self.i += 1
            if kind == "ch" and val == "{":
                depth += 1
            elif kind == "ch" and val == "}":
                depth -= 1
                if depth == 0:
                    return "".join(parts)
            parts.append("\\" + val if kind == "cmd" and val != " " else " " if kind == "cmd" else val)

    def sequence(self, stop=None, stops=()) -> list:
        items = []
        while True:
            kind, val = self.peek()
            if kind is None:
                if stop is not None:
                    raise TexError(f"missing {stop}")
                return items
            if kind == "ch" and val == stop:
                return items
            if (kind, val) in stops:
                return items
            if kind == "cmd" and val == "right":
                raise TexError("\\right without \\left")
            items.append(self.scripted())

    def scripted(self) -> str:
        base = self.atom()
        sub = sup = None
        primes = ""
        while True:
            kind, val = self.peek()
            if kind == "ch" and val == "^" and sup is None:
                self.take()
                sup = self.group()
            elif kind == "ch" and val == "_" and sub is None:
                self.take()
                sub = self.group()
            elif kind == "ch" and val == "'":
                self.take()
                primes += "<mo>′</mo>"
            else:
                break
        if primes:  # z'' and z'^2: the primes (and the exponent) are one superscript
            sup = f"<mrow>{primes}</mrow>" if sup is None else f"<mrow>{primes}{sup}</mrow>"
        # A function name carries its scripts (cos^3): the application operator follows them.
        apply = ""
        if base.endswith(_APPLY) and (sub is not None or sup is not None):
            base, apply = base[:-len(_APPLY)], _APPLY
        if sub is not None and sup is not None:
            return f"<msubsup>{base}{sub}{_row([sup])}</msubsup>{apply}"
        if sup is not None:
            return f"<msup>{base}{_row([sup])}</msup>{apply}"
        if sub is not None:
            return f"<msub>{base}{sub}</msub>{apply}"
        return base

    def atom(self) -> str:
        kind, val = self.take()
        if kind == "num":
            return f"<mn>{val}</mn>"
        if kind == "ch":
            if val == "{":
                items = self.sequence(stop="}")
                self.take()
                return _row(items)
            if val.isalpha():
                return f"<mi>{_esc(val)}</mi>"
            if val in "}^_&":
                raise TexError(f"unexpected {val!r}")
            return f"<mo>{_esc(val)}</mo>"
        return self.command(val)

    def command(self, name: str) -> str:
        if name in GREEK:
            variant = ' mathvariant="normal"' if name[0].isupper() else ""
            return f"<mi{variant}>{GREEK[name]}</mi>"
        if name in SPACES:
            return f'<mspace width="{SPACES[name]}"/>'
        if name == "operatorname":
            return f"<mi>{_esc(self.raw_group())}</mi>{_APPLY}"
        if name in FUNCTIONS:
            return f"<mi>{name}</mi>{_APPLY}"
        if name in OPERATORS:
            return f"<mo>{_esc(OPERATORS[name])}</mo>"
        if name == "frac" or name == "dfrac" or name == "tfrac":
            return f"<mfrac>{self.group()}{self.group()}</mfrac>"
        if name == "sqrt":
            if self.peek() == ("ch", "["):
                self.take()
                index = _row(self.sequence(stop="]"))
                self.take()
                return f"<mroot>{self.group()}{index}</mroot>"
            return f"<msqrt>{self.group()}</msqrt>"
        if name in ACCENTS:
            return f'<mover accent="true">{self.group()}<mo>{ACCENTS[name]}</mo></mover>'
        if name in TEXT_COMMANDS:
            text = self.raw_group()
            if name in ("mathit", "textit"):
                return f"<mi>{_esc(text)}</mi>"
            return f"<mtext>{_esc(text)}</mtext>"
        if name == "left":
            opening = self.delimiter()
            items = self.sequence(stops=(("cmd", "right"),))
            if self.take() != ("cmd", "right"):
                raise TexError("\\left without \\right")
            closing = self.delimiter()
            return _row([opening, *items, closing])
        if name in IGNORED:
            return "<mrow></mrow>"
        if name == "begin":
            return self.environment(self.raw_group())
        raise TexError(f"unsupported command \\{name}")

    def delimiter(self) -> str:
        kind, val = self.take()
        if kind == "ch" and val == ".":
            return "<mrow></mrow>"
        if kind == "ch":
            return f'<mo stretchy="true">{_esc(val)}</mo>'
        if val in OPERATORS:
            return f'<mo stretchy="true">{_esc(OPERATORS[val])}</mo>'
        raise TexError(f"unsupported delimiter \\{val}")

    def environment(self, name: str) -> str:
        if name not in ENVIRONMENTS:
            raise TexError(f"unsupported environment {name}")
        if name == "array":
            self.raw_group()  # column specification
        rows, row, cell = [], [], []
        while True:
            kind, val = self.peek()
            if kind is None:
                raise TexError(f"missing \\end{{{name}}}")
            if kind == "cmd" and val == "end":
                self.take()
                self.raw_group()
                break
            if kind == "ch" and val == "&":
                self.take()
                row.append(cell)
                cell = []
            elif kind == "cmd" and val == "\\":
                self.take()
                row.append(cell)
                rows.append(row)
                row, cell = [], []
            else:
                cell.append(self.scripted())
        if cell or row:
            row.append(cell)
            rows.append(row)
        table = "<mtable>" + "".join(
            "<mtr>" + "".join(f'<mtd columnalign="left">{_row(c)}</mtd>' for c in r) + "</mtr>" for r in rows
        ) + "</mtable>"
        fences = {"cases": ("{", ""), "pmatrix": ("(", ")"), "bmatrix": ("[", "]")}.get(name, ("", ""))
        left = f'<mo stretchy="true">{fences[0]}</mo>' if fences[0] else ""
        right = f'<mo stretchy="true">{fences[1]}</mo>' if fences[1] else ""
        return f"<mrow>{left}{table}{right}</mrow>"


def _row(items) -> str:
    return items[0] if len(items) == 1 else "<mrow>" + "".join(items) + "</mrow>"


def tex_to_mathml(tex: str, *, display: bool = False) -> str:
    """The MathML of a TeX formula (the subset above); raises :class:`TexError` outside it."""
    parser = _Parser(tex)
    items = parser.sequence()
    if parser.peek()[0] is not None:
        raise TexError("unbalanced formula")
    attr = ' display="block"' if display else ""
    return (f"<math{attr}><semantics>{'<mrow>' + ''.join(items) + '</mrow>'}"
            f'<annotation encoding="application/x-tex">{_esc(tex)}</annotation></semantics></math>')


def to_mathml(tex: str, *, display: bool = False) -> str | None:
    """:func:`tex_to_mathml`, or None for a formula outside the subset (the caller shows its TeX)."""
    try:
        return tex_to_mathml(tex, display=display)
    except (TexError, IndexError):
        return None
