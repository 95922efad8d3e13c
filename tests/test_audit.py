"""The paper audited: the verdict for every printed equation, and the errata document."""
from pathlib import Path

import pytest

from symvib.symbolic.audit import audit, errata_markdown

#: Verdicts established by hand (see docs/errata.md for the evidence).
EXPECTED = {
    "eq1": True, "eq2": True,
    "eq3": True, "eq4": True, "parabola.F_N": True, "parabola.P_mu": True, "parabola.Ek": True,
    "parabola.Ep": True, "parabola.E": True,
    "eq5": False, "eq6": False, "cycloid.F_N": False, "cycloid.P_mu": False, "cycloid.Ek": False,
    "cycloid.Ep": True, "cycloid.E": False,
    "eq7": True, "eq8": False, "circle.F_N": False, "circle.P_mu": False, "circle.Ek": False,
    "circle.Ep": True, "circle.E": False,
}


@pytest.fixture(scope="module")
def verdicts():
    return audit()


def test_every_printed_equation_has_its_verdict(verdicts):
    got = {v.key: v.matches for v in verdicts}
    assert got == EXPECTED


def test_evidence_says_what_is_wrong(verdicts):
    by = {v.key: v for v in verdicts}
    assert r"\frac{\mu}{2}" in by["eq5"].evidence
    assert "solve the printed eq. (5)" in by["eq6"].evidence
    assert "lower sign" in by["eq8"].evidence and "upper sign (v > 0) is right" in by["eq8"].evidence
    assert "itself wrong" in by["cycloid.F_N"].evidence
    assert "inserted phase trajectory" in by["circle.F_N"].evidence
    assert by["parabola.Ep"].how == "equal up to a shift of the potential-energy level"


def test_errata_document_is_current(verdicts):
    path = Path(__file__).resolve().parents[1] / "docs" / "errata.md"
    assert path.read_text(encoding="utf-8").strip() == errata_markdown(verdicts).strip(), \
        "docs/errata.md is stale: run `python -m symvib.symbolic.audit docs/errata.md`"


def test_errata_table_rows_keep_their_four_cells(verdicts):
    # A note may hold "|F_N|" or "eq. (6)": neither may split a cell or cut the note short.
    import re

    rows = [line for line in errata_markdown(verdicts).splitlines()
            if line.startswith("| ") and not line.startswith("| ---")]
    assert len(rows) == 1 + len(verdicts)
    for row in rows:
        assert len(re.split(r"(?<!\\)\|", row.strip()[1:-1])) == 4, row
    notes = {v.key: re.split(r"(?<!\\)\|", row.strip()[1:-1])[3].strip() for v, row in zip(verdicts, rows[1:])}
    assert notes["eq6"].startswith("Eq. (6) solves the printed eq. (5), not the equation of motion")
    assert notes["circle.P_mu"].startswith(r"The power of friction is -mu \|F_N\| R \|phidot\| <= 0")


def test_report_html_keeps_escaped_pipes_in_cells():
    from symvib.paper import markdown_to_html

    html = markdown_to_html("| a | b |\n| --- | --- |\n| x \\|y\\| | z |\n", title="t")
    assert "<td>x |y|</td><td>z</td>" in html
