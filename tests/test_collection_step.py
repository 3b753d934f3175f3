"""The compiled data-collection step of SequenceLstmPolicy / SequenceGruPolicy against torch's, its weight cache,
its sampling, and the architectures it leaves to torch."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from sb3_contrib.common.recurrent.type_aliases import RNNStates

from sb3_smc import train_smc, untrained_smc
from sb3_smc.common.recurrent import SequenceLstmPolicy

CORNER_ID = "PW-cl_self-in-left-corner_vs_on-hline-v0"


@pytest.fixture(scope="module", params=["lstm", "gru"])
def policy(request):
    """A policy after two updates (weights away from their initialisation)."""
    smc = train_smc(CORNER_ID, rnn=request.param, total_timesteps=4000, seed=0, log_every=0)
    return smc.model.policy


def _inputs(policy, n: int = 6, seed: int = 1):
    generator = torch.Generator().manual_seed(seed)
    obs = (torch.rand((n, policy.observation_space.shape[0]), generator=generator) < 0.15).float()
    h = torch.randn((1, n, 32), generator=generator)
    c = torch.randn((1, n, 32), generator=generator) if policy.lstm_actor.__class__ is torch.nn.LSTM else \
        torch.zeros((1, n, 32))
    starts = torch.tensor([1.0, 0.0, 0.0, 1.0, 0.0, 0.0][:n])
    return obs, RNNStates((h, c), (h, c)), starts


def _torch_step(policy, obs, states, starts, deterministic: bool):
    policy.compiled_collection = False
    try:
        return policy.forward(obs, states, starts, deterministic=deterministic)
    finally:
        policy.compiled_collection = True


def test_the_compiled_step_is_used_and_matches_torch(policy) -> None:
    obs, states, starts = _inputs(policy)
    with torch.no_grad():
        compiled = policy.forward(obs, states, starts, deterministic=True)
        lean = _torch_step(policy, obs, states, starts, deterministic=True)
        stock = super(SequenceLstmPolicy, policy).forward(obs, states, starts, deterministic=True)
    assert policy._collection_cache[2] is not None  # the compiled path ran
    for reference in (lean, stock):
        torch.testing.assert_close(compiled[0], reference[0], rtol=0, atol=0)
        for got, want in zip((*compiled[1:3], *compiled[3].pi, *compiled[3].vf),
                             (*reference[1:3], *reference[3].pi, *reference[3].vf), strict=True):
            assert got.dtype == want.dtype and got.shape == want.shape
            torch.testing.assert_close(got, want, rtol=1e-5, atol=1e-6)


def test_sampling_is_the_inverse_cdf_of_torch_rand(policy) -> None:
    obs, states, starts = _inputs(policy)
    with torch.no_grad():
        torch.manual_seed(7)
        actions, _, log_probs, _ = policy.forward(obs, states, starts)
        torch.manual_seed(7)
        uniforms = torch.rand(len(obs), dtype=torch.float64)
        distribution = _torch_step(policy, obs, states, starts, deterministic=True)
        probabilities = policy.get_distribution(obs, states.pi, starts)[0].distribution.probs.double()
    expected = torch.searchsorted(probabilities.cumsum(1), uniforms[:, None] * probabilities.sum(1, keepdim=True),
                                  right=True)[:, 0]
    torch.testing.assert_close(actions, expected, rtol=0, atol=0)
    torch.testing.assert_close(log_probs, probabilities.log()[torch.arange(len(obs)), actions].float(), rtol=1e-5,
                               atol=1e-6)
    assert distribution[0].dtype == actions.dtype
    # over many draws, each action comes up as often as its probability says
    with torch.no_grad():
        draws = torch.stack([policy.forward(obs[:1], RNNStates(tuple(s[:, :1] for s in states.pi),
                                                                tuple(s[:, :1] for s in states.vf)),
                                            starts[:1])[0][0] for _ in range(4000)])
    frequencies = torch.bincount(draws, minlength=probabilities.shape[1]).double() / 4000
    torch.testing.assert_close(frequencies, probabilities[0], rtol=0, atol=0.03)


def test_the_weights_follow_training_and_loading(policy) -> None:
    obs, states, starts = _inputs(policy)
    original = {k: v.clone() for k, v in policy.state_dict().items()}
    try:
        with torch.no_grad():
            before = policy.forward(obs, states, starts, deterministic=True)
            for parameter in policy.parameters():  # an optimizer's in-place update
                parameter.add_(0.05 * torch.randn_like(parameter))
            after = policy.forward(obs, states, starts, deterministic=True)
            assert not torch.allclose(before[1], after[1])
            torch.testing.assert_close(after[1], _torch_step(policy, obs, states, starts, True)[1], rtol=1e-5,
                                       atol=1e-6)
        policy.load_state_dict(original)
        with torch.no_grad():
            torch.testing.assert_close(policy.forward(obs, states, starts, deterministic=True)[1], before[1],
                                       rtol=0, atol=0)
    finally:
        policy.load_state_dict(original)


def test_with_gradients_the_step_stays_in_torch(policy) -> None:
    obs, states, starts = _inputs(policy)
    _, values, log_probs, _ = policy.forward(obs, states, starts)
    assert values.requires_grad and log_probs.requires_grad


def test_other_architectures_keep_the_torch_step() -> None:
    smc = untrained_smc(CORNER_ID, seed=0, policy_kwargs={"net_arch": [16]})
    policy = smc.model.policy
    obs, states, starts = _inputs(policy)
    with torch.no_grad():
        got = policy.forward(obs, states, starts, deterministic=True)
        stock = super(SequenceLstmPolicy, policy).forward(obs, states, starts, deterministic=True)
    assert policy._collection_cache == (None, None, None)
    torch.testing.assert_close(got[1], stock[1], rtol=1e-5, atol=1e-6)


def test_a_seed_collects_the_same_rollout() -> None:
    runs = [train_smc(CORNER_ID, total_timesteps=2000, seed=3, log_every=0).model.rollout_buffer for _ in range(2)]
    for name in ("observations", "actions", "values", "log_probs", "hidden_states_pi"):
        np.testing.assert_array_equal(getattr(runs[0], name), getattr(runs[1], name))


@pytest.mark.parametrize("exact", [True, False], ids=["np.tanh", "fast_tanh"])
def test_the_gru_group_step_is_each_policys_step_bit_for_bit(exact: bool) -> None:
    """``gru_collection_steps`` computes three GRU policies of the same shapes in one call (policy 1 not a member:
    its rows are action 0 and zeros); every member's rows are ``gru_collection_step``'s with its own weights."""
    from sb3_smc.common import kernels

    rng = np.random.default_rng(1)
    features, hidden, n_actions, sizes = 20, 8, 5, (3, 2, 4)
    policies = [(rng.standard_normal((features, 3 * hidden)), rng.standard_normal((hidden, 3 * hidden)),
                 rng.standard_normal(3 * hidden), rng.standard_normal(3 * hidden),
                 rng.standard_normal((features, hidden)), rng.standard_normal(hidden), rng.standard_normal(hidden),
                 float(rng.standard_normal()),
                 rng.standard_normal((hidden, n_actions)), rng.standard_normal(n_actions)) for _ in sizes]
    n = sum(sizes)
    x = (rng.random((n, features)) < 0.3).astype(np.float32)
    h = rng.standard_normal((n, hidden)).astype(np.float32)
    starts, uniforms = (rng.random(n) < 0.3).astype(np.float64), rng.random(n)
    bounds = np.array([0, 3, 5, 9])
    stacked = [np.stack([np.asarray(p[i]) for p in policies]) for i in range(10)]
    got = kernels.gru_collection_steps(x, h, starts, uniforms, bounds, np.array([0, 2]), exact, *stacked)
    for wrong_bounds, members in ((np.array([0, 3, 5, 8]), np.array([0])), (bounds, np.array([3]))):
        with pytest.raises(ValueError, match="wrong shape"):
            kernels.gru_collection_steps(x, h, starts, uniforms, wrong_bounds, members, exact, *stacked)
    for m in (0, 2):
        rows = slice(bounds[m], bounds[m + 1])
        alone = kernels.gru_collection_step(x[rows], h[rows], starts[rows], uniforms[rows], False, exact,
                                            *policies[m])
        for a, b in zip(got, alone, strict=True):
            assert np.array_equal(a[rows], b)
    assert not got[0][3:5].any() and not got[3][3:5].any() and not got[1][3:5].any()


@pytest.mark.parametrize("exact", [True, False], ids=["np.tanh", "fast_tanh"])
def test_the_group_step_is_each_policys_step_bit_for_bit(exact: bool) -> None:
    """``lstm_collection_steps`` computes three policies of the same shapes in one call (policy 1 not a member: its
    rows are action 0 and zeros); every member's rows are ``lstm_collection_step``'s with its own weights."""
    from sb3_smc.common import kernels

    rng = np.random.default_rng(0)
    features, hidden, n_actions, sizes = 20, 8, 5, (3, 2, 4)
    policies = [(rng.standard_normal((features, 4 * hidden)), rng.standard_normal((hidden, 4 * hidden)),
                 rng.standard_normal(4 * hidden), rng.standard_normal((features, hidden)), rng.standard_normal(hidden),
                 rng.standard_normal(hidden), float(rng.standard_normal()), rng.standard_normal((hidden, n_actions)),
                 rng.standard_normal(n_actions)) for _ in sizes]
    n = sum(sizes)
    x = (rng.random((n, features)) < 0.3).astype(np.float32)
    h, c = rng.standard_normal((n, hidden)).astype(np.float32), rng.standard_normal((n, hidden)).astype(np.float32)
    starts, uniforms = (rng.random(n) < 0.3).astype(np.float64), rng.random(n)
    bounds = np.array([0, 3, 5, 9])
    stacked = [np.stack([np.asarray(p[i]) for p in policies]) for i in range(9)]
    got = kernels.lstm_collection_steps(x, h, c, starts, uniforms, bounds, np.array([0, 2]), exact, *stacked)
    for wrong_bounds, members in ((np.array([0, 3, 5, 8]), np.array([0])), (bounds, np.array([3]))):
        with pytest.raises(ValueError, match="wrong shape"):
            kernels.lstm_collection_steps(x, h, c, starts, uniforms, wrong_bounds, members, exact, *stacked)
    for m in (0, 2):
        rows = slice(bounds[m], bounds[m + 1])
        alone = kernels.lstm_collection_step(x[rows], h[rows], c[rows], starts[rows], uniforms[rows], False, exact,
                                             *policies[m])
        for a, b in zip(got, alone, strict=True):
            assert np.array_equal(a[rows], b)
    assert not got[0][3:5].any() and not got[3][3:5].any() and not got[1][3:5].any()
