"""The numbers of a report, torch-free: seed summaries, means with standard errors across concepts, paired t-tests
(also at the paper's degrees of freedom), win counts, and the claims table that sets every quantitative claim of the
paper beside ours.

Scores are fractions (0-1) as the results hold them; the paper's numbers (:mod:`sb3_smc.experiments.paper`) are
percentages.
"""

from __future__ import annotations

import math
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from sb3_smc.experiments.paper import PAPER_CONCEPTS, PAPER_COUNTS, PAPER_MEANS, PAPER_NOPRIM, PAPER_TTESTS

__all__ = ["ALPHA", "Claim", "SeedSummary", "claims", "mean_of_all", "mean_se", "method_mean", "method_test",
           "paired_ttest", "p_at_df", "seed_summary", "wins"]

ALPHA = 0.05
"""Significance level of the claims table."""
Score = Mapping[tuple[str, str], float]
"""(target, method) -> the reported score (best seed; curr: best curriculum)."""
Pairs = Collection[tuple[str, str]]
"""(target, method) pairs: those of a run still being trained (some of their SMCs not trained yet)."""


def paired_ttest(ours: Sequence[float], theirs: Sequence[float]) -> tuple[int, float, float] | None:
    """``(df, t, p)`` of the paired t-test of ``ours`` against ``theirs`` (two-sided); ``None`` below 2 pairs or
    when every difference is equal (t undefined)."""
    from scipy import stats

    a, b = np.asarray(ours, dtype=float), np.asarray(theirs, dtype=float)
    if len(a) < 2 or np.allclose(a - b, (a - b)[0]):
        return None
    result = stats.ttest_rel(a, b)
    return len(a) - 1, float(result.statistic), float(result.pvalue)


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


def wins(score: Score, targets: Sequence[str], better: Sequence[str], than: str) -> tuple[int, int]:
    """On how many of ``targets`` the best of the ``better`` methods scores above ``than``; and over how many
    targets both were run."""
    compared = [t for t in targets if (t, than) in score and any((t, m) in score for m in better)]
    won = sum(max(score[(t, m)] for m in better if (t, m) in score) > score[(t, than)] for t in compared)
    return won, len(compared)


@dataclass(frozen=True)
class Claim:
    """One quantitative claim of the paper: what it says, its number, ours, and whether ours reproduces it."""

    claim: str
    paper: str
    ours: str
    reproduced: str

    @property
    def outcome(self) -> str:
        """The verdict's class, one of :data:`OUTCOMES`' values, from how the verdict begins."""
        found = next((label for start, label in OUTCOMES if self.reproduced.startswith(start)), None)
        if found is None:
            raise ValueError(f"the claim {self.claim!r} has a verdict of no known class: {self.reproduced!r} (should "
                             f"begin with one of {', '.join(repr(start) for start, _ in OUTCOMES)})")
        return found


OUTCOMES = (("yes", "reproduced"), ("direction only", "in direction only (not significant)"), ("no:", "not"),
            ("not judged", "not judged yet (partial)"), ("not comparable", "not comparable (a subset)"),
            ("not run", "not run"))
"""How a claim's verdict begins -> its class, in the order :func:`tally` counts them."""


def tally(found: Sequence[Claim]) -> str:
    """How many of the claims ``found`` are reproduced, in direction only, not, ... (the classes present only)."""
    counts = {label: sum(c.outcome == label for c in found) for _, label in OUTCOMES}
    return ", ".join(f"{n} {label}" for label, n in counts.items() if n)


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


def _gap(score: Score, targets: Sequence[str], a: str, b: str) -> float | None:
    """Mean of ``a`` minus mean of ``b`` over ``targets`` (``None`` unless both ran on all of them)."""
    mean_a, mean_b = method_mean(score, targets, a), method_mean(score, targets, b)
    return None if mean_a is None or mean_b is None else mean_a - mean_b


def _partial(text: str, paper: str, score: Score, targets: Sequence[str], methods: Sequence[str],
             unfinished: Pairs) -> Claim | None:
    """The claim ``text`` over ``targets`` marked unjudged while ``methods`` have each begun on them but have not all
    finished on all of them (a table still being run: a concept not run yet, or one whose seeds or curricula are not
    all trained); ``None`` when they finished on all, or one of them has not begun (the caller judges it, or says
    "not run")."""
    if not all(any((t, m) in score for t in targets) for m in methods):
        return None
    done = sum(all((t, m) in score and (t, m) not in unfinished for m in methods) for t in targets)
    if done < len(targets):
        return Claim(text, paper, f"{done} of {len(targets)} concepts finished", "not judged: partial")
    return None


def _mean_claim(kind: str, method: str, paper: float, score: Score, targets: Sequence[str],
                tolerance: float, unfinished: Pairs) -> Claim:
    text = f"{kind}: mean of {method} ({len(targets)} concepts)"
    return (_partial(text, f"{paper:.1f}", score, targets, (method,), unfinished)
            or _value_claim(text, paper, method_mean(score, targets, method), tolerance))


def _value_claim(text: str, paper: float, ours: float | None, tolerance: float) -> Claim:
    """A number of the paper (percent) against ours (a fraction): reproduced within ``tolerance`` points."""
    if ours is None:
        return Claim(text, f"{paper:.1f}", "-", "not run")
    diff = 100 * ours - paper
    if abs(diff) <= tolerance:
        return Claim(text, f"{paper:.1f}", f"{100 * ours:.1f} ({diff:+.1f})", f"yes (within {tolerance:g} points)")
    return Claim(text, f"{paper:.1f}", f"{100 * ours:.1f} ({diff:+.1f})",
                 f"no: {abs(diff):.1f} points {'above' if diff > 0 else 'below'}")


def _test_claim(kind: str, a: str, b: str, score: Score, targets: Sequence[str],
                paper: tuple[int, float, float], unfinished: Pairs) -> Claim:
    df_paper, t_paper, p_paper = paper
    _, test = method_test(score, targets, a, b)
    text = f"{kind}: {a} > {b}, paired t-test across concepts"
    partial = _partial(text, f"t({df_paper}) = {t_paper}, p = {p_paper}", score, targets, (a, b), unfinished)
    if partial is not None:
        return partial
    if test is None:
        return Claim(text, f"t({df_paper}) = {t_paper}, p = {p_paper}", "-", "not run")
    df, t, p = test
    same_direction = (t > 0) == (t_paper > 0)
    significant = p < ALPHA
    verdict = ("yes" if same_direction and significant else
               "direction only (not significant)" if same_direction else "no: opposite direction")
    return Claim(text, f"t({df_paper}) = {t_paper}, p = {p_paper}",
                 f"t({df}) = {t:.2f}, p = {p:.2g} (p at df {df_paper}: {p_at_df(t, df_paper):.2g})", verdict)


def _order_claim(text: str, paper_gap: float, score: Score, targets: Sequence[str], a: str, b: str,
                 unfinished: Pairs, tolerance: float = 2.0) -> Claim:
    """A claim that the mean of ``a`` is above that of ``b`` over ``targets``: the paper's gap and ours, in points
    (unjudged until they finished on all the targets); a gap the paper gives as under one point is a claim of
    about equal means (reproduced within ``tolerance`` points)."""
    partial = _partial(text, f"{paper_gap:+.1f}", score, targets, (a, b), unfinished)
    if partial is not None:
        return partial
    ours_gap = _gap(score, targets, a, b)
    if ours_gap is None:
        return Claim(text, f"{paper_gap:+.1f}", "-", "not run")
    ours = 100 * ours_gap
    if abs(paper_gap) < 1.0:
        verdict = "yes (about equal)" if abs(ours) <= tolerance else f"no: {abs(ours):.1f} points apart"
    else:
        verdict = "yes" if (ours > 0) == (paper_gap > 0) else "no: opposite direction"
    return Claim(text, f"{paper_gap:+.1f}", f"{ours:+.1f}", verdict)


def claims(score: Score, kind_of: Mapping[str, str], category_of: Mapping[str, str], *,
           tolerance: float = 5.0, variants: Mapping[str, Sequence[str]] | None = None,
           unfinished: Pairs = ()) -> list[Claim]:
    """Every quantitative claim of the paper's results (means per kind, t-tests, wins, the headline
    concepts, the CNN by category, the noprim ablation) with ours. A mean is reproduced within ``tolerance``
    points; a comparison when its direction is the paper's and it is significant at :data:`ALPHA`. The claims
    over all concepts of a kind are judged only when ``score`` holds all of them (the paper's 34 / 17); a report of
    fewer says so in one row per kind, and a claim whose methods ran on some of them only is "not judged: partial".
    The per-concept claims (the headline targets) are judged wherever present. ``variants``: the paper's method ->
    our methods each judged in every claim about it (``{"base": ["base", "base-gru"]}``); default: the method
    itself. ``unfinished``: target x method pairs still being trained; no claim is judged on them (the CNN claims
    leave them out of a concept's best SMC method)."""
    out: list[Claim] = []

    def ours(method: str) -> Sequence[str]:
        """Our methods for the paper's ``method``."""
        return (variants or {}).get(method, (method,))

    flats = ours("base")

    for kind in ("classification", "bring-about"):
        targets = sorted(t for t in kind_of if kind_of[t] == kind and category_of[t] != "pushable")
        if not targets:
            continue
        if len(targets) != PAPER_COUNTS[kind]:
            out.append(Claim(f"{kind}: the claims over all {PAPER_COUNTS[kind]} concepts (means, t-tests, wins, "
                             "noprim)", f"{PAPER_COUNTS[kind]} concepts", f"{len(targets)} concepts here",
                             "not comparable: a subset"))
            continue
        for method, paper in PAPER_MEANS[kind].items():
            out += [_mean_claim(kind, m, paper, score, targets, tolerance, unfinished) for m in ours(method)]
        for comparison, paper_test in PAPER_TTESTS[kind].items():
            a, _, b = comparison.split()
            out += [_test_claim(kind, mine, flat, score, targets, paper_test, unfinished)
                    for mine in ours(a) for flat in ours(b)]
        if kind == "bring-about":
            for flat in flats:
                text = f"bring-about: a hierarchical SMC (best of curr, canon) beats the flat one ({flat})"
                partial = _partial(text, "on 14 of 16 concepts", score, targets, ("curr", "canon", flat), unfinished)
                won, n = wins(score, targets, ("curr", "canon"), flat)
                out.append(partial or Claim(text, "on 14 of 16 concepts", f"on {won} of {n} concepts" if n else "-", (
                    "yes" if won / n >= 14 / 16 - 1e-9 else f"no: {won / n:.0%} of concepts against 88%")
                    if n else "not run"))
        else:
            paper_means = PAPER_MEANS[kind]
            for a, b in (("cnn", "base"), ("curr", "cnn")):
                out += [_order_claim(f"classification: {a} above {other} (mean gap, points)",
                                     paper_means[a] - paper_means[b], score, targets, a, other, unfinished)
                        for other in ours(b)]
            finished = {key: value for key, value in score.items() if key not in unfinished}
            out.extend(_cnn_claims(finished, targets, category_of, (*flats, "curr", "canon")))
        for method in ("curr", "canon"):
            paper_with, paper_without = PAPER_NOPRIM[kind][method], PAPER_NOPRIM[kind][f"{method}-noprim"]
            out.append(_mean_claim(kind, f"{method}-noprim", paper_without, score, targets, tolerance, unfinished))
            out.append(_order_claim(f"{kind}: {method} without primitives against with (mean gap, points)",
                                    paper_without - paper_with, score, targets, f"{method}-noprim", method,
                                    unfinished))
    for target, paper_scores in PAPER_CONCEPTS.items():
        for method, value in paper_scores.items():
            for m in ours(method):
                text, ran = f"{target}: {m}", score.get((target, m))
                out.append(Claim(text, f"{value:.1f}", f"{100 * ran:.1f} so far", "not judged: partial")
                           if ran is not None and (target, m) in unfinished
                           else _value_claim(text, value, ran, tolerance))
    return out


def _cnn_claims(score: Score, targets: Sequence[str], category_of: Mapping[str, str],
                smcs: Sequence[str]) -> list[Claim]:
    """The qualitative Fig. 5a claims: SMCs clearly ahead of the CNN on containment; the CNN relatively better on
    objects and objcon (its gap to the best SMC method of ``smcs`` smaller there than on containment)."""
    gaps: dict[str, float] = {}
    for category in ("containment", "objcon", "objects"):
        members = [t for t in targets if category_of[t] == category]
        best = [max(score[(t, m)] for m in smcs if (t, m) in score) - score[(t, "cnn")]
                for t in members if (t, "cnn") in score and any((t, m) in score for m in smcs)]
        if members and len(best) == len(members):
            gaps[category] = float(np.mean(best))
    out = []
    if "containment" in gaps:
        out.append(Claim("classification / containment: the best SMC method clearly above the cnn",
                         "qualitative (Fig. 5a)", f"{100 * gaps['containment']:+.1f} points",
                         "yes" if gaps["containment"] >= 0.05 else "no: a lead under 5 points"))
    for category in ("objects", "objcon"):
        if category in gaps and "containment" in gaps:
            out.append(Claim(f"classification / {category}: the cnn relatively better than on containment",
                             "qualitative (Fig. 5a)",
                             f"SMC lead {100 * gaps[category]:+.1f} against {100 * gaps['containment']:+.1f}",
                             "yes" if gaps[category] < gaps["containment"] else "no: the SMCs' lead is not smaller"))
    return out
