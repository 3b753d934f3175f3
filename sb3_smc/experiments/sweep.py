"""The sweep of the one free parameter of each reading of an SMC call (:data:`~sb3_smc.experiments.design.
SWEEP_METHODS`, on :data:`~sb3_smc.experiments.design.SWEEP_TARGETS`): each setting's numbers on the swept targets.
Torch-free.

The sweep runs on 12 targets chosen before its run, and the paper's numbers are means over all 34 / 17 concepts of a
kind, so a setting's numbers there are the subset's and are not judged against the paper's: per kind, its mean and
its lead over the flat SMC on the swept targets, each with a 95 % bootstrap interval that resamples the swept
concepts as well as seeds and test worlds (a hierarchical bootstrap), the lead with the paired t-test across them;
on the bring-about targets, the share it beats the flat SMC on. The paper's two headline targets are concepts of its
own, so a setting's score there is judged against the paper's curr (:func:`~sb3_smc.experiments.claims.verdict`).
The setting of each reading that fits the paper best here, ``curr-cap10`` and ``curr-moves-200``, is run on every
concept and judged with the paper's other statements in the claims table (:data:`~sb3_smc.experiments.claims.
READINGS`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from sb3_smc.experiments.bootstrap import Interval, Replicates
from sb3_smc.experiments.claims import verdict
from sb3_smc.experiments.design import SWEEP_METHODS, SWEEP_TARGETS
from sb3_smc.experiments.paper import PAPER_CONCEPTS
from sb3_smc.experiments.statistics import method_test

__all__ = ["SweepNumber", "SweepRow", "sweep_rows"]

KINDS = ("classification", "bring-about")
Score = Callable[[str, str], np.ndarray]


@dataclass(frozen=True)
class SweepNumber:
    """One of a setting's numbers: what it is, ours (points) and, on a headline target, the paper's and the
    verdict."""

    what: str
    ours: Interval
    gap: bool = False
    """A difference (shown signed)."""
    test: tuple[int, float, float] | None = None
    """The paired t-test across the swept targets (a lead)."""
    paper: float | None = None
    verdict: str = ""


@dataclass(frozen=True)
class SweepRow:
    """A setting of the sweep and its numbers."""

    method: str
    numbers: tuple[SweepNumber, ...]


def sweep_rows(replicates: Replicates, kind_of: Mapping[str, str], methods: Sequence[str]) -> list[SweepRow]:
    """Every setting of the sweep that ran, in the sweep's order (each reading's settings by their parameter)."""
    return [row for m in SWEEP_METHODS if m in methods and (row := _row(replicates, kind_of, m)).numbers]


def _row(replicates: Replicates, kind_of: Mapping[str, str], method: str) -> SweepRow:
    numbers: list[SweepNumber] = []
    for kind in KINDS:
        swept = tuple(t for t in SWEEP_TARGETS if kind_of.get(t) == kind and (t, method) in replicates.estimate)
        if not swept:
            continue
        where = f"on the {len(swept)} swept"
        numbers.append(SweepNumber(f"{kind}: mean {where}", _points(replicates.mean(swept, method, concepts=True))))
        if not replicates.has(swept, "base"):
            continue
        _, test = method_test(replicates.estimate, swept, method, "base")
        numbers.append(SweepNumber(f"{kind}: lead over base {where}",
                                   _points(replicates.gap(swept, method, "base", concepts=True)), gap=True, test=test))
        if kind == "bring-about":
            def won(score: Score, swept: tuple[str, ...] = swept) -> np.ndarray:
                return np.asarray(100 * sum(score(t, method) > score(t, "base") for t in swept) / len(swept),
                                  dtype=float)

            numbers.append(SweepNumber(f"bring-about: beats base {where}, %", replicates.interval(won, [swept])))
    for target, paper in PAPER_CONCEPTS.items():
        if (target, method) in replicates.estimate:
            found = _points(replicates.mean([target], method))
            numbers.append(SweepNumber(target, found, paper=paper["curr"],
                                       verdict=verdict(paper["curr"], found, gap=False)))
    return SweepRow(method, tuple(numbers))


def _points(interval: Interval) -> Interval:
    """A share's interval in points."""
    return Interval(100 * interval.estimate, 100 * interval.low, 100 * interval.high)
