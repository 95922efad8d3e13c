"""The rendered notebooks in docs/notebooks/ are current: the stored notebooks' cells, executed, no errors.

``python derivations/nbtool.py render`` writes them; these checks read files only (no
kernel), so they run in the quick suite.  The one test that renders (into a temporary
folder) is slow.
"""
from __future__ import annotations

import json
from pathlib import Path

import pytest
from readme_blocks import load_nbtool

ROOT = Path(__file__).resolve().parent.parent
DERIVATIONS = ROOT / "derivations"
RENDERED = ROOT / "docs" / "notebooks"
NOTEBOOKS = sorted(DERIVATIONS.glob("*.ipynb"))


nbtool = load_nbtool()


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_rendered_copy_is_current(path):
    assert nbtool.rendered_problems(path) == []


def test_no_rendered_copy_without_its_notebook():
    stems = {p.stem for p in NOTEBOOKS}
    assert {p.stem for p in RENDERED.glob("*.ipynb")} == stems
    assert {p.stem for p in RENDERED.glob("*.md") if p.name != "README.md"} == stems


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_rendered_copy_shows_figures_and_its_markdown_links_them(path):
    copy = json.loads((RENDERED / path.name).read_text(encoding="utf-8"))
    pngs = sum("image/png" in o.get("data", {}) for c in copy["cells"] for o in c.get("outputs", []))
    assert pngs >= 1
    page = (RENDERED / f"{path.stem}.md").read_text(encoding="utf-8")
    linked = [line for line in page.splitlines() if line.startswith("![figure")]
    assert len(linked) == pngs
    for line in linked:
        assert (RENDERED / line.split("](", 1)[1].rstrip(")")).is_file(), line


def test_the_check_catches_a_stale_or_failed_copy(tmp_path):
    path = DERIVATIONS / "circle.ipynb"
    copy = json.loads((RENDERED / path.name).read_text(encoding="utf-8"))
    (tmp_path / "circle.md").write_text("x", encoding="utf-8")
    stale = json.loads(json.dumps(copy))
    code = next(c for c in stale["cells"] if c["cell_type"] == "code")
    code["source"] = "print('edited')"
    (tmp_path / path.name).write_text(json.dumps(stale), encoding="utf-8")
    assert any("cells differ" in p for p in nbtool.rendered_problems(path, tmp_path))
    failed = json.loads(json.dumps(copy))
    cell = next(c for c in failed["cells"] if c["cell_type"] == "code")
    cell["outputs"].append({"output_type": "error", "ename": "AssertionError", "evalue": "", "traceback": []})
    (tmp_path / path.name).write_text(json.dumps(failed), encoding="utf-8")
    assert nbtool.rendered_problems(path, tmp_path) == ["an output is an error"]
    (tmp_path / path.name).unlink()
    assert nbtool.rendered_problems(path, tmp_path) == ["no rendered copy circle.ipynb"]


@pytest.mark.slow
def test_render_writes_a_current_copy(tmp_path, monkeypatch):
    pytest.importorskip("nbclient")
    monkeypatch.setenv("SYMVIB_CACHE", str(tmp_path / "kernels"))
    path = DERIVATIONS / "explorer.ipynb"
    assert nbtool.main(["render", str(path), "--out", str(tmp_path)]) == 0
    assert nbtool.rendered_problems(path, tmp_path) == []
    assert list((tmp_path / "explorer_files").glob("*.png"))
