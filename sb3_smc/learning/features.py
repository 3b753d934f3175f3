"""A features extractor for SB3's ``CnnPolicy`` on PixelWorld's image observation (``observation="image"``).

SB3's default ``NatureCNN`` starts with an 8 x 8 convolution of stride 4 and needs images of at least 36 x 36; the
PixelWorld grid is 18 x 35. :class:`PixelWorldCNN` uses the layers of the paper's CNN baseline
(:mod:`sb3_smc.experiments.cnn`) instead::

    import gymnasium as gym
    from stable_baselines3 import PPO

    import pixelworld_env  # noqa: F401
    from sb3_smc.learning.features import PixelWorldCNN

    env = gym.make("PW-cl_self-in-container_vs_noncontainer-v0", observation="image")
    model = PPO("CnnPolicy", env, policy_kwargs=dict(features_extractor_class=PixelWorldCNN))
"""

from __future__ import annotations

from collections.abc import Sequence

import torch as th
from gymnasium import spaces
from stable_baselines3.common.preprocessing import is_image_space, is_image_space_channels_first
from stable_baselines3.common.torch_layers import BaseFeaturesExtractor
from torch import nn

from pixelworld_env.validation import check_int
from sb3_smc.errors import SMCError, SMCTypeError

__all__ = ["PixelWorldCNN"]


class PixelWorldCNN(BaseFeaturesExtractor):
    """The paper's CNN layers as SB3 features: 3 x 3 convolutions (stride 1, same padding, ReLU) with ``filters``
    output channels (the paper: 8 then 16), then a linear layer of ``features_dim`` units (the paper: 8) with ReLU.

    ``observation_space`` must be a channel-first uint8 image (``PixelWorldEnv(observation="image")``: one channel
    per colour code); SB3's ``CnnPolicy`` scales it by 1/255, so the convolutions see the one-hot grid. Pass
    ``features_extractor_kwargs=dict(features_dim=..., filters=...)`` to change the sizes.
    """

    def __init__(self, observation_space: spaces.Space, features_dim: int = 8, filters: Sequence[int] = (8, 16)
                 ) -> None:
        if not (isinstance(observation_space, spaces.Box) and is_image_space(observation_space)
                and is_image_space_channels_first(observation_space)):
            raise SMCError(f"PixelWorldCNN needs a channel-first uint8 image space in [0, 255] "
                           f"(PixelWorldEnv(observation='image')), got {observation_space}")
        features_dim = check_int(features_dim, "features_dim", 1)
        if isinstance(filters, str | bytes) or not isinstance(filters, Sequence) or not filters:
            raise SMCTypeError(f"filters must be a non-empty sequence of channel counts, got {filters!r}")
        filters = [check_int(count, "each of filters", 1) for count in filters]
        super().__init__(observation_space, features_dim)
        channels, height, width = observation_space.shape
        layers: list[nn.Module] = []
        for count in filters:
            layers += [nn.Conv2d(channels, count, kernel_size=3, stride=1, padding=1), nn.ReLU()]
            channels = count
        self.cnn = nn.Sequential(*layers, nn.Flatten())
        self.linear = nn.Sequential(nn.Linear(channels * height * width, features_dim), nn.ReLU())

    def forward(self, observations: th.Tensor) -> th.Tensor:
        return self.linear(self.cnn(observations))
