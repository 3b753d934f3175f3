"""``SMCVecEnv``: SB3's ``DummyVecEnv`` for SMC environments, with the SMC calls of all environments in lockstep.

A level-2 SMC spends most of its time in its children: each call runs a child policy one decision at a time.
Stepped one environment after another, every decision of every environment is one small policy evaluation.
Here the calls of all environments advance together: at each round, the pending decisions of the environments
are grouped by policy and each group is answered by one ``probabilities_batch`` call (policies without one, such
as scripted ones, answer one by one; the compiled numpy actors of the default architecture, whose single steps
cost less than stacking a group, declare ``batch_from = None`` and the wrapper asks them directly, without a round
trip through here). Every environment samples from its own generator
as before, so a seed gives the same episodes; only the rounding of batched matrix products can differ from
unbatched ones (see ``docs/benchmarks.md``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, cast

import gymnasium as gym
import numpy as np
from stable_baselines3.common.vec_env import DummyVecEnv
from stable_baselines3.common.vec_env.base_vec_env import VecEnvStepReturn

from sb3_smc.wrapper import HierarchicalSMCWrapper

__all__ = ["SMCVecEnv", "answer_in_batches"]


def answer_in_batches(requests: dict[int, tuple[Any, np.ndarray, Any]]) -> dict[int, tuple[np.ndarray, Any]]:
    """Answer pending policy decisions ``{key: (policy, observation, state)}`` with ``{key: (probabilities,
    next state)}``: one ``probabilities_batch`` call per policy with at least ``policy.batch_from`` decisions
    pending (default 2; ``None``: never, as for the compiled numpy actors), single calls otherwise."""
    if len(requests) == 1:
        (key, (policy, observation, state)), = requests.items()
        return {key: policy.probabilities(observation, state)}
    groups: dict[int, list[int]] = {}
    for key, (policy, _, _) in requests.items():
        groups.setdefault(id(policy), []).append(key)
    answers: dict[int, tuple[np.ndarray, Any]] = {}
    for keys in groups.values():
        policy = requests[keys[0]][0]
        batch = getattr(policy, "probabilities_batch", None)
        threshold = getattr(policy, "batch_from", 2)
        if batch is None or threshold is None or len(keys) < threshold:
            for key in keys:
                _, observation, state = requests[key]
                answers[key] = policy.probabilities(observation, state)
            continue
        probabilities, states = batch(np.stack([requests[key][1] for key in keys]), [requests[key][2] for key in keys])
        for row, key in enumerate(keys):
            answers[key] = (probabilities[row], states[row])
    return answers


class SMCVecEnv(DummyVecEnv):
    """``DummyVecEnv`` whose :class:`~sb3_smc.wrapper.HierarchicalSMCWrapper` environments run their SMC calls in
    lockstep (one batched policy evaluation per child and decision round, :func:`answer_in_batches`).

    Other environments step as in ``DummyVecEnv``. Step infos are copied shallowly instead of deep-copied: the
    wrapper returns a new ``info`` dict (and a new ``smc_calls`` list) at every step, so the deep copy
    ``DummyVecEnv`` makes against aliasing would only cost time.
    """

    def __init__(self, env_fns: Sequence[Callable[[], gym.Env]]) -> None:
        super().__init__(list(env_fns))
        self._coroutine_step = [isinstance(env, HierarchicalSMCWrapper) for env in self.envs]

    def step_wait(self) -> VecEnvStepReturn:
        results: list[Any] = [None] * self.num_envs
        running: dict[int, Any] = {}
        requests: dict[int, tuple[Any, np.ndarray, Any]] = {}
        for i, env in enumerate(self.envs):
            if not self._coroutine_step[i]:
                results[i] = env.step(self.actions[i])
                continue
            coroutine = cast(HierarchicalSMCWrapper, env).step_coroutine(self.actions[i])  # as _coroutine_step says
            try:
                requests[i] = next(coroutine)
                running[i] = coroutine
            except StopIteration as stop:
                results[i] = stop.value
        while requests:
            answers = answer_in_batches(requests)
            requests = {}
            for i, answer in answers.items():
                try:
                    requests[i] = running[i].send(answer)
                except StopIteration as stop:
                    results[i] = stop.value
                    del running[i]
        for i, (obs, reward, terminated, truncated, info) in enumerate(results):
            self.buf_rews[i] = reward
            self.buf_dones[i] = terminated or truncated
            info["TimeLimit.truncated"] = truncated and not terminated
            if self.buf_dones[i]:
                info["terminal_observation"] = obs
                obs, self.reset_infos[i] = self.envs[i].reset()
            self.buf_infos[i] = info
            self._save_obs(i, obs)
        return self._obs_from_buf(), np.copy(self.buf_rews), np.copy(self.buf_dones), [dict(i) for i in self.buf_infos]
