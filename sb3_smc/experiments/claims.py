"""The paper's statements judged as a reviewer would: one row per statement, a verdict under each reading of an SMC
call, bootstrap intervals (:mod:`sb3_smc.experiments.bootstrap`) instead of a fixed tolerance. Torch-free.

The paper does not say how a hierarchical SMC's episode counted a call, so every statement about a hierarchical
method is judged under each :data:`READINGS` entry: a call is one step (``curr``, ``canon``), a call costs its moves
(``curr-moves``), the one-step reading against a flat SMC with as many moves (``base-400``), the setting of each
reading that fits the paper best on every concept (``curr-cap10``: a call cut after 10 moves; ``curr-moves-200``:
200 moves an episode), and, where the statement compares curr with the flat SMC, the flat SMC at as much experience
(:mod:`sb3_smc.experiments.experience`: curr's setting of each reading on the sweep's 12 concepts, and
``curr-cap10`` on all 51). Against a number of the paper our
interval resamples seeds and test worlds (the paper's number is over the same concepts as ours); where a statement
is judged by its sign, a claimed effect across concepts, it resamples the concepts too (a hierarchical bootstrap),
and a statement of significance needs our paired t-test across concepts as well. A verdict compares the paper's
number with our interval:

* ``reproduced``: the paper's number lies inside our interval;
* ``exceeded``: our interval lies beyond it, in the direction the statement claims (a higher mean, a larger gap);
* ``not significant``: a statement of significance (the paper's paired t-tests) whose interval gives a sign
  (reproduced, exceeded or opposite) where our paired t-test across the concepts does not give p < 0.05
  (:data:`SIGNIFICANCE`) with that sign;
* ``short``: our interval lies on the near side of it, not beyond zero;
* ``opposite``: our interval lies entirely on the other side of zero (a comparison reversed).

A statement without a number of the paper (the CNN by category, Fig. 5a) is reproduced where our interval has the
claimed sign, opposite where it has the other, and short where it holds zero; so is a comparison at equal
experience (the paper's number is not at equal experience: only its sign is claimed there), and one judged on a
subset of the concepts the paper's number is over says on how many of which targets in its cell (a statement of the
subset, not of the kind). A later reading that runs all of a statement's methods as the
first does says "same as one step" (:data:`SAME`) and is not counted in its column. Wins at the ceiling are counted
apart (:data:`~sb3_smc.experiments.statistics.CEILING`). Our own methods that no reading uses (``base-gru``,
``canon-scaled``, the flat SMC's points of experience) are judged in a table of their own (:func:`method_checks`);
the sweep's other settings have their section (:mod:`sb3_smc.experiments.sweep`).
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from sb3_smc.experiments.bootstrap import Interval, Replicates
from sb3_smc.experiments.design import METHOD_REGISTRY, SWEEP_METHODS, SWEEP_TARGETS
from sb3_smc.experiments.experience import flat_at
from sb3_smc.experiments.paper import PAPER_CONCEPTS, PAPER_COUNTS, PAPER_MEANS, PAPER_NOPRIM, PAPER_TTESTS
from sb3_smc.experiments.statistics import ceiling_wins, method_test, ttest_text, wins

__all__ = ["NOT_COMPARABLE", "NOT_JUDGED", "NOT_RUN", "NOT_SIGNIFICANT", "READINGS", "SAME", "SIGNIFICANCE",
           "VERDICTS", "Judged", "Reading", "Statement", "judge", "method_checks", "points", "significance",
           "statements", "tally", "verdict"]

NOT_SIGNIFICANT = "not significant"
VERDICTS = ("reproduced", "exceeded", NOT_SIGNIFICANT, "short", "opposite")
NOT_RUN, NOT_JUDGED, NOT_COMPARABLE = "not run", "not judged: partial", "not comparable: a subset"
SAME = "same as one step"
"""A later reading's cell where it runs the statement's methods as the first reading does (not counted there)."""
SIGNIFICANCE = 0.05
"""The p below which our paired t-test supports a statement of significance."""
WON = 14 / 16
"""The paper's share of bring-about concepts on which a hierarchical SMC beats the flat one."""


@dataclass(frozen=True)
class Reading:
    """One reading of an SMC call: which of our methods stands for each of the paper's."""

    name: str
    methods: Mapping[str, str]
    targets: tuple[str, ...] | None = None
    """Judged on these concepts only (chosen before the run); ``None``: on all of each statement's."""
    subset: str = ""
    """What the concepts it is judged on are called in a cell (``swept targets``)."""
    by_sign: bool = False
    """Only the comparisons of two of its methods are judged, by the sign the paper claims (equal experience)."""

    def __post_init__(self) -> None:
        if self.targets is not None and not self.by_sign:
            raise ValueError(f"reading {self.name!r}: on a subset of the concepts it must be judged by sign (the "
                             "paper's numbers are over all of them)")


_PAPERS = ("cnn", "base", "curr", "canon", "curr-noprim", "canon-noprim")
READINGS = (
    Reading("a call is one step", {m: m for m in _PAPERS}),
    Reading("a call costs its moves", {"cnn": "cnn", "base": "base", "curr": "curr-moves"}),
    Reading("one step, the flat SMC with 400 moves", {**{m: m for m in _PAPERS}, "base": "base-400"}),
    Reading("one step, a call cut after 10 moves", {"cnn": "cnn", "base": "base", "curr": "curr-cap10"}),
    Reading("costs its moves, 200 moves an episode", {"cnn": "cnn", "base": "base", "curr": "curr-moves-200"}),
    Reading("one step, at equal experience", {"curr": "curr-cap100", "base": flat_at("curr-cap100")},
            targets=SWEEP_TARGETS, subset="swept targets", by_sign=True),
    Reading("costs its moves, at equal experience", {"curr": "curr-moves-100", "base": flat_at("curr-moves-100")},
            targets=SWEEP_TARGETS, subset="swept targets", by_sign=True),
    Reading("cut after 10 moves, at equal experience", {"curr": "curr-cap10", "base": flat_at("curr-cap10")},
            by_sign=True),
)
"""The readings of a call the claims are judged under, in the table's column order: the paper's methods as run;
curr whose calls cost their moves; the flat SMC with as many moves as curr makes; the setting of each reading's free
parameter that fits the paper best (the sweep, :mod:`sb3_smc.experiments.sweep`), run on every concept; and the flat
SMC at as much experience as curr's setting of each reading (on the sweep's concepts) and the best one-step setting
(on every concept)."""

Score = Callable[[str, str], np.ndarray]


@dataclass(frozen=True)
class Statement:
    """One statement of the paper: its text, the paper's number (points; ``None``: qualitative), the concepts and
    paper methods it is about, and how to compute ours from (replicated) scores."""

    text: str
    paper: float | None
    paper_text: str
    targets: tuple[str, ...]
    methods: tuple[str, ...]
    statistic: Callable[[Score, Mapping[str, str]], np.ndarray | float]
    gap: bool = False
    """A comparison (a difference of means): it can be reversed."""
    test: tuple[str, str] | None = None
    """The two paper methods of the paper's paired t-test: ours is shown beside our interval, and the statement is
    one of significance (:func:`significance`)."""
    groups: tuple[tuple[str, ...], ...] | None = None
    """The concepts resampled, each group apart (Fig. 5a's categories); ``None``: all of :attr:`targets` together."""
    note: Callable[[Mapping[tuple[str, str], float], Mapping[str, str]], str] | None = None
    """A remark on our number from the reported scores and the reading's methods (the wins at the ceiling)."""

    @property
    def strata(self) -> tuple[tuple[str, ...], ...]:
        """The groups of concepts the bootstrap resamples (:meth:`~sb3_smc.experiments.bootstrap.Replicates.
        interval`)."""
        return self.groups if self.groups is not None else (self.targets,)


@dataclass(frozen=True)
class Judged:
    """A statement's cell under one reading: our number, its interval and the verdict."""

    ours: str
    verdict: str


def statements(kind_of: Mapping[str, str], category_of: Mapping[str, str]) -> list[Statement | str]:
    """The paper's statements over the concepts of ``kind_of``; a kind with fewer concepts than the paper's gives one
    string (its statements are not comparable)."""
    out: list[Statement | str] = []
    for kind in ("classification", "bring-about"):
        targets = tuple(sorted(t for t in kind_of if kind_of[t] == kind and category_of[t] != "pushable"))
        if not targets:
            continue
        if len(targets) != PAPER_COUNTS[kind]:
            out.append(f"{kind}: the statements over all {PAPER_COUNTS[kind]} concepts ({len(targets)} here)")
            continue
        means = PAPER_MEANS[kind]
        out += [_mean(f"{kind}: mean of {m}", means[m], targets, m) for m in means]
        for comparison, (df, t, p) in PAPER_TTESTS[kind].items():
            a, _, b = comparison.split()
            out.append(_gap(f"{kind}: {a} above {b} (paired t-test)", means[a] - means[b],
                            f"{means[a] - means[b]:+.1f}; t({df}) = {t}, p = {p}", targets, a, b, test=(a, b)))
        if kind == "classification":
            out += [_gap(f"classification: {a} above {b}", means[a] - means[b], f"{means[a] - means[b]:+.1f}",
                         targets, a, b) for a, b in (("cnn", "base"), ("curr", "cnn"))]
            out += _cnn_statements(targets, category_of)
        else:
            out.append(Statement("bring-about: a hierarchical SMC (best of curr, canon) beats the flat one, % of "
                                 "concepts", 100 * WON, "on 14 of 16 concepts", targets, ("curr", "canon", "base"),
                                 functools.partial(_won, targets=targets),
                                 note=functools.partial(_ceiling_note, targets=targets)))
        noprim = PAPER_NOPRIM[kind]
        for method in ("curr", "canon"):
            without = f"{method}-noprim"
            out.append(_mean(f"{kind}: mean of {without}", noprim[without], targets, without))
            out.append(_gap(f"{kind}: {without} against {method}", noprim[without] - noprim[method],
                            f"{noprim[without] - noprim[method]:+.1f}", targets, without, method))
    for target, numbers in PAPER_CONCEPTS.items():
        if target in kind_of:
            out += [_mean(f"{target}: {m}", value, (target,), m) for m, value in numbers.items()]
    return out


def _won(score: Score, ours: Mapping[str, str], *, targets: tuple[str, ...]) -> np.ndarray:
    """The share (%) of ``targets`` on which the better of curr and canon scores above the flat SMC."""
    best = [np.maximum(score(t, ours["curr"]), score(t, ours["canon"])) > score(t, ours["base"]) for t in targets]
    return np.asarray(100 * sum(best) / len(targets), dtype=float)


def _ceiling_note(estimate: Mapping[tuple[str, str], float], ours: Mapping[str, str], *,
                  targets: tuple[str, ...]) -> str:
    """How many of the wins of the better of curr and canon are at the ceiling (none: nothing to say)."""
    better = [ours["curr"], ours["canon"]]
    at_ceiling = ceiling_wins(estimate, targets, better, ours["base"])
    won, _ = wins(estimate, targets, better, ours["base"])
    return f" ({won} wins, {at_ceiling} of them at the ceiling)" if at_ceiling else ""


def _mean(text: str, paper: float, targets: tuple[str, ...], method: str) -> Statement:
    return Statement(text, paper, f"{paper:.1f}", targets, (method,),
                     lambda score, ours: 100 * sum(score(t, ours[method]) for t in targets) / len(targets))


def _gap(text: str, paper: float, paper_text: str, targets: tuple[str, ...], a: str, b: str,
         test: tuple[str, str] | None = None) -> Statement:
    return Statement(text, paper, paper_text, targets, (a, b),
                     lambda score, ours: 100 * sum(score(t, ours[a]) - score(t, ours[b]) for t in targets)
                     / len(targets), gap=True, test=test)


def _cnn_statements(targets: tuple[str, ...], category_of: Mapping[str, str]) -> list[Statement]:
    """Fig. 5a: the best SMC method (of base, curr and canon, per concept) clearly above the CNN on containment;
    the CNN relatively better on objects and objcon (the SMCs' lead smaller there)."""
    members = {c: tuple(t for t in targets if category_of[t] == c) for c in ("containment", "objcon", "objects")}
    if not all(members.values()):
        return []
    smcs = ("base", "curr", "canon")

    def lead(score: Score, ours: Mapping[str, str], category: str) -> np.ndarray:
        found = members[category]
        return 100 * sum(np.maximum.reduce([score(t, ours[m]) for m in smcs]) - score(t, ours["cnn"])
                         for t in found) / len(found)

    out = [Statement("classification / containment: the best SMC method above the cnn", None, "qualitative (Fig. 5a)",
                     members["containment"], ("cnn", *smcs), lambda s, o: lead(s, o, "containment"), gap=True)]
    out += [Statement(f"classification / {c}: the cnn relatively better than on containment", None,
                      "qualitative (Fig. 5a)", members[c] + members["containment"], ("cnn", *smcs),
                      functools.partial(_lead_difference, lead=lead, category=c), gap=True,
                      groups=(members[c], members["containment"]))
            for c in ("objects", "objcon")]
    return out


def _lead_difference(score: Score, ours: Mapping[str, str], *,
                     lead: Callable[[Score, Mapping[str, str], str], np.ndarray], category: str) -> np.ndarray:
    """How much larger the SMCs' lead over the CNN is on containment than on ``category``."""
    return lead(score, ours, "containment") - lead(score, ours, category)


def verdict(paper: float | None, interval: Interval, gap: bool) -> str:
    """The verdict of our ``interval`` (points) against the paper's number (module docstring)."""
    if paper is None:
        return "reproduced" if interval.low > 0 else "opposite" if interval.high < 0 else "short"
    if interval.contains(paper):
        return "reproduced"
    sign = 1.0 if paper >= 0 else -1.0
    low, high = sorted((sign * interval.low, sign * interval.high))
    if gap and high < 0:
        return "opposite"
    return "exceeded" if low > abs(paper) else "short"


def significance(found: str, test: tuple[int, float, float] | None, paper: float) -> str:
    """The verdict of a statement of significance: ``found`` (the interval's verdict), except that one that gives a
    sign (reproduced, exceeded: the paper's; opposite: the other) needs our paired ``test`` at p <
    :data:`SIGNIFICANCE` with that sign (``paper``: the paper's gap); without it, :data:`NOT_SIGNIFICANT`."""
    claimed = {"reproduced": 1.0, "exceeded": 1.0, "opposite": -1.0}.get(found)
    if claimed is None:
        return found
    supported = test is not None and test[2] < SIGNIFICANCE and claimed * test[1] * paper > 0
    return found if supported else NOT_SIGNIFICANT


def judge(statement: Statement, reading: Reading, replicates: Replicates,
          unfinished: Collection[tuple[str, str]] = ()) -> Judged:
    """``statement`` under ``reading``: our number with its interval and the verdict, or why there is none."""
    if reading.by_sign:
        return _judge_by_sign(statement, reading, replicates, unfinished)
    first = READINGS[0].methods
    if reading is not READINGS[0] and all(m in first and reading.methods.get(m) == first[m]
                                          for m in statement.methods):
        return Judged(SAME, "")
    if not all(m in reading.methods for m in statement.methods):
        return Judged("-", NOT_RUN)
    ours = [reading.methods[m] for m in statement.methods]
    if any((t, m) in unfinished for t in statement.targets for m in ours):
        return Judged("-", NOT_JUDGED)
    if not replicates.has(statement.targets, *ours):
        return Judged("-", NOT_RUN)
    # the paper's number is over the same concepts as ours: against it, only seeds and worlds vary; a claimed sign
    # (an effect across concepts) is judged with the concepts resampled too
    strata = statement.strata if statement.paper is None else ()
    interval = replicates.interval(lambda score: statement.statistic(score, reading.methods), strata)
    text = points(interval, statement.gap)
    if statement.note is not None:
        text += statement.note(replicates.estimate, reading.methods)
    found = verdict(statement.paper, interval, statement.gap)
    if statement.test is not None and statement.paper is not None:
        a, b = (reading.methods[m] for m in statement.test)
        _, test = method_test(replicates.estimate, statement.targets, a, b)
        text += f"; {ttest_text(test)}" if test is not None else ""
        found = significance(found, test, statement.paper)
    return Judged(text, found)


def _judge_by_sign(statement: Statement, reading: Reading, replicates: Replicates,
                   unfinished: Collection[tuple[str, str]]) -> Judged:
    """A comparison of two of ``reading``'s methods on the concepts it is about (those of the reading's
    :attr:`~Reading.targets` where it has them), judged by the sign of the paper's claim, the concepts resampled, and,
    for a statement of significance, by our paired t-test too; a subset's cell says on how many of its targets. Any
    other statement is not judged (a blank cell)."""
    if not (statement.gap and statement.paper is not None and len(statement.methods) == 2
            and all(m in reading.methods for m in statement.methods)):
        return Judged("", "")
    a, b = (reading.methods[m] for m in statement.methods)
    targets = [t for t in statement.targets if t in reading.targets] if reading.targets is not None else \
        list(statement.targets)
    if not all(any((t, m) in replicates.estimate or (t, m) in unfinished for t in targets) for m in (a, b)):
        return Judged("-", NOT_RUN)  # one of the two neither ran nor is running here (the curve's run not begun)
    if any((t, m) in unfinished for t in targets for m in (a, b)):
        return Judged("-", NOT_JUDGED)
    if not replicates.has(targets, a, b):
        return Judged("-", NOT_RUN)
    gap = replicates.gap(targets, a, b, concepts=True)
    gap = Interval(100 * gap.estimate, 100 * gap.low, 100 * gap.high)
    sign = 1.0 if statement.paper >= 0 else -1.0
    claimed = Interval(sign * gap.estimate, min(sign * gap.low, sign * gap.high), max(sign * gap.low, sign * gap.high))
    _, test = method_test(replicates.estimate, targets, a, b)
    text = points(gap, True) + (f" on {len(targets)} {reading.subset}" if reading.subset else "") \
        + (f"; {ttest_text(test)}" if test is not None else "")
    found = verdict(None, claimed, gap=True)
    return Judged(text, significance(found, test, statement.paper) if statement.test is not None else found)


def points(interval: Interval, signed: bool) -> str:
    """``84.9 [80.1, 88.2]`` (points; ``signed``: ``+3.1 [-1.0, +7.2]``)."""
    form = "+.1f" if signed else ".1f"
    return f"{interval.estimate:{form}} [{interval.low:{form}}, {interval.high:{form}}]"


def tally(cells: Sequence[str]) -> str:
    """How many of the verdicts ``cells`` are each of :data:`VERDICTS`, not judged and not run (those present)."""
    labels = (*VERDICTS, NOT_JUDGED, NOT_RUN)
    counts = {label: sum(c == label for c in cells) for label in labels}
    unknown = sorted({c for c in cells if c and c not in labels})
    if unknown:
        raise ValueError(f"verdict(s) of no known class: {unknown} (one of {labels})")
    return ", ".join(f"{n} {label}" for label, n in counts.items() if n)


def method_checks(replicates: Replicates, kind_of: Mapping[str, str], category_of: Mapping[str, str],
                  methods: Sequence[str], unfinished: Collection[tuple[str, str]] = ()) -> list[tuple[str, str, str,
                                                                                                    str]]:
    """Our own methods that no reading of every concept uses and the sweep's section does not show, against the
    paper's numbers for the method they stand for: per kind, their mean and their gap to the flat SMC (``base``).
    Rows of (statement, paper, ours, verdict)."""
    used = {m for reading in READINGS if reading.targets is None for m in reading.methods.values()}
    rows = []
    for method in (m for m in methods if m not in used and m not in SWEEP_METHODS and METHOD_REGISTRY[m].smc):
        paper_name = METHOD_REGISTRY[method].paper_name
        for kind in ("classification", "bring-about"):
            targets = tuple(sorted(t for t in kind_of if kind_of[t] == kind and category_of[t] != "pushable"))
            ran = tuple(t for t in targets if (t, method) in replicates.estimate)
            if not ran or paper_name not in PAPER_MEANS[kind]:
                continue
            whole = len(ran) == len(targets) == PAPER_COUNTS[kind]
            label = f" ({len(ran)} concepts)" if not whole else ""
            checks = [_mean(f"{kind}: mean of {method}{label}", PAPER_MEANS[kind][paper_name], ran, method)]
            if paper_name != "base":
                gap = PAPER_MEANS[kind][paper_name] - PAPER_MEANS[kind]["base"]
                checks.append(_gap(f"{kind}: {method} above base{label}", gap, f"{gap:+.1f}", ran, method, "base"))
            reading = Reading(method, {method: method, "base": "base"})
            for check in checks:
                cell = judge(check, reading, replicates, unfinished)
                # the paper's number is over all the kind's concepts: ours on fewer is shown, not judged
                rows.append((check.text, check.paper_text, cell.ours,
                             cell.verdict if whole or cell.verdict not in VERDICTS else NOT_COMPARABLE))
    return rows
