"""Engines compiled at install time (symvib/numeric/engine/installed.py, symvib/install_engines.py, setup.py).

The paper parabola's engine is compiled once into a folder of its own (as the build step does into the
package); each case then runs in a fresh process on empty caches (its own ``$SYMVIB_CACHE`` and
``$NUMBA_CACHE_DIR``) with that folder as the installed one.
"""
import importlib.util
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from symvib.numeric.backends import backend_available
from symvib.numeric.engine import installed

ROOT = Path(__file__).resolve().parents[1]

needs_numba = pytest.mark.skipif(not backend_available("numba"), reason="numba is not installed")

#: Seconds a process may take at most (a guard against a hang, not a speed limit).
HANG_GUARD = 900

#: One case: the installed folder, a digest (``stale``: the engine's sources changed), and whether to
#: run ``backend="numba"`` too; prints what ran as JSON.
CASE = """
import json, sys
from pathlib import Path
import symvib
from symvib.numeric.engine import installed
from symvib.numeric.kernels import load
installed.FOLDER = Path(sys.argv[1])
if sys.argv[2] == "stale":   # as after an edit of the engine: another content key
    installed.installed_digest = lambda: "the digest of an engine whose sources changed"
scene = symvib.load_scene("paper-parabola")
mod = load(scene.shape)

def events(result):
    return [[e.kind.value, e.t, e.q] for e in result.events]

out = {"has": installed.has(mod, "simulate_bound")}
auto = symvib.simulate(scene)
out["auto"], out["auto_events"] = auto.stats["backend"], events(auto)
if sys.argv[3] == "numba":
    out["numba_events"] = events(symvib.simulate(scene, backend="numba"))
    out["from_installed"] = installed.from_installed(mod._symvib_specialized_engine["simulate_bound"])
out["plain_events"] = events(symvib.simulate(scene, backend="python"))
print(json.dumps(out))
"""


def _env(caches: Path, **extra) -> dict:
    env = {k: v for k, v in os.environ.items() if k not in ("SYMVIB_BACKEND", "SYMVIB_INSTALLED_ENGINES")}
    env.update(SYMVIB_CACHE=str(caches / "kernels"), NUMBA_CACHE_DIR=str(caches / "numba"), SYMVIB_TIER="off",
               **extra)
    return env


@pytest.fixture(scope="module")
def engines(tmp_path_factory):
    """A folder holding the paper parabola's engine compiled as the build step compiles it."""
    folder = tmp_path_factory.mktemp("installed")
    subprocess.run([sys.executable, "-m", "symvib.install_engines", str(folder), "parabola"], cwd=ROOT, check=True,
                   env=_env(tmp_path_factory.mktemp("build-caches")), timeout=HANG_GUARD)
    return folder


def _case(folder: Path, caches: Path, digest: str = "same", numba: bool = False, **env) -> dict:
    done = subprocess.run([sys.executable, "-c", CASE, str(folder), digest, "numba" if numba else "auto"],
                          cwd=ROOT, env=_env(caches, **env), capture_output=True, text=True, timeout=HANG_GUARD)
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def _same_events(a, b):
    """The same kinds in the same order, times and positions within 1e-13 (the two engines sum in another
    order: not bit for bit)."""
    assert [e[0] for e in a] == [e[0] for e in b]
    for (_, t1, q1), (_, t2, q2) in zip(a, b):
        assert abs(t1 - t2) <= 1e-13 * max(1.0, abs(t2)) and abs(q1 - q2) <= 1e-13


def _compiled_files(caches: Path) -> list:
    return sorted(p.name for p in (caches / "numba").rglob("*.nbc"))


@needs_numba
@pytest.mark.slow
def test_an_installed_engine_is_taken_on_empty_caches(engines, tmp_path):
    out = _case(engines, tmp_path, numba=True)
    assert out["has"] and out["auto"] == "numba"   # the first run of a process: no compile to wait for
    assert out["from_installed"]                   # loaded from the installed folder, not compiled
    assert _compiled_files(tmp_path) == []         # nothing compiled into the user's cache
    _same_events(out["auto_events"], out["plain_events"])
    assert out["numba_events"] == out["auto_events"]
    # no marker either: the user's cache does not hold the engine
    assert not list((tmp_path / "kernels" / "engines").glob("compiled-*"))


@needs_numba
@pytest.mark.slow
def test_a_stale_installed_engine_is_not_used_and_the_run_is_right(engines, tmp_path):
    out = _case(engines, tmp_path, digest="stale", numba=True)
    assert not out["has"] and out["auto"] == "python"   # auto does not take it for compiled
    assert not out["from_installed"]                    # backend="numba" compiled the engine instead
    assert any(name.startswith("loop.simulate_bound") for name in _compiled_files(tmp_path))
    _same_events(out["numba_events"], out["plain_events"])
    _same_events(out["auto_events"], out["plain_events"])


@needs_numba
@pytest.mark.slow
def test_a_record_of_another_module_or_cpu_is_not_taken(engines, tmp_path):
    folder = tmp_path / "installed"
    shutil.copytree(engines, folder)
    (record,) = folder.glob("parabola_*.json")
    original = json.loads(record.read_text(encoding="utf-8"))
    for change in ({"key": "0" * 24}, {"magic": ["another-triple", "another-cpu", ""]}):
        record.write_text(json.dumps({**original, **change}), encoding="utf-8")
        out = _case(folder, tmp_path / f"caches-{next(iter(change))}")
        assert not out["has"] and out["auto"] == "python"
        _same_events(out["auto_events"], out["plain_events"])


@needs_numba
@pytest.mark.slow
def test_the_switch_ignores_installed_engines(engines, tmp_path):
    out = _case(engines, tmp_path, SYMVIB_INSTALLED_ENGINES="off")
    assert not out["has"] and out["auto"] == "python"


def test_the_switch_values():
    assert installed.enabled({}) and installed.enabled({installed.INSTALLED_ENV: "on"})
    assert not any(installed.enabled({installed.INSTALLED_ENV: v}) for v in ("off", "OFF", "0", "no", "false"))


def test_no_installed_folder_is_no_engine(tmp_path, monkeypatch):
    from symvib.numeric.kernels import load

    monkeypatch.delenv(installed.INSTALLED_ENV, raising=False)
    monkeypatch.setattr(installed, "FOLDER", tmp_path / "nothing here")
    assert not installed.has(load("parabola"), "simulate_bound")


def _setup_module():
    spec = importlib.util.spec_from_file_location("symvib_setup", ROOT / "setup.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)   # (setup() runs only as __main__)
    return module


def test_a_failing_build_step_warns_and_ships_no_engines(tmp_path, capsys):
    setup = _setup_module()
    (tmp_path / "symvib" / "_installed").mkdir(parents=True)   # an earlier build's, removed
    env = dict(os.environ, **{setup.BUILD_ENV: "no-such-curve"})
    assert setup.build_installed_engines(tmp_path, environ=env) is False
    assert not (tmp_path / "symvib" / "_installed").exists()
    assert "no engines compiled at install time" in capsys.readouterr().err
    assert setup.build_installed_engines(tmp_path, environ=env, python=str(tmp_path / "no-python")) is False
    assert setup.build_installed_engines(tmp_path, environ=dict(env, **{setup.BUILD_ENV: "off"})) is False


@pytest.mark.slow
def test_an_install_whose_build_step_fails_works(tmp_path):
    """``pip install`` of the package with the build step failing: the install succeeds, ships no
    engines, and runs."""
    source = tmp_path / "source"
    source.mkdir()
    for name in ("pyproject.toml", "setup.py", "README.md"):
        shutil.copy2(ROOT / name, source / name)
    for name in ("symvib", "generated"):
        shutil.copytree(ROOT / name, source / name, ignore=shutil.ignore_patterns("__pycache__", "_installed"))
    target = tmp_path / "site"
    env = _env(tmp_path / "caches", SYMVIB_BUILD_ENGINES="no-such-curve")
    # (as the README installs: pip's isolated build environment, build-system.requires from the index)
    done = subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--target", str(target),
                           str(source)], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=HANG_GUARD)
    assert done.returncode == 0, done.stderr[-3000:]
    assert (target / "symvib" / "generated" / "parabola.py").exists()
    assert not (target / "symvib" / "_installed").exists()
    run = subprocess.run([sys.executable, "-c", "import symvib; r = symvib.simulate('paper-parabola'); "
                          "print(symvib.__file__, r.status.value, r.stats['backend'])"],
                         cwd=tmp_path, env=dict(env, PYTHONPATH=str(target)), capture_output=True, text=True,
                         timeout=HANG_GUARD)
    assert run.returncode == 0, run.stderr[-3000:]
    where, status, backend = run.stdout.split()
    assert Path(where).is_relative_to(target) and status == "arrested" and backend == "python"
