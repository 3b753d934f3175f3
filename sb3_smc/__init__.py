"""Sensorimotor contingencies (SMCs) for Stable-Baselines3: train them, reuse them as actions, save them."""

from sb3_smc.smc import SMC, StepPolicy, observation_size, smc_action_names

__all__ = ["SMC", "StepPolicy", "observation_size", "smc_action_names"]
