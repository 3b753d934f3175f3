"""Training callbacks for SMCs: per-update task statistics, TensorBoard curves, best-snapshot selection, progress.

:class:`SMCTrainingCallback` watches every rollout (one rollout = one policy update, 2,000 environment steps by
default) and

* computes the **mean training return** of the episodes that ended during the rollout and keeps a copy of the
  policy that collected the rollout whenever that mean beats every earlier one (the paper reports the iteration
  with the maximum training ``AverageReturn``; ties go to the earliest update; docs/design.md, "Selection and
  test"), see
  :class:`BestSnapshot`;
* records the task's own curves next to SB3's (``rollout/``, ``train/``) in the logger, so they reach
  TensorBoard when the model has a ``tensorboard_log``:

  ===================================================  ==========================================================
  ``smc/training_return``                              mean undiscounted return of the episodes ended in the
                                                       rollout (the selection statistic)
  ``smc/best_training_return``                         the best mean training return so far
  ``smc/selected_update``                              its update (0-based; the snapshot kept)
  ``smc/success_rate``                                 fraction of those episodes with final reward > 0
  ``smc/accuracy``                                     the same number, for classification tasks only
  ``smc/episode_length``                               decisions per episode (an SMC call is one decision)
  ``smc/episode_primitive_steps``                      primitive actions executed on the world per episode
                                                       (moves, those of calls included, and the final signal)
  ``smc/episodes``                                     episodes ended in the rollout
  ``smc_calls/<child>/calls_per_episode``              direct calls of each child SMC per episode
  ``smc_calls/<child>/call_share``                     fraction of the decisions that called the child
  ``smc_calls/<child>/call_length``                    mean primitive steps per call of the child
  ``smc_calls/<child>/sig1_rate``                      fraction of the child's calls that ended with SIG1
  ===================================================  ==========================================================

* optionally prints one progress line every ``log_every`` updates (``rich`` is not a dependency, so SB3's
  ``progress_bar`` is not used);
* with ``stop_at`` (the largest return an episode can earn), ends training once an update's mean training return
  reaches it: no later update can then be selected (ties keep the earliest), so the selected weights are those
  the whole budget would select; the records end there (SB3 has applied that rollout's update when it stops, at
  the first step of the next rollout). A callback that has stopped stays stopped (its selection is final).

The callback is idempotent at the end of training (rl_zoo3 calls ``on_training_end`` twice).
"""

from __future__ import annotations

import copy
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from stable_baselines3.common.callbacks import BaseCallback

from pixelworld_env.core.kinds import task_kind
from sb3_smc.envs.vec_env import SMCStep

__all__ = ["BestSnapshot", "RolloutStats", "SMCTrainingCallback"]


@dataclass
class BestSnapshot:
    """The paper's selection rule: keep the snapshot of the update with the highest mean training return.

    Call :meth:`update` once per update with that update's mean return; ``snapshot`` (a callable) is only
    evaluated when the return is a new maximum. Ties keep the earliest update; ``NaN`` returns (no episode ended
    in the rollout) are recorded but never selected.
    """

    best_update: int | None = None
    best_return: float = -math.inf
    state: Any = None
    returns: list[float] = field(default_factory=list)

    def update(self, mean_return: float, snapshot: Callable[[], Any] | None = None) -> bool:
        """Record the next update's mean return; return whether it became the selected one."""
        index = len(self.returns)
        value = float(mean_return)
        self.returns.append(value)
        if math.isnan(value) or value <= self.best_return:
            return False
        self.best_update, self.best_return = index, value
        self.state = snapshot() if snapshot is not None else None
        return True


@dataclass
class RolloutStats:
    """What happened during one rollout (episodes ended in it, SMC calls made in it)."""

    returns: list[float] = field(default_factory=list)
    lengths: list[int] = field(default_factory=list)
    primitive_lengths: list[int] = field(default_factory=list)
    successes: list[bool] = field(default_factory=list)
    decisions: int = 0
    calls: dict[str, int] = field(default_factory=dict)
    call_steps: dict[str, int] = field(default_factory=dict)
    call_sig1: dict[str, int] = field(default_factory=dict)

    @property
    def mean_return(self) -> float:
        return float(np.mean(self.returns)) if self.returns else math.nan

    @property
    def success_rate(self) -> float:
        return float(np.mean(self.successes)) if self.successes else math.nan


class SMCTrainingCallback(BaseCallback):
    """Statistics, TensorBoard curves, best-snapshot selection and progress lines for SMC training.

    ``children`` are the names of the SMCs the trained policy can call (their curves are written even when a
    child is never called, as zeros); ``kind`` is the task kind (one scored by accuracy, classification, adds
    ``smc/accuracy``). ``total_updates`` is only used for the progress line. ``stop_at``: the largest mean training
    return there is (:data:`sb3_smc.tasks.task.MAX_RETURN`); training stops once the selection reaches it
    (:attr:`solved`). After training, :attr:`best` holds the selection (``best.state``: a deep copy of the
    policy's ``state_dict`` of the selected update) and :attr:`history` one dict of statistics per update.
    """

    def __init__(self, *, kind: str, children: Sequence[str] = (), total_updates: int | None = None,
                 log_every: int = 0, name: str = "smc", printer: Callable[[str], None] = print,
                 stop_at: float | None = None, verbose: int = 0) -> None:
        super().__init__(verbose)
        self.stop_at = stop_at
        self.solved = False
        self.kind = kind
        self.children = tuple(children)
        self.total_updates = total_updates
        self.log_every = int(log_every)
        self.name = name
        self.printer = printer
        self.best = BestSnapshot()
        self.history: list[dict[str, float]] = []
        self.total_primitive_steps = 0
        self._stats = RolloutStats()
        # per environment; sized on the training's first start (and again if its number of environments differs)
        self._episode_return = np.zeros(0)
        self._episode_length = np.zeros(0, dtype=np.int64)
        self._episode_primitive = np.zeros(0, dtype=np.int64)
        self._start_time = 0.0
        self._finished = False

    def __getstate__(self) -> dict[str, Any]:
        """For a group's checkpoint (:mod:`sb3_smc.learning.group_checkpoint`): the clock as seconds elapsed, without
        ``learn``'s locals and globals (set again before they are read)."""
        state = dict(vars(self))
        state.update(_start_time=self.elapsed, locals={}, globals={})
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        vars(self).update(state)
        self._start_time = time.perf_counter() - state["_start_time"]

    # -------------------------------------------------------------------------------------------- SB3 hooks

    def _on_training_start(self) -> None:
        n = self.training_env.num_envs
        if len(self._episode_return) != n:
            self._episode_return = np.zeros(n)
            self._episode_length = np.zeros(n, dtype=np.int64)
            self._episode_primitive = np.zeros(n, dtype=np.int64)
        self._start_time = time.perf_counter()
        self._start_steps = self.num_timesteps
        self._finished = False

    def _on_rollout_start(self) -> None:
        self._stats = RolloutStats(calls=dict.fromkeys(self.children, 0), call_steps=dict.fromkeys(self.children, 0),
                                   call_sig1=dict.fromkeys(self.children, 0))

    def _on_step(self) -> bool:
        stats = self._stats
        rewards = self.locals["rewards"]
        dones = self.locals["dones"]
        infos = self.locals["infos"]
        self._episode_return += rewards
        self._episode_length += 1
        stats.decisions += len(infos)
        primitive = self._episode_primitive
        calls, call_steps, call_sig1 = stats.calls, stats.call_steps, stats.call_sig1
        for i, info in enumerate(infos):
            moves = info.get("primitive_steps", 1)
            smc_calls = info.get("smc_calls", ())
            # primitive actions executed on the environment: moves (inside calls too) and the SMC's own signals
            primitive[i] += moves if moves or smc_calls else 1
            for call in smc_calls:
                if call["depth"] == 1:
                    child = call["smc"]
                    calls[child] = calls.get(child, 0) + 1
                    call_steps[child] = call_steps.get(child, 0) + call["primitive_steps"]
                    call_sig1[child] = call_sig1.get(child, 0) + (call["outcome"] > 0)
        for k in np.flatnonzero(dones):
            info = infos[k]
            # VecMonitor's episode record when present (the same numbers), else the callback's own sums
            episode = info.get("episode")
            self._episode_ended(int(k), float(episode["r"]) if episode else float(self._episode_return[k]),
                                int(episode["l"]) if episode else int(self._episode_length[k]),
                                bool(info.get("is_success", False)))
        return not self.solved  # False: the first step after the solving rollout's update (its steps counted)

    def on_array_step(self, rewards: np.ndarray, ended: np.ndarray, calls: np.ndarray, episode_returns: np.ndarray,
                      episode_lengths: np.ndarray, step: SMCStep, part: slice, names: Sequence[str]) -> bool:
        """``on_step`` for a step given as arrays instead of info dicts (:mod:`sb3_smc.learning.batched`): the same
        statistics. ``step`` is the group's step, ``part`` this SMC's environments in it (``rewards`` theirs);
        ``ended`` / ``calls``: those of them (indices in ``part``, ascending) whose episode ended / that called a
        child; ``episode_returns`` / ``episode_lengths``: ``VecMonitor``'s records of the episodes ending;
        ``names`` the SMCs that ``step.called`` indexes."""
        self.n_calls += 1
        self.num_timesteps = self.model.num_timesteps
        self._episode_return += rewards
        self._episode_length += 1
        stats = self._stats
        stats.decisions += len(rewards)
        # primitive actions executed on the environment: moves (inside calls too) and the SMC's own signals
        self._episode_primitive += 1
        if calls.size:
            moves = step.moves[part]
            called = step.called[part]
            self._episode_primitive[calls] += moves[calls] - 1
            for k, child, outcome in zip(calls.tolist(), called[calls].tolist(), step.outcomes[part][calls].tolist(),
                                         strict=True):
                name = names[child]
                stats.calls[name] = stats.calls.get(name, 0) + 1
                stats.call_steps[name] = stats.call_steps.get(name, 0) + int(moves[k])
                stats.call_sig1[name] = stats.call_sig1.get(name, 0) + (outcome > 0)
        if ended.size:
            success = step.success[part]
            for k, ret, length in zip(ended.tolist(), episode_returns.tolist(), episode_lengths.tolist(),
                                      strict=True):
                self._episode_ended(k, ret, int(length), bool(success[k]))
        return not self.solved

    def _episode_ended(self, k: int, episode_return: float, length: int, success: bool) -> None:
        """Environment ``k``'s episode ended: into the rollout's statistics, its sums back to zero."""
        stats, primitive = self._stats, self._episode_primitive
        stats.returns.append(episode_return)
        stats.lengths.append(length)
        stats.primitive_lengths.append(int(primitive[k]))
        stats.successes.append(success)
        self._episode_return[k] = 0.0
        self._episode_length[k] = 0
        self.total_primitive_steps += int(primitive[k])
        primitive[k] = 0

    def _on_rollout_end(self) -> None:
        stats = self._stats
        policy = self.model.policy
        self.best.update(stats.mean_return, lambda: copy.deepcopy(policy.state_dict()))
        self.solved = self.stop_at is not None and self.best.best_return >= self.stop_at
        row = self._record(stats)
        self.history.append(row)
        update = len(self.best.returns)
        if self.log_every > 0 and (update % self.log_every == 0 or update == 1):
            self._print_progress(update, row)

    def _on_training_end(self) -> None:
        if self._finished:  # idempotent: rl_zoo3 calls it twice
            return
        self._finished = True
        # primitive steps of episodes still running when training stopped
        if self._episode_primitive is not None:
            self.total_primitive_steps += int(self._episode_primitive.sum())
            self._episode_primitive[:] = 0
        if self.verbose > 0 or self.log_every > 0:
            best = self.best
            self.printer(f"[{self.name}] done: {self.num_timesteps:,} steps in {self.elapsed:.0f} s; selected update "
                         f"{best.best_update} (mean training return {best.best_return:.3f}"
                         + (", the largest there is: stopped there)" if self.solved else ")"))

    # -------------------------------------------------------------------------------------------- helpers

    @property
    def elapsed(self) -> float:
        """Seconds since the start of training."""
        return time.perf_counter() - self._start_time

    def _record(self, stats: RolloutStats) -> dict[str, float]:
        episodes = len(stats.returns)
        row: dict[str, float] = {
            "smc/training_return": stats.mean_return,
            "smc/best_training_return": self.best.best_return if self.best.best_update is not None else math.nan,
            "smc/selected_update": float(self.best.best_update if self.best.best_update is not None else -1),
            "smc/success_rate": stats.success_rate,
            "smc/episode_length": float(np.mean(stats.lengths)) if episodes else math.nan,
            "smc/episode_primitive_steps": float(np.mean(stats.primitive_lengths)) if episodes else math.nan,
            "smc/episodes": float(episodes),
        }
        if task_kind(self.kind).score == "accuracy":
            row["smc/accuracy"] = stats.success_rate
        for child, count in stats.calls.items():
            row[f"smc_calls/{child}/calls_per_episode"] = count / episodes if episodes else math.nan
            row[f"smc_calls/{child}/call_share"] = count / stats.decisions if stats.decisions else math.nan
            row[f"smc_calls/{child}/call_length"] = stats.call_steps[child] / count if count else math.nan
            row[f"smc_calls/{child}/sig1_rate"] = stats.call_sig1[child] / count if count else math.nan
        row["time/num_timesteps"] = float(self.num_timesteps)
        for key, value in row.items():
            if key.startswith("time/"):
                continue
            if not math.isnan(value):  # TensorBoard cannot draw NaN; a missing point is clearer
                self.logger.record(key, value)
        return row

    def _print_progress(self, update: int, row: dict[str, float]) -> None:
        total = f"/{self.total_updates}" if self.total_updates else ""
        steps = self.num_timesteps - self._start_steps
        rate = steps / max(self.elapsed, 1e-9)
        best = self.best
        left = ""
        if self.total_updates and update < self.total_updates:
            left = f"  about {(self.total_updates - update) * self.elapsed / update:.0f} s left"
        self.printer(f"[{self.name}] update {update}{total}{left}  steps {self.num_timesteps:,}  {rate:,.0f} steps/s  "
                     f"return {row['smc/training_return']:.3f}  success {row['smc/success_rate']:.2f}  "
                     f"length {row['smc/episode_length']:.1f}  best {best.best_return:.3f} @ {best.best_update}")
