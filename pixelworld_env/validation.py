"""Checks of user input shared by the environment, the dataset loaders and the agents: one rule per kind of value,
with messages that say what was given and what is expected."""

from __future__ import annotations

from collections.abc import Collection, Mapping, Sequence
from typing import Any

import numpy as np

from pixelworld_env.errors import PixelWorldError, PixelWorldTypeError

__all__ = ["MAX_SEED", "as_integer", "check_action", "check_bool", "check_count", "check_int", "check_options",
           "check_seed", "no_episode"]

MAX_SEED = 2**63 - 1
"""Seeds are integers in ``[0, 2**63 - 1]`` (they are stored in JSON records and numpy ``int64`` arrays)."""


def as_integer(value: Any) -> int | None:
    """``value`` as an int when it is an integer (Python or numpy, or a 0-d integer array), else ``None``."""
    if isinstance(value, bool | np.bool_):
        return None
    if isinstance(value, int | np.integer):
        return int(value)
    if isinstance(value, np.ndarray) and value.shape == () and value.dtype.kind in "iu":
        return int(value)
    return None


def check_int(value: Any, name: str, minimum: int | None = None) -> int:
    """``value`` as an int; ``TypeError`` if it is not an integer (bools and floats included), ``ValueError`` below
    ``minimum``."""
    number = as_integer(value)
    if number is None:
        raise PixelWorldTypeError(f"{name} must be an integer, got {value!r} ({type(value).__name__})")
    if minimum is not None and number < minimum:
        raise PixelWorldError(f"{name} must be >= {minimum}, got {number}")
    return number


def check_count(value: Any, name: str, maximum: int, limit: str) -> int:
    """A count of things to build or do: an integer (bools and floats refused) in ``[1, maximum]``, checked before any
    work starts; ``limit`` names the stated bound in the message (as ``pixelworld_env.envs.vector.MAX_VECTOR_ENVS``)."""
    number = check_int(value, name, 1)
    if number > maximum:
        raise PixelWorldError(f"{name} must be at most {maximum:,} (the limit {limit}), got {number:,}")
    return number


def check_bool(value: Any, name: str) -> bool:
    """``value`` when it is ``True`` or ``False`` (numpy bools too); anything else (``1``, ``"yes"``, ``None``) is a
    ``TypeError`` naming ``name``."""
    if not isinstance(value, bool | np.bool_):
        raise PixelWorldTypeError(f"{name} must be a bool (True or False), got {value!r} ({type(value).__name__})")
    return bool(value)


def check_seed(seed: Any, name: str = "seed") -> int:
    """A seed: an integer (numpy integers too) in ``[0, 2**63 - 1]``; anything else raises, nothing is converted."""
    number = check_int(seed, name)
    if not 0 <= number <= MAX_SEED:
        raise PixelWorldError(f"{name} must be in [0, 2**63 - 1], got {number}")
    return number


def check_action(action: Any, action_names: Sequence[str]) -> int:
    """An action index: an integer (numpy integers and 0-d integer arrays too) in ``[0, len(action_names))``.

    Negative indices, bools, floats and anything else raise ``ValueError`` listing the actions.
    """
    index = as_integer(action)
    if index is None or not 0 <= index < len(action_names):
        raise PixelWorldError(f"invalid action {action!r}: expected an integer in [0, {len(action_names)}); the "
                              f"actions are {list(enumerate(action_names))}")
    return index


def no_episode(started: bool, method: str) -> RuntimeError:
    """The error of ``method`` called outside an episode: before the first ``reset`` (``started`` false) or after
    the episode ended."""
    return RuntimeError(f"the episode has ended: call reset() before {method}()" if started
                        else f"no episode has started: call reset() before {method}()")


def check_options(options: Any, known: Collection[str], takes: str) -> dict[str, Any]:
    """``reset``'s ``options`` as a new dict (``{}`` for ``None``): a dict (any mapping) of the names in ``known``.

    Another type is a ``TypeError``, another name a ``ValueError``; both messages end with ``takes`` (what the reset
    takes).
    """
    if options is None:
        return {}
    if not isinstance(options, Mapping):
        raise PixelWorldTypeError(f"reset options must be a dict, got {options!r} ({type(options).__name__}); "
                                  f"{takes}")
    unknown = [key for key in options if key not in known]
    if unknown:
        raise PixelWorldError(f"unknown reset option(s) {unknown}; {takes}")
    return dict(options)
