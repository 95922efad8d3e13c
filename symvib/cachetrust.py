"""Cache folders symvib trusts: the user's alone, checked before any file in them is read.

A cache of code is code that runs: the kernel cache (``$SYMVIB_CACHE``,
default ``~/.cache/symvib/kernels``) holds Python modules symvib imports, and
numba's cache (``$NUMBA_CACHE_DIR``) holds pickles numba loads.  As ssh and pip
do, symvib uses a cache folder only when it is a real folder (not a symbolic
link) owned by the current user and not writable by group or others, and
every folder above it is owned by the user or by root and not writable by
others unless sticky (``/tmp``).  Cache folders are created ``0700``.

A folder that fails is not used: one warning line (:class:`CacheTrustWarning`)
names it and why, and the run goes on with a private temporary folder
(created ``0700``, removed at exit), so nothing is cached across runs until the
folder is fixed.  numba is always given a checked folder through
``NUMBA_CACHE_DIR`` (:func:`configure_numba`: the user's own if it passes,
else ``~/.cache/symvib/numba``), so it never reads the ``__pycache__``
folders beside the modules it compiles, or a ``.numba_config.yaml``'s choice.

Examples
--------
>>> import os, tempfile
>>> folder = tempfile.mkdtemp()
>>> problem(folder) is None
True
>>> os.chmod(folder, 0o777)
>>> problem(folder)
'writable by group or others (mode 0777)'
"""
from __future__ import annotations

import atexit
import os
import shutil
import stat
import sys
import tempfile
import warnings
from pathlib import Path

from symvib import safeio

__all__ = ["CACHE_ENV", "NUMBA_CACHE_ENV", "CacheTrustWarning", "problem", "trusted", "kernel_cache",
           "numba_cache", "configure_numba"]

#: Environment variable naming the kernel cache folder.
CACHE_ENV = "SYMVIB_CACHE"
#: numba's environment variable naming its cache folder.
NUMBA_CACHE_ENV = "NUMBA_CACHE_DIR"
#: The kernel cache below the user's cache home (``~/.cache``) when ``$SYMVIB_CACHE`` is not set.
DEFAULT_KERNEL_CACHE = ("symvib", "kernels")
#: numba's cache below the user's cache home when ``$NUMBA_CACHE_DIR`` is not set (or not trusted).
DEFAULT_NUMBA_CACHE = ("symvib", "numba")
#: Prefix of the private temporary folder used instead of a cache that is not trusted.
FALLBACK_PREFIX = "symvib-untrusted-cache-"
#: The owner a folder above a cache may have besides the user: root.
ROOT_UID = 0


class CacheTrustWarning(UserWarning):
    """A cache folder is not the user's alone (or not usable); it is not used in this run."""


def _cache_home() -> Path:
    return Path.home() / ".cache"


def _ancestor_problem(path: Path) -> str | None:
    """Why a folder above ``path`` lets others replace it (``None`` if none does)."""
    for folder in Path(os.path.realpath(path)).parents:
        try:
            info = os.stat(folder)
        except OSError as exc:
            return f"its parent folder {folder} cannot be checked ({exc.strerror or exc})"
        if info.st_uid not in (ROOT_UID, os.geteuid()):
            return f"its parent folder {folder} is owned by another user (uid {info.st_uid})"
        if info.st_mode & safeio.SHARED_WRITE and not info.st_mode & stat.S_ISVTX:
            return (f"its parent folder {folder} is writable by group or others "
                    f"(mode {stat.S_IMODE(info.st_mode):04o})")
    return None


def _make_private(path: Path) -> None:
    """Create ``path`` and its missing parents, each ``0700`` (``os.makedirs`` gives the mode to the last only)."""
    missing = []
    for folder in (path, *path.parents):
        if os.path.lexists(folder):
            break
        missing.append(folder)
    for folder in reversed(missing):
        try:
            os.mkdir(folder, safeio.PRIVATE_FOLDER_MODE)
        except FileExistsError:
            pass   # made meanwhile: checked like any folder


def problem(path, *, create: bool = False) -> str | None:
    """Why the folder ``path`` cannot be trusted as a cache (``None`` when it can).

    Parameters
    ----------
    path : str or path-like
    create : bool
        Create it (``0700``, with missing parents ``0700``) when it is missing.

    Returns
    -------
    str or None
        The reason, such as ``"owned by another user (uid 1001)"`` or ``"a file,
        not a folder"``.
    """
    path = Path(os.fspath(path))
    try:
        info = os.lstat(path)
    except FileNotFoundError:
        if not create:
            return "missing"
        try:
            _make_private(path)
            info = os.lstat(path)
        except OSError as exc:
            return f"cannot be created ({exc.strerror or exc})"
    except OSError as exc:
        return f"cannot be checked ({exc.strerror or exc})"
    if stat.S_ISLNK(info.st_mode):
        return "a symbolic link (name the folder it points to)"
    if not stat.S_ISDIR(info.st_mode):
        return "a file, not a folder" if stat.S_ISREG(info.st_mode) else "not a folder"
    return safeio.trust_problem(info, private=True) or _ancestor_problem(path)


def trusted(path, what: str) -> Path:
    """``path`` if it is (or was created as) a trusted cache folder; else a private temporary folder,
    with one :class:`CacheTrustWarning` line naming ``what`` and ``path``."""
    path = Path(os.fspath(path))
    why = problem(path, create=True)
    if why is None:
        return path
    fallback = _fallback(str(path))
    _warn_once(f"{what} {path} is {why}; it is not used{_hint(why)}: this run caches in {fallback}")
    return fallback


def _hint(why: str) -> str:
    """The remedy for a cache others could change (none for a path that is not a folder)."""
    return " (a cache must be yours alone: chmod 700)" if "owned by" in why or "writable by" in why else ""


#: Private temporary folders used instead of untrusted caches, by the path they replace.
_FALLBACKS: dict = {}
#: Warnings already given in this process.
_WARNED: set = set()
#: The numba cache folder :func:`configure_numba` checked and set in this process (its text and its Path).
_CONFIGURED: list = []


def _fallback(key: str) -> Path:
    folder = _FALLBACKS.get(key)
    if folder is None or not folder.is_dir():
        folder = Path(tempfile.mkdtemp(prefix=FALLBACK_PREFIX))   # 0700, a new name: nothing else in it
        atexit.register(shutil.rmtree, folder, ignore_errors=True)
        _FALLBACKS[key] = folder
    return folder


def _warn_once(message: str) -> None:
    if message not in _WARNED:
        _WARNED.add(message)
        warnings.warn(message, CacheTrustWarning, stacklevel=3)


def kernel_cache() -> Path:
    """The kernel cache folder: ``$SYMVIB_CACHE`` (default ``~/.cache/symvib/kernels``), created ``0700``
    and checked (:func:`trusted`) each time it is asked for."""
    configured = os.environ.get(CACHE_ENV)
    path = Path(configured) if configured else _cache_home().joinpath(*DEFAULT_KERNEL_CACHE)
    return trusted(path, f"the kernel cache (${CACHE_ENV})" if configured else "the kernel cache")


def numba_cache() -> Path:
    """The folder numba caches in: ``$NUMBA_CACHE_DIR`` if it is trusted, else ``~/.cache/symvib/numba``
    (created ``0700``), else a private temporary folder (each with a warning line)."""
    configured = os.environ.get(NUMBA_CACHE_ENV)
    if configured and configured not in {str(p) for p in _FALLBACKS.values()}:
        why = problem(configured, create=True)
        if why is None:
            return Path(configured)
        _warn_once(f"numba's cache ${NUMBA_CACHE_ENV} {configured} is {why}; it is not used{_hint(why)}")
    elif configured:
        return Path(configured)   # this process's private fallback, set by configure_numba
    return trusted(_cache_home().joinpath(*DEFAULT_NUMBA_CACHE), "numba's cache")


def configure_numba() -> Path:
    """Point numba at :func:`numba_cache` (``NUMBA_CACHE_DIR``, read again by numba if it is imported).

    Called before any compiled function is made (:func:`symvib.numeric.kernels.load`), so numba
    reads no cache file from a folder that was not checked; child processes inherit the setting.
    """
    if _CONFIGURED and os.environ.get(NUMBA_CACHE_ENV) == _CONFIGURED[0]:
        return _CONFIGURED[1]   # checked in this process already (every run asks: no new Path)
    folder = numba_cache()
    _CONFIGURED[:] = [str(folder), folder]
    if os.environ.get(NUMBA_CACHE_ENV) != str(folder):
        os.environ[NUMBA_CACHE_ENV] = str(folder)
        config = sys.modules.get("numba.core.config")
        if config is not None:
            config.reload_config()
    return folder
