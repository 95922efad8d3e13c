"""The report as HTML that reads offline (formulas as MathML) and as a PDF one flag away (issue 16)."""
import math
import re
import subprocess
import sys
import xml.etree.ElementTree as ET
from html.parser import HTMLParser
from pathlib import Path

import pytest
from matplotlib.figure import Figure

from symvib.paper import report, report_html, report_pdf
from symvib.paper.texmathml import tex_to_mathml, to_mathml

ROOT = Path(__file__).resolve().parents[1]
#: Elements without an end tag (HTML void elements, and MathML's written self-closed).
VOID = {"img", "meta", "br", "hr", "link", "input", "mspace"}
MATHML = "{http://www.w3.org/1998/Math/MathML}"


class Structure(HTMLParser):
    """Checks that every element is closed in order, a list item sits in a list, and collects
    the external references of scripts, styles, images and links."""

    def __init__(self):
        super().__init__()
        self.stack, self.errors, self.external, self.scripts = [], [], [], 0

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag == "li" and (not self.stack or self.stack[-1] not in ("ul", "ol")):
            self.errors.append("li outside a list")
        if tag == "script":
            self.scripts += 1
        for key in ("src", "href"):
            if re.match(r"^\s*(https?:)?//", attrs.get(key) or ""):
                self.external.append((tag, attrs[key]))
        if tag not in VOID:
            self.stack.append(tag)

    def handle_startendtag(self, tag, attrs):
        self.handle_starttag(tag, attrs)
        if tag not in VOID:
            self.stack.pop()

    def handle_endtag(self, tag):
        if not self.stack or self.stack[-1] != tag:
            self.errors.append(f"</{tag}> closes {self.stack[-1:]}")
        else:
            self.stack.pop()


def structure(html_text):
    s = Structure()
    s.feed(html_text)
    s.close()
    return s


SAMPLE = """# The paper reproduced by symvib

*Energy analysis of vibro-impact systems* (parabola), with `symvib paper`.

- [Parabola](#parabola)
- [Circle](#circle)

## Parabola

Geometry: $$h = \\frac{p}{\\cos^{3}{\\left(\\varphi \\right)}},\\quad \\alpha = \\varphi$$

| eq. | printed | verdict |
| --- | --- | --- |
| (3) | $\\ddot{\\varphi} \\pm \\mu \\dot{\\varphi}^{2} = 0$ | **differs** |

![f.png](figures/f.png)

*A caption with $k = 1$.*

Odd: $\\weirdmacro{x}$ stays TeX.
"""


def test_html_needs_no_network_and_is_well_formed():
    out = report_html.markdown_to_html(SAMPLE, title="t")
    s = structure(out)
    assert s.errors == [] and s.stack == []
    assert s.external == [] and s.scripts == 0 and "MathJax" not in out and "http" not in out
    assert "<ul>" in out and out.count("<li>") == 2
    # The title in italics, not with literal stars; formulas as MathML; the figure with its caption.
    assert "<em>Energy analysis of vibro-impact systems</em>" in out and "*Energy" not in out
    assert out.count("<math") == 3 and 'display="block"' in out
    assert re.search(r'<figure><img alt="f.png" src="figures/f.png"><figcaption>A caption with <math', out)
    # A formula outside the supported subset shows its TeX, escaped.
    assert '<code class="tex">\\weirdmacro{x}</code>' in out


def test_mathml_is_well_formed_xml_with_the_tex_kept():
    for tex in (r"\dot{\varphi}^{2} = \frac{\cos^{6}{\left(\varphi \right)} \left(C - 2 F_{\pm} g\right) "
                r"e^{\mp 2 \varphi \mu}}{p^{2}}",
                r"\sqrt{x^{2} + z'^{2}} \leq \mu \vert N \vert",
                r"\begin{cases} a & x > 0 \\ b & \text{otherwise} \end{cases}"):
        root = ET.fromstring(tex_to_mathml(tex).replace("<math>", '<math xmlns="http://www.w3.org/1998/Math/MathML">'))
        assert root.find(f".//{MATHML}annotation").text == tex
    m = tex_to_mathml(r"\frac{a}{b} \sqrt{c} \left( d \right) \dot{q} x_{1}^{2}")
    for tag in ("<mfrac>", "<msqrt>", '<mo stretchy="true">(</mo>', '<mover accent="true">', "<msubsup>"):
        assert tag in m
    assert "<mtext>otherwise</mtext>" in tex_to_mathml(r"\text{otherwise}")


@pytest.mark.parametrize("tex", [r"\frac{a}", r"\left( x", r"x^", r"{x", r"\unknown", r"\begin{tabular}x\end{tabular}"])
def test_a_formula_outside_the_subset_is_refused_not_garbled(tex):
    assert to_mathml(tex) is None


def test_every_formula_of_the_committed_report_renders_as_mathml():
    text = (ROOT / "docs" / "paper" / "report.md").read_text(encoding="utf-8")
    formulas = report_html.formulas(text)
    assert len(formulas) > 100
    assert [f for f in formulas if to_mathml(f) is None] == []
    html_text = (ROOT / "docs" / "paper" / "report.html").read_text(encoding="utf-8")
    s = structure(html_text)
    assert s.errors == [] and s.external == [] and s.scripts == 0


def _pdf_pages(data: bytes) -> int:
    """Page objects of a PDF (``/Type /Page``, not ``/Pages``)."""
    return len(re.findall(rb"/Type\s*/Page(?![s\w])", data))


def test_pdf_has_the_text_pages_and_the_figure_pages(tmp_path):
    figures = []
    for i in range(3):
        fig = Figure(figsize=(4, 3))
        fig.subplots().plot([0, 1], [0, i])
        path = tmp_path / f"f{i}.png"
        fig.savefig(path)
        figures.append(path)
    text = SAMPLE + "\n".join(f"line {i} with $x_{i}$ and a long tail " * 4 for i in range(200))
    path, pages = report_pdf.write_pdf(text, figures, tmp_path / "report.pdf")
    data = path.read_bytes()
    text_pages = len(report_pdf.pdf_text_pages(text))
    assert data.startswith(b"%PDF-")
    assert text_pages > 1 and pages == _pdf_pages(data) == text_pages + math.ceil(3 / report_pdf.PDF_FIGURES_PER_PAGE)


def test_cli_paper_offers_pdf():
    out = subprocess.run([sys.executable, "-m", "symvib.cli", "paper", "--help"], capture_output=True, text=True)
    assert out.returncode == 0 and "--pdf" in out.stdout


@pytest.mark.slow  # the whole paper job (about a minute on 2 shared cores)
def test_paper_pdf_and_html_offline(tmp_path):
    written = report.run_paper(tmp_path, pdf=True)
    data = written["pdf"].read_bytes()
    assert data.startswith(b"%PDF-")
    text = written["report"].read_text(encoding="utf-8")
    per_page = report_pdf.PDF_FIGURES_PER_PAGE
    expected = len(report_pdf.pdf_text_pages(text)) + math.ceil(len(written["figures"]) / per_page)
    assert _pdf_pages(data) == written["pdf_pages"] == expected
    s = structure(written["html"].read_text(encoding="utf-8"))
    assert s.errors == [] and s.external == [] and s.scripts == 0


#: Children a MathML element must have (MathML Core): the base and its scripts, a fraction's two parts.
ARITY = {"msup": 2, "msub": 2, "mover": 2, "munder": 2, "mfrac": 2, "msubsup": 3, "munderover": 3}


def test_every_formula_of_the_committed_report_is_well_formed_mathml():
    """A script element with the wrong number of children is drawn wrongly (seen: ``cos^3`` as
    ``<msup>`` of three children put the 3 on the base line)."""
    text = (ROOT / "docs" / "paper" / "report.md").read_text(encoding="utf-8")
    bad = []
    for tex in report_html.formulas(text):
        root = ET.fromstring(to_mathml(tex).replace("<math>", f'<math xmlns="{MATHML[1:-1]}">'))
        for element in root.iter():
            tag = element.tag.split("}")[-1]
            if tag in ARITY and len(element) != ARITY[tag]:
                bad.append((tex, tag, len(element)))
    assert bad == []
