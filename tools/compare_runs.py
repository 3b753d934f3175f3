"""Two runs of the same experiment compared: a rerun (another commit, update, worker count or machine) against kept
records, method by method.

    python tools/compare_runs.py docs/results/paper/objcon runs/objcon-rerun

For each method both runs hold, on the targets both reported:

- the SMCs both trained (the same target, curriculum node and seed) and how many came out the same (test score,
  selected update and training return all equal): all of them where the code, its arithmetic and the CPU are the
  same (torch and numba choose their float kernels per CPU, so another machine's SMCs may differ bit for bit);
- the reported score (best seed; curr: best curriculum) and each target's mean over the SMCs both trained, averaged
  over the targets in each run: the mean paired difference (second minus first, points) with its 95 % interval, and
  the paired t-test's p with Holm's adjustment over every test printed (one family: "no difference" holds where every
  adjusted p is 0.05 or more);
- the mean recorded training time of those SMCs in each run and their ratio (second / first).

Each run's commit, CPU, total wall time and command come first. Bad input is refused before any output.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np

from sb3_smc.errors import SMCError
from sb3_smc.experiments.design import METHODS
from sb3_smc.experiments.runner import read_results
from sb3_smc.experiments.statistics import holm, paired_ttest

Key = tuple[str, str, str, int]
"""An SMC of a run: (target, method, curriculum node, seed)."""


def smc_rows(run: Path, results: dict[str, Any]) -> dict[Key, dict[str, Any]]:
    """The run's rows by SMC; an SMC found twice is an error naming the run."""
    found: dict[Key, dict[str, Any]] = {}
    for row in results["rows"]:
        key = (row["target"], row["method"], row["curriculum"], int(row["seed"]))
        if key in found:
            raise SMCError(f"{run}/results.json holds {key[1]} on {key[0]} ({key[2]}, seed {key[3]}) twice")
        found[key] = row
    return found


def difference(first: list[float], second: list[float]) -> tuple[float, float | None, float | None]:
    """The mean paired difference (second - first), the half-width of its 95 % t interval and the paired t-test's
    p (``None`` below two pairs; p 1.0 where every difference is the same)."""
    from scipy import stats

    d = np.asarray(second) - np.asarray(first)
    if len(d) < 2:
        return float(d.mean()), None, None
    half = float(stats.t.ppf(0.975, len(d) - 1) * d.std(ddof=1) / math.sqrt(len(d)))
    test = paired_ttest(second, first)
    return float(d.mean()), half, 1.0 if test is None else test[2]


def compare(first: tuple[Path, dict[str, Any]], second: tuple[Path, dict[str, Any]]) -> list[dict[str, Any]]:
    """One row per method both runs reported (in the package's order of methods): see the module's docstring."""
    rows_a, rows_b = (smc_rows(*run) for run in (first, second))
    reported_a, reported_b = ({(r["target"], r["method"]): float(r["test_score"]) for r in run[1]["reported"]}
                              for run in (first, second))
    table = []
    for method in [m for m in METHODS if any(k[1] == m for k in reported_a) and any(k[1] == m for k in reported_b)]:
        targets = sorted(t for t, m in reported_a if m == method and (t, m) in reported_b)
        both = sorted(k for k in rows_a if k[1] == method and k[0] in targets and k in rows_b)
        by_target: dict[str, list[Key]] = defaultdict(list)
        for key in both:
            by_target[key[0]].append(key)
        mean_targets = sorted(by_target)

        def score(rows: dict[Key, dict[str, Any]], key: Key) -> float:
            return float(rows[key]["test_score"])

        times = [(rows_a[k].get("wall_time_s"), rows_b[k].get("wall_time_s")) for k in both]
        times = [(a, b) for a, b in times if a is not None and b is not None]
        table.append({
            "method": method, "targets": len(targets), "smcs": len(both),
            "same": sum(all(rows_a[k].get(f) == rows_b[k].get(f)
                            for f in ("test_score", "selected_update", "training_return")) for k in both),
            "reported": ([reported_a[(t, method)] for t in targets], [reported_b[(t, method)] for t in targets]),
            "smc_means": ([float(np.mean([score(rows_a, k) for k in by_target[t]])) for t in mean_targets],
                          [float(np.mean([score(rows_b, k) for k in by_target[t]])) for t in mean_targets]),
            "time": (float(np.mean([a for a, _ in times])), float(np.mean([b for _, b in times]))) if times else None,
        })
    for row in table:
        for measure in ("reported", "smc_means"):
            row[f"{measure}_test"] = difference(*row[measure]) if row[measure][0] else None
    tests = [(row, m) for row in table for m in ("reported", "smc_means") if row[f"{m}_test"] is not None
             and row[f"{m}_test"][2] is not None]
    for (row, measure), adjusted in zip(tests, holm([row[f"{m}_test"][2] for row, m in tests]), strict=True):
        row[f"{measure}_holm"] = adjusted
    return table


def _cells(row: dict[str, Any], measure: str) -> str:
    first, second = row[measure]
    if not first:
        return "- | - | - | -"
    mean, half, p = row[f"{measure}_test"]
    interval = f" [{100 * (mean - half):+.1f}, {100 * (mean + half):+.1f}]" if half is not None else ""
    test = f"{p:.2f} ({row[f'{measure}_holm']:.2f})" if p is not None else "-"
    return f"{100 * np.mean(first):.1f} | {100 * np.mean(second):.1f} | {100 * mean:+.1f}{interval} | {test}"


def describe(run: Path, results: dict[str, Any]) -> str:
    """One line on a run: directory, commit, CPU, total wall time, whether complete, command."""
    commit = (results.get("code") or {}).get("commit") or "unknown"
    cpu = (results.get("machine") or {}).get("processor") or "unknown"
    total = results.get("wall_time_total_s")
    hours = f"{total / 3600:.2f} h recorded" if isinstance(total, (int, float)) else "no wall time recorded"
    complete = "complete" if results.get("complete") else "incomplete"
    return f"- `{run}`: commit `{commit[:7]}`, CPU {cpu}, {hours}, {complete}: `{results.get('command', '?')}`"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("first", type=Path, help="an experiment directory (or kept records: its results.json)")
    parser.add_argument("second", type=Path, help="the run compared with it")
    args = parser.parse_args(argv)
    try:  # both runs read and checked before any output
        runs = [(run, read_results(run)) for run in (args.first, args.second)]
        table = compare(*runs)
    except (OSError, SMCError) as error:
        parser.error(str(error))
    if not table:
        parser.error(f"{args.first} and {args.second} report no method in common")
    print("\n".join(describe(*run) for run in runs) + "\n")
    print("| method | targets | SMCs in both | the same | reported: first | second | difference [95 %] | p (Holm) "
          "| SMC mean: first | second | difference [95 %] | p (Holm) | s per SMC: first | second | ratio |\n"
          "|---|---:|---:|---:|---:|---:|---|---|---:|---:|---|---|---:|---:|---:|")
    for row in table:
        time = (f"{row['time'][0]:.1f} | {row['time'][1]:.1f} | {row['time'][1] / row['time'][0]:.2f}"
                if row["time"] else "- | - | -")
        print(f"| {row['method']} | {row['targets']} | {row['smcs']} | {row['same']} | {_cells(row, 'reported')} | "
              f"{_cells(row, 'smc_means')} | {time} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
