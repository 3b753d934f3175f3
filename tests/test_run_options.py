"""A run's options as one checked record (``RunOptions``) and a job's typed identity (``JobId``): the options are
checked once, with the messages of the keyword API; the public functions take them as keywords or whole; a job's name
``<node>@<seed>`` is its identity's string form, read back strictly."""

from __future__ import annotations

import dataclasses
import inspect
from pathlib import Path

import pytest

from sb3_smc.curricula.jobs import JobId, job_name, node_of
from sb3_smc.curricula.options import RunOptions
from sb3_smc.curricula.trainer import check_run_options, finished_jobs, train_curriculum
from sb3_smc.errors import SMCError

BAD_OPTIONS = [
    ({"seeds": 0}, "seeds must be a positive integer, got 0"),
    ({"seeds": True}, "seeds must be a positive integer, got True"),
    ({"workers": 1.5}, "workers must be a positive integer, got 1.5"),
    ({"timesteps": 0}, "timesteps must be a positive integer, got 0"),
    ({"group_size": 0}, "group_size must be a positive integer, got 0"),
    ({"reuse": "three_best"}, "reuse must be one of ['one_best', 'two_best'], got 'three_best'"),
    ({"backend": "slurm"}, "backend must be 'local' or 'ray', got 'slurm'"),
    ({"ray_address": "auto"}, "a Ray address ('auto') is for backend 'ray', not 'local'"),
    ({"algo": "XYZ"}, "algo must be one of ('RecurrentPPO', 'TRPO', 'PPO', 'RecurrentTRPO'), got 'XYZ'"),
    ({"rnn": "rnn"}, "rnn must be one of ['gru', 'lstm'], got 'rnn'"),
]


@pytest.mark.parametrize(("options", "message"), BAD_OPTIONS)
def test_run_options_refuse_what_the_keywords_refused_with_the_same_message(tmp_path, options, message):
    with pytest.raises(SMCError) as caught:
        RunOptions(**options)
    assert str(caught.value) == message
    with pytest.raises(ValueError) as caught:
        check_run_options(**options)  # the earlier check, now the record's own
    assert str(caught.value) == message
    with pytest.raises(ValueError) as caught:
        train_curriculum("con2-cl", tmp_path / "run", **options, progress=False)
    assert str(caught.value) == message
    assert not (tmp_path / "run").exists()


def test_run_options_are_frozen_and_derive_what_the_layers_below_need():
    options = RunOptions(seeds=3, reuse="one_best", reuse_from="some/library")
    assert options.reuse_from == Path("some/library") and options.k == 1 and RunOptions().k == 2
    assert options.jobs(["a", "b"]) == [JobId("a", 0), JobId("a", 1), JobId("a", 2), JobId("b", 0), JobId("b", 1),
                                        JobId("b", 2)]
    with pytest.raises(dataclasses.FrozenInstanceError):
        options.seeds = 4  # type: ignore[misc]
    assert check_run_options(seeds=3) == RunOptions(seeds=3)
    with pytest.raises(SMCError, match="seeds must be a positive integer, got 0"):
        dataclasses.replace(options, seeds=0)  # a changed copy is checked too


def test_the_keyword_defaults_of_every_public_function_are_the_records():
    from sb3_smc.experiments.runner import run_experiment

    defaults = {field.name: field.default for field in dataclasses.fields(RunOptions)}
    for function in (train_curriculum, finished_jobs, run_experiment):
        parameters = inspect.signature(function).parameters
        shared = {name: parameters[name].default for name in defaults if name in parameters}
        assert shared == {name: defaults[name] for name in shared}, function.__name__
        assert parameters["options"].default is None


def test_options_are_given_whole_or_as_keywords_not_both(tmp_path):
    options = RunOptions(seeds=2, timesteps=1000)
    assert RunOptions.of(None, seeds=2, timesteps=1000) == options
    assert RunOptions.of(options, seeds=RunOptions().seeds, algo=None) is options  # keywords left at their defaults
    with pytest.raises(SMCError, match="either as options= or as keywords, not both: seeds, algo given beside"):
        RunOptions.of(options, seeds=3, algo="PPO")
    with pytest.raises(TypeError, match="options must be a RunOptions, got dict"):
        RunOptions.of({"seeds": 2})  # type: ignore[arg-type]
    with pytest.raises(SMCError, match="not both: workers given beside options"):
        train_curriculum("con2-cl", tmp_path / "run", options=options, workers=2, progress=False)
    with pytest.raises(SMCError, match="holds no run yet"):
        finished_jobs("con2-cl", tmp_path / "run", options=options)
    assert not (tmp_path / "run").exists()


def test_an_experiment_takes_options_whole_and_refuses_another_reuse(tmp_path):
    from sb3_smc.experiments.runner import run_experiment

    target = "cl_self-in-container_vs_noncontainer"
    with pytest.raises(SMCError, match="with reuse 'two_best' \\(the paper's\\), got 'one_best'"):
        run_experiment(tmp_path / "exp", methods=["base"], targets=[target], options=RunOptions(reuse="one_best"))
    with pytest.raises(SMCError, match="not both: seeds given beside options"):
        run_experiment(tmp_path / "exp", methods=["base"], targets=[target], seeds=2, options=RunOptions())
    with pytest.raises(SMCError, match="method base-gru has a learner of its own"):
        run_experiment(tmp_path / "exp", methods=["base-gru"], targets=[target], options=RunOptions(rnn="gru"))
    assert not (tmp_path / "exp").exists()


@pytest.mark.parametrize(("node", "seed"), [("left", 0), ("obj-con2-cl/cl_self-left-of-two-objects-vs-one-curr", 12),
                                            ("a%2Fb", 4)])
def test_a_job_id_round_trips_through_its_name(node, seed):
    job = JobId(node, seed)
    name = f"{node}@{seed}"
    assert str(job) == f"{job}" == job_name(node, seed) == name
    assert JobId.parse(name) == JobId.of(name) == job == (node, seed)  # a tuple: (node, seed) as before
    assert (job.node, job.seed) == (node_of(name), seed)
    assert sorted([JobId("b", 0), JobId("a", 10), JobId("a", 2)]) == [("a", 2), ("a", 10), ("b", 0)]


@pytest.mark.parametrize("name", ["left", "left@", "@3", "left@-1", "left@+1", "left@01", "left@1.0", "left@x",
                                  "left@ 1", "left@\u0663"])
def test_a_name_that_is_no_job_is_refused_by_name(name):
    assert JobId.of(name) is None
    with pytest.raises(SMCError) as caught:
        JobId.parse(name)
    assert str(caught.value) == (f"{name!r} is not a job name: <node>@<seed>, a node name and a seed 0, 1, ... "
                                 "(no sign or leading zero)")
