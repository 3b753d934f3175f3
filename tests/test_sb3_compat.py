"""PPO, TRPO and RecurrentPPO construct and train on every observation of PixelWorldEnv; PPO's CnnPolicy on the image
observation with :class:`sb3_smc.learning.features.PixelWorldCNN`."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import torch as th
from sb3_contrib import TRPO, RecurrentPPO
from stable_baselines3 import PPO
from stable_baselines3.common.preprocessing import preprocess_obs
from stable_baselines3.common.vec_env import VecTransposeImage, is_vecenv_wrapped

import pixelworld_env  # noqa: F401  (registers the PW-* ids)
from sb3_smc.learning.features import PixelWorldCNN
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


def test_ppo_cnn_policy_learns_on_the_image_observation() -> None:
    """``PPO("CnnPolicy", ...)`` with :class:`PixelWorldCNN` takes the image as it is (channel-first: no transpose),
    sees the one-hot grid after SB3's scaling, and its weights move in a few hundred steps."""
    env = gym.make("PW-cl_self-in-container_vs_noncontainer-v0", observation="image")
    model = PPO("CnnPolicy", env, policy_kwargs=dict(features_extractor_class=PixelWorldCNN), n_steps=128,
                batch_size=64, n_epochs=2, seed=0, device="cpu")
    extractor = model.policy.features_extractor
    assert isinstance(extractor, PixelWorldCNN) and model.policy.features_dim == 8
    assert [layer.out_channels for layer in extractor.cnn if isinstance(layer, th.nn.Conv2d)] == [8, 16]
    assert not is_vecenv_wrapped(model.get_env(), VecTransposeImage)
    obs, _ = env.reset(seed=0)
    seen = preprocess_obs(th.as_tensor(obs[None]), model.observation_space, normalize_images=True)
    np.testing.assert_array_equal(seen[0].argmax(0).numpy(), env.unwrapped.world.state())
    assert set(np.unique(seen.numpy())) == {0.0, 1.0}
    before = [p.detach().clone() for p in model.policy.parameters()]
    model.learn(256)
    assert model.num_timesteps == 256
    assert all(not th.equal(a, b) for a, b in zip(before, model.policy.parameters(), strict=True))
    action, _ = model.predict(obs)
    assert env.action_space.contains(int(action))


def test_pixelworld_cnn_refuses_what_it_cannot_read() -> None:
    image = gym.spaces.Box(0, 255, (9, 18, 35), np.uint8)
    assert PixelWorldCNN(image, features_dim=32, filters=[4]).features_dim == 32
    with pytest.raises(ValueError, match="channel-first uint8 image space"):
        PixelWorldCNN(gym.spaces.Box(0.0, 1.0, (81,), np.float32))
    with pytest.raises(TypeError, match="features_dim must be an integer, got 8.0"):
        PixelWorldCNN(image, features_dim=8.0)
    with pytest.raises(TypeError, match="filters must be a non-empty sequence"):
        PixelWorldCNN(image, filters=())
    with pytest.raises(ValueError, match="each of filters must be >= 1, got 0"):
        PixelWorldCNN(image, filters=(8, 0))
