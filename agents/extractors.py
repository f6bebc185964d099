"""A small CNN features extractor for the Dict observation's belief image, for SB3's ``MultiInputPolicy``.

SB3's ``CombinedExtractor`` sends image keys through NatureCNN, built for 84 x 84 Atari frames (an 8 x 8 kernel
with stride 4 would leave nothing of a 16 x 16 belief image) and expecting uint8 pixels. The belief image is a
small robot-centred float map, so here: two 3 x 3 convolutions with stride 1 and 2, a third with stride 2, a
linear layer; every other key (pose, covariances, landmarks, scan, ...) is flattened beside it, as SB3 does.

Use in a config: ``policy: MultiInputPolicy`` and
``policy_kwargs: {features_extractor_class: ekfslam_gym.agents.extractors.BeliefCNN, features_extractor_kwargs: {cnn_features: 128}}``
(``train.py`` resolves the dotted class name).
"""

from __future__ import annotations

import gymnasium as gym
import torch
from stable_baselines3.common.preprocessing import get_flattened_obs_dim
from stable_baselines3.common.torch_layers import BaseFeaturesExtractor
from torch import nn


def is_belief_image(space: gym.Space) -> bool:
    """A (channels, height, width) Box: the keys this extractor convolves."""
    return isinstance(space, gym.spaces.Box) and len(space.shape) == 3


class BeliefCNN(BaseFeaturesExtractor):
    """Convolves every (C, H, W) Box of a Dict space, flattens the others, and concatenates the features."""

    def __init__(
        self, observation_space: gym.spaces.Dict, cnn_features: int = 128, channels: int = 32
    ) -> None:
        if not isinstance(observation_space, gym.spaces.Dict):
            raise TypeError(f"BeliefCNN needs a Dict observation space, got {observation_space}")
        super().__init__(observation_space, features_dim=1)
        extractors: dict[str, nn.Module] = {}
        total = 0
        for key, space in observation_space.spaces.items():
            if is_belief_image(space):
                conv = nn.Sequential(
                    nn.Conv2d(space.shape[0], channels, 3, stride=1, padding=1),
                    nn.ReLU(),
                    nn.Conv2d(channels, channels, 3, stride=2, padding=1),
                    nn.ReLU(),
                    nn.Conv2d(channels, channels, 3, stride=2, padding=1),
                    nn.ReLU(),
                    nn.Flatten(),
                )
                with torch.no_grad():
                    flat = conv(torch.zeros((1, *space.shape))).shape[1]
                extractors[key] = nn.Sequential(conv, nn.Linear(flat, cnn_features), nn.ReLU())
                total += cnn_features
            else:
                extractors[key] = nn.Flatten()
                total += get_flattened_obs_dim(space)
        if not any(is_belief_image(space) for space in observation_space.spaces.values()):
            raise ValueError(
                "BeliefCNN found no (C, H, W) image in the observation; set observation.belief_image"
            )
        self.extractors = nn.ModuleDict(extractors)
        self._features_dim = total

    def forward(self, observations: dict[str, torch.Tensor]) -> torch.Tensor:
        return torch.cat([extractor(observations[key]) for key, extractor in self.extractors.items()], dim=1)
