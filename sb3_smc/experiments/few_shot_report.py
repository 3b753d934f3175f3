"""The few-shot table's report from its ``results.csv`` (:mod:`sb3_smc.experiments.few_shot`): score against the number
of training worlds per kind and method (a table and a figure), the fewest worlds at which each library method reaches
the flat SMC's score on every world, paired tests across concepts at each ``N`` with intervals from a hierarchical
bootstrap (concepts resampled, then seeds within each), and what the library cost (its SMCs' primitive experience,
counted once) beside each cell's own. Only what was measured is reported: a cell without records is left out, and
each statement says on how many concepts it stands."""

from __future__ import annotations

import csv
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pixelworld_env.atomic import atomic_write
from sb3_smc.experiments.statistics import hierarchical_interval, paired_ttest, ttest_text

__all__ = ["Comparison", "Fewest", "compare", "fewest_worlds", "read_results", "write_report"]

LIBRARY_METHODS = ("curr", "canon", "auto")
COLOURS = {"cnn": "tab:gray", "base": "tab:blue", "curr": "tab:orange", "canon": "tab:green", "auto": "tab:red"}
"""One colour per method, the same in every panel."""


def read_results(path: str | Path) -> list[dict[str, object]]:
    """The rows of a few-shot ``results.csv`` (numbers parsed; ``train_worlds`` an int, or ``"all"``)."""
    rows: list[dict[str, object]] = []
    with open(path, encoding="utf-8", newline="") as handle:
        for row in csv.DictReader(handle):
            worlds = row["train_worlds"]
            rows.append({**row, "train_worlds": worlds if worlds == "all" else int(worlds), "seed": int(row["seed"]),
                         "test_score": float(row["test_score"]), "offered": int(row["offered"]),
                         "primitive_steps": int(row["primitive_steps"])})
    return rows


def _by_concept(rows: Sequence[Mapping[str, object]], method: str, worlds: object) -> dict[str, list[float]]:
    """concept -> its seeds' test scores of ``method`` at ``worlds``."""
    out: dict[str, list[float]] = {}
    for row in rows:
        if row["method"] == method and row["train_worlds"] == worlds:
            out.setdefault(str(row["target"]), []).append(float(row["test_score"]))  # type: ignore[arg-type]
    return out


@dataclass(frozen=True)
class Comparison:
    """A library method against the flat SMC at one ``N`` and kind, on the concepts both have: the mean paired
    difference in points with its hierarchical interval, and the paired t-test across concepts (``None`` below 2)."""

    method: str
    kind: str
    worlds: object
    concepts: int
    difference: float
    low: float
    high: float
    test: tuple[int, float, float] | None


def compare(rows: Sequence[Mapping[str, object]], method: str, kind: str, worlds: object) -> Comparison | None:
    """``method`` against ``base`` at ``worlds`` on the concepts of ``kind`` where both have seeds paired by seed
    (``None`` where there are none)."""
    kind_rows = [r for r in rows if r["kind"] == kind]
    ours, flat = _seeded(kind_rows, method, worlds), _seeded(kind_rows, "base", worlds)
    shared = sorted(set(ours) & set(flat))
    differences = {c: [100 * (ours[c][s] - flat[c][s]) for s in sorted(set(ours[c]) & set(flat[c]))] for c in shared}
    differences = {c: d for c, d in differences.items() if d}
    if not differences:
        return None
    mean, low, high = hierarchical_interval(differences)
    seeds = {c: sorted(set(ours[c]) & set(flat[c])) for c in differences}  # the seeds both have, as the interval
    test = paired_ttest([float(np.mean([ours[c][s] for s in seeds[c]])) for c in differences],
                        [float(np.mean([flat[c][s] for s in seeds[c]])) for c in differences])
    return Comparison(method, kind, worlds, len(differences), mean, low, high, test)


@dataclass(frozen=True)
class Fewest:
    """The fewest training worlds at which a library method reaches the flat SMC's score on every world: per concept
    (``None``: not reached at any ``N`` measured), and pooled over the concepts measured at each ``N``."""

    method: str
    per_concept: dict[str, object]
    pooled: object


def fewest_worlds(rows: Sequence[Mapping[str, object]], method: str, worlds: Sequence[object]) -> Fewest | None:
    """``method`` against the flat SMC on every world (``base`` at ``"all"``) over the concepts of ``rows`` where
    both are measured, ``worlds`` in increasing order; ``None`` where no concept has both."""
    reference = {c: float(np.mean(v)) for c, v in _by_concept(rows, "base", "all").items()}
    scores = {w: {c: float(np.mean(v)) for c, v in _by_concept(rows, method, w).items() if c in reference}
              for w in sorted(worlds, key=_order)}
    concepts = sorted({c for by in scores.values() for c in by})
    if not concepts:
        return None
    per_concept = {c: next((w for w, by in scores.items() if c in by and by[c] >= reference[c]), None)
                   for c in concepts}
    pooled = next((w for w, by in scores.items()
                   if by and np.mean(list(by.values())) >= np.mean([reference[c] for c in by])), None)
    return Fewest(method, per_concept, pooled)


def _seeded(rows: Sequence[Mapping[str, object]], method: str, worlds: object) -> dict[str, dict[int, float]]:
    out: dict[str, dict[int, float]] = {}
    for row in rows:
        if row["method"] == method and row["train_worlds"] == worlds:
            out.setdefault(str(row["target"]), {})[int(row["seed"])] = float(row["test_score"])  # type: ignore
    return out


def _order(worlds: object) -> tuple[int, int]:
    return (1, 0) if worlds == "all" else (0, int(worlds))  # type: ignore[call-overload]


def write_report(out: str | Path, library_steps: Mapping[str, int] | None = None) -> Path:
    """``<out>/report.md`` and ``<out>/few_shot.png`` from ``<out>/results.csv``. ``library_steps``: the primitive
    steps each pretrained SMC trained with, by name (default: the package's pretrained library's records), for the
    library's cost."""
    out = Path(out)
    rows = read_results(out / "results.csv")
    if library_steps is None:
        library_steps = _pretrained_steps()
    methods = [m for m in ("cnn", "base", *LIBRARY_METHODS) if any(r["method"] == m for r in rows)]
    worlds = sorted({r["train_worlds"] for r in rows}, key=_order)
    kinds = sorted({str(r["kind"]) for r in rows})
    lines = ["# The few-shot table", "", f"{len({r['target'] for r in rows})} concepts, {len(rows)} cells measured "
             "(a cell: one concept, method, number of training worlds and seed). Scores: the paper's protocol, every "
             "test world 10 times; a concept's score is the mean over its seeds.", ""]
    concepts_of = {kind: len({r["target"] for r in rows if r["kind"] == kind}) for kind in kinds}
    lines += ["## Score against the number of training worlds", "",
              "Mean over concepts (their seeds' means), in %, with the number of concepts measured; a count below "
              "the kind's (" + ", ".join(f"{n} {kind}" for kind, n in concepts_of.items()) + ") marks a cell "
              "still being run (or a method the concept has no entry for), its mean over those concepts only.", ""]
    for kind in kinds:
        lines += [f"### {kind}", "", "| method | " + " | ".join(f"N={w}" for w in worlds) + " |",
                  "|---|" + "---:|" * len(worlds)]
        for method in [m for m in methods if any(r["method"] == m and r["kind"] == kind for r in rows)]:
            cells = []
            for w in worlds:
                concepts = _by_concept([r for r in rows if r["kind"] == kind], method, w)
                means = [float(np.mean(v)) for v in concepts.values()]
                cells.append(f"{100 * np.mean(means):.1f} ({len(means)})" if means else "-")
            lines.append(f"| {method} | " + " | ".join(cells) + " |")
        lines.append("")
    lines += ["## Fewest worlds to the flat SMC's score on every world", "",
              "Per concept, the fewest N at which a method's score (mean over its seeds) reaches the flat SMC's "
              "on every training world of the same concept (25 bring-about, 50 classification); the concepts are "
              "those where both are measured. Pooled: the first N at which the method's mean over those concepts "
              "(the ones measured at that N) reaches the flat SMC's mean over the same concepts.", "",
              "| kind | method | concepts | the flat SMC on every world | reached on | fewest N (median of those "
              "reached; of two, the lower) | pooled: first N |",
              "|---|---|---:|---:|---:|---|---|"]
    for kind in kinds:
        kind_rows = [r for r in rows if r["kind"] == kind]
        full = _by_concept(kind_rows, "base", "all")
        if not full:
            lines.append(f"| {kind} | - | 0 | not measured yet | - | - | - |")
            continue
        for method in LIBRARY_METHODS:
            fewest = fewest_worlds(kind_rows, method, worlds)
            if fewest is None:
                continue
            reached = [w for w in fewest.per_concept.values() if w is not None]
            median = "-" if not reached else str(sorted(reached, key=_order)[(len(reached) - 1) // 2])
            flat = 100 * np.mean([np.mean(full[c]) for c in fewest.per_concept])
            lines.append(f"| {kind} | {method} | {len(fewest.per_concept)} | {flat:.1f} % | {len(reached)} | "
                         f"{median} | {fewest.pooled if fewest.pooled is not None else 'not reached'} |")
    lines += ["", "## Library methods against the flat SMC, paired", "",
              "Mean difference in points over concepts, 95 % interval resampling concepts and seeds (hierarchical "
              "bootstrap), paired t-test across concepts on their seed means.", "",
              "| kind | method | N | concepts | difference | interval | t-test |", "|---|---|---|---:|---:|---|---|"]
    for kind in kinds:
        for method in LIBRARY_METHODS:
            for w in worlds:
                paired = compare(rows, method, kind, w)
                if paired is not None:
                    test = ttest_text(paired.test) if paired.test is not None else "-"
                    lines.append(f"| {kind} | {method} | {w} | {paired.concepts} | {paired.difference:+.1f} | "
                                 f"[{paired.low:+.1f}, {paired.high:+.1f}] | {test} |")
    lines += ["", "## What the library cost", "",
              f"The pretrained library's {len(library_steps)} SMCs trained with "
              f"{sum(library_steps.values()):,} primitive steps in all, counted once whatever calls them. Per cell "
              "(median over its concepts and seeds), the cell's own primitive steps:", "",
              "| method | " + " | ".join(f"N={w}" for w in worlds) + " |", "|---|" + "---:|" * len(worlds)]
    for method in methods:
        if method == "cnn":
            continue
        cells = [f"{int(np.median(s)):,}" if (s := [int(r["primitive_steps"]) for r in rows  # type: ignore
                                                     if r["method"] == method and r["train_worlds"] == w]) else "-"
                 for w in worlds]
        lines.append(f"| {method} | " + " | ".join(cells) + " |")
    _figure(rows, methods, worlds, kinds, out / "few_shot.png")
    lines += ["", "![score against the number of training worlds](few_shot.png)", "",
              "Score against N per kind, the mean over concepts; a hollow point stands on fewer concepts than the "
              "method's other points (still being run).", ""]
    return atomic_write(out / "report.md", "\n".join(lines) + "\n")


def _pretrained_steps() -> dict[str, int]:
    from sb3_smc.library import storage
    from sb3_smc.library.pretrained import pretrained_root

    entries = storage.checked_entries(pretrained_root())[0]
    return {n: e.record.primitive_steps for n, e in entries.items() if e.record is not None}


def _figure(rows: Sequence[Mapping[str, object]], methods: Sequence[str], worlds: Sequence[object],
            kinds: Sequence[str], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(1, len(kinds), figsize=(5 * len(kinds), 3.6), squeeze=False)
    for ax, kind in zip(axes[0], kinds, strict=True):
        for method in methods:
            points = []
            for k, w in enumerate(worlds):
                concepts = _by_concept([r for r in rows if r["kind"] == kind], method, w)
                if concepts:
                    points.append((k, 100 * np.mean([np.mean(v) for v in concepts.values()]), len(concepts)))
            if not points:
                continue
            most = max(n for *_, n in points)
            colour = COLOURS.get(method, "black")
            ax.plot([x for x, *_ in points], [y for _, y, _ in points], color=colour, label=method)
            for x, y, n in points:  # hollow: fewer concepts than the method's other points (still being run)
                ax.plot(x, y, "o", color=colour, markerfacecolor=colour if n == most else "white")
        ax.set_xticks(range(len(worlds)), [str(w) for w in worlds])
        ax.set_xlabel("training worlds N")
        ax.set_ylabel("test score (%)")
        ax.set_ylim(0, 100)
        ax.set_title(kind)
        ax.legend(fontsize=8)
    figure.tight_layout()
    figure.savefig(path, dpi=120)
    plt.close(figure)
