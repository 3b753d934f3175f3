"""The learners' hyperparameters in one place (torch-free): defaults, merging, and storage as plain JSON.

:data:`DEFAULT_HYPERPARAMETERS` is the single source of the paper's settings (spec §5.2-§5.3): ``train_smc``
merges a user's overrides into it (:func:`resolve_hyperparameters`), a :class:`~sb3_smc.records.TrainingSpec`
stores the merged result, and the rl_zoo3 files in ``zoo_configs/`` are generated from it (:mod:`sb3_smc.zoo`).

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
from collections.abc import Callable, Mapping
from typing import Any

__all__ = [
    "ALGORITHMS",
    "DEFAULT_HYPERPARAMETERS",
    "DEFAULT_N_ENVS",
    "STEPS_PER_UPDATE",
    "constructor_arguments",
    "decode_value",
    "encode_value",
    "recurrent_policy",
    "resolve_hyperparameters",
]

STEPS_PER_UPDATE = 2000
"""Environment steps per policy update (the paper's batch size)."""
DEFAULT_N_ENVS = 16
"""Environments stepped together (``n_steps = STEPS_PER_UPDATE // n_envs`` each)."""

ALGORITHMS = ("RecurrentPPO", "TRPO", "PPO", "RecurrentTRPO")
"""Algorithms :func:`~sb3_smc.training.train_smc` trains."""

DEFAULT_HYPERPARAMETERS: dict[str, dict[str, Any]] = {
    "RecurrentPPO": {
        "policy": "SequenceLstmPolicy",
        "gamma": 0.99,
        "gae_lambda": 1.0,
        "batch_size": STEPS_PER_UPDATE,
        "n_epochs": 4,
        "learning_rate": 3e-3,
        "clip_range": 0.2,
        "ent_coef": 0.0,
        "policy_kwargs": {"lstm_hidden_size": 32, "n_lstm_layers": 1, "net_arch": [],
                          "shared_lstm": False, "enable_critic_lstm": False},
    },
    "TRPO": {
        "policy": "MlpPolicy",
        "gamma": 0.99,
        "gae_lambda": 1.0,
        "batch_size": STEPS_PER_UPDATE,
        "target_kl": 0.01,
        "learning_rate": 1e-3,
        "policy_kwargs": {"net_arch": {"pi": [32], "vf": [32]}},
    },
    "RecurrentTRPO": {
        "policy": "SequenceLstmPolicy",
        "gamma": 0.99,
        "gae_lambda": 1.0,
        "batch_size": STEPS_PER_UPDATE,
        "target_kl": 0.01,
        "learning_rate": 1e-3,
        "n_critic_updates": 10,
        "cg_max_steps": 15,
        "cg_damping": 0.1,
        "baseline": "critic",
        "policy_kwargs": {"lstm_hidden_size": 32, "n_lstm_layers": 1, "net_arch": [],
                          "shared_lstm": False, "enable_critic_lstm": False},
    },
    "PPO": {
        "policy": "MlpPolicy",
        "gamma": 0.99,
        "gae_lambda": 1.0,
        "batch_size": 250,
        "n_epochs": 10,
        "learning_rate": 3e-4,
        "clip_range": 0.2,
        "ent_coef": 0.0,
        "policy_kwargs": {"net_arch": {"pi": [32], "vf": [32]}},
    },
}
"""Constructor arguments of each algorithm (``n_steps`` comes from the budget: ``STEPS_PER_UPDATE // n_envs``).
Overrides replace these key by key, ``policy_kwargs`` key by key too. RecurrentPPO and TRPO are the measured
settings of ``docs/training.md``; PPO (memoryless; minibatches of 250, 10 epochs, learning rate 3e-4, the settings
of the earlier hand-written rl_zoo3 file) is offered for comparison, untuned. RecurrentTRPO
(:mod:`sb3_smc.recurrent_trpo`, the paper's learner with ``rnn="gru"``) has TRPO's trust region (KL 0.01) and
critic learning rate on RecurrentPPO's recurrent policy; ``baseline="linear_feature"`` gives spec §5.3's linear
feature baseline instead of the critic."""

RECURRENT_POLICIES = {"lstm": "SequenceLstmPolicy", "gru": "SequenceGruPolicy"}
"""``rnn`` option of ``train_smc`` -> the recurrent policy (by name) of the recurrent algorithms."""
RECURRENT_ALGORITHMS = ("RecurrentPPO", "RecurrentTRPO")


def recurrent_policy(rnn: str, algo: str | None = None) -> str:
    """The policy (by name) of the ``rnn`` option; ``ValueError`` for an unknown cell, or for ``algo`` when given and
    not recurrent."""
    if rnn not in RECURRENT_POLICIES:
        raise ValueError(f"rnn must be one of {sorted(RECURRENT_POLICIES)}, got {rnn!r}")
    if algo is not None and algo not in RECURRENT_ALGORITHMS:
        raise ValueError(f"rnn={rnn!r} needs a recurrent algorithm ({' or '.join(RECURRENT_ALGORITHMS)}); "
                         f"{algo} has no recurrence")
    return RECURRENT_POLICIES[rnn]

CLASS_KEY = "__class__"
SCHEDULE_KEYS = ("learning_rate", "clip_range")
_RESERVED = {"n_steps": "the budget's n_steps", "seed": "the spec's seed", "env": "the environment factory",
             "device": "training always runs on the CPU", "tensorboard_log": "train_smc's tensorboard_log"}


def _check_algo(algo: str) -> None:
    if algo not in ALGORITHMS:
        raise ValueError(f"algo must be one of {ALGORITHMS}, got {algo!r}")


def encode_value(value: Any, where: str) -> Any:
    """``value`` as JSON data (classes as ``{"__class__": path}``); ``ValueError`` naming ``where`` otherwise."""
    if value is None or isinstance(value, bool | str):
        return value
    if isinstance(value, int | float):
        if isinstance(value, float) and not math.isfinite(value):
            raise ValueError(f"hyperparameter {where}: {value} is not a finite number")
        return value
    if type(value).__module__ == "numpy" and hasattr(value, "item"):
        return encode_value(value.item(), where)
    if isinstance(value, type):
        path = f"{value.__module__}.{value.__qualname__}"
        if "<locals>" in path:
            raise ValueError(f"hyperparameter {where}: class {path} is defined inside a function and cannot be "
                             "imported again; define it at module level")
        return {CLASS_KEY: path}
    if isinstance(value, Mapping):
        if CLASS_KEY in value and len(value) == 1:
            return {CLASS_KEY: str(value[CLASS_KEY])}
        return {str(k): encode_value(v, f"{where}.{k}") for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [encode_value(v, f"{where}[{i}]") for i, v in enumerate(value)]
    raise ValueError(f"hyperparameter {where}: a {type(value).__name__} ({value!r}) cannot be stored in a training "
                     "spec; use JSON values, classes, or 'lin_<initial value>' for a linear schedule")


def _import_class(path: str, where: str) -> type:
    module, _, name = path.rpartition(".")
    try:
        obj: Any = importlib.import_module(module)
        for part in name.split("."):
            obj = getattr(obj, part)
    except (ImportError, AttributeError, ValueError) as err:
        raise ValueError(f"hyperparameter {where}: cannot import class {path!r} ({err})") from None
    return obj


def _linear(initial: float) -> Callable[[float], float]:
    def schedule(progress_remaining: float) -> float:
        return progress_remaining * initial

    return schedule


def decode_value(value: Any, where: str) -> Any:
    """The inverse of :func:`encode_value` (classes imported, ``"lin_<x>"`` becomes a linear schedule)."""
    if isinstance(value, Mapping):
        if set(value) == {CLASS_KEY}:
            return _import_class(value[CLASS_KEY], where)
        return {k: decode_value(v, f"{where}.{k}") for k, v in value.items()}
    if isinstance(value, list):
        return [decode_value(v, f"{where}[{i}]") for i, v in enumerate(value)]
    if isinstance(value, str) and where.split(".")[-1] in SCHEDULE_KEYS and value.startswith("lin_"):
        try:
            return _linear(float(value[4:]))
        except ValueError:
            raise ValueError(f"hyperparameter {where}: {value!r} is not 'lin_<number>'") from None
    return value


def resolve_hyperparameters(algo: str, overrides: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """``DEFAULT_HYPERPARAMETERS[algo]`` with ``overrides`` applied (``policy_kwargs`` key by key), as JSON data."""
    _check_algo(algo)
    overrides = dict(overrides or {})
    for key, why in _RESERVED.items():
        if key in overrides:
            raise ValueError(f"hyperparameter {key!r} is not set through the hyperparameters ({why})")
    resolved = copy.deepcopy(DEFAULT_HYPERPARAMETERS[algo])
    policy_kwargs = resolved.pop("policy_kwargs")
    policy_kwargs.update(overrides.pop("policy_kwargs", None) or {})
    resolved.update(overrides)
    resolved["policy_kwargs"] = policy_kwargs
    policy = resolved.get("policy")
    if not isinstance(policy, str | type):
        raise ValueError(f"hyperparameter 'policy' must be a policy name or class, got {policy!r}")
    return {key: encode_value(value, key) for key, value in resolved.items()}


def constructor_arguments(hyperparameters: Mapping[str, Any]) -> tuple[Any, dict[str, Any]]:
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
