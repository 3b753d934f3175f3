"""The SMC observation and the step's rules are defined once (``sb3_smc.envs.smc_step``) and every step path uses
them: ``HierarchicalSMCWrapper`` (one environment), ``FlatSMCVecEnv`` and ``HierarchicalSMCVecEnv`` (arrays of
environments). The equality of the paths' transitions is tested in ``tests/test_vec_env.py`` and
``tests/test_hierarchical_vec_env.py``; here, that the shared definitions are the ones each path calls: changed
here, every path changes."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest

from sb3_smc import SMC
from sb3_smc.core.layout import observation_size, smc_action_names
from sb3_smc.envs import smc_step
from sb3_smc.envs.hierarchical_vec_env import HierarchicalSMCVecEnv
from sb3_smc.envs.smc_step import NO_ACTION, SMCObservation
from sb3_smc.envs.vec_env import FlatSMCVecEnv
from sb3_smc.envs.wrapper import HierarchicalSMCWrapper
from sb3_smc.smc.policies import ScriptedPolicy

ENV_ID = "PW-cl_self-in-container_vs_noncontainer-v0"
MOVES = ("DOWN", "RIGHT", "UP", "LEFT")


def flat_env(num_envs: int = 3, max_steps: int = 100) -> FlatSMCVecEnv:
    venv = FlatSMCVecEnv(gym.make_vec(ENV_ID, num_envs=num_envs, max_steps=max_steps))
    venv.seed(0)
    return venv


def hierarchical_env(num_envs: int = 3, max_steps: int = 100) -> HierarchicalSMCVecEnv:
    """The native env of an SMC calling one compiled leaf (a random policy)."""
    from tests.test_compiled_calls import random_smc

    venv = HierarchicalSMCVecEnv(gym.make_vec(ENV_ID, num_envs=num_envs, max_steps=max_steps),
                                 [random_smc("leaf", "classification", "lstm")])
    venv.seed(0)
    return venv


def recording_child(seen: list[np.ndarray]) -> SMC:
    """A leaf SMC (scripted, so its calls run in Python) that records what it observes: two moves, then SIG1."""
    names = smc_action_names("classification")

    def act(obs: np.ndarray, step: int) -> int:
        seen.append(obs.copy())
        return names.index("SIG1") if step >= 2 else names.index("RIGHT")

    return SMC("child", "classification", ScriptedPolicy(len(names), act))


@pytest.mark.parametrize("n_outcomes,n_actions", [(0, 6), (3, 9)])
def test_rows_and_one_observation_are_written_alike(n_outcomes: int, n_actions: int) -> None:
    """``write`` gives each row of a batch what it gives that observation alone: the sensor left as written, the
    outcomes, the one-hot previous action (none for NO_ACTION)."""
    parts = SMCObservation(81, n_outcomes, n_actions)
    assert parts.size == observation_size(n_outcomes, n_actions) == parts.blank().shape[0]
    assert (parts.sensor, parts.outcomes, parts.previous) == (slice(0, 81), slice(81, 81 + n_outcomes),
                                                               81 + n_outcomes)
    rng = np.random.default_rng(0)
    n = 2 * n_actions
    sensor = rng.integers(0, 2, size=(n, 81)).astype(np.float32)
    outcomes = rng.choice([-1.0, 0.0, 1.0], size=(n, n_outcomes)).astype(np.float32)
    previous = np.concatenate([np.arange(n_actions), np.full(n_actions, NO_ACTION)])
    rows = parts.blank(n)
    rows[:, parts.sensor] = sensor
    rows = parts.write(rows, outcomes if n_outcomes else None, previous)
    for k in range(n):
        one = parts.blank()
        one[parts.sensor] = sensor[k]
        one = parts.write(one, outcomes[k] if n_outcomes else None, int(previous[k]))
        np.testing.assert_array_equal(rows[k], one)
        expected = np.concatenate([sensor[k], outcomes[k], np.eye(n_actions)[previous[k]] if previous[k] >= 0
                                   else np.zeros(n_actions)]).astype(np.float32)
        np.testing.assert_array_equal(one, expected)
    assert rows.dtype == np.float32 and parts.space().contains(rows[0])


def test_the_rules_give_scalars_and_arrays_the_same_answers() -> None:
    cases = [(t, e, el) for t in (False, True) for e in (False, True) for el in (3, 99, 100, 101)]
    terminated, env_truncated, elapsed = (np.array(column) for column in zip(*cases, strict=True))
    truncated = smc_step.truncated(terminated, env_truncated, elapsed, 100)
    assert truncated.tolist() == [smc_step.truncated(t, e, el, 100) for t, e, el in cases]
    assert truncated.tolist() == [not t and (e or el >= 100) for t, e, el in cases]
    assert all(type(smc_step.truncated(t, e, el, 100)) is bool for t, e, el in cases)
    done, reward = np.array([False, True, True, True]), np.array([1.0, 1.0, 0.0, -1.0])
    assert smc_step.is_success(done, reward).tolist() == [smc_step.is_success(bool(d), float(r))
                                                          for d, r in zip(done, reward, strict=True)]
    assert smc_step.is_success(done, reward).tolist() == [False, True, False, False]
    assert [smc_step.step_cost(m, c) for m, c in ((None, False), (None, True), (0, False), (7, False), (0, True),
                                                   (7, True))] == [1, 1, 1, 1, 1, 7]
    assert smc_step.primitive_steps(("SIG0", "SIG1", *MOVES, "SMC:a"), MOVES) == (0, 0, 1, 1, 1, 1, 0)


def test_both_paths_write_the_observation_with_the_shared_function(monkeypatch: pytest.MonkeyPatch) -> None:
    """A changed ``SMCObservation.write`` shows in every observation of both paths: the flat env's (after a reset,
    a step and a same-step reset), the wrapper's, and that of an SMC the wrapper calls."""
    original = SMCObservation.write
    calls: list[int] = []

    def marked(self: SMCObservation, obs: np.ndarray, outcomes: Any, previous: Any) -> np.ndarray:
        calls.append(obs.ndim)
        original(self, obs, outcomes, previous)
        obs[..., self.sensor] = -0.5
        return obs

    monkeypatch.setattr(SMCObservation, "write", marked)
    for venv in (flat_env(max_steps=2), hierarchical_env(max_steps=2)):
        observations = [venv.reset()]
        for _ in range(3):  # the second step ends every episode (max_steps=2): same-step resets
            observations.append(venv.step(np.full(venv.num_envs, 2))[0])
        assert np.all(np.stack(observations)[..., :81] == -0.5)
        assert calls and set(calls) == {2}
        calls.clear()

    calls.clear()
    seen: list[np.ndarray] = []
    env = HierarchicalSMCWrapper(gym.make(ENV_ID), [recording_child(seen)])
    observations = [env.reset(seed=0)[0], env.step(env.action_names.index("RIGHT"))[0],
                    env.step(env.action_names.index("SMC:child"))[0]]
    assert len(seen) == 3 and all(np.all(obs[:81] == -0.5) for obs in [*observations, *seen])
    assert set(calls) == {1} and len(calls) == 6


def test_both_paths_apply_the_shared_step_rules(monkeypatch: pytest.MonkeyPatch) -> None:
    """Changed step rules (every action two steps, success on any end, 7 primitive steps per move) change the
    episodes and infos of both paths alike."""
    monkeypatch.setattr(smc_step, "step_cost", lambda call_moves, count_primitive_steps: 2)
    monkeypatch.setattr(smc_step, "is_success", lambda done, reward: done)
    monkeypatch.setattr(smc_step, "primitive_steps", lambda names, primitives: tuple(
        7 * int(name in primitives) for name in names))
    right = 3  # RIGHT in a classification SMC's actions: SIG0, SIG1, DOWN, RIGHT, ...
    flat, native = flat_env(max_steps=6), hierarchical_env(max_steps=6)
    for venv in (flat, native):
        venv.reset()
    env = HierarchicalSMCWrapper(gym.make(ENV_ID, max_steps=6))
    env.reset(seed=0)
    for step in range(3):
        _, _, terminated, truncated, info = env.step(right)
        ended = step == 2  # 3 steps of cost 2: max_steps=6 reached
        assert (terminated, truncated) == (False, ended) and info["is_success"] == ended
        assert info["primitive_steps"] == 7 and info["elapsed_steps"] == 2 * (step + 1)
        for venv in (flat, native):
            _, _, dones, infos = venv.step(np.full(venv.num_envs, right))
            assert dones.tolist() == [ended] * venv.num_envs
            assert [i["is_success"] for i in infos] == [ended] * venv.num_envs
            assert [i["primitive_steps"] for i in infos] == [7] * venv.num_envs
            assert [i["TimeLimit.truncated"] for i in infos] == [ended] * venv.num_envs


def test_the_truncation_rule_is_the_one_both_paths_call(monkeypatch: pytest.MonkeyPatch) -> None:
    """A changed truncation rule (cut after one step) ends the episodes of both paths after one step."""
    original = smc_step.truncated
    monkeypatch.setattr(smc_step, "truncated", lambda terminated, env_truncated, elapsed, max_steps: original(
        terminated, env_truncated, elapsed, 1))
    for venv in (flat_env(), hierarchical_env()):
        venv.reset()
        assert venv.step(np.full(venv.num_envs, 3))[2].all()
    env = HierarchicalSMCWrapper(gym.make(ENV_ID))
    env.reset(seed=0)
    assert env.step(3)[3]
