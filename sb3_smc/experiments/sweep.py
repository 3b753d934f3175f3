"""Which reading of an SMC call fits the paper: each setting of the sweep (:data:`~sb3_smc.experiments.design.
SWEEP_METHODS`, on :data:`~sb3_smc.experiments.design.SWEEP_TARGETS`) scored against every number of the paper it
touches. Torch-free.

The sweep runs on 12 targets, and the paper gives means over all 34 / 17 concepts of a kind, so a setting's mean over
a kind is estimated concept by concept: on the sweep's targets its own score; on the others the whole table's score
of its reading's method (``curr`` for a cap, ``curr-moves`` for an episode's moves) plus the setting's mean
difference, on the sweep's targets of that kind, from the sweep's own setting of 100 (``curr-cap100``,
``curr-moves-100``: the same lower-level SMCs as every setting), kept within 0-100 % (a shift of +60 points on a
concept already at 80 % gives 100 %, not 140 %): an extrapolation from the swept targets, labelled so, whose interval
resamples the swept targets as well as seeds and worlds (they stand for the others). From it: the kind's mean
against the paper's curr, and its lead over the flat SMC against the paper's. Beside them: the two headline targets,
and the share of the sweep's bring-about targets on which the setting beats the flat SMC against the paper's 14 of 16.
Every number has its bootstrap interval (:mod:`sb3_smc.experiments.bootstrap`) and a verdict
(:func:`~sb3_smc.experiments.claims.verdict`); a setting fits better the more of the paper's numbers lie inside its
intervals, then the closer its numbers are to them (mean absolute difference, points). The noprim statements are not
touched: the sweep does not run the noprim variants.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from sb3_smc.experiments.bootstrap import Interval, Replicates
from sb3_smc.experiments.claims import WON, verdict
from sb3_smc.experiments.design import METHOD_REGISTRY, SWEEP_METHODS
from sb3_smc.experiments.paper import PAPER_CONCEPTS, PAPER_MEANS

__all__ = ["Fit", "Scored", "sweep_fits", "sweep_reference"]

Score = Callable[[str, str], np.ndarray]


@dataclass(frozen=True)
class Scored:
    """One number of the paper against a setting's: what it is, the paper's, ours and the verdict."""

    what: str
    paper: float
    ours: Interval
    verdict: str
    gap: bool = False
    """A difference (shown signed)."""


@dataclass(frozen=True)
class Fit:
    """A setting of the sweep and how it fits the paper's numbers."""

    method: str
    numbers: tuple[Scored, ...]

    @property
    def reproduced(self) -> int:
        return sum(n.verdict == "reproduced" for n in self.numbers)

    @property
    def distance(self) -> float:
        """The mean absolute difference from the paper's numbers, in points."""
        return float(np.mean([abs(n.ours.estimate - n.paper) for n in self.numbers]))


def sweep_reference(method: str) -> tuple[str, str]:
    """The whole table's method of ``method``'s reading and the sweep's setting of 100 of that reading."""
    if METHOD_REGISTRY[method].count_primitive_steps:
        return "curr-moves", "curr-moves-100"
    return "curr", "curr-cap100"


def sweep_fits(replicates: Replicates, kind_of: Mapping[str, str], methods: Sequence[str]) -> list[Fit]:
    """Every setting of the sweep that ran, scored (best fit first); a setting without the sweep's setting of 100 or
    the whole table's methods its estimates need has only the numbers it can give."""
    fits = [_fit(replicates, kind_of, m) for m in SWEEP_METHODS if m in methods]
    return sorted((f for f in fits if f.numbers), key=lambda f: (-f.reproduced, f.distance))


def _fit(replicates: Replicates, kind_of: Mapping[str, str], method: str) -> Fit:
    whole, hundred = sweep_reference(method)
    numbers: list[Scored] = []
    for kind in ("classification", "bring-about"):
        everything = tuple(t for t in kind_of if kind_of[t] == kind)
        swept = tuple(t for t in everything if (t, method) in replicates.estimate)
        if swept and replicates.has(everything, whole, "base") and replicates.has(swept, hundred):
            numbers += _kind_numbers(replicates, kind, everything, swept, method, whole, hundred)
    for target, paper_numbers in PAPER_CONCEPTS.items():
        if (target, method) in replicates.estimate:
            def value(score: Score, target: str = target) -> np.ndarray:
                return 100 * score(target, method)

            found = replicates.interval(value)
            numbers.append(Scored(target, paper_numbers["curr"], found,
                                  verdict(paper_numbers["curr"], found, gap=False)))
    return Fit(method, tuple(numbers))


def _kind_numbers(replicates: Replicates, kind: str, everything: tuple[str, ...], swept: tuple[str, ...],
                  method: str, whole: str, hundred: str) -> list[Scored]:
    """A kind's estimated mean and lead over the flat SMC (and, bring-about, the share of concepts won)."""
    def mean(score: Score) -> np.ndarray:
        shift = sum(score(t, method) - score(t, hundred) for t in swept) / len(swept)
        return np.asarray(100 * sum(score(t, method) if t in swept else np.clip(score(t, whole) + shift, 0.0, 1.0)
                                    for t in everything) / len(everything))

    def lead(score: Score) -> np.ndarray:
        return mean(score) - 100 * sum(score(t, "base") for t in everything) / len(everything)

    def won(score: Score) -> np.ndarray:
        return np.asarray(100 * sum(score(t, method) > score(t, "base") for t in swept) / len(swept), dtype=float)

    paper = PAPER_MEANS[kind]
    gap = paper["curr"] - paper["base"]
    # the swept targets stand for the kind's other concepts: resampled (a hierarchical bootstrap)
    estimated, ahead = replicates.interval(mean, [swept]), replicates.interval(lead, [swept])
    out = [Scored(f"{kind}: mean (extrapolated to all {len(everything)} from {len(swept)} swept)", paper["curr"],
                  estimated, verdict(paper["curr"], estimated, gap=False)),
           Scored(f"{kind}: lead over base", gap, ahead, verdict(gap, ahead, gap=True), gap=True)]
    if kind == "bring-about":
        share = replicates.interval(won, [swept])
        out.append(Scored(f"bring-about: beats base on the {len(swept)} swept targets, %", 100 * WON, share,
                          verdict(100 * WON, share, gap=False)))
    return out
