"""What to train: :class:`TrainingSpec` and its parts (:class:`TaskSpec`, :class:`WrapperSettings`,
:class:`Budget`, :class:`SignalBias`)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, ClassVar

from sb3_smc.core.hyperparameters import (
    ALGORITHM_REGISTRY,
    DEFAULT_ALGORITHM,
    DEFAULT_N_ENVS,
    DEFAULT_TIMESTEPS,
    MAX_N_ENVS,
    MAX_STEPS_PER_UPDATE,
    MAX_TIMESTEPS,
    STEPS_PER_UPDATE,
    resolve_hyperparameters,
)
from sb3_smc.core.layout import PIXELWORLD_LAYOUT, SIGNALS, Layout, observation_size, smc_action_names
from sb3_smc.errors import SMCError
from sb3_smc.records.base import (
    Record,
    RecordError,
    bool_field,
    float_field,
    int_field,
    mapping_field,
    names_field,
    set_field,
    str_field,
)

__all__ = ["DISCOUNTS", "MAX_EPISODE_STEPS", "MAX_FRAME_STACK", "MAX_TRAINING_SEED", "SPLITS", "Budget", "SignalBias",
           "TaskSpec", "TrainingSpec", "WrapperSettings", "smc_name_from_env_id"]

SPLITS = ("train", "test", "all")
DISCOUNTS = ("decision", "semi-mdp")
"""How a decision is discounted (``WrapperSettings.discount``): ``decision``, by gamma, whatever it did (the paper);
``semi-mdp``, by gamma ** its primitive steps."""
MAX_TRAINING_SEED = 2**32 - 1
"""The largest training seed (``TrainingSpec.seed``): Stable-Baselines3 seeds numpy's global generator with it, which
takes ``0 .. 2**32 - 1``."""
MAX_EPISODE_STEPS = 10**6
"""The most decisions of an episode (``wrapper.max_steps``) and moves of one SMC call (``wrapper.call_step_cap``):
the native vector env keeps ``call_step_cap`` random numbers per environment."""
MAX_FRAME_STACK = 100
"""The most observations a memoryless policy sees stacked (``frame_stack``)."""


def smc_name_from_env_id(env_id: str) -> str:
    """``PW-<name>-v0`` -> ``<name>`` (the dataset or concept-pool name); other ids are returned unchanged."""
    name = env_id.split(":", 1)[-1]
    if name.startswith("PW-"):
        name = name[3:]
    head, sep, version = name.rpartition("-v")
    if sep and version.isdigit():
        name = head
    return name




# ---------------------------------------------------------------------------------------------------------------
# Training spec
# ---------------------------------------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class TaskSpec(Record):
    """The environment an SMC is trained on: ``gym.make(env_id, split=split, **env_kwargs)``.

    ``kind`` and ``datasets`` are filled from the PixelWorld catalog for ``PW-*`` ids (:meth:`resolved`);
    ``None`` / empty means "not known yet" (e.g. a user's own registered id before its env is built). ``layout``
    is the environment's sensor size and primitive actions (:class:`~sb3_smc.smc.smc.Layout`): ``None`` for
    PixelWorld's, set from the environment for any other (an :class:`~sb3_smc.tasks.task.SMCTask`); in JSON only when
    set.
    """

    env_id: str
    split: str = "train"
    kind: str | None = None
    datasets: tuple[str, ...] = ()
    env_kwargs: dict[str, Any] = field(default_factory=dict)
    layout: Layout | None = None

    def to_dict(self) -> dict[str, Any]:
        out = super().to_dict()
        if self.layout is None:
            del out["layout"]
        else:
            out["layout"] = {"sensor_size": self.layout.sensor_size, "primitives": list(self.layout.primitives)}
        return out

    @classmethod
    def from_dict(cls, data: Any, where: str | None = None) -> TaskSpec:
        layout = data.get("layout") if isinstance(data, Mapping) else None
        if isinstance(layout, Mapping):
            where = where or cls.__name__
            if set(layout) != {"sensor_size", "primitives"}:
                raise RecordError(f"{where}.layout: expected the fields ['primitives', 'sensor_size'], got "
                                  f"{sorted(layout)}")
            try:
                data = {**data, "layout": Layout(layout["sensor_size"], tuple(layout["primitives"]))}
            except (SMCError, TypeError) as err:
                raise RecordError(f"{where}.layout: {err}") from None
        return super().from_dict(data, where)

    @property
    def train_worlds(self) -> int | None:
        """``N`` where the SMC trains on the first ``N`` worlds of its training split (``env_kwargs``'
        ``train_worlds``: :func:`pixelworld_env.datasets.loading.training_order`); ``None``: the whole split."""
        value = self.env_kwargs.get("train_worlds")
        return None if value is None else int_field(value, "env_kwargs.train_worlds", 1)

    @property
    def smc_layout(self) -> Layout:
        """The layout of the SMCs trained on this task (PixelWorld's unless :attr:`layout` says otherwise)."""
        return self.layout if self.layout is not None else PIXELWORLD_LAYOUT

    def __post_init__(self) -> None:
        if self.layout is not None and not isinstance(self.layout, Layout):
            raise RecordError(f"layout must be a Layout or None, got {type(self.layout).__name__}")
        str_field(self.env_id, "env_id")
        str_field(self.split, "split", SPLITS)
        if self.kind is not None:
            str_field(self.kind, "kind", tuple(SIGNALS))
        set_field(self, "datasets", names_field(self.datasets, "datasets"))
        kwargs = mapping_field(self.env_kwargs, "env_kwargs")
        clash = sorted({"split", "max_steps"} & set(kwargs))
        if clash:
            raise RecordError(f"env_kwargs: {clash} are set by the spec (split, wrapper.max_steps), not env_kwargs")
        set_field(self, "env_kwargs", kwargs)

    def resolved(self) -> TaskSpec:
        """This task with ``kind`` and ``datasets`` read from the Gymnasium registry and the catalog, where known;
        for another environment's SMC task (:class:`~sb3_smc.tasks.task.SMCTask`) its ``kind`` and ``layout``, read from
        one instance of it (:func:`sb3_smc.tasks.resolved_task.resolve_task`, imported here: the records load no
        Gymnasium)."""
        from sb3_smc.tasks.resolved_task import resolve_task

        return dataclasses.replace(self, **resolve_task(self).spec_fields)


@dataclass(frozen=True, eq=False)
class WrapperSettings(Record):
    """How :class:`~sb3_smc.envs.wrapper.HierarchicalSMCWrapper` presents the task (docs/design.md, "Hierarchy: SMC
    calls")."""

    include_primitives: bool = True
    """The four moves are actions (False: the paper's "noprim" ablation)."""
    count_primitive_steps: bool = False
    """A call costs its moves (at least 1) of the episode budget instead of one step."""
    call_step_cap: int = 100
    """Decisions a called SMC may take before it is cut off."""
    max_steps: int = 100
    """Episode length in decisions (``gym.make(..., max_steps=...)``)."""
    discount: str = "decision"
    """How the learner discounts a decision: ``"decision"`` by gamma, whatever it did (the paper), or
    ``"semi-mdp"`` by gamma ** its primitive steps (:mod:`sb3_smc.common.discounting`); in JSON only when not the
    paper's."""

    def to_dict(self) -> dict[str, Any]:
        out = super().to_dict()
        if self.discount == "decision":
            del out["discount"]
        return out

    def __post_init__(self) -> None:
        str_field(self.discount, "wrapper.discount", DISCOUNTS)
        bool_field(self.include_primitives, "wrapper.include_primitives")
        bool_field(self.count_primitive_steps, "wrapper.count_primitive_steps")
        for name in ("call_step_cap", "max_steps"):
            set_field(self, name, int_field(getattr(self, name), f"wrapper.{name}", 1, MAX_EPISODE_STEPS))


@dataclass(frozen=True, eq=False)
class Budget(Record):
    """How much experience: ``total_timesteps`` in updates of ``n_envs x n_steps`` environment steps.

    ``n_steps=None`` means ``max(1, STEPS_PER_UPDATE // n_envs)`` (125 with 16 environments). Each size is an integer
    within its limit (:data:`~sb3_smc.core.hyperparameters.MAX_TIMESTEPS`, ``MAX_N_ENVS``, ``MAX_STEPS_PER_UPDATE``
    for ``n_envs x n_steps``), checked when the record is made.
    """

    total_timesteps: int = DEFAULT_TIMESTEPS
    n_envs: int = DEFAULT_N_ENVS
    n_steps: int | None = None

    def __post_init__(self) -> None:
        set_field(self, "total_timesteps", int_field(self.total_timesteps, "budget.total_timesteps", 0, MAX_TIMESTEPS))
        set_field(self, "n_envs", int_field(self.n_envs, "budget.n_envs", 1, MAX_N_ENVS))
        n_steps = max(1, STEPS_PER_UPDATE // self.n_envs) if self.n_steps is None else self.n_steps
        n_steps = int_field(n_steps, "budget.n_steps", 1)
        if self.n_envs * n_steps > MAX_STEPS_PER_UPDATE:
            raise RecordError(f"budget.n_steps: n_envs x n_steps, the steps of one update's rollout, must be at most "
                              f"{MAX_STEPS_PER_UPDATE:,}, got {self.n_envs} x {n_steps:,}")
        set_field(self, "n_steps", n_steps)

    @property
    def env_steps(self) -> int:
        """Steps per environment and update: ``n_steps`` as resolved (never ``None`` once built)."""
        assert self.n_steps is not None  # resolved in __post_init__
        return self.n_steps

    @property
    def steps_per_update(self) -> int:
        return self.n_envs * self.env_steps

    @property
    def updates(self) -> int:
        """Policy updates (rollouts) training runs: ``ceil(total_timesteps / steps_per_update)``."""
        return math.ceil(self.total_timesteps / self.steps_per_update)


@dataclass(frozen=True, eq=False)
class SignalBias(Record):
    """The initial action distribution, the signal bias (:func:`sb3_smc.learning.bias.initial_action_probabilities`)."""

    enabled: bool = True
    signal_weight: float = 1.0
    nonsignal_weight: float = 20.0
    smc_weight: float = 20.0

    def __post_init__(self) -> None:
        bool_field(self.enabled, "signal_bias.enabled")
        for name in ("signal_weight", "nonsignal_weight", "smc_weight"):
            value = float_field(getattr(self, name), f"signal_bias.{name}")
            if value <= 0:
                raise RecordError(f"signal_bias.{name} must be > 0, got {value}")
            set_field(self, name, value)

    @property
    def weights(self) -> dict[str, float]:
        return {"signal_weight": self.signal_weight, "nonsignal_weight": self.nonsignal_weight,
                "smc_weight": self.smc_weight}


@dataclass(frozen=True, eq=False)
class TrainingSpec(Record):
    """Everything that decides how one SMC is trained (not where logs go or how progress is shown).

    ``hyperparameters`` are the algorithm's complete constructor arguments (the defaults of
    :data:`~sb3_smc.core.hyperparameters.DEFAULT_HYPERPARAMETERS` merged with the given ones, ``policy_kwargs`` key by
    key; ``batch_size`` is capped at the budget's steps per update). ``children`` are the names of the SMCs the
    SMC may call, in action order. Build one with :meth:`create` (keyword interface of ``train_smc``) or directly.
    """

    name: str
    task: TaskSpec
    algo: str = DEFAULT_ALGORITHM
    hyperparameters: dict[str, Any] = field(default_factory=dict)
    seed: int = 0
    budget: Budget = field(default_factory=Budget)
    wrapper: WrapperSettings = field(default_factory=WrapperSettings)
    signal_bias: SignalBias = field(default_factory=SignalBias)
    frame_stack: int = 1
    children: tuple[str, ...] = ()

    _nested: ClassVar[dict[str, type[Record]]] = {"task": TaskSpec, "budget": Budget, "wrapper": WrapperSettings,
                                                    "signal_bias": SignalBias}

    def __post_init__(self) -> None:
        str_field(self.name, "name")
        for name, cls in self._nested.items():
            if not isinstance(getattr(self, name), cls):
                raise RecordError(f"{name} must be a {cls.__name__}, got {getattr(self, name)!r}")
        str_field(self.algo, "algo", tuple(ALGORITHM_REGISTRY))
        set_field(self, "seed", int_field(self.seed, "seed", 0, MAX_TRAINING_SEED))
        set_field(self, "frame_stack", int_field(self.frame_stack, "frame_stack", 1, MAX_FRAME_STACK))
        if ALGORITHM_REGISTRY[self.algo].recurrent and self.frame_stack != 1:
            raise RecordError(f"frame_stack is meant for memoryless policies (TRPO, PPO); {self.algo} has a "
                              "recurrent cell")
        children = names_field(self.children, "children")
        duplicates = sorted({c for c in children if children.count(c) > 1})
        if duplicates:
            raise RecordError(f"children named twice: {duplicates}")
        if self.name in children:
            raise RecordError(f"SMC {self.name!r} lists itself among its children")
        if not self.wrapper.include_primitives and not children:
            raise RecordError(f"SMC {self.name!r}: include_primitives=False (noprim) needs children to call")
        set_field(self, "children", children)
        if not isinstance(self.hyperparameters, Mapping):
            raise RecordError(f"hyperparameters must be a mapping, got {self.hyperparameters!r}")
        try:
            hyperparameters = resolve_hyperparameters(self.algo, self.hyperparameters)
        except ValueError as err:
            raise RecordError(str(err)) from None
        batch = hyperparameters.get("batch_size")
        if batch is not None:
            hyperparameters["batch_size"] = min(int_field(batch, "hyperparameters.batch_size", 1),
                                                self.budget.steps_per_update)
        set_field(self, "hyperparameters", hyperparameters)

    @classmethod
    def create(cls, env_id: str | TaskSpec, *, name: str | None = None, algo: str = DEFAULT_ALGORITHM, seed: int = 0,
               total_timesteps: int = DEFAULT_TIMESTEPS, n_envs: int = DEFAULT_N_ENVS, children: Sequence[str] = (),
               include_primitives: bool = True, count_primitive_steps: bool = False, call_step_cap: int = 100,
               max_steps: int = 100, signal_bias: bool | SignalBias = True, frame_stack: int = 1,
               split: str = "train", env_kwargs: Mapping[str, Any] | None = None, rnn: str | None = None,
               discount: str = "decision", train_worlds: int | None = None, **hyperparameters: Any) -> TrainingSpec:
        """The spec of ``train_smc``'s keyword interface (``n_steps`` in ``hyperparameters`` goes to the budget;
        ``rnn="lstm"`` or ``"gru"`` picks the recurrent policy of a recurrent algorithm).

        ``env_id`` is the task's id (its :class:`TaskSpec` with ``split`` and ``env_kwargs``, :meth:`TaskSpec.resolved`)
        or a :class:`TaskSpec`, taken as it is (``train_smc`` passes its task unresolved and resolves it once itself);
        ``split`` and ``env_kwargs`` then belong in it. ``train_worlds=N``: train on the first ``N`` worlds of the
        training split (stored in the task's ``env_kwargs``, so in the spec, the records and the library)."""
        if train_worlds is not None:
            given = env_id.env_kwargs if isinstance(env_id, TaskSpec) else (env_kwargs or {})
            if "train_worlds" in given:
                raise RecordError("TrainingSpec.create: give train_worlds once (not also in env_kwargs)")
            cut = {**given, "train_worlds": int_field(train_worlds, "train_worlds", 1)}
            if isinstance(env_id, TaskSpec):
                env_id = dataclasses.replace(env_id, env_kwargs=cut)
            else:
                env_kwargs = cut
        n_steps = hyperparameters.pop("n_steps", None)
        if rnn is not None:
            from sb3_smc.core.hyperparameters import recurrent_policy

            try:
                policy = recurrent_policy(rnn, algo)
            except ValueError as err:
                raise RecordError(str(err)) from None
            if "policy" in hyperparameters and hyperparameters["policy"] != policy:
                raise RecordError(f"rnn={rnn!r} and policy={hyperparameters['policy']!r} disagree: give one of them")
            hyperparameters["policy"] = policy
        bias = signal_bias if isinstance(signal_bias, SignalBias) else SignalBias(enabled=bool_field(signal_bias,
                                                                                                 "signal_bias"))
        if isinstance(env_id, TaskSpec):
            if split != "train" or env_kwargs:
                raise RecordError("TrainingSpec.create: give split and env_kwargs in the TaskSpec, not beside it")
            task = env_id
        else:
            task = TaskSpec(env_id, split=split, env_kwargs=dict(env_kwargs or {})).resolved()
        return cls(
            name=name or smc_name_from_env_id(task.env_id), task=task,
            algo=algo, hyperparameters=hyperparameters, seed=seed,
            budget=Budget(total_timesteps, n_envs, n_steps),
            wrapper=WrapperSettings(include_primitives, count_primitive_steps, call_step_cap, max_steps, discount),
            signal_bias=bias, frame_stack=frame_stack, children=tuple(children))

    @property
    def kind(self) -> str | None:
        return self.task.kind

    @property
    def action_names(self) -> tuple[str, ...]:
        """The SMC's actions (``ValueError`` while the task's kind is unknown)."""
        if self.task.kind is None:
            raise SMCError(f"SMC {self.name!r}: the kind of task {self.task.env_id!r} is not known yet")
        return smc_action_names(self.task.kind, self.children, self.wrapper.include_primitives,
                                self.task.smc_layout.primitives)

    @property
    def observation_size(self) -> int:
        """Length of one observation (before frame stacking)."""
        return observation_size(len(self.children), len(self.action_names), self.task.smc_layout.sensor_size)
