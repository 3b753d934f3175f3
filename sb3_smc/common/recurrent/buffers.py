"""``CompactRecurrentRolloutBuffer``: sb3-contrib's recurrent rollout buffer without padding."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import torch
from sb3_contrib import RecurrentPPO
from sb3_contrib.common.recurrent.buffers import RecurrentRolloutBuffer
from sb3_contrib.common.recurrent.type_aliases import RecurrentRolloutBufferSamples

from sb3_smc.common.recurrent.policies import SequenceLstmPolicy
from sb3_smc.common.recurrent.type_aliases import SequenceStates

if TYPE_CHECKING:
    from stable_baselines3.common.vec_env import VecNormalize

__all__ = ["CompactRecurrentRolloutBuffer", "use_compact_buffer"]


class CompactRecurrentRolloutBuffer(RecurrentRolloutBuffer):
    """sb3-contrib's recurrent rollout buffer without padding.

    The stock buffer pads every sequence of a minibatch (cut at episode starts) to the longest one, one tensor
    per sequence: with short episodes a 2,000-step minibatch becomes ~90,000 padded rows built by ~500,000 small
    ``torch.tensor`` calls. This buffer returns the minibatch's rows unpadded, in the stock order (sequence after
    sequence), with an all-ones ``mask`` and the layout in :class:`SequenceStates`; :class:`SequenceLstmPolicy`
    reads it. The minibatch order and sequence cuts are the stock ones.
    """

    # sb3-contrib's signature (env_change added before env), which mypy finds incompatible with SB3's base buffers
    def _get_samples(  # type: ignore[override]
            self, batch_inds: np.ndarray, env_change: np.ndarray, env: VecNormalize | None = None
    ) -> RecurrentRolloutBufferSamples:
        episode_starts = self.episode_starts[batch_inds].reshape(-1)
        seq_start = np.logical_or(episode_starts, env_change[batch_inds].reshape(-1))
        seq_start[0] = True
        starts = np.flatnonzero(seq_start)
        lengths = np.diff(np.append(starts, len(batch_inds)))

        def initial(array: np.ndarray) -> torch.Tensor:
            return self.to_torch(array[batch_inds][starts].swapaxes(0, 1)).contiguous()

        states = SequenceStates((initial(self.hidden_states_pi), initial(self.cell_states_pi)),
                                (initial(self.hidden_states_vf), initial(self.cell_states_vf)))
        states.starts = torch.as_tensor(starts, dtype=torch.long)
        states.lengths = torch.as_tensor(lengths, dtype=torch.long)
        states.resets = self.to_torch(episode_starts[starts])
        return RecurrentRolloutBufferSamples(
            observations=self.to_torch(self.observations[batch_inds]),
            actions=self.to_torch(self.actions[batch_inds]),
            old_values=self.to_torch(self.values[batch_inds].reshape(-1)),
            old_log_prob=self.to_torch(self.log_probs[batch_inds].reshape(-1)),
            advantages=self.to_torch(self.advantages[batch_inds].reshape(-1)),
            returns=self.to_torch(self.returns[batch_inds].reshape(-1)),
            lstm_states=states,
            episode_starts=self.to_torch(episode_starts),
            mask=torch.ones(len(batch_inds), dtype=torch.float32, device=self.device),
        )



def use_compact_buffer(model: RecurrentPPO) -> bool:
    """Give a ``RecurrentPPO`` model with a :class:`SequenceLstmPolicy` a :class:`CompactRecurrentRolloutBuffer`.

    The model stays a plain ``RecurrentPPO`` (saved, loaded and stored in an ``SMCLibrary`` as such; a loaded
    model gets sb3-contrib's padded buffer back, which the policy also reads). Returns whether the buffer was
    replaced (not for other policies or ``Dict`` observations).
    """
    buffer = model.rollout_buffer
    if not isinstance(model.policy, SequenceLstmPolicy) or type(buffer) is not RecurrentRolloutBuffer:
        return False
    model.rollout_buffer = CompactRecurrentRolloutBuffer(
        model.n_steps, model.observation_space, model.action_space, buffer.hidden_state_shape, model.device,
        gamma=model.gamma, gae_lambda=model.gae_lambda, n_envs=model.n_envs)
    return True
