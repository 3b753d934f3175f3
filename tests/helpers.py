"""Helpers shared by several test modules: the reference data, small hand-drawn environments, test policies."""

from __future__ import annotations

import gzip
import importlib.util
import json
import os
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
import pytest

from pixelworld_env import PixelWorldEnv, Scene

REFERENCE = Path(os.environ.get("PIXELWORLD_REFERENCE",
                                Path(__file__).resolve().parents[2] / "shared" / "reference"))
"""The full reference (``$PIXELWORLD_REFERENCE``, default ``../shared/reference`` beside the checkout)."""
FIXTURE = Path(__file__).resolve().parent / "data" / "reference"
"""The compact fixture the repository carries, made from the reference by ``tools/build_fixture.py``."""
REQUIRE = "PIXELWORLD_REQUIRE_REFERENCE"
"""Set (CI, where the reference exists): a test that needs the full reference fails instead of skipping."""


def has_reference() -> bool:
    """Whether the full reference is there."""
    return (REFERENCE / "aaai18_samples" / "index.json").is_file()


def require_reference() -> Path:
    """The full reference folder; where it is missing, the calling test is skipped with the reason (fails where
    ``$PIXELWORLD_REQUIRE_REFERENCE`` is set)."""
    if not has_reference():
        reason = (f"needs the full reference data (not found at {REFERENCE}): set PIXELWORLD_REFERENCE to the "
                  "folder holding aaai18/ and aaai18_samples/")
        if os.environ.get(REQUIRE):
            pytest.fail(f"{reason} ({REQUIRE} is set)", pytrace=False)
        pytest.skip(reason)
    return REFERENCE


def samples_folder() -> Path:
    """The original samples: the reference's 126 files (8,700 samples) where it is there, else the fixture's 125
    (the first 4 samples of each label of each dataset)."""
    return REFERENCE / "aaai18_samples" if has_reference() else FIXTURE / "samples"


def sample_files() -> list[Path]:
    """Every decoded dataset file of :func:`samples_folder`."""
    return sorted(samples_folder().glob("*.jsonl.gz"))


def shape_library_file() -> Path:
    """The original shape library (the same file in the reference and the fixture)."""
    return (REFERENCE / "aaai18_samples" if has_reference() else FIXTURE) / "shape_library.json.gz"


def read_samples(path: Path) -> tuple[dict, list[dict]]:
    """The header and the sample records of one decoded dataset file."""
    with gzip.open(path, "rt", encoding="utf-8") as handle:
        header = json.loads(handle.readline())
        return header, [json.loads(line) for line in handle]


CONTAINER = """
#########
#...S...#
#.a...a.#
#.a...a.#
#.aaaaa.#
#=======#
#.......#
#########
"""
IN_CONTAINER = "?x container(x) & inside_supported(self,x)"


def make(kind: str = "bring-about", text: str = CONTAINER, **kwargs) -> PixelWorldEnv:
    scenes = [Scene.from_ascii(text, {"a": "container"})]
    return PixelWorldEnv(scenes, kind=kind, concept=kwargs.pop("concept", IN_CONTAINER), **kwargs)


def classification_env(**kwargs) -> PixelWorldEnv:
    inside = Scene.from_ascii(CONTAINER.replace("#...S...#", "#.......#").replace("#.a...a.#\n#.aaaaa.#",
                                                                                    "#.a.S.a.#\n#.aaaaa.#"),
                              {"a": "container"})
    outside = Scene.from_ascii(CONTAINER, {"a": "container"})
    return PixelWorldEnv([inside, outside], kind="classification", concept=IN_CONTAINER, **kwargs)



class UniformPolicy:
    """Stochastic test policy: uniform over the actions (the evaluation's sampling decides everything)."""

    def __init__(self, n_actions: int) -> None:
        self.n_actions = n_actions

    def initial_state(self) -> None:
        return None

    def probabilities(self, observation: np.ndarray, state: None) -> tuple[np.ndarray, None]:
        return np.full(self.n_actions, 1.0 / self.n_actions), None


def import_script(folder: str, name: str) -> ModuleType:
    """The script ``<folder>/<name>.py`` of the repository (``benchmarks``, ``tools``: not packages) as a module."""
    path = Path(__file__).resolve().parents[1] / folder / f"{name}.py"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def import_benchmark(name: str) -> ModuleType:
    """The script ``benchmarks/<name>.py`` imported as a module."""
    return import_script("benchmarks", name)


def import_tool(name: str) -> ModuleType:
    """The script ``tools/<name>.py`` imported as a module."""
    return import_script("tools", name)


def sb3_smc_cli(*argv: str) -> tuple[int, str, str]:
    """``sb3-smc`` run in this process: its exit status, stdout and stderr (argparse's errors included)."""
    import contextlib
    import io

    from sb3_smc.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(list(argv))
        except SystemExit as exit_:
            code = exit_.code
    return code, out.getvalue(), err.getvalue()


def step_side_by_side(native, reference, steps: int, keys: tuple[str, ...]) -> tuple[int, list[dict]]:
    """Step two SB3 vec envs (``native`` and its ``reference``, monitored) with the same random actions after the same
    reset, asserting the same observations, rewards, dones, info ``keys``, terminal observations and monitor
    episodes; returns how many episodes ended and the native infos of every step."""
    assert native.observation_space == reference.observation_space
    assert native.action_space == reference.action_space
    np.testing.assert_array_equal(native.reset(), reference.reset())
    rng = np.random.default_rng(0)
    ended, seen = 0, []
    for _ in range(steps):
        actions = rng.integers(native.action_space.n, size=native.num_envs)
        obs, rewards, dones, infos = native.step(actions)
        obs_ref, rewards_ref, dones_ref, infos_ref = reference.step(actions)
        np.testing.assert_array_equal(obs, obs_ref)
        np.testing.assert_array_equal(rewards, rewards_ref)
        np.testing.assert_array_equal(dones, dones_ref)
        assert rewards.dtype == rewards_ref.dtype and obs.dtype == obs_ref.dtype
        for info, info_ref in zip(infos, infos_ref, strict=True):
            for key in keys:
                assert info[key] == info_ref[key], key
            assert ("terminal_observation" in info) == ("terminal_observation" in info_ref)
            if "terminal_observation" in info:
                np.testing.assert_array_equal(info["terminal_observation"], info_ref["terminal_observation"])
                assert info["episode"]["r"] == info_ref["episode"]["r"]
                assert info["episode"]["l"] == info_ref["episode"]["l"]
        ended += int(dones.sum())
        seen.extend(infos)
    return ended, seen


def assert_same_smc(reference: Any, other: Any) -> None:
    """Two SMCs trained from one spec by two paths are the same: weights (the selected snapshot), records and
    selection, the spec; ``other`` recorded a wall time."""
    import torch  # the tests that compare trained SMCs only

    first, second = reference.model.policy.state_dict(), other.model.policy.state_dict()
    assert first.keys() == second.keys()
    assert all(torch.equal(first[name], second[name]) for name in first)
    a, b = reference.record, other.record
    assert a is not None and b is not None
    assert a.training_returns == b.training_returns
    assert a.success_rates == b.success_rates
    assert (a.selected_update, a.selected_return) == (b.selected_update, b.selected_return)
    assert (a.total_timesteps, a.primitive_steps) == (b.total_timesteps, b.primitive_steps)
    assert a.initial_action_probabilities == b.initial_action_probabilities
    assert reference.spec == other.spec
    assert b.wall_time_s > 0
