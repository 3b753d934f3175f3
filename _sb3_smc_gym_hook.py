"""Registers the PixelWorld ``PW-*`` ids with Gymnasium as soon as Gymnasium is imported, in any program, and
sb3-smc's algorithms that rl_zoo3 lacks (``RecurrentTRPO`` as ``--algo recurrent_trpo``) as soon as rl_zoo3 is
imported.

Every install of sb3-smc (a wheel, and ``pip install -e .``, as ``make`` does) puts ``sb3_smc_gym_hook.pth`` in
site-packages; its one line imports this module at interpreter start. That costs a few microseconds: nothing is
imported here except ``importlib`` and ``os``. When a program later imports ``gymnasium``, the ids are registered
right after it (importing ``pixelworld_env``, no torch, no datasets), so ``rl_zoo3 train --env PW-...`` and
``gymnasium.make("PW-...")`` work without ``--gym-packages pixelworld_env`` or ``import pixelworld_env``. When
rl_zoo3 loads its algorithm table (``rl_zoo3.utils.ALGOS``), every rl_zoo3 name of sb3-smc's algorithm registry
(``sb3_smc.hyperparameters.ALGORITHM_REGISTRY``) that the table lacks is added to it (``recurrent_trpo``: importing
``sb3_smc.recurrent_trpo``; rl_zoo3 has already loaded torch and SB3 by then).

When Gymnasium is first imported by ``pixelworld_env`` itself (``import pixelworld_env``, the ``pixelworld`` and
``sb3-smc`` commands), the hook does nothing: the package registers the ids at the end of its own import. Set
``SB3_SMC_GYM_HOOK=0`` to switch it off. A failure while registering is reported as a warning and never breaks the
import of Gymnasium.
"""

from __future__ import annotations

import importlib.abc
import importlib.machinery
import importlib.util
import os
import sys

ENVIRONMENT_SWITCH = "SB3_SMC_GYM_HOOK"


def _register(module) -> None:
    if "pixelworld_env" in sys.modules:  # Gymnasium was imported by pixelworld_env, which registers the ids itself
        return  # at the end of its own import (registering now would import it half-initialised)
    try:
        from pixelworld_env.envs.registration import register_envs

        register_envs()
    except Exception as error:  # never break the program that imported gymnasium
        import warnings

        warnings.warn(f"sb3-smc could not register the PW-* environments ({type(error).__name__}: {error}); "
                      f"use `import pixelworld_env` (or rl_zoo3's --gym-packages pixelworld_env)", stacklevel=2)


def _add_zoo_algorithms(module) -> None:
    try:
        from sb3_smc.hyperparameters import ALGORITHM_REGISTRY

        for algorithm in ALGORITHM_REGISTRY.values():
            if algorithm.zoo_name is not None and algorithm.zoo_name not in module.ALGOS:
                module.ALGOS[algorithm.zoo_name] = algorithm.load_class()
    except Exception as error:  # never break rl_zoo3
        import warnings

        warnings.warn(f"sb3-smc could not add its algorithms to rl_zoo3 ({type(error).__name__}: {error})",
                      stacklevel=2)


_TARGETS = {"gymnasium": _register, "rl_zoo3.utils": _add_zoo_algorithms}
"""Module -> what to run right after it is imported."""


class _RunAfter(importlib.abc.Loader):
    """Runs a module's own loader, then ``after(module)``."""

    def __init__(self, loader: importlib.abc.Loader, after) -> None:
        self.loader, self.after = loader, after

    def create_module(self, spec: importlib.machinery.ModuleSpec):
        return self.loader.create_module(spec)

    def exec_module(self, module) -> None:
        self.loader.exec_module(module)
        self.after(module)


class _ImportWatcher(importlib.abc.MetaPathFinder):
    """A meta-path finder that only answers for the modules of ``_TARGETS``, once each, by wrapping the real
    spec's loader; it leaves ``sys.meta_path`` when none is left."""

    def __init__(self, pending: set[str]) -> None:
        self.pending = pending

    def find_spec(self, name: str, path=None, target=None):
        if name not in self.pending:
            return None
        self.pending.discard(name)  # also keeps the lookup below from coming back here
        if not self.pending and self in sys.meta_path:
            sys.meta_path.remove(self)
        spec = importlib.util.find_spec(name)
        if spec is not None and spec.loader is not None:
            spec.loader = _RunAfter(spec.loader, _TARGETS[name])
        return spec


def install() -> None:
    """Register the ids now if Gymnasium is loaded, else right after it is imported; the same for rl_zoo3's
    algorithm table (no-op when switched off)."""
    if os.environ.get(ENVIRONMENT_SWITCH, "1").strip().lower() in ("0", "false", "no", "off"):
        return
    if any(isinstance(finder, _ImportWatcher) for finder in sys.meta_path):
        return
    pending = set()
    for name, action in _TARGETS.items():
        if name in sys.modules:
            action(sys.modules[name])
        else:
            pending.add(name)
    if pending:
        sys.meta_path.insert(0, _ImportWatcher(pending))
