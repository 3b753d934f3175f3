"""The module paths of ``sb3_smc`` before its stage sub-packages (2026-11-27), kept for one release.

Each old module is a shim at its old path that re-exports the new module's public names and warns once, at import,
with a ``DeprecationWarning`` naming the new path (as :mod:`pixelworld_env._moved` does for ``pixelworld_env``). The
old modules ``envs``, ``smc`` and ``tasks`` share their paths with the sub-packages now (:data:`PACKAGES`): those
packages re-export the old module's names themselves, without a warning, so ``from sb3_smc.envs import make_smc_env``
stays a path of its own. ``sb3_smc.training`` also keeps ``SequenceLstmPolicy``, the class path that models saved by
sb3-smc 0.1 pickled.
"""

from __future__ import annotations

from pixelworld_env._moved import warn_module_moved

MODULES: dict[str, str] = {f"sb3_smc.{old}": f"sb3_smc.{new}" for old, new in (
    ("batched", "learning.batched"),
    ("bias", "learning.bias"),
    ("callbacks", "learning.callbacks"),
    ("dag", "core.dag"),
    ("envs", "envs.factory"),
    ("evaluation", "learning.evaluation"),
    ("features", "learning.features"),
    ("gymnasium_vec_env", "envs.gymnasium_vec_env"),
    ("hyperparameters", "core.hyperparameters"),
    ("layout", "core.layout"),
    ("numpy_actors", "smc.numpy_actors"),
    ("policies", "smc.policies"),
    ("resolved_task", "tasks.resolved_task"),
    ("smc", "smc.smc"),
    ("smc_step", "envs.smc_step"),
    ("tasks", "tasks.task"),
    ("training", "learning.training"),
    ("vec_env", "envs.vec_env"),
    ("wrapper", "envs.wrapper"),
)}
"""Old module path -> the module its content moved to."""

PACKAGES = frozenset({"sb3_smc.envs", "sb3_smc.smc", "sb3_smc.tasks"})
"""The old modules whose paths are sub-packages now: each re-exports its old module's names, without a warning."""


def warn_moved(old: str) -> None:
    """The warning of the shim module ``old``, attributed to the import that loads it (pixelworld_env's message)."""
    warn_module_moved(old, MODULES[old])
