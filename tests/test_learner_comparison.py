"""``benchmarks/compare_learners.py`` (docs/learners.md): where its SMCs come from, its job files and its table."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from sb3_smc import SMCLibrary, untrained_smc
from tests.helpers import import_benchmark

NODE = "cl_self-in-left-corner_vs_on-hline"


@pytest.fixture(scope="module")
def compare():
    return import_benchmark("compare_learners")


def _run_with(root: Path, names: list[str]) -> Path:
    """A curriculum-run directory whose library holds untrained SMCs of ``NODE`` under ``names``."""
    library = SMCLibrary([untrained_smc(f"PW-{NODE}-v0", n_envs=1, seed=0, name=name)
                          for name in names])
    library.save(root / "library")
    return root


def test_each_smc_comes_from_the_first_run_that_has_it(compare, tmp_path: Path) -> None:
    first = _run_with(tmp_path / "first", [f"{NODE}@0"])
    second = _run_with(tmp_path / "second", [f"{NODE}@0", f"{NODE}@1"])
    runs = [str(first), str(tmp_path / "not-a-run"), str(second)]
    assert compare.library_with(runs, f"{NODE}@0") == first / "library"
    assert compare.library_with(runs, f"{NODE}@1") == second / "library"
    with pytest.raises(FileNotFoundError, match=f"{NODE}@2"):
        compare.library_with(runs, f"{NODE}@2")


def test_a_job_writes_its_row_once_and_the_table_reads_it(compare, tmp_path: Path) -> None:
    run = _run_with(tmp_path / "run", [f"{NODE}@0"])
    out = tmp_path / "out"
    out.mkdir()
    path = Path(compare.run_one([str(run)], str(out), "ppo-lstm", NODE, 0, 0))
    row = json.loads(path.read_text())
    assert path == compare.result_path(out, "ppo-lstm", NODE, 0)
    assert (row["learner"], row["node"], row["seed"], row["level"]) == ("ppo-lstm", NODE, 0, 1)
    assert 0.0 <= row["test_score"] <= 1.0
    path.write_text(json.dumps({**row, "test_score": 0.5}))  # a finished job is not run again
    assert compare.run_one([str(run)], str(out), "ppo-lstm", NODE, 0, 0) == str(path)
    assert json.loads(path.read_text())["test_score"] == 0.5
    for seed, score in ((1, 0.75), (2, 1.0)):
        compare.result_path(out, "ppo-lstm", NODE, seed).write_text(json.dumps({**row, "seed": seed,
                                                                                 "test_score": score}))
    lines = compare.table(out).splitlines()
    assert lines[0] == "| SMC | ppo-lstm best / mean |"
    assert f"| {NODE} | 100.0 / 75.0 (3) |" in lines
    assert "| **mean, level 1** | 100.0 / 75.0 |" in lines
