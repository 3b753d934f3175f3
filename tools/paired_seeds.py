"""Two methods of the whole table compared seed by seed (docs/results/paper/README.md: does `canon-scaled`'s larger
budget lift canon's weak seeds?).

A method that gives the same node a longer run (``canon-scaled`` against ``canon``) trains each seed along the same
path for as long as the shorter run lasts, so seed ``s`` of one is paired with seed ``s`` of the other. For each
kind this counts, over the targets both methods ran, the seeds the second method lifts or lowers by 5 points or
more, and the first method's weak seeds (more than 15 points below that concept's best seed) that the second
brings within 15 points of it; with ``--by-target``, every target's seeds side by side.

    python tools/paired_seeds.py docs/results/paper/{search,objects,containment,objcon,canon-scaled} \\
        --methods canon,canon-scaled
"""

from __future__ import annotations

import argparse
import sys
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np

from sb3_smc.errors import SMCError
from sb3_smc.experiments.design import METHODS
from sb3_smc.experiments.runner import read_results

MOVED = 0.05  # a seed lifted or lowered: by 5 points or more
WEAK = 0.15  # a weak seed: more than 15 points below its concept's best


def seed_scores(results: list[dict[str, Any]], method: str) -> dict[str, dict[int, float]]:
    """Each target's seed scores for ``method`` (the seeds of its reported curriculum, as the report takes them)."""
    reported = {(r["target"], r["curriculum"]) for res in results for r in res["reported"] if r["method"] == method}
    scores: dict[str, dict[int, float]] = defaultdict(dict)
    for res in results:
        for row in res["rows"]:
            if row["method"] == method and (row["target"], row["curriculum"]) in reported:
                scores[row["target"]][int(row["seed"])] = float(row["test_score"])
    return dict(scores)


def summary(a: dict[str, dict[int, float]], b: dict[str, dict[int, float]], targets: list[str]) -> dict[str, Any]:
    """The counts of one kind over ``targets``: seeds paired, lifted, lowered, A's weak seeds (against the best of
    all of A's seeds of the concept) and how many B brings within ``WEAK`` of that best, the means over paired
    seeds, and the mean across targets of the best paired seed."""
    paired = {t: sorted(set(a[t]) & set(b[t])) for t in targets}
    pairs = [(a[t][s], b[t][s], max(a[t].values())) for t in targets for s in paired[t]]
    weak = [(x, y, best) for x, y, best in pairs if x < best - WEAK]
    return {"targets": len(targets), "seeds": len(pairs),
            "mean_a": float(np.mean([x for x, _, _ in pairs])), "mean_b": float(np.mean([y for _, y, _ in pairs])),
            "best_a": float(np.mean([max(a[t][s] for s in paired[t]) for t in targets])),
            "best_b": float(np.mean([max(b[t][s] for s in paired[t]) for t in targets])),
            "lifted": sum(y - x >= MOVED for x, y, _ in pairs), "lowered": sum(x - y >= MOVED for x, y, _ in pairs),
            "weak": len(weak), "weak_lifted": sum(y >= best - WEAK for _, y, best in weak)}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("runs", nargs="+", type=Path, help="experiment directories or kept records (results.json)")
    parser.add_argument("--methods", required=True, help="the two methods, the shorter run first: canon,canon-scaled")
    parser.add_argument("--by-target", action="store_true", help="also every target's seeds side by side")
    args = parser.parse_args(argv)
    methods = args.methods.split(",")
    if len(methods) != 2 or any(m not in METHODS for m in methods):
        parser.error(f"--methods: two of {', '.join(METHODS)}, comma-separated (got {args.methods!r})")
    try:  # every directory read before any counting
        results = [read_results(run) for run in args.runs]
    except (OSError, SMCError) as error:
        parser.error(str(error))
    a, b = (seed_scores(results, m) for m in methods)
    kind_of = {r["target"]: r["kind"] for res in results for r in res["reported"]}
    both = sorted(t for t in a if t in b and set(a[t]) & set(b[t]))
    if not both:
        parser.error(f"no target has seeds of both {methods[0]} and {methods[1]} in {', '.join(map(str, args.runs))}")
    pct = "{:.1f}".format
    print(f"| kind | targets | paired seeds | mean {methods[0]} | mean {methods[1]} | best paired {methods[0]} | "
          f"best paired {methods[1]} | lifted >= 5 | lowered >= 5 | weak seeds of {methods[0]} | brought within 15 |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for kind in ("classification", "bring-about", None):
        targets = [t for t in both if kind in (None, kind_of[t])]
        if not targets:
            continue
        s = summary(a, b, targets)
        print(f"| {kind or 'all'} | {s['targets']} | {s['seeds']} | {pct(100 * s['mean_a'])} | "
              f"{pct(100 * s['mean_b'])} | {pct(100 * s['best_a'])} | {pct(100 * s['best_b'])} | {s['lifted']} | "
              f"{s['lowered']} | {s['weak']} | {s['weak_lifted']} |")
    if args.by_target:
        print(f"\n| target | {methods[0]} by seed | {methods[1]} by seed |\n|---|---|---|")
        for t in both:
            cells = (" / ".join(pct(100 * m[t][s]) if s in m[t] else "-" for s in sorted(set(a[t]) | set(b[t])))
                     for m in (a, b))
            print(f"| `{t}` | " + " | ".join(cells) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
