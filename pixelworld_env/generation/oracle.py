"""A planner that knows the world: breadth-first search over moves to a state where a concept holds.

Used to check that bring-about tasks are solvable (generation drops scenes whose goal cannot be reached), to
certify that a concept cannot be brought about in a world (:func:`can_bring_about`: the labels of the
``bring-about-or-cannot`` kind), and to script episodes (``python -m pixelworld_env.demo``).

The search is exhaustive: it visits every state the self can reach from the start by the four moves (the engine's
own moves, pushing included). Where only the one-pixel self moves a state is the self's cell, so a world of at most
``MAX_STATES`` cells is always searched to the end; elsewhere a state is every object's position, and a search that
meets ``max_states`` states before it ends has not looked everywhere (:func:`can_bring_about` then refuses to answer).
"""

from __future__ import annotations

import copy
from collections import deque
from typing import Protocol

from pixelworld_env.concepts import Concept
from pixelworld_env.core.objects import Cell
from pixelworld_env.core.scene import Scene
from pixelworld_env.core.world import EMPTY, MOVES, World
from pixelworld_env.errors import PixelWorldError

MAX_STATES = 100_000
"""The most states a search visits."""


class ReachabilityLimit(PixelWorldError):
    """A search met ``max_states`` states before it had visited every reachable one: no exact answer."""


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
    return _search(world, concept, max_states)[0]


def _search(world: World, concept: Concept, max_states: int) -> tuple[list[str] | None, bool]:
    """:func:`plan_moves`'s plan, and whether the search visited every reachable state (it did where a plan was
    found, or where the frontier ran out before ``max_states`` states)."""
    floor_row = world.scene.floor_row
    if concept.holds_objects(world.objects, floor_row):
        return [], True
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
                return _path(parents, state), True
            frontier.append(state)
    return None, not frontier


def _plan_self_only(world: World, concept: Concept, max_states: int) -> tuple[list[str] | None, bool]:
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
                return _path(parents, cell), True
            frontier.append(cell)
    return None, not frontier


def goal_reachable(scene: Scene, concept: Concept, max_states: int = MAX_STATES) -> bool:
    """Whether some sequence of moves from ``scene`` makes ``concept`` hold."""
    return plan_moves(World(scene), concept, max_states) is not None


def can_bring_about(concept: Concept, scene: Scene, *, max_states: int = MAX_STATES) -> bool:
    """Whether some sequence of moves from ``scene``'s start makes ``concept`` hold (the start itself included),
    decided exactly; :class:`ReachabilityLimit` where the search met ``max_states`` states before it ended."""
    plan, exhausted = _search(World(scene), concept, max_states)
    if plan is not None:
        return True
    if not exhausted:
        raise ReachabilityLimit(f"more than {max_states} states are reachable in this world before the concept "
                                f"{concept.text!r} holds: no exact answer")
    return False


class _Planned(Protocol):
    """What :func:`plan_to_goal` reads of an environment (:class:`~pixelworld_env.PixelWorldEnv` has it)."""

    @property
    def world(self) -> World: ...

    concept: Concept
    action_names: tuple[str, ...]


def plan_to_goal(env: _Planned, max_states: int = MAX_STATES) -> list[int] | None:
    """:func:`plan_moves` from the env's current state, as the env's action indices."""
    names = plan_moves(env.world, env.concept, max_states)
    return None if names is None else [env.action_names.index(name) for name in names]
