"""The numeric wing's vocabulary is defined once (symvib/numeric/layout.py) and flows everywhere.

Adding an event kind touches the vocabulary (and the engine code that raises it):
the typed records, the JSON, the event table, the sweep's tables and the figures
follow without an edit; the last test proves it on a copy of the package with a
kind added to ``layout.EventCode`` only.
"""
import dataclasses
import json
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path
from types import SimpleNamespace

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")

import symvib
from symvib import simulate
from symvib.numeric import layout
from symvib.numeric.events import Event, EventKind, Status, kind_of, status_of
from symvib.numeric.figures import event_style, phase_portrait
from symvib.numeric.scene import resolve_scene
from symvib.numeric.sweep.result import SweepResult


def test_codes_and_names_are_one_table():
    assert [k.value for k in EventKind] == list(layout.EVENT_KINDS)
    assert [s.value for s in Status] == list(layout.STATUSES[1:])  # RUNNING never ends a run
    assert all(kind_of(c) is EventKind[c.name] for c in layout.EventCode)
    assert all(status_of(c).code == c for c in layout.StatusCode if c != layout.StatusCode.RUNNING)
    for table in (layout.EventColumn, layout.IntervalColumn, layout.SceneRow, layout.Summary):
        assert sorted(int(c) for c in table) == list(range(len(table))), table.__name__


def _with_events(kinds):
    base = simulate(resolve_scene("paper-parabola"), backend="python")
    events = tuple(Event(k, 0.1 * i, 0.01 * i, 1.0, -0.5, 2.0) for i, k in enumerate(kinds))
    return dataclasses.replace(base, events=events)


@pytest.mark.parametrize("kind", list(EventKind), ids=lambda k: k.value)
def test_every_event_kind_reaches_json_table_sweep_and_figure(kind):
    result = _with_events([kind])
    assert json.loads(result.to_json())["events"][0]["kind"] == kind.value
    assert kind.value in result.event_table()
    ax = phase_portrait(result)
    assert event_style(kind)[2] in [t.get_text() for t in ax.get_legend().get_texts()]
    log = np.zeros((1, 1, len(layout.EVENT_COLUMNS)))
    log[0, 0, layout.EventColumn.kind] = kind.code
    columns = {"events": np.array([1]), "event_log": log}
    logged = type("R", (), {"columns": columns, "spec": SimpleNamespace(log_events=1)})()  # a sweep's log
    assert SweepResult.events(logged, 0)[0][0] == kind.value


def test_a_new_event_kind_needs_only_the_vocabulary(tmp_path):
    # A copy of the package with one more member in layout.EventCode and no other edit.
    copy = tmp_path / "symvib"
    shutil.copytree(Path(symvib.__file__).parent, copy, ignore=shutil.ignore_patterns("__pycache__"))
    gen = copy / "generated"
    if not gen.exists():  # the editable checkout keeps generated/ beside the package
        shutil.copytree(Path(symvib.__file__).parent.parent / "generated", gen,
                        ignore=shutil.ignore_patterns("__pycache__"))
    layout_py = copy / "numeric" / "layout.py"
    text = layout_py.read_text(encoding="utf-8")
    marker = "    LANDING = 7\n"   # the last member
    assert marker in text
    layout_py.write_text(text.replace(marker, marker + "    GRAZING_CONTACT = 8\n", 1), encoding="utf-8")
    script = textwrap.dedent(f"""
        import sys, json
        sys.meta_path[:] = [f for f in sys.meta_path if "editable" not in repr(f).lower()]
        sys.path.insert(0, {str(tmp_path)!r})
        import dataclasses, matplotlib
        matplotlib.use("Agg")
        import numpy as np
        import symvib
        assert symvib.__file__.startswith({str(tmp_path)!r}), symvib.__file__
        from symvib.numeric import layout
        from symvib import simulate
        from symvib.numeric.events import Event, EventKind, kind_of
        from symvib.numeric.figures import phase_portrait
        from symvib.numeric.scene import resolve_scene
        from symvib.numeric.sweep.result import SweepResult
        kind = kind_of(8)
        base = simulate(resolve_scene("paper-parabola"), backend="python", samples=True)
        r = dataclasses.replace(base, events=(Event(kind, 0.1, 0.2, 1.0, 1.0, 2.0),))
        legend = [t.get_text() for t in phase_portrait(r).get_legend().get_texts()]
        log = np.zeros((1, 1, len(layout.EVENT_COLUMNS)))
        log[0, 0, 0] = 8
        from types import SimpleNamespace
        fake = type("R", (), {{"columns": {{"events": np.array([1]), "event_log": log}},
                               "spec": SimpleNamespace(log_events=1)}})()
        print(json.dumps([kind.value, json.loads(r.to_json())["events"][0]["kind"],
                          "grazing_contact" in r.event_table(), "grazing contact" in legend,
                          SweepResult.events(fake, 0)[0][0], list(layout.EVENT_KINDS)[-1]]))
    """)
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    assert json.loads(out.stdout.strip().splitlines()[-1]) == [
        "grazing_contact", "grazing_contact", True, True, "grazing_contact", "grazing_contact"]
