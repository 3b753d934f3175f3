"""The rl_zoo3 hyperparameter files in ``zoo_configs/``: keys, the paper's settings, and that each one builds and
trains its algorithm on a real PixelWorld env the way rl_zoo3 would (without importing rl_zoo3)."""

from __future__ import annotations

import importlib
import inspect
from pathlib import Path

import gymnasium as gym
import pytest
import yaml
from sb3_contrib import TRPO, RecurrentPPO
from stable_baselines3 import PPO
from stable_baselines3.common.env_util import make_vec_env
from torch import nn

import pixelworld_env  # noqa: F401  (registers the PW-* ids, what --gym-packages pixelworld_env does)
from sb3_smc.library import SMCLibrary
from sb3_smc.policies import policy_from_model
from sb3_smc.smc import SMC

CONFIGS = Path(__file__).resolve().parents[1] / "zoo_configs"
ALGOS = {"ppo_lstm": (RecurrentPPO, "MlpLstmPolicy"), "trpo": (TRPO, "MlpPolicy"), "ppo": (PPO, "MlpPolicy")}
ZOO_KEYS = {"n_envs", "n_timesteps", "policy", "normalize", "env_wrapper", "vec_env_wrapper", "frame_stack",
            "callback", "env_kwargs", "monitor_kwargs", "policy_kwargs"}
"""Keys rl_zoo3 consumes itself; every other key is passed to the algorithm's constructor."""
ENV_IDS = {"ppo_lstm": "PW-cl_self-in-left-corner_vs_on-hline-v0", "trpo": "PW-ba_self-in-container_from_on-floor-v0",
           "ppo": "PW-cl_self-in-left-corner_vs_on-hline-v0"}


def _load(algo: str) -> dict:
    return yaml.safe_load((CONFIGS / f"{algo}.yml").read_text())


def _import(path: str):
    module, _, name = path.rpartition(".")
    return getattr(importlib.import_module(module), name)


def _policy_kwargs(text: str) -> dict:
    return eval(text, {"dict": dict, "nn": nn})  # rl_zoo3 evaluates the string the same way


@pytest.mark.parametrize("algo", list(ALGOS))
def test_config_keys_and_paper_settings(algo):
    cls, policy = ALGOS[algo]
    config = _load(algo)
    assert "default" in config, "rl_zoo3 falls back to the `default` key for env ids it does not list"
    for key in config:
        assert key == "default" or key in gym.registry, f"{key} is not a registered env id"
    for key, hyperparams in config.items():
        constructor = set(inspect.signature(cls.__init__).parameters) - {"self", "env", "policy"}
        unknown = set(hyperparams) - ZOO_KEYS - constructor
        assert not unknown, f"{algo}.yml [{key}]: unknown keys {unknown}"
        assert hyperparams["policy"] == policy
        assert hyperparams["n_envs"] * hyperparams["n_steps"] == 2000  # the paper's batch per update
        assert hyperparams["batch_size"] <= 2000 and 2000 % hyperparams["batch_size"] == 0
        assert int(hyperparams["n_timesteps"]) == 400_000
        assert (hyperparams["gamma"], hyperparams["gae_lambda"]) == (0.99, 1.0)
        assert _import(hyperparams["env_wrapper"]).__name__ == "HierarchicalSMCWrapper"
        kwargs = _policy_kwargs(hyperparams["policy_kwargs"])
        if algo == "ppo_lstm":
            assert kwargs["lstm_hidden_size"] == 32 and kwargs["n_lstm_layers"] == 1
        else:
            assert kwargs["net_arch"] == {"pi": [32], "vf": [32]}
        if algo == "trpo":
            assert hyperparams["target_kl"] == 0.01


@pytest.mark.parametrize("algo", list(ALGOS))
def test_config_trains_and_gives_a_storable_smc(algo, tmp_path):
    """Build the model from the `default` entry as rl_zoo3 does (with 64 steps per update), train 64 steps."""
    cls, _ = ALGOS[algo]
    hyperparams = dict(_load(algo)["default"])
    for key in ("n_timesteps", "n_envs", "normalize"):
        hyperparams.pop(key)
    wrapper = _import(hyperparams.pop("env_wrapper"))
    policy = hyperparams.pop("policy")
    policy_kwargs = _policy_kwargs(hyperparams.pop("policy_kwargs"))
    hyperparams.update(n_steps=64, batch_size=min(hyperparams["batch_size"], 64))
    env_id = ENV_IDS[algo]
    venv = make_vec_env(env_id, n_envs=1, seed=0, wrapper_class=wrapper)
    model = cls(policy, venv, policy_kwargs=policy_kwargs, seed=0, device="cpu", **hyperparams)
    model.learn(64)
    assert model.num_timesteps >= 64
    # what rl_zoo3 trains has the flat-SMC layout: it goes into an SMCLibrary as it is
    base = venv.envs[0].unwrapped
    smc = SMC(algo, base.kind, policy_from_model(model), model=model, metadata={"env_id": env_id, "source": "zoo"})
    library = SMCLibrary([smc])
    assert SMCLibrary.load(library.save(tmp_path / "library")).names == (algo,)
