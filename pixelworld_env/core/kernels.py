"""PixelWorld's physics, compiled (numba), in one place: the moves of :class:`pixelworld_env.core.world.World`, of
the native vector env (:class:`pixelworld_env.envs.vector.PixelWorldVectorEnv`, whose batched steps and observations
are here too) and of ``sb3_smc``'s compiled SMC calls.

:func:`self_target_free` is the self-only move's rule: the self may enter a cell iff the padded owner array has it
empty or owned by the self (``World.move`` where only the self moves; ``sb3_smc.common.kernels.leaf_call`` calls it
too). The vector env reads it from each scene's *initial* owner array: the only cells a self-only move changes are
the self's own, and the self never moves onto itself, so the initial array answers exactly as the live one.
:func:`push_move` is the general move (transitive pushing) on one world's live arrays, for the worlds where objects
besides the self move; :func:`draw_objects` draws a world's arrays from its objects' positions.

The batched functions take those worlds' arrays as one tuple, ``pushing`` = ``(grid0, owner0, cells, n_cells, colors,
moveable, n_objects, initial, disjoint0, grids, owners, positions, disjoint, plan, planned)``: per scene the initial
padded colours and owners, the objects' cells / cell counts / colours / moveability, their count and initial
positions, whether they start disjoint; per environment its live padded colours and owners, object positions and
disjointness (empty arrays when no scene pushes); scratch arrays for :func:`push_move`.

The compiled code is cached next to this file (numba's import and the first call of a cached function cost about
half a second per process); numba checks only the caller's file for changes, so after editing
:func:`self_target_free` delete ``sb3_smc/common/__pycache__/kernels*.nbi`` / ``*.nbc``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from pixelworld_env.core.constants import EMPTY, OUTSIDE

__all__ = ["NEED_DRAWS", "NEED_SCENES", "OK", "draw_objects", "observe_states", "observe_windows", "push_move",
           "reset_envs", "self_target_free", "step_envs"]

OK, NEED_DRAWS, NEED_SCENES = 0, 1, 2
"""What :func:`step_envs` and :func:`reset_envs` return: done; an environment to reset has no scene draw left (refill
its block and call again: nothing was changed); a scene to reset into is not prepared yet (its goal table)."""

MOVE = 1
"""``kinds`` entry of a move action (0: a signal)."""


@njit(cache=True, inline="always")
def self_target_free(owner: np.ndarray, me: int, row: int, col: int) -> bool:  # pragma: no cover
    """Whether the one-pixel self (object ``me``) may move to cell ``(row, col)`` (unpadded coordinates) of a world
    where only it moves: that cell of the padded ``owner`` array is empty or the self's own."""
    target = owner[row + 1, col + 1]
    return target == EMPTY or target == me  # noqa: SIM109 (numba: no tuple membership)


@njit(cache=True)
def draw_objects(grid: np.ndarray, owner: np.ndarray, positions: np.ndarray, cells: np.ndarray, n_cells: np.ndarray,
                 colors: np.ndarray, n_objects: int) -> bool:  # pragma: no cover
    """Redraw the padded ``grid`` / ``owner`` arrays with every object at ``positions``, in index order (a later
    object over an earlier one); returns whether no two objects share a cell."""
    grid[:, :] = 0
    owner[:, :] = OUTSIDE
    owner[1:-1, 1:-1] = EMPTY
    n_pixels = 0
    for i in range(n_objects):
        n_pixels += n_cells[i]
        for p in range(n_cells[i]):
            r, c = positions[i, 0] + cells[i, p, 0] + 1, positions[i, 1] + cells[i, p, 1] + 1
            grid[r, c] = colors[i]
            owner[r, c] = i
    drawn = 0
    for r in range(owner.shape[0]):
        for c in range(owner.shape[1]):
            if owner[r, c] >= 0:
                drawn += 1
    return drawn == n_pixels


@njit(cache=True)
def push_move(grid: np.ndarray, owner: np.ndarray, positions: np.ndarray, cells: np.ndarray, n_cells: np.ndarray,
              colors: np.ndarray, moveable: np.ndarray, n_objects: int, me: int, dr: int, dc: int,
              disjoint: np.ndarray, k: int, plan: np.ndarray, planned: np.ndarray) -> bool:  # pragma: no cover
    """``World.move``'s general path on one world's live padded ``grid`` / ``owner`` and object ``positions``
    (``cells`` / ``n_cells`` / ``colors`` / ``moveable`` the scene's objects): move the self (object ``me``) by
    ``(dr, dc)``, pushing moveable objects transitively; any immoveable object or the world's edge in the chain
    blocks the whole move. Redraws only the moved objects while ``disjoint[k]`` (no two objects share a cell), else
    everything. ``plan`` / ``planned`` are scratch arrays of ``n_objects`` entries. Returns whether it moved."""
    planned[:n_objects] = False
    plan[0] = me
    planned[me] = True
    size = 1
    i = 0
    while i < size:  # breadth-first closure of the pushed objects
        index = plan[i]
        i += 1
        for p in range(n_cells[index]):
            other = owner[positions[index, 0] + cells[index, p, 0] + dr + 1,
                          positions[index, 1] + cells[index, p, 1] + dc + 1]
            if other == OUTSIDE:
                return False
            if other == EMPTY or planned[other]:
                continue
            if not moveable[other]:
                return False
            planned[other] = True
            plan[size] = other
            size += 1
    if not disjoint[k]:
        for i in range(size):
            positions[plan[i], 0] += dr
            positions[plan[i], 1] += dc
        disjoint[k] = draw_objects(grid, owner, positions, cells, n_cells, colors, n_objects)
        return True
    for i in range(size):  # the same arrays as a full redraw: erase the moved objects, then draw them moved
        index = plan[i]
        for p in range(n_cells[index]):
            r, c = positions[index, 0] + cells[index, p, 0] + 1, positions[index, 1] + cells[index, p, 1] + 1
            grid[r, c] = 0
            owner[r, c] = EMPTY
    for i in range(size):
        index = plan[i]
        positions[index, 0] += dr
        positions[index, 1] += dc
        for p in range(n_cells[index]):
            r, c = positions[index, 0] + cells[index, p, 0] + 1, positions[index, 1] + cells[index, p, 1] + 1
            grid[r, c] = colors[index]
            owner[r, c] = index
    return True


@njit(cache=True, inline="always")
def _ready(s: int, tracks_goal: bool, ready: np.ndarray) -> bool:  # pragma: no cover
    return not tracks_goal or ready[s] != 0


@njit(cache=True, inline="always")
def _reset_one(k: int, s: int, tracks_goal: bool, start: np.ndarray, goal0: np.ndarray, push_scene: np.ndarray,
               pushing: tuple, scene: np.ndarray, row: np.ndarray, col: np.ndarray, steps: np.ndarray,
               goal: np.ndarray, autoreset: np.ndarray) -> None:  # pragma: no cover
    scene[k] = s
    row[k] = start[s, 0]
    col[k] = start[s, 1]
    steps[k] = 0
    goal[k] = goal0[s] if tracks_goal else 0
    autoreset[k] = False
    if push_scene[s]:
        grid0, owner0, _, _, _, _, n_objects, initial, disjoint0, grids, owners, positions, disjoint, _, _ = pushing
        grids[k] = grid0[s]
        owners[k] = owner0[s]
        positions[k, : n_objects[s]] = initial[s, : n_objects[s]]
        disjoint[k] = disjoint0[s]


@njit(cache=True)
def reset_envs(mask: np.ndarray, forced: np.ndarray, tracks_goal: bool, ready: np.ndarray, start: np.ndarray,
               goal0: np.ndarray, push_scene: np.ndarray, pushing: tuple, draws: np.ndarray, used: np.ndarray,
               scene: np.ndarray, row: np.ndarray, col: np.ndarray, steps: np.ndarray, goal: np.ndarray,
               autoreset: np.ndarray) -> int:  # pragma: no cover
    """Reset the environments where ``mask`` is set: into scene ``forced[k]`` where it is >= 0, else into the next of
    their scene draws (``draws[k, used[k]]``, then ``used[k]`` grows). Returns ``OK``, or ``NEED_DRAWS`` /
    ``NEED_SCENES`` before changing anything."""
    n = mask.shape[0]
    for k in range(n):
        if mask[k]:
            if forced[k] >= 0:
                s = forced[k]
            elif used[k] >= draws.shape[1]:
                return NEED_DRAWS
            else:
                s = draws[k, used[k]]
            if not _ready(s, tracks_goal, ready):
                return NEED_SCENES
    for k in range(n):
        if mask[k]:
            if forced[k] >= 0:
                s = forced[k]
            else:
                s = draws[k, used[k]]
                used[k] += 1
            _reset_one(k, s, tracks_goal, start, goal0, push_scene, pushing, scene, row, col, steps, goal, autoreset)
    return OK


@njit(cache=True)
def step_envs(actions: np.ndarray, kinds: np.ndarray, signal_rewards: np.ndarray, deltas: np.ndarray,
              tracks_goal: bool, max_steps: int, potential: float, me: np.ndarray,
              start: np.ndarray, labels: np.ndarray, goal_table: np.ndarray, goal0: np.ndarray, ready: np.ndarray,
              push_scene: np.ndarray, pushing: tuple, draws: np.ndarray, used: np.ndarray, scene: np.ndarray,
              row: np.ndarray, col: np.ndarray, steps: np.ndarray, goal: np.ndarray, autoreset: np.ndarray,
              rewards: np.ndarray, terminated: np.ndarray, truncated: np.ndarray, success: np.ndarray,
              was_reset: np.ndarray, goal_pending: np.ndarray) -> int:  # pragma: no cover
    """One step of every environment (Gymnasium's next-step autoreset): those that ended last step are reset (reward
    0, ``was_reset``), the others take ``actions[k]`` (per action ``kinds``: 0 signal, 1 move; ``signal_rewards`` a
    signal's reward by the scene's label and the goal's truth, the kind's table
    :meth:`~pixelworld_env.core.kinds.TaskKind.reward_table`; ``deltas`` a move's offsets) with
    :class:`~pixelworld_env.PixelWorldEnv`'s rewards; ``tracks_goal``: the kind's (shaping by ``potential``). Scenes
    are read from
    the per-scene arrays (``me`` / ``start`` the self's index and cell, ``labels``, ``goal_table`` the goal's truth
    per self cell, -1 where not yet known, ``goal0`` at the start; ``pushing`` see above). In a scene where more
    than the self moves (``push_scene``) a move is :func:`push_move`. In bring-about, the goal after a move in such a
    scene, or to a cell whose truth is not yet known, is left to the caller (``goal_pending``; reward 0 so far) where
    the kind tracks the goal.
    Returns ``OK``, or ``NEED_DRAWS`` / ``NEED_SCENES`` before changing anything."""
    grid0, owner0, cells, n_cells, colors, moveable, n_objects, _, _, grids, owners, positions, disjoint, plan, \
        planned = pushing
    n = actions.shape[0]
    for k in range(n):
        if autoreset[k]:
            if used[k] >= draws.shape[1]:
                return NEED_DRAWS
            if not _ready(draws[k, used[k]], tracks_goal, ready):
                return NEED_SCENES
    for k in range(n):
        goal_pending[k] = False
        if autoreset[k]:
            s = draws[k, used[k]]
            used[k] += 1
            _reset_one(k, s, tracks_goal, start, goal0, push_scene, pushing, scene, row, col, steps, goal, autoreset)
            rewards[k] = 0.0
            terminated[k] = False
            truncated[k] = False
            success[k] = False
            was_reset[k] = True
            continue
        was_reset[k] = False
        a = actions[k]
        s = scene[k]
        steps[k] += 1
        reward = 0.0
        term = False
        if kinds[a] == MOVE:
            if push_scene[s]:
                if push_move(grids[k], owners[k], positions[k], cells[s], n_cells[s], colors[s], moveable[s],
                             n_objects[s], me[s], deltas[a, 0], deltas[a, 1], disjoint, k, plan, planned):
                    row[k] = positions[k, me[s], 0]
                    col[k] = positions[k, me[s], 1]
                    goal_pending[k] = tracks_goal
            else:
                r = row[k] + deltas[a, 0]
                c = col[k] + deltas[a, 1]
                if self_target_free(owner0[s], me[s], r, c):
                    row[k] = r
                    col[k] = c
                    if tracks_goal:
                        g = goal_table[s, r, c]
                        if g < 0:  # a cell not reached before in this scene: its goal is tested by the caller
                            goal_pending[k] = True
                        elif g != goal[k]:
                            goal[k] = g
                            reward = potential if g == 1 else -potential
        else:
            term = True
            reward = signal_rewards[a, labels[s], goal[k]]
        trunc = not term and steps[k] >= max_steps
        rewards[k] = reward
        terminated[k] = term
        truncated[k] = trunc
        success[k] = (term or trunc) and reward > 0.0
        autoreset[k] = term or trunc
    return OK


@njit(cache=True)
def observe_windows(one_hot: bool, n_colors: int, start: np.ndarray, self_color: np.ndarray, push_scene: np.ndarray,
                    pushing: tuple, scene: np.ndarray, row: np.ndarray, col: np.ndarray,
                    out: np.ndarray) -> None:  # pragma: no cover
    """Write the 3 x 3 window of every environment into its row of ``out``: ``one_hot`` ``(n, 9 * n_colors)``
    float32, else ``(n, 9)`` raw codes. Where only the self moves, the window is the scene's initial colours with
    the self's start emptied and the self at the centre."""
    grid0, grids = pushing[0], pushing[9]
    width = out.shape[1]
    for k in range(scene.shape[0]):
        s = scene[k]
        r0, c0 = row[k], col[k]
        push = push_scene[s]
        start_r, start_c = start[s, 0] + 1, start[s, 1] + 1
        if one_hot:
            for x in range(width):
                out[k, x] = 0.0
        for i in range(3):
            for j in range(3):
                pr, pc = r0 + i, c0 + j
                if push:
                    value = grids[k, pr, pc]
                elif i == 1 and j == 1:
                    value = self_color[s]
                elif pr == start_r and pc == start_c:
                    value = 0
                else:
                    value = grid0[s, pr, pc]
                if one_hot:
                    out[k, (3 * i + j) * n_colors + value] = 1.0
                else:
                    out[k, 3 * i + j] = value


@njit(cache=True)
def observe_states(start: np.ndarray, self_color: np.ndarray, push_scene: np.ndarray, pushing: tuple,
                   scene: np.ndarray, row: np.ndarray, col: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover
    """Write the state array of every environment into ``out`` ``(n, height, width)``."""
    grid0, grids = pushing[0], pushing[9]
    height, width = out.shape[1], out.shape[2]
    for k in range(scene.shape[0]):
        s = scene[k]
        source = grids[k] if push_scene[s] else grid0[s]
        for i in range(height):
            for j in range(width):
                out[k, i, j] = source[i + 1, j + 1]
        if not push_scene[s]:
            out[k, start[s, 0], start[s, 1]] = 0
            out[k, row[k], col[k]] = self_color[s]
