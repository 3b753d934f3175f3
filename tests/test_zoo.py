"""The rl_zoo3 hyperparameter files in ``zoo_configs/``: generated from DEFAULT_HYPERPARAMETERS, keys, the paper's
settings, and that each one builds and trains its algorithm on a real PixelWorld env the way rl_zoo3 would (without
importing rl_zoo3)."""

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
from sb3_smc.core.hyperparameters import DEFAULT_HYPERPARAMETERS
from sb3_smc.envs.wrapper import HierarchicalSMCWrapper
from sb3_smc.library import SMCLibrary
from sb3_smc.smc.policies import policy_from_model
from sb3_smc.smc.smc import SMC
from sb3_smc.zoo import ZOO_ALGOS, render_config, smc_env

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
def test_configs_are_generated_from_the_defaults(algo):
    """The shipped file is what `python -m sb3_smc.zoo` writes, and carries every default of its algorithm."""
    assert (CONFIGS / f"{algo}.yml").read_text() == render_config(algo), "run: python -m sb3_smc.zoo zoo_configs"
    defaults = DEFAULT_HYPERPARAMETERS[ZOO_ALGOS[algo]]
    config = _load(algo)["default"]
    for key, value in defaults.items():
        if key == "policy_kwargs":
            assert _policy_kwargs(config[key]) == value
        elif key != "policy":
            assert config[key] == value, key
    assert config["n_envs"] * config["n_steps"] == 2000


def test_zoo_env_wrapper_entry(tmp_path):
    env = smc_env(gym.make(ENV_IDS["trpo"]))
    assert isinstance(env, HierarchicalSMCWrapper) and env.smcs == ()
    with pytest.raises(ValueError, match="without the library"):
        smc_env(gym.make(ENV_IDS["trpo"]), names=["x"])


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
        assert _import(hyperparams["env_wrapper"]) is smc_env
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
    callback = _import(hyperparams.pop("callback"))()
    policy = hyperparams.pop("policy")
    policy_kwargs = _policy_kwargs(hyperparams.pop("policy_kwargs"))
    hyperparams.update(n_steps=64, batch_size=min(hyperparams["batch_size"], 64))
    env_id = ENV_IDS[algo]
    venv = make_vec_env(env_id, n_envs=1, seed=0, wrapper_class=wrapper)
    model = cls(policy, venv, policy_kwargs=policy_kwargs, seed=0, device="cpu", **hyperparams)
    model.learn(64, callback=callback)
    assert model.num_timesteps >= 64
    assert callback.kind == venv.envs[0].unwrapped.kind and callback.history  # the smc/ curves were computed
    # what rl_zoo3 trains has the flat-SMC layout: it goes into an SMCLibrary as it is
    base = venv.envs[0].unwrapped
    smc = SMC(algo, base.kind, policy_from_model(model), model=model)
    library = SMCLibrary([smc])
    path = library.save(tmp_path / "library")
    assert SMCLibrary.load(path).names == (algo,)
    # and the library's SMC goes back into a zoo run as an action
    wrapped = smc_env(gym.make(env_id), library=str(path), names=[algo])
    assert wrapped.action_names[-1] == f"SMC:{algo}"
