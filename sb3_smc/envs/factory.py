"""The one environment factory: (training spec, children) -> the wrapped environment the SMC sees.

Training (:func:`sb3_smc.train_smc`), evaluation (:func:`sb3_smc.evaluate`), the library
(:meth:`sb3_smc.SMCLibrary.env_for`) and the rl_zoo3 wrapper entry (:func:`sb3_smc.zoo.smc_env`) all build the
SMC's environment here, so the observation layout, action list and wrapper settings cannot drift apart. The task
under the wrapper is built by the spec's task resolved (:class:`~sb3_smc.tasks.resolved_task.ResolvedTask`, which also
owns :func:`is_pixelworld_id` and :func:`check_env_kwargs`, kept importable from here).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from typing import Any

import gymnasium as gym

from pixelworld_env.envs.env import PixelWorldEnv  # pixelworld_env registers the PW-* ids on import
from sb3_smc.envs.wrapper import HierarchicalSMCWrapper
from sb3_smc.errors import SMCError, SMCTypeError
from sb3_smc.records import TaskSpec, TrainingSpec, WrapperSettings
from sb3_smc.smc.smc import SMC
from sb3_smc.tasks.resolved_task import ResolvedTask, check_env_kwargs, is_pixelworld_id, resolve_task
from sb3_smc.tasks.task import TaskEnv, task_layer

__all__ = ["check_env_kwargs", "is_pixelworld_id", "make_smc_env", "pixelworld_base", "spec_for_smc", "task_base",
           "wrap_with_smcs"]


def task_base(env: gym.Env) -> TaskEnv:
    """The task under ``env`` that SMCs act on (a :class:`~pixelworld_env.envs.env.PixelWorldEnv` or an
    :class:`~sb3_smc.tasks.task.SMCTask`, :func:`~sb3_smc.tasks.task.task_layer`); ``TypeError`` if there is none,
    ``ValueError`` if ``env`` already has SMC actions (a :class:`HierarchicalSMCWrapper` layer)."""
    base = task_layer(env)
    layer: Any = env
    while layer is not base:
        if isinstance(layer, HierarchicalSMCWrapper):
            raise SMCError("the environment is already wrapped with SMC actions (HierarchicalSMCWrapper); "
                           "wrap the task itself")
        layer = layer.env
    return base


def pixelworld_base(env: gym.Env) -> PixelWorldEnv:
    """:func:`task_base`, which must be a :class:`~pixelworld_env.envs.env.PixelWorldEnv` (``TypeError`` otherwise)."""
    base = task_base(env)
    if not isinstance(base, PixelWorldEnv):
        raise SMCTypeError(f"SMCs act on PixelWorld environments here; got {type(env.unwrapped).__name__}")
    return base


def make_smc_env(spec: TrainingSpec, children: Sequence[SMC] = (), *, env: gym.Env | None = None,
                 env_id: str | None = None, split: str | None = None, wrapper: WrapperSettings | None = None,
                 env_kwargs: Mapping[str, Any] | None = None, record_cells: bool = False,
                 task: ResolvedTask | None = None) -> HierarchicalSMCWrapper:
    """The environment SMC ``spec`` sees: its task inside :class:`HierarchicalSMCWrapper` with ``children``.

    The task is ``gym.make(env_id or spec.task.env_id, max_steps=wrapper.max_steps, **spec.task.env_kwargs,
    **env_kwargs)``, with ``split=split or spec.task.split`` for a PixelWorld id, built by the task resolved
    (:meth:`ResolvedTask.make_env <sb3_smc.tasks.resolved_task.ResolvedTask.make_env>`).

    :param spec: the SMC's spec.
    :param children: the SMCs named by ``spec.children``, in that order.
    :param env: the task itself, instead of making it (a task without SMC actions).
    :param env_id: another task than the spec's (the id of a non-PixelWorld task, an
        :class:`~sb3_smc.tasks.task.SMCTask`, must take ``max_steps``).
    :param split: another dataset split than the spec's (PixelWorld ids).
    :param wrapper: replaces ``spec.wrapper`` (e.g. another ``call_step_cap``).
    :param env_kwargs: extra keyword arguments for ``gym.make``.
    :param record_cells: the wrapper reports the self's cells after every move (for trajectory pictures).
    :param task: ``spec.task`` resolved (:func:`~sb3_smc.tasks.resolved_task.resolve_task`), as training passes it to
        build its environments on one look-up of the id; resolved here when not given or when ``env_id`` names
        another task.
    """
    children = tuple(children)
    names = tuple(child.name for child in children)
    if names != spec.children:
        raise SMCError(f"SMC {spec.name!r} calls the children {list(spec.children)} (in that order), but was given "
                       f"{list(names)}")
    settings = wrapper or spec.wrapper
    if env is None:
        if task is None or env_id not in (None, task.env_id):
            named = spec.task if env_id in (None, spec.task.env_id) else TaskSpec(
                env_id, split=spec.task.split, env_kwargs=spec.task.env_kwargs)
            task = resolve_task(named, smc=spec.name)
        env = task.make_env(settings.max_steps, smc=spec.name, split=split, env_kwargs=env_kwargs)
    elif env_id is not None or split is not None or env_kwargs or task is not None:
        raise SMCError("make_smc_env: give either env, or env_id / split / env_kwargs / task to build one, not both")
    else:
        task_base(env)
    return wrap_with_smcs(env, children, settings, record_cells=record_cells)


def wrap_with_smcs(env: gym.Env, smcs: Sequence[SMC], settings: WrapperSettings, *,
                   record_cells: bool = False) -> HierarchicalSMCWrapper:
    """``env`` with ``smcs`` as actions, as ``settings`` say (the one place the wrapper is built from settings).

    :func:`make_smc_env` builds an SMC's own environment through it; on its own it serves a new higher-level policy
    whose spec does not exist yet (:meth:`sb3_smc.SMCLibrary.wrap`, the rl_zoo3 entry).
    """
    return HierarchicalSMCWrapper(env, tuple(smcs), include_primitives=settings.include_primitives,
                                  count_primitive_steps=settings.count_primitive_steps,
                                  call_step_cap=settings.call_step_cap, record_cells=record_cells)


def spec_for_smc(smc: SMC, env_id: str) -> TrainingSpec:
    """``smc.spec``, or for an SMC without one (scripted, imported) the default settings on ``env_id``."""
    if smc.spec is not None:
        return smc.spec
    return TrainingSpec(
        name=smc.name, task=TaskSpec(env_id, kind=smc.kind),
        wrapper=dataclasses.replace(WrapperSettings(), include_primitives=smc.include_primitives),
        children=tuple(child.name for child in smc.children))

