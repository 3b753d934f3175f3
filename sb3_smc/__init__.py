"""Sensorimotor contingencies (SMCs) for Stable-Baselines3: train them, reuse them as actions, save them."""

from sb3_smc.evaluation import EvaluationResult, evaluate
from sb3_smc.library import (
    CorruptModelError,
    LayoutMismatchError,
    LibraryError,
    ManifestError,
    MissingChildError,
    SMCLibrary,
    UnknownSMCError,
)
from sb3_smc.policies import ScriptedPolicy, SequencePolicy, policy_from_model, sample_action
from sb3_smc.smc import SMC, StepPolicy, observation_size, smc_action_names
from sb3_smc.training import apply_signal_bias, initial_action_probabilities, train_smc
from sb3_smc.wrapper import HierarchicalSMCWrapper

__all__ = [
    "SMC",
    "CorruptModelError",
    "EvaluationResult",
    "HierarchicalSMCWrapper",
    "LayoutMismatchError",
    "LibraryError",
    "ManifestError",
    "MissingChildError",
    "SMCLibrary",
    "ScriptedPolicy",
    "SequencePolicy",
    "StepPolicy",
    "UnknownSMCError",
    "apply_signal_bias",
    "evaluate",
    "initial_action_probabilities",
    "observation_size",
    "policy_from_model",
    "sample_action",
    "smc_action_names",
    "train_smc",
]
