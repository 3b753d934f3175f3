"""Registers the PixelWorld ``PW-*`` ids with Gymnasium as soon as Gymnasium is imported, in any program, and
sb3-smc's algorithms that rl_zoo3 lacks (``RecurrentTRPO`` as ``--algo recurrent_trpo``) as soon as rl_zoo3 is
imported.

Every install of sb3-smc (a wheel, and ``pip install -e .``, as ``make`` does) puts ``sb3_smc_gym_hook.pth`` in
site-packages; its one line imports this module at interpreter start, in every Python process of that environment.
So this module does nothing at start but put one small finder first on ``sys.meta_path``: it imports nothing (only
``os`` and ``sys``, which the interpreter has loaded before any ``.pth`` line runs; not ``importlib.abc``, which
alone pulls in ``importlib.resources``, ``tempfile``, ``shutil``, ``random`` and ``typing``), and the finder answers
every other import with one set look-up. Measured in docs/architecture.md ("The start-up hook").

When a program later imports ``gymnasium``, the ids are registered right after it (importing ``pixelworld_env``, no
torch, no datasets), so ``rl_zoo3 train --env PW-...`` and ``gymnasium.make("PW-...")`` work without
``--gym-packages pixelworld_env`` or ``import pixelworld_env``. When rl_zoo3 loads its algorithm table
(``rl_zoo3.utils.ALGOS``), every rl_zoo3 name of sb3-smc's algorithm registry
(``sb3_smc.core.hyperparameters.ALGORITHM_REGISTRY``) that the table lacks is added to it (``recurrent_trpo``: importing
``sb3_smc.recurrent_trpo``; rl_zoo3 has already loaded torch and SB3 by then). Once both have been imported, the
finder leaves ``sys.meta_path``; a program that imports neither runs no code of sb3-smc beyond that look-up.

When Gymnasium is first imported by ``pixelworld_env`` itself (``import pixelworld_env``, the ``pixelworld`` and
``sb3-smc`` commands), the hook does nothing: the package registers the ids at the end of its own import. Set
``SB3_SMC_GYM_HOOK=0`` to switch it off. A failure while registering is reported as a warning and never breaks the
import of Gymnasium.
"""

import os  # no `from __future__ import annotations`: that imports the module __future__
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
        from sb3_smc.core.hyperparameters import ALGORITHM_REGISTRY

        for algorithm in ALGORITHM_REGISTRY.values():
            if algorithm.zoo_name is not None and algorithm.zoo_name not in module.ALGOS:
                module.ALGOS[algorithm.zoo_name] = algorithm.load_class()
    except Exception as error:  # never break rl_zoo3
        import warnings

        warnings.warn(f"sb3-smc could not add its algorithms to rl_zoo3 ({type(error).__name__}: {error})",
                      stacklevel=2)


_TARGETS = {"gymnasium": _register, "rl_zoo3.utils": _add_zoo_algorithms}
"""Module -> what to run right after it is imported."""


class _RunAfter:
    """A loader (``importlib.abc.Loader``'s protocol, not its class) that runs a module's own loader, then
    ``after(module)``. The module is given back its own loader before it runs, so that ``__loader__`` and
    ``__spec__.loader`` are the real one (``importlib.resources``, ``inspect`` and ``pkgutil`` read them)."""

    def __init__(self, loader, after) -> None:
        self.loader, self.after = loader, after

    def create_module(self, spec):
        return self.loader.create_module(spec)

    def exec_module(self, module) -> None:
        module.__loader__ = self.loader
        if module.__spec__ is not None:
            module.__spec__.loader = self.loader
        self.loader.exec_module(module)
        self.after(module)


class _ImportWatcher:
    """A meta-path finder (``importlib.abc.MetaPathFinder``'s protocol, not its class) that only answers for the
    modules of ``_TARGETS``, once each, with the spec the finders after it give, its loader wrapped; every other
    import gets ``None`` after one set look-up. It leaves ``sys.meta_path`` when none is left."""

    def __init__(self, pending: set[str]) -> None:
        self.pending = pending

    def find_spec(self, name: str, path=None, target=None):
        if name not in self.pending:
            return None
        self.pending.discard(name)
        if not self.pending and self in sys.meta_path:
            sys.meta_path.remove(self)
        for finder in list(sys.meta_path):  # what the import system would ask next, as it would ask them
            find = getattr(finder, "find_spec", None)
            if finder is self or find is None:
                continue
            spec = find(name, path, target)
            if spec is not None:
                if spec.loader is not None and hasattr(spec.loader, "exec_module"):
                    spec.loader = _RunAfter(spec.loader, _TARGETS[name])
                return spec
        return None


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
