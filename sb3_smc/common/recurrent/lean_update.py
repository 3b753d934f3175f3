"""The lean update: sb3-contrib's ``RecurrentPPO.train``, and RecurrentTRPO's policy step, with the actor's
recurrence compiled (opt-in; equal up to float rounding, not bit for bit).

:func:`lean_train` computes what ``model.train()`` computes for a ``RecurrentPPO``: the same minibatch per epoch
(the buffer's random rotation drawn from numpy as sb3-contrib draws it, so the sequences are cut where the stock
minibatch cuts them), the same losses (clipped surrogate, value loss with ``clip_range_vf`` if set, entropy),
gradient clipping to ``max_grad_norm``, the ``target_kl`` early stop, the same optimizer and the same logged values.
What differs is how the recurrence runs: the rollout is laid out once (sequences cut at environment boundaries and
episode starts; each epoch adds the cut of its rotation), and the recurrence, forward and backward, runs over every
sequence in one compiled (numba) loop in float64 (:mod:`~sb3_smc.common.recurrent.lean_recurrence`), with no padding
and no per-step torch calls. Sums are taken in another order and in float64, so the losses and gradients equal the
stock ones to float rounding (tested to 1e-5 relative on real rollouts); training on them is shown statistically
equal, not bit-identical (``docs/training.md``, "The lean update"). With an LSTM and the package's default heads
(:func:`_plain_heads`: no layers after the LSTM, a linear critic on the features, a categorical distribution, Adam)
the whole epoch is written out, forward and backward, with no autograd graph (:func:`_numpy_epoch`: the heads and
losses compiled too, :func:`ppo_heads`; its large arrays reused from epoch to epoch); a GRU or other heads run in
torch around the compiled recurrence (:func:`_torch_epoch`).
:class:`~sb3_smc.recurrent_trpo.RecurrentTRPO` takes the compiled recurrence in its own policy step (its
``lean_policy_step``).

It applies to the default architecture's recurrence: one ``nn.LSTM`` or GRU layer for the actor, no critic LSTM,
and, for PPO, one minibatch per epoch (``batch_size`` at least the rollout, the default); :func:`lean_update_applies`
says whether a model qualifies. :func:`use_lean_update` switches a model to it (``train_smc(..., lean_update=True)``).
The recurrence's tanh is :func:`~sb3_smc.common.kernels.fast_tanh` (float32 accuracy, no library call, so the loops
vectorize), and while the lean update trains a model its compiled collection step takes the same tanh
(``SequenceLstmPolicy.lean_collection``).
"""

from __future__ import annotations

import threading
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

from sb3_smc.common.recurrent.buffers import CompactRecurrentRolloutBuffer
from sb3_smc.common.recurrent.lean_recurrence import (
    Sequences,
    SparseRows,
    compiled_layer,
    lstm_backward,
    lstm_forward,
    recurrence,
)
from sb3_smc.common.recurrent.policies import SequenceLstmPolicy
from sb3_smc.common.threads import blas_threads

__all__ = ["LEAN_UPDATE_NEEDS", "lean_train", "lean_update_applies", "ppo_heads", "use_lean_update"]

LEAN_UPDATE_NEEDS = ("RecurrentPPO or RecurrentTRPO with one LSTM or GRU layer for the actor, no critic LSTM, flat "
                     "observations and, for RecurrentPPO, one minibatch per epoch")
"""What :func:`lean_update_applies` checks, in words (for error messages)."""


def lean_update_applies(model: Any) -> bool:
    """Whether the lean update computes ``model``'s update: a ``RecurrentPPO`` with one minibatch per epoch
    (:func:`lean_train`), or a :class:`~sb3_smc.recurrent_trpo.RecurrentTRPO` (any class with a
    ``lean_policy_step``) with the compact rollout buffer; with a :class:`SequenceLstmPolicy` (or its GRU variant)
    whose actor is one LSTM or GRU layer (no projection, with biases), no critic LSTM, flat ``Box`` observations."""
    if not isinstance(model, RecurrentPPO) or not isinstance(model.rollout_buffer, RecurrentRolloutBuffer):
        return False
    ppo = type(model) is RecurrentPPO
    if not ppo and not (hasattr(type(model), "lean_policy_step")
                        and isinstance(model.rollout_buffer, CompactRecurrentRolloutBuffer)):
        return False
    policy = model.policy
    if not isinstance(policy, SequenceLstmPolicy) or not compiled_layer(policy.lstm_actor):
        return False
    return (policy.lstm_critic is None and not policy.shared_lstm and policy.share_features_extractor
            and type(policy.features_extractor) is FlattenExtractor
            and isinstance(model.observation_space, spaces.Box) and len(model.observation_space.shape) == 1
            and (not ppo or model.batch_size is None or model.batch_size >= model.n_steps * model.n_envs))


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
    """Whether :func:`_numpy_epoch` computes the policy's epoch: an LSTM actor and the package's default heads (no
    layers after the LSTM, ``net_arch=[]``; a linear critic on the features; a categorical distribution; Adam)."""
    extractor = policy.mlp_extractor
    return (type(policy.lstm_actor) is nn.LSTM and type(extractor) is MlpExtractor and len(extractor.policy_net) == 0
            and len(extractor.value_net) == 0
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
        self.sparse = SparseRows.of(self.x)
        self.actions = _flat(buffer, "actions")
        self.old_values, self.old_log_prob, advantages, self.returns = (
            _flat(buffer, name).reshape(rows).astype(np.float64)
            for name in ("values", "log_probs", "advantages", "returns"))
        if model.normalize_advantage:  # sb3-contrib normalizes over the minibatch: here the whole rollout
            advantages = (advantages - advantages.mean()) / (advantages.std(ddof=1) + 1e-8)
        self.advantages = advantages

    def sequences(self) -> Sequences:
        """An epoch's sequences: the rollout's cut plus the rotation ``RecurrentRolloutBuffer.get`` draws."""
        epoch_cut = self.cut.copy()
        epoch_cut[np.random.randint(self.rows)] = True
        return Sequences.cut(epoch_cut, self.h0, self.c0, self.episode_starts)

    @cached_property
    def int_actions(self) -> np.ndarray:
        """A ``Discrete`` action space's actions as int64, one per row."""
        return self.actions.reshape(self.rows).astype(np.int64)

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
    set_gradients: Callable[[], None]  #: sets every parameter's ``grad`` (``None`` where it has none)


@njit(cache=True, fastmath={"reassoc", "contract", "nsz", "arcp"}, error_model="numpy")
def ppo_heads(out_h: np.ndarray, ptr: np.ndarray, idx: np.ndarray, val: np.ndarray, w_action: np.ndarray,
              b_action: np.ndarray, w_critic_t: np.ndarray, b_critic: np.ndarray, w_value: np.ndarray, b_value: float,
              actions: np.ndarray, old_log_prob: np.ndarray, old_values: np.ndarray, advantages: np.ndarray,
              returns: np.ndarray, clip_range: float, clip_range_vf: float, ent_coef: float, vf_coef: float,
              grad_h: np.ndarray, grad_w_action: np.ndarray, grad_b_action: np.ndarray, grad_w_critic_t: np.ndarray,
              grad_b_critic: np.ndarray, grad_w_value: np.ndarray) -> np.ndarray:  # pragma: no cover
    """PPO's loss on the default heads, forward and backward, row by row in float64: a categorical policy on the
    LSTM's outputs ``out_h`` (``w_action``, ``b_action``), a linear critic on the inputs (their non-zero entries
    ``ptr``, ``idx``, ``val``: :class:`~sb3_smc.common.recurrent.lean_recurrence.SparseRows`; ``w_critic_t``
    transposed) then a linear value (``w_value``, ``b_value``); the clipped surrogate, the value loss
    (clipped where ``clip_range_vf >= 0``), the entropy term. Writes the loss's gradient at each output row
    (``grad_h``) and the heads' weight gradients (torch's at ``min`` ties and ``clamp`` bounds; into zeroed
    arrays); returns the sums over rows of the surrogate's minimum, the clipped rows, the squared value error, the
    entropy, ``ratio - 1 - log ratio`` and the value head's bias gradient."""
    rows, hidden = out_h.shape
    n_actions, width = w_action.shape[0], w_critic_t.shape[1]
    sums = np.zeros(6)
    logits, probabilities = np.empty(n_actions), np.empty(n_actions)
    latent = np.empty(width)
    for r in range(rows):
        h = out_h[r]
        top = -np.inf
        for a in range(n_actions):
            total = b_action[a]
            for j in range(hidden):
                total += w_action[a, j] * h[j]
            logits[a] = total
            top = max(top, total)
        norm = 0.0
        for a in range(n_actions):
            logits[a] -= top
            norm += np.exp(logits[a])
        log_norm = np.log(norm)
        entropy = 0.0
        for a in range(n_actions):  # logits become log-probabilities
            logits[a] -= log_norm
            probabilities[a] = np.exp(logits[a])
            entropy -= probabilities[a] * logits[a]
        action = actions[r]
        latent[:] = b_critic
        for e in range(ptr[r], ptr[r + 1]):
            k, v = idx[e], val[e]
            for m in range(width):
                latent[m] += v * w_critic_t[k, m]
        value = b_value
        for m in range(width):
            value += latent[m] * w_value[m]

        log_ratio = logits[action] - old_log_prob[r]
        ratio = np.exp(log_ratio)
        adv = advantages[r]
        inside = 1.0 if 1.0 - clip_range <= ratio <= 1.0 + clip_range else 0.0
        surrogate, clipped = adv * ratio, adv * min(max(ratio, 1.0 - clip_range), 1.0 + clip_range)
        sums[0] += min(surrogate, clipped)
        if abs(ratio - 1.0) > clip_range:
            sums[1] += 1.0
        value_pred, value_inside = value, 1.0
        if clip_range_vf >= 0.0:
            change = value - old_values[r]
            value_pred = old_values[r] + min(max(change, -clip_range_vf), clip_range_vf)
            value_inside = 1.0 if -clip_range_vf <= change <= clip_range_vf else 0.0
        error = returns[r] - value_pred
        sums[2] += error * error
        sums[3] += entropy
        sums[4] += (ratio - 1.0) - log_ratio

        first = 1.0 if surrogate < clipped else (0.5 if surrogate == clipped else 0.0)  # torch.min's split
        grad_log_prob = -adv * ratio * (first + (1.0 - first) * inside) / rows
        g_h = grad_h[r]
        g_h[:] = 0.0
        for a in range(n_actions):
            p = probabilities[a]
            g = -grad_log_prob * p + (ent_coef / rows) * p * (logits[a] + entropy)
            if a == action:
                g += grad_log_prob
            grad_b_action[a] += g
            for j in range(hidden):
                g_h[j] += g * w_action[a, j]
                grad_w_action[a, j] += g * h[j]
        grad_value = vf_coef * -2.0 / rows * error * value_inside
        sums[5] += grad_value
        for m in range(width):
            grad_w_value[m] += grad_value * latent[m]
            grad_b_critic[m] += grad_value * w_value[m]
        for e in range(ptr[r], ptr[r + 1]):
            k, v = idx[e], val[e] * grad_value
            for m in range(width):
                grad_w_critic_t[k, m] += v * w_value[m]
    return sums


_SCRATCH = threading.local()


def _scratch(rows: int, n: int) -> tuple[np.ndarray, ...]:
    """The float64 arrays an epoch of :func:`_numpy_epoch` writes (the LSTM's outputs, cell tanh, cells and gates,
    the gradients at its outputs and gates), made once per thread and shape and reused by every epoch: a fresh set
    each epoch was freshly mapped memory whose first writes page faulted (about 1,650 times an update in a group)."""
    cache: dict[tuple[int, int], tuple[np.ndarray, ...]] = _SCRATCH.__dict__.setdefault("arrays", {})
    if (rows, n) not in cache:
        cache[(rows, n)] = (np.empty((rows, n)), np.empty((rows, n)), np.empty((rows, n)), np.empty((rows, 4 * n)),
                            np.empty((rows, n)), np.empty((rows, 4 * n)))
    return cache[(rows, n)]


def _numpy_epoch(model: RecurrentPPO, policy: SequenceLstmPolicy, data: _Rollout, clip_range: float,
                 clip_range_vf: float | None) -> _Losses:
    """An epoch of PPO on the default heads (:func:`_plain_heads`) in float64, forward and backward written out,
    with no autograd graph: the LSTM by the compiled recurrence, the heads and losses by :func:`ppo_heads`; the
    gradients clipped to ``max_grad_norm`` as ``clip_grad_norm_`` does."""
    w = {name: p.detach().numpy().astype(np.float64) for name, p in policy.named_parameters()}
    seqs, n_rows = data.sequences(), data.rows
    n = w["lstm_actor.weight_hh_l0"].shape[1]
    out_h, tanh_c, cells, gates, grad_h, grad_z = _scratch(n_rows, n)
    w_hh_t = np.ascontiguousarray(w["lstm_actor.weight_hh_l0"].T)
    lstm_forward(*data.sparse, np.ascontiguousarray(w["lstm_actor.weight_ih_l0"].T), w_hh_t,
                 w["lstm_actor.bias_ih_l0"] + w["lstm_actor.bias_hh_l0"], seqs.starts, seqs.lengths, seqs.h0, seqs.c0,
                 out_h, gates, tanh_c, cells)
    grads = {name: np.zeros_like(w[name]) for name in ("action_net.weight", "action_net.bias", "critic.bias",
                                                       "value_net.weight")}
    grad_w_critic_t = np.zeros(w["critic.weight"].shape[::-1])
    sums = ppo_heads(out_h, *data.sparse, w["action_net.weight"], w["action_net.bias"],
                     np.ascontiguousarray(w["critic.weight"].T), w["critic.bias"], w["value_net.weight"][0],
                     float(w["value_net.bias"][0]), data.int_actions, data.old_log_prob, data.old_values,
                     data.advantages, data.returns, clip_range, -1.0 if clip_range_vf is None else clip_range_vf,
                     model.ent_coef, model.vf_coef, grad_h, grads["action_net.weight"], grads["action_net.bias"],
                     grad_w_critic_t, grads["critic.bias"], grads["value_net.weight"][0])
    policy_loss, value_loss, entropy_loss = -sums[0] / n_rows, sums[2] / n_rows, -sums[3] / n_rows

    def set_gradients() -> None:
        grad_w_ih_t = np.zeros((data.x.shape[1], 4 * n))
        lstm_backward(grad_h, *data.sparse, w_hh_t, seqs.starts, seqs.lengths, seqs.c0, gates, tanh_c, cells, grad_z,
                      grad_w_ih_t)
        grad_bias = grad_z.sum(axis=0)
        grads.update({"value_net.bias": sums[5:6], "critic.weight": grad_w_critic_t.T,
                      "lstm_actor.weight_ih_l0": grad_w_ih_t.T,
                      "lstm_actor.weight_hh_l0": grad_z.T.astype(np.float32) @ seqs.input_states(out_h, np.float32),
                      "lstm_actor.bias_ih_l0": grad_bias, "lstm_actor.bias_hh_l0": grad_bias})
        norm = float(np.sqrt(sum(float(np.sum(g * g)) for g in grads.values())))
        scale = min(1.0, model.max_grad_norm / (norm + 1e-6))
        for name, param in policy.named_parameters():
            param.grad = torch.from_numpy((grads[name] * scale).astype(np.float32)) if name in grads else None

    return _Losses(policy_loss, sums[1] / n_rows, value_loss, entropy_loss,
                   policy_loss + model.ent_coef * entropy_loss + model.vf_coef * value_loss, sums[4] / n_rows,
                   set_gradients)


def _torch_epoch(model: RecurrentPPO, policy: SequenceLstmPolicy, data: _Rollout, clip_range: float,
                 clip_range_vf: float | None) -> _Losses:
    """An epoch of PPO with the policy's own heads in torch (any ``net_arch``, distribution and optimizer), the
    recurrence compiled (:func:`~sb3_smc.common.recurrent.lean_recurrence.recurrence`)."""
    critic = cast(nn.Module, policy.critic)
    obs, actions, old_values, old_log_prob, advantages, returns = data.tensors
    features = policy.extract_features(obs)
    hidden = recurrence(policy.lstm_actor, data.x, data.sequences(), data.sparse)
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
        policy.optimizer.zero_grad()
        loss.backward()
        torch.nn.utils.clip_grad_norm_(policy.parameters(), model.max_grad_norm)

    return _Losses(policy_loss.item(), torch.mean((torch.abs(ratio - 1) > clip_range).float()).item(),
                   value_loss.item(), entropy_loss.item(), loss.item(), approx_kl, set_gradients)


def lean_train(model: RecurrentPPO) -> None:
    """``model.train()`` (sb3-contrib's ``RecurrentPPO.train``) with the compiled recurrence: the same update up to
    float rounding, the same draws from numpy's global generator, the same logged values. numpy's BLAS runs it in
    one thread (its matrix products' sums would otherwise depend on the caller's thread count, and the SMC with
    them). ``ValueError`` where :func:`lean_update_applies` is false."""
    if type(model) is not RecurrentPPO or not lean_update_applies(model):
        raise ValueError(f"lean_train needs a RecurrentPPO that the lean update applies to: {LEAN_UPDATE_NEEDS}")
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
    """Within the block, ``model`` trains with the lean update: a ``RecurrentPPO``'s ``train()`` is :func:`lean_train`,
    a RecurrentTRPO's ``lean_policy_step`` is true, and the policy's compiled collection step takes the lean update's
    tanh (``policy.lean_collection``). All are instance attributes, removed on leaving, and ``model.save`` leaves
    them out within the block too (a checkpoint callback's), so the model saves and loads as a plain one.
    ``ValueError`` where :func:`lean_update_applies` is false."""
    if not lean_update_applies(model):
        raise ValueError(f"the lean update needs {LEAN_UPDATE_NEEDS}")
    switch = "train" if type(model) is RecurrentPPO else "lean_policy_step"  # else a RecurrentTRPO (checked above)
    excluded = model._excluded_save_params
    setattr(model, switch, (lambda: lean_train(model)) if switch == "train" else True)
    model._excluded_save_params = lambda: [*excluded(), switch, "_excluded_save_params"]  # type: ignore[method-assign]
    cast(SequenceLstmPolicy, model.policy).lean_collection = True  # lean_update_applies checked the type
    try:
        yield
    finally:
        delattr(model, switch)
        del model._excluded_save_params
        del model.policy.lean_collection
