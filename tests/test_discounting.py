"""Semi-MDP discounting: gamma ** primitive steps per decision; the paper's rule where every decision is one step."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from gymnasium import spaces
from stable_baselines3.common.buffers import RolloutBuffer

from sb3_smc import SMC, train_smc
from sb3_smc.common.discounting import gae
from sb3_smc.records import TrainingSpec, WrapperSettings
from sb3_smc.smc.policies import ScriptedPolicy

CORNER_ID = "PW-cl_self-in-left-corner_vs_on-hline-v0"
CONTAINER_ID = "PW-cl_self-in-container_vs_noncontainer-v0"


def _rollout(steps: int = 7, envs: int = 3, seed: int = 0) -> tuple[np.ndarray, ...]:
    rng = np.random.default_rng(seed)
    rewards = rng.normal(size=(steps, envs)).astype(np.float32)
    values = rng.normal(size=(steps, envs)).astype(np.float32)
    starts = (rng.random((steps, envs)) < 0.3).astype(np.float32)
    last = rng.normal(size=envs).astype(np.float32)
    dones = rng.random(envs) < 0.5
    return rewards, values, starts, last, dones


@pytest.mark.parametrize("gae_lambda", [1.0, 0.95])
def test_one_step_per_decision_is_sb3s_gae_exactly(gae_lambda: float) -> None:
    rewards, values, starts, last, dones = _rollout()
    buffer = RolloutBuffer(7, spaces.Box(-1, 1, (2,)), spaces.Discrete(2), gamma=0.99, gae_lambda=gae_lambda, n_envs=3)
    buffer.rewards, buffer.values, buffer.episode_starts = rewards.copy(), values.copy(), starts.copy()
    buffer.compute_returns_and_advantage(torch.as_tensor(last), dones)
    ours = gae(rewards, values, starts, last, dones, np.full((7, 3), 0.99), gae_lambda)
    assert ours.dtype == buffer.advantages.dtype and np.array_equal(ours, buffer.advantages)


def test_a_call_of_k_steps_is_discounted_by_gamma_to_the_k() -> None:
    """One environment, three decisions (a move, a call of 3 moves, a signal that ends the episode), lambda 1:
    A_t = sum of the rewards discounted by gamma ** (primitive steps in between) - V(s_t)."""
    gamma = 0.9
    rewards = np.array([[0.0], [0.5], [1.0]], dtype=np.float32)
    values = np.zeros((3, 1), dtype=np.float32)
    starts = np.zeros((3, 1), dtype=np.float32)
    advantages = gae(rewards, values, starts, np.zeros(1, np.float32), np.array([True]),
                     gamma ** np.array([[1.0], [3.0], [1.0]]), 1.0)
    expected = [0.0 + gamma * (0.5 + gamma ** 3 * 1.0), 0.5 + gamma ** 3 * 1.0, 1.0]
    np.testing.assert_allclose(advantages[:, 0], expected, rtol=1e-6)


@pytest.mark.parametrize("algo", ["RecurrentPPO", "TRPO"])
def test_a_flat_smc_trains_as_under_the_papers_rule(algo: str) -> None:
    settings = dict(algo=algo, total_timesteps=768, n_envs=4, n_steps=64, seed=3, log_every=0)
    paper = train_smc(CORNER_ID, **settings)
    semi = train_smc(CORNER_ID, discount="semi-mdp", **settings)
    assert semi.spec.wrapper.discount == "semi-mdp" and semi.record.training_returns == paper.record.training_returns
    state, reference = semi.model.policy.state_dict(), paper.model.policy.state_dict()
    assert all(torch.equal(state[k], reference[k]) for k in state)


def test_calls_change_the_discount_and_the_spec_says_so() -> None:
    walker = SMC("walker", "bring-about", ScriptedPolicy(5, lambda obs, step: 1 if step < 6 else 0))  # 6 moves, SIG1
    settings = dict(algo="TRPO", total_timesteps=768, n_envs=4, n_steps=64, seed=1, log_every=0, children=[walker])
    paper = train_smc(CONTAINER_ID, **settings)
    semi = train_smc(CONTAINER_ID, discount="semi-mdp", **settings)
    assert semi.record.training_returns[0] == paper.record.training_returns[0]  # the first rollout: the same episodes
    assert semi.record.training_returns != paper.record.training_returns  # then other advantages, other updates
    assert "discount" not in paper.spec.wrapper.to_dict() and semi.spec.wrapper.to_dict()["discount"] == "semi-mdp"
    assert TrainingSpec.from_json(semi.spec.to_json()) == semi.spec
    with pytest.raises(ValueError, match="wrapper.discount"):
        WrapperSettings(discount="smdp")
