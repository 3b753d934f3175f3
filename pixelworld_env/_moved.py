"""The module paths of ``pixelworld_env`` before its sub-packages (2026-11-25, ``fc6e2e9``), kept for one release.

Each old module is a shim at its old path that re-exports the new module's public names and warns once, at import,
with a ``DeprecationWarning`` naming the new path. The old ``datasets`` and ``generation`` modules share their paths
with the sub-packages now: their names resolve from the package (its ``__getattr__``), with the warning, on first use.
"""

from __future__ import annotations

import importlib
import sys
import warnings
from typing import Any

MODULES: dict[str, str] = {f"pixelworld_env.{old}": f"pixelworld_env.{new}" for old, new in (
    ("catalog", "datasets.catalog"),
    ("constants", "core.constants"),
    ("csp", "generation.csp"),
    ("dataset_spec", "generation.dataset_spec"),
    ("definitions", "generation.definitions"),
    ("env", "envs.env"),
    ("experiment_files", "generation.experiment_files"),
    ("kernels", "core.kernels"),
    ("loading", "datasets.loading"),
    ("objects", "core.objects"),
    ("oracle", "generation.oracle"),
    ("placement", "generation.placement"),
    ("regions", "core.regions"),
    ("registration", "envs.registration"),
    ("render", "core.render"),
    ("sampling", "generation.sampling"),
    ("scene", "core.scene"),
    ("shapes", "core.shapes"),
    ("vector", "envs.vector"),
    ("world", "core.world"),
)}
"""Old module path -> the module its content moved to."""

_CACHE = "pixelworld_env.datasets.cache"
_GENERATION = "pixelworld_env.generation."
NAMES: dict[str, dict[str, str]] = {
    "pixelworld_env.datasets": dict.fromkeys(("CACHE_ENV", "FORMAT_VERSION", "CacheWarning", "DatasetCache",
                                              "cache_dir", "cache_key", "load_or_generate"), _CACHE),
    "pixelworld_env.generation": {
        **dict.fromkeys(("GENERATOR_VERSION", "GeneratedDataset", "GeneratorStats", "generate", "split"),
                        _GENERATION + "dataset"),
        **dict.fromkeys(("KINDS", "DatasetSpec"), _GENERATION + "dataset_spec"),
        **dict.fromkeys(("COLORS", "NUM_SHAPE_IDX", "GenerationError"), _GENERATION + "sampling"),
        "library_object": _GENERATION + "placement",
    },
}
"""The public names of the old modules ``datasets`` and ``generation`` (paths of packages now) -> their modules."""


def warn_moved(old: str) -> None:
    """The warning of the shim module ``old``, attributed to the import that loads it."""
    warn_module_moved(old, MODULES[old])


def warn_module_moved(old: str, new: str) -> None:
    """The warning of a shim module at ``old`` whose content moved to ``new``, attributed to the import that loads
    the shim (called by a package's ``warn_moved``, itself called by the shim; ``sb3_smc._moved`` uses it too)."""
    warnings.warn(f"{old} moved to {new}: import {new} instead ({old} is deprecated and goes in the next release)",
                  DeprecationWarning, stacklevel=4)


def moved_name(package: str, name: str) -> Any:
    """``package.name`` for a name of the old module at ``package``'s path: the object from its new module, with the
    warning (once: the package keeps the name); ``AttributeError`` for any other name."""
    home = NAMES[package].get(name)
    if home is None:
        raise AttributeError(f"module {package!r} has no attribute {name!r}")
    warnings.warn(f"{package}.{name} moved to {home}: import it from {home} ({package}.{name} is deprecated and goes "
                  "in the next release)", DeprecationWarning, stacklevel=3)
    value = getattr(importlib.import_module(home), name)
    setattr(sys.modules[package], name, value)
    return value
