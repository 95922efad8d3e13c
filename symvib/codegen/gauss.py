"""The table of Gauss-Legendre rules, ``generated/gauss_rules.json`` (written and checked here).

Nodes, weights and integration matrices are computed at high precision and
rounded once by :func:`symvib.quadrature_rules.rule_mp` (mpmath; why the last
ulp matters is told there); this module writes the node counts in
:data:`TABULATED` (``symvib generate``; the format is
:func:`symvib.quadrature_rules.table_text`'s: exact JSON data) and checks the table
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

from pathlib import Path

# The computation (mpmath only) and the table's format live on the ground floor, where the
# numeric wing's reader finds them too.
from symvib import quadrature_rules
from symvib.quadrature_rules import MAX_NODES, TABLE_FILE, rule_mp

__all__ = ["rule_mp", "table_text", "write_table", "table_problems", "TABULATED", "MAX_NODES", "TABLE_FILE"]

#: Node counts written to ``generated/gauss_rules.json`` (the driver's default
#: 16, the benchmark's settings, the 3/4 of them that panels off a root take
#: (:func:`symvib.numeric.quadrature.plain_nodes`), and a few more).
TABULATED = (1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 12, 15, 16, 18, 20, 24, 32)
#: Stem of the table's former Python module (:func:`write_table` removes one it finds,
#: :func:`table_problems` names it).
TABLE_MODULE = "gauss_rules"
LEGACY_MODULE = f"{TABLE_MODULE}.py"


def table_text() -> str:
    """Text of ``generated/gauss_rules.json``: the rules of :data:`TABULATED`, computed now."""
    return quadrature_rules.table_text({n: rule_mp(n) for n in TABULATED})


def write_table(out_dir) -> Path:
    """Write the table into ``out_dir`` (:func:`symvib.safeio.write_text`); returns its path.

    The table's former Python module there, if any, is removed.
    """
    from symvib import safeio

    out = safeio.check_root(out_dir, "output folder")
    path = safeio.write_text(out, TABLE_FILE, table_text())
    legacy = out / LEGACY_MODULE
    if legacy.is_file() and not legacy.is_symlink():
        legacy.unlink()
    return path


def table_problems(out_dir) -> list:
    """Empty when ``out_dir``'s table equals a fresh computation, else what is wrong."""
    path = Path(out_dir) / TABLE_FILE
    legacy = Path(out_dir) / LEGACY_MODULE
    problems = [f"{legacy}: the table's former Python module (remove it)"] if legacy.exists() else []
    if not path.exists():
        return problems + [f"{path}: missing"]
    if path.read_text(encoding="utf-8") != table_text():
        problems.append(f"{path}: stale or edited by hand; run `symvib generate`")
    return problems
