"""Train many SMCs in one process: :func:`train_smcs`.

Every experiment trains many small, independent SMCs (5 seeds of every node, many nodes of a level). Trained one
after another, each pays the per-call costs of its environment and its learner alone. :func:`train_smcs` trains a
group of SMCs together:

* the environments of all SMCs on the same task (same env id and settings, the same children) are one PixelWorld
  vector env (:class:`~sb3_smc.envs.vec_env.FlatSMCVecEnv` over ``sum(n_envs)`` environments, or, for SMCs whose
  children are compiled leaves, :class:`~sb3_smc.envs.hierarchical_vec_env.HierarchicalSMCVecEnv`, the children's calls
  included), stepped in **one compiled call** per step for the whole group; each SMC's model sees its own
  environments through a :class:`~sb3_smc.learning.env_group.SliceVecEnv` (with SB3's ``VecMonitor`` on top, as in
  :func:`~sb3_smc.learning.training.train_smc`);
* each SMC keeps its own model (a real sb3-contrib ``RecurrentPPO`` / :class:`~sb3_smc.recurrent_trpo.RecurrentTRPO`
  object, saved and loaded as today), optimizer state, rollout buffer,
  :class:`~sb3_smc.learning.callbacks.SMCTrainingCallback` (records, best-update selection, early stop) and its own
  random streams: the global torch, numpy and Python generators are swapped to the SMC's own state around each of its
  policy steps and updates, so each SMC draws what it would draw trained alone;
* the rollout loop is sb3-contrib's ``RecurrentPPO.collect_rollouts`` and SB3's ``learn`` step for step, run for
  all SMCs of the group in lockstep (an SMC that stops early or ends its budget leaves the group; its
  environments are still stepped, with action 0, and their results ignored). Where the policy takes the compiled
  collection step and the SMC's only callback is its :class:`~sb3_smc.learning.callbacks.SMCTrainingCallback` (the
  default), the step runs on numpy arrays: :meth:`~sb3_smc.common.recurrent.SequenceLstmPolicy.compiled_step`
  with the rollout's draws made in one ``torch.rand`` call (the same numbers as one call per step), the group's
  :meth:`~sb3_smc.envs.vec_env.FlatSMCVecEnv.step_arrays` without info dicts, and the monitor's, the callback's and the
  buffer's bookkeeping written out on arrays; any other SMC takes SB3's path with info dicts. Where every SMC of
  the group takes the compiled LSTM step with networks of the same shapes, their steps are one compiled call for
  the whole group (:func:`~sb3_smc.common.kernels.lstm_collection_steps`, each SMC's weights and draws stacked once
  per rollout).

So each SMC is the one :func:`~sb3_smc.learning.training.train_smc` gives for its spec, bit for bit (tested for one SMC
and for a group of five seeds). Its record's ``wall_time_s`` is its share of the group's time: its own bookkeeping
and updates, and the group's policy and environment steps divided among the SMCs training at that step.

Specs the group cannot host (children that are not compiled leaves of one cell and size, a world where objects
besides the self move under an SMC with children, a non-PixelWorld task, a memoryless learner, frame stacking,
RecurrentTRPO's linear feature baseline, semi-MDP discounting) are trained by ``train_smc``, one after another.
"""

from __future__ import annotations

import random
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import ExitStack, contextmanager
from copy import deepcopy
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, cast

import numpy as np
import torch
from sb3_contrib import RecurrentPPO
from sb3_contrib.common.recurrent.type_aliases import RNNStates
from stable_baselines3.common.utils import obs_as_tensor
from stable_baselines3.common.vec_env import VecEnv, VecMonitor

from sb3_smc.common import kernels
from sb3_smc.common.recurrent import SequenceLstmPolicy
from sb3_smc.common.recurrent.lean_update import use_lean_update
from sb3_smc.common.recurrent.policies import gru_cell_state
from sb3_smc.core.hyperparameters import constructor_arguments
from sb3_smc.envs.hierarchical_vec_env import native_smc_vec_env
from sb3_smc.errors import SMCError
from sb3_smc.learning.env_group import EnvGroup, SliceVecEnv
from sb3_smc.learning.group_checkpoint import GroupCheckpoint
from sb3_smc.learning.training import (
    TaskFacts,
    build_model,
    check_lean_update,
    check_model_settings,
    finished_smc,
    resolve_children,
    resolved_spec,
    task_of,
    train_smc,
    training_callbacks,
)
from sb3_smc.records import TrainingSpec
from sb3_smc.smc.smc import SMC
from sb3_smc.tasks.resolved_task import resolve_task

__all__ = ["batchable", "train_smcs"]


def batchable(spec: TrainingSpec) -> bool:
    """Whether :func:`train_smcs` trains ``spec`` in a group (else it runs ``train_smc`` for it): a recurrent learner
    (``RecurrentPPO`` or ``RecurrentTRPO`` with its critic), no frame stacking, the paper's discounting. The group
    also needs a PixelWorld id with a native vector env, and, for an SMC with children, children that are compiled
    leaves in worlds where only the self moves (:func:`~sb3_smc.envs.hierarchical_vec_env.hosts`): ``train_smcs``
    checks those."""
    if spec.frame_stack != 1 or spec.wrapper.discount != "decision":
        return False
    if spec.algo not in ("RecurrentPPO", "RecurrentTRPO"):
        return False
    _, settings = constructor_arguments(spec.hyperparameters)
    return settings.get("baseline", "critic") == "critic"


@dataclass
class _RandomState:
    """An SMC's own global random streams (torch, numpy, Python), swapped in while it draws."""

    torch_state: torch.Tensor = field(default_factory=torch.get_rng_state)
    numpy_state: Any = field(default_factory=np.random.get_state)
    python_state: Any = field(default_factory=random.getstate)

    @contextmanager
    def torch_only(self) -> Iterator[None]:
        """Its torch stream (the policy's draws during collection)."""
        outside = torch.get_rng_state()
        torch.set_rng_state(self.torch_state)
        try:
            yield
        finally:
            self.torch_state = torch.get_rng_state()
            torch.set_rng_state(outside)

    @contextmanager
    def all_streams(self) -> Iterator[None]:
        """All three streams (updates: the buffer's shuffling draws from numpy's)."""
        outside = torch.get_rng_state(), np.random.get_state(), random.getstate()
        torch.set_rng_state(self.torch_state)
        np.random.set_state(self.numpy_state)
        random.setstate(self.python_state)
        try:
            yield
        finally:
            self.torch_state, self.numpy_state, self.python_state = (
                torch.get_rng_state(), np.random.get_state(), random.getstate())
            torch.set_rng_state(outside[0])
            np.random.set_state(outside[1])
            random.setstate(outside[2])


class _Job:
    """One SMC of a group: its model and callbacks, and sb3-contrib's ``collect_rollouts`` / SB3's ``learn`` cut
    at the environment step (:meth:`act` before it, :meth:`observe` after it)."""

    def __init__(self, spec: TrainingSpec, children: tuple[SMC, ...], task: TaskFacts, venv: VecEnv, *,
                 tensorboard_log: str | None,
                 log_every: int | None, printer: Callable[[str], None], stop_at_max_return: bool,
                 lean_update: bool) -> None:
        self.spec, self.children, self.task = spec, children, task
        self.model, self.initial = build_model(spec, venv, task, tensorboard_log=tensorboard_log)
        if not isinstance(self.model, RecurrentPPO):
            raise SMCError(f"SMC {spec.name!r}: a group trains recurrent learners, got {spec.algo}")
        if lean_update:
            check_lean_update(spec, self.model)
        self.lean_update = lean_update
        self._enter_lean()
        self.random = _RandomState()  # the streams as the model's seeding left them
        self.stats, self.callback = training_callbacks(spec, task, log_every=log_every, printer=printer,
                                                       stop_at_max_return=stop_at_max_return)
        self.seconds = 0.0
        self.iteration = 0
        self.total_timesteps = spec.budget.total_timesteps
        self.lstm_states: Any = None
        self._step: tuple[Any, ...] = ()
        self.lean = False  # set by start: the compiled collection step and array bookkeeping apply
        self._weights: tuple[Any, ...] = ()
        self._uniforms = np.zeros((0, 0))
        self._monitor = (np.zeros(0, dtype=np.float32), np.zeros(0, dtype=np.int32))
        self._monitor_start = time.time()

    def start(self) -> None:
        """``learn``'s set-up (the environments are reset already)."""
        model = self.model
        with self.random.all_streams():
            self.total_timesteps, self.callback = model._setup_learn(
                self.total_timesteps, self.callback, True, self.spec.name, False)
            self.callback.on_training_start(locals(), globals())
        policy, n = model.policy, model.n_envs
        with torch.no_grad():
            self.lean = (self.callback is self.stats and isinstance(policy, SequenceLstmPolicy)
                         and policy.compiled_collection_weights(torch.as_tensor(model._last_obs))
                         is not None)
        self._monitor = (np.zeros(n, dtype=np.float32), np.zeros(n, dtype=np.int32))
        self._monitor_start = time.time()

    @property
    def running(self) -> bool:
        return bool(self.model.num_timesteps < self.total_timesteps)

    def __getstate__(self) -> dict[str, Any]:
        """For a group's checkpoint (:mod:`~sb3_smc.learning.group_checkpoint`, taken within :meth:`lean_off`): the
        monitor's clock as seconds elapsed."""
        return {**vars(self), "_lean": None, "_monitor_start": time.time() - self._monitor_start}

    def __setstate__(self, state: dict[str, Any]) -> None:
        vars(self).update(state)
        self._monitor_start = time.time() - state["_monitor_start"]
        self._enter_lean()

    def _enter_lean(self) -> None:
        """The lean update's train and collection (with ``lean_update``), until :meth:`finish`, as in train_smc."""
        self._lean = ExitStack()
        if self.lean_update:
            self._lean.enter_context(use_lean_update(self.model))

    @contextmanager
    def lean_off(self) -> Iterator[None]:
        """The model without the lean update's patches within the block (a checkpoint pickles it)."""
        self._lean.close()
        try:
            yield
        finally:
            self._enter_lean()

    def start_rollout(self) -> None:
        model = self.model
        model.policy.set_training_mode(False)
        model.rollout_buffer.reset()
        self.callback.on_rollout_start()
        self.lstm_states = deepcopy(model._last_lstm_states)
        if self.lean:  # the rollout's draws at once: torch.rand in one call gives the per-step calls' numbers
            policy = model.policy
            with torch.no_grad():
                self._weights = policy.compiled_collection_weights(torch.as_tensor(model._last_obs))
            with self.random.torch_only():
                self._uniforms = torch.rand(model.n_steps * model.n_envs, dtype=torch.float64).numpy().reshape(
                    model.n_steps, model.n_envs)
            self._h, self._c = (self.lstm_states.pi[0][0].numpy(), self.lstm_states.pi[1][0].numpy())

    def act(self) -> None:
        """The policy's step on the last observations; the actions go to the group's step."""
        model = self.model
        if self.lean:
            buffer = model.rollout_buffer
            starts = model._last_episode_starts.astype(np.float64)
            step = model.policy.compiled_step(self._weights, model._last_obs, self._h, self._c, starts,
                                              self._uniforms[buffer.pos])
            part = cast(SliceVecEnv, model.env.unwrapped)
            part.group.actions[part.start:part.stop] = step[0]
            self._step = step
            return
        with self.random.torch_only(), torch.no_grad():
            obs_tensor = obs_as_tensor(model._last_obs, model.device)
            episode_starts = torch.tensor(model._last_episode_starts, dtype=torch.float32, device=model.device)
            actions, values, log_probs, lstm_states = model.policy(obs_tensor, self.lstm_states, episode_starts)
        actions = actions.cpu().numpy()
        model.env.step_async(actions)
        self._step = (actions, values, log_probs, lstm_states)

    def observe(self) -> bool:
        """The step's results into the callbacks and the rollout buffer; ``False`` when a callback stops training."""
        if self.lean:
            return self._observe_arrays()
        model = self.model
        env = model.env
        actions, values, log_probs, lstm_states = self._step
        new_obs, rewards, dones, infos = env.step_wait()
        model.num_timesteps += env.num_envs
        self.callback.update_locals({"new_obs": new_obs, "rewards": rewards, "dones": dones, "infos": infos,
                                     "actions": actions, "values": values, "log_probs": log_probs})
        if not self.callback.on_step():
            return False
        model._update_info_buffer(infos, dones)
        actions = actions.reshape(-1, 1)
        for idx in np.flatnonzero(dones):  # a time limit: bootstrap with the value of the terminal observation
            if infos[idx].get("terminal_observation") is not None and infos[idx].get("TimeLimit.truncated", False):
                terminal_obs = model.policy.obs_to_tensor(infos[idx]["terminal_observation"])[0]
                with torch.no_grad():
                    terminal_lstm_state = (lstm_states.vf[0][:, idx:idx + 1, :].contiguous(),
                                           lstm_states.vf[1][:, idx:idx + 1, :].contiguous())
                    starts = torch.tensor([False], dtype=torch.float32, device=model.device)
                    terminal_value = model.policy.predict_values(terminal_obs, terminal_lstm_state, starts)[0]
                rewards[idx] += model.gamma * terminal_value
        model.rollout_buffer.add(model._last_obs, actions, rewards, model._last_episode_starts, values, log_probs,
                                 lstm_states=model._last_lstm_states)
        model._last_obs = new_obs
        model._last_episode_starts = dones
        model._last_lstm_states = self.lstm_states = lstm_states
        return True

    def _observe_arrays(self) -> bool:
        """:meth:`observe` on the group's arrays: ``VecMonitor``'s sums, the callback's statistics
        (:meth:`~sb3_smc.learning.callbacks.SMCTrainingCallback.on_array_step`), the time-limit bootstrap and the
        buffer's ``add`` written out, the same numbers without info dicts."""
        model = self.model
        part = cast(SliceVecEnv, model.env.unwrapped)
        group, i = part.group, part.index
        step = group.step_result
        assert step is not None
        a, b = part.start, part.stop
        obs, rewards, dones = step.obs[a:b], step.rewards[a:b], step.dones[a:b]
        first, last = group.ended_at[i], group.ended_at[i + 1]
        ended, terminal = step.ended[first:last] - a, step.terminal[first:last]
        model.num_timesteps += b - a
        returns, lengths = self._monitor
        returns += rewards
        lengths += 1
        episode_returns, episode_lengths = returns[ended], lengths[ended]
        returns[ended] = 0
        lengths[ended] = 0
        calls = group.calls[group.calls_at[i]:group.calls_at[i + 1]] - a
        if not self.stats.on_array_step(rewards, ended, calls, episode_returns, episode_lengths, step, slice(a, b),
                                        group.env.children):
            self._set_lstm_states()
            return False
        actions, values, log_probs, h, c = self._step
        if ended.size:
            seconds = round(time.time() - self._monitor_start, 6)
            model.ep_info_buffer.extend({"r": r, "l": n, "t": seconds}
                                        for r, n in zip(episode_returns, episode_lengths, strict=True))
            model.ep_success_buffer.extend(step.success[a:b][ended].tolist())
            for row, idx in enumerate(ended.tolist()):  # a time limit: bootstrap with the terminal value
                if step.time_limit[a + idx]:
                    terminal_obs = model.policy.obs_to_tensor(terminal[row])[0]
                    with torch.no_grad():
                        state = (torch.from_numpy(h[idx:idx + 1])[None], torch.from_numpy(c[idx:idx + 1])[None])
                        starts = torch.tensor([False], dtype=torch.float32, device=model.device)
                        terminal_value = model.policy.predict_values(terminal_obs, state, starts)[0]
                    rewards[idx] += model.gamma * terminal_value
        buffer = model.rollout_buffer
        pos = buffer.pos
        for states in (buffer.hidden_states_pi, buffer.hidden_states_vf):
            states[pos, 0] = self._h
        for states in (buffer.cell_states_pi, buffer.cell_states_vf):
            states[pos, 0] = self._c
        buffer.observations[pos] = model._last_obs
        buffer.actions[pos] = actions.reshape(-1, 1)
        buffer.rewards[pos] = rewards
        buffer.episode_starts[pos] = model._last_episode_starts
        buffer.values[pos] = values.flatten()
        buffer.log_probs[pos] = log_probs
        buffer.pos += 1
        buffer.full = buffer.pos == buffer.buffer_size
        model._last_obs = obs
        model._last_episode_starts = dones
        self._h, self._c = h, c  # the model's torch states from them at the rollout's end (_set_lstm_states)
        return True

    def _set_lstm_states(self) -> None:
        """The model's last LSTM states from the last step's arrays (the lean collection keeps them as numpy)."""
        states = (torch.from_numpy(self._h)[None], torch.from_numpy(self._c)[None])
        self.model._last_lstm_states = self.lstm_states = RNNStates(states, states)

    def end_rollout(self) -> None:
        """The rollout's returns and advantages, the callbacks' rollout end, then ``learn``'s update step."""
        model = self.model
        if self.lean:
            self._set_lstm_states()
        with torch.no_grad():
            episode_starts = torch.tensor(model._last_episode_starts, dtype=torch.float32, device=model.device)
            values = model.policy.predict_values(obs_as_tensor(model._last_obs, model.device), self.lstm_states.vf,
                                                 episode_starts)
        model.rollout_buffer.compute_returns_and_advantage(last_values=values, dones=model._last_episode_starts)
        self.callback.on_rollout_end()
        self.iteration += 1
        model._update_current_progress_remaining(model.num_timesteps, self.total_timesteps)
        model.dump_logs(self.iteration)
        with self.random.all_streams():
            model.train()  # lean_train under the lean update

    def finish(self) -> SMC:
        self._lean.close()
        self.callback.on_training_end()
        self.stats.on_training_end()
        return finished_smc(self.spec, self.children, self.model, self.stats, self.task, self.initial, self.seconds,
                            lean_update=self.lean_update)


class _GroupCollection:
    """The compiled collection steps of a group's SMCs in one call
    (:func:`~sb3_smc.common.kernels.lstm_collection_steps`, :func:`~sb3_smc.common.kernels.gru_collection_steps`)
    where every SMC takes the compiled step with the same cell and shapes: the group's observations, episode starts
    and states are whole arrays, each SMC's weights and draws are stacked once per rollout; each SMC's step is the
    one :meth:`_Job.act` computes, bit for bit."""

    def __init__(self, group: EnvGroup, jobs: Sequence[_Job]) -> None:
        self.group, self.jobs = group, list(jobs)
        self.bounds = np.array([0, *(part.stop for part in group.slices)], dtype=np.int64)
        n, hidden = group.env.num_envs, jobs[0].model.policy.lstm_actor.hidden_size
        self.obs = np.asarray(group.reset_obs)
        self.starts = np.ones(n)  # learn's first step starts every episode
        self.h, self.c = np.zeros((n, hidden), dtype=np.float32), np.zeros((n, hidden), dtype=np.float32)
        self.exact = not jobs[0].lean_update
        self.gru = jobs[0].model.policy.gru_actor
        self.weights: tuple[np.ndarray, ...] = ()
        self.uniforms = np.zeros((0, n))
        self.members = np.zeros(0, dtype=np.int64)

    @classmethod
    def of(cls, group: EnvGroup, jobs: Sequence[_Job]) -> _GroupCollection | None:
        """The group's collection in one call, or ``None`` where an SMC takes another step (SB3's path) or the SMCs'
        networks differ in shape or cell."""
        if not all(job.lean for job in jobs) or len({job.model.policy.gru_actor for job in jobs}) > 1:
            return None
        shapes = {tuple(tuple(p.shape) for p in job.model.policy.parameters()) for job in jobs}
        return cls(group, jobs) if len(shapes) == 1 else None

    def _members(self, running: Sequence[_Job]) -> np.ndarray:
        return np.array([m for m, job in enumerate(self.jobs) if job in running], dtype=np.int64)

    def start_rollout(self, running: Sequence[_Job]) -> None:
        """Stack the running SMCs' weights and draws (each :meth:`_Job.start_rollout`'s)."""
        self.members = self._members(running)
        first = running[0]._weights
        self.weights = tuple(np.stack([np.asarray(job._weights[i]) if job in running else np.zeros_like(first[i])
                                       for job in self.jobs]) for i in range(len(first)))
        self.uniforms = np.zeros((running[0].model.n_steps, self.group.env.num_envs))
        for job in running:
            part = cast(SliceVecEnv, job.model.env.unwrapped)
            self.uniforms[:, part.start:part.stop] = job._uniforms

    def act(self, running: Sequence[_Job]) -> None:
        """Every running SMC's step at once; the actions go to the group's step, each SMC keeps its slice."""
        if len(running) != len(self.members):  # an SMC left the group: its environments get action 0
            self.members = self._members(running)
        pos = running[0].model.rollout_buffer.pos
        if self.gru:  # the cell state as the one-SMC step leaves it
            step = (*kernels.gru_collection_steps(self.obs, self.h, self.starts, self.uniforms[pos], self.bounds,
                                                  self.members, self.exact, *self.weights),
                    gru_cell_state(self.c, self.starts))
        else:
            step = kernels.lstm_collection_steps(self.obs, self.h, self.c, self.starts, self.uniforms[pos],
                                                 self.bounds, self.members, self.exact, *self.weights)
        self.group.actions[:] = step[0]
        for job in running:
            part = cast(SliceVecEnv, job.model.env.unwrapped)
            job._step = tuple(array[part.start:part.stop] for array in step)
        self.h, self.c = step[3], step[4]

    def observed(self) -> None:
        """After the group's step: its observations and episode starts are the next step's inputs."""
        result = self.group.step_result
        assert result is not None
        self.obs, self.starts = result.obs, result.dones.astype(np.float64)


def _env_key(spec: TrainingSpec) -> tuple[Any, ...]:
    """What the SMCs trained in one vector env must share: their task (resolved once for all of them), its
    environments' settings and the children they call."""
    task = spec.task
    return (task.env_id, task.split, task.kind, task.datasets, task.layout, repr(sorted(task.env_kwargs.items())),
            repr(spec.wrapper), spec.budget.env_steps, spec.children)


def train_smcs(specs: Sequence[TrainingSpec], *, children: Mapping[str, SMC] | None = None,
               tensorboard_log: str | None = None, log_every: int | None = 0, printer: Callable[[str], None] = print,
               stop_at_max_return: bool = True, lean_update: bool = False, checkpoints: str | Path | None = None,
               checkpoint_every: float = 300.0) -> list[SMC]:
    """Train the SMCs of ``specs`` together and return them in the same order, each the SMC
    :func:`~sb3_smc.learning.training.train_smc` gives for its spec (same weights, records and selection).

    Batchable specs (:func:`batchable`) with the same task, environment settings, children and steps per rollout
    train as one group, their environments stepped in one call (with children: when they are compiled leaves on a
    world where only the self moves); every other spec is trained by ``train_smc`` alone. ``children``: the SMCs
    the specs call, by name (an :class:`~sb3_smc.library.SMCLibrary`). ``tensorboard_log``, ``log_every``,
    ``printer``, ``stop_at_max_return`` and ``lean_update`` are ``train_smc``'s, for every SMC (with
    ``tensorboard_log``, each SMC's curves in ``<tensorboard_log>/<name>_<n>/``); with ``lean_update`` each SMC is
    the one ``train_smc(spec, lean_update=True)`` gives, and a spec whose model the lean update does not fit is
    refused before its group trains. With ``checkpoints`` (a folder), each group's training is saved there between
    two updates, at most every ``checkpoint_every`` seconds, and a later call with the same group resumes from it
    (:mod:`~sb3_smc.learning.group_checkpoint`): the same SMCs as without a break."""
    if checkpoint_every < 0:
        raise SMCError(f"checkpoint_every must be >= 0 seconds, got {checkpoint_every}")
    results: list[SMC | None] = [None] * len(specs)
    groups: dict[tuple[Any, ...], list[int]] = {}
    for i, spec in enumerate(specs):
        if not isinstance(spec, TrainingSpec):
            raise SMCError(f"train_smcs takes TrainingSpecs, got {type(spec).__name__}")
        if spec.budget.total_timesteps < 1:
            raise SMCError(f"SMC {spec.name!r}: total_timesteps must be >= 1, got {spec.budget.total_timesteps}")
        groups.setdefault(_env_key(spec) if batchable(spec) else (i,), []).append(i)
    for members in groups.values():
        chosen = [specs[i] for i in members]
        called = resolve_children(children or {}, chosen[0].children) if chosen[0].children else ()
        task = resolve_task(chosen[0].task, smc=chosen[0].name) if batchable(chosen[0]) else None
        if task is not None:  # the group's task, resolved once: its specs completed with it
            chosen = [resolved_spec(spec, task) for spec in chosen]
        for spec in chosen:
            if spec.task.kind is not None:
                check_model_settings(spec)  # a typo in a hyperparameter: a message before any environment is built
        sizes = [spec.budget.n_envs for spec in chosen]
        checkpoint = saved = None
        if checkpoints is not None and task is not None:
            settings = {"stop_at_max_return": stop_at_max_return, "lean_update": lean_update}
            checkpoint = GroupCheckpoint(checkpoints, chosen, called, every=checkpoint_every, settings=settings,
                                         printer=printer)
            saved = checkpoint.load()
        env = None if task is None or saved else native_smc_vec_env(task, sum(sizes), called, chosen[0].wrapper)
        if saved or env is not None:
            group = EnvGroup(env, sizes) if env is not None else None
            trained = _train_group(chosen, called, group, saved=saved, checkpoint=checkpoint,
                                   tensorboard_log=tensorboard_log, log_every=log_every, printer=printer,
                                   stop_at_max_return=stop_at_max_return, lean_update=lean_update)
        else:
            trained = [train_smc(spec, children=called, tensorboard_log=tensorboard_log, log_every=log_every,
                                 printer=printer, stop_at_max_return=stop_at_max_return, lean_update=lean_update)
                       for spec in chosen]
        for i, smc in zip(members, trained, strict=True):
            results[i] = smc
    return [smc for smc in results if smc is not None]


def _train_group(specs: Sequence[TrainingSpec], children: tuple[SMC, ...], group: EnvGroup | None, *,
                 saved: Any = None, checkpoint: GroupCheckpoint | None, tensorboard_log: str | None,
                 log_every: int | None, printer: Callable[[str], None], stop_at_max_return: bool,
                 lean_update: bool) -> list[SMC]:
    """Train SMCs on one task in one vector env (see the module's docstring), or go on from ``saved``, the state a
    ``checkpoint`` kept between two updates."""
    if saved:
        jobs, group, collection, running = saved
    else:
        assert group is not None
        jobs = []
        for spec, part in zip(specs, group.slices, strict=True):
            task = task_of(spec, group.env)
            venv = VecMonitor(part)
            venv.seed(spec.seed)
            jobs.append(_Job(spec, children, task, venv, tensorboard_log=tensorboard_log, log_every=log_every,
                             printer=printer, stop_at_max_return=stop_at_max_return, lean_update=lean_update))
        group.reset()
        for job in jobs:
            job.start()
        group.with_infos = not all(job.lean for job in jobs)
        collection = _GroupCollection.of(group, jobs)
        running = [job for job in jobs if job.running]
    n_steps = jobs[0].model.n_steps
    while running:
        for job in running:
            job.start_rollout()
        if collection is not None:
            collection.start_rollout(running)
        for _ in range(n_steps):
            if collection is None:  # each SMC's own step, its own time
                for job in running:
                    begin = time.perf_counter()
                    job.act()
                    job.seconds += time.perf_counter() - begin
            begin = time.perf_counter()
            if collection is not None:  # the group's step, shared as the environment step is
                collection.act(running)
            group.step()
            if collection is not None:
                collection.observed()
            share = (time.perf_counter() - begin) / len(running)
            still = []
            for job in running:
                begin = time.perf_counter()
                if job.observe():
                    still.append(job)
                job.seconds += time.perf_counter() - begin + share
            running = still
            if not running:
                break
        for job in running:
            begin = time.perf_counter()
            job.end_rollout()
            job.seconds += time.perf_counter() - begin
        running = [job for job in running if job.running]
        if checkpoint is not None and running and checkpoint.due():
            with ExitStack() as stack:
                for job in jobs:
                    stack.enter_context(job.lean_off())
                checkpoint.save((jobs, group, collection, running))
    smcs = [job.finish() for job in jobs]
    if checkpoint is not None:
        checkpoint.remove()
    return smcs
