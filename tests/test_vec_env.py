"""SMCVecEnv: SMC calls of many environments in lockstep give the episodes of stepping them one by one."""

from __future__ import annotations

import functools

import gymnasium as gym
import numpy as np
import pytest
import torch
from sb3_contrib import RecurrentPPO
from stable_baselines3.common.vec_env import DummyVecEnv

from sb3_smc import SMC
from sb3_smc.common.recurrent import SequenceLstmPolicy
from sb3_smc.core.layout import observation_size, smc_action_names
from sb3_smc.envs.vec_env import FlatSMCVecEnv, SMCVecEnv, answer_in_batches
from sb3_smc.envs.wrapper import HierarchicalSMCWrapper
from sb3_smc.learning.training import make_vec_env, train_smc, untrained_smc
from sb3_smc.records import TrainingSpec
from sb3_smc.smc.numpy_actors import NumpyLSTMPolicy
from sb3_smc.smc.policies import ScriptedPolicy
from tests.helpers import assert_same_smc, classification_env, step_side_by_side


def random_lstm(name: str, kind: str, children: tuple[SMC, ...] = (), seed: int = 0) -> SMC:
    """An SMC with a random numpy LSTM policy that favours moves and calls (so calls last several decisions)."""
    rng = np.random.default_rng(seed)
    names = smc_action_names(kind, [c.name for c in children])
    size, hidden = observation_size(len(children), len(names)), 8
    lstm = [(rng.normal(size=(size, 4 * hidden)), rng.normal(size=(hidden, 4 * hidden)), rng.normal(size=4 * hidden))]
    bias = np.array([-2.5 if n.startswith("SIG") else 0.0 for n in names])
    head = [("linear", rng.normal(size=(hidden, len(names))), bias)]
    return SMC(name, kind, NumpyLSTMPolicy(lstm, head, size), children=children)


def hierarchy() -> list[SMC]:
    """A three-level hierarchy: two leaves, an SMC calling both, and a scripted SMC calling the middle one."""
    left = random_lstm("left", "classification", seed=1)
    right = random_lstm("right", "bring-about", seed=2)
    middle = random_lstm("middle", "classification", (left, right), seed=3)
    names = smc_action_names("bring-about", ["middle"])
    script = SMC("script", "bring-about",
                 ScriptedPolicy(len(names), lambda obs, step: names.index("SMC:middle") if step < 2 else 0),
                 children=(middle,))
    return [left, middle, script]


def make_envs(n: int) -> list[HierarchicalSMCWrapper]:
    smcs = hierarchy()
    return [HierarchicalSMCWrapper(classification_env(max_steps=30), smcs) for _ in range(n)]


def roll(venv, steps: int, seed: int) -> list:
    venv.seed(seed)
    venv.reset()
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(steps):
        actions = rng.integers(venv.action_space.n, size=venv.num_envs)
        obs, rewards, dones, infos = venv.step(actions)
        out.append((obs.copy(), rewards.copy(), dones.copy(),
                    [(i["smc_calls"], i["primitive_steps"], i["elapsed_steps"]) for i in infos]))
    return out


def test_lockstep_calls_give_the_episodes_of_sequential_stepping() -> None:
    lockstep = roll(SMCVecEnv([lambda e=e: e for e in make_envs(6)]), 60, seed=4)
    sequential = roll(DummyVecEnv([lambda e=e: e for e in make_envs(6)]), 60, seed=4)
    calls = sum(len(c) for _, _, _, infos in lockstep for c, _, _ in infos)
    assert calls > 100  # the calls really ran (nested, several decisions each)
    assert any(call["depth"] == 3 for _, _, _, infos in lockstep for c, _, _ in infos for call in c)
    for (o1, r1, d1, i1), (o2, r2, d2, i2) in zip(lockstep, sequential, strict=True):
        np.testing.assert_array_equal(o1, o2)
        np.testing.assert_array_equal(r1, r2)
        np.testing.assert_array_equal(d1, d2)
        assert i1 == i2


@pytest.mark.parametrize("compiled", [False, True])
def test_lockstep_answers_one_batch_per_policy(compiled: bool) -> None:
    """A numpy-code policy answers a group of pending decisions in one batch; a compiled one (``batch_from`` None)
    step by step, which costs less than stacking the group."""
    import copy

    policy = random_lstm("leaf", "classification", seed=5).policy
    assert policy.batch_from is None  # the default architecture runs compiled
    if not compiled:
        policy = copy.copy(policy)
        policy._compiled = None
    calls = []
    batch = policy.probabilities_batch

    class Counting:
        def __getattr__(self, name):
            return getattr(policy, name)

        def probabilities_batch(self, observations, states):
            calls.append(len(observations))
            return batch(observations, states)

    counting = Counting()
    rng = np.random.default_rng(0)
    requests = {k: (counting, rng.integers(0, 2, size=policy.observation_size).astype(np.float32),
                    policy.initial_state()) for k in range(5)}
    scripted = ScriptedPolicy(3, lambda obs, step: 1)
    requests[9] = (scripted, np.zeros(4, dtype=np.float32), 0)
    answers = answer_in_batches(requests)
    assert calls == ([] if compiled else [5]) and sorted(answers) == [0, 1, 2, 3, 4, 9]
    for k in range(5):
        alone, state = policy.probabilities(requests[k][1], requests[k][2])
        np.testing.assert_allclose(answers[k][0], alone, rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(answers[k][1][0], state[0], rtol=1e-12, atol=1e-15)
    np.testing.assert_array_equal(answers[9][0], [0.0, 1.0, 0.0])


def test_an_error_inside_a_lockstep_call_names_the_smc() -> None:
    names = smc_action_names("classification")

    class Undeclared:  # declares no layout: only the call can find out
        def initial_state(self):
            return None

        def probabilities(self, observation, state):
            return np.full(7, 1 / 7), None

    bad = SMC("bad", "classification", Undeclared())
    venv = SMCVecEnv([lambda: HierarchicalSMCWrapper(classification_env(), [bad]) for _ in range(2)])
    venv.reset()
    with pytest.raises(ValueError, match="SMC 'bad': its policy gives 7 action probabilities"):
        venv.step(np.array([len(names), len(names)]))


@pytest.mark.parametrize("starts", [[0.0] * 4, [1.0, 0.0, 1.0, 0.0]])
def test_the_lean_collection_step_matches_the_stock_forward(starts: list[float]) -> None:
    venv = SMCVecEnv([lambda: HierarchicalSMCWrapper(classification_env(), []) for _ in range(4)])
    model = RecurrentPPO(SequenceLstmPolicy, venv, n_steps=8, seed=0, device="cpu",
                         policy_kwargs={"lstm_hidden_size": 16, "enable_critic_lstm": False, "net_arch": []})
    policy = model.policy
    policy.set_training_mode(False)
    obs = torch.as_tensor(np.stack([venv.envs[0].reset(seed=k)[0] for k in range(4)]))
    generator = torch.Generator().manual_seed(0)
    states = model._last_lstm_states
    states = type(states)(*[tuple(torch.randn(t.shape, generator=generator) for t in pair) for pair in states])
    episode_starts = torch.tensor(starts)
    with torch.no_grad():
        lean = policy.forward(obs, states, episode_starts, deterministic=True)
        stock = super(SequenceLstmPolicy, policy).forward(obs, states, episode_starts, deterministic=True)
    torch.testing.assert_close(lean[0], stock[0], rtol=0, atol=0)  # the same greedy actions
    for a, b in zip(lean[1:3], stock[1:3], strict=True):
        torch.testing.assert_close(a, b, rtol=1e-5, atol=1e-6)
    for a, b in zip((*lean[3].pi, *lean[3].vf), (*stock[3].pi, *stock[3].vf), strict=True):
        torch.testing.assert_close(a, b, rtol=1e-5, atol=1e-6)


# ------------------------------------------------------------------------------------------------ FlatSMCVecEnv

FLAT_IDS = ["PW-cl_self-in-container_vs_noncontainer-v0", "PW-ba_self-in-container-v0",
            "PW-ba_pixel-touches-reference_from_left-on-floor-pushable-v0"]


@pytest.mark.parametrize("env_id", FLAT_IDS)
def test_flat_smc_vec_env_steps_as_the_wrapper(env_id: str) -> None:
    """The native flat SMC env gives SMCVecEnv's observations, rewards, dones and the info keys training reads, with
    the same seeds, across many same-step resets (classification, bring-about, pushing)."""
    spec = TrainingSpec.create(env_id, seed=3, n_envs=6, max_steps=20)
    reference, native = make_vec_env(spec, native=False), make_vec_env(spec, native=True)
    assert isinstance(reference.unwrapped, SMCVecEnv) and isinstance(native.unwrapped, FlatSMCVecEnv)
    assert native.unwrapped.action_names == reference.unwrapped.envs[0].action_names
    ended, _ = step_side_by_side(native, reference, 400, ("is_success", "primitive_steps", "TimeLimit.truncated"))
    assert ended > 50


@pytest.mark.parametrize("algo,frame_stack", [("RecurrentPPO", 1), ("TRPO", 1), ("TRPO", 3), ("PPO", 1)])
def test_train_smc_on_the_native_env_is_bit_identical(algo: str, frame_stack: int,
                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    """A flat SMC trained in FlatSMCVecEnv (train_smc's choice) is the one trained in SMCVecEnv: the same returns,
    selected update and weights."""
    import sb3_smc.learning.training as training

    settings = dict(algo=algo, total_timesteps=768, n_envs=4, n_steps=64, seed=5, frame_stack=frame_stack,
                    **({"batch_size": 128} if algo == "PPO" else {}))
    native = train_smc("PW-ba_self-in-container-v0", **settings)
    assert isinstance(native.model.get_env().unwrapped, FlatSMCVecEnv)
    monkeypatch.setattr(training, "make_vec_env", functools.partial(training.make_vec_env, native=False))
    reference = train_smc("PW-ba_self-in-container-v0", **settings)
    assert isinstance(reference.model.get_env().unwrapped, SMCVecEnv)
    assert_same_smc(reference, native)


def test_smcs_with_children_and_other_ids_keep_smc_vec_env() -> None:
    child = untrained_smc("PW-ba_self-in-container-v0", algo="TRPO", n_envs=2, seed=1)
    spec = TrainingSpec.create("PW-cl_self-in-container_vs_noncontainer-v0", children=[child.name], n_envs=2)
    assert isinstance(make_vec_env(spec, (child,)).unwrapped, SMCVecEnv)
    with pytest.raises(ValueError, match="hosts SMCs on PixelWorld ids only"):
        make_vec_env(spec, (child,), native=True)
    buggy = TrainingSpec.create("PW-ba_self-in-container-v0", n_envs=2, env_kwargs={"aaai18_reset_bug": True})
    assert isinstance(make_vec_env(buggy).unwrapped, SMCVecEnv)


def test_flat_smc_vec_env_refuses_another_observation() -> None:
    with pytest.raises(ValueError, match="needs observation='hand', got 'full'"):
        FlatSMCVecEnv(gym.make_vec("PW-ba_self-in-container-v0", num_envs=2, observation="full"))
