"""Sensorimotor contingencies (SMCs) for Stable-Baselines3."""
