"""The two registries: the algorithms (:data:`sb3_smc.core.hyperparameters.ALGORITHM_REGISTRY`) and the experiment's
methods (:data:`sb3_smc.experiments.design.METHOD_REGISTRY`), and that what trains, stores, plans and parses reads
them: each entry builds its model, the library and rl_zoo3 take their names and classes from it, the ``sb3-smc``
options' choices and defaults are the registries' and the run defaults'."""

from __future__ import annotations

import dataclasses
import importlib
import inspect
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest
from sb3_contrib.common.recurrent.policies import RecurrentActorCriticPolicy

from sb3_smc.core.hyperparameters import (
    ALGORITHM_REGISTRY,
    ALGORITHMS,
    DEFAULT_ALGORITHM,
    DEFAULT_HYPERPARAMETERS,
    DEFAULT_TIMESTEPS,
    RECURRENT_POLICIES,
    algorithm,
    algorithm_of,
    recurrent_policy,
)
from sb3_smc.curricula import shipped_curricula
from sb3_smc.curricula.trainer import BACKENDS, DEFAULT_REUSE, DEFAULT_SEEDS
from sb3_smc.experiments.design import (
    CATEGORIES,
    DEFAULT_METHODS,
    DEFAULT_REPEATS,
    METHOD_REGISTRY,
    METHODS,
    SMC_METHODS,
    SWEEP_METHODS,
    plan,
)
from sb3_smc.learning.training import train_smc, untrained_smc
from sb3_smc.records import Budget, TaskSpec, TrainingSpec
from sb3_smc.zoo import ZOO_ALGOS, hyperparams_for, render_config
from tests.helpers import sb3_smc_cli

ROOT = Path(__file__).resolve().parents[1]
FLAT = "PW-cl_self-in-left-corner_vs_on-hline-v0"
LEFT_OF = "cl_self-left-of-two-objects-vs-one"
IN_CONTAINER = "ba_self-in-container_from_between-potential-containers"


@pytest.mark.parametrize("name", ALGORITHMS)
def test_every_algorithm_builds_its_class_with_its_defaults_and_cells(name: str) -> None:
    entry = algorithm(name)
    assert entry.name == name and DEFAULT_HYPERPARAMETERS[name] is entry.hyperparameters
    for cell in entry.cells or (None,):
        smc = untrained_smc(FLAT, algo=name, rnn=cell, n_envs=2)
        assert type(smc.model) is entry.load_class()
        assert isinstance(smc.model.policy, RecurrentActorCriticPolicy) == entry.recurrent
        if cell is not None:
            assert type(smc.model.policy).__name__ == RECURRENT_POLICIES[cell]
    with pytest.raises(ValueError, match="algo must be one of"):
        algorithm("DQN")


def test_rnn_must_be_a_cell_the_algorithm_takes(monkeypatch: pytest.MonkeyPatch) -> None:
    lstm_only = dataclasses.replace(ALGORITHM_REGISTRY["RecurrentTRPO"], cells=("lstm",))
    monkeypatch.setitem(ALGORITHM_REGISTRY, "RecurrentTRPO", lstm_only)
    assert recurrent_policy("lstm", "RecurrentTRPO") == "SequenceLstmPolicy"
    with pytest.raises(ValueError, match="rnn='gru': RecurrentTRPO takes rnn lstm"):
        recurrent_policy("gru", "RecurrentTRPO")
    with pytest.raises(ValueError, match=r"needs a recurrent algorithm \(RecurrentPPO or RecurrentTRPO\); TRPO"):
        recurrent_policy("gru", "TRPO")


def test_the_defaults_are_defined_once() -> None:
    settings = inspect.signature(train_smc).parameters
    assert settings["algo"].default == DEFAULT_ALGORITHM == ALGORITHMS[0]
    assert settings["total_timesteps"].default == DEFAULT_TIMESTEPS == Budget().total_timesteps
    spec = TrainingSpec(name="x", task=TaskSpec(FLAT))
    assert spec.algo == DEFAULT_ALGORITHM and spec.budget.total_timesteps == DEFAULT_TIMESTEPS


def test_library_and_rl_zoo3_read_the_algorithm_registry() -> None:
    assert all(algorithm_of(entry.load_class()) == name for name, entry in ALGORITHM_REGISTRY.items())
    for zoo_name, name in ZOO_ALGOS.items():
        assert importlib.import_module(f"sb3_smc.zoo.{zoo_name}").hyperparams == hyperparams_for(zoo_name)
        text = render_config(zoo_name)
        assert (ROOT / "zoo_configs" / f"{zoo_name}.yml").read_text() == text
        assert algorithm(name).zoo_note.split()[0] in text
        assert hyperparams_for(zoo_name)["default"]["n_timesteps"] == DEFAULT_TIMESTEPS


def test_the_start_up_hook_gives_rl_zoo3_every_zoo_name() -> None:
    import _sb3_smc_gym_hook

    table: dict[str, Any] = {"trpo": object}
    _sb3_smc_gym_hook._add_zoo_algorithms(SimpleNamespace(ALGOS=table))
    assert table["trpo"] is object  # rl_zoo3's own entries are kept
    assert table.keys() == set(ZOO_ALGOS)
    assert table["recurrent_trpo"] is algorithm("RecurrentTRPO").load_class()


def test_each_method_trains_what_its_entry_says() -> None:
    design = plan([LEFT_OF, IN_CONTAINER], list(METHODS))
    assert set(SMC_METHODS) == {name for name, method in METHOD_REGISTRY.items() if method.smc}
    shipped = shipped_curricula().values()
    for name, method in METHOD_REGISTRY.items():
        if not method.smc:
            assert design.nodes[(LEFT_OF, name)] == ()
            assert ((IN_CONTAINER, name) in design.nodes) != method.classifies_only
        elif method.flat:
            for target in (LEFT_OF, IN_CONTAINER):
                (node,) = design.nodes[(target, name)]
                assert node == (target if name == "base" else f"{name}/{target}")
                entry = design.curriculum.node(node)
                assert (entry.task, entry.algo, entry.uses) == (target, method.algo, ())
                assert (entry.max_steps, entry.budget_scale) == (method.max_steps or 100, method.budget_factor)
                policy = entry.hyperparameters.get("policy")
                assert policy == (recurrent_policy(method.rnn, method.algo) if method.rnn else None)
        else:  # the shipped entries' target nodes, or (settings of its own) copies of them, changed
            for target in (LEFT_OF, IN_CONTAINER):
                for node in design.nodes[(target, name)]:
                    entry = design.curriculum.node(node)
                    shipped_name = node.removeprefix(f"{name}/") if method.changes_targets else node
                    assert node != shipped_name or not method.changes_targets
                    home = next(c for c in shipped if c.method == method.curricula and shipped_name in c.targets)
                    original = home.node(shipped_name)
                    assert entry.budget_scale == pytest.approx(original.budget_scale * method.budget_scale(original))
                    assert entry.uses == tuple(map(method.lower_name, original.uses)) and entry.task == original.task
                    for below in home.closure([shipped_name]) - {shipped_name}:  # the lower levels: scaled copies
                        assert design.curriculum.node(method.lower_name(below)) == dataclasses.replace(
                            home.node(below), name=method.lower_name(below),
                            uses=tuple(map(method.lower_name, home.node(below).uses)),
                            budget_scale=home.node(below).budget_scale * method.lower_budget_factor)
                    assert entry.count_primitive_steps == method.count_primitive_steps
                    assert (entry.max_steps, entry.call_step_cap) == (method.max_steps or 100,
                                                                      method.call_step_cap or 100)
                    assert not any(design.curriculum.node(u).count_primitive_steps for u in entry.uses)
                    assert all((design.curriculum.node(u).max_steps, design.curriculum.node(u).call_step_cap)
                               == (100, 100) for u in entry.uses)
    assert design.cnn_skipped == [IN_CONTAINER]


def test_the_command_line_takes_its_choices_and_defaults_from_the_registries(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    calls: dict[str, dict[str, Any]] = {}

    def experiment(out: str, **options: Any) -> dict[str, Any]:
        calls["experiment"] = options
        return {}

    def train(curriculum: str, out: str, **options: Any) -> SimpleNamespace:
        calls["train"] = options
        return SimpleNamespace(library=Path(out) / "library", failed=[])

    monkeypatch.setattr("sb3_smc.experiments.runner.run_experiment", experiment)
    monkeypatch.setattr("sb3_smc.curricula.trainer.train_curriculum", train)
    assert sb3_smc_cli("experiment", "--out", str(tmp_path / "e"))[0] == 0
    assert sb3_smc_cli("train", "con2-cl", "--out", str(tmp_path / "t"))[0] == 0
    assert calls["experiment"]["methods"] == list(DEFAULT_METHODS) == [  # the paper's six
        "cnn", "base", "curr", "canon", "curr-noprim", "canon-noprim"]
    assert not any(METHOD_REGISTRY[m].own_learner or METHOD_REGISTRY[m].paper for m in DEFAULT_METHODS)
    # every other method is ours, compared with the paper's method it stands for
    assert all(METHOD_REGISTRY[m].paper in DEFAULT_METHODS for m in set(METHODS) - set(DEFAULT_METHODS))
    assert set(SWEEP_METHODS) <= set(METHODS)
    assert calls["experiment"]["repeats"] == DEFAULT_REPEATS
    for command in ("experiment", "train"):  # the command line passes its options whole (RunOptions)
        options = calls[command]["options"]
        assert options.seeds == DEFAULT_SEEDS and options.backend == BACKENDS[0]
    assert calls["train"]["options"].reuse == DEFAULT_REUSE
    code, _, err = sb3_smc_cli("experiment", "--out", str(tmp_path / "e"), "--category", "shapes")
    assert code == 2 and all(repr(c) in err for c in (*CATEGORIES, "all"))
    code, _, err = sb3_smc_cli("train", "con2-cl", "--out", str(tmp_path / "t"), "--algo", "DQN")
    assert code == 2 and all(repr(a) in err for a in ALGORITHMS)
