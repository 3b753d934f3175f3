"""Deprecated: the path of :mod:`pixelworld_env.core.kernels` before 2026-11-25, kept for one release."""

from pixelworld_env._moved import warn_moved as _warn_moved
from pixelworld_env.core.kernels import *  # noqa: F403

_warn_moved(__name__)
