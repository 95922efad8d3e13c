"""The errata document ``docs/errata.md``: the printed equations, the "alpha0 = 3" reading, the conclusions.

One function writes it, :func:`write_errata` (``python -m symvib.paper.errata
docs/errata.md``, or ``symvib audit --write docs/errata.md``);
``tests/test_audit.py`` checks that the file is current.  It joins

* the audit of every printed equation (:func:`symvib.paper.audit.errata_markdown`:
  root errors and the errors inherited from them, each transcription beside
  the seed's text),
* a row for the first circle scene's "alpha0 = 3", whose readings are
  simulated here (:func:`alpha0_readings`),
* the table of the paper's conclusions (:mod:`symvib.paper.conclusions`).

Examples
--------
>>> [label.split(" (")[0] for label, _ in ALPHA0_READINGS]
['mu = 3', 'alpha0 = 3 degrees', 'alpha0 = pi - 3 rad = 8.1 deg']
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

from symvib.numeric.scene import packaged_scene

__all__ = ["ALPHA0_READINGS", "REMARK", "Reading", "alpha0_readings", "alpha0_row", "errata_document", "write_errata"]

#: Readings of the first circle scene's "alpha0 = 3": label, physics section.
ALPHA0_READINGS = [
    ("mu = 3 (the text's \"friction coefficient 3\")", {"mu": 3.0}),
    ("alpha0 = 3 degrees (mu = tan 3 deg = 0.0524)", {"alpha0": "3*pi/180"}),
    ("alpha0 = pi - 3 rad = 8.1 deg (mu = |tan 3| = 0.1425)", {"alpha0": "pi - 3"}),
]
#: The paper's remark the readings are judged by.
REMARK = "one impact and one oscillation until arrestment"
#: Reversals of "one oscillation" after the impact: the swing back and the return.
ONE_OSCILLATION = 2
#: The scene of the reading (its file in symvib/scenes).
ALPHA0_SCENE = "paper-circle-3.8"


@dataclass(frozen=True)
class Reading:
    """One reading of "alpha0 = 3", simulated with ``k = 1``: its friction coefficient and event kinds."""

    label: str
    mu: float
    kinds: tuple

    @property
    def impacts(self) -> int:
        return self.kinds.count("impact")

    @property
    def reversals(self) -> int:
        return self.kinds.count("reversal")


def _with_physics(data: dict, physics: dict):
    from symvib.numeric.scene import scene_from_dict

    d = json.loads(json.dumps(data))
    d["physics"] = {k: v for k, v in d["physics"].items() if k not in ("mu", "alpha0")} | physics
    return scene_from_dict(d)


def alpha0_readings() -> tuple:
    """``(readings, rejection)``: each :class:`Reading` simulated, and symvib's message for ``mu = tan 3``."""
    from symvib import simulate
    from symvib.numeric.scene import SceneError

    data = packaged_scene(ALPHA0_SCENE).to_dict()
    readings = []
    for label, physics in ALPHA0_READINGS:
        scene = _with_physics(data, physics)
        result = simulate(scene, backend="python", samples=False)
        readings.append(Reading(label, scene.mu, tuple(e.kind.value for e in result.events)))
    try:
        _with_physics(data, {"mu": math.tan(3.0)})
        rejection = "accepted"
    except SceneError as exc:
        rejection = str(exc)
    return tuple(readings), rejection


def _matches_remark(r: Reading) -> bool:
    return r.impacts == 1 and r.reversals == ONE_OSCILLATION and r.kinds[-1] == "arrest"


def alpha0_row(readings) -> str:
    """The errata-table row (five cells) of the circle's "alpha0 = 3"."""
    chosen = [r for r in readings if _matches_remark(r)]
    others = "; ".join(f"{r.label.split(' (')[0]}: {r.impacts} impact(s), {r.reversals} reversal(s)"
                       for r in readings if r not in chosen)
    which = (f"only {chosen[0].label} gives the paper's \"{REMARK}\" ({chosen[0].impacts} impact, "
             f"{chosen[0].reversals} reversals, arrest)" if len(chosen) == 1
             else f"{len(chosen)} readings give the paper's \"{REMARK}\"")
    return (f"| \"alpha0 = 3\" | circle (fig. 20) | **differs** | root | tan 3 = {math.tan(3.0):.4f} < 0 is no "
            f"friction coefficient; {which}; {others} |").replace("|tan 3|", "\\|tan 3\\|")


def errata_document(verdicts=None, readings=None, claims=None) -> str:
    """The whole of ``docs/errata.md`` (Markdown); what is not given is computed."""
    from symvib.paper.audit import errata_markdown
    from symvib.paper.conclusions import conclusions, conclusions_markdown

    readings = alpha0_readings()[0] if readings is None else readings
    claims = conclusions() if claims is None else claims
    text = errata_markdown(verdicts, extra_rows=[alpha0_row(readings)])
    head, sep, rest = text.partition("\n## The equations that differ")
    return "\n".join([
        head, "",
        "## The paper's conclusions, checked", "",
        "Each claim of the paper's concluding remarks (and of its remarks on the circle), in its own words, "
        "against symvib's runs of the paper's scenes with the ideally elastic impact `k = 1` "
        "(`symvib/paper/conclusions.py`; per motion interval, between two events; tests: `tests/test_conclusions.py`).",
        "",
        conclusions_markdown(claims),
    ]) + sep + rest


def write_errata(path="docs/errata.md", *, verdicts=None) -> Path:
    """Write :func:`errata_document` to ``path`` (the audit's ``verdicts`` if already made); returns the path."""
    from symvib import safeio

    path = Path(path)
    with safeio.replacing_file(path, what="errata file") as fh:   # whole, never through a link
        fh.write((errata_document(verdicts) + "\n").encode("utf-8"))
    return path


if __name__ == "__main__":  # pragma: no cover - writes docs/errata.md
    import sys

    if len(sys.argv) > 1:
        print(f"wrote {write_errata(sys.argv[1])}")
    else:
        print(errata_document())
