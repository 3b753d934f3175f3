"""Curricula: the shipped files, validation errors with file / line / node, seed ranking, training a tiny two-level
curriculum end to end, resuming after a kill, settings changes (refused, or accepted node by node), damaged model
files trained again, bad node settings and run files reported before anything runs, and the same library from 1 or
2 workers and Ray."""

from __future__ import annotations

import dataclasses
import json
import math
import os
import re
import signal
import subprocess
import sys
import time
from itertools import pairwise
from pathlib import Path

import pytest
import torch

from sb3_smc.curricula import (
    Curriculum,
    CurriculumError,
    Node,
    load_curriculum,
    parse_curriculum,
    resolve_curriculum,
    shipped_curricula,
)
from sb3_smc.curricula.format import describe, merge
from sb3_smc.curricula.shipped import build_shipped, render
from sb3_smc.curricula.trainer import RunSettingsError, job_name, rank_seeds, status, train_curriculum
from sb3_smc.library import CorruptModelError, SMCLibrary
from sb3_smc.records import TrainingRecord
from tests.helpers import import_tool, sb3_smc_cli

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "sb3_smc" / "curricula" / "data"
LEFT, RIGHT, ABOVE = ("cl_self-in-left-corner_vs_on-hline", "cl_self-in-right-corner_vs_on-hline",
                      "ba_self-on-something_from_directly-above")
CONTAINER = "cl_self-in-container_vs_noncontainer"
TINY = f"""\
curriculum: tiny
description: two corners and a container
nodes:
  - name: left
    task: {LEFT}
  - name: above
    task: {ABOVE}
  - name: container
    task: {CONTAINER}
    uses: [left, above]
"""


# ------------------------------------------------------------------------------------------------ shipped

def test_shipped_files_are_generated_from_the_catalog():
    built = build_shipped()
    assert sorted(p.stem for p in DATA.glob("*.yml")) == sorted(built), "run: python -m sb3_smc.curricula"
    for name, curriculum in built.items():
        assert (DATA / f"{name}.yml").read_text() == render(curriculum), f"{name}: run python -m sb3_smc.curricula"


def test_shipped_curricula_match_the_paper():
    curricula = {name: c for name, c in shipped_curricula().items() if name != "pushable"}  # the paper's 31
    assert len(curricula) == 31 and {"con2-cl", "obj-con2-cl", "con2-ba-canon", "con2-cl-noprim"} <= set(curricula)
    curr = [c for c in curricula.values() if c.method == "smc-curr"]
    assert sum(len(c.targets) for c in curr) == 83  # hand-designed entries
    assert len({c.node(t).task for c in curr for t in c.targets}) == 51  # level-2 targets
    lower = {u for c in curricula.values() for n in c.nodes for u in n.uses}
    assert len(lower) == 62  # lower-level nodes (the paper's 68 group x dataset references)
    canon = {c.name: sorted({len(c.node(t).uses) for t in c.targets}) for c in curricula.values()
             if c.method == "smc-canon"}
    assert canon == {"con2-ba-canon": [13], "con2-cl-canon": [13], "search2-canon": [13], "objects2-ba-canon": [11],
                     "objects2-cl-canon": [11], "obj-con2-canon-cl": [3, 11, 15]}
    noprim = curricula["con2-cl-noprim"]
    assert all(not noprim.node(t).include_primitives for t in noprim.targets)
    assert [n.uses for n in noprim.nodes] == [n.uses for n in curricula["con2-cl"].nodes]
    base = curricula["con1-cl"]
    assert base.method == "smc-base" and base.levels() == [list(base.targets)]
    # a flat node is one node wherever it is used
    assert curricula["con2-cl"].node(LEFT) == curricula["con2-cl-canon"].node(LEFT) == Node(LEFT, LEFT)


def test_the_pushable_curriculum_has_11_concepts_over_6_levels():
    from pixelworld_env.datasets import catalog
    from sb3_smc.curricula.designed import PUSHABLE, PUSHABLE_TOP

    pushable = shipped_curricula()["pushable"]
    assert pushable.method == "smc-curr" and len(pushable.nodes) == 11
    levels = pushable.levels()
    assert [len(level) for level in levels] == [3, 2, 1, 2, 2, 1]
    assert levels[-1] == [f"pushable/{PUSHABLE_TOP}"] and pushable.targets == tuple(n for lv in levels[1:] for n in lv)
    tasks = {node.task for node in pushable.nodes}
    assert tasks == set(PUSHABLE) == {n for n in catalog.dataset_names() if catalog.dataset(n).category == "pushable"}
    kinds = {catalog.dataset(t).kind for lv in levels for t in (pushable.node(n).task for n in lv)}
    assert kinds == {"classification", "bring-about"}
    # every node above level 1 uses a node of the level just below it (the levels are the DAG's depth)
    for k, level in enumerate(levels[1:], 1):
        assert all(set(pushable.node(n).uses) & set(levels[k - 1]) for n in level)


def test_targets_by_node_or_dataset_name():
    curriculum = shipped_curricula()["con2-cl"]
    by_dataset = curriculum.select([CONTAINER])
    assert by_dataset == ["con2-cl/cl_self-in-container_vs_noncontainer",
                          "con2-cl/cl_self-in-container_vs_noncontainer_curr1"]
    assert curriculum.select(["con2-cl/cl_self-in-container_vs_noncontainer"]) == by_dataset[:1]
    assert curriculum.order(by_dataset[:1]) == [LEFT, RIGHT, by_dataset[0]]
    with pytest.raises(CurriculumError, match="--targets 'cl_self-in-container' is neither"):
        curriculum.select(["cl_self-in-container"])


# ------------------------------------------------------------------------------------------------ validation

@pytest.mark.parametrize(("text", "message"), [
    (TINY.replace("uses: [left, above]", "uses: [left, container]"), r"tiny.yml:8: node 'container' uses itself"),
    (TINY + "  - name: cycle-a\n    task: " + LEFT + "\n    uses: [cycle-b]\n  - name: cycle-b\n    task: " + LEFT
     + "\n    uses: [cycle-a]\n", r"tiny.yml:\d+: nodes use each other in a cycle: cycle-a -> cycle-b -> cycle-a"),
    (TINY.replace(f"task: {ABOVE}", "task: ba_self-on-somthing"),
     r"tiny.yml:6: node 'above': unknown dataset or concept pool 'ba_self-on-somthing'; did you mean"),
    (TINY.replace("uses: [left, above]", "uses: [left, abov]"),
     r"tiny.yml:8: node 'container' uses an unknown node 'abov'; did you mean 'above'"),
    (TINY.replace("- name: above", "- name: left"), r"tiny.yml:6: node 'left' is defined twice \(first defined at "
                                                    r"line 4\)"),
    (TINY.replace("- name: above\n    task", "- name: above\n    primitives: false\n    task"),
     r"tiny.yml:6: node 'above' has primitives: false \(noprim\) but uses no nodes"),
    (TINY.replace("uses: [left, above]", "uses: [left, above"), r"tiny.yml:\d+: malformed YAML"),
    (TINY.replace("  - name: above\n", "  - name: above\n    usses: [left]\n"),
     r"tiny.yml:6: node 'above': unknown key 'usses' .*did you mean 'uses'"),
    (TINY.replace("description:", "descriptin:"), r"tiny.yml:2: unknown key 'descriptin'"),
    (TINY.replace("    task: " + LEFT, "    task: " + LEFT + "\n    task: " + RIGHT),
     r"tiny.yml:6: key 'task' given twice"),
    (TINY + "targets: [containr]\n", r"target 'containr' is not a node; did you mean 'container'"),
    (TINY.replace("  - name: left\n", "  - name: left@2\n"), r"tiny.yml:4: node 'left@2': names may not contain '@'"),
    (TINY.replace("  - name: above\n", "  - name: above\n    timesteps: -5\n"),
     r"tiny.yml:6: node 'above': 'timesteps' must be a positive integer, got -5"),
    (TINY.replace("  - name: above\n", "  - name: above\n    budget_scale: 0\n"),
     r"tiny.yml:6: node 'above': 'budget_scale' must be a positive number, got 0"),
    (TINY.replace("  - name: above\n", "  - name: above\n    budget_scale: .nan\n"),
     r"tiny.yml:6: node 'above': 'budget_scale' must be a positive number, got nan"),
    (TINY.replace("  - name: above\n", "  - name: above\n    count_primitive_steps: yes please\n"),
     r"tiny.yml:6: node 'above': 'count_primitive_steps' must be true or false, got 'yes please'"),
    ("nodes: []\n", r"tiny.yml: missing key 'curriculum'"),
    (TINY + "1: x\n", r"tiny.yml: top-level keys must be names, got 1"),
    ("- a\n- b\n", r"tiny.yml: a curriculum file is a mapping"),
])
def test_invalid_curricula_name_file_line_and_node(tmp_path, text, message):
    path = tmp_path / "tiny.yml"
    path.write_text(text)
    with pytest.raises(CurriculumError, match=message):
        load_curriculum(path)


def test_a_valid_file_round_trips_and_resolves(tmp_path):
    path = tmp_path / "tiny.yml"
    path.write_text(TINY)
    curriculum = resolve_curriculum(str(path))
    assert curriculum.targets == ("container",) and curriculum.levels() == [["left", "above"], ["container"]]
    again = parse_curriculum(curriculum.to_yaml(), "again")
    assert again.nodes == curriculum.nodes and again.targets == curriculum.targets
    with pytest.raises(CurriculumError, match="no shipped curriculum named 'con2-c'; did you mean 'con2-cl'"):
        resolve_curriculum("con2-c")


def test_a_budget_scale_multiplies_whichever_budget_a_node_has(tmp_path):
    """``budget_scale`` multiplies the run's budget, the node's own or the default; it round-trips through the file
    format, and a node without one has the settings it had before the key existed (runs of then resume)."""
    from sb3_smc.core.hyperparameters import DEFAULT_TIMESTEPS
    from sb3_smc.curricula.jobs import node_budget, node_spec

    text = TINY.replace("    uses: [left, above]", "    uses: [left, above]\n    budget_scale: 2.5")
    curriculum = parse_curriculum(text.replace("  - name: above\n", "  - name: above\n    timesteps: 3000\n"))
    container, above, left = map(curriculum.node, ("container", "above", "left"))
    assert container.budget_scale == 2.5 and left.budget_scale == 1.0
    assert [node_budget(container, t) for t in (None, 2000)] == [round(2.5 * DEFAULT_TIMESTEPS), 5000]
    assert [node_budget(above, t) for t in (None, 2000)] == [3000, 2000]
    assert node_spec(container, 0, ("left@0", "above@0"), timesteps=2000).budget.total_timesteps == 5000
    assert "budget_scale" not in left.settings() and container.settings()["budget_scale"] == 2.5
    assert parse_curriculum(curriculum.to_yaml()).nodes == curriculum.nodes
    assert "budget x2.5" in describe(curriculum)
    with pytest.raises(CurriculumError, match="node 'x': budget_scale must be a positive number, got -1"):
        Curriculum("bad", (Node("x", LEFT, budget_scale=-1),), ("x",))
    with pytest.raises(CurriculumError, match="node 'x': budget_scale must be a positive number, got True"):
        Curriculum("bad", (Node("x", LEFT, budget_scale=True),), ("x",))
    assert node_budget(Node("x", LEFT, budget_scale=1e-9), 2000) == 1  # never a budget of nothing
    everywhere = parse_curriculum(TINY.replace("nodes:", "defaults: {budget_scale: 3}\nnodes:"))
    assert {n.budget_scale for n in everywhere.nodes} == {3.0}  # a default like the other settings
    with pytest.raises(CurriculumError, match="node 'container' is defined differently"):  # part of a node's identity
        merge([curriculum, Curriculum("other", (*curriculum.nodes[:2], dataclasses.replace(container, budget_scale=1)),
                                      ("container",))])


def test_a_node_whose_calls_cost_their_moves(tmp_path):
    """``count_primitive_steps: true`` makes the node's SMC calls cost the episode the moves they made (its spec's
    wrapper setting); it round-trips through the file format, is part of a node's identity, and a node without it has
    the settings it had before the key existed (runs of then resume)."""
    from sb3_smc.curricula.jobs import node_spec

    curriculum = parse_curriculum(TINY.replace("    uses: [left, above]",
                                               "    uses: [left, above]\n    count_primitive_steps: true"))
    container, left = curriculum.node("container"), curriculum.node("left")
    assert container.count_primitive_steps and not left.count_primitive_steps
    assert node_spec(container, 0, ("left@0", "above@0")).wrapper.count_primitive_steps
    assert not node_spec(left, 0, ()).wrapper.count_primitive_steps
    assert "count_primitive_steps" not in left.settings() and container.settings()["count_primitive_steps"] is True
    assert parse_curriculum(curriculum.to_yaml()).nodes == curriculum.nodes
    assert "calls cost their moves" in describe(curriculum) and describe(curriculum).count("calls cost") == 1
    with pytest.raises(CurriculumError, match="node 'x': count_primitive_steps must be true or false, got 1"):
        Curriculum("bad", (Node("x", LEFT, count_primitive_steps=1),), ("x",))  # type: ignore[arg-type]
    with pytest.raises(CurriculumError, match="node 'container' is defined differently"):
        merge([curriculum, Curriculum("other", (*curriculum.nodes[:2],
                                                dataclasses.replace(container, count_primitive_steps=False)),
                                      ("container",))])


def test_a_node_with_its_own_episode_length_and_call_cap() -> None:
    """``max_steps`` / ``call_step_cap`` go to the node's spec's wrapper settings, round-trip through the file
    format, are part of a node's identity, and a node without them has the settings it had before they existed."""
    from sb3_smc.curricula.jobs import node_spec

    curriculum = parse_curriculum(TINY.replace("    uses: [left, above]",
                                               "    uses: [left, above]\n    max_steps: 400\n    call_step_cap: 25"))
    container, left = curriculum.node("container"), curriculum.node("left")
    assert (container.max_steps, container.call_step_cap, left.max_steps, left.call_step_cap) == (400, 25, 100, 100)
    wrapper = node_spec(container, 0, ("left@0", "above@0")).wrapper
    assert (wrapper.max_steps, wrapper.call_step_cap) == (400, 25)
    assert node_spec(left, 0, ()).wrapper == node_spec(Node("left", LEFT), 0, ()).wrapper
    assert not {"max_steps", "call_step_cap"} & set(left.settings())
    assert (container.settings()["max_steps"], container.settings()["call_step_cap"]) == (400, 25)
    assert parse_curriculum(curriculum.to_yaml()).nodes == curriculum.nodes
    assert "400 steps an episode, calls cut at 25 moves" in describe(curriculum)
    with pytest.raises(CurriculumError, match="node 'container' is defined differently"):
        merge([curriculum, Curriculum("other", (*curriculum.nodes[:2], dataclasses.replace(container, max_steps=100)),
                                      ("container",))])


@pytest.mark.parametrize("key, value", [("max_steps", 0), ("max_steps", True), ("call_step_cap", 2.5),
                                        ("call_step_cap", "ten")])
def test_a_bad_episode_length_or_call_cap_names_the_line(key: str, value: object) -> None:
    text = TINY.replace("  - name: above\n", f"  - name: above\n    {key}: {value!r}\n".replace("'", ""))
    with pytest.raises(CurriculumError, match=rf"tiny.yml:6: node 'above': '{key}' must be a positive integer"):
        parse_curriculum(text, source="tiny.yml")
    with pytest.raises(CurriculumError, match=rf"node 'x': {key} must be a positive integer"):
        Curriculum("bad", (Node("x", LEFT, **{key: value}),), ("x",))  # type: ignore[arg-type]


def test_bad_hyperparameters_stop_before_any_training(tmp_path):
    path = tmp_path / "tiny.yml"
    path.write_text(TINY.replace("    uses: [left, above]", "    uses: [left, above]\n    hyperparameters: "
                                                                "{n_steps: 5}"))
    with pytest.raises(CurriculumError, match=r"tiny.yml:8: node 'container': hyperparameter 'n_steps'"):
        train_curriculum(str(path), tmp_path / "run", seeds=1, timesteps=2000, progress=False)
    assert not (tmp_path / "run" / "library").exists()


# ------------------------------------------------------------------------------------------------ reuse

def _record(value: float | None) -> TrainingRecord:
    returns = (0.0,) if value is None else (value,)
    return TrainingRecord(training_returns=(float("nan"),) if value is None else returns, success_rates=(0.0,),
                          selected_update=None if value is None else 0, selected_return=value, total_timesteps=2000,
                          primitive_steps=2000, wall_time_s=1.0)


def test_seeds_rank_by_selected_training_return():
    records = {0: _record(0.2), 1: _record(0.9), 2: _record(None), 3: _record(0.9), 4: _record(0.5)}
    assert rank_seeds(records) == [1, 3, 4, 0, 2]  # ties to the lower seed, never-selected last
    assert rank_seeds(records)[:2] == [1, 3]  # two_best
    assert rank_seeds(records)[:1] == [1]  # one_best


def test_the_longest_chain_starts_first_and_top_nodes_fill_in(tmp_path):
    from sb3_smc.curricula.options import RunOptions
    from sb3_smc.curricula.scheduler import Scheduler

    deep = parse_curriculum(TINY.replace("curriculum: tiny", "curriculum: deep") + f"""\
  - name: top
    task: {RIGHT}
    uses: [container]
  - name: flat
    task: {RIGHT}
""")
    order = deep.order()
    assert order.index("flat") < order.index("container")  # lower levels first: the flat node comes early
    scheduler = Scheduler(deep, order, RunOptions(seeds=2, timesteps=1000), tmp_path)
    assert scheduler.height == {"left": 2, "above": 2, "container": 1, "top": 0, "flat": 0}
    first = [job for job in scheduler.ready()]
    assert first == [("left", 0), ("left", 1), ("above", 0), ("above", 1), ("flat", 0), ("flat", 1)]
    for node in ("left", "above"):
        scheduler.records[node] = {0: _record(0.5), 1: _record(0.4)}
    assert scheduler.ready()[:2] == [("container", 0), ("container", 1)]
    assert scheduler.jobs()[:2] == [(order[0], 0), (order[0], 1)]  # tables keep the curriculum's order


def test_seeds_form_groups_of_up_to_group_size_spread_over_the_workers(tmp_path):
    from sb3_smc.curricula.jobs import JobId
    from sb3_smc.curricula.options import RunOptions
    from sb3_smc.curricula.scheduler import Scheduler

    curriculum = parse_curriculum(TINY + f"""\
  - name: trpo
    task: {RIGHT}
    algo: TRPO
  - name: top
    task: {RIGHT}
    uses: [container]
  - name: container-noprim
    task: {CONTAINER}
    uses: [left, above]
    primitives: false
""")
    scheduler = Scheduler(curriculum, curriculum.order(), RunOptions(seeds=5, timesteps=1000), tmp_path)
    # flat nodes and a level-2 node over flat ones group (one without primitives too: its spec needs its children);
    # a level-3 node and a memoryless learner do not
    assert [scheduler.groupable(n) for n in ("left", "above", "container", "trpo", "top", "container-noprim")] == [
        True, True, True, False, False, True]
    left, above = [JobId("left", s) for s in range(5)], [JobId("above", s) for s in range(5)]
    container, trpo, top = [JobId("container", s) for s in range(2)], [JobId("trpo", 0)], [JobId("top", 0)]

    def sizes(ready, group_size, workers):
        units = scheduler.units(ready, group_size, workers)
        assert [job for unit in units for job in unit] == ready  # every ready job once, in its order
        assert all(len({node for node, _ in unit}) == 1 for unit in units)  # a group is seeds of one node
        return [len(unit) for unit in units]

    assert sizes(left + above, 5, 2) == [5, 5]
    assert sizes(left + above, 1, 2) == [1] * 10  # one job per worker, as before groups
    assert sizes(left + above, 2, 1) == [2, 2, 1, 2, 2, 1]
    assert sizes(left, 5, 1) == [5]
    assert sizes(left, 5, 2) == [3, 2]  # a lone node's seeds spread over the workers
    assert sizes(left, 5, 4) == [1, 1, 1, 2] and sizes(left[:2], 5, 8) == [1, 1]
    assert sizes(left[:3] + trpo, 5, 2) == [3, 1]
    assert sizes(trpo + top + container + left[3:], 5, 1) == [1, 1, 2, 2]  # trpo and top gain nothing: alone
    assert scheduler.units([], 5, 2) == []
    # a group whose training is saved in the run's checkpoints goes on whole; the others are halved as before
    from sb3_smc.learning.group_checkpoint import checkpoint_path

    saved = checkpoint_path(tmp_path / "checkpoints", [str(job) for job in left])
    saved.parent.mkdir()
    saved.write_bytes(b"")
    assert sizes(left, 5, 2) == [5] and sizes(left[:4], 5, 2) == [2, 2]
    assert sizes(left + above[:4], 5, 4) == [5, 1, 1, 2]
    with pytest.raises(ValueError, match="group_size must be a positive integer, got 0"):
        train_curriculum(str(_tiny(tmp_path)), tmp_path / "run", seeds=1, group_size=0, progress=False)


# ------------------------------------------------------------------------------------------------ training

def _tiny(tmp_path: Path) -> Path:
    path = tmp_path / "tiny.yml"
    path.write_text(TINY)
    return path


def _library_state(path: Path) -> dict[str, tuple[dict, dict, dict[str, torch.Tensor]]]:
    """Every SMC of a library: its manifest entry's spec and record (but the wall time) and its policy's weights."""
    library = SMCLibrary.load(path)
    out = {}
    for name in library:
        smc = library[name]
        assert smc.spec is not None and smc.record is not None
        record = smc.record.to_dict()
        record.pop("wall_time_s")
        out[name] = (smc.spec.to_dict(), record, smc.model.policy.state_dict())
    return out


def assert_same_library(got: dict, expected: dict) -> None:
    """The same SMCs, bit for bit: specs, records (but wall times) and weights."""
    assert got.keys() == expected.keys()
    for name, (spec, record, weights) in expected.items():
        assert got[name][:2] == (spec, record), name
        assert got[name][2].keys() == weights.keys() and all(
            torch.equal(got[name][2][key], value) for key, value in weights.items()), name


def test_tiny_two_level_curriculum_end_to_end(tmp_path):
    run = train_curriculum(str(_tiny(tmp_path)), tmp_path / "run", seeds=2, timesteps=2000, progress=False)
    library = SMCLibrary.load(run.library)
    assert library.names == ("left@0", "left@1", "above@0", "above@1", "container@0", "container@1")
    records = {s: library[job_name("left", s)].record for s in (0, 1)}
    best_left = rank_seeds(records)
    container = library["container@1"]
    assert container.spec.children == tuple(job_name("left", s) for s in best_left) + tuple(
        job_name("above", s) for s in rank_seeds({s: library[job_name("above", s)].record for s in (0, 1)}))
    assert container.action_names[-4:] == tuple(f"SMC:{c}" for c in container.spec.children)
    assert container.spec.budget.total_timesteps == 2000 and container.spec.seed == 1
    assert [(r["node"], r["seed"]) for r in run.rows] == [(n, s) for n in ("left", "above", "container")
                                                         for s in (0, 1)]
    assert len(list((tmp_path / "run" / "tensorboard").glob("container@1_*"))) == 1
    assert "| container | 1 |" in run.table()
    state = status(tmp_path / "run")
    assert len(state["done"]) == 6 and state["left"] == state["running"] == state["failed"] == []
    # one_best: a caller gets one seed of each node
    one = train_curriculum(str(_tiny(tmp_path)), tmp_path / "one", seeds=2, timesteps=2000, reuse="one_best",
                           targets=["container"], progress=False)
    assert len(SMCLibrary.load(one.library)["container@0"].spec.children) == 2


def test_the_learner_of_every_node_is_chosen_by_algo_and_rnn(tmp_path):
    from sb3_smc.common.recurrent import SequenceGruPolicy
    from sb3_smc.recurrent_trpo import RecurrentTRPO

    path = _tiny(tmp_path)
    with pytest.raises(ValueError, match="rnn must be one of"):
        train_curriculum(str(path), tmp_path / "bad", seeds=1, timesteps=2000, rnn="rnn", progress=False)
    with pytest.raises(CurriculumError, match="node 'left': rnn='gru' needs a recurrent algorithm"):
        train_curriculum(str(path), tmp_path / "bad", seeds=1, timesteps=2000, algo="TRPO", rnn="gru",
                         progress=False)
    run = train_curriculum(str(path), tmp_path / "run", seeds=1, timesteps=2000, algo="RecurrentTRPO", rnn="gru",
                           progress=False)
    library = SMCLibrary.load(run.library)
    for name in ("left@0", "above@0", "container@0"):
        smc = library[name]
        assert isinstance(smc.model, RecurrentTRPO) and isinstance(smc.model.policy, SequenceGruPolicy), name
        assert smc.spec.algo == "RecurrentTRPO" and smc.spec.hyperparameters["policy"] == "SequenceGruPolicy"
    settings = json.loads((tmp_path / "run" / "run.json").read_text())
    assert (settings["algo"], settings["rnn"]) == ("RecurrentTRPO", "gru")
    with pytest.raises(RunSettingsError, match="rnn"):
        train_curriculum(str(path), tmp_path / "run", seeds=1, timesteps=2000, algo="RecurrentTRPO", progress=False)


def test_skipped_jobs_are_not_trained_unless_a_job_to_train_needs_them(tmp_path):
    path = str(_tiny(tmp_path))
    for bad in ("container@2", "container@01", "nothing@0", "container"):
        with pytest.raises(ValueError, match=f"skip: '{bad}' is not a job of this run"):
            train_curriculum(path, tmp_path / "bad", seeds=2, timesteps=2000, skip=[bad], progress=False)
    with pytest.raises(TypeError, match="collection of job names"):
        train_curriculum(path, tmp_path / "bad", seeds=2, timesteps=2000, skip="container@1", progress=False)
    lines: list[str] = []
    run = train_curriculum(path, tmp_path / "run", seeds=2, timesteps=2000, skip=iter(["container@0"]),
                           printer=lines.append)
    assert SMCLibrary.load(run.library).names == ("left@0", "left@1", "above@0", "above@1", "container@1")
    assert "(1 already done, 1 of them skipped)" in lines[0]
    state = status(tmp_path / "run")
    assert state["skipped"] == ["container@0"] and state["left"] == [] and len(state["done"]) == 5
    nothing = train_curriculum(path, tmp_path / "top", seeds=2, timesteps=2000,
                               skip=["container@0", "container@1"], progress=False)
    assert not (nothing.library / "manifest.json").exists()  # no job left: its lower levels are not needed
    assert nothing.rows == []
    # nested targets (as in the pushable curriculum): a skipped job whose node a job to train uses is trained anyway,
    # since that job's children are the best of every seed
    both = ["left", "container"]
    needed = train_curriculum(path, tmp_path / "nested", seeds=2, timesteps=2000, targets=both,
                              skip=["left@0", "left@1", "container@0"], progress=False)
    assert SMCLibrary.load(needed.library).names == ("left@0", "left@1", "above@0", "above@1", "container@1")
    alone = train_curriculum(path, tmp_path / "alone", seeds=2, timesteps=2000, targets=both,
                             skip=["left@0", "container@0", "container@1"], progress=False)
    assert SMCLibrary.load(alone.library).names == ("left@1",)  # container needs nothing now: no 'above' either
    state = status(tmp_path / "alone")
    assert state["left"] == [] and state["done"] == ["left@1"]
    assert sorted(state["skipped"]) == ["above@0", "above@1", "container@0", "container@1", "left@0"]


def test_changed_settings_are_refused_with_the_differences(tmp_path):
    path = _tiny(tmp_path)
    train_curriculum(str(path), tmp_path / "run", seeds=1, timesteps=2000, targets=["left"], progress=False)
    with pytest.raises(RunSettingsError, match=r"seeds: 1 in the directory, 2 now"):
        train_curriculum(str(path), tmp_path / "run", seeds=2, timesteps=2000, targets=["left"], progress=False)
    with pytest.raises(RunSettingsError, match=r"node 'above': new in this run"):
        train_curriculum(str(path), tmp_path / "run", seeds=1, timesteps=2000, targets=["left", "above"],
                         progress=False)
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "notes.txt").write_text("mine")
    with pytest.raises(RunSettingsError, match=r"not empty and holds no run.json: not a curriculum run directory$"):
        train_curriculum(str(path), tmp_path / "other", seeds=1, timesteps=2000, progress=False)
    (tmp_path / "kept" / "evaluations").mkdir(parents=True)  # records copied back without their run.json
    with pytest.raises(RunSettingsError, match=r"no run.json: .*\(a run kept as records .*copy its run.json too\)"):
        train_curriculum(str(path), tmp_path / "kept", seeds=1, timesteps=2000, progress=False)


def test_a_failing_job_is_reported_and_retried(tmp_path, monkeypatch):
    from sb3_smc.curricula import trainer

    path = tmp_path / "tiny.yml"
    path.write_text(TINY.replace("name: container", "name: tiny/container"))

    def run_job(job):
        if job.spec.name == "tiny/container@0":
            raise RuntimeError("out of luck")
        return real(job)

    real = trainer.run_job
    monkeypatch.setattr(trainer, "run_job", run_job)
    run = train_curriculum(str(path), tmp_path / "run", seeds=1, timesteps=2000, group_size=1, progress=False)
    assert set(run.failed) == {"tiny/container@0"} and "out of luck" in run.failed["tiny/container@0"]
    assert (tmp_path / "run" / "failed" / "tiny%2Fcontainer@0.txt").is_file()
    state = status(tmp_path / "run")
    assert state["done"] == ["left@0", "above@0"] and state["failed"] == ["tiny/container@0"] and state["left"] == []
    monkeypatch.setattr(trainer, "run_job", real)
    again = train_curriculum(str(path), tmp_path / "run", seeds=1, timesteps=2000, group_size=1, progress=False)
    assert not again.failed and status(tmp_path / "run")["done"] == ["left@0", "above@0", "tiny/container@0"]
    assert not (tmp_path / "run" / "failed" / "tiny%2Fcontainer@0.txt").exists()


def test_hyperparameters_that_do_not_decode_stop_before_training(tmp_path):
    path = tmp_path / "tiny.yml"
    path.write_text(TINY.replace("  - name: above\n", "  - name: above\n    hyperparameters: {learning_rate: lin_x}\n"))
    with pytest.raises(CurriculumError, match="tiny.yml:6: node 'above': hyperparameter learning_rate: 'lin_x'"):
        train_curriculum(str(path), tmp_path / "run", seeds=1, timesteps=2000, progress=False)
    assert not (tmp_path / "run" / "run.json").exists()  # nothing written: the fixed file can use the same --out


def test_one_coordinator_per_run_directory(tmp_path):
    import fcntl

    out = tmp_path / "run"
    train_curriculum(str(_tiny(tmp_path)), out, seeds=1, timesteps=2000, targets=["left"], progress=False)
    with open(out / ".lock", "a+") as held:
        fcntl.flock(held.fileno(), fcntl.LOCK_EX)
        with pytest.raises(RunSettingsError, match="being trained by another process"):
            train_curriculum(str(_tiny(tmp_path)), out, seeds=1, timesteps=2000, targets=["left"], progress=False)


def test_a_partial_library_cannot_replace_the_whole(tmp_path):
    run = train_curriculum(str(_tiny(tmp_path)), tmp_path / "run", seeds=1, timesteps=2000, progress=False)
    partial = SMCLibrary.load(run.library, names=["left@0"])
    assert partial.names == ("left@0",) and partial.path is None
    with pytest.raises(Exception, match="needs a path"):
        partial.save()
    assert len(SMCLibrary.load(run.library)) == 3


def test_resuming_a_half_done_group_trains_only_its_missing_smcs(tmp_path, monkeypatch):
    """SMCs taken out of a finished run's library (as if the run had died while storing a group's results): the next
    run trains only them, together, and they are the SMCs they were; the others' files are untouched."""
    from sb3_smc.curricula import trainer
    from sb3_smc.library import storage

    path, out = str(_tiny(tmp_path)), tmp_path / "run"
    settings = {"seeds": 3, "timesteps": 2000, "targets": ["left", "above"], "tensorboard": False}
    train_curriculum(path, out, progress=False, **settings)
    expected = _library_state(out / "library")
    trained: list[tuple[str, ...]] = []

    def counted(run):
        def run_and_count(work):
            trained.append(tuple(job.spec.name for job in ([work] if isinstance(work, trainer.Job) else work)))
            return run(work)
        return run_and_count

    monkeypatch.setattr(trainer, "run_job", counted(trainer.run_job))
    monkeypatch.setattr(trainer, "run_group", counted(trainer.run_group))
    manifest = out / "library" / "manifest.json"
    for missing, units in ((["left@1"], [("left@1",)]), (["left@0", "left@2", "above@1"],
                                                          [("left@0", "left@2"), ("above@1",)])):
        kept = {n: e for n, e in json.loads(manifest.read_text())["smcs"].items() if n not in missing}
        stamps = {n: (out / "library" / e["model"]).stat().st_mtime_ns for n, e in kept.items()}
        storage.remove_from_library(out / "library", missing)
        trained.clear()
        lines: list[str] = []
        train_curriculum(path, out, printer=lines.append, **settings)
        assert f"({6 - len(missing)} already done)" in lines[0]
        assert trained == units
        after = json.loads(manifest.read_text())["smcs"]
        assert all(after[n] == e and (out / "library" / e["model"]).stat().st_mtime_ns == stamps[n]
                   for n, e in kept.items())
        assert_same_library(_library_state(out / "library"), expected)


def test_a_failing_group_fails_each_of_its_jobs_and_stores_none(tmp_path, monkeypatch):
    from sb3_smc.curricula import trainer

    def broken(jobs):
        raise RuntimeError(f"lost {len(jobs)} jobs")

    monkeypatch.setattr(trainer, "run_group", broken)
    path, out = str(_tiny(tmp_path)), tmp_path / "run"
    run = train_curriculum(path, out, seeds=2, timesteps=2000, progress=False)
    assert run.failed == dict.fromkeys(["left@0", "left@1", "above@0", "above@1"], "RuntimeError: lost 2 jobs")
    assert all((out / "failed" / f"{name}.txt").is_file() for name in run.failed)
    state = status(out)
    assert state["done"] == [] and state["failed"] == sorted(run.failed) and state["left"] == ["container@0",
                                                                                               "container@1"]
    monkeypatch.undo()
    again = train_curriculum(path, out, seeds=2, timesteps=2000, progress=False)
    assert not again.failed and len(status(out)["done"]) == 6 and not list((out / "failed").iterdir())


def test_a_group_stopped_mid_training_resumes_from_its_checkpoint(tmp_path, monkeypatch):
    """A group whose worker stops between two updates (here: an error in its third rollout, after two updates were
    saved) is trained on from its checkpoint in the run directory by the next run, which trains only the updates
    after it and gives the library an uninterrupted run gives; the checkpoints go when the run is complete."""
    import sb3_smc.learning.batched as batched_module
    from sb3_smc.curricula import jobs as jobs_module

    path, out = str(_tiny(tmp_path)), tmp_path / "run"
    settings = {"seeds": 2, "timesteps": 6000, "targets": ["left", "above"], "tensorboard": False, "progress": False}
    end_rollout = batched_module._Job.end_rollout
    updates: list[str] = []
    stops: list[str] = []

    def stopped(job):
        if job.spec.name.startswith("left@") and job.iteration == 2 and not stops:
            stops.append(job.spec.name)
            raise RuntimeError("stopped")  # the first attempt only
        updates.append(job.spec.name)
        end_rollout(job)

    monkeypatch.setattr(jobs_module, "CHECKPOINT_EVERY", 0.0)
    monkeypatch.setattr(batched_module._Job, "end_rollout", stopped)
    first = train_curriculum(path, out, **settings)
    assert set(first.failed) == {"left@0", "left@1"} and len(list((out / "checkpoints").glob("group-*.pkl"))) == 1
    updates.clear()
    again = train_curriculum(path, out, **settings)
    assert not again.failed and sorted(updates) == ["left@0", "left@1"]  # the third update of each, no more
    assert not (out / "checkpoints").exists()
    monkeypatch.undo()
    assert_same_library(_library_state(out / "library"), _library_state(
        train_curriculum(path, tmp_path / "fresh", **settings).library))


def test_other_work_runs_on_the_workers_and_its_first_error_is_raised():
    """``map_unordered`` (an experiment's evaluations after training): every item's result, in this process in
    order for one worker, on 2 spawned processes as they finish; an item's error is raised, after the items yielded
    before it."""
    from sb3_smc.curricula.executors import map_unordered
    from sb3_smc.curricula.options import RunOptions

    one, two = RunOptions(workers=1), RunOptions(workers=2)
    assert list(map_unordered(math.factorial, [5, 3, 4], one)) == [(5, 120), (3, 6), (4, 24)]
    assert sorted(map_unordered(math.factorial, [5, 3, 4], two)) == [(3, 6), (4, 24), (5, 120)]
    assert list(map_unordered(math.factorial, [], two)) == []
    for options in (one, two):
        done = []
        with pytest.raises(ValueError, match="negative values"):
            for item, _ in map_unordered(math.factorial, [3, -1], options):
                done.append(item)
        assert done == [3] if options is one else done in ([3], [])  # on workers: as they finish


def test_ray_without_a_cluster_says_how_to_connect(tmp_path, monkeypatch):
    monkeypatch.delenv("RAY_ADDRESS", raising=False)
    with pytest.raises(RuntimeError, match="existing Ray cluster: pass ray_address"):
        train_curriculum(str(_tiny(tmp_path)), tmp_path / "run", seeds=1, timesteps=2000, backend="ray",
                         progress=False)


def test_kill_and_resume_trains_no_job_twice(tmp_path):
    """SIGKILL the CLI while it trains (flat seeds in groups: it may be killed between storing a group's SMCs), run it
    again: finished jobs keep their files, the rest is trained once."""
    path = _tiny(tmp_path)
    out = tmp_path / "run"
    command = [sys.executable, "-m", "sb3_smc.cli", "train", str(path), "--out", str(out), "--seeds", "2",
               "--timesteps", "4000"]
    manifest = out / "library" / "manifest.json"
    process = subprocess.Popen(command, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    deadline = time.time() + 120
    while time.time() < deadline:
        if manifest.is_file() and len(json.loads(manifest.read_text())["smcs"]) >= 2:
            break
        time.sleep(0.05)
    process.send_signal(signal.SIGKILL)
    process.wait()
    finished = json.loads(manifest.read_text())["smcs"]
    assert 2 <= len(finished) < 6, "the run ended before it could be killed"
    files = {name: (out / "library" / e["model"]).stat().st_mtime_ns for name, e in finished.items()}
    state = status(out)
    assert state["running"] == [] and len(state["done"]) == len(finished)  # the dead coordinator runs nothing

    result = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout + result.stderr
    assert f"({len(finished)} already done)" in result.stdout
    progress = [int(line.split()[1].split("/")[0]) for line in result.stdout.splitlines() if line.startswith("jobs ")]
    assert progress[-1] == 6 and all(len(finished) < a < b for a, b in pairwise(progress))  # SMCs counted
    after = json.loads(manifest.read_text())["smcs"]
    assert len(after) == 6
    assert all(after[name]["record"] == finished[name]["record"] for name in finished)  # never trained again
    assert all((out / "library" / after[n]["model"]).stat().st_mtime_ns == files[n] for n in finished)
    assert_same_library(_library_state(out / "library"), _library_state(
        train_curriculum(str(path), tmp_path / "fresh", seeds=2, timesteps=4000, progress=False).library))


def _alive(pid: int) -> bool:
    """Whether process ``pid`` runs (a zombie that no one has reaped yet has ended)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def _children(pid: int) -> list[int]:
    """The processes whose parent is ``pid`` (Linux /proc)."""
    out = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue  # ended meanwhile
        if int(fields[1]) == pid:
            out.append(int(stat.parent.name))
    return out


def _training_on_two_workers(tmp_path: Path) -> tuple[subprocess.Popen, list[int]]:
    """``sb3-smc train --workers 2`` started, once both its workers train: the process (stderr piped) and the pids
    of its children."""
    command = [sys.executable, "-m", "sb3_smc.cli", "train", str(_tiny(tmp_path)), "--out", str(tmp_path / "run"),
               "--seeds", "2", "--timesteps", "400000", "--workers", "2", "--no-tensorboard"]
    process = subprocess.Popen(command, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 120
    while time.time() < deadline and len(status(tmp_path / "run")["running"] if (tmp_path / "run" / "state.json")
                                             .is_file() else []) < 2:
        time.sleep(0.1)
    time.sleep(3.0)  # the workers have started their jobs
    workers = _children(process.pid)
    assert len(workers) >= 2, "the run did not start its workers"
    return process, workers


def _left_alive(workers: list[int]) -> list[int]:
    """Those of ``workers`` still alive 15 s on (killed then, so that a failing test leaves none behind)."""
    deadline = time.time() + 15
    while time.time() < deadline and any(map(_alive, workers)):
        time.sleep(0.2)
    alive = [pid for pid in workers if _alive(pid)]
    for pid in alive:
        os.kill(pid, signal.SIGKILL)
    return alive


@pytest.mark.skipif(not Path("/proc/self/stat").is_file(), reason="reads the process table from /proc")
def test_a_killed_run_leaves_no_worker_training(tmp_path):
    """SIGKILL the run's process while its two workers train: the workers end too (within seconds), instead of
    training their jobs on for nothing."""
    process, workers = _training_on_two_workers(tmp_path)
    process.send_signal(signal.SIGKILL)
    process.communicate()
    assert not _left_alive(workers), "workers went on after their run was killed"


@pytest.mark.skipif(not Path("/proc/self/stat").is_file(), reason="reads the process table from /proc")
def test_sigterm_stops_a_run_with_workers_as_ctrl_c_does(tmp_path):
    """SIGTERM to ``sb3-smc train --workers 2`` while its workers train: it says so and how to resume, exits 143,
    ends its workers and leaves no semaphore to the resource tracker (no "leaked semaphore" warning)."""
    process, workers = _training_on_two_workers(tmp_path)
    process.send_signal(signal.SIGTERM)
    _, err = process.communicate(timeout=60)
    assert process.returncode == 143, err
    assert err.strip().endswith("terminated: what finished is saved; run the same command again to resume"), err
    assert "leaked semaphore" not in err and "Traceback" not in err
    assert status(tmp_path / "run")["running"] == []
    assert not _left_alive(workers), "workers went on after their run was terminated"


def test_cli_lists_shows_trains_and_reports(tmp_path):
    def cli(*args: str) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, "-m", "sb3_smc.cli", *args], cwd=ROOT, capture_output=True,
                              text=True, timeout=300)

    listed = cli("curricula")
    assert listed.returncode == 0 and "con2-cl " in listed.stdout and "smc-curr" in listed.stdout
    shown = cli("curricula", "con2-cl")
    assert "level 2: 15 nodes" in shown.stdout and "* con2-cl/cl_self-in-container_vs_noncontainer" in shown.stdout
    bad = cli("curricula", str(tmp_path / "missing.yml"))
    assert bad.returncode == 2 and "cannot read curriculum file" in bad.stderr and "Traceback" not in bad.stderr
    trained = cli("train", str(_tiny(tmp_path)), "--out", str(tmp_path / "run"), "--targets", "left,above",
                  "--seeds", "1", "--timesteps", "2000", "--no-tensorboard")
    assert trained.returncode == 0, trained.stderr
    assert "| left | 0 |" in trained.stdout and "library:" in trained.stdout
    assert not (tmp_path / "run" / "tensorboard").exists()
    report = cli("status", str(tmp_path / "run"))
    assert "done        2" in report.stdout and "left        0" in report.stdout


def test_curriculum_objects_are_validated_too():
    with pytest.raises(CurriculumError, match="curriculum 'x': node 'a' uses an unknown node 'b'"):
        Curriculum("x", (Node("a", LEFT, ("b",)),), ("a",))
    assert os.environ.get("PIXELWORLD_CACHE")  # the suite never writes into the user's cache
    assert torch.get_num_threads() == 1


def test_a_script_without_a_main_guard_is_told_what_broke_its_workers(tmp_path):
    """Workers are spawned and import the calling script again: at its top level the run starts again in every
    worker, which dies; the failure says so instead of only 'process pool terminated abruptly'."""
    script = tmp_path / "train_it.py"
    script.write_text("from sb3_smc.curricula import train_curriculum\n"
                      f"train_curriculum({str(_tiny(tmp_path))!r}, {str(tmp_path / 'run')!r}, targets=['left'], "
                      "seeds=1, timesteps=2000, workers=2, progress=False)\n")
    result = subprocess.run([sys.executable, str(script)], cwd=ROOT, capture_output=True, text=True, timeout=300)
    failure = (tmp_path / "run" / "failed" / "left@0.txt").read_text()
    assert 'if __name__ == "__main__":' in failure and "BrokenProcessPool" in failure, result.stderr[-2000:]


# ------------------------------------------------------------------------------------------------ bad input and repair

@pytest.mark.parametrize(("setting", "message"), [
    ("{learning_rate: -1}", r"tiny.yml:8: node 'container': RecurrentPPO refuses its hyperparameters: ValueError: "
                            r"Invalid learning rate: -1.0"),
    ("{learnin_rate: 0.001}", r"tiny.yml:8: node 'container': hyperparameter 'learnin_rate' is not an argument of "
                              r"RecurrentPPO; did you mean 'learning_rate'\?"),
    ("{policy_kwargs: {lstm_hiden_size: 8}}", r"tiny.yml:8: node 'container': .*unexpected keyword argument "
                                              r"'lstm_hiden_size'"),
])
def test_a_bad_node_hyperparameter_stops_the_run_before_anything_is_trained(tmp_path, setting, message):
    path = tmp_path / "tiny.yml"
    path.write_text(TINY.replace("    uses: [left, above]", f"    uses: [left, above]\n    hyperparameters: {setting}"))
    with pytest.raises(CurriculumError, match=message):
        train_curriculum(str(path), tmp_path / "run", seeds=1, timesteps=2000, progress=False)
    code, out, err = sb3_smc_cli("train", str(path), "--out", str(tmp_path / "run"), "--seeds", "1")
    assert code == 2 and re.search(message, err) and out == "" and "Traceback" not in err
    assert not (tmp_path / "run").exists()  # nothing written: the fixed file can use the same --out
    code, _, err = sb3_smc_cli("curricula", str(path))  # the same check
    assert code == 2 and re.search(message, err)


def test_curricula_checks_what_train_checks(tmp_path):
    path = tmp_path / "tiny.yml"
    path.write_text(TINY.replace("  - name: above\n", "  - name: above\n    hyperparameters: {n_steps: 0}\n"))
    code, _, err = sb3_smc_cli("curricula", str(path))
    assert code == 2 and "tiny.yml:6: node 'above': hyperparameter 'n_steps' is not set through the hyperparameters" \
        in err
    path.write_text(TINY + "targets: [container, left, container]\n")
    with pytest.raises(CurriculumError, match="tiny.yml: target 'container' is listed twice"):
        load_curriculum(path)
    binary = tmp_path / "binary.yml"
    binary.write_bytes(b"\xff\xfe\x00curriculum")
    code, _, err = sb3_smc_cli("curricula", str(binary))
    assert code == 2 and "binary.yml: not a curriculum file: not UTF-8 text (byte 0xff at position 0)" in err
    same = tmp_path / "same.yml"  # a node named after its dataset: the suggestion names it once
    same.write_text(f"curriculum: same\nnodes:\n  - name: {LEFT}\n    task: {LEFT}\n")
    with pytest.raises(CurriculumError, match=rf"did you mean '{LEFT}'\?$"):
        load_curriculum(same).select([LEFT[:-1]])
    with pytest.raises(CurriculumError, match="--targets names no node"):
        load_curriculum(same).select([])


def test_changed_nodes_are_trained_again_with_accept_changes_the_others_kept(tmp_path):
    path = _tiny(tmp_path)
    out = tmp_path / "run"
    train_curriculum(str(path), out, seeds=1, timesteps=2000, progress=False)
    before = json.loads((out / "library" / "manifest.json").read_text())["smcs"]
    files = {name: (out / "library" / e["model"]).stat().st_mtime_ns for name, e in before.items()}
    path.write_text(TINY.replace("  - name: left\n", "  - name: left\n    hyperparameters: {learning_rate: 0.01}\n"))
    with pytest.raises(RunSettingsError, match=r"(?s)node 'left': hyperparameters \{\} in the directory, "
                                               r"\{'learning_rate': 0.01\} now.*sb3-smc train --accept-changes.*"
                                               r"the jobs of left, container are trained again, the other nodes keep "
                                               r"theirs"):
        train_curriculum(str(path), out, seeds=1, timesteps=2000, progress=False)
    with pytest.raises(RunSettingsError, match="--accept-changes takes changed nodes only; seeds decide every job"):
        train_curriculum(str(path), out, seeds=2, timesteps=2000, progress=False, accept_changes=True)
    code, stdout, err = sb3_smc_cli("train", str(path), "--out", str(out), "--seeds", "1", "--timesteps", "2000",
                             "--accept-changes")
    assert code == 0, err
    assert "node 'left' is trained again (changed)" in stdout
    assert "node 'container' is trained again (uses a changed node)" in stdout and "'above'" not in stdout
    assert "(1 already done)" in stdout  # above@0
    after = json.loads((out / "library" / "manifest.json").read_text())["smcs"]
    assert after["above@0"] == before["above@0"]
    assert (out / "library" / after["above@0"]["model"]).stat().st_mtime_ns == files["above@0"]
    assert after["left@0"]["spec"]["hyperparameters"]["learning_rate"] == 0.01
    [kept] = (out / "replaced").iterdir()  # what was replaced is kept, loadable
    old = SMCLibrary.load(kept / "library")
    assert old.names == ("left@0", "above@0", "container@0") and old["left@0"].record.to_dict() == before["left@0"][
        "record"]
    assert json.loads((kept / "run.json").read_text())["nodes"]["left"]["hyperparameters"] == {}
    assert len(list((kept / "tensorboard").glob("*@0_1"))) == 2
    assert status(out)["done"] == ["left@0", "above@0", "container@0"]
    assert train_curriculum(str(path), out, seeds=1, timesteps=2000, progress=False).rows  # the run is the new one
    # fewer targets: the nodes left out keep their jobs; another curriculum name is another run, refused
    train_curriculum(str(path), out, seeds=1, timesteps=2000, targets=["left"], progress=False, accept_changes=True)
    assert {"above@0", "container@0"} <= set(SMCLibrary.load(out / "library").names)
    renamed = tmp_path / "renamed.yml"
    renamed.write_text(path.read_text().replace("curriculum: tiny", "curriculum: other"))
    with pytest.raises(RunSettingsError, match="--accept-changes takes changed nodes only; curriculum decide"):
        train_curriculum(str(renamed), out, seeds=1, timesteps=2000, targets=["left"], progress=False,
                         accept_changes=True)


def test_a_damaged_model_file_is_reported_and_trained_again(tmp_path, monkeypatch):
    from sb3_smc.curricula import trainer

    path = _tiny(tmp_path)
    out = tmp_path / "run"
    train_curriculum(str(path), out, seeds=1, timesteps=2000, targets=["left", "container"], progress=False)
    manifest = out / "library" / "manifest.json"
    before = json.loads(manifest.read_text())["smcs"]
    model = out / "library" / before["left@0"]["model"]
    model.write_bytes(model.read_bytes()[:300])  # truncated
    (out / "library" / before["above@0"]["model"]).unlink()  # deleted
    truncated = f"SMC 'left@0': model file {model} does not match the SHA-256 recorded in the manifest"
    missing = f"SMC 'above@0': model file {out / 'library' / before['above@0']['model']} is missing"
    code, stdout, _ = sb3_smc_cli("status", str(out))
    assert code == 0 and re.search(r"damaged\s+2\s+left@0, above@0", stdout) and re.search(r"done\s+1\s", stdout)
    assert truncated in stdout and missing in stdout
    assert (f"trains them again:\n  sb3-smc train <the curriculum file of 'tiny'> --out {out} --targets left,container "
            "--seeds 1 --timesteps 2000 --reuse two_best") in stdout
    with pytest.raises(CorruptModelError, match=re.escape(truncated)):
        SMCLibrary.load(out / "library")
    lines: list[str] = []
    train_curriculum(str(path), out, seeds=1, timesteps=2000, targets=["left", "container"], printer=lines.append)
    assert "(1 already done)" in lines[0] and truncated in lines[1]
    after = json.loads(manifest.read_text())["smcs"]
    assert after["container@0"] == before["container@0"]  # trained alike: what uses them is kept
    assert {n: after[n]["record"]["training_returns"] for n in after} == {
        n: before[n]["record"]["training_returns"] for n in before}
    assert len(SMCLibrary.load(out / "library")) == 3 and status(out)["damaged"] == {}
    # trained again differently (another CPU, say): what was trained with the damaged copy is trained again too
    model = out / "library" / after["left@0"]["model"]  # the file of the model trained again (named by its bytes)
    model.write_bytes(b"")
    monkeypatch.setattr(trainer, "_trained_alike", lambda a, b: False)
    lines.clear()
    train_curriculum(str(path), out, seeds=1, timesteps=2000, targets=["left", "container"], printer=lines.append)
    assert any("left@0 trained again differs from its damaged copy's training" in line and "(container@0)" in line
               for line in lines)
    assert [line.split(",")[0] for line in lines if line.startswith("jobs ")] == ["jobs 3/3"]  # 2 + 1 again
    [kept] = (out / "replaced").iterdir()
    assert "container@0" in SMCLibrary.load(kept / "library", names=["container@0"])
    assert status(out)["done"] == ["left@0", "above@0", "container@0"]


def test_run_directory_files_and_a_full_disk_are_explained(tmp_path, monkeypatch):
    import errno

    from sb3_smc.library import storage

    path = str(_tiny(tmp_path))
    a_file = tmp_path / "a-file"
    a_file.write_text("x")
    code, _, err = sb3_smc_cli("train", path, "--out", str(a_file), "--seeds", "1")
    assert code == 2 and f"{a_file} is a file, not a run directory" in err
    out = tmp_path / "run"
    written = []

    def full(target, data):
        if str(target).endswith(".safetensors") and written:
            raise OSError(errno.ENOSPC, "No space left on device", str(target))
        written.append(target)
        return real(target, data)

    real = storage.atomic_write
    monkeypatch.setattr(storage, "atomic_write", full)
    code, _, err = sb3_smc_cli("train", path, "--out", str(out), "--seeds", "1", "--timesteps", "2000")
    assert code == 2 and "No space left on device (" in err and "the disk is full" in err
    assert "run the same command again to resume" in err and "Traceback" not in err
    state = status(out)
    assert state["done"] == ["left@0"] and state["running"] == [] and state["damaged"] == {}
    monkeypatch.setattr(storage, "atomic_write", real)
    code, stdout, _ = sb3_smc_cli("train", path, "--out", str(out), "--seeds", "1", "--timesteps", "2000")
    assert code == 0 and "(1 already done)" in stdout
    (out / "state.json").write_text("")
    code, _, err = sb3_smc_cli("status", str(out))
    assert code == 2 and f"{out / 'state.json'} is not valid JSON" in err and "delete it" in err
    (out / "run.json").write_text('{"format": "sb3-smc-run"')
    code, _, err = sb3_smc_cli("status", str(out))
    assert code == 2 and f"{out / 'run.json'} is not valid JSON (corrupt or truncated?)" in err
    assert "the settings of a curriculum run" in err
    (out / "run.json").write_text("[]")
    code, _, err = sb3_smc_cli("status", str(out))
    assert code == 2 and "is not the settings of an sb3-smc run" in err
    for option in ("--seeds", "--workers", "--timesteps", "--group-size"):
        code, _, err = sb3_smc_cli("train", path, "--out", str(tmp_path / "new"), option, "0")
        assert code == 2 and f"argument {option}: must be a positive integer, got 0" in err
    code, _, err = sb3_smc_cli("train", path, "--out", str(tmp_path / "new"), "--ray-address", "auto")
    assert code == 2 and "a Ray address ('auto') is for backend 'ray', not 'local'" in err
    assert not (tmp_path / "new").exists()


def test_a_kill_after_storing_a_differing_repair_still_retrains_what_is_above(tmp_path, monkeypatch):
    """The run dies after storing the repaired job (trained differently) and before taking out the jobs trained with
    its damaged copy: the next run takes them out first and trains them again."""
    from sb3_smc.curricula import trainer

    path = _tiny(tmp_path)
    out = tmp_path / "run"
    train_curriculum(str(path), out, seeds=1, timesteps=2000, targets=["left", "container"], progress=False)
    before = json.loads((out / "library" / "manifest.json").read_text())["smcs"]
    (out / "library" / before["left@0"]["model"]).write_bytes(b"")
    monkeypatch.setattr(trainer, "_trained_alike", lambda a, b: False)

    def killed(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(trainer, "_retrain_above", killed)
    with pytest.raises(KeyboardInterrupt):
        train_curriculum(str(path), out, seeds=1, timesteps=2000, targets=["left", "container"], progress=False)
    pending = json.loads((out / "retrain.json").read_text())
    assert pending == {"repaired": "left@0", "jobs": ["container@0"]}
    assert "container@0" in json.loads((out / "library" / "manifest.json").read_text())["smcs"]  # still there
    monkeypatch.undo()
    lines: list[str] = []
    train_curriculum(str(path), out, seeds=1, timesteps=2000, targets=["left", "container"], printer=lines.append)
    assert any("left@0 was trained again differently before the last run stopped" in line and "container@0" in line
               for line in lines)
    assert [line.split(",")[0] for line in lines if line.startswith("jobs ")] == ["jobs 3/3"]  # container again
    assert not (out / "retrain.json").exists() and status(out)["done"] == ["left@0", "above@0", "container@0"]
    [kept] = (out / "replaced").iterdir()
    assert "container@0" in SMCLibrary.load(kept / "library", names=["container@0"])


def test_a_record_that_stopped_at_the_largest_return_is_trained_alike_with_the_whole_budgets() -> None:
    """A job repaired after training began to stop at the largest return has a shorter record than the damaged copy
    trained with the whole budget: the same selection, so what was trained with the copy is kept."""
    from sb3_smc.curricula.trainer import _trained_alike
    from sb3_smc.records import TrainingRecord

    def record(returns: list[float], selected: int, steps: int) -> TrainingRecord:
        return TrainingRecord(training_returns=tuple(returns), success_rates=tuple(0.5 for _ in returns),
                              selected_update=selected, selected_return=returns[selected], total_timesteps=steps,
                              primitive_steps=steps, wall_time_s=1.0)

    whole = record([0.2, float("nan"), 1.0, 1.0, 0.9], 2, 10_000)
    assert _trained_alike(whole, record([0.2, float("nan"), 1.0], 2, 6_016))
    assert not _trained_alike(whole, record([0.3, float("nan"), 1.0], 2, 6_016))  # trained otherwise before
    assert not _trained_alike(whole, record([0.2, 1.0], 1, 4_016))


def test_the_probe_picks_the_worst_seeds_as_the_original_release_does():
    """``tools/probe_node.py --children worst``: the release's selection helper (a stable ascending sort of the seeds
    by training return, the first two kept); ``best``: the package's rule."""
    probe_node = import_tool("probe_node")
    records = {0: _record(0.2), 1: _record(0.9), 2: _record(None), 3: _record(0.9), 4: _record(0.5)}
    assert probe_node.chosen_seeds(records, "best") == [1, 3]
    assert probe_node.chosen_seeds(records, "worst") == [2, 0]  # never-selected first, then the lowest return
    tied = {s: _record(1.0) for s in range(5)}
    assert probe_node.chosen_seeds(tied, "worst") == probe_node.chosen_seeds(tied, "best") == [0, 1]


def test_progress_on_a_terminal_is_a_tqdm_bar_over_the_budget_steps(monkeypatch):
    """On a terminal the run's progress is a tqdm bar over its budget steps, described by the jobs done and running;
    a note is written above it; elsewhere, one line per round of finished jobs."""
    import io

    from sb3_smc.curricula.trainer import _Progress

    class Terminal(io.StringIO):
        def isatty(self) -> bool:
            return True

    screen = Terminal()
    monkeypatch.setattr(sys, "stdout", screen)
    bar = _Progress(2, 0, 800, 0, print)
    bar.show(2)
    bar.finished(400)
    bar.show(1)
    assert "jobs 0/2, running 2: " in screen.getvalue()  # drawn at once, before any job finished
    bar.note("job x failed: why")
    text = screen.getvalue()
    assert "jobs 1/2, running 1: " in text and "400/800" in text and "job x failed: why\n" in text
    bar.close()
    lines: list[str] = []
    plain = _Progress(2, 0, 800, 0, lines.append)
    plain.show(2)
    plain.finished(400)
    plain.show(1)
    assert len(lines) == 1 and lines[0].startswith("jobs 1/2, running 1, ")
