"""Deprecated: the path of :mod:`sb3_smc.learning.callbacks` before 2026-11-27, kept for one release."""

from sb3_smc._moved import warn_moved as _warn_moved
from sb3_smc.learning.callbacks import *  # noqa: F403

_warn_moved(__name__)
