"""rl_zoo3 integration: the hyperparameter files of ``zoo_configs/`` (generated from
:data:`~sb3_smc.hyperparameters.DEFAULT_HYPERPARAMETERS`) and the ``env_wrapper`` entry :func:`smc_env`.

Regenerate the files after changing the defaults: ``python -m sb3_smc.zoo zoo_configs`` (a test checks that the
shipped files equal what this module writes).
"""

from __future__ import annotations

import argparse
import functools
import textwrap
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import yaml

from sb3_smc.hyperparameters import DEFAULT_HYPERPARAMETERS, DEFAULT_N_ENVS, STEPS_PER_UPDATE
from sb3_smc.records import WrapperSettings

__all__ = ["ZOO_ALGOS", "ZOO_POLICY_NAMES", "render_config", "smc_env", "write_configs"]

ZOO_ALGOS = {"ppo_lstm": "RecurrentPPO", "trpo": "TRPO", "ppo": "PPO"}
"""rl_zoo3's ``--algo`` name -> the algorithm of :data:`DEFAULT_HYPERPARAMETERS`."""
ZOO_POLICY_NAMES = {"SequenceLstmPolicy": "MlpLstmPolicy"}
"""Policies rl_zoo3 cannot name (it passes the string to SB3) -> the stock policy computing the same numbers."""
ENV_WRAPPER = "sb3_smc.zoo.smc_env"

_NOTES = {
    "ppo_lstm": "RecurrentPPO: one 32-unit LSTM (the paper's GRU-32 size) with the action layer directly on it and a "
                "critic linear in the observation. train_smc uses SequenceLstmPolicy, a faster subclass of "
                "MlpLstmPolicy with the same numbers; rl_zoo3 can only name SB3's own policies.",
    "trpo": "TRPO: one hidden layer of 32 tanh units for actor and critic, KL step 0.01 (the paper's NPO step size).",
    "ppo": "PPO: one hidden layer of 32 tanh units for actor and critic (memoryless).",
}


def _python(value: Any) -> str:
    """``value`` as the Python expression rl_zoo3 evaluates for ``policy_kwargs``."""
    if isinstance(value, dict):
        if set(value) == {"__class__"}:
            return value["__class__"]
        return "dict(" + ", ".join(f"{k}={_python(v)}" for k, v in value.items()) + ")"
    if isinstance(value, list):
        return "[" + ", ".join(_python(v) for v in value) + "]"
    return repr(value)


def _yaml_scalar(value: Any) -> str:
    if isinstance(value, float):
        return f"!!float {value!r}" if "e" in repr(value) else repr(value)
    return yaml.safe_dump(value, default_flow_style=True).strip().removesuffix("...").strip()


def render_config(zoo_algo: str) -> str:
    """The text of ``zoo_configs/<zoo_algo>.yml``."""
    algo = ZOO_ALGOS[zoo_algo]
    hyper = dict(DEFAULT_HYPERPARAMETERS[algo])
    policy_kwargs = hyper.pop("policy_kwargs")
    policy = ZOO_POLICY_NAMES.get(hyper.pop("policy"), DEFAULT_HYPERPARAMETERS[algo]["policy"])
    lines = [
        f"# rl_zoo3 hyperparameters for {algo} on PixelWorld (PW-*) environments.",
        "# Generated from sb3_smc.hyperparameters.DEFAULT_HYPERPARAMETERS by `python -m sb3_smc.zoo zoo_configs`;",
        "# do not edit by hand (tests/test_zoo.py checks the file equals what the generator writes).",
        "#",
        f"#   python -m rl_zoo3.train --algo {zoo_algo} --env PW-cl_self-in-left-corner_vs_on-hline-v0 \\",
        f"#       --gym-packages pixelworld_env -conf zoo_configs/{zoo_algo}.yml --num-threads 1",
        "#",
        *textwrap.wrap(_NOTES[zoo_algo], 114, initial_indent="# ", subsequent_indent="# "),
        f"# The paper's batch (spec §5.3): {DEFAULT_N_ENVS} envs x {STEPS_PER_UPDATE // DEFAULT_N_ENVS} steps = "
        f"{STEPS_PER_UPDATE:,} steps per update, 400k steps.",
        f"# {ENV_WRAPPER} puts the env in sb3_smc's HierarchicalSMCWrapper (without SMCs unless `library` and `names`",
        "# are given), so the policy sees what an SMC sees and the trained model goes into an SMCLibrary.",
        "# Not reproduced by rl_zoo3: the initial action distribution of spec §5.2 and the best-update selection of",
        "# spec §5.4 (sb3_smc.train_smc does both). rl_zoo3 looks up the exact env id first, then `default`.",
        "default:",
        f"  env_wrapper: {ENV_WRAPPER}",
        f"  n_envs: {DEFAULT_N_ENVS}",
        "  n_timesteps: !!float 4e5",
        f"  policy: {policy}",
        f"  n_steps: {STEPS_PER_UPDATE // DEFAULT_N_ENVS}",
    ]
    lines += [f"  {key}: {_yaml_scalar(value)}" for key, value in hyper.items()]
    lines += ["  normalize: false", f"  policy_kwargs: \"{_python(policy_kwargs)}\""]
    return "\n".join(lines) + "\n"


def write_configs(directory: str | Path) -> list[Path]:
    """Write every ``<zoo_algo>.yml`` into ``directory``; returns the paths."""
    from pixelworld_env.atomic import atomic_write

    return [atomic_write(Path(directory) / f"{zoo_algo}.yml", render_config(zoo_algo)) for zoo_algo in ZOO_ALGOS]


@functools.lru_cache(maxsize=8)
def _library(path: str) -> Any:
    from sb3_smc.library import SMCLibrary

    return SMCLibrary.load(path)


def smc_env(env: Any, library: str | None = None, names: Sequence[str] = (), include_primitives: bool = True,
            count_primitive_steps: bool = False, call_step_cap: int = 100) -> Any:
    """rl_zoo3 ``env_wrapper`` entry: ``env`` with the SMCs ``names`` of the library at ``library`` as actions.

    Without ``library`` the env gets no SMC actions: a flat SMC's layout (window, previous action). The library is
    loaded once per process and path.
    """
    from sb3_smc.envs import wrap_with_smcs

    if names and library is None:
        raise ValueError(f"smc_env: names {list(names)} given without the library they come from")
    smcs = [_library(str(library))[name] for name in names] if library is not None else []
    settings = WrapperSettings(include_primitives=include_primitives, count_primitive_steps=count_primitive_steps,
                               call_step_cap=call_step_cap)
    return wrap_with_smcs(env, smcs, settings)


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description="Write the rl_zoo3 hyperparameter files (zoo_configs/*.yml).")
    parser.add_argument("directory", nargs="?", default="zoo_configs")
    args = parser.parse_args(argv)
    for path in write_configs(args.directory):
        print(f"wrote {path}")


if __name__ == "__main__":
    main()
