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
"The lean update").

It applies to the default architecture's recurrence: one ``nn.LSTM`` layer for the actor, no critic LSTM, one
minibatch per epoch (``batch_size`` at least the rollout, the default); :func:`lean_update_applies` says whether a
model qualifies. :func:`use_lean_update` swaps a model's ``train`` for it (``train_smc(..., lean_update=True)``).
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any, cast

import numpy as np
import torch
from gymnasium import spaces
from numba import njit
from sb3_contrib import RecurrentPPO
from sb3_contrib.common.recurrent.buffers import RecurrentRolloutBuffer
from stable_baselines3.common.torch_layers import FlattenExtractor
from stable_baselines3.common.type_aliases import Schedule
from stable_baselines3.common.utils import explained_variance
from torch import nn

from sb3_smc.common.recurrent.policies import SequenceLstmPolicy

__all__ = ["lean_train", "lean_update_applies", "use_lean_update"]


@njit(cache=True, inline="always", error_model="numpy")
def _tanh(x: float) -> float:  # pragma: no cover
    """``tanh(x)`` to float32 accuracy (absolute error below 3e-7) without a library call, so the loops around it
    vectorize: Eigen's rational approximation (``ptanh_float``), clamped to +-7.905."""
    x = 7.90531110763549805 if x > 7.90531110763549805 else (-7.90531110763549805 if x < -7.90531110763549805 else x)
    x2 = x * x
    p = x2 * -2.76076847742355e-16 + 2.00018790482477e-13
    p = p * x2 + -8.60467152213735e-11
    p = p * x2 + 5.12229709037114e-08
    p = p * x2 + 1.48572235717979e-05
    p = p * x2 + 6.37261928875436e-04
    p = p * x2 + 4.89352455891786e-03
    q = x2 * 1.19825839466702e-06 + 1.18534705686654e-04
    q = q * x2 + 2.26843463243900e-03
    q = q * x2 + 4.89352518554385e-03
    return x * p / q


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
                gate[j] = 0.5 * _tanh(0.5 * z[j]) + 0.5
            for j in range(2 * n, 3 * n):
                gate[j] = _tanh(z[j])
            tc, out = tanh_c[t], out_h[t]
            for j in range(n):
                c[j] = gate[n + j] * c[j] + gate[j] * gate[2 * n + j]
            for j in range(n):
                tc[j] = _tanh(c[j])
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


def lean_train(model: RecurrentPPO) -> None:
    """``model.train()`` (sb3-contrib's ``RecurrentPPO.train``) with the compiled recurrence: the same update up to
    float rounding, the same draws from numpy's global generator, the same logged values. ``ValueError`` where
    :func:`lean_update_applies` is false."""
    if not lean_update_applies(model):
        raise ValueError("lean_train needs a RecurrentPPO with SequenceLstmPolicy's default recurrence (one LSTM "
                         "layer, no critic LSTM) and one minibatch per epoch")
    # the types lean_update_applies checked
    policy, buffer = cast(SequenceLstmPolicy, model.policy), cast(RecurrentRolloutBuffer, model.rollout_buffer)
    lstm, critic = policy.lstm_actor, cast(nn.Module, policy.critic)
    schedule, schedule_vf = cast(Schedule, model.clip_range), cast("Schedule | None", model.clip_range_vf)
    assert buffer.full, "Rollout buffer must be full before sampling from it"
    policy.set_training_mode(True)
    model._update_learning_rate(policy.optimizer)
    clip_range = schedule(model._current_progress_remaining)
    clip_range_vf = schedule_vf(model._current_progress_remaining) if schedule_vf is not None else None

    rows = buffer.buffer_size * buffer.n_envs
    episode_starts = _flat(buffer, "episode_starts").reshape(rows)
    env_first = np.zeros((buffer.n_envs, buffer.buffer_size), dtype=bool)
    env_first[:, 0] = True
    cut = np.logical_or(episode_starts != 0.0, env_first.reshape(rows))
    h0, c0 = _flat(buffer, "hidden_states_pi")[:, 0], _flat(buffer, "cell_states_pi")[:, 0]
    x = _flat(buffer, "observations").reshape(rows, -1).astype(np.float32)
    obs = torch.from_numpy(x)
    actions = torch.as_tensor(_flat(buffer, "actions"))
    actions = actions.long().flatten() if isinstance(model.action_space, spaces.Discrete) else actions.float()
    old_values, old_log_prob, advantages_raw, returns = (
        torch.as_tensor(_flat(buffer, name).reshape(rows), dtype=torch.float32)
        for name in ("values", "log_probs", "advantages", "returns"))

    entropy_losses: list[float] = []
    pg_losses, value_losses = [], []
    clip_fractions = []
    approx_kl_divs: list[Any] = []
    continue_training = True
    loss = torch.zeros(())
    for epoch in range(model.n_epochs):
        approx_kl_divs = []
        split = np.random.randint(rows)  # the rotation RecurrentRolloutBuffer.get draws: a sequence is cut there
        epoch_cut = cut.copy()
        epoch_cut[split] = True
        seqs = _Sequences(epoch_cut, h0, c0, episode_starts)

        features = policy.extract_features(obs)
        hidden = _Recurrence.apply(x, seqs, lstm.weight_ih_l0, lstm.weight_hh_l0, lstm.bias_ih_l0, lstm.bias_hh_l0)
        latent_pi = policy.mlp_extractor.forward_actor(hidden)
        latent_vf = policy.mlp_extractor.forward_critic(critic(features))
        values = policy.value_net(latent_vf).flatten()
        distribution = policy._get_action_dist_from_latent(latent_pi)
        log_prob, entropy = distribution.log_prob(actions), distribution.entropy()

        advantages = advantages_raw
        if model.normalize_advantage:
            advantages = (advantages - advantages.mean()) / (advantages.std() + 1e-8)
        ratio = torch.exp(log_prob - old_log_prob)
        policy_loss_1 = advantages * ratio
        policy_loss_2 = advantages * torch.clamp(ratio, 1 - clip_range, 1 + clip_range)
        policy_loss = -torch.mean(torch.min(policy_loss_1, policy_loss_2))
        pg_losses.append(policy_loss.item())
        clip_fractions.append(torch.mean((torch.abs(ratio - 1) > clip_range).float()).item())
        values_pred = values if clip_range_vf is None else old_values + torch.clamp(
            values - old_values, -clip_range_vf, clip_range_vf)
        value_loss = torch.mean((returns - values_pred) ** 2)
        value_losses.append(value_loss.item())
        entropy_loss = -torch.mean(-log_prob) if entropy is None else -torch.mean(entropy)
        entropy_losses.append(entropy_loss.item())
        loss = policy_loss + model.ent_coef * entropy_loss + model.vf_coef * value_loss

        with torch.no_grad():
            log_ratio = log_prob - old_log_prob
            approx_kl_div = torch.mean((torch.exp(log_ratio) - 1) - log_ratio).cpu().numpy()
            approx_kl_divs.append(approx_kl_div)
        if model.target_kl is not None and approx_kl_div > 1.5 * model.target_kl:
            continue_training = False
            if model.verbose >= 1:
                print(f"Early stopping at step {epoch} due to reaching max kl: {approx_kl_div:.2f}")
        else:
            policy.optimizer.zero_grad()
            loss.backward()
            torch.nn.utils.clip_grad_norm_(policy.parameters(), model.max_grad_norm)
            policy.optimizer.step()
        model._n_updates += 1
        if not continue_training:
            break

    explained_var = explained_variance(_flat(buffer, "values").flatten(), _flat(buffer, "returns").flatten())
    logger = model.logger
    logger.record("train/entropy_loss", np.mean(entropy_losses))
    logger.record("train/policy_gradient_loss", np.mean(pg_losses))
    logger.record("train/value_loss", np.mean(value_losses))
    logger.record("train/approx_kl", np.mean(approx_kl_divs))
    logger.record("train/clip_fraction", np.mean(clip_fractions))
    logger.record("train/loss", loss.item())
    logger.record("train/explained_variance", explained_var)
    logger.record("train/n_updates", model._n_updates, exclude="tensorboard")
    logger.record("train/clip_range", clip_range)
    if clip_range_vf is not None:
        logger.record("train/clip_range_vf", clip_range_vf)


@contextmanager
def use_lean_update(model: RecurrentPPO) -> Iterator[None]:
    """Within the block, ``model.train()`` is :func:`lean_train` (an instance attribute, removed on leaving, so
    the model saves and loads as a plain ``RecurrentPPO``). ``ValueError`` where :func:`lean_update_applies` is
    false."""
    if not lean_update_applies(model):
        raise ValueError("the lean update needs a RecurrentPPO with SequenceLstmPolicy's default recurrence (one "
                         "LSTM layer, no critic LSTM) and one minibatch per epoch")
    model.train = lambda: lean_train(model)  # type: ignore[method-assign]
    try:
        yield
    finally:
        del model.train
