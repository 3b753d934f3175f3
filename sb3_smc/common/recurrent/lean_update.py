"""A lean PPO update for ``RecurrentPPO`` with :class:`SequenceLstmPolicy`: sb3-contrib's ``RecurrentPPO.train``
with the LSTM's recurrence compiled (opt-in; equal up to float rounding, not bit for bit).

:func:`lean_train` computes what ``model.train()`` computes: the same minibatch per epoch (the buffer's random
rotation drawn from numpy as sb3-contrib draws it, so the sequences are cut where the stock minibatch cuts them), the
same losses (clipped surrogate, value loss with ``clip_range_vf`` if set, entropy), gradient clipping to
``max_grad_norm``, the ``target_kl`` early stop, the same optimizer and the same logged values. What differs is
how the LSTM runs: the rollout is laid out once (sequences cut at environment boundaries and episode starts; each
epoch adds the cut of its rotation), the input projection of all rows is one matrix product, and the recurrence,
forward and backward, runs over every sequence in one compiled (numba) loop in float64, with no padding and no
per-step torch calls; the weight gradient of the recurrence is one matrix product over all rows. Sums are taken in
another order and in float64, so the losses and gradients equal the stock ones to float rounding (tested to 1e-5
relative on real rollouts); training on them is shown statistically equal, not bit-identical (``docs/training.md``,
"The lean update"). With the package's default heads (:func:`_plain_heads`: no layers after the LSTM, a linear
critic on the features, a categorical distribution, Adam) the whole epoch is written out in numpy, forward and
backward (:func:`_numpy_epoch`), with no autograd graph; other heads run in torch around the compiled recurrence
(:func:`_torch_epoch`).

It applies to the default architecture's recurrence: one ``nn.LSTM`` layer for the actor, no critic LSTM, one
minibatch per epoch (``batch_size`` at least the rollout, the default); :func:`lean_update_applies` says whether a
model qualifies. :func:`use_lean_update` swaps a model's ``train`` for it (``train_smc(..., lean_update=True)``).
The recurrence's tanh is :func:`~sb3_smc.common.kernels.fast_tanh` (float32 accuracy, no library call, so the loops
vectorize), and while the lean update trains a model its compiled collection step takes the same tanh
(``SequenceLstmPolicy.lean_collection``).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from functools import cached_property
from typing import Any, NamedTuple, cast

import numpy as np
import torch
from gymnasium import spaces
from numba import njit
from sb3_contrib import RecurrentPPO
from sb3_contrib.common.recurrent.buffers import RecurrentRolloutBuffer
from stable_baselines3.common.distributions import CategoricalDistribution
from stable_baselines3.common.torch_layers import FlattenExtractor, MlpExtractor
from stable_baselines3.common.type_aliases import Schedule
from stable_baselines3.common.utils import explained_variance
from torch import nn

from sb3_smc.common.kernels import fast_tanh
from sb3_smc.common.recurrent.policies import SequenceLstmPolicy
from sb3_smc.common.threads import blas_threads

__all__ = ["lean_train", "lean_update_applies", "use_lean_update"]


@njit(cache=True, fastmath=True, inline="always")
def _axpy(y: np.ndarray, a: float, x: np.ndarray) -> None:  # pragma: no cover
    """``y += a * x``."""
    for j in range(y.shape[0]):
        y[j] += a * x[j]


@njit(cache=True, fastmath=True, error_model="numpy")
def _forward(x: np.ndarray, w_ih_t: np.ndarray, w_hh_t: np.ndarray, bias: np.ndarray, starts: np.ndarray,
             lengths: np.ndarray, h0: np.ndarray, c0: np.ndarray, out_h: np.ndarray, gates: np.ndarray,
             tanh_c: np.ndarray, cells: np.ndarray) -> None:  # pragma: no cover
    """The LSTM over each sequence ``rows starts[s] : starts[s] + lengths[s]`` of the inputs ``x`` from
    ``(h0[s], c0[s])``, skipping zero inputs (a mostly one-hot observation): writes each row's output ``h``
    (``out_h``), its gate activations i, f, g, o (``gates``), its cell and the cell's tanh. The weights transposed
    (``(inputs, 4 n)``), ``bias`` the sum of torch's two."""
    n = h0.shape[1]
    z = np.empty(4 * n)
    h = np.empty(n)
    c = np.empty(n)
    for s in range(starts.shape[0]):
        h[:] = h0[s]
        c[:] = c0[s]
        for t in range(starts[s], starts[s] + lengths[s]):
            z[:] = bias
            x_t = x[t]
            for k in range(x_t.shape[0]):
                if x_t[k] != 0.0:
                    _axpy(z, x_t[k], w_ih_t[k])
            for k in range(n):
                _axpy(z, h[k], w_hh_t[k])
            gate = gates[t]
            for j in range(4 * n):  # sigmoid(z) = 0.5 tanh(z / 2) + 0.5 on i, f, o; tanh on g (overwritten)
                gate[j] = 0.5 * fast_tanh(0.5 * z[j]) + 0.5
            for j in range(2 * n, 3 * n):
                gate[j] = fast_tanh(z[j])
            tc, out = tanh_c[t], out_h[t]
            for j in range(n):
                c[j] = gate[n + j] * c[j] + gate[j] * gate[2 * n + j]
            for j in range(n):
                tc[j] = fast_tanh(c[j])
            for j in range(n):
                h[j] = gate[3 * n + j] * tc[j]
                out[j] = h[j]
            cells[t] = c


@njit(cache=True, fastmath=True, error_model="numpy")
def _backward(grad_h: np.ndarray, x: np.ndarray, w_hh_t: np.ndarray, starts: np.ndarray, lengths: np.ndarray,
              c0: np.ndarray, gates: np.ndarray, tanh_c: np.ndarray, cells: np.ndarray, grad_z: np.ndarray,
              grad_w_ih_t: np.ndarray) -> None:  # pragma: no cover
    """Backpropagation through time of :func:`_forward`: from the loss's gradient at each row's output
    (``grad_h``) writes the gradient at each row's gate pre-activations (``grad_z``) and adds the input weights'
    (transposed) to ``grad_w_ih_t``; the initial states get none (they are rollout data)."""
    n = c0.shape[1]
    dh = np.empty(n)
    dc = np.empty(n)
    for s in range(starts.shape[0]):
        first = starts[s]
        dh[:] = 0.0
        dc[:] = 0.0
        for t in range(first + lengths[s] - 1, first - 1, -1):
            gate, tc, gz, gh = gates[t], tanh_c[t], grad_z[t], grad_h[t]
            c_prev = cells[t - 1] if t > first else c0[s]
            for j in range(n):
                d_h = gh[j] + dh[j]
                d_c = dc[j] + d_h * gate[3 * n + j] * (1.0 - tc[j] * tc[j])
                gz[j] = d_c * gate[2 * n + j] * gate[j] * (1.0 - gate[j])
                gz[n + j] = d_c * c_prev[j] * gate[n + j] * (1.0 - gate[n + j])
                gz[2 * n + j] = d_c * gate[j] * (1.0 - gate[2 * n + j] * gate[2 * n + j])
                gz[3 * n + j] = d_h * tc[j] * gate[3 * n + j] * (1.0 - gate[3 * n + j])
                dc[j] = d_c * gate[n + j]
            for k in range(n):
                w_k, total = w_hh_t[k], 0.0
                for j in range(4 * n):
                    total += w_k[j] * gz[j]
                dh[k] = total
            x_t = x[t]
            for k in range(x_t.shape[0]):
                if x_t[k] != 0.0:
                    _axpy(grad_w_ih_t[k], x_t[k], gz)


class _Sequences:
    """The sequences of one minibatch: flat start rows, lengths, initial states (float64, zeroed where a sequence
    starts an episode)."""

    def __init__(self, cut: np.ndarray, h0: np.ndarray, c0: np.ndarray, resets: np.ndarray) -> None:
        self.starts = np.flatnonzero(cut)
        self.lengths = np.diff(np.append(self.starts, len(cut)))
        keep = 1.0 - resets[self.starts, None]
        self.h0 = h0[self.starts].astype(np.float64) * keep
        self.c0 = c0[self.starts].astype(np.float64) * keep


class _Recurrence(torch.autograd.Function):
    """The LSTM layer's outputs over the sequences of a :class:`_Sequences` (see :func:`_forward`), with the
    gradients of its four parameters."""

    @staticmethod
    def forward(ctx: Any, x: np.ndarray, seqs: _Sequences, w_ih: torch.Tensor, w_hh: torch.Tensor,
                b_ih: torch.Tensor, b_hh: torch.Tensor) -> torch.Tensor:
        rows, n = x.shape[0], w_hh.shape[1]
        w_ih64, w_hh64 = (w.detach().numpy().astype(np.float64) for w in (w_ih, w_hh))
        bias = b_ih.detach().numpy().astype(np.float64) + b_hh.detach().numpy()
        out_h, tanh_c, cells = np.empty((rows, n)), np.empty((rows, n)), np.empty((rows, n))
        gates = np.empty((rows, 4 * n))
        w_hh_t = np.ascontiguousarray(w_hh64.T)
        _forward(x, np.ascontiguousarray(w_ih64.T), w_hh_t, bias, seqs.starts, seqs.lengths, seqs.h0, seqs.c0, out_h,
                 gates, tanh_c, cells)
        ctx.saved = (x, seqs, w_hh_t, out_h, gates, tanh_c, cells)
        return torch.from_numpy(out_h.astype(np.float32))

    @staticmethod
    def backward(ctx: Any, grad_out: torch.Tensor) -> tuple[None, None, torch.Tensor, torch.Tensor, torch.Tensor,
                                                             torch.Tensor]:
        x, seqs, w_hh_t, out_h, gates, tanh_c, cells = ctx.saved
        grad_z = np.empty_like(gates)
        grad_w_ih_t = np.zeros((x.shape[1], gates.shape[1]))
        _backward(grad_out.detach().numpy().astype(np.float64), x, w_hh_t, seqs.starts, seqs.lengths, seqs.c0, gates,
                  tanh_c, cells, grad_z, grad_w_ih_t)
        h_prev = np.empty_like(out_h)  # each row's input state: the row before's output, or its sequence's h0
        h_prev[1:] = out_h[:-1]
        h_prev[seqs.starts] = seqs.h0
        grad_bias = torch.from_numpy(grad_z.sum(axis=0).astype(np.float32))
        return (None, None, torch.from_numpy(grad_w_ih_t.T.astype(np.float32)),
                torch.from_numpy((grad_z.T @ h_prev).astype(np.float32)), grad_bias, grad_bias.clone())


def lean_update_applies(model: Any) -> bool:
    """Whether :func:`lean_train` computes ``model``'s update: a ``RecurrentPPO`` with a :class:`SequenceLstmPolicy`
    whose actor is one ``nn.LSTM`` layer (no projection, with biases), no critic LSTM, flat ``Box`` observations,
    and one minibatch per epoch."""
    if type(model) is not RecurrentPPO or not isinstance(model.rollout_buffer, RecurrentRolloutBuffer):
        return False
    policy = model.policy
    if not isinstance(policy, SequenceLstmPolicy) or type(policy.lstm_actor) is not nn.LSTM:
        return False
    lstm = policy.lstm_actor
    return (lstm.num_layers == 1 and lstm.bias and not lstm.proj_size and not lstm.batch_first
            and policy.lstm_critic is None and not policy.shared_lstm and policy.share_features_extractor
            and type(policy.features_extractor) is FlattenExtractor
            and isinstance(model.observation_space, spaces.Box) and len(model.observation_space.shape) == 1
            and (model.batch_size is None or model.batch_size >= model.n_steps * model.n_envs))


def _flat(buffer: RecurrentRolloutBuffer, name: str) -> np.ndarray:
    """A buffer array in the flat order of ``buffer.get`` (environment after environment), whether or not ``get``
    has already flattened it."""
    array = getattr(buffer, name)
    if buffer.generator_ready:
        return array
    if name.endswith("_states_pi"):  # (n_steps, n_layers, n_envs, hidden) -> (n_steps, n_envs, n_layers, hidden)
        array = array.swapaxes(1, 2)
    return array.swapaxes(0, 1).reshape(buffer.buffer_size * buffer.n_envs, *array.shape[2:])


def _plain_heads(policy: SequenceLstmPolicy) -> bool:
    """Whether the policy's heads are the package's default ones, which :func:`_numpy_epoch` computes: no layers
    after the LSTM (``net_arch=[]``), a linear critic on the features, a categorical distribution, Adam."""
    extractor = policy.mlp_extractor
    return (type(extractor) is MlpExtractor and len(extractor.policy_net) == 0 and len(extractor.value_net) == 0
            and type(policy.critic) is nn.Linear and isinstance(policy.action_dist, CategoricalDistribution)
            and type(policy.optimizer) is torch.optim.Adam)


class _Rollout:
    """What every epoch of an update reads from the rollout buffer, laid out once (rows in ``buffer.get``'s order)."""

    def __init__(self, model: RecurrentPPO, buffer: RecurrentRolloutBuffer) -> None:
        rows = self.rows = buffer.buffer_size * buffer.n_envs
        self.action_space = model.action_space
        self.episode_starts = _flat(buffer, "episode_starts").reshape(rows)
        env_first = np.zeros((buffer.n_envs, buffer.buffer_size), dtype=bool)
        env_first[:, 0] = True
        self.cut = np.logical_or(self.episode_starts != 0.0, env_first.reshape(rows))
        self.h0, self.c0 = _flat(buffer, "hidden_states_pi")[:, 0], _flat(buffer, "cell_states_pi")[:, 0]
        self.x = _flat(buffer, "observations").reshape(rows, -1).astype(np.float32)
        self.actions = _flat(buffer, "actions")
        self.old_values, self.old_log_prob, advantages, self.returns = (
            _flat(buffer, name).reshape(rows).astype(np.float64)
            for name in ("values", "log_probs", "advantages", "returns"))
        if model.normalize_advantage:  # sb3-contrib normalizes over the minibatch: here the whole rollout
            advantages = (advantages - advantages.mean()) / (advantages.std(ddof=1) + 1e-8)
        self.advantages = advantages

    def sequences(self) -> _Sequences:
        """An epoch's sequences: the rollout's cut plus the rotation ``RecurrentRolloutBuffer.get`` draws."""
        epoch_cut = self.cut.copy()
        epoch_cut[np.random.randint(self.rows)] = True
        return _Sequences(epoch_cut, self.h0, self.c0, self.episode_starts)

    @cached_property
    def tensors(self) -> tuple[torch.Tensor, ...]:
        """Observations, actions (``Discrete``: long, else float), old values, old log-probabilities, advantages and
        returns as torch tensors (float32), for the torch heads; made once per update."""
        actions = torch.as_tensor(self.actions)
        discrete = isinstance(self.action_space, spaces.Discrete)
        return (torch.from_numpy(self.x), actions.long().flatten() if discrete else actions.float(),
                *(torch.as_tensor(a, dtype=torch.float32)
                  for a in (self.old_values, self.old_log_prob, self.advantages, self.returns)))


class _Losses(NamedTuple):
    """One epoch's logged values, and how to set the (clipped) gradients of its loss."""

    policy: float
    clip_fraction: float
    value: float
    entropy: float
    total: float
    approx_kl: float
    set_gradients: Callable[[], None]


def _numpy_epoch(model: RecurrentPPO, policy: SequenceLstmPolicy, data: _Rollout, clip_range: float,
                 clip_range_vf: float | None) -> _Losses:
    """An epoch of PPO on the default heads (:func:`_plain_heads`) in float64 numpy, forward and backward written
    out: the LSTM by the compiled kernels, the action and value heads, the clipped surrogate, the value loss (clipped
    if ``clip_range_vf``), the entropy term; the gradients (torch's at ``min`` ties and ``clamp`` bounds) clipped to
    ``max_grad_norm`` as ``clip_grad_norm_`` does."""
    w = {name: p.detach().numpy().astype(np.float64) for name, p in policy.named_parameters()}
    seqs, n_rows = data.sequences(), data.rows
    n = w["lstm_actor.weight_hh_l0"].shape[1]
    out_h, tanh_c, cells, gates = (np.empty((n_rows, n)), np.empty((n_rows, n)), np.empty((n_rows, n)),
                                   np.empty((n_rows, 4 * n)))
    w_hh_t = np.ascontiguousarray(w["lstm_actor.weight_hh_l0"].T)
    _forward(data.x, np.ascontiguousarray(w["lstm_actor.weight_ih_l0"].T), w_hh_t,
             w["lstm_actor.bias_ih_l0"] + w["lstm_actor.bias_hh_l0"], seqs.starts, seqs.lengths, seqs.h0, seqs.c0,
             out_h, gates, tanh_c, cells)
    logits = out_h @ w["action_net.weight"].T + w["action_net.bias"]
    logits -= logits.max(axis=1, keepdims=True)
    log_p = logits - np.log(np.exp(logits).sum(axis=1, keepdims=True))
    p = np.exp(log_p)
    rows, actions = np.arange(n_rows), data.actions.reshape(n_rows).astype(np.int64)
    log_prob = log_p[rows, actions]
    entropy = -(p * log_p).sum(axis=1)
    critic = cast(nn.Linear, policy.critic)  # _plain_heads checked
    latent_vf = (data.x @ critic.weight.detach().numpy().T).astype(np.float64) + w["critic.bias"]
    values = latent_vf @ w["value_net.weight"][0] + w["value_net.bias"][0]

    log_ratio = log_prob - data.old_log_prob
    ratio = np.exp(log_ratio)
    adv = data.advantages
    inside = (ratio >= 1 - clip_range) & (ratio <= 1 + clip_range)
    surrogate, clipped = adv * ratio, adv * np.clip(ratio, 1 - clip_range, 1 + clip_range)
    policy_loss = -float(np.minimum(surrogate, clipped).mean())
    values_pred, value_inside = values, np.ones(n_rows, dtype=bool)
    if clip_range_vf is not None:
        change = values - data.old_values
        values_pred = data.old_values + np.clip(change, -clip_range_vf, clip_range_vf)
        value_inside = (change >= -clip_range_vf) & (change <= clip_range_vf)
    value_loss = float(((data.returns - values_pred) ** 2).mean())
    entropy_loss = -float(entropy.mean())

    def set_gradients() -> None:
        first = np.where(surrogate < clipped, 1.0, np.where(surrogate == clipped, 0.5, 0.0))  # torch.min's split
        grad_log_prob = -adv * ratio * (first + (1.0 - first) * inside) / n_rows
        grad_logits = -grad_log_prob[:, None] * p
        grad_logits[rows, actions] += grad_log_prob
        grad_logits += (model.ent_coef / n_rows) * p * (log_p + entropy[:, None])
        grad_values = model.vf_coef * -2.0 / n_rows * (data.returns - values_pred) * value_inside
        grad_latent_vf = grad_values[:, None] * w["value_net.weight"]
        grad_h = grad_logits @ w["action_net.weight"]
        grad_z, grad_w_ih_t = np.empty_like(gates), np.zeros((data.x.shape[1], 4 * n))
        _backward(grad_h, data.x, w_hh_t, seqs.starts, seqs.lengths, seqs.c0, gates, tanh_c, cells, grad_z,
                  grad_w_ih_t)
        h_prev = np.empty(out_h.shape, dtype=np.float32)  # each row's input state: the row before's output, or
        h_prev[1:] = out_h[:-1]                             # its sequence's h0
        h_prev[seqs.starts] = seqs.h0
        grad_bias = grad_z.sum(axis=0)
        grads = {"action_net.weight": grad_logits.T @ out_h, "action_net.bias": grad_logits.sum(axis=0),
                 "value_net.weight": (grad_values @ latent_vf)[None], "value_net.bias": grad_values.sum(keepdims=True),
                 "lstm_actor.weight_ih_l0": grad_w_ih_t.T,
                 "lstm_actor.weight_hh_l0": grad_z.T.astype(np.float32) @ h_prev,
                 "lstm_actor.bias_ih_l0": grad_bias, "lstm_actor.bias_hh_l0": grad_bias,
                 "critic.weight": grad_latent_vf.T.astype(np.float32) @ data.x,
                 "critic.bias": grad_latent_vf.sum(axis=0)}
        norm = float(np.sqrt(sum(float(np.sum(g * g)) for g in grads.values())))
        scale = min(1.0, model.max_grad_norm / (norm + 1e-6))
        for name, param in policy.named_parameters():
            param.grad = torch.from_numpy((grads[name] * scale).astype(np.float32)) if name in grads else None

    return _Losses(policy_loss, float(np.mean(np.abs(ratio - 1) > clip_range)), value_loss, entropy_loss,
                   policy_loss + model.ent_coef * entropy_loss + model.vf_coef * value_loss,
                   float(np.mean((ratio - 1) - log_ratio)), set_gradients)


def _torch_epoch(model: RecurrentPPO, policy: SequenceLstmPolicy, data: _Rollout, clip_range: float,
                 clip_range_vf: float | None) -> _Losses:
    """An epoch of PPO with the policy's own heads in torch (any ``net_arch``, distribution and optimizer), the
    LSTM by the compiled kernels (:class:`_Recurrence`)."""
    lstm, critic = policy.lstm_actor, cast(nn.Module, policy.critic)
    obs, actions, old_values, old_log_prob, advantages, returns = data.tensors
    features = policy.extract_features(obs)
    hidden = _Recurrence.apply(data.x, data.sequences(), lstm.weight_ih_l0, lstm.weight_hh_l0, lstm.bias_ih_l0,
                               lstm.bias_hh_l0)
    latent_pi = policy.mlp_extractor.forward_actor(hidden)
    latent_vf = policy.mlp_extractor.forward_critic(critic(features))
    values = policy.value_net(latent_vf).flatten()
    distribution = policy._get_action_dist_from_latent(latent_pi)
    log_prob, entropy = distribution.log_prob(actions), distribution.entropy()
    ratio = torch.exp(log_prob - old_log_prob)
    policy_loss = -torch.mean(torch.min(advantages * ratio,
                                        advantages * torch.clamp(ratio, 1 - clip_range, 1 + clip_range)))
    values_pred = values if clip_range_vf is None else old_values + torch.clamp(
        values - old_values, -clip_range_vf, clip_range_vf)
    value_loss = torch.mean((returns - values_pred) ** 2)
    entropy_loss = -torch.mean(-log_prob) if entropy is None else -torch.mean(entropy)
    loss = policy_loss + model.ent_coef * entropy_loss + model.vf_coef * value_loss
    with torch.no_grad():
        log_ratio = log_prob - old_log_prob
        approx_kl = float(torch.mean((torch.exp(log_ratio) - 1) - log_ratio))

    def set_gradients() -> None:
        loss.backward()
        torch.nn.utils.clip_grad_norm_(policy.parameters(), model.max_grad_norm)

    return _Losses(policy_loss.item(), torch.mean((torch.abs(ratio - 1) > clip_range).float()).item(),
                   value_loss.item(), entropy_loss.item(), loss.item(), approx_kl, set_gradients)


def lean_train(model: RecurrentPPO) -> None:
    """``model.train()`` (sb3-contrib's ``RecurrentPPO.train``) with the compiled recurrence: the same update up to
    float rounding, the same draws from numpy's global generator, the same logged values. numpy's BLAS runs it in
    one thread (its matrix products' sums would otherwise depend on the caller's thread count, and the SMC with
    them). ``ValueError`` where :func:`lean_update_applies` is false."""
    if not lean_update_applies(model):
        raise ValueError("lean_train needs a RecurrentPPO with SequenceLstmPolicy's default recurrence (one LSTM "
                         "layer, no critic LSTM) and one minibatch per epoch")
    with blas_threads(1):
        _lean_train(model)


def _lean_train(model: RecurrentPPO) -> None:
    # the types lean_update_applies checked
    policy, buffer = cast(SequenceLstmPolicy, model.policy), cast(RecurrentRolloutBuffer, model.rollout_buffer)
    schedule, schedule_vf = cast(Schedule, model.clip_range), cast("Schedule | None", model.clip_range_vf)
    assert buffer.full, "Rollout buffer must be full before sampling from it"
    policy.set_training_mode(True)
    model._update_learning_rate(policy.optimizer)
    clip_range = schedule(model._current_progress_remaining)
    clip_range_vf = schedule_vf(model._current_progress_remaining) if schedule_vf is not None else None
    data = _Rollout(model, buffer)
    epoch = _numpy_epoch if _plain_heads(policy) else _torch_epoch
    losses: list[_Losses] = []
    for _ in range(model.n_epochs):
        losses.append(epoch(model, policy, data, clip_range, clip_range_vf))
        model._n_updates += 1
        if model.target_kl is not None and losses[-1].approx_kl > 1.5 * model.target_kl:
            if model.verbose >= 1:
                print(f"Early stopping at step {len(losses) - 1} due to reaching max kl: {losses[-1].approx_kl:.2f}")
            break
        policy.optimizer.zero_grad()
        losses[-1].set_gradients()
        policy.optimizer.step()

    explained_var = explained_variance(_flat(buffer, "values").flatten(), _flat(buffer, "returns").flatten())
    logger = model.logger
    logger.record("train/entropy_loss", np.mean([e.entropy for e in losses]))
    logger.record("train/policy_gradient_loss", np.mean([e.policy for e in losses]))
    logger.record("train/value_loss", np.mean([e.value for e in losses]))
    logger.record("train/approx_kl", losses[-1].approx_kl)
    logger.record("train/clip_fraction", np.mean([e.clip_fraction for e in losses]))
    logger.record("train/loss", losses[-1].total)
    logger.record("train/explained_variance", explained_var)
    logger.record("train/n_updates", model._n_updates, exclude="tensorboard")
    logger.record("train/clip_range", clip_range)
    if clip_range_vf is not None:
        logger.record("train/clip_range_vf", clip_range_vf)


@contextmanager
def use_lean_update(model: RecurrentPPO) -> Iterator[None]:
    """Within the block, ``model.train()`` is :func:`lean_train` and the policy's compiled collection step takes the
    lean update's tanh (``policy.lean_collection``); both are instance attributes, removed on leaving, so the model
    saves and loads as a plain ``RecurrentPPO``. ``ValueError`` where :func:`lean_update_applies` is false."""
    if not lean_update_applies(model):
        raise ValueError("the lean update needs a RecurrentPPO with SequenceLstmPolicy's default recurrence (one "
                         "LSTM layer, no critic LSTM) and one minibatch per epoch")
    model.train = lambda: lean_train(model)  # type: ignore[method-assign]
    cast(SequenceLstmPolicy, model.policy).lean_collection = True  # lean_update_applies checked the type
    try:
        yield
    finally:
        del model.train
        del model.policy.lean_collection
