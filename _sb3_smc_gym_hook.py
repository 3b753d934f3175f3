"""Registers the PixelWorld ``PW-*`` ids with Gymnasium as soon as Gymnasium is imported, in any program.

Installed wheels of sb3-smc put ``sb3_smc_gym_hook.pth`` in site-packages; its one line imports this module at
interpreter start. That costs a few microseconds: nothing is imported here except ``importlib`` and ``os``. When a
program later imports ``gymnasium``, the ids are registered right after it (importing ``pixelworld_env``, no
torch, no datasets), so ``rl_zoo3 train --env PW-...`` and ``gymnasium.make("PW-...")`` work without
``--gym-packages pixelworld_env`` or ``import pixelworld_env``.

Set ``SB3_SMC_GYM_HOOK=0`` to switch it off. A failure while registering is reported as a warning and never
breaks the import of Gymnasium.
"""

from __future__ import annotations

import importlib.abc
import importlib.machinery
import importlib.util
import os
import sys

ENVIRONMENT_SWITCH = "SB3_SMC_GYM_HOOK"
_TARGET = "gymnasium"


def _register() -> None:
    try:
        from pixelworld_env.registration import register_envs

        register_envs()
    except Exception as error:  # never break the program that imported gymnasium
        import warnings

        warnings.warn(f"sb3-smc could not register the PW-* environments ({type(error).__name__}: {error}); "
                      f"use `import pixelworld_env` (or rl_zoo3's --gym-packages pixelworld_env)", stacklevel=2)


class _RegisterAfter(importlib.abc.Loader):
    """Runs Gymnasium's own loader, then registers the ids."""

    def __init__(self, loader: importlib.abc.Loader) -> None:
        self.loader = loader

    def create_module(self, spec: importlib.machinery.ModuleSpec):
        return self.loader.create_module(spec)

    def exec_module(self, module) -> None:
        self.loader.exec_module(module)
        _register()


class _GymnasiumWatcher(importlib.abc.MetaPathFinder):
    """A meta-path finder that only answers for ``gymnasium``, once, by wrapping the real spec's loader."""

    def find_spec(self, name: str, path=None, target=None):
        if name != _TARGET:
            return None
        if self in sys.meta_path:
            sys.meta_path.remove(self)
        spec = importlib.util.find_spec(name)
        if spec is not None and spec.loader is not None:
            spec.loader = _RegisterAfter(spec.loader)
        return spec


def install() -> None:
    """Register the ids now if Gymnasium is loaded, else right after it is imported (no-op when switched off)."""
    if os.environ.get(ENVIRONMENT_SWITCH, "1").strip().lower() in ("0", "false", "no", "off"):
        return
    if _TARGET in sys.modules:
        _register()
    elif not any(isinstance(finder, _GymnasiumWatcher) for finder in sys.meta_path):
        sys.meta_path.insert(0, _GymnasiumWatcher())
