"""The numbers of a report, torch-free: seed summaries, means with standard errors across concepts, paired t-tests
(also at the paper's degrees of freedom) and win counts, those at the ceiling apart (the claims table:
:mod:`sb3_smc.experiments.claims`).

Scores are fractions (0-1) as the results hold them; the paper's numbers (:mod:`sb3_smc.experiments.paper`) are
percentages.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["BOOTSTRAP", "CEILING", "NEAR", "SeedSummary", "ceiling_wins", "hierarchical_interval", "holm",
           "mean_of_all", "mean_se", "method_mean", "method_test", "p_at_df", "paired_ttest", "seed_summary", "wins",
           "wins_text"]

Score = Mapping[tuple[str, str], float]
"""(target, method) -> the reported score (best seed; curr: best curriculum)."""
BOOTSTRAP = 2000
"""Bootstrap resamples of an interval."""
CEILING, NEAR = 0.98, 0.02
"""A win at the ceiling: the winner scores at least ``CEILING`` and wins by at most ``NEAR`` (both near 100 %: the
win says little about which method is better)."""


def paired_ttest(ours: Sequence[float], theirs: Sequence[float]) -> tuple[int, float, float] | None:
    """``(df, t, p)`` of the paired t-test of ``ours`` against ``theirs`` (two-sided); ``None`` below 2 pairs or
    when every difference is equal (t undefined)."""
    from scipy import stats

    a, b = np.asarray(ours, dtype=float), np.asarray(theirs, dtype=float)
    if len(a) < 2 or np.allclose(a - b, (a - b)[0]):
        return None
    result = stats.ttest_rel(a, b)
    return len(a) - 1, float(result.statistic), float(result.pvalue)


def hierarchical_interval(differences: Mapping[str, Sequence[float]], *, resamples: int = BOOTSTRAP,
                          seed: int = 0) -> tuple[float, float, float]:
    """``(mean, low, high)``: the mean over concepts of each concept's mean over its seeds, and its 95 % percentile
    interval from resampling concepts with replacement and then, within each drawn concept, its seeds with
    replacement (so the interval covers both the choice of concepts and the seeds' noise)."""
    concepts = [np.asarray(v, dtype=float) for v in differences.values() if len(v)]
    if not concepts:
        raise ValueError("no concept to resample")
    rng = np.random.default_rng(seed)
    point = float(np.mean([c.mean() for c in concepts]))
    draws = np.empty(resamples)
    for b in range(resamples):
        picked = rng.integers(0, len(concepts), len(concepts))
        draws[b] = np.mean([concepts[i][rng.integers(0, len(concepts[i]), len(concepts[i]))].mean() for i in picked])
    low, high = np.percentile(draws, [2.5, 97.5])
    return point, float(low), float(high)


def holm(pvalues: Sequence[float]) -> list[float]:
    """Holm's step-down adjustment of ``pvalues`` (one family of tests): each below 0.05 exactly when Holm's
    procedure rejects its hypothesis at a family-wise error rate of 0.05."""
    order = sorted(range(len(pvalues)), key=lambda i: pvalues[i])
    adjusted = [0.0] * len(pvalues)
    running = 0.0
    for rank, i in enumerate(order):
        running = max(running, min(1.0, (len(pvalues) - rank) * pvalues[i]))
        adjusted[i] = running
    return adjusted


def ttest_text(test: tuple[int, float, float]) -> str:
    """A paired t-test's result as the report writes it: ``t(16) = 5.68, p = 3.4e-05``."""
    return f"t({test[0]}) = {test[1]:.2f}, p = {test[2]:.2g}"


def p_at_df(t: float, df: int) -> float:
    """The two-sided p of ``t`` read with ``df`` degrees of freedom (the paper's t(34) on 34 concepts, say)."""
    from scipy import stats

    return float(2 * stats.t.sf(abs(t), df))


@dataclass(frozen=True)
class SeedSummary:
    """The seeds of one target x method (of its reported curriculum): the best (what the paper reports), the mean
    and the sample standard deviation (``None`` for one seed)."""

    best: float
    mean: float
    sd: float | None
    seeds: int

    def text(self) -> str:
        """``best (mean ± s.d.)`` in percent; the best alone for one seed."""
        if self.sd is None:
            return f"{100 * self.best:.1f}"
        return f"{100 * self.best:.1f} ({100 * self.mean:.1f} ± {100 * self.sd:.1f})"


def seed_summary(scores: Sequence[float]) -> SeedSummary:
    """Best, mean and sample s.d. of the test scores of a target x method's seeds."""
    if not scores:
        raise ValueError("no seeds to summarise")
    values = np.asarray(scores, dtype=float)
    sd = float(values.std(ddof=1)) if len(values) > 1 else None
    return SeedSummary(best=float(values.max()), mean=float(values.mean()), sd=sd, seeds=len(values))


def mean_se(values: Sequence[float]) -> tuple[float, float | None]:
    """Mean and standard error of the mean (``None`` below two values: no error bar for a single value)."""
    if not values:
        raise ValueError("no values")
    array = np.asarray(values, dtype=float)
    se = float(array.std(ddof=1)) / math.sqrt(len(array)) if len(array) > 1 else None
    return float(array.mean()), se


def _won(score: Score, targets: Sequence[str], better: Sequence[str], than: str) -> list[tuple[float, float]]:
    """(the best of ``better``, ``than``) on each of ``targets`` where both were run."""
    return [(max(score[(t, m)] for m in better if (t, m) in score), score[(t, than)]) for t in targets
            if (t, than) in score and any((t, m) in score for m in better)]


def wins(score: Score, targets: Sequence[str], better: Sequence[str], than: str) -> tuple[int, int]:
    """On how many of ``targets`` the best of the ``better`` methods scores above ``than``; and over how many
    targets both were run."""
    compared = _won(score, targets, better, than)
    return sum(a > b for a, b in compared), len(compared)


def ceiling_wins(score: Score, targets: Sequence[str], better: Sequence[str], than: str) -> int:
    """How many of :func:`wins`'s wins are at the ceiling (:data:`CEILING`, :data:`NEAR`)."""
    return sum(b < a and a >= CEILING - 1e-9 and a - b <= NEAR + 1e-9 for a, b in _won(score, targets, better, than))


def wins_text(won: int, compared: int, ceiling: int) -> str:
    """``9 of 12 (3 of them at the ceiling)``: a win count with its wins at the ceiling counted apart."""
    return f"{won} of {compared}" + (f" ({ceiling} of them at the ceiling)" if ceiling else "")


def mean_of_all(values: Sequence[float | None]) -> float | None:
    """The mean of ``values``; ``None`` when there are none or any is missing (``None``)."""
    present = [v for v in values if v is not None]
    return float(np.mean(present)) if present and len(present) == len(values) else None


def method_mean(score: Score, targets: Sequence[str], method: str) -> float | None:
    """The mean score of ``method`` over ``targets`` (``None`` unless it ran on all of them)."""
    return mean_of_all([score.get((t, method)) for t in targets])


def method_test(score: Score, targets: Sequence[str], a: str, b: str) -> tuple[int, tuple[int, float, float] | None]:
    """The paired t-test of method ``a`` against ``b`` over the ``targets`` where both ran: (how many such
    targets, :func:`paired_ttest`'s result)."""
    pairs = [(score[(t, a)], score[(t, b)]) for t in targets if (t, a) in score and (t, b) in score]
    return len(pairs), paired_ttest([x for x, _ in pairs], [y for _, y in pairs]) if pairs else None
