"""A planner that knows the world: breadth-first search over moves to a state where a concept holds.

Used to check that bring-about tasks are solvable (generation drops scenes whose goal cannot be reached)
and to script episodes (``python -m pixelworld_env.demo``).
"""

from __future__ import annotations

import copy
from collections import deque
from typing import TYPE_CHECKING

from pixelworld_env.concepts import Concept
from pixelworld_env.core.objects import Cell
from pixelworld_env.core.scene import Scene
from pixelworld_env.core.world import EMPTY, MOVES, World

if TYPE_CHECKING:
    from pixelworld_env.envs.env import PixelWorldEnv

MAX_STATES = 100_000


def _path(parents: dict, node) -> list[str]:
    path = []
    while (link := parents[node]) is not None:
        node, move = link
        path.append(move)
    return path[::-1]


def plan_moves(world: World, concept: Concept, max_states: int = MAX_STATES) -> list[str] | None:
    """The shortest list of move names (``DOWN``, ``RIGHT``, ``UP``, ``LEFT``) after which ``concept`` holds.

    Starts from the world's current state and uses its dynamics (pushing included) on a copy; ``[]`` if the
    concept already holds, ``None`` if no sequence reaches it within ``max_states`` distinct states.
    """
    floor_row = world.scene.floor_row
    if concept.holds_objects(world.objects, floor_row):
        return []
    if world.self_only:
        return _plan_self_only(world, concept, max_states)
    world = copy.deepcopy(world)
    start = tuple(world.positions)
    parents: dict[tuple, tuple[tuple, str] | None] = {start: None}
    frontier = deque([start])
    while frontier and len(parents) < max_states:
        here = frontier.popleft()
        for name, delta in MOVES.items():
            world.set_positions(here)
            if not world.move(delta):
                continue
            state = tuple(world.positions)
            if state in parents:
                continue
            parents[state] = (here, name)
            if concept.holds_objects(world.objects, floor_row):
                return _path(parents, state)
            frontier.append(state)
    return None


def _plan_self_only(world: World, concept: Concept, max_states: int) -> list[str] | None:
    """Breadth-first search over the self's cell when nothing else can move (read-only: no copies, no redraws)."""
    me = world.self_index
    self_object = world.scene.objects[me]
    holds_for = concept.self_evaluator(world.scene.objects, world.scene.floor_row)
    start = world.positions[me]
    parents: dict[Cell, tuple[Cell, str] | None] = {start: None}
    frontier = deque([start])
    while frontier and len(parents) < max_states:
        row, col = frontier.popleft()
        for name, (dr, dc) in MOVES.items():
            cell = (row + dr, col + dc)
            if cell in parents or world.owner[cell[0] + 1, cell[1] + 1] not in (EMPTY, me):
                continue
            parents[cell] = ((row, col), name)
            if holds_for(self_object.moved_to(cell)):
                return _path(parents, cell)
            frontier.append(cell)
    return None


def goal_reachable(scene: Scene, concept: Concept, max_states: int = MAX_STATES) -> bool:
    """Whether some sequence of moves from ``scene`` makes ``concept`` hold."""
    return plan_moves(World(scene), concept, max_states) is not None


def plan_to_goal(env: PixelWorldEnv, max_states: int = MAX_STATES) -> list[int] | None:
    """:func:`plan_moves` from the env's current state, as the env's action indices."""
    names = plan_moves(env.world, env.concept, max_states)
    return None if names is None else [env.action_names.index(name) for name in names]
