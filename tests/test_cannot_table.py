"""The cannot table: its metrics on hand-made records with known answers, and a run that resumes."""

from __future__ import annotations

import json
import shutil

import pytest

from sb3_smc.errors import SMCError
from sb3_smc.experiments.cannot import CANNOT_CHILD, ordinary, results_rows, run_cannot
from sb3_smc.library import SMCLibrary

TARGET = "bc_self-in-container_from_on-floor"


def _write(tmp_path, cell: str, episodes: list[list], **extra) -> None:
    folder = tmp_path / "records" / TARGET
    folder.mkdir(parents=True, exist_ok=True)
    record = {"target": TARGET, "cell": cell, "seed": 0, "offered": [], "record": {"primitive_steps": 1234},
              "evaluations": [{"split": "train", "score": 1.0}, {"split": "test", "score": 0.5}],
              "episodes": episodes, **extra}
    (folder / f"{cell}@0.json").write_text(json.dumps(record))


def test_the_metrics_of_a_bc_cell_and_a_ba_cell(tmp_path):
    """Episodes ``[world, label, signal, success, moves]``: the verdict is CANNOT or not, read against the label."""
    _write(tmp_path, "bc", [[0, 0, "CANNOT", True, 2], [0, 0, None, False, 100],     # impossible world: 1 of 2
                            [1, 1, "SIG1", True, 10], [1, 1, "CANNOT", False, 4]])   # possible world: 1 of 2 wrong
    _write(tmp_path, "ba", [[0, 1, "SIG1", True, 8]],
           possible_episodes=[[0, None, "SIG1", True, 6], [1, None, None, False, 100], [2, None, "SIG1", True, 9]])
    ba, bc = results_rows(tmp_path)
    assert bc["cell"] == "bc" and bc["test_score"] == 0.5 and bc["primitive_steps"] == 1234
    assert bc["cannot_accuracy"] == 0.5  # right: CANNOT on impossible, SIG1 on possible
    assert bc["cannot_on_impossible"] == 0.5 and bc["cannot_on_possible"] == 0.5
    assert bc["success_on_possible"] == 0.5 and bc["moves_to_cannot"] == 2.0
    assert bc["moves_per_episode"] == pytest.approx(116 / 4)
    assert ba["success_on_possible"] == pytest.approx(2 / 3) and ba["cannot_accuracy"] == ""
    assert ba["moves_per_episode"] == 8.0


def test_bad_targets_are_refused_before_any_work(tmp_path):
    with pytest.raises(SMCError, match="cannot-table targets"):
        run_cannot(tmp_path, targets=["bc_nope"])
    with pytest.raises(SMCError, match="keep it among the targets"):
        run_cannot(tmp_path, targets=["bc_self-inside-container_from_on-floor"])
    with pytest.raises(SMCError, match="not a bring-about-or-cannot"):
        ordinary("ba_self-in-container_from_on-floor")
    assert not (tmp_path / "records").exists()


def test_a_run_records_its_cells_and_resumes_without_training_again(tmp_path):
    lines: list[str] = []
    run_cannot(tmp_path, targets=[CANNOT_CHILD], parents=[], seeds=1, printer=lines.append, total_timesteps=600,
               n_envs=4)
    first = {p.name: p.read_bytes() for p in (tmp_path / "records" / TARGET).iterdir()}
    assert sorted(first) == ["ba@0.json", "bc-ba@0.json", "bc@0.json"] and "3 to run" in lines[0]
    bc = json.loads(first["bc@0.json"])
    assert {label for _, label, *_ in bc["episodes"]} == {0, 1} and len(bc["episodes"]) == 50 * 10
    ba = json.loads(first["ba@0.json"])
    assert len(ba["possible_episodes"]) == 25 * 10  # the bc test split's 25 possible worlds
    lines.clear()
    run_cannot(tmp_path, targets=[CANNOT_CHILD], parents=[], seeds=1, printer=lines.append, total_timesteps=600,
               n_envs=4)
    assert "0 to run" in lines[0]
    assert {p.name: p.read_bytes() for p in (tmp_path / "records" / TARGET).iterdir()} == first
    assert (tmp_path / "results.csv").read_text().count("\n") == 4
    assert json.loads(first["bc-ba@0.json"])["offered"] == ["self-in-container_from_on-floor-ba@0"]
    shutil.rmtree(tmp_path / "library")  # the SMC bc-ba calls is lost: its cell runs again, to the same record
    lines.clear()
    run_cannot(tmp_path, targets=[CANNOT_CHILD], parents=[], seeds=1, printer=lines.append, total_timesteps=600,
               n_envs=4)
    assert "1 to run" in lines[0] and "ba@0" in lines[1]
    again = json.loads((tmp_path / "records" / TARGET / "ba@0.json").read_text())
    before = json.loads(first["ba@0.json"])
    assert again["record"].pop("wall_time_s") > 0 and before["record"].pop("wall_time_s") > 0
    assert again == before  # the same SMC: weights aside, every number of its record and tests
    assert "self-in-container_from_on-floor-ba@0" in SMCLibrary.load(tmp_path / "library")


def test_the_report_pairs_targets_and_seeds(tmp_path):
    """Two targets x two seeds and one parent: the table's means, the difference on possible worlds (bc minus ba)
    and the parents' paired difference are the hand-computed ones."""
    from sb3_smc.experiments.cannot import CANNOT_PARENTS, CANNOT_TARGETS, FIELDS, _csv, write_report

    first, second = CANNOT_TARGETS[:2]
    rows = []
    for target, bc, ba in ((first, (0.6, 0.8), (0.5, 0.5)), (second, (0.4, 0.4), (0.5, 0.7))):
        for seed in (0, 1):
            rows.append({**dict.fromkeys(FIELDS, ""), "target": target, "cell": "bc", "seed": seed,
                         "test_score": 0.5, "cannot_accuracy": 0.75, "cannot_on_impossible": 0.9,
                         "cannot_on_possible": 0.1, "success_on_possible": bc[seed], "moves_to_cannot": 3 + seed,
                         "moves_per_episode": 20, "primitive_steps": 100})
            rows.append({**rows[-1], "cell": "bc-ba", "cannot_accuracy": 0.95 - 0.1 * seed})
            rows.append({**dict.fromkeys(FIELDS, ""), "target": target, "cell": "ba", "seed": seed,
                         "test_score": 0.6, "success_on_possible": ba[seed], "moves_per_episode": 30,
                         "primitive_steps": 100})
    for seed, (with_bc, with_ba) in enumerate(((0.9, 0.7), (0.8, 0.7), (1.0, 0.7))):
        for cell, score, moves in (("parent-bc", with_bc, 50 + seed), ("parent-ba", with_ba, 150 + 2 * seed)):
            rows.append({**dict.fromkeys(FIELDS, ""), "target": CANNOT_PARENTS[0], "cell": cell, "seed": seed,
                         "test_score": score, "moves_per_episode": moves, "primitive_steps": 100})
    (tmp_path / "results.csv").write_text(_csv(rows))
    report = write_report(tmp_path).read_text()
    assert report.startswith("# Bring about, or say it cannot be done")
    row = "| 2 | 75.0 ± 0.0 | 90.0 ± 0.0 | 10.0 ± 0.0 | 70.0 ± 14.1 | 50.0 ± 0.0 | +20.0 | 3.5 ± 0.7 |"
    assert f"| {first[3:]} {row}" in report
    assert f"| {second[3:]} | 2 |" in report and "| -20.0 |" in report
    assert "bc minus ba: +0.0 points" in report  # (+20 - 20) / 2
    assert "### bc SMCs calling the ordinary SMC" in report and "bc-ba minus ba: +0.0 points" in report
    assert "cannot accuracy, bc-ba minus bc: +15.0 points" in report  # (+20 + 10) / 2 on each target
    assert f"| {CANNOT_PARENTS[0][3:]} | 3 | 90.0 ± 10.0 | 70.0 ± 0.0 | +20.0 | t(2) = 3.46" in report
    assert "| 51.0 ± 1.0 | 152.0 ± 2.0 |" in report
