"""The benchmarks' results as Markdown tables: ``summary.md`` and ``stability.md``.

:func:`summary_markdown` gives the work-precision job's summary (the ratio at
equal accuracy, each setting's error and CPU time, the wrong-sequence counts over
the random scenes); :func:`stability_markdown` the stability table, one row per
case and one column per method.

Examples
--------
>>> print(summary_markdown([], [(1e-6, None)], {"usable": 0, "left_out": 0, "rows": []}, "python", {}, []),
...       end="")  # doctest: +ELLIPSIS
symvib backend: **python** (first call per curve, excluded from the timings: ).
Scenes: .
<BLANKLINE>
| ratio at error <= | cheapest peer setting | ...
| --- | --- | --- | --- | --- | --- |
| 1.0e-06 | none reaches it | | | | |
...
"""
from __future__ import annotations

import math

from symvib.checks.bench.scenes import RANDOM_MAX_EVENTS

__all__ = ["summary_markdown", "stability_markdown"]


def summary_markdown(summary, ratios, seq, backend, warm, scenes) -> str:
    """The work-precision job's ``summary.md``.

    Parameters
    ----------
    summary : list of dict
        One row per setting (``label``, ``error``, ``cpu`` in seconds, ``wrong``, ``scenes``).
    ratios : list of (float, tuple or None)
        Each accuracy target with its
        :func:`~symvib.checks.bench.work_precision_job.ratio_at_equal_accuracy`.
    seq : dict
        The random scenes' counts (:func:`~symvib.checks.bench.sequences.sequence_counts`).
    backend : str
        symvib's driver backend.
    warm : dict
        Seconds of each curve's first call (:func:`~symvib.checks.bench.timing.warm_up`).
    scenes : list of (str, Scene)
        The paper scenes that ran.

    Returns
    -------
    str
        The Markdown text, ending in a newline.
    """
    lines = [f"symvib backend: **{backend}** (first call per curve, excluded from the timings: "
             + ", ".join(f"{k} {v:.2f} s" for k, v in warm.items()) + ").",
             f"Scenes: {', '.join(label for label, _ in scenes)}.", "",
             "| ratio at error <= | cheapest peer setting | its CPU / trajectory | cheapest symvib setting "
             "| its CPU / trajectory | ratio |", "| --- | --- | --- | --- | --- | --- |"]
    for target, got in ratios:
        if got:
            lines.append(f"| {target:.1e} | {got[0]} | {got[1] * 1e3:.3f} ms | {got[2]} | {got[3] * 1e3:.4f} ms "
                         f"| {got[4]:.0f} |")
        else:
            lines.append(f"| {target:.1e} | none reaches it | | | | |")
    lines += ["", "| setting | max error (all sequences right) | CPU / trajectory | wrong sequence (paper scenes) |",
              "| --- | --- | --- | --- |"]
    for r in summary:
        err = f"{r['error']:.1e}" if math.isfinite(r["error"]) else "-"
        lines.append(f"| {r['label']} | {err} | {r['cpu'] * 1e3:.3f} ms | {r['wrong']}/{r['scenes']} |")
    lines += ["", f"Wrong event sequences over {seq['usable']} random parabola/circle scenes "
              f"({seq['left_out']} more were left out: over {RANDOM_MAX_EVENTS} events, or the reference failed):", "",
              "| setting | wrong sequence | failed or out of budget |", "| --- | --- | --- |"]
    for r in seq["rows"]:
        lines.append(f"| {r['label']} | {r['wrong']}/{r['scenes']} | {r['failed']} |")
    return "\n".join(lines) + "\n"


def stability_markdown(rows, names, methods) -> str:
    """The stability table: one row per case, one column per method."""
    from symvib.checks.stability import CORRECT, case

    cell = {(r["case"], r["method"]): r["outcome"] for r in rows}
    lines = ["| case | " + " | ".join(methods) + " |", "| --- |" + " --- |" * len(methods)]
    for n in names:
        marks = []
        for m in methods:
            o = cell.get((n, m), "")
            marks.append(f"**{CORRECT}**" if o == CORRECT else o)
        lines.append(f"| {case(n).title} | " + " | ".join(marks) + " |")
    return "\n".join(lines) + "\n"
