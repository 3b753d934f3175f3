"""``HierarchicalSMCVecEnv``: the environments of an SMC whose children are compiled leaves, stepped together, the
children's calls included, in one compiled call over PixelWorld's native vector env.

A level-2 SMC of a curriculum calls children without children of their own. In :class:`~sb3_smc.envs.vec_env.SMCVecEnv`
each environment's step is a :class:`~sb3_smc.envs.wrapper.HierarchicalSMCWrapper` step in Python (the action, the
compiled call of the child, the observation), about a hundred microseconds per environment and decision besides the
call itself. Here the step of every environment is one :func:`sb3_smc.envs.leaf_calls.smc_steps` call: each
environment keeps its padded world arrays and moves the self in them with the same
:func:`~sb3_smc.envs.leaf_calls.leaf_call` the wrapper runs, on the native vector env's scenes, cells and goal
tables (:meth:`pixelworld_env.envs.vector.PixelWorldVectorEnv.self_moves`), which also resets the environments
whose episode ended. Each environment's calls draw from its own generator, seeded as the wrapper seeds its own
(``(seed, 0x5EED)``), the uniforms drawn ahead in blocks: the same numbers in the same order.

So it gives what ``SMCVecEnv`` over ``HierarchicalSMCWrapper`` environments gives, step for step with the same seeds
(tested): observations, rewards, SB3's same-step reset with ``terminal_observation`` and ``TimeLimit.truncated``,
and the wrapper's info keys that training reads (``is_success``, ``primitive_steps``,
``smc_calls``). :func:`~sb3_smc.learning.training.make_vec_env` trains SMCs in it where it applies
(:func:`hosts`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from stable_baselines3.common.vec_env.base_vec_env import VecEnvObs

from pixelworld_env.core.constants import NUM_COLORS
from pixelworld_env.core.kinds import GOAL_POTENTIAL
from pixelworld_env.envs.vector import PixelWorldVectorEnv
from sb3_smc.core.layout import CALL_PREFIX, HAND_SIZE, MOVES, PIXELWORLD_LAYOUT, smc_action_names
from sb3_smc.envs import smc_step
from sb3_smc.envs.vec_env import FlatSMCVecEnv, NativeSMCVecEnv, SMCStep
from sb3_smc.envs.wrapper import LeafPlan, leaf_plan
from sb3_smc.errors import SMCError
from sb3_smc.records import WrapperSettings
from sb3_smc.smc.smc import SMC
from sb3_smc.tasks.resolved_task import ResolvedTask

__all__ = ["HierarchicalSMCVecEnv", "hosts", "native_smc_vec_env"]

UNIFORM_BLOCK = 1024
"""Uniforms drawn ahead per environment at a time (at least the call's cap: one per decision of a call)."""


def _leaf_plans(smcs: Sequence[SMC]) -> tuple[list[LeafPlan], str | None]:
    """The children's compiled plans, and why they cannot run as one stacked kernel argument (None if they can)."""
    plans: list[LeafPlan] = []
    for smc in smcs:
        if smc.layout != PIXELWORLD_LAYOUT:
            return plans, f"SMC {smc.name!r} acts on another layout ({smc.layout})"
        plan = leaf_plan(smc, HAND_SIZE, MOVES)
        if plan is None:
            return plans, (f"SMC {smc.name!r} is not a leaf with a compiled policy (children of its own, or a policy "
                           "without the compiled recurrent step)")
        plans.append(plan)
    if not plans:
        return plans, "there are no children"
    first = plans[0]
    for smc, plan in zip(smcs, plans, strict=True):
        if plan.gru != first.gru or plan.hidden != first.hidden:
            return plans, (f"the children's networks differ ({smcs[0].name!r} and {smc.name!r}: recurrent cell or "
                           "size)")
    return plans, None


def _stacked(plans: Sequence[LeafPlan]) -> tuple[Any, ...]:
    """The children's plans and weights as :func:`~sb3_smc.envs.leaf_calls.smc_steps` takes them: per child its
    number of actions, then each array stacked, one row per child, padded with zeros to the most actions (the
    previous-action inputs of ``w_ih``, the columns of ``w_out``; the kernel takes each child's part)."""
    actions = np.array([len(p.kinds) for p in plans], dtype=np.int64)
    most = int(actions.max())

    def stack(arrays: Sequence[np.ndarray], axis: int = 0) -> np.ndarray:
        """The arrays stacked, each padded at the end of ``axis`` by the actions its child lacks."""
        padded = []
        for array, n in zip(arrays, actions.tolist(), strict=True):
            widths = [(0, 0)] * array.ndim
            widths[axis] = (0, most - n)
            padded.append(np.pad(array, widths))
        return np.ascontiguousarray(np.stack(padded))

    w_ih, w_hh, b_first, b_second, w_out, b_out = zip(*(p.weights for p in plans), strict=True)
    return (actions, stack([p.kinds for p in plans]), stack([p.values for p in plans]),
            stack([p.deltas for p in plans]), np.array([p.cut_outcome for p in plans]), plans[0].gru, stack(w_ih),
            np.stack(w_hh), np.stack(b_first),
            np.stack(b_second), stack(w_out, axis=1), stack(b_out))


def hosts(smcs: Sequence[SMC]) -> bool:
    """Whether :class:`HierarchicalSMCVecEnv` can call ``smcs``: compiled leaves on PixelWorld's layout, with
    networks of the same cell and sizes (the task must also move only the self: the vector env checks that)."""
    return _leaf_plans(smcs)[1] is None


def native_smc_vec_env(task: ResolvedTask, num_envs: int, children: Sequence[SMC],
                       settings: WrapperSettings) -> NativeSMCVecEnv | None:
    """The environments of an SMC calling ``children`` on ``task`` over PixelWorld's native vector env, ``num_envs``
    of them with the wrapper ``settings``: a :class:`~sb3_smc.envs.vec_env.FlatSMCVecEnv` without children, a
    :class:`HierarchicalSMCVecEnv` with children it :func:`hosts` on worlds where only the self moves; None where
    neither hosts the SMC (the task has no native vector env, other children, objects besides the self move)."""
    if not task.native_vector or children and not hosts(children):
        return None
    vector = task.make_vector_env(num_envs, settings.max_steps)
    if not children:
        return FlatSMCVecEnv(vector)
    if not vector.self_only:
        return None  # the children's calls run in the wrapper
    return HierarchicalSMCVecEnv(vector, children, include_primitives=settings.include_primitives,
                                 count_primitive_steps=settings.count_primitive_steps,
                                 call_step_cap=settings.call_step_cap)


class HierarchicalSMCVecEnv(NativeSMCVecEnv):
    """SB3's ``VecEnv`` of an SMC with the children ``smcs`` (compiled leaves: :func:`hosts`) over PixelWorld's
    native vector env (``observation="hand"``, worlds where only the self moves), with the wrapper settings of
    :class:`~sb3_smc.envs.wrapper.HierarchicalSMCWrapper` (``include_primitives``, ``count_primitive_steps``,
    ``call_step_cap``); ``record_cells`` is the wrapper's alone. Reset options are refused (the wrapper's
    ``call_seed`` and ``index`` are for single environments). ``get_attr`` and the other per-environment calls are
    :class:`~sb3_smc.envs.gymnasium_vec_env.GymnasiumVecEnv`'s.
    """

    def __init__(self, env: PixelWorldVectorEnv, smcs: Sequence[SMC], *, include_primitives: bool = True,
                 count_primitive_steps: bool = False, call_step_cap: int = 100) -> None:
        if call_step_cap < 1:
            raise SMCError(f"call_step_cap must be >= 1, got {call_step_cap}")
        smcs = tuple(smcs)
        names = [smc.name for smc in smcs]
        if len(set(names)) != len(names):
            raise SMCError(f"SMC names must be unique, got {names}")
        plans, why = _leaf_plans(smcs)
        if why is not None:
            raise SMCError(f"HierarchicalSMCVecEnv calls compiled leaf SMCs of one network shape: {why}")
        super().__init__(env, smc_action_names(env.kind, names, include_primitives, MOVES), names)
        self._world = env.self_moves()  # PixelWorldError where objects besides the self move
        self.smcs = smcs
        self.count_primitive_steps = count_primitive_steps
        self.call_step_cap = int(call_step_cap)
        n, n_actions = env.num_envs, len(self.action_names)
        from sb3_smc.envs import leaf_calls  # numba: loaded with the first such vector env

        self._calls = leaf_calls
        # the top-level actions: a signal or a move (the base env's effect), or a call of a child
        kinds, signal_rewards, deltas, targets = [], [], [], []
        for name in self.action_names:
            if name.startswith(CALL_PREFIX):
                kinds.append(leaf_calls.CALL)
                signal_rewards.append(np.zeros((2, 2)))
                deltas.append((0, 0))
                targets.append(names.index(name[len(CALL_PREFIX):]))
            else:
                a = env.action_names.index(name)
                kinds.append(int(self._world.kinds[a]))  # leaf_calls.MOVE or leaf_calls.SIGNAL, as the vector env's
                signal_rewards.append(self._world.signal_rewards[a])
                deltas.append(tuple(self._world.deltas[a]))
                targets.append(-1)
        self._kinds = np.array(kinds, dtype=np.int64)
        self._signal_rewards = np.array(signal_rewards, dtype=np.float64)
        self._deltas = np.array(deltas, dtype=np.int64).reshape(n_actions, 2)
        self._targets = np.array(targets, dtype=np.int64)
        self._children = _stacked(plans)
        hidden = plans[0].hidden
        # per environment
        self._grids = np.zeros((n, *self._world.grid0.shape[1:]), dtype=self._world.grid0.dtype)
        self._owners = np.zeros((n, *self._world.owner0.shape[1:]), dtype=self._world.owner0.dtype)
        self._phase = np.zeros(n, dtype=np.int64)
        self._counters = np.zeros((n, leaf_calls.N_COUNTERS), dtype=np.int64)
        self._totals = np.zeros((n, 2))
        self._h, self._c = np.zeros((n, hidden)), np.zeros((n, hidden))
        self._block = max(UNIFORM_BLOCK, self.call_step_cap)
        self._uniforms = np.zeros((n, self._block))
        self._used = np.full(n, self._block, dtype=np.int64)
        self._generators: list[np.random.Generator | None] = [None] * n
        self._unused_generator = np.random.default_rng(0)  # leaf_call's argument when it draws from ``uniforms``
        self._rewards = np.zeros(n)
        self._terminated = np.zeros(n, dtype=np.bool_)
        self._moves = np.zeros(n, dtype=np.int64)

    # ------------------------------------------------------------------------------------------ helpers

    def _started(self, ended: np.ndarray) -> None:
        """The environments ``ended`` (a bool mask) have been reset: their worlds and episode state anew."""
        super()._started(ended)
        scenes = self._world.scene[ended]
        self._grids[ended] = self._world.grid0[scenes]
        self._owners[ended] = self._world.owner0[scenes]

    def _draw_ahead(self, k: int, needed: int) -> None:
        """At least ``needed`` uniforms of environment ``k`` drawn ahead (those drawn and not used kept first)."""
        left = self._block - self._used[k]
        if left >= needed:
            return
        generator = self._generators[k]
        if generator is None:
            generator = self._generators[k] = np.random.default_rng()
        row = self._uniforms[k]
        row[:left] = row[self._used[k]:]
        row[left:] = generator.random(self._block - left)
        self._used[k] = 0

    # ------------------------------------------------------------------------------------------ VecEnv API

    def reset(self) -> VecEnvObs:
        hand = self._reset_all()
        for k, seed in enumerate(self._seeds):
            if seed is not None or self._generators[k] is None:  # the wrapper's call generator, seeded as it seeds it
                self._generators[k] = np.random.default_rng((seed, 0x5EED) if seed is not None else None)
                self._used[k] = self._block
        self._reset_seeds()
        return self._observation(hand)

    def step_arrays(self, actions: np.ndarray) -> SMCStep:
        leaf_calls, world = self._calls, self._world
        caps = np.full(self.num_envs, self.call_step_cap, dtype=np.int64)
        if self.count_primitive_steps:  # a call may not run past the episode's moves (the wrapper's rule)
            caps = np.maximum(1, np.minimum(caps, self._max_steps - self._elapsed))
        calls = self._kinds[actions] == leaf_calls.CALL
        for k in np.flatnonzero(calls).tolist():
            self._draw_ahead(k, int(caps[k]))
        self._phase[:] = leaf_calls.STARTING
        while True:
            status = leaf_calls.smc_steps(
                actions, self._kinds, self._signal_rewards, self._deltas, self._targets, caps,
                self.vector_env.task_kind.tracks_goal, GOAL_POTENTIAL, NUM_COLORS, world.me, world.self_color,
                world.labels, world.goal_table, *self._children, world.scene, world.row, world.col, world.goal,
                self._grids, self._owners, self._phase, self._counters, self._totals, self._h, self._c,
                self._uniforms, self._used, self._unused_generator, self._rewards, self._terminated, self._moves)
            if status == -1:
                break
            if status >= 0:  # the self entered a cell whose goal truth is not known yet: test it, then resume
                self.vector_env.goal_at(int(world.scene[status]), int(world.row[status]), int(world.col[status]))
                continue
            child = self.smcs[self._targets[actions[-2 - status]]]
            raise SMCError(f"SMC {child.name!r}: its policy gave action probabilities without a positive finite sum")
        called = np.where(calls, self._targets[actions], -1)
        outcomes = np.where(calls, self._totals[:, 1], 0.0)
        where = np.flatnonzero(calls)
        self._outcomes[where, called[where]] = outcomes[where]
        moves = np.where(calls, self._moves, self._primitive_steps[actions])  # a call's moves, else the rule's
        self._elapsed += smc_step.step_cost(np.where(calls, moves, -1), self.count_primitive_steps)
        terminated = self._terminated.copy()
        # the task's own time limit counts the actions that are not calls: never more than the elapsed steps
        truncated = smc_step.truncated(terminated, np.zeros_like(terminated), self._elapsed, self._max_steps)
        dones = terminated | truncated
        rewards = self._rewards.copy()
        self._previous[:] = actions
        obs = self._observation(self.vector_env.observe())
        ended = np.flatnonzero(dones)
        terminal = obs[ended]  # a copy (fancy indexing)
        if ended.size:
            hand, _ = self.env.reset(options={"reset_mask": dones.copy()})
            self._started(dones)
            obs[ended] = self._observation(hand)[ended]
        return SMCStep(obs, rewards.astype(np.float32), dones, smc_step.is_success(dones, rewards), truncated, ended,
                       terminal, moves, called, outcomes, np.where(calls, rewards, 0.0))
