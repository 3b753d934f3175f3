"""The report's numbers: :class:`ResultTable` (the merged results of one experiment directory or several) and the
Markdown sections :func:`number_sections` writes from it: the claims table, every concept (best seed, mean ± s.d.
over seeds), the flat SMC beside the original runs', means per kind and category ± s.e. across concepts, the paired
t-tests (with the paper's beside them) and win counts, the same means and tests over seeds, and the noprim table.
The statistics themselves: :mod:`sb3_smc.experiments.statistics`; the paper's numbers:
:mod:`sb3_smc.experiments.paper`.
"""

from __future__ import annotations

import functools
import math
from collections import defaultdict
from collections.abc import Collection, Sequence
from typing import Any

import numpy as np

from sb3_smc.errors import SMCError
from sb3_smc.experiments.bootstrap import Candidate, Replicates
from sb3_smc.experiments.claims import (
    NOT_COMPARABLE,
    NOT_JUDGED,
    READINGS,
    SAME,
    SIGNIFICANCE,
    VERDICTS,
    Reading,
    judge,
    method_checks,
    points,
    statements,
    tally,
)
from sb3_smc.experiments.design import CATEGORIES, EXPERIENCE_METHODS, METHOD_REGISTRY, METHODS, PAPER_CATEGORIES
from sb3_smc.experiments.experience import ExperienceSource, at_experience, blends, experience_section, flat_at
from sb3_smc.experiments.paper import (
    ORIGINAL_FLAT_RUNS,
    PAPER_CONCEPTS,
    PAPER_COUNTS,
    PAPER_MEANS,
    PAPER_NOPRIM,
    PAPER_TTESTS,
)
from sb3_smc.experiments.statistics import (
    CEILING,
    NEAR,
    Score,
    ceiling_wins,
    mean_of_all,
    mean_se,
    method_mean,
    method_test,
    p_at_df,
    paired_ttest,
    seed_summary,
    ttest_text,
    wins,
    wins_text,
)
from sb3_smc.experiments.sweep import sweep_rows

__all__ = ["CHECKS_HEADING", "CLAIMS_COUNT", "CLAIMS_HEADING", "KINDS", "MEANS_HEADING", "ResultTable",
           "SWEEP_HEADING", "TESTS_HEADING", "number_sections"]

KINDS = ("classification", "bring-about")
CLAIMS_COUNT = "**In all**"
"""How the line under the claims table that counts their verdicts begins."""
MEANS_HEADING = "## Means per kind and category (Fig. 5a/5d)"
TESTS_HEADING = "## Paired t-tests across concepts"
CLAIMS_HEADING = "## The paper's claims"
CHECKS_HEADING = "## Our checks of the method"
SWEEP_HEADING = "## The readings of a call: the sweep"
"""The headings of the report's sections that the README quotes (tools/readme_table.py finds them by these)."""


def _pct(value: float | None) -> str:
    return "-" if value is None or (isinstance(value, float) and math.isnan(value)) else f"{100 * value:.1f}"


def _marked(text: str, mark: str) -> str:
    """``text`` and ``mark`` (``""`` stays ``""``: no number, nothing to mark)."""
    return text + mark if text and text != "-" else text


def _diff(ours: float | None, paper: float | None) -> str:
    if ours is None or paper is None:
        return ""
    return f"{100 * ours - paper:+.1f}"


PARTIAL = " (partial)"
"""The mark of a number over a target x method with SMCs not trained yet (:attr:`ResultTable.unfinished`)."""


class ResultTable:
    """The merged results of a report: reported scores, seed scores, kinds and categories; ``unfinished``: the
    target x method pairs of a run still being trained (some of their seeds or curricula not trained yet), whose
    numbers are marked partial and whose claims are not judged."""

    def __init__(self, rows: Sequence[dict[str, Any]], reported: Sequence[dict[str, Any]],
                 unfinished: Collection[tuple[str, str]] = ()) -> None:
        if not reported:
            raise SMCError("no results to report")
        self.unfinished = frozenset(unfinished)
        self.methods = [m for m in METHODS if any(r["method"] == m for r in reported)]
        self.score = {(r["target"], r["method"]): r["test_score"] for r in reported}
        self.targets = sorted({r["target"] for r in reported})
        self.kind_of = {r["target"]: r["kind"] for r in reported}
        self.category_of = {r["target"]: r["category"] for r in reported}
        best_curriculum = {(r["target"], r["method"]): r["curriculum"] for r in reported}
        by_seed: dict[tuple[str, str], list[float]] = defaultdict(list)
        for row in rows:  # the seeds of the reported curriculum
            if row["curriculum"] == best_curriculum.get((row["target"], row["method"])):
                by_seed[(row["target"], row["method"])].append(row["test_score"])
        self.seeds = dict(by_seed)
        self.seed_mean = {key: float(np.mean(scores)) for key, scores in self.seeds.items()}
        """Each target x method's mean over the seeds of its reported curriculum (none where the records have no
        seeds: the means over seeds then leave it out)."""
        candidates: dict[tuple[str, str], list[Candidate]] = defaultdict(list)
        for row in rows:  # every SMC a method may report: each row's per-world scores where the report read them
            candidates[(row["target"], row["method"])].append(
                Candidate(row["curriculum"], row["test_score"], tuple(row.get("worlds") or ())))
        self._candidates = dict(candidates)

    @functools.cached_property
    def replicates(self) -> Replicates:
        """Bootstrap replicates of every reported score, over seeds and test worlds (the claims' intervals)."""
        return Replicates(self._candidates)

    def candidate_nodes(self, target: str, method: str) -> set[str]:
        """The nodes (curriculum entries) of the SMCs that ``method``'s score on ``target`` was chosen from."""
        return {c.node for c in self._candidates.get((target, method), ())}

    def like(self, paper: str) -> list[str]:
        """Our methods that ran compared with the paper's method ``paper`` (``base``: ``base`` and ``base-gru``;
        ``canon``: ``canon`` and ``canon-scaled``), or ``[paper]`` when none did (its comparisons then say it did
        not run)."""
        return [m for m in self.methods if METHOD_REGISTRY[m].paper_name == paper] or [paper]

    @property
    def flats(self) -> list[str]:
        """The flat methods that ran, each compared with the paper's flat SMC (:meth:`like` ``base``)."""
        return self.like("base")

    @property
    def hierarchical(self) -> list[str]:
        """The hierarchical methods compared with the flat ones: those of the paper's ``curr`` and ``canon``."""
        return [*self.like("curr"), *self.like("canon")]

    def of_kind(self, kind: str, category: str | None = None) -> list[str]:
        return [t for t in self.targets if self.kind_of[t] == kind and category in (None, self.category_of[t])]

    def partial(self, members: Sequence[str], *methods: str) -> str:
        """:data:`PARTIAL` when any of ``methods`` is unfinished on any of ``members``, else ``""``."""
        return PARTIAL if any((t, m) in self.unfinished for t in members for m in methods) else ""

    def cell(self, target: str, method: str) -> str:
        """Best seed (mean ± s.d. over seeds), marked partial while the pair is unfinished."""
        if (target, method) not in self.score:
            return "-"
        scores = self.seeds.get((target, method)) or [self.score[(target, method)]]
        return seed_summary(scores).text() + self.partial([target], method)

    def mean_se(self, members: Sequence[str], method: str,
                score: Score | None = None) -> tuple[float, float | None] | None:
        """Mean and s.e. of ``method``'s ``score`` (the reported one unless given) across ``members``
        (:func:`mean_se`); ``None`` unless all of them ran."""
        score = self.score if score is None else score
        values = [score[(t, method)] for t in members if (t, method) in score]
        return mean_se(values) if values and len(values) == len(members) else None

    def mean_cell(self, members: Sequence[str], method: str, score: Score | None = None) -> str:
        """Mean ± s.e. across ``members`` (all of them must have run), marked partial while any is unfinished."""
        found = self.mean_se(members, method, score)
        if found is None:
            return "-"
        mean, se = found
        return f"{100 * mean:.1f}" + (f" ± {100 * se:.1f}" if se is not None else "") + self.partial(members, method)


def _scope(reading: Reading) -> str:
    """The concepts a reading is judged on, where not all (``""``): ``the 12 swept targets``, ``the targets outside
    the sweep``."""
    if reading.targets is not None:
        return f"the {len(reading.targets)} {reading.subset}"
    return f"the {reading.subset}" if reading.subset else ""


def _claims_section(table: ResultTable, experience: ExperienceSource | None) -> list[str]:
    """One row per statement of the paper, a verdict under each reading of a call that ran (``claims``); the flat
    SMC at a curriculum's experience where the runs' ``experience`` was kept."""
    found = statements(table.kind_of, table.category_of)
    at = at_experience(table, experience)
    replicates = table.replicates.blended(blends(at))
    # the flat SMC at a method's experience is unfinished where a point of its curve is (trained in part, or not yet)
    unfinished = table.unfinished | {(t, flat_at(m)) for t in table.targets for m in table.hierarchical
                                     if any((t, f) in table.unfinished for f in EXPERIENCE_METHODS)}
    cells = {id(st): [judge(st, reading, replicates, unfinished) for reading in READINGS]
             for st in found if not isinstance(st, str)}
    first = set(READINGS[0].methods.values())  # a later reading is shown where a method of its own ran
    shown = [k for k, reading in enumerate(READINGS)
             if (k == 0 or (set(reading.methods.values()) - first) & set(table.methods))
             and any(row[k].verdict in (*VERDICTS, NOT_JUDGED) for row in cells.values())]
    if not shown:
        return []
    readings = [READINGS[k] for k in shown]
    lines = [CLAIMS_HEADING, "",
             "Every statement of the paper's results with ours under each reading of an SMC call: ours with its 95 % "
             "bootstrap interval (points) over seeds and test worlds (the paper's numbers are over the same concepts "
             "as ours), and over the concepts too where a statement is judged by its sign (a hierarchical bootstrap), "
             "and the verdict: reproduced where the paper's number lies inside our interval, exceeded or short where "
             "our interval lies beyond or before it, opposite where it lies on the other side of zero; a statement "
             "without a number of the paper, or on a subset of its concepts, by the sign of our interval. A statement "
             "of significance (a paired t-test of the paper) keeps a verdict that gives a sign (reproduced, exceeded, "
             f"opposite) only where our paired t-test gives p < {SIGNIFICANCE} with that sign, else it is not "
             "significant (docs/experiments.md, \"The claims table\"). A later reading that runs a statement's "
             f"methods as the first does says \"{SAME}\", not counted in its column. A win at the ceiling: the "
             f"winner at {100 * CEILING:.0f} % or more, by {100 * NEAR:.0f} points or less. "
             + " ".join(f"*{r.name}*: {', '.join(f'{p} = {m}' for p, m in r.methods.items() if p != m) or 'as run'}"
                        + (" (the comparisons of curr with the flat SMC" + (f" on {_scope(r)}" if r.subset else "")
                           + ", the flat SMC read off its curve of experience, judged by the sign the paper claims"
                           + (" on these targets only" if r.subset else "") + ")" if r.by_sign else "")
                        + "."
                        for r in readings), "",
             "| statement | paper | " + " | ".join(r.name for r in readings) + " |",
             "|---|---|" + "---|" * len(readings)]
    verdicts: list[list[str]] = [[] for _ in readings]
    same = [0] * len(readings)
    for st in found:
        if isinstance(st, str):
            lines.append(f"| {st} | | " + " | ".join(NOT_COMPARABLE for _ in readings) + " |")
            continue
        row = [cells[id(st)][k] for k in shown]
        for k, cell in enumerate(row):
            if cell.verdict:
                verdicts[k].append(cell.verdict)
            same[k] += cell.ours == SAME
        lines.append(f"| {st.text} | {st.paper_text} | "
                     + " | ".join(f"{c.ours}: {c.verdict}" if c.verdict in VERDICTS else (c.verdict or c.ours)
                                  for c in row) + " |")
    count = sum(not isinstance(st, str) for st in found)
    lines += ["", f"{CLAIMS_COUNT} ({count} statements): "
              + "; ".join(f"{r.name}" + (f" (on {_scope(r)})" if r.subset else "")
                          + f": {tally(v)}" + (f" ({n} {SAME}, not counted)" if n else "")
                          for r, v, n in zip(readings, verdicts, same, strict=True)) + ".", ""]
    checks = method_checks(table.replicates, table.kind_of, table.category_of, table.methods, table.unfinished)
    if checks:
        lines += [CHECKS_HEADING, "",
                  "Our own methods that no reading uses (the sweep's settings: its section below), against the paper's "
                  "numbers for the method they stand for "
                  "(their mean, and their lead over the flat SMC), judged by the same rules; on fewer concepts than "
                  "the paper's, shown and not judged.", "",
                  "| check | paper | ours | verdict |", "|---|---|---|---|"]
        lines += [f"| {text} | {paper} | {ours} | {verdict} |" for text, paper, ours, verdict in checks]
        lines.append("")
    return lines


def _sweep_section(table: ResultTable) -> list[str]:
    """The sweep of the readings' free parameters: each setting's numbers on the swept targets
    (:mod:`sb3_smc.experiments.sweep`), the headline targets judged against the paper."""
    kinds = {t: k for t, k in table.kind_of.items() if table.category_of[t] != "pushable"}
    rows = sweep_rows(table.replicates, kinds, table.methods)
    if not rows:
        return []
    columns = list(dict.fromkeys(n.what for row in rows for n in row.numbers))
    paper = {n.what: f"{n.paper:.1f}" for row in rows for n in row.numbers if n.paper is not None}
    lines = [SWEEP_HEADING, "",
             "Each setting of the sweep (docs/experiments.md, \"Equal budgets and the readings of a call\") on the "
             "swept targets: per kind its mean and its lead over the flat SMC (with the paired t-test across the "
             "targets), on the bring-about targets the share it beats the flat SMC on, each with its 95 % bootstrap "
             "interval over the swept targets as well as seeds and test worlds. These are the subset's numbers, not "
             "the kinds': they are not judged against the paper's means. The headline targets are the paper's own "
             "concepts: ours there is judged against its curr. The best setting of each reading here, curr-cap10 and "
             "curr-moves-200, is run on every concept: the claims table judges it (its columns \"one step, a call "
             "cut after 10 moves\" and \"costs its moves, 200 moves an episode\").", "",
             "| setting | " + " | ".join(columns) + " |", "|---|" + "---|" * len(columns),
             "| **paper** | " + " | ".join(paper.get(c, "") for c in columns) + " |"]
    for row in rows:
        partial = table.partial(table.targets, row.method)
        cells = {n.what: points(n.ours, n.gap) + (f"; {ttest_text(n.test)}" if n.test is not None else "")
                 + (f": {n.verdict}" if n.verdict and not partial else "") for n in row.numbers}
        lines.append(f"| {row.method}{partial} | " + " | ".join(cells.get(c, "-") for c in columns) + " |")
    return [*lines, ""]


def _concept_section(table: ResultTable) -> list[str]:
    methods = table.methods
    given = [t for t in table.targets if t in PAPER_CONCEPTS]  # the paper's column only where it gives a number
    paper_column = " paper (base / curr / canon) |" if given else ""
    lines = ["## Per concept", "",
             "Best seed (curr: best curriculum) as the paper reports, then the mean ± s.d. over the seeds of that "
             "curriculum.", "",
             "| target | kind | category | " + " | ".join(methods) + " |" + paper_column,
             "|---|---|---|" + "---:|" * len(methods) + ("---|" if given else "")]
    for target in table.targets:
        paper = PAPER_CONCEPTS.get(target)
        paper_text = " / ".join(f"{paper[m]:.1f}" for m in ("base", "curr", "canon")) if paper else ""
        paper_cell = f" {paper_text} |" if given else ""
        lines.append(f"| {target} | {table.kind_of[target]} | {table.category_of[target]} | "
                     + " | ".join(table.cell(target, m) for m in methods) + " |" + paper_cell)
    if given:
        lines += ["", "Differences to the paper (ours - paper, points):", ""]
        for target in given:
            parts = [f"{m} {_diff(table.score[(target, m)], PAPER_CONCEPTS[target][name])}{table.partial([target], m)}"
                     for m in methods if (name := METHOD_REGISTRY[m].paper_name) in PAPER_CONCEPTS[target]
                     and (target, m) in table.score]
            lines.append(f"- {target}: " + ", ".join(parts))
    return lines


def _original_flat_section(table: ResultTable) -> list[str]:
    """Our flat SMCs beside the original runs' on the concepts whose numbers the release's files record."""
    lines: list[str] = []
    for flat in table.flats:
        given = [t for t in table.targets if t in ORIGINAL_FLAT_RUNS and (t, flat) in table.score]
        if not given:
            continue
        lines += ["", f"## The flat SMC ({flat}) beside the original runs'", "",
                  "The release's curriculum files record the original runs' flat SMCs on the objects concepts (best "
                  f"seed and mean over seeds, their comments' \"Max\" and \"Avg\"); ours (`{flat}`) beside them.", "",
                  "| target | kind | ours: best (mean ± s.d.) | original: best (mean) | best: ours - original |",
                  "|---|---|---:|---:|---:|"]
        for target in given:
            best, mean = ORIGINAL_FLAT_RUNS[target]
            lines.append(f"| {target} | {table.kind_of[target]} | {table.cell(target, flat)} | {best:.1f} "
                         f"({mean:.1f}) | {_diff(table.score[(target, flat)], best)}{table.partial([target], flat)} |")
        for kind in KINDS:
            members = [t for t in given if table.kind_of[t] == kind]
            if not members:
                continue
            sentences = []
            for which, score, column in (("best seed", table.score, 0), ("mean over seeds", table.seed_mean, 1)):
                ours = [score[(t, flat)] for t in members]
                theirs = [ORIGINAL_FLAT_RUNS[t][column] / 100 for t in members]
                test = paired_ttest(ours, theirs)
                tested = f" (paired {ttest_text(test)})" if test else ""
                sentences.append(f"{which} ours {100 * sum(ours) / len(ours):.1f}, original "
                                 f"{100 * sum(theirs) / len(theirs):.1f}{tested}")
            lines.append(f"\n{kind}, {len(members)} concepts{table.partial(members, flat)}, means: "
                         f"{'; '.join(sentences)}.")
    return lines


def _means_header(methods: Sequence[str]) -> list[str]:
    return ["| kind | category | concepts | " + " | ".join(methods) + " |", "|---|---|---:|" + "---:|" * len(methods)]


def _category_rows(table: ResultTable, kind: str, score: Score) -> list[str]:
    """A kind's rows of a means table: each category's mean ± s.e. of ``score`` per method, then all of the kind's."""
    groups = [(c, table.of_kind(kind, c)) for c in CATEGORIES]
    return [f"| {kind} | {label} | {len(members)} | "
            + " | ".join(table.mean_cell(members, m, score) for m in table.methods) + " |"
            for label, members in [*[(c, m) for c, m in groups if m], ("all", table.of_kind(kind))]]


def _means_section(table: ResultTable) -> list[str]:
    methods = table.methods
    lines = ["", MEANS_HEADING, "",
             "Mean of the reported scores ± standard error across concepts.", "", *_means_header(methods)]
    for kind in KINDS:
        in_kind = table.of_kind(kind)
        if not in_kind:
            continue
        lines += _category_rows(table, kind, table.score)
        in_paper = [t for t in in_kind if table.category_of[t] in PAPER_CATEGORIES]
        if not in_paper:  # the designed pushable curriculum: the paper gives no numbers (Fig. 5c only)
            continue
        names = {m: METHOD_REGISTRY[m].paper_name for m in methods}  # the noprim means: that paragraph's
        paper = {m: PAPER_MEANS[kind].get(name, PAPER_NOPRIM[kind].get(name)) for m, name in names.items()}
        lines.append(f"| {kind} | **paper** (all) | {PAPER_COUNTS[kind]} | "
                     + " | ".join(f"{paper[m]:.1f}" if paper[m] is not None else "" for m in methods) + " |")
        if len(in_paper) == PAPER_COUNTS[kind]:  # the paper's whole set: its means
            lines.append(f"| {kind} | ours - paper ({len(in_paper)} concepts) | | " + " | ".join(
                _marked(_diff(method_mean(table.score, in_paper, m), paper[m]), table.partial(in_paper, m))
                for m in methods) + " |")
        else:  # a subset: only against the paper's own numbers for the same concepts, where it gives them
            diffs = [_marked(_diff(method_mean(table.score, in_paper, m), mean_of_all(
                [PAPER_CONCEPTS.get(t, {}).get(METHOD_REGISTRY[m].paper_name) for t in in_paper])),
                table.partial(in_paper, m)) for m in methods]
            if any(diffs):
                lines.append(f"| {kind} | ours - paper (the same {len(in_paper)} concept(s), where the paper gives "
                             "them) | | " + " | ".join(diffs) + " |")
    return lines


def _seed_means_section(table: ResultTable) -> list[str]:
    """The means per kind and category and the hierarchical-against-flat tests from each concept's mean over its
    seeds instead of its best seed."""
    methods = table.methods
    lines = ["", "## Over seeds: means and tests from each concept's mean over its seeds", "",
             "The paper reports each concept's best seed. Here each concept's score is the mean over the seeds of its "
             "reported curriculum instead: what a method gives in a typical seed, without the luck of the best one "
             "(a method that learns a concept in one seed of five keeps its best seed above, not here; curr's "
             "curriculum per concept is still the one with the best seed). Mean ± "
             "standard error across concepts; paired t-tests across concepts, df = concepts - 1.", "",
             *_means_header(methods)]
    tests = []
    for kind in KINDS:
        in_kind = table.of_kind(kind)
        if not in_kind:
            continue
        lines += _category_rows(table, kind, table.seed_mean)
        for a, b in ((a, b) for b in table.flats for a in table.hierarchical):
            compared, test = method_test(table.seed_mean, in_kind, a, b)
            if test is not None:
                df, t, p = test
                tests.append(f"| {kind} | {a} vs {b}{table.partial(in_kind, a, b)} | {compared} | {t:.2f} | {df} | "
                             f"{p:.2g} |")
    if tests:
        lines += ["", "| kind | comparison | concepts | t | df | p |", "|---|---|---:|---:|---:|---:|", *tests]
    return lines


def _ttest_section(table: ResultTable) -> list[str]:
    methods = table.methods
    lines = ["", TESTS_HEADING, "",
             "Two-sided paired t-tests of the reported scores (scipy `ttest_rel`); df = concepts - 1. Where the "
             "paper tested the same comparison over the same concepts (all of a kind), its t, df and p are beside "
             "ours, and the last column reads our t at the paper's degrees of freedom (it gives df 34 for 34 "
             "classification concepts).", "",
             "| kind / category | comparison | concepts | t | df | p | paper | p at the paper's df |",
             "|---|---|---:|---:|---:|---:|---|---:|"]
    for kind in KINDS:
        in_kind = table.of_kind(kind)
        if not in_kind:
            continue
        whole = len(in_kind) == PAPER_COUNTS[kind] and all(
            table.category_of[t] in PAPER_CATEGORIES for t in in_kind)  # the paper tested all its concepts
        for a, b in ((a, b) for b in table.flats for a in table.hierarchical):
            partial = table.partial(in_kind, a, b)  # not beside the paper's test until finished
            paper_test = PAPER_TTESTS[kind].get(f"{_paper_name(a)} vs {_paper_name(b)}") \
                if whole and not partial else None
            lines.append(_ttest_row(kind, f"{a} vs {b}{partial}", in_kind, a, b, table.score, paper_test))
        if kind == "classification":
            for category in CATEGORIES:
                members = table.of_kind(kind, category)
                if members:
                    best_smc = "curr" if "curr" in methods else "canon"
                    lines.append(_ttest_row(f"{kind} / {category}",
                                            f"{best_smc} vs cnn{table.partial(members, best_smc, 'cnn')}", members,
                                            best_smc, "cnn", table.score, None))
    counts = []
    for kind in KINDS:
        for flat in table.flats:
            for better, label in (*(((m,), m) for m in table.hierarchical), (("curr", "canon"), "curr or canon")):
                won, n = wins(table.score, table.of_kind(kind), better, flat)
                if n:
                    partial = table.partial(table.of_kind(kind), *better, flat)
                    whole = (kind == "bring-about" and label == "curr or canon" and n == PAPER_COUNTS[kind]
                             and not partial)
                    at_ceiling = ceiling_wins(table.score, table.of_kind(kind), better, flat)
                    counts.append(f"| {kind} | {label} | {flat}{partial} | {wins_text(won, n, at_ceiling)} |"
                                  + (" 14 of 16 |" if whole else " |"))
    if counts:
        lines += ["", "Concepts on which a hierarchical SMC beats a flat one (reported scores; a win at the ceiling: "
                  f"the winner at {100 * CEILING:.0f} % or more, by {100 * NEAR:.0f} points or less):", "",
                  "| kind | hierarchical | flat | beats it on | paper |", "|---|---|---|---:|---|", *counts]
    return lines


def _paper_name(method: str) -> str:
    """The paper's method that ``method`` is compared with (``method`` itself when it is none of ours)."""
    return METHOD_REGISTRY[method].paper_name if method in METHOD_REGISTRY else method


def _noprim_section(table: ResultTable) -> list[str]:
    if not any(m in table.methods for m in ("curr-noprim", "canon-noprim")):
        return []
    lines = ["", "## The role of hierarchy: without primitive moves", "",
             "| kind | method | with primitives | without | paper with | paper without |",
             "|---|---|---:|---:|---:|---:|"]
    for kind in KINDS:  # over the paper's concepts (the pushable curriculum has no noprim variant)
        in_kind = [t for t in table.of_kind(kind) if table.category_of[t] in PAPER_CATEGORIES]
        for method in ("curr", "canon"):
            if f"{method}-noprim" not in table.methods or not in_kind:
                continue
            paper = PAPER_NOPRIM[kind]
            with_, without = (_marked(_pct(method_mean(table.score, in_kind, m)), table.partial(in_kind, m))
                              for m in (method, f"{method}-noprim"))
            lines.append(f"| {kind} | {method} | {with_} | {without} | "
                         f"{paper[method]:.1f} | {paper[method + '-noprim']:.1f} |")
    return lines


def _ttest_row(label: str, comparison: str, members: Sequence[str], a: str, b: str,
               score: Score, paper: tuple[int, float, float] | None) -> str:
    """One row of the t-test table: ``a`` against ``b`` over those of ``members`` where both ran, and ``paper``'s
    test beside it only when both ran on all of them."""
    compared, test = method_test(score, members, a, b)
    if compared < len(members):  # the paper's test is over all its concepts: beside ours only when ours is too
        paper = None
    paper_text = f"t({paper[0]}) = {paper[1]}, p = {paper[2]}" if paper else ""
    if test is None:
        return f"| {label} | {comparison} | {compared} | - | - | - | {paper_text} | |"
    df, t, p = test
    at_paper = f"{p_at_df(t, paper[0]):.2g}" if paper else ""
    return f"| {label} | {comparison} | {compared} | {t:.2f} | {df} | {p:.2g} | {paper_text} | {at_paper} |"


def number_sections(table: ResultTable, experience: ExperienceSource | None = None) -> list[str]:
    """The report's Markdown sections of numbers, in the report's order (the equal-experience section where the
    runs' ``experience`` was kept)."""
    return [*_claims_section(table, experience), *_sweep_section(table), *experience_section(table, experience),
            *_concept_section(table),
            *_original_flat_section(table),
            *_means_section(table), *_ttest_section(table), *_seed_means_section(table), *_noprim_section(table)]
