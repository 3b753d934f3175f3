"""The base of every error sb3_smc raises for bad input: :class:`SMCError`, a ``ValueError``.

Every error class of the package derives from it (records' :class:`~sb3_smc.records.RecordError`, the curricula's
:class:`~sb3_smc.curricula.format.CurriculumError`, the trainer's run-settings and run-file errors, the library's
:class:`~sb3_smc.library.errors.LibraryError` family, the zoo import's :class:`~sb3_smc.zoo.importing.ZooRunError`), and
so do the checks of options that were bare ``ValueError``, ``KeyError`` and ``TypeError`` before:
:class:`SMCKeyError`, :class:`SMCTypeError` and :class:`SMCRuntimeError` are also the builtin they replaced. The
``sb3-smc`` command prints an :class:`SMCError` (or a :class:`~pixelworld_env.errors.PixelWorldError`, sb3_smc builds
on pixelworld_env) as a one-line message; anything else is a bug and surfaces as one.
"""

from __future__ import annotations

__all__ = ["SMCError", "SMCKeyError", "SMCRuntimeError", "SMCTypeError"]


class SMCError(ValueError):
    """Bad input to sb3_smc (an option, a name, a file, a run directory): the message says what is wrong."""


class SMCKeyError(SMCError, KeyError):
    """An unknown name, catchable as ``KeyError`` too (its message is not quoted, as a ``KeyError``'s would be)."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


class SMCTypeError(SMCError, TypeError):
    """A value of the wrong type, catchable as ``TypeError`` too."""


class SMCRuntimeError(SMCError, RuntimeError):
    """A run that cannot go on as asked (failed jobs, a missing optional dependency), catchable as ``RuntimeError``
    too."""
