"""One step of an SMC's environment, defined once for both step paths (docs/design.md, "Hierarchy: SMC calls"):
:class:`~sb3_smc.envs.wrapper.HierarchicalSMCWrapper` (one environment, SMC calls among the actions) and
:class:`~sb3_smc.envs.vec_env.FlatSMCVecEnv` (a flat SMC's environments as arrays over PixelWorld's native vector env).

* The **observation** (:class:`SMCObservation`): the sensor (PixelWorld's one-hot 3 x 3 window), the last outcome of
  each SMC (:data:`SIGNAL_OUTCOMES`; :data:`NO_OUTCOME` until called in the episode, a call cut at its cap its
  kind's ``cut_outcome``), the one-hot previous action (none, :data:`NO_ACTION`, after a reset), float32.
  :meth:`SMCObservation.write` writes the outcomes and the previous action of one observation or of rows of them;
  the environment writes the sensor.
* The **step's rules**: how many of the episode's ``max_steps`` an action takes (:func:`step_cost`), when the step
  ends the episode by time (:func:`truncated`), whether the episode succeeded (:func:`is_success`), what
  ``primitive_steps`` an action that is not a call makes (:func:`primitive_steps`), and the info keys.

The functions take Python scalars (the wrapper's one environment) and numpy arrays (one entry per environment)
alike, with the same results. The two paths call them through this module (``smc_step.truncated(...)``; what is
constant for an environment, such as :func:`primitive_steps`, once when it is built), so that
``tests/test_smc_step.py`` can check, by changing them, that each path uses them.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, overload

import numpy as np
from gymnasium import spaces

from pixelworld_env.core.kinds import signal_outcomes
from sb3_smc.core.layout import observation_size

__all__ = ["ELAPSED_STEPS", "IS_SUCCESS", "NO_ACTION", "NO_OUTCOME", "PRIMITIVE_STEPS", "SIGNAL_OUTCOMES",
           "SMC_CALLS", "SMCObservation", "is_success", "primitive_steps", "step_cost", "truncated"]

SIGNAL_OUTCOMES = signal_outcomes()
"""The outcome an SMC call records for each signal (the table of kinds: +1 SIG1, -1 SIG0, -1 CANNOT)."""
NO_OUTCOME = 0.0
"""The outcome of an SMC not called in this episode (a call cut at its cap records its kind's ``cut_outcome``: 0,
or -0.5 for bring-about-or-cannot, so that a parent tells done, cannot, cut and not called apart)."""
NO_ACTION = -1
"""The previous action after a reset: none (the one-hot previous action is all zeros)."""

IS_SUCCESS = "is_success"
"""Info key: the episode ended on this step with a positive reward (:func:`is_success`)."""
PRIMITIVE_STEPS = "primitive_steps"
"""Info key: the primitive actions executed during the step, those of SMC calls included (:func:`primitive_steps`)."""
ELAPSED_STEPS = "elapsed_steps"
"""Info key of the wrapper: the steps of ``max_steps`` used so far in the episode (:func:`step_cost`)."""
SMC_CALLS = "smc_calls"
"""Info key of the wrapper: one dict per SMC call made during the step."""


@dataclass(frozen=True)
class SMCObservation:
    """The observation of an SMC with ``n_outcomes`` SMC actions and ``n_actions`` actions in all, on an environment
    with ``sensor_size`` sensor values: ``[sensor | outcomes | previous action]``
    (:func:`~sb3_smc.core.layout.observation_size` values, float32)."""

    sensor_size: int
    n_outcomes: int
    n_actions: int
    sensor: slice = field(init=False, repr=False, compare=False)
    """Where the sensor values lie (the environment writes them: ``PixelWorldEnv.sense``, the vector env's rows)."""
    outcomes: slice = field(init=False, repr=False, compare=False)
    """Where the outcome vector lies."""
    previous: int = field(init=False, repr=False, compare=False)
    """Where the one-hot previous action starts."""
    size: int = field(init=False, repr=False, compare=False)
    """The observation's length."""
    _one_hot: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        start = self.sensor_size + self.n_outcomes
        object.__setattr__(self, "sensor", slice(0, self.sensor_size))
        object.__setattr__(self, "outcomes", slice(self.sensor_size, start))
        object.__setattr__(self, "previous", start)
        object.__setattr__(self, "size", observation_size(self.n_outcomes, self.n_actions, self.sensor_size))
        # per action its one-hot row, and last (at NO_ACTION = -1) the row of no action: zeros
        object.__setattr__(self, "_one_hot", np.eye(self.n_actions + 1, self.n_actions, dtype=np.float32))

    def space(self, bounded: bool = True) -> spaces.Box:
        """The observation space: within [-1, 1] when the sensor is (PixelWorld's one-hot window), else unbounded."""
        low = -1.0 if bounded else -np.inf
        return spaces.Box(low, -low, shape=(self.size,), dtype=np.float32)

    def blank(self, n: int | None = None) -> np.ndarray:
        """One observation of zeros, or ``n`` rows of them: what :meth:`write` and the sensor write into."""
        return np.zeros(self.size if n is None else (n, self.size), dtype=np.float32)

    def write(self, obs: np.ndarray, outcomes: np.ndarray | None, previous: int | np.ndarray) -> np.ndarray:
        """Write the outcome vector and the one-hot previous action into ``obs`` (from :meth:`blank`: zeros there)
        and return it. One observation: ``obs`` of shape ``(size,)``, ``outcomes`` ``(n_outcomes,)``, ``previous`` an
        action index or :data:`NO_ACTION`; rows of them: ``obs`` ``(n, size)``, ``outcomes`` ``(n, n_outcomes)``,
        ``previous`` an int array ``(n,)``. ``outcomes`` is not read when there are none (``None`` then)."""
        if self.n_outcomes:
            obs[..., self.outcomes] = outcomes
        if obs.ndim == 1:  # one observation: the cheapest write of one value
            if previous != NO_ACTION:
                obs[self.previous + previous] = 1.0
        else:  # rows: each row's part is the row of the one-hot table (zeros for NO_ACTION)
            obs[:, self.previous:] = self._one_hot[previous]
        return obs


@overload
def step_cost(call_moves: int | None, count_primitive_steps: bool) -> int: ...
@overload
def step_cost(call_moves: np.ndarray, count_primitive_steps: bool) -> np.ndarray: ...
def step_cost(call_moves: Any, count_primitive_steps: bool) -> Any:
    """How many of the episode's ``max_steps`` an action takes: one for a signal or a primitive action
    (``call_moves`` None; in an array, -1); an SMC call one, or, with ``count_primitive_steps``, the moves it made (at
    least one)."""
    if isinstance(call_moves, np.ndarray):
        return np.where((call_moves >= 0) & count_primitive_steps, np.maximum(1, call_moves), 1)
    if call_moves is not None and count_primitive_steps:
        return max(1, call_moves)
    return 1


@overload
def truncated(terminated: bool, env_truncated: bool, elapsed: int, max_steps: int) -> bool: ...
@overload
def truncated(terminated: np.ndarray, env_truncated: np.ndarray, elapsed: np.ndarray, max_steps: int) -> np.ndarray: ...
def truncated(terminated: Any, env_truncated: Any, elapsed: Any, max_steps: int) -> Any:
    """Whether the step ends the episode by time: unless it terminated, when the environment cut the episode or
    ``elapsed`` (:func:`step_cost` summed) reached ``max_steps``."""
    return (env_truncated | (elapsed >= max_steps)) > terminated  # a > b: a and not b, for bools and arrays


@overload
def is_success(done: bool, reward: float) -> bool: ...
@overload
def is_success(done: np.ndarray, reward: np.ndarray) -> np.ndarray: ...
def is_success(done: Any, reward: Any) -> Any:
    """Whether the episode succeeded (``info["is_success"]``, the test score): it ended on this step with a positive
    reward (a Python ``bool`` for one episode, whatever number type the reward has)."""
    success = done & (reward > 0)
    return success if isinstance(success, np.ndarray) else bool(success)


def primitive_steps(action_names: Sequence[str], primitives: Sequence[str]) -> tuple[int, ...]:
    """Per action, the ``primitive_steps`` of a step that takes it itself: 1 for a primitive action, 0 for a signal
    (and for an SMC action, whose step reports the moves its call made instead)."""
    return tuple(int(name in primitives) for name in action_names)
