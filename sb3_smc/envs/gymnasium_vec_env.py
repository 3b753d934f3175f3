"""``GymnasiumVecEnv``: SB3's ``VecEnv`` API over a Gymnasium vector env with next-step autoreset.

SB3 takes no Gymnasium vector env; its own convention differs: an environment that ends is reset in the same step, the
step returns the reset observation, and ``infos[i]`` holds the last one as ``"terminal_observation"`` (with
``"TimeLimit.truncated"`` on every step). This adapter steps the vector env, then resets the environments that ended
with ``options={"reset_mask": done}`` (Gymnasium's partial reset, which also clears their pending next-step reset),
and turns the vector ``info`` (arrays with ``_key`` masks) into SB3's list of dicts, with the values of the single
env's ``info`` (Python scalars). Over :class:`pixelworld_env.envs.vector.PixelWorldVectorEnv` (or ``SyncVectorEnv``) a
model sees what it sees through ``DummyVecEnv`` over ``gym.make`` of the same id with the same seeds (tested on
PPO's first rollout).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, cast

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode
from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvIndices, VecEnvObs, VecEnvStepReturn

from sb3_smc.errors import SMCError

__all__ = ["GymnasiumVecEnv", "info_list"]


def info_list(info: dict[str, Any], num_envs: int) -> list[dict[str, Any]]:
    """A Gymnasium vector ``info`` (arrays, ``_key`` masks, nested dicts) as one dict per environment."""
    infos: list[dict[str, Any]] = [{} for _ in range(num_envs)]
    for key, values in info.items():
        if key.startswith("_") and key[1:] in info:
            continue
        mask = info.get(f"_{key}")
        envs = range(num_envs) if mask is None else np.flatnonzero(mask)
        if isinstance(values, dict):
            column: list[Any] = info_list(values, num_envs)
        else:
            column = values.tolist() if isinstance(values, np.ndarray) else list(values)
        for k in envs:
            infos[k][key] = column[k]
    return infos


class GymnasiumVecEnv(VecEnv):
    """SB3's ``VecEnv`` over ``env``, a Gymnasium vector env with next-step autoreset that takes
    ``options={"reset_mask": ...}`` (``PixelWorldVectorEnv``, ``SyncVectorEnv``).

    ``seed`` / ``set_options`` reach the vector env's next ``reset`` (``options={"index": i}`` per environment becomes
    its per-environment list). ``get_attr`` / ``set_attr`` read and write the vector env's own attribute (shared by
    its environments); ``env_method`` calls the vector env's method once per environment index asked for.
    """

    def __init__(self, env: gym.vector.VectorEnv) -> None:
        if env.metadata.get("autoreset_mode") != AutoresetMode.NEXT_STEP:
            raise SMCError(f"GymnasiumVecEnv needs a vector env with next-step autoreset, got "
                           f"{env.metadata.get('autoreset_mode')!r}")
        self.env = env
        super().__init__(env.num_envs, env.single_observation_space, env.single_action_space)
        self._actions: np.ndarray | None = None

    def reset(self) -> VecEnvObs:
        seeds = None if all(s is None for s in self._seeds) else list(self._seeds)
        options = None
        if any(self._options):
            unknown = {key for option in self._options for key in option} - {"index"}
            if unknown:
                raise SMCError(f"GymnasiumVecEnv passes only the reset option 'index', got {sorted(unknown)}")
            options = {"index": [option.get("index") for option in self._options]}
        # a list of seeds: the vector envs this adapter takes accept one (VectorEnv.reset is typed for an int)
        obs, info = self.env.reset(seed=cast("int | None", seeds), options=options)
        self.reset_infos = info_list(info, self.num_envs)
        self._reset_seeds()
        self._reset_options()
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions

    def step_wait(self) -> VecEnvStepReturn:
        assert self._actions is not None, "step_async first"
        obs, rewards, terminated, truncated, info = self.env.step(self._actions)
        self._actions = None
        dones = terminated | truncated
        infos = info_list(info, self.num_envs)
        for k, (term, trunc) in enumerate(zip(terminated.tolist(), truncated.tolist(), strict=True)):
            infos[k]["TimeLimit.truncated"] = trunc and not term
        ended = np.flatnonzero(dones).tolist()
        if ended:
            for k in ended:
                infos[k]["terminal_observation"] = obs[k].copy()
            obs, reset_info = self.env.reset(options={"reset_mask": dones.copy()})
            reset_infos = info_list(reset_info, self.num_envs)
            for k in ended:
                self.reset_infos[k] = reset_infos[k]
        return obs, rewards.astype(np.float32), dones, infos

    def close(self) -> None:
        self.env.close()

    def get_images(self) -> Sequence[np.ndarray | None]:
        frames = self.env.render()
        return list(cast("Sequence[np.ndarray | None]", frames)) if frames is not None else [None] * self.num_envs

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        return [getattr(self.env, attr_name)] * len(list(self._get_indices(indices)))

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        setattr(self.env, attr_name, value)

    def env_method(self, method_name: str, *method_args: Any, indices: VecEnvIndices = None,
                   **method_kwargs: Any) -> list[Any]:
        method = getattr(self.env, method_name)
        return [method(*method_args, **method_kwargs) for _ in self._get_indices(indices)]

    def env_is_wrapped(self, wrapper_class: type[gym.Wrapper], indices: VecEnvIndices = None) -> list[bool]:
        return [False] * len(list(self._get_indices(indices)))
