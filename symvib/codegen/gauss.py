"""The table of Gauss-Legendre rules, ``generated/gauss_rules.py`` (written and checked here).

Nodes, weights and integration matrices are computed at high precision and
rounded once by :func:`symvib.quadrature_rules.rule_mp` (mpmath; why the last
ulp matters is told there); this module writes the node counts in
:data:`TABULATED` as exact literals (``symvib generate``) and checks the table
against a fresh computation (``symvib generate --check``), so running the
driver needs no mpmath (:mod:`symvib.numeric.quadrature` reads the table and
computes other node counts with the same function on first use).

Examples
--------
>>> 16 in TABULATED and max(TABULATED) <= MAX_NODES   # the driver's default rule is in the table
True
>>> [round(v * 3 ** 0.5, 15) for v in rule_mp(2)[0]]   # the 2-point rule's nodes, -+1/sqrt(3)
[-1.0, 1.0]
"""
from __future__ import annotations

import hashlib
from pathlib import Path

# The computation (mpmath only) lives on the ground floor, where the numeric fallback finds it too.
from symvib.quadrature_rules import DPS, MAX_NODES, rule_mp

__all__ = ["rule_mp", "table_text", "write_table", "table_problems", "TABULATED", "MAX_NODES"]

#: Node counts written to ``generated/gauss_rules.py`` (the driver's default
#: 16, the benchmark's settings, the 3/4 of them that panels off a root take
#: (:func:`symvib.numeric.driver.plain_nodes`), and a few more).
TABULATED = (1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 12, 15, 16, 18, 20, 24, 32)
#: Name of the table module in the generated folder.
TABLE_MODULE = "gauss_rules"
TABLE_PREFIX = "# symvib generated Gauss-Legendre rules; body sha256: "


def table_text() -> str:
    """Source of ``generated/gauss_rules.py``: ``RULES[n] = (x, w, S, SW)`` as exact literals."""
    lines = ['"""Gauss-Legendre rules and integration matrices, correctly rounded',
             "(written by ``symvib generate`` from :func:`symvib.codegen.gauss.rule_mp`; do not edit).",
             '"""', "", f"DPS = {DPS}", "RULES = {}"]
    for n in TABULATED:
        x, w, S, SW = rule_mp(n)
        lines.append(f"RULES[{n}] = (")
        for name, rows in (("x", [x]), ("w", [w]), ("S", S), ("SW", SW)):
            lines.append(f"    # {name}")
            lines.append("    (" if name in ("S", "SW") else "")
            for row in rows:
                lines.append("        (" + ", ".join(repr(v) for v in row) + ("," if n == 1 else "") + "),")
            lines.append("    )," if name in ("S", "SW") else "")
        lines.append(")")
    body = "\n".join(line for line in lines if line != "") + "\n"
    return TABLE_PREFIX + hashlib.sha256(body.encode()).hexdigest() + "\n" + body


def write_table(out_dir) -> Path:
    """Write the table module into ``out_dir`` (:func:`symvib.safeio.write_text`); returns its path."""
    from symvib import safeio

    out = safeio.check_root(out_dir, "output folder")
    return safeio.write_text(out, f"{TABLE_MODULE}.py", table_text())


def table_problems(out_dir) -> list:
    """Empty when ``out_dir``'s table equals a fresh computation, else what is wrong."""
    path = Path(out_dir) / f"{TABLE_MODULE}.py"
    if not path.exists():
        return [f"{path}: missing"]
    if path.read_text(encoding="utf-8") != table_text():
        return [f"{path}: stale or edited by hand; run `symvib generate`"]
    return []
