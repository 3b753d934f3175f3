"""sb3_smc.smc.policies: numpy actors match SB3's distributions, scripted policies, sampling, pickling.

The speed of the numpy actors is measured by ``benchmarks/bench_policies.py``.
"""

from __future__ import annotations

import math
import pickle
from collections.abc import Callable

import gymnasium as gym
import numpy as np
import pytest
import torch as th
from sb3_contrib import TRPO, RecurrentPPO
from stable_baselines3 import DQN, PPO
from stable_baselines3.common.vec_env import DummyVecEnv
from torch import nn

from sb3_smc.common.kernels import accurate_tanh
from sb3_smc.smc.numpy_actors import (
    COMPILED_BATCH_FROM,
    NumpyGRUPolicy,
    NumpyLSTMPolicy,
    NumpyMLPPolicy,
    _activate,
    _compilable,
)
from sb3_smc.smc.policies import (
    ScriptedPolicy,
    SequencePolicy,
    _activation_spec,
    policy_from_model,
    sample_action,
    sample_actions,
)
from sb3_smc.smc.smc import StepPolicy

N_ACTIONS = 6
SIDE = 9


class GridEnv(gym.Env):
    """Tiny stand-in for an SMC observation: one-hot cell of a 9 x 9 grid (81) + one-hot previous action (6)."""

    def __init__(self, continuous_actions: bool = False) -> None:
        self.observation_space = gym.spaces.Box(0.0, 1.0, (SIDE * SIDE + N_ACTIONS,), np.float32)
        self.action_space = (gym.spaces.Box(-1.0, 1.0, (2,), np.float32) if continuous_actions
                             else gym.spaces.Discrete(N_ACTIONS))
        self.cell = 0
        self.t = 0
        self.length = 1

    def _obs(self, previous: int | None) -> np.ndarray:
        obs = np.zeros(self.observation_space.shape, np.float32)
        obs[self.cell] = 1.0
        if previous is not None:
            obs[SIDE * SIDE + previous] = 1.0
        return obs

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        self.cell = int(self.np_random.integers(SIDE * SIDE))
        self.t = 0
        self.length = int(self.np_random.integers(4, 16))
        return self._obs(None), {}

    def step(self, action):
        a = int(np.asarray(action).reshape(-1)[0] > 0) if isinstance(self.action_space, gym.spaces.Box) else int(
            action)
        row, col = divmod(self.cell, SIDE)
        if a >= 2:
            dr, dc = ((1, 0), (0, 1), (-1, 0), (0, -1))[a - 2]
            row, col = min(max(row + dr, 0), SIDE - 1), min(max(col + dc, 0), SIDE - 1)
            self.cell = row * SIDE + col
        self.t += 1
        terminated = a < 2
        reward = float(terminated and (a == int(col < SIDE // 2)))
        return self._obs(a % N_ACTIONS), reward, terminated, self.t >= self.length, {}


def trained(cls, policy: str = "MlpPolicy", make_env: Callable[[], gym.Env] = GridEnv, noise: float = 0.3,
            steps: int = 256, **policy_kwargs):
    """A model after a tiny ``learn`` (4 environments, so that collecting is cheap), with noise on every weight so
    that probabilities are far from uniform."""
    kwargs = {"n_steps": 16, "batch_size": 64}
    if cls is not TRPO:
        kwargs["n_epochs"] = 1
    env = DummyVecEnv([make_env] * 4)
    model = cls(policy, env, seed=0, device="cpu", policy_kwargs=policy_kwargs, **kwargs)
    if steps:
        model.learn(steps)
    gen = th.Generator().manual_seed(1)
    with th.no_grad():
        for p in model.policy.parameters():
            p.add_(noise * th.randn(p.shape, generator=gen))
    model.policy.set_training_mode(False)
    return model


def compare_rollout(model, policy: StepPolicy, env: gym.Env, steps: int = 60, seed: int = 0,
                    atol: float = 1e-5) -> float:
    """Step ``policy`` and SB3's own distribution through a rollout; return the largest deviation from uniform."""
    recurrent = isinstance(policy, NumpyLSTMPolicy)
    rng = np.random.default_rng(seed)
    obs, _ = env.reset(seed=seed)
    state = policy.initial_state()
    if recurrent:
        shape = model.policy.lstm_hidden_state_shape
        sb3_state = (th.zeros(shape), th.zeros(shape))
    episode_start = True
    spread = 0.0
    episodes = 0
    for _ in range(steps):
        obs_t = th.as_tensor(obs[None])
        with th.no_grad():
            if recurrent:
                dist, sb3_state = model.policy.get_distribution(obs_t, sb3_state, th.tensor([float(episode_start)]))
            else:
                dist = model.policy.get_distribution(obs_t)
        expected = dist.distribution.probs[0].double().numpy()
        probs, state = policy.probabilities(obs, state)
        assert probs.shape == expected.shape
        np.testing.assert_allclose(probs, expected, atol=atol, rtol=0)
        assert abs(probs.sum() - 1.0) < 1e-6
        if recurrent:
            np.testing.assert_allclose(state[0], sb3_state[0][:, 0].numpy(), atol=atol, rtol=0)
            np.testing.assert_allclose(state[1], sb3_state[1][:, 0].numpy(), atol=atol, rtol=0)
        else:
            assert state is None
        spread = max(spread, float(np.max(np.abs(expected - 1.0 / len(expected)))))
        obs, _, terminated, truncated, _ = env.step(sample_action(expected, rng))
        episode_start = terminated or truncated
        if episode_start:
            episodes += 1
            obs, _ = env.reset()
            state = policy.initial_state()
    assert episodes >= 2, "the rollout should cross episode boundaries"
    return spread


RECURRENT_CONFIGS = {
    "lstm32-no-mlp": {"lstm_hidden_size": 32, "net_arch": []},
    "lstm32-default-mlp": {"lstm_hidden_size": 32},
    "shared-lstm": {"lstm_hidden_size": 16, "shared_lstm": True, "enable_critic_lstm": False,
                    "net_arch": {"pi": [16], "vf": [8]}},
    "two-layers-relu": {"lstm_hidden_size": 16, "n_lstm_layers": 2, "net_arch": {"pi": [24, 12], "vf": [16]},
                        "activation_fn": nn.ReLU},
    "critic-linear-elu": {"lstm_hidden_size": 8, "enable_critic_lstm": False, "net_arch": [16],
                          "activation_fn": nn.ELU},
}


@pytest.mark.parametrize("config", list(RECURRENT_CONFIGS))
def test_recurrent_ppo_matches_sb3(config: str) -> None:
    model = trained(RecurrentPPO, "MlpLstmPolicy", **RECURRENT_CONFIGS[config])
    policy = policy_from_model(model)
    assert isinstance(policy, NumpyLSTMPolicy) and isinstance(policy, StepPolicy)
    assert policy.n_actions == N_ACTIONS
    assert policy.n_layers == RECURRENT_CONFIGS[config].get("n_lstm_layers", 1)
    assert compare_rollout(model, policy, GridEnv()) > 0.05  # the check is not against a near-uniform policy


MLP_CONFIGS = {
    "PPO-default": (PPO, {}),
    "PPO-relu": (PPO, {"net_arch": {"pi": [32, 16], "vf": [8]}, "activation_fn": nn.ReLU}),
    "PPO-leaky": (PPO, {"net_arch": {"pi": [8], "vf": []}, "activation_fn": nn.LeakyReLU}),
    "PPO-linear": (PPO, {"net_arch": {"pi": [], "vf": [8]}}),
    "TRPO-default": (TRPO, {}),
    "TRPO-separate-extractor": (TRPO, {"net_arch": [16], "share_features_extractor": False}),
}


@pytest.mark.parametrize("config", list(MLP_CONFIGS))
def test_mlp_policies_match_sb3(config: str) -> None:
    cls, kwargs = MLP_CONFIGS[config]
    model = trained(cls, **kwargs)
    policy = policy_from_model(model)
    assert isinstance(policy, NumpyMLPPolicy) and isinstance(policy, StepPolicy)
    assert policy.initial_state() is None
    assert compare_rollout(model, policy, GridEnv()) > 0.05


@pytest.mark.parametrize("module", [nn.Tanh(), nn.ReLU(), nn.LeakyReLU(0.2), nn.ELU(0.7), nn.SELU(), nn.Sigmoid(),
                                    nn.SiLU(), nn.Softplus(), nn.Identity()], ids=lambda m: type(m).__name__)
def test_activations_match_torch(module: nn.Module) -> None:
    name, param = _activation_spec(module)
    x = np.linspace(-30.0, 30.0, 241)
    expected = module(th.as_tensor(x)).numpy()
    np.testing.assert_allclose(_activate(name, param, x), expected, atol=1e-12, rtol=1e-12)


def test_pixelworld_recurrent_and_float32() -> None:
    from tests.helpers import classification_env

    def make_env() -> gym.Env:
        return classification_env(observation="hand")

    env = make_env()
    model = trained(RecurrentPPO, "MlpLstmPolicy", make_env=make_env, lstm_hidden_size=32, net_arch=[])
    compare_rollout(model, policy_from_model(model), env, steps=80)
    compare_rollout(model, policy_from_model(model, dtype=np.float32), env, steps=80)
    assert policy_from_model(model, dtype=np.float32).head[0][1].dtype == np.float32


def test_policy_of_the_model_or_its_policy_and_copy_is_frozen() -> None:
    model = trained(PPO, steps=0, net_arch=[8])
    policy = policy_from_model(model.policy)
    obs = GridEnv().reset(seed=3)[0]
    before = policy.probabilities(obs, None)[0]
    with th.no_grad():
        model.policy.action_net.weight.add_(1.0)
    np.testing.assert_array_equal(policy.probabilities(obs, None)[0], before)


def test_batches_match_single_steps() -> None:
    env = GridEnv()
    observations = np.stack([env.reset(seed=s)[0] for s in range(5)])
    for model in (trained(RecurrentPPO, "MlpLstmPolicy", steps=0, lstm_hidden_size=8, n_lstm_layers=2,
                          net_arch=[8]),
                  trained(PPO, steps=0, net_arch=[8])):
        policy = policy_from_model(model)
        states = [policy.initial_state() for _ in observations]
        for _ in range(3):  # carry states through a few steps
            probs, next_states = policy.probabilities_batch(observations, states)
            assert probs.shape == (5, N_ACTIONS)
            for row, obs in enumerate(observations):
                single, single_state = policy.probabilities(obs, states[row])
                np.testing.assert_allclose(probs[row], single, atol=1e-12)
                if single_state is not None:
                    np.testing.assert_allclose(next_states[row][0], single_state[0], atol=1e-12)
                    np.testing.assert_allclose(next_states[row][1], single_state[1], atol=1e-12)
            states = next_states
            observations = observations[::-1].copy()


def _random_recurrent(cell: str, layers: int = 1, head: int = 0, dtype: type = np.float64, seed: int = 0,
                      size: int = 87, hidden: int = 32, actions: int = 9) -> NumpyLSTMPolicy | NumpyGRUPolicy:
    """A recurrent numpy actor with random weights (``head``: a hidden tanh layer of that size before the output)."""
    rng = np.random.default_rng(seed)
    gates = (4 if cell == "lstm" else 3) * hidden
    recurrent = []
    for k in range(layers):
        inputs = size if k == 0 else hidden
        weights = [rng.normal(0, 0.3, (inputs, gates)), rng.normal(0, 0.3, (hidden, gates)), rng.normal(0, 0.1, gates)]
        recurrent.append(tuple(weights) if cell == "lstm" else (*weights, rng.normal(0, 0.1, gates)))
    layers_out = [("linear", rng.normal(0, 0.5, (hidden, head)), rng.normal(0, 0.1, head)), ("tanh", 0.0, None)] \
        if head else []
    layers_out.append(("linear", rng.normal(0, 0.5, (head or hidden, actions)), rng.normal(0, 0.1, actions)))
    cls = NumpyLSTMPolicy if cell == "lstm" else NumpyGRUPolicy
    return cls(recurrent, layers_out, size, dtype=dtype)


def test_accurate_tanh_is_the_c_library_s_within_2_ulp() -> None:
    """The numpy actors' cells take ``accurate_tanh``: within 2 units in the last place of the C library's ``tanh`` on
    every scale (both branches, the clamp), equal on the special values, the sign of zero kept."""
    rng = np.random.default_rng(0)
    x = np.concatenate([rng.uniform(-1.0, 1.0, 20_000) * scale
                        for scale in (1e-300, 1e-9, 1e-3, 0.3, 0.625, 1.0, 3.0, 10.0, 19.1, 25.0, 1e6)])
    x = np.concatenate([x, [0.625, -0.625, np.nextafter(0.625, 0.0), 20.0, 1e308, 5e-324]])
    got = np.array([accurate_tanh(v) for v in x])
    expected = np.array([math.tanh(v) for v in x])  # the C library's
    assert (np.abs(got - expected) <= 2 * np.spacing(np.abs(expected).clip(1e-300))).all()
    assert (got == expected).mean() > 0.5
    special = np.array([0.0, -0.0, np.inf, -np.inf])
    got = np.array([accurate_tanh(v) for v in special])
    np.testing.assert_array_equal(got, [0.0, -0.0, 1.0, -1.0])
    assert list(np.signbit(got)) == [False, True, False, True]
    assert np.isnan(accurate_tanh(np.nan))


@pytest.mark.parametrize("cell", ["lstm", "gru"])
def test_the_compiled_step_equals_the_numpy_code(cell: str) -> None:
    """The default architecture (float64, one recurrent layer, linear head) runs compiled; its probabilities and
    states equal the numpy code's to rounding, for one-hot float32 observations and dense float64 ones."""
    import copy

    policy = _random_recurrent(cell)
    assert policy._compiled is not None
    numpy_code = copy.copy(policy)
    numpy_code._compiled = None
    rng = np.random.default_rng(1)
    observations = []
    for step in range(12):
        obs = np.zeros(87, dtype=np.float32)
        obs[rng.choice(81, 9, replace=False)] = 1.0
        obs[81 + step % 6] = rng.choice([-1.0, 1.0])
        observations.append(obs if step % 2 else rng.normal(size=87))
    state, reference = policy.initial_state(), numpy_code.initial_state()
    for obs in observations:
        p, state = policy.probabilities(obs, state)
        q, reference = numpy_code.probabilities(obs, reference)
        np.testing.assert_allclose(p, q, rtol=0, atol=1e-14)
        for ours, theirs in zip(state if cell == "lstm" else (state,), reference if cell == "lstm" else (reference,),
                                strict=True):
            assert ours.shape == theirs.shape == (1, 32)
            np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-14)
    assert policy.batch_from is COMPILED_BATCH_FROM is None and numpy_code.batch_from == 2  # SMCVecEnv: singles
    for rows in (1, 2, 4):  # row by row: the single steps' numbers
        batch, states = policy.probabilities_batch(np.stack(observations[:rows]), [state] * rows)
        single = [policy.probabilities(obs, state) for obs in observations[:rows]]
        np.testing.assert_array_equal(batch, np.stack([s[0] for s in single]))
        for ours, theirs in zip(states, single, strict=True):
            for a, b in zip(ours if cell == "lstm" else (ours,), theirs[1] if cell == "lstm" else (theirs[1],),
                            strict=True):
                assert a.shape == (1, 32)
                np.testing.assert_array_equal(a, b)
    with pytest.raises(ValueError, match="4 observations but 3 states"):
        policy.probabilities_batch(np.stack(observations[:4]), [state] * 3)
    with pytest.raises(ValueError, match="observation of 86 values, but the policy takes 87"):
        policy.probabilities(observations[0][:86], state)
    short = (state[0][:, :31], state[1][:, :31]) if cell == "lstm" else state[:, :31]
    with pytest.raises(ValueError, match="state or observation of the wrong size"):
        policy.probabilities(observations[0], short)
    integers = (observations[1] != 0).astype(np.int64)  # other input types are converted, as the numpy code does
    np.testing.assert_allclose(policy.probabilities(integers, state)[0],
                               numpy_code.probabilities(integers, reference)[0], rtol=0, atol=1e-14)
    for other in (_random_recurrent(cell, layers=2), _random_recurrent(cell, head=16),
                  _random_recurrent(cell, dtype=np.float32)):
        assert other._compiled is None  # any other architecture: the numpy code
    mismatched = _random_recurrent(cell)
    mismatched.head = [("linear", mismatched.head[0][1][:31], mismatched.head[0][2])]
    assert not _compilable(mismatched)  # an inconsistent output layer is left to the numpy code (its shape error)


def test_states_are_not_modified_in_place() -> None:
    policy = policy_from_model(trained(RecurrentPPO, "MlpLstmPolicy", steps=0, lstm_hidden_size=8, net_arch=[]))
    obs = GridEnv().reset(seed=0)[0]
    state = policy.initial_state()
    _, state1 = policy.probabilities(obs, state)
    assert not state[0].any() and not state[1].any()
    p_a, _ = policy.probabilities(obs, state1)
    p_b, _ = policy.probabilities(obs, state1)
    np.testing.assert_array_equal(p_a, p_b)


def test_numpy_policies_pickle_without_torch() -> None:
    env = GridEnv()
    for model in (trained(RecurrentPPO, "MlpLstmPolicy", steps=0, lstm_hidden_size=8, net_arch=[8]),
                  trained(PPO, steps=0)):
        policy = policy_from_model(model)
        data = pickle.dumps(policy)
        assert b"torch" not in data
        copy = pickle.loads(data)
        obs = env.reset(seed=1)[0]
        state, copy_state = policy.initial_state(), copy.initial_state()
        for _ in range(3):
            p, state = policy.probabilities(obs, state)
            q, copy_state = copy.probabilities(obs, copy_state)
            np.testing.assert_array_equal(p, q)


def test_unsupported_models_raise() -> None:
    with pytest.raises(TypeError, match="Discrete"):
        policy_from_model(PPO("MlpPolicy", GridEnv(continuous_actions=True), device="cpu"))
    with pytest.raises(TypeError, match="actor-critic"):
        policy_from_model(DQN("MlpPolicy", GridEnv(), device="cpu", buffer_size=10, learning_starts=0))
    with pytest.raises(TypeError, match="GELU"):
        policy_from_model(PPO("MlpPolicy", GridEnv(), device="cpu", policy_kwargs={"activation_fn": nn.GELU}))
    dict_env = gym.wrappers.TransformObservation(
        GridEnv(), lambda o: {"x": o}, gym.spaces.Dict({"x": GridEnv().observation_space}))
    with pytest.raises(TypeError, match="Box"):
        policy_from_model(PPO("MultiInputPolicy", dict_env, device="cpu"))
    with pytest.raises(TypeError, match="FlattenExtractor"):
        from stable_baselines3.common.torch_layers import FlattenExtractor

        class Extractor(FlattenExtractor):
            pass

        policy_from_model(PPO("MlpPolicy", GridEnv(), device="cpu",
                              policy_kwargs={"features_extractor_class": Extractor}))
    with pytest.raises(ValueError, match="LSTM options"):
        policy_from_model(RecurrentPPO("MlpLstmPolicy", GridEnv(), device="cpu",
                                       policy_kwargs={"lstm_hidden_size": 8, "lstm_kwargs": {"proj_size": 4}}))


# ----------------------------------------------------------------------------------------------------------------
# Scripted policies
# ----------------------------------------------------------------------------------------------------------------

def go_right_then_signal(observation: np.ndarray, step: int) -> int:
    return 3 if step < 2 else int(observation[0] > 0.5)


def test_scripted_policy() -> None:
    policy = ScriptedPolicy(N_ACTIONS, go_right_then_signal)
    assert isinstance(policy, StepPolicy)
    state = policy.initial_state()
    assert state == 0
    obs = np.zeros(87)
    obs[0] = 1.0
    actions = []
    for _ in range(4):
        probs, state = policy.probabilities(obs, state)
        assert probs.sum() == 1.0 and probs.max() == 1.0
        actions.append(int(np.argmax(probs)))
    assert actions == [3, 3, 1, 1] and state == 4
    copy = pickle.loads(pickle.dumps(policy))
    np.testing.assert_array_equal(copy.probabilities(obs, 2)[0], np.eye(N_ACTIONS)[1])
    with pytest.raises(ValueError, match="out of range"):
        ScriptedPolicy(2, go_right_then_signal).probabilities(obs, 0)


def test_sequence_policy() -> None:
    policy = SequencePolicy(N_ACTIONS, [2, 5, 0])
    state = policy.initial_state()
    actions = []
    for _ in range(5):
        probs, state = policy.probabilities(np.zeros(3), state)
        actions.append(int(np.argmax(probs)))
    assert actions == [2, 5, 0, 0, 0]
    strict = pickle.loads(pickle.dumps(SequencePolicy(N_ACTIONS, [4], when_exhausted="raise")))
    _, state = strict.probabilities(None, strict.initial_state())
    with pytest.raises(IndexError, match="exhausted"):
        strict.probabilities(None, state)
    with pytest.raises(ValueError):
        SequencePolicy(N_ACTIONS, [6])
    with pytest.raises(ValueError):
        SequencePolicy(N_ACTIONS, [])


# ----------------------------------------------------------------------------------------------------------------
# Sampling
# ----------------------------------------------------------------------------------------------------------------

def test_sample_action_frequencies() -> None:
    p = np.array([0.1, 0.0, 0.25, 0.4, 0.25, 0.0])
    rng = np.random.default_rng(0)
    n = 20000
    counts = np.bincount([sample_action(p, rng) for _ in range(n)], minlength=len(p))
    assert counts[1] == 0 and counts[5] == 0
    support = p > 0
    chi2 = float((((counts - n * p) ** 2)[support] / (n * p[support])).sum())
    assert chi2 < 16.3  # 3 degrees of freedom, p ~ 0.001
    # unnormalised weights give the same draws as the normalised vector
    rng_a, rng_b = np.random.default_rng(5), np.random.default_rng(5)
    assert [sample_action(p * 7.0, rng_a) for _ in range(200)] == [sample_action(p, rng_b) for _ in range(200)]


def test_sample_action_is_deterministic_and_handles_edges() -> None:
    p = np.array([0.2, 0.3, 0.5])
    draws = [sample_action(p, rng) for rng in [np.random.default_rng(7)] for _ in range(50)]
    again = [sample_action(p, rng) for rng in [np.random.default_rng(7)] for _ in range(50)]
    assert draws == again
    rng = np.random.default_rng(0)
    for k in range(4):
        assert all(sample_action(np.eye(4)[k], rng) == k for _ in range(50))

    class TopRng:  # the top of the CDF (1.0 itself, which rounding of u * total can reach)
        def random(self, size=None):
            return 1.0 if size is None else np.ones(size)

    assert sample_action(np.array([0.3, 0.7]), TopRng()) == 1
    assert sample_action(np.array([0.1, 0.2, 0.7, 0.0, 0.0]), TopRng()) == 2
    assert sample_actions(np.array([[0.1, 0.2, 0.7, 0.0], [0.5, 0.0, 0.0, 0.5]]), TopRng()).tolist() == [2, 3]
    with pytest.raises(ValueError):
        sample_action(np.zeros(3), rng)
    for bad in (np.array([np.nan, 1.0]), np.array([np.inf, 1.0])):
        for form in (bad, bad.astype(np.float32)):  # the compiled draw and the numpy code
            with pytest.raises(ValueError, match="positive finite sum"):
                sample_action(form, rng)


def test_the_compiled_draw_equals_the_numpy_code() -> None:
    """float64 vectors are drawn by the compiled kernel; a list takes the numpy code: the same index for the same
    uniform draw, on random vectors with zeros and on draws exactly at the CDF's steps."""
    rng = np.random.default_rng(3)
    for _ in range(3000):
        p = rng.random(rng.integers(1, 12)) * (rng.random() < 0.5 or 1e-3)
        p[rng.random(len(p)) < 0.3] = 0.0
        if not p.any():
            continue
        seed = int(rng.integers(1 << 30))
        assert sample_action(p, np.random.default_rng(seed)) == sample_action(list(p), np.random.default_rng(seed))

    class Fixed:
        def __init__(self, u: float) -> None:
            self.u = u

        def random(self) -> float:
            return self.u

    steps = np.array([0.25, 0.0, 0.25, 0.5])
    for u in (0.0, 0.25, 0.5, 0.75, 1.0, 0.2499999, 0.5000001):
        assert sample_action(steps, Fixed(u)) == sample_action(list(steps), Fixed(u))


def test_sample_actions_batch_matches_sample_action() -> None:
    p = np.random.default_rng(1).dirichlet(np.ones(5), size=200)
    p[::7, 2] = 0.0
    batch = sample_actions(p, np.random.default_rng(3))
    rng = np.random.default_rng(3)
    assert batch.tolist() == [sample_action(row, rng) for row in p]
