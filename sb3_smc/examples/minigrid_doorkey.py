"""SMC tasks on Minigrid's DoorKey: the example of SMCs on an environment nobody here wrote.

``MiniGrid-DoorKey-<n>x<n>-v0``: a key, a locked door in a wall, a goal square behind it. The tasks
(:class:`~sb3_smc.tasks.task.SMCTask`, bring-about, observation the agent's 7 x 7 view and direction, the seven Minigrid
actions as primitives):

* ``get-key``: the agent carries the key (from DoorKey's own start states);
* ``open-door``: the door is open (starting with the key in hand);
* ``reach-goal``: the agent stands on the goal square (starting with the key in hand and the door open);
* ``doorkey``: the agent stands on the goal square (from DoorKey's own start states): the target, trained flat or
  with the three others as SMC actions.

Each is registered on import as a Gymnasium id ``DoorKey<n>-<task>-v0`` for n in 5, 6, 8 (taking ``max_steps``,
as ``train_smc`` needs), so ``train_smc("sb3_smc.examples.minigrid_doorkey:DoorKey8-get-key-v0")`` trains it (a
curriculum names it so too) and ``evaluate`` tests it on held-out start states. Needs
``pip install "sb3-smc[minigrid]"``.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym

from sb3_smc.tasks.task import SMCTask

__all__ = ["OBSERVATION", "SIZES", "TASKS", "at_goal", "door_open", "has_key", "register", "task_id"]

OBSERVATION = ("image", "direction")
"""The keys of Minigrid's observation an SMC senses (``mission`` is text, the same in every episode)."""


def has_key(env: Any) -> bool:
    """The agent carries the key."""
    return env.carrying is not None and env.carrying.type == "key"


def door_open(env: Any) -> bool:
    """The door is open."""
    return any(cell is not None and cell.type == "door" and cell.is_open for cell in env.grid.grid)


def at_goal(env: Any) -> bool:
    """The agent stands on the goal square."""
    cell = env.grid.get(*env.agent_pos)
    return cell is not None and cell.type == "goal"


class StartWith(gym.Wrapper):
    """DoorKey with the key already in the agent's hand (``key=True``) and the door open (``door=True``) at reset."""

    def __init__(self, env: gym.Env, *, key: bool, door: bool) -> None:
        super().__init__(env)
        self.key, self.door = key, door

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        _, info = self.env.reset(seed=seed, options=options)
        env: Any = self.env.unwrapped
        for i, cell in enumerate(env.grid.grid):
            if cell is None:
                continue
            if self.key and cell.type == "key":
                env.carrying = cell
                cell.cur_pos = (-1, -1)
                env.grid.grid[i] = None
            elif self.door and cell.type == "door":
                cell.is_locked, cell.is_open = False, True
        return env.gen_obs(), info


TASKS: dict[str, tuple[Any, bool, bool]] = {
    "get-key": (has_key, False, False),
    "open-door": (door_open, True, False),
    "reach-goal": (at_goal, True, True),
    "doorkey": (at_goal, False, False),
}
"""Each task: its goal, and whether it starts with the key in hand and with the door open."""


def task_id(size: int, task: str) -> str:
    return f"DoorKey{size}-{task}-v0"


def make_task(size: int, task: str, max_steps: int = 100) -> SMCTask:
    """The SMC task ``task`` on ``MiniGrid-DoorKey-<size>x<size>-v0``."""
    import minigrid  # noqa: F401  (registers the MiniGrid ids)

    goal, key, door = TASKS[task]
    env = gym.make(f"MiniGrid-DoorKey-{size}x{size}-v0")
    if key or door:
        env = StartWith(env, key=key, door=door)
    return SMCTask(env, "bring-about", goal=goal, observation=OBSERVATION, max_steps=max_steps)


def register(size: int = 8) -> list[str]:
    """Register ``DoorKey<size>-<task>-v0`` for every task (once); returns the ids."""
    ids = []
    for task in TASKS:
        env_id = task_id(size, task)
        if env_id not in gym.registry:
            gym.register(env_id, entry_point=f"{__name__}:make_task", kwargs={"size": size, "task": task})
        ids.append(env_id)
    return ids


SIZES = (5, 6, 8)
for _size in SIZES:  # registered on import, so that "sb3_smc.examples.minigrid_doorkey:DoorKey8-doorkey-v0" works
    register(_size)
