"""``PixelWorldVectorEnv``: N PixelWorld environments stepped together in one compiled call (Gymnasium's vector API).

``gymnasium.make_vec("PW-...", num_envs=N)`` builds it (the ids register it as their ``vector_entry_point``). For the
same seeds, actions and reset options its transitions equal those of ``SyncVectorEnv`` over ``gym.make`` of the same
id, step by step: observations, rewards, terminations, truncations and infos (tested).

How: the environments' state is a handful of arrays (scene index, self cell, step count, goal truth, autoreset flag,
the block of scene draws and the PCG64 state of each environment's generator); the scenes are arrays too (initial
colours and owners, the self's start, labels, and the goal per self cell where the kind tracks it, computed per scene
the first time an environment is reset into it with the single env's own test, ``Concept.self_evaluator``). A step
of all environments is :func:`pixelworld_env.core.kernels.step_envs` and their observations
:func:`~pixelworld_env.core.kernels.observe_windows` / :func:`~pixelworld_env.core.kernels.observe_states`. Where
only the self moves (all AAAI-18 data) an environment needs no world arrays of its own: a move is
:func:`~pixelworld_env.core.kernels.self_target_free` on the scene's initial owners. In worlds where objects besides
the self move (the pushable datasets, ``World.self_only`` false) each environment keeps its own padded colours, owners
and object positions, moved by :func:`~pixelworld_env.core.kernels.push_move` (``World.move``'s pushing, compiled);
a goal there is ``Concept.holds_objects`` in Python, as in the single env, memoised per scene and object
positions.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Literal, NamedTuple

import gymnasium as gym
import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from pixelworld_env.concepts.evaluate import SelfEvaluator
from pixelworld_env.core import kernels
from pixelworld_env.core.constants import NUM_COLORS
from pixelworld_env.core.kinds import GOAL_POTENTIAL
from pixelworld_env.core.objects import Cell
from pixelworld_env.core.render import rgb_image
from pixelworld_env.core.scene import Scene
from pixelworld_env.core.world import World
from pixelworld_env.envs.env import PixelWorldEnv, check_scene_index
from pixelworld_env.errors import PixelWorldError, PixelWorldTypeError
from pixelworld_env.validation import check_count, check_options

DRAW_BLOCK = 256
"""Scene indices drawn at a time from an environment's generator, as :meth:`PixelWorldEnv.reset` draws them."""
MAX_VECTOR_ENVS = 65_536
"""The most environments of one vector env (``num_envs``; sb3_smc trains an SMC in 16 by default, 1,024 at most):
each holds arrays of its own (about a kilobyte, more with image observations or objects that are pushed), so a
larger number is refused before anything is built."""
RENDER_ENVS = ("all", "first")

_COLOR_CODES = np.arange(NUM_COLORS, dtype=np.uint8)[:, None, None]
_MASK64 = (1 << 64) - 1


class SelfMoves(NamedTuple):
    """The live arrays of a :class:`PixelWorldVectorEnv` whose worlds move only the self, for a compiled caller that
    moves the self itself instead of calling ``step`` (``sb3_smc``'s :class:`~sb3_smc.envs.hierarchical_vec_env.
    HierarchicalSMCVecEnv`): it resets through ``reset`` (with ``reset_mask``) and keeps each environment's cell
    and goal truth here, as :meth:`PixelWorldVectorEnv.step` would."""

    scene: np.ndarray  #: per environment: its scene (read only)
    row: np.ndarray  #: per environment: the self's row (the caller writes it)
    col: np.ndarray  #: per environment: the self's column (the caller writes it)
    goal: np.ndarray  #: per environment: the goal's truth now, int8 (kinds that track it; the caller writes it)
    goal_table: np.ndarray  #: per scene and self cell: the goal's truth, -1 not known yet (``goal_at`` tests it)
    grid0: np.ndarray  #: per scene: the padded initial colours (int8), the self at its start
    owner0: np.ndarray  #: per scene: the padded initial owners (int16), the self's index at its start
    me: np.ndarray  #: per scene: the self's object index
    self_color: np.ndarray  #: per scene: the self's colour
    labels: np.ndarray  #: per scene: its label (kinds with labels; zeros otherwise)
    kinds: np.ndarray  #: per action: 1 a move, 0 a signal
    signal_rewards: np.ndarray  #: per action, label and goal truth: a signal's reward (``TaskKind.reward_table``)
    deltas: np.ndarray  #: per action: a move's row and column offsets


class PixelWorldVectorEnv(VectorEnv):
    """``num_envs`` copies of a :class:`~pixelworld_env.PixelWorldEnv` (``env``, which is not stepped itself) as one
    Gymnasium vector environment with next-step autoreset (``metadata["autoreset_mode"]``, as ``SyncVectorEnv``);
    ``num_envs`` is an int in ``[1, MAX_VECTOR_ENVS]``.

    * ``reset(seed=...)``: an int seeds environment ``i`` with ``seed + i``, a list one seed (or ``None``) per
      environment. ``options``: ``{"index": i}`` resets every environment into scene ``i``, ``{"index": [i_0, ...]}``
      one index (or ``None``: a drawn scene) per environment; ``{"reset_mask": mask}`` resets only where the bool
      array ``mask`` is set (``SyncVectorEnv``'s option).
    * ``step(actions)``: an integer array of ``num_envs`` valid actions. ``info`` holds each key of the single env's
      ``info`` as an array with its ``_key`` mask (``split`` only for the environments that were reset).
    * ``render()``: the frames (``"rgb_array"`` or ``"ansi"``) of every environment, or of the first one with
      ``render_envs="first"``, as a tuple.

    Observations ``"hand"``, ``"hand_raw"``, ``"full"`` and ``"image"`` are all built in the compiled call (the image
    from the state array); ``render_mode="human"`` and ``aaai18_reset_bug=True`` are for single envs and refused.
    """

    metadata: dict[str, Any] = {"render_modes": ["rgb_array", "ansi"], "autoreset_mode": AutoresetMode.NEXT_STEP}

    def __init__(self, env: PixelWorldEnv, num_envs: int, *, render_envs: Literal["all", "first"] = "all") -> None:
        num_envs = check_count(num_envs, "num_envs", MAX_VECTOR_ENVS, "pixelworld_env.envs.vector.MAX_VECTOR_ENVS")
        self.check_settings(aaai18_reset_bug=env.aaai18_reset_bug, render_mode=env.render_mode,
                            render_envs=render_envs)
        self.num_envs = num_envs
        self.scenes: tuple[Scene, ...] = env.scenes
        self.concept = env.concept
        self.kind = env.kind
        self.labels = env.labels
        self.action_names = env.action_names
        self.max_steps = env.max_steps
        self.observation = env.observation
        self.split = env.split
        self.render_mode = env.render_mode
        self.render_envs = render_envs
        self.metadata = {**type(self).metadata, "render_fps": env.metadata["render_fps"]}
        self.single_observation_space = env.observation_space
        self.observation_space = batch_space(env.observation_space, num_envs)
        self.single_action_space = env.action_space
        self.action_space = batch_space(env.action_space, num_envs)
        self.task_kind = env.task_kind
        self._tracks_goal = env.task_kind.tracks_goal

        # actions: kind (0 signal, 1 move), a signal's rewards, a move's offsets
        self._moves: list[Cell | None] = [e if isinstance(e, tuple) else None for e in env._effects]
        self._kinds = np.array([int(m is not None) for m in self._moves], dtype=np.int64)
        self._signal_rewards = env.task_kind.reward_table(len(self._moves))
        self._deltas = np.array([m if m is not None else (0, 0) for m in self._moves], dtype=np.int64)

        # per scene
        n_scenes = len(self.scenes)
        height, width = self.scenes[0].height, self.scenes[0].width
        worlds = [World(scene) for scene in self.scenes]
        grid0 = np.stack([w.grid for w in worlds])
        self._owner0 = np.stack([w.owner for w in worlds])
        self._start = np.array([w.self_position for w in worlds], dtype=np.int64)
        self._me = np.array([w.self_index for w in worlds], dtype=np.int64)
        self._self_color = np.array([int(s.self_object.color) for s in self.scenes], dtype=np.int64)
        self._push_scene = np.array([not w.self_only for w in worlds], dtype=np.bool_)
        self._labels = np.array(self.labels if self.labels is not None else [0] * n_scenes, dtype=np.int64)
        table_shape = (n_scenes, height, width) if self._tracks_goal else (n_scenes, 1, 1)
        self._goal_table = np.full(table_shape, -1, dtype=np.int8)
        self._goal0 = np.zeros(n_scenes, dtype=np.int8)
        self._ready = np.zeros(n_scenes, dtype=np.uint8)
        # the objects, for the worlds where more than the self moves (kernels.push_move)
        n_objects = np.array([len(s.objects) for s in self.scenes], dtype=np.int64)
        most_objects = int(n_objects.max())
        most_cells = max(len(o.cells) for s in self.scenes for o in s.objects)
        cells = np.zeros((n_scenes, most_objects, most_cells, 2), dtype=np.int64)
        n_cells = np.zeros((n_scenes, most_objects), dtype=np.int64)
        colors = np.zeros((n_scenes, most_objects), dtype=np.int8)
        moveable = np.zeros((n_scenes, most_objects), dtype=np.bool_)
        initial = np.zeros((n_scenes, most_objects, 2), dtype=np.int64)
        for s, scene in enumerate(self.scenes):
            for i, obj in enumerate(scene.objects):
                cells[s, i, : len(obj.cells)] = obj.cells
                n_cells[s, i] = len(obj.cells)
                colors[s, i] = obj.color
                moveable[s, i] = obj.moveable
                initial[s, i] = obj.position
        disjoint0 = (self._owner0 >= 0).sum(axis=(1, 2)) == n_cells.sum(axis=1)
        pushers = num_envs if self._push_scene.any() else 0
        self._positions = np.zeros((pushers, most_objects, 2), dtype=np.int64)
        self._grids = np.zeros((pushers, height + 2, width + 2), dtype=np.int8)
        self._pushing = (grid0, self._owner0, cells, n_cells, colors, moveable, n_objects, initial, disjoint0,
                         self._grids, np.zeros((pushers, height + 2, width + 2), dtype=np.int16), self._positions,
                         np.zeros(pushers, dtype=np.bool_), np.zeros(most_objects, dtype=np.int64),
                         np.zeros(most_objects, dtype=np.bool_))
        self._push_goals: dict[tuple[int, bytes], bool] = {}
        self._evaluators: dict[int, SelfEvaluator] = {}

        # per environment
        self._draws = np.zeros((num_envs, DRAW_BLOCK), dtype=np.int32)
        self._used = np.full(num_envs, DRAW_BLOCK, dtype=np.int64)
        self._rng = np.zeros((num_envs, 4), dtype=np.uint64)  # PCG64 state and increment, high and low words
        self._rng_buffer = np.zeros((num_envs, 2), dtype=np.uint64)  # has_uint32, uinteger
        self._seeded = np.zeros(num_envs, dtype=np.bool_)
        self._bit_generator = np.random.PCG64()
        self._generator = np.random.Generator(self._bit_generator)
        self._scene, self._row, self._col, self._steps = (np.zeros(num_envs, dtype=np.int64) for _ in range(4))
        self._goal = np.zeros(num_envs, dtype=np.int8)
        self._rewards = np.zeros(num_envs, dtype=np.float64)
        (self._autoreset, self._terminated, self._truncated, self._success, self._was_reset,
         self._goal_pending) = (np.zeros(num_envs, dtype=np.bool_) for _ in range(6))
        self._no_index = np.full(num_envs, -1, dtype=np.int64)
        self._everyone = np.ones(num_envs, dtype=np.bool_)
        self._started = False

    @staticmethod
    def check_settings(*, aaai18_reset_bug: bool, render_mode: str | None, render_envs: str) -> None:
        """``ValueError`` for the settings only single envs have (the reset bug, the pygame window) and an unknown
        ``render_envs``."""
        if aaai18_reset_bug:
            raise PixelWorldError("aaai18_reset_bug=True is not supported by the vector env; use "
                                  "gym.make_vec(id, n, vectorization_mode='sync', aaai18_reset_bug=True)")
        if render_mode == "human":
            raise PixelWorldError("render_mode='human' draws one env in a window; use gym.make(id, "
                                  "render_mode='human') or render_mode='rgb_array' here")
        if render_envs not in RENDER_ENVS:
            raise PixelWorldError(f"render_envs must be one of {RENDER_ENVS}, got {render_envs!r}")

    def __repr__(self) -> str:
        name = self.spec.id if self.spec is not None else f"{self.kind}, {len(self.scenes)} scenes"
        return f"{type(self).__name__}({name}, num_envs={self.num_envs})"

    # ------------------------------------------------------------------------------------------ scenes and draws

    def _prepare_scene(self, s: int) -> None:
        """The goal's truth in scene ``s`` at the start (the other self cells are tested when first reached)."""
        if self._push_scene[s]:
            self._goal0[s] = self._push_goal(s, self._pushing[7][s])
        else:
            self._goal0[s] = self._self_goal(s, int(self._start[s, 0]), int(self._start[s, 1]))
        self._ready[s] = 1

    def _self_goal(self, s: int, r: int, c: int) -> bool:
        """Whether the concept holds with the self at ``(r, c)`` in scene ``s`` where only the self moves, tested
        once per scene and cell (``Concept.self_evaluator``, as the single env tests it) into ``_goal_table``."""
        known = self._goal_table[s, r, c]
        if known >= 0:
            return bool(known)
        holds_for = self._evaluators.get(s)
        if holds_for is None:
            scene = self.scenes[s]
            holds_for = self._evaluators[s] = self.concept.self_evaluator(scene.objects, scene.floor_row)
        holds = holds_for(self.scenes[s].self_object.moved_to((r, c)))
        self._goal_table[s, r, c] = holds
        return holds

    def _seed(self, k: int, seed: int | None) -> None:
        generator, _ = seeding.np_random(seed)
        self._store_rng(k, generator)
        self._used[k] = DRAW_BLOCK

    def _store_rng(self, k: int, generator: np.random.Generator) -> None:
        state = generator.bit_generator.state
        value, increment = state["state"]["state"], state["state"]["inc"]
        self._rng[k] = (value >> 64, value & _MASK64, increment >> 64, increment & _MASK64)
        self._rng_buffer[k] = (state["has_uint32"], state["uinteger"])
        self._seeded[k] = True

    def _draw_block(self, k: int) -> None:
        """Environment ``k``'s next block of scene draws, from its generator as the single env draws them."""
        if not self._seeded[k]:
            self._seed(k, None)
        high, low, inc_high, inc_low = (int(x) for x in self._rng[k])
        self._bit_generator.state = {
            "bit_generator": "PCG64", "state": {"state": high << 64 | low, "inc": inc_high << 64 | inc_low},
            "has_uint32": int(self._rng_buffer[k, 0]), "uinteger": int(self._rng_buffer[k, 1]),
        }
        self._draws[k] = self._generator.integers(len(self.scenes), size=DRAW_BLOCK)
        self._used[k] = 0
        self._store_rng(k, self._generator)

    def _prepare(self, pending: np.ndarray, index: np.ndarray) -> None:
        """Give every environment about to be reset (``pending``, into scene ``index`` where >= 0) a scene draw,
        and prepare the scenes they will be reset into."""
        for k in np.flatnonzero(pending & (index < 0) & (self._used >= DRAW_BLOCK)):
            self._draw_block(int(k))
        if self._tracks_goal:
            drawn = self._draws[np.arange(self.num_envs), np.minimum(self._used, DRAW_BLOCK - 1)]
            for s in np.unique(np.where(index >= 0, index, drawn)[pending]):
                if not self._ready[s]:
                    self._prepare_scene(int(s))

    def goal_at(self, scene: int, row: int, col: int) -> bool:
        """Whether the concept holds with the self at ``(row, col)`` of ``scene`` in a world where only the self
        moves, tested once per scene and cell into :attr:`SelfMoves.goal_table` (as the single env tests it)."""
        return self._self_goal(scene, row, col)

    @property
    def self_only(self) -> bool:
        """Whether only the self moves in every scene (``World.self_only``: all AAAI-18 data)."""
        return not self._push_scene.any()

    def self_moves(self) -> SelfMoves:
        """The live arrays through which a compiled caller moves the self itself (:class:`SelfMoves`);
        ``PixelWorldError`` where objects besides the self move in some scene (``World.self_only`` false)."""
        if not self.self_only:
            pushing = np.flatnonzero(self._push_scene)[:3].tolist()
            raise PixelWorldError(f"objects besides the self move in scenes {pushing} (of {len(self.scenes)}): only "
                                  "step() moves them")
        return SelfMoves(self._scene, self._row, self._col, self._goal, self._goal_table, self._pushing[0],
                         self._owner0, self._me, self._self_color, self._labels, self._kinds,
                         self._signal_rewards, self._deltas)

    # ------------------------------------------------------------------------------------------ pushing worlds

    def _push_goal(self, s: int, positions: np.ndarray) -> bool:
        """Whether the concept holds in scene ``s`` with its objects at ``positions`` (``Concept.holds_objects``, as
        the single env tests it after every move there), memoised per scene and positions."""
        scene = self.scenes[s]
        key = (s, positions[: len(scene.objects)].tobytes())
        holds = self._push_goals.get(key)
        if holds is None:
            objects = tuple(obj if obj.position == (r, c) else obj.moved_to((r, c))
                            for obj, (r, c) in zip(scene.objects, positions.tolist(), strict=False))
            holds = self._push_goals[key] = self.concept.holds_objects(objects, scene.floor_row)
        return holds

    def _goals_after_moves(self) -> None:
        """The goal's shaping after the moves whose goal the compiled step left to Python (``_goal_pending``): in
        pushing worlds, and where the self reached a cell of its scene for the first time."""
        for k in np.flatnonzero(self._goal_pending).tolist():
            s = int(self._scene[k])
            if self._push_scene[s]:
                goal = self._push_goal(s, self._positions[k])
            else:
                goal = self._self_goal(s, int(self._row[k]), int(self._col[k]))
            if goal != bool(self._goal[k]):
                self._goal[k] = goal
                self._rewards[k] = GOAL_POTENTIAL if goal else -GOAL_POTENTIAL
                self._success[k] = self._truncated[k] and self._rewards[k] > 0

    # ------------------------------------------------------------------------------------------ observations, infos

    def observe(self) -> np.ndarray:
        """The observations of every environment now (for a caller that moves the self itself: :meth:`self_moves`)."""
        n, observation = self.num_envs, self.observation
        if observation in ("full", "image"):
            out = np.empty((n, self.scenes[0].height, self.scenes[0].width), dtype=np.uint8)
            kernels.observe_states(self._start, self._self_color, self._push_scene, self._pushing, self._scene,
                                   self._row, self._col, out)
            if observation == "image":
                return (out[:, None] == _COLOR_CODES).astype(np.uint8) * np.uint8(255)
            return out
        one_hot = observation == "hand"
        out = np.empty((n, 9 * NUM_COLORS), dtype=np.float32) if one_hot else np.empty((n, 9), dtype=np.int64)
        kernels.observe_windows(one_hot, NUM_COLORS, self._start, self._self_color, self._push_scene, self._pushing,
                                self._scene, self._row, self._col, out)
        return out

    def _infos(self, mask: np.ndarray, success: np.ndarray, signalled: np.ndarray,
               reset: np.ndarray) -> dict[str, Any]:
        """The vector ``info``: the environments in ``mask`` have the single env's keys, those in ``reset`` also
        ``split``; each key with its ``_key`` mask (values 0 / False / None outside it, as Gymnasium's)."""
        everyone = bool(mask.all())
        columns: dict[str, np.ndarray] = {"scene_index": self._scene.copy(), "is_success": success.copy(),
                                          "signalled": signalled.copy()}
        if self.labels is not None:
            columns["label"] = self._labels[self._scene]
        if self._tracks_goal:
            columns["goal"] = self._goal.astype(np.bool_)
        info: dict[str, Any] = {}
        for key, values in columns.items():
            info[key] = values if everyone else np.where(mask, values, np.zeros_like(values))
            info[f"_{key}"] = mask.copy()
        if self.split is not None and reset.any():
            split = np.full(self.num_envs, None, dtype=object)
            split[reset] = self.split
            info["split"], info["_split"] = split, reset.copy()
        return info

    # ------------------------------------------------------------------------------------------ Gymnasium API

    def reset(self, *, seed: int | Sequence[int | None] | None = None,
              options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        n = self.num_envs
        if seed is None:
            seeds: Sequence[int | None] = [None] * n
        elif isinstance(seed, int):
            seeds = [seed + i for i in range(n)]
        else:
            seeds = list(seed)
            if len(seeds) != n:
                raise PixelWorldError(f"If seeds are passed as a list the length must match num_envs={n} but got "
                                      f"length={len(seeds)}.")
        options = check_options(options, ("index", "reset_mask"), "PixelWorldVectorEnv.reset takes "
                                "options={'index': i or [i, ...], 'reset_mask': mask}")
        mask = self._reset_mask(options.get("reset_mask"))
        index = self._indices(options.get("index"))
        if not self._started and not mask.all():
            raise RuntimeError("the first reset must reset every environment (no reset_mask)")
        for k in np.flatnonzero(mask).tolist():
            if seeds[k] is not None:
                self._seed(k, seeds[k])
        while kernels.reset_envs(mask, index, self._tracks_goal, self._ready, self._start, self._goal0,
                                 self._push_scene, self._pushing, self._draws, self._used, self._scene, self._row,
                                 self._col, self._steps, self._goal, self._autoreset) != kernels.OK:
            self._prepare(mask, index)
        self._terminated[mask] = False
        self._truncated[mask] = False
        self._started = True
        nothing = np.zeros(n, dtype=np.bool_)
        return self.observe(), self._infos(mask, nothing, nothing, mask)

    def _reset_mask(self, mask: Any) -> np.ndarray:
        if mask is None:
            return self._everyone.copy()
        if not isinstance(mask, np.ndarray):
            raise PixelWorldTypeError(f"`options['reset_mask']` must be a numpy array, got {type(mask)}")
        if mask.shape != (self.num_envs,):
            raise PixelWorldError(f"`options['reset_mask']` must have shape `({self.num_envs},)`, got {mask.shape}")
        if mask.dtype != np.bool_:
            raise PixelWorldTypeError(f"`options['reset_mask']` must have `dtype=np.bool_`, got {mask.dtype}")
        if not mask.any():
            raise PixelWorldError("`options['reset_mask']` must contain a boolean array with at least one True value, "
                                  f"got reset_mask={mask}")
        return mask.copy()

    def _indices(self, index: Any) -> np.ndarray:
        """``options["index"]`` as one scene index per environment (-1, which users cannot give: draw one), each
        checked as the single env checks it."""
        if index is None:
            return self._no_index
        n = len(self.scenes)
        if isinstance(index, list | tuple) or isinstance(index, np.ndarray) and index.ndim == 1:
            if len(index) != self.num_envs:
                raise PixelWorldError(f"options['index'] as a list needs one entry per environment ({self.num_envs}), "
                                      f"got {len(index)}")
            values = [-1 if i is None else check_scene_index(i, n) for i in index]
        else:
            values = [check_scene_index(index, n)] * self.num_envs
        return np.array(values, dtype=np.int64)

    def step(self, actions: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        if not self._started:
            raise RuntimeError("call reset() first")
        actions = np.asarray(actions)
        if actions.shape != (self.num_envs,) or actions.dtype.kind not in "iu":
            raise PixelWorldError(f"actions must be an integer array of shape ({self.num_envs},), got {actions.dtype} "
                                  f"{actions.shape}")
        if actions.size and (actions.min() < 0 or actions.max() >= len(self.action_names)):
            raise PixelWorldError(f"actions must be in [0, {len(self.action_names)}), got {actions}")
        actions = actions.astype(np.int64, copy=False)
        while kernels.step_envs(actions, self._kinds, self._signal_rewards, self._deltas, self._tracks_goal,
                                self.max_steps, GOAL_POTENTIAL, self._me, self._start,
                                self._labels, self._goal_table, self._goal0, self._ready, self._push_scene,
                                self._pushing, self._draws, self._used, self._scene, self._row, self._col,
                                self._steps, self._goal, self._autoreset, self._rewards, self._terminated,
                                self._truncated, self._success, self._was_reset, self._goal_pending) != kernels.OK:
            self._prepare(self._autoreset, self._no_index)
        if self._tracks_goal and self._goal_pending.any():
            self._goals_after_moves()
        info = self._infos(self._everyone, self._success, self._terminated, self._was_reset)
        return (self.observe(), self._rewards.copy(), self._terminated.copy(), self._truncated.copy(), info)

    def _state(self, k: int) -> np.ndarray:
        """Environment ``k``'s state array (colour codes)."""
        s = self._scene[k]
        if self._push_scene[s]:
            return self._grids[k, 1:-1, 1:-1].copy()
        state = self._pushing[0][s, 1:-1, 1:-1].copy()
        state[self._start[s, 0], self._start[s, 1]] = 0
        state[self._row[k], self._col[k]] = self._self_color[s]
        return state

    def _current_scene(self, k: int) -> Scene:
        scene = self.scenes[self._scene[k]]
        if self._push_scene[self._scene[k]]:
            return scene.with_positions([(r, c) for r, c in self._positions[k, : len(scene.objects)].tolist()])
        positions = [obj.position for obj in scene.objects]
        positions[scene.self_index] = (int(self._row[k]), int(self._col[k]))
        return scene.with_positions(positions)

    def render(self) -> tuple[Any, ...] | None:
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode='rgb_array' or 'ansi'")
            return None
        if not self._started:
            raise RuntimeError("call reset() first")
        envs = range(self.num_envs) if self.render_envs == "all" else range(1)
        if self.render_mode == "ansi":
            return tuple(self._current_scene(k).to_ascii() + "\n" for k in envs)
        return tuple(rgb_image(self._state(k), window=(int(self._row[k]), int(self._col[k]))) for k in envs)
