"""Semi-MDP discounting of SMC calls: a decision that ran ``k`` primitive steps is discounted by ``gamma ** k``.

By default a call is one decision (the simplest reading: the paper does not say how its learner discounted a call):
the learner discounts every decision by ``gamma``, whether it was one move or a call of 40. With ``discount="semi-mdp"``
(:class:`~sb3_smc.records.WrapperSettings`) the advantage and the return of decision ``t`` use
``gamma_t = gamma ** max(1, k_t)``, where ``k_t`` is the number of primitive steps the decision executed (the wrapper's
``info["primitive_steps"]``: 1 for a move, the moves of a call; a signal counts 1):

    delta_t = r_t + gamma_t V(s_t+1) (1 - done_t) - V(s_t),   A_t = delta_t + gamma_t lambda (1 - done_t) A_t+1

A flat SMC (every decision one step) trains exactly as under the default (tested). SB3's bootstrap at a
time-limit cut (``TimeLimit.truncated``: ``gamma V(terminal)`` added to the last reward) keeps ``gamma``.

:class:`SemiMDPDiscount` is a callback that records ``k_t`` for every stored transition and replaces the rollout
buffer's ``compute_returns_and_advantage`` (any SB3 / sb3-contrib on-policy buffer: they share SB3's), for PPO,
TRPO, RecurrentPPO and RecurrentTRPO alike.
"""

from __future__ import annotations

import numpy as np
import torch
from stable_baselines3.common.buffers import RolloutBuffer
from stable_baselines3.common.callbacks import BaseCallback

__all__ = ["SemiMDPDiscount", "gae"]


def gae(rewards: np.ndarray, values: np.ndarray, episode_starts: np.ndarray, last_values: np.ndarray,
        dones: np.ndarray, gammas: np.ndarray, gae_lambda: float) -> np.ndarray:
    """GAE(lambda) advantages of a rollout (float32 arrays ``(steps, envs)``) with a discount per transition
    ``gammas`` (float64): SB3's ``RolloutBuffer.compute_returns_and_advantage`` with ``gamma`` replaced by
    ``gammas[t]``, in its float32 arithmetic and order (the same numbers where every ``gammas[t]`` is ``gamma``)."""
    advantages = np.zeros_like(rewards)
    last = np.zeros(rewards.shape[1], dtype=rewards.dtype)
    steps = rewards.shape[0]
    discounts = gammas.astype(rewards.dtype)
    traces = (gammas * gae_lambda).astype(rewards.dtype)
    for step in reversed(range(steps)):
        if step == steps - 1:
            next_non_terminal = 1.0 - dones.astype(np.float32)
            next_values = last_values
        else:
            next_non_terminal = 1.0 - episode_starts[step + 1]
            next_values = values[step + 1]
        delta = rewards[step] + discounts[step] * next_values * next_non_terminal - values[step]
        last = delta + traces[step] * next_non_terminal * last
        advantages[step] = last
    return advantages


class SemiMDPDiscount(BaseCallback):
    """Discount each decision by ``gamma ** primitive steps`` (module docstring). Pass it to ``learn`` (with the
    other callbacks); it takes over the rollout buffer's return computation when training starts."""

    def __init__(self) -> None:
        super().__init__()
        self._steps: np.ndarray | None = None
        self._buffer: RolloutBuffer | None = None

    def _on_training_start(self) -> None:
        buffer = getattr(self.model, "rollout_buffer", None)
        if not isinstance(buffer, RolloutBuffer):  # an on-policy algorithm has one
            raise TypeError(f"semi-MDP discounting needs an on-policy algorithm's RolloutBuffer, got "
                            f"{type(buffer).__name__}")
        self._buffer = buffer
        self._steps = np.ones((buffer.buffer_size, buffer.n_envs), dtype=np.float64)
        steps = self._steps

        def compute_returns_and_advantage(last_values: torch.Tensor, dones: np.ndarray) -> None:
            gammas = buffer.gamma ** steps
            values = last_values.clone().cpu().numpy().flatten()
            buffer.advantages = gae(buffer.rewards, buffer.values, buffer.episode_starts, values, dones, gammas,
                                    buffer.gae_lambda)
            buffer.returns = buffer.advantages + buffer.values

        buffer.compute_returns_and_advantage = compute_returns_and_advantage  # type: ignore[method-assign]

    def _on_step(self) -> bool:
        assert self._steps is not None and self._buffer is not None
        infos = self.locals["infos"]
        self._steps[self._buffer.pos] = [max(1, int(info.get("primitive_steps", 1))) for info in infos]
        return True
