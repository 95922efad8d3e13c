"""Safe writes: every file symvib writes or deletes, without following a symbolic link.

symvib writes into a *root* folder: the folder the user named (``-o``,
``--plot``, ``--out``, the folder of ``--json FILE``) or a cache folder.  The
root's own last component is checked (:func:`check_root`: a real folder, not a
symbolic link, owned by the user; a cache also not writable by group or
others), then opened once; everything below it is reached component by
component with ``O_NOFOLLOW`` relative to that open folder (``dir_fd``), so a
link planted anywhere below the root (``out/maps`` pointing elsewhere, a link at
a temporary name) is refused, never followed.

A file is written whole or not at all (:func:`replacing`): into a new
temporary file created with ``O_CREAT | O_EXCL | O_NOFOLLOW`` under a random
name, then renamed (``os.replace``) onto its final name, which is checked
first (a folder or a symbolic link there is refused).  Deletion
(:func:`remove_file`, :func:`remove_tree`) removes regular files and folders
only, never through a link, and a tree only after every entry passed the
caller's test of what it wrote.

Every refusal is a one-line :class:`symvib.paths.UserPathError` naming the path.
This module imports neither SymPy nor NumPy; it needs the POSIX ``dir_fd``
calls (Linux, macOS).

Examples
--------
>>> import tempfile
>>> root = tempfile.mkdtemp()
>>> write_text(root, "maps/notes.txt", "hello\\n").name
'notes.txt'
>>> read_bytes(root, "maps/notes.txt")
b'hello\\n'
>>> remove_file(root, "maps/notes.txt")
True
"""
from __future__ import annotations

import contextlib
import errno
import os
import secrets
import stat
from pathlib import Path

from symvib.paths import UserPathError

__all__ = ["FOLDER_MODE", "FILE_MODE", "PRIVATE_FOLDER_MODE", "PRIVATE_FILE_MODE", "TEMP_SUFFIX", "MAX_READ_BYTES",
           "check_root", "trust_problem", "make_folders", "replacing", "replacing_file", "write_file", "write_bytes",
           "write_text",
           "reading", "read_bytes", "remove_file", "remove_tree", "entries", "is_temporary"]

#: Mode of the folders symvib creates for output (the umask applies).
FOLDER_MODE = 0o777
#: Mode of the files symvib writes for output (the umask applies).
FILE_MODE = 0o666
#: Mode of cache folders: the user's alone (as ssh and pip keep theirs).
PRIVATE_FOLDER_MODE = 0o700
#: Mode of cache files.
PRIVATE_FILE_MODE = 0o600
#: Permission bits that let someone other than the owner change a folder or file.
SHARED_WRITE = stat.S_IWGRP | stat.S_IWOTH
#: Ending of symvib's temporary files (``.NAME.<random>.symvib-tmp``): never a name symvib writes for good.
TEMP_SUFFIX = ".symvib-tmp"
#: Random bytes in a temporary file's name (hex: twice as many digits).
TEMP_TOKEN_BYTES = 8
#: Largest file :func:`read_bytes` reads unless told otherwise (16 MiB).
MAX_READ_BYTES = 16 * 2**20

_NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)
_DIRECTORY = getattr(os, "O_DIRECTORY", 0)
_CLOEXEC = getattr(os, "O_CLOEXEC", 0)
_FOLDER_FLAGS = os.O_RDONLY | _DIRECTORY | _NOFOLLOW | _CLOEXEC
_NEW_FILE_FLAGS = os.O_WRONLY | os.O_CREAT | os.O_EXCL | _NOFOLLOW | _CLOEXEC


def _reason(exc: OSError) -> str:
    return exc.strerror or str(exc)


def trust_problem(info: os.stat_result, *, private: bool) -> str | None:
    """Why a folder or file with status ``info`` is not the user's alone (``None`` if it is).

    Parameters
    ----------
    info : os.stat_result
        Its status (``os.stat``, ``os.lstat`` or ``os.fstat``).
    private : bool
        Also refuse write permission for group or others (caches: what others
        can write, others can run).

    Returns
    -------
    str or None
        A reason such as ``"owned by another user (uid 1001)"``.
    """
    if info.st_uid != os.geteuid():
        return f"owned by another user (uid {info.st_uid})"
    if private and info.st_mode & SHARED_WRITE:
        return f"writable by group or others (mode {stat.S_IMODE(info.st_mode):04o})"
    return None


def check_root(path, what: str = "output folder", *, create: bool = True, private: bool = False) -> Path:
    """Create (with missing parents) and check a root folder symvib writes into.

    The last component must be a real folder (not a symbolic link) owned by the
    user; with ``private`` it is created ``0700`` and may not be writable by
    group or others.  Parents are the user's choice and are followed.

    Parameters
    ----------
    path : str or path-like
    what : str
        What the folder is, for the messages (``"--plot folder"``).
    create : bool
        Create it when missing.
    private : bool
        A cache folder (see above).

    Returns
    -------
    pathlib.Path

    Raises
    ------
    UserPathError
        Naming the folder and what is wrong with it.
    """
    root = Path(os.fspath(path))
    if not str(root) or "\0" in str(root):
        raise UserPathError(path, f"not a usable name for the {what}")
    mode = PRIVATE_FOLDER_MODE if private else FOLDER_MODE
    try:
        info = os.lstat(root)
    except FileNotFoundError:
        if not create:
            raise UserPathError(path, f"the {what} does not exist") from None
        try:
            if str(root.parent) not in ("", "."):
                os.makedirs(root.parent, mode=mode, exist_ok=True)
            os.mkdir(root, mode)
        except FileExistsError:
            pass   # made meanwhile (another process): checked below like any folder
        except NotADirectoryError:
            raise UserPathError(path, f"a parent of the {what} is a file, not a folder") from None
        except OSError as exc:
            raise UserPathError(path, f"cannot create the folder for the {what}: {_reason(exc)}") from None
        info = os.lstat(root)
    except NotADirectoryError:
        raise UserPathError(path, f"a parent of the {what} is a file, not a folder") from None
    except OSError as exc:
        raise UserPathError(path, f"cannot use it as the {what}: {_reason(exc)}") from None
    if stat.S_ISLNK(info.st_mode):
        raise UserPathError(path, f"the {what} is a symbolic link; symvib writes only into a real folder "
                                  "(name the folder it points to)")
    if not stat.S_ISDIR(info.st_mode):
        kind = "a file" if stat.S_ISREG(info.st_mode) else "a device, fifo or socket"
        raise UserPathError(path, f"the {what} is {kind}, not a folder")
    problem = trust_problem(info, private=private)
    if problem:
        raise UserPathError(path, f"the {what} is {problem}; symvib writes only into folders that are yours"
                                  + (" alone (chmod 700)" if private else ""))
    return root


def _parts(relpath) -> list:
    """The components of a path relative to a root: no empty, ``.``, ``..`` or absolute part."""
    text = os.fspath(relpath)
    parts = [p for p in text.split("/") if p not in ("", ".")]
    if text.startswith("/") or ".." in parts or any("\0" in p for p in parts):
        raise UserPathError(text, "not a plain path inside its folder")
    return parts


@contextlib.contextmanager
def _opened(root, parts, *, what: str, private: bool, create: bool, mode: int, owner: bool = True,
            named_file: bool = False):
    """The open folder ``root/parts...`` (a file descriptor), each component opened without following a link.

    Each folder must be the user's (``owner``: where symvib writes or deletes), and with
    ``private`` not writable by group or others; reading someone else's folder needs neither.
    ``named_file``: ``root`` is the folder of a file the user named (``--json /tmp/run.json``):
    it is opened as the user wrote it (a link in it is the user's choice) and may be anyone's.
    """
    shown = Path(os.fspath(root))
    try:
        fd = os.open(root, _FOLDER_FLAGS & ~_NOFOLLOW if named_file else _FOLDER_FLAGS)
    except OSError as exc:
        raise _refusal(shown, exc, what) from None
    try:
        problem = trust_problem(os.fstat(fd), private=private) if (owner or private) and not named_file else None
        if problem:
            raise UserPathError(shown, f"the {what} is {problem}")
        for part in parts:
            shown = shown / part
            if create:
                with contextlib.suppress(FileExistsError):
                    os.mkdir(part, mode, dir_fd=fd)
            try:
                sub = os.open(part, _FOLDER_FLAGS, dir_fd=fd)
            except OSError as exc:
                raise _refusal(shown, exc, "folder") from None
            os.close(fd)
            fd = sub
            problem = trust_problem(os.fstat(fd), private=private) if owner or private else None
            if problem:
                raise UserPathError(shown, f"folder is {problem}")
        yield fd
    finally:
        os.close(fd)


def _refusal(path: Path, exc: OSError, what: str) -> UserPathError:
    """A one-line refusal for a failed ``open`` of ``path`` (a link, a file, missing, ...)."""
    if exc.errno in (errno.ELOOP, errno.EMLINK) or (exc.errno == errno.ENOTDIR and os.path.islink(path)):
        return UserPathError(path, f"is a symbolic link; symvib never writes through one (the {what})")
    if exc.errno == errno.ENOTDIR:
        return UserPathError(path, f"is not a folder (the {what})")
    if exc.errno == errno.ENOENT:
        return UserPathError(path, f"the {what} does not exist")
    return UserPathError(path, f"cannot use the {what}: {_reason(exc)}")


def make_folders(root, relpath, *, what: str = "output folder", private: bool = False) -> Path:
    """Create the folders ``relpath`` below ``root`` (each checked: real, the user's); returns the path."""
    parts = _parts(relpath)
    mode = PRIVATE_FOLDER_MODE if private else FOLDER_MODE
    with _opened(root, parts, what=what, private=private, create=True, mode=mode):
        pass
    return Path(os.fspath(root), *parts)


def _check_target(fd: int, name: str, path: Path) -> None:
    """Refuse a folder, a symbolic link or a device at the final name ``name`` (in the open folder ``fd``)."""
    try:
        info = os.stat(name, dir_fd=fd, follow_symlinks=False)
    except FileNotFoundError:
        return
    if stat.S_ISLNK(info.st_mode):
        raise UserPathError(path, "is a symbolic link; symvib never writes through one (remove it, or name "
                                  "another file)")
    if not stat.S_ISREG(info.st_mode):
        raise UserPathError(path, "exists and is not a regular file (a folder, device or fifo)")


@contextlib.contextmanager
def replacing(root, relpath, *, what: str = "output folder", private: bool = False, named_file: bool = False):
    """A binary file that becomes ``root/relpath`` when the block ends without an error.

    Written to a temporary file created exclusively (``O_EXCL | O_NOFOLLOW``, a
    random name beside the target), then renamed onto the target, whose name
    was checked (no folder, link or device there).  On an error the temporary
    file is removed and the target is untouched.

    Parameters
    ----------
    root : str or path-like
        The root folder (checked by the caller with :func:`check_root`; its own
        owner is checked again here).
    relpath : str
        The file, relative to ``root``; missing folders on the way are created.
    what : str
        What ``root`` is, for the messages.
    private : bool
        A cache: folders ``0700``, the file ``0600``, nothing shared-writable accepted.
    named_file : bool
        ``root`` is the folder of a file the user named (:func:`replacing_file`).

    Yields
    ------
    file
        Open for binary writing; its ``temporary`` is the temporary file's path
        (for a program that writes by name, such as ffmpeg).

    Raises
    ------
    UserPathError
        A link, file or foreign folder on the way, or a failed write (naming the file).
    """
    parts = _parts(relpath)
    if not parts:
        raise UserPathError(relpath, "names no file")
    *folders, name = parts
    target = Path(os.fspath(root), *parts)
    folder_mode, file_mode = (PRIVATE_FOLDER_MODE, PRIVATE_FILE_MODE) if private else (FOLDER_MODE, FILE_MODE)
    with _opened(root, folders, what=what, private=private, create=True, mode=folder_mode,
                 named_file=named_file) as fd:
        _check_target(fd, name, target)
        tmp = f".{name[:100]}.{secrets.token_hex(TEMP_TOKEN_BYTES)}{TEMP_SUFFIX}"
        try:
            handle = os.open(tmp, _NEW_FILE_FLAGS, file_mode, dir_fd=fd)
        except OSError as exc:
            raise UserPathError(target, f"cannot write it: {_reason(exc)}") from None
        done = False
        try:
            with os.fdopen(handle, "wb") as fh:
                fh.temporary = target.with_name(tmp)   # for a writer that needs a path (ffmpeg): created here
                yield fh
            _check_target(fd, name, target)
            os.replace(tmp, name, src_dir_fd=fd, dst_dir_fd=fd)
            done = True
        except OSError as exc:
            if isinstance(exc, UserPathError):
                raise
            raise UserPathError(target, f"cannot write it: {_reason(exc)}") from None
        finally:
            if not done:
                with contextlib.suppress(OSError):
                    os.unlink(tmp, dir_fd=fd)


@contextlib.contextmanager
def replacing_file(path, *, what: str = "output file"):
    """:func:`replacing` for one file the user named (``--json PATH``): written in its folder, which
    must exist, under a temporary name, then renamed onto ``path`` (never through a link there)."""
    target = Path(os.fspath(path))
    if not target.name or target.name in (".", ".."):
        raise UserPathError(path, f"names no file (the {what})")
    folder = target.parent if str(target.parent) else Path(".")
    with replacing(folder, target.name, what=f"folder of the {what}", named_file=True) as fh:
        yield fh


def write_file(path, data, *, what: str = "output folder") -> Path:
    """Write ``data`` (bytes or text) to ``path`` whole: its folder is created if missing and checked
    (:func:`check_root`), the file written by :func:`replacing`; returns the path."""
    target = Path(os.fspath(path))
    root = check_root(target.parent if str(target.parent) else Path("."), what)
    return write_bytes(root, target.name, data.encode("utf-8") if isinstance(data, str) else data, what=what)


def write_bytes(root, relpath, data: bytes, *, what: str = "output folder", private: bool = False) -> Path:
    """Write ``data`` to ``root/relpath`` whole or not at all (:func:`replacing`); returns the path."""
    with replacing(root, relpath, what=what, private=private) as fh:
        fh.write(data)
    return Path(os.fspath(root), *_parts(relpath))


def write_text(root, relpath, text: str, *, what: str = "output folder", private: bool = False) -> Path:
    """Write UTF-8 ``text`` to ``root/relpath`` whole or not at all; returns the path."""
    return write_bytes(root, relpath, text.encode("utf-8"), what=what, private=private)


@contextlib.contextmanager
def reading(root, relpath, *, what: str = "folder", private: bool = False):
    """The regular file ``root/relpath`` open for binary reading, reached without following a link.

    With ``private`` the file and every folder below ``root`` must be the user's
    and not writable by group or others (what a cache must be before its
    content is trusted).

    Raises
    ------
    FileNotFoundError
        When the file does not exist.
    UserPathError
        A link, a non-regular file (fifo, device) or a file not the user's.
    """
    *folders, name = _parts(relpath)
    target = Path(os.fspath(root), *folders, name)
    with _opened(root, folders, what=what, private=private, create=False, mode=FOLDER_MODE, owner=False) as fd:
        try:
            handle = os.open(name, os.O_RDONLY | _NOFOLLOW | _CLOEXEC | getattr(os, "O_NONBLOCK", 0), dir_fd=fd)
        except FileNotFoundError:
            raise
        except OSError as exc:
            raise _refusal(target, exc, "file") from None
    try:
        info = os.fstat(handle)
        problem = "is not a regular file" if not stat.S_ISREG(info.st_mode) else None
        if problem is None and private and trust_problem(info, private=True):
            problem = f"is {trust_problem(info, private=True)}; not read"
    except OSError as exc:
        problem = f"cannot be read: {_reason(exc)}"
    if problem:
        os.close(handle)
        raise UserPathError(target, problem)
    with os.fdopen(handle, "rb") as fh:
        yield fh


def read_bytes(root, relpath, *, max_bytes: int = MAX_READ_BYTES, what: str = "folder",
               private: bool = False) -> bytes:
    """Read the regular file ``root/relpath`` (:func:`reading`), at most ``max_bytes``.

    Raises
    ------
    FileNotFoundError
        When the file does not exist.
    UserPathError
        What :func:`reading` refuses, and a file larger than ``max_bytes``.
    """
    target = Path(os.fspath(root), *_parts(relpath))
    with reading(root, relpath, what=what, private=private) as fh:
        size = os.fstat(fh.fileno()).st_size
        if size > max_bytes:
            raise UserPathError(target, f"is {size} bytes; at most {max_bytes} are read")
        data = fh.read(max_bytes + 1)
    if len(data) > max_bytes:
        raise UserPathError(target, f"is larger than {max_bytes} bytes")
    return data


def entries(root, relpath="") -> dict:
    """The entries of the folder ``root/relpath``: name -> ``"file"``, ``"folder"``, ``"link"`` or ``"other"``
    (``{}`` when it does not exist; a link on the way is refused)."""
    parts = _parts(relpath)
    try:
        with _opened(root, parts, what="folder", private=False, create=False, mode=FOLDER_MODE, owner=False) as fd:
            out = {}
            with os.scandir(fd) as it:
                for entry in it:
                    out[entry.name] = ("link" if entry.is_symlink() else "folder" if entry.is_dir(follow_symlinks=False)
                                       else "file" if entry.is_file(follow_symlinks=False) else "other")
            return out
    except UserPathError as exc:
        if "does not exist" in exc.reason:
            return {}
        raise


def is_temporary(name: str) -> bool:
    """Whether ``name`` is one of symvib's temporary files (:func:`replacing`)."""
    return name.startswith(".") and name.endswith(TEMP_SUFFIX)


def remove_file(root, relpath, *, links: bool = False) -> bool:
    """Remove the regular file ``root/relpath`` (never a folder, never through a link).

    Parameters
    ----------
    root, relpath
        The file.
    links : bool
        Also remove a symbolic link at that name (the link itself, never what it
        points to): for a name symvib is about to write in a folder of its own.

    Returns
    -------
    bool
        Whether a file was removed (``False``: there was none).

    Raises
    ------
    UserPathError
        When a link or something other than a regular file is there.
    """
    *folders, name = _parts(relpath)
    target = Path(os.fspath(root), *folders, name)
    try:
        with _opened(root, folders, what="folder", private=False, create=False, mode=FOLDER_MODE) as fd:
            try:
                info = os.stat(name, dir_fd=fd, follow_symlinks=False)
            except FileNotFoundError:
                return False
            if not (stat.S_ISREG(info.st_mode) or links and stat.S_ISLNK(info.st_mode)):
                raise UserPathError(target, "is not a regular file symvib wrote; not removed")
            os.unlink(name, dir_fd=fd)
            return True
    except UserPathError as exc:
        if "does not exist" in exc.reason:
            return False
        raise


def remove_tree(root, relpath, owned) -> None:
    """Remove the folder ``root/relpath`` and all in it, if ``owned`` accepts every entry; else remove nothing.

    Parameters
    ----------
    root, relpath
        The folder to remove.
    owned : callable
        ``owned(parts, kind) -> bool`` for every entry below it (``parts``: its
        path components below the folder; ``kind``: ``"file"`` or ``"folder"``).
        Links and other kinds are never accepted.

    Raises
    ------
    UserPathError
        Naming the first entry not accepted (nothing was removed then).
    """
    parts = _parts(relpath)
    if not parts:
        raise UserPathError(relpath, "names no folder")
    *folders, name = parts
    target = Path(os.fspath(root), *parts)
    with _opened(root, folders, what="folder", private=False, create=False, mode=FOLDER_MODE) as fd:
        try:
            info = os.stat(name, dir_fd=fd, follow_symlinks=False)
        except FileNotFoundError:
            return
        if not stat.S_ISDIR(info.st_mode):
            raise UserPathError(target, "is not a folder symvib wrote; not removed")
        plan = []
        _scan(fd, name, (), owned, target, plan)
        for kind, names in plan:   # children before their folder
            *inner, last = names
            with _opened(root, [*folders, name, *inner], what="folder", private=False, create=False,
                         mode=FOLDER_MODE) as sub:
                (os.rmdir if kind == "folder" else os.unlink)(last, dir_fd=sub)
        os.rmdir(name, dir_fd=fd)


def _scan(fd: int, name: str, prefix: tuple, owned, shown: Path, plan: list) -> None:
    """Check every entry below ``name`` (open folder ``fd``) with ``owned``; append them to ``plan``, children first."""
    try:
        sub = os.open(name, _FOLDER_FLAGS, dir_fd=fd)
    except OSError as exc:
        raise _refusal(shown, exc, "folder") from None
    try:
        with os.scandir(sub) as it:
            listing = [(e.name, "link" if e.is_symlink() else "folder" if e.is_dir(follow_symlinks=False)
                        else "file" if e.is_file(follow_symlinks=False) else "other") for e in it]
        for entry, kind in sorted(listing):
            parts = (*prefix, entry)
            if kind not in ("file", "folder") or not owned(parts, kind):
                raise UserPathError(shown / entry, "was not written by symvib (or cannot be proven to be); "
                                                   "nothing removed")
            if kind == "folder":
                _scan(sub, entry, parts, owned, shown / entry, plan)
            plan.append((kind, parts))
    finally:
        os.close(sub)
