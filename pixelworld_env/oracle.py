"""A planner that knows the world: breadth-first search over moves to a state where the goal holds."""

from __future__ import annotations

import copy
from collections import deque

from pixelworld_env.env import PixelWorldEnv


def plan_to_goal(env: PixelWorldEnv, max_states: int = 100_000) -> list[int] | None:
    """The shortest list of move actions that makes the concept hold from the current state, or ``None``.

    Searches over object positions (pushing included) with the env's own world dynamics; ``[]`` if the goal
    already holds. Gives up (``None``) after ``max_states`` distinct states.
    """
    moves = [(a, d) for a, d in enumerate(env._moves) if d is not None]  # noqa: SLF001 - same package
    start = copy.deepcopy(env.world)
    key = tuple(o.position for o in start.objects)
    if env.concept.holds_objects(tuple(start.objects), start.scene.floor_row):
        return []
    parents: dict[tuple, tuple[tuple, int] | None] = {key: None}
    frontier = deque([start])
    while frontier and len(parents) < max_states:
        world = frontier.popleft()
        here = tuple(o.position for o in world.objects)
        for action, delta in moves:
            child = copy.deepcopy(world)
            if not child.move(delta):
                continue
            state = tuple(o.position for o in child.objects)
            if state in parents:
                continue
            parents[state] = (here, action)
            if env.concept.holds_objects(tuple(child.objects), child.scene.floor_row):
                path = []
                node: tuple | None = state
                while parents[node] is not None:
                    node, step = parents[node]  # type: ignore[misc]
                    path.append(step)
                return path[::-1]
            frontier.append(child)
    return None
