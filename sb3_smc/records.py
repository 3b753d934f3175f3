"""Typed records of SMC training, torch-free: what to train and what came out.

* :class:`TrainingSpec` — "train this SMC": the task (:class:`TaskSpec`), the wrapper settings
  (:class:`WrapperSettings`), the algorithm and its complete hyperparameters, the seed, the budget
  (:class:`Budget`), the signal-bias settings (:class:`SignalBias`), frame stacking, and the children **by name**
  (references into an :class:`~sb3_smc.library.SMCLibrary`, never objects).
* :class:`TrainingRecord` — what training produced: per-update training returns and success rates, the selected
  update and its return, wall time, primitive steps, the package versions it ran with.
* :class:`EvaluationRecord` — one run of the paper's test protocol: split, repeats, seed, score, per-environment
  scores.

All are frozen dataclasses of plain values: they pickle (to worker processes, to Ray), round-trip through JSON
(``to_dict`` / ``from_dict``, ``to_json`` / ``from_json``; ``from_dict`` rejects unknown or missing fields with
the field's name) and importing this module imports neither torch nor Stable-Baselines3.
"""

from __future__ import annotations

import dataclasses
import json
import math
import platform
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from importlib import metadata as importlib_metadata
from typing import Any, ClassVar, TypeVar

from pixelworld_env.validation import as_integer
from sb3_smc.errors import SMCError
from sb3_smc.hyperparameters import (
    ALGORITHM_REGISTRY,
    ALGORITHMS,
    DEFAULT_ALGORITHM,
    DEFAULT_N_ENVS,
    DEFAULT_TIMESTEPS,
    STEPS_PER_UPDATE,
    encode_value,
    resolve_hyperparameters,
)
from sb3_smc.layout import PIXELWORLD_LAYOUT, SIGNALS, Layout, observation_size, smc_action_names

__all__ = [
    "Budget",
    "EvaluationRecord",
    "RecordError",
    "SignalBias",
    "TaskSpec",
    "TrainingRecord",
    "TrainingSpec",
    "WrapperSettings",
    "package_versions",
    "smc_name_from_env_id",
    "test_score_of",
]

SPLITS = ("train", "test", "all")
DISCOUNTS = ("decision", "semi-mdp")
"""How a decision is discounted (``WrapperSettings.discount``): ``decision``, by gamma, whatever it did (the paper);
``semi-mdp``, by gamma ** its primitive steps."""
R = TypeVar("R", bound="_Record")


class RecordError(SMCError):
    """A record's field is missing, unknown, or of the wrong type or value (the message names it)."""


def package_versions() -> dict[str, str]:
    """Versions of the packages that decide a training result (and of Python)."""

    def version(dist: str) -> str:
        try:
            return importlib_metadata.version(dist)
        except importlib_metadata.PackageNotFoundError:
            return "unknown"

    return {"sb3_smc": version("sb3-smc"), "stable_baselines3": version("stable-baselines3"),
            "sb3_contrib": version("sb3-contrib"), "torch": version("torch"), "gymnasium": version("gymnasium"),
            "numpy": version("numpy"), "python": platform.python_version()}


def test_score_of(spec: TrainingSpec | None, evaluations: Sequence[EvaluationRecord]) -> float | None:
    """The latest test-split score on the spec's own task (else on any task); ``None`` without one."""
    tests = [e for e in evaluations if e.split == "test"]
    own = [e for e in tests if spec is not None and e.env_id == spec.task.env_id]
    chosen = own or tests
    return chosen[-1].score if chosen else None


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
# Field checks
# ---------------------------------------------------------------------------------------------------------------

def _int(value: Any, where: str, minimum: int | None = None) -> int:
    number = as_integer(value)  # the package's one integer rule (bools and floats are not integers)
    if number is None:
        raise RecordError(f"{where} must be an integer, got {value!r}")
    if minimum is not None and number < minimum:
        raise RecordError(f"{where} must be >= {minimum}, got {number}")
    return number


def _float(value: Any, where: str, allow_nan: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) and not (
            type(value).__module__ == "numpy" and hasattr(value, "dtype") and value.dtype.kind in "iuf"):
        raise RecordError(f"{where} must be a number, got {value!r}")
    value = float(value)
    if math.isnan(value) and not allow_nan or math.isinf(value):
        raise RecordError(f"{where} must be a finite number, got {value}")
    return value


def _bool(value: Any, where: str) -> bool:
    if not isinstance(value, bool):
        raise RecordError(f"{where} must be true or false, got {value!r}")
    return value


def _str(value: Any, where: str, choices: Sequence[str] | None = None) -> str:
    if not isinstance(value, str) or not value:
        raise RecordError(f"{where} must be a non-empty string, got {value!r}")
    if choices is not None and value not in choices:
        raise RecordError(f"{where} must be one of {tuple(choices)}, got {value!r}")
    return value


def _names(value: Any, where: str) -> tuple[str, ...]:
    if isinstance(value, str) or not isinstance(value, Sequence):
        raise RecordError(f"{where} must be a list of names, got {value!r}")
    return tuple(_str(v, f"{where}[{i}]") for i, v in enumerate(value))


def _json_mapping(value: Any, where: str) -> dict[str, Any]:
    if not isinstance(value, Mapping):
        raise RecordError(f"{where} must be a mapping, got {value!r}")
    try:
        return {str(k): encode_value(v, f"{where}.{k}") for k, v in value.items()}
    except ValueError as err:
        raise RecordError(str(err)) from None


def _set(obj: Any, name: str, value: Any) -> None:
    object.__setattr__(obj, name, value)


def _nan_to_none(values: Sequence[float]) -> list[float | None]:
    return [None if math.isnan(v) else v for v in values]


def _none_to_nan(values: Any, where: str) -> tuple[float, ...]:
    if isinstance(values, str) or not isinstance(values, Sequence):
        raise RecordError(f"{where} must be a list of numbers, got {values!r}")
    return tuple(math.nan if v is None else _float(v, f"{where}[{i}]", allow_nan=True) for i, v in enumerate(values))


# ---------------------------------------------------------------------------------------------------------------
# Base: dict / JSON round trip
# ---------------------------------------------------------------------------------------------------------------

class _Record:
    """``to_dict`` / ``from_dict`` / JSON for the frozen dataclasses below (nested records by field type)."""

    _nested: ClassVar[dict[str, type[_Record]]] = {}

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for f in dataclasses.fields(self):  # type: ignore[arg-type]
            value = getattr(self, f.name)
            if isinstance(value, _Record):
                value = value.to_dict()
            elif isinstance(value, tuple):
                value = list(value)
            elif isinstance(value, dict):
                value = json.loads(json.dumps(value))
            out[f.name] = value
        return out

    @classmethod
    def from_dict(cls: type[R], data: Any, where: str | None = None) -> R:
        where = where or cls.__name__
        if not isinstance(data, Mapping):
            raise RecordError(f"{where}: expected a mapping, got {type(data).__name__}")
        fields = {f.name: f for f in dataclasses.fields(cls)}  # type: ignore[arg-type]
        unknown = sorted(set(data) - set(fields))
        if unknown:
            raise RecordError(f"{where}: unknown field(s) {unknown} (expected {sorted(fields)})")
        required = [n for n, f in fields.items()
                    if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING]
        missing = [n for n in required if n not in data]
        if missing:
            raise RecordError(f"{where}: missing field(s) {missing}")
        kwargs = {}
        for name, value in data.items():
            nested = cls._nested.get(name)
            kwargs[name] = nested.from_dict(value, f"{where}.{name}") if nested is not None else value
        try:
            return cls(**kwargs)
        except RecordError as err:
            raise RecordError(f"{where}: {err}") from None

    def __eq__(self, other: object) -> bool:
        # by JSON form: NaN returns (null in JSON) compare equal, which field-wise float comparison would not
        if type(other) is not type(self):
            return NotImplemented
        return self.to_dict() == other.to_dict()  # type: ignore[attr-defined]

    __hash__ = None  # type: ignore[assignment]  # records hold dicts

    def to_json(self, **kwargs: Any) -> str:
        return json.dumps(self.to_dict(), allow_nan=False, **kwargs)

    @classmethod
    def from_json(cls: type[R], text: str, where: str | None = None) -> R:
        try:
            data = json.loads(text)
        except json.JSONDecodeError as err:
            raise RecordError(f"{where or cls.__name__}: not valid JSON: {err}") from None
        return cls.from_dict(data, where)


# ---------------------------------------------------------------------------------------------------------------
# Training spec
# ---------------------------------------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class TaskSpec(_Record):
    """The environment an SMC is trained on: ``gym.make(env_id, split=split, **env_kwargs)``.

    ``kind`` and ``datasets`` are filled from the PixelWorld catalog for ``PW-*`` ids (:meth:`resolved`);
    ``None`` / empty means "not known yet" (e.g. a user's own registered id before its env is built). ``layout``
    is the environment's sensor size and primitive actions (:class:`~sb3_smc.smc.Layout`): ``None`` for
    PixelWorld's, set from the environment for any other (an :class:`~sb3_smc.tasks.SMCTask`); in JSON only when
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
    def smc_layout(self) -> Layout:
        """The layout of the SMCs trained on this task (PixelWorld's unless :attr:`layout` says otherwise)."""
        return self.layout if self.layout is not None else PIXELWORLD_LAYOUT

    def __post_init__(self) -> None:
        if self.layout is not None and not isinstance(self.layout, Layout):
            raise RecordError(f"layout must be a Layout or None, got {type(self.layout).__name__}")
        _str(self.env_id, "env_id")
        _str(self.split, "split", SPLITS)
        if self.kind is not None:
            _str(self.kind, "kind", tuple(SIGNALS))
        _set(self, "datasets", _names(self.datasets, "datasets"))
        kwargs = _json_mapping(self.env_kwargs, "env_kwargs")
        clash = sorted({"split", "max_steps"} & set(kwargs))
        if clash:
            raise RecordError(f"env_kwargs: {clash} are set by the spec (split, wrapper.max_steps), not env_kwargs")
        _set(self, "env_kwargs", kwargs)

    def resolved(self) -> TaskSpec:
        """This task with ``kind`` and ``datasets`` read from the Gymnasium registry and the catalog, where known;
        for another environment's SMC task (:class:`~sb3_smc.tasks.SMCTask`) its ``kind`` and ``layout``, read from
        one instance of it."""
        if self.kind is not None and (self.datasets or self.layout is not None):
            return self
        datasets = self.datasets or _registered_datasets(self.env_id)
        kind, layout = self.kind, self.layout
        if kind is None and datasets:
            from pixelworld_env.datasets import catalog

            kinds = {catalog.dataset(name).kind for name in datasets}
            kind = kinds.pop() if len(kinds) == 1 else None
        elif not datasets and (kind is None or layout is None):
            from sb3_smc.tasks import describe_task

            found = describe_task(self.env_id, self.env_kwargs)
            if found is not None:
                kind, task_layout = found
                layout = None if task_layout == PIXELWORLD_LAYOUT else task_layout
        return dataclasses.replace(self, kind=kind, datasets=datasets, layout=layout)


def _registered_datasets(env_id: str) -> tuple[str, ...]:
    import gymnasium as gym

    import pixelworld_env  # noqa: F401  (registers the PW-* ids)

    try:
        spec = gym.spec(env_id)
    except gym.error.Error:
        return ()
    return tuple(spec.kwargs.get("datasets", ()))


@dataclass(frozen=True, eq=False)
class WrapperSettings(_Record):
    """How :class:`~sb3_smc.wrapper.HierarchicalSMCWrapper` presents the task (docs/design.md, "Hierarchy: SMC
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
        _str(self.discount, "wrapper.discount", DISCOUNTS)
        _bool(self.include_primitives, "wrapper.include_primitives")
        _bool(self.count_primitive_steps, "wrapper.count_primitive_steps")
        _set(self, "call_step_cap", _int(self.call_step_cap, "wrapper.call_step_cap", 1))
        _set(self, "max_steps", _int(self.max_steps, "wrapper.max_steps", 1))


@dataclass(frozen=True, eq=False)
class Budget(_Record):
    """How much experience: ``total_timesteps`` in updates of ``n_envs x n_steps`` environment steps.

    ``n_steps=None`` means ``max(1, STEPS_PER_UPDATE // n_envs)`` (125 with 16 environments).
    """

    total_timesteps: int = DEFAULT_TIMESTEPS
    n_envs: int = DEFAULT_N_ENVS
    n_steps: int | None = None

    def __post_init__(self) -> None:
        _set(self, "total_timesteps", _int(self.total_timesteps, "budget.total_timesteps", 0))
        _set(self, "n_envs", _int(self.n_envs, "budget.n_envs", 1))
        n_steps = max(1, STEPS_PER_UPDATE // self.n_envs) if self.n_steps is None else self.n_steps
        _set(self, "n_steps", _int(n_steps, "budget.n_steps", 1))

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
class SignalBias(_Record):
    """The initial action distribution, the signal bias (:func:`sb3_smc.bias.initial_action_probabilities`)."""

    enabled: bool = True
    signal_weight: float = 1.0
    nonsignal_weight: float = 20.0
    smc_weight: float = 20.0

    def __post_init__(self) -> None:
        _bool(self.enabled, "signal_bias.enabled")
        for name in ("signal_weight", "nonsignal_weight", "smc_weight"):
            value = _float(getattr(self, name), f"signal_bias.{name}")
            if value <= 0:
                raise RecordError(f"signal_bias.{name} must be > 0, got {value}")
            _set(self, name, value)

    @property
    def weights(self) -> dict[str, float]:
        return {"signal_weight": self.signal_weight, "nonsignal_weight": self.nonsignal_weight,
                "smc_weight": self.smc_weight}


@dataclass(frozen=True, eq=False)
class TrainingSpec(_Record):
    """Everything that decides how one SMC is trained (not where logs go or how progress is shown).

    ``hyperparameters`` are the algorithm's complete constructor arguments (the defaults of
    :data:`~sb3_smc.hyperparameters.DEFAULT_HYPERPARAMETERS` merged with the given ones, ``policy_kwargs`` key by
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

    _nested: ClassVar[dict[str, type[_Record]]] = {"task": TaskSpec, "budget": Budget, "wrapper": WrapperSettings,
                                                    "signal_bias": SignalBias}

    def __post_init__(self) -> None:
        _str(self.name, "name")
        for name, cls in self._nested.items():
            if not isinstance(getattr(self, name), cls):
                raise RecordError(f"{name} must be a {cls.__name__}, got {getattr(self, name)!r}")
        _str(self.algo, "algo", ALGORITHMS)
        _set(self, "seed", _int(self.seed, "seed", 0))
        _set(self, "frame_stack", _int(self.frame_stack, "frame_stack", 1))
        if ALGORITHM_REGISTRY[self.algo].recurrent and self.frame_stack != 1:
            raise RecordError(f"frame_stack is meant for memoryless policies (TRPO, PPO); {self.algo} has a "
                              "recurrent cell")
        children = _names(self.children, "children")
        duplicates = sorted({c for c in children if children.count(c) > 1})
        if duplicates:
            raise RecordError(f"children named twice: {duplicates}")
        if self.name in children:
            raise RecordError(f"SMC {self.name!r} lists itself among its children")
        if not self.wrapper.include_primitives and not children:
            raise RecordError(f"SMC {self.name!r}: include_primitives=False (noprim) needs children to call")
        _set(self, "children", children)
        if not isinstance(self.hyperparameters, Mapping):
            raise RecordError(f"hyperparameters must be a mapping, got {self.hyperparameters!r}")
        try:
            hyperparameters = resolve_hyperparameters(self.algo, self.hyperparameters)
        except ValueError as err:
            raise RecordError(str(err)) from None
        batch = hyperparameters.get("batch_size")
        if batch is not None:
            hyperparameters["batch_size"] = min(_int(batch, "hyperparameters.batch_size", 1),
                                                self.budget.steps_per_update)
        _set(self, "hyperparameters", hyperparameters)

    @classmethod
    def create(cls, env_id: str, *, name: str | None = None, algo: str = DEFAULT_ALGORITHM, seed: int = 0,
               total_timesteps: int = DEFAULT_TIMESTEPS, n_envs: int = DEFAULT_N_ENVS, children: Sequence[str] = (),
               include_primitives: bool = True, count_primitive_steps: bool = False, call_step_cap: int = 100,
               max_steps: int = 100, signal_bias: bool | SignalBias = True, frame_stack: int = 1,
               split: str = "train", env_kwargs: Mapping[str, Any] | None = None, rnn: str | None = None,
               discount: str = "decision", **hyperparameters: Any) -> TrainingSpec:
        """The spec of ``train_smc``'s keyword interface (``n_steps`` in ``hyperparameters`` goes to the budget;
        ``rnn="lstm"`` or ``"gru"`` picks the recurrent policy of a recurrent algorithm)."""
        n_steps = hyperparameters.pop("n_steps", None)
        if rnn is not None:
            from sb3_smc.hyperparameters import recurrent_policy

            try:
                policy = recurrent_policy(rnn, algo)
            except ValueError as err:
                raise RecordError(str(err)) from None
            if "policy" in hyperparameters and hyperparameters["policy"] != policy:
                raise RecordError(f"rnn={rnn!r} and policy={hyperparameters['policy']!r} disagree: give one of them")
            hyperparameters["policy"] = policy
        bias = signal_bias if isinstance(signal_bias, SignalBias) else SignalBias(enabled=_bool(signal_bias,
                                                                                                 "signal_bias"))
        return cls(
            name=name or smc_name_from_env_id(env_id),
            task=TaskSpec(env_id, split=split, env_kwargs=dict(env_kwargs or {})).resolved(),
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


# ---------------------------------------------------------------------------------------------------------------
# What came out
# ---------------------------------------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class TrainingRecord(_Record):
    """What a training run produced (the selection of docs/design.md, "Selection and test", included).

    ``training_returns[k]`` is the mean undiscounted return of the episodes that ended in rollout ``k`` (NaN when
    none did; ``null`` in JSON), ``success_rates[k]`` the fraction of them with a final reward > 0. The selected
    update is the earliest one with the highest return; its policy is the SMC's.
    """

    training_returns: tuple[float, ...]
    success_rates: tuple[float, ...]
    selected_update: int | None
    selected_return: float | None
    total_timesteps: int
    primitive_steps: int
    wall_time_s: float
    action_names: tuple[str, ...] = ()
    initial_action_probabilities: tuple[float, ...] | None = None
    torch_threads: int = 1
    versions: dict[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        _set(self, "training_returns", _none_to_nan(self.training_returns, "training_returns"))
        _set(self, "success_rates", _none_to_nan(self.success_rates, "success_rates"))
        if len(self.success_rates) != len(self.training_returns):
            raise RecordError(f"success_rates has {len(self.success_rates)} values for "
                              f"{len(self.training_returns)} updates")
        if self.selected_update is not None:
            update = _int(self.selected_update, "selected_update", 0)
            if update >= len(self.training_returns):
                raise RecordError(f"selected_update {update} is past the last update "
                                  f"({len(self.training_returns)} updates)")
            _set(self, "selected_update", update)
            _set(self, "selected_return", _float(self.selected_return, "selected_return"))
        elif self.selected_return is not None:
            raise RecordError("selected_return is set but selected_update is not")
        _set(self, "total_timesteps", _int(self.total_timesteps, "total_timesteps", 0))
        _set(self, "primitive_steps", _int(self.primitive_steps, "primitive_steps", 0))
        _set(self, "wall_time_s", _float(self.wall_time_s, "wall_time_s"))
        _set(self, "action_names", _names(self.action_names, "action_names"))
        if self.initial_action_probabilities is not None:
            _set(self, "initial_action_probabilities",
                 _none_to_nan(self.initial_action_probabilities, "initial_action_probabilities"))
        _set(self, "torch_threads", _int(self.torch_threads, "torch_threads", 1))
        _set(self, "versions", {str(k): str(v) for k, v in _json_mapping(self.versions, "versions").items()})

    @property
    def updates(self) -> int:
        return len(self.training_returns)

    @property
    def final_return(self) -> float | None:
        return self.training_returns[-1] if self.training_returns else None

    def to_dict(self) -> dict[str, Any]:
        out = super().to_dict()
        out["training_returns"] = _nan_to_none(self.training_returns)
        out["success_rates"] = _nan_to_none(self.success_rates)
        if self.initial_action_probabilities is not None:
            out["initial_action_probabilities"] = _nan_to_none(self.initial_action_probabilities)
        return out


@dataclass(frozen=True, eq=False)
class EvaluationRecord(_Record):
    """One run of the paper's test of SMC ``smc`` on ``env_id``'s ``split`` (docs/design.md, "Selection and test").

    ``environment_scores[i]``: the success fraction over the repeats of environment ``i``; ``score``: the mean over
    environments x repeats. ``repeats`` and ``seed`` are ``None`` only for a score converted from a version-1
    library, which did not record them (its ``environment_scores`` are then empty).
    """

    smc: str
    env_id: str
    split: str
    kind: str
    repeats: int | None
    seed: int | None
    score: float
    environment_scores: tuple[float, ...] = ()
    mean_length: float | None = None
    call_counts: dict[str, int] = field(default_factory=dict)

    def __post_init__(self) -> None:
        _str(self.smc, "smc")
        _str(self.env_id, "env_id")
        _str(self.split, "split", SPLITS)
        _str(self.kind, "kind", tuple(SIGNALS))
        if self.repeats is not None:
            _set(self, "repeats", _int(self.repeats, "repeats", 1))
        if self.seed is not None:
            _set(self, "seed", _int(self.seed, "seed"))
        _set(self, "score", _float(self.score, "score"))
        _set(self, "environment_scores", _none_to_nan(self.environment_scores, "environment_scores"))
        if self.mean_length is not None:
            _set(self, "mean_length", _float(self.mean_length, "mean_length"))
        counts = _json_mapping(self.call_counts, "call_counts")
        _set(self, "call_counts", {k: _int(v, f"call_counts.{k}", 0) for k, v in counts.items()})

    def to_dict(self) -> dict[str, Any]:
        out = super().to_dict()
        out["environment_scores"] = _nan_to_none(self.environment_scores)
        return out

    @property
    def key(self) -> tuple[str, str]:
        """``(env_id, split)``: an SMC keeps one evaluation per key (the latest)."""
        return self.env_id, self.split
