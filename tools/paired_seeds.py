"""Two methods of the whole table compared seed by seed (docs/results/paper/README.md: does `canon-scaled`'s larger
budget lift canon's weak seeds?).

A method that gives the same node a longer run (``canon-scaled`` against ``canon``: the same curriculum node, its
name prefixed by the method) trains each seed along the same path for as long as the shorter run lasts (with
constant hyperparameters, the package's defaults; a ``lin_`` schedule depends on the budget), provided it calls the
same lower-level SMCs (its spec's children in the run's ``evaluations/``: by name, and by the digests of their
weights where the records have them; a run resumed on another machine may have trained a child again under the same
name): seed ``s`` of one is paired with seed ``s`` of the other, on the targets whose reported curricula are the same
node. For each kind this counts the seeds the second method lifts or lowers by 5 points or more, and the first
method's weak seeds (more than 15 points below that concept's best seed) that the second brings within 15 points of
it: over the seeds that continue the shorter run (the same children), over those on other children (another run's
lower level: not a continuation), and over all; with ``--by-target``, every target's seeds side by side.

    python tools/paired_seeds.py docs/results/paper/{search,objects,containment,objcon,canon-scaled} \\
        --methods canon,canon-scaled

With ``--across-targets FLAT,...`` it compares the two methods across targets instead, on the same lower level only
(docs/results/paper/README.md: does ``curr-moves`` collapse where it calls other children than ``curr``?): it
names the second method's curricula whose seeds call other lower-level SMCs than the first's same curriculum and
seed, and on the targets left (each with at least one curriculum on the same lower level) takes each method's best
seed over those curricula, each flat method's best seed, their means per kind and the paired t-tests across the
targets (scipy's, as the report's):

    python tools/paired_seeds.py docs/results/paper/{search,objects,containment,objcon,curr-moves,curr-moves-cl} \\
        docs/results/paper/base-gru --methods curr,curr-moves --across-targets base,base-gru
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

import numpy as np

from sb3_smc.curricula.jobs import job_name
from sb3_smc.errors import SMCError
from sb3_smc.experiments.design import METHODS
from sb3_smc.experiments.runner import evaluation_path, read_evaluation, read_results
from sb3_smc.experiments.statistics import paired_ttest

MOVED = 5.0  # a seed lifted or lowered: by 5 points or more
WEAK = 15.0  # a weak seed: more than 15 points below its concept's best


def points(score: float) -> float:
    """A test score (a fraction) in points, to 0.1 (so that differences compare exactly at 5 and 15 points)."""
    return round(100 * score, 1)


LowerLevel = list[tuple[str, str | None]]
"""The lower-level SMCs a seed called: (name, digest of its weights where the evaluation recorded it)."""


def children(run: Path, node: str, seed: int) -> LowerLevel:
    """The lower-level SMCs that seed ``seed`` of ``node`` called, from its evaluation record in ``run``."""
    path = evaluation_path(run, job_name(node, seed))
    if not path.is_file():
        raise SMCError(f"{path} not found: the evaluation of {job_name(node, seed)} (its spec names the lower-level "
                       "SMCs it called) is needed to pair its seed")
    saved = read_evaluation(path)
    spec = saved.get("spec")
    if not isinstance(spec, dict) or not isinstance(spec.get("children"), list):
        raise SMCError(f"{path} has no spec with its children: it should be an SMC's evaluation that sb3-smc "
                       "experiment wrote")
    digests = saved.get("children_digests", [None] * len(spec["children"]))  # older records name the children only
    if (not isinstance(digests, list) or len(digests) != len(spec["children"])
            or not all(d is None or isinstance(d, str) for d in digests)):
        raise SMCError(f"{path}: 'children_digests' must list one digest (a string, or null) per child of its spec "
                       f"({len(spec['children'])}), got {digests!r}")
    return list(zip(spec["children"], digests, strict=True))


def same_lower_level(a: LowerLevel, b: LowerLevel) -> bool:
    """Whether two seeds called the same lower-level SMCs: the same names and, where both evaluations recorded
    them, the same weights (older records name their children only)."""
    return [name for name, _ in a] == [name for name, _ in b] and all(
        x is None or y is None or x == y for (_, x), (_, y) in zip(a, b, strict=True))


Seeds = dict[int, tuple[float, LowerLevel]]
"""A target's seeds: seed -> (test score in points, the lower-level SMCs it called)."""


def seed_scores(runs: list[tuple[Path, dict[str, Any]]], method: str) -> dict[str, tuple[str, Seeds]]:
    """Each target's reported curriculum for ``method`` and its seeds (the seeds the report takes) from the runs
    (directory, results); a seed found twice with different scores is an error."""
    reported = {r["target"]: r["curriculum"] for _, res in runs for r in res["reported"] if r["method"] == method}
    scores: dict[str, Seeds] = {target: {} for target in reported}
    for run, res in runs:
        for row in res["rows"]:
            target, seed = row["target"], int(row["seed"])
            if row["method"] != method or row["curriculum"] != reported.get(target):
                continue
            score = points(float(row["test_score"]))
            found = scores[target].setdefault(seed, (score, children(run, row["curriculum"], seed)))[0]
            if found != score:
                raise SMCError(f"{method} on {target}, seed {seed}: two results ({found} and {score})")
    return {target: (reported[target], scores[target]) for target in reported}


def curricula_seeds(runs: list[tuple[Path, dict[str, Any]]], method: str) -> dict[str, dict[str, Seeds]]:
    """Every curriculum (node) of every target of ``method`` and its seeds, from the runs (directory, results); a
    seed found twice with different scores is an error."""
    found: dict[str, dict[str, Seeds]] = {}
    for run, res in runs:
        for row in res["rows"]:
            if row["method"] != method:
                continue
            seeds = found.setdefault(row["target"], {}).setdefault(row["curriculum"], {})
            score, seed = points(float(row["test_score"])), int(row["seed"])
            if seeds.setdefault(seed, (score, children(run, row["curriculum"], seed)))[0] != score:
                raise SMCError(f"{method} on {row['target']}, {row['curriculum']} seed {seed}: two results "
                               f"({seeds[seed][0]} and {score})")
    return found


def same_lower_level_curricula(a: dict[str, dict[str, Seeds]], b: dict[str, dict[str, Seeds]], second: str
                               ) -> tuple[dict[str, list[tuple[str, str]]], dict[str, list[tuple[str, int, int]]]]:
    """Per target, the pairs (A's curriculum, B's) of the same node (B's named as A's or ``<second>/<A's>``) whose
    every seed of both calls the same lower-level SMCs; and per target B's other curricula of such a pair, with
    how many of their seeds call other ones and how many seeds they have."""
    alike: dict[str, list[tuple[str, str]]] = {}
    other: dict[str, list[tuple[str, int, int]]] = {}
    for target, curricula in b.items():
        for node, seeds in curricula.items():
            theirs = a.get(target, {}).get(node.removeprefix(f"{second}/"))
            if theirs is None or not set(seeds) & set(theirs):
                continue
            differ = sum(not same_lower_level(seeds[s][1], theirs[s][1]) for s in set(seeds) & set(theirs))
            if differ:
                other.setdefault(target, []).append((node, differ, len(seeds)))
            else:
                alike.setdefault(target, []).append((node.removeprefix(f"{second}/"), node))
    return alike, other


def across_targets(runs: list[tuple[Path, dict[str, Any]]], methods: list[str], flat: list[str]) -> None:
    """Print the comparison of ``methods`` across targets on the same lower level only, beside the ``flat`` methods
    (the module's docstring)."""
    a, b = (curricula_seeds(runs, m) for m in methods)
    alike, other = same_lower_level_curricula(a, b, methods[1])
    if not alike:
        raise SMCError(f"no curriculum of {methods[1]} calls the same lower-level SMCs as {methods[0]}'s")
    best: dict[str, dict[str, float]] = {}  # target -> flat method -> its best seed
    for _, res in runs:
        for r in res["reported"]:
            if r["method"] in flat:
                best.setdefault(r["target"], {})[r["method"]] = points(r["test_score"])
    kind_of = {r["target"]: r["kind"] for _, res in runs for r in res["reported"]}
    missing = sorted({f"{m} on {t}" for t in alike for m in flat if m not in best.get(t, {})})
    if missing:
        raise SMCError(f"no result of {', '.join(missing[:5])}{', ...' if len(missing) > 5 else ''}: give the run "
                       "directories of the flat methods too")
    seeds_b = sum(len(seeds) for curricula in b.values() for seeds in curricula.values())
    differing = [(t, node, n, of) for t in sorted(other) for node, n, of in other[t]]
    print(f"{methods[1]} calls other lower-level SMCs than {methods[0]} in {sum(n for *_, n, _ in differing)} of its "
          f"{seeds_b} SMCs, in {len(differing)} curricula of {len(other)} targets (seeds on other children / seeds):\n")
    for target, node, n, of in differing:
        kept = len(alike.get(target, ()))
        print(f"- `{node}`: {n} / {of}" + (f" (the target keeps {kept} curricul{'a' if kept > 1 else 'um'} on the "
                                          "same ones)" if kept else ""))
    scores: dict[str, dict[str, float]] = {}  # target -> method -> its best seed (over the curricula alike)
    for t, pairs in alike.items():
        scores[t] = {**best[t],
                     methods[0]: max(score for node, _ in pairs for score, _ in a[t][node].values()),
                     methods[1]: max(score for _, node in pairs for score, _ in b[t][node].values())}
    columns = [*methods, *flat]
    print(f"\nOn the {len(scores)} targets with a curriculum on the same lower level (best seed over those curricula; "
          "flat methods: best seed):\n")
    print("| kind | targets | " + " | ".join(columns) + " |\n|---|---:|" + "---:|" * len(columns))
    tests: list[str] = []
    for kind in ("classification", "bring-about", None):
        targets = sorted(t for t in scores if kind in (None, kind_of[t]))
        if not targets:
            continue
        print(f"| {kind or 'all'} | {len(targets)} | "
              + " | ".join(f"{np.mean([scores[t][m] for t in targets]):.1f}" for m in columns) + " |")
        if kind is None:
            continue
        for x, y in [(methods[1], methods[0]), *((m, f) for f in flat for m in (methods[1], methods[0]))]:
            test = paired_ttest([scores[t][x] for t in targets], [scores[t][y] for t in targets])
            better = sum(scores[t][x] > scores[t][y] for t in targets)
            worse = sum(scores[t][x] < scores[t][y] for t in targets)
            tests.append(f"| {kind} | {x} vs {y} | {len(targets)} | "
                         + ("- | - | - |" if test is None else f"{test[1]:.2f} | {test[0]} | {test[2]:.2g} |")
                         + f" {better} / {worse} |")
    print("\nPaired t-tests across those targets (two-sided):\n\n| kind | comparison | targets | t | df | p | "
          "better / worse |\n|---|---|---:|---:|---:|---:|---:|")
    print("\n".join(tests) + "\n")


def summary(a: dict[str, dict[int, float]], b: dict[str, dict[int, float]], targets: list[str],
            best: dict[str, float]) -> dict[str, Any]:
    """The counts of one kind over ``targets``: seeds paired, lifted, lowered, A's weak seeds (against ``best``, the
    best of all of A's seeds of the concept) and how many B brings within ``WEAK`` of that best, the means over
    paired seeds, and the mean across targets of the best paired seed."""
    paired = {t: sorted(set(a[t]) & set(b[t])) for t in targets}
    pairs = [(a[t][s], b[t][s], best[t]) for t in targets for s in paired[t]]
    weak = [(x, y, top) for x, y, top in pairs if round(top - x, 1) > WEAK]
    return {"targets": len(targets), "seeds": len(pairs),
            "mean_a": float(np.mean([x for x, _, _ in pairs])), "mean_b": float(np.mean([y for _, y, _ in pairs])),
            "best_a": float(np.mean([max(a[t][s] for s in paired[t]) for t in targets])),
            "best_b": float(np.mean([max(b[t][s] for s in paired[t]) for t in targets])),
            "lifted": sum(round(y - x, 1) >= MOVED for x, y, _ in pairs),
            "lowered": sum(round(x - y, 1) >= MOVED for x, y, _ in pairs),
            "weak": len(weak), "weak_lifted": sum(round(top - y, 1) <= WEAK for _, y, top in weak)}


def print_table(title: str, methods: list[str], a: dict[str, dict[int, float]], b: dict[str, dict[int, float]],
                kind_of: dict[str, str], best: dict[str, float]) -> None:
    """The counts (:func:`summary`) per kind and over all of the targets of ``kind_of``, under ``title``."""
    print(f"{title}:\n\n| kind | targets | paired seeds | mean {methods[0]} | mean {methods[1]} | best paired "
          f"{methods[0]} | best paired {methods[1]} | lifted >= 5 | lowered >= 5 | weak seeds of {methods[0]} (> 15 "
          "below its best) | brought within 15 |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for kind in ("classification", "bring-about", None):
        targets = [t for t in kind_of if kind in (None, kind_of[t])]
        if targets:
            s = summary(a, b, targets, best)
            print(f"| {kind or 'all'} | {s['targets']} | {s['seeds']} | {s['mean_a']:.1f} | {s['mean_b']:.1f} | "
                  f"{s['best_a']:.1f} | {s['best_b']:.1f} | {s['lifted']} | {s['lowered']} | {s['weak']} | "
                  f"{s['weak_lifted']} |")
    print()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("runs", nargs="+", type=Path, help="experiment directories or kept records (results.json)")
    parser.add_argument("--methods", required=True, help="the two methods, the shorter run first: canon,canon-scaled")
    parser.add_argument("--by-target", action="store_true", help="also every target's seeds side by side")
    parser.add_argument("--across-targets", metavar="FLAT", default=None,
                        help="instead: compare the two across targets, on the curricula where the second calls the "
                             "same lower-level SMCs as the first, beside these flat methods (comma-separated)")
    args = parser.parse_args(argv)
    methods = args.methods.split(",")
    if len(methods) != 2 or any(m not in METHODS for m in methods):
        parser.error(f"--methods: two of {', '.join(METHODS)}, comma-separated (got {args.methods!r})")
    if args.across_targets is not None:
        flat = [m for m in args.across_targets.split(",") if m]
        if not flat or any(m not in METHODS for m in flat):
            parser.error(f"--across-targets: methods of {', '.join(METHODS)}, comma-separated "
                         f"(got {args.across_targets!r})")
        try:
            across_targets([(run, read_results(run)) for run in args.runs], methods, flat)
        except (OSError, SMCError) as error:
            parser.error(str(error))
        return 0
    try:  # every directory read, and every seed checked, before any counting
        runs = [(run, read_results(run)) for run in args.runs]
        found_a, found_b = (seed_scores(runs, m) for m in methods)
    except (OSError, SMCError) as error:
        parser.error(str(error))
    common = sorted(t for t in found_a if t in found_b and set(found_a[t][1]) & set(found_b[t][1]))
    both = [t for t in common if found_b[t][0] in (found_a[t][0], f"{methods[1]}/{found_a[t][0]}")]
    if not both:
        parser.error(f"no target has seeds of both {methods[0]} and {methods[1]} on the same curriculum node in "
                     f"{', '.join(map(str, args.runs))}")
    kind_of = {r["target"]: r["kind"] for _, res in runs for r in res["reported"]}
    other = {t: {s for s in set(found_a[t][1]) & set(found_b[t][1])
                if not same_lower_level(found_a[t][1][s][1], found_b[t][1][s][1])}
             for t in both}  # the seeds on another lower level
    best = {t: max(v[0] for v in found_a[t][1].values()) for t in both}
    for title, keep in (("Seeds continuing the shorter run (the same lower-level SMCs)",
                         lambda t, s: s not in other[t]),
                        ("Seeds on other lower-level SMCs (not a continuation)", lambda t, s: s in other[t]),
                        ("All paired seeds", lambda t, s: True)):
        a, b = ({t: {s: v[0] for s, v in found[t][1].items() if keep(t, s)} for t in both}
                for found in (found_a, found_b))
        paired = [t for t in both if set(a[t]) & set(b[t])]
        if paired:
            print_table(title, methods, a, b, {t: kind_of[t] for t in paired}, best)
    apart = [t for t in common if t not in both]
    if apart:
        print(f"Not paired (the reported curricula are different nodes): {', '.join(apart)}\n")
    if args.by_target:
        print(f"| target | {methods[0]} by seed | {methods[1]} by seed | seeds on other lower-level SMCs |\n"
              "|---|---|---|---|")
        for t in both:
            a_t, b_t = found_a[t][1], found_b[t][1]
            cells = (" / ".join(f"{m[s][0]:.1f}" if s in m else "-" for s in sorted(set(a_t) | set(b_t)))
                     for m in (a_t, b_t))
            print(f"| `{t}` | " + " | ".join(cells) + f" | {', '.join(map(str, sorted(other[t])))} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
