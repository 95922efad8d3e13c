"""The tiered engine (symvib/numeric/tiered.py): a loop of plain runs compiles its curve in a child.

Each case runs in a fresh process on empty caches (its own ``$SYMVIB_CACHE`` and
``$NUMBA_CACHE_DIR``), with the thresholds lowered so that the third run starts the child.
"""
import json
import os
import signal
import subprocess
import sys
import textwrap
import time
import warnings
from pathlib import Path

import pytest

from symvib.numeric import tiered
from symvib.numeric.backends import backend_available

ROOT = Path(__file__).resolve().parents[1]

needs_numba = pytest.mark.skipif(not backend_available("numba"), reason="numba is not installed")

#: The start of every script: small thresholds, the paper parabola, a run that reports its engine.
PRELUDE = """
import json, os, sys, warnings
import symvib
from symvib.numeric import tiered
tiered.TIER_CALLS, tiered.TIER_SECONDS = 3, 0.0
scene = symvib.load_scene("paper-parabola")

def run(i, **options):
    return symvib.simulate(scene.replace(qdot0=7.0 + 1e-3 * i), **options)
"""

#: Seconds a script may take at most (a guard against a hang, not a speed limit).
HANG_GUARD = 900


def _env(tmp_path, **extra):
    env = {k: v for k, v in os.environ.items() if k not in ("SYMVIB_BACKEND", "SYMVIB_TIER")}
    env.update(SYMVIB_CACHE=str(tmp_path / "kernels"), NUMBA_CACHE_DIR=str(tmp_path / "numba"), **extra)
    return env


def _script(body: str) -> str:
    return PRELUDE + textwrap.dedent(body)


def _run(tmp_path, body: str, **extra) -> dict:
    """Run ``body`` after :data:`PRELUDE` in a fresh process; its last stdout line, as JSON."""
    done = subprocess.run([sys.executable, "-c", _script(body)], env=_env(tmp_path, **extra), cwd=ROOT,
                          capture_output=True, text=True, timeout=HANG_GUARD)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1]) | {"stderr": done.stderr}


def _gone(pid: int) -> bool:
    """Whether process ``pid`` no longer runs (gone, or a zombie left to init to reap)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, ProcessLookupError):
        return True
    return state in ("Z", "X")


@needs_numba
@pytest.mark.slow  # the child compiles the parabola's engine (about 20 s of CPU)
def test_a_loop_switches_to_the_compiled_engine_once_its_child_compiled_it(tmp_path):
    out = _run(tmp_path, """
        backends, alive_after_start = [], None
        for i in range(3):
            backends.append(run(i).stats["backend"])
        (child,) = tiered.children_of_tiers()      # the third run started it, and returned
        alive_after_start = child.exitcode is None
        pid, i = child.pid, 3
        while tiered.children_of_tiers():          # runs go on meanwhile, on the plain engine
            backends.append(run(i).stats["backend"])
            i += 1
        compiled = [run(i + j) for j in range(3)]
        plain = [run(i + j, backend="python") for j in range(3)]
        print(json.dumps({"backends": backends + [r.stats["backend"] for r in compiled],
                          "alive_after_start": alive_after_start, "pid": pid,
                          "events": [[[e.kind.value, e.t, e.q] for e in r.events] for r in compiled],
                          "plain": [[[e.kind.value, e.t, e.q] for e in r.events] for r in plain]}))
    """)
    assert out["alive_after_start"]
    backends = out["backends"]
    first = backends.index("numba")
    assert set(backends[:first]) == {"python"} and set(backends[first:]) == {"numba"}, backends
    assert first >= 3 and backends[-3:] == ["numba"] * 3
    for compiled, plain in zip(out["events"], out["plain"]):   # the engines' events, independently run
        assert [e[0] for e in compiled] == [e[0] for e in plain] and len(plain) > 10
        for (_, t, q), (_, t0, q0) in zip(compiled, plain):
            assert abs(t - t0) <= 1e-13 * max(1.0, abs(t0)) and abs(q - q0) <= 1e-13
    assert _gone(out["pid"])
    assert "compiling the engine of curve 'parabola'" not in out["stderr"]   # logged at INFO: silent by default


@needs_numba
def test_killing_the_parent_leaves_no_compile_child(tmp_path):
    body = """
        for i in range(3):
            run(i)
        (child,) = tiered.children_of_tiers()
        print(json.dumps({"pid": child.pid}), flush=True)
        while True:
            run(0)
    """
    parent = subprocess.Popen([sys.executable, "-c", _script(body)], env=_env(tmp_path), cwd=ROOT,
                              stdout=subprocess.PIPE, text=True)
    try:
        pid = json.loads(parent.stdout.readline())["pid"]
        assert not _gone(pid)   # compiling
        parent.send_signal(signal.SIGKILL)
        parent.wait(HANG_GUARD)
        for _ in range(200):    # the kernel's parent-death signal ends it at once; allow 10 s under load
            if _gone(pid):
                break
            time.sleep(0.05)
        assert _gone(pid)
    finally:
        parent.kill()
        parent.wait()


@needs_numba
def test_the_parent_s_exit_kills_its_compile_child_instead_of_waiting(tmp_path):
    out = _run(tmp_path, """
        for i in range(3):
            run(i)
        (child,) = tiered.children_of_tiers()
        print(json.dumps({"pid": child.pid, "alive": child.exitcode is None}))
    """)
    assert out["alive"]
    assert _gone(out["pid"])   # killed and reaped by the parent at its exit, before the test looks


@needs_numba
@pytest.mark.parametrize("how", [{"SYMVIB_TIER": "off"}, {"SYMVIB_BACKEND": "python"}, {"backend": "python"}],
                         ids=lambda how: "-".join(f"{k}={v}" for k, v in how.items()))
def test_an_opt_out_or_an_explicit_backend_starts_no_child(tmp_path, how):
    env = {k: v for k, v in how.items() if k != "backend"}
    options = {k: v for k, v in how.items() if k == "backend"}
    out = _run(tmp_path, f"""
        results = [run(i, **{options!r}) for i in range(10)]
        print(json.dumps({{"children": len(tiered.children_of_tiers()),
                          "backends": sorted({{r.stats["backend"] for r in results}})}}))
    """, **env)
    assert out["children"] == 0 and out["backends"] == ["python"]
    assert "TierWarning" not in out["stderr"]


#: Failing compile children: one that exits 1, the real one whose compiler raises, one that "compiles"
#: without writing numba's cache, one that never ends; and what the warning says of each.
FAILING_CHILDREN = {
    "exits-1": ("def child(parent, module, call, send):\n    sys.exit(1)\n", "ended with status 1"),
    "raises": ("from symvib.numeric import backends\nbound = backends.bound_engine\n"
               "def no_numba(mod, backend):\n"
               "    if backend == 'numba':\n        raise MemoryError('out of memory')\n"
               "    return bound(mod, backend)\n"
               "backends.bound_engine = no_numba\nchild = tiered._compile\n",
               "MemoryError: out of memory"),
    "no-cache": ("def child(parent, module, call, send):\n    pass\n", "numba could not write"),
    # a child that never ends (a lock held at the fork, a stuck compile): killed after TIER_TIMEOUT
    "stuck": ("import time\ntiered.TIER_TIMEOUT = 1.0\n"
              "def child(parent, module, call, send):\n    time.sleep(3600)\n", "did not end within 1 s"),
}


@needs_numba
@pytest.mark.parametrize("case", sorted(FAILING_CHILDREN))
def test_a_failed_child_leaves_the_plain_engine_with_one_warning(tmp_path, case):
    child, says = FAILING_CHILDREN[case]
    out = _run(tmp_path, child + """
tiered._compile = child
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    results = [run(i) for i in range(3)]
    while tiered.children_of_tiers():
        results.append(run(0))
    results += [run(i) for i in range(5)]
tier_warnings = [str(w.message) for w in caught if w.category is tiered.TierWarning]
print(json.dumps({"warnings": tier_warnings, "backends": sorted({r.stats["backend"] for r in results}),
                  "children": len(tiered.children_of_tiers())}))
""")
    assert out["backends"] == ["python"] and out["children"] == 0
    assert len(out["warnings"]) == 1 and says in out["warnings"][0], out["warnings"]
    assert "stays on the plain engine" in out["warnings"][0]


@needs_numba
def test_a_process_forked_from_the_loop_leaves_its_parent_s_compile_child_alone(tmp_path):
    # A worker forked from the loop's process inherits its tiers: its exit must not kill the
    # parent's compile child, nor may it count that child as its own.
    out = _run(tmp_path, """
        for i in range(3):
            run(i)
        (child,) = tiered.children_of_tiers()
        pid = os.fork()
        if pid == 0:
            own = len(tiered.children_of_tiers())
            tiered.stop_children()
            os._exit(own)
        _, status = os.waitpid(pid, 0)
        print(json.dumps({"worker_saw": os.waitstatus_to_exitcode(status), "alive": child.exitcode is None}))
    """)
    assert out["worker_saw"] == 0 and out["alive"]


def test_turned_off_the_tier_leaves_auto_to_the_disk_cache(tmp_path, monkeypatch):
    # SYMVIB_TIER=off must give back the behaviour without tiers: auto takes an engine that
    # another process compiled meanwhile.
    import importlib

    from symvib.numeric import backends, driver, tiered
    from symvib.numeric.scene import resolve_scene

    bind_module = importlib.import_module("symvib.numeric.engine.bind")   # (the package's `bind` is the function)

    monkeypatch.setenv("SYMVIB_CACHE", str(tmp_path))
    monkeypatch.setenv("SYMVIB_TIER", "off")
    monkeypatch.delenv("SYMVIB_BACKEND", raising=False)
    monkeypatch.setattr(tiered, "TIER_CALLS", 2)
    monkeypatch.setattr(tiered, "TIER_SECONDS", 0.0)
    monkeypatch.setattr(backends, "_BOUND", {})
    scene = resolve_scene("paper-parabola")
    results = [driver.simulate(scene, samples=False) for _ in range(4)]
    assert {r.stats["backend"] for r in results} == {"python"} and not tiered.children_of_tiers()
    monkeypatch.setattr(bind_module, "is_compiled", lambda module, entry="simulate_bound": True)
    assert driver.run_backend(scene.shape) == "numba"


@pytest.mark.parametrize("value, enabled", [("off", False), (" OFF\n", False), ("0", False), ("False", False),
                                            ("", True), ("on", True), ("Yes", True), ("1", True)])
def test_symvib_tier_values_turn_the_tiered_engine_on_or_off(value, enabled):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert tiered.tier_enabled({"SYMVIB_TIER": value}) is enabled


@pytest.mark.parametrize("value", ["disabled", "of", "never", "\uff4f\uff46\uff46", "off;rm -rf /", "$(id)",
                                   "x" * 10_000])
def test_an_unknown_symvib_tier_value_keeps_the_tiered_engine_off_and_names_the_variable(value):
    with pytest.warns(tiered.TierWarning, match=r"\$SYMVIB_TIER=.* is not one of on, 1, yes, true or off") as info:
        assert tiered.tier_enabled({"SYMVIB_TIER": value}) is False
    assert len(str(info[0].message)) < 300
