"""PPO, TRPO and RecurrentPPO construct and train on every observation of PixelWorldEnv."""

from __future__ import annotations

import pytest
from sb3_contrib import TRPO, RecurrentPPO
from stable_baselines3 import PPO

from tests.helpers import classification_env, make

ALGOS = {"PPO": (PPO, "MlpPolicy"), "TRPO": (TRPO, "MlpPolicy"), "RecurrentPPO": (RecurrentPPO, "MlpLstmPolicy")}


@pytest.mark.parametrize("observation", ["hand", "hand_raw"])
@pytest.mark.parametrize("algo", list(ALGOS))
def test_algorithms_train(algo: str, observation: str) -> None:
    cls, policy = ALGOS[algo]
    for env in (classification_env(observation=observation), make(observation=observation)):
        model = cls(policy, env, n_steps=64, batch_size=64, seed=0, device="cpu")
        model.learn(128)
        obs, _ = env.reset(seed=0)
        action, _ = model.predict(obs)
        assert env.action_space.contains(int(action))
