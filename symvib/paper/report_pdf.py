"""The report as a PDF: its text pages, then its figures, with Matplotlib's PDF backend (no other dependency).

The Markdown of :mod:`symvib.paper.report` is set as monospaced text pages (formulas stay TeX:
the HTML report, :mod:`symvib.paper.report_html`, renders them), and each figure, with its file
name, follows on the figure pages.

Examples
--------
>>> pages = pdf_text_pages("\\n".join(f"line {i}" for i in range(100)))
>>> len(pages), pages[1].splitlines()[0], PDF_LINES
(2, 'line 78', 78)
"""
from __future__ import annotations

import re
import textwrap
from pathlib import Path

from symvib import safeio

__all__ = ["PDF_PAGE", "PDF_LINES", "PDF_COLUMNS", "PDF_FIGURES_PER_PAGE", "pdf_text_pages", "write_pdf"]

#: Pages of the PDF report: A4 portrait [inches], text lines per page and characters per line,
#: figures per page.
PDF_PAGE = (8.27, 11.69)
PDF_LINES, PDF_COLUMNS, PDF_FIGURES_PER_PAGE = 78, 118, 2


def pdf_text_pages(text: str) -> list:
    """The report's Markdown as pages of at most :data:`PDF_LINES` lines of :data:`PDF_COLUMNS`
    characters (formulas stay TeX; the HTML report renders them)."""
    lines = []
    caption_next = False
    for line in text.splitlines():
        image = re.match(r"^!\[([^\]]*)\]\(([^)]+)\)$", line)
        if image:  # the figure pages follow the text, each figure with its caption
            line, caption_next = f"[figure {image.group(1)}: on the figure pages]", True
        elif caption_next and line.strip():
            caption_next = False
            if line.startswith("*"):
                continue
        lines += textwrap.wrap(line, PDF_COLUMNS, subsequent_indent="    ", break_long_words=True,
                               replace_whitespace=False) or [""]
    return ["\n".join(lines[i:i + PDF_LINES]) for i in range(0, len(lines), PDF_LINES)] or [""]


def write_pdf(text: str, figures, path: Path) -> tuple:
    """``report.pdf``: the report's text, then its figures (:data:`PDF_FIGURES_PER_PAGE` a page),
    with Matplotlib's PDF backend (no other dependency).  Returns ``(path, pages)``."""
    from matplotlib.backends.backend_pdf import PdfPages
    from matplotlib.figure import Figure
    from matplotlib.image import imread

    pages = 0
    path = Path(path)
    with safeio.replacing_file(path, what="PDF file") as fh, PdfPages(fh) as pdf:
        info = pdf.infodict()
        info["Title"], info["Creator"] = "symvib: the paper reproduced", "symvib paper --pdf"
        for page in pdf_text_pages(text):
            fig = Figure(figsize=PDF_PAGE)
            fig.text(0.06, 0.97, page, family="monospace", fontsize=6.3, va="top", ha="left", parse_math=False)
            pdf.savefig(fig)
            pages += 1
        figures = list(figures)
        for i in range(0, len(figures), PDF_FIGURES_PER_PAGE):
            fig = Figure(figsize=PDF_PAGE)
            chunk = figures[i:i + PDF_FIGURES_PER_PAGE]
            axes = fig.subplots(PDF_FIGURES_PER_PAGE, 1)
            for ax, fpath in zip(axes, chunk):
                ax.imshow(imread(fpath))
                ax.set_title(Path(fpath).name, fontsize=7)
            for ax in axes:
                ax.axis("off")
            fig.tight_layout()
            pdf.savefig(fig)
            pages += 1
    return path, pages
