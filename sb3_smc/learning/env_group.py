"""The shared vector env of a group of SMCs trained together (:func:`~sb3_smc.learning.batched.train_smcs`):
:class:`EnvGroup`, one native SMC env stepped in one call for all of them, and :class:`SliceVecEnv`, one model's
share of it as an SB3 ``VecEnv``."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from stable_baselines3.common.vec_env import VecEnv
from stable_baselines3.common.vec_env.base_vec_env import VecEnvIndices, VecEnvObs, VecEnvStepReturn

from sb3_smc.envs.vec_env import NativeSMCVecEnv, SMCStep

__all__ = ["EnvGroup", "SliceVecEnv"]


class SliceVecEnv(VecEnv):
    """Environments ``[start, stop)`` of a group's shared :class:`~sb3_smc.envs.vec_env.NativeSMCVecEnv`, as one model's
    SB3 ``VecEnv``. The group steps them: :meth:`step_async` writes the actions into the group's action array,
    :meth:`step_wait` returns this slice of the group's last step; :meth:`reset` returns this slice of the
    group's reset (done once for all, with each slice's seeds)."""

    def __init__(self, group: EnvGroup, index: int, start: int, stop: int) -> None:
        self.group, self.index, self.start, self.stop = group, index, start, stop  # before VecEnv's set-up
        super().__init__(stop - start, group.env.observation_space, group.env.action_space)

    def reset(self) -> VecEnvObs:
        return self.group.reset_obs[self.start:self.stop]

    def step_async(self, actions: np.ndarray) -> None:
        self.group.actions[self.start:self.stop] = actions

    def step_wait(self) -> VecEnvStepReturn:
        obs, rewards, dones, infos = self.group.results
        part = slice(self.start, self.stop)
        return obs[part], rewards[part], dones[part], infos[part]

    def close(self) -> None:
        """Nothing: the group owns the environments."""

    def _indices(self, indices: VecEnvIndices) -> list[int]:
        return [self.start + i for i in self._get_indices(indices)]

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        return self.group.env.get_attr(attr_name, self._indices(indices))

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        self.group.env.set_attr(attr_name, value, self._indices(indices))

    def env_method(self, method_name: str, *method_args: Any, indices: VecEnvIndices = None,
                   **method_kwargs: Any) -> list[Any]:
        return self.group.env.env_method(method_name, *method_args, indices=self._indices(indices), **method_kwargs)

    def env_is_wrapped(self, wrapper_class: type, indices: VecEnvIndices = None) -> list[bool]:
        return self.group.env.env_is_wrapped(wrapper_class, self._indices(indices))


class EnvGroup:
    """One native SMC env (:func:`~sb3_smc.envs.hierarchical_vec_env.native_smc_vec_env`) for the SMCs of a task:
    ``sizes[i]`` of its environments for SMC ``i``, stepped in one call."""

    def __init__(self, env: NativeSMCVecEnv, sizes: Sequence[int]) -> None:
        self.env = env
        self.bounds = np.cumsum([0, *sizes])
        self.slices = [SliceVecEnv(self, i, int(a), int(b))
                       for i, (a, b) in enumerate(zip(self.bounds[:-1], self.bounds[1:], strict=True))]
        self.actions = np.zeros(self.env.num_envs, dtype=np.int64)
        self.reset_obs: np.ndarray = np.zeros(0)
        self.step_result: SMCStep | None = None
        self.results: tuple[np.ndarray, np.ndarray, np.ndarray, list[dict[str, Any]]] = (
            np.zeros(0), np.zeros(0), np.zeros(0), [])
        self.with_infos = True  #: whether a step builds SB3's info dicts (for SMCs on the generic path)
        self.calls = np.zeros(0, dtype=np.int64)  #: the environments that called a child at the last step
        self.ended_at = np.zeros(len(sizes) + 1, dtype=np.int64)  #: see step
        self.calls_at = np.zeros(len(sizes) + 1, dtype=np.int64)

    def reset(self) -> None:
        """Reset every environment with the seeds its model set (``VecEnv.seed`` of each slice)."""
        self.env._seeds = [seed for part in self.slices for seed in part._seeds]
        self.reset_obs = np.asarray(self.env.reset())
        for part in self.slices:
            part._reset_seeds()

    def step(self) -> None:
        """Step every environment with :attr:`actions`; slice ``i``'s environments whose episode ended are
        ``step_result.ended[ended_at[i]:ended_at[i + 1]]``, those that called a child
        ``calls[calls_at[i]:calls_at[i + 1]]`` (group indices)."""
        step = self.step_result = self.env.step_arrays(self.actions)
        self.ended_at = np.searchsorted(step.ended, self.bounds)
        self.calls = np.flatnonzero(step.called >= 0)
        self.calls_at = np.searchsorted(self.calls, self.bounds)
        if self.with_infos:
            self.results = (step.obs, step.rewards, step.dones, self.env.step_infos(step))
        self.actions[:] = 0  # the actions of SMCs that left the group
