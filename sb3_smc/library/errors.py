"""Errors of SMC libraries: every one is a :class:`LibraryError` (a ``ValueError``) naming the file and the SMC."""

from __future__ import annotations

import difflib
from collections.abc import Sequence

from sb3_smc.errors import SMCError, SMCKeyError

__all__ = ["CorruptModelError", "LayoutMismatchError", "LibraryConflictError", "LibraryError", "ManifestError",
           "MissingChildError", "UnknownSMCError", "UnreadableFileError", "UntrustedModelError", "suggest"]


class LibraryError(SMCError):
    """Any problem with an SMC library (base class of the errors below)."""


class ManifestError(LibraryError):
    """The manifest is missing, unreadable, of another format or version, or has wrong or missing fields."""


class UnknownSMCError(LibraryError, SMCKeyError):
    """No SMC of that name in the library (the message suggests close names)."""


class MissingChildError(LibraryError):
    """An SMC's child is not in the library."""


class LayoutMismatchError(LibraryError):
    """Action names or observation size disagree (manifest vs. model, or SMC vs. environment)."""


class CorruptModelError(LibraryError):
    """A model file is missing, truncated, corrupt, modified since it was saved, or not loadable."""


class UnreadableFileError(LibraryError):
    """A library's file is there but the system does not let it be read (permissions, an I/O error): not a damaged
    file, so a run never trains its SMC again or replaces it for that."""


class UntrustedModelError(LibraryError):
    """A model file that only loads by running code from it (a pickled archive of an old library), asked for without
    ``trust=True``."""


class LibraryConflictError(LibraryError):
    """Another writer changed the library since this one read it, in a way a save cannot merge (nothing is
    written)."""


def suggest(name: str, names: Sequence[str], empty: str = " (the library is empty)") -> str:
    """"; did you mean ..." with close names, else a few of ``names`` (``empty`` when there are none)."""
    close = difflib.get_close_matches(name, list(dict.fromkeys(names)), n=3, cutoff=0.5)
    if close:
        return f"; did you mean {' or '.join(repr(c) for c in close)}?"
    if not names:
        return empty
    shown = ", ".join(repr(n) for n in list(names)[:10])
    return f"; it has {len(names)}: {shown}{', ...' if len(names) > 10 else ''}"
