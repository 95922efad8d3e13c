"""The paper's wing: every module that serves the seed paper, in one folder.

The seed is the paper *Energy analysis of vibro-impact system dynamics based on a
heavy mass particle's free oscillations along curvilinear rough trajectories*.
Its printed equations, its conclusions and its figures are checked and redone here;
the physics is done by the wings below:

* :mod:`~symvib.paper.seed`: the paper's OCR text of each printed equation, and the
  OCR differences each transcription declares; :mod:`~symvib.paper.seedtex` reads
  such a text into SymPy;
* :mod:`~symvib.paper.audit` (SymPy): every printed equation transcribed and compared
  with the derivation of :mod:`symvib.symbolic`;
* :mod:`~symvib.paper.conclusions`: the paper's concluding claims against the runs of
  its scenes (:mod:`symvib.numeric`);
* :mod:`~symvib.paper.errata`: the errata document ``docs/errata.md``;
* :mod:`~symvib.paper.report`: the ``symvib paper`` job (report, figures, results);
  :mod:`~symvib.paper.report_html` turns the report's Markdown into one offline HTML
  page (formulas as MathML: :mod:`~symvib.paper.texmathml`), :mod:`~symvib.paper.report_pdf`
  into a PDF.

The wing imports :mod:`symvib.symbolic` and :mod:`symvib.numeric`, and neither imports
it (``symvib.errata``, ``symvib.conclusions`` and ``symvib.texmathml``, the old names of
three of its modules, stay as aliases on the top floor).  ``import symvib.paper`` imports
nothing: the names of the report job (the module ``symvib/paper.py`` before the wing was
gathered) load their module on first use.

>>> import symvib.paper
>>> symvib.paper.LOW_K, symvib.paper.markdown_to_html is symvib.paper.report_html.markdown_to_html
(0.8, True)
"""
from __future__ import annotations

import importlib

#: The report job's names, by the module that defines them.
_LAZY = {
    **dict.fromkeys(("SCENES", "SCENE_FIGURES", "PAPER_FIGURES", "LOW_K_FIGURES", "HIGH_K", "LOW_K", "BACKEND",
                     "DIGITS", "SYMBOLIC_JOBS", "Run", "event_table", "parse_event_tables", "run_paper", "main"),
                    "symvib.paper.report"),
    **dict.fromkeys(("HTML_STYLE", "MATH", "formulas", "markdown_to_html"), "symvib.paper.report_html"),
    **dict.fromkeys(("PDF_PAGE", "PDF_LINES", "PDF_COLUMNS", "PDF_FIGURES_PER_PAGE", "pdf_text_pages", "write_pdf"),
                    "symvib.paper.report_pdf"),
    **dict.fromkeys(("ALPHA0_READINGS", "REMARK"), "symvib.paper.errata"),
}

__all__ = ["SCENES", "LOW_K", "HIGH_K", "run_paper", "ALPHA0_READINGS", "main"]


def __getattr__(name: str):
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'symvib.paper' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_LAZY))
