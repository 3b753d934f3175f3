"""Train one SMC on a ``PW-*`` environment with sb3-contrib RecurrentPPO (default) or TRPO (docs/design.md, "The
learner").

:func:`train_smc` takes a :class:`~sb3_smc.records.TrainingSpec` (or builds one from its keyword arguments), builds
``n_envs`` copies of the SMC's environment (:func:`make_vec_env`: every SMC sees the same observation layout, the
one-hot window, the outcome vector of its children and its previous action; a flat SMC on a ``PW-*`` id steps them
in PixelWorld's native vector env, the same transitions), trains a paper-sized policy with the signal-bias
initialisation (:mod:`sb3_smc.learning.bias`), keeps the snapshot of the update with the highest mean training return
(ties -> earliest; docs/design.md, "Selection and test") and returns it as an :class:`~sb3_smc.smc.smc.SMC` whose policy
is a numpy copy of the selected actor, with its ``spec`` and :class:`~sb3_smc.records.TrainingRecord`.

Defaults (:data:`sb3_smc.core.hyperparameters.ALGORITHM_REGISTRY`, measured, see ``docs/training.md``): 16
environments x 125 steps = 2,000 steps per update, 200 updates (``DEFAULT_TIMESTEPS``), gamma 0.99, GAE lambda 1,
episodes of at most 100 decisions.

* ``RecurrentPPO`` (with :class:`~sb3_smc.common.recurrent.SequenceLstmPolicy` and
  :class:`~sb3_smc.common.recurrent.CompactRecurrentRolloutBuffer`: sb3-contrib's numbers, faster): one LSTM layer
  of 32 units for the actor (the paper's GRU-32 size) with the action layer directly on its output
  (``net_arch=[]``); a critic without memory, linear in the observation (``enable_critic_lstm=False``, like the
  paper's linear feature baseline); one 2,000-step minibatch, 4 epochs, learning rate 3e-3, clip 0.2.
* ``TRPO``: ``MlpPolicy`` with one hidden layer of 32 tanh units (actor and critic), KL step 0.01 (the paper's
  NPO step size). An MLP has no memory of its own; its memory is what the observation carries — the previous
  action and the outcome vector of the children — plus, optionally, the last ``frame_stack`` observations
  (:class:`~sb3_smc.smc.policies.FrameStackPolicy` replays the stacking when the SMC is called as a child).
"""

from __future__ import annotations

import contextlib
import dataclasses
import difflib
import inspect
import time
from collections.abc import Callable, Mapping, Sequence
from typing import Any, cast

import gymnasium as gym
import numpy as np
import torch
from sb3_contrib import RecurrentPPO
from stable_baselines3.common.logger import Logger
from stable_baselines3.common.vec_env import VecEnv

from sb3_smc.common.discounting import SemiMDPDiscount
from sb3_smc.common.recurrent import use_compact_buffer
from sb3_smc.common.recurrent.lean_update import LEAN_UPDATE_NEEDS, lean_update_applies, use_lean_update
from sb3_smc.core.hyperparameters import (
    ALGORITHM_REGISTRY,
    DEFAULT_ALGORITHM,
    DEFAULT_N_ENVS,
    DEFAULT_TIMESTEPS,
    constructor_arguments,
)
from sb3_smc.core.layout import PIXELWORLD_LAYOUT, Layout
from sb3_smc.envs.factory import make_smc_env
from sb3_smc.envs.hierarchical_vec_env import native_smc_vec_env
from sb3_smc.envs.vec_env import NativeSMCVecEnv, SMCVecEnv
from sb3_smc.envs.wrapper import HierarchicalSMCWrapper
from sb3_smc.errors import SMCError, SMCKeyError, SMCTypeError
from sb3_smc.learning.bias import apply_signal_bias
from sb3_smc.learning.callbacks import SMCTrainingCallback
from sb3_smc.records import TaskSpec, TrainingRecord, TrainingSpec, package_versions
from sb3_smc.smc.policies import FrameStackPolicy, policy_from_model
from sb3_smc.smc.smc import SMC, StepPolicy
from sb3_smc.tasks.resolved_task import ResolvedTask, resolve_task
from sb3_smc.tasks.task import MAX_RETURN

__all__ = ["check_model_settings", "make_vec_env", "resolve_children", "smc_spec", "train_smc", "untrained_smc"]


Children = Sequence[SMC] | tuple[Mapping[str, SMC], Sequence[str]] | Mapping[str, SMC] | None
"""What ``children=`` takes: SMCs, ``(library, [names])``, or a library (a mapping ``name -> SMC``) whose SMCs the
spec names."""


def resolve_children(children: Children, names: Sequence[str] | None = None) -> tuple[SMC, ...]:
    """The child SMCs: from ``None``, a sequence of SMCs, ``(library, [names])``, or a mapping ``name -> SMC``
    (an :class:`~sb3_smc.library.SMCLibrary`) looked up with ``names`` (a spec's children)."""
    if isinstance(children, Mapping):
        if names is None:
            raise SMCTypeError("children given as a mapping (a library) need the names to take from it")
        missing = [n for n in names if n not in children]
        if missing:
            raise SMCKeyError(f"children {missing} are not in the given library (it has {sorted(children)[:10]})")
        return tuple(children[n] for n in names)
    if children is None:
        resolved: tuple[SMC, ...] = ()
    elif (isinstance(children, tuple) and len(children) == 2 and not isinstance(children[0], SMC)
            and not isinstance(children[1], str | SMC)):
        library, chosen = children
        resolved = tuple(library[name] for name in chosen)
    else:
        resolved = tuple(cast("Sequence[SMC]", children))  # checked just below: a user may pass anything
    bad = [type(c).__name__ for c in resolved if not isinstance(c, SMC)]
    if bad:
        raise SMCTypeError(f"children must be SMCs, (library, [names]) or a library, got {bad}")
    if names is not None and tuple(c.name for c in resolved) != tuple(names):
        raise SMCError(f"the spec's children are {list(names)}, but the SMCs given are "
                       f"{[c.name for c in resolved]}")
    return resolved


class _SpacesOnly(gym.Env):
    """An environment with only the spaces of an SMC's: enough to build its model (never stepped)."""

    def __init__(self, size: int, n_actions: int) -> None:
        self.observation_space = gym.spaces.Box(-1.0, 1.0, shape=(size,), dtype=np.float32)
        self.action_space = gym.spaces.Discrete(n_actions)


def check_model_settings(spec: TrainingSpec, *, lean_update: bool = False) -> None:
    """Build the model ``spec`` trains, on an environment with the spaces of the SMC's (its task's kind must be
    known), without training it: ``ValueError`` naming a hyperparameter the algorithm does not take or what the
    algorithm or its policy refuses (a value out of range), or, with ``lean_update``, a model the lean update does
    not apply to (:func:`check_lean_update`), so a run can refuse it before anything is trained. The caller's torch
    random state is left as it was."""
    from stable_baselines3.common.vec_env import DummyVecEnv

    cls = ALGORITHM_REGISTRY[spec.algo].load_class()
    policy, settings = constructor_arguments(spec.hyperparameters)
    accepted = inspect.signature(cls).parameters
    for key in settings:
        if key not in accepted:
            close = difflib.get_close_matches(key, list(accepted), n=1)
            raise SMCError(f"hyperparameter {key!r} is not an argument of {spec.algo}"
                           + (f"; did you mean {close[0]!r}?" if close else ""))
    size, n_actions = spec.frame_stack * spec.observation_size, len(spec.action_names)
    venv = DummyVecEnv([lambda: _SpacesOnly(size, n_actions)] * spec.budget.n_envs)
    with torch.random.fork_rng(devices=[]):
        try:
            model = cls(policy, venv, n_steps=spec.budget.env_steps, device="cpu", verbose=0, **settings)
        except Exception as err:  # noqa: BLE001 - whatever the constructor refuses is the message
            raise SMCError(f"{spec.algo} refuses its hyperparameters: {type(err).__name__}: {err}") from None
    if lean_update:
        check_lean_update(spec, model)


def _returning(env: gym.Env) -> Callable[[], gym.Env]:
    """A thunk for SB3's vector envs, returning the env already built."""
    return lambda: env


def make_vec_env(spec: TrainingSpec, children: Sequence[SMC] = (), *, native: bool | None = None,
                 task: ResolvedTask | None = None) -> VecEnv:
    """``n_envs`` copies of the SMC's environment in a seeded, monitored SB3 ``VecEnv`` (``VecFrameStack`` on top
    when ``spec.frame_stack > 1``).

    On a task PixelWorld's native vector env hosts (:attr:`~sb3_smc.tasks.resolved_task.ResolvedTask.native_vector`),
    a flat SMC (no children) trains in :class:`~sb3_smc.envs.vec_env.FlatSMCVecEnv` over it and an SMC whose children
    are compiled leaves (:func:`~sb3_smc.envs.hierarchical_vec_env.hosts`; worlds where only the self moves) in
    :class:`~sb3_smc.envs.hierarchical_vec_env.HierarchicalSMCVecEnv`: one compiled call steps every environment,
    the children's calls included (:func:`~sb3_smc.envs.hierarchical_vec_env.native_smc_vec_env` chooses). Any
    other SMC trains in :class:`~sb3_smc.envs.vec_env.SMCVecEnv` over :func:`~sb3_smc.envs.factory.make_smc_env`
    (SMC calls in lockstep). They give the same transitions with the same
    seeds (tested).

    :param spec: the SMC's spec.
    :param children: the SMCs named by ``spec.children``, in that order.
    :param native: ``None`` chooses as above, ``False`` forces ``SMCVecEnv``, ``True`` refuses an SMC the native env
        cannot host.
    :param task: ``spec.task`` resolved (:func:`~sb3_smc.tasks.resolved_task.resolve_task`; resolved here when not
    given).
    """
    from stable_baselines3.common.vec_env import VecFrameStack, VecMonitor

    if task is None:
        task = resolve_task(spec.task, smc=spec.name)
    base: VecEnv | None = None
    if native is not False and (children or not spec.children):  # named children not given: refused below
        base = native_smc_vec_env(task, spec.budget.n_envs, children, spec.wrapper)
    if native and base is None:
        raise SMCError(f"SMC {spec.name!r}: the native vector env hosts SMCs on PixelWorld ids only, flat ones or "
                       "those whose children are compiled leaves (on worlds where only the self moves)")
    if base is None:
        envs = [make_smc_env(spec, children, task=task) for _ in range(spec.budget.n_envs)]
        base = SMCVecEnv([_returning(e) for e in envs])
    venv: VecEnv = VecMonitor(base)
    if spec.frame_stack > 1:
        venv = VecFrameStack(venv, spec.frame_stack)
    venv.seed(spec.seed)
    return venv


def resolved_spec(spec: TrainingSpec, task: ResolvedTask) -> TrainingSpec:
    """``spec`` with the kind, datasets and layout of its task as ``task`` (``spec.task`` resolved) has them."""
    return dataclasses.replace(spec, task=dataclasses.replace(spec.task, **task.spec_fields))


def train_smc(
    task: str | TrainingSpec,
    *,
    children: Children = None,
    tensorboard_log: str | None = None,
    log_every: int | None = None,
    callback: Any = None,
    printer: Callable[[str], None] = print,
    stop_at_max_return: bool = True,
    lean_update: bool = False,
    algo: str = DEFAULT_ALGORITHM,
    total_timesteps: int = DEFAULT_TIMESTEPS,
    seed: int = 0,
    include_primitives: bool = True,
    name: str | None = None,
    n_envs: int = DEFAULT_N_ENVS,
    signal_bias: bool = True,
    frame_stack: int = 1,
    max_steps: int = 100,
    count_primitive_steps: bool = False,
    call_step_cap: int = 100,
    env_kwargs: Mapping[str, Any] | None = None,
    rnn: str | None = None,
    discount: str = "decision",
    train_worlds: int | None = None,
    **hyperparams: Any,
) -> SMC:
    """Train an SMC and return the snapshot with the best mean training return.

    The spec's settings (``algo`` to ``discount`` and ``hyperparams``) build a :class:`~sb3_smc.records.TrainingSpec`
    (:meth:`TrainingSpec.create <sb3_smc.records.TrainingSpec.create>`) when ``task`` is an env id; with a spec,
    passing any of them is an error. The others are run options, not part of the spec.

    :param task: a :class:`~sb3_smc.records.TrainingSpec`, or the env id of the task (``PW-<dataset>-v0`` or any
        registered :class:`~sb3_smc.tasks.task.SMCTask` id).
    :param children: the SMCs to use as actions: a sequence of SMCs, ``(library, [names])``, or, with a spec, a
        library (any mapping name -> SMC) to look the spec's children up in.
    :param tensorboard_log: a folder for SB3's curves and those of
    :class:`~sb3_smc.learning.callbacks.SMCTrainingCallback`
        (run name: the SMC's name).
    :param log_every: a progress line through ``printer`` every that many updates, with the time left (0: quiet;
        ``None``: about ten lines in all, every ``ceil(updates / 10)`` updates).
    :param callback: an extra SB3 callback.
    :param printer: where progress lines go.
    :param stop_at_max_return: end training once an update's mean training return is
        :data:`~sb3_smc.tasks.task.MAX_RETURN` (every episode a clean success): no later update can be selected then, so
        the SMC has the weights the whole budget would select, and its record ends there (``False``: run the whole
        budget, for complete learning curves). A task whose rewards may exceed it
        (:func:`~sb3_smc.tasks.task.returns_bounded`) runs its whole budget.
    :param lean_update: update ``RecurrentPPO``'s LSTM policy with
        :func:`~sb3_smc.common.recurrent.lean_update.lean_train` (the compiled recurrence): the same update up to
        float rounding, faster, shown statistically equal but not bit-identical (``docs/training.md``, "The lean
        update"); ``SMCError`` for a model it does not apply to (another algorithm or cell, a critic LSTM, several
        minibatches per epoch). Off by default: results stay bit-identical.
    :param algo: a name of :data:`~sb3_smc.core.hyperparameters.ALGORITHM_REGISTRY`: ``"RecurrentPPO"`` (LSTM 32),
        ``"TRPO"`` (MLP 32), ``"PPO"`` (MLP 32), ``"RecurrentTRPO"`` (:mod:`sb3_smc.recurrent_trpo`) or a learner
        of your own (:func:`~sb3_smc.core.hyperparameters.register_algorithm`).
    :param total_timesteps: the budget in decisions, at least 1 (:func:`untrained_smc` gives the SMC before
        training).
    :param seed: the training seed (environments, network, sampling).
    :param include_primitives: ``False`` drops the moves (the "noprim" ablation); signals and SMC calls stay.
    :param name: the SMC's name (default: the task's).
    :param n_envs: environments collected in parallel; ``n_steps`` defaults to ``2000 // n_envs``.
    :param signal_bias: the paper's initial action distribution (on by default; without it episodes end after a few
        random signals and little is learned).
    :param frame_stack: stack the last k observations (meant for TRPO's memoryless MLP).
    :param max_steps: the episode's length in decisions (moves where calls cost their moves).
    :param count_primitive_steps: an SMC call costs the episode the moves it made instead of one step.
    :param call_step_cap: the moves one SMC call may make, its nested calls' included, before it is cut off.
    :param env_kwargs: extra keyword arguments for ``gym.make``.
    :param rnn: ``"gru"`` gives the recurrent algorithms a GRU (:class:`~sb3_smc.common.recurrent.SequenceGruPolicy`,
        the paper's cell) instead of the default LSTM (``"lstm"``).
    :param discount: ``"semi-mdp"`` discounts a decision by ``gamma ** k`` for its k primitive steps (an SMC call of
        40 moves by ``gamma ** 40``) instead of ``gamma`` per decision (``"decision"``;
        :mod:`sb3_smc.common.discounting`).
    :param train_worlds: train on the first ``N`` worlds of the training split only (PixelWorld ids: nested and
        stratified, :func:`pixelworld_env.datasets.loading.training_order`); recorded in the spec's
        ``task.env_kwargs``; the test split is never cut.
    :param hyperparams: override the algorithm's defaults (``policy_kwargs`` key by key).
    :return: the SMC: its ``policy`` a numpy copy of the selected snapshot's actor, ``model`` the SB3 model with the
        selected weights loaded, ``spec`` the (resolved) spec and ``record`` the :class:`TrainingRecord`.
    """
    given = locals()
    settings = {key: given[key] for key in _KEYWORD_DEFAULTS}  # the spec settings among the keyword arguments
    spec, kids, resolved = _spec_and_children(task, children, settings, hyperparams)
    if spec.budget.total_timesteps < 1:
        raise SMCError(f"SMC {spec.name!r}: total_timesteps must be >= 1, got {spec.budget.total_timesteps} "
                       "(nothing would be trained); untrained_smc(...) builds an SMC with its initial policy on "
                       "purpose")
    return _train(spec, kids, resolved, tensorboard_log=tensorboard_log, log_every=log_every, callback=callback,
                  printer=printer, stop_at_max_return=stop_at_max_return, lean_update=lean_update)


def untrained_smc(task: str | TrainingSpec, *, children: Children = None, **settings: Any) -> SMC:
    """The SMC :func:`train_smc` starts from: the model as built (signal bias set), no update run. ``task`` and
    ``children`` as for ``train_smc``, with its keyword settings and hyperparameters (``total_timesteps`` aside: the
    returned spec's budget is 0 steps); for tests, benchmarks and baselines that need a model, not a trained
    one."""
    if "total_timesteps" in settings:
        raise SMCTypeError("untrained_smc trains nothing: it takes no total_timesteps")
    known = {key: settings.pop(key) for key in list(settings) if key in _KEYWORD_DEFAULTS}
    if isinstance(task, TrainingSpec):
        task = dataclasses.replace(task, budget=dataclasses.replace(task.budget, total_timesteps=0))
    else:
        known["total_timesteps"] = 0
    spec, kids, resolved = _spec_and_children(task, children, {**_KEYWORD_DEFAULTS, **known}, settings)
    return _train(spec, kids, resolved, tensorboard_log=None, log_every=0, callback=None, printer=print,
                  stop_at_max_return=False)


def smc_spec(task: str | TrainingSpec, *, children: Children = None, **settings: Any) -> tuple[TrainingSpec,
                                                                                             tuple[SMC, ...]]:
    """The spec :func:`train_smc` would train for these arguments (its task resolved) and the child SMCs it names:
    for :func:`~sb3_smc.learning.batched.train_smcs`, which trains many such specs together, each as ``train_smc``
    would. ``settings``: ``train_smc``'s spec settings and hyperparameters (not its run options)."""
    runs = sorted(set(settings) & set(_RUN_OPTIONS))
    if runs:
        raise SMCTypeError(f"smc_spec takes the spec's settings, not the run options {runs}")
    known = {key: settings.pop(key) for key in list(settings) if key in _KEYWORD_DEFAULTS}
    spec, kids, _ = _spec_and_children(task, children, {**_KEYWORD_DEFAULTS, **known}, settings)
    return spec, kids


def _spec_and_children(task: str | TrainingSpec, children: Children, settings: dict[str, Any],
                       hyperparams: dict[str, Any]) -> tuple[TrainingSpec, tuple[SMC, ...], ResolvedTask]:
    """The spec of :func:`train_smc`'s arguments (its task resolved: kind, datasets and layout filled in), the child
    SMCs it names, and its task resolved, once (:func:`~sb3_smc.tasks.resolved_task.resolve_task`: an unknown id or a
    bad env kwarg is refused here, before any work)."""
    if isinstance(task, TrainingSpec):
        given = {k: v for k, v in settings.items() if v != _KEYWORD_DEFAULTS[k]}
        if given or hyperparams:
            raise SMCTypeError(f"train_smc got a TrainingSpec and the settings {sorted({*given, *hyperparams})}; "
                               "put them in the spec (dataclasses.replace) instead")
        spec, kids = task, resolve_children(children, task.children)
    elif isinstance(task, str):
        kids = resolve_children(children)
        split, env_kwargs = hyperparams.pop("split", "train"), settings.pop("env_kwargs")  # split: create's keyword
        spec = TrainingSpec.create(TaskSpec(task, split=split, env_kwargs=dict(env_kwargs or {})),
                                   children=[c.name for c in kids], **settings, **hyperparams)
    else:
        raise SMCTypeError(f"train_smc needs an env id or a TrainingSpec, got {type(task).__name__}")
    resolved = resolve_task(spec.task, smc=spec.name)
    return resolved_spec(spec, resolved), kids, resolved


_RUN_OPTIONS = ("children", "tensorboard_log", "log_every", "callback", "printer", "stop_at_max_return",
                "lean_update")
_KEYWORD_DEFAULTS = {name: parameter.default for name, parameter in inspect.signature(train_smc).parameters.items()
                     if parameter.kind is inspect.Parameter.KEYWORD_ONLY and name not in _RUN_OPTIONS}
"""The spec settings of :func:`train_smc` and their defaults (its keyword arguments but the run options)."""


def _train(spec: TrainingSpec, children: tuple[SMC, ...], resolved: ResolvedTask, *, tensorboard_log: str | None,
           log_every: int | None, callback: Any, printer: Callable[[str], None], stop_at_max_return: bool,
           lean_update: bool = False) -> SMC:
    if spec.task.kind is not None:
        check_model_settings(spec)  # a typo in a hyperparameter: a message before any environment is built
    venv = make_vec_env(spec, children, task=resolved)
    task = task_of(spec, venv.unwrapped)  # the NativeSMCVecEnv or SMCVecEnv under the monitor
    model, initial = build_model(spec, venv, task, tensorboard_log=tensorboard_log)
    if lean_update:
        check_lean_update(spec, model)
    stats, callbacks = training_callbacks(spec, task, log_every=log_every, printer=printer,
                                          stop_at_max_return=stop_at_max_return, callback=callback)
    start = time.perf_counter()
    with use_lean_update(model) if lean_update else contextlib.nullcontext():
        model.learn(total_timesteps=spec.budget.total_timesteps, callback=callbacks, tb_log_name=spec.name,
                    progress_bar=False)
    wall_time = time.perf_counter() - start
    stats.on_training_end()  # no-op when SB3 already called it; makes the totals final either way
    return finished_smc(spec, children, model, stats, task, initial, wall_time, lean_update=lean_update)


def check_lean_update(spec: TrainingSpec, model: Any) -> None:
    """``SMCError`` unless the lean update (:mod:`~sb3_smc.common.recurrent.lean_update`) computes ``model``'s
    update."""
    if not lean_update_applies(model):
        raise SMCError(f"SMC {spec.name!r}: lean_update needs {LEAN_UPDATE_NEEDS}")


@dataclasses.dataclass(frozen=True)
class TaskFacts:
    """What training reads from an SMC's environment: its task kind, action names, layout, and whether its
    returns are bounded by :data:`~sb3_smc.tasks.task.MAX_RETURN` (the early stop applies)."""

    kind: str
    action_names: tuple[str, ...]
    layout: Layout
    bounded: bool


def task_of(spec: TrainingSpec, under: VecEnv) -> TaskFacts:
    """The :class:`TaskFacts` of the environments ``spec`` trains in (``under``: the :class:`NativeSMCVecEnv` or
    :class:`SMCVecEnv` under the monitor), read from them; ``SMCError`` where they are not the task the spec (its
    task resolved, :func:`resolved_spec`) says."""
    if isinstance(under, NativeSMCVecEnv):  # PixelWorld's compiled vector env: its own rewards
        kind, action_names, layout, bounded = under.kind, under.action_names, PIXELWORLD_LAYOUT, True
    else:
        wrappers = [cast(HierarchicalSMCWrapper, env) for env in cast(SMCVecEnv, under).envs]
        wrapper = wrappers[0]
        kind, action_names, layout = wrapper.base.kind, wrapper.action_names, wrapper.layout
        bounded = all(w.returns_bounded for w in wrappers)
    if spec.task.smc_layout != layout:
        raise SMCError(f"SMC {spec.name!r}: the spec says a {spec.task.kind} task on {spec.task.smc_layout}, but "
                       f"{spec.task.env_id} is a {kind} task on {layout}")
    if spec.task.kind != kind:
        raise SMCError(f"SMC {spec.name!r}: the spec says a {spec.task.kind} task, but {spec.task.env_id} is a "
                       f"{kind} task")
    return TaskFacts(kind, tuple(action_names), layout, bounded)


def build_model(spec: TrainingSpec, venv: VecEnv, task: TaskFacts, *, tensorboard_log: str | None = None
                ) -> tuple[Any, Any]:
    """The SB3 model ``spec`` trains in ``venv`` (seeded, on the CPU, the compact buffer for ``RecurrentPPO``, the
    signal bias set) and the initial action probabilities the bias gave (``None`` without it)."""
    policy_class, settings = constructor_arguments(spec.hyperparameters)
    algorithm_class = ALGORITHM_REGISTRY[spec.algo].load_class()
    model = algorithm_class(policy_class, venv, n_steps=spec.budget.env_steps, seed=spec.seed, device="cpu",
                            tensorboard_log=tensorboard_log, verbose=0, **settings)
    if tensorboard_log is None:  # SB3's default logger would create an empty /tmp/SB3-<date> folder per run
        model.set_logger(Logger(folder=None, output_formats=[]))
    if isinstance(model, RecurrentPPO):
        use_compact_buffer(model)
    initial = (apply_signal_bias(model, task.action_names, task.layout.primitives, **spec.signal_bias.weights)
               if spec.signal_bias.enabled else None)
    return model, initial


def training_callbacks(spec: TrainingSpec, task: TaskFacts, *, log_every: int | None,
                       printer: Callable[[str], None], stop_at_max_return: bool, callback: Any = None
                       ) -> tuple[SMCTrainingCallback, Any]:
    """The :class:`SMCTrainingCallback` of a training and the callback to give ``learn`` (it, the semi-MDP
    discounting where the spec asks for it, and the caller's ``callback``)."""
    from stable_baselines3.common.callbacks import BaseCallback, CallbackList

    total_updates = spec.budget.updates
    if log_every is None:
        log_every = -(-total_updates // 10)
    stats = SMCTrainingCallback(kind=task.kind, children=spec.children, total_updates=total_updates,
                                log_every=log_every, name=spec.name, printer=printer,
                                stop_at=MAX_RETURN if stop_at_max_return and task.bounded else None)
    parts: list[BaseCallback] = [stats]
    if spec.wrapper.discount == "semi-mdp":
        parts.append(SemiMDPDiscount())
    if callback is not None:
        parts.append(callback)
    return stats, CallbackList(parts) if len(parts) > 1 else stats


def finished_smc(spec: TrainingSpec, children: tuple[SMC, ...], model: Any, stats: SMCTrainingCallback,
                 task: TaskFacts, initial: Any, wall_time: float, *, lean_update: bool = False) -> SMC:
    """The trained SMC: the selected snapshot loaded into ``model``, its step policy and its record (which says
    whether the updates were the lean ones)."""
    best = stats.best
    if best.state is not None:
        model.policy.load_state_dict(best.state)
    policy: StepPolicy = policy_from_model(model)
    if spec.frame_stack > 1:
        policy = FrameStackPolicy(policy, spec.frame_stack, spec.observation_size)

    record = TrainingRecord(
        training_returns=tuple(best.returns),
        success_rates=tuple(row["smc/success_rate"] for row in stats.history),
        selected_update=best.best_update,
        selected_return=best.best_return if best.best_update is not None else None,
        total_timesteps=int(model.num_timesteps),
        primitive_steps=stats.total_primitive_steps,
        wall_time_s=wall_time,
        action_names=task.action_names,
        initial_action_probabilities=None if initial is None else tuple(float(p) for p in np.asarray(initial)),
        torch_threads=torch.get_num_threads(),
        versions=package_versions(),
        lean_update=lean_update,
    )
    return SMC.from_spec(spec, policy, children, model=model, record=record)
