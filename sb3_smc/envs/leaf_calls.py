"""Compiled (numba) calls of leaf SMCs in a PixelWorld where only the self moves.

A leaf SMC (no children: its actions are signals and moves) with a compiled actor is called here in one loop:
:func:`leaf_call` reads the 3 x 3 window from the world's array, takes the recurrent step
(:func:`~sb3_smc.common.kernels.lstm_cell` / :func:`~sb3_smc.common.kernels.gru_cell`, the same cells as every
compiled path), draws the action and makes the move (its rule :func:`pixelworld_env.core.kernels.self_target_free`,
shared with the vector env) with the goal shaping, decision by decision the same arithmetic and draws as
:meth:`sb3_smc.HierarchicalSMCWrapper.call_coroutine`. :func:`smc_steps` is a step of every environment of an SMC
whose children are such leaves (a signal, a move or a whole :func:`leaf_call`; resumable where a goal's truth is not
known yet): :class:`~sb3_smc.envs.hierarchical_vec_env.HierarchicalSMCVecEnv` runs it, and the wrapper runs
:func:`leaf_call` for its compiled calls. Imported on first use (numba's import and the first compilation cost
about a second; the compiled code is cached next to this file).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from pixelworld_env.core.kernels import self_target_free
from sb3_smc.common.kernels import ACCURATE_TANH, gru_cell, linear_softmax, lstm_cell, sample_index

__all__ = ["LEAF_BAD_PROBABILITIES", "LEAF_DONE", "LEAF_NEEDS_GOAL", "N_COUNTERS", "leaf_call", "smc_steps"]


LEAF_DONE, LEAF_NEEDS_GOAL, LEAF_BAD_PROBABILITIES = 0, 1, 2
"""What :func:`leaf_call` returns: the call has ended; it stopped after a move into a cell whose goal truth is not
known yet (fill it in ``goal_cells`` and call again: it resumes); a policy gave probabilities without a positive
finite sum."""

# the entries of leaf_call's ``counters``
ROW, COL, DECISIONS_LEFT, BUDGET, MOVES_MADE, PREVIOUS, GOAL, RESUME, DRAWN = range(9)
N_COUNTERS = 9
"""The length of leaf_call's ``counters``."""


@njit(cache=True)
def _shape(goal: int, counters: np.ndarray, totals: np.ndarray, potential: float) -> None:  # pragma: no cover
    """The self has entered a cell whose goal truth is ``goal``: the shaping reward of entering or leaving the goal."""
    if goal != counters[GOAL]:
        counters[GOAL] = goal
        totals[0] += potential if goal == 1 else -potential


@njit(cache=True, error_model="numpy")  # no division checks: the cell's tanh vectorizes
def leaf_call(grid: np.ndarray, owner: np.ndarray, me: int, self_color: int, goal_cells: np.ndarray,
              tracks_goal: bool, potential: float, n_colors: int, kinds: np.ndarray, values: np.ndarray,
              deltas: np.ndarray, counters: np.ndarray, totals: np.ndarray, gru: bool, h: np.ndarray, c: np.ndarray,
              w_ih: np.ndarray, w_hh: np.ndarray, b_first: np.ndarray, b_second: np.ndarray, w_out: np.ndarray,
              b_out: np.ndarray, rng: np.random.Generator, uniforms: np.ndarray) -> int:  # pragma: no cover
    """One call of a leaf SMC (no children; its actions are signals and moves) with a compiled actor, made entirely
    here, in a world where only the one-pixel self moves: the loop of
    :meth:`sb3_smc.HierarchicalSMCWrapper.call_coroutine` with :meth:`pixelworld_env.World.move`'s self-only move
    (its rule :func:`pixelworld_env.core.kernels.self_target_free`, shared with the vector env) and
    :class:`pixelworld_env.PixelWorldEnv`'s goal shaping, decision by decision the same arithmetic and the same draws
    from ``rng`` as that loop, so the same call.

    ``grid`` / ``owner``: the world's live padded arrays (moves are made in them); ``goal_cells``: per self cell
    the goal's truth (1 / 0, -1 not known yet; read where the task's kind ``tracks_goal``), ``potential`` the reward
    of entering the goal (minus that of leaving it); ``n_colors`` the window's one-hot width. Per action ``kinds`` (0
    signal, 1 move), ``values`` (a signal's outcome) and ``deltas`` (a move's row/column offsets). ``counters``
    (int64, see ``ROW`` ...) and ``totals`` (``[reward, outcome]``; the outcome as it comes in stays where the call
    ends without a signal: the caller sets it to the child kind's cut outcome) carry the call's state in and out,
    ``h`` / ``c`` the
    recurrent state (``c`` unused for a GRU, whose biases are ``b_first`` / ``b_second``; an LSTM's bias is
    ``b_first``). Each decision takes one uniform: ``rng.random()`` when ``uniforms`` is empty, else
    ``uniforms[counters[DRAWN]]`` (draws made ahead from the same generator: the same numbers; ``uniforms`` must
    hold one per decision left). Returns ``LEAF_DONE``, ``LEAF_NEEDS_GOAL`` or ``LEAF_BAD_PROBABILITIES``."""
    n_actions = kinds.shape[0]
    hidden = h.shape[0]
    x = np.zeros(w_ih.shape[0])
    first_previous = w_ih.shape[0] - n_actions
    probabilities = np.empty(n_actions)
    h_next = np.empty(hidden)
    c_next = np.empty(hidden)
    row, col = counters[ROW], counters[COL]
    if counters[RESUME] == 1:  # the last move entered a cell whose goal truth has been filled in since
        counters[RESUME] = 0
        _shape(goal_cells[row, col], counters, totals, potential)
    while counters[DECISIONS_LEFT] > 0:
        if counters[BUDGET] <= 0:
            break
        counters[DECISIONS_LEFT] -= 1
        x[:] = 0.0
        for i in range(3):
            for j in range(3):
                x[(3 * i + j) * n_colors + grid[row + i, col + j]] = 1.0
        if counters[PREVIOUS] >= 0:
            x[first_previous + counters[PREVIOUS]] = 1.0
        if gru:
            gru_cell(x, h, w_ih, w_hh, b_first, b_second, h_next, ACCURATE_TANH)
        else:
            lstm_cell(x, h, c, w_ih, w_hh, b_first, 1.0, h_next, c_next, ACCURATE_TANH)
            c[:] = c_next
        h[:] = h_next
        linear_softmax(h_next, w_out, b_out, probabilities)
        u = rng.random() if uniforms.shape[0] == 0 else uniforms[counters[DRAWN]]
        counters[DRAWN] += 1
        action = sample_index(probabilities, u)
        if action < 0:
            return LEAF_BAD_PROBABILITIES
        if kinds[action] == 0:
            totals[1] = values[action]
            return LEAF_DONE
        counters[MOVES_MADE] += 1
        counters[BUDGET] -= 1
        counters[PREVIOUS] = action
        dr, dc = deltas[action, 0], deltas[action, 1]
        if not self_target_free(owner, me, row + dr, col + dc):
            continue  # blocked: the move costs a decision and a move, and changes nothing
        grid[row + 1, col + 1] = 0
        owner[row + 1, col + 1] = -1
        row += dr
        col += dc
        grid[row + 1, col + 1] = self_color
        owner[row + 1, col + 1] = me
        counters[ROW] = row
        counters[COL] = col
        if tracks_goal:
            goal = goal_cells[row, col]
            if goal < 0:
                counters[RESUME] = 1
                return LEAF_NEEDS_GOAL
            _shape(goal, counters, totals, potential)
    return LEAF_DONE


SIGNAL, MOVE, CALL = 0, 1, 2
"""The kinds of a top-level action in :func:`smc_steps`."""
STARTING, IN_CALL, IN_MOVE, STEPPED = 0, 1, 2, 3
"""An environment's progress through a step of :func:`smc_steps` (``phase``): not begun; stopped inside a call or
after a top-level move for a goal truth not known yet (the step resumes there); done."""


@njit(cache=True)
def smc_steps(actions: np.ndarray, kinds: np.ndarray, signal_rewards: np.ndarray, deltas: np.ndarray,
              targets: np.ndarray, caps: np.ndarray, tracks_goal: bool, potential: float,
              n_colors: int, me: np.ndarray, self_color: np.ndarray, labels: np.ndarray, goal_table: np.ndarray,
              child_actions: np.ndarray, child_kinds: np.ndarray, child_values: np.ndarray,
              child_deltas: np.ndarray, child_cut: np.ndarray, gru: bool,
              w_ih: np.ndarray, w_hh: np.ndarray, b_first: np.ndarray, b_second: np.ndarray, w_out: np.ndarray,
              b_out: np.ndarray, scene: np.ndarray, row: np.ndarray, col: np.ndarray, goal: np.ndarray,
              grids: np.ndarray, owners: np.ndarray, phase: np.ndarray, counters: np.ndarray, totals: np.ndarray,
              h: np.ndarray, c: np.ndarray, uniforms: np.ndarray, used: np.ndarray, rng: np.random.Generator,
              rewards: np.ndarray, terminated: np.ndarray, moves: np.ndarray) -> int:  # pragma: no cover
    """One step of an SMC whose children are compiled leaves, in every environment of a PixelWorld where only the
    self moves: :meth:`sb3_smc.HierarchicalSMCWrapper.step`'s action (a signal, a move, or a whole call of a child
    by :func:`leaf_call`) with :class:`~pixelworld_env.PixelWorldEnv`'s rewards, the same moves and draws.

    Per top-level action ``kinds`` (:data:`SIGNAL`, :data:`MOVE`, :data:`CALL`), ``signal_rewards`` (a signal's
    reward by label and goal truth: the task kind's table), ``deltas`` (a move's offsets), ``targets`` (a call's
    child); ``caps`` per environment its call's decisions and moves; ``tracks_goal`` the task kind's. Per scene
    ``me``, ``self_color``, ``labels`` and ``goal_table`` (the goal's truth per self cell, -1 not known yet). The
    children's plans and weights stacked (one row per child, ``child_actions`` its actions; the rows padded to the
    most actions; ``child_cut`` the outcome of a call that ends without a signal; ``b_second`` empty rows for an
    LSTM).
    Per environment its live state (``scene``, ``row``, ``col``, ``goal``, its padded ``grids`` / ``owners``), a
    call's ``counters`` / ``totals`` / ``h`` / ``c`` and its ``uniforms`` drawn ahead, ``used`` of them. Writes
    ``rewards`` and ``terminated``, and for a call ``moves`` (its outcome stays in ``totals[k, 1]``).

    Environments whose ``phase`` is :data:`STEPPED` are skipped. Returns -1 when every environment has stepped;
    ``k >= 0`` when environment ``k`` moved the self into a cell of its scene whose goal truth is not known yet
    (fill it in ``goal_table`` and call again: it resumes); ``-2 - k`` when a child's policy gave probabilities
    without a positive finite sum in environment ``k``."""
    n_most = child_kinds.shape[1]
    for k in range(actions.shape[0]):
        if phase[k] == STEPPED:
            continue
        s = scene[k]
        a = actions[k]
        if kinds[a] == CALL:
            child = targets[a]
            na = child_actions[child]
            if phase[k] == STARTING:
                counters[k, :] = 0
                counters[k, ROW] = row[k]
                counters[k, COL] = col[k]
                counters[k, DECISIONS_LEFT] = caps[k]
                counters[k, BUDGET] = caps[k]
                counters[k, PREVIOUS] = -1
                counters[k, GOAL] = goal[k]
                counters[k, DRAWN] = used[k]
                totals[k, 0] = 0.0
                totals[k, 1] = child_cut[child]
                h[k, :] = 0.0
                c[k, :] = 0.0
            status = leaf_call(grids[k], owners[k], me[s], self_color[s], goal_table[s], tracks_goal, potential,
                               n_colors, child_kinds[child, :na], child_values[child, :na], child_deltas[child, :na],
                               counters[k], totals[k], gru, h[k], c[k], w_ih[child, :w_ih.shape[1] - n_most + na],
                               w_hh[child], b_first[child], b_second[child], w_out[child, :, :na], b_out[child, :na],
                               rng, uniforms[k])
            row[k] = counters[k, ROW]
            col[k] = counters[k, COL]
            goal[k] = counters[k, GOAL]
            used[k] = counters[k, DRAWN]
            if status == LEAF_NEEDS_GOAL:
                phase[k] = IN_CALL
                return k
            if status == LEAF_BAD_PROBABILITIES:
                return -2 - k
            rewards[k] = totals[k, 0]
            moves[k] = counters[k, MOVES_MADE]
            terminated[k] = False
        elif kinds[a] == MOVE:
            if phase[k] == STARTING:
                rewards[k] = 0.0
                terminated[k] = False
                r, q = row[k], col[k]
                r_next, q_next = r + deltas[a, 0], q + deltas[a, 1]
                if self_target_free(owners[k], me[s], r_next, q_next):  # the self's move (World.move, self only)
                    grids[k, r + 1, q + 1] = 0
                    owners[k, r + 1, q + 1] = -1
                    grids[k, r_next + 1, q_next + 1] = self_color[s]
                    owners[k, r_next + 1, q_next + 1] = me[s]
                    row[k] = r_next
                    col[k] = q_next
                    if tracks_goal:
                        phase[k] = IN_MOVE
                if phase[k] == IN_MOVE and goal_table[s, row[k], col[k]] < 0:
                    return k
            if phase[k] == IN_MOVE:
                g = goal_table[s, row[k], col[k]]
                if g != goal[k]:
                    goal[k] = g
                    rewards[k] = potential if g == 1 else -potential
        else:  # a signal ends the episode
            terminated[k] = True
            rewards[k] = signal_rewards[a, labels[s], goal[k]]
        phase[k] = STEPPED
    return -1
