"""The rl_zoo3 hyperparameters of PW-* environments, generated from the algorithm registry
(:data:`~sb3_smc.core.hyperparameters.ALGORITHM_REGISTRY`): the files of ``zoo_configs/`` and the conf modules
``sb3_smc.zoo.<zoo name>`` (``trpo``, ``ppo``, ``ppo_lstm``, ``recurrent_trpo``).

Regenerate the files after changing the defaults: ``python -m sb3_smc.zoo zoo_configs`` (a test checks that the
shipped files equal what this module writes).
"""

from __future__ import annotations

import textwrap
from pathlib import Path
from typing import Any

import yaml

from pixelworld_env.atomic import atomic_write
from sb3_smc.core.hyperparameters import ALGORITHM_REGISTRY, DEFAULT_N_ENVS, DEFAULT_TIMESTEPS, STEPS_PER_UPDATE
from sb3_smc.errors import SMCError

__all__ = ["CALLBACK", "ENV_WRAPPER", "ZOO_ALGOS", "ZOO_POLICY_NAMES", "hyperparams_for", "render_config",
           "write_configs"]

ZOO_ALGOS = {algo.zoo_name: name for name, algo in ALGORITHM_REGISTRY.items() if algo.zoo_name is not None}
"""rl_zoo3's ``--algo`` name -> the algorithm (:attr:`~sb3_smc.core.hyperparameters.Algorithm.zoo_name`)."""
ZOO_POLICY_NAMES = {"SequenceLstmPolicy": "MlpLstmPolicy"}
"""Policies rl_zoo3 cannot name (it passes the string to SB3) -> the stock policy computing the same numbers."""
ENV_WRAPPER = "sb3_smc.zoo.smc_env"
CALLBACK = "sb3_smc.zoo.SMCZooCallback"


def _python(value: Any) -> str:
    """``value`` as the Python expression rl_zoo3 evaluates for ``policy_kwargs``."""
    if isinstance(value, dict):
        if set(value) == {"__class__"}:
            return value["__class__"]
        return "dict(" + ", ".join(f"{k}={_python(v)}" for k, v in value.items()) + ")"
    if isinstance(value, list):
        return "[" + ", ".join(_python(v) for v in value) + "]"
    return repr(value)


def _short_float(value: float) -> str:
    """``value`` in the shortest scientific notation, as rl_zoo3's files write step counts (``4e5``)."""
    mantissa, exponent = f"{value:e}".split("e")
    return f"{float(mantissa):g}e{int(exponent)}"


def _yaml_scalar(value: Any) -> str:
    if isinstance(value, float):
        return f"!!float {value!r}" if "e" in repr(value) else repr(value)
    return yaml.safe_dump(value, default_flow_style=True).strip().removesuffix("...").strip()


def render_config(zoo_algo: str) -> str:
    """The text of ``zoo_configs/<zoo_algo>.yml``."""
    algorithm = ALGORITHM_REGISTRY[ZOO_ALGOS[zoo_algo]]
    hyper = dict(algorithm.hyperparameters)
    policy_kwargs = hyper.pop("policy_kwargs")
    policy = ZOO_POLICY_NAMES.get(hyper.pop("policy"), algorithm.hyperparameters["policy"])
    lines = [
        f"# rl_zoo3 hyperparameters for {algorithm.name} on PixelWorld (PW-*) environments.",
        "# Generated from sb3_smc.core.hyperparameters.DEFAULT_HYPERPARAMETERS by `python -m sb3_smc.zoo zoo_configs`;",
        "# do not edit by hand (tests/test_zoo.py checks the file equals what the generator writes).",
        "#",
        f"#   rl_zoo3 train --algo {zoo_algo} --env PW-cl_self-in-left-corner_vs_on-hline-v0 \\",
        f"#       -conf sb3_smc.zoo.{zoo_algo}   (the same settings as this file; or -conf zoo_configs/{zoo_algo}.yml)",
        "#",
        *textwrap.wrap(algorithm.zoo_note, 114, initial_indent="# ", subsequent_indent="# "),
        f"# The paper's batch: {DEFAULT_N_ENVS} envs x {STEPS_PER_UPDATE // DEFAULT_N_ENVS} steps = "
        f"{STEPS_PER_UPDATE:,} steps per update, {DEFAULT_TIMESTEPS // 1000}k steps.",
        f"# {ENV_WRAPPER} puts the env in sb3_smc's HierarchicalSMCWrapper (without SMCs unless `library` and `names`",
        "# are given), so the policy sees what an SMC sees and the trained model goes into an SMCLibrary;",
        f"# {CALLBACK} writes the smc/ and smc_calls/ TensorBoard curves.",
        "# Not reproduced by rl_zoo3: the initial action distribution (signal bias) and the best-update selection",
        "# (sb3_smc.train_smc does both; docs/design.md). rl_zoo3 looks up the exact env id first, then `default`.",
        "default:",
        f"  env_wrapper: {ENV_WRAPPER}",
        f"  callback: {CALLBACK}",
        f"  n_envs: {DEFAULT_N_ENVS}",
        f"  n_timesteps: !!float {_short_float(DEFAULT_TIMESTEPS)}",
        f"  policy: {policy}",
        f"  n_steps: {STEPS_PER_UPDATE // DEFAULT_N_ENVS}",
    ]
    lines += [f"  {key}: {_yaml_scalar(value)}" for key, value in hyper.items()]
    lines += ["  normalize: false", f"  policy_kwargs: \"{_python(policy_kwargs)}\""]
    return "\n".join(lines) + "\n"


def write_configs(directory: str | Path) -> list[Path]:
    """Write every ``<zoo_algo>.yml`` into ``directory``; returns the paths."""
    return [atomic_write(Path(directory) / f"{zoo_algo}.yml", render_config(zoo_algo)) for zoo_algo in ZOO_ALGOS]


def hyperparams_for(zoo_algo: str) -> dict[str, Any]:
    """What ``-conf sb3_smc.zoo.<zoo_algo>`` gives rl_zoo3: ``{"default": <the shipped file's settings>}`` (rl_zoo3
    uses ``default`` for every env id that has no entry of its own, so every PW-* id gets them)."""
    if zoo_algo not in ZOO_ALGOS:
        raise SMCError(f"no shipped rl_zoo3 configuration for --algo {zoo_algo!r} (have: {sorted(ZOO_ALGOS)})")
    return yaml.safe_load(render_config(zoo_algo))
