"""The build step beside pyproject.toml: engines compiled at install time (docs/design.md, "Engines compiled
at install time").

After setuptools copies the package into its build folder, :func:`build_installed_engines` compiles the
paper curves' engines into ``symvib/_installed/`` there (``python -m symvib.install_engines``, in a child
process on the build folder, with caches of its own), so that they ship inside the wheel.  It never
fails an install: on any failure (numba missing, a compile error, :data:`TIMEOUT`) it warns and ships no
engines; the package then works as before (engines compiled on first need, into the user's cache).
Not in an editable install (``pip install -e .``): there the package is the checkout, whose engine
sources change under the developer, and runs compile into the user's cache as before.
``$SYMVIB_BUILD_ENGINES``: ``off`` skips the step; a comma list names the curves (default: the paper's).
"""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

#: Environment variable of the build step: "off", or a comma list of curves.
BUILD_ENV = "SYMVIB_BUILD_ENGINES"
#: Longest the build step may take, seconds (a compile is 20-40 s of CPU a curve).
TIMEOUT = 900


def warn(message: str) -> None:
    print(f"symvib build: {message}", file=sys.stderr, flush=True)


def build_installed_engines(build_lib, environ=None, python=sys.executable) -> bool:
    """Compile the engines into ``build_lib``/symvib/_installed; whether they were.  Never raises."""
    environ = dict(os.environ if environ is None else environ)
    folder = Path(build_lib) / "symvib" / "_installed"
    try:
        shutil.rmtree(folder, ignore_errors=True)   # (an earlier build's)
        choice = environ.get(BUILD_ENV, "").strip()
        if choice.lower() == "off":
            return False
        curves = [c.strip() for c in choice.split(",") if c.strip()]
        with tempfile.TemporaryDirectory(prefix="symvib-build-") as tmp:
            env = {k: v for k, v in environ.items() if k != "SYMVIB_BACKEND"}
            # (the build folder first; pip's isolated build environment reaches its packages through
            # PYTHONPATH too, so that stays behind it)
            path = [str(Path(build_lib).resolve()), *filter(None, [environ.get("PYTHONPATH")])]
            env.update(PYTHONPATH=os.pathsep.join(path), SYMVIB_CACHE=str(Path(tmp) / "kernels"),
                       NUMBA_CACHE_DIR=str(Path(tmp) / "numba"), SYMVIB_TIER="off")
            done = subprocess.run([python, "-m", "symvib.install_engines", str(folder.resolve()), *curves],
                                  env=env, cwd=tmp, capture_output=True, text=True, timeout=TIMEOUT)
        if done.returncode != 0:
            raise RuntimeError(f"exit code {done.returncode}: {(done.stderr or done.stdout)[-1500:]}")
        return True
    except Exception as exc:   # noqa: BLE001 - the install goes on without engines
        shutil.rmtree(folder, ignore_errors=True)
        warn(f"no engines compiled at install time ({exc}); the package works without them (a first compile "
             "then goes to the user's cache)")
        return False


class BuildPyWithEngines(build_py):
    """``build_py``, then the engines compiled into the build folder (not in an editable install)."""

    def run(self):
        super().run()
        if getattr(self, "editable_mode", False) or self.dry_run:
            return
        build_installed_engines(self.build_lib)


if __name__ == "__main__":
    setup(cmdclass={"build_py": BuildPyWithEngines})
