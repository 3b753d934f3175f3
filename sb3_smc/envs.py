"""The one environment factory: (training spec, children) -> the wrapped environment the SMC sees.

Training (:func:`sb3_smc.train_smc`), evaluation (:func:`sb3_smc.evaluate`), the library
(:meth:`sb3_smc.SMCLibrary.env_for`) and the rl_zoo3 wrapper entry (:func:`sb3_smc.zoo.smc_env`) all build the
SMC's environment here, so the observation layout, action list and wrapper settings cannot drift apart.
"""

from __future__ import annotations

import dataclasses
import difflib
import inspect
from collections.abc import Mapping, Sequence
from typing import Any

import gymnasium as gym
from gymnasium.envs.registration import load_env_creator

from pixelworld_env.envs.env import PixelWorldEnv  # pixelworld_env registers the PW-* ids on import
from pixelworld_env.envs.registration import make_env
from sb3_smc.errors import SMCError, SMCTypeError
from sb3_smc.records import TaskSpec, TrainingSpec, WrapperSettings
from sb3_smc.smc import SMC
from sb3_smc.tasks import TaskEnv, task_layer
from sb3_smc.wrapper import HierarchicalSMCWrapper

__all__ = ["check_env_kwargs", "is_pixelworld_id", "make_smc_env", "pixelworld_base", "spec_for_smc", "task_base",
           "wrap_with_smcs"]


def task_base(env: gym.Env) -> TaskEnv:
    """The task under ``env`` that SMCs act on (a :class:`~pixelworld_env.envs.env.PixelWorldEnv` or an
    :class:`~sb3_smc.tasks.SMCTask`, :func:`~sb3_smc.tasks.task_layer`); ``TypeError`` if there is none, ``ValueError``
    if ``env`` already has SMC actions (a :class:`HierarchicalSMCWrapper` layer)."""
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
                 env_kwargs: Mapping[str, Any] | None = None, record_cells: bool = False) -> HierarchicalSMCWrapper:
    """The environment SMC ``spec`` sees: its task inside :class:`HierarchicalSMCWrapper` with ``children``.

    The task is ``gym.make(env_id or spec.task.env_id, max_steps=wrapper.max_steps, **spec.task.env_kwargs,
    **env_kwargs)``, with ``split=split or spec.task.split`` for a PixelWorld id.

    :param spec: the SMC's spec.
    :param children: the SMCs named by ``spec.children``, in that order.
    :param env: the task itself, instead of making it (a task without SMC actions).
    :param env_id: another task than the spec's (the id of a non-PixelWorld task, an
        :class:`~sb3_smc.tasks.SMCTask`, must take ``max_steps``).
    :param split: another dataset split than the spec's (PixelWorld ids).
    :param wrapper: replaces ``spec.wrapper`` (e.g. another ``call_step_cap``).
    :param env_kwargs: extra keyword arguments for ``gym.make``.
    :param record_cells: the wrapper reports the self's cells after every move (for trajectory pictures).
    """
    children = tuple(children)
    names = tuple(child.name for child in children)
    if names != spec.children:
        raise SMCError(f"SMC {spec.name!r} calls the children {list(spec.children)} (in that order), but was given "
                       f"{list(names)}")
    settings = wrapper or spec.wrapper
    if env is None:
        env_id = env_id or spec.task.env_id
        kwargs = {"disable_env_checker": True, **check_env_kwargs(env_id, {**spec.task.env_kwargs,
                                                                           **_mapping(env_kwargs)})}
        if is_pixelworld_id(env_id):
            kwargs["split"] = split or spec.task.split
        env = _make(env_id, spec.name, max_steps=settings.max_steps, **kwargs)
    elif env_id is not None or split is not None or env_kwargs:
        raise SMCError("make_smc_env: give either env, or env_id / split / env_kwargs to build one, not both")
    else:
        task_base(env)
    return wrap_with_smcs(env, children, settings, record_cells=record_cells)


def _make(env_id: str, name: str, **kwargs: Any) -> gym.Env:
    """``gym.make(env_id, **kwargs)``; an id Gymnasium does not know is an :class:`SMCError` naming the SMC, with
    Gymnasium's suggestion, and the ``PW-<name>-v0`` id when ``env_id`` names a PixelWorld dataset or concept pool;
    an entry point that takes no ``max_steps`` an :class:`SMCTypeError` saying that it must."""
    try:
        return gym.make(env_id, **kwargs)
    except TypeError:
        if _takes_max_steps(env_id):  # the error is its environment's own
            raise
        raise SMCTypeError(f"SMC {name!r}: sb3_smc makes its task with gym.make({env_id!r}, max_steps=...) (the "
                           f"episode length, WrapperSettings.max_steps), and the entry point of {env_id!r} takes no "
                           "max_steps: register an entry point that takes it and passes it on, e.g. "
                           "entry_point=lambda max_steps=100: SMCTask(..., max_steps=max_steps)") from None
    except gym.error.Error as err:
        if _registered(env_id):  # the error is its environment's own
            raise
        from pixelworld_env.datasets import catalog

        named = env_id in catalog.dataset_names() or env_id in catalog.concept_pools()
        hint = f"; PixelWorld's {env_id!r} is the id 'PW-{env_id}-v0'" if named else ""
        raise SMCError(f"SMC {name!r}: unknown environment id {env_id!r}: {err}{hint}") from None


def _takes_max_steps(env_id: str) -> bool:
    """Whether the entry point registered as ``env_id`` takes a ``max_steps`` keyword (``True`` where its signature
    cannot be read)."""
    entry = gym.spec(env_id.rsplit(":", 1)[-1]).entry_point
    creator = load_env_creator(entry) if isinstance(entry, str) else entry
    if not callable(creator):
        return True
    try:
        parameters = inspect.signature(creator).parameters
    except (TypeError, ValueError):
        return True
    taken = parameters.get("max_steps")
    return (taken is not None and taken.kind is not inspect.Parameter.POSITIONAL_ONLY) or any(
        p.kind is inspect.Parameter.VAR_KEYWORD for p in parameters.values())


def _registered(env_id: str) -> bool:
    """Whether Gymnasium knows ``env_id`` (after ``gym.make`` imported the module of a ``"module:Id-v0"`` id)."""
    try:
        gym.spec(env_id.rsplit(":", 1)[-1])
    except gym.error.Error:
        return False
    return True


def _mapping(env_kwargs: Any) -> dict[str, Any]:
    if env_kwargs is None:
        return {}
    if not isinstance(env_kwargs, Mapping) or not all(isinstance(key, str) for key in env_kwargs):
        raise SMCTypeError(f"env_kwargs must be a mapping of argument names to values, got {env_kwargs!r}")
    return dict(env_kwargs)


def is_pixelworld_id(env_id: str) -> bool:
    """Whether ``env_id`` is registered with PixelWorld's entry point (a ``PW-*`` id or one made like them)."""
    try:
        entry = gym.spec(env_id).entry_point
    except gym.error.Error:
        return False
    return entry == f"{make_env.__module__}:{make_env.__name__}"


def check_env_kwargs(env_id: str, kwargs: dict[str, Any]) -> dict[str, Any]:
    """``kwargs`` for ``gym.make(env_id, split=..., max_steps=..., **kwargs)``: :class:`SMCError` for ``split`` or
    ``max_steps`` (set by the spec or make_smc_env's arguments) and, for a PixelWorld id, for a name its
    environment does not take (the values are checked by the environment)."""
    clash = sorted({"split", "max_steps"} & set(kwargs))
    if clash:
        raise SMCError(f"env_kwargs {clash}: the split is make_smc_env's split= (else the spec's task.split), "
                       "max_steps the wrapper settings' (wrapper=WrapperSettings(max_steps=...)); give them there")
    if not is_pixelworld_id(env_id):
        return kwargs  # not registered (gym.make says so), or a user's own environment: its arguments are not known
    names = {*inspect.signature(gym.make).parameters, *inspect.signature(make_env).parameters}
    taken = sorted(names - {"id", "datasets", "kwargs", "split", "max_steps"})
    for key in kwargs:
        if key not in taken:
            close = difflib.get_close_matches(key, taken, n=1)
            raise SMCError(f"env_kwargs: {env_id} takes no argument {key!r} (it takes {taken})"
                           + (f"; did you mean {close[0]!r}?" if close else ""))
    return kwargs


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

