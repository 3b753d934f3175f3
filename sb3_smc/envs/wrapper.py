"""``HierarchicalSMCWrapper``: SMCs as extra actions of a task: a PixelWorld environment or an SMC task on any
Gymnasium environment (:mod:`sb3_smc.tasks.task`) (docs/design.md, "Hierarchy: SMC calls")."""

from __future__ import annotations

from collections.abc import Generator, Iterable, Sequence
from typing import Any, NamedTuple, Protocol, TypeVar, cast

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.wrappers import OrderEnforcing, PassiveEnvChecker

from pixelworld_env.core.constants import NUM_COLORS
from pixelworld_env.core.kinds import GOAL_POTENTIAL, task_kind
from pixelworld_env.core.world import MOVES as MOVE_OFFSETS
from pixelworld_env.envs.env import PixelWorldEnv
from pixelworld_env.validation import check_action, no_episode
from sb3_smc.core.layout import CALL_PREFIX, smc_action_names
from sb3_smc.envs import smc_step
from sb3_smc.envs.smc_step import (
    ELAPSED_STEPS,
    IS_SUCCESS,
    NO_ACTION,
    NO_OUTCOME,
    PRIMITIVE_STEPS,
    SIGNAL_OUTCOMES,
    SMC_CALLS,
    SMCObservation,
)
from sb3_smc.errors import SMCError, SMCTypeError
from sb3_smc.smc.policies import NumpyGRUPolicy, sample_action
from sb3_smc.smc.smc import SMC, StepPolicy
from sb3_smc.tasks.task import layout_of, returns_bounded, task_layer

_SIGNAL, _MOVE, _CALL = 0, 1, 2
_NO_UNIFORMS = np.empty(0)  # leaf_call draws from the generator

PolicyRequest = tuple[StepPolicy, np.ndarray, Any]
"""What a wrapper coroutine yields when a policy must decide: ``(policy, observation, state)``."""
_Result = TypeVar("_Result")


class _CompiledPolicy(StepPolicy, Protocol):
    """A step policy whose calls can be compiled (``compiled_weights`` not None): the recurrent numpy actors."""

    observation_size: int
    n_actions: int
    hidden_size: int


class LeafPlan(NamedTuple):
    """The constant arguments of a compiled call of a leaf SMC (:func:`sb3_smc.envs.leaf_calls.leaf_call`)."""

    kinds: np.ndarray  #: per action: 1 a move, 0 a signal
    values: np.ndarray  #: per action: a signal's outcome (0 for a move)
    deltas: np.ndarray  #: per action: a move's row and column offsets (0 for a signal)
    cut_outcome: float  #: the outcome of a call that ends without a signal (the SMC kind's)
    gru: bool  #: the policy is a GRU (else an LSTM)
    hidden: int  #: the recurrent state's size
    weights: tuple[np.ndarray, ...]  #: the compiled step's weights (``compiled_weights``)


def leaf_plan(smc: SMC, sensor_size: int, primitives: Sequence[str]) -> LeafPlan | None:
    """How a call of ``smc`` runs compiled on a task with ``sensor_size`` sensor values and the moves
    ``primitives``; None unless ``smc`` is a leaf (no children; its actions are signals and those moves) whose policy
    has a compiled step taking exactly its observation and actions."""
    policy = cast(_CompiledPolicy, smc.policy)  # a policy with compiled weights has the sizes read below
    weights = getattr(policy, "compiled_weights", None)
    names = smc.action_names
    n_actions = len(names)
    if (weights is None or smc.children or any(n not in SIGNAL_OUTCOMES and n not in primitives for n in names)
            or policy.observation_size != SMCObservation(sensor_size, 0, n_actions).size
            or policy.n_actions != n_actions):
        return None
    return LeafPlan(np.array([int(name in primitives) for name in names], dtype=np.int64),
                    np.array([SIGNAL_OUTCOMES.get(name, 0.0) for name in names], dtype=np.float64),
                    np.array([MOVE_OFFSETS.get(name, (0, 0)) for name in names], dtype=np.int64).reshape(n_actions, 2),
                    task_kind(smc.kind).cut_outcome, isinstance(policy, NumpyGRUPolicy), policy.hidden_size, weights)


def _only_order_checks(env: gym.Env, base: gym.Env) -> bool:
    layer = env
    while layer is not base:
        if type(layer) not in (OrderEnforcing, PassiveEnvChecker):
            return False
        layer = cast(gym.Wrapper, layer).env  # one of the two wrappers
    return True


def _smc_actions(smcs: Any) -> tuple[SMC, ...]:
    """``smcs`` as a tuple of SMC objects; ``TypeError`` naming what else was given."""
    if isinstance(smcs, str | SMC) or not isinstance(smcs, Iterable):
        raise SMCTypeError(f"smcs must be a sequence of SMCs, got {type(smcs).__name__} {smcs!r}")
    out = tuple(smcs)
    for i, smc in enumerate(out):
        if not isinstance(smc, SMC):
            hint = (": SMCs are objects, not names; take them from their library (library.wrap(env, names), or "
                    "[library[name] for name in names])") if isinstance(smc, str) else ""
            raise SMCTypeError(f"smcs[{i}] must be an SMC, got {type(smc).__name__} {smc!r}{hint}")
    return out


class HierarchicalSMCWrapper(gym.Wrapper, gym.utils.RecordConstructorArgs):
    """A task whose actions are its signals, its primitive actions (PixelWorld: the four moves) and one action per
    SMC. The task is the :class:`~sb3_smc.tasks.task.TaskEnv` under ``env``: a PixelWorld environment, or an
    :class:`~sb3_smc.tasks.task.SMCTask` on any Gymnasium environment (stepped through its own ``step``; the compiled
    calls below are PixelWorld's).

    Choosing an SMC runs its frozen policy on the same world, from a fresh recurrent state and stochastically
    (seeded by ``reset(seed=...)``), until it emits one of its signals or ``call_step_cap`` primitive moves have
    been made under it, the moves of the calls it makes included (docs/design.md, "Hierarchy: SMC calls"); each
    call also takes at most ``call_step_cap`` decisions of its own. Its signal
    never ends the episode: it becomes the SMC's **outcome** (the signal's: +1 SIG1, -1 SIG0, -1 CANNOT; a call
    cut at its cap: the SMC kind's ``cut_outcome``, 0, or -0.5 for bring-about-or-cannot). An SMC that has
    children calls them the same way, each with its own outcome vector, at any depth; a nested call shares the
    move budget of the top-level call it runs in, so a call of any depth makes at most ``call_step_cap`` moves.

    * Observation: the one-hot 3 x 3 window (81), the last outcome of each SMC (0 until called in this
      episode), the one-hot previous action (zeros after reset): :class:`sb3_smc.envs.smc_step.SMCObservation`, which
      :class:`~sb3_smc.envs.vec_env.FlatSMCVecEnv` writes too, as it applies the same step rules
      (:mod:`sb3_smc.envs.smc_step`).
    * Reward of a call: the sum of the environment rewards of its primitive moves (shaping included).
    * Time: a call counts as one step of the episode's ``max_steps`` budget (the default), or, with
      ``count_primitive_steps=True``, as the number of moves it made (at least 1); calls are then also cut
      at the remaining budget.
    * ``include_primitives=False`` removes the four moves (the paper's "noprim" ablation); signals stay.
    * ``info`` on every step adds ``primitive_steps`` (moves executed during the step), ``elapsed_steps``
      and ``smc_calls``: one dict per call made during the step, nested calls included, in the order the
      calls finished: ``{"smc", "depth", "primitive_steps", "outcome", "reward"}``. With ``record_cells=True``
      it also has ``moves``: for each primitive step of the step (those inside calls included), the chain of SMCs
      that made it (outermost first; empty for a move of the policy itself) and the action's name; and ``cells``:
      on PixelWorld the self's cell after each of those moves (empty elsewhere).

    Any policy following :class:`sb3_smc.smc.smc.StepPolicy` can stand behind an SMC (scripted ones included).
    """

    def __init__(self, env: gym.Env, smcs: Sequence[SMC] = (), *, include_primitives: bool = True,
                 count_primitive_steps: bool = False, call_step_cap: int = 100, record_cells: bool = False) -> None:
        smcs = _smc_actions(smcs)
        gym.utils.RecordConstructorArgs.__init__(self, smcs=smcs, include_primitives=include_primitives,
                                                 count_primitive_steps=count_primitive_steps,
                                                 call_step_cap=call_step_cap, record_cells=record_cells)
        super().__init__(env)
        base = task_layer(env)
        if call_step_cap < 1:
            raise SMCError(f"call_step_cap must be >= 1, got {call_step_cap}")
        self.base = base
        self.pixelworld = isinstance(base, PixelWorldEnv)
        self.smcs = smcs
        names = [smc.name for smc in self.smcs]
        if len(set(names)) != len(names):
            raise SMCError(f"SMC names must be unique, got {names}")
        if self.pixelworld and cast(PixelWorldEnv, base).observation != "hand":
            raise SMCError(f"HierarchicalSMCWrapper builds SMC observations from the one-hot 3 x 3 window: the "
                           f"environment needs observation='hand', got {cast(PixelWorldEnv, base).observation!r}")
        self.layout = layout_of(base)
        for smc in self.smcs:
            if smc.layout != self.layout:
                raise SMCError(f"SMC {smc.name!r} acts on another environment layout ({smc.layout}) than this "
                               f"environment's ({self.layout}): it was trained on another environment or "
                               "observation")
            smc.check_layout()
        self.include_primitives = include_primitives
        self.count_primitive_steps = count_primitive_steps
        self._action_cost = smc_step.step_cost(None, count_primitive_steps)  # a signal's or a primitive's
        self.call_step_cap = int(call_step_cap)
        self.action_names = smc_action_names(base.kind, names, include_primitives, self.layout.primitives)
        self.action_space = spaces.Discrete(len(self.action_names))
        self._observations: dict[tuple[int, int], SMCObservation] = {}
        self._observation_parts = self._observation_of(len(self.smcs), len(self.action_names))
        self.observation_space = self._observation_parts.space(bounded=self.pixelworld)
        self._plan = self._action_plan(self.action_names, self.action_names.index)
        self._primitive_steps = smc_step.primitive_steps(self.action_names, self.layout.primitives)
        self._child_plans: dict[int, list[tuple[int, Any]]] = {}
        self._leaf_plans: dict[int, tuple[SMC, Any, LeafPlan | None]] = {}
        self._outcomes = np.full(len(self.smcs), NO_OUTCOME, dtype=np.float32)
        self._previous_action = NO_ACTION
        # Moves and signals may skip the layers between this wrapper and the base env when those only check the
        # call order (gym.make's OrderEnforcing / PassiveEnvChecker), which the wrapper checks itself.
        self._direct = _only_order_checks(env, cast(gym.Env, base))
        self.returns_bounded = self._direct and returns_bounded(base)
        """Whether no episode returns more than :data:`~sb3_smc.tasks.task.MAX_RETURN`: the task's own rewards reach the
        wrapper unchanged (:func:`~sb3_smc.tasks.task.returns_bounded`; between them only Gymnasium's order checks)."""
        self._ended = (False, False)  # (terminated, truncated) when the environment ended the episode in a call
        self._rng: np.random.Generator | None = None
        self._elapsed = 0
        self._done = True
        self.record_cells = record_cells
        self._cells: list[tuple[int, int]] = []
        self._moves: list[tuple[tuple[str, ...], str]] = []
        self._stack: list[str] = []

    # ------------------------------------------------------------------------------------------ helpers

    def _observation_of(self, n_outcomes: int, n_actions: int) -> SMCObservation:
        """The observation of an SMC with ``n_outcomes`` SMC actions and ``n_actions`` actions on this task."""
        parts = self._observations.get((n_outcomes, n_actions))
        if parts is None:
            parts = self._observations[n_outcomes, n_actions] = SMCObservation(self.layout.sensor_size, n_outcomes,
                                                                               n_actions)
        return parts

    def _action_plan(self, names: Sequence[str], parent_index) -> list[tuple[int, Any]]:
        """For each action name: (_SIGNAL, base index or outcome), (_MOVE, base index) or (_CALL, child index)."""
        plan: list[tuple[int, Any]] = []
        children = [n for n in names if n.startswith(CALL_PREFIX)]
        for name in names:
            if name in SIGNAL_OUTCOMES:
                plan.append((_SIGNAL, SIGNAL_OUTCOMES[name] if parent_index is None else parent_index(name)))
            elif name in self.layout.primitives:
                plan.append((_MOVE, self.base.action_names.index(name)))
            else:
                plan.append((_CALL, children.index(name)))
        return plan

    def _plan_of(self, smc: SMC) -> list[tuple[int, Any]]:
        plan = self._child_plans.get(id(smc))
        if plan is None:
            plan = self._child_plans[id(smc)] = self._action_plan(smc.action_names, None)
        return plan

    def _leaf_plan(self, smc: SMC) -> LeafPlan | None:
        """:func:`leaf_plan` of ``smc`` on this task, cached while ``smc`` keeps its policy."""
        key = id(smc)
        cached = self._leaf_plans.get(key)
        if cached is None or cached[0] is not smc or cached[1] is not smc.policy:  # new, or its policy replaced
            leaf = leaf_plan(smc, self.layout.sensor_size, self.layout.primitives)
            cached = self._leaf_plans[key] = (smc, smc.policy, leaf)  # the SMC kept: its id is not reused meanwhile
        return cached[2]

    def _compilable(self) -> bool:
        """Whether a leaf's call can be compiled now: a PixelWorld where only the self moves, no stale pixel."""
        world = cast(PixelWorldEnv, self.base).world
        return world.self_only and not world.stale

    def _compiled_call(self, smc: SMC, leaf: LeafPlan, cap: int, budget: list[int], rng: np.random.Generator
                       ) -> tuple[float, int, float]:
        """One call of the leaf ``smc`` made by the compiled loop: the same moves, draws and result as the loop of
        :meth:`call_coroutine`."""
        from sb3_smc.envs import leaf_calls  # numba: loaded on the first compiled call

        kinds, values, deltas, cut, gru, hidden, (w_ih, w_hh, b_first, b_second, w_out, b_out) = leaf
        base = cast(PixelWorldEnv, self.base)
        world = base.world
        row, col = world.positions[world.self_index]
        counters = np.array([row, col, cap, budget[0], 0, -1, int(base.goal), 0, 0], dtype=np.int64)
        totals = np.array([0.0, cut])
        h, c = np.zeros(hidden), np.zeros(hidden)
        cells = base.goal_cells()
        tracks_goal = base.task_kind.tracks_goal
        color = int(world.scene.self_object.color)
        try:
            while True:
                status = leaf_calls.leaf_call(world.grid, world.owner, world.self_index, color, cells, tracks_goal,
                                              GOAL_POTENTIAL, NUM_COLORS, kinds, values, deltas, counters, totals, gru,
                                              h, c, w_ih, w_hh, b_first, b_second, w_out, b_out, rng,
                                              _NO_UNIFORMS)
                if status != leaf_calls.LEAF_NEEDS_GOAL:
                    break
                base.goal_at((int(counters[leaf_calls.ROW]), int(counters[leaf_calls.COL])))
        finally:  # the world's arrays hold the moves made so far, whatever happened: keep the rest in step
            world.place_self((int(counters[leaf_calls.ROW]), int(counters[leaf_calls.COL])))
            base.self_moved(bool(counters[leaf_calls.GOAL]))
            budget[0] = int(counters[leaf_calls.BUDGET])
        if status == leaf_calls.LEAF_BAD_PROBABILITIES:
            raise SMCError(f"SMC {smc.name!r}: its policy gave action probabilities without a positive finite sum")
        return float(totals[0]), int(counters[leaf_calls.MOVES_MADE]), float(totals[1])

    @property
    def outcomes(self) -> np.ndarray:
        """The last outcome of each SMC in this episode (a copy)."""
        return self._outcomes.copy()

    def _observation(self) -> np.ndarray:
        return self._call_observation(self._observation_parts, self._outcomes, self._previous_action)

    def call_coroutine(self, smc: SMC, depth: int, calls: list[dict[str, Any]], cap: int,
                       budget: list[int] | None = None
                       ) -> Generator[PolicyRequest, tuple[np.ndarray, Any], tuple[float, int, float]]:
        """One call of ``smc`` on the live world as a coroutine; returns ``(reward, primitive steps, outcome)``.

        The call takes at most ``cap`` decisions and makes at most ``budget[0]`` moves (default ``cap``), nested
        calls included: ``budget`` is the one-element move budget shared by the calls of one top-level call,
        decreased by every move; the call ends timed out (its kind's cut outcome) when it is used up.

        It yields ``(policy, observation, state)`` whenever a policy must decide (``smc``'s or, inside a child's call,
        the child's) and expects ``policy.probabilities(observation, state)`` back: :func:`run_coroutine` (what
        :meth:`step` uses) answers at once; :class:`sb3_smc.envs.vec_env.SMCVecEnv` answers the requests of many
        environments with one batched evaluation per policy. A policy that is never batched (``batch_from = None``: the
        compiled numpy actors, whose single steps cost less than stacking a group) is asked here directly instead,
        without the round trip. The draws from this env's generator are the same either way. A call of a leaf SMC (no
        children, a compiled actor) in a world where only the self moves is made whole by one compiled loop
        (:func:`sb3_smc.envs.leaf_calls.leaf_call`), with the same moves, draws and result, and yields nothing.
        """
        assert self._rng is not None
        if budget is None:
            budget = [cap]
        if self.pixelworld and not self.record_cells and self._compilable():
            leaf = self._leaf_plan(smc)
            if leaf is not None:  # the whole call compiled: no decision to yield
                reward, moves, outcome = self._compiled_call(smc, leaf, cap, budget, self._rng)
                calls.append({"smc": smc.name, "depth": depth, "primitive_steps": moves, "outcome": outcome,
                              "reward": reward})
                return reward, moves, outcome
        plan = self._plan_of(smc)
        n_actions = len(plan)
        policy = smc.policy
        inline = getattr(policy, "batch_from", 2) is None
        parts = self._observation_of(len(smc.children), n_actions)
        outcomes = np.full(len(smc.children), NO_OUTCOME, dtype=np.float32)
        previous = NO_ACTION
        state = policy.initial_state()
        reward, moves, outcome = 0.0, 0, task_kind(smc.kind).cut_outcome
        self._stack.append(smc.name)
        for _ in range(cap):
            if budget[0] <= 0:  # the moves of the top-level call are used up (by a call this one made)
                break
            obs = self._call_observation(parts, outcomes, previous)
            if inline:
                probabilities, state = policy.probabilities(obs, state)
            else:
                probabilities, state = yield policy, obs, state
            if len(probabilities) != n_actions:
                raise SMCError(f"SMC {smc.name!r}: its policy gives {len(probabilities)} action probabilities, "
                               f"but its actions are {smc.action_names}")
            action = sample_action(probabilities, self._rng)
            kind, value = plan[action]
            if kind == _SIGNAL:
                outcome = value
                break
            if kind == _MOVE:
                r, terminated, truncated = self.base.apply_primitive(value)
                reward += r
                moves += 1
                budget[0] -= 1
                if self.record_cells:
                    if self.pixelworld:
                        self._cells.append(cast(PixelWorldEnv, self.base).world.self_position)
                    self._moves.append((tuple(self._stack), smc.action_names[action]))
                if terminated or truncated:  # the environment ended the episode: the call ends with it
                    self._ended = (terminated, truncated)
                    break
            else:
                r, m, o = yield from self.call_coroutine(smc.children[value], depth + 1, calls, cap, budget)
                outcomes[value] = o
                reward += r
                moves += m
                if self._ended != (False, False):
                    break
            previous = action
        self._stack.pop()
        calls.append({"smc": smc.name, "depth": depth, "primitive_steps": moves, "outcome": outcome,
                      "reward": reward})
        return reward, moves, outcome

    def _call_observation(self, parts: SMCObservation, outcomes: np.ndarray, previous: int) -> np.ndarray:
        """The observation of the SMC of ``parts`` (the top-level policy or a called SMC) in the current state."""
        obs = parts.blank()
        self.base.sense(obs)
        return parts.write(obs, outcomes, previous)

    # ------------------------------------------------------------------------------------------ gym API

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        """Reset the task with ``seed`` and ``options``; the SMC calls' sampling is seeded with ``seed`` too, or with
        ``options["call_seed"]`` (taken out before the task sees the options), so that one start state can be
        replayed with different calls."""
        options = dict(options) if options else None
        call_seed = options.pop("call_seed", None) if options else None
        _, info = self.env.reset(seed=seed, options=options or None)
        if call_seed is not None:
            self._rng = np.random.default_rng((call_seed, 0x5EED))
        elif seed is not None:
            self._rng = np.random.default_rng((seed, 0x5EED))
        elif self._rng is None:
            self._rng = np.random.default_rng()
        self._outcomes[:] = NO_OUTCOME
        self._previous_action = NO_ACTION
        self._elapsed = 0
        self._done = False
        self._ended = (False, False)
        info = {**info, PRIMITIVE_STEPS: 0, ELAPSED_STEPS: 0, SMC_CALLS: []}
        return self._observation(), info

    def step(self, action):
        return run_coroutine(self.step_coroutine(action))

    def step_coroutine(self, action) -> Generator[PolicyRequest, tuple[np.ndarray, Any], tuple]:
        """:meth:`step` as a coroutine that yields the policy decisions of SMC calls (see :meth:`call_coroutine`)
        and returns the step's ``(observation, reward, terminated, truncated, info)``."""
        if self._done:
            raise no_episode(self._rng is not None, "step")
        action = check_action(action, self.action_names)
        kind, value = self._plan[action]
        calls: list[dict[str, Any]] = []
        self._cells = []
        self._moves = []
        self._stack = []
        if kind == _CALL:
            cap = self.call_step_cap
            if self.count_primitive_steps:
                cap = max(1, min(cap, self.base.max_steps - self._elapsed))
            reward, moves, outcome = yield from self.call_coroutine(self.smcs[value], 1, calls, cap)
            self._outcomes[value] = outcome
            terminated, base_truncated = self._ended
            info = self.base.step_info()
            cost = smc_step.step_cost(moves, self.count_primitive_steps)
        else:
            if self._direct:  # the base env's step without the observation the wrapper would discard
                reward, terminated, base_truncated, info = self.base.transition(value)
            else:
                _, step_reward, terminated, base_truncated, info = self.env.step(value)
                reward = cast(float, step_reward)  # PixelWorldEnv.step's float, behind Gymnasium's checking wrappers
            moves = self._primitive_steps[action]
            cost = self._action_cost
            if moves and self.record_cells:
                if self.pixelworld:
                    self._cells.append(cast(PixelWorldEnv, self.base).world.self_position)
                self._moves.append(((), self.action_names[action]))
        self._elapsed += cost
        truncated = smc_step.truncated(terminated, base_truncated, self._elapsed, self.base.max_steps)
        self._done = terminated or truncated
        self._previous_action = action
        info = {**info, IS_SUCCESS: smc_step.is_success(self._done, reward), PRIMITIVE_STEPS: moves,
                ELAPSED_STEPS: self._elapsed, SMC_CALLS: calls}
        if self.record_cells:
            info["cells"] = self._cells
            info["moves"] = self._moves
        return self._observation(), float(reward), terminated, truncated, info


def run_coroutine(coroutine: Generator[PolicyRequest, tuple[np.ndarray, Any], _Result]) -> _Result:
    """Drive a wrapper coroutine to its end, answering each decision with the policy's own ``probabilities``."""
    try:
        policy, observation, state = next(coroutine)
        while True:
            policy, observation, state = coroutine.send(policy.probabilities(observation, state))
    except StopIteration as stop:
        return stop.value
