"""Equal experience (:mod:`sb3_smc.experiments.experience`): the primitive moves behind a score, from a run's
records, and the report's section setting a curriculum's score beside the flat SMC's at the same experience."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any

import pytest

from sb3_smc.errors import SMCError
from sb3_smc.experiments.experience import EXPERIENCE_HEADING, Experience, Experiences, experience_section, main
from sb3_smc.experiments.tables import ResultTable

TARGET = "ba_self-in-container_from_on-floor"
CURR = f"con2-ba/{TARGET}_curr-in"


def _run(directory: Path, nodes: dict[str, list[str]], steps: dict[str, int], seeds: int = 5) -> Path:
    """A run directory's run.json (nodes and their uses) and library manifest (a record per job)."""
    (directory / "library").mkdir(parents=True)
    (directory / "run.json").write_text(json.dumps(
        {"format": "sb3-smc-run", "version": 1, "seeds": seeds, "nodes": {n: {"uses": u} for n, u in nodes.items()}}))
    smcs = {job: {"record": {"primitive_steps": n}} for job, n in steps.items()}
    smcs["scripted@0"] = {"record": None}  # a job without a record counts for nothing
    (directory / "library" / "manifest.json").write_text(json.dumps({"smcs": smcs}))
    return directory


def test_experience_counts_every_seed_of_every_node_below_once(tmp_path: Path) -> None:
    """Two entries share a lower node (counted once); a node with two of five seeds recorded (pretrained) counts as
    their mean times five; a node without records makes the total unknown. The file round-trips; the command
    writes it. Several runs' experience is kept apart, each score's from its own run."""
    nodes = {"a": [], "b": [], "c": ["a"], CURR: ["a", "b"], f"{CURR}2": ["c"], "untrained": ["a"]}
    steps = {**{f"a@{s}": 100 for s in range(5)}, "b@0": 10, "b@3": 30, **{f"c@{s}": 7 for s in range(5)},
             **{f"{CURR}@{s}": 1000 + s for s in range(5)}, **{f"{CURR}2@{s}": 1 for s in range(5)}}
    run = _run(tmp_path / "run", nodes, steps)
    experience = Experience.from_run(run)
    assert experience.node_total("b") == (10 + 30) / 2 * 5 and experience.node_total("a") == 500
    assert experience.total([CURR]) == 5010 + 500 + 100
    assert experience.total([CURR, f"{CURR}2"]) == 5010 + 500 + 100 + 35 + 5  # "a" once
    assert experience.total(["untrained"]) is None and experience.node_total("scripted") is None
    main([str(run)])
    assert Experience.load(run / "experience.json") == experience
    with pytest.raises(SMCError, match="does not exist"):
        Experience.from_run(tmp_path / "nowhere")
    (run / "experience.json").write_text('{"format": "sb3-smc-experience", "version": 2}')
    with pytest.raises(SMCError, match="experience.json: not an sb3-smc-experience file of version 1"):
        Experience.load(run / "experience.json")
    # two runs with SMCs of one node name trained apart (node "a"): each score counts the records of its own run
    other = Experience(5, {"a": (), CURR: ("a",)}, {"a": {0: 1, 1: 3}, CURR: {s: 2 for s in range(5)}})
    runs = Experiences(((experience, frozenset({(TARGET, "curr")})), (other, frozenset({(TARGET, "curr-cap10")}))))
    assert runs.of(TARGET, "curr") is experience and runs.of(TARGET, "curr-cap10") is other
    assert runs.of(TARGET, "base") is None and experience.of(TARGET, "anything") is experience
    assert other.total([CURR]) == 10 + 2 * 5 and experience.total([CURR]) == 5010 + 500 + 100


def _row(method: str, node: str, seed: int, score: float) -> dict[str, Any]:
    return {"target": TARGET, "kind": "bring-about", "category": "containment", "method": method,
            "curriculum": node, "seed": seed, "test_score": score}


def test_the_section_reads_the_flat_curve_at_the_curriculum_experience(tmp_path: Path) -> None:
    """The flat SMC at 1, 4 and 16 x (2M, 8M, 32M moves; 10, 30, 50 %); curr at 4M moves (its target's and its
    lower nodes') is set against the flat SMC's score interpolated in log experience: 10 + (log 4M - log 2M) /
    (log 8M - log 2M) x 20 = 20 %."""
    flat = {f"base-x{k}/{TARGET}": k * 400_000 for k in (1, 4, 16)}
    nodes = {**{n: [] for n in flat}, "lower": [], CURR: ["lower"]}
    steps = {**{f"{n}@{s}": per for n, per in flat.items() for s in range(5)},
             **{f"lower@{s}": 100_000 for s in range(5)}, **{f"{CURR}@{s}": 700_000 for s in range(5)}}
    experience = Experience.from_run(_run(tmp_path / "run", nodes, steps))
    rows = [_row(f"base-x{k}", f"base-x{k}/{TARGET}", s, score - 0.01 * s)
            for k, score in ((1, 0.1), (4, 0.3), (16, 0.5)) for s in range(5)]
    rows += [_row("curr", CURR, s, 0.4 - 0.01 * s) for s in range(5)]
    reported = [r for r in rows if r["seed"] == 0]
    lines = experience_section(ResultTable(rows, reported), experience)
    assert lines[0] == EXPERIENCE_HEADING
    (row,) = [line for line in lines if line.startswith(f"| {TARGET}")]
    assert "10.0 @ 2.0M / 30.0 @ 8.0M / 50.0 @ 32.0M" in row and "| curr | 40.0 @ 4.0M (2 x) |" in row
    assert math.isclose(10 + (math.log(4) - math.log(2)) / (math.log(8) - math.log(2)) * 20, 20.0)
    assert row.endswith("| 20.0 | +20.0 |")
    assert "curr: ahead on 1 of 1 targets, mean lead +20.0 points [" in lines[-2]
    beyond = Experience(5, experience.uses, {**experience.steps, CURR: {s: 20_000_000 for s in range(5)}})
    (row,) = [line for line in experience_section(ResultTable(rows, reported), beyond) if line.startswith("| ba")]
    assert row.endswith("| 50.0 (its best point: less experience) | -10.0 |")
    assert "curr: ahead on 0 of 1 targets (on 1 the flat SMC's curve ends below its experience), mean lead -10.0" in \
        experience_section(ResultTable(rows, reported), beyond)[-2]
    assert experience_section(ResultTable(rows, reported), None) == []
    # the curve falls at its last point (30 -> 25 %): beyond it, the flat SMC is read at its best point, 30 %
    fell = [{**r, "test_score": r["test_score"] - 0.25} if r["method"] == "base-x16" else r for r in rows]
    (row,) = [line for line in experience_section(ResultTable(fell, [r for r in fell if r["seed"] == 0]), beyond)
              if line.startswith("| ba")]
    assert "10.0 @ 2.0M / 30.0 @ 8.0M / 25.0 @ 32.0M" in row
    assert row.endswith("| 30.0 (its best point: less experience) | +10.0 |")


def test_the_claims_table_judges_curr_against_the_flat_smc_at_its_experience(tmp_path: Path) -> None:
    """The whole table (base and curr on all 51 concepts) with the sweep's curr-cap100 and the flat SMC's curve on
    the sweep's 12: curr-cap100's experience (8M moves) is base-x4's, so the flat SMC there is base-x4's score; the
    one-step equal-experience column judges curr-cap100 against it on the sweep's concepts of each kind, and the
    section gives each method's lead with its interval and t-test. Without the curve the column is not shown."""
    from pixelworld_env.datasets import catalog
    from sb3_smc.experiments import level2_targets
    from sb3_smc.experiments.design import SWEEP_TARGETS
    from sb3_smc.experiments.tables import number_sections

    rows: list[dict[str, Any]] = []
    nodes: dict[str, list[str]] = {"lower": []}
    steps = {f"lower@{s}": 1_000_000 for s in range(5)}
    for k, target in enumerate(level2_targets()):
        data = catalog.dataset(target)
        levels = {"base": 0.5, "curr": 0.9}
        if target in SWEEP_TARGETS:
            levels.update({"curr-cap100": 0.8 + 0.01 * (k % 3), "base-x1": 0.3, "base-x4": 0.5, "base-x16": 0.7})
            for factor in (1, 4, 16):
                nodes[f"base-x{factor}/{target}"] = []
                steps.update({f"base-x{factor}/{target}@{s}": factor * 400_000 for s in range(5)})
            nodes[f"cap/{target}"] = ["lower"]
            steps.update({f"cap/{target}@{s}": 600_000 for s in range(5)})  # 3M + the lower node's 5M = 8M
        for method, level in levels.items():
            node = f"cap/{target}" if method == "curr-cap100" else f"{method}/{target}"
            rows += [{"target": target, "kind": data.kind, "category": data.category, "method": method,
                      "curriculum": node, "seed": s, "test_score": level - 0.01 * s} for s in range(5)]
    reported = [r for r in rows if r["seed"] == 0]
    experience = Experience.from_run(_run(tmp_path / "run", nodes, steps))
    lines = number_sections(ResultTable(rows, reported), experience)
    header = next(line for line in lines if line.startswith("| statement | paper |"))
    assert header.endswith("| one step, at equal experience |")  # curr-moves-100 did not run: no column of its own
    (row,) = [line for line in lines if line.startswith("| bring-about: curr above base (paired t-test)")]
    sweep = [t for t in SWEEP_TARGETS if catalog.dataset(t).kind == "bring-about"]
    lead = 100 * sum(0.01 * (level2_targets().index(t) % 3) for t in sweep) / len(sweep) + 30
    assert f"| +{lead:.1f} [" in row and f"] on {len(sweep)} swept targets; t({len(sweep) - 1}) = " in row
    assert row.endswith(": reproduced |")
    (mean_row,) = [line for line in lines if line.startswith("| bring-about: mean of curr |")]
    assert mean_row.endswith("|  |")  # not a comparison with the flat SMC: blank
    summary = next(line for line in lines if line.startswith("**At equal experience**"))
    assert re.search(r"curr-cap100: ahead on 12 of 12 targets, mean lead \+3\d\.\d points \[\+\d+\.\d, \+\d+\.\d\], "
                     r"t\(11\) = \d+\.\d\d, p = ", summary)
    without = number_sections(ResultTable(rows, reported), None)
    assert "equal experience" not in next(line for line in without if line.startswith("| statement | paper |"))
    # curr-cap100 still training and no curve yet (its run not begun): still no column
    still = ResultTable(rows, reported, {(t, "curr-cap100") for t in SWEEP_TARGETS})
    assert "equal experience" not in next(line for line in number_sections(still, None)
                                          if line.startswith("| statement | paper |"))


def test_while_the_flat_smc_s_curve_is_trained_curr_is_not_judged_at_its_experience(tmp_path: Path) -> None:
    """While the flat SMC's curve is being trained (base-x1 done, base-x4 and base-x16 not yet: no curve at all), the
    equal-experience comparison is shown as "not judged: partial" (not "not run")."""
    from pixelworld_env.datasets import catalog
    from sb3_smc.experiments import level2_targets
    from sb3_smc.experiments.design import SWEEP_TARGETS
    from sb3_smc.experiments.tables import number_sections

    rows: list[dict[str, Any]] = []
    nodes: dict[str, list[str]] = {}
    steps: dict[str, int] = {}
    for target in level2_targets():
        data = catalog.dataset(target)
        levels = {"base": 0.5, "curr": 0.9}
        if target in SWEEP_TARGETS:
            levels.update({"curr-cap100": 0.8, "base-x1": 0.3})
            for name, per in ((f"base-x1/{target}", 400_000), (f"cap/{target}", 1_000_000)):
                nodes[name] = []
                steps.update({f"{name}@{s}": per for s in range(5)})
        for method, level in levels.items():
            node = f"cap/{target}" if method == "curr-cap100" else f"{method}/{target}"
            rows += [{"target": target, "kind": data.kind, "category": data.category, "method": method,
                      "curriculum": node, "seed": s, "test_score": level - 0.01 * s} for s in range(5)]
    reported = [r for r in rows if r["seed"] == 0]
    unfinished = {(t, m) for t in SWEEP_TARGETS for m in ("base-x4", "base-x16")}
    experience = Experience.from_run(_run(tmp_path / "run", nodes, steps))
    lines = number_sections(ResultTable(rows, reported, unfinished), experience)
    (row,) = [line for line in lines if line.startswith("| bring-about: curr above base (paired t-test)")]
    assert row.endswith("| not judged: partial |")


def test_the_flat_curve_is_extended_where_curr_leads_beyond_it_and_the_flat_smc_has_not_converged(
        tmp_path: Path) -> None:
    """The next point of the flat SMC's curve (sb3_smc.experiments.extension) on a target: where curr's experience
    lies beyond the curve, curr leads the flat SMC's best point and a seed of its last point ran its whole budget;
    not where every seed stopped early (converged), where curr trails, where curr's experience lies inside the
    curve, or where the point is measured already; beyond 16 x only while the curve still rises."""
    from sb3_smc.experiments.extension import needs_point

    def case(flat: dict[int, tuple[float, int]], curr: tuple[float, int], name: str) -> list[list[str]]:
        """flat: factor -> (score, each seed's moves); curr: (score, its target node's moves a seed)."""
        nodes = {**{f"base-x{k}/{TARGET}": [] for k in flat}, CURR: []}
        steps = {**{f"base-x{k}/{TARGET}@{s}": moves for k, (_, moves) in flat.items() for s in range(5)},
                 **{f"{CURR}@{s}": curr[1] for s in range(5)}}
        experience = Experience.from_run(_run(tmp_path / name, nodes, steps))
        rows = [_row(f"base-x{k}", f"base-x{k}/{TARGET}", s, score) for k, (score, _) in flat.items() for s in range(5)]
        rows += [_row("curr", CURR, s, curr[0]) for s in range(5)]
        table = ResultTable(rows, [r for r in rows if r["seed"] == 0])
        return [needs_point(table, experience, method, 100) for method in ("base-x16", "base-x64")]

    full = {1: (0.3, 100), 4: (0.5, 400)}  # every seed ran its whole budget (100 moves a seed at 1 x)
    assert case(full, (0.9, 10_000), "leads") == [[TARGET], []]
    assert case({1: (0.3, 100), 4: (0.5, 250)}, (0.9, 10_000), "converged") == [[], []]  # stopped early at 4 x
    assert case(full, (0.4, 10_000), "trails") == [[], []]
    assert case(full, (0.9, 200), "inside") == [[], []]  # 1,000 moves: between the points (500 and 2,000)
    assert case({**full, 16: (0.7, 1600)}, (0.9, 100_000), "rises") == [[], [TARGET]]  # x16 measured; still rising
    assert case({**full, 16: (0.5, 1600)}, (0.9, 100_000), "flat") == [[], []]  # 16 x no better than 4 x
    with pytest.raises(SMCError, match="the curve's next point is one of"):
        needs_point(ResultTable([_row("curr", CURR, 0, 0.5)], [_row("curr", CURR, 0, 0.5)]),
                    Experience(5), "base-x4", 100)
