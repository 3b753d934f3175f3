"""Bring a model trained by rl_zoo3 into an :class:`~sb3_smc.library.SMCLibrary` (``sb3-smc import-zoo``)."""

from __future__ import annotations

import importlib
import os
from pathlib import Path
from typing import Any

import yaml

from sb3_smc.core.hyperparameters import ALGORITHM_REGISTRY
from sb3_smc.errors import SMCError
from sb3_smc.zoo.configs import ENV_WRAPPER, ZOO_ALGOS

__all__ = ["ZooRunError", "import_zoo_model", "read_zoo_run"]


class ZooRunError(SMCError):
    """A zoo run directory that cannot become an SMC (what is wrong, in which file, and what to do)."""


class _ZooLoader(yaml.SafeLoader):
    """rl_zoo3 writes its ``args.yml`` / ``config.yml`` as ``OrderedDict`` objects; read those as dicts and nothing
    else (no arbitrary Python objects)."""


_ZooLoader.add_constructor("tag:yaml.org,2002:python/object/apply:collections.OrderedDict",
                           lambda loader, node: dict(loader.construct_sequence(node, deep=True)[0]))


def _read(path: Path) -> dict[str, Any]:
    try:
        data = yaml.load(path.read_text(encoding="utf-8"), Loader=_ZooLoader)  # noqa: S506 (safe loader subclass)
    except OSError as error:
        raise ZooRunError(f"{path}: cannot read the zoo's saved settings ({error.strerror or error})") from None
    except (UnicodeDecodeError, yaml.YAMLError) as error:
        raise ZooRunError(f"{path}: the zoo's saved settings are not YAML rl_zoo3 wrote ({error})") from None
    if not isinstance(data, dict):
        raise ZooRunError(f"{path}: expected a mapping of settings, got {type(data).__name__}")
    return data


def read_zoo_run(run_dir: str | os.PathLike) -> tuple[dict[str, Any], dict[str, Any]]:
    """``(args, hyperparameters)`` a zoo run saved in ``RUN_DIR/<env id>/args.yml`` and ``config.yml``."""
    run = Path(run_dir)
    if not run.is_dir():
        raise ZooRunError(f"{run}: not a directory (expected an rl_zoo3 run such as logs/trpo/PW-...-v0_1)")
    found = sorted(p.parent for p in run.glob("*/config.yml") if (p.parent / "args.yml").is_file())
    if len(found) != 1:
        raise ZooRunError(f"{run}: expected one <env id>/ folder with args.yml and config.yml (an rl_zoo3 run "
                          f"directory), found {[p.name for p in found]}")
    return _read(found[0] / "args.yml"), _read(found[0] / "config.yml")


def _wrapper_kwargs(config: dict[str, Any], where: Path, zoo_algo: str) -> dict[str, Any]:
    wrappers = config.get("env_wrapper")
    entries = wrappers if isinstance(wrappers, list) else [wrappers] if wrappers is not None else []
    for entry in entries:
        if entry == ENV_WRAPPER:
            return {}
        if isinstance(entry, dict) and ENV_WRAPPER in entry:
            return dict(entry[ENV_WRAPPER] or {})
    raise ZooRunError(
        f"{where}: the run did not use sb3-smc's wrapper (env_wrapper: {wrappers!r}), so its model sees the bare "
        f"PixelWorld observation, not an SMC's (window, outcomes, previous action), and cannot be called as an SMC; "
        f"train it with `-conf sb3_smc.zoo.{zoo_algo}` (or env_wrapper: {ENV_WRAPPER} in your own configuration)")


def _load_model(path: Path, algo: str) -> Any:
    """The zoo's model file ``path`` loaded as ``algo``; :class:`ZooRunError` saying whether the file cannot be read
    (an ``OSError``: not allowed, unreadable) or is no model archive of ``algo`` (corrupt, truncated, another kind)."""
    cls = ALGORITHM_REGISTRY[algo].load_class()
    try:
        return cls.load(path, device="cpu")
    except OSError as err:
        raise ZooRunError(f"{path}: cannot read the zoo's model file ({err.strerror or err})") from None
    except Exception as err:  # noqa: BLE001 - SB3 raises many kinds of errors for a bad archive
        raise ZooRunError(f"{path}: not a {algo} model archive (corrupt or truncated?): {type(err).__name__}: "
                          f"{err}") from None


def import_zoo_model(run_dir: str | os.PathLike, library: str | os.PathLike, *, name: str | None = None,
                     model_file: str = "final", save: bool = True) -> Any:
    """Load the model of an rl_zoo3 run and add it to the library at ``library`` as an SMC; returns the SMC.

    ``run_dir`` is the zoo's run directory (``logs/<algo>/<env id>_<n>``); ``model_file`` is ``"final"`` (the
    zoo's ``<env id>.zip``) or ``"best"`` (``best_model.zip`` of its evaluation callback). The SMC is named ``name``
    (default: the dataset name of the env id) and calls the SMCs the run had as actions (``smc_env``'s ``library`` /
    ``names``): they are added too when the library lacks them, and must be the same SMCs when it has them. The
    library is created when ``library`` does not exist, and saved atomically (``save=False``: not saved). An
    imported SMC has no training spec (the zoo's run is its record): evaluate it with an explicit env id.
    """
    from sb3_smc.library import SMCLibrary
    from sb3_smc.records import TaskSpec, smc_name_from_env_id
    from sb3_smc.smc.policies import FrameStackPolicy, policy_from_model
    from sb3_smc.smc.smc import SMC

    run = Path(run_dir)
    args, config = read_zoo_run(run)
    env_id, zoo_algo = args.get("env"), args.get("algo")
    where = run / str(env_id) / "config.yml"
    if zoo_algo not in ZOO_ALGOS:
        raise ZooRunError(f"{run}: trained with --algo {zoo_algo!r}; an SMC's model is one of "
                          f"{sorted(ZOO_ALGOS)} ({', '.join(ZOO_ALGOS.values())})")
    if config.get("normalize"):
        raise ZooRunError(f"{where}: the run normalised observations or rewards (normalize: {config['normalize']!r}); "
                          f"an SMC's policy reads raw observations: train without normalize")
    kwargs = _wrapper_kwargs(config, where, zoo_algo)
    names = list(kwargs.get("names") or ())
    if names and kwargs.get("library") is None:
        raise ZooRunError(f"{where}: smc_env names {names} without the library they come from")
    files = {"final": run / f"{env_id}.zip", "best": run / "best_model.zip"}
    if model_file not in files:
        raise SMCError(f"model_file must be 'final' or 'best', got {model_file!r}")
    path = files[model_file]
    if path.exists() and not path.is_file():
        raise ZooRunError(f"{path}: the zoo's {model_file} model is not a file (a folder in its place?)")
    if not path.is_file():
        raise ZooRunError(f"{path}: no {model_file} model in the zoo run (have: "
                          f"{sorted(p.name for p in run.glob('*.zip'))})")
    model = _load_model(path, ZOO_ALGOS[zoo_algo])
    for package in args.get("gym_packages") or ():  # what registered the run's env id (--gym-packages)
        importlib.import_module(package)
    task = TaskSpec(str(env_id)).resolved()
    if task.kind is None:
        raise ZooRunError(f"{run}: {env_id!r} is not an SMC task (a PW-* environment, or an sb3_smc.tasks.task.SMCTask "
                          "registered by one of the run's --gym-packages)")
    children = tuple(SMCLibrary.load(kwargs["library"], names=names)[n] for n in names) if names else ()
    policy = policy_from_model(model)
    stack = int(config.get("frame_stack") or 1)
    include_primitives = bool(kwargs.get("include_primitives", True))
    smc = SMC(name or smc_name_from_env_id(str(env_id)), task.kind, policy, children=children,
              include_primitives=include_primitives, model=model, layout=task.smc_layout)
    if stack > 1:
        smc.policy = FrameStackPolicy(policy, stack, smc.observation_size)
    target = Path(library)
    lib = SMCLibrary.load(target) if (target / "manifest.json").exists() else SMCLibrary(path=target)
    stored = lib.add(smc)
    if save:
        lib.save(target)
    return stored
