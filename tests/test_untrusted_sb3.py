"""Untrusted input to sb3_smc is refused before any work, with an error of the package's own (an ``SMCError``) that
names what was expected: counts and budgets beyond their limits (the command line, ``RunOptions``, a run's
``run.json``, the spec's budget, wrapper settings, seed and hyperparameters, the test's repeats), observations that
are not finite, and files that cannot be read (said so, not called corrupt)."""

from __future__ import annotations

import builtins
import errno
import io
import json
import os
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces

from sb3_smc import train_smc
from sb3_smc.core.hyperparameters import MAX_ITERATIONS, MAX_N_ENVS, MAX_STEPS_PER_UPDATE, MAX_TIMESTEPS
from sb3_smc.curricula.options import MAX_SEEDS, MAX_WORKERS, RunOptions
from sb3_smc.curricula.run_directory import RunFileError, read_settings
from sb3_smc.errors import SMCError
from sb3_smc.experiments.design import level2_targets
from sb3_smc.experiments.runner import run_experiment
from sb3_smc.learning.evaluation import MAX_REPEATS, evaluate
from sb3_smc.library import storage
from sb3_smc.records import Budget, RecordError, TaskSpec, TrainingSpec, WrapperSettings
from sb3_smc.records.spec import MAX_EPISODE_STEPS, MAX_FRAME_STACK, MAX_TRAINING_SEED
from sb3_smc.tasks.task import SMCTask
from sb3_smc.zoo.importing import ZooRunError, import_zoo_model
from tests.helpers import sb3_smc_cli

ENV_ID = "PW-cl_self-in-left-corner_vs_on-hline-v0"


# ------------------------------------------------------------------------------------------------ counts and budgets

@pytest.mark.parametrize(("command", "option", "limit"), [
    ("train", "--seeds", MAX_SEEDS), ("train", "--timesteps", MAX_TIMESTEPS), ("train", "--workers", MAX_WORKERS),
    ("train", "--group-size", MAX_SEEDS), ("experiment", "--seeds", MAX_SEEDS),
    ("experiment", "--repeats", MAX_REPEATS), ("experiment", "--workers", MAX_WORKERS),
])
def test_command_line_counts_beyond_their_limit_are_refused_as_read(tmp_path, command, option, limit):
    out = tmp_path / "run"
    first = ["con2-cl"] if command == "train" else []
    code, _, err = sb3_smc_cli(command, *first, "--out", str(out), option, str(limit + 1))
    assert code == 2 and f"argument {option}: must be at most {limit:,}, got {limit + 1:,}" in err
    assert not out.exists()


def test_a_huge_seed_count_is_refused_at_once_not_allocated(tmp_path):
    # before: sb3-smc train ... --seeds 99999999999999999999999 built a list of that many jobs (3.4 GB, nothing written)
    code, _, err = sb3_smc_cli("train", "con2-cl", "--out", str(tmp_path / "run"), "--seeds", "9" * 23)
    assert code == 2 and f"argument --seeds: must be at most {MAX_SEEDS:,}, got {int('9' * 23):,}" in err
    with pytest.raises(SMCError, match=f"seeds must be at most {MAX_SEEDS:,}, got 100,000,000,000,000,000,000,000"):
        RunOptions(seeds=10**23)
    assert RunOptions(seeds=MAX_SEEDS).seeds == MAX_SEEDS


@pytest.mark.parametrize(("options", "message"), [
    ({"timesteps": MAX_TIMESTEPS + 1}, f"timesteps must be at most {MAX_TIMESTEPS:,}"),
    ({"workers": MAX_WORKERS + 1}, f"workers must be at most {MAX_WORKERS:,}"),
    ({"group_size": MAX_SEEDS + 1}, f"group_size must be at most {MAX_SEEDS:,}"),
])
def test_run_options_bound_every_count(options, message):
    with pytest.raises(SMCError, match=message):
        RunOptions(**options)


@pytest.mark.parametrize("seeds", [10**23, 0, True, "5"])
def test_a_run_json_with_a_seed_count_out_of_range_is_refused(tmp_path, seeds):
    (tmp_path / "run.json").write_text(json.dumps({"format": "sb3-smc-run", "nodes": {}, "seeds": seeds}))
    with pytest.raises(RunFileError, match=rf"run.json: seeds must be an integer in \[1, {MAX_SEEDS:,}\]"):
        read_settings(tmp_path)
    code, _, err = sb3_smc_cli("status", str(tmp_path))
    assert code == 2 and "seeds must be an integer in" in err


def test_train_smc_refuses_a_budget_beyond_the_limit_before_anything_is_built():
    with pytest.raises(RecordError, match=f"budget.total_timesteps must be at most {MAX_TIMESTEPS:,}, got 1,000,"):
        train_smc(ENV_ID, total_timesteps=10**30)


@pytest.mark.parametrize(("make", "message"), [
    (lambda: Budget(MAX_TIMESTEPS + 1), f"budget.total_timesteps must be at most {MAX_TIMESTEPS:,}"),
    (lambda: Budget(2.5), "budget.total_timesteps must be an integer, got 2.5"),
    (lambda: Budget(True), "budget.total_timesteps must be an integer, got True"),
    (lambda: Budget(n_envs=MAX_N_ENVS + 1), f"budget.n_envs must be at most {MAX_N_ENVS:,}"),
    (lambda: Budget(n_envs=2.0), "budget.n_envs must be an integer, got 2.0"),
    (lambda: Budget(n_envs=16, n_steps=MAX_STEPS_PER_UPDATE),
     f"budget.n_steps: n_envs x n_steps, the steps of one update's rollout, must be at most {MAX_STEPS_PER_UPDATE:,}"),
    (lambda: WrapperSettings(max_steps=MAX_EPISODE_STEPS + 1),
     f"wrapper.max_steps must be at most {MAX_EPISODE_STEPS:,}"),
    (lambda: WrapperSettings(call_step_cap=10**12), f"wrapper.call_step_cap must be at most {MAX_EPISODE_STEPS:,}"),
    (lambda: TrainingSpec("x", TaskSpec(ENV_ID), seed=MAX_TRAINING_SEED + 1),
     "seed must be at most 4,294,967,295, got 4,294,967,296"),
    (lambda: TrainingSpec("x", TaskSpec(ENV_ID), algo="TRPO", frame_stack=MAX_FRAME_STACK + 1),
     f"frame_stack must be at most {MAX_FRAME_STACK:,}"),
    (lambda: TrainingSpec("x", TaskSpec(ENV_ID), hyperparameters={"n_epochs": 10**9}),
     rf"hyperparameter 'n_epochs' must be an integer in \[1, {MAX_ITERATIONS:,}\], got 1000000000"),
    (lambda: TrainingSpec("x", TaskSpec(ENV_ID), hyperparameters={"n_epochs": 2.5}),
     r"hyperparameter 'n_epochs' must be an integer in \[1, 10,000\], got 2.5"),
    (lambda: TrainingSpec("x", TaskSpec(ENV_ID), algo="TRPO", hyperparameters={"cg_max_steps": True}),
     r"hyperparameter 'cg_max_steps' must be an integer in \[1, 10,000\], got True"),
])
def test_spec_sizes_are_integers_within_their_limits(make, message):
    with pytest.raises(RecordError, match=message):
        make()


def test_the_limits_leave_real_budgets_alone():
    assert Budget(MAX_TIMESTEPS, n_envs=MAX_N_ENVS).n_steps == 1
    assert TrainingSpec("x", TaskSpec(ENV_ID), seed=MAX_TRAINING_SEED, hyperparameters={"n_epochs": np.int64(8)}
                        ).hyperparameters["n_epochs"] == 8


def test_test_repeats_beyond_the_limit_are_refused_before_any_episode(tmp_path):
    with pytest.raises(SMCError, match=f"repeats must be at most {MAX_REPEATS:,}, got 1,001"):
        evaluate(SimpleNamespace(), repeats=MAX_REPEATS + 1)  # checked before the SMC is looked at
    with pytest.raises(SMCError, match=f"repeats must be at most {MAX_REPEATS:,}"):
        run_experiment(tmp_path / "exp", targets=["x"], repeats=10**9, progress=False)
    assert not (tmp_path / "exp").exists()


# ------------------------------------------------------------------------------------------------ observations

class Glitchy(gym.Env):
    """Three sensor values: NaN at index 1 after ``reset`` when ``nan_at_reset``, an infinity at index 2 after a
    step."""

    observation_space = spaces.Box(-1.0, 1.0, (3,), np.float32)
    action_space = spaces.Discrete(2)

    def __init__(self, nan_at_reset: bool = True) -> None:
        self.nan_at_reset = nan_at_reset

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        return np.array([0.0, np.nan if self.nan_at_reset else 0.0, 0.0], np.float32), {}

    def step(self, action):
        return np.array([0.0, 0.0, np.inf], np.float32), 0.0, False, False, {}


def test_an_observation_with_nan_or_inf_is_an_error_naming_the_env_and_the_index():
    # before: the NaN reached the policy and failed inside torch.distributions (Categorical's logits)
    task = SMCTask(Glitchy(), "bring-about", goal=lambda env: False)
    with pytest.raises(SMCError, match=r"environment Glitchy: the observation its reset\(\) returned holds nan at "
                                       r"index 1 of the 3 sensor values"):
        task.reset(seed=0)
    task = SMCTask(Glitchy(nan_at_reset=False), "classification", label=lambda env: 1)
    task.reset(seed=0)
    with pytest.raises(SMCError, match=r"Glitchy: the observation its step\(\) returned holds inf at index 2"):
        task.step(2)  # a primitive


def test_a_registered_env_is_named_by_its_id():
    gym.register("GlitchyUntrusted-v0", entry_point=Glitchy)
    try:
        task = SMCTask(gym.make("GlitchyUntrusted-v0", disable_env_checker=True), "bring-about",
                       goal=lambda env: False)
        with pytest.raises(SMCError, match="environment GlitchyUntrusted-v0: .* holds nan at index 1"):
            task.reset(seed=0)
    finally:
        gym.registry.pop("GlitchyUntrusted-v0")


# ------------------------------------------------------------------------------------------------ unreadable files

def _deny_reading(monkeypatch: pytest.MonkeyPatch, path: Path) -> None:
    """Opening ``path`` fails as a file without read permission does (the tests run as root, who may read any file,
    so chmod 000 would not do)."""
    denied = os.fspath(path)
    for module in (os, io, builtins):
        real = module.open

        def refuse(file: Any, *args: Any, real: Any = real, **kwargs: Any) -> Any:
            if isinstance(file, str | os.PathLike) and os.fspath(file) == denied:
                raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), denied)
            return real(file, *args, **kwargs)

        monkeypatch.setattr(module, "open", refuse)


def test_a_model_file_that_cannot_be_read_is_not_called_corrupt(tmp_path, monkeypatch):
    (tmp_path / "a.zip").write_bytes(b"PK\x05\x06" + bytes(18))  # an empty zip: readable, were it allowed
    entry = SimpleNamespace(model="a.zip", sha256="0" * 64, algo="TRPO")
    _deny_reading(monkeypatch, tmp_path / "a.zip")
    with pytest.raises(SMCError) as caught:
        storage.check_model_file(tmp_path, "a@0", entry)
    assert "cannot read" in str(caught.value) and "Permission denied" in str(caught.value)
    assert "corrupt" not in str(caught.value)


def _zoo_run(root: Path) -> Path:
    """A zoo run directory of ``ENV_ID`` trained with sb3-smc's wrapper; its final model file is not written."""
    (root / ENV_ID).mkdir(parents=True)
    (root / ENV_ID / "args.yml").write_text(f"env: {ENV_ID}\nalgo: trpo\n")
    (root / ENV_ID / "config.yml").write_text("env_wrapper: sb3_smc.zoo.smc_env\n")
    return root / f"{ENV_ID}.zip"


def test_a_zoo_model_file_that_cannot_be_read_says_so_and_a_damaged_one_says_corrupt(tmp_path, monkeypatch):
    model = _zoo_run(tmp_path / "zoo")
    model.write_bytes(b"PK\x03\x04 not a zip")
    with pytest.raises(ZooRunError, match=r"not a TRPO model archive \(corrupt or truncated\?\)"):
        import_zoo_model(tmp_path / "zoo", tmp_path / "lib")  # before: SB3's bare ValueError, a traceback
    _deny_reading(monkeypatch, model)
    with pytest.raises(ZooRunError, match=r"cannot read the zoo's model file \(Permission denied\)"):
        import_zoo_model(tmp_path / "zoo", tmp_path / "lib")
    monkeypatch.undo()
    model.unlink()
    model.mkdir()
    with pytest.raises(ZooRunError, match="model is not a file"):
        import_zoo_model(tmp_path / "zoo", tmp_path / "lib")
    assert not (tmp_path / "lib").exists()


def test_an_unreadable_zoo_settings_file_is_told_from_a_damaged_one(tmp_path, monkeypatch):
    _zoo_run(tmp_path / "zoo")
    settings = tmp_path / "zoo" / ENV_ID / "config.yml"
    settings.write_text("env_wrapper: [unclosed\n")
    with pytest.raises(ZooRunError, match="config.yml: the zoo's saved settings are not YAML rl_zoo3 wrote"):
        import_zoo_model(tmp_path / "zoo", tmp_path / "lib")
    _deny_reading(monkeypatch, settings)
    with pytest.raises(ZooRunError, match=r"config.yml: cannot read the zoo's saved settings \(Permission denied\)"):
        import_zoo_model(tmp_path / "zoo", tmp_path / "lib")


def test_an_unreadable_results_json_stops_an_experiment_before_any_work(tmp_path):
    # before: read as "no earlier results", the run trained and evaluated, then failed to write results.json at its end
    out = tmp_path / "exp"
    (out / "results.json").mkdir(parents=True)
    with pytest.raises(RunFileError, match=r"cannot read .*results.json \(Is a directory\): the results of earlier "
                                           "runs"):
        run_experiment(out, targets=[level2_targets()[0]], methods=["base"], progress=False)
    assert sorted(p.name for p in out.iterdir()) == ["results.json"]
