"""Sensorimotor contingencies (SMCs) for Stable-Baselines3: train them, reuse them as actions, save them.

The names below are imported on first use (PEP 562), so ``import sb3_smc.records`` (the typed specs and records)
loads neither torch nor Stable-Baselines3; ``from sb3_smc import train_smc`` loads them.
"""

from __future__ import annotations

import importlib
from importlib import metadata as _metadata
from typing import TYPE_CHECKING, Any

try:
    __version__ = _metadata.version("sb3-smc")
    """The installed distribution's version (pyproject.toml's), shared by ``pixelworld_env`` and ``sb3_smc``."""
except _metadata.PackageNotFoundError:  # a checkout on sys.path, not installed
    __version__ = "unknown"

_EXPORTS = {
    "SMCError": "sb3_smc.errors",
    "SMC": "sb3_smc.smc.smc",
    "StepPolicy": "sb3_smc.smc.smc",
    "observation_size": "sb3_smc.core.layout",
    "smc_action_names": "sb3_smc.core.layout",
    "Budget": "sb3_smc.records",
    "EvaluationRecord": "sb3_smc.records",
    "RecordError": "sb3_smc.records",
    "SignalBias": "sb3_smc.records",
    "TaskSpec": "sb3_smc.records",
    "TrainingRecord": "sb3_smc.records",
    "TrainingSpec": "sb3_smc.records",
    "WrapperSettings": "sb3_smc.records",
    "DEFAULT_HYPERPARAMETERS": "sb3_smc.core.hyperparameters",
    "register_algorithm": "sb3_smc.core.hyperparameters",
    "initial_action_probabilities": "sb3_smc.learning.bias",
    "apply_signal_bias": "sb3_smc.learning.bias",
    "HierarchicalSMCWrapper": "sb3_smc.envs.wrapper",
    "make_smc_env": "sb3_smc.envs.factory",
    "FrameStackPolicy": "sb3_smc.smc.policies",
    "ScriptedPolicy": "sb3_smc.smc.policies",
    "SequencePolicy": "sb3_smc.smc.policies",
    "policy_from_model": "sb3_smc.smc.policies",
    "sample_action": "sb3_smc.smc.policies",
    "train_smc": "sb3_smc.learning.training",
    "untrained_smc": "sb3_smc.learning.training",
    "RecurrentTRPO": "sb3_smc.recurrent_trpo",
    "EvaluationResult": "sb3_smc.learning.evaluation",
    "evaluate": "sb3_smc.learning.evaluation",
    "SMCLibrary": "sb3_smc.library",
    "CorruptModelError": "sb3_smc.library",
    "LayoutMismatchError": "sb3_smc.library",
    "LibraryError": "sb3_smc.library",
    "ManifestError": "sb3_smc.library",
    "MissingChildError": "sb3_smc.library",
    "UnknownSMCError": "sb3_smc.library",
}

__all__ = [
    "__version__",
    "Budget",
    "CorruptModelError",
    "DEFAULT_HYPERPARAMETERS",
    "EvaluationRecord",
    "EvaluationResult",
    "FrameStackPolicy",
    "HierarchicalSMCWrapper",
    "LayoutMismatchError",
    "LibraryError",
    "ManifestError",
    "MissingChildError",
    "RecordError",
    "RecurrentTRPO",
    "SMC",
    "SMCError",
    "SMCLibrary",
    "ScriptedPolicy",
    "SequencePolicy",
    "SignalBias",
    "StepPolicy",
    "TaskSpec",
    "TrainingRecord",
    "TrainingSpec",
    "UnknownSMCError",
    "WrapperSettings",
    "apply_signal_bias",
    "evaluate",
    "initial_action_probabilities",
    "make_smc_env",
    "observation_size",
    "policy_from_model",
    "register_algorithm",
    "sample_action",
    "smc_action_names",
    "train_smc",
    "untrained_smc",
]
assert set(__all__) == {*_EXPORTS, "__version__"}


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'sb3_smc' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_EXPORTS})


if TYPE_CHECKING:  # pragma: no cover - for type checkers and IDEs
    from sb3_smc.core.hyperparameters import DEFAULT_HYPERPARAMETERS, register_algorithm
    from sb3_smc.core.layout import observation_size, smc_action_names
    from sb3_smc.envs.factory import make_smc_env
    from sb3_smc.envs.wrapper import HierarchicalSMCWrapper
    from sb3_smc.errors import SMCError
    from sb3_smc.learning.bias import apply_signal_bias, initial_action_probabilities
    from sb3_smc.learning.evaluation import EvaluationResult, evaluate
    from sb3_smc.learning.training import train_smc, untrained_smc
    from sb3_smc.library import (
        CorruptModelError,
        LayoutMismatchError,
        LibraryError,
        ManifestError,
        MissingChildError,
        SMCLibrary,
        UnknownSMCError,
    )
    from sb3_smc.records import (
        Budget,
        EvaluationRecord,
        RecordError,
        SignalBias,
        TaskSpec,
        TrainingRecord,
        TrainingSpec,
        WrapperSettings,
    )
    from sb3_smc.recurrent_trpo import RecurrentTRPO
    from sb3_smc.smc.policies import FrameStackPolicy, ScriptedPolicy, SequencePolicy, policy_from_model, sample_action
    from sb3_smc.smc.smc import SMC, StepPolicy
