"""Recurrent TRPO: sb3-contrib's TRPO update on recurrent (LSTM or GRU) policies, over whole-episode sequences.

The paper trained GRU-32 policies with rllab's NPO (docs/design.md). sb3-contrib's ``TRPO`` is feed-forward
and its ``RecurrentPPO`` has no trust region. :class:`RecurrentTRPO` collects rollouts like ``RecurrentPPO``
(recurrent states, episode starts, ``predict`` with state) and updates like ``TRPO``: the surrogate objective and
the mean KL between the old and the new policy are computed over the whole batch with the recurrent policy run
along each episode (the fast sequence pass of :class:`~sb3_smc.common.recurrent.SequenceLstmPolicy`); the
natural-gradient direction comes from conjugate gradient on Fisher-vector products (the Gauss-Newton form of the
KL's Hessian: a central difference of the logits and one backward pass, :meth:`RecurrentTRPO.fisher_vector_product`);
a backtracking line search accepts the largest step with KL below ``target_kl`` (0.01, the paper's step size) that
improves the surrogate, and reverts otherwise. The critic is fitted afterwards, or replaced by the linear feature
baseline of the paper (``baseline="linear_feature"``, rllab's ``LinearFeatureBaseline``).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from contextlib import nullcontext
from functools import partial
from typing import TYPE_CHECKING, Any, ClassVar, TypeVar, cast

import numpy as np
import torch
from sb3_contrib import RecurrentPPO
from stable_baselines3.common.utils import explained_variance
from torch.distributions import Categorical, kl_divergence
from torch.nn import functional as F

from sb3_smc.common.recurrent import SequenceGruPolicy, SequenceLstmPolicy, use_compact_buffer
from sb3_smc.common.recurrent.lean_recurrence import Sequences, SparseRows, recurrence
from sb3_smc.common.threads import blas_threads
from sb3_smc.errors import SMCError, SMCTypeError

if TYPE_CHECKING:
    from stable_baselines3.common.type_aliases import GymEnv, MaybeCallback

__all__ = ["BASELINES", "LinearFeatureBaseline", "RecurrentTRPO"]

SelfRecurrentTRPO = TypeVar("SelfRecurrentTRPO", bound="RecurrentTRPO")
BASELINES = ("critic", "linear_feature")
_UNPACKED = "RNN module weights are not part of single contiguous chunk"  # torch's warning on a cuDNN call


class LinearFeatureBaseline:
    """rllab's ``LinearFeatureBaseline``: values linear in ``[o, o^2, t, t^2, t^3, 1]`` (observation clipped to
    [-10, 10], ``t`` = step in the episode / 100), fitted to the returns of the last batch by ridge-regularised
    least squares (the regulariser grows tenfold until the solution is finite). Predicts zeros before the first
    fit."""

    def __init__(self, reg_coeff: float = 1e-5) -> None:
        self.reg_coeff = float(reg_coeff)
        self.coefficients: np.ndarray | None = None

    @staticmethod
    def features(observations: np.ndarray, steps: np.ndarray) -> np.ndarray:
        o = np.clip(np.asarray(observations, dtype=np.float64).reshape(len(observations), -1), -10, 10)
        t = np.asarray(steps, dtype=np.float64).reshape(-1, 1) / 100.0
        return np.concatenate([o, o ** 2, t, t ** 2, t ** 3, np.ones_like(t)], axis=1)

    def predict(self, observations: np.ndarray, steps: np.ndarray) -> np.ndarray:
        if self.coefficients is None:
            return np.zeros(len(observations))
        return self.features(observations, steps) @ self.coefficients

    def fit(self, observations: np.ndarray, steps: np.ndarray, returns: np.ndarray) -> None:
        x = self.features(observations, steps)
        gram, target = x.T @ x, x.T @ np.asarray(returns, dtype=np.float64).reshape(-1)
        reg = self.reg_coeff
        for _ in range(5):
            solution = np.linalg.lstsq(gram + reg * np.eye(len(gram)), target, rcond=None)[0]
            if np.all(np.isfinite(solution)):
                self.coefficients = solution
                return
            reg *= 10



def conjugate_gradient(matrix_vector_dot: Callable[[torch.Tensor], torch.Tensor], b: torch.Tensor,
                       max_iter: int = 10, residual_tol: float = 1e-10) -> torch.Tensor:
    """An approximate solution of ``A x = b`` (``matrix_vector_dot(v)`` is ``A v``): sb3-contrib's
    ``conjugate_gradient_solver``, the same arithmetic and random start, so the same ``x`` wherever that one ends
    finite, but it returns its last finite iterate where a step would not be finite. The finite-difference Fisher
    product of a long recurrent batch can lose its curvature in float32 (``p·Ap`` shrinking to 0 as ``p`` grows):
    sb3-contrib's solver then returns NaN and the update raises on NaN logits; the line search judges the finite
    direction instead (it takes a step only if the exact KL and the surrogate allow)."""
    x = 1e-4 * torch.randn_like(b)
    residual = b - matrix_vector_dot(x)
    residual_squared_norm = torch.matmul(residual, residual)
    if residual_squared_norm < residual_tol:
        return x
    p = residual.clone()
    for i in range(max_iter):
        a_dot_p = matrix_vector_dot(p)
        alpha = residual_squared_norm / p.dot(a_dot_p)
        stepped = x + alpha * p
        if not bool(torch.isfinite(stepped).all()):
            return x
        x = stepped
        if i == max_iter - 1:
            return x
        residual -= alpha * a_dot_p
        new_residual_squared_norm = torch.matmul(residual, residual)
        if new_residual_squared_norm < residual_tol:
            return x
        beta = new_residual_squared_norm / residual_squared_norm
        residual_squared_norm = new_residual_squared_norm
        p = residual + beta * p
    return x

class RecurrentTRPO(RecurrentPPO):
    """TRPO with a recurrent policy (``"MlpLstmPolicy"`` or ``"MlpGruPolicy"``), sb3-contrib style.

    :param target_kl: the trust region: the mean KL between old and new policy after a step (0.01)
    :param cg_max_steps: conjugate-gradient iterations for the step direction
    :param cg_damping: damping added to the Fisher-vector products
    :param line_search_shrinking_factor: step shrinking per backtracking iteration
    :param line_search_max_iter: backtracking iterations before the step is abandoned
    :param n_critic_updates: passes over the batch (in minibatches of ``batch_size``) fitting the critic
    :param normalize_advantage: normalise the advantages of each batch
    :param baseline: ``"critic"`` (the policy's value head, trained by regression on the returns) or
        ``"linear_feature"`` (:class:`LinearFeatureBaseline`, the paper's; the value head is then not used)
    :param learning_rate: the critic's learning rate (the policy moves by the natural gradient)

    Other arguments are ``RecurrentPPO``'s (``n_steps``, ``batch_size``, ``gamma``, ``gae_lambda``,
    ``policy_kwargs``, ``seed``, ...). Learning, saving, loading and ``predict`` (with recurrent state and
    episode starts) work as for ``RecurrentPPO``.
    """

    policy_aliases: ClassVar[dict[str, type]] = {"MlpLstmPolicy": SequenceLstmPolicy, "MlpGruPolicy": SequenceGruPolicy}
    #: Whether the policy step runs the actor's recurrence compiled
    #: (:func:`~sb3_smc.common.recurrent.lean_recurrence.recurrence`: equal up to float rounding, faster); set by
    #: :func:`~sb3_smc.common.recurrent.lean_update.use_lean_update`.
    lean_policy_step: bool = False
    target_kl: float  # never None here (checked > 0), unlike RecurrentPPO's
    policy: SequenceLstmPolicy  # checked by _setup_model

    def __init__(self, policy: str | type[SequenceLstmPolicy], env: GymEnv | str, learning_rate: float = 1e-3,
                 n_steps: int = 2048, batch_size: int | None = None, gamma: float = 0.99, gae_lambda: float = 0.95,
                 cg_max_steps: int = 15, cg_damping: float = 0.1, line_search_shrinking_factor: float = 0.8,
                 line_search_max_iter: int = 10, n_critic_updates: int = 10, normalize_advantage: bool = True,
                 target_kl: float = 0.01, baseline: str = "critic", stats_window_size: int = 100,
                 tensorboard_log: str | None = None, policy_kwargs: dict[str, Any] | None = None, verbose: int = 0,
                 seed: int | None = None, device: torch.device | str = "auto", _init_setup_model: bool = True
                 ) -> None:
        if baseline not in BASELINES:
            raise SMCError(f"baseline must be one of {BASELINES}, got {baseline!r}")
        if not target_kl > 0:
            raise SMCError(f"target_kl must be > 0, got {target_kl}")
        self.cg_max_steps = cg_max_steps
        self.cg_damping = cg_damping
        self.line_search_shrinking_factor = line_search_shrinking_factor
        self.line_search_max_iter = line_search_max_iter
        self.n_critic_updates = n_critic_updates
        self.baseline = baseline
        self.linear_baseline = LinearFeatureBaseline() if baseline == "linear_feature" else None
        self._episode_steps: np.ndarray | None = None
        super().__init__(policy, env, learning_rate=learning_rate, n_steps=n_steps,
                         batch_size=batch_size or n_steps * env_count(env), n_epochs=1, gamma=gamma,
                         gae_lambda=gae_lambda, normalize_advantage=normalize_advantage, target_kl=target_kl,
                         stats_window_size=stats_window_size, tensorboard_log=tensorboard_log,
                         policy_kwargs=policy_kwargs, verbose=verbose, seed=seed, device=device,
                         _init_setup_model=False)
        if _init_setup_model:
            self._setup_model()

    def _setup_model(self) -> None:
        super()._setup_model()
        if not isinstance(self.policy, SequenceLstmPolicy):
            raise SMCTypeError(f"RecurrentTRPO needs a SequenceLstmPolicy or SequenceGruPolicy (\"MlpLstmPolicy\" / "
                               f"\"MlpGruPolicy\"), got {type(self.policy).__name__}")
        use_compact_buffer(self)

    # ------------------------------------------------------------------------------------ the linear baseline

    def collect_rollouts(self, env, callback, rollout_buffer, n_rollout_steps: int) -> bool:
        if self.linear_baseline is None:
            return super().collect_rollouts(env, callback, rollout_buffer, n_rollout_steps)
        if self._episode_steps is None:
            self._episode_steps = np.zeros(env.num_envs, dtype=np.int64)
        start_steps = self._episode_steps.copy()
        if not super().collect_rollouts(env, callback, rollout_buffer, n_rollout_steps):
            return False
        # the step in the episode of every stored transition (episodes continue across rollouts)
        starts = rollout_buffer.episode_starts.astype(bool)
        steps = np.empty(starts.shape, dtype=np.int64)
        previous = start_steps - 1
        for t in range(n_rollout_steps):
            steps[t] = previous = np.where(starts[t], 0, previous + 1)
        assert self._last_episode_starts is not None  # set by learn's first reset
        last_starts = self._last_episode_starts.astype(bool)
        self._episode_steps = np.where(last_starts, 0, steps[-1] + 1)
        observations = rollout_buffer.observations.reshape(n_rollout_steps * env.num_envs, -1)
        values = self.linear_baseline.predict(observations, steps.reshape(-1)).reshape(n_rollout_steps, env.num_envs)
        rollout_buffer.values[:] = values
        last_obs = cast(np.ndarray, self._last_obs)  # set by learn's first reset; a Box observation here
        last = self.linear_baseline.predict(last_obs.reshape(env.num_envs, -1), self._episode_steps)
        rollout_buffer.compute_returns_and_advantage(last_values=torch.as_tensor(last, dtype=torch.float32),
                                                     dones=self._last_episode_starts)
        self.linear_baseline.fit(observations, steps.reshape(-1), rollout_buffer.returns.reshape(-1))
        return True

    # ------------------------------------------------------------------------------------------ the update

    def fisher_vector_product(self, params: list[torch.nn.Parameter], originals: list[torch.Tensor],
                              logits: torch.Tensor, probs: torch.Tensor, evaluate: Callable[[], Any],
                              vector: torch.Tensor) -> torch.Tensor:
        """The Hessian of the mean KL at the collecting policy times ``vector``, plus damping.

        ``params`` hold the collecting policy's values, ``originals`` (detached copies of them) and leave with them;
        ``logits`` / ``probs`` are that policy's on the batch (``logits`` with its graph), ``evaluate()`` recomputes
        the action distribution.

        At the collecting policy that Hessian is the Fisher matrix ``mean_i J_iᵀ M_i J_i`` (``J_i``: the Jacobian
        of step i's logits, ``M_i = diag(p_i) - p_i p_iᵀ``). ``J v`` is a central difference of the logits along
        ``vector`` (two forward passes without gradients), ``Jᵀ (M J v)`` one backward pass through the graph of
        ``logits``: several times cheaper than the double backward through the recurrent net that sb3-contrib's
        feed-forward TRPO uses, and the line search checks the exact KL anyway.
        """
        theta = torch.sqrt(cast(torch.Tensor, sum((o ** 2).sum() for o in originals)))  # originals is not empty
        step = 5e-3 * max(1.0, float(theta)) / max(float(vector.norm()), 1e-12)
        with torch.no_grad():
            shifted = []
            for sign in (1.0, -1.0):
                self._set(params, originals, sign * step, vector)
                shifted.append(evaluate().distribution.logits)
            self._set(params, originals, 0.0, vector)  # back to the values the graph of ``logits`` holds
        jv = (shifted[0] - shifted[1]) / (2 * step)
        mjv = probs * jv - probs * (probs * jv).sum(dim=1, keepdim=True)
        grads = torch.autograd.grad(logits, params, grad_outputs=mjv / len(logits), retain_graph=True)
        return torch.cat([g.reshape(-1) for g in grads]) + self.cg_damping * vector

    @staticmethod
    def _set(params: list[torch.nn.Parameter], originals: list[torch.Tensor], scale: float,
             direction: torch.Tensor) -> None:
        """``params = originals + scale * direction``, swapping the parameters' data (as sb3-contrib's TRPO does)
        rather than writing in place, so that autograd graphs built on the parameters stay usable once the original
        values are back."""
        offset = 0
        with torch.no_grad():
            for param, original in zip(params, originals, strict=True):
                n = param.numel()
                shift = direction[offset:offset + n].view_as(param)
                param.data = original if scale == 0.0 else original + scale * shift
                offset += n

    def _critic_values(self, data: Any) -> torch.Tensor:
        """The value head on a minibatch: a feed-forward pass for a critic without recurrence (the default), else
        the sequence pass."""
        policy = self.policy
        if policy.lstm_critic is None and not policy.shared_lstm:
            features = policy.extract_features(data.observations, policy.vf_features_extractor)
            critic = cast(torch.nn.Linear, policy.critic)  # sb3-contrib's: a Linear when the critic has no LSTM
            return policy.value_net(policy.mlp_extractor.forward_critic(critic(features))).flatten()
        return policy.evaluate_sequences(data.observations, data.lstm_states, data.episode_starts)[1].flatten()

    def _policy_step(self, data: Any) -> tuple[list[torch.nn.Parameter], bool, float, float]:
        """TRPO's step of the actor on the batch ``data``: the actor's parameters, whether the line search took a
        step, the surrogate after it (before, when none) and the step's mean KL (0 when none)."""
        actions = data.actions.long().flatten()
        policy = self.policy
        if self.lean_policy_step:
            x = np.ascontiguousarray(data.observations.numpy(), dtype=np.float32)
            sequences, sparse = Sequences.of(data.lstm_states), SparseRows.of(x)  # once for every evaluation

            def evaluate():
                latent = policy.mlp_extractor.forward_actor(recurrence(policy.lstm_actor, x, sequences, sparse))
                return policy._get_action_dist_from_latent(latent)
        else:
            def evaluate():
                evaluated = policy.evaluate_sequences(data.observations, data.lstm_states, data.episode_starts)
                if evaluated is None:
                    raise RuntimeError("RecurrentTRPO needs the compact recurrent buffer's minibatches")
                return evaluated[0]

        distribution = evaluate()
        logits = distribution.distribution.logits
        probs = distribution.distribution.probs.detach()
        old = Categorical(probs=probs)
        advantages = data.advantages
        if self.normalize_advantage and len(advantages) > 1:
            advantages = (advantages - advantages.mean()) / (advantages.std() + 1e-8)
        objective = (advantages * torch.exp(distribution.log_prob(actions) - data.old_log_prob)).mean()
        params = list(self.policy.parameters())
        grads = torch.autograd.grad(objective, params, retain_graph=True, allow_unused=True)
        actor_params = [p for p, g in zip(params, grads, strict=True) if g is not None]  # the critic is unused
        objective_grad = torch.cat([g.reshape(-1) for g in grads if g is not None])
        originals = [param.detach().clone() for param in actor_params]
        fisher = partial(self.fisher_vector_product, actor_params, originals, logits, probs, evaluate)
        direction = conjugate_gradient(fisher, objective_grad, max_iter=self.cg_max_steps)
        curvature = float(torch.dot(direction, fisher(direction)))
        max_step = np.sqrt(2 * self.target_kl / curvature) if curvature > 0 else 0.0
        success, coefficient, new_kl = False, 1.0, torch.zeros(())
        with torch.no_grad():
            for _ in range(self.line_search_max_iter):
                self._set(actor_params, originals, coefficient * max_step, direction)
                candidate = evaluate()
                new_objective = (advantages * torch.exp(candidate.log_prob(actions) - data.old_log_prob)).mean()
                new_kl = kl_divergence(candidate.distribution, old).mean()
                if new_kl < self.target_kl and new_objective > objective:
                    success = True
                    break
                coefficient *= self.line_search_shrinking_factor
            if not success:
                self._set(actor_params, originals, 0.0, direction)
        return (actor_params, success, float((new_objective if success else objective).detach()),
                float(new_kl) if success else 0.0)

    def train(self) -> None:
        self.policy.set_training_mode(True)
        self._update_learning_rate(self.policy.optimizer)
        with warnings.catch_warnings():  # on a GPU, ``_set`` holds the parameters apart from cuDNN's packed copy
            warnings.filterwarnings("ignore", _UNPACKED, UserWarning)  # during the search (packed again below)
            with blas_threads(1) if self.lean_policy_step else nullcontext():  # as lean_train: the same SMC
                steps = [self._policy_step(data) for data in self.rollout_buffer.get(batch_size=None)]
        for module in self.policy.modules():  # the data swaps of ``_set`` leave cuDNN's packed recurrent weights
            if isinstance(module, torch.nn.RNNBase):  # apart; pack them again (a no-op on the CPU)
                module.flatten_parameters()
        actor_params = steps[-1][0]  # (the whole batch is one minibatch: one step)
        successes = [success for _, success, _, _ in steps]
        objectives = [objective for _, _, objective, _ in steps]
        kls = [kl for _, _, _, kl in steps]

        value_losses: list[float] = []
        if self.linear_baseline is None:
            for _ in range(self.n_critic_updates):
                for data in self.rollout_buffer.get(self.batch_size):
                    value_loss = F.mse_loss(data.returns, self._critic_values(data))
                    value_losses.append(value_loss.item())
                    self.policy.optimizer.zero_grad()
                    value_loss.backward()
                    for param in actor_params:  # the critic's regression must not move the policy
                        param.grad = None
                    self.policy.optimizer.step()

        self._n_updates += 1
        explained = explained_variance(self.rollout_buffer.values.flatten(), self.rollout_buffer.returns.flatten())
        self.logger.record("train/policy_objective", float(np.mean(objectives)))
        self.logger.record("train/kl_divergence_loss", float(np.mean(kls)))
        self.logger.record("train/is_line_search_success", float(np.mean(successes)))
        if value_losses:
            self.logger.record("train/value_loss", float(np.mean(value_losses)))
        self.logger.record("train/explained_variance", explained)
        self.logger.record("train/n_updates", self._n_updates, exclude="tensorboard")

    def learn(self: SelfRecurrentTRPO, total_timesteps: int, callback: MaybeCallback = None, log_interval: int = 1,
              tb_log_name: str = "RecurrentTRPO", reset_num_timesteps: bool = True,
              progress_bar: bool = False) -> SelfRecurrentTRPO:
        return super().learn(total_timesteps=total_timesteps, callback=callback, log_interval=log_interval,
                             tb_log_name=tb_log_name, reset_num_timesteps=reset_num_timesteps,
                             progress_bar=progress_bar)

    def _excluded_save_params(self) -> list[str]:
        return [*super()._excluded_save_params(), "_episode_steps"]


def env_count(env: Any) -> int:
    """Environments in ``env`` (a VecEnv, a gym env, or an env id that SB3 will wrap into one)."""
    return int(getattr(env, "num_envs", 1))
