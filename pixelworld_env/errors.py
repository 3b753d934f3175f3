"""The base of every error pixelworld_env raises for bad input: :class:`PixelWorldError`, a ``ValueError``.

Every error class of the package derives from it (the concept language's :class:`ConceptError` family, generation's
:class:`GenerationError`, the catalog's, the definitions'), and so do the checks of arguments that were bare
``ValueError``, ``KeyError`` and ``TypeError`` before: :class:`PixelWorldKeyError` and :class:`PixelWorldTypeError`
are also the builtin they replaced, so ``except KeyError`` / ``except TypeError`` still catch them. The ``pixelworld``
command prints a :class:`PixelWorldError` as a one-line message; anything else is a bug and surfaces as one.
"""

from __future__ import annotations

__all__ = ["PixelWorldError", "PixelWorldKeyError", "PixelWorldTypeError"]


class PixelWorldError(ValueError):
    """Bad input to pixelworld_env (a value, a name, a file): the message says what was given and what is expected."""


class PixelWorldKeyError(PixelWorldError, KeyError):
    """An unknown name, catchable as ``KeyError`` too (its message is not quoted, as a ``KeyError``'s would be)."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


class PixelWorldTypeError(PixelWorldError, TypeError):
    """A value of the wrong type, catchable as ``TypeError`` too."""
