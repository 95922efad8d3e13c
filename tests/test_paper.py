"""``symvib paper``: every promised file, valid figures, and event tables equal to the driver's."""
import json
import struct
import subprocess
import sys

import pytest

from symvib import simulate
from symvib.numeric.events import EventKind
from symvib.paper import report
from symvib.paper.report_html import markdown_to_html

#: Smallest plausible size of a figure file, bytes, and the pixel sizes allowed.
MIN_PNG_BYTES = 10_000
PNG_PIXELS = (400, 3000)


def png_size(path):
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", f"{path.name} is not a PNG"
    assert data[12:16] == b"IHDR"
    return struct.unpack(">II", data[16:24]), len(data)


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    return report.run_paper(tmp_path_factory.mktemp("paper"))


@pytest.mark.slow
def test_every_promised_file_exists(written):
    out = written["report"].parent
    assert (out / "report.md").exists() and (out / "report.html").exists() and (out / "results.json").exists()
    names = {p.name for p in written["figures"]}
    for scene, _ in report.SCENES:
        for fig in ("phase", "F_N", "P_mu", "Ek", "Ep", "E", "energy-time"):
            assert f"{scene}-k{report.HIGH_K:g}-{fig}.png" in names
        for fig in ("phase", "energy-time"):
            assert f"{scene}-k{report.LOW_K:g}-{fig}.png" in names
    for path in written["figures"]:
        (w, h), size = png_size(path)
        assert size > MIN_PNG_BYTES and PNG_PIXELS[0] <= w <= PNG_PIXELS[1] and PNG_PIXELS[0] // 2 <= h <= PNG_PIXELS[1]
    text = (out / "report.md").read_text()
    for fig in names:
        assert f"(figures/{fig})" in text


@pytest.mark.slow
def test_event_tables_match_the_driver(written):
    text = written["report"].read_text()
    tables = report.parse_event_tables(text)
    assert len(tables) == len(report.SCENES) * 2
    for run in written["runs"]:
        fresh = simulate(run.scene, backend="python", samples=False)
        rows = tables[run.key]
        assert [r[0] for r in rows] == [e.kind.value for e in fresh.events]
        for row, e in zip(rows, fresh.events):
            for got, want in zip(row[1:], (e.t, e.q, e.qdot_before, e.qdot_after, e.energy)):
                assert got == pytest.approx(want, rel=1e-11, abs=1e-12)
    results = json.loads((written["report"].parent / "results.json").read_text())
    assert results["paper-circle-7-k1"]["status"] == "arrested"


@pytest.mark.slow
def test_report_states_the_readings_and_the_errata(written):
    text = written["report"].read_text()
    assert "pi - 3" in text and "one impact and one oscillation until arrestment" in text
    assert "## Errata of the paper's printed equations" in text
    assert "**differs**" in text and r"\frac{\mu}{2}" in text and "(differs)" not in text
    assert "k = 0.8" in text
    # The conclusions, and the seed's text beside each transcription.
    from symvib.paper.audit import PRINTED, seed_cell
    from symvib.paper.conclusions import CLAIM_KEYS

    conclusions = text.split("## Conclusions")[1].split("## Errata")[0]
    assert all(c.quote in conclusions for c in CLAIM_KEYS)
    assert all(seed_cell(e) in text for e in PRINTED if e.shape != "general")
    assert '| "alpha0 = 3" | circle (fig. 20) | **differs** | root |' in text
    # The reading chosen reproduces the remark: one impact, then oscillation, then arrest.
    run = next(r for r in written["runs"] if r.key == "paper-circle-3.8-k1")
    kinds = [e.kind for e in run.result.events]
    assert kinds.count(EventKind.IMPACT) == 1 and kinds[-1] is EventKind.ARREST


def test_markdown_to_html_renders_tables_and_images():
    html = markdown_to_html("# T\n\n| a | b |\n| --- | --- |\n| 1 | $x$ |\n\n![f](figures/f.png)\n", title="t")
    assert "<table>" in html and "<td>1</td>" in html and 'src="figures/f.png"' in html
    assert "<math><semantics><mrow><mi>x</mi>" in html and "MathJax" not in html  # offline (issue 16)


def test_cli_rejects_a_bad_restitution():
    out = subprocess.run([sys.executable, "-m", "symvib.cli", "paper", "--restitution", "1.5"],
                         capture_output=True, text=True)
    assert out.returncode == 2 and "--restitution" in out.stderr and "Traceback" not in out.stderr
