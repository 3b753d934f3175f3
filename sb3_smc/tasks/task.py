"""SMC tasks on any Gymnasium environment with discrete actions: :class:`SMCTask`, and the protocol :class:`TaskEnv`
that :class:`~sb3_smc.envs.wrapper.HierarchicalSMCWrapper` drives.

An SMC task is what the paper trains an SMC on (its rules, in the package's words in ``docs/smcs.md``):

* **bring-about** (``goal(env) -> bool`` on the environment's state): actions SIG1 then the environment's own
  (primitive) actions. A primitive step that makes the goal true earns +0.5, one that makes it false -0.5 (the
  shaping); SIG1 ends the episode and earns 0.5 more if the goal holds (1 in all with the shaping), else 0.
* **classification** (``label(env) -> 0 or 1``, read from the episode's initial state at reset): actions SIG0,
  SIG1, then the primitives. The signal equal to the label earns +1, the other -1; either ends the episode.
  Primitive steps earn 0.
* **bring-about-or-cannot** (``goal`` as for bring-about, and ``possible(env) -> bool``, read at reset: whether the
  goal can be brought about from this state): actions SIG1, CANNOT, then the primitives; bring-about's shaping, SIG1
  in the goal +1 in all and outside it -1, CANNOT +1 where the goal is impossible and -1 (in all) where it is not.

The signals and their rewards are PixelWorld's table of kinds (:data:`pixelworld_env.core.kinds.TASK_KINDS`).

The environment's own rewards are not the task's and are dropped. An episode is cut (truncated) after
``max_steps`` actions. When the environment ends its episode itself (Minigrid reaching its goal square, a time
limit of its own), the task's episode ends there, as if the SMC had stopped without a signal: terminated if the
environment terminated, truncated if it truncated; a kind with a goal then pays what a right SIG1 would (0.5 if the
goal holds, else nothing), a classification task nothing more.

The observation is the environment's, flattened to float32 (:attr:`SMCTask.sensor_size` values): a ``Box``,
``Discrete`` (one-hot), ``MultiBinary`` / ``MultiDiscrete`` or a ``Dict`` / ``Tuple`` of them, as
``gymnasium.spaces.flatten`` flattens them; ``observation=("image", "direction")`` takes only those keys of a
``Dict`` (Minigrid's ``mission`` is text, which has no flat form), and a function ``observation(obs) -> array``
builds it any other way. Anything else is refused at construction, naming what cannot be flattened. Sensor values
must be finite: an observation holding NaN or an infinity is an :class:`~sb3_smc.errors.SMCError` at the ``reset`` or
step that gave it, naming the environment and the value's index among the sensor values.
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Sequence
from typing import Any, Protocol, runtime_checkable

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from pixelworld_env.core.kinds import GOAL_POTENTIAL, GOAL_REWARD, SIGNAL_REWARD, TASK_KINDS
from pixelworld_env.envs.env import PixelWorldEnv
from pixelworld_env.validation import no_episode
from sb3_smc.core.layout import SIGNALS, Layout
from sb3_smc.errors import SMCError, SMCTypeError

__all__ = ["MAX_RETURN", "SMCTask", "TaskEnv", "describe_task", "layout_of", "returns_bounded", "task_layer"]

MAX_RETURN = max(SIGNAL_REWARD, GOAL_REWARD)
"""The largest undiscounted return an episode of an SMC task can earn, a clean success of either kind (1): the right
signal once, or (the shaping telescoping to at most ``GOAL_POTENTIAL``) SIG1 in the goal. No task with these rules
returns more, PixelWorld's or :class:`SMCTask`'s, whatever the SMC calls; a subclass that rewards otherwise, or a
wrapper that changes the rewards on their way, may (:func:`returns_bounded`)."""

Goal = Callable[[gym.Env], bool]
Label = Callable[[gym.Env], int]
Possible = Callable[[gym.Env], bool]
Observation = Callable[[Any], np.ndarray]


@runtime_checkable
class TaskEnv(Protocol):
    """What :class:`~sb3_smc.envs.wrapper.HierarchicalSMCWrapper` needs of the environment under it (beside Gymnasium's
    ``reset``): :class:`pixelworld_env.PixelWorldEnv` implements it natively, :class:`SMCTask` for any environment.

    ``action_names`` are the task's signals then its ``primitive_names``; :meth:`sense` writes the current sensor
    values (``sensor_size`` of them) into the start of an observation; :meth:`transition` takes one action of the
    episode (a signal or a primitive) and returns ``(reward, terminated, truncated, info)``;
    :meth:`apply_primitive` takes a primitive inside an SMC call (not counted against ``max_steps``) and returns
    ``(reward, terminated, truncated)``, the last two true when the environment itself ended the episode.
    """

    @property
    def kind(self) -> str: ...

    @property
    def action_names(self) -> tuple[str, ...]: ...

    @property
    def primitive_names(self) -> tuple[str, ...]: ...

    @property
    def sensor_size(self) -> int: ...

    @property
    def max_steps(self) -> int: ...

    def sense(self, out: np.ndarray) -> np.ndarray: ...

    def transition(self, action: int) -> tuple[float, bool, bool, dict[str, Any]]: ...

    def apply_primitive(self, action: int) -> tuple[float, bool, bool]: ...

    def step_info(self) -> dict[str, Any]: ...


def layout_of(task: TaskEnv) -> Layout:
    """The :class:`~sb3_smc.smc.smc.Layout` of the SMCs that act on ``task``."""
    return Layout(task.sensor_size, task.primitive_names)


def _flattener(space: spaces.Space, observation: Observation | Sequence[str] | None
               ) -> tuple[Callable[[Any], np.ndarray], int]:
    """A function from the environment's observations to flat float32 sensor values, and their count."""
    if callable(observation):
        sample = np.asarray(observation(space.sample()), dtype=np.float32)
        if sample.ndim != 1 or sample.size == 0:
            raise SMCError(f"observation= must return a non-empty 1-D array, got shape {sample.shape} for a sample "
                           "of the environment's observation space")
        user = observation
        return (lambda obs: np.asarray(user(obs), dtype=np.float32)), int(sample.size)
    if observation is not None:
        keys = [observation] if isinstance(observation, str) else list(observation)
        if not isinstance(space, spaces.Dict):
            raise SMCError(f"observation={keys!r} takes keys of a Dict observation, but the environment's is "
                           f"{space}")
        missing = [key for key in keys if key not in space.spaces]
        if missing:
            raise SMCError(f"observation keys {missing} are not in the environment's observation "
                           f"(it has {list(space.spaces)})")
        parts = [(key, space.spaces[key]) for key in keys]
        for key, part in parts:
            _check_flat(part, f"observation key {key!r}")
        size = sum(spaces.flatdim(part) for _, part in parts)
        return (lambda obs: np.concatenate([spaces.flatten(part, obs[key]) for key, part in parts]
                                           ).astype(np.float32, copy=False)), size
    _check_flat(space, "the environment's observation")
    return (lambda obs: np.asarray(spaces.flatten(space, obs), dtype=np.float32)), spaces.flatdim(space)


def _check_flat(space: spaces.Space, what: str) -> None:
    """:class:`SMCError` naming the part of ``space`` that has no flat numeric form."""
    if isinstance(space, spaces.Dict):
        for key, part in space.spaces.items():
            _check_flat(part, f"{what}[{key!r}]")
    elif isinstance(space, spaces.Tuple):
        for i, part in enumerate(space.spaces):
            _check_flat(part, f"{what}[{i}]")
    elif not isinstance(space, spaces.Box | spaces.Discrete | spaces.MultiBinary | spaces.MultiDiscrete):
        hint = (": give observation=[keys] to take only some keys of the Dict, or observation=function"
                if "[" in what else ": give observation=function to build the sensor values")
        raise SMCError(f"{what} is {space}, which has no flat numeric form{hint}")


def _primitive_names(env: gym.Env, n: int, names: Sequence[str] | None) -> tuple[str, ...]:
    """The names of the environment's ``n`` actions: ``names``, else an enum the environment keeps as ``actions``
    (Minigrid's), else ``A0``, ``A1``, ..."""
    if names is not None:
        names = tuple(names)
        if len(names) != n:
            raise SMCError(f"primitive_names has {len(names)} names, but the environment has {n} actions")
        return names
    actions = getattr(env.unwrapped, "actions", None)
    if isinstance(actions, type) and issubclass(actions, enum.Enum) and len(actions) == n:
        ordered = sorted(actions, key=lambda a: a.value)
        if [a.value for a in ordered] == list(range(n)):
            return tuple(a.name for a in ordered)
    return tuple(f"A{i}" for i in range(n))


class SMCTask(gym.Wrapper, gym.utils.RecordConstructorArgs):
    """``env`` (any Gymnasium environment with a ``Discrete`` action space) as an SMC task of ``kind``
    ``"bring-about"`` (with ``goal``), ``"classification"`` (with ``label``) or ``"bring-about-or-cannot"`` (with
    ``goal`` and ``possible``): the paper's signals, rewards and episode limit (see the module docstring), the
    environment's observation flattened to its sensor values.

    ``goal(env)`` and ``possible(env)`` (bools, numpy's too; anything else is a ``TypeError`` naming the function)
    and ``label(env)`` (0 or 1) receive the unwrapped environment (Minigrid's ``MiniGridEnv``, with its ``agent_pos``,
    ``carrying``, ``grid``). ``primitive_names`` names the environment's actions (default: its
    ``actions`` enum, as Minigrid has, else ``A0``...). It is a Gymnasium environment of its own (``reset`` /
    ``step``, observation the sensor values) and the :class:`TaskEnv` a
    :class:`~sb3_smc.envs.wrapper.HierarchicalSMCWrapper` builds SMC calls on.
    """

    def __init__(self, env: gym.Env, kind: str, *, goal: Goal | None = None, label: Label | None = None,
                 possible: Possible | None = None, observation: Observation | Sequence[str] | None = None,
                 max_steps: int = 100, primitive_names: Sequence[str] | None = None) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, kind=kind, goal=goal, label=label, possible=possible,
                                                 observation=observation, max_steps=max_steps,
                                                 primitive_names=primitive_names)
        super().__init__(env)
        if not isinstance(env.action_space, spaces.Discrete) or int(env.action_space.start) != 0:
            raise SMCError(f"an SMC task needs a Discrete action space starting at 0 (actions become SMC actions), "
                           f"got {env.action_space}")
        if kind not in SIGNALS:
            raise SMCError(f"kind must be one of {tuple(SIGNALS)}, got {kind!r}")
        self.task_kind = TASK_KINDS[kind]  # SIGNALS is the table's
        given: dict[str, Callable[[gym.Env], Any] | None] = {"goal": goal, "label": label, "possible": possible}
        needed: list[str] = ["goal"] if self.task_kind.tracks_goal else []
        if self.task_kind.label is not None:
            needed.append(self.task_kind.label)
        for name in needed:
            if not callable(given[name]):
                raise SMCTypeError(f"a {kind} task needs {name}=function(env), got {given[name]!r}")
        extra = [name for name, value in given.items() if value is not None and name not in needed]
        if extra:
            raise SMCError(f"a {kind} task takes {', '.join(f'{n}=' for n in needed)}, not {extra[0]}=")
        if not isinstance(max_steps, int) or isinstance(max_steps, bool) or max_steps < 1:
            raise SMCError(f"max_steps must be an integer >= 1, got {max_steps!r}")
        self.kind = kind
        self.max_steps = max_steps
        self._goal_of = goal
        self._label_of, self._possible_of = label, possible
        self._flatten, self.sensor_size = _flattener(env.observation_space, observation)
        self.primitive_names = _primitive_names(env, int(env.action_space.n), primitive_names)
        self.action_names = (*SIGNALS[kind], *self.primitive_names)
        Layout(self.sensor_size, self.primitive_names)  # the names' checks
        self._n_signals = len(SIGNALS[kind])
        self.action_space = spaces.Discrete(len(self.action_names))
        self.observation_space = spaces.Box(-np.inf, np.inf, shape=(self.sensor_size,), dtype=np.float32)
        self._sensor = np.zeros(self.sensor_size, dtype=np.float32)
        self._goal = False
        self._label = 0
        self._steps = 0
        self._started = False
        self._done = True

    # ------------------------------------------------------------------------------------------ the task

    def _read_bool(self, function: Goal | Possible) -> bool:
        holds = function(self.env.unwrapped)
        if not isinstance(holds, bool | np.bool_):
            name = getattr(function, "__qualname__", repr(function))
            which = "goal" if function is self._goal_of else "possible"
            raise SMCTypeError(f"{which} function {name} must return a bool (True or False, numpy bools too), got "
                               f"{holds!r} ({type(holds).__name__})")
        return bool(holds)

    def _read_goal(self) -> bool:
        assert self._goal_of is not None
        return self._read_bool(self._goal_of)

    def _read_sensor(self, obs: Any, method: str) -> np.ndarray:
        """The sensor values of the observation ``obs`` the environment's ``method`` returned; :class:`SMCError`
        naming the environment and the first value that is NaN or infinite (no policy can act on it)."""
        sensor = self._flatten(obs)
        if not np.isfinite(sensor).all():
            bad = np.flatnonzero(~np.isfinite(sensor))
            name = getattr(self.env.spec, "id", None) or type(self.env.unwrapped).__name__
            raise SMCError(f"environment {name}: the observation its {method}() returned holds {sensor[bad[0]]} at "
                           f"index {bad[0]} of the {sensor.size} sensor values (flattened; {bad.size} not finite): an "
                           "SMC needs finite observations")
        return sensor

    def _check_episode(self, method: str) -> None:
        """``RuntimeError`` unless an episode is running (``reset`` called, the episode not ended)."""
        if self._done:
            raise no_episode(self._started, method)

    def _info(self, success: bool = False, signalled: bool = False) -> dict[str, Any]:
        info: dict[str, Any] = {"is_success": success, "signalled": signalled}
        if self.task_kind.tracks_goal:
            info["goal"] = self._goal
        if self.task_kind.label is not None:  # "label" whatever it says (bring-about-or-cannot: possible)
            info["label"] = self._label
        return info

    def sense(self, out: np.ndarray) -> np.ndarray:
        out[: self.sensor_size] = self._sensor
        return out

    def step_info(self) -> dict[str, Any]:
        return self._info()

    def apply_primitive(self, action: int) -> tuple[float, bool, bool]:
        """Primitive ``action`` (an index into :attr:`action_names`) on the environment, not counted against
        ``max_steps``: ``(reward, terminated, truncated)`` (the last two: the environment ended its episode)."""
        self._check_episode("apply_primitive")
        if not self._n_signals <= action < len(self.action_names):
            raise SMCError(f"action {action} is not a primitive action of this task ({self.action_names})")
        obs, _, terminated, truncated, _ = self.env.step(action - self._n_signals)
        self._sensor = self._read_sensor(obs, "step")
        reward = 0.0
        if self.task_kind.tracks_goal:
            goal = self._read_goal()
            if goal != self._goal:
                self._goal = goal
                reward = GOAL_POTENTIAL if goal else -GOAL_POTENTIAL
        ended = bool(terminated or truncated)
        if ended:
            self._done = True
            reward += self.task_kind.reward_at_end(self._label, self._goal)
        return reward, bool(terminated), bool(truncated and not terminated)

    def transition(self, action: int) -> tuple[float, bool, bool, dict[str, Any]]:
        """One action of the episode: ``(reward, terminated, truncated, info)``."""
        self._check_episode("step")
        self._steps += 1
        if action < self._n_signals:
            reward = self.task_kind.reward(action, self._label, self._goal)
            self._done = True
            return reward, True, False, self._info(success=reward > 0, signalled=True)
        reward, terminated, truncated = self.apply_primitive(action)
        truncated = truncated or (not terminated and self._steps >= self.max_steps)
        self._done = terminated or truncated
        return reward, terminated, truncated, self._info(success=self._done and reward > 0)

    # ------------------------------------------------------------------------------------------ gym API

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[np.ndarray, dict[str, Any]]:
        obs, info = self.env.reset(seed=seed, options=options)
        self._sensor = self._read_sensor(obs, "reset")
        self._steps = 0
        self._started = True
        self._done = False
        if self.task_kind.tracks_goal:
            self._goal = self._read_goal()
        if self.task_kind.label == "possible":
            assert self._possible_of is not None
            self._label = int(self._read_bool(self._possible_of))
        elif self.task_kind.label == "label":
            assert self._label_of is not None
            label = self._label_of(self.env.unwrapped)
            if label not in (0, 1) or isinstance(label, float):
                raise SMCError(f"label(env) must give 0 or 1, got {label!r}")
            self._label = int(label)
        return self._sensor.copy(), {**info, **self._info()}

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        if not self.action_space.contains(action):
            raise SMCError(f"action must be an integer in [0, {len(self.action_names)}), got {action!r}")
        reward, terminated, truncated, info = self.transition(int(action))
        return self._sensor.copy(), reward, terminated, truncated, info


_REWARD_METHODS = {PixelWorldEnv: ("transition", "apply_primitive", "apply_move", "_move"),
                   SMCTask: ("transition", "apply_primitive")}


def returns_bounded(task: TaskEnv) -> bool:
    """Whether no episode of ``task`` returns more than :data:`MAX_RETURN`: a :class:`pixelworld_env.PixelWorldEnv`
    or :class:`SMCTask` whose reward methods are those classes' own (not a subclass's)."""
    return any(isinstance(task, cls) and all(getattr(type(task), name) is getattr(cls, name) for name in names)
               for cls, names in _REWARD_METHODS.items())


def task_layer(env: gym.Env) -> TaskEnv:
    """The task under ``env``'s wrappers that SMC calls act on: a :class:`pixelworld_env.PixelWorldEnv` or an
    :class:`SMCTask` (the outermost one); :class:`SMCTypeError` if there is none."""
    layer: Any = env
    while True:
        if isinstance(layer, PixelWorldEnv | SMCTask):
            return layer
        if not isinstance(layer, gym.Wrapper):
            raise SMCTypeError(f"SMCs act on a PixelWorld environment or an SMCTask (sb3_smc.tasks.task: any Gymnasium "
                               f"environment with a goal or a label); got {type(env.unwrapped).__name__} without one")
        layer = layer.env


def describe_task(env_id: str, env_kwargs: dict[str, Any] | None = None) -> tuple[str, Layout] | None:
    """The kind and layout of the SMC task registered as ``env_id`` (``"module:Id-v0"`` imports the module first, as
    ``gym.make`` does), read from one instance of it; ``None`` if the id is not registered or is not a task (a bare
    environment)."""
    try:
        env = gym.make(env_id, **(env_kwargs or {}))
    except gym.error.Error:
        return None
    try:
        task = task_layer(env)
    except SMCTypeError:
        return None
    finally:
        env.close()
    return task.kind, layout_of(task)
