"""Deprecated: the path of :mod:`sb3_smc.learning.training` before 2026-11-27, kept for one release."""

from sb3_smc._moved import warn_moved as _warn_moved

# models saved by sb3-smc 0.1 pickled their LSTM policy class as sb3_smc.training.SequenceLstmPolicy
from sb3_smc.common.recurrent import SequenceLstmPolicy  # noqa: F401
from sb3_smc.learning.training import *  # noqa: F403

_warn_moved(__name__)
