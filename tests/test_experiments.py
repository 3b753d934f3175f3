"""The paper's experiments: the design (methods, targets, nodes), the CNN baseline, a tiny run end to end with its
results table, resuming, and the report with its t-tests and figures."""

from __future__ import annotations

import csv
import json
import math
import os
import re
import shlex
import shutil
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
import torch
from PIL import Image

from sb3_smc.curricula.trainer import RunSettingsError
from sb3_smc.errors import SMCError
from sb3_smc.experiments import CATEGORIES, level2_targets, plan
from sb3_smc.experiments.claims import tally
from sb3_smc.experiments.cnn import CHANNELS, encode, train_cnn
from sb3_smc.experiments.design import EXPERIENCE_METHODS, PAPER_CATEGORIES, SWEEP_METHODS, SWEEP_TARGETS
from sb3_smc.experiments.report import write_report
from sb3_smc.experiments.runner import RESULT_FIELDS, cpu_model, reported, run_experiment
from sb3_smc.experiments.statistics import paired_ttest
from tests.helpers import import_tool

ROOT = Path(__file__).resolve().parents[1]
LEFT_OF = "cl_self-left-of-two-objects-vs-one"
IN_CONTAINER = "ba_self-in-container_from_between-potential-containers"


def test_level2_targets_match_the_paper():
    everything = level2_targets()
    assert len(everything) == 51
    sizes = {c: len(level2_targets(c)) for c in CATEGORIES}
    assert sizes == {"containment": 19, "objcon": 16, "objects": 15, "search": 1, "pushable": 8}
    with pytest.raises(ValueError, match="category must be one of"):
        level2_targets("shapes")


def test_plan_names_the_nodes_of_every_method():
    design = plan([LEFT_OF, IN_CONTAINER], ["cnn", "base", "curr", "canon", "curr-noprim", "canon-noprim"])
    assert design.nodes[(LEFT_OF, "base")] == (LEFT_OF,)
    assert design.nodes[(LEFT_OF, "curr")] == tuple(f"obj-con2-cl/{LEFT_OF}-curr{s}" for s in ("", "1", "2"))
    assert design.nodes[(LEFT_OF, "canon")] == (f"obj-con2-canon-cl/{LEFT_OF}-curr",)
    assert design.nodes[(IN_CONTAINER, "canon-noprim")] == (f"con2-ba-canon-noprim/{IN_CONTAINER}_canon",)
    assert (LEFT_OF, "cnn") in design.nodes and (IN_CONTAINER, "cnn") not in design.nodes  # CNN classifies only
    order = design.curriculum.order(design.training_targets)
    assert len(order) == len(set(order))  # a lower-level node shared by several methods is one node
    assert design.curriculum.node(f"obj-con2-canon-cl/{LEFT_OF}-curr").uses[0] in order
    with pytest.raises(ValueError, match=r"unknown method\(s\) \['flat'\]"):
        plan([LEFT_OF], ["flat"])
    with pytest.raises(KeyError, match="did you mean"):
        plan(["cl_self-left-of-two-objects"], ["base"])


def test_every_level2_target_is_trained_by_every_method():
    """The whole table plans: the original canonical entry named after ..._vs_corner trains ..._vs_noncontainer (a
    typo in the curriculum file); it ships as written but the target's canon node is the intended one."""
    everything = level2_targets()
    methods = ["cnn", "base", "curr", "canon", "curr-noprim", "canon-noprim"]
    design = plan(everything, methods)
    assert len({key for key in design.nodes if key[1] != "cnn"}) == 51 * 5
    corner, noncontainer = "cl_self-touches-container_vs_corner", "cl_self-touches-container_vs_noncontainer"
    for method, stem in (("canon", "con2-cl-canon"), ("canon-noprim", "con2-cl-canon-noprim")):
        (intended,) = design.nodes[(corner, method)]
        assert intended == f"{stem}/{corner}_canon-intended" and design.curriculum.node(intended).task == corner
        as_written = design.curriculum.node(f"{stem}/{corner}_canon")
        assert as_written.task == noncontainer and as_written.uses == design.curriculum.node(intended).uses
        assert design.nodes[(noncontainer, method)] == (f"{stem}/{noncontainer}_canon",)  # not trained twice


def test_paired_ttest_against_a_hand_computed_case():
    ours, theirs = [0.9, 0.8, 0.7, 0.95], [0.5, 0.6, 0.7, 0.55]
    d = np.array(ours) - np.array(theirs)  # 0.4, 0.2, 0.0, 0.4: mean 0.25, sd 0.19149
    t_by_hand = d.mean() / (math.sqrt(((d - d.mean()) ** 2).sum() / 3) / 2)
    df, t, p = paired_ttest(ours, theirs)
    assert df == 3 and t == pytest.approx(t_by_hand) == pytest.approx(2.61116, abs=1e-4)
    assert p == pytest.approx(0.079605, abs=1e-5)  # two-sided, Student's t with 3 degrees of freedom
    assert paired_ttest([0.5], [0.4]) is None and paired_ttest([0.5, 0.6], [0.4, 0.5]) is None


def test_cnn_input_and_it_beats_chance_on_an_easy_concept():
    grid = np.array([[7, 7, 7], [7, 2, 0], [7, 3, 3]])
    x = encode([grid])
    assert x.shape == (1, len(CHANNELS), 3, 3) and x.sum() == 9 and x[0, CHANNELS.index(2), 1, 1] == 1
    torch.set_num_threads(2)
    try:
        result = train_cnn("cl_self-in-left-corner_vs_on-hline", seed=0)
        assert torch.get_num_threads() == 2  # one thread inside, the caller's count back afterwards
    finally:
        torch.set_num_threads(1)
    assert result.train_accuracy == 1.0 and result.test_score >= 0.8  # measured 0.96
    assert train_cnn("cl_self-in-left-corner_vs_on-hline", seed=0).test_score == result.test_score  # seeded
    with pytest.raises(ValueError, match="bring-about dataset"):
        train_cnn(IN_CONTAINER, seed=0)


def test_the_moves_probe_retests_a_runs_best_seeds_counting_their_moves(tmp_path, capsys, monkeypatch):
    """``tools/probe_moves.py`` on a tiny run: each target x method's best seed tested again with the run's own test
    (its recorded score reproduced), how its other episodes ended (a wrong signal or none), its moves per episode,
    and its score with calls costing their moves (a flat SMC makes at most 100 moves, and curr-moves was trained
    counting them: neither is tested twice); resumable; a directory that is not an experiment's and an unknown
    method are refused before any work."""
    from sb3_smc.library import SMCLibrary

    probe_moves = import_tool("probe_moves")
    out = tmp_path / "exp"
    run_experiment(out, methods=["base", "curr", "curr-moves"], targets=[LEFT_OF], seeds=1, timesteps=2000, repeats=1,
                   progress=False)
    table = tmp_path / "moves.csv"
    argv = [str(out), "--kind", "classification", "--methods", "base,curr,curr-moves", "--out", str(table)]
    tested = []  # (SMC, calls costing their moves) of every test the probe runs
    real_test = probe_moves.test

    def test(smc, count_moves, repeats):
        tested.append((smc.name, count_moves, repeats))
        return real_test(smc, count_moves, repeats)

    monkeypatch.setattr(probe_moves, "test", test)
    assert probe_moves.main(argv) == 0
    rows = {row["method"]: row for row in csv.DictReader(table.open())}
    assert sorted(rows) == ["base", "curr", "curr-moves"]
    assert all(row["score"] == row["recorded"] for row in rows.values())
    base, curr, moves = rows["base"], rows["curr"], rows["curr-moves"]
    assert tested == [(base["smc"], False, 1), (curr["smc"], False, 1), (curr["smc"], True, 1),
                      (moves["smc"], True, 1)]  # the run's repeats; curr-moves as trained, counting moves
    assert moves["score_counting_moves"] == moves["score"] and float(moves["moves_p90"]) <= 100
    for row in rows.values():  # every episode right, wrong or without a signal
        assert float(row["score"]) + float(row["wrong_signal"]) + float(row["no_signal"]) == pytest.approx(1, abs=2e-3)
    assert float(base["moves_p90"]) <= 100 and base["over_100"] == "0.000"  # a flat SMC: at most 100 moves
    counted = real_test(SMCLibrary.load(out / "library", names=[curr["smc"]])[curr["smc"]], True, 1)[0]
    assert curr["score_counting_moves"] == f"{np.mean(counted):.3f}" and float(curr["moves_mean"]) > 0
    written = table.read_text()
    capsys.readouterr()
    assert probe_moves.main(argv) == 0 and table.read_text() == written and capsys.readouterr().out == ""
    for bad, says in (([str(tmp_path)], "not an experiment directory"),
                      ([str(out), "--methods", "base,cur"], "--methods: unknown cur")):
        with pytest.raises(SystemExit):
            probe_moves.main([*bad, "--out", str(tmp_path / "other.csv")])
        assert says in capsys.readouterr().err and not (tmp_path / "other.csv").exists()
    older = tmp_path / "older.csv"  # an older version's columns: not resumed with blanks
    older.write_text(written.splitlines()[0].rsplit(",", 2)[0] + "\n")
    with pytest.raises(SystemExit):
        probe_moves.main([str(out), "--out", str(older)])
    assert "older.csv: its columns are not this tool's" in capsys.readouterr().err


def test_the_paired_seeds_tool_counts_what_a_longer_run_does_to_each_seed(tmp_path, capsys):
    """``tools/paired_seeds.py``: seed s of one method against seed s of another on the same curriculum node (the
    reported curriculum's seeds only), the seeds lifted or lowered by 5 points or more, the first method's weak
    seeds (more than 15 below its concept's best) brought within 15 of it, exactly at those boundaries; the seeds
    on other lower-level SMCs (their evaluations' children) counted apart, not as a continuation; targets on
    different nodes named and left out; bad input refused before any output."""
    from sb3_smc.curricula.jobs import file_stem, job_name

    paired_seeds = import_tool("paired_seeds")

    def results(name, method, scores, unreported=(), other=()):
        """A run directory: results.json and each seed's evaluation, its children ``["c@1"]``, or ``["c@2"]`` for
        the (target, seed) in ``other``."""
        rows = [{"target": t, "kind": "bring-about" if t.startswith("ba_") else "classification",
                 "category": "objcon", "method": method, "curriculum": curriculum, "seed": seed, "test_score": v}
                for table in (scores, unreported) for t, curriculum, values in table for seed, v in enumerate(values)]
        (tmp_path / name / "evaluations").mkdir(parents=True)
        (tmp_path / name / "results.json").write_text(json.dumps({"rows": rows, "reported": reported(rows)}))
        for row in rows:
            children = ["c@2"] if (row["target"], row["seed"]) in other else ["c@1"]
            (tmp_path / name / "evaluations" / f"{file_stem(job_name(row['curriculum'], row['seed']))}.json") \
                .write_text(json.dumps({"test_score": row["test_score"], "spec": {"children": children}}))
        return str(tmp_path / name)

    canon = results("canon", "canon", [("cl_t", "c", [0.27, 0.44, 0.60, 0.23, 0.29]),
                                       ("cl_edge", "e", [0.90, 0.75, 0.20]), ("cl_other", "o", [0.5]),
                                       ("ba_t", "b", [1.0, 1.0, 0.98, 1.0, 1.0]), ("ba_u", "u/b", [0.5, 0.6])])
    scaled = results("scaled", "canon-scaled",
                     [("cl_t", "canon-scaled/c", [0.91, 0.53, 0.76, 0.39, 0.29]),
                      ("cl_edge", "canon-scaled/e", [0.95, 0.70, 0.75]),  # +5, -5, and 15 below the best
                      ("cl_other", "d", [0.9]), ("ba_t", "canon-scaled/b", [1.0, 0.9]),
                      ("ba_u", "canon-scaled/u/b", [0.4, 0.7])],
                     unreported=[("cl_t", "lower", [0.2] * 5)],  # a lower curriculum: not paired
                     other=[("ba_u", 0), ("ba_u", 1)])  # on other children: apart
    assert paired_seeds.main([canon, scaled, "--methods", "canon,canon-scaled", "--by-target"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == "Seeds continuing the shorter run (the same lower-level SMCs):"
    assert lines[4] == "| classification | 2 | 8 | 46.0 | 66.0 | 75.0 | 93.0 | 6 | 1 | 5 | 3 |"
    assert lines[5] == "| bring-about | 1 | 2 | 100.0 | 95.0 | 100.0 | 100.0 | 0 | 1 | 0 | 0 |"
    assert lines[6] == "| all | 3 | 10 | 56.8 | 71.8 | 83.3 | 95.3 | 6 | 2 | 5 | 3 |"
    assert lines[8] == "Seeds on other lower-level SMCs (not a continuation):"
    assert lines[12:14] == ["| bring-about | 1 | 2 | 55.0 | 55.0 | 60.0 | 70.0 | 1 | 1 | 0 | 0 |",
                            "| all | 1 | 2 | 55.0 | 55.0 | 60.0 | 70.0 | 1 | 1 | 0 | 0 |"]
    assert lines[15] == "All paired seeds:" and lines[19:22] == [
        "| classification | 2 | 8 | 46.0 | 66.0 | 75.0 | 93.0 | 6 | 1 | 5 | 3 |",
        "| bring-about | 2 | 4 | 77.5 | 75.0 | 80.0 | 85.0 | 1 | 2 | 0 | 0 |",
        "| all | 4 | 12 | 56.5 | 69.0 | 77.5 | 89.0 | 7 | 3 | 5 | 3 |"]
    assert lines[23] == "Not paired (the reported curricula are different nodes): cl_other"
    assert "| `ba_t` | 100.0 / 100.0 / 98.0 / 100.0 / 100.0 | 100.0 / 90.0 / - / - / - |  |" in lines
    assert "| `ba_u` | 50.0 / 60.0 | 40.0 / 70.0 | 0, 1 |" in lines
    again = results("again", "canon", [("cl_t", "c", [0.28])])  # seed 0 of canon once more, another score
    (tmp_path / "bare").mkdir()
    (tmp_path / "bare" / "results.json").write_text((tmp_path / "canon" / "results.json").read_text())
    for argv, says in (([canon, "--methods", "canon"], "--methods: two of"),
                       ([canon, str(tmp_path), "--methods", "canon,canon-scaled"], "results.json not found"),
                       ([canon, again, scaled, "--methods", "canon,canon-scaled"], "seed 0: two results"),
                       ([str(tmp_path / "bare"), scaled, "--methods", "canon,canon-scaled"],
                        "bare/evaluations/c@0.json not found: the evaluation of c@0"),
                       ([canon, "--methods", "canon,canon-scaled"], "no target has seeds of both")):
        with pytest.raises(SystemExit):
            paired_seeds.main(argv)
        captured = capsys.readouterr()
        assert says in captured.err and captured.out == ""
    # the digests of the children's weights, where both records have them, tell the same names apart
    a, b, c = "a" * 64, "b" * 64, None
    assert paired_seeds.same_lower_level([("x", a), ("y", b)], [("x", a), ("y", c)])  # an older record: by name
    assert not paired_seeds.same_lower_level([("x", a), ("y", b)], [("x", a), ("y", a)])  # trained again
    assert not paired_seeds.same_lower_level([("x", a)], [("y", a)])
    record = tmp_path / "canon" / "evaluations" / "c@0.json"
    record.write_text(json.dumps({"test_score": 0.27, "spec": {"children": ["c@1"]}, "children_digests": [a, b]}))
    with pytest.raises(SystemExit):
        paired_seeds.main([canon, scaled, "--methods", "canon,canon-scaled"])
    assert ("c@0.json: 'children_digests' must list one digest (a string, or null) per child of its spec (1)"
            in capsys.readouterr().err)


def test_the_paired_seeds_tool_compares_across_targets_on_the_same_lower_level_only(tmp_path, capsys):
    """``tools/paired_seeds.py --across-targets``: the second method's curricula on other lower-level SMCs than the
    first's (their evaluations' children) are named and left out, a target with none left is left out, and on the
    others each method's best seed over the curricula on the same lower level is compared, beside the flat methods'
    best seeds: means per kind and paired t-tests (checked by hand)."""
    from sb3_smc.curricula.jobs import file_stem, job_name

    paired_seeds = import_tool("paired_seeds")

    def run(name, method, table, other=()):
        """A run directory of ``method``: (target, curriculum, scores by seed); the curricula in ``other`` call
        ``c@2``, the others ``c@1``."""
        rows = [{"target": t, "kind": "bring-about" if t.startswith("ba_") else "classification",
                 "category": "objcon", "method": method, "curriculum": curriculum, "seed": seed, "test_score": v}
                for t, curriculum, values in table for seed, v in enumerate(values)]
        (tmp_path / name / "evaluations").mkdir(parents=True)
        (tmp_path / name / "results.json").write_text(json.dumps({"rows": rows, "reported": reported(rows)}))
        for row in rows:
            (tmp_path / name / "evaluations" / f"{file_stem(job_name(row['curriculum'], row['seed']))}.json") \
                .write_text(json.dumps({"test_score": row["test_score"],
                                        "spec": {"children": ["c@2" if row["curriculum"] in other else "c@1"]}}))
        return str(tmp_path / name)

    curr = run("curr", "curr", [("cl_a", "n1", [0.9, 0.8]), ("cl_a", "n2", [0.95, 0.5]), ("cl_b", "nb", [0.7, 0.6]),
                                ("cl_c", "nc", [0.8, 0.85]), ("ba_a", "ma", [1.0, 0.9]), ("ba_b", "mb", [0.9, 0.9])])
    moves = run("moves", "curr-moves", [("cl_a", "curr-moves/n1", [0.6, 0.7]), ("cl_a", "curr-moves/n2", [0.99, 0.1]),
                                        ("cl_b", "curr-moves/nb", [0.5, 0.4]), ("cl_c", "curr-moves/nc", [0.9, 0.3]),
                                        ("ba_a", "curr-moves/ma", [0.3, 0.2]), ("ba_b", "curr-moves/mb", [0.5, 0.5])],
                other={"curr-moves/n2", "curr-moves/mb"})
    base = run("base", "base", [(t, t, [v]) for t, v in (("cl_a", 0.5), ("cl_b", 0.6), ("cl_c", 0.55), ("ba_a", 0.4),
                                                         ("ba_b", 0.1))])
    argv = [curr, moves, base, "--methods", "curr,curr-moves", "--across-targets", "base"]
    assert paired_seeds.main(argv) == 0
    out = capsys.readouterr().out
    assert out.startswith("curr-moves calls other lower-level SMCs than curr in 4 of its 12 SMCs, in 2 curricula of "
                          "2 targets (seeds on other children / seeds):\n\n"
                          "- `curr-moves/mb`: 2 / 2\n"
                          "- `curr-moves/n2`: 2 / 2 (the target keeps 1 curriculum on the same ones)\n")
    assert "On the 4 targets with a curriculum on the same lower level" in out
    assert "| classification | 3 | 81.7 | 70.0 | 55.0 |" in out and "| bring-about | 1 | 100.0 | 30.0 | 40.0 |" in out
    df, t, p = paired_ttest([70, 50, 90], [90, 70, 85])  # cl_a: n1's best seeds only; cl_b, cl_c
    assert f"| classification | curr-moves vs curr | 3 | {t:.2f} | {df} | {p:.2g} | 1 / 2 |" in out
    df, t, p = paired_ttest([90, 70, 85], [50, 60, 55])
    assert f"| classification | curr vs base | 3 | {t:.2f} | {df} | {p:.2g} | 3 / 0 |" in out
    assert "| bring-about | curr-moves vs base | 1 | - | - | - | 0 / 1 |" in out  # one target: no test
    for bad, says in (([curr, moves, "--methods", "curr,curr-moves", "--across-targets", "base"],
                       "no result of base on ba_a"),
                      ([curr, moves, base, "--methods", "curr,curr-moves", "--across-targets", "flat"],
                       "--across-targets: methods of"),
                      ([curr, base, "--methods", "curr,curr-moves", "--across-targets", "base"],
                       "no curriculum of curr-moves calls the same lower-level SMCs as curr's")):
        with pytest.raises(SystemExit):
            paired_seeds.main(bad)
        captured = capsys.readouterr()
        assert says in captured.err and captured.out == ""


def test_the_compare_runs_tool_pairs_the_smcs_of_two_runs(tmp_path, capsys):
    """``tools/compare_runs.py``: per method both runs reported, the SMCs both trained and how many came out the
    same, the reported scores and the per-target means over the shared SMCs compared across targets (numbers by hand:
    two targets, t(1) = 1, p = 0.5, Holm 1.0 over the two tests), the time per SMC; bad input refused before output."""
    compare_runs = import_tool("compare_runs")

    def run(name, scores, times, **extra):
        """An experiment directory: ``scores`` {(method, target): per-seed test scores}; ``extra`` its results.json's
        other keys."""
        rows = [{"target": t, "kind": "classification", "category": "objcon", "method": m, "curriculum": t,
                 "seed": seed, "training_return": 1.0, "selected_update": 7, "test_score": v, "wall_time_s": times}
                for (m, t), values in scores.items() for seed, v in enumerate(values)]
        (tmp_path / name).mkdir()
        (tmp_path / name / "results.json").write_text(json.dumps({"rows": rows, "reported": reported(rows), **extra}))
        return str(tmp_path / name)

    first = run("first", {("base", "cl_t"): [0.5, 0.6, 0.7], ("base", "cl_u"): [0.8, 0.9, 1.0],
                          ("curr", "cl_t"): [0.9]}, 10.0, complete=True, wall_time_total_s=7200.0, command="x",
                machine={"processor": "AMD EPYC (family 26, model 2)"}, code={"commit": "0123456789"})
    second = run("second", {("base", "cl_t"): [0.5, 0.6, 0.7, 0.99], ("base", "cl_u"): [0.7, 0.9, 1.0]}, 5.0)
    assert compare_runs.main([first, second]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == (f"- `{first}`: commit `0123456`, CPU AMD EPYC (family 26, model 2), 2.00 h recorded, "
                        "complete: `x`")
    assert lines[1] == f"- `{second}`: commit `unknown`, CPU unknown, no wall time recorded, incomplete: `?`"
    # reported: 70 / 99 and 100 / 100; SMC means over seeds 0-2: 60 / 60 and 90 / 86.7; seed 0 of cl_u differs
    assert lines[5:] == ["| base | 2 | 6 | 5 | 85.0 | 99.5 | +14.5 [-169.7, +198.7] | 0.50 (1.00) | 75.0 | 73.3 | "
                         "-1.7 [-22.8, +19.5] | 0.50 (1.00) | 10.0 | 5.0 | 0.50 |"]
    assert compare_runs.main([first, first]) == 0
    assert capsys.readouterr().out.splitlines()[5:] == [
        "| base | 2 | 6 | 6 | 85.0 | 85.0 | +0.0 [+0.0, +0.0] | 1.00 (1.00) | 75.0 | 75.0 | +0.0 [+0.0, +0.0] | "
        "1.00 (1.00) | 10.0 | 10.0 | 1.00 |",
        "| curr | 1 | 1 | 1 | 90.0 | 90.0 | +0.0 | - | 90.0 | 90.0 | +0.0 | - | 10.0 | 10.0 | 1.00 |"]
    twice = run("twice", {("base", "cl_t"): [0.5]}, 1.0)
    saved = json.loads(Path(twice, "results.json").read_text())
    saved["rows"] *= 2
    Path(twice, "results.json").write_text(json.dumps(saved))
    other = run("other", {("cnn", "cl_t"): [0.5]}, 1.0)
    for argv, says in (([first, str(tmp_path / "none")], "results.json not found"),
                       ([first, twice], "holds base on cl_t (cl_t, seed 0) twice"),
                       ([first, other], "report no method in common")):
        with pytest.raises(SystemExit):
            compare_runs.main(argv)
        captured = capsys.readouterr()
        assert says in captured.err and captured.out == ""


def test_the_job_costs_tool_gives_each_levels_cost_and_the_childrens_share(tmp_path, capsys, monkeypatch):
    """``tools/job_costs.py``: jobs grouped by level (SMCs without a record left out), medians per job and per
    decision against the flat jobs', moves per decision, and the fit of microseconds per decision against moves per
    decision over nodes (a node's seeds summed: they share their group's time whatever their own moves), leaving out
    a node above 3 times its level's median (numbers by hand: 10 + 2 x moves); several runs pooled; bad input
    refused before any output."""
    from types import SimpleNamespace

    job_costs = import_tool("job_costs")

    def entry(seconds: float | None, moves: float = 1.0, children: tuple[str, ...] = ()) -> SimpleNamespace:
        record = None if seconds is None else SimpleNamespace(wall_time_s=seconds, total_timesteps=100_000,
                                                              primitive_steps=int(moves * 100_000))
        return SimpleNamespace(children=children, record=record)

    # node a's two seeds: 3 and 1 moves a decision, 1.4 s each (the group's share): 2 moves, 14 us a decision
    entries = {"f@0": entry(2.0), "f@1": entry(4.0), "untrained@0": entry(None),
               "a@0": entry(1.4, 3, ("f@0",)), "a@1": entry(1.4, 1, ("f@1",)), "b@0": entry(1.8, 4, ("f@0", "f@1")),
               "c": entry(2.2, 6, ("f@1",)), "paused@0": entry(30.0, 4, ("f@0",)), "top@0": entry(9.0, 50, ("a@0",))}
    levels = job_costs.jobs_by_level(entries)
    assert {level: len(jobs) for level, jobs in levels.items()} == {1: 2, 2: 5, 3: 1}
    a, b, r2, left_out = job_costs.fit(levels[2])
    assert (round(a, 9), round(b, 9), round(r2, 9), left_out) == (10.0, 2.0, 1.0, 1)
    assert job_costs.table(Path("run"), levels)[4:] == [
        "| 1 | 2 | 3.0 | 30.0 | 1.0 | 1.00 | 1.00 |  |",
        "| 2 | 5 | 1.8 | 18.0 | 3.6 | 0.60 | 0.60 | 10.0 + 2.00 x moves (1.00; 1) |",
        "| 3 | 1 | 9.0 | 90.0 | 50.0 | 3.00 | 3.00 |  |"]

    with monkeypatch.context() as patch:
        patch.setattr(job_costs.storage, "checked_entries", lambda root: (entries, {}, root / "manifest.json"))
        assert job_costs.main([str(tmp_path / "x"), str(tmp_path / "y")]) == 0
    out = capsys.readouterr().out.split("\n\n")
    assert out[4] == "the 2 runs pooled" and out[5].splitlines()[3] == (
        "| 2 | 10 | 1.8 | 18.0 | 3.6 | 0.60 | 0.60 | 10.0 + 2.00 x moves (1.00; 2) |")
    with pytest.raises(SystemExit):
        job_costs.main([str(tmp_path / "none")])
    captured = capsys.readouterr()
    assert "none: not a run with a library" in captured.err and captured.out == ""


def test_reported_scores_are_the_best_seed_and_curriculum():
    rows = [{"target": "t", "kind": "classification", "category": "objcon", "method": "curr", "curriculum": c,
             "seed": s, "test_score": v} for c, s, v in (("a", 0, 0.5), ("a", 1, 0.7), ("b", 0, 0.9), ("b", 1, 0.1))]
    assert reported(rows) == [{"target": "t", "kind": "classification", "category": "objcon", "method": "curr",
                               "test_score": 0.9, "seed": 0, "curriculum": "b"}]


def test_the_wall_clock_keeps_a_stopped_runs_time(tmp_path):
    """``DIR/wall_time.json``: each run's entry is rewritten while it runs, so a run killed without warning keeps
    its time up to its last beat; a directory from before the ledger starts from its results' recorded total; runs
    at once keep their own entries; a damaged ledger is refused before any work."""
    from sb3_smc.curricula.run_directory import RunFileError
    from sb3_smc.experiments.wall_clock import LEDGER, WallClock, lower_bound

    run = tmp_path / "run"
    run.mkdir()
    (run / "results.json").write_text(json.dumps({"wall_time_s": 10.0, "wall_time_total_s": 100.0}))
    script = ("import sys, time; from pathlib import Path; from sb3_smc.experiments.wall_clock import WallClock\n"
              "clock = WallClock(Path(sys.argv[1]), train=True, interval=0.05).__enter__()\n"
              "print('started', flush=True); time.sleep(60)")
    killed = subprocess.Popen([sys.executable, "-c", script, str(run)], cwd=ROOT, stdout=subprocess.PIPE, text=True)
    assert killed.stdout is not None and killed.stdout.readline() == "started\n"
    deadline = time.time() + 30
    while time.time() < deadline and not (run / LEDGER).is_file():
        time.sleep(0.05)
    time.sleep(0.5)
    killed.kill()
    killed.wait()
    ledger = json.loads((run / LEDGER).read_text())
    assert ledger["before"] == 100.0 and len(ledger["runs"]) == 1
    assert ledger["before_lower_bound"] is True and lower_bound(run)  # results from before the ledger: a bound
    [stopped] = ledger["runs"]
    assert stopped["ended"] is False and stopped["train"] is True and stopped["seconds"] >= 0.3
    with WallClock(run, train=False, interval=0.05) as first, WallClock(run, train=True, interval=0.05):
        time.sleep(0.2)
    runs = json.loads((run / LEDGER).read_text())["runs"]
    assert len(runs) == 3 and runs[0] == stopped and all(r["ended"] for r in runs[1:])
    assert first.total() == pytest.approx(100.0 + sum(r["seconds"] for r in runs))
    # the ledger damaged while a run fails: the run's own error is the one raised
    with (pytest.warns(RuntimeWarning, match="wall time not written"), pytest.raises(KeyError, match="the run's own"),
          WallClock(run, train=True)):
        (run / LEDGER).write_text("{")
        raise KeyError("the run's own")
    with pytest.raises(RunFileError, match="wall_time.json is not valid JSON"):
        WallClock(run, train=True)
    (run / LEDGER).write_text('{"format": "sb3-smc-wall-time", "runs": "many"}')
    with pytest.raises(RunFileError, match="wall_time.json is not an sb3-smc wall-time ledger"):
        WallClock(run, train=True)
    # a directory without an experiment's records gets no ledger: a wrong --out, or a run refused before it wrote
    other = tmp_path / "notes"
    other.mkdir()
    (other / "notes.txt").write_text("mine")
    with WallClock(other, train=True, interval=0.01) as clock:
        time.sleep(0.05)
    assert [p.name for p in other.iterdir()] == ["notes.txt"] and clock.total() == clock.seconds > 0
    with pytest.raises(SMCError):
        run_experiment(tmp_path / "new", methods=["base"], targets=[LEFT_OF], seeds=1, train=False, progress=False)
    assert not (tmp_path / "new").exists() or not any((tmp_path / "new").iterdir())


def test_a_tiny_experiment_end_to_end(tmp_path):
    out = tmp_path / "exp"
    results = run_experiment(out, methods=["cnn", "base", "curr"], targets=[LEFT_OF], seeds=1, timesteps=2000,
                             repeats=1, progress=False)
    rows = list(csv.DictReader((out / "results.csv").open()))
    assert list(rows[0]) == list(RESULT_FIELDS)
    assert sorted((r["method"], r["curriculum"]) for r in rows) == sorted(
        [("cnn", "cnn"), ("base", LEFT_OF)] + [("curr", f"obj-con2-cl/{LEFT_OF}-curr{s}") for s in ("", "1", "2")])
    assert all(0.0 <= float(r["test_score"]) <= 1.0 for r in rows)
    assert {r["method"] for r in results["reported"]} == {"cnn", "base", "curr"}
    smc_rows = [r for r in results["rows"] if r["method"] != "cnn"]
    assert all(r["selected_update"] is not None and r["training_return"] is not None for r in smc_rows)
    saved = json.loads((out / "results.json").read_text())
    code = saved["code"]
    assert saved["command"] == (f"sb3-smc experiment --out {out} --methods cnn,base,curr --targets {LEFT_OF} "
                                "--seeds 1 --timesteps 2000 --repeats 1 --workers 1 --backend local")  # as given
    assert saved["machine"]["cores"] >= 1 and saved["machine"]["processor"]
    assert saved["wall_time_total_s"] == saved["wall_time_s"] > 0
    assert code["versions"]["torch"] == torch.__version__
    assert code["commit"] is None or re.fullmatch(r"[0-9a-f]{40}(\+changes)?", code["commit"])
    evaluations = sorted((out / "evaluations").glob("*.json"))
    assert len(evaluations) == 4 and json.loads(evaluations[0].read_text())["evaluation"]["repeats"] == 1
    from sb3_smc.experiments.runner import evaluation_path, read_evaluation
    from sb3_smc.library import SMCLibrary

    trained = SMCLibrary.load(out / "library")
    for name in (f"{LEFT_OF}@0", f"obj-con2-cl/{LEFT_OF}-curr@0"):  # the weights each evaluated SMC called
        record = read_evaluation(evaluation_path(out, name))
        assert record["digest"] == trained[name].digest is not None
        assert record["children_digests"] == [child.digest for child in trained[name].children]
    assert record["children_digests"] and None not in record["children_digests"]
    stamps = {p: p.stat().st_mtime_ns for p in [*evaluations, *(out / "cnn").glob("*.json")]}

    again = run_experiment(out, methods=["cnn", "base", "curr"], targets=[LEFT_OF], seeds=1, timesteps=2000,
                           repeats=1, progress=False)
    assert again["rows"] == results["rows"]  # nothing trained or evaluated again
    assert again["wall_time_total_s"] == pytest.approx(saved["wall_time_total_s"] + again["wall_time_s"])
    argv = shlex.split(saved["command"])  # the recorded command resumes this very run
    resumed = subprocess.run([sys.executable, "-m", "sb3_smc.cli", *argv[1:], "--no-train"], cwd=ROOT,
                             capture_output=True, text=True, timeout=300)
    assert argv[:2] == ["sb3-smc", "experiment"] and resumed.returncode == 0, resumed.stderr
    assert all(p.stat().st_mtime_ns == stamp for p, stamp in stamps.items())

    # partial results while a run is still training: drop one finished SMC, tabulate without training, complete it
    dropped = f"obj-con2-cl/{LEFT_OF}-curr2@0"
    library = SMCLibrary.load(out / "library")
    library.remove(dropped)
    library.save(out / "library")
    (out / "evaluations" / f"obj-con2-cl%2F{LEFT_OF}-curr2@0.json").unlink()
    partial = run_experiment(out, methods=["cnn", "base", "curr"], targets=[LEFT_OF], seeds=1, timesteps=2000,
                             repeats=1, progress=False, train=False)
    assert partial["complete"] is False and partial["missing"] == [dropped]
    assert partial["rows"] == [r for r in results["rows"] if r["curriculum"] != f"obj-con2-cl/{LEFT_OF}-curr2"]
    assert dropped not in SMCLibrary.load(out / "library")  # nothing trained
    [report] = write_report(out, behaviour=False)
    assert "**Partial results**: 1 SMC(s)" in report.read_text() and f"`{dropped}`" in report.read_text()
    with pytest.raises(RunSettingsError, match="other settings") as refused:
        run_experiment(out, methods=["cnn", "base", "curr"], targets=[LEFT_OF], seeds=2, timesteps=2000,
                       repeats=1, progress=False, train=False)
    with pytest.raises(RunSettingsError, match="other settings") as refused:  # other methods: another run
        run_experiment(out, methods=["cnn", "base"], targets=[LEFT_OF], seeds=1, timesteps=2000, repeats=1,
                       progress=False, train=False)
    assert "--accept-changes" not in str(refused.value)  # an experiment's merged curriculum has no command line
    with pytest.raises(RunSettingsError, match="no run.json"):
        run_experiment(tmp_path / "none", methods=["base"], targets=[LEFT_OF], seeds=1, progress=False, train=False)
    completed = run_experiment(out, methods=["cnn", "base", "curr"], targets=[LEFT_OF], seeds=1, timesteps=2000,
                               repeats=1, progress=False)
    def timeless(rows: list[dict]) -> list[dict]:
        return [{k: v for k, v in row.items() if k != "wall_time_s"} for row in rows]

    assert completed["complete"] is True
    assert timeless(completed["rows"]) == timeless(results["rows"])  # retrained alike: deterministic

    [report] = write_report(out)
    text = report.read_text()
    assert "Partial results" not in text
    for method in ("cnn", "base", "curr"):
        assert f"| {method} " in text or f" {method} |" in text
    assert "52.6 / 90.4 / 89.0" in text and "Paired t-tests" in text and "## How this was run" in text
    assert f"torch {torch.__version__}," in text and "(a resumed run: the code of its last run)" in text
    base = next(r["test_score"] for r in results["reported"] if r["method"] == "base")
    subset = next(line for line in text.splitlines() if "ours - paper (the same 1 concept(s)" in line)
    cells = [cell.strip() for cell in subset.strip("|").split("|")]  # kind, label, concepts, cnn, base, curr
    assert cells[4] == f"{100 * base - 52.6:+.1f}"  # against the paper's number for this concept, not its mean
    assert cells[3] == ""  # the paper gives no per-concept CNN number
    assert "- learner: RecurrentPPO (LSTM)" in text
    for name in ("categories", "concepts-classification", "trajectories", "timeline"):
        image = np.asarray(Image.open(out / "figures" / f"{name}.png").convert("L"))
        assert image.size > 10_000 and image.std() > 5, name  # written and not blank
        assert f"figures/{name}.png" in text


def test_evaluations_and_cnns_on_two_workers_are_those_of_one(tmp_path):
    """After training, the evaluations and CNNs an experiment needs run on its workers (each saved as it finishes,
    with a progress line): on 2 worker processes the same records as in one process (the CNNs' training time aside),
    and a run that has them all computes nothing again."""
    out = tmp_path / "one"
    settings = dict(methods=["cnn", "base", "curr"], targets=[LEFT_OF], seeds=1, timesteps=2000, repeats=1)
    first = run_experiment(out, progress=False, **settings)
    shutil.copytree(out, tmp_path / "two")
    for folder in ("evaluations", "cnn"):
        shutil.rmtree(tmp_path / "two" / folder)
    lines: list[str] = []
    second = run_experiment(tmp_path / "two", workers=2, printer=lines.append, **settings)
    assert "evaluating 4 SMC(s), training 1 CNN(s), 2 at a time" in lines and "evaluated 5/5" in lines
    assert [{k: v for k, v in r.items() if r["method"] != "cnn" or k != "wall_time_s"} for r in second["rows"]] == \
        [{k: v for k, v in r.items() if r["method"] != "cnn" or k != "wall_time_s"} for r in first["rows"]]
    for path in sorted((out / "evaluations").glob("*.json")):
        assert path.read_text() == (tmp_path / "two" / "evaluations" / path.name).read_text(), path.name
    lines.clear()
    run_experiment(tmp_path / "two", workers=2, printer=lines.append, **settings)
    assert not any(line.startswith("evaluat") for line in lines), lines


def test_the_papers_learner_as_a_second_flat_baseline(tmp_path):
    """``base-gru``: a flat SMC trained with RecurrentTRPO + GRU whatever the run's learner, beside ``base``; its
    jobs are those of ``base`` run with ``--algo RecurrentTRPO --rnn gru`` but for their names."""
    from sb3_smc.curricula.jobs import node_spec
    from sb3_smc.errors import SMCError

    design = plan([LEFT_OF], ["base", "base-gru"])
    gru = design.curriculum.node(f"base-gru/{LEFT_OF}")
    as_option = node_spec(design.curriculum.node(LEFT_OF), 3, (), algo="RecurrentTRPO", rnn="gru").to_dict()
    own = node_spec(gru, 3, ()).to_dict()
    assert own.pop("name") == f"base-gru/{LEFT_OF}@3" and as_option.pop("name") == f"{LEFT_OF}@3"
    assert own == as_option and own["hyperparameters"]["policy"] == "SequenceGruPolicy"
    from sb3_smc import train_smc  # and training does not read the name: the same weights under either

    specs = [node_spec(gru, 3, (), timesteps=2000),
             node_spec(design.curriculum.node(LEFT_OF), 3, (), timesteps=2000, algo="RecurrentTRPO", rnn="gru")]
    weights = [train_smc(spec, printer=lambda _: None).model.policy.state_dict() for spec in specs]
    assert weights[0].keys() == weights[1].keys()
    assert all(torch.equal(weights[0][k], weights[1][k]) for k in weights[0])
    for option in ({"algo": "RecurrentPPO"}, {"rnn": "gru"}):
        with pytest.raises(SMCError, match="base-gru has a learner of its own"):  # before any work
            run_experiment(tmp_path / "refused", methods=["base-gru"], targets=[LEFT_OF], **option)
    assert not (tmp_path / "refused").exists()

    # base and base-gru run in directories of their own, one report over both (with the trajectory pictures)
    runs = {method: run_experiment(tmp_path / method, methods=[method], targets=[LEFT_OF], seeds=1, timesteps=2000,
                                   repeats=1, progress=False) for method in ("base", "base-gru")}
    assert [(r["method"], r["curriculum"]) for r in runs["base-gru"]["rows"]] == [("base-gru", f"base-gru/{LEFT_OF}")]
    spec = json.loads((tmp_path / "base-gru" / "evaluations" / f"base-gru%2F{LEFT_OF}@0.json").read_text())["spec"]
    assert (spec["algo"], spec["hyperparameters"]["policy"]) == ("RecurrentTRPO", "SequenceGruPolicy")
    base_spec = json.loads((tmp_path / "base" / "evaluations" / f"{LEFT_OF}@0.json").read_text())["spec"]
    assert base_spec["algo"] == "RecurrentPPO"
    [path] = write_report([tmp_path / "base", tmp_path / "base-gru"], out=tmp_path / "report")
    text = path.read_text()
    assert "figures/trajectories.png" in text and "does not hold" not in text  # each SMC from its own directory
    assert "- learner: RecurrentPPO (LSTM)\n" in text  # base's directory
    assert "- learner: base-gru: its own, RecurrentTRPO (GRU)\n" in text  # every SMC method there has its own
    header = next(line for line in text.splitlines() if line.startswith("| target | kind | category |"))
    assert "| base | base-gru |" in header
    paper = next(line for line in text.splitlines() if "ours - paper (the same 1 concept(s)" in line)
    base_gru = runs["base-gru"]["reported"][0]["test_score"]
    assert paper.strip("|").split("|")[4].strip() == f"{100 * base_gru - 52.6:+.1f}"  # the paper's flat number


def test_canon_with_a_budget_that_grows_with_its_smc_actions():
    """``canon-scaled``: canon's target nodes as copies named ``canon-scaled/<node>`` whose budget is the run's x
    their SMC actions / 8 (at least 1), calling the same lower-level nodes as canon's (trained once for both); its
    jobs are canon's but for their names and budgets."""
    from sb3_smc.curricula.jobs import node_spec
    from sb3_smc.experiments.design import METHOD_REGISTRY

    design = plan([LEFT_OF, IN_CONTAINER], ["canon", "canon-scaled"])
    for target, uses in ((LEFT_OF, 15), (IN_CONTAINER, 13)):
        (canon,) = design.nodes[(target, "canon")]
        (scaled,) = design.nodes[(target, "canon-scaled")]
        assert scaled == f"canon-scaled/{canon}"
        node, copy = design.curriculum.node(canon), design.curriculum.node(scaled)
        assert copy.uses == node.uses and len(node.uses) == uses and copy.task == node.task
        assert copy.budget_scale == uses * 2 / 8 and node.budget_scale == 1.0
        children = tuple(f"{u}@0" for u in node.uses)
        own, theirs = (node_spec(n, 1, children, timesteps=2000).to_dict() for n in (copy, node))
        assert (own.pop("name"), theirs.pop("name")) == (f"{scaled}@1", f"{canon}@1")
        assert own.pop("budget") == {**theirs.pop("budget"), "total_timesteps": 2000 * uses // 4}
        assert own == theirs
    few = next(n for n in plan(level2_targets(), ["canon"]).curriculum.nodes if len(n.uses) == 3)
    assert METHOD_REGISTRY["canon-scaled"].budget_scale(few) == 1.0  # 6 SMC actions: the run's budget
    order = design.curriculum.order(design.training_targets)
    assert len(order) == len(set(order)) == 2 * 2 + len(design.curriculum.closure(
        [design.nodes[(t, "canon")][0] for t in (LEFT_OF, IN_CONTAINER)])) - 2  # the lower nodes are shared


def test_curr_with_calls_that_cost_their_moves():
    """``curr-moves``: curr's target nodes as copies named ``curr-moves/<node>`` whose SMC calls cost the episode
    the moves they made, calling the same lower-level nodes as curr's (trained once for both); its jobs are curr's
    but for their names and that wrapper setting."""
    from sb3_smc.curricula.jobs import node_spec

    design = plan([LEFT_OF, IN_CONTAINER], ["curr", "curr-moves"])
    for target in (LEFT_OF, IN_CONTAINER):
        curr, moves = design.nodes[(target, "curr")], design.nodes[(target, "curr-moves")]
        assert moves == tuple(f"curr-moves/{n}" for n in curr) and len(curr) >= 1
        for name in curr:
            node, copy = design.curriculum.node(name), design.curriculum.node(f"curr-moves/{name}")
            assert copy.uses == node.uses and copy.count_primitive_steps and not node.count_primitive_steps
            children = tuple(f"{u}@0" for u in node.uses)
            own, theirs = (node_spec(n, 1, children, timesteps=2000).to_dict() for n in (copy, node))
            assert own.pop("name") == f"curr-moves/{theirs.pop('name')}"
            assert own.pop("wrapper") == {**theirs.pop("wrapper"), "count_primitive_steps": True}
            assert own == theirs
    order = design.curriculum.order(design.training_targets)
    assert len(order) == len(set(order))  # the lower nodes are shared


def test_the_fair_methods_change_only_their_episode_length_or_call_cap():
    """``base-400``: the flat SMC with 400 steps an episode, named ``base-400/<target>``; the sweep's methods: curr's
    target nodes with their call cap or (calls costing their moves) episode length changed, calling curr's lower
    levels; their jobs are base's and curr's but for their names and those wrapper settings."""
    from sb3_smc.curricula.jobs import node_spec

    design = plan([LEFT_OF, IN_CONTAINER], ["base", "curr", "base-400", *SWEEP_METHODS])
    changed = {"base-400": {"max_steps": 400}, "curr-cap10": {"call_step_cap": 10}, "curr-cap25": {"call_step_cap": 25},
               "curr-cap50": {"call_step_cap": 50}, "curr-cap100": {},
               "curr-moves-100": {"count_primitive_steps": True},
               "curr-moves-200": {"count_primitive_steps": True, "max_steps": 200},
               "curr-moves-400": {"count_primitive_steps": True, "max_steps": 400}}
    assert set(changed) == {"base-400", *SWEEP_METHODS}
    for method, wrapper in changed.items():
        for target in (LEFT_OF, IN_CONTAINER):
            ours, theirs = design.nodes[(target, method)], design.nodes[(target, "base" if method == "base-400"
                                                                                 else "curr")]
            assert ours == tuple(f"{method}/{n}" for n in theirs)
            for mine, base in zip(ours, theirs, strict=True):
                node, copy = design.curriculum.node(base), design.curriculum.node(mine)
                children = tuple(f"{u}@0" for u in node.uses)
                own, other = (node_spec(n, 1, children, timesteps=2000).to_dict() for n in (copy, node))
                assert own.pop("name") == f"{method}/{other.pop('name')}"
                assert own.pop("wrapper") == {**other.pop("wrapper"), **wrapper}
                assert own == other


def test_the_equal_experience_methods_are_base_with_its_budget_scaled():
    """``base-x1`` / ``-x4`` / ``-x16`` / ``-x64``: base's flat SMC named ``<method>/<target>``, its budget 1 / 4 / 16 /
    64 times the run's, all else base's job."""
    from sb3_smc.curricula.jobs import node_spec

    design = plan([LEFT_OF, IN_CONTAINER], ["base", *EXPERIENCE_METHODS])
    assert EXPERIENCE_METHODS == ("base-x1", "base-x4", "base-x16", "base-x64")
    for method, factor in zip(EXPERIENCE_METHODS, (1, 4, 16, 64), strict=True):
        for target in (LEFT_OF, IN_CONTAINER):
            (name,) = design.nodes[(target, method)]
            assert name == f"{method}/{target}" and design.nodes[(target, "base")] == (target,)
            own, base = (node_spec(design.curriculum.node(n), 2, (), timesteps=2000).to_dict() for n in (name, target))
            assert own.pop("name") == f"{method}/{base.pop('name')}"
            steps = own["budget"].pop("total_timesteps"), base["budget"].pop("total_timesteps")
            assert steps == (factor * 2000, 2000)
            assert own == base


def test_curr_whose_lower_levels_train_with_twice_the_budget():
    """``curr-lower-x2``: curr's target nodes as copies named ``curr-lower-x2/<node>`` calling copies of every lower
    node (``curr-lower-x2/<node>``, one per node however many targets use it) whose budget is twice the run's; its
    jobs are curr's but for their names, their children's names and the lower nodes' budgets."""
    from sb3_smc.curricula.jobs import node_spec

    method = "curr-lower-x2"
    design = plan([LEFT_OF, IN_CONTAINER], ["curr", method])
    curriculum = design.curriculum
    for target in (LEFT_OF, IN_CONTAINER):
        curr, ours = design.nodes[(target, "curr")], design.nodes[(target, method)]
        assert ours == tuple(f"{method}/{n}" for n in curr)
        lower = curriculum.closure(curr) - set(curr)
        assert lower and curriculum.closure(ours) - set(ours) == {f"{method}/{n}" for n in lower}
        for name in (*curr, *lower):
            node, copy = curriculum.node(name), curriculum.node(f"{method}/{name}")
            assert copy.uses == tuple(f"{method}/{u}" for u in node.uses) and copy.task == node.task
            own, theirs = (node_spec(n, 1, tuple(f"{u}@0" for u in n.uses), timesteps=2000).to_dict()
                           for n in (copy, node))
            assert own.pop("name") == f"{method}/{theirs.pop('name')}"
            assert own.pop("children") == [f"{method}/{c}" for c in theirs.pop("children")]
            factor = 1 if name in curr else 2
            assert own.pop("budget") == {**theirs.pop("budget"), "total_timesteps": 2000 * factor}
            assert own == theirs
    curr_nodes = [n for t in (LEFT_OF, IN_CONTAINER) for n in design.nodes[(t, "curr")]]
    order = curriculum.order(design.training_targets)
    assert len(order) == len(set(order)) == 2 * len(curriculum.closure(curr_nodes))  # a shared lower node: one copy


def test_the_sweep_targets_cover_both_kinds_and_every_category():
    from pixelworld_env.datasets import catalog

    assert len(SWEEP_TARGETS) == len(set(SWEEP_TARGETS)) >= 12 and set(SWEEP_TARGETS) <= set(level2_targets())
    infos = [catalog.dataset(t) for t in SWEEP_TARGETS]
    assert {i.kind for i in infos} == {"classification", "bring-about"}
    assert {i.category for i in infos} == set(PAPER_CATEGORIES)
    required = ("ba_self-left-of-two-objects_from_not-left-on-floor",
                "ba_self-right-of-two-objects_from_not-right-on-floor", LEFT_OF,
                "ba_self-in-container_from_between-potential-containers")
    assert set(required) <= set(SWEEP_TARGETS)


def test_a_run_reduced_to_its_records_resumes_without_model_files(tmp_path, monkeypatch):
    """What docs/results/ commits (run.json + evaluations, no library) is a run that resumes where it stopped; its
    results record the commit each SMC was trained at, over the resumed runs, and the SMCs copied from a
    ``--reuse-from`` library apart."""
    from sb3_smc.curricula.trainer import file_stem
    from sb3_smc.experiments import runner
    from sb3_smc.library import SMCLibrary

    settings = dict(methods=["base", "curr"], targets=[LEFT_OF], seeds=1, timesteps=2000, repeats=1, progress=False)
    first, second = "1" * 40, "2" * 40
    monkeypatch.setattr(runner, "code_commit", lambda: first)
    results = run_experiment(tmp_path / "full", **settings)
    everything = sorted(SMCLibrary.load(tmp_path / "full" / "library").names)
    assert results["commits"] == {first: everything} and results["copied"] == []
    assert results["wall_time_lower_bound"] is False  # a ledger from the first run
    copied = run_experiment(tmp_path / "copied", **settings, reuse_from=tmp_path / "full" / "library")
    assert copied["commits"] == {} and copied["copied"] == everything  # nothing trained: every SMC copied
    monkeypatch.setattr(runner, "code_commit", lambda: second)
    kept = tmp_path / "kept"
    kept.mkdir()
    shutil.copy(tmp_path / "full" / "run.json", kept)
    shutil.copy(tmp_path / "full" / "results.json", kept)  # as tools/paper_table.sh keeps it (no ledger)
    shutil.copytree(tmp_path / "full" / "evaluations", kept / "evaluations")
    curr1 = f"obj-con2-cl/{LEFT_OF}-curr1@0"
    saved = json.loads((kept / "evaluations" / f"{file_stem(curr1)}.json").read_text())
    assert saved["spec"]["name"] == curr1 and saved["spec"]["children"]  # the children it was trained with

    again = run_experiment(kept, **settings)
    assert again["rows"] == results["rows"] and again["complete"] is True
    assert not (kept / "library").exists()  # nothing trained: every SMC of the table is evaluated already
    [report] = write_report(kept)  # the tables and bar charts from the records; the pictures need models
    text = report.read_text()
    assert "figures/concepts-classification.png" in text and "figures/trajectories.png" not in text
    assert f"{kept} does not hold `{LEFT_OF}@0`" in text and "to retrain them (alike" in text

    (kept / "evaluations" / f"{file_stem(curr1)}.json").unlink()
    partial = run_experiment(kept, **{**settings}, train=False)
    assert partial["missing"] == [curr1] and len(partial["rows"]) == len(results["rows"]) - 1
    completed = run_experiment(kept, **settings)
    trained = set(SMCLibrary.load(kept / "library").names)
    assert curr1 in trained and f"{LEFT_OF}@0" not in trained and f"obj-con2-cl/{LEFT_OF}-curr@0" not in trained
    assert {c for c in saved["spec"]["children"]} <= trained  # its lower levels, retrained
    assert completed["commits"] == {first: sorted(set(everything) - trained), second: sorted(trained)}
    assert completed["wall_time_lower_bound"] is False  # its ledger began from a total that a ledger kept
    def timeless(rows: list[dict]) -> list[dict]:
        return [{k: v for k, v in row.items() if k != "wall_time_s"} for row in rows]

    assert timeless(completed["rows"]) == timeless(results["rows"])  # the lost SMC retrained alike
    (kept / "evaluations" / f"{file_stem(curr1)}.json").write_text("{ not json")
    with pytest.raises(ValueError, match=r"curr1@0.json is not valid JSON"):
        run_experiment(kept, **settings)


def test_cli_experiment_and_report_errors(tmp_path):
    def cli(*args: str) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, "-m", "sb3_smc.cli", *args], cwd=ROOT, capture_output=True,
                              text=True, timeout=120)

    bad = cli("experiment", "--out", str(tmp_path / "x"), "--methods", "base,flat", "--targets", LEFT_OF)
    assert bad.returncode == 2 and "unknown method(s) ['flat']" in bad.stderr and "Traceback" not in bad.stderr
    wrong = cli("experiment", "--out", str(tmp_path / "x"), "--targets", LEFT_OF, "--rnn", "rnn")
    assert wrong.returncode == 2 and "invalid choice: 'rnn'" in wrong.stderr
    missing = cli("report", str(tmp_path / "nothing"))
    assert missing.returncode == 2 and "results.json not found" in missing.stderr


def test_cli_experiment_and_report_succeed(tmp_path):
    """The commands as users type them: a CNN-only experiment (seconds), then its report."""
    out = tmp_path / "cnn"
    easy = "cl_self-in-left-corner_vs_on-hline"
    run = subprocess.run([sys.executable, "-m", "sb3_smc.cli", "experiment", "--out", str(out), "--methods", "cnn",
                          "--targets", easy, "--seeds", "2", "--workers", "2"], cwd=ROOT, capture_output=True,
                         text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    rows = list(csv.DictReader((out / "results.csv").open()))
    assert [(r["method"], r["seed"]) for r in rows] == [("cnn", "0"), ("cnn", "1")]
    assert float(rows[0]["test_score"]) >= 0.8
    report = subprocess.run([sys.executable, "-m", "sb3_smc.cli", "report", str(out)], cwd=ROOT,
                            capture_output=True, text=True, timeout=300)
    assert report.returncode == 0, report.stderr
    text = (out / "report.md").read_text()
    assert f"--targets {easy} --seeds 2" in text and "--workers 2" in text and "cores" in text
    assert "- code: sb3-smc " in text and "a resumed run" not in text  # one run: not called resumed


def test_the_report_has_the_noprim_table_and_the_cnn_tests_per_category(tmp_path):
    """Synthetic results: the noprim table (means with and without primitives beside the paper's) and one paired
    t-test of the best SMC method against the CNN per classification category, with scipy's numbers."""
    from scipy import stats

    from pixelworld_env.datasets import catalog

    targets = [t for t in level2_targets("objcon") if catalog.dataset(t).kind == "classification"][:4]
    methods = ["cnn", "base", "curr", "curr-noprim"]
    score = {(t, m): 0.5 + 0.1 * k + 0.05 * j + (0.02 * k * k if m == "cnn" else 0.0)
             for k, t in enumerate(targets) for j, m in enumerate(methods)}
    rows = [{"target": t, "kind": "classification", "category": "objcon", "method": m, "curriculum": m, "seed": 0,
             "test_score": v} for (t, m), v in score.items()]
    (tmp_path / "results.json").write_text(json.dumps({
        "rows": rows, "reported": reported(rows), "wall_time_s": 60.0, "command": None, "machine": {},
        "settings": {"methods": methods, "targets": targets, "seeds": 1, "timesteps": 400_000, "repeats": 10,
                     "workers": 1, "backend": "local"}}))
    [report] = write_report(tmp_path, behaviour=False)
    text = report.read_text()
    noprim = text.split("## The role of hierarchy")[1].split("##")[0]
    with_, without = (100 * np.mean([score[(t, m)] for t in targets]) for m in ("curr", "curr-noprim"))
    assert f"| classification | curr | {with_:.1f} | {without:.1f} | 84.9 | 82.7 |" in noprim
    t, p = stats.ttest_rel([score[(t, "curr")] for t in targets], [score[(t, "cnn")] for t in targets])
    row = next(line for line in text.splitlines() if line.startswith("| classification / objcon | curr vs cnn"))
    assert f"| {t:.2f} | 3 | {p:.2g} |" in row


def test_the_report_sets_the_flat_smc_beside_the_original_runs(tmp_path):
    """The objects concepts whose flat results the release's files record: ours beside them, paired t-tests of our
    best seeds against theirs and of our means over seeds against theirs."""
    from scipy import stats

    from sb3_smc.experiments.paper import ORIGINAL_FLAT_RUNS

    targets = [t for t in ORIGINAL_FLAT_RUNS if t.startswith("cl_")][:3]
    rows = [{"target": t, "kind": "classification", "category": "objects", "method": "base", "curriculum": "base",
             "seed": seed, "test_score": 0.5 + 0.1 * k + 0.02 * seed} for k, t in enumerate(targets) for seed in (0, 1)]
    (tmp_path / "results.json").write_text(json.dumps({
        "rows": rows, "reported": reported(rows), "wall_time_s": 60.0, "command": None, "machine": {},
        "settings": {"methods": ["base"], "targets": targets, "seeds": 2, "timesteps": 400_000, "repeats": 10,
                     "workers": 1, "backend": "local"}}))
    [report] = write_report(tmp_path, behaviour=False)
    section = report.read_text().split("## The flat SMC (base) beside the original runs'")[1].split("## ")[0]
    first = targets[0]
    assert f"| {first} | classification | 52.0 (51.0 ± 1.4) | {ORIGINAL_FLAT_RUNS[first][0]:.1f} " in section
    sentences = []  # the best seeds against the original best, the means over seeds against the original means
    for which, ours, column in (("best seed", [0.52 + 0.1 * k for k in range(3)], 0),
                                ("mean over seeds", [0.51 + 0.1 * k for k in range(3)], 1)):
        theirs = [ORIGINAL_FLAT_RUNS[t][column] / 100 for t in targets]
        t, p = stats.ttest_rel(ours, theirs)
        sentences.append(f"{which} ours {100 * np.mean(ours):.1f}, original {100 * np.mean(theirs):.1f} (paired "
                         f"t(2) = {t:.2f}, p = {p:.2g})")
    assert f"classification, 3 concepts, means: {sentences[0]}; {sentences[1]}." in section


def test_the_report_orders_the_pushable_curriculum_by_level(tmp_path):
    from pixelworld_env.datasets import catalog
    from sb3_smc.experiments.report import pushable_levels

    targets = level2_targets("pushable")
    levels = pushable_levels()
    assert sorted(levels.values()) == [1, 1, 1, 2, 2, 3, 4, 4, 5, 5, 6] and min(levels[t] for t in targets) == 2
    rows, best = [], []
    for k, target in enumerate(targets):
        kind = catalog.dataset(target).kind
        for method in ("cnn", "base", "curr") if kind == "classification" else ("base", "curr"):
            scores = [0.5 + 0.01 * k + 0.1 * seed for seed in range(2)]
            curriculum = target if method != "curr" else f"pushable/{target}"
            rows += [{"target": target, "kind": kind, "category": "pushable", "method": method,
                      "curriculum": curriculum, "seed": seed, "test_score": v} for seed, v in enumerate(scores)]
            best.append({"target": target, "kind": kind, "category": "pushable", "method": method,
                         "curriculum": curriculum, "seed": 1, "test_score": scores[1]})
    (tmp_path / "results.json").write_text(json.dumps({
        "rows": rows, "reported": best, "wall_time_s": 60.0, "command": None, "machine": {},
        "settings": {"methods": ["cnn", "base", "curr"], "targets": targets, "seeds": 2, "timesteps": 400_000,
                     "repeats": 10, "workers": 2, "backend": "local"}}))
    [report] = write_report(tmp_path, behaviour=False)
    text = report.read_text()
    section = text.split("## The pushable curriculum by level (Fig. 5c)")[1].split("## Figures")[0]
    table = [line.split(" | ") for line in section.splitlines() if line.startswith("| ") and "---" not in line][1:]
    assert [int(r[0][2:]) for r in table] == sorted(levels[t] for t in targets)  # ordered by level
    top = "cl_pushable-floor-pixel_vs_unpushable"
    best, mean = 50 + targets.index(top) + 10, 50 + targets.index(top) + 5  # the cnn: best seed (mean ± s.d.)
    assert table[-1][1] == top and table[-1][3] == f"{best:.1f} ({mean:.1f} ± {100 * np.std([0, 0.1], ddof=1):.1f})"
    assert "ours - paper" not in text and "t(34)" not in text  # the paper gives no pushable numbers or tests
    image = np.asarray(Image.open(tmp_path / "figures" / "pushable.png").convert("L"))
    assert image.std() > 5 and "figures/pushable.png" in text


def test_the_demo_plays_trains_evaluates_and_reports(tmp_path):
    """What `make demo` runs, at a tiny budget: the played episodes, then the small experiment and its report."""
    out = tmp_path / "demo"
    demo = subprocess.run([sys.executable, "-m", "sb3_smc.demo", "--quiet", "--out", str(out), "--timesteps", "2000",
                           "--seeds", "1", "--workers", "1"],
                          cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert demo.returncode == 0, demo.stderr
    assert f"report: {out / 'report.md'}" in demo.stdout
    for method in ("cnn", "base", "curr"):
        assert re.search(rf"^{method} +\d+\.\d%", demo.stdout, re.MULTILINE), method
    text = (out / "report.md").read_text()
    assert "## How this was run" in text and "figures/timeline.png" in text
    assert all((out / "figures" / f"{name}.png").stat().st_size > 1000 for name in ("categories", "trajectories"))
    other = subprocess.run([sys.executable, "-m", "sb3_smc.demo", "--quiet", "--out", str(out), "--timesteps", "3000",
                            "--seeds", "1", "--workers", "1"], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert other.returncode == 1 and "holds a demo run with other settings" in other.stderr  # say how to go on
    assert "Traceback" not in other.stderr


def test_the_whole_table_report_with_a_second_flat_baseline(tmp_path):
    """``base-gru`` from a directory of its own: its column with the paper's flat numbers, the t-tests and win counts
    of the hierarchical methods against it (the paper's tests beside them) and its claims, beside ``base``'s."""
    from pixelworld_env.datasets import catalog

    everything = level2_targets()
    gain = {"cnn": 0.25, "base": 0.2, "base-gru": 0.3, "curr": 0.4, "canon": 0.35}

    def score(t: str, m: str) -> float:
        lost = m == "curr" and everything.index(t) % 4 == 0  # curr below base-gru (not base) on every fourth concept
        return 0.4 + 0.01 * (everything.index(t) % 7) + (0.25 if lost else gain[m]) + 0.003 * everything.index(t) * (
            m == "base-gru")

    _synthetic_table(tmp_path / "paper", everything, ["cnn", "base", "curr", "canon"], score)
    _synthetic_table(tmp_path / "gru", everything, ["base-gru"], score)
    [path] = write_report([tmp_path / "paper", tmp_path / "gru"], out=tmp_path / "report", behaviour=False)
    text = path.read_text()
    ba = [t for t in everything if catalog.dataset(t).kind == "bring-about"]
    means = next(line for line in text.splitlines() if line.startswith("| bring-about | **paper** (all) | 17 |"))
    cells = [c.strip() for c in means.strip("|").split("|")]
    assert cells[3:] == ["", "52.7", "74.5", "75.0", "52.7"]  # cnn, base, curr, canon, base-gru: the paper's flat
    cells = _row_cells(text, "| bring-about | curr vs base-gru |")
    assert cells[2:5] == ["17", f"{_hand_t(score, ba, 'curr', 'base-gru'):.2f}", "16"]
    assert cells[6] == "t(16) = 4.1, p = 0.0008"
    assert next(line for line in text.splitlines() if line.startswith("| bring-about | curr vs base |"))
    won = sum(everything.index(t) % 4 != 0 for t in ba)
    assert f"| bring-about | curr | base-gru | {won} of 17 |" in text
    assert "| bring-about | curr | base | 17 of 17 |" in text
    claims = text.split("## The paper's claims")[1].split("\n## ")[0]
    assert "base-gru" not in claims  # the paper's statements are judged on its methods; ours are checked apart
    checks = text.split("## Our checks of the method")[1].split("\n## ")[0]
    gru_mean = 100 * np.mean([score(t, "base-gru") for t in ba])
    assert f"| bring-about: mean of base-gru | 52.7 | {gru_mean:.1f} [" in checks
    assert "| classification: mean of base-gru | 74.5 | " in checks
    assert "## The flat SMC (base-gru) beside the original runs'" in text
    # base-gru on 16 of the 17 bring-about concepts: its test is over 16, without the paper's (over all 17) beside it
    _synthetic_table(tmp_path / "gru-part", everything[1:], ["base-gru"], score)
    [part] = write_report([tmp_path / "paper", tmp_path / "gru-part"], out=tmp_path / "part", behaviour=False)
    row = next(line for line in part.read_text().splitlines() if line.startswith("| bring-about | curr vs base-gru |"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert everything[0] in ba and cells[2] == "16" and cells[6:] == ["", ""]
    checks = part.read_text().split("## Our checks of the method")[1].split("\n## ")[0]  # nor judged on all 17
    part_mean = 100 * np.mean([score(t, "base-gru") for t in ba[1:]])
    row = next(line for line in checks.splitlines() if line.startswith("| bring-about: mean of base-gru (16 concepts)"))
    assert row.startswith(f"| bring-about: mean of base-gru (16 concepts) | 52.7 | {part_mean:.1f} [")
    assert row.endswith("| not comparable: a subset |")


def test_a_run_still_training_is_marked_partial_and_not_judged(tmp_path, monkeypatch):
    """A directory tabulated while it trains (``missing``): a target x method with seeds not trained yet has its
    numbers marked partial, no claim is judged on it, the paper's test is not put beside a partial one; the pairs
    that finished are judged as before. A missing SMC the run's plan does not know is refused, naming the file."""
    from pixelworld_env.datasets import catalog

    everything = level2_targets()
    ba = [t for t in everything if catalog.dataset(t).kind == "bring-about"]
    gain = {"cnn": 0.25, "base": 0.2, "base-gru": 0.3, "curr": 0.4, "canon": 0.35}

    def score(t: str, m: str) -> float:
        return 0.4 + 0.01 * (everything.index(t) % 7) + gain[m] + 0.003 * everything.index(t) * (m == "base-gru")

    _synthetic_table(tmp_path / "paper", everything, ["cnn", "base", "curr", "canon"], score)
    _synthetic_table(tmp_path / "gru", everything, ["base-gru"], score)
    results = json.loads((tmp_path / "gru" / "results.json").read_text())  # seed 1 of the bring-about ones to train
    results["rows"] = [r for r in results["rows"] if r["kind"] == "classification" or r["seed"] == 0]
    results["reported"] = reported(results["rows"])
    results.update(complete=False, missing=[f"base-gru/{t}@1" for t in ba])
    (tmp_path / "gru" / "results.json").write_text(json.dumps(results))
    import sb3_smc.experiments.report as report_module

    legends: list[set[str]] = []
    bar_panels = report_module.bar_panels
    monkeypatch.setattr(report_module, "bar_panels", lambda *args, partial=(), **kwargs: legends.append(set(partial))
                        or bar_panels(*args, partial=partial, **kwargs))
    [path] = write_report([tmp_path / "paper", tmp_path / "gru"], out=tmp_path / "report", behaviour=False)
    assert legends == [{"base-gru"}] * 3  # the figures' legends: "base-gru (...) (partial)"
    text = path.read_text()
    checks = text.split("## Our checks of the method")[1].split("\n## ")[0]
    assert "| bring-about: mean of base-gru | 52.7 | - | not judged: partial |" in checks
    cl_mean = 100 * np.mean([score(t, "base-gru") for t in everything if t not in ba])  # finished: judged
    assert f"| classification: mean of base-gru | 74.5 | {cl_mean:.1f} [" in checks
    claims = text.split("## The paper's claims")[1].split("\n## ")[0]
    base = 100 * np.mean([score(t, "base") for t in ba])
    assert f"| bring-about: mean of base | 52.7 | {base:.1f} [" in claims
    rows = [line for line in claims.splitlines() if line.startswith("| ") and not line.startswith("| statement |")]
    verdicts = [row.rsplit("|", 2)[1].split(": ")[-1].strip() for row in rows]  # the one reading that ran
    assert len(rows) == 31 and f"**In all** (31 statements): a call is one step: {tally(verdicts)}." in claims
    cells = _row_cells(text, "| bring-about | curr vs base-gru (partial) |")  # ours, without the paper's beside it
    assert cells[2:5] == ["17", f"{_hand_t(score, ba, 'curr', 'base-gru'):.2f}", "16"] and cells[6:] == ["", ""]
    assert _row_cells(text, "| bring-about | curr vs base |")[6] == "t(16) = 4.1, p = 0.0008"
    means = _row_cells(text, "| bring-about | all | 17 |")
    assert means[-1].endswith(" (partial)") and not any(c.endswith("(partial)") for c in means[:-1])
    assert not _row_cells(text, "| classification | all | 34 |")[-1].endswith("(partial)")
    assert _row_cells(text, "| bring-about | ours - paper (17 concepts) |")[-1].endswith(" (partial)")
    concept = _row_cells(text, f"| {ba[0]} | bring-about |")  # seed 0 of 2 so far: marked
    assert concept[-2] == f"{100 * score(ba[0], 'base-gru'):.1f} (partial)" and "partial" not in concept[-3]
    assert "| bring-about | curr | base-gru (partial) | 17 of 17 |" in text
    assert "is marked (partial), and no claim is judged on it" in text
    results["missing"].append("base-gru/no-such-node@1")
    (tmp_path / "gru" / "results.json").write_text(json.dumps(results))
    with pytest.raises(SMCError, match=r"gru/results.json: the untrained SMC 'base-gru/no-such-node@1'"):
        write_report([tmp_path / "paper", tmp_path / "gru"], out=tmp_path / "again", behaviour=False)
    assert not (tmp_path / "again").exists()


def test_the_whole_table_report_with_canon_scaled_and_curr_moves(tmp_path):
    """``canon-scaled`` and ``curr-moves`` (bring-about only) from directories of their own: columns with the paper's
    canon and curr numbers beside them, their t-tests against the flat SMC (the paper's canon and curr tests beside
    them), their win counts and claims, and their rules in the provenance."""
    from pixelworld_env.datasets import catalog

    everything = level2_targets()
    gain = {"cnn": 0.25, "base": 0.2, "curr": 0.4, "canon": 0.35, "canon-scaled": 0.38, "curr-moves": 0.3}

    def score(t: str, m: str) -> float:
        spread = 0.002 * everything.index(t) * (m in ("canon-scaled", "curr-moves"))
        return 0.4 + 0.01 * (everything.index(t) % 7) + gain[m] + spread

    _synthetic_table(tmp_path / "paper", everything, ["cnn", "base", "curr", "canon"], score)
    _synthetic_table(tmp_path / "scaled", everything, ["canon-scaled"], score)
    ba = [t for t in everything if catalog.dataset(t).kind == "bring-about"]
    _synthetic_table(tmp_path / "moves", ba, ["curr-moves"], score)
    [path] = write_report([tmp_path / "paper", tmp_path / "scaled", tmp_path / "moves"], out=tmp_path / "report",
                         behaviour=False)
    text = path.read_text()
    means = next(line for line in text.splitlines() if line.startswith("| classification | **paper** (all) | 34 |"))
    assert [c.strip() for c in means.strip("|").split("|")][3:] == ["79.9", "74.5", "84.9", "80.2", "80.2", "84.9"]
    cells = _row_cells(text, "| bring-about | curr-moves vs base |")
    assert cells[2:5] == ["17", f"{_hand_t(score, ba, 'curr-moves', 'base'):.2f}", "16"]
    assert cells[6] == "t(16) = 4.1, p = 0.0008"
    mean = 100 * np.mean([score(t, "curr-moves") for t in ba])
    assert _row_cells(text, "| bring-about: mean of curr |")[3].startswith(f"{mean:.1f} [")  # a call costs its moves
    assert "(curr-moves: an SMC call of its target nodes costs the episode's steps the moves it made)" in text
    assert "| classification | curr-moves vs base | 0 |" in text  # it ran on no classification concept
    cells = _row_cells(text, "| bring-about | canon-scaled vs base |")
    assert cells[2:5] == ["17", f"{_hand_t(score, ba, 'canon-scaled', 'base'):.2f}", "16"]
    assert cells[6] == "t(16) = 4.4, p = 0.0005"
    assert "| bring-about | canon-scaled | base | 17 of 17 |" in text
    checks = text.split("## Our checks of the method")[1].split("\n## ")[0]
    mean = 100 * np.mean([score(t, "canon-scaled") for t in ba])
    assert f"| bring-about: mean of canon-scaled | 75.0 | {mean:.1f} [" in checks
    assert "| classification: canon-scaled above base | +5.7 | " in checks
    claims = text.split("## The paper's claims")[1].split("\n## ")[0]
    assert "canon-scaled" not in claims
    assert "| statement | paper | a call is one step | a call costs its moves |" in claims
    assert "400,000 steps per SMC (canon-scaled: its target nodes' budget x their SMC actions / 8, at least 1)" in text
    # the claims that pool methods keep the paper's curr and canon (canon-scaled trains longer)
    assert "| bring-about | curr or canon | base | 17 of 17 | 14 of 16 |" in text
    assert ("| bring-about: a hierarchical SMC (best of curr, canon) beats the flat one, % of concepts | on 14 of 16 "
            "concepts | 100.0 [") in claims


def test_the_readme_gets_the_answer_from_the_report(tmp_path):
    """``tools/readme_table.py`` writes, between the README's markers, the answer table (base, curr and canon, curr's
    lead per reading, the best setting of each reading where it ran on every concept), the verdict and the headline
    targets, every number copied from the report's claims table with the paper's t-tests beside ours; says when
    the table is partial (which run directories, and whether every one of the paper's methods has all its concepts);
    leaves the rest of the README as it was, and refuses a README without its markers."""
    from pixelworld_env.datasets import catalog

    readme_table = import_tool("readme_table")

    everything = level2_targets()

    def score(t: str, m: str) -> float:
        k = everything.index(t)
        return 0.5 + 0.01 * (k % 7) + (0.1 + 0.01 * (k % 3)) * ("curr" in m)

    _synthetic_table(tmp_path / "run", everything, ["base", "curr"], score)
    [report] = write_report([tmp_path / "run"], out=tmp_path / "docs", behaviour=False)
    claims = report.read_text().split("## The paper's claims")[1].split("\n## ")[0]
    readme = tmp_path / "README.md"
    readme.write_text(f"# Title\n\nbefore\n{readme_table.START}\nold\n{readme_table.END}\nafter\n")
    cl = [t for t in everything if catalog.dataset(t).kind == "classification"]
    lead = 100 * np.mean([score(t, "curr") - score(t, "base") for t in cl])
    for _ in range(2):  # the same README again: nothing else changes
        assert readme_table.main(["--report", str(report), "--readme", str(readme)]) == 0
        text = readme.read_text()
        assert text.startswith("# Title\n\nbefore\n<!-- paper-table:start -->\n") and text.endswith("-->\nafter\n")
        assert "old" not in text and "partial" not in text and "(docs/report.md)" in text
        assert "| | classification: ours | paper | bring-about: ours | paper |" in text
        row = _row_cells(text, "| curr above base (a call is one step) |")
        ours = _row_cells(claims, "| classification: curr above base (paired t-test) |")[2]
        assert row[1] == ours.replace(": reproduced", " (reproduced)") and row[1].startswith(f"+{lead:.1f} [")
        assert f"t(33) = {_hand_t(score, cl, 'curr', 'base'):.2f}" in row[1]
        assert row[2] == "+10.4; t(34) = 4.9, p = 2e-05" and row[4] == "+21.8; t(16) = 4.1, p = 0.0008"
        assert _row_cells(text, "| the flat SMC (base): mean |")[2] == "74.5"
        assert "canon" not in text.split("**The paper's claims")[0]  # not run: no row, no headline number
        assert f"- **A call as one step** (the paper's count): curr leads the flat SMC by +{lead:.1f} (p = " in text
        assert "; paper +10.4) on classification and +" in text
        assert "**Fair in moves**" not in text and "**At equal experience**" not in text  # no such rows
        assert ("**The paper's two headline targets** (best seed of 5): `cl_self-left-of-two-objects-vs-one` base "
                in text)
        counted = next(line for line in report.read_text().splitlines() if line.startswith("**In all**"))
        assert counted.startswith("**In all** (31 statements): a call is one step: ")
        assert ("**[The paper's claims](docs/report.md#the-papers-claims)**" + counted.removeprefix("**In all**")
                in text)
    # the best setting of each reading on a few targets only: no row (the paper's numbers are over all concepts)
    swept = [t for t in everything if catalog.dataset(t).kind == "bring-about"][:5]
    _synthetic_table(tmp_path / "sweep", swept, ["curr-cap10", "curr-moves-200"], score)
    [report] = write_report([tmp_path / "run", tmp_path / "sweep"], out=tmp_path / "docs", behaviour=False)
    readme_table.main(["--report", str(report), "--readme", str(readme)])
    assert "curr-cap10:" not in readme.read_text() and "curr-moves-200:" not in readme.read_text()
    # on every concept: their rows are the claims table's columns of those readings, judged
    _synthetic_table(tmp_path / "best", everything, ["curr-cap10", "curr-moves-200"], score)
    [report] = write_report([tmp_path / "run", tmp_path / "best"], out=tmp_path / "docs", behaviour=False)
    readme_table.main(["--report", str(report), "--readme", str(readme)])
    text = readme.read_text()
    for setting, label in (("curr-cap10", "a call is one step, cut after 10 moves"),
                           ("curr-moves-200", "calls cost their moves, 200 moves an episode")):
        row = _row_cells(text, f"| {setting}: mean ({label}) |")
        mean = 100 * np.mean([score(t, setting) for t in cl])
        assert row[1].startswith(f"{mean:.1f} [") and row[1].endswith(")") and row[2] == "84.9"
        assert _row_cells(text, f"| {setting} above base |")[1].startswith(f"+{lead:.1f} [")
    assert ("- **Fair in moves**, curr's lead over the flat SMC is: with calls costing their moves in 200 moves an "
            f"episode (that reading's best setting), +{lead:.1f} (p = ") in text
    readme_table.main(["--report", str(report), "--readme", str(readme), "--brief"])  # the landing page's
    brief = readme.read_text()
    assert "| curr above base (a call is one step) |" in brief and "**[The paper's claims]" in brief
    assert "curr-cap10:" not in brief and "**A call as one step**" not in brief
    assert "headline targets** (best seed" not in brief
    assert ("The verdict, the paper's headline targets and the best setting of each reading: [the results "
            "page](docs/README.md).") in brief
    readme_table.main(["--report", str(report), "--readme", str(readme)])
    # a cell the report could not judge yet (partial) is no result: no row, no sentence, no headline number
    unjudged = re.sub(r"(\| classification: curr above base \(paired t-test\) \| [^|]+ \| )[^|]+\|",
                      r"\1not judged: partial |", report.read_text())
    assert "not judged: partial" in unjudged
    rows = readme_table.answer_rows(unjudged)
    row = readme_table.answer_table(rows)[[r.split(" | ")[0] for r in readme_table.answer_table(rows)]
                                          .index("| curr above base (a call is one step)")]
    assert _row_cells(row, "|")[1] == "-" and "not judged" not in " ".join(readme_table.verdict(rows))
    # a claims table without one of the statements the answer reads: refused, naming it
    with pytest.raises(SystemExit, match="has no statement 'classification: mean of base'"):
        readme_table.answer_rows(report.read_text().replace("| classification: mean of base |", "| renamed |"))
    results = json.loads((tmp_path / "run" / "results.json").read_text())
    (tmp_path / "run" / "results.json").write_text(json.dumps({**results, "complete": False,
                                                                     "missing": [f"{everything[0]}@2"]}))  # base
    [report] = write_report([tmp_path / "run"], out=tmp_path / "docs", behaviour=False)
    readme_table.main(["--report", str(report), "--readme", str(readme)])
    assert "**partial: the table is still being run**" in readme.read_text()
    report.write_text("\n".join(line for line in report.read_text().splitlines() if not line.startswith("**In all**")))
    with pytest.raises(SystemExit, match="needs exactly one line beginning '\\*\\*In all\\*\\*' \\(it has 0\\)"):
        readme_table.main(["--report", str(report), "--readme", str(readme)])
    # over several directories: the partial ones by name, and whether the paper's methods are whole all the same
    first = cl[0]
    _synthetic_table(tmp_path / "flat", everything, ["base"], score)
    _synthetic_table(tmp_path / "curr", [t for t in everything if t != first], ["curr"], score)

    def mark_partial(directory: Path) -> None:
        results = json.loads((directory / "results.json").read_text())
        node = next(iter(plan(everything, results["settings"]["methods"]).nodes.values()))[0]  # one of its own
        (directory / "results.json").write_text(json.dumps({**results, "complete": False, "missing": [f"{node}@2"]}))

    mark_partial(tmp_path / "curr")  # curr on 33 of 34: classification is not whole
    [report] = write_report([tmp_path / "flat", tmp_path / "curr"], out=tmp_path / "docs", behaviour=False)
    readme_table.main(["--report", str(report), "--readme", str(readme)])
    assert "report.md), **partial: `curr` is still being run**; scores in %" in readme.read_text()
    _synthetic_table(tmp_path / "more", everything, ["curr"], score)
    mark_partial(tmp_path / "flat")
    mark_partial(tmp_path / "more")
    [report] = write_report([tmp_path / "flat", tmp_path / "more"], out=tmp_path / "docs", behaviour=False)
    readme_table.main(["--report", str(report), "--readme", str(readme)])
    assert "report.md), **partial: `flat` and `more` are still being run**; scores" in readme.read_text()  # no cnn
    _synthetic_table(tmp_path / "rest", everything, ["cnn", "canon", "curr-noprim", "canon-noprim"], score)
    [report] = write_report([tmp_path / "flat", tmp_path / "more", tmp_path / "rest"], out=tmp_path / "docs",
                            behaviour=False)
    readme_table.main(["--report", str(report), "--readme", str(readme)])
    text = readme.read_text()
    assert ("report.md), **partial: `flat` and `more` are still being run**; the paper's methods have all their "
            "concepts; scores" in text)
    assert _row_cells(text, "| canon above base (a call is one step) |")[2] == "+5.7; t(34) = 2.3, p = 0.025"
    readme.write_text("# no markers\n")
    with pytest.raises(SystemExit, match="needs exactly one <!-- paper-table:start -->"):
        readme_table.main(["--report", str(report), "--readme", str(readme)])
    assert readme.read_text() == "# no markers\n"
    with pytest.raises(SystemExit, match="nope.md not found: the report"):
        readme_table.main(["--report", str(tmp_path / "nope.md"), "--readme", str(readme)])
    elsewhere = tmp_path / "other" / "README.md"  # a README beside neither: the link climbs to the report
    elsewhere.parent.mkdir()
    elsewhere.write_text(f"{readme_table.START}\n{readme_table.END}\n")
    readme_table.main(["--report", str(report), "--readme", str(elsewhere)])
    assert "(../docs/report.md#the-papers-claims)" in elsewhere.read_text()


def test_the_verdict_says_where_the_flat_curve_ends_below_curr_cap10():
    """The equal-experience sentence of the verdict carries, from the report's summary line, on how many targets the
    flat SMC's curve ends below curr-cap10's experience; nothing where the report says none or has no summary."""
    readme_table = import_tool("readme_table")
    summary = ("**At equal experience**: curr-cap10: ahead on 41 of 51 targets (6 of them at the ceiling; on 27 the "
               "flat SMC's curve ends below its experience), mean lead +7.8 points; curr-cap50: ahead on 9 of 12 "
               "targets (on 9 the flat SMC's curve ends below its experience), mean lead +11.9 points.")
    said = " (on 27 of its 51 targets the flat SMC's curve ends below curr-cap10's experience: read at its best point)"
    assert readme_table.beyond(f"# r\n\n{summary}\n", "curr-cap10") == said
    assert readme_table.beyond(summary, "curr-cap50").startswith(" (on 9 of its 12 targets")
    assert readme_table.beyond(summary.replace("; on 27 the flat SMC's curve ends below its experience", ""),
                               "curr-cap10") == ""
    assert readme_table.beyond("# no summary", "curr-cap10") == ""
    cell = ("+7.4 [+2.8, +12.1]; t(33) = 3.63, p = 0.00094", "reproduced", "+10.4; t(34) = 4.9, p = 2e-05")
    rows = [(readme_table.ANSWER_ROWS[9][0], {"classification": cell, "bring-about": cell})]
    [sentence] = readme_table.verdict(rows, summary)
    assert sentence == ("- **At equal experience** (the flat SMC read off its curve of experience), it is: with a call "
                        "cut after 10 moves, +7.4 (p = 0.00094) on classification and +7.4 (p = 0.00094) on "
                        f"bring-about: in the paper's direction, p < 0.05 on both kinds{said}.")
    short = ("-1.0 [-5.0, +3.0]; t(33) = -0.5, p = 0.6", "short", "+10.4")
    rows = [(readme_table.ANSWER_ROWS[7][0], {"classification": short, "bring-about": short})]
    assert readme_table.verdict(rows, summary)[0].endswith(": its interval holding zero on both kinds.")


def _row_cells(text: str, start: str) -> list[str]:
    """The cells of the report's table row that begins with ``start``."""
    row = next(line for line in text.splitlines() if line.startswith(start))
    return [c.strip() for c in row.strip("|").split("|")]


def _hand_t(score: Callable[[str, str], float], targets: list[str], a: str, b: str) -> float:
    """The paired t of ``a`` against ``b`` over ``targets``, by hand: mean difference over its standard error."""
    diffs = np.array([score(t, a) - score(t, b) for t in targets])
    return float(diffs.mean() / (diffs.std(ddof=1) / math.sqrt(len(diffs))))


def _synthetic_table(directory: Path, targets: list[str], methods: list[str], score) -> None:
    """A results.json of two seeds per target x method: seed 0 scores ``score(t, m)``, seed 1 ten points less."""
    from pixelworld_env.datasets import catalog

    rows = []
    for t in targets:
        info = catalog.dataset(t)
        for m in methods:
            if m == "cnn" and info.kind != "classification":
                continue
            rows += [{"target": t, "kind": info.kind, "category": info.category, "method": m, "curriculum": m,
                      "seed": seed, "test_score": score(t, m) - 0.1 * seed} for seed in range(2)]
    directory.mkdir(parents=True)
    (directory / "results.json").write_text(json.dumps({
        "rows": rows, "reported": reported(rows), "wall_time_s": 3600.0, "wall_time_total_s": 7200.0,
        "command": f"sb3-smc experiment --out {directory}", "machine": {},
        "settings": {"methods": methods, "targets": targets, "seeds": 2, "timesteps": 400_000, "repeats": 10,
                     "workers": 2, "backend": "local"}}))


def test_the_whole_table_report_over_two_directories(tmp_path):
    """One report over the paper's 51 targets run as two directories: category means ± s.e. across concepts, the
    t-tests with the paper's degrees of freedom, the win count, the claims table and the Fig. 5 panels."""
    from pixelworld_env.datasets import catalog
    from sb3_smc.experiments.statistics import p_at_df

    methods = ["cnn", "base", "curr", "canon", "curr-noprim", "canon-noprim"]
    everything = level2_targets()
    offset = {t: 0.01 * (k % 7) for k, t in enumerate(everything)}  # concept-to-concept spread
    gain = {"cnn": 0.25, "base": 0.2, "curr": 0.4, "canon": 0.35, "curr-noprim": 0.38, "canon-noprim": 0.35}

    def score(t: str, m: str) -> float:
        worse = m == "canon" and everything.index(t) % 5 == 0  # canon below base on every fifth concept
        return 0.5 + offset[t] + (0.15 if worse else gain[m]) + (0.005 * everything.index(t) if m == "curr" else 0)

    containment = [t for t in everything if catalog.dataset(t).category == "containment"]
    rest = [t for t in everything if t not in containment]
    _synthetic_table(tmp_path / "containment", containment, methods, score)
    _synthetic_table(tmp_path / "rest", rest, methods, score)
    [path] = write_report([tmp_path / "containment", tmp_path / "rest"], out=tmp_path / "paper", behaviour=False)
    text = path.read_text()
    assert path == tmp_path / "paper" / "report.md" and "51 target(s) from 2 run directories" in text
    # category means ± s.e. across concepts
    cl_cont = [t for t in containment if catalog.dataset(t).kind == "classification"]
    values = 100 * np.array([score(t, "base") for t in cl_cont])
    mean, se = values.mean(), values.std(ddof=1) / math.sqrt(len(values))
    row = next(line for line in text.splitlines() if line.startswith("| classification | containment | 9 |"))
    assert row.split(" | ")[4] == f"{mean:.1f} ± {se:.1f}"
    # per concept: best seed (mean ± s.d.); seed 1 is ten points below seed 0
    first = everything[0]
    concept = next(line for line in text.splitlines() if line.startswith(f"| {first} |"))
    best = 100 * score(first, "base")
    assert f"{best:.1f} ({best - 5:.1f} ± {100 * np.std([0, 0.1], ddof=1):.1f})" in concept
    # t-tests: df = concepts - 1, and our t read at the paper's df; a hand-checked t quantile
    assert p_at_df(2.032244509, 34) == pytest.approx(0.05, abs=1e-6)  # the 97.5 % point of t(34), from tables
    cl = [t for t in everything if catalog.dataset(t).kind == "classification"]
    diffs = np.array([score(t, "curr") - score(t, "base") for t in cl])
    t_hand = diffs.mean() / (diffs.std(ddof=1) / math.sqrt(len(diffs)))
    row = next(line for line in text.splitlines() if line.startswith("| classification | curr vs base |"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert cells[2:5] == ["34", f"{t_hand:.2f}", "33"] and cells[6] == "t(34) = 4.9, p = 2e-05"
    assert cells[7] == f"{p_at_df(t_hand, 34):.2g}"
    # wins: canon below base on every fifth concept
    ba = [t for t in everything if catalog.dataset(t).kind == "bring-about"]
    canon_wins = sum(everything.index(t) % 5 != 0 for t in ba)
    assert f"| bring-about | canon | base | {canon_wins} of 17 |" in text
    assert "| bring-about | curr or canon | base | 17 of 17 | 14 of 16 |" in text
    # the claims table
    claims = text.split("## The paper's claims")[1].split("\n## ")[0]
    base_mean = 100 * np.mean([score(t, "base") for t in cl])
    assert f"| classification: mean of base | 74.5 | {base_mean:.1f} [" in claims
    row = _row_cells(claims, "| classification: curr above base (paired t-test) |")
    assert row[1] == "+10.4; t(34) = 4.9, p = 2e-05" and f"; t(33) = {t_hand:.2f}, p = " in row[2]
    assert _row_cells(claims, "| bring-about: a hierarchical SMC (best of curr, canon) beats the flat one")[1:] == [
        "on 14 of 16 concepts", "100.0 [100.0, 100.0]: exceeded"]
    assert "a call costs its moves" not in claims  # no method of that reading ran
    # the figures: Fig. 5a/5d and one Fig. 5b/5e per kind, in the combined report's folder
    for name in ("categories", "concepts-classification", "concepts-bring-about"):
        image = np.asarray(Image.open(tmp_path / "paper" / "figures" / f"{name}.png").convert("L"))
        assert image.std() > 5 and f"figures/{name}.png" in text
    # a report of one category: the paper's whole-table claims and tests are not judged on a subset
    [subset] = write_report(tmp_path / "containment", behaviour=False)
    part = subset.read_text()
    assert "| classification: the statements over all 34 concepts (9 here) | | not comparable: a subset |" in part
    assert "mean of base" not in part
    row = next(line for line in part.splitlines() if line.startswith("| classification | curr vs base |"))
    assert [c.strip() for c in row.strip("|").split("|")][6:] == ["", ""]  # no paper test, no p at its df
    assert "### ../containment" in text and "Wall time of all runs of the 2 directories: ≥ 4.00 h" in text
    # a target x method in two directories is refused, before anything is written
    _synthetic_table(tmp_path / "again", containment[:1], ["base"], score)
    with pytest.raises(ValueError, match=f"{containment[0]} with base is in both"):
        write_report([tmp_path / "containment", tmp_path / "again"], out=tmp_path / "twice", behaviour=False)
    assert not (tmp_path / "twice").exists()


def test_a_reruns_rows_replace_those_of_the_pairs_it_ran_again(tmp_path):
    """``reruns``: a directory that ran some target x method pairs of another again (a method retrained with its
    moves recorded, say) replaces that directory's rows of those pairs, in the table and in one report over both,
    whose provenance names them; a rerun not among the directories, reruns without one report over all, and a
    partial directory with pairs replaced are refused before anything is written."""
    from sb3_smc.experiments.report import read_table

    a, b = level2_targets()[:2]
    _synthetic_table(tmp_path / "first", [a, b], ["base", "curr"], lambda t, m: 0.5)
    _synthetic_table(tmp_path / "again", [a], ["curr"], lambda t, m: 0.9)
    with pytest.raises(SMCError, match=f"{a} with curr is in both"):
        read_table([tmp_path / "first", tmp_path / "again"])
    table, _ = read_table([tmp_path / "first", tmp_path / "again"], reruns=[tmp_path / "again"])
    assert table.score == {(a, "base"): 0.5, (a, "curr"): 0.9, (b, "base"): 0.5, (b, "curr"): 0.5}
    assert table.seeds[(a, "curr")] == pytest.approx([0.9, 0.8])  # the rerun's seeds, not the first's
    [path] = write_report([tmp_path / "first", tmp_path / "again"], out=tmp_path / "both", behaviour=False,
                          reruns=[tmp_path / "again"])
    text = path.read_text()
    assert f"- replaced by the rerun `../again` (not in this report): curr on 1 target(s), {a}" in text
    assert text.count("replaced by the rerun") == 1
    for reruns, out, message in (([tmp_path / "other"], tmp_path / "x", "is not one of the directories"),
                                 ([tmp_path / "again"], None, "give --out")):
        with pytest.raises(SMCError, match=message):
            write_report([tmp_path / "first", tmp_path / "again"], out=out, behaviour=False, reruns=reruns)
    results = json.loads((tmp_path / "first" / "results.json").read_text())
    (tmp_path / "first" / "results.json").write_text(json.dumps({**results, "complete": False,
                                                                  "missing": ["x@0"]}))
    with pytest.raises(SMCError, match="is partial: a rerun replaces pairs of complete directories only"):
        read_table([tmp_path / "first", tmp_path / "again"], reruns=[tmp_path / "again"])
    assert not (tmp_path / "x").exists()


def test_the_report_marks_wall_times_recorded_before_the_ledger_and_gives_every_commit(tmp_path):
    """A directory whose wall time was recorded without the wall-time ledger (none, or one begun from such a total)
    gives only a lower bound, marked ``≥``, and so does the total over directories when any part is one; a
    directory's results that say so are believed. Every commit its SMCs were trained at is listed with its count of
    jobs (a commit unknown last), the copies and a reconstruction's note; results from before say that they do not
    record it."""
    from sb3_smc.experiments.wall_clock import LEDGER, lower_bound

    targets = level2_targets()
    dirs = {name: tmp_path / name for name in ("old", "ledger", "resumed", "said")}
    for k, directory in enumerate(dirs.values()):
        _synthetic_table(directory, [targets[k]], ["base"], lambda t, m: 0.5)
    ledger = {"format": "sb3-smc-wall-time", "version": 1, "before": 0.0,
              "runs": [{"id": "a", "train": True, "commit": "c" * 40, "seconds": 7200.0, "ended": True}]}
    (dirs["ledger"] / LEDGER).write_text(json.dumps(ledger))
    (dirs["resumed"] / LEDGER).write_text(json.dumps({**ledger, "before": 100.0}))
    said = json.loads((dirs["said"] / "results.json").read_text())
    commits = {"a" * 40: ["x@0", "y@0"], "unknown": ["z@0"], "b" * 40 + "+changes": ["w@1", "w@2", "w@3"]}
    (dirs["said"] / "results.json").write_text(json.dumps(
        {**said, "wall_time_lower_bound": False, "code": {"versions": {}, "commit": "b" * 40}, "commits": commits,
         "copied": ["v@0"], "commits_note": "from the notes"}))
    old = json.loads((dirs["old"] / "results.json").read_text())
    (dirs["old"] / "results.json").write_text(json.dumps({**old, "code": {"versions": {}, "commit": "d" * 40}}))
    assert [lower_bound(d) for d in dirs.values()] == [True, False, True, True]  # "said": its results say otherwise
    (tmp_path / "damaged").mkdir()
    (tmp_path / "damaged" / LEDGER).write_text("{")
    assert lower_bound(tmp_path / "damaged")

    [path] = write_report(list(dirs.values()), out=tmp_path / "report", behaviour=False)
    sections = {part.split("\n")[0]: part for part in path.read_text().split("### ../")[1:]}
    bound = "; of all its runs recorded here: ≥ 2.00 h (a lower bound: recorded without the wall-time ledger"
    assert bound in sections["old"] and bound in sections["resumed"]
    for exact in ("ledger", "said"):
        assert "; of all its runs recorded here: 2.00 h\n" in sections[exact]
    assert ("- trained at: not recorded per SMC (results written before `commits`): the commit above is that of the "
            "last run\n") in sections["old"]
    assert "trained at" not in sections["ledger"]  # results without the code's record: nothing to say
    assert ("- trained at: `bbbbbbb+changes` (3 SMC jobs), `aaaaaaa` (2 SMC jobs), a commit unknown (1 SMC job); 1 "
            "SMC job copied from a `--reuse-from` library; from the notes\n") in sections["said"]
    assert ("Wall time of all runs of the 4 directories: ≥ 8.00 h (a lower bound: 2 of them recorded without the "
            "wall-time ledger") in path.read_text()
    [exact] = write_report([dirs["ledger"], dirs["said"]], out=tmp_path / "exact", behaviour=False)
    assert "Wall time of all runs of the 2 directories: 4.00 h.\n" in exact.read_text()


def test_results_record_every_commit_their_smcs_were_trained_at():
    """``results.json``'s ``commits``, accumulated over a directory's runs: what this run trained goes to its commit
    (a job trained again moves there), what an earlier run recorded stays, and jobs nobody recorded (a run stopped
    before it wrote its results) are the last earlier training run's, or of a commit unknown."""
    from sb3_smc.experiments.runner import record_commits

    previous = {"a" * 40: ["lower@0", "lower@1", "top@0"]}
    jobs = {"lower@0", "lower@1", "lower@2", "top@0", "top@1"}
    assert record_commits(previous, jobs, {"lower@1", "top@1"}, "b" * 40, "c" * 40) == {
        "a" * 40: ["lower@0", "top@0"], "b" * 40: ["lower@1", "top@1"], "c" * 40: ["lower@2"]}
    assert record_commits(previous, jobs, set(), None, None) == {
        "a" * 40: ["lower@0", "lower@1", "top@0"], "unknown": ["lower@2", "top@1"]}
    assert record_commits({}, set(), {"x@0"}, None, "c" * 40) == {"unknown": ["x@0"]}  # code outside git


def test_the_wall_clock_names_the_commit_of_the_last_earlier_training_run(tmp_path):
    """Each ledger entry names its run's commit; a run finds the last other training run's (a run stopped before
    it wrote its results, or one training beside a ``--no-train`` tabulation), or none."""
    from sb3_smc.experiments.wall_clock import LEDGER, WallClock

    run = tmp_path / "run"
    run.mkdir()
    (run / "run.json").write_text("{}")
    with WallClock(run, train=True, commit="a" * 40) as first:
        assert first.earlier_commit() is None
    entries = [{"id": "s", "train": True, "commit": "b" * 40, "seconds": 5.0, "ended": False},  # stopped
               {"id": "t", "train": False, "commit": "c" * 40, "seconds": 1.0, "ended": True}]  # a tabulation
    ledger = json.loads((run / LEDGER).read_text())
    assert ledger["runs"][0]["commit"] == "a" * 40
    (run / LEDGER).write_text(json.dumps({**ledger, "runs": ledger["runs"] + entries}))
    with WallClock(run, train=False, commit="d" * 40) as tabulating:
        assert tabulating.earlier_commit() == "b" * 40
    (run / LEDGER).write_text(json.dumps({**ledger, "runs": [*ledger["runs"], {"id": "u", "train": True,
                                                                              "seconds": 2.0}]}))
    with WallClock(run, train=True) as after_an_old_run:  # the last training run recorded no commit
        assert after_an_old_run.earlier_commit() is None


def test_the_report_gives_means_and_tests_over_seeds_beside_the_best_seeds(tmp_path):
    """Besides the paper's best seed per concept, the report gives each kind's and category's means from every
    concept's mean over its seeds, and the hierarchical-against-flat t-tests over those means (checked by hand): a
    flat method that learns in one seed of three keeps its best seed but not its mean."""
    from pixelworld_env.datasets import catalog

    targets = [t for t in level2_targets() if catalog.dataset(t).category == "objects"
               and catalog.dataset(t).kind == "bring-about"][:4]
    seeds = {"base": lambda k: [0.9, 0.05 * k, 0.0],  # learns in seed 0 only
             "curr": lambda k: [0.95, 0.9 - 0.1 * k, 0.85]}
    rows = [{"target": t, "kind": "bring-about", "category": "objects", "method": m, "curriculum": m, "seed": seed,
             "test_score": value}
            for k, t in enumerate(targets) for m, of in seeds.items() for seed, value in enumerate(of(k))]
    run = tmp_path / "run"
    run.mkdir()
    (run / "results.json").write_text(json.dumps({
        "rows": rows, "reported": reported(rows), "wall_time_s": 60.0, "command": "sb3-smc experiment", "machine": {},
        "settings": {"methods": ["base", "curr"], "targets": targets, "seeds": 3, "timesteps": 400_000,
                     "repeats": 10, "workers": 1, "backend": "local"}}))
    [path] = write_report(run, out=tmp_path / "report", behaviour=False)
    text = path.read_text().split("## Over seeds")[1]
    means = {m: np.array([np.mean(of(k)) for k in range(4)]) for m, of in seeds.items()}
    se = {m: v.std(ddof=1) / 2 for m, v in means.items()}
    assert _row_cells(text, "| bring-about | all |") == [
        "bring-about", "all", "4", f"{100 * means['base'].mean():.1f} ± {100 * se['base']:.1f}",
        f"{100 * means['curr'].mean():.1f} ± {100 * se['curr']:.1f}"]
    diffs = means["curr"] - means["base"]
    t_hand = diffs.mean() / (diffs.std(ddof=1) / 2)
    assert _row_cells(text, "| bring-about | curr vs base |")[2:5] == ["4", f"{t_hand:.2f}", "3"]
    best = path.read_text().split("## Means per kind")[1]  # the best seeds: base at 90.0 on every concept
    assert _row_cells(best, "| bring-about | all |")[3] == "90.0 ± 0.0"


def test_the_concept_figures_name_only_the_methods_of_their_kind(tmp_path, monkeypatch):
    """Fig. 5b/5e: the bring-about figure has no CNN in its bars or legend (the CNN classifies only); the category
    figure, with both kinds, has every method."""
    from sb3_smc.experiments import report as report_module

    drawn: dict[str, tuple[list[str], list[list[str]]]] = {}

    def record(panels, methods, caption, path, horizontal=False, partial=()):
        drawn[Path(path).stem] = (list(methods), [sorted(panel.values) for panel in panels])
        return Path(path)

    monkeypatch.setattr(report_module, "bar_panels", record)
    targets = level2_targets()
    _synthetic_table(tmp_path / "run", [targets[0], targets[-1]], ["cnn", "base", "curr"], lambda t, m: 0.5)
    write_report(tmp_path / "run", out=tmp_path / "report", behaviour=False)
    assert drawn["categories"][0] == drawn["concepts-classification"][0] == ["cnn", "base", "curr"]
    assert drawn["concepts-bring-about"] == (["base", "curr"], [["base", "curr"]])


@pytest.mark.parametrize("horizontal", [False, True])
def test_bar_panels_leave_no_empty_band_under_the_legend(tmp_path, horizontal):
    """The legend on top, the panels right under it, the caption below (a caption placed as a bottom suptitle once
    left a band of its own height empty at the top)."""
    from sb3_smc.experiments.figures import Panel, bar_panels

    methods = ["cnn", "base", "curr", "canon"]
    panels = [Panel(f"panel {i}", ["a", "b"], {m: [50.0, 70.0] for m in methods}, {m: [5.0, None] for m in methods})
              for i in range(2)]
    path = bar_panels(panels, methods, "a caption under the panels", tmp_path / "bars.png", horizontal=horizontal)
    image = np.asarray(Image.open(path).convert("L"))
    rows = np.flatnonzero((image < 250).any(axis=1))  # rows with anything drawn
    blank_runs = np.diff(rows) - 1  # empty rows after each drawn one
    top = blank_runs[rows[:-1] < image.shape[0] / 3]  # the legend and the panels' titles (it was 78 rows)
    assert top.max() < 0.25 * 120, top.max()  # no band over a quarter inch (120 dpi)
    assert rows[-1] > 0.9 * image.shape[0]  # the caption at the bottom


def _executable(path: Path, body: str) -> None:
    """A shell script at ``path`` running ``body``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(f"#!/bin/sh\n{body}\n")
    path.chmod(0o755)


def _script_repo(tmp_path: Path, stubs: dict[str, str]) -> Path:
    """A repository with ``tools/paper_table.sh`` and, in ``.venv/bin``, stub programs (name -> shell body) for the
    binaries it calls there."""
    repo = tmp_path / "repo"
    (repo / "tools").mkdir(parents=True)
    shutil.copy(ROOT / "tools" / "paper_table.sh", repo / "tools")  # with its mode
    for name, body in stubs.items():
        _executable(repo / ".venv" / "bin" / name, body)
    return repo


def test_the_whole_tables_script_keeps_a_runs_records_without_its_models(tmp_path):
    """``tools/paper_table.sh keep <category> <repo>``: a run directory's records (run.json, results, the wall-time
    ledger, evaluations, the CNN's) copied into ``docs/results/paper/<category>`` (no library, no curves, no lock), a
    later keep replacing the evaluations whole; an unknown command is refused with the usage."""
    run = tmp_path / "runs" / "paper-objects"
    for name in ("run.json", "results.csv", "results.json", "wall_time.json", "evaluations/a@0.json", "cnn/t@0.json",
                 "library/models/" + "0" * 64 + ".safetensors", "tensorboard/a/events", ".wall_time.json.lock"):
        (run / name).parent.mkdir(parents=True, exist_ok=True)
        (run / name).write_text(name)
    script, env = str(ROOT / "tools" / "paper_table.sh"), {**os.environ, "RUNS": str(tmp_path / "runs")}

    def keep() -> None:
        subprocess.run([script, "keep", "objects", str(tmp_path / "repo")], env=env, check=True, capture_output=True)

    keep()
    kept = tmp_path / "repo" / "docs" / "results" / "paper" / "objects"
    assert sorted(str(p.relative_to(kept)) for p in kept.rglob("*") if p.is_file()) == [
        "cnn/t@0.json", "evaluations/a@0.json", "results.csv", "results.json", "run.json", "wall_time.json"]
    (run / "evaluations" / "a@0.json").rename(run / "evaluations" / "a@1.json")
    keep()
    assert [p.name for p in (kept / "evaluations").iterdir()] == ["a@1.json"]
    refused = subprocess.run([script, "nonsense"], env=env, capture_output=True, text=True)
    assert refused.returncode == 2 and "usage:" in refused.stderr


def test_the_whole_tables_script_reports_the_queued_directories_it_has(tmp_path):
    """``tools/paper_table.sh report``: one ``sb3-smc report`` over the complete kept directories of the queue's
    categories, in the queue's order (a category with no records yet, or kept partial, left out), then the README's
    table."""
    repo = _script_repo(tmp_path, {"sb3-smc": f'echo "sb3-smc $*" >> {tmp_path}/calls',
                                   "python": f'echo "python $*" >> {tmp_path}/calls'})
    paper = repo / "docs" / "results" / "paper"
    paper.mkdir(parents=True)
    (paper / "queue.txt").write_text("# category, commit, reuse\nobjects  abc  -\npartial  abc  -\nsearch  abc  -\n"
                                     "later  abc  -\n")
    for category, complete in (("search", True), ("objects", True), ("partial", False)):
        (paper / category).mkdir()
        (paper / category / "results.json").write_text(json.dumps({"complete": complete}))
    subprocess.run([str(repo / "tools" / "paper_table.sh"), "report"], check=True, capture_output=True,
                   env={**os.environ, "RUNS": str(tmp_path / "runs")})
    assert (tmp_path / "calls").read_text().splitlines() == [
        f"sb3-smc report {paper}/objects {paper}/search --out {paper} --no-behaviour",
        f"python {repo}/tools/readme_table.py --brief",  # the landing page
        f"python {repo}/tools/readme_table.py --readme {paper}/README.md"]


def test_the_whole_tables_script_keeps_nothing_of_a_run_with_nothing_evaluated(tmp_path):
    """``tools/paper_table.sh partial <category>`` at a session's end: a run whose tabulation has no row yet (no
    target node finished) or fails is not kept and does not stop the checkpoint (exit 0, said on its output); one
    with rows is kept."""
    run = tmp_path / "runs" / "paper-objects"
    run.mkdir(parents=True)
    (run / "run.json").write_text("{}")
    _executable(tmp_path / "env" / "bin" / "sb3-smc",  # the run's sb3-smc: writes the tabulation it is given
                f"[ -f {tmp_path}/fail ] && exit 1\ncp {tmp_path}/results.json {run}/results.json")
    repo = _script_repo(tmp_path, {"sb3-smc": f'echo "$*" > {tmp_path}/reported'})
    env = {**os.environ, "RUNS": str(tmp_path / "runs"), "RUN_ENV": str(tmp_path / "env")}

    def partial() -> str:
        done = subprocess.run([str(repo / "tools" / "paper_table.sh"), "partial", "objects"], env=env,
                              capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
        return done.stdout

    kept = repo / "docs" / "results" / "paper" / "objects"
    (tmp_path / "results.json").write_text(json.dumps({"rows": [], "complete": False}))
    assert "objects: nothing evaluated yet, not kept" in partial() and not kept.exists()
    (tmp_path / "fail").touch()
    assert "objects: not tabulated (the error above), not kept" in partial() and not kept.exists()
    (tmp_path / "fail").unlink()
    (tmp_path / "results.json").write_text(json.dumps({"rows": [{"target": "t"}], "complete": False}))
    partial()
    assert (kept / "results.json").is_file() and (tmp_path / "reported").read_text().startswith(f"report {kept}")


def test_the_whole_tables_script_passes_a_queue_lines_further_options(tmp_path):
    """A queue line's fourth column on (such as ``--lean-update``) goes to its category's ``sb3-smc experiment``,
    in ``run`` and in ``partial``; a line without one adds nothing."""
    _executable(tmp_path / "env" / "bin" / "sb3-smc", f'echo "$*" >> {tmp_path}/calls')
    repo = _script_repo(tmp_path, {})
    paper = repo / "docs" / "results" / "paper"
    paper.mkdir(parents=True)
    (paper / "queue.txt").write_text("# category, commit, reuse, options\nobjects  abc  -  --lean-update\n"
                                     "search  abc  pretrained\n")
    env = {**os.environ, "RUNS": str(tmp_path / "runs"), "RUN_ENV": str(tmp_path / "env")}
    script = str(repo / "tools" / "paper_table.sh")
    subprocess.run([script, "run", "objects", "search"], env=env, check=True, capture_output=True)
    subprocess.run([script, "partial", "objects"], env=env, check=True, capture_output=True)
    calls = (tmp_path / "calls").read_text().splitlines()
    assert len(calls) == 3
    assert calls[0].startswith(f"experiment --out {tmp_path}/runs/paper-objects --category objects --seeds 5 "
                               "--workers 2") and calls[0].endswith(" --lean-update")
    assert "--lean-update" not in calls[1] and calls[1].endswith("--workers 2")
    assert calls[2].endswith("--no-train --lean-update")


def test_the_whole_tables_script_extends_the_flat_curve_where_the_rule_says(tmp_path):
    """``experience-x16`` / ``experience-x64``: their targets come from ``python -m sb3_smc.experiments.extension``
    over the queue's complete kept categories; where it names none, nothing runs (said on the output)."""
    _executable(tmp_path / "env" / "bin" / "sb3-smc", f'echo "$*" >> {tmp_path}/calls')
    repo = _script_repo(tmp_path, {"python": f'echo "$*" >> {tmp_path}/asked\ncat {tmp_path}/answer'})
    paper = repo / "docs" / "results" / "paper"
    paper.mkdir(parents=True)
    (paper / "queue.txt").write_text("experience  abc  -\nexperience-x16  abc  -  --lean-update\n"
                                     "experience-x64  abc  -  --lean-update\n")
    (paper / "experience").mkdir()
    (paper / "experience" / "results.json").write_text(json.dumps({"complete": True}))
    env = {**os.environ, "RUNS": str(tmp_path / "runs"), "RUN_ENV": str(tmp_path / "env")}
    script = str(repo / "tools" / "paper_table.sh")
    (tmp_path / "answer").write_text("--methods base-x16 --targets a,b\n")
    subprocess.run([script, "run", "experience-x16"], env=env, check=True, capture_output=True)
    assert (tmp_path / "asked").read_text().splitlines() == [
        f"-m sb3_smc.experiments.extension base-x16 {paper}/experience"]
    (call,) = (tmp_path / "calls").read_text().splitlines()
    assert call.startswith(f"experiment --out {tmp_path}/runs/paper-experience-x16 --methods base-x16 --targets a,b "
                           "--seeds 5") and call.endswith(" --lean-update")
    (tmp_path / "answer").write_text("")
    done = subprocess.run([script, "run", "experience-x64"], env=env, check=True, capture_output=True, text=True)
    assert "experience-x64: no target needs it, nothing to run" in done.stdout
    assert len((tmp_path / "calls").read_text().splitlines()) == 1


def test_the_whole_tables_script_lets_a_rerun_replace_an_earlier_categorys_pairs(tmp_path):
    """A complete category of the script's reruns (``experience-cap10``) goes to the report as ``--rerun``, and to the
    curve's extension only for a category after it; the extension of a category reads only the categories before it
    in the queue."""
    repo = _script_repo(tmp_path, {"sb3-smc": f'echo "sb3-smc $*" >> {tmp_path}/calls',
                                   "python": f'echo "python $*" >> {tmp_path}/calls'})
    _executable(tmp_path / "env" / "bin" / "sb3-smc", "true")
    paper = repo / "docs" / "results" / "paper"
    paper.mkdir(parents=True)
    (paper / "queue.txt").write_text("readings  abc  -\nexperience-x64  abc  -\nexperience-cap10  abc  -\n")
    for category in ("readings", "experience-cap10"):
        (paper / category).mkdir()
        (paper / category / "results.json").write_text(json.dumps({"complete": True}))
    env = {**os.environ, "RUNS": str(tmp_path / "runs"), "RUN_ENV": str(tmp_path / "env")}
    script = str(repo / "tools" / "paper_table.sh")
    subprocess.run([script, "run", "experience-x64"], env=env, check=True, capture_output=True)
    subprocess.run([script, "report"], env=env, check=True, capture_output=True)
    calls = (tmp_path / "calls").read_text().splitlines()
    assert calls[0] == f"python -m sb3_smc.experiments.extension base-x64 {paper}/readings"
    assert calls[1] == (f"sb3-smc report {paper}/readings {paper}/experience-cap10 --out {paper} --no-behaviour "
                        f"--rerun {paper}/experience-cap10")


def test_cpu_model_names_the_family_and_model(tmp_path: Path) -> None:
    """The CPU's model of a result (and of the slow tests' reference values): the first processor's name with its
    family and model numbers, since two generations may share a name; the name alone where the numbers are absent,
    None without a name or a file."""
    info = tmp_path / "cpuinfo"
    block = "processor\t: {0}\nvendor_id\t: AuthenticAMD\ncpu family\t: 25\nmodel\t\t: {1}\nmodel name\t: AMD EPYC\n\n"
    info.write_text(block.format(0, 1) + block.format(1, 17))
    assert cpu_model(info) == "AMD EPYC (family 25, model 1)"
    info.write_text("processor\t: 0\nmodel name\t: Apple M2\n")
    assert cpu_model(info) == "Apple M2"
    info.write_text("processor\t: 0\nCPU implementer\t: 0x41\n")
    assert cpu_model(info) is None
    assert cpu_model(tmp_path / "absent") is None


def test_the_per_concept_table_has_the_papers_column_only_where_the_paper_gives_a_number(tmp_path):
    """The demo's target has no number in the paper: no empty "paper" column; a headline target brings it."""
    for name, targets in (("demo", ["cl_self-in-container_vs_noncontainer"]),
                          ("headline", ["cl_self-in-container_vs_noncontainer", "cl_self-left-of-two-objects-vs-one"])):
        _synthetic_table(tmp_path / name, targets, ["base", "curr"], lambda t, m: 0.8)
        [path] = write_report([tmp_path / name], out=tmp_path / f"{name}-report", behaviour=False)
        header = next(line for line in path.read_text().splitlines() if line.startswith("| target | kind | category"))
        assert ("paper (base / curr / canon)" in header) == (name == "headline"), header


@pytest.mark.parametrize("readme", ["README.md", "docs/results/paper/README.md"])
def test_the_committed_readmes_hold_the_reports_answer(readme):
    """Both READMEs' blocks are what ``tools/readme_table.py`` makes from the committed report today: no number of
    them was edited by hand, and none is stale (``tools/paper_table.sh report`` rewrites them)."""
    readme_table = import_tool("readme_table")
    report = ROOT / "docs" / "results" / "paper" / "report.md"
    path = ROOT / readme
    source = Path(os.path.relpath(report, path.parent)).as_posix()
    text = path.read_text(encoding="utf-8")
    start, end = text.index(readme_table.START), text.index(readme_table.END) + len(readme_table.END)
    assert text[start:end] == readme_table.block(report.read_text(encoding="utf-8"), source,
                                                 brief=readme == "README.md")
