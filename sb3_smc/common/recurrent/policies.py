"""``SequenceLstmPolicy``: sb3-contrib's ``MlpLstmPolicy`` with a faster training pass."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, cast

import numpy as np
import torch
from gymnasium import spaces
from sb3_contrib.common.recurrent.policies import RecurrentActorCriticPolicy
from sb3_contrib.common.recurrent.type_aliases import RNNStates
from stable_baselines3.common.distributions import CategoricalDistribution
from stable_baselines3.common.torch_layers import FlattenExtractor
from torch import nn
from torch.distributions import Categorical

from sb3_smc.common import kernels
from sb3_smc.common.recurrent.type_aliases import SequenceStates

if TYPE_CHECKING:
    from sb3_smc.common.recurrent.layers import GRUAsLSTM

__all__ = ["SequenceLstmPolicy", "gru_cell_state"]


def gru_cell_state(c: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """A GRU policy's next (unused) cell state after a compiled collection step, as torch's step leaves it:
    ``c`` zeroed where an episode starts (``starts`` 1.0), float32."""
    return c * (1.0 - starts[:, None]).astype(np.float32)


def _lstm_by_length(lstm: torch.nn.LSTM, features: torch.Tensor, starts: torch.Tensor, lengths: torch.Tensor,
                    states: tuple[torch.Tensor, torch.Tensor]) -> torch.Tensor:
    """Run ``lstm`` over the sequences ``features[starts[i] : starts[i] + lengths[i]]`` of a flat batch.

    Sequences whose lengths fall in the same power-of-two bucket run together, padded only to the longest of
    their bucket, from their initial ``states`` (``(n_layers, n_seq, hidden)`` each). Returns the outputs at the
    same flat positions as ``features`` (zeros where no sequence covers a row).
    """
    n_rows = features.shape[0]
    positions, outputs = [], []
    low, high = 0, 1
    longest_overall = int(lengths.max()) if len(lengths) else 0
    while low < longest_overall:
        members = torch.nonzero((lengths > low) & (lengths <= high)).flatten()
        if len(members):
            longest = int(lengths[members].max())
            offsets = torch.arange(longest, device=starts.device)
            index = starts[members, None] + offsets[None, :]  # (n_bucket, longest)
            valid = offsets[None, :] < lengths[members, None]
            index = torch.where(valid, index, starts[members, None])  # rows past the end: any row (causal LSTM)
            output, _ = lstm(features[index].transpose(0, 1), (states[0][:, members], states[1][:, members]))
            positions.append(index[valid])
            outputs.append(output.transpose(0, 1)[valid])
        low, high = high, 2 * high
    result = features.new_zeros((n_rows, lstm.hidden_size))
    if positions:
        result = result.index_put((torch.cat(positions),), torch.cat(outputs))
    return result


def _steppable(lstm: torch.nn.LSTM) -> bool:
    """Whether :func:`_lstm_step` computes ``lstm`` (no projection, no dropout between layers, sequence first)."""
    return not lstm.batch_first and not lstm.proj_size and not (lstm.dropout and lstm.training)


def _lstm_step(lstm: nn.LSTM | GRUAsLSTM, x: torch.Tensor, states: tuple[torch.Tensor, torch.Tensor]
               ) -> tuple[torch.Tensor, tuple[torch.Tensor, torch.Tensor]]:
    """One time step of ``lstm`` for a batch ``x`` ``(batch, input)``: the last layer's output and the new
    ``(h, c)``, each ``(n_layers, batch, hidden)`` (a module with its own ``step``, such as a GRU behind the LSTM
    interface, does it itself)."""
    step = getattr(lstm, "step", None)
    if step is not None:
        return step(x, states)
    hs, cs = [], []
    for k in range(lstm.num_layers):
        bias = (getattr(lstm, f"bias_ih_l{k}"), getattr(lstm, f"bias_hh_l{k}")) if lstm.bias else (None, None)
        x, c = torch.lstm_cell(x, (states[0][k], states[1][k]), getattr(lstm, f"weight_ih_l{k}"),
                               getattr(lstm, f"weight_hh_l{k}"), *bias)
        hs.append(x)
        cs.append(c)
    return x, (torch.stack(hs), torch.stack(cs))


class SequenceLstmPolicy(RecurrentActorCriticPolicy):
    """sb3-contrib's ``MlpLstmPolicy`` with a faster training pass and a faster collection step.

    The stock policy runs its LSTM one time step at a time over padded minibatches whenever an episode starts
    inside them (a Python loop over up to ``n_steps`` steps, forward and backward). This policy runs it once per
    power-of-two bucket of sequence lengths, each padded only to its own longest sequence, from the sequences'
    initial states (zeroed where a sequence starts an episode). It reads compact minibatches of
    :class:`CompactRecurrentRolloutBuffer` (see :func:`use_compact_buffer`) and sb3-contrib's padded ones
    (plain ``RecurrentPPO``; the sequence lengths are then read from the padding, whose observations are all
    zeros, which a one-hot SMC observation never is): the same numbers on every real step. Data collection takes a
    lean one-step path (:meth:`forward`; equal up to float rounding), compiled for the default architecture.
    :func:`sb3_smc.smc.policies.policy_from_model` reads it like ``MlpLstmPolicy``.
    """

    #: Whether data collection may use the compiled step of :mod:`sb3_smc.common.kernels` (see :meth:`forward`).
    compiled_collection: bool = True
    #: Whether the compiled step takes the lean update's tanh (:func:`~sb3_smc.common.kernels.fast_tanh`) for
    #: ``np.tanh``; set while the lean update trains the model
    #: (:func:`~sb3_smc.common.recurrent.lean_update.use_lean_update`).
    lean_collection: bool = False
    _collection_cache: tuple[Any, tuple[torch.Tensor, ...] | None, tuple[Any, ...] | None] | None = None

    def forward(self, obs, lstm_states, episode_starts, deterministic=False):
        """sb3-contrib's forward pass. One step per sequence (data collection) with a categorical action and a
        feed-forward critic takes a lean path: the LSTM as ``torch.lstm_cell`` per layer (a third of the time of
        the sequence kernel for one step; equal to it up to float rounding), no sequence reshaping, and no
        argument validation in the action distribution.

        Without gradients, for the default architecture (one recurrent layer, linear critic, value and action
        heads, ``net_arch=[]``, flat float32 observations on the CPU), the whole step is one compiled function
        (:func:`~sb3_smc.common.kernels.lstm_collection_step`, computed in float64 from float32 weights, equal to
        the torch step up to float rounding); the action is then drawn by inverse CDF from ``torch.rand``, so
        seeding torch still seeds the collection. ``compiled_collection = False`` turns that off."""
        n_seq = lstm_states.pi[0].shape[1]
        if not self._lean_step() or obs.shape[0] != n_seq:
            return super().forward(obs, lstm_states, episode_starts, deterministic)
        weights = self._collection_weights(obs) if self.compiled_collection and not torch.is_grad_enabled() else None
        if weights is not None:
            return self._compiled_forward(weights, obs, lstm_states, episode_starts, deterministic)
        features = self.extract_features(obs)
        states = lstm_states.pi
        if not bool((episode_starts == 0.0).all()):  # as _process_sequence: reset the states of new episodes
            keep = (1.0 - episode_starts).view(1, n_seq, 1)
            states = (keep * states[0], keep * states[1])
        latent_pi, states_pi = _lstm_step(self.lstm_actor, features, states)
        latent_pi = self.mlp_extractor.forward_actor(latent_pi)
        latent_vf = self.mlp_extractor.forward_critic(self.critic(features))
        values = self.value_net(latent_vf)
        distribution = Categorical(logits=self.action_net(latent_pi), validate_args=False)
        actions = torch.argmax(distribution.probs, dim=1) if deterministic else distribution.sample()
        return actions, values, distribution.log_prob(actions), RNNStates(states_pi, states_pi)

    @property
    def gru_actor(self) -> bool:
        """Whether the actor's recurrent cell is a GRU (:class:`~sb3_smc.common.recurrent.layers.GRUAsLSTM`): its
        compiled steps take :func:`~sb3_smc.common.kernels.gru_collection_step` and keep no cell state."""
        return hasattr(self.lstm_actor, "gru")

    def _lean_step(self) -> bool:
        """Whether :meth:`forward` takes its lean one-step path (a categorical action, a feed-forward critic)."""
        return (self.lstm_critic is None and not self.shared_lstm and self.share_features_extractor
                and isinstance(self.action_dist, CategoricalDistribution) and _steppable(self.lstm_actor))

    def compiled_collection_weights(self, obs: torch.Tensor) -> tuple[Any, ...] | None:
        """The arrays of :meth:`compiled_step` when :meth:`forward` would compute a collection step on ``obs`` (one
        row per sequence, no gradients) with it, else ``None``."""
        if not (self._lean_step() and self.compiled_collection and not torch.is_grad_enabled()):
            return None
        return self._collection_weights(obs)

    def compiled_step(self, weights: tuple[Any, ...], obs: np.ndarray, h: np.ndarray, c: np.ndarray,
                      starts: np.ndarray, uniforms: np.ndarray, deterministic: bool = False
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`forward`'s compiled collection step on numpy arrays: ``obs`` ``(n, features)`` float32, the
        actor's previous ``h`` / ``c`` ``(n, hidden)``, ``starts`` float64 (1.0 at an episode start), ``uniforms``
        the draws; returns ``(actions, values (n, 1), log-probabilities, h', c')``. With :attr:`lean_collection`
        the cell's tanh is :func:`~sb3_smc.common.kernels.fast_tanh`."""
        if self.gru_actor:
            actions, values, log_probs, h_next = kernels.gru_collection_step(
                obs, h, starts, uniforms, deterministic, not self.lean_collection, *weights)
            return actions, values, log_probs, h_next, gru_cell_state(c, starts)
        return kernels.lstm_collection_step(obs, h, c, starts, uniforms, deterministic, not self.lean_collection,
                                            *weights)

    def _collection_parameters(self) -> tuple[torch.Tensor, ...] | None:
        """The tensors of the compiled collection step, or ``None`` where the architecture is not the default one:
        the recurrent layer's (``weight_ih, weight_hh, bias_ih, bias_hh``), then the critic's, value head's and
        action head's weights and biases."""
        # an nn.LSTM or nn.GRU, whose weight_*_l0 / bias_*_l0 parameters torch registers by name
        recurrent: Any = getattr(self.lstm_actor, "gru", self.lstm_actor)
        linear = (self.critic, self.value_net, self.action_net)
        if (recurrent.num_layers != 1 or not recurrent.bias or not all(isinstance(m, nn.Linear) and m.bias is not None
                                                                       for m in linear)
                or len(self.mlp_extractor.policy_net) or len(self.mlp_extractor.value_net)
                or type(self.features_extractor) is not FlattenExtractor
                or not isinstance(self.observation_space, spaces.Box) or len(self.observation_space.shape) != 1):
            return None
        heads = cast(tuple[nn.Linear, ...], linear)  # all nn.Linear with a bias, as checked above
        tensors = (recurrent.weight_ih_l0, recurrent.weight_hh_l0, recurrent.bias_ih_l0, recurrent.bias_hh_l0,
                   *(t for m in heads for t in (m.weight, m.bias)))
        if any(t.dtype != torch.float32 or t.device.type != "cpu" for t in tensors):
            return None
        return tensors

    def _collection_weights(self, obs: torch.Tensor) -> tuple[Any, ...] | None:
        """The compiled step's arrays (transposed float64 copies), rebuilt whenever a parameter changed (the
        optimizer and ``load_state_dict`` update them in place, which bumps their version; ``.to`` gives them new
        storage); ``None`` where the compiled step does not apply to this policy or to ``obs``."""
        if obs.dtype != torch.float32 or obs.device.type != "cpu" or obs.dim() != 2:
            return None
        cache = self._collection_cache
        if cache is not None:
            tensors = cache[1]
            if tensors is None:
                return None
            key = tuple(t._version for t in tensors), tuple(t.data_ptr() for t in tensors)
            if key == cache[0]:
                return cache[2]
            if key[1] != cache[0][1]:  # new storage (a dtype or device change): check the architecture again
                cache = None
        tensors = self._collection_parameters() if cache is None else cache[1]
        if tensors is None:
            self._collection_cache = (None, None, None)
            return None
        w_ih, w_hh, b_ih, b_hh, w_critic, b_critic, w_value, b_value, w_action, b_action = (
            t.detach().numpy().astype(np.float64) for t in tensors)
        biases = (b_ih, b_hh) if self.gru_actor else (b_ih + b_hh,)
        weights = (w_ih.T.copy(), w_hh.T.copy(), *biases, w_critic.T.copy(), b_critic, w_value[0], float(b_value[0]),
                   w_action.T.copy(), b_action)
        key = tuple(t._version for t in tensors), tuple(t.data_ptr() for t in tensors)
        self._collection_cache = (key, tensors, weights)
        return weights

    def _compiled_forward(self, weights: tuple[Any, ...], obs: torch.Tensor, lstm_states: RNNStates,
                          episode_starts: torch.Tensor, deterministic: bool):
        """:meth:`forward`'s compiled step (see there)."""
        n_seq = obs.shape[0]
        uniforms = np.zeros(n_seq) if deterministic else torch.rand(n_seq, dtype=torch.float64).numpy()
        starts = episode_starts.detach().numpy().astype(np.float64, copy=False).reshape(n_seq)
        actions, values, log_probs, h_next, c_next = self.compiled_step(
            weights, obs.numpy(), lstm_states.pi[0][0].numpy(), lstm_states.pi[1][0].numpy(), starts, uniforms,
            deterministic)
        states = (torch.from_numpy(h_next)[None], torch.from_numpy(c_next)[None])
        return torch.from_numpy(actions), torch.from_numpy(values), torch.from_numpy(log_probs), \
            RNNStates(states, states)

    def evaluate_actions(self, obs, actions, lstm_states, episode_starts):
        evaluated = self.evaluate_sequences(obs, lstm_states, episode_starts)
        if evaluated is None:
            return super().evaluate_actions(obs, actions, lstm_states, episode_starts)
        distribution, values = evaluated
        return values, distribution.log_prob(actions), distribution.entropy()

    def evaluate_sequences(self, obs, lstm_states, episode_starts):
        """``(action distribution, values)`` of every row of a compact or padded minibatch (the fast training
        pass), or ``None`` for layouts only sb3-contrib's stock pass reads (then ``evaluate_actions`` uses it)."""
        n_seq = lstm_states.pi[0].shape[1]
        if not self.share_features_extractor or obs.dim() != 2:
            return None
        if isinstance(lstm_states, SequenceStates):
            starts, lengths, resets = lstm_states.starts, lstm_states.lengths, lstm_states.resets
        else:  # sb3-contrib's padded layout: n_seq sequences of max_len rows, an episode start only first
            padded = episode_starts.reshape((n_seq, -1))
            max_len = padded.shape[1]
            if obs.shape[0] != n_seq * max_len or bool(padded[:, 1:].any()):
                return None
            real = obs.reshape(n_seq, max_len, -1).ne(0).any(dim=2)
            steps = torch.arange(1, max_len + 1, device=obs.device).expand(n_seq, max_len)
            lengths = (steps * real).amax(dim=1).clamp(min=1)
            starts = torch.arange(n_seq, device=obs.device) * max_len
            resets = padded[:, 0]
        keep = (1.0 - resets).view(1, n_seq, 1)
        features = self.extract_features(obs)
        states = (lstm_states.pi[0] * keep, lstm_states.pi[1] * keep)
        latent_pi = _lstm_by_length(self.lstm_actor, features, starts, lengths, states)
        if self.lstm_critic is not None:
            states = (lstm_states.vf[0] * keep, lstm_states.vf[1] * keep)
            latent_vf = _lstm_by_length(self.lstm_critic, features, starts, lengths, states)
        elif self.shared_lstm:
            latent_vf = latent_pi.detach()
        else:
            latent_vf = self.critic(features)
        latent_pi = self.mlp_extractor.forward_actor(latent_pi)
        latent_vf = self.mlp_extractor.forward_critic(latent_vf)
        return self._get_action_dist_from_latent(latent_pi), self.value_net(latent_vf)
