"""Crash-safe writes, shared by the dataset cache and ``sb3_smc``'s SMC libraries and run directories.

* :func:`atomic_write` writes a file through a temporary file in the same folder, ``fsync`` and ``os.replace``:
  readers see the old content or the new one, never a mixture, whatever happens to the writing process.
* :func:`replace_directory` swaps a completely written directory into place with two renames (the old one is
  renamed aside first and deleted last), for things that are several files (an SMC library).
"""

from __future__ import annotations

import os
import shutil
import tempfile
import uuid
from collections.abc import Callable
from pathlib import Path
from typing import BinaryIO

__all__ = ["OLD_MARKER", "atomic_write", "fsync_dir", "fsync_file", "make_temporary_directory", "path_inside",
           "replace_directory"]

OLD_MARKER = ".old-"
"""A directory being replaced is renamed to ``.<name>.old-<random>`` beside it until the new one is in place."""


def _read_umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


_UMASK = _read_umask()
"""The process's umask, read once at import (reading it sets it for a moment, which other threads would see)."""


def _umask() -> int:
    return _UMASK


def make_temporary_directory(parent: str | os.PathLike, prefix: str) -> Path:
    """A new directory in ``parent`` with the permissions of the user's umask (``mkdtemp`` would make it 0700)."""
    path = Path(tempfile.mkdtemp(prefix=prefix, dir=parent))
    os.chmod(path, 0o777 & ~_umask())
    return path


def fsync_dir(directory: str | os.PathLike) -> None:
    """Flush a directory's entries (renames, new files) to disk; a no-op where directories cannot be opened."""
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:  # pragma: no cover - platforms without directory descriptors
        return
    try:
        os.fsync(fd)
    except OSError:  # pragma: no cover
        pass
    finally:
        os.close(fd)


def fsync_file(path: str | os.PathLike) -> None:
    """Flush a written file's content to disk."""
    with open(path, "rb") as handle:
        os.fsync(handle.fileno())


def atomic_write(path: str | os.PathLike, data: bytes | str | Callable[[BinaryIO], None]) -> Path:
    """Write ``data`` (bytes, text as UTF-8, or a function writing to a binary handle) to ``path`` atomically.

    The content goes to ``.<name>.<random>.tmp`` in the same folder (created if missing), with the permissions
    of the user's umask, is flushed with ``fsync`` and renamed over ``path``; any error (Ctrl-C included) deletes
    the temporary file and leaves an existing ``path`` untouched. Returns ``path``.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as handle:
            os.fchmod(handle.fileno(), 0o666 & ~_umask())  # mkstemp makes 0600; others may read the folder
            if callable(data):
                data(handle)
            else:
                handle.write(data.encode("utf-8") if isinstance(data, str) else data)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    fsync_dir(path.parent)
    return path


def replace_directory(new: str | os.PathLike, target: str | os.PathLike) -> None:
    """Move the complete directory ``new`` to ``target``, replacing an existing ``target`` atomically enough.

    An existing ``target`` is renamed to ``.<name>.old-<random>`` first, ``new`` renamed to ``target``, then the
    old copy deleted. If the second rename fails, the old directory is put back. Only a crash of the process
    between the two renames leaves no ``target``; both complete copies are then still on disk.
    """
    new, target = Path(new), Path(target)
    old = None
    if target.exists():
        old = target.parent / f".{target.name}{OLD_MARKER}{uuid.uuid4().hex[:12]}"
        os.rename(target, old)
    try:
        os.rename(new, target)
    except BaseException:
        if old is not None:
            os.rename(old, target)
        raise
    fsync_dir(target.parent)
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)


def path_inside(root: str | os.PathLike, *parts: str) -> Path:
    """``root / parts...``, resolved, after proving that it lies inside ``root`` (resolved too) and that no part of it
    below ``root`` is a symbolic link: a name such as ``../x``, an absolute path or a link planted in the folder
    cannot make a write or a removal reach outside it (``PixelWorldError`` naming both paths otherwise)."""
    from pixelworld_env.errors import PixelWorldError

    base = Path(root).resolve()
    path = base
    for part in parts:
        for piece in Path(part).parts:
            if piece in ("", ".", "..") or Path(piece).is_absolute() or "\x00" in piece:
                raise PixelWorldError(f"{part!r} is not a name inside {base} (it holds {piece!r})")
            path = path / piece
            if path.is_symlink():
                raise PixelWorldError(f"{path} is a symbolic link; refusing to follow it out of {base}")
    if not path.resolve().is_relative_to(base):
        raise PixelWorldError(f"{path} lies outside {base}")
    return path

