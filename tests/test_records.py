"""Typed records (sb3_smc.records): JSON and pickle round trips, validation with named fields, no torch on import,
and the package boundary (pixelworld_env never imports sb3_smc)."""

from __future__ import annotations

import dataclasses
import json
import math
import pickle
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from torch import nn

from sb3_smc.core.hyperparameters import DEFAULT_HYPERPARAMETERS, constructor_arguments
from sb3_smc.records import (
    Budget,
    EvaluationRecord,
    RecordError,
    SignalBias,
    TaskSpec,
    TrainingRecord,
    TrainingSpec,
    WrapperSettings,
)
from sb3_smc.smc.policies import ScriptedPolicy
from sb3_smc.smc.smc import SMC

ROOT = Path(__file__).resolve().parents[1]
CORNER_ID = "PW-cl_self-in-left-corner_vs_on-hline-v0"
POOL_ID = "PW-ba_self-in-container-v0"


def _spec(**changes) -> TrainingSpec:
    spec = TrainingSpec.create(CORNER_ID, algo="TRPO", seed=7, total_timesteps=4000, n_envs=4, children=["a", "b"],
                               call_step_cap=20, frame_stack=2, policy_kwargs={"activation_fn": nn.ReLU},
                               learning_rate="lin_1e-3")
    return dataclasses.replace(spec, **changes)


def _record() -> TrainingRecord:
    return TrainingRecord(training_returns=(0.1, float("nan"), np.float32(0.5)), success_rates=(0.0, np.nan, 0.5),
                          selected_update=np.int64(2), selected_return=0.5, total_timesteps=6000, primitive_steps=7000,
                          wall_time_s=1.25, action_names=("SIG0", "SIG1"), initial_action_probabilities=(0.5, 0.5),
                          versions={"torch": "2.13.0"})


def _evaluation() -> EvaluationRecord:
    return EvaluationRecord(smc="corner", env_id=CORNER_ID, split="test", kind="classification", repeats=10,
                            evaluation_seed=0, score=0.75, environment_scores=(0.5, 1.0), mean_length=3.0,
                            call_counts={"a": 4})


RECORDS = {"spec": _spec, "record": _record, "evaluation": _evaluation, "task": lambda: TaskSpec(POOL_ID).resolved(),
           "wrapper": lambda: WrapperSettings(False, True, 7, 50), "budget": lambda: Budget(100, 3),
           "bias": lambda: SignalBias(signal_weight=2.0)}


@pytest.mark.parametrize("name", list(RECORDS))
def test_json_and_pickle_round_trips(name):
    record = RECORDS[name]()
    again = type(record).from_json(record.to_json())
    assert again == record and again.to_dict() == record.to_dict()
    assert pickle.loads(pickle.dumps(record)) == record
    with pytest.raises(dataclasses.FrozenInstanceError):
        record.__setattr__(dataclasses.fields(record)[0].name, None)


def test_spec_create_resolves_the_task_and_hyperparameters():
    spec = _spec()
    assert spec.name == "cl_self-in-left-corner_vs_on-hline" and spec.kind == "classification"
    assert spec.task.datasets == ("cl_self-in-left-corner_vs_on-hline",) and spec.task.split == "train"
    assert spec.budget == Budget(4000, 4, 500) and spec.budget.steps_per_update == 2000 and spec.budget.updates == 2
    assert spec.wrapper == WrapperSettings(include_primitives=True, call_step_cap=20)
    assert spec.action_names == ("SIG0", "SIG1", "DOWN", "RIGHT", "UP", "LEFT", "SMC:a", "SMC:b")
    assert spec.observation_size == 81 + 2 + 8
    hyper = spec.hyperparameters
    assert hyper["target_kl"] == DEFAULT_HYPERPARAMETERS["TRPO"]["target_kl"]
    assert hyper["policy_kwargs"] == {"net_arch": {"pi": [32], "vf": [32]},
                                      "activation_fn": {"__class__": "torch.nn.modules.activation.ReLU"}}
    policy, kwargs = constructor_arguments(hyper)
    assert policy == "MlpPolicy" and kwargs["policy_kwargs"]["activation_fn"] is nn.ReLU
    assert kwargs["learning_rate"](1.0) == pytest.approx(1e-3) and kwargs["learning_rate"](0.5) == pytest.approx(5e-4)
    pool = TrainingSpec.create(POOL_ID)
    assert pool.kind == "bring-about" and len(pool.task.datasets) > 1
    assert constructor_arguments(pool.hyperparameters)[0].__name__ == "SequenceLstmPolicy"
    unknown = TaskSpec("MyOwnEnv-v0").resolved()
    assert unknown.kind is None and unknown.datasets == ()


@pytest.mark.parametrize(("make", "message"), [
    (lambda: TrainingSpec.create(CORNER_ID, algo="DQN"), "algo must be one of"),
    (lambda: TrainingSpec.create(CORNER_ID, seed=1.5), "seed must be an integer, got 1.5"),
    (lambda: TrainingSpec.create(CORNER_ID, seed=True), "seed must be an integer, got True"),
    (lambda: TrainingSpec.create(CORNER_ID, n_envs=0), "budget.n_envs must be >= 1"),
    (lambda: TrainingSpec.create(CORNER_ID, include_primitives=False), "noprim.* needs children"),
    (lambda: TrainingSpec.create(CORNER_ID, children=["a", "a"]), r"children named twice: \['a'\]"),
    (lambda: TrainingSpec.create(CORNER_ID, name="x", children=["x"]), "lists itself"),
    (lambda: TrainingSpec.create(CORNER_ID, frame_stack=2), "frame_stack is meant for memoryless"),
    (lambda: TrainingSpec.create(CORNER_ID, split="dev"), "split must be one of"),
    (lambda: TrainingSpec.create(CORNER_ID, call_step_cap=0), "wrapper.call_step_cap must be >= 1"),
    (lambda: TrainingSpec.create(CORNER_ID, learning_rate=lambda p: p), r"hyperparameter learning_rate: a function"),
    (lambda: TrainingSpec.create(CORNER_ID, gamma=float("nan")), "hyperparameter gamma: nan is not a finite number"),
    (lambda: TrainingSpec.create(CORNER_ID, device="cuda"), "'device' is not set through the hyperparameters"),
    (lambda: TrainingSpec.create(CORNER_ID, env_kwargs={"max_steps": 5}), r"\['max_steps'\] are set by the spec"),
    (lambda: SignalBias(smc_weight=0), "signal_bias.smc_weight must be > 0"),
])
def test_invalid_specs_name_the_field(make, message):
    with pytest.raises(RecordError, match=message):
        make()


def test_from_dict_names_unknown_missing_and_wrong_fields():
    data = _spec().to_dict()
    with pytest.raises(RecordError, match=r"TrainingSpec: unknown field\(s\) \['sede'\]"):
        TrainingSpec.from_dict({**data, "sede": 1})
    missing = {k: v for k, v in data.items() if k != "task"}
    with pytest.raises(RecordError, match=r"TrainingSpec: missing field\(s\) \['task'\]"):
        TrainingSpec.from_dict(missing)
    wrong = {**data, "budget": {**data["budget"], "n_envs": "4"}}
    with pytest.raises(RecordError, match="budget.n_envs must be an integer, got '4'"):
        TrainingSpec.from_dict(wrong)
    with pytest.raises(RecordError, match=r"TrainingSpec.task: unknown field\(s\) \['envid'\]"):
        TrainingSpec.from_dict({**data, "task": {"envid": CORNER_ID}})
    with pytest.raises(RecordError, match="not valid JSON"):
        TrainingSpec.from_json('{"name": ')
    with pytest.raises(RecordError, match="selected_update 5 is past the last update"):
        dataclasses.replace(_record(), selected_update=5)
    with pytest.raises(RecordError, match="success_rates has 1 values for 3 updates"):
        dataclasses.replace(_record(), success_rates=(0.0,))


def test_nan_returns_are_null_in_json():
    record = _record()
    assert record.to_dict()["training_returns"] == [0.1, None, 0.5]
    assert math.isnan(TrainingRecord.from_json(record.to_json()).training_returns[1])
    assert record.final_return == 0.5 and record.updates == 3


def test_smc_checks_its_spec_and_keeps_evaluations():
    policy = ScriptedPolicy(8, lambda obs, step: 0)
    children = [SMC(n, "bring-about", ScriptedPolicy(5, lambda obs, step: 0)) for n in ("a", "b")]
    smc = SMC("corner", "classification", policy, children, spec=_spec())
    with pytest.raises(ValueError, match=r"spec does not match it \(children: spec \('a', 'b'\), SMC \('b', 'a'\)\)"):
        SMC("corner", "classification", policy, children[::-1], spec=_spec())
    with pytest.raises(ValueError, match="kind: spec 'classification', SMC 'bring-about'"):
        SMC("corner", "bring-about", ScriptedPolicy(7, lambda obs, step: 0), children, spec=_spec())
    assert smc.test_score is None
    first = _evaluation()
    smc.add_evaluation(first)
    smc.add_evaluation(dataclasses.replace(first, split="train", score=0.9))
    smc.add_evaluation(dataclasses.replace(first, score=0.8))  # replaces the first (same env id and split)
    assert [(e.split, e.score) for e in smc.evaluations] == [("train", 0.9), ("test", 0.8)]
    assert smc.test_score == 0.8
    with pytest.raises(ValueError, match="evaluation of SMC 'other' given to SMC 'corner'"):
        smc.add_evaluation(dataclasses.replace(first, smc="other"))


def _fresh_import(code: str) -> str:
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert result.returncode == 0, result.stderr
    return result.stdout.strip()


def test_records_and_pixelworld_import_no_torch():
    loaded = _fresh_import(
        "import sys\n"
        "import sb3_smc.records, sb3_smc.core.hyperparameters, sb3_smc\n"
        "spec = sb3_smc.TrainingSpec.create('PW-cl_self-in-left-corner_vs_on-hline-v0')\n"
        "import pixelworld_env\n"
        "print(sorted(m for m in ('torch', 'stable_baselines3', 'sb3_contrib') if m in sys.modules))")
    assert loaded == "[]"
    loaded = _fresh_import("import sys\nimport pixelworld_env\nimport pixelworld_env.cli\n"
                           "print(sorted(m for m in sys.modules if m.split('.')[0] in ('torch', 'sb3_smc')))")
    assert loaded == "[]"


def test_pixelworld_env_never_imports_sb3_smc():
    offenders = [str(path.relative_to(ROOT)) for path in (ROOT / "pixelworld_env").rglob("*.py")
                 if re.search(r"^\s*(import|from) sb3_smc", path.read_text(encoding="utf-8"), re.M)]
    assert offenders == []


def test_an_evaluation_saved_with_the_old_seed_key_loads_and_is_written_with_the_new_one():
    evaluation = _evaluation()
    new = evaluation.to_dict()
    assert "seed" not in new and new["evaluation_seed"] == 0
    assert list(new)[:6] == ["smc", "env_id", "split", "kind", "repeats", "evaluation_seed"]  # in the old key's place
    old = {("seed" if key == "evaluation_seed" else key): value for key, value in new.items()}  # as saved before
    assert EvaluationRecord.from_dict(old) == evaluation and EvaluationRecord.from_json(json.dumps(old)) == evaluation
    assert EvaluationRecord.from_dict({**old, "seed": None}).evaluation_seed is None  # a version-1 conversion's
    with pytest.raises(RecordError, match="EvaluationRecord: both 'seed' \\(the old name\\) and 'evaluation_seed'"):
        EvaluationRecord.from_dict({**new, "seed": 0})
    with pytest.raises(RecordError, match="evaluation_seed must be an integer, got 'x'"):
        EvaluationRecord.from_dict({**old, "seed": "x"})


def test_every_nan_field_is_null_in_json():
    evaluation = dataclasses.replace(_evaluation(), environment_scores=(0.5, float("nan")))
    assert evaluation.to_dict()["environment_scores"] == [0.5, None]
    assert EvaluationRecord.from_json(evaluation.to_json()) == evaluation
    record = dataclasses.replace(_record(), initial_action_probabilities=(0.5, float("nan")))
    assert TrainingRecord.from_json(record.to_json()).to_dict()["initial_action_probabilities"] == [0.5, None]
