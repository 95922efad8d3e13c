"""The plain engine's wall-clock limit: a long run answers in bounded time, and says how far it got.

A frictionless elastic bounce between limiters never stops; with ``t_max = 1e6`` the plain engine
needs about a minute for the default 100,000 events.  ``simulate(..., wall_time=...)`` (and
``symvib run --wall-time``, 40 s by default) ends such a run with status ``wall_time_limit``:
the events before it are the same as those of a run bounded by their number.
"""
from __future__ import annotations

import subprocess
import sys

import pytest

from symvib.numeric.driver import check_wall_time, simulate
from symvib.numeric.events import Status
from symvib.numeric.scene import scene_from_dict

#: Seconds of plain-engine computing in these tests (a few thousand events).
SHORT = 0.5


def _endless(**run):
    return scene_from_dict({"curve": {"shape": "parabola"}, "parameters": {"p": 1.0},
                            "physics": {"mu": 0.0, "restitution": 1.0},
                            "limiters": {"left": "-pi/6", "right": "pi/4"}, "initial": {"q": 0.0, "qdot": 7.0},
                            "run": {"t_max": 1e6, **run}})


def test_a_run_past_its_wall_time_stops_with_its_events_right():
    result = simulate(_endless(), backend="python", wall_time=SHORT, samples=False)
    assert result.status is Status.WALL_TIME_LIMIT and result.success
    n = len(result.events)
    assert 0 < n < 100_000 and result.t_final < 1e6
    assert f"limit of {SHORT:g} s was reached" in result.message and "--wall-time" in result.message
    bounded = simulate(_endless(max_events=n), backend="python", samples=False)
    assert bounded.status is Status.MAX_EVENTS
    assert [(e.kind, e.t, e.q, e.qdot_before) for e in bounded.events] == \
        [(e.kind, e.t, e.q, e.qdot_before) for e in result.events]
    assert result.energy_budget.relative_residual < 1e-12


def test_no_wall_time_means_no_limit():
    result = simulate(_endless(max_events=300), backend="python", wall_time=0, samples=False)
    assert result.status is Status.MAX_EVENTS and len(result.events) == 300


def test_the_compiled_engine_has_no_clock_and_ignores_it():
    pytest.importorskip("numba")
    result = simulate(_endless(max_events=3000), backend="numba", wall_time=1e-9, samples=False)
    assert result.status is Status.MAX_EVENTS and len(result.events) == 3000


@pytest.mark.parametrize("value", [float("nan"), float("inf"), -1.0, "3", True, [1]])
def test_a_bad_wall_time_names_the_field(value):
    with pytest.raises(ValueError, match=r"^wall_time must be a number of seconds >= 0"):
        simulate(_endless(max_events=10), wall_time=value)


def test_check_wall_time_names_the_option_it_is_given():
    with pytest.raises(ValueError, match=r"^--wall-time must be"):
        check_wall_time(-2.0, "--wall-time")
    assert check_wall_time(None) is None and check_wall_time(0) is None and check_wall_time(2) == 2.0


def test_symvib_run_stops_on_its_wall_time(tmp_path):
    path = tmp_path / "endless.toml"
    path.write_text('[curve]\nshape = "parabola"\n[parameters]\np = 1.0\n[physics]\nmu = 0.0\nrestitution = 1.0\n'
                    '[limiters]\nleft = "-pi/6"\nright = "pi/4"\n[initial]\nq = 0.0\nqdot = 7.0\n[run]\nt_max = 1e6\n')
    out = subprocess.run([sys.executable, "-m", "symvib.cli", "run", str(path), "--backend", "python",
                          "--wall-time", str(SHORT)], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert "status: wall_time_limit (the plain engine's wall-clock limit of 0.5 s" in out.stdout
    bad = subprocess.run([sys.executable, "-m", "symvib.cli", "run", str(path), "--wall-time", "nan"],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and bad.stderr.strip().splitlines() == [
        "symvib run: error: --wall-time must be a number of seconds >= 0 (0: no limit), not nan"]
