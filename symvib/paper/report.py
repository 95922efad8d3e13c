"""``symvib paper``: the paper reproduced end to end, as a report with figures.

For the parabola, the cycloid and the circle (two scenes) this writes, into
one folder:

* ``report.md`` (and ``report.html``): per curve the derived double equations
  of motion and phase trajectories in LaTeX beside the paper's printed forms
  and the verdicts of :mod:`symvib.paper.audit`, the scene parameters, the event
  table and the energy budget of each run;
* PNG figures of every scene with ``k = 1`` (the paper's conclusions): the
  scene sketch, the force plan, the phase portrait, ``F_N``, ``P_mu``, ``Ek``,
  ``Ep`` and ``E`` against the coordinate, and ``E(t)`` with the friction work
  and impact losses stacked; with ``k = 0.8`` (the paper does not state its
  ``k``) the phase portrait, ``E`` and ``E(t)``; each titled and captioned with
  the paper's figure it reproduces (:data:`PAPER_FIGURES`);
* ``results.json``: every run's result (status, events, energy budget);
* ``report.html``, which reads offline (:mod:`symvib.paper.report_html`: formulas as MathML),
  and ``report.pdf`` with ``pdf=True`` (``symvib paper --pdf``; :mod:`symvib.paper.report_pdf`).

The simulations use the generated kernels and the driver's plain-Python core,
so the job needs no compiler and runs in seconds; SymPy is used for the
equations of the report only.

Examples
--------
>>> from symvib.paper.report import SCENES, LOW_K
>>> [s for s, _ in SCENES], LOW_K
(['paper-parabola', 'paper-cycloid', 'paper-circle-3.8', 'paper-circle-7'], 0.8)
"""
from __future__ import annotations

import json
import re
import time
from dataclasses import dataclass
from pathlib import Path

from symvib import safeio
from symvib.numeric.scene import packaged_scene
from symvib.paper.errata import REMARK
from symvib.paper.report_html import markdown_to_html
from symvib.paper.report_pdf import write_pdf
from symvib.shapes import PAPER_SCENES

__all__ = ["SCENES", "LOW_K", "HIGH_K", "run_paper", "main"]

#: The figure numbers each of the paper's scenes reproduces.
SCENE_FIGURES = {"paper-parabola": "figs. 6-11", "paper-cycloid": "figs. 13-18", "paper-circle-3.8": "fig. 20",
                 "paper-circle-7": "figs. 21-26"}
#: The paper's scenes (:data:`symvib.shapes.PAPER_SCENES`, files in symvib/scenes) with the figures they reproduce.
SCENES = [(name, SCENE_FIGURES[name]) for name in PAPER_SCENES]
#: The paper's figure each of a scene's figures reproduces (by figure name of
#: :data:`symvib.numeric.figures.FIGURE_NAMES`; absent: not in the paper).
PAPER_FIGURES = {
    "paper-parabola": {"sketch": "figs. 2 a, 5 a", "forces": "figs. 1 b, 2 b, 5 b", "phase": "fig. 6",
                       "F_N": "fig. 7", "P_mu": "fig. 8", "Ek": "fig. 9", "Ep": "fig. 10", "E": "fig. 11"},
    "paper-cycloid": {"sketch": "figs. 3 a, 12 a", "forces": "figs. 1 b, 3 b, 12 b", "phase": "fig. 13",
                      "F_N": "fig. 14", "P_mu": "fig. 15", "Ek": "fig. 16", "Ep": "fig. 17", "E": "fig. 18"},
    "paper-circle-3.8": {"sketch": "figs. 4, 19 a", "forces": "figs. 1 b, 4 a, 19 b", "phase": "fig. 20"},
    "paper-circle-7": {"sketch": "fig. 19 a", "forces": "figs. 1 b, 19 b", "phase": "fig. 21", "F_N": "fig. 22",
                       "P_mu": "fig. 23", "Ek": "fig. 24", "Ep": "fig. 25", "E": "fig. 26"},
}
#: Figures of the k < 1 runs (the scene sketch and force plan are those of k = 1).
LOW_K_FIGURES = ("phase", "E", "energy-time")
#: Restitution of the paper's conclusions, and the k < 1 run added.
HIGH_K, LOW_K = 1.0, 0.8
#: Backend of the simulations (no compile time; the runs are short).
BACKEND = "python"
#: Significant digits of the numbers in the report's event tables.
DIGITS = 12


@dataclass(frozen=True)
class Run:
    """One simulated scene of the report."""

    key: str
    scene: object
    result: object
    figures: tuple


def _num(x) -> str:
    return f"{x:.{DIGITS}g}"


def _greek(name: str) -> str:
    return {"phi": r"\varphi", "theta": r"\theta"}.get(name, name)


def event_table(result, coordinate: str) -> list:
    """Markdown lines of a run's event table."""
    sym = _greek(coordinate)
    lines = [f"| # | kind | $t$ [s] | ${sym}$ | $\\dot{{{sym}}}$ before | $\\dot{{{sym}}}$ after | $E$ [J] |",
             "| ---: | --- | ---: | ---: | ---: | ---: | ---: |"]
    for i, e in enumerate(result.events, 1):
        lines.append(f"| {i} | {e.kind.value} | {_num(e.t)} | {_num(e.q)} | {_num(e.qdot_before)} | "
                     f"{_num(e.qdot_after)} | {_num(e.energy)} |")
    return lines


def parse_event_tables(text: str) -> dict:
    """The event tables of a report, by the run key in the heading above each (for tests)."""
    out = {}
    key = None
    for line in text.splitlines():
        m = re.match(r"^#### Events of run `([^`]+)`", line)
        if m:
            key = m.group(1)
            out[key] = []
            continue
        if key and line.startswith("| ") and not line.startswith("| #") and not line.startswith("| ---"):
            cells = [c.strip() for c in line.strip("|").split("|")]
            if len(cells) == 7 and cells[0].isdigit():
                out[key].append((cells[1], *map(float, cells[2:])))
        elif key and not line.strip():
            if out[key]:
                key = None
    return out


def _budget_lines(result) -> list:
    b = result.energy_budget
    return [
        f"Status: **{result.status.value}** ({result.message}) at $t$ = {_num(result.t_final)} s. "
        f"Energy budget: initial {_num(b.initial)} J, final {_num(b.final)} J, friction work "
        f"{_num(b.friction_work)} J, impact losses {_num(b.impact_loss)} J; residual "
        f"$E_0 - E - W_\\mu - W_k$ = {b.residual:.2g} J ({b.relative_residual:.1g} of $E_0$)."
    ]


def _scene_table(scene) -> list:
    lim = lambda v: "none" if v is None else f"{v:.6g}"  # noqa: E731
    params = ", ".join(f"{k} = {v:g}" for k, v in scene.params)
    q = _greek(scene.shape.q)
    return [
        "| curve | parameters | $g$ [m/s²] | $m$ [kg] | $\\mu$ | left limiter | right limiter | "
        f"${q}_0$ | $\\dot{{{q}}}_0$ |",
        "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
        f"| {scene.shape.name} | {params} | {scene.g:g} | {scene.m:g} | {scene.mu:.6g} | {lim(scene.left)} | "
        f"{lim(scene.right)} | {scene.q0:.6g} | {scene.qdot0:g} |",
    ]


def _equations(shape_name, verdicts) -> list:
    from symvib.paper.audit import PRINTED, derivation, ocr_cell, seed_cell

    d = derivation(shape_name)
    tex = d.latex()
    lines = [
        f"Geometry: $${tex['geometry']}$$",
        "",
        "Derived double equation of motion (eq. 1; upper sign for $v > 0$, $N > 0$):",
        "",
        f"$${tex['eom']}$$",
        "",
        "Derived double phase trajectory (eq. 2):",
        "",
        f"$${tex['phase']}$$",
        "",
        f"$${tex['F+']}$$",
        "",
        f"$${tex['F-']}$$",
        "",
        f"Routes of $F_\\sigma$: {d.branches[1].F.route} (verified {d.branches[1].F.verification}); "
        f"back-substitution of eq. 2 into eq. 1: {', '.join(f'{s:+d}: {v}' for s, v in d.check().items())}.",
        "",
        "The paper's printed forms beside the derivation ([errata](#errata-of-the-papers-printed-equations)):",
        "",
        "The seed's text is the paper's OCR text of the equation, verbatim (`↵`: its line breaks); the",
        "transcription is compared with it in `tests/test_audit.py`, the OCR differences it declares listed.",
        "",
        "| eq. | printed (transcription) | seed text | declared OCR differences | derived (energies in terms of "
        "the velocity) | verdict |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    printed = {e.key: e for e in PRINTED}
    for v in verdicts:
        if v.shape != shape_name:
            continue
        verdict = f"matches ({v.how})" if v.matches else f"**differs** ({v.origin})"
        e = printed[v.key]
        lines.append(f"| {v.label} | ${_flat(v.printed_tex)}$ | {seed_cell(e)} | {ocr_cell(e)} | "
                     f"${_flat(v.corrected_tex)}$ | {verdict} |")
    return lines


def _flat(tex: str) -> str:
    return " ".join(tex.split()).replace("|", r"\vert ")


def _figures(result, out: Path, key: str, every: bool, scene_name: str) -> tuple:
    """The run's figures as ``(file name, caption)``: all of them, or :data:`LOW_K_FIGURES`."""
    from symvib.numeric.figures import FIGURE_NAMES, caption, save_run_figures

    which = FIGURE_NAMES if every else LOW_K_FIGURES
    refs = PAPER_FIGURES.get(scene_name, {})
    if not every:  # the paper does not state its k: a k < 1 run is not the paper's figure
        refs = {name: f"{ref} (there without a stated k)" for name, ref in refs.items()}
    paths = save_run_figures(result, out / "figures", prefix=key, only=which, paper=refs)
    return tuple((p.name, caption(name, refs.get(name))) for name, p in zip([n for n in FIGURE_NAMES if n in which],
                                                                            paths))


def _alpha0_section(out_lines) -> tuple:
    """The report's section on "alpha0 = 3"; returns the readings (for the errata row)."""
    from symvib.paper.errata import alpha0_readings

    readings, rejected = alpha0_readings()
    out_lines += [
        "### The reading of \"alpha0 = 3\"",
        "",
        "The paper gives $\\alpha_0 = 3$ for this scene and remarks that there was \"" + REMARK + "\". "
        "Read as radians, $\\tan 3 = -0.1425 < 0$ is no friction coefficient (symvib rejects a negative "
        "$\\mu$). Each reading, simulated with $k = 1$:",
        "",
        "| reading | $\\mu$ | events | impacts | reversals |",
        "| --- | ---: | --- | ---: | ---: |",
    ]
    for r in readings:
        out_lines.append(f"| {r.label.replace('|', chr(92) + '|')} | {r.mu:.4g} | {', '.join(r.kinds)} | "
                         f"{r.impacts} | {r.reversals} |")
    out_lines += [
        "",
        f"($\\mu = \\tan 3$ as given: `{rejected}`.) Only the friction angle $\\pi - 3$ (the same line as 3 rad, "
        "$\\mu = |\\tan 3|$) reproduces \"" + REMARK + "\": one impact, a swing back with one reversal, a "
        "second reversal, arrest. $\\mu = 3$ stops the particle before it reaches the limiter, and 3 degrees "
        "gives three oscillations. This report uses $\\alpha_0 = \\pi - 3$.",
        "",
    ]
    return readings


#: The report's symbolic part, one job each: eqs. (1)-(2) for a general curve
#: (``None``), then each curve's derivation and audit, in the report's order.
SYMBOLIC_JOBS = (None, "parabola", "cycloid", "circle")


def _symbolic(shape_name):
    """One symbolic job: ``(verdicts, equation lines)`` of a curve, or the general verdicts."""
    from symvib.paper.audit import audit

    if shape_name is None:
        return audit(shapes=()), []
    verdicts = audit(shapes=(shape_name,), general=False)
    return verdicts, _equations(shape_name, verdicts)


def _start_symbolic():
    """Start the symbolic jobs on up to two worker processes, while the caller simulates."""
    import os

    from symvib.symbolic.budget import worker_pool

    pool = worker_pool(min(2, os.cpu_count() or 1))
    return pool, {name: pool.submit(_symbolic, name) for name in SYMBOLIC_JOBS}


def run_paper(out_dir="symvib-paper", *, low_k: float = LOW_K, html_too: bool = True, pdf: bool = False,
              progress=None) -> dict:
    """Write the report, figures and results into ``out_dir`` (and ``report.pdf`` with ``pdf``);
    returns what was written."""
    from symvib import simulate
    from symvib.paper.audit import errata_markdown
    from symvib.paper.conclusions import conclusions, conclusions_markdown
    from symvib.paper.errata import alpha0_row

    say = progress or (lambda msg: None)
    out = safeio.check_root(out_dir, "report folder")   # a real folder of the user's, not a link
    safeio.make_folders(out, "figures", what="report folder")
    start = time.perf_counter()
    say("deriving and auditing the paper's equations (in worker processes)")
    pool, jobs = _start_symbolic()
    with pool:
        runs = []
        for name, _figs in SCENES:
            base = packaged_scene(name)
            for k in (HIGH_K, low_k):
                key = f"{name}-k{k:g}"
                scene = base.replace(k=k, name=key)
                say(f"simulating {key}")
                result = simulate(scene, backend=BACKEND)
                runs.append(Run(key, scene, result, _figures(result, out, key, k == HIGH_K, name)))
        say("waiting for the derivations and the audit")
        parts = {name: job.result() for name, job in jobs.items()}
    verdicts = sum((parts[name][0] for name in SYMBOLIC_JOBS), ())
    lines = [
        "# The paper reproduced by symvib",
        "",
        "*Energy analysis of vibro-impact system dynamics based on a heavy mass particle's free oscillations "
        "along curvilinear rough trajectories* (parabola, cycloid, circle), redone with `symvib paper`: "
        "equations derived with SymPy and checked by back-substitution, the paper's printed equations "
        "audited, every scene simulated event by event with generated kernels.",
        "",
        f"The paper does not state its restitution coefficient; its conclusions discuss the ideally elastic "
        f"case, so every scene runs with $k = {HIGH_K:g}$, and again with $k = {low_k:g}$.",
        "",
        "## Contents",
        "",
        "- [Parabola](#parabola)",
        "- [Cycloid](#cycloid)",
        "- [Circle](#circle)",
        "- [Conclusions](#conclusions)",
        "- [Errata](#errata-of-the-papers-printed-equations)",
        "",
    ]
    for shape_name, title in (("parabola", "Parabola"), ("cycloid", "Cycloid"), ("circle", "Circle")):
        lines += [f"## {title}", ""]
        lines += parts[shape_name][1] + [""]
        if shape_name == "circle":
            readings = _alpha0_section(lines)
        for name, figs in SCENES:
            base = packaged_scene(name)
            if base.shape.name != shape_name:
                continue
            lines += [f"### Scene `{name}` (paper {figs})", ""] + _scene_table(base) + [""]
            for run in runs:
                if not run.key.startswith(name + "-k"):
                    continue
                coord = run.scene.shape.q
                lines += [f"#### Events of run `{run.key}` ($k = {run.scene.k:g}$)", ""]
                lines += event_table(run.result, coord) + [""] + _budget_lines(run.result) + [""]
                for fig, text in run.figures:
                    lines += [f"![{fig}](figures/{fig})", "", f"*{text}*", ""]
    say("checking the paper's conclusions")
    elastic = {r.key.removesuffix(f"-k{HIGH_K:g}"): r.result for r in runs if r.scene.k == HIGH_K}
    lines += ["## Conclusions", "",
              "The paper's concluding claims about the motion, in its own words, against the runs above with "
              f"$k = {HIGH_K:g}$ (the quantities per motion interval between two events; "
              "`symvib/paper/conclusions.py`).",
              "", conclusions_markdown(conclusions(elastic)), ""]
    lines += [""] + errata_markdown(verdicts, extra_rows=[alpha0_row(readings)],
                                    title="## Errata of the paper's printed equations").splitlines()
    lines += ["", f"Generated in {time.perf_counter() - start:.1f} s."]
    text = "\n".join(lines) + "\n"
    safeio.write_text(out, "report.md", text, what="report folder")
    written = {"report": out / "report.md", "figures": [out / "figures" / f for r in runs for f, _ in r.figures]}
    results = {r.key: r.result.to_dict() for r in runs}
    safeio.write_text(out, "results.json", json.dumps(results, indent=1) + "\n", what="report folder")
    written["results"] = out / "results.json"
    if html_too:
        safeio.write_text(out, "report.html", markdown_to_html(text, title="symvib: the paper reproduced"),
                          what="report folder")
        written["html"] = out / "report.html"
    if pdf:
        say("writing report.pdf")
        written["pdf"], written["pdf_pages"] = write_pdf(text, written["figures"], out / "report.pdf")
    written["runs"] = runs
    return written


def main(out_dir="symvib-paper", *, low_k: float = LOW_K, quiet: bool = False, pdf: bool = False) -> int:
    """The ``symvib paper`` job (see the module docstring)."""
    start = time.perf_counter()
    written = run_paper(out_dir, low_k=low_k, pdf=pdf, progress=None if quiet else (lambda m: print(m, flush=True)))
    runs = written["runs"]
    for r in runs:
        res = r.result
        print(f"{r.key:24s} {res.status.value:10s} {len(res.events):3d} events, t = {res.t_final:8.4f} s, "
              f"budget residual {res.energy_budget.relative_residual:.1e}")
    if pdf:
        print(f"wrote {written['pdf']} ({written['pdf_pages']} pages)")
    print(f"wrote {written['report']} ({len(written['figures'])} figures) in {time.perf_counter() - start:.1f} s")
    return 0
