"""Deprecated: the path of :mod:`pixelworld_env.generation.experiment_files` before 2026-11-25, kept for one release."""

from pixelworld_env._moved import warn_moved as _warn_moved
from pixelworld_env.generation.experiment_files import *  # noqa: F403

_warn_moved(__name__)
