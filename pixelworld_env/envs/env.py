"""``PixelWorldEnv``: classification and bring-about tasks over a set of scenes.

The rules: docs/design.md, "Observations and actions", "Episodes and the reset" and "Rewards".
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from typing import Any, Literal

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.envs.registration import EnvSpec

from pixelworld_env.concepts import Concept
from pixelworld_env.concepts.evaluate import SelfEvaluator
from pixelworld_env.concepts.parser import Expression
from pixelworld_env.core.constants import NUM_COLORS
from pixelworld_env.core.kinds import GOAL_POTENTIAL, TASK_KINDS, Kind, TaskKind, task_kind
from pixelworld_env.core.objects import Cell
from pixelworld_env.core.render import HUMAN_CELL_SIZE, Window, check_display, rgb_image
from pixelworld_env.core.scene import Scene
from pixelworld_env.core.world import MOVES, World
from pixelworld_env.errors import PixelWorldError
from pixelworld_env.generation.oracle import can_bring_about
from pixelworld_env.validation import check_action, check_bool, check_int, check_options, no_episode

Observation = Literal["hand", "hand_raw", "full", "image"]
OBSERVATIONS: tuple[Observation, ...] = ("hand", "hand_raw", "full", "image")
RENDER_MODES = ("human", "rgb_array", "ansi")

_ONE_HOT_OFFSETS = np.arange(9) * NUM_COLORS
_COLOR_CODES = np.arange(NUM_COLORS, dtype=np.uint8)[:, None, None]


def check_settings(*, max_steps: Any = 100, observation: Any = "hand", render_mode: Any = None,
                   aaai18_reset_bug: Any = False) -> int:
    """Check the settings of a :class:`PixelWorldEnv` before anything is built or loaded; returns ``max_steps``.

    ``ValueError`` for an unknown observation or render mode or ``max_steps < 1``, ``TypeError`` for a ``max_steps``
    that is not an integer or an ``aaai18_reset_bug`` that is not a bool; ``render_mode="human"`` also needs pygame,
    and warns where there is no display (:func:`pixelworld_env.core.render.check_display`).
    """
    if observation not in OBSERVATIONS:
        raise PixelWorldError(f"observation must be one of {OBSERVATIONS}, got {observation!r}")
    if render_mode is not None and render_mode not in RENDER_MODES:
        raise PixelWorldError(f"render_mode must be None or one of {list(RENDER_MODES)}, got {render_mode!r}")
    check_bool(aaai18_reset_bug, "aaai18_reset_bug")
    max_steps = check_int(max_steps, "max_steps", 1)
    if render_mode == "human":
        check_display()
    return max_steps


def check_scene_index(index: Any, num_scenes: int) -> int:
    """``options["index"]`` of a reset: an integer (numpy integers too) in ``[0, num_scenes)``; ``TypeError``
    otherwise, ``IndexError`` out of range (negative indices included)."""
    index = check_int(index, "options['index']")
    if not 0 <= index < num_scenes:
        raise IndexError(f"scene index {index} out of range (0..{num_scenes - 1})")
    return index


def default_labels(kind: TaskKind, concept: Concept, scenes: Sequence[Scene]) -> list[int]:
    """The labels of ``scenes`` for a kind whose worlds have them, where none are given: whether ``concept`` holds
    (``"label"``), or whether it can be brought about by some moves (``"possible"``: an exhaustive search)."""
    if kind.label == "possible":
        return [int(can_bring_about(concept, s)) for s in scenes]
    return [int(concept.holds(s)) for s in scenes]


class PixelWorldEnv(gym.Env):
    """A PixelWorld task: explore a scene with a 3 x 3 window, then signal (docs/design.md, "Observations and
    actions", "Rewards").

    The actions are the kind's signals (:data:`pixelworld_env.core.kinds.TASK_KINDS`), then DOWN, RIGHT, UP, LEFT:

    * ``kind="classification"``: SIG0, SIG1. The signal that matches the scene's label earns +1, the other -1;
      either ends the episode.
    * ``kind="bring-about"``: SIG1. Moving into a state where ``concept`` holds earns +0.5, moving out of it
      -0.5; SIG1 ends the episode with +0.5 if the goal holds, else 0.
    * ``kind="bring-about-or-cannot"``: SIG1 and CANNOT, the shaping of bring-about. SIG1 earns +0.5 if the goal
      holds (+1 in all), else -1; CANNOT +1 in a world where the concept cannot be brought about, else -1 (all told).
      ``labels`` say which worlds allow it (1) or not (0); without them each scene is searched exhaustively
      (:func:`pixelworld_env.generation.oracle.can_bring_about`).

    Episodes are truncated after ``max_steps`` actions (every action counts). ``info`` holds, on every step,
    ``scene_index``, ``label`` (kinds with labels) and ``goal`` (kinds that track it: whether the concept holds now),
    ``is_success`` (the paper's rule: the episode has ended with a final reward > 0) and ``signalled``
    (whether the episode ended with a signal).

    Observations: ``"hand"`` the one-hot (9 colour codes) of the 3 x 3 window, 81 floats; ``"hand_raw"`` the
    window's 9 raw colour codes row-major (the paper's input); ``"full"`` the whole state array; ``"image"`` the
    whole state as a channel-first uint8 image, one channel per colour code, 255 where the cell has that code
    (``(9, height, width)``; SB3's ``CnnPolicy`` divides by 255, so the network sees the one-hot grid;
    :class:`sb3_smc.learning.features.PixelWorldCNN` is a features extractor for it).

    Render modes: ``"rgb_array"`` (10 px per cell, the window outlined), ``"ansi"`` (the text format), ``"human"``
    (the same picture at 20 px per cell in a pygame window, drawn on every ``reset`` and ``step``; pygame is the
    ``render`` extra; without a display the window is drawn off screen, with a warning).

    ``gym.make`` of a ``PW-*`` id adds no ``TimeLimit``: the env truncates itself, and its ``spec.max_episode_steps``
    says when (``max_steps``).
    """

    metadata = {"render_modes": list(RENDER_MODES), "render_fps": 10}

    def __init__(
        self,
        scenes: Sequence[Scene],
        *,
        kind: Kind,
        concept: str | Expression | Concept,
        labels: Sequence[int] | None = None,
        macros: Mapping[str, str] | None = None,
        max_steps: int = 100,
        observation: Observation = "hand",
        render_mode: str | None = None,
        aaai18_reset_bug: bool = False,
    ) -> None:
        self.task_kind = task_kind(kind)
        """The kind's signals, rewards and outcomes (:class:`pixelworld_env.core.kinds.TaskKind`)."""
        max_steps = check_settings(max_steps=max_steps, observation=observation, render_mode=render_mode,
                                   aaai18_reset_bug=aaai18_reset_bug)
        self.scenes: tuple[Scene, ...] = tuple(scenes)
        if not self.scenes:
            raise PixelWorldError("PixelWorldEnv needs at least one scene")
        height, width = self.scenes[0].height, self.scenes[0].width
        if any((s.height, s.width) != (height, width) for s in self.scenes):
            raise PixelWorldError("all scenes of an environment must have the same size")
        if observation == "image" and min(height, width) < NUM_COLORS:
            raise PixelWorldError(f"observation='image' needs scenes of at least {NUM_COLORS} x {NUM_COLORS} cells, "
                                  f"got {height} x {width}: SB3 takes an image's smallest dimension for its "
                                  f"{NUM_COLORS} channels")
        self.kind = kind
        self.concept = concept if isinstance(concept, Concept) else Concept(concept, macros)
        if self.task_kind.label is None and labels is not None:
            labelled = [name for name, k in TASK_KINDS.items() if k.label is not None]
            raise PixelWorldError(f"labels are for {' and '.join(labelled)} tasks; a {kind} task's goal is its "
                                  "concept")
        if self.task_kind.label is not None:
            if labels is None:
                labels = default_labels(self.task_kind, self.concept, self.scenes)
            if len(labels) != len(self.scenes):
                raise PixelWorldError(f"got {len(labels)} labels for {len(self.scenes)} scenes")
            if any(label not in (0, 1) for label in labels):
                raise PixelWorldError(f"{kind} labels must be 0 or 1")
        self.labels: tuple[int, ...] | None = tuple(int(x) for x in labels) if labels is not None else None
        self.max_steps = int(max_steps)
        self.split: str | None = None
        """The dataset split the scenes come from, when known (``gym.make`` of a ``PW-*`` id sets it); reported in
        the ``info`` of every ``reset`` so that evaluations say which split they ran on."""
        self.train_worlds: int | None = None
        """``N`` where the scenes are the first ``N`` worlds of the training split (``gym.make(id,
        train_worlds=N)``); ``None``: the whole split (or not known)."""
        self.observation = observation
        self.render_mode = render_mode
        self._window = Window(f"PixelWorld: {self.concept.text}", self.metadata["render_fps"]) \
            if render_mode == "human" else None
        self.aaai18_reset_bug = aaai18_reset_bug
        self._spec: EnvSpec | None = None

        self.primitive_names: tuple[str, ...] = tuple(MOVES)
        self.action_names: tuple[str, ...] = (*self.task_kind.signal_names, *self.primitive_names)
        self.action_space = spaces.Discrete(len(self.action_names))
        # What each action does: a move offset, or the signal's number in the kind's table.
        self._effects: tuple[Cell | int, ...] = (*range(len(self.task_kind.signals)),
                                                 *(MOVES[name] for name in self.primitive_names))
        if observation == "hand":
            self.observation_space = spaces.Box(0.0, 1.0, shape=(9 * NUM_COLORS,), dtype=np.float32)
        elif observation == "hand_raw":
            self.observation_space = spaces.Box(0, NUM_COLORS - 1, shape=(9,), dtype=np.int64)
        elif observation == "full":
            self.observation_space = spaces.Box(0, NUM_COLORS - 1, shape=(height, width), dtype=np.uint8)
        else:
            self.observation_space = spaces.Box(0, 255, shape=(NUM_COLORS, height, width), dtype=np.uint8)

        self._draws: list[int] = []
        self._worlds: dict[int, World] = {}
        self._last_self: dict[int, Cell] = {}
        # Per scene: the goal's truth per self cell (-1 not known yet), and the concept's test for a moved self.
        self._goal_memo: dict[int, tuple[np.ndarray, SelfEvaluator]] = {}
        # Per scene: the one-hot positions of the window per self cell (worlds where only the self moves).
        self._hot_memo: dict[int, dict[Cell, np.ndarray]] = {}
        self._world: World | None = None
        self._index = 0
        self._steps = 0
        self._goal = False
        self._done = True

    # ------------------------------------------------------------------------------------------ helpers

    def _observe(self) -> np.ndarray:
        if self.observation == "hand":
            return self.hand_observation()
        if self.observation == "hand_raw":
            return self.world.window().astype(np.int64).reshape(-1)
        if self.observation == "full":
            return self.world.state().astype(np.uint8)
        return (self.world.state() == _COLOR_CODES).astype(np.uint8) * np.uint8(255)

    def hand_observation(self, out: np.ndarray | None = None) -> np.ndarray:
        """The one-hot 3 x 3 window of the current state (81 float32), whatever ``observation`` is.

        With ``out`` (zeros in its first 81 entries), the ones are written there and ``out`` is returned.
        """
        obs = np.zeros(9 * NUM_COLORS, dtype=np.float32) if out is None else out
        world = self._world
        assert world is not None
        if world.self_only:  # only the self moves: the window is a function of its cell (memoised per scene)
            memo = self._hot_memo[self._index]
            position = world.positions[world.self_index]
            hot = memo.get(position)
            if hot is None:
                hot = memo[position] = _ONE_HOT_OFFSETS + world.window().ravel()
        else:
            hot = _ONE_HOT_OFFSETS + world.window().ravel()
        obs[hot] = 1.0
        return obs

    def goal_holds(self) -> bool:
        """Whether the concept holds in the current state (memoised per self cell when only the self moves)."""
        world = self._world
        assert world is not None
        if not world.self_only:
            return self.concept.holds_objects(world.objects, world.scene.floor_row)
        return self.goal_at(world.positions[world.self_index])

    @property
    def goal(self) -> bool:
        """Whether the goal holds in the current state (bring-about; always False for classification)."""
        return self._goal

    def goal_at(self, position: Cell) -> bool:
        """Whether the concept would hold with the self at ``position`` (the rest as in the scene; for worlds where
        only the self moves), memoised in :meth:`goal_cells`."""
        cells, holds_for = self._goal_memo[self._index]
        row, col = position
        holds = cells[row, col]
        if holds < 0:
            holds = cells[row, col] = holds_for(self.world.scene.self_object.moved_to(position))
        return bool(holds)

    def goal_cells(self) -> np.ndarray:
        """The current scene's memo of :meth:`goal_at`: one int8 per cell, 1 or 0 where known, -1 where not yet
        (callers that move the self themselves read it and fill it through :meth:`goal_at`)."""
        return self._goal_memo[self._index][0]

    def self_moved(self, goal: bool) -> None:
        """Record the goal's truth after a caller moved the self in the world's arrays itself (compiled option loops
        in worlds where only the self moves: :func:`sb3_smc.common.kernels.leaf_call`); the caller sets the self's
        position with :meth:`World.place_self`."""
        self._goal = goal

    def _info(self, success: bool = False, signalled: bool = False) -> dict[str, Any]:
        info: dict[str, Any] = {"scene_index": self._index, "is_success": success, "signalled": signalled}
        if self.labels is not None:
            info["label"] = self.labels[self._index]
        if self.task_kind.tracks_goal:
            info["goal"] = self._goal
        return info

    def __repr__(self) -> str:
        split = f", split={self.split!r}" if self.split is not None else ""
        return f"{type(self).__name__}({self.kind}, {len(self.scenes)} scenes{split}, concept={self.concept.text!r})"

    @property
    def spec(self) -> EnvSpec | None:
        """The Gymnasium spec (set by ``gym.make``), its ``max_episode_steps`` this env's own limit ``max_steps``.

        Tools read the limit there; a registered ``max_episode_steps`` would instead make ``gym.make`` wrap the env in
        a second limit (``TimeLimit``), so the ``PW-*`` ids register none and the env states its own here.
        """
        return self._spec

    @spec.setter
    def spec(self, value: EnvSpec | None) -> None:
        self._spec = None if value is None else dataclasses.replace(value, max_episode_steps=self.max_steps)

    @property
    def world(self) -> World:
        """The live world of the current episode."""
        if self._world is None:
            raise RuntimeError("call reset() first")
        return self._world

    # ------------------------------------------------------------------------------------------ gym API

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        if seed is not None:
            self._draws = []
        options = check_options(options, ("index",), "PixelWorldEnv.reset takes options={'index': i}")
        if "index" in options:
            index = check_scene_index(options["index"], len(self.scenes))
        else:
            if not self._draws:  # uniform scene indices from np_random, drawn in blocks for speed
                self._draws = self.np_random.integers(len(self.scenes), size=256).tolist()[::-1]
            index = self._draws.pop()
        if self._world is not None and self.aaai18_reset_bug:
            self._last_self[self._index] = self._world.self_position
        self._index = index
        world = self._worlds.get(index)
        if world is None:
            world = self._worlds[index] = World(self.scenes[index])
            scene = self.scenes[index]
            self._goal_memo[index] = (np.full((scene.height, scene.width), -1, dtype=np.int8),
                                      self.concept.self_evaluator(scene.objects, scene.floor_row))
            self._hot_memo[index] = {}
        world.reset(self._last_self.get(index) if self.aaai18_reset_bug else None)
        self._world = world
        self._steps = 0
        self._done = False
        self._goal = self.goal_holds() if self.task_kind.tracks_goal else False
        info = self._info()
        if self.split is not None:
            info["split"] = self.split
        if self._window is not None:
            self.render()
        return self._observe(), info

    def step(self, action):
        reward, terminated, truncated, info = self.transition(check_action(action, self.action_names))
        if self._window is not None:
            self.render()
        return self._observe(), reward, terminated, truncated, info

    def transition(self, action: int) -> tuple[float, bool, bool, dict[str, Any]]:
        """:meth:`step` without building the observation: ``(reward, terminated, truncated, info)``.

        ``action`` must be a valid action index (:meth:`step` checks it); for wrappers that build their own
        observation (:class:`sb3_smc.HierarchicalSMCWrapper`).
        """
        if self._done:
            raise no_episode(self._world is not None, "step")
        effect = self._effects[action]
        self._steps += 1
        terminated = False
        if effect.__class__ is tuple:  # a move
            reward = self._move(effect)  # type: ignore[arg-type]
        else:  # a signal: its number in the kind's table
            terminated = True
            label = self.labels[self._index] if self.labels is not None else 0
            reward = self.task_kind.reward(effect, label, self._goal)  # type: ignore[arg-type]
        truncated = not terminated and self._steps >= self.max_steps
        self._done = terminated or truncated
        info = self._info(success=self._done and reward > 0, signalled=terminated)
        return reward, terminated, truncated, info

    def _move(self, delta: Cell) -> float:
        if self._world.move(delta) and self.task_kind.tracks_goal:  # type: ignore[union-attr]
            goal = self.goal_holds()
            if goal != self._goal:
                self._goal = goal
                return GOAL_POTENTIAL if goal else -GOAL_POTENTIAL
        return 0.0

    def apply_move(self, action: int) -> float:
        """Apply a move action without counting a step or ending the episode; return its (shaping) reward.

        For options that act on the world inside one step of a higher-level policy
        (:class:`sb3_smc.HierarchicalSMCWrapper`); signals are not moves and raise ``ValueError``.
        """
        if self._done:
            raise no_episode(self._world is not None, "apply_move")
        effect = self._effects[action]
        if effect.__class__ is not tuple:
            raise PixelWorldError(f"action {action} ({self.action_names[action]}) is not a move")
        return self._move(effect)  # type: ignore[arg-type]

    # the task protocol that sb3_smc's HierarchicalSMCWrapper drives (sb3_smc.tasks.task.TaskEnv), implemented natively
    sensor_size = 9 * NUM_COLORS
    """Length of :meth:`sense`'s sensor: the one-hot 3 x 3 window."""

    def sense(self, out: np.ndarray) -> np.ndarray:
        """Write the one-hot window into the first :attr:`sensor_size` entries of ``out`` (zeros there)."""
        return self.hand_observation(out=out)

    def apply_primitive(self, action: int) -> tuple[float, bool, bool]:
        """:meth:`apply_move` in the protocol's form ``(reward, terminated, truncated)``: a move never ends the
        episode."""
        return self.apply_move(action), False, False

    def step_info(self) -> dict[str, Any]:
        """The ``info`` of the current state (``is_success`` and ``signalled`` false)."""
        return self._info()

    @property
    def elapsed_steps(self) -> int:
        """Actions taken in this episode (``apply_move`` does not count)."""
        return self._steps

    def render(self):
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode='rgb_array', 'ansi' or 'human'")
            return None
        world = self.world
        if self.render_mode == "ansi":
            return world.current_scene().to_ascii() + "\n"
        if self._window is None:
            return rgb_image(world.state(), window=world.self_position)
        self._window.show(rgb_image(world.state(), cell_size=HUMAN_CELL_SIZE, window=world.self_position))
        return None

    def close(self) -> None:
        if self._window is not None:
            self._window.close()
        super().close()
