"""A learner from outside the package (:func:`sb3_smc.register_algorithm`): a class defined here trains, saves and
loads without ``trust``; bad registrations are refused; a learner whose module cannot be imported breaks only its
own SMCs."""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Iterator

import numpy as np
import pytest
import torch
from sb3_contrib import RecurrentPPO
from stable_baselines3 import DQN
from stable_baselines3.common.on_policy_algorithm import OnPolicyAlgorithm

import sb3_smc
from sb3_smc.core.hyperparameters import (
    ALGORITHM_REGISTRY,
    ALGORITHMS,
    DEFAULT_HYPERPARAMETERS,
    SAFE_CLASS_MODULES,
    algorithm_of,
)
from sb3_smc.errors import SMCError, SMCTypeError
from sb3_smc.learning.training import train_smc, untrained_smc
from sb3_smc.library import LibraryError, SMCLibrary
from sb3_smc.records import TrainingSpec

FLAT = "PW-cl_self-in-left-corner_vs_on-hline-v0"


class MyPPO(RecurrentPPO):
    """A learner of the user's own: sb3-contrib's RecurrentPPO under another name, in a module no file may name."""


class OtherPPO(RecurrentPPO):
    """Another one, for a name taken already."""


class Bare(OnPolicyAlgorithm):
    """An on-policy algorithm that derives from no registered one: it needs its own defaults."""


@pytest.fixture(autouse=True)
def registry() -> Iterator[None]:
    """Each test's registrations undone after it."""
    algorithms, defaults = dict(ALGORITHM_REGISTRY), dict(DEFAULT_HYPERPARAMETERS)
    yield
    ALGORITHM_REGISTRY.clear()
    ALGORITHM_REGISTRY.update(algorithms)
    DEFAULT_HYPERPARAMETERS.clear()
    DEFAULT_HYPERPARAMETERS.update(defaults)


def test_a_registered_learner_trains_saves_and_loads_without_trust(tmp_path) -> None:
    assert not any(MyPPO.__module__.startswith(module) for module in SAFE_CLASS_MODULES)
    entry = sb3_smc.register_algorithm("MyPPO", MyPPO)
    assert entry.load_class() is MyPPO and entry.cells == ALGORITHM_REGISTRY["RecurrentPPO"].cells
    assert DEFAULT_HYPERPARAMETERS["MyPPO"] == DEFAULT_HYPERPARAMETERS["RecurrentPPO"]
    assert sb3_smc.register_algorithm("MyPPO", MyPPO) is entry  # the same class again: nothing changes
    torch.set_num_threads(1)
    smc = train_smc(FLAT, algo="MyPPO", total_timesteps=256, n_envs=2, n_steps=64, log_every=0)
    assert type(smc.model) is MyPPO and smc.spec.algo == "MyPPO" and smc.record.total_timesteps == 256
    loaded = SMCLibrary.load(SMCLibrary([smc]).save(tmp_path / "library"))[smc.name]
    assert type(loaded.model) is MyPPO and loaded.spec == smc.spec
    weights, again = smc.model.policy.state_dict(), loaded.model.policy.state_dict()
    assert weights.keys() == again.keys() and all(torch.equal(weights[k], again[k]) for k in weights)
    observations = np.random.default_rng(0).uniform(-1, 1, (4, *smc.model.observation_space.shape))
    observations = observations.astype(np.float32)
    starts = np.ones(4, dtype=bool)
    actions, states = smc.model.predict(observations, episode_start=starts, deterministic=True)
    actions_again, states_again = loaded.model.predict(observations, episode_start=starts, deterministic=True)
    assert np.array_equal(actions, actions_again)
    assert all(np.array_equal(a, b) for a, b in zip(states, states_again, strict=True))
    first, second = (policy.probabilities(observations[0], policy.initial_state())[0]
                     for policy in (smc.policy, loaded.policy))
    assert np.array_equal(first, second)


def test_a_learner_with_defaults_of_its_own() -> None:
    with pytest.raises(SMCError, match="Bare derives from no registered algorithm; give its hyperparameters"):
        sb3_smc.register_algorithm("Bare", Bare)
    for bad in ({"gamma": 0.9}, {"policy": "MlpPolicy", "n_steps": 8}, {"policy": "MlpPolicy", "policy_kwargs": 3}):
        with pytest.raises(SMCError, match="hyperparameters need a 'policy'"):
            sb3_smc.register_algorithm("Bare", Bare, hyperparameters=bad)
    with pytest.raises(SMCError, match="hyperparameter hyperparameters.gamma: a function"):
        sb3_smc.register_algorithm("Bare", Bare, hyperparameters={"policy": "MlpPolicy", "gamma": lambda: 0.9})
    assert "Bare" not in ALGORITHM_REGISTRY
    entry = sb3_smc.register_algorithm("Bare", Bare, hyperparameters={"policy": "MlpPolicy", "gamma": 0.9})
    assert entry.hyperparameters == {"policy_kwargs": {}, "policy": "MlpPolicy", "gamma": 0.9} and not entry.recurrent
    spec = TrainingSpec.create(FLAT, algo="Bare", gamma=0.5)
    assert spec.hyperparameters["gamma"] == 0.5 and spec.hyperparameters["policy"] == "MlpPolicy"


@pytest.mark.parametrize(("name", "cls", "error", "message"), [
    ("", MyPPO, SMCError, "a non-empty string without white space, got ''"),
    ("my ppo", MyPPO, SMCError, "without white space, got 'my ppo'"),
    (3, MyPPO, SMCTypeError, "name must be a string, got int"),
    ("MyPPO", train_smc, SMCTypeError, "cls must be a subclass"),
    ("MyPPO", "sb3_contrib.RecurrentPPO", SMCTypeError, "cls must be a subclass"),
    ("MyDQN", DQN, SMCTypeError, "OnPolicyAlgorithm, got <class 'stable_baselines3.dqn.dqn.DQN'>"),
    ("PPO", MyPPO, SMCError, "algorithm 'PPO' is registered already, to stable_baselines3.PPO; choose another name"),
    ("MyRecurrentPPO", RecurrentPPO, SMCError, "RecurrentPPO is registered already as 'RecurrentPPO'; use that name"),
])
def test_bad_registrations_are_refused(name, cls, error, message) -> None:
    with pytest.raises(error, match=re.escape(message)):
        sb3_smc.register_algorithm(name, cls)
    assert tuple(ALGORITHM_REGISTRY) == ALGORITHMS


def test_a_name_registered_to_another_class_is_refused() -> None:
    sb3_smc.register_algorithm("MyPPO", MyPPO)
    with pytest.raises(SMCError, match=r"'MyPPO' is registered already, to tests\.test_register_algorithm\.MyPPO"):
        sb3_smc.register_algorithm("MyPPO", OtherPPO)
    with pytest.raises(SMCError, match="MyPPO is registered already as 'MyPPO'"):
        sb3_smc.register_algorithm("AlsoMyPPO", MyPPO)
    assert ALGORITHM_REGISTRY["MyPPO"].load_class() is MyPPO and "AlsoMyPPO" not in ALGORITHM_REGISTRY


def test_a_learner_whose_module_cannot_be_imported_breaks_only_its_own_smcs(tmp_path) -> None:
    """Saving a library of other SMCs imports no other learner's module; an SMC of the broken one fails to save and
    to load with an error naming the algorithm and the module, and the library's other SMCs still load."""
    sb3_smc.register_algorithm("MyPPO", MyPPO)
    mine = untrained_smc(FLAT, algo="MyPPO", n_envs=2, name="mine")
    other = untrained_smc(FLAT, algo="TRPO", n_envs=2, name="other")
    both = SMCLibrary([mine, other]).save(tmp_path / "both")
    ALGORITHM_REGISTRY["MyPPO"] = dataclasses.replace(ALGORITHM_REGISTRY["MyPPO"], registered=None,
                                                      class_path="no_such_learner_module.MyPPO")
    ALGORITHM_REGISTRY["Broken"] = dataclasses.replace(ALGORITHM_REGISTRY["MyPPO"], name="Broken",
                                                       class_path="no_such_learner_module.Broken")
    SMCLibrary([other]).save(tmp_path / "other")
    assert SMCLibrary.load(tmp_path / "other").names == ("other",)
    assert SMCLibrary.load(both, names=["other"]).names == ("other",)
    message = (r"SMC 'mine': .*algorithm 'MyPPO': cannot import its class 'MyPPO' from module "
               r"'no_such_learner_module' \(ModuleNotFoundError")
    with pytest.raises(LibraryError, match=message):
        SMCLibrary([mine, other]).save(tmp_path / "again")
    with pytest.raises(LibraryError, match=message):
        SMCLibrary.load(both)
    assert algorithm_of(type(other.model)) == "TRPO"


def test_an_unregistered_learner_is_not_stored_and_runs_take_the_built_in_ones(tmp_path) -> None:
    from sb3_smc.curricula.options import RunOptions

    sb3_smc.register_algorithm("MyPPO", MyPPO)
    smc = untrained_smc(FLAT, algo="MyPPO", n_envs=2, name="mine")
    with pytest.raises(SMCError, match=re.escape(f"algo must be one of {ALGORITHMS}, got 'MyPPO'")):
        RunOptions(algo="MyPPO")  # a curriculum's jobs may run in processes that never registered it
    del ALGORITHM_REGISTRY["MyPPO"]
    with pytest.raises(LibraryError, match="SMC 'mine': cannot store a MyPPO model .*sb3_smc.register_algorithm"):
        SMCLibrary([smc]).save(tmp_path / "library")
