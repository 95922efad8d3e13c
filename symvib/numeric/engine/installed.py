"""Engines compiled at install time: read from a folder inside the installed package, never written at run time.

``pip install .`` compiles the specialized engine of the paper's curves (their ``simulate``,
``samples`` and ``sweep`` entries and their kernels; :mod:`symvib.install_engines`, run by
``setup.py``'s build step) into ``symvib/_installed/``.  A process on empty caches then loads them
as numba loads its own disk cache, in about a second, instead of compiling for 20 s.

What makes an installed engine safe to load:

* **A content key, not a path or a time.** Every file is named by :func:`content_key`: a
  SHA-256 of the engine's code and compile options (:func:`installed_digest`: every module of
  the engine package, the binding's included, a superset of what
  :func:`~symvib.numeric.engine.bind.engine_digest` reads, and the layout), the kernel module's
  bytes, Python's cache tag and the numba, llvmlite and NumPy releases.  The same key is the
  index's source stamp.  A package built in ``build/lib`` works from ``site-packages``; an
  engine, a kernel module or a release that changed misses.
* **numba's own index.** Inside a file, numba keys each compiled function by its signature,
  its bytecode and the code generator's magic tuple (target triple, CPU name and features): an
  engine built for another CPU misses too.
* **A miss is today's behaviour.** The dispatcher then loads from the user's cache
  (``$NUMBA_CACHE_DIR``) or compiles and saves there, as before; nothing is written into the
  installed folder at run time, and :func:`~symvib.numeric.engine.bind.flush_if_stale` flushes
  the user's cache only.  Any error while reading the installed folder is a miss.

``auto`` (a single run never waits for a compiler) takes an installed engine as compiled
(:func:`has`, asked by :func:`~symvib.numeric.engine.bind.is_compiled`): the curve's record
(``<curve tag>.json``) must name the entry under the same key and the same magic tuple as this
process's numba.  ``$SYMVIB_INSTALLED_ENGINES=off`` ignores the folder (:func:`enabled`).

Examples
--------
>>> import os
>>> enabled({"SYMVIB_INSTALLED_ENGINES": "off"}), enabled({})
(False, True)
"""
from __future__ import annotations

import hashlib
import json
import logging
import os
import sys
from functools import cache
from pathlib import Path

__all__ = ["INSTALLED_ENV", "FOLDER", "enabled", "installed_digest", "content_key", "record_path", "has",
           "attach", "from_installed", "building", "magic"]

#: Environment variable: ``off`` ignores the engines compiled at install time.
INSTALLED_ENV = "SYMVIB_INSTALLED_ENGINES"
#: Values of :data:`INSTALLED_ENV` that switch them off.
OFF = ("off", "0", "no", "false")
#: The installed folder (read only at run time; tests point it elsewhere).
FOLDER = Path(__file__).resolve().parents[2] / "_installed"
#: Format of a curve's record.
FORMAT = 1

_log = logging.getLogger(__name__)
#: Set by :func:`building`: the folder this process compiles into (the build step only).
_BUILD: list = []


def enabled(environ=None) -> bool:
    """Whether installed engines are read (``$SYMVIB_INSTALLED_ENGINES`` is not ``off``)."""
    return (environ if environ is not None else os.environ).get(INSTALLED_ENV, "").strip().lower() not in OFF


def building(folder) -> None:
    """Compile into ``folder`` in this process (the build step, :mod:`symvib.install_engines`): the
    dispatchers :func:`attach` sets up save there instead of the user's cache."""
    _BUILD[:] = [Path(folder)]


def _folder() -> Path:
    return _BUILD[0] if _BUILD else FOLDER


@cache
def installed_digest() -> str:
    """SHA-256 (hex) of what the compiled code depends on besides a curve's module: the engine
    package's sources and the layout (:func:`_engine_sources`), Python, numba, llvmlite and NumPy
    (their versions read from their metadata: nothing is imported)."""
    from importlib.metadata import PackageNotFoundError, version

    digest = hashlib.sha256()
    for path in _engine_sources():
        digest.update(path.name.encode() + b"\0" + path.read_bytes())
    digest.update(sys.implementation.cache_tag.encode())
    for package in ("numba", "llvmlite", "numpy"):
        try:
            digest.update(f"{package}={version(package)}".encode())
        except PackageNotFoundError:
            digest.update(f"{package}=?".encode())
    return digest.hexdigest()


def _engine_sources() -> list:
    """Every source file the compiled code can depend on besides a curve's module: all of the engine
    package's modules (the engine, its binding, this module; a superset of what
    :func:`~symvib.numeric.engine.bind.engine_digest` reads, so nothing it keys on is missed) and the
    layout and kernel interface the engine takes as compile-time constants.  Found, not imported."""
    import importlib.util

    here = Path(__file__).resolve().parent
    extra = [Path(importlib.util.find_spec(name).origin) for name in ("symvib.numeric.layout", "symvib.kernelformat")]
    return sorted(here.glob("*.py")) + extra


def content_key(module) -> str:
    """The key of ``module``'s installed engine (24 hex digits): :func:`installed_digest` and the
    module file's bytes (cached on the module)."""
    key = getattr(module, "_symvib_installed_key", None)
    if key is None:
        digest = hashlib.sha256(installed_digest().encode())
        digest.update(Path(module.__file__).read_bytes())
        key = module._symvib_installed_key = digest.hexdigest()[:24]
    return key


def record_path(module) -> Path:
    """The record of ``module``'s installed engine (its entries, key and magic tuple)."""
    from symvib.numeric.kernels import curve_tag

    return _folder() / f"{curve_tag(module)}.json"


@cache
def magic() -> tuple:
    """numba's code-generator magic tuple of this process (target triple, CPU name, CPU features);
    imports numba."""
    from numba.core.registry import cpu_target

    return tuple(cpu_target.target_context.codegen().magic_tuple())


def has(module, entry: str) -> bool:
    """Whether ``module``'s compiled ``entry`` (``"simulate_bound"``, ...) was installed for this
    engine, this module, these releases and this CPU (numba is imported only when all else matches)."""
    if not enabled() or _BUILD or not getattr(module, "__file__", None):
        return False
    try:
        record = _record(record_path(module))
        if record is None or record.get("format") != FORMAT or record.get("key") != content_key(module):
            return False
        if entry not in record.get("entries", ()):
            return False
        return tuple(record.get("magic", ())) == magic()
    except (OSError, ValueError, TypeError, AttributeError):   # (a record that is not a mapping too)
        return False


#: Largest record read (a record names a curve's entries, key and magic tuple: well under a kilobyte).
MAX_RECORD_BYTES = 64 * 1024
#: Records read in this process, by path (the installed folder is not written after the install; a
#: plain run asks :func:`has` each time, so the file is read once).
_RECORDS: dict = {}


def _record(path: Path):
    """The record at ``path`` (``None`` when there is none, it is larger than :data:`MAX_RECORD_BYTES`
    or it does not parse as JSON), read once.  Data, never code: the engine reads no source text."""
    if path not in _RECORDS:
        try:
            with open(path, "rb") as fh:
                data = fh.read(MAX_RECORD_BYTES + 1)
            _RECORDS[path] = json.loads(data) if len(data) <= MAX_RECORD_BYTES else None
        except (OSError, ValueError):
            _RECORDS[path] = None
    return _RECORDS[path]


def write_record(module, entries) -> Path:
    """Write ``module``'s record after the build step compiled its ``entries``."""
    path = record_path(module)
    path.write_text(json.dumps({"format": FORMAT, "module": module.__name__, "key": content_key(module),
                                "entries": sorted(entries), "magic": list(magic())}, indent=1) + "\n",
                    encoding="utf-8")
    return path


def from_installed(dispatcher) -> bool:
    """Whether every compiled signature of ``dispatcher`` came from the installed folder."""
    cache_ = getattr(dispatcher, "_cache", None)
    return bool(getattr(cache_, "installed_hits", 0)) and not any(dispatcher._cache_misses.values())


def attach(dispatcher, module) -> None:
    """Let a numba dispatcher with ``cache=True`` load ``module``'s installed engine first (its
    cache then reads the installed folder, then the user's; it writes the user's, or the build
    folder in the build step)."""
    if not getattr(module, "__file__", None) or not enabled() and not _BUILD:
        return
    try:
        dispatcher._cache = _cache_class()(dispatcher.py_func, content_key(module))
    except Exception as exc:   # noqa: BLE001 - numba's caching internals not as expected: its own cache, as before
        if _BUILD:
            raise
        _log.debug("installed engines not read for %s: %s", dispatcher.py_func.__qualname__, exc)


@cache
def _cache_class():
    from numba.core.caching import FunctionCache, IndexDataCacheFile

    class InstalledCache(FunctionCache):
        """numba's function cache (the user's folder) behind a read-only installed folder."""

        def __init__(self, py_func, key: str):
            super().__init__(py_func)
            base = f"{py_func.__qualname__}-{key}.py{sys.version_info[0]}{sys.version_info[1]}"
            self._installed = IndexDataCacheFile(cache_path=str(_folder()), filename_base=base, source_stamp=key)
            self._building = bool(_BUILD)
            self.installed_hits = 0

        def load_overload(self, sig, target_context):
            if self._enabled and not self._building and enabled():
                try:
                    target_context.refresh()
                    data = self._installed.load(self._index_key(sig, target_context.codegen()))
                    if data is not None:
                        out = self._impl.rebuild(target_context, data)
                        self.installed_hits += 1
                        return out
                except Exception as exc:   # noqa: BLE001 - a broken installed file is a miss
                    _log.debug("installed engine %s not loaded: %s", self._name, exc)
            return super().load_overload(sig, target_context)

        def save_overload(self, sig, data):
            if not self._building:
                return super().save_overload(sig, data)
            if self._enabled and self._impl.check_cachable(data):
                self._installed.save(self._index_key(sig, data.codegen), self._impl.reduce(data))
            return None

    return InstalledCache
