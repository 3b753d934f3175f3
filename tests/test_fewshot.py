"""A new concept from a few examples with a library's SMCs (sb3_smc.fewshot): the held-out rule, what is offered,
the automatic choice, and a learned concept saved, loaded and called by the next one."""

from __future__ import annotations

import dataclasses

import pytest

from sb3_smc.errors import SMCError, SMCTypeError
from sb3_smc.fewshot import choose_smcs, held_out, learn_concept, offered_smcs
from sb3_smc.library import SMCLibrary
from tests.helpers import sb3_smc_cli

CL = "PW-cl_self-in-container_vs_noncontainer-v0"
BA = "PW-ba_self-in-container_from_on-floor-v0"
INSIDE = ("cl_self-inside-container_vs_noncontainer@1", "cl_self-inside-container_vs_noncontainer@3")


@pytest.fixture(scope="module")
def pretrained() -> SMCLibrary:
    from sb3_smc.library.pretrained import pretrained_root

    return SMCLibrary.load(pretrained_root())


def test_no_smc_trained_on_the_concepts_own_datasets_is_offered(pretrained):
    """An SMC trained on one of the concept's datasets is held out, and so is one that calls it; naming it is
    refused."""
    some = pretrained.names[0]
    smc = pretrained[some]
    datasets = smc.spec.task.datasets
    allowed = held_out(pretrained, datasets)
    assert some not in allowed and all(set(pretrained[n].spec.task.datasets).isdisjoint(datasets) for n in allowed)
    caller = dataclasses.replace(smc, name="caller", children=(smc,),
                                 spec=dataclasses.replace(smc.spec, name="caller", children=(smc.name,),
                                                          task=dataclasses.replace(smc.spec.task, datasets=("x",))))
    assert held_out({"caller": caller}, datasets) == []
    with pytest.raises(SMCError, match=r"trained on the concept's own datasets"):
        offered_smcs(pretrained, [some], datasets)
    assert offered_smcs(pretrained, "none", datasets) == []
    assert offered_smcs(pretrained, "all", datasets) == allowed
    with pytest.raises(SMCError, match=r"does not hold"):
        offered_smcs(pretrained, ["no-such-smc@0"], datasets)


def test_the_automatic_choice_keeps_the_smcs_whose_outcomes_separate_the_labels(pretrained):
    """From 8 examples of 'the self is in a container', the SMCs of 'the self is inside a container' separate the
    labels best (score 1: their outcomes are the labels), and the choice is the same on a second call."""
    candidates = [pretrained[n] for n in held_out(pretrained, ("cl_self-in-container_vs_noncontainer",))]
    choice = choose_smcs(CL, candidates, train_worlds=8, k=3, seed=0)
    assert set(INSIDE) <= set(choice.chosen) and len(choice.chosen) == 3
    assert all(0.0 <= s <= 1.0 for s in choice.scores.values()) and choice.scores[INSIDE[0]] == 1.0
    assert choice == choose_smcs(CL, candidates, train_worlds=8, k=3, seed=0)
    with pytest.raises(SMCError, match=r"no SMC to choose from"):
        choose_smcs(CL, [], train_worlds=8)


def test_a_learned_concept_is_saved_loaded_and_called_by_the_next(pretrained, tmp_path):
    """learn_concept trains on 2 worlds with the SMCs offered, tests on every test world, and adds the SMC to a
    library folder; the next concept is offered that SMC by name, calls it, and the library loads both."""
    folder = tmp_path / "mine"
    first = learn_concept(CL, library=pretrained, offer=list(INSIDE), train_worlds=2, total_timesteps=2000,
                          add_to=folder)
    smc = first.smc
    assert smc.name == "cl_self-in-container_vs_noncontainer-n2@0" and first.offered == INSIDE
    assert smc.spec.task.train_worlds == 2 and [c.name for c in smc.children] == list(INSIDE)
    (test,) = [e for e in smc.evaluations if e.split == "test"]
    assert len(test.environment_scores) == 50 and test.repeats == 10
    second = learn_concept(BA, library=folder, offer=[smc.name], train_worlds=2, total_timesteps=2000,
                           add_to=folder)
    assert [c.name for c in second.smc.children] == [smc.name]
    loaded = SMCLibrary.load(folder)
    assert set(loaded.names) == {*INSIDE, smc.name, second.smc.name}
    assert [c.name for c in loaded[second.smc.name].children] == [smc.name]
    assert loaded[smc.name].evaluations == smc.evaluations


def test_the_learn_command_refuses_bad_input_before_any_work(tmp_path):
    code, _, err = sb3_smc_cli("learn", CL, "--train-worlds", "0")
    assert code == 2 and "--train-worlds: must be a positive integer, got 0" in err
    code, _, err = sb3_smc_cli("learn", CL, "--offer", "nope@0,other@1", "--add-to", str(tmp_path / "x"))
    assert code == 2 and "does not hold" in err and not (tmp_path / "x").exists()
    code, _, err = sb3_smc_cli("learn", CL, "--train-worlds", "51")
    assert code == 2 and "the training split of cl_self-in-container_vs_noncontainer has 50 worlds" in err


def test_the_few_shot_table_records_each_cell_and_resumes(tmp_path):
    """``run_few_shot`` on one concept at N = 1 and 2: a record per cell (the CNN's too) and one results.csv row,
    curr's set held out, a progress line per cell; run again, it trains nothing; an unknown method is refused."""
    import csv

    from sb3_smc.experiments.few_shot import children_of, run_few_shot

    target = "cl_self-in-container_vs_noncontainer"
    lines: list[str] = []
    path = run_few_shot(tmp_path, targets=[target], worlds=[1, 2], methods=["cnn", "base", "curr"], seeds=1,
                        printer=lines.append, total_timesteps=2048)
    assert lines[0] == f"{tmp_path}: 6 cells, 0 recorded, 6 to run"
    assert [line.split(":")[0] for line in lines[1:]] == [
        f"[1/6] {target} cnn N=1 seed 0", f"[2/6] {target} base N=1 seed 0", f"[3/6] {target} curr N=1 seed 0",
        f"[4/6] {target} cnn N=2 seed 0", f"[5/6] {target} base N=2 seed 0", f"[6/6] {target} curr N=2 seed 0"]
    with open(path, newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert [(r["method"], r["train_worlds"]) for r in rows] == [("base", "1"), ("base", "2"), ("cnn", "1"),
                                                                 ("cnn", "2"), ("curr", "1"), ("curr", "2")]
    curr = [r for r in rows if r["method"] == "curr"]
    assert all(int(r["offered"]) == len(children_of(target, "curr") or []) > 0 for r in curr)
    assert all(0 <= float(r["test_score"]) <= 1 for r in rows) and (tmp_path / "records" / target).is_dir()
    assert children_of("ba_self-in-target-container_from_nontarget-container", "curr") is None  # search: no curr
    again: list[str] = []
    run_few_shot(tmp_path, targets=[target], worlds=[1, 2], methods=["cnn", "base", "curr"], seeds=1,
                 printer=again.append, total_timesteps=2048)
    assert again == [f"{tmp_path}: 6 cells, 6 recorded, 0 to run"]
    with pytest.raises(SMCError, match="few-shot methods are"):
        run_few_shot(tmp_path, methods=["flat"])


def test_learn_concepts_trains_seeds_together_each_as_train_smc_does(pretrained):
    """Two seeds offered the same SMCs train as one group (``train_smcs``), and each is the SMC ``train_smc`` gives
    for its seed alone: the same weights, record and test score."""
    import numpy as np

    from sb3_smc import evaluate, train_smc
    from sb3_smc.fewshot import learn_concepts

    together = learn_concepts(CL, seeds=[0, 1], library=pretrained, offer=list(INSIDE), train_worlds=2,
                              total_timesteps=4000)
    assert [one.offered for one in together] == [INSIDE, INSIDE]
    for seed, one in enumerate(together):
        alone = train_smc(CL, children=[pretrained[n] for n in INSIDE], seed=seed, train_worlds=2,
                          total_timesteps=4000, name=one.smc.name, log_every=0)
        evaluate(alone, repeats=10, seed=0, record_cells=False)
        assert one.smc.record is not None and alone.record is not None
        timeless = [dataclasses.replace(r, wall_time_s=0.0) for r in (one.smc.record, alone.record)]
        assert timeless[0] == timeless[1] and one.smc.test_score == alone.test_score
        mine, theirs = one.smc.model.policy.state_dict(), alone.model.policy.state_dict()
        assert all(np.array_equal(mine[key].numpy(), theirs[key].numpy()) for key in theirs)
    assert together[0].smc.record.training_returns != together[1].smc.record.training_returns  # two seeds
    with pytest.raises(SMCError, match="1 names for 2 seeds"):
        learn_concepts(CL, seeds=[0, 1], library=pretrained, offer="none", names=["x"])
    with pytest.raises(SMCTypeError, match="learn_concept takes no callback"):
        learn_concept(CL, library=pretrained, offer="none", callback=object())


def test_learn_concepts_gives_train_smcs_both_seeds_in_one_group(pretrained, monkeypatch, tmp_path):
    """The seeds reach ``train_smcs`` in one call, as one group (batchable, the same group key), with the run
    options ``learn_concept`` takes (TensorBoard curves, the printer)."""
    from sb3_smc.fewshot import learn_concepts
    from sb3_smc.learning import batched

    calls = []
    real = batched.train_smcs

    def spy(specs, **options):
        calls.append((list(specs), options))
        return real(specs, **options)

    monkeypatch.setattr(batched, "train_smcs", spy)
    lines: list[str] = []
    learn_concepts(CL, seeds=[0, 1], library=pretrained, offer="none", train_worlds=2, total_timesteps=2000,
                   tensorboard_log=str(tmp_path / "tb"), printer=lines.append, log_every=1)
    [(specs, options)] = calls
    assert [s.seed for s in specs] == [0, 1] and all(batched.batchable(s) for s in specs)
    assert batched._env_key(specs[0]) == batched._env_key(specs[1])  # one group
    assert options["tensorboard_log"] == str(tmp_path / "tb") and any(tmp_path.joinpath("tb").iterdir()) and lines
