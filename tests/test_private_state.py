"""The private state of Stable-Baselines3 and sb3-contrib that :mod:`sb3_smc.learning.batched` reads and writes
(it runs their rollout loop cut at the environment step): every attribute is there, of the layout it writes, in the
installed versions, and those are inside ``pyproject.toml``'s pins. A failure names the attribute and the version:
a new SB3 release moved it, so ``batched.py`` (and the pin) must follow."""

from __future__ import annotations

import inspect
import tomllib
from collections import deque
from importlib.metadata import version
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from packaging.requirements import Requirement
from sb3_contrib.common.recurrent.type_aliases import RNNStates

from sb3_smc.learning.training import untrained_smc

ROOT = Path(__file__).resolve().parents[1]
FLAT = "PW-cl_self-in-left-corner_vs_on-hline-v0"
N_ENVS, N_STEPS = 2, 8
VERSIONS = f"stable-baselines3 {version('stable-baselines3')}, sb3-contrib {version('sb3-contrib')}"

MODEL_STATE = {"_last_obs": np.ndarray, "_last_episode_starts": np.ndarray, "_last_lstm_states": RNNStates,
               "ep_info_buffer": deque, "ep_success_buffer": deque, "num_timesteps": int, "n_envs": int,
               "n_steps": int, "gamma": float}
"""The model's attributes ``batched.py`` reads and writes after ``_setup_learn``, and their types."""
MODEL_METHODS = {"_setup_learn": ("total_timesteps", "callback", "reset_num_timesteps", "tb_log_name", "progress_bar"),
                 "_update_info_buffer": ("infos", "dones"),
                 "_update_current_progress_remaining": ("num_timesteps", "total_timesteps"),
                 "dump_logs": ("iteration",), "train": ()}
"""The model's methods it calls, with their parameters in the order it passes them."""
BUFFER_ARRAYS = {"observations": (N_STEPS, N_ENVS, None), "actions": (N_STEPS, N_ENVS, 1),
                 "rewards": (N_STEPS, N_ENVS), "episode_starts": (N_STEPS, N_ENVS), "values": (N_STEPS, N_ENVS),
                 "log_probs": (N_STEPS, N_ENVS), "hidden_states_pi": (N_STEPS, 1, N_ENVS, None),
                 "hidden_states_vf": (N_STEPS, 1, N_ENVS, None), "cell_states_pi": (N_STEPS, 1, N_ENVS, None),
                 "cell_states_vf": (N_STEPS, 1, N_ENVS, None)}
"""The rollout buffer's arrays it writes a step into (``None``: any size), with ``pos``, ``full`` and
``buffer_size``."""


def _missing(what: str, name: str) -> str:
    return (f"{what} has no {name} under {VERSIONS}: sb3_smc.learning.batched relies on it; follow the change there "
            "and in pyproject.toml's pins")


@pytest.fixture(scope="module", params=["RecurrentPPO", "RecurrentTRPO"])
def model(request: pytest.FixtureRequest) -> Any:
    """A model of each learner ``train_smcs`` groups, built as ``train_smc`` builds it, after ``learn``'s set-up."""
    model = untrained_smc(FLAT, algo=request.param, n_envs=N_ENVS, n_steps=N_STEPS).model
    model._setup_learn(N_STEPS * N_ENVS, None, True, "private-state", False)
    return model


def test_the_model_state_batched_relies_on_is_there(model: Any) -> None:
    what = type(model).__name__
    for name, kind in MODEL_STATE.items():
        assert hasattr(model, name), _missing(what, name)
        assert isinstance(getattr(model, name), kind), \
            f"{what}.{name} is a {type(getattr(model, name)).__name__}, not a {kind.__name__}, under {VERSIONS}"
    for name, parameters in MODEL_METHODS.items():
        assert callable(getattr(model, name, None)), _missing(what, f"method {name}")
        have = tuple(inspect.signature(getattr(model, name)).parameters)
        assert have[:len(parameters)] == parameters, \
            f"{what}.{name} takes {have} under {VERSIONS}, where batched.py passes {parameters}"


def test_the_rollout_buffer_state_batched_writes_is_there(model: Any) -> None:
    buffer = model.rollout_buffer
    what = type(buffer).__name__
    buffer.reset()
    for name in ("pos", "full", "buffer_size"):
        assert hasattr(buffer, name), _missing(what, name)
    assert (buffer.pos, buffer.full, buffer.buffer_size) == (0, False, N_STEPS)
    for name, shape in BUFFER_ARRAYS.items():
        assert isinstance(getattr(buffer, name, None), np.ndarray), _missing(what, f"array {name}")
        have = getattr(buffer, name).shape
        assert len(have) == len(shape) and all(s is None or s == h for s, h in zip(shape, have, strict=True)), \
            f"{what}.{name} has shape {have} under {VERSIONS}, where batched.py writes {shape}"
    assert "lstm_states" in inspect.signature(buffer.add).parameters, _missing(f"{what}.add", "lstm_states")
    compute = inspect.signature(buffer.compute_returns_and_advantage).parameters
    assert {"last_values", "dones"} <= set(compute), _missing(f"{what}.compute_returns_and_advantage", "its arguments")


@pytest.mark.parametrize("package", ["stable-baselines3", "sb3-contrib"])
def test_the_installed_versions_are_inside_the_pins(package: str) -> None:
    dependencies = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]["dependencies"]
    requirement = next(Requirement(d) for d in dependencies if Requirement(d).name == package)
    assert any(spec.operator == "<" for spec in requirement.specifier), f"{requirement}: no upper bound"
    assert requirement.specifier.contains(version(package)), \
        f"{package} {version(package)} is installed, outside pyproject.toml's {requirement}"
