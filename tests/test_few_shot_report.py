"""The few-shot report's statistics on synthetic rows with known answers, and the report written from a results.csv."""

from __future__ import annotations

import csv

import numpy as np
import pytest

from sb3_smc.experiments.few_shot_report import compare, fewest_worlds, read_results, write_report
from sb3_smc.experiments.statistics import hierarchical_interval

FIELDS = ("target", "kind", "category", "method", "train_worlds", "seed", "test_score", "offered", "primitive_steps")


def test_the_hierarchical_interval_covers_concepts_and_seeds():
    """Equal concepts with no seed noise: the interval is the point; concepts that differ widen it; with many
    concepts drawn around a known mean the 95 % interval holds it."""
    assert hierarchical_interval({"a": [2.0, 2.0], "b": [2.0, 2.0]}) == (2.0, 2.0, 2.0)
    point, low, high = hierarchical_interval({"a": [0.0, 0.0], "b": [10.0, 10.0]})
    assert point == 5.0 and low == 0.0 and high == 10.0
    rng = np.random.default_rng(1)
    concepts = {f"c{i}": list(3.0 + rng.normal(0, 1) + rng.normal(0, 0.5, 5)) for i in range(40)}
    point, low, high = hierarchical_interval(concepts)
    assert low < 3.0 < high and high - low < 1.5
    with pytest.raises(ValueError):
        hierarchical_interval({})


def _rows(scores: dict[tuple[str, str, object], list[float]], kind: str = "bring-about") -> list[dict]:
    return [{"target": t, "kind": kind, "category": "x", "method": m, "train_worlds": w, "seed": s,
             "test_score": v, "offered": 0, "primitive_steps": 100}
            for (t, m, w), values in scores.items() for s, v in enumerate(values)]


def test_compare_pairs_concepts_and_seeds():
    """The difference is the library method's minus the flat SMC's, in points, over the concepts both have; the
    t-test is across concepts."""
    rows = _rows({("a", "auto", 4): [0.9, 0.8], ("a", "base", 4): [0.1, 0.2],
                  ("b", "auto", 4): [0.7, 0.7], ("b", "base", 4): [0.3, 0.2],
                  ("c", "auto", 4): [0.5, 0.5]})  # c has no flat cell: left out
    c = compare(rows, "auto", "bring-about", 4)
    assert c is not None and c.concepts == 2 and c.difference == pytest.approx((70 + 45) / 2)
    assert c.test is not None and c.test[0] == 1
    assert compare(rows, "auto", "classification", 4) is None


def test_the_fewest_worlds_are_paired_on_the_concepts_with_a_flat_smc_on_every_world():
    """Per concept, the first N whose seed mean reaches that concept's flat SMC on every world; pooled, the first N
    whose mean over the concepts measured there reaches the flat SMC's mean over the same concepts; a concept
    without the flat SMC on every world is left out."""
    rows = _rows({("a", "base", "all"): [0.8, 0.6], ("a", "auto", 1): [0.5], ("a", "auto", 2): [0.7, 0.8],
                  ("b", "base", "all"): [0.5], ("b", "auto", 1): [0.6], ("b", "auto", 2): [0.4],
                  ("c", "base", "all"): [0.9], ("c", "auto", 1): [0.2], ("c", "auto", 2): [0.3],
                  ("d", "auto", 1): [1.0]})  # d: no flat SMC on every world
    fewest = fewest_worlds(rows, "auto", [2, "all", 1])
    assert fewest is not None and fewest.per_concept == {"a": 2, "b": 1, "c": None}
    # pooled: N = 1 gives (0.5 + 0.6 + 0.2) / 3 < (0.7 + 0.5 + 0.9) / 3; N = 2 gives (0.75 + 0.4 + 0.3) / 3 < 0.7
    assert fewest.pooled is None
    assert fewest_worlds(rows, "curr", [1, 2]) is None
    closer = _rows({("a", "base", "all"): [0.5], ("a", "curr", 1): [0.2], ("a", "curr", 4): [0.6],
                    ("b", "base", "all"): [0.5], ("b", "curr", 4): [0.5]})  # b measured at N = 4 only
    fewest = fewest_worlds(closer, "curr", [1, 4])
    assert fewest is not None and fewest.per_concept == {"a": 4, "b": 4} and fewest.pooled == 4


def test_the_report_is_written_from_results_csv(tmp_path):
    rows = _rows({("a", "auto", 4): [0.9], ("a", "base", 4): [0.1], ("a", "base", "all"): [0.5],
                  ("b", "auto", 4): [0.7], ("b", "base", 4): [0.3], ("b", "base", "all"): [0.6]})
    rows += _rows({("c", "cnn", 4): [0.6, 0.8], ("c", "base", 4): [0.5]}, kind="classification")
    with open(tmp_path / "results.csv", "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=FIELDS)
        writer.writeheader()
        writer.writerows(rows)
    assert read_results(tmp_path / "results.csv")[0]["train_worlds"] in (4, "all")
    report = write_report(tmp_path, library_steps={"x@0": 1000, "y@0": 2000}).read_text()
    assert "| auto | 80.0 (2) | - |" in report and "| base | 20.0 (2) | 55.0 (2) |" in report
    assert "a count below the kind's (2 bring-about, 1 classification) marks a cell" in report
    bring_about, classification = report.split("### bring-about")[1].split("### classification")
    assert "| cnn |" not in bring_about and "| cnn | 70.0 (1) | - |" in classification.split("\n## ")[0]
    assert "| bring-about | auto | 2 | 55.0 % | 2 | 4 | 4 |" in report  # a: 0.9 >= 0.5 at N = 4; b: 0.7 >= 0.6
    assert "| classification | - | 0 | not measured yet | - | - | - |" in report
    assert "3,000 primitive steps in all" in report and (tmp_path / "few_shot.png").stat().st_size > 1000
    assert "a hollow point stands on fewer concepts than the method's other points" in report
    from sb3_smc.experiments.few_shot import FEW_SHOT_METHODS
    from sb3_smc.experiments.few_shot_report import COLOURS

    assert set(COLOURS) == set(FEW_SHOT_METHODS)  # one colour per method in every panel


def test_the_few_shot_script_checkpoints_a_runs_new_records(tmp_path):
    """``tools/few_shot_table.sh checkpoint``: the run's records copied into docs/results/few_shot/records (the
    committed ones left as they are), then results.csv and the report written by the repository's Python; without a
    run it says so; an unknown command gets the usage."""
    import os
    import shutil
    import subprocess
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    repo = tmp_path / "repo"
    (repo / "tools").mkdir(parents=True)
    shutil.copy(root / "tools" / "few_shot_table.sh", repo / "tools")
    stub = repo / ".venv" / "bin" / "python"
    stub.parent.mkdir(parents=True)
    stub.write_text(f"#!/bin/sh\necho \"$@\" > {tmp_path}/called\n")
    stub.chmod(0o755)
    kept = repo / "docs" / "results" / "few_shot" / "records" / "a"
    kept.mkdir(parents=True)
    (kept / "base-n1@0.json").write_text("committed")
    run = tmp_path / "src" / "runs" / "few-shot" / "records" / "a"
    run.mkdir(parents=True)
    (run / "base-n1@0.json").write_text("the run's copy")
    (run / "base-n8@0.json").write_text("new")
    script = [str(repo / "tools" / "few_shot_table.sh")]
    env = {**os.environ, "FEW_SHOT_SRC": str(tmp_path / "src")}
    subprocess.run([*script, "checkpoint"], check=True, env=env, capture_output=True)
    assert (kept / "base-n1@0.json").read_text() == "committed" and (kept / "base-n8@0.json").read_text() == "new"
    assert "write_results(out)" in (tmp_path / "called").read_text()
    assert "write_report(out)" in (tmp_path / "called").read_text()
    missing = subprocess.run([*script, "checkpoint"], env={**env, "FEW_SHOT_SRC": str(tmp_path / "none")},
                             capture_output=True, text=True)
    assert missing.returncode == 1 and f"no run at {tmp_path / 'none'}" in missing.stderr
    wrong = subprocess.run([*script, "go"], env=env, capture_output=True, text=True)
    assert wrong.returncode == 2 and "usage:" in wrong.stderr


def test_the_committed_few_shot_report_is_its_records(tmp_path):
    """The committed results.csv is the committed records' rows, and report.md is what write_report makes of it: a
    checkpoint left nothing stale."""
    import shutil
    from pathlib import Path

    from sb3_smc.experiments.few_shot import results_csv

    committed = Path(__file__).resolve().parents[1] / "docs" / "results" / "few_shot"
    assert (committed / "results.csv").read_text(encoding="utf-8") == results_csv(committed)
    shutil.copy(committed / "results.csv", tmp_path / "results.csv")
    assert write_report(tmp_path).read_text(encoding="utf-8") == (committed / "report.md").read_text(encoding="utf-8")
