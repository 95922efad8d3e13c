"""A cache others can write is code others run: the kernel cache and numba's are used only while
they are the user's alone, checked before any file in them is read (symvib.cachetrust; docs/trust.md),
and a cached module may hold only what the generator writes (symvib.numeric.kernels.verify_text).
"""
import hashlib
import math
import os
import re
import sys
import warnings
from pathlib import Path

import pytest

from symvib import cachetrust
from symvib.cachetrust import CacheTrustWarning
from symvib.numeric import kernels
from symvib.prepare import load_kernels

BOWL = {"kind": "graph", "q": "x", "z": "x**2/(2*p)", "params": {"p": "positive"}, "name": "bowl"}
PLANTED_PANEL = 0.123


@pytest.fixture
def fresh(monkeypatch, tmp_path):
    """No module loaded, no warning given, no numba folder chosen yet in this process; home in tmp_path."""
    monkeypatch.setattr(kernels, "_LOADED", {})
    monkeypatch.setattr(cachetrust, "_WARNED", set())
    monkeypatch.setattr(cachetrust, "_FALLBACKS", {})
    monkeypatch.setattr(cachetrust, "_CONFIGURED", [])
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    for key in [k for k in sys.modules if k.startswith("symvib.generated.bowl")]:
        monkeypatch.delitem(sys.modules, key)
    return tmp_path


def _redigest(text):
    body = text.partition("\n")[2]
    return f"{kernels.DIGEST_PREFIX}{hashlib.sha256(body.encode()).hexdigest()}\n{body}"


def _good_module(tmp_path, monkeypatch):
    """The text and file name of BOWL's module, made in a private cache of its own."""
    private = tmp_path / "maker"
    monkeypatch.setenv(cachetrust.CACHE_ENV, str(private))
    module = load_kernels(BOWL)
    path = Path(module.__file__)
    text = path.read_text()
    kernels._LOADED.clear()
    sys.modules.pop(module.__name__, None)
    return text, path.name


def _plant(folder, name, text):
    """A module with its digest recomputed and another PANEL: it passes every check but the folder's."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / name).write_text(_redigest(text.replace("PANEL = 0.25", f"PANEL = {PLANTED_PANEL}", 1)))


def _mode(path):
    return os.stat(path).st_mode & 0o777


# --------------------------------------------------------------------- the kernel cache's folder

#: Ways a cache folder is not the user's alone: (make it, a word of the warning).
UNTRUSTED = {
    "world-writable": (lambda f: f.chmod(0o777), "writable by group or others (mode 0777)"),
    "group-writable": (lambda f: f.chmod(0o775), "writable by group or others (mode 0775)"),
    "writable by others": (lambda f: f.chmod(0o702), "writable by group or others (mode 0702)"),
    "world-writable parent": (lambda f: f.parent.chmod(0o777), "parent folder"),
}


@pytest.mark.parametrize("how", sorted(UNTRUSTED))
def test_a_module_planted_in_an_untrusted_cache_never_runs(fresh, monkeypatch, how):
    text, name = _good_module(fresh, monkeypatch)
    cache = fresh / "shared" / "cache"
    _plant(cache, name, text)
    make, says = UNTRUSTED[how]
    make(cache)
    planted = (cache / name).read_bytes()
    monkeypatch.setenv(cachetrust.CACHE_ENV, str(cache))
    with pytest.warns(CacheTrustWarning, match=re.escape(says)) as caught:
        module = load_kernels(BOWL)
    assert module.PANEL != PLANTED_PANEL and str(cache) not in module.__file__
    assert (cache / name).read_bytes() == planted                       # not read, not replaced
    message = str(caught[0].message)
    assert "\n" not in message and str(cache) in message and "SYMVIB_CACHE" in message
    (cache.parent if how.endswith("parent") else cache).chmod(0o700)


def test_a_cache_owned_by_another_user_is_not_used(fresh, monkeypatch):
    text, name = _good_module(fresh, monkeypatch)
    cache = fresh / "theirs"
    _plant(cache, name, text)
    real = os.lstat

    def lstat(path, *args, **kwargs):
        info = real(path, *args, **kwargs)
        if Path(path) == cache:                  # as if another user owned it (a test cannot chown)
            fields = list(info)
            fields[4] = info.st_uid + 1
            return os.stat_result(fields)
        return info

    monkeypatch.setattr(os, "lstat", lstat)
    monkeypatch.setenv(cachetrust.CACHE_ENV, str(cache))
    with pytest.warns(CacheTrustWarning, match=r"owned by another user \(uid \d+\)"):
        module = load_kernels(BOWL)
    assert module.PANEL != PLANTED_PANEL


@pytest.mark.parametrize("kind", ["file", "link", "device"])
def test_a_cache_that_is_not_a_folder_is_named_in_one_line(fresh, monkeypatch, kind):
    cache = fresh / "cache"
    if kind == "file":
        cache.write_text("x")
    elif kind == "link":
        (fresh / "real").mkdir()
        cache.symlink_to(fresh / "real")
    else:
        cache = Path("/dev/null")
    monkeypatch.setenv(cachetrust.CACHE_ENV, str(cache))
    with pytest.warns(CacheTrustWarning) as caught:
        folder = kernels.cache_dir()
    message = str(caught[0].message)
    assert str(cache) in message and "$SYMVIB_CACHE" in message and "\n" not in message
    assert folder != cache and folder.is_dir() and _mode(folder) == 0o700
    assert kind != "file" or cache.read_text() == "x"


def test_a_new_cache_is_private_and_its_modules_too(fresh, monkeypatch):
    cache = fresh / "a" / "b" / "cache"
    monkeypatch.setenv(cachetrust.CACHE_ENV, str(cache))
    with warnings.catch_warnings():
        warnings.simplefilter("error", CacheTrustWarning)
        module = load_kernels(BOWL)
    assert _mode(cache) == 0o700 and _mode(cache.parent) == 0o700 and _mode(module.__file__) == 0o600


#: A cached file that is not the user's alone, or not a file: refused before it is read, then made again.
BAD_FILES = {
    "group-writable": (lambda p, other: p.chmod(0o664), "writable by group or others"),
    "world-writable": (lambda p, other: p.chmod(0o666), "writable by group or others"),
    "a link to a file elsewhere": (lambda p, other: (p.unlink(), p.symlink_to(other)), "symbolic link"),
    "a folder": (lambda p, other: (p.unlink(), p.mkdir()), "not a regular file"),
}


@pytest.mark.parametrize("how", sorted(BAD_FILES))
def test_a_cached_module_that_is_not_the_users_alone_is_not_read(fresh, monkeypatch, how):
    text, name = _good_module(fresh, monkeypatch)
    cache = fresh / "cache"
    _plant(cache, name, text)
    cache.chmod(0o700)
    other = fresh / "elsewhere.py"
    other.write_text(_redigest(text.replace("PANEL = 0.25", f"PANEL = {PLANTED_PANEL}", 1)))
    before = other.read_bytes()
    make, says = BAD_FILES[how]
    make(cache / name, other)
    monkeypatch.setenv(cachetrust.CACHE_ENV, str(cache))
    if how == "a folder":   # not read, not removed: the run goes on with the module uncached
        with pytest.warns(UserWarning, match="not a regular file"):
            module = load_kernels(BOWL)
        assert module.PANEL != PLANTED_PANEL and (cache / name).is_dir()
        return
    with pytest.warns(UserWarning, match=says):
        module = load_kernels(BOWL)
    assert module.PANEL != PLANTED_PANEL and other.read_bytes() == before
    assert not (cache / name).is_symlink() and _mode(cache / name) == 0o600   # made again, private


def test_generating_never_writes_through_a_link_at_a_temporary_name(fresh, monkeypatch):
    """The issue's planted link at a cache entry's temporary name (then ``NAME.<pid>.tmp.py``)."""
    text, name = _good_module(fresh, monkeypatch)
    cache = fresh / "cache"
    cache.mkdir(mode=0o700)
    victim = fresh / "victim.txt"
    victim.write_text("precious")
    stem = name.removesuffix(".py")
    for planted in (f"{stem}.{os.getpid()}.tmp.py", f"{stem}.{os.getpid()}.tmp.py.{os.getpid()}.part",
                    f"{name}.{os.getpid()}.part"):
        (cache / planted).symlink_to(victim)
    monkeypatch.setenv(cachetrust.CACHE_ENV, str(cache))
    module = load_kernels(BOWL)
    assert victim.read_text() == "precious"
    assert not (cache / name).is_symlink() and (cache / name).read_text() == text
    assert module.__file__ == str(cache / name)


# --------------------------------------------------------------------- numba's cache

@pytest.mark.parametrize("mode", [0o777, 0o775, 0o757])
def test_an_untrusted_numba_cache_is_replaced_before_numba_reads_it(fresh, monkeypatch, mode):
    planted = fresh / "numba-shared"
    planted.mkdir()
    (planted / "index.nbi").write_bytes(b"a pickle someone planted")
    planted.chmod(mode)
    monkeypatch.setenv(cachetrust.NUMBA_CACHE_ENV, str(planted))
    with pytest.warns(CacheTrustWarning, match="NUMBA_CACHE_DIR"):
        chosen = cachetrust.configure_numba()
    assert chosen != planted and os.environ[cachetrust.NUMBA_CACHE_ENV] == str(chosen)
    assert chosen == Path(os.environ["HOME"]) / ".cache" / "symvib" / "numba" and _mode(chosen) == 0o700
    numba_config = pytest.importorskip("numba.core.config")
    numba_config.reload_config()
    assert numba_config.CACHE_DIR == str(chosen)
    planted.chmod(0o700)


def test_numba_is_always_given_a_checked_folder(fresh, monkeypatch):
    monkeypatch.delenv(cachetrust.NUMBA_CACHE_ENV, raising=False)
    with warnings.catch_warnings():
        warnings.simplefilter("error", CacheTrustWarning)
        load_kernels("circle")   # any load configures numba first
    chosen = Path(os.environ[cachetrust.NUMBA_CACHE_ENV])
    assert chosen == Path(os.environ["HOME"]) / ".cache" / "symvib" / "numba" and _mode(chosen) == 0o700


def test_a_trusted_numba_cache_of_the_users_is_kept(fresh, monkeypatch):
    own = fresh / "my-numba"
    monkeypatch.setenv(cachetrust.NUMBA_CACHE_ENV, str(own))
    with warnings.catch_warnings():
        warnings.simplefilter("error", CacheTrustWarning)
        assert cachetrust.configure_numba() == own
    assert _mode(own) == 0o700


def test_the_command_line_shows_the_warning_in_one_line_and_runs(fresh):
    import subprocess

    cache = fresh / "cache"
    cache.mkdir()
    cache.chmod(0o777)
    scene = fresh / "scene.toml"   # a user curve: its kernels come from the cache
    scene.write_text('name = "bowl"\n[curve]\nname = "bowl"\nz = "x**2/(2*p)"\nq = "x"\nparams = {p = "positive"}\n'
                     '[parameters]\np = 1.0\n[physics]\nmu = 0.1\nrestitution = 0.8\n'
                     '[initial]\nq = 0.5\nqdot = 0.0\n[limiters]\nleft = -1.0\n')
    env = dict(os.environ, SYMVIB_CACHE=str(cache), HOME=str(fresh / "home"), SYMVIB_BACKEND="python")
    env.pop("NUMBA_CACHE_DIR", None)
    done = subprocess.run([sys.executable, "-m", "symvib.cli", "run", str(scene)], env=env, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    lines = [line for line in done.stderr.splitlines() if "warning" in line.lower()]
    assert len(lines) == 1 and lines[0].startswith("symvib run: warning: ") and str(cache) in lines[0]
    assert "Traceback" not in done.stderr and not list(cache.iterdir())
    cache.chmod(0o700)


# --------------------------------------------------------------------- the whitelist: what the generator writes

#: Modules that pass the digest (recomputed) and the old whitelist, and must not run (issue 29, 5-6).
TIGHTENED = {
    "rebind math.isfinite": ("import math\n\ndef f(q):\n    return q\nmath.isfinite = f\n", "an attribute"),
    "rebind in a kernel": ("import math\n\ndef f(q):\n    math.isfinite = q\n    return q\n", "an attribute"),
    "numpy attribute": ("import numpy\nnumpy.pi = 3.0\n", "an attribute"),
    "augmented attribute": ("import math\n\ndef f(q):\n    math.pi += 1\n    return q\n", "augmented"),
    "hang at import": ("X = max(range(10**12))\n", "a call at module level"),
    "power at import": ("X = 10**10**8\n", "not a literal"),
    "call at import": ("import numpy\nX = numpy.ones(10**12)\n", "a call at module level"),
    "default runs at import": ("def f(q, x=max(range(10**12))):\n    return q\n", "defaults"),
    "keyword-only argument": ("def f(q, *, x):\n    return q\n", "keyword-only"),
    "ufunc out=": ("import numpy\n\ndef f(q, a):\n    return numpy.sin(q, out=a)\n", "keyword argument 'out'"),
    "double-star keywords": ("import numpy\n\ndef f(q, k):\n    return numpy.sin(q, **k)\n", "keyword argument"),
    "item assignment": ("def f(q, a):\n    a[0] = q\n    return q\n", "an item"),
    "loop over a constant": ("def f(q):\n    t = 0\n    for k in range(10**12):\n        t += k\n    return t\n",
                             "a loop other than"),
    "loop with else": ("def f(q, n):\n    for k in range(n):\n        q = q\n    else:\n        q = 1\n    return q\n",
                       "a loop other than"),
    "comprehension over a call": ("def f(q):\n    return [k for k in range(10**12)]\n", "a comprehension"),
    "chained assignment": ("A = B = 1\n", "chained"),
    "starred target": ("def f(q):\n    a, *b = q\n    return a\n", "a starred name"),
    "item of a call at import": ("X = {}\nX[max(range(9))] = 1\n", "NAME[integer]"),
}


@pytest.mark.parametrize("label", sorted(TIGHTENED))
def test_the_whitelist_refuses_what_no_generator_writes(label, tmp_path):
    text, why = TIGHTENED[label]
    path = tmp_path / f"{label}.py"
    with pytest.raises(kernels.KernelError, match=re.escape(why)) as err:
        kernels.verify_text(text, path)
    assert str(err.value).startswith(f"{path}:") and "\n" not in str(err.value)


def test_every_catalogue_module_still_passes_the_tightened_whitelist():
    for path in sorted(kernels.generated_dir().glob("*.py")):
        kernels.verify_text(path.read_text(encoding="utf-8"), path)


def test_a_cached_module_rebinding_math_isfinite_is_regenerated_and_never_runs(fresh, monkeypatch):
    """The issue's module: digest recomputed, ``math.isfinite`` rebound at import (NaN no longer flagged)."""
    text, name = _good_module(fresh, monkeypatch)
    cache = fresh / "cache"
    cache.mkdir(mode=0o700)
    payload = "\n\ndef _always(x):\n    return True\n\n\nmath.isfinite = _always\n"
    (cache / name).write_text(_redigest(text + payload))
    (cache / name).chmod(0o600)
    monkeypatch.setenv(cachetrust.CACHE_ENV, str(cache))
    real = math.isfinite
    with pytest.warns(UserWarning, match="regenerating it"):
        load_kernels(BOWL)
    assert math.isfinite is real and not math.isfinite(float("nan"))
    assert (cache / name).read_text() == text
