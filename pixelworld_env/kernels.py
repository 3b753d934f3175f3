"""Compiled (numba) PixelWorld physics for worlds where only the one-pixel self moves, and the batched steps and
observations of :class:`pixelworld_env.vector.PixelWorldVectorEnv`.

:func:`self_target_free` is the self-only move's rule in one place: the self may enter a cell iff the padded owner
array has it empty or owned by the self (``World.move``'s fast path; ``sb3_smc.common.kernels.leaf_call`` calls it
too). The vector env reads it from each scene's *initial* owner array: the only cells a self-only move changes are
the self's own, and the self never moves onto itself, so the initial array answers exactly as the live one.

Imported only by the vector env and ``sb3_smc`` (numba's import costs about half a second; ``import pixelworld_env``
does not pay it). The compiled code is cached next to this file; numba checks only the caller's file for changes, so
after editing :func:`self_target_free` delete ``sb3_smc/common/__pycache__/kernels*.nbi`` / ``*.nbc``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from pixelworld_env.world import EMPTY

__all__ = ["NEED_DRAWS", "NEED_SCENES", "OK", "observe_states", "observe_windows", "reset_envs", "self_target_free",
           "step_envs"]

OK, NEED_DRAWS, NEED_SCENES = 0, 1, 2
"""What :func:`step_envs` and :func:`reset_envs` return: done; an environment to reset has no scene draw left (refill
its block and call again: nothing was changed); a scene to reset into is not prepared yet (its goal table)."""

MOVE = 1
"""``kinds`` entry of a move action (0: a signal)."""


@njit(cache=True)
def self_target_free(owner: np.ndarray, me: int, row: int, col: int) -> bool:  # pragma: no cover
    """Whether the one-pixel self (object ``me``) may move to cell ``(row, col)`` (unpadded coordinates) of a world
    where only it moves: that cell of the padded ``owner`` array is empty or the self's own."""
    target = owner[row + 1, col + 1]
    return target == EMPTY or target == me  # noqa: SIM109 (numba: no tuple membership)


@njit(cache=True)
def _ready(s: int, bring_about: bool, ready: np.ndarray) -> bool:  # pragma: no cover
    return not bring_about or ready[s] != 0


@njit(cache=True)
def _reset_one(k: int, s: int, bring_about: bool, start: np.ndarray, goal0: np.ndarray, scene: np.ndarray,
               row: np.ndarray, col: np.ndarray, steps: np.ndarray, goal: np.ndarray,
               autoreset: np.ndarray) -> None:  # pragma: no cover
    scene[k] = s
    row[k] = start[s, 0]
    col[k] = start[s, 1]
    steps[k] = 0
    goal[k] = goal0[s] if bring_about else 0
    autoreset[k] = False


@njit(cache=True)
def reset_envs(mask: np.ndarray, forced: np.ndarray, bring_about: bool, ready: np.ndarray, start: np.ndarray,
               goal0: np.ndarray, draws: np.ndarray, used: np.ndarray, scene: np.ndarray, row: np.ndarray,
               col: np.ndarray, steps: np.ndarray, goal: np.ndarray, autoreset: np.ndarray) -> int:  # pragma: no cover
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
            if not _ready(s, bring_about, ready):
                return NEED_SCENES
    for k in range(n):
        if mask[k]:
            if forced[k] >= 0:
                s = forced[k]
            else:
                s = draws[k, used[k]]
                used[k] += 1
            _reset_one(k, s, bring_about, start, goal0, scene, row, col, steps, goal, autoreset)
    return OK


@njit(cache=True)
def step_envs(actions: np.ndarray, kinds: np.ndarray, values: np.ndarray, deltas: np.ndarray, bring_about: bool,
              max_steps: int, signal_reward: float, potential: float, goal_reward: float, owner0: np.ndarray,
              me: np.ndarray, start: np.ndarray, labels: np.ndarray, python_scene: np.ndarray,
              goal_table: np.ndarray, goal0: np.ndarray, ready: np.ndarray, draws: np.ndarray, used: np.ndarray,
              scene: np.ndarray, row: np.ndarray, col: np.ndarray, steps: np.ndarray, goal: np.ndarray,
              autoreset: np.ndarray, rewards: np.ndarray, terminated: np.ndarray, truncated: np.ndarray,
              success: np.ndarray, was_reset: np.ndarray, python_move: np.ndarray) -> int:  # pragma: no cover
    """One step of every environment (Gymnasium's next-step autoreset): those that ended last step are reset (reward
    0, ``was_reset``), the others take ``actions[k]`` (per action ``kinds``: 0 signal, 1 move; ``values`` a signal's
    value; ``deltas`` a move's offsets) with :class:`~pixelworld_env.PixelWorldEnv`'s rewards. Scenes are read
    from the per-scene arrays (``owner0`` the initial padded owners, ``start`` / ``me`` the self's cell and index,
    ``labels``, ``goal_table`` the goal's truth per self cell, ``goal0`` at the start). A move in a scene where more
    than the self moves (``python_scene``) is left to the caller (``python_move``, reward 0 so far). Returns ``OK``,
    or ``NEED_DRAWS`` / ``NEED_SCENES`` before changing anything."""
    n = actions.shape[0]
    for k in range(n):
        if autoreset[k]:
            if used[k] >= draws.shape[1]:
                return NEED_DRAWS
            if not _ready(draws[k, used[k]], bring_about, ready):
                return NEED_SCENES
    for k in range(n):
        python_move[k] = False
        if autoreset[k]:
            s = draws[k, used[k]]
            used[k] += 1
            _reset_one(k, s, bring_about, start, goal0, scene, row, col, steps, goal, autoreset)
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
            if python_scene[s]:
                python_move[k] = True
            else:
                r = row[k] + deltas[a, 0]
                c = col[k] + deltas[a, 1]
                if self_target_free(owner0[s], me[s], r, c):
                    row[k] = r
                    col[k] = c
                    if bring_about:
                        g = goal_table[s, r, c]
                        if g != goal[k]:
                            goal[k] = g
                            reward = potential if g == 1 else -potential
        else:
            term = True
            if bring_about:
                reward = goal_reward - potential if goal[k] == 1 else 0.0
            else:
                reward = signal_reward if values[a] == labels[s] else -signal_reward
        trunc = not term and steps[k] >= max_steps
        rewards[k] = reward
        terminated[k] = term
        truncated[k] = trunc
        success[k] = (term or trunc) and reward > 0.0
        autoreset[k] = term or trunc
    return OK


@njit(cache=True)
def _cell(s: int, pr: int, pc: int, r0: int, c0: int, grid0: np.ndarray, start: np.ndarray,
          self_color: np.ndarray) -> int:  # pragma: no cover
    """The colour of padded cell ``(pr, pc)`` of scene ``s`` with the self at unpadded ``(r0, c0)``."""
    if pr == r0 + 1 and pc == c0 + 1:
        return self_color[s]
    if pr == start[s, 0] + 1 and pc == start[s, 1] + 1:
        return 0
    return grid0[s, pr, pc]


@njit(cache=True)
def observe_windows(one_hot: bool, n_colors: int, grid0: np.ndarray, start: np.ndarray, self_color: np.ndarray,
                    python_scene: np.ndarray, scene: np.ndarray, row: np.ndarray, col: np.ndarray,
                    out: np.ndarray) -> None:  # pragma: no cover
    """Write the 3 x 3 window of every environment in a scene where only the self moves into its row of ``out``:
    ``one_hot`` ``(n, 9 * n_colors)`` float32, else ``(n, 9)`` raw codes (rows of other environments are left)."""
    for k in range(scene.shape[0]):
        s = scene[k]
        if python_scene[s]:
            continue
        r0, c0 = row[k], col[k]
        if one_hot:
            out[k, :] = 0.0
        for i in range(3):
            for j in range(3):
                value = _cell(s, r0 + i, c0 + j, r0, c0, grid0, start, self_color)
                if one_hot:
                    out[k, (3 * i + j) * n_colors + value] = 1.0
                else:
                    out[k, 3 * i + j] = value


@njit(cache=True)
def observe_states(grid0: np.ndarray, start: np.ndarray, self_color: np.ndarray, python_scene: np.ndarray,
                   scene: np.ndarray, row: np.ndarray, col: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover
    """Write the state array of every environment in a scene where only the self moves into ``out`` ``(n, height,
    width)`` (rows of other environments are left)."""
    for k in range(scene.shape[0]):
        s = scene[k]
        if python_scene[s]:
            continue
        for i in range(out.shape[1]):
            for j in range(out.shape[2]):
                out[k, i, j] = _cell(s, i + 1, j + 1, row[k], col[k], grid0, start, self_color)
