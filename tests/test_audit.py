"""The paper audited: the verdict for every printed equation, each transcription against the seed's
text, and the errata document."""
import dataclasses
import re
from pathlib import Path

import pytest
import sympy as sp

from symvib.paper.audit import GENERAL, PRINTED, audit, errata_markdown, pm, seed_differences
from symvib.paper.errata import errata_document
from symvib.paper.seed import OCR_EDITS, SEED_FILE, SEED_TEXT
from symvib.paper.seedtex import SeedTexError, layout, read
from symvib.symbolic.symbols import mu

ROOT = Path(__file__).resolve().parents[1]
#: The seed shipped with the checkout, and the project's shared copy beside the checkout (or a worktree's).
SEED_PATH = ROOT / "docs" / "seed" / SEED_FILE
SHARED_SEEDS = [p / "shared" / "seed" / SEED_FILE for p in ROOT.parents[:2]]

#: Verdicts established by hand (see docs/errata.md for the evidence).
EXPECTED = {
    "eq1": True, "eq2": False,
    "eq3": True, "eq4": True, "parabola.F_N": True, "parabola.P_mu": True, "parabola.Ek": True,
    "parabola.Ep": True, "parabola.E": True,
    "eq5": False, "eq6": False, "cycloid.F_N": False, "cycloid.P_mu": False, "cycloid.Ek": False,
    "cycloid.Ep": True, "cycloid.E": False,
    "eq7": True, "eq8": False, "circle.F_N": False, "circle.P_mu": False, "circle.Ek": False,
    "circle.Ep": True, "circle.E": False,
}


#: Root errors and inherited ones, established by hand (an entry not here matches).
ORIGIN = {
    "eq2": "root", "eq5": "root", "eq6": "inherited from eq. (5)", "cycloid.F_N": "root; also inherits eq. (6)",
    "cycloid.P_mu": "inherited from the printed F_N and eq. (6)", "cycloid.Ek": "inherited from eq. (6)",
    "cycloid.E": "inherited from eq. (6)", "eq8": "root", "circle.F_N": "inherited from eq. (8)",
    "circle.P_mu": "root; also inherits the printed F_N and eq. (8)", "circle.Ek": "inherited from eq. (8)",
    "circle.E": "inherited from eq. (8)",
}


@pytest.fixture(scope="module")
def verdicts():
    return audit()


def test_root_and_inherited_errors(verdicts):
    assert {v.key: v.origin for v in verdicts if v.origin} == ORIGIN


def test_every_printed_equation_has_its_verdict(verdicts):
    got = {v.key: v.matches for v in verdicts}
    assert got == EXPECTED


def test_evidence_says_what_is_wrong(verdicts):
    by = {v.key: v for v in verdicts}
    assert "with e^{+int ... dx} inside the integral" in by["eq2"].evidence
    assert r"\frac{\mu}{2}" in by["eq5"].evidence
    assert "solve the printed eq. (5)" in by["eq6"].evidence
    assert "lower sign" in by["eq8"].evidence and "upper sign (v > 0) is right" in by["eq8"].evidence
    assert "itself wrong" in by["cycloid.F_N"].evidence
    assert "inserted phase trajectory" in by["circle.F_N"].evidence
    assert by["parabola.Ep"].how == "equal up to a shift of the potential-energy level"


def test_errata_document_is_current(verdicts):
    path = ROOT / "docs" / "errata.md"
    assert path.read_text(encoding="utf-8").strip() == errata_document(verdicts).strip(), \
        "docs/errata.md is stale: run `python -m symvib.paper.errata docs/errata.md`"


def test_errata_document_has_the_alpha0_row_and_the_conclusions(verdicts):
    text = errata_document(verdicts)
    row = next(line for line in text.splitlines() if line.startswith('| "alpha0 = 3"'))
    assert "| **differs** | root |" in row and "pi - 3" in row
    assert "## The paper's conclusions, checked" in text and "(differs)" not in text


def test_errata_table_rows_keep_their_four_cells(verdicts):
    # A note may hold "|F_N|" or "eq. (6)": neither may split a cell or cut the note short.
    text = errata_markdown(verdicts)
    table = text.split("\n\n| eq. | curve | verdict | error | note |")[1].split("\n\n")[0]
    rows = [line for line in table.splitlines() if line.startswith("| ") and not line.startswith("| ---")]
    assert len(rows) == len(verdicts)
    for row in rows:
        assert len(re.split(r"(?<!\\)\|", row.strip()[1:-1])) == 5, row
    notes = {v.key: re.split(r"(?<!\\)\|", row.strip()[1:-1])[4].strip() for v, row in zip(verdicts, rows)}
    assert notes["eq6"].startswith("Eq. (6) solves the printed eq. (5), not the equation of motion")
    assert notes["circle.P_mu"].startswith(r"The power of friction is -mu \|F_N\| R \|phidot\| <= 0")


def test_report_html_keeps_escaped_pipes_in_cells():
    from symvib.paper.report_html import markdown_to_html

    html = markdown_to_html("| a | b |\n| --- | --- |\n| x \\|y\\| | z |\n", title="t")
    assert "<td>x |y|</td><td>z</td>" in html


# --- every transcription against the seed's own text ------------------------------------------
def test_the_shipped_seed_is_the_projects_seed():
    shared = [p for p in SHARED_SEEDS if p.exists()]
    if not shared:
        pytest.skip("no shared seed beside the checkout")
    assert SEED_PATH.read_bytes() == shared[0].read_bytes()


@pytest.mark.parametrize("entry", PRINTED, ids=lambda e: e.key)
def test_seed_text_is_verbatim_in_the_seed(entry):
    seed = SEED_PATH.read_text(encoding="utf-8")
    assert entry.seed_text and entry.seed_text == SEED_TEXT[entry.key]
    assert seed.count(entry.seed_text) == 1, f"{entry.key}: its seed_text is not (once) in {SEED_FILE}"


@pytest.mark.parametrize("entry", PRINTED, ids=lambda e: e.key)
def test_transcription_equals_the_seed_text(entry):
    # The seed's text, read into SymPy with only the declared OCR edits, equals the transcription
    # (and, where printed, its form in terms of the velocity).
    assert seed_differences(entry) == []


def test_every_printed_equation_has_a_seed_text_and_every_declaration_a_reason():
    assert {e.key for e in PRINTED} == set(SEED_TEXT)
    assert set(OCR_EDITS) <= set(SEED_TEXT)
    for key, edits in OCR_EDITS.items():
        for e in edits:
            assert len(e.reason) > 20 and e.seed != e.reading, (key, e)
            assert e.seed in layout(SEED_TEXT[key]), (key, e.seed)


def _entry(key):
    return next(e for e in PRINTED if e.key == key)


@pytest.mark.parametrize("key, mutate", [
    # The old transcription of eq. (2): e^{+int} inside the integral, the corrected form.
    ("eq2", lambda e: dataclasses.replace(e, build=lambda c: e.build(c).replace(
        lambda x: isinstance(x, sp.Integral) and x.function.has(sp.exp),
        lambda x: sp.Integral(x.function.replace(sp.exp, lambda a: sp.exp(-a)), *x.limits)))),
    # A sign inside eq. (8) flipped (the corrected lower branch).
    ("eq8", lambda e: dataclasses.replace(e, build=lambda c: e.build(c).subs(pm * sp.atan(mu), -pm * sp.atan(mu)))),
    # An exponent changed: cos^6 -> cos^4 in eq. (4).
    ("eq4", lambda e: dataclasses.replace(e, build=lambda c: e.build(c) / sp.cos(c.q) ** 2)),
    # The velocity form of a P_mu off by its sign.
    ("circle.P_mu", lambda e: dataclasses.replace(e, formula=lambda c, F_N=None: -e.formula(c, F_N))),
    # A declared OCR difference left out: the missing dot then differs.
    ("cycloid.P_mu", lambda e: dataclasses.replace(e, ocr=())),
])
def test_an_undeclared_difference_fails(key, mutate):
    assert seed_differences(mutate(_entry(key))), f"a changed {key} went unnoticed"


def test_a_declaration_that_does_not_match_fails():
    from symvib.paper.seedtex import Edit

    e = _entry("eq3")
    bad = dataclasses.replace(e, ocr=(Edit(r"\sin\phi \pm", r"\sin\phi -", "a made-up reason of some length"),))
    assert seed_differences(bad)  # the edit matches nothing after layout (the seed writes "\sin\phi \pm")
    with pytest.raises(SeedTexError, match="unknown symbol"):
        read(SEED_TEXT["eq3"], (), {"pm": pm}, sides=(0,))


def test_general_entries_are_built_on_the_general_symbols():
    assert _entry("eq1").build(GENERAL).has(GENERAL.R_k) and _entry("eq2").build(GENERAL).has(sp.Integral)
