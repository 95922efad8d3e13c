"""docs/physics.md holds what is cited: every ``physics.md, "Section"`` names one of its headings.

Citations take three forms (docs/physics.md, first paragraph):
``(physics.md, "Events")`` a section by its heading, ``(physics.md, "Events" 4)``
item 4 of the section's numbered list, and ``(physics.md, eq. 2)`` the section of
the paper's equation 2 (a heading ending ``(paper eq. 2)``).
"""
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PHYSICS = ROOT / "docs" / "physics.md"
#: Where citations are looked for: the package, the README and the other documents.
CITING = sorted([*(ROOT / "symvib").rglob("*.py"), ROOT / "README.md",
                 *(p for p in (ROOT / "docs").glob("*.md") if p != PHYSICS), *(ROOT / "derivations").glob("*.ipynb")])
#: ``physics.md`` then, within a few characters (``, `` or `` (``), a quoted heading and an optional item number.
SECTION = re.compile(r'physics\.md(?:,\s*|\s+\(|\s+)"([^"\\]+)"(?:\s+(\d+))?')
#: ``physics.md, eq. N``.
EQUATION = re.compile(r"physics\.md(?:,\s*|\s+\(|\s+)eq\.\s*(\d+)")


def sections() -> dict:
    """Heading text -> the section's body, for every ``##`` (and deeper) heading of physics.md."""
    out, name = {}, None
    for line in PHYSICS.read_text(encoding="utf-8").splitlines():
        heading = re.match(r"#{2,6}\s+(.*?)\s*$", line)
        if heading:
            name = heading.group(1)
            out[name] = []
        elif name is not None:
            out[name].append(line)
    return {k: "\n".join(v) for k, v in out.items()}


def citations() -> list:
    """``(file:line, kind, value, item)`` of every citation of physics.md outside it."""
    found = []
    for path in CITING:
        for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            where = f"{path.relative_to(ROOT).as_posix()}:{n}"
            found += [(where, "section", m.group(1), m.group(2)) for m in SECTION.finditer(line)]
            found += [(where, "equation", m.group(1), None) for m in EQUATION.finditer(line)]
    return found


def test_there_are_citations_to_check():
    kinds = {kind for _, kind, _, _ in citations()}
    assert kinds == {"section", "equation"}, kinds


@pytest.mark.parametrize("where,kind,value,item", citations(), ids=lambda v: str(v))
def test_citation_names_a_heading(where, kind, value, item):
    heads = sections()
    if kind == "equation":
        assert any(h.endswith(f"(paper eq. {value})") for h in heads), \
            f"{where}: cites physics.md, eq. {value}; no heading of docs/physics.md ends '(paper eq. {value})'"
        return
    assert value in heads, f"{where}: cites physics.md, \"{value}\"; docs/physics.md headings: {sorted(heads)}"
    if item is not None:
        assert re.search(rf"^{item}\.\s", heads[value], re.M), \
            f"{where}: cites item {item} of physics.md, \"{value}\", which has no item {item}"


def test_the_scan_sees_each_form():
    line = 'x (physics.md, "Events" 4) y (physics.md ("Assumptions", regular) z (physics.md, eq. 2)'
    assert [(m.group(1), m.group(2)) for m in SECTION.finditer(line)] == [("Events", "4"), ("Assumptions", None)]
    assert [m.group(1) for m in EQUATION.finditer(line)] == ["2"]
    assert not SECTION.search('keep their events (docs/physics.md). `"unilateral"` is')
