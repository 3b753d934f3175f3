"""Recurrent TRPO: the trust region and the surrogate on one update, the linear feature baseline, save/load, the
SMC spec and library, and a memory task only recurrent learners solve."""

from __future__ import annotations

import copy

import gymnasium as gym
import numpy as np
import pytest
import torch
from sb3_contrib import RecurrentPPO
from stable_baselines3 import PPO
from stable_baselines3.common.env_util import make_vec_env
from torch.distributions import Categorical, kl_divergence

from sb3_smc import SMCLibrary, evaluate, train_smc
from sb3_smc.common.recurrent import SequenceGruPolicy, SequenceLstmPolicy, use_compact_buffer
from sb3_smc.records import RecordError, TrainingSpec
from sb3_smc.recurrent_trpo import LinearFeatureBaseline, RecurrentTRPO

CORNER_ID = "PW-cl_self-in-left-corner_vs_on-hline-v0"


class CueRecallEnv(gym.Env):
    """A cue (one of two) is shown at the first step only; after ``delay`` blank steps the agent is asked which it
    was. Reward 1 for naming the cue at the question, 0 otherwise: a memoryless policy sees the same question either
    way and scores 0.5 on average; a recurrent one can score 1."""

    def __init__(self, delay: int = 3) -> None:
        self.delay = delay
        # [cue A, cue B, question, bias]: never all zeros
        self.observation_space = gym.spaces.Box(0.0, 1.0, (4,), np.float32)
        self.action_space = gym.spaces.Discrete(2)

    def _obs(self) -> np.ndarray:
        obs = np.zeros(4, dtype=np.float32)
        obs[3] = 1.0
        if self.t == 0:
            obs[self.cue] = 1.0
        if self.t == self.delay + 1:
            obs[2] = 1.0
        return obs

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        self.t, self.cue = 0, int(self.np_random.integers(2))
        return self._obs(), {}

    def step(self, action):
        asked = self.t == self.delay + 1
        reward = float(asked and int(action) == self.cue)
        self.t += 1
        return self._obs(), reward, asked, False, {}


def _recall_rate(model, episodes: int = 200) -> float:
    """The fraction of deterministic episodes in which ``model`` names the cue."""
    env = CueRecallEnv()
    total = 0.0
    for episode in range(episodes):
        obs, _ = env.reset(seed=10_000 + episode)
        state, start, done = None, np.ones((1,), dtype=bool), False
        while not done:
            action, state = model.predict(obs[None], state=state, episode_start=start, deterministic=True)
            obs, reward, done, _, _ = env.step(int(action[0]))
            start = np.zeros((1,), dtype=bool)
            total += reward
    return total / episodes


def _recurrent(algo: type, seed: int, device: str = "cpu", **kwargs):
    env = make_vec_env(CueRecallEnv, n_envs=8, seed=seed)
    model = algo("MlpGruPolicy" if algo is RecurrentTRPO else SequenceGruPolicy, env, n_steps=64, seed=seed,
                 device=device, policy_kwargs={"lstm_hidden_size": 16, "net_arch": [], "shared_lstm": False,
                                               "enable_critic_lstm": True}, **kwargs)
    use_compact_buffer(model)
    return model


@pytest.mark.parametrize("baseline", ["critic", "linear_feature"])
def test_one_update_keeps_the_kl_in_the_trust_region_and_improves_the_surrogate(baseline) -> None:
    model = _recurrent(RecurrentTRPO, seed=0, baseline=baseline, target_kl=0.01)
    model.learn(64 * 8)  # one rollout and one update; then inspect a second update by hand
    _, callback = model._setup_learn(64 * 8, callback=None, reset_num_timesteps=False)
    model.collect_rollouts(model.env, callback, model.rollout_buffer, model.n_steps)
    (data,) = list(model.rollout_buffer.get(batch_size=None))
    actions = data.actions.long().flatten()

    def surrogate_and_distribution():
        with torch.no_grad():
            distribution, _ = model.policy.evaluate_sequences(data.observations, data.lstm_states,
                                                              data.episode_starts)
        advantages = (data.advantages - data.advantages.mean()) / (data.advantages.std() + 1e-8)
        ratio = torch.exp(distribution.log_prob(actions) - data.old_log_prob)
        return float((advantages * ratio).mean()), distribution

    before, old = surrogate_and_distribution()
    old = copy.copy(old)
    actor_before = [p.detach().clone() for p in model.policy.lstm_actor.parameters()]
    model.train()
    after, new = surrogate_and_distribution()
    kl = float(kl_divergence(new.distribution, old.distribution).mean())
    moved = any(not torch.equal(a, p) for a, p in zip(actor_before, model.policy.lstm_actor.parameters(),
                                                       strict=True))
    assert abs(before) < 1e-5  # the surrogate of the collecting policy: the mean of normalised advantages
    assert moved and 0 < kl <= 0.01 and after > before, (kl, before, after)
    assert model.logger.name_to_value["train/is_line_search_success"] == 1.0


def test_the_fisher_vector_product_equals_the_hessian_of_the_mean_kl() -> None:
    """The Gauss-Newton product (central difference + one backward pass) against the exact Hessian-vector product
    of the mean KL at the collecting policy (double backward, as sb3-contrib's TRPO computes it)."""
    model = _recurrent(RecurrentTRPO, seed=4)
    model.learn(64 * 8)  # weights away from their initialisation
    _, callback = model._setup_learn(64 * 8, callback=None, reset_num_timesteps=False)
    model.collect_rollouts(model.env, callback, model.rollout_buffer, model.n_steps)
    (data,) = list(model.rollout_buffer.get(batch_size=None))

    def evaluate():
        return model.policy.evaluate_sequences(data.observations, data.lstm_states, data.episode_starts)[0]

    params = [*model.policy.lstm_actor.parameters(), *model.policy.action_net.parameters()]
    distribution = evaluate().distribution  # (SB3 reuses the wrapper object: keep the torch distribution)
    logits, probs = distribution.logits, distribution.probs.detach()
    kl = kl_divergence(distribution, Categorical(probs=probs)).mean()
    grads = torch.autograd.grad(kl, params, create_graph=True)
    flat = torch.cat([g.reshape(-1) for g in grads])
    generator = torch.Generator().manual_seed(0)
    for _ in range(3):
        vector = torch.randn(flat.shape, generator=generator)
        exact = torch.cat([g.reshape(-1) for g in torch.autograd.grad(flat @ vector, params, retain_graph=True)])
        originals = [p.detach().clone() for p in params]
        got = model.fisher_vector_product(params, originals, logits, probs, evaluate, vector)
        got = got - model.cg_damping * vector
        assert torch.linalg.norm(got - exact) <= 0.02 * torch.linalg.norm(exact), (got[:5], exact[:5])


def test_a_step_that_does_not_improve_the_surrogate_is_not_taken() -> None:
    """Without a learning signal (all advantages 0) no step improves the surrogate: the line search fails and every
    actor weight stays as it was."""
    model = _recurrent(RecurrentTRPO, seed=1)
    model.learn(64 * 8)
    _, callback = model._setup_learn(64 * 8, callback=None, reset_num_timesteps=False)
    model.collect_rollouts(model.env, callback, model.rollout_buffer, model.n_steps)
    model.rollout_buffer.advantages[:] = 0.0
    before = copy.deepcopy(model.policy.lstm_actor.state_dict())
    model.train()
    assert model.logger.name_to_value["train/is_line_search_success"] == 0.0
    for name, value in model.policy.lstm_actor.state_dict().items():
        assert torch.equal(value, before[name]), name


def test_the_conjugate_gradient_is_sb3_contribs_and_keeps_a_finite_iterate_where_that_one_diverges() -> None:
    """On a positive definite system the solver gives sb3-contrib's ``x`` bit for bit (same start from the same
    seed); where the product loses its curvature (``p·Ap`` of 0, as a float32 finite-difference Fisher product of
    a long recurrent batch did on one job of the whole table), sb3-contrib's returns non-finite values and this one
    its last finite iterate."""
    from sb3_contrib.common.utils import conjugate_gradient_solver

    from sb3_smc.recurrent_trpo.recurrent_trpo import conjugate_gradient

    generator = torch.Generator().manual_seed(0)
    m = torch.randn(20, 20, generator=generator)
    a, b = m @ m.T / 20 + torch.eye(20), torch.randn(20, generator=generator)  # well conditioned
    torch.manual_seed(3)
    ours = conjugate_gradient(lambda v: a @ v, b, max_iter=15)
    torch.manual_seed(3)
    theirs = conjugate_gradient_solver(lambda v: a @ v, b, max_iter=15)
    assert torch.equal(ours, theirs) and float(torch.linalg.norm(a @ ours - b)) < 1e-2 * float(torch.linalg.norm(b))
    calls: list[int] = []

    def flat_after_two(v: torch.Tensor) -> torch.Tensor:  # the curvature gone from the third product on
        calls.append(1)
        return a @ v if len(calls) <= 2 else torch.zeros_like(v)

    torch.manual_seed(3)
    assert not torch.isfinite(conjugate_gradient_solver(lambda v: torch.zeros_like(v), b.clone())).all()
    torch.manual_seed(3)
    x = conjugate_gradient(flat_after_two, b)
    torch.manual_seed(3)
    start = 1e-4 * torch.randn_like(b)
    assert torch.isfinite(x).all() and not torch.equal(x, start) and len(calls) == 3  # one step taken, then kept


def test_the_linear_feature_baseline_fits_returns_linear_in_its_features() -> None:
    rng = np.random.default_rng(0)
    observations, steps = rng.random((300, 3)), rng.integers(0, 50, 300)
    features = LinearFeatureBaseline.features(observations, steps)
    assert features.shape == (300, 3 + 3 + 4)
    np.testing.assert_allclose(features[:, -1], 1.0)
    np.testing.assert_allclose(features[:, 6], steps / 100)
    weights = rng.normal(size=features.shape[1])
    baseline = LinearFeatureBaseline()
    np.testing.assert_array_equal(baseline.predict(observations, steps), np.zeros(300))
    baseline.fit(observations, steps, features @ weights)
    np.testing.assert_allclose(baseline.predict(observations, steps), features @ weights, atol=1e-4)


def test_the_linear_baseline_gives_the_rollout_values() -> None:
    model = _recurrent(RecurrentTRPO, seed=2, baseline="linear_feature")
    model.learn(64 * 8 * 2)
    assert model.linear_baseline.coefficients is not None
    buffer = model.rollout_buffer
    # values are the baseline's (fitted on the previous batch), not the value head's
    assert buffer.values.std() > 0 and "train/value_loss" not in model.logger.name_to_value


@pytest.mark.parametrize("baseline", ["critic", "linear_feature"])
def test_save_load_round_trip(baseline, tmp_path) -> None:
    model = _recurrent(RecurrentTRPO, seed=3, baseline=baseline)
    model.learn(64 * 8 * 2)
    model.save(tmp_path / "model.zip")
    loaded = RecurrentTRPO.load(tmp_path / "model.zip", device="cpu")
    assert isinstance(loaded.policy, SequenceGruPolicy) and loaded.baseline == baseline
    assert (loaded.target_kl, loaded.cg_max_steps, loaded.n_critic_updates) == (0.01, 15, 10)
    for (name, a), (_, b) in zip(model.policy.state_dict().items(), loaded.policy.state_dict().items(), strict=True):
        assert torch.equal(a, b), name
    if baseline == "linear_feature":
        np.testing.assert_array_equal(loaded.linear_baseline.coefficients, model.linear_baseline.coefficients)
    obs = np.array([[1, 0, 0, 1], [0, 0, 0, 1], [0, 0, 1, 1]], dtype=np.float32)
    a, state_a = model.predict(obs, episode_start=np.ones(3, dtype=bool), deterministic=True)
    b, state_b = loaded.predict(obs, episode_start=np.ones(3, dtype=bool), deterministic=True)
    np.testing.assert_array_equal(a, b)
    np.testing.assert_allclose(state_a[0], state_b[0], atol=1e-6)
    loaded.set_env(make_vec_env(CueRecallEnv, n_envs=8, seed=3))
    loaded.learn(64 * 8, reset_num_timesteps=False)  # a loaded model trains on
    assert loaded.num_timesteps == 64 * 8 * 3


def test_bad_arguments_are_refused() -> None:
    env = make_vec_env(CueRecallEnv, n_envs=2, seed=0)
    with pytest.raises(ValueError, match="baseline must be one of"):
        RecurrentTRPO("MlpGruPolicy", env, baseline="linear")
    with pytest.raises(ValueError, match="target_kl must be > 0"):
        RecurrentTRPO("MlpGruPolicy", env, target_kl=0)
    with pytest.raises(TypeError, match="needs a SequenceLstmPolicy"):
        RecurrentTRPO(RecurrentPPO.policy_aliases["MlpLstmPolicy"], env)  # sb3-contrib's stock LSTM policy
    assert isinstance(RecurrentTRPO("MlpLstmPolicy", env).policy, SequenceLstmPolicy)


def test_a_recurrent_trpo_smc_goes_through_the_library_and_evaluation(tmp_path) -> None:
    spec = TrainingSpec.create(CORNER_ID, algo="RecurrentTRPO", rnn="gru")
    assert spec.hyperparameters["policy"] == "SequenceGruPolicy" and spec.hyperparameters["target_kl"] == 0.01
    with pytest.raises(RecordError, match="RecurrentPPO or RecurrentTRPO"):
        TrainingSpec.create(CORNER_ID, algo="PPO", rnn="gru")
    smc = train_smc(CORNER_ID, algo="RecurrentTRPO", rnn="gru", total_timesteps=4000, seed=0, log_every=0)
    assert isinstance(smc.model, RecurrentTRPO) and smc.spec.algo == "RecurrentTRPO"
    again = SMCLibrary.load(SMCLibrary([smc]).save(tmp_path / "library"))[smc.name]
    assert isinstance(again.model, RecurrentTRPO)
    assert evaluate(again, repeats=1).score == evaluate(smc, repeats=1).score
    parent = train_smc("PW-cl_self-in-container_vs_noncontainer-v0", children=[again], algo="RecurrentTRPO",
                       total_timesteps=2000, seed=0, log_every=0)
    assert evaluate(parent, repeats=1).call_counts().get(smc.name, 0) > 0


def test_a_memoryless_policy_cannot_solve_the_memory_task() -> None:
    """Measured (seed 0): 0.50 after 10,000 steps, and after 30,000."""
    memoryless = PPO("MlpPolicy", make_vec_env(CueRecallEnv, n_envs=8, seed=0), n_steps=64, seed=0)
    memoryless.learn(10_000)
    assert _recall_rate(memoryless) <= 0.65


@pytest.mark.parametrize("learner", ["RecurrentPPO", "RecurrentTRPO"])
def test_both_recurrent_learners_solve_the_memory_task(learner) -> None:
    """Measured (seed 0, GRU 16): both recall the cue in all 200 test episodes after 10,000 steps."""
    algo = {"RecurrentPPO": RecurrentPPO, "RecurrentTRPO": RecurrentTRPO}[learner]
    model = _recurrent(algo, seed=0)
    assert _recall_rate(model) <= 0.65  # untrained
    model.learn(10_000)
    assert _recall_rate(model) >= 0.95
