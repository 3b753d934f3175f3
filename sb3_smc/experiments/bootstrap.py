"""Bootstrap confidence intervals for the report's numbers, over seeds and test worlds. Torch-free.

A reported score is the best of a method's SMCs on a target (its seeds, and for curr its 1-3 curricula), each tested
on the target's test worlds. One bootstrap replicate draws, for every target, its test worlds with replacement (the
same draw for every SMC tested on them, as they were tested on the same worlds) and, for every node, its seeds with
replacement, and takes the best SMC of the draw. Any number computed from reported scores (a mean over concepts, a
difference of means, a count of concepts won) is then computed on every replicate, and its interval is the 2.5th to
97.5th percentile of those values, moved by their bias (their mean minus the estimate) and kept within their range.
A best-of statistic is biased under the bootstrap: a draw of worlds adds noise to every SMC's score, and the best of
noisier scores is higher; a draw of seeds may leave out the best seed, and is then lower. Moving the interval by the
net difference puts the estimate where the replicates' mean is. An SMC whose per-world scores are not recorded counts
with its test score in every draw of worlds.

A statement that generalises beyond the concepts run (an effect claimed across concepts, an extrapolation from some
of them) may also resample the concepts (a hierarchical bootstrap, :meth:`Replicates.interval`'s ``strata``): each
replicate draws the concepts with replacement, and each drawn concept brings a replicate of its own seeds and worlds.
That counts a concept's seed and world noise once more than its observed score already holds it: conservative, up to
sqrt(2) times too wide where the concepts are alike, little where they differ (as scores across concepts do).
"""

from __future__ import annotations

import copy
import zlib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["LEVEL", "REPLICATES", "Candidate", "Interval", "Replicates"]

REPLICATES = 2000
"""Bootstrap replicates of a report."""
LEVEL = 0.95
"""The confidence level of the intervals."""


def _stream(seed: int, *names: str) -> np.random.Generator:
    """A generator of its own for ``names`` (a target, or a target and a method) under ``seed``."""
    return np.random.default_rng([seed, *(zlib.crc32(name.encode("utf-8")) for name in names)])


@dataclass(frozen=True)
class Candidate:
    """One SMC a method may report on a target: its node (curriculum entry), its test score and, where recorded, its
    score on each test world (in the test split's order)."""

    node: str
    score: float
    worlds: tuple[float, ...] = ()


@dataclass(frozen=True)
class Interval:
    """A number (a fraction, or a count) with its bootstrap interval."""

    estimate: float
    low: float
    high: float

    def contains(self, value: float) -> bool:
        return self.low <= value <= self.high



class Replicates:
    """Bootstrap replicates of every (target, method)'s reported score.

    ``candidates``: (target, method) -> its SMCs. A target's draws of worlds come from a generator seeded with
    ``seed`` and the target's name, and a method's draws of seeds from one seeded with ``seed`` and both names, so
    the same records give the same intervals, whatever other targets and methods are reported beside them.
    """

    def __init__(self, candidates: Mapping[tuple[str, str], Sequence[Candidate]], *, replicates: int = REPLICATES,
                 seed: int = 0) -> None:
        if replicates < 2:
            raise ValueError(f"replicates must be at least 2, got {replicates}")
        self.replicates = replicates
        self.seed = seed
        self.estimate = {key: max(c.score for c in found) for key, found in candidates.items() if found}
        """The reported scores themselves (each pair's best SMC)."""
        self.draws: dict[tuple[str, str], np.ndarray] = {}
        """(target, method) -> its reported score in each replicate."""
        for target in sorted({t for t, _ in self.estimate}):
            methods = sorted(m for t, m in self.estimate if t == target)
            lengths = [len(c.worlds) for m in methods for c in candidates[(target, m)] if c.worlds]
            worlds = max(set(lengths), key=lengths.count) if lengths else 0
            picks = _stream(seed, target).integers(0, worlds, size=(replicates, worlds)) if worlds else None
            for method in methods:
                self.draws[(target, method)] = self._best(candidates[(target, method)], picks,
                                                          _stream(seed, target, method))

    def _best(self, found: Sequence[Candidate], picks: np.ndarray | None, rng: np.random.Generator) -> np.ndarray:
        """Each replicate's best SMC of ``found``: every node's seeds drawn with replacement, scored on the drawn
        worlds ``picks`` (their test score where their per-world scores are not of those worlds)."""
        best = np.full(self.replicates, -np.inf)
        nodes = sorted({c.node for c in found})
        for node in nodes:
            seeds = [c for c in found if c.node == node]
            scores = np.stack([np.asarray(c.worlds)[picks].mean(axis=1)
                               if picks is not None and len(c.worlds) == picks.shape[1]
                               else np.full(self.replicates, c.score) for c in seeds])  # seeds x replicates
            drawn = rng.integers(0, len(seeds), size=(self.replicates, len(seeds)))
            best = np.maximum(best, scores[drawn, np.arange(self.replicates)[:, None]].max(axis=1))
        return best

    def blended(self, blends: Mapping[str, Mapping[str, Sequence[tuple[str, float]]]]) -> Replicates:
        """A copy with a score of its own for each name of ``blends``: on each of its targets, the weighted sum of
        other methods' scores there (``{name: {target: [(method, weight), ...]}}``), in the estimate and in every
        replicate (the flat SMC's score at a curriculum's experience, read off its curve)."""
        out = copy.copy(self)
        out.estimate, out.draws = dict(self.estimate), dict(self.draws)
        for name, per_target in blends.items():
            for target, weights in per_target.items():
                out.estimate[(target, name)] = sum(w * self.estimate[(target, m)] for m, w in weights)
                out.draws[(target, name)] = sum((w * self.draws[(target, m)] for m, w in weights),
                                                 np.zeros(self.replicates))
        return out

    def has(self, targets: Sequence[str], *methods: str) -> bool:
        """Whether every one of ``methods`` has a score on every one of ``targets``."""
        return bool(targets) and all((t, m) in self.estimate for t in targets for m in methods)

    def interval(self, statistic: Callable[[Callable[[str, str], np.ndarray]], np.ndarray | float],
                 strata: Sequence[Sequence[str]] = ()) -> Interval:
        """The estimate and interval of ``statistic``, a function of the scores (called with ``score(target,
        method)``, an array over replicates or the reported score) that returns a number per replicate; ``strata``:
        groups of targets resampled too, each apart (:meth:`_resampled`)."""
        estimate = float(statistic(lambda t, m: np.asarray(self.estimate[(t, m)])))
        values = np.asarray(statistic(self._resampled(strata)), dtype=float)
        tail = 100 * (1 - LEVEL) / 2
        bias = float(values.mean()) - estimate
        low, high = np.percentile(values, [tail, 100 - tail]) - bias
        # never beyond what the records can give (a share of concepts above 100 %)
        low, high = max(low, min(values.min(), estimate)), min(high, max(values.max(), estimate))
        return Interval(estimate, float(low), float(high))

    def _resampled(self, strata: Sequence[Sequence[str]]) -> Callable[[str, str], np.ndarray]:
        """``score(target, method)`` over the replicates with the targets of each of ``strata`` drawn with
        replacement: in replicate r, a target's place holds a concept of its stratum drawn at random, in a replicate
        of that concept drawn at random (its seeds and worlds drawn anew for each draw of it), the same for every
        method (comparisons stay paired). Each stratum's draws come from a generator seeded with :attr:`seed` and
        its targets' names. A target in no stratum of two or more keeps its own replicates."""
        place: dict[str, tuple[tuple[str, ...], np.ndarray, np.ndarray]] = {}
        for stratum in strata:
            members = tuple(sorted(set(stratum)))
            if len(members) < 2:
                continue
            rng = _stream(self.seed, "concepts", *members)
            picks = rng.integers(0, len(members), size=(len(members), self.replicates))
            columns = rng.integers(0, self.replicates, size=(len(members), self.replicates))
            place.update((t, (members, picks[i], columns[i])) for i, t in enumerate(members))
        stacked: dict[tuple[tuple[str, ...], str], np.ndarray] = {}

        def score(target: str, method: str) -> np.ndarray:
            if target not in place:
                return self.draws[(target, method)]
            members, picks, columns = place[target]
            if (members, method) not in stacked:
                stacked[(members, method)] = np.stack([self.draws[(t, method)] for t in members])
            return stacked[(members, method)][picks, columns]

        return score

    def mean(self, targets: Sequence[str], method: str, *, concepts: bool = False) -> Interval:
        """``method``'s mean over ``targets`` (``concepts``: the targets resampled too)."""
        return self.interval(lambda score: sum(score(t, method) for t in targets) / len(targets),
                             [targets] if concepts else ())

    def gap(self, targets: Sequence[str], a: str, b: str, *, concepts: bool = False) -> Interval:
        """The mean of ``a`` minus the mean of ``b`` over ``targets`` (``concepts``: the targets resampled too)."""
        return self.interval(lambda score: sum(score(t, a) - score(t, b) for t in targets) / len(targets),
                             [targets] if concepts else ())
