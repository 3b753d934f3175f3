"""A task resolved once: what the env id of a :class:`~sb3_smc.records.TaskSpec` names, and how its environments are
built (:func:`resolve_task` -> :class:`ResolvedTask`).

The flow is *spec -> resolved task -> environments*: :func:`resolve_task` looks the id up in Gymnasium's registry
once (importing the module of a ``"module:Id-v0"`` id first, and taking the latest version of an id without one, as
``gym.make`` does) and checks the env kwargs; the :class:`ResolvedTask` knows where the task comes from
(:class:`TaskSource`: PixelWorld's entry point, another registered environment such as an
:class:`~sb3_smc.tasks.task.SMCTask`, or an id Gymnasium does not know), its kind, datasets and
:class:`~sb3_smc.core.layout.Layout`, whether PixelWorld's native vector env can host it, and builds its environments
(:meth:`ResolvedTask.make_env`, :meth:`ResolvedTask.make_vector_env`). :func:`~sb3_smc.learning.training.train_smc`,
:func:`~sb3_smc.learning.batched.train_smcs` and :func:`~sb3_smc.envs.factory.make_smc_env` resolve a task here and pass
the result down; :meth:`TaskSpec.resolved() <sb3_smc.records.TaskSpec.resolved>` fills a record's ``kind``, ``datasets``
and ``layout`` from it (the records themselves import no Gymnasium).

The kind and layout of a task that is not PixelWorld's are read from one instance of it
(:func:`~sb3_smc.tasks.task.describe_task`), and only when asked for: building the task's environments never needs them.
"""

from __future__ import annotations

import difflib
import enum
import importlib
import inspect
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, Protocol

import gymnasium as gym
from gymnasium.envs.registration import EnvSpec, find_highest_version, get_env_id, load_env_creator, parse_env_id

from pixelworld_env.envs.registration import ENTRY_POINT, VECTOR_ENTRY_POINT, WORLDS_VECTOR_ENTRY_POINT, make_env
from pixelworld_env.envs.vector import PixelWorldVectorEnv
from sb3_smc.core.layout import PIXELWORLD_LAYOUT, Layout
from sb3_smc.errors import SMCError, SMCTypeError
from sb3_smc.tasks.task import describe_task

__all__ = ["ResolvedTask", "TaskFields", "TaskSource", "check_env_kwargs", "is_pixelworld_id", "resolve_task"]


class TaskFields(Protocol):
    """What :func:`resolve_task` reads of a task: a :class:`~sb3_smc.records.TaskSpec`'s fields."""

    @property
    def env_id(self) -> str: ...

    @property
    def split(self) -> str: ...

    @property
    def kind(self) -> str | None: ...

    @property
    def datasets(self) -> tuple[str, ...]: ...

    @property
    def env_kwargs(self) -> Mapping[str, Any]: ...

    @property
    def layout(self) -> Layout | None: ...


class TaskSource(enum.Enum):
    """Where a task's environment comes from."""

    PIXELWORLD = "pixelworld"
    """Registered with PixelWorld's entry point (a ``PW-*`` id, or one made like them): a split, datasets, the kind
    from the catalog, the layout PixelWorld's."""
    REGISTERED = "registered"
    """Another registered environment: an :class:`~sb3_smc.tasks.task.SMCTask` (kind and layout read from one instance),
    or a bare environment (no kind: the wrapper refuses it)."""
    UNREGISTERED = "unregistered"
    """An id Gymnasium does not know: refused where an environment is to be built."""


@dataclass(frozen=True)
class ResolvedTask:
    """A task resolved by :func:`resolve_task`: its env id, split and checked env kwargs, Gymnasium's registration of
    the id (``None`` if there is none, ``problem`` then says why), and the kind, datasets and layout its spec gave
    (``None`` / empty: not given); the properties complete them."""

    env_id: str
    split: str
    env_kwargs: dict[str, Any]
    registration: EnvSpec | None = field(repr=False)
    problem: str = field(default="", repr=False)
    given_kind: str | None = field(default=None, repr=False)
    given_datasets: tuple[str, ...] = field(default=(), repr=False)
    given_layout: Layout | None = field(default=None, repr=False)

    @property
    def source(self) -> TaskSource:
        if self.registration is None:
            return TaskSource.UNREGISTERED
        return TaskSource.PIXELWORLD if self.registration.entry_point == ENTRY_POINT else TaskSource.REGISTERED

    @property
    def datasets(self) -> tuple[str, ...]:
        """The datasets the task samples from: the spec's, else the registration's (PixelWorld's ids)."""
        if self.given_datasets or self.registration is None:
            return self.given_datasets
        return tuple(self.registration.kwargs.get("datasets", ()))

    @property
    def native_vector(self) -> bool:
        """Whether PixelWorld's native vector env hosts the task (a flat SMC on it trains there): a ``PW-*`` id or
        one of :func:`pixelworld_env.register_worlds`, with PixelWorld's vector entry point, without
        ``aaai18_reset_bug`` or ``render_mode="human"``."""
        return (self.registration is not None
                and self.registration.vector_entry_point in (VECTOR_ENTRY_POINT, WORLDS_VECTOR_ENTRY_POINT)
                and not self.env_kwargs.get("aaai18_reset_bug") and self.env_kwargs.get("render_mode") != "human")

    @cached_property
    def _facts(self) -> tuple[str | None, Layout | None]:
        """The kind, and the layout as a :class:`~sb3_smc.records.TaskSpec` keeps it (``None``: PixelWorld's): the
        catalog's kind of the datasets, or, for a task without datasets whose kind or layout is not given, those of
        one instance of it."""
        kind, layout, datasets = self.given_kind, self.given_layout, self.datasets
        if kind is None and datasets:
            from pixelworld_env.datasets import catalog

            kinds = {catalog.dataset(name).kind for name in datasets}
            kind = kinds.pop() if len(kinds) == 1 else None
        elif not datasets and (kind is None or layout is None) and self.registration is not None:
            found = describe_task(self.env_id, self.env_kwargs)
            if found is not None:
                kind, task_layout = found
                layout = None if task_layout == PIXELWORLD_LAYOUT else task_layout
        return kind, layout

    @property
    def kind(self) -> str | None:
        """The task's kind (``None`` where not known: an unknown id, an environment that is not a task)."""
        return self._facts[0]

    @property
    def spec_layout(self) -> Layout | None:
        """The layout as :attr:`TaskSpec.layout <sb3_smc.records.TaskSpec.layout>` keeps it: ``None`` for
        PixelWorld's."""
        return self._facts[1]

    @property
    def layout(self) -> Layout:
        """The layout of the SMCs trained on the task (PixelWorld's unless the task says otherwise)."""
        return self.spec_layout if self.spec_layout is not None else PIXELWORLD_LAYOUT

    @property
    def spec_fields(self) -> dict[str, Any]:
        """The fields a :class:`~sb3_smc.records.TaskSpec` of this task is completed with: ``kind``, ``datasets``,
        ``layout``."""
        return {"kind": self.kind, "datasets": self.datasets, "layout": self.spec_layout}

    def check_known(self, smc: str) -> None:
        """:class:`SMCError` naming SMC ``smc`` if Gymnasium does not know the id (with Gymnasium's suggestion, and
        the ``PW-<name>-v0`` id when the id names a PixelWorld dataset or concept pool)."""
        if self.registration is not None:
            return
        from pixelworld_env.datasets import catalog

        named = self.env_id in catalog.dataset_names() or self.env_id in catalog.concept_pools()
        hint = f"; PixelWorld's {self.env_id!r} is the id 'PW-{self.env_id}-v0'" if named else ""
        raise SMCError(f"SMC {smc!r}: unknown environment id {self.env_id!r}: {self.problem}{hint}")

    def make_env(self, max_steps: int, *, smc: str, split: str | None = None,
                 env_kwargs: Mapping[str, Any] | None = None) -> gym.Env:
        """The task itself (no SMC actions): ``gym.make(env_id, max_steps=max_steps, **env_kwargs)``, with the split
        for a PixelWorld id.

        :param max_steps: the episode length in decisions.
        :param smc: the SMC the environment is for (named in the errors).
        :param split: another dataset split than the task's (PixelWorld ids, and registered tasks whose entry point
            takes ``split``, such as :func:`pixelworld_env.register_worlds`'; ignored for others). On another split
            than ``"train"`` a task's ``train_worlds`` is left out: only training worlds are ever cut.
        :param env_kwargs: extra keyword arguments for ``gym.make``, checked as the task's are.
        :return: the environment, Gymnasium's checker off.
        """
        self.check_known(smc)
        pixelworld = self.source is TaskSource.PIXELWORLD
        kwargs = {"disable_env_checker": True,
                  **_check_kwargs(self.env_id, {**self.env_kwargs, **_mapping(env_kwargs)}, pixelworld)}
        if pixelworld or (self.registration is not None and _takes(self.registration, "split", unreadable=False)):
            kwargs["split"] = split or self.split  # PixelWorld's ids, and a registered task that has splits
            if kwargs["split"] != "train":  # train_worlds cuts the training split only: a test has every test world
                kwargs.pop("train_worlds", None)
        try:
            return gym.make(self.env_id, max_steps=max_steps, **kwargs)
        except TypeError:
            if self.registration is None or _takes_max_steps(self.registration):  # the environment's own error
                raise
            raise SMCTypeError(f"SMC {smc!r}: sb3_smc makes its task with gym.make({self.env_id!r}, max_steps=...) "
                               f"(the episode length, WrapperSettings.max_steps), and the entry point of "
                               f"{self.env_id!r} takes no max_steps: register an entry point that takes it and passes "
                               "it on, e.g. entry_point=lambda max_steps=100: SMCTask(..., max_steps=max_steps)"
                               ) from None

    def make_vector_env(self, num_envs: int, max_steps: int) -> PixelWorldVectorEnv:
        """PixelWorld's native vector env of the task (:attr:`native_vector` must hold): ``num_envs`` environments
        of episodes of ``max_steps`` decisions, stepped in one compiled call.

        :param num_envs: how many environments.
        :param max_steps: the episode length in decisions.
        """
        if not self.native_vector:
            raise SMCError(f"{self.env_id}: PixelWorld's native vector env hosts PW-* ids without aaai18_reset_bug "
                           "or render_mode='human' only")
        vector = gym.make_vec(self.env_id, num_envs=num_envs, vectorization_mode="vector_entry_point",
                              split=self.split, max_steps=max_steps, **self.env_kwargs)
        if not isinstance(vector, PixelWorldVectorEnv):
            raise SMCError(f"{self.env_id}: its vector entry point gives a {type(vector).__name__}, not PixelWorld's "
                           "native vector env")
        return vector


def resolve_task(task: TaskFields, *, smc: str | None = None) -> ResolvedTask:
    """Resolve ``task`` once: its id looked up in Gymnasium's registry, its env kwargs checked.

    :param task: a :class:`~sb3_smc.records.TaskSpec` (or anything with its fields).
    :param smc: the SMC the task is resolved for, to train or run it: an id Gymnasium does not know is then refused
        naming it (without: it resolves to :attr:`TaskSource.UNREGISTERED`, kind unknown, as a record may name a task
        registered later).
    :return: the :class:`ResolvedTask`.
    :raises SMCError: an env kwarg the spec sets (``split``, ``max_steps``) or a PixelWorld environment does not
        take; an unknown id, with ``smc``.
    """
    registration, problem = _look_up(task.env_id)
    resolved = ResolvedTask(task.env_id, task.split, dict(task.env_kwargs), registration, problem, task.kind,
                            tuple(task.datasets), task.layout)
    _check_kwargs(task.env_id, resolved.env_kwargs, resolved.source is TaskSource.PIXELWORLD)
    if ("train_worlds" in resolved.env_kwargs and registration is not None
            and resolved.source is not TaskSource.PIXELWORLD and not _takes(registration, "train_worlds",
                                                                             unreadable=False)):
        raise SMCError(f"env_kwargs: train_worlds cuts a task's training worlds; {task.env_id} has none (its entry "
                       "point takes no train_worlds): PixelWorld ids and pixelworld_env.register_worlds' ids have them")
    if smc is not None:
        resolved.check_known(smc)
    return resolved


def _look_up(env_id: str) -> tuple[EnvSpec | None, str]:
    """Gymnasium's registration of ``env_id`` as ``gym.make`` finds it, or ``None`` and Gymnasium's message why
    there is none."""
    module, _, name = env_id.rpartition(":")
    if module:
        importlib.import_module(module)  # what gym.make does with a "module:Id-v0" id (registers the id)
    try:
        if name not in gym.registry:
            namespace, base, version = parse_env_id(name)
            latest = find_highest_version(namespace, base) if version is None else None
            if latest is not None:
                name = get_env_id(namespace, base, latest)
        return gym.spec(name), ""
    except gym.error.Error as err:
        return None, str(err)


def is_pixelworld_id(env_id: str) -> bool:
    """Whether ``env_id`` is registered with PixelWorld's entry point (a ``PW-*`` id or one made like them)."""
    registration, _ = _look_up(env_id)
    return registration is not None and registration.entry_point == ENTRY_POINT


def check_env_kwargs(env_id: str, kwargs: dict[str, Any]) -> dict[str, Any]:
    """``kwargs`` for ``gym.make(env_id, split=..., max_steps=..., **kwargs)``: :class:`SMCError` for ``split`` or
    ``max_steps`` (set by the spec or make_smc_env's arguments) and, for a PixelWorld id, for a name its
    environment does not take (the values are checked by the environment)."""
    return _check_kwargs(env_id, kwargs, is_pixelworld_id(env_id))


def _check_kwargs(env_id: str, kwargs: dict[str, Any], pixelworld: bool) -> dict[str, Any]:
    """:func:`check_env_kwargs` with the id's source known."""
    clash = sorted({"split", "max_steps"} & set(kwargs))
    if clash:
        raise SMCError(f"env_kwargs {clash}: the split is make_smc_env's split= (else the spec's task.split), "
                       "max_steps the wrapper settings' (wrapper=WrapperSettings(max_steps=...)); give them there")
    if not pixelworld:
        return kwargs  # not registered (refused where it is built), or a user's own environment: arguments unknown
    names = {*inspect.signature(gym.make).parameters, *inspect.signature(make_env).parameters}
    taken = sorted(names - {"id", "datasets", "kwargs", "split", "max_steps"})
    for key in kwargs:
        if key not in taken:
            close = difflib.get_close_matches(key, taken, n=1)
            raise SMCError(f"env_kwargs: {env_id} takes no argument {key!r} (it takes {taken})"
                           + (f"; did you mean {close[0]!r}?" if close else ""))
    return kwargs


def _mapping(env_kwargs: Any) -> dict[str, Any]:
    if env_kwargs is None:
        return {}
    if not isinstance(env_kwargs, Mapping) or not all(isinstance(key, str) for key in env_kwargs):
        raise SMCTypeError(f"env_kwargs must be a mapping of argument names to values, got {env_kwargs!r}")
    return dict(env_kwargs)


def _takes_max_steps(registration: EnvSpec) -> bool:
    """Whether the registered entry point takes a ``max_steps`` keyword (``True`` where its signature cannot be
    read)."""
    return _takes(registration, "max_steps", unreadable=True, any_keyword=True)


def _takes(registration: EnvSpec, keyword: str, *, unreadable: bool, any_keyword: bool = False) -> bool:
    """Whether the registered entry point takes ``keyword`` by name (``unreadable`` where its signature cannot be
    read; ``any_keyword``: a ``**kwargs`` counts too)."""
    entry = registration.entry_point
    creator = load_env_creator(entry) if isinstance(entry, str) else entry
    if not callable(creator):
        return unreadable
    try:
        parameters = inspect.signature(creator).parameters
    except (TypeError, ValueError):
        return unreadable
    taken = parameters.get(keyword)
    return (taken is not None and taken.kind is not inspect.Parameter.POSITIONAL_ONLY) or (any_keyword and any(
        p.kind is inspect.Parameter.VAR_KEYWORD for p in parameters.values()))
