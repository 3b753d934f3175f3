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

from abc import abstractmethod
from collections.abc import Callable, Sequence
from typing import Any, NamedTuple, cast

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from stable_baselines3.common.vec_env import DummyVecEnv
from stable_baselines3.common.vec_env.base_vec_env import VecEnvObs, VecEnvStepReturn

from pixelworld_env.envs.vector import PixelWorldVectorEnv
from sb3_smc.core.layout import HAND_SIZE, MOVES, smc_action_names
from sb3_smc.envs import smc_step
from sb3_smc.envs.gymnasium_vec_env import GymnasiumVecEnv
from sb3_smc.envs.smc_step import IS_SUCCESS, NO_ACTION, NO_OUTCOME, PRIMITIVE_STEPS, SMC_CALLS, SMCObservation
from sb3_smc.envs.wrapper import HierarchicalSMCWrapper
from sb3_smc.errors import SMCError

__all__ = ["FlatSMCVecEnv", "NativeSMCVecEnv", "SMCStep", "SMCVecEnv", "answer_in_batches"]


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
    """``DummyVecEnv`` whose :class:`~sb3_smc.envs.wrapper.HierarchicalSMCWrapper` environments run their SMC calls in
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


class NativeSMCVecEnv(GymnasiumVecEnv):
    """What the SMC environments over PixelWorld's native vector env (``observation="hand"``) share: the SMC's
    observation (:class:`~sb3_smc.envs.smc_step.SMCObservation`: the window, one outcome per SMC of ``children``,
    the one-hot previous action), spaces, each environment's previous action and elapsed steps, a reset without
    options, integer actions, and the step as arrays (``step_arrays``: an :class:`SMCStep`) or with SB3's info
    dicts (``step_infos``). :class:`FlatSMCVecEnv` and
    :class:`~sb3_smc.envs.hierarchical_vec_env.HierarchicalSMCVecEnv` step them."""

    def __init__(self, env: PixelWorldVectorEnv, action_names: Sequence[str], children: Sequence[str] = ()) -> None:
        if env.observation != "hand":
            raise SMCError(f"{type(self).__name__} builds SMC observations from the one-hot 3 x 3 window: the vector "
                           f"env needs observation='hand', got {env.observation!r}")
        super().__init__(env)
        self.vector_env = env
        self.kind: str = env.kind
        self.action_names = tuple(action_names)
        self.children = tuple(children)
        """The names of the SMCs called (the outcomes' order)."""
        n_outcomes = len(self.children)
        self._parts = SMCObservation(HAND_SIZE, n_outcomes, len(self.action_names))
        self.observation_space = self._parts.space()
        self.action_space = spaces.Discrete(len(self.action_names))
        self._primitive_steps = np.array(smc_step.primitive_steps(self.action_names, MOVES), dtype=np.int64)
        self._outcomes = np.full((env.num_envs, n_outcomes), NO_OUTCOME, dtype=np.float32)
        self._previous = np.full(env.num_envs, NO_ACTION, dtype=np.int64)
        self._elapsed = np.zeros(env.num_envs, dtype=np.int64)
        self._max_steps: int = env.max_steps
        self._no_calls = np.full(env.num_envs, -1, dtype=np.int64)
        self._no_outcomes = np.zeros(env.num_envs)

    def _observation(self, hand: np.ndarray) -> np.ndarray:
        parts = self._parts
        obs = parts.blank(self.num_envs)
        obs[:, parts.sensor] = hand
        return parts.write(obs, self._outcomes, self._previous)

    def _reset_all(self) -> np.ndarray:
        """Reset every environment (with the seeds given, if any; options are refused): their windows."""
        if any(self._options):
            raise SMCError(f"{type(self).__name__} takes no reset options, got {self._options}")
        seeds = None if all(s is None for s in self._seeds) else list(self._seeds)
        hand, _ = self.env.reset(seed=cast("int | None", seeds))  # a list of seeds: one per environment
        self.reset_infos = [{} for _ in range(self.num_envs)]
        self._started(np.ones(self.num_envs, dtype=np.bool_))
        return hand

    def _started(self, ended: np.ndarray) -> None:
        """The environments ``ended`` (a bool mask) have been reset: their episode state anew."""
        self._outcomes[ended] = NO_OUTCOME
        self._previous[ended] = NO_ACTION
        self._elapsed[ended] = 0

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.asarray(actions, dtype=np.int64).reshape(self.num_envs)

    def step_wait(self) -> VecEnvStepReturn:
        assert self._actions is not None, "step_async first"
        actions, self._actions = self._actions, None
        step = self.step_arrays(actions)
        return step.obs, step.rewards, step.dones, self.step_infos(step)

    @abstractmethod
    def step_arrays(self, actions: np.ndarray) -> SMCStep:
        """:meth:`step_wait` for ``actions`` (int64, one per environment) without the info dicts."""

    def step_infos(self, step: SMCStep) -> list[dict[str, Any]]:
        """SB3's info dicts of a step of :meth:`step_arrays`: the wrapper's keys that training reads
        (``is_success``, ``primitive_steps``, a call's record in ``smc_calls``), ``TimeLimit.truncated`` and
        ``terminal_observation``."""
        infos: list[dict[str, Any]] = []
        names = self.children
        for s, m, t, child, outcome, r in zip(step.success.tolist(), step.moves.tolist(), step.time_limit.tolist(),
                                              step.called.tolist(), step.outcomes.tolist(),
                                              step.call_rewards.tolist(), strict=True):
            info: dict[str, Any] = {IS_SUCCESS: s, PRIMITIVE_STEPS: m, "TimeLimit.truncated": t}
            if names:
                info[SMC_CALLS] = [] if child < 0 else [{"smc": names[child], "depth": 1, "primitive_steps": m,
                                                         "outcome": outcome, "reward": r}]
            infos.append(info)
        for k, terminal in zip(step.ended.tolist(), step.terminal, strict=True):
            infos[k]["terminal_observation"] = terminal
        return infos


class FlatSMCVecEnv(NativeSMCVecEnv):
    """SB3's ``VecEnv`` of a flat SMC (one without children) over PixelWorld's native vector env
    (:class:`pixelworld_env.envs.vector.PixelWorldVectorEnv`, ``observation="hand"``): all environments stepped in one
    compiled call.

    It gives what :class:`SMCVecEnv` over ``HierarchicalSMCWrapper`` environments without children gives, step for
    step with the same seeds: the SMC's actions (:func:`~sb3_smc.smc.smc.smc_action_names`), its observation (the
    one-hot window and the one-hot previous action, zeros after a reset), rewards, SB3's same-step reset with
    ``terminal_observation`` and ``TimeLimit.truncated``, and the info keys of the wrapper that training reads
    (``is_success``: the episode ended with a positive reward; ``primitive_steps``: 1 for a move, 0 for a signal).
    The observation and the step's rules (elapsed steps, truncation, success, ``primitive_steps``) are the
    wrapper's own, :mod:`sb3_smc.envs.smc_step`'s, applied here to the arrays of all environments at once.
    ``train_smc`` trains flat SMCs in it (:func:`sb3_smc.learning.training.make_vec_env`). ``get_attr`` and the other
    per-environment calls are :class:`~sb3_smc.envs.gymnasium_vec_env.GymnasiumVecEnv`'s.
    """

    def __init__(self, env: PixelWorldVectorEnv) -> None:
        super().__init__(env, smc_action_names(env.kind))
        self._to_base = np.array([env.action_names.index(name) for name in self.action_names], dtype=np.int64)
        self._step_cost = smc_step.step_cost(None, False)  # every action of a flat SMC is a signal or a move

    def reset(self) -> VecEnvObs:
        hand = self._reset_all()
        self._reset_seeds()
        return self._observation(hand)

    def step_arrays(self, actions: np.ndarray) -> SMCStep:
        """:meth:`step_wait` for ``actions`` (int64, one per environment) without the info dicts (their content is
        in the arrays: a flat SMC's step is one primitive action)."""
        hand, rewards, terminated, env_truncated, _ = self.env.step(self._to_base[actions])
        self._previous[:] = actions
        self._elapsed += self._step_cost
        obs = self._observation(hand)
        # the wrapper's rules; truncated is never true where terminated is, so it is also TimeLimit.truncated
        truncated = smc_step.truncated(terminated, env_truncated, self._elapsed, self._max_steps)
        dones = terminated | truncated
        ended = np.flatnonzero(dones)
        terminal = obs[ended]  # a copy (fancy indexing)
        if ended.size:
            hand, _ = self.env.reset(options={"reset_mask": dones})
            self._started(dones)
            obs[ended] = self._observation(hand)[ended]
        return SMCStep(obs, rewards.astype(np.float32), dones, smc_step.is_success(dones, rewards), truncated,
                       ended, terminal, self._primitive_steps[actions], self._no_calls, self._no_outcomes,
                       self._no_outcomes)


class SMCStep(NamedTuple):
    """One step of a :class:`NativeSMCVecEnv` as arrays (``step_arrays``)."""

    obs: np.ndarray  #: the observations after the step (after the reset where an episode ended)
    rewards: np.ndarray  #: float32
    dones: np.ndarray  #: the episode ended (terminated or truncated)
    success: np.ndarray  #: it ended with a positive reward (``is_success``)
    time_limit: np.ndarray  #: it was cut by the time limit (``TimeLimit.truncated``)
    ended: np.ndarray  #: the indices of the environments whose episode ended
    terminal: np.ndarray  #: their last observations (``terminal_observation``), one row each
    moves: np.ndarray  #: the primitive steps of each environment's action (``primitive_steps``: a call's moves)
    called: np.ndarray  #: the child each environment called (its index; -1: none)
    outcomes: np.ndarray  #: the outcome of that call (0 where none)
    call_rewards: np.ndarray  #: the reward of that call, float64 (0 where none)
