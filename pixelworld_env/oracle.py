"""A planner that knows the world: breadth-first search over moves to a state where the goal holds."""

from __future__ import annotations

import copy
from collections import deque

from pixelworld_env.env import PixelWorldEnv
from pixelworld_env.objects import Cell
from pixelworld_env.world import EMPTY, MOVES, World


def plan_to_goal(env: PixelWorldEnv, max_states: int = 100_000) -> list[int] | None:
    """The shortest list of move actions that makes the concept hold from the current state, or ``None``.

    Searches over object positions (pushing included) with the env's own world dynamics, on a copy of the
    world; ``[]`` if the goal already holds. Gives up (``None``) after ``max_states`` distinct states.
    """
    moves = [(env.action_names.index(name), delta) for name, delta in MOVES.items()]
    world = copy.deepcopy(env.world)
    floor_row = world.scene.floor_row
    start = tuple(world.positions)
    if env.concept.holds_objects(world.objects, floor_row):
        return []
    if world.self_only:
        return _plan_self_only(env, world, moves, max_states)
    parents: dict[tuple, tuple[tuple, int] | None] = {start: None}
    frontier = deque([start])
    while frontier and len(parents) < max_states:
        here = frontier.popleft()
        for action, delta in moves:
            world.set_positions(here)
            if not world.move(delta):
                continue
            state = tuple(world.positions)
            if state in parents:
                continue
            parents[state] = (here, action)
            if env.concept.holds_objects(world.objects, floor_row):
                path = []
                node: tuple | None = state
                while parents[node] is not None:
                    node, step = parents[node]  # type: ignore[misc]
                    path.append(step)
                return path[::-1]
            frontier.append(state)
    return None


def _plan_self_only(env: PixelWorldEnv, world: World, moves: list[tuple[int, Cell]], max_states: int
                    ) -> list[int] | None:
    """Breadth-first search over the self's cell when nothing else can move (no redraws needed)."""
    me = world.self_index
    scene_objects = list(world.scene.objects)
    floor_row = world.scene.floor_row
    start = world.positions[me]
    parents: dict[Cell, tuple[Cell, int] | None] = {start: None}
    frontier = deque([start])
    while frontier and len(parents) < max_states:
        row, col = frontier.popleft()
        for action, (dr, dc) in moves:
            cell = (row + dr, col + dc)
            if cell in parents or world.owner[cell[0] + 1, cell[1] + 1] not in (EMPTY, me):
                continue
            parents[cell] = ((row, col), action)
            scene_objects[me] = world.scene.objects[me].moved_to(cell)
            if env.concept.holds_objects(tuple(scene_objects), floor_row):
                path = []
                node: Cell = cell
                while (link := parents[node]) is not None:
                    node, step = link
                    path.append(step)
                return path[::-1]
            frontier.append(cell)
    return None
