"""The claims table's rules: bootstrap intervals over seeds and test worlds (and concepts: the hierarchical
bootstrap), the verdicts (a statement of significance needs our t-test), the readings of a call (a column holds only
what ran under it; a subset's cell says so), wins at the ceiling, our own methods' checks (sb3_smc.experiments.
bootstrap, sb3_smc.experiments.claims, sb3_smc.experiments.statistics)."""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np
import pytest

from pixelworld_env.datasets import catalog
from sb3_smc.experiments import level2_targets
from sb3_smc.experiments.bootstrap import Candidate, Interval, Replicates
from sb3_smc.experiments.claims import (
    NOT_COMPARABLE,
    NOT_JUDGED,
    NOT_RUN,
    NOT_SIGNIFICANT,
    READINGS,
    SAME,
    VERDICTS,
    Judged,
    Reading,
    Statement,
    judge,
    method_checks,
    significance,
    statements,
    tally,
    verdict,
)
from sb3_smc.experiments.statistics import ceiling_wins, wins, wins_text


def _candidates(seed: int = 0, worlds: int = 25) -> dict[tuple[str, str], list[Candidate]]:
    rng = np.random.default_rng(seed)
    out = {}
    for target in ("a", "b", "c"):
        for method, level in (("base", 0.5), ("curr", 0.8)):
            found = []
            for node in ("n1", "n2"):
                for _ in range(5):
                    scores = tuple(float(x) for x in rng.random(worlds) < level)
                    found.append(Candidate(node, float(np.mean(scores)), scores))
            out[(target, method)] = found
    return out


def test_the_estimate_is_the_reported_best_and_the_interval_is_reproducible() -> None:
    candidates = _candidates()
    replicates = Replicates(candidates, replicates=500)
    assert replicates.estimate[("a", "curr")] == max(c.score for c in candidates[("a", "curr")])
    mean = replicates.mean(["a", "b", "c"], "curr")
    assert mean.estimate == pytest.approx(np.mean([replicates.estimate[(t, "curr")] for t in "abc"]))
    assert mean.low < mean.estimate < mean.high
    again = Replicates(candidates, replicates=500).mean(["a", "b", "c"], "curr")
    assert again == mean  # the same records, the same interval
    other = Replicates(candidates, replicates=500, seed=1).mean(["a", "b", "c"], "curr")
    assert other != mean and other.estimate == mean.estimate
    more = {**candidates, ("a", "another"): candidates[("a", "base")], ("d", "curr"): candidates[("a", "curr")]}
    assert Replicates(more, replicates=500).mean(["a", "b", "c"], "curr") == mean  # others beside change nothing
    gap = replicates.gap(["a", "b", "c"], "curr", "base")
    assert gap.estimate == pytest.approx(mean.estimate - replicates.mean(["a", "b", "c"], "base").estimate)
    assert 0 < gap.low < gap.estimate < gap.high


def test_test_worlds_and_seeds_both_widen_the_interval() -> None:
    """An SMC tested on more varied worlds has a wider interval; one without per-world scores counts with its test
    score in every draw (only its seeds vary); one seed of one SMC with constant worlds has no spread at all."""
    def interval(found: list[Candidate]) -> Interval:
        return Replicates({("a", "m"): found}, replicates=1000).mean(["a"], "m")

    varied = [Candidate("n", 0.5, tuple([0.0, 1.0] * 10))]
    steady = [Candidate("n", 0.5, tuple([0.5] * 20))]
    assert interval(varied).high - interval(varied).low > 0.2
    assert interval(steady) == Interval(0.5, 0.5, 0.5)
    seeds = [Candidate("n", s, ()) for s in (0.2, 0.4, 0.6)]
    spread = interval(seeds)
    assert spread.estimate == 0.6 and 0.2 <= spread.low < spread.high <= 0.6  # within what the records can give


def test_the_verdicts() -> None:
    inside, above, below = Interval(80, 75, 85), Interval(90, 88, 92), Interval(70, 68, 72)
    assert [verdict(80.0, i, gap=False) for i in (inside, above, below)] == ["reproduced", "exceeded", "short"]
    # a gap the paper gives as +10: reversed where our interval is wholly below zero
    assert verdict(10.0, Interval(-5, -8, -2), gap=True) == "opposite"
    assert verdict(10.0, Interval(2, -1, 5), gap=True) == "short"
    assert verdict(10.0, Interval(20, 15, 25), gap=True) == "exceeded"
    assert verdict(-2.2, Interval(1.6, 0.5, 2.9), gap=True) == "opposite"  # noprim: the paper's is negative
    assert verdict(-2.2, Interval(-5.0, -6.0, -4.0), gap=True) == "exceeded"
    assert verdict(0.0, Interval(-0.6, -2.3, 1.2), gap=True) == "reproduced"
    # a qualitative statement: the sign of our interval
    assert [verdict(None, i, gap=True) for i in (Interval(3, 1, 5), Interval(0, -1, 1), Interval(-3, -5, -1))] == [
        "reproduced", "short", "opposite"]
    assert tally(["reproduced", "short", "reproduced", NOT_RUN, NOT_JUDGED]) == \
        "2 reproduced, 1 short, 1 not judged: partial, 1 not run"
    with pytest.raises(ValueError, match=r"verdict\(s\) of no known class: \['yes'\]"):
        tally(["yes"])


def _table(methods: dict[str, float]) -> tuple[Replicates, dict[str, str], dict[str, str]]:
    everything = level2_targets()
    kind_of = {t: catalog.dataset(t).kind for t in everything}
    category_of = {t: catalog.dataset(t).category for t in everything}
    candidates = {}
    for k, target in enumerate(everything):
        for method, level in methods.items():
            if method == "cnn" and kind_of[target] != "classification":
                continue
            scores = [level + 0.01 * (k % 5) + 0.004 * (k * sum(map(ord, method)) % 3) + 0.005 * s for s in range(5)]
            candidates[(target, method)] = [Candidate(target, s) for s in scores]
    return Replicates(candidates, replicates=200), kind_of, category_of


def test_every_statement_of_the_paper_under_each_reading() -> None:
    """31 statements (15 classification, 10 bring-about, 6 headline); a reading whose methods did not run says so, a
    later reading that runs a statement's methods as the first does says so (the flat-with-400-moves reading judges
    only the statements about the flat SMC, the costs-its-moves reading none about the cnn and base alone), a pair
    still training is not judged, and a subset of a kind's concepts is not comparable."""
    replicates, kind_of, category_of = _table({"cnn": 0.7, "base": 0.6, "curr": 0.9, "canon": 0.85,
                                               "curr-noprim": 0.9, "canon-noprim": 0.85, "curr-moves": 0.55,
                                               "base-400": 0.65})
    found = statements(kind_of, category_of)
    assert len(found) == 31 and not any(isinstance(s, str) for s in found)
    one_step, moves, flat400, cap10, moves200, *_ = READINGS
    by_text = {s.text: s for s in found}
    curr_mean = by_text["bring-about: mean of curr"]
    cell = judge(curr_mean, one_step, replicates)
    mean = 100 * np.mean([replicates.estimate[(t, "curr")] for t in curr_mean.targets])
    assert cell.verdict == "exceeded" and cell.ours.startswith(f"{mean:.1f} [") and mean > 90  # against 74.5
    assert judge(curr_mean, moves, replicates).verdict == "short"  # curr-moves 55-59 against 74.5
    assert judge(curr_mean, flat400, replicates) == Judged(SAME, "")
    for copied in ("classification: mean of cnn", "bring-about: mean of base", "classification: cnn above base"):
        assert judge(by_text[copied], moves, replicates) == Judged(SAME, "")  # not curr-moves': not counted there
    assert judge(by_text["classification: mean of cnn"], one_step, replicates).verdict in VERDICTS
    test = by_text["bring-about: curr above base (paired t-test)"]
    assert judge(test, moves, replicates).verdict == "opposite" and "t(16) = " in judge(test, moves, replicates).ours
    assert judge(test, flat400, replicates).verdict in VERDICTS  # curr against base-400
    assert judge(by_text["bring-about: mean of canon"], moves, replicates).verdict == NOT_RUN
    for best in (cap10, moves200):  # curr's best setting of each reading: only its own statements count there
        assert judge(curr_mean, best, replicates).verdict == NOT_RUN  # it did not run here
        assert judge(by_text["bring-about: mean of base"], best, replicates) == Judged(SAME, "")
    ran, _, _ = _table({"base": 0.6, "curr-cap10": 0.9, "curr-moves-200": 0.8})
    assert judge(curr_mean, cap10, ran).verdict == "exceeded" and judge(test, moves200, ran).verdict in VERDICTS
    assert "swept" not in judge(test, moves200, ran).ours and "t(16) = " in judge(test, moves200, ran).ours
    target = "ba_self-in-container_from_between-potential-containers"
    assert judge(curr_mean, one_step, replicates, unfinished={(target, "curr")}).verdict == NOT_JUDGED
    subset = {t: kind_of[t] for t in list(kind_of)[:5]}
    assert all(isinstance(s, str) or s.targets[0] in subset for s in statements(subset, category_of))
    assert any(isinstance(s, str) and "17 concepts" in s for s in statements(subset, category_of))
    assert NOT_COMPARABLE == "not comparable: a subset"


def test_a_blend_is_the_weighted_sum_of_scores_in_every_replicate() -> None:
    """The flat SMC's score at a curriculum's experience: a weighted sum of two flat methods' scores, in the estimate
    and in each replicate (so its interval is theirs, drawn together); the original is left as it was."""
    candidates = _candidates()
    replicates = Replicates(candidates, replicates=300)
    blended = replicates.blended({"mix": {"a": (("base", 0.25), ("curr", 0.75))}})
    assert blended.estimate[("a", "mix")] == pytest.approx(
        0.25 * replicates.estimate[("a", "base")] + 0.75 * replicates.estimate[("a", "curr")])
    assert np.allclose(blended.draws[("a", "mix")],
                       0.25 * replicates.draws[("a", "base")] + 0.75 * replicates.draws[("a", "curr")])
    assert ("a", "mix") not in replicates.estimate and not replicates.has(["a"], "mix")
    assert blended.has(["a"], "mix") and not blended.has(["a", "b"], "mix")
    assert blended.mean(["a", "b"], "curr") == replicates.mean(["a", "b"], "curr")


def test_the_equal_experience_readings_judge_curr_against_the_flat_smc_by_sign_on_the_sweep_s_concepts() -> None:
    """Only the comparisons of curr with the flat SMC are judged, on the sweep's concepts of their kind, by the sign
    the paper claims: above zero reproduced, below opposite, holding zero short; other statements are blank, a
    reading without the flat SMC's blend is not run, and a pair still training is not judged."""
    from sb3_smc.experiments.design import SWEEP_TARGETS
    from sb3_smc.experiments.experience import flat_at

    replicates, kind_of, category_of = _table({"base": 0.6, "curr": 0.9})
    by_text = {s.text: s for s in statements(kind_of, category_of) if not isinstance(s, str)}
    one_step, moves, cap10 = READINGS[5:]
    assert one_step.methods == {"curr": "curr-cap100", "base": flat_at("curr-cap100")}
    assert moves.methods == {"curr": "curr-moves-100", "base": flat_at("curr-moves-100")}
    test = by_text["bring-about: curr above base (paired t-test)"]
    assert judge(test, one_step, replicates).verdict == NOT_RUN
    sweep = [t for t in SWEEP_TARGETS if kind_of[t] == "bring-about"]
    extra = {(t, m): [Candidate(t, level + step * k)] for k, t in enumerate(sweep)  # the flat SMC: 50 + k there
             for m, level, step in (("curr-cap100", 0.8, 0.02), ("curr-moves-100", 0.45, 0.005), ("base-x1", 0.4, 0.01),
                                    ("base-x4", 0.6, 0.01))}
    flat = Replicates(extra, replicates=50).blended(
        {flat_at(m): {t: (("base-x1", 0.5), ("base-x4", 0.5)) for t in sweep} for m in ("curr-cap100",
                                                                                        "curr-moves-100")})
    cell = judge(test, one_step, flat)  # curr-cap100 30 + k points above the flat SMC on the 5 concepts
    assert cell.verdict == "reproduced" and cell.ours.startswith("+32.0 [")
    assert f"] on {len(sweep)} swept targets; t(4) = " in cell.ours  # the subset's, said in the cell
    assert judge(test, moves, flat).verdict == "opposite"  # curr-moves-100 5 + k / 2 points below it
    assert judge(by_text["bring-about: mean of curr"], one_step, flat) == Judged("", "")
    assert judge(test, one_step, flat, unfinished={(sweep[0], flat_at("curr-cap100"))}).verdict == NOT_JUDGED
    # curr-cap10 at equal experience: on every concept of the kind, no subset said
    every = [t for t in kind_of if kind_of[t] == "bring-about"]
    assert cap10.methods == {"curr": "curr-cap10", "base": flat_at("curr-cap10")} and len(every) == 17
    extra = {(t, m): [Candidate(t, level - step * k)] for k, t in enumerate(every)
             for m, level, step in (("curr-cap10", 0.5, 0.0), ("base-x1", 0.6, 0.01), ("base-x4", 0.7, 0.01))}
    flat = Replicates(extra, replicates=50).blended(
        {flat_at("curr-cap10"): {t: (("base-x4", 1.0),) for t in every[1:]}})
    assert judge(test, cap10, flat).verdict == NOT_RUN  # the flat SMC's curve misses a concept
    flat = Replicates(extra, replicates=50).blended({flat_at("curr-cap10"): {t: (("base-x4", 1.0),) for t in every}})
    cell = judge(test, cap10, flat)  # 20 - k points below the flat SMC at 4x
    assert cell.verdict == "opposite" and cell.ours.startswith("-12.0 [")
    assert "targets" not in cell.ours and "; t(16) = " in cell.ours


def test_our_own_methods_are_checked_apart() -> None:
    replicates, kind_of, category_of = _table({"base": 0.6, "base-gru": 0.62, "canon-scaled": 0.9})
    rows = method_checks(replicates, kind_of, category_of, ["base", "base-gru", "canon-scaled"])
    texts = [r[0] for r in rows]
    assert texts == ["classification: mean of base-gru", "bring-about: mean of base-gru",
                     "classification: mean of canon-scaled", "classification: canon-scaled above base",
                     "bring-about: mean of canon-scaled", "bring-about: canon-scaled above base"]
    assert rows[0][1] == "74.5" and rows[3][1] == "+5.7" and all(r[3] in VERDICTS for r in rows)


def test_the_sweep_gives_each_setting_s_numbers_on_the_swept_targets_only(tmp_path) -> None:
    """Each setting's mean and lead over base per kind on the swept targets (the subset's, concepts resampled, with
    the paired t-test), the share of swept bring-about targets won, and the headline targets judged against the
    paper's curr; no extrapolation to the other concepts, whatever the whole table's scores there; in the sweep's
    order; the report's section says so, marks a setting still training, and the checks table leaves the settings
    out."""
    import json

    from sb3_smc.experiments.design import SWEEP_METHODS, SWEEP_TARGETS, plan
    from sb3_smc.experiments.report import write_report
    from sb3_smc.experiments.runner import reported
    from sb3_smc.experiments.sweep import sweep_rows

    everything = level2_targets()
    kind_of = {t: catalog.dataset(t).kind for t in everything}
    level = {"base": 0.5, "curr": 0.1, "curr-moves": 0.1}  # far from the settings: an extrapolation would show
    shift = {"curr-cap10": 0.6, "curr-cap25": 0.7, "curr-cap50": 0.8, "curr-cap100": 0.9, "curr-moves-100": 0.3,
             "curr-moves-200": 0.4, "curr-moves-400": 0.45}
    rows = []
    for k, target in enumerate(everything):
        for method, value in {**level, **(shift if target in SWEEP_TARGETS else {})}.items():
            for seed in range(3):
                rows.append({"target": target, "kind": kind_of[target], "category": catalog.dataset(target).category,
                             "method": method, "curriculum": f"{method}/{target}", "seed": seed,
                             "test_score": value - 0.01 * seed + (0.02 if method in shift else 0.01) * (k % 3)})
    replicates = Replicates({key: [Candidate(r["curriculum"], r["test_score"]) for r in rows
                                   if (r["target"], r["method"]) == key]
                             for key in {(r["target"], r["method"]) for r in rows}}, replicates=200)
    found = sweep_rows(replicates, kind_of, [*level, *reversed(shift)])
    assert [row.method for row in found] == list(SWEEP_METHODS)
    numbers = {n.what: n for n in next(row for row in found if row.method == "curr-cap25").numbers}
    swept = [t for t in SWEEP_TARGETS if kind_of[t] == "classification"]
    mean = 100 * np.mean([0.7 + 0.02 * (everything.index(t) % 3) for t in swept])
    assert numbers["classification: mean on the 7 swept"].ours.estimate == pytest.approx(mean)
    lead = numbers["bring-about: lead over base on the 5 swept"]
    ba = [t for t in SWEEP_TARGETS if kind_of[t] == "bring-about"]
    assert lead.ours.estimate == pytest.approx(20 + 100 * np.mean([0.01 * (everything.index(t) % 3) for t in ba]))
    assert lead.gap and lead.test is not None and lead.test[0] == 4 and lead.ours.low < lead.ours.high
    assert numbers["bring-about: beats base on the 5 swept, %"].ours.estimate == 100.0
    headline = numbers["cl_self-left-of-two-objects-vs-one"]
    assert headline.paper == 90.4 and headline.verdict in VERDICTS and not any("extrapolated" in w for w in numbers)
    (tmp_path / "results.json").write_text(json.dumps({
        "rows": rows, "reported": reported(rows), "wall_time_s": 60.0, "command": None, "machine": {},
        "settings": {"methods": [*level, *shift], "targets": everything, "seeds": 3, "timesteps": 400_000,
                     "repeats": 10, "workers": 1, "backend": "local"}}))
    [report] = write_report(tmp_path, behaviour=False)
    text = report.read_text()
    section = text.split("## The readings of a call: the sweep")[1].split("\n## ")[0]
    assert "| **paper** | | | | | | 90.4 | 82.0 |" in section.replace("|  |", "| |").replace("|  |", "| |")
    assert "not judged against the paper's means" in section and "Best fit" not in section
    row = next(line for line in section.splitlines() if line.startswith("| curr-cap25 |"))
    assert f"| {mean:.1f} [" in row and "; t(6) = " in row
    assert "curr-cap25" not in text.split("## Our checks of the method")[1].split("\n## ")[0] \
        if "## Our checks of the method" in text else True
    # a setting still training is shown, marked, its headline targets not judged
    results = json.loads((tmp_path / "results.json").read_text())
    node = plan([SWEEP_TARGETS[0]], ["curr-cap25"]).nodes[(SWEEP_TARGETS[0], "curr-cap25")][0]
    results.update(complete=False, missing=[f"{node}@2"])
    (tmp_path / "results.json").write_text(json.dumps(results))
    [report] = write_report(tmp_path, behaviour=False)
    section = report.read_text().split("## The readings of a call: the sweep")[1].split("\n## ")[0]
    row = next(line for line in section.splitlines() if line.startswith("| curr-cap25 (partial) |"))
    assert ": reproduced" not in row and ": exceeded" not in row and ": short" not in row


def test_the_hierarchical_bootstrap_resamples_concepts_with_a_known_answer() -> None:
    """Concepts without seed or world noise: the concepts held fixed give no spread at all; resampled, the interval of
    the mean is the textbook one (1.96 population s.d. / sqrt(concepts)) and covers the true mean of the population
    the concepts were drawn from in about 95 % of draws; a method a constant above another on every concept has a
    gap without spread (the draws stay paired); the same records and seed give the same interval."""
    rng = np.random.default_rng(7)
    values = rng.normal(0.6, 0.1, 40)
    targets = [f"t{k}" for k in range(40)]
    candidates = {(t, m): [Candidate(t, v + shift)] for t, v in zip(targets, values, strict=True)
                  for m, shift in (("a", 0.0), ("b", 0.05))}
    replicates = Replicates(candidates, replicates=4000)
    assert replicates.mean(targets, "a") == Interval(pytest.approx(values.mean()), pytest.approx(values.mean()),
                                                      pytest.approx(values.mean()))
    found = replicates.mean(targets, "a", concepts=True)
    half = 1.96 * values.std() / np.sqrt(len(values))
    assert found.estimate == pytest.approx(values.mean())
    assert (found.high - found.low) / 2 == pytest.approx(half, rel=0.08)
    assert found.low < values.mean() < found.high
    gap = replicates.gap(targets, "b", "a", concepts=True)
    assert gap.low == pytest.approx(0.05) and gap.high == pytest.approx(0.05)
    assert Replicates(candidates, replicates=4000).mean(targets, "a", concepts=True) == found
    assert Replicates(candidates, replicates=4000, seed=1).mean(targets, "a", concepts=True) != found
    covered = 0
    for draw in range(200):  # coverage of the population's mean 0.6
        sample = np.random.default_rng(100 + draw).normal(0.6, 0.1, 20)
        names = [f"c{k}" for k in range(20)]
        interval = Replicates({(t, "a"): [Candidate(t, v)] for t, v in zip(names, sample, strict=True)},
                              replicates=400, seed=draw).mean(names, "a", concepts=True)
        covered += interval.low <= 0.6 <= interval.high
    assert 0.88 <= covered / 200 <= 0.99


def test_the_hierarchical_bootstrap_adds_the_concepts_to_the_seeds_and_worlds() -> None:
    """Concepts alike but for their worlds' noise: resampling them as well counts that noise about twice (each
    concept's observed score already holds it: the interval sqrt(2) times as wide, the known conservative bias of a
    two-level bootstrap); concepts far apart: the spread between them dominates."""
    rng = np.random.default_rng(3)
    names = [f"t{k}" for k in range(12)]

    def interval(levels: list[float], concepts: bool) -> Interval:
        found = {(t, "m"): [Candidate("n", float(np.mean(w)), tuple(w))
                            for w in [[float(x) for x in rng.random(40) < level]]]
                 for t, level in zip(names, levels, strict=True)}
        return Replicates(found, replicates=2000).mean(names, "m", concepts=concepts)

    def width(found: Interval) -> float:
        return found.high - found.low

    alike, apart = [0.5] * 12, [0.1 + 0.07 * k for k in range(12)]
    assert width(interval(alike, True)) / width(interval(alike, False)) == pytest.approx(np.sqrt(2), rel=0.15)
    assert width(interval(apart, True)) > 2 * width(interval(apart, False))


def _subset_statement(significant: bool) -> tuple[Statement, Replicates]:
    """A hand-made statement of significance (the paper's +10, t-test) over three concepts, with no seed or world
    noise: curr above base by 30, 1 and 2 points (interval excluding zero, t-test p = 0.37) or by 11, 10 and 12
    (p < 0.05)."""
    gaps = (0.11, 0.10, 0.12) if significant else (0.30, 0.01, 0.02)
    targets = ("x", "y", "z")
    candidates = {}
    for target, gap in zip(targets, gaps, strict=True):
        candidates[(target, "base")] = [Candidate(target, 0.5)]
        candidates[(target, "curr")] = [Candidate(target, 0.5 + gap)]
    def gap(score: Callable[[str, str], np.ndarray], ours: Mapping[str, str]) -> np.ndarray:
        return 100 * sum(score(t, ours["curr"]) - score(t, ours["base"]) for t in targets) / len(targets)

    statement = Statement("classification: curr above base (paired t-test)", 10.0, "+10.0; t(2) = 9", targets,
                          ("curr", "base"), gap, gap=True, test=("curr", "base"))
    return statement, Replicates(candidates, replicates=200)


def test_a_statement_of_significance_needs_our_paired_t_test() -> None:
    """Reproduced or exceeded (the paper's sign) and opposite (the other) need our paired t-test at p < 0.05 with that
    sign; otherwise not significant. The interval's other verdicts stay."""
    paper = 10.0
    assert significance("reproduced", (33, 3.0, 0.006), paper) == "reproduced"
    assert significance("exceeded", (33, 5.0, 1e-5), paper) == "exceeded"
    assert significance("reproduced", (6, 1.43, 0.20), paper) == NOT_SIGNIFICANT  # interval alone is not a test
    assert significance("exceeded", (6, 1.43, 0.20), paper) == NOT_SIGNIFICANT
    assert significance("reproduced", (10, -3.0, 0.01), paper) == NOT_SIGNIFICANT  # p < 0.05 the wrong way
    assert significance("reproduced", None, paper) == NOT_SIGNIFICANT
    assert significance("opposite", (4, -2.59, 0.061), paper) == NOT_SIGNIFICANT
    assert significance("opposite", (16, -4.0, 0.001), paper) == "opposite"
    assert significance("reproduced", (16, -4.0, 0.001), -2.0) == "reproduced"  # a negative gap: a negative t
    assert significance("short", (6, 1.43, 0.20), paper) == "short"
    assert NOT_SIGNIFICANT in VERDICTS
    # hand-made rows: the interval beyond the paper's +10 (no noise: [+11, +11]) but p = 0.37 across the concepts
    reading = READINGS[0]
    statement, replicates = _subset_statement(significant=False)
    cell = judge(statement, reading, replicates)
    assert cell.ours.startswith("+11.0 [+11.0, +11.0]; t(2) = 1.16, p = 0.37") and cell.verdict == NOT_SIGNIFICANT
    statement, replicates = _subset_statement(significant=True)
    assert judge(statement, reading, replicates).verdict == "exceeded"
    # on a subset (the equal-experience readings): the cell says on how many of the subset's targets
    subset = Reading("on a subset", {"curr": "curr", "base": "base"}, targets=("x", "y"), subset="swept targets",
                     by_sign=True)
    cell = judge(statement, subset, replicates)
    assert " on 2 swept targets; t(1) = " in cell.ours and cell.verdict in VERDICTS
    statement, replicates = _subset_statement(significant=False)
    cell = judge(statement, Reading("on a subset", subset.methods, targets=("x", "y", "z"), subset="swept targets",
                                    by_sign=True), replicates)
    assert " on 3 swept targets; t(2) = 1.16, p = 0.37" in cell.ours and cell.verdict == NOT_SIGNIFICANT
    with pytest.raises(ValueError, match="judged by sign"):  # a subset's mean is never set against the paper's
        Reading("on a subset", subset.methods, targets=("x", "y"), subset="swept targets")


def test_wins_at_the_ceiling_are_counted_apart() -> None:
    """A win at the ceiling: the winner at 98 % or more, by 2 points or less; the claims table's share of bring-about
    concepts won says how many of its wins are."""
    score = {("a", "h"): 1.0, ("a", "f"): 0.985, ("b", "h"): 0.99, ("b", "f"): 0.96, ("c", "h"): 0.9,
             ("c", "f"): 0.89, ("d", "h"): 0.98, ("d", "f"): 0.97, ("e", "h"): 0.97, ("e", "f"): 0.99,
             ("g", "h"): 1.0, ("g", "f"): 0.98}
    targets = list("abcdeg")
    assert wins(score, targets, ["h"], "f") == (5, 6)
    assert ceiling_wins(score, targets, ["h"], "f") == 3  # a, d and g (by exactly 2 points); not b (3), c (at 90)
    assert wins_text(5, 6, 3) == "5 of 6 (3 of them at the ceiling)" and wins_text(5, 6, 0) == "5 of 6"
    replicates, kind_of, category_of = _table({"base": 0.955, "curr": 0.965, "canon": 0.5})
    won = next(s for s in statements(kind_of, category_of)
               if not isinstance(s, str) and s.text.startswith("bring-about: a hierarchical SMC"))
    cell = judge(won, READINGS[0], replicates)  # curr 0.2-1.8 points above base, at 98.5 % or more
    assert "(17 wins, 17 of them at the ceiling)" in cell.ours and cell.verdict == "exceeded"
    replicates, kind_of, category_of = _table({"base": 0.6, "curr": 0.9, "canon": 0.5})
    assert "ceiling" not in judge(won, READINGS[0], replicates).ours


def test_a_reading_column_counts_only_what_ran_under_it() -> None:
    """The claims table's tally line: the costs-its-moves column leaves out the cnn and base rows it shares with the
    first (said once there) and says how many it left out; a subset column says what it is measured on."""
    from sb3_smc.experiments.runner import reported
    from sb3_smc.experiments.tables import CLAIMS_COUNT, ResultTable, number_sections

    everything = level2_targets()
    level = {"cnn": 0.7, "base": 0.6, "curr": 0.9, "canon": 0.85, "curr-moves": 0.55}
    rows = []
    for k, target in enumerate(everything):
        info = catalog.dataset(target)
        for method, value in level.items():
            if method == "cnn" and info.kind != "classification":
                continue
            rows += [{"target": target, "kind": info.kind, "category": info.category, "method": method,
                      "curriculum": method, "seed": seed, "test_score": value + 0.01 * (k % 7) - 0.05 * seed
                      + 0.002 * k * (method == "curr-moves")} for seed in range(2)]
    lines = number_sections(ResultTable(rows, reported(rows)))
    counted = next(line for line in lines if line.startswith(CLAIMS_COUNT))
    moves = counted.split("a call costs its moves: ")[1].split(";")[0].removesuffix(".")
    assert moves.endswith(f"(6 {SAME}, not counted)")  # mean of cnn, of base (two kinds), cnn above base, 2 headline
    judged = sum(int(part.split()[0]) for part in moves.split(" (")[0].split(", "))
    assert judged == 31 - 6  # every other statement: judged or not run
    rows_of = [line for line in lines if line.startswith("| classification: mean of cnn |")]
    assert rows_of and rows_of[0].split(" | ")[3].strip(" |") == SAME
