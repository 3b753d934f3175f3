"""The paper's test protocol (docs/design.md, "Selection and test") as a function: :func:`evaluate`.

Every environment of the split (each scene, in order) is run ``repeats`` times (10 in the paper) with the SMC's
**stochastic** policy; an episode succeeds when its final step's reward is > 0 (classification: the right signal;
bring-about: SIG1 in the goal, or a time-out on the very step that entered it). The score is the mean over
environments x repeats: classification accuracy or bring-about success rate.

Seeding: episode ``(environment i, repeat r)`` uses the seed derived from ``(seed, 512 + r, i)`` (the paper seeds
repeat ``r`` with 512 + r) for the policy's sampling and, through ``reset(seed=...)``, for the child SMCs it
calls; every episode is reproducible on its own and the whole result is deterministic for a given ``seed``.

Each episode also records the cells the self visited (``(row, col)``, including the moves made inside SMC calls,
consecutive duplicates removed) for trajectory pictures.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from pixelworld_env.core.kinds import task_kind
from pixelworld_env.validation import check_int, check_seed
from sb3_smc.envs.factory import make_smc_env, spec_for_smc
from sb3_smc.errors import SMCError
from sb3_smc.records import EvaluationRecord, WrapperSettings
from sb3_smc.smc.policies import sample_action
from sb3_smc.smc.smc import SMC

if TYPE_CHECKING:
    from pixelworld_env.envs.env import PixelWorldEnv
    from sb3_smc.envs.wrapper import HierarchicalSMCWrapper

__all__ = ["FOREIGN_TEST_SEED", "MAX_REPEATS", "MAX_STARTS", "EnvironmentResult", "EpisodeResult", "EvaluationResult",
           "REPEAT_SEED_OFFSET", "evaluate", "episode_seed", "make_evaluation_env", "run_episode", "start_seed"]

REPEAT_SEED_OFFSET = 512
"""Repeat ``r`` of the paper's test is seeded with ``512 + r``."""
FOREIGN_TEST_SEED = 1_000_000_000
"""The first start seed of the test split of a task without datasets (:func:`start_seed`)."""
FOREIGN_SPLITS = {"train": 0, "test": FOREIGN_TEST_SEED}
"""The first start seed of each split of a task without datasets."""
MAX_REPEATS = 1000
"""The most episodes per environment of one test (``repeats``; the paper's 10): :func:`evaluate`,
``run_experiment`` and ``sb3-smc experiment --repeats``."""
MAX_STARTS = 100_000
"""The most start states a test of a task without datasets runs (``starts``; default 100)."""

Cell = tuple[int, int]


@dataclass
class EpisodeResult:
    """One test episode."""

    environment: int
    repeat: int
    seed: int
    success: bool
    final_reward: float
    total_reward: float
    length: int
    """Decisions of the SMC (an SMC call is one)."""
    primitive_steps: int
    """World moves, those made by SMC calls included."""
    signalled: bool
    """Whether the episode ended with a signal (not a time-out)."""
    actions: list[int] = field(default_factory=list)
    cells: list[Cell] = field(default_factory=list)
    """The self's cells from the start, in order, consecutive duplicates removed."""
    calls: dict[str, int] = field(default_factory=dict)
    """Direct calls of each child SMC."""
    moves: list[tuple[tuple[str, ...], str]] = field(default_factory=list)
    """Each primitive move in order: the chain of SMCs that made it (outermost first; empty: the SMC itself) and
    the move (recorded with the cells)."""
    move_decisions: list[int] = field(default_factory=list)
    """For each move of ``moves``, the decision (0-based step of the episode) it belongs to."""
    call_log: list[dict[str, Any]] = field(default_factory=list)
    """Every SMC call of the episode, nested ones included, in the order they finished (``info["smc_calls"]``)."""
    label: int | None = None
    """The classification label of a task without datasets, read at reset (PixelWorld's are its scenes')."""


@dataclass
class EnvironmentResult:
    """The repeats of one environment (scene) of the split."""

    index: int
    score: float
    label: int | None
    """The world's label (classification: the concept holds; bring-about-or-cannot: the goal is possible; ``None``
    for bring-about)."""
    episodes: list[EpisodeResult]


@dataclass
class EvaluationResult:
    """Result of :func:`evaluate`: the overall ``score`` and one :class:`EnvironmentResult` per environment."""

    smc: str
    env_id: str
    split: str
    kind: str
    repeats: int
    seed: int
    score: float
    environments: list[EnvironmentResult]
    action_names: tuple[str, ...] = ()
    train_worlds: int | None = None
    """``N`` where the environments were the first ``N`` worlds of the training split (``None``: the whole split)."""

    @property
    def scores(self) -> list[float]:
        """Per-environment scores, in environment order."""
        return [env.score for env in self.environments]

    @property
    def episodes(self) -> list[EpisodeResult]:
        """Every episode, environment by environment, repeat by repeat."""
        return [episode for env in self.environments for episode in env.episodes]

    @property
    def n_episodes(self) -> int:
        return sum(len(env.episodes) for env in self.environments)

    @property
    def mean_length(self) -> float:
        """Mean decisions per episode."""
        return float(np.mean([e.length for e in self.episodes])) if self.environments else float("nan")

    def call_counts(self) -> dict[str, int]:
        """Direct calls of each child SMC over all episodes."""
        total: dict[str, int] = {}
        for episode in self.episodes:
            for name, count in episode.calls.items():
                total[name] = total.get(name, 0) + count
        return total

    @property
    def record(self) -> EvaluationRecord:
        """The summary an SMC and its library keep (no episodes)."""
        return EvaluationRecord(smc=self.smc, env_id=self.env_id, split=self.split, kind=self.kind,
                                repeats=self.repeats, evaluation_seed=self.seed, score=self.score,
                                environment_scores=tuple(self.scores), mean_length=self.mean_length,
                                call_counts=self.call_counts(), train_worlds=self.train_worlds)

    def to_dict(self) -> dict[str, Any]:
        """Plain data (JSON-ready: cells become lists)."""
        return asdict(self)

    def summary(self) -> str:
        what = task_kind(self.kind).score
        return (f"{self.smc} on {self.env_id} ({self.split}): {what} {self.score:.3f} over {len(self.environments)} "
                f"environments x {self.repeats} repeats, mean length {self.mean_length:.1f}")


def episode_seed(seed: int, repeat: int, index: int) -> int:
    """The seed of episode (environment ``index``, repeat ``repeat``) of an evaluation with ``seed``."""
    return int(np.random.SeedSequence((seed, REPEAT_SEED_OFFSET + repeat, index)).generate_state(1)[0])


def run_episode(smc: SMC, env: HierarchicalSMCWrapper, *, index: int | None = None, seed: int,
                record_cells: bool = True, start_seed: int | None = None) -> EpisodeResult:
    """Run one episode of ``smc`` on ``env`` (a :class:`~sb3_smc.envs.wrapper.HierarchicalSMCWrapper` built for it).

    On PixelWorld ``index`` picks the scene (``None``: the env's own draw) and the env is reset with ``seed``. On
    another task (:class:`~sb3_smc.tasks.task.SMCTask`) the task is reset with ``start_seed`` (its start state) and the
    SMC calls' sampling with ``seed``. Actions are sampled from the SMC's policy with
    ``numpy.random.default_rng((seed, 1))``. Moves and calls are recorded with ``record_cells``, cells on PixelWorld
    only.
    """
    label = None
    if env.pixelworld:
        observation, _ = env.reset(seed=seed, options=None if index is None else {"index": index})
    else:
        observation, reset_info = env.reset(seed=start_seed, options={"call_seed": seed})
        label = reset_info.get("label")
    cells: list[Cell] = ([cast("PixelWorldEnv", env.base).world.self_position] if record_cells and env.pixelworld
                         else [])
    rng = np.random.default_rng((seed, 1))
    policy = smc.policy
    state = policy.initial_state()
    actions: list[int] = []
    calls: dict[str, int] = {}
    moves: list[tuple[tuple[str, ...], str]] = []
    move_decisions: list[int] = []
    call_log: list[dict[str, Any]] = []
    total = reward = 0.0
    length = primitive = 0
    terminated = truncated = False
    while not (terminated or truncated):
        probabilities, state = policy.probabilities(observation, state)
        action = sample_action(probabilities, rng)
        observation, reward, terminated, truncated, info = env.step(action)
        actions.append(action)
        total += reward
        length += 1
        primitive += int(info.get("primitive_steps", 1))
        for call in info.get("smc_calls", ()):
            if call["depth"] == 1:
                calls[call["smc"]] = calls.get(call["smc"], 0) + 1
            if record_cells:
                call_log.append(dict(call, decision=length - 1))
        if record_cells:
            step_moves = info.get("moves", ())
            moves.extend(step_moves)
            move_decisions.extend([length - 1] * len(step_moves))
            for cell in info.get("cells", ()):
                if cells[-1] != cell:
                    cells.append(cell)
    return EpisodeResult(environment=-1 if index is None else index, repeat=-1, seed=seed, success=bool(reward > 0),
                         final_reward=float(reward), total_reward=float(total), length=length,
                         primitive_steps=primitive, signalled=bool(terminated), actions=actions, cells=cells,
                         calls=calls, moves=moves, move_decisions=move_decisions, call_log=call_log, label=label)


def make_evaluation_env(smc: SMC, env_id: str | None = None, *, split: str = "test", max_steps: int | None = None,
                        env_kwargs: Mapping[str, Any] | None = None,
                        wrapper: WrapperSettings | None = None) -> HierarchicalSMCWrapper:
    """The environment ``smc`` was trained in (:func:`sb3_smc.envs.factory.make_smc_env` with its spec), on ``split``.

    ``env_id`` defaults to the SMC's own task; ``wrapper`` replaces the wrapper settings it was trained with (e.g.
    ``count_primitive_steps``), ``max_steps`` the episode length. The wrapper reports the cells of every move (those
    inside SMC calls too) for :func:`run_episode`.
    """
    env_id = _env_id(smc, env_id)
    spec = spec_for_smc(smc, env_id)
    wrapper = wrapper or spec.wrapper
    if max_steps is not None:
        wrapper = dataclasses.replace(wrapper, max_steps=max_steps)
    return make_smc_env(spec, smc.children, env_id=env_id, split=split, wrapper=wrapper, env_kwargs=env_kwargs,
                        record_cells=True)


def _env_id(smc: SMC, env_id: str | None) -> str:
    if env_id is not None:
        return env_id
    if smc.spec is None:
        raise SMCError(f"SMC {smc.name!r} has no training spec: name the env id to evaluate it on")
    return smc.spec.task.env_id


def start_seed(split: str, index: int) -> int:
    """The reset seed of start state ``index`` of ``split`` on a task without datasets (an
    :class:`~sb3_smc.tasks.task.SMCTask`): ``index`` for ``"train"``, ``FOREIGN_TEST_SEED + index`` for ``"test"``."""
    if split not in FOREIGN_SPLITS:
        raise SMCError(f"a task without datasets has the splits {tuple(FOREIGN_SPLITS)} (start seeds), got {split!r}")
    return FOREIGN_SPLITS[split] + index


def evaluate(smc: SMC, env_id: str | None = None, *, split: str = "test", repeats: int = 10, seed: int = 0,
             max_steps: int | None = None, record_cells: bool = True, env_kwargs: Mapping[str, Any] | None = None,
             keep: bool = True, starts: int | None = None, wrapper: WrapperSettings | None = None) -> EvaluationResult:
    """The paper's test: every environment of ``split`` run ``repeats`` times, stochastic policy; deterministic for a
    given ``seed``. The SMC's children, primitive-action setting and wrapper settings are those of its spec.

    :param smc: the SMC to test.
    :param env_id: the task (default: the one the SMC was trained on).
    :param split: ``"test"`` or ``"train"``. On a task without datasets (an :class:`~sb3_smc.tasks.task.SMCTask` on any
        Gymnasium environment) the environments are ``starts`` start states: the task reset with
        :func:`start_seed` (``"test"``: seeds from ``FOREIGN_TEST_SEED``, far from the ``seed + i`` training resets;
        ``"train"``: from 0), each repeat sampling the policy and the SMC calls anew from the same start.
    :param repeats: episodes per environment (the paper's 10; at most :data:`MAX_REPEATS`).
    :param seed: the evaluation seed (policy sampling and SMC calls), not the SMC's training seed.
    :param max_steps: the episode's length (default: the spec's).
    :param record_cells: keep the cells visited in each episode.
    :param env_kwargs: extra keyword arguments for ``gym.make``.
    :param keep: add the result's :class:`~sb3_smc.records.EvaluationRecord` to ``smc.evaluations`` (replacing an
        earlier one of the same env id and split), so a library saves it.
    :param starts: start states of a task without datasets (default 100; at most :data:`MAX_STARTS`).
    :param wrapper: replaces the spec's wrapper settings (e.g. to count the moves of calls against the episode's
        steps).
    :return: the overall ``score`` (mean of final-step reward > 0 over environments x repeats), one
        :class:`EnvironmentResult` per environment (its score, label and episodes) and, per episode, the visited
        cells.
    """
    repeats = check_int(repeats, "repeats", 1)
    if repeats > MAX_REPEATS:
        raise SMCError(f"repeats must be at most {MAX_REPEATS:,}, got {repeats:,}")
    seed = check_seed(seed, "evaluation seed")
    env_id = _env_id(smc, env_id)
    smc.check_layout()
    env = make_evaluation_env(smc, env_id, split=split, max_steps=max_steps, env_kwargs=env_kwargs, wrapper=wrapper)
    try:
        base = env.base
        if base.kind != smc.kind:
            raise SMCError(f"SMC {smc.name!r} is a {smc.kind} SMC but {env_id} is a {base.kind} task")
        if tuple(env.action_names) != tuple(smc.action_names):
            raise SMCError(f"SMC {smc.name!r} has actions {smc.action_names}, the env {env.action_names}")
        pixelworld = cast("PixelWorldEnv", base) if env.pixelworld else None
        if pixelworld is not None:
            if pixelworld.split != split:  # a user's own id over chosen scenes: its worlds are not that split
                ran = f"its {pixelworld.split} split" if pixelworld.split is not None else "worlds of no known split"
                raise SMCError(f"SMC {smc.name!r}: {env_id} runs {ran} ({len(pixelworld.scenes)} worlds), not the "
                               f"{split} split: evaluate on the PixelWorld id whose {split} split it is "
                               "(evaluate(smc, env_id='PW-...-v0')), or register your worlds with their splits "
                               "(pixelworld_env.register_worlds)")
            if starts is not None:
                raise SMCError(f"starts= is for tasks without datasets; {env_id} runs every scene of its {split} "
                               "split")
            n = len(pixelworld.scenes)
        else:
            n = check_int(100 if starts is None else starts, "starts", 1)
            if n > MAX_STARTS:
                raise SMCError(f"starts must be at most {MAX_STARTS:,}, got {n:,}")
        environments = []
        for index in range(n):
            episodes = []
            for repeat in range(repeats):
                episode = run_episode(smc, env, index=index, seed=episode_seed(seed, repeat, index),
                                      record_cells=record_cells,
                                      start_seed=None if pixelworld is not None else start_seed(split, index))
                episode.repeat = repeat
                episodes.append(episode)
            if pixelworld is not None:
                label = pixelworld.labels[index] if pixelworld.labels is not None else None
            else:
                label = episodes[0].label
            score = float(np.mean([e.success for e in episodes]))
            environments.append(EnvironmentResult(index=index, score=score, label=label, episodes=episodes))
    finally:
        env.close()
    score = float(np.mean([e.success for env_result in environments for e in env_result.episodes]))
    result = EvaluationResult(smc=smc.name, env_id=env_id, split=split, kind=smc.kind, repeats=repeats, seed=seed,
                              score=score, environments=environments, action_names=tuple(smc.action_names),
                              train_worlds=getattr(pixelworld, "train_worlds", None))
    if keep:
        smc.add_evaluation(result.record)
    return result
