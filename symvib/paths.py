"""Files and folders named by users: what symvib reads and where it writes.

Text from a scene (its ``name``, a curve's ``name``) becomes part of file
names: :func:`safe_stem` makes it a plain file-name stem, so a name such as
``../../x`` or ``/abs/path`` writes inside the folder the user named and
nowhere else (:func:`inside` checks it).  Input files are read by
:func:`read_user_file`, which refuses directories, devices and fifos and
files larger than :data:`MAX_INPUT_BYTES` *before* reading them.  Output
paths are checked by :func:`check_output_file` and :func:`check_output_dir`
before any work is done.  Every refusal is a one-line :class:`UserPathError`
naming the path.

This module imports neither SymPy nor NumPy.

Examples
--------
>>> safe_stem("paper-parabola")
'paper-parabola'
>>> safe_stem("../../x")
'_._.._x-9cdf6a50'
>>> inside("out/a.png", "out"), inside("out/../a.png", "out")
(True, False)
"""
from __future__ import annotations

import hashlib
import os
import re
import stat
from pathlib import Path

import tomllib

__all__ = ["UserPathError", "MAX_INPUT_BYTES", "MAX_STEM_LENGTH", "MAX_TOML_DOTS", "safe_stem", "inside",
           "read_user_file", "read_user_toml", "check_output_file", "check_output_dir"]

#: Largest input file (scene, sweep definition) read, in bytes (1 MB; a scene is a few hundred bytes).
MAX_INPUT_BYTES = 1_000_000
#: Longest file-name stem made from user text, in characters (file systems allow 255 bytes per name).
MAX_STEM_LENGTH = 100
#: Hex digits of the hash appended to a stem that had to be changed (keeps distinct names distinct).
STEM_HASH_DIGITS = 8
#: Stem used when nothing of the text is left.
EMPTY_STEM = "unnamed"
#: Most dots of dotted keys and table names in one TOML file: the standard parser spends
#: time and memory quadratic in the depth of a dotted key (100,000 of them take tens of GB).
MAX_TOML_DOTS = 1000

#: TOML strings (multi-line first) and comments, removed before the dots of keys are counted.
_TOML_STRINGS = re.compile(r'"""[\s\S]*?"""|\'\'\'[\s\S]*?\'\'\'|"(?:[^"\\\n]|\\.)*"|\'[^\'\n]*\'|#[^\n]*')
#: A dot that is not the decimal point of a number.
_KEY_DOT = re.compile(r"(?<![0-9])\.|\.(?![0-9])")

_UNSAFE = re.compile(r"[^A-Za-z0-9._-]")
#: The byte-order mark some editors put at the start of a UTF-8 file (TOML parsers refuse it).
BYTE_ORDER_MARK = "\ufeff"


class UserPathError(OSError):
    """A file or folder named by the user cannot be used; the message names it."""

    def __init__(self, path, reason: str):
        self.path = str(path)
        self.reason = reason
        super().__init__(f"{_show(path)}: {reason}")

    def __str__(self) -> str:
        return self.args[0]


def _show(path) -> str:
    """A path as one printable line (control characters escaped)."""
    text = os.fsdecode(path) if isinstance(path, (bytes, os.PathLike)) else str(path)
    return text if text.isprintable() else repr(text)[1:-1]


def safe_stem(text, *, max_length: int = MAX_STEM_LENGTH) -> str:
    """A file-name stem made from user text: only ``[A-Za-z0-9._-]``, no leading dot or dash.

    Any other character (``/``, ``\\``, NUL, newline, non-ASCII) becomes ``_``;
    the stem is at most ``max_length`` characters.  When the text had to be
    changed, a short hash of the original is appended, so two different
    names never share a file.

    Parameters
    ----------
    text : str
        The user text (a scene or curve name).
    max_length : int
        Longest stem returned.

    Returns
    -------
    str
    """
    text = str(text)
    stem = _UNSAFE.sub("_", text)
    stem = re.sub(r"^[.-]", "_", stem)
    if stem == text and 0 < len(stem) <= max_length:
        return stem
    digest = hashlib.sha256(text.encode("utf-8", "surrogatepass")).hexdigest()[:STEM_HASH_DIGITS]
    stem = (stem or EMPTY_STEM)[:max_length - STEM_HASH_DIGITS - 1]
    return f"{stem}-{digest}"


def inside(path, folder) -> bool:
    """Whether ``path`` (after resolving ``..`` and symbolic links) lies inside ``folder``."""
    folder = Path(os.path.abspath(folder)).resolve()
    target = Path(os.path.abspath(path)).resolve()
    return target == folder or folder in target.parents


def read_user_file(path, what: str = "file", *, max_bytes: int = MAX_INPUT_BYTES) -> str:
    """Read a UTF-8 text file named by the user, refusing what is not a small regular file.

    The size is checked before reading, and at most ``max_bytes + 1`` bytes
    are ever read (a file that grows, ``/dev/zero``), so no input costs more
    than that much memory; a fifo is refused without blocking.

    Parameters
    ----------
    path : str or path-like
    what : str
        What the file should be (``"scene file"``), for the messages.
    max_bytes : int
        Largest accepted size.

    Returns
    -------
    str

    Raises
    ------
    UserPathError
        Missing, a directory, a device/fifo/socket, unreadable, larger than
        ``max_bytes`` or not UTF-8; the message names the file.
    """
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0)
    try:
        fd = os.open(path, flags)
    except FileNotFoundError:
        raise UserPathError(path, f"no such file (the {what})") from None
    except PermissionError:
        raise UserPathError(path, f"{what} is not readable (permission denied)") from None
    except (OSError, ValueError) as exc:
        raise UserPathError(path, f"cannot open the {what}: {_reason(exc)}") from None
    try:
        info = os.fstat(fd)
        if stat.S_ISDIR(info.st_mode):
            raise UserPathError(path, f"is a directory, not a {what}")
        if not stat.S_ISREG(info.st_mode):
            raise UserPathError(path, f"is not a regular file (a device, fifo or socket), not a {what}")
        if info.st_size > max_bytes:
            raise UserPathError(path, f"{what} is {info.st_size} bytes; at most {max_bytes} are read")
        chunks, size = [], 0
        while size <= max_bytes:
            chunk = os.read(fd, max_bytes + 1 - size)
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
        if size > max_bytes:
            raise UserPathError(path, f"{what} is larger than {max_bytes} bytes")
    except OSError as exc:
        if isinstance(exc, UserPathError):
            raise
        raise UserPathError(path, f"cannot read the {what}: {_reason(exc)}") from None
    finally:
        os.close(fd)
    data = b"".join(chunks)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        raise UserPathError(path, f"{what} is not UTF-8 text (byte {data[exc.start]:#04x} on line {line})") from None


def read_user_toml(path, what: str = "file", *, max_bytes: int = MAX_INPUT_BYTES) -> dict:
    """Read a TOML file named by the user (:func:`read_user_file`, then :mod:`tomllib`).

    A UTF-8 byte-order mark at the start (some editors write one) is dropped.
    Before parsing, the dots of keys are counted (at most :data:`MAX_TOML_DOTS`),
    and nesting too deep for the parser is refused, so no file within the size
    cap can exhaust memory or escape as a RecursionError.

    Raises
    ------
    UserPathError
        Everything :func:`read_user_file` refuses, and text that is not valid
        TOML (the message names the file and says ``not valid TOML``).
    """
    text = read_user_file(path, what, max_bytes=max_bytes).removeprefix(BYTE_ORDER_MARK)
    dots = len(_KEY_DOT.findall(_TOML_STRINGS.sub("", text)))
    if dots > MAX_TOML_DOTS:
        raise UserPathError(path, f"not valid TOML for a {what}: {dots} dots in keys and table names; "
                                  f"at most {MAX_TOML_DOTS} are accepted")
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise UserPathError(path, f"not valid TOML: {exc}") from None
    except (RecursionError, MemoryError):
        raise UserPathError(path, f"not valid TOML for a {what}: nested too deeply") from None


def _reason(exc: BaseException) -> str:
    return getattr(exc, "strerror", None) or str(exc)


def _check_path_text(path, what: str) -> Path:
    text = os.fspath(path)
    if not isinstance(text, str):
        text = os.fsdecode(text)
    if not text:
        raise UserPathError(path, f"empty path for the {what}")
    if "\0" in text:
        raise UserPathError(path, f"the {what} path holds a NUL character")
    return Path(text)


def _refuse_link(p: Path, path, what: str) -> None:
    """Refuse a symbolic link as the output itself (links in its parents are the user's choice)."""
    try:
        if stat.S_ISLNK(os.lstat(p).st_mode):
            raise UserPathError(path, f"the {what} is a symbolic link; symvib never writes through one "
                                      "(name its target instead)")
    except (OSError, ValueError) as exc:
        if isinstance(exc, UserPathError):
            raise


def check_output_file(path, what: str = "output file") -> Path:
    """Check, before any work, that a file can be written at ``path``.

    The path may not be an existing directory, device, fifo or symbolic link
    (symvib never writes through one: :mod:`symvib.safeio`), its folder must
    exist and be writable, an existing file must be writable.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    UserPathError
    """
    p = _check_path_text(path, what)
    _refuse_link(p, path, what)
    try:
        info = os.stat(p)
    except FileNotFoundError:
        info = None
    except NotADirectoryError:
        raise UserPathError(path, f"a parent of the {what} is a file, not a folder") from None
    except OSError as exc:
        raise UserPathError(path, f"cannot use it as the {what}: {_reason(exc)}") from None
    if info is not None:
        if stat.S_ISDIR(info.st_mode):
            raise UserPathError(path, f"is a directory; the {what} must be a file name")
        if not stat.S_ISREG(info.st_mode):
            raise UserPathError(path, f"is not a regular file (a device, fifo or socket); cannot be the {what}")
        if not os.access(p, os.W_OK):
            raise UserPathError(path, f"the {what} exists and is not writable")
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.exists():
        raise UserPathError(path, f"folder {_show(parent)} of the {what} does not exist")
    if not parent.is_dir():
        raise UserPathError(path, f"{_show(parent)} is not a folder")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise UserPathError(path, f"folder {_show(parent)} of the {what} is not writable")
    return p


def check_output_dir(path, what: str = "output folder") -> Path:
    """Check, before any work, that ``path`` is (or can be created as) a writable folder.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    UserPathError
        When the path (or a parent of it) is a file or a device, the path is a
        symbolic link, or the folder (or its nearest existing parent) is not writable.
    """
    p = _check_path_text(path, what)
    _refuse_link(p, path, what)
    probe = Path(os.path.abspath(p))
    while True:
        try:
            info = os.stat(probe)
            break
        except (FileNotFoundError, NotADirectoryError):
            if probe.parent == probe:
                raise UserPathError(path, f"no existing parent folder for the {what}") from None
            probe = probe.parent
        except OSError as exc:
            raise UserPathError(path, f"cannot use it as the {what}: {_reason(exc)}") from None
    if not stat.S_ISDIR(info.st_mode):
        kind = "a file" if stat.S_ISREG(info.st_mode) else "a device, fifo or socket"
        where = "is" if probe == Path(os.path.abspath(p)) else f"has {_show(probe)}, which is"
        raise UserPathError(path, f"{where} {kind}, not a folder (the {what})")
    if not os.access(probe, os.W_OK | os.X_OK):
        raise UserPathError(path, f"folder {_show(probe)} is not writable")
    return p
