"""The one writer of a sweep folder: a lock file created exclusively, checked before each chunk.

Examples
--------
>>> import tempfile
>>> folder = tempfile.mkdtemp()
>>> lock = WriterLock(folder).acquire()
>>> WriterLock(folder).acquire()
Traceback (most recent call last):
...
symvib.numeric.sweep.limits.SweepError: out: another sweep writes ...
>>> lock.verify(); lock.release()
"""
from __future__ import annotations

import json
import os
import secrets
import socket
import time
from pathlib import Path

from symvib import safeio
from symvib.numeric.sweep.limits import SweepError
from symvib.paths import UserPathError

__all__ = ["WriterLock", "LOCK_GRACE"]

#: Seconds a lock file may stay empty (its writer between creating and filling it) before it counts as stale.
LOCK_GRACE = 10.0
#: Most bytes of a lock file read (a lock holds a short JSON object).
MAX_LOCK_BYTES = 4096
#: Mode of the lock file (the umask applies).
LOCK_MODE = 0o644


class WriterLock:
    """The one writer of a sweep folder: ``FOLDER/sweep.lock``, created with ``O_CREAT | O_EXCL``.

    The lock file holds the writer's pid, host and a random nonce (JSON).  A
    lock whose pid is dead on this host (a killed sweep) is taken over; any
    other lock stops the second writer with a one-line :class:`SweepError`.
    The writer checks (:meth:`verify`) before each chunk it writes that the
    lock still holds its nonce, so even a lock taken over wrongly (a pid reused
    on another host sharing the folder) stops one writer instead of mixing two.
    """

    NAME = "sweep.lock"

    def __init__(self, folder):
        self.folder = Path(folder)
        self.path = self.folder / self.NAME
        self.nonce = secrets.token_hex(16)
        self.held = False

    def _text(self) -> str:
        return json.dumps({"pid": os.getpid(), "host": socket.gethostname(), "nonce": self.nonce,
                           "since": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())})

    def _holder(self):
        """The lock file's content as (raw bytes, parsed dict or None); ``None`` if there is no lock."""
        try:
            raw = safeio.read_bytes(self.folder, self.NAME, max_bytes=MAX_LOCK_BYTES)   # never through a link
        except FileNotFoundError:
            return None
        except OSError as exc:
            if isinstance(exc, UserPathError) and "does not exist" in exc.reason:
                return None
            raise SweepError(str(self.path), f"cannot read the lock: {exc.strerror or exc}") from None
        try:
            data = json.loads(raw.decode("utf-8"))
        except (UnicodeDecodeError, ValueError):
            data = None
        return raw, data if isinstance(data, dict) else None

    def _stale(self, data) -> bool:
        if data is None:   # empty or garbled: its writer died between creating and filling it, or is filling it
            try:
                return time.time() - os.lstat(self.path).st_mtime > LOCK_GRACE
            except FileNotFoundError:
                return True
        pid, host = data.get("pid"), data.get("host")
        if host != socket.gethostname() or isinstance(pid, bool) or not isinstance(pid, int) or pid <= 0:
            return False
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return True
        except (PermissionError, OverflowError):
            return False
        return False

    def acquire(self) -> WriterLock:
        """Take the lock, or raise :class:`SweepError` naming the folder and the holder."""
        for _ in range(3):
            try:
                fd = os.open(self.path, os.O_CREAT | os.O_EXCL | os.O_WRONLY | getattr(os, "O_NOFOLLOW", 0),
                             LOCK_MODE)
            except FileExistsError:
                holder = self._holder()
                if holder is None:
                    continue   # released meanwhile
                raw, data = holder
                if not self._stale(data):
                    who = (f"pid {data.get('pid')} on {data.get('host')}, since {data.get('since')}"
                           if data else "lock file being written")
                    raise SweepError("out", f"another sweep writes {self.folder} ({who}); wait for it, or delete "
                                            f"{self.path} if that sweep is dead") from None
                self._take_over(raw)
                continue
            except OSError as exc:
                raise SweepError(str(self.path), f"cannot create the lock: {exc.strerror or exc}") from None
            try:
                os.write(fd, self._text().encode("utf-8"))
            finally:
                os.close(fd)
            self.held = True
            return self
        raise SweepError("out", f"could not take the lock {self.path}: other writers keep taking it")

    def _take_over(self, raw: bytes) -> None:
        """Remove a stale lock whose content is ``raw`` (and only that one)."""
        aside = self.path.with_name(f"{self.NAME}.stale-{self.nonce}")
        try:
            os.rename(self.path, aside)
        except FileNotFoundError:
            return
        try:
            if safeio.read_bytes(self.folder, aside.name, max_bytes=MAX_LOCK_BYTES) != raw:
                # another writer replaced the stale lock meanwhile: put it back
                try:
                    os.link(aside, self.path)
                except FileExistsError:
                    pass
        finally:
            aside.unlink(missing_ok=True)

    def verify(self) -> None:
        """Raise :class:`SweepError` unless the lock file still holds this writer's nonce."""
        holder = self._holder()
        if holder is None or holder[1] is None or holder[1].get("nonce") != self.nonce:
            raise SweepError("out", f"lost the lock {self.path}: another sweep took over {self.folder}; "
                                    f"this one stops")

    def release(self) -> None:
        """Remove the lock file if it is still this writer's."""
        if not self.held:
            return
        self.held = False
        holder = self._holder()
        if holder is not None and holder[1] is not None and holder[1].get("nonce") == self.nonce:
            self.path.unlink(missing_ok=True)


