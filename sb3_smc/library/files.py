"""A library folder's files as the package touches them: the lock of its writers and readers, and reading a file
inside it without following a link out of it (:mod:`sb3_smc.library.storage` does the rest)."""

from __future__ import annotations

import contextlib
import os
import stat
import threading
from collections.abc import Iterator
from pathlib import Path

from sb3_smc.library.errors import LibraryError, UnreadableFileError

__all__ = ["LOCK", "locked", "read_inside"]

LOCK = ".lock"
"""The lock file inside a library folder (``fcntl.flock``: exclusive for writers, shared for readers)."""


_HELD: dict[str, tuple[int, bool, int]] = {}
"""The library locks this process holds, by lock file: its descriptor, whether exclusive, how many holders (the
holding thread's nested calls)."""
_THREADS: dict[str, threading.RLock] = {}
"""By lock file, the lock that lets one thread of this process at a time use the library (``flock`` is per process)."""
_GUARD = threading.Lock()


@contextlib.contextmanager
def locked(root: Path, *, exclusive: bool) -> Iterator[None]:
    """Hold the lock of the library in ``root``: exclusive for a writer (the folder is created), shared for a reader.

    Writers wait for each other and for readers, readers only for writers (``fcntl.flock`` on ``root/.lock``); within
    a process, one thread at a time. A reader of a library whose folder it cannot write (a read-only copy) reads
    without a lock. Re-entrant for the holding thread (an exclusive hold serves a nested shared one)."""
    try:
        import fcntl
    except ImportError:  # not POSIX: no locking
        yield
        return
    if exclusive:
        root.mkdir(parents=True, exist_ok=True)
    lock = root / LOCK
    key = str(lock.absolute())
    with _GUARD:
        thread_lock = _THREADS.setdefault(key, threading.RLock())
    with thread_lock:
        held = _HELD.get(key)
        if held is not None:  # a nested call of this thread
            if exclusive and not held[1]:
                raise LibraryError(f"{root}: this process reads the library and asks to write it meanwhile (a "
                                   "shared lock cannot become exclusive)")
            _HELD[key] = (held[0], held[1], held[2] + 1)
        else:
            try:
                fd = os.open(lock, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o666)
            except FileNotFoundError:
                if exclusive:
                    raise
                fd = -1  # no library folder: the read that follows says so
            except OSError as err:
                if exclusive:
                    raise LibraryError(f"cannot lock {root} for writing ({lock}: {err.strerror})") from None
                fd = -1
            if fd >= 0:
                fcntl.flock(fd, fcntl.LOCK_EX if exclusive else fcntl.LOCK_SH)
            _HELD[key] = (fd, exclusive, 1)
        try:
            yield
        finally:
            fd_, mode, count = _HELD[key]
            if count > 1:
                _HELD[key] = (fd_, mode, count - 1)
            else:
                del _HELD[key]
                if fd_ >= 0:
                    os.close(fd_)  # releases the flock


def read_inside(root: Path, relative: str, limit: int, what: str) -> bytes:
    """The bytes of the regular file ``root/relative``, at most ``limit`` of them; a symbolic link anywhere below
    ``root`` is refused (a library's files are its own). :class:`FileNotFoundError` where it is missing;
    :class:`LibraryError` for a link, something else than a file or a file too large;
    :class:`UnreadableFileError` for one the system does not let be read."""
    path = root
    for part in Path(relative).parts:
        path = path / part
        if path.is_symlink():
            raise LibraryError(f"{what} {path} is a symbolic link; a library's files must be its own (copy the file "
                               "into the folder)")
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_CLOEXEC)
    except FileNotFoundError:
        raise
    except OSError as err:
        raise UnreadableFileError(f"cannot read {what} {path}: {err.strerror}") from None
    info = os.fstat(fd)
    if not stat.S_ISREG(info.st_mode):
        os.close(fd)
        raise LibraryError(f"{what} {path} is not a regular file")
    with os.fdopen(fd, "rb") as handle:
        if info.st_size > limit:
            raise LibraryError(f"{what} {path} holds {info.st_size} bytes, more than {limit}")
        try:
            return handle.read(limit + 1)[:limit]
        except OSError as err:
            raise UnreadableFileError(f"cannot read {what} {path}: {err.strerror}") from None
