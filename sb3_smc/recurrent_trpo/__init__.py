"""Recurrent TRPO (LSTM or GRU policies), in sb3-contrib's layout: one folder per algorithm."""

from sb3_smc.recurrent_trpo.recurrent_trpo import BASELINES, LinearFeatureBaseline, RecurrentTRPO

__all__ = ["BASELINES", "LinearFeatureBaseline", "RecurrentTRPO"]
