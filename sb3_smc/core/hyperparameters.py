"""The learners in one place (torch-free): the algorithm registry, default hyperparameters, merging, and storage
as plain JSON.

:data:`ALGORITHM_REGISTRY` is the single source of what sb3-smc knows of each algorithm (like rl_zoo3's ``ALGOS``,
but torch-free: each class is imported on first use, and only where an SMC of its algorithm needs it): its SB3 class,
the paper's settings (docs/design.md), the recurrent cells it takes, its rl_zoo3 name. ``train_smc`` builds the class
and merges a user's overrides into the defaults (:func:`resolve_hyperparameters`), a
:class:`~sb3_smc.records.TrainingSpec` stores the merged result, a library loads its models with the class,
curricula and the ``sb3-smc`` command take the built-in names (:data:`ALGORITHMS`), and the rl_zoo3 files in
``zoo_configs/`` are generated from it (:mod:`sb3_smc.zoo`). :func:`register_algorithm` adds a learner of the user's
own, for ``train_smc`` and libraries.

Stored hyperparameters are JSON data. Two non-JSON kinds of value have a JSON form:

* a class (``policy_kwargs={"activation_fn": torch.nn.ReLU}``) is stored as ``{"__class__": "torch.nn...ReLU"}``
  and imported again when the model is built;
* a linear schedule is written as rl_zoo3 writes it, ``"lin_3e-3"`` (from 3e-3 at the start to 0 at the end),
  for ``learning_rate`` and ``clip_range``.

Anything else that is not JSON (a lambda, an object) is refused with an error naming the key.
"""

from __future__ import annotations

import copy
import importlib
import math
import sys
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from sb3_smc.errors import SMCError, SMCRuntimeError, SMCTypeError

if TYPE_CHECKING:
    from stable_baselines3.common.on_policy_algorithm import OnPolicyAlgorithm
    from stable_baselines3.common.policies import ActorCriticPolicy

__all__ = [
    "ALGORITHMS",
    "ALGORITHM_REGISTRY",
    "DEFAULT_ALGORITHM",
    "DEFAULT_HYPERPARAMETERS",
    "DEFAULT_N_ENVS",
    "DEFAULT_TIMESTEPS",
    "MAX_ITERATIONS",
    "MAX_N_ENVS",
    "MAX_STEPS_PER_UPDATE",
    "MAX_TIMESTEPS",
    "RECURRENT_POLICIES",
    "SAFE_CLASS_MODULES",
    "STEPS_PER_UPDATE",
    "Algorithm",
    "algorithm",
    "algorithm_of",
    "constructor_arguments",
    "decode_value",
    "encode_value",
    "recurrent_policy",
    "register_algorithm",
    "resolve_hyperparameters",
]

STEPS_PER_UPDATE = 2000
"""Environment steps per policy update (the paper's batch size)."""
DEFAULT_N_ENVS = 16
"""Environments stepped together (``n_steps = STEPS_PER_UPDATE // n_envs`` each)."""
DEFAULT_TIMESTEPS = 400_000
"""Environment steps of one SMC's training when none are given (200 updates of ``STEPS_PER_UPDATE``)."""

MAX_TIMESTEPS = 10**10
"""The most environment steps one SMC trains (``budget.total_timesteps``, ``--timesteps``): 25,000 times the default,
decades of one job's CPU time; a larger number is a typo, refused before anything is built."""
MAX_N_ENVS = 1024
"""The most environments stepped together in one SMC's training (``budget.n_envs``)."""
MAX_STEPS_PER_UPDATE = 10**6
"""The most environment steps of one update's rollout (``budget.n_envs x budget.n_steps``; 500 times the paper's
2,000): the rollout buffer holds them all."""
MAX_ITERATIONS = 10_000
"""The most passes an update makes of one kind (the hyperparameters of :data:`ITERATION_HYPERPARAMETERS`)."""
ITERATION_HYPERPARAMETERS = ("n_epochs", "n_critic_updates", "cg_max_steps", "line_search_max_iter")
"""Hyperparameters that count an update's passes: integers in ``[1, MAX_ITERATIONS]``."""

RECURRENT_POLICIES = {"lstm": "SequenceLstmPolicy", "gru": "SequenceGruPolicy"}
"""``rnn`` option of ``train_smc`` -> the recurrent policy (by name) of the recurrent algorithms."""


@dataclass(frozen=True)
class Algorithm:
    """One algorithm ``train_smc`` trains and a library stores: everything the package knows of it."""

    name: str
    """Its name in specs, manifests, curricula and ``--algo``."""
    class_path: str
    """``module.Class`` of its Stable-Baselines3 class (imported by :meth:`load_class`: this module stays
    torch-free)."""
    hyperparameters: dict[str, Any]
    """Its constructor arguments by default (``n_steps`` comes from the budget: ``STEPS_PER_UPDATE // n_envs``)."""
    cells: tuple[str, ...] = ()
    """The ``rnn`` options (:data:`RECURRENT_POLICIES`) it takes; none for a memoryless (MLP) policy."""
    zoo_name: str | None = None
    """rl_zoo3's ``--algo`` name: ``zoo_configs/<zoo_name>.yml`` and the conf module ``sb3_smc.zoo.<zoo_name>``
    (the start-up hook ``_sb3_smc_gym_hook`` adds the names rl_zoo3 lacks to its table)."""
    zoo_note: str = ""
    """What ``zoo_configs/<zoo_name>.yml`` says of the settings."""
    registered: type[OnPolicyAlgorithm] | None = field(default=None, repr=False)
    """The class itself, for one the user's code registered (:func:`register_algorithm`): nothing is imported."""

    @property
    def recurrent(self) -> bool:
        """Whether its policy has memory of its own (a recurrent cell)."""
        return bool(self.cells)

    def load_class(self) -> type[OnPolicyAlgorithm]:
        """The Stable-Baselines3 class (imports torch); on-policy: ``n_steps`` comes from the budget.
        :class:`~sb3_smc.errors.SMCRuntimeError` naming the algorithm and its module where that cannot be imported
        (only this algorithm's SMCs need it)."""
        if self.registered is not None:
            return self.registered
        module, _, name = self.class_path.rpartition(".")
        try:
            return getattr(importlib.import_module(module), name)
        except Exception as err:  # noqa: BLE001 - whatever the module's code raises on import
            raise SMCRuntimeError(f"algorithm {self.name!r}: cannot import its class {name!r} from module {module!r} "
                                  f"({type(err).__name__}: {err}); only the SMCs of {self.name} need it") from err


def _lstm_32() -> dict[str, Any]:
    """``policy_kwargs`` of one 32-unit recurrent layer, the action layer on it, a critic without memory."""
    return {"lstm_hidden_size": 32, "n_lstm_layers": 1, "net_arch": [], "shared_lstm": False,
            "enable_critic_lstm": False}


def _mlp_32() -> dict[str, Any]:
    """``policy_kwargs`` of one hidden layer of 32 units for actor and critic."""
    return {"net_arch": {"pi": [32], "vf": [32]}}


ALGORITHM_REGISTRY: dict[str, Algorithm] = {algo.name: algo for algo in (
    Algorithm(
        "RecurrentPPO", "sb3_contrib.RecurrentPPO",
        {"policy": "SequenceLstmPolicy", "gamma": 0.99, "gae_lambda": 1.0, "batch_size": STEPS_PER_UPDATE,
         "n_epochs": 4, "learning_rate": 3e-3, "clip_range": 0.2, "ent_coef": 0.0, "policy_kwargs": _lstm_32()},
        cells=tuple(RECURRENT_POLICIES), zoo_name="ppo_lstm",
        zoo_note="RecurrentPPO: one 32-unit LSTM (the paper's GRU-32 size) with the action layer directly on it and "
                 "a critic linear in the observation. train_smc uses SequenceLstmPolicy, a faster subclass of "
                 "MlpLstmPolicy with the same numbers; rl_zoo3 can only name SB3's own policies."),
    Algorithm(
        "TRPO", "sb3_contrib.TRPO",
        {"policy": "MlpPolicy", "gamma": 0.99, "gae_lambda": 1.0, "batch_size": STEPS_PER_UPDATE, "target_kl": 0.01,
         "learning_rate": 1e-3, "policy_kwargs": _mlp_32()},
        zoo_name="trpo",
        zoo_note="TRPO: one hidden layer of 32 tanh units for actor and critic, KL step 0.01 (the paper's NPO step "
                 "size)."),
    Algorithm(
        "PPO", "stable_baselines3.PPO",
        {"policy": "MlpPolicy", "gamma": 0.99, "gae_lambda": 1.0, "batch_size": 250, "n_epochs": 10,
         "learning_rate": 3e-4, "clip_range": 0.2, "ent_coef": 0.0, "policy_kwargs": _mlp_32()},
        zoo_name="ppo", zoo_note="PPO: one hidden layer of 32 tanh units for actor and critic (memoryless)."),
    Algorithm(
        "RecurrentTRPO", "sb3_smc.recurrent_trpo.RecurrentTRPO",
        {"policy": "SequenceLstmPolicy", "gamma": 0.99, "gae_lambda": 1.0, "batch_size": STEPS_PER_UPDATE,
         "target_kl": 0.01, "learning_rate": 1e-3, "n_critic_updates": 10, "cg_max_steps": 15, "cg_damping": 0.1,
         "baseline": "critic", "policy_kwargs": _lstm_32()},
        cells=tuple(RECURRENT_POLICIES), zoo_name="recurrent_trpo",
        zoo_note="RecurrentTRPO (sb3_smc.recurrent_trpo): TRPO's trust-region step (KL 0.01) on a 32-unit LSTM "
                 "policy; policy: MlpGruPolicy gives the paper's GRU, baseline: linear_feature its linear feature "
                 "baseline. sb3-smc's start-up hook adds --algo recurrent_trpo to rl_zoo3."),
)}
"""Every algorithm by name: the built-in ones (:data:`ALGORITHMS`), then those :func:`register_algorithm` added.
Overrides replace the defaults key by key, ``policy_kwargs`` key by key too. RecurrentPPO and TRPO are the measured
settings of ``docs/training.md``; PPO (memoryless; minibatches of 250, 10 epochs, learning rate 3e-4, the settings
of the earlier hand-written rl_zoo3 file) is offered for comparison, untuned. RecurrentTRPO
(:mod:`sb3_smc.recurrent_trpo`, the paper's learner with ``rnn="gru"``) has TRPO's trust region (KL 0.01) and critic
learning rate on RecurrentPPO's recurrent policy; ``baseline="linear_feature"`` gives the paper's linear feature
baseline instead of the critic."""

ALGORITHMS = tuple(ALGORITHM_REGISTRY)
"""The built-in algorithms: those of the ``sb3-smc`` command's ``--algo`` and of curricula. ``train_smc`` and
libraries take these and those :func:`register_algorithm` adds (every name of :data:`ALGORITHM_REGISTRY`)."""
DEFAULT_ALGORITHM = ALGORITHMS[0]
"""The algorithm of a spec, a curriculum node or a run that names none."""
DEFAULT_HYPERPARAMETERS: dict[str, dict[str, Any]] = {name: algo.hyperparameters
                                                       for name, algo in ALGORITHM_REGISTRY.items()}
"""Constructor arguments of each algorithm (:attr:`Algorithm.hyperparameters`)."""


def algorithm(name: str) -> Algorithm:
    """The registry's entry of ``name``; ``ValueError`` naming the algorithms for an unknown one."""
    if name not in ALGORITHM_REGISTRY:
        raise SMCError(f"algo must be one of {tuple(ALGORITHM_REGISTRY)}, got {name!r}")
    return ALGORITHM_REGISTRY[name]


def algorithm_of(cls: type) -> str | None:
    """The name of the registry's algorithm whose class is exactly ``cls`` (a model's type), ``None`` if none is.
    Only a class that can be ``cls`` is looked at: a registered one by identity, a built-in one (imported on first
    use) where its name is ``cls``'s, so an algorithm whose module cannot be imported fails only for its own models
    (:meth:`Algorithm.load_class`'s error)."""
    for name, entry in ALGORITHM_REGISTRY.items():
        if entry.registered is cls or (entry.registered is None and entry.class_path.rpartition(".")[2] == cls.__name__
                                       and entry.load_class() is cls):
            return name
    return None


def recurrent_policy(rnn: str, algo: str | None = None) -> str:
    """The policy (by name) of the ``rnn`` option; ``ValueError`` for an unknown cell, or for ``algo`` when given and
    not taking it."""
    if rnn not in RECURRENT_POLICIES:
        raise SMCError(f"rnn must be one of {sorted(RECURRENT_POLICIES)}, got {rnn!r}")
    entry = ALGORITHM_REGISTRY.get(algo) if algo is not None else None
    if algo is not None and (entry is None or not entry.recurrent):
        recurrent = [name for name, known in ALGORITHM_REGISTRY.items() if known.recurrent]
        raise SMCError(f"rnn={rnn!r} needs a recurrent algorithm ({' or '.join(recurrent)}); {algo} has no "
                       "recurrence")
    if entry is not None and rnn not in entry.cells:
        raise SMCError(f"rnn={rnn!r}: {algo} takes rnn {' or '.join(entry.cells)}")
    return RECURRENT_POLICIES[rnn]


CLASS_KEY = "__class__"
SCHEDULE_KEYS = ("learning_rate", "clip_range")
_RESERVED = {"n_steps": "the budget's n_steps", "seed": "the spec's seed", "env": "the environment factory",
             "device": "training always runs on the CPU", "tensorboard_log": "train_smc's tensorboard_log"}


MAX_VALUE_DEPTH = 32
"""The deepest nesting of lists and mappings a stored hyperparameter may have (``policy_kwargs.net_arch.pi``: 3)."""


def _check_depth(depth: int, where: str) -> None:
    if depth > MAX_VALUE_DEPTH:
        raise SMCError(f"hyperparameter {where[:80]}...: nested more than {MAX_VALUE_DEPTH} deep")


def encode_value(value: Any, where: str, _depth: int = 0) -> Any:
    """``value`` as JSON data (classes as ``{"__class__": path}``); ``ValueError`` naming ``where`` otherwise."""
    _check_depth(_depth, where)
    if value is None or isinstance(value, bool | str):
        return value
    if isinstance(value, int | float):
        if isinstance(value, float) and not math.isfinite(value):
            raise SMCError(f"hyperparameter {where}: {value} is not a finite number")
        return value
    if type(value).__module__ == "numpy" and hasattr(value, "item"):
        return encode_value(value.item(), where)
    if isinstance(value, type):
        path = f"{value.__module__}.{value.__qualname__}"
        if "<locals>" in path:
            raise SMCError(f"hyperparameter {where}: class {path} is defined inside a function and cannot be "
                           "imported again; define it at module level")
        return {CLASS_KEY: path}
    if isinstance(value, Mapping):
        if CLASS_KEY in value and len(value) == 1:
            return {CLASS_KEY: str(value[CLASS_KEY])}
        return {str(k): encode_value(v, f"{where}.{k}", _depth + 1) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [encode_value(v, f"{where}[{i}]", _depth + 1) for i, v in enumerate(value)]
    raise SMCError(f"hyperparameter {where}: a {type(value).__name__} ({value!r}) cannot be stored in a training "
                   "spec; use JSON values, classes, or 'lin_<initial value>' for a linear schedule")


SAFE_CLASS_MODULES = ("torch.nn", "torch.optim", "stable_baselines3", "sb3_contrib", "sb3_smc")
"""The modules (and their sub-modules) a stored class is imported from without ``trust``: PyTorch's layers and
optimisers, Stable-Baselines3's and sb3-contrib's classes and this package's. Importing a module runs its code, so a
file that names another module's class (``{"__class__": "mypackage.MyExtractor"}``) loads only when its reader
trusts it. Even there, without trust, only a module already imported is looked in, or one of
:data:`SAFE_IMPORTS` (a package's scripts and launchers, ``__main__`` or ``zoo.record_video``, run code when
imported)."""
SAFE_IMPORTS = ("torch.nn", "torch.optim", "stable_baselines3.common.policies",
                "stable_baselines3.common.torch_layers", "sb3_contrib.common.recurrent.policies",
                "sb3_smc.common.recurrent", "sb3_smc.common.recurrent.policies", "sb3_smc.learning.features")
"""The modules a stored class may be imported from without trust when they are not imported yet: those that define
the policies, layers, optimisers and feature extractors an SMC's model uses, and run nothing on import."""


def _import_class(path: str, where: str, trust: bool = False) -> type:
    module, _, name = path.rpartition(".")
    if not trust and not any(module == safe or module.startswith(safe + ".") for safe in SAFE_CLASS_MODULES):
        raise SMCError(f"hyperparameter {where}: class {path!r} is not from a module loaded without trust "
                       f"({', '.join(SAFE_CLASS_MODULES)}); importing it would run its module's code: pass "
                       "trust=True (--trust) only for a file from a source you trust")
    if not trust and module not in sys.modules and module not in SAFE_IMPORTS:
        raise SMCError(f"hyperparameter {where}: class {path!r}: its module {module!r} is not imported yet and is "
                       "none of the modules imported without trust (sb3_smc.core.hyperparameters.SAFE_IMPORTS); "
                       "pass trust=True (--trust) only for a file from a source you trust")
    try:
        obj: Any = importlib.import_module(module)
        for part in name.split("."):
            obj = getattr(obj, part)
    except (ImportError, AttributeError, ValueError) as err:
        raise SMCError(f"hyperparameter {where}: cannot import class {path!r} ({err})") from None
    if not isinstance(obj, type):
        raise SMCError(f"hyperparameter {where}: {path!r} is a {type(obj).__name__}, not a class")
    return obj


def _linear(initial: float) -> Callable[[float], float]:
    def schedule(progress_remaining: float) -> float:
        return progress_remaining * initial

    return schedule


def decode_value(value: Any, where: str, *, trust: bool = True, _depth: int = 0) -> Any:
    """The inverse of :func:`encode_value` (classes imported, ``"lin_<x>"`` becomes a linear schedule).
    ``trust=False`` (a file someone else wrote): classes only from :data:`SAFE_CLASS_MODULES`."""
    _check_depth(_depth, where)
    if isinstance(value, Mapping):
        if set(value) == {CLASS_KEY}:
            if not isinstance(value[CLASS_KEY], str):
                raise SMCError(f"hyperparameter {where}: a class path must be a string, got {value[CLASS_KEY]!r}")
            return _import_class(value[CLASS_KEY], where, trust)
        return {k: decode_value(v, f"{where}.{k}", trust=trust, _depth=_depth + 1) for k, v in value.items()}
    if isinstance(value, list):
        return [decode_value(v, f"{where}[{i}]", trust=trust, _depth=_depth + 1) for i, v in enumerate(value)]
    if isinstance(value, str) and where.split(".")[-1] in SCHEDULE_KEYS and value.startswith("lin_"):
        try:
            return _linear(float(value[4:]))
        except ValueError:
            raise SMCError(f"hyperparameter {where}: {value!r} is not 'lin_<number>'") from None
    return value


def resolve_hyperparameters(algo: str, overrides: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """The defaults of ``algo`` with ``overrides`` applied (``policy_kwargs`` key by key), as JSON data."""
    defaults = algorithm(algo).hyperparameters
    overrides = dict(overrides or {})
    for key, why in _RESERVED.items():
        if key in overrides:
            raise SMCError(f"hyperparameter {key!r} is not set through the hyperparameters ({why})")
    resolved = copy.deepcopy(defaults)
    policy_kwargs = resolved.pop("policy_kwargs")
    policy_kwargs.update(overrides.pop("policy_kwargs", None) or {})
    resolved.update(overrides)
    resolved["policy_kwargs"] = policy_kwargs
    policy = resolved.get("policy")
    if not isinstance(policy, str | type):
        raise SMCError(f"hyperparameter 'policy' must be a policy name or class, got {policy!r}")
    encoded = {key: encode_value(value, key) for key, value in resolved.items()}
    for key in ITERATION_HYPERPARAMETERS:
        value = encoded.get(key)
        if value is not None and not (type(value) is int and 1 <= value <= MAX_ITERATIONS):  # bools are not counts
            raise SMCError(f"hyperparameter {key!r} must be an integer in [1, {MAX_ITERATIONS:,}], got {value!r}")
    return encoded


def constructor_arguments(hyperparameters: Mapping[str, Any]) -> tuple[str | type[ActorCriticPolicy], dict[str, Any]]:
    """``(policy, keyword arguments)`` for the algorithm's constructor from stored hyperparameters.

    ``"SequenceLstmPolicy"`` / ``"SequenceGruPolicy"`` become the classes of :mod:`sb3_smc.common.recurrent` (SB3
    only knows its own policy names); classes are imported and ``"lin_<x>"`` schedules built.
    """
    kwargs = {key: decode_value(value, key) for key, value in hyperparameters.items()}
    policy = kwargs.pop("policy")
    if policy in RECURRENT_POLICIES.values():
        from sb3_smc.common import recurrent

        policy = getattr(recurrent, policy)
    return policy, kwargs


def register_algorithm(name: str, cls: type[OnPolicyAlgorithm], *,
                       hyperparameters: Mapping[str, Any] | None = None) -> Algorithm:
    """Add a learner of your own: ``train_smc(..., algo=name)`` trains with ``cls``, and libraries save and load its
    SMCs, in this process (register it in every process that trains or loads them, before it does).

    Registering is your trust in ``cls``: a library's SMC of ``name`` is rebuilt with it without ``trust=True``,
    though its module is none of :data:`SAFE_CLASS_MODULES` (a file names the algorithm, never its module, so
    nothing is imported for it). Another class of that module that a file names (a policy of your own) still needs
    ``trust=True``. Curricula and the ``sb3-smc`` command take the built-in algorithms only (:data:`ALGORITHMS`).

    :param name: the algorithm's name in specs and manifests: a non-empty string without white space, not
        registered to another class (registering the same class again changes nothing).
    :param cls: a subclass of Stable-Baselines3's ``OnPolicyAlgorithm`` (``train_smc`` sets ``n_steps``) with an
        actor-critic policy over discrete actions (what :func:`~sb3_smc.smc.policies.policy_from_model` copies).
    :param hyperparameters: its default constructor arguments, ``policy`` among them (JSON values and classes, as
        :func:`encode_value` stores them); default: those of the nearest registered class it derives from, whose
        recurrent cells (``rnn=``) it takes in any case.
    :return: its registry entry.
    :raises SMCTypeError: a name that is not a string, or a ``cls`` that is not such a class.
    :raises SMCError: a name that is empty, has white space or is another class's, a class registered under another
        name, missing or bad defaults.
    """
    from stable_baselines3.common.on_policy_algorithm import OnPolicyAlgorithm

    if not isinstance(name, str):
        raise SMCTypeError(f"an algorithm's name must be a string, got {type(name).__name__}")
    if not name or not name.isprintable() or any(c.isspace() for c in name):
        raise SMCError(f"an algorithm's name must be a non-empty string without white space, got {name!r}")
    if not (isinstance(cls, type) and issubclass(cls, OnPolicyAlgorithm)):
        raise SMCTypeError(f"algorithm {name!r}: cls must be a subclass of stable_baselines3's OnPolicyAlgorithm, "
                           f"got {cls!r}")
    known = ALGORITHM_REGISTRY.get(name)
    if known is not None:
        if known.load_class() is cls:
            return known
        raise SMCError(f"algorithm {name!r} is registered already, to {known.class_path}; choose another name")
    other = algorithm_of(cls)
    if other is not None:
        raise SMCError(f"{cls.__qualname__} is registered already as {other!r}; use that name")
    parent = next((ALGORITHM_REGISTRY[found] for base in cls.__mro__[1:] if (found := algorithm_of(base))), None)
    if hyperparameters is not None:
        defaults = {"policy_kwargs": {}, **copy.deepcopy(dict(hyperparameters))}
        encode_value(defaults, "hyperparameters")  # JSON values and classes only
        reserved = sorted(set(defaults) & set(_RESERVED))
        if not isinstance(defaults.get("policy"), str | type) or not isinstance(defaults["policy_kwargs"], dict) \
                or reserved:
            raise SMCError(f"algorithm {name!r}: its hyperparameters need a 'policy' (a name or a class) and a "
                           f"mapping 'policy_kwargs', and none of {sorted(_RESERVED)} (train_smc sets those)")
    elif parent is not None:
        defaults = copy.deepcopy(parent.hyperparameters)
    else:
        raise SMCError(f"algorithm {name!r}: {cls.__qualname__} derives from no registered algorithm; give its "
                       "hyperparameters (its policy at least)")
    entry = Algorithm(name, f"{cls.__module__}.{cls.__qualname__}", defaults,
                      cells=parent.cells if parent is not None else (), registered=cls)
    ALGORITHM_REGISTRY[name] = entry
    DEFAULT_HYPERPARAMETERS[name] = entry.hyperparameters
    return entry
