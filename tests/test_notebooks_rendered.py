"""The rendered pages in docs/notebooks/ are current, hold each figure once, and a render is deterministic.

``python derivations/nbtool.py render`` writes one Markdown page per notebook of
``derivations/`` (``NAME.md``) and its figures as files (``NAME_files/figure-NN.png``).
These checks read files only (no kernel), so they run in the quick suite; the one test
that renders (a notebook twice, into temporary folders, compared byte for byte) is slow.
"""
from __future__ import annotations

import base64
import json
import re
import shutil
from pathlib import Path

import pytest
from readme_blocks import load_nbtool

ROOT = Path(__file__).resolve().parent.parent
DERIVATIONS = ROOT / "derivations"
RENDERED = ROOT / "docs" / "notebooks"
NOTEBOOKS = sorted(DERIVATIONS.glob("*.ipynb"))


nbtool = load_nbtool()


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_rendered_page_is_current(path):
    assert nbtool.rendered_problems(path) == []


def test_each_notebook_has_a_page_and_nothing_else_is_rendered():
    """One page and one figure folder per notebook; no executed ``.ipynb`` (its figures would be stored twice)."""
    stems = {p.stem for p in NOTEBOOKS}
    assert {p.stem for p in RENDERED.glob("*.md") if p.name != "README.md"} == stems
    assert {p.name for p in RENDERED.iterdir() if p.is_dir()} == {f"{s}_files" for s in stems}
    assert {p.name for p in RENDERED.iterdir() if p.is_file()} == {"README.md"} | {f"{s}.md" for s in stems}


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_each_figure_is_stored_once(path):
    """A page links files for its figures: no image data inline, no figure linked twice or left unlinked."""
    page = (RENDERED / f"{path.stem}.md").read_text(encoding="utf-8")
    assert "data:image" not in page and "base64" not in page
    assert not re.search(r"[A-Za-z0-9+/]{400}", page), "a long base64 run on the page"
    linked = re.findall(r"^!\[figure (\d+)\]\(([^)]+)\)$", page, re.M)
    assert linked, f"{path.stem} shows no figure"
    assert [int(n) for n, _ in linked] == list(range(1, len(linked) + 1))
    files = sorted(f"{path.stem}_files/{f.name}" for f in (RENDERED / f"{path.stem}_files").iterdir())
    assert sorted(link for _, link in linked) == files


def test_rendered_files_hold_no_run_metadata():
    """Nothing of a run that changes from render to render: dates, times, temporary paths, kernel metadata."""
    volatile = re.compile(r"\b20\d\d-\d\d-\d\dT\d\d:\d\d|/tmp/|/home/|/root/|execution_count|\"execution\"|"
                          r"iopub\.|shell\.execute|kernelspec|language_info|\(\d+\.\d s\)")
    for page in sorted(RENDERED.glob("*.md")):
        found = volatile.findall(page.read_text(encoding="utf-8"))
        assert not found, f"{page.name}: {found}"
    for figure in sorted(RENDERED.glob("*_files/*")):
        assert nbtool.figure_problems(figure) == []


def _executed():
    """A small executed notebook: a markdown cell, a code cell with a stream, a figure and a LaTeX output."""
    png = next(RENDERED.glob("*_files/*.png")).read_bytes()
    cells = [{"cell_type": "markdown", "id": "a", "metadata": {}, "source": "# Title"},
             {"cell_type": "code", "id": "b", "metadata": {"execution": {"iopub.status.busy": "2026-01-01T00:00"}},
              "execution_count": 1, "source": "print(1)",
              "outputs": [{"output_type": "stream", "name": "stdout", "text": "1\n"},
                          {"output_type": "display_data", "metadata": {},
                           "data": {"image/png": base64.b64encode(png).decode(), "text/plain": "<Figure>"}},
                          {"output_type": "execute_result", "execution_count": 1, "metadata": {},
                           "data": {"text/latex": "$x$", "text/plain": "x"}}]}]
    return {"cells": cells, "metadata": {}, "nbformat": 4, "nbformat_minor": 5}, png


def test_the_page_is_the_same_for_the_same_run_and_holds_the_figure_once(tmp_path):
    nb, png = _executed()
    first = nbtool.markdown_export(nb, "demo", tmp_path / "a" / "demo_files")
    again = json.loads(json.dumps(nb))
    again["cells"][1]["id"] = "other"                  # ids, counts and metadata are not on the page
    again["cells"][1]["execution_count"] = 7
    again["cells"][1]["metadata"] = {}
    assert nbtool.markdown_export(again, "demo", tmp_path / "b" / "demo_files") == first
    assert (tmp_path / "a" / "demo_files" / "figure-01.png").read_bytes() == png
    assert first.count("![figure 1](demo_files/figure-01.png)") == 1 and "2026" not in first
    assert f"(cells {nbtool.cells_digest(nb['cells'])})" in first.splitlines()[0]
    nb["cells"][1]["outputs"].append({"output_type": "error", "ename": "AssertionError", "evalue": "",
                                      "traceback": []})
    with pytest.raises(ValueError, match="cell 2 failed"):
        nbtool.markdown_export(nb, "demo", tmp_path / "c" / "demo_files")


def test_the_check_catches_a_stale_edited_or_incomplete_page(tmp_path):
    path = DERIVATIONS / "circle.ipynb"
    shutil.copy(RENDERED / "circle.md", tmp_path / "circle.md")
    shutil.copytree(RENDERED / "circle_files", tmp_path / "circle_files")
    assert nbtool.rendered_problems(path, tmp_path) == []
    page = (tmp_path / "circle.md").read_text(encoding="utf-8")

    stale = re.sub(r"\(cells [0-9a-f]{16}\)", "(cells 0123456789abcdef)", page, count=1)
    (tmp_path / "circle.md").write_text(stale, encoding="utf-8")
    assert any("cells differ" in p for p in nbtool.rendered_problems(path, tmp_path))

    edited = page.replace("d = derive(sh)\n", "d = derive(sh)  # edited by hand\n", 1)
    assert edited != page
    (tmp_path / "circle.md").write_text(edited, encoding="utf-8")
    assert any("not on the page" in p for p in nbtool.rendered_problems(path, tmp_path))

    (tmp_path / "circle.md").write_text(page, encoding="utf-8")
    figure = tmp_path / "circle_files" / "figure-01.png"
    data = figure.read_bytes()
    figure.unlink()
    assert nbtool.rendered_problems(path, tmp_path) == ["figure circle_files/figure-01.png is missing"]
    # The same figure with Matplotlib's Software text chunk (as a render without the fixed config writes it).
    chunk = b"tEXtSoftware\x00Matplotlib"
    figure.write_bytes(data[:33] + len(chunk[4:]).to_bytes(4, "big") + chunk + b"\x00\x00\x00\x00" + data[33:])
    assert nbtool.rendered_problems(path, tmp_path) == ["figure-01.png carries PNG chunks tEXt"]
    figure.write_bytes(data)
    (tmp_path / "circle_files" / "figure-99.png").write_bytes(data)
    assert nbtool.rendered_problems(path, tmp_path) == [
        "figure files the page does not link: circle_files/figure-99.png"]

    (tmp_path / "circle.md").unlink()
    assert nbtool.rendered_problems(path, tmp_path) == ["no rendered page circle.md"]


@pytest.mark.slow
def test_render_is_current_and_deterministic(tmp_path):
    """Two renders of a notebook on the same code give the same bytes, and the page is current."""
    pytest.importorskip("nbclient")
    path = DERIVATIONS / "explorer.ipynb"
    for out in ("first", "second"):
        assert nbtool.main(["render", str(path), "--out", str(tmp_path / out)]) == 0
        assert nbtool.rendered_problems(path, tmp_path / out) == []
    first = sorted(p.relative_to(tmp_path / "first") for p in (tmp_path / "first").rglob("*") if p.is_file())
    second = sorted(p.relative_to(tmp_path / "second") for p in (tmp_path / "second").rglob("*") if p.is_file())
    assert first == second and any(p.suffix == ".png" for p in first)
    for rel in first:
        assert (tmp_path / "first" / rel).read_bytes() == (tmp_path / "second" / rel).read_bytes(), rel
