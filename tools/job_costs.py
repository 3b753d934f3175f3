"""What a run's jobs cost, level by level, from the records in its library: how much a level-2 job costs beside a
flat one, and how much of that is its children's moves.

    python tools/job_costs.py runs/objcon-lean [runs/containment-lean ...]

With several runs, their jobs are also pooled in one table (each run's nodes its own).

Per run and level (1: flat SMCs; 1 + the highest level of an SMC's children): the jobs, the median of their recorded
seconds (an SMC trained in a group records its share of the group's time) and of their microseconds per decision,
the primitive moves per decision (all the level's moves over all its decisions; a flat SMC's decisions are moves),
and the ratios of the medians to the flat jobs', per job and per decision (the decisions of a job differ between
levels where early stopping ends jobs at different updates). For each level above 1, a least-squares fit over its
nodes of microseconds per decision against moves per decision: what a decision costs besides its children's moves,
and what each move adds. Over nodes, not SMCs: the seeds of a node train as one group, and each records its share of
the group's time whatever its own moves (``node@seed`` names an SMC of a node). Medians, and a fit that leaves out
nodes above 3 times their level's median per decision: a run paused (or sharing its machine) lengthens the records
of the jobs running meanwhile, and the records cannot say so.

Reads only the library's manifest (checked as on load; no model is loaded). Bad input is refused before any output.
"""

from __future__ import annotations

import argparse
import functools
import sys
from pathlib import Path

import numpy as np

from sb3_smc.errors import SMCError
from sb3_smc.library import storage
from sb3_smc.library.manifest import LibraryEntry

Job = tuple[str, float, int, int]
"""A trained SMC's node (its name without ``@seed``), recorded seconds, decisions and primitive moves."""


def jobs_by_level(entries: dict[str, LibraryEntry]) -> dict[int, list[Job]]:
    """The trained SMCs' records grouped by level (SMCs without a training record are left out)."""
    @functools.cache
    def level(name: str) -> int:
        children = entries[name].children
        return 1 + max(level(child) for child in children) if children else 1

    levels: dict[int, list[Job]] = {}
    for name, entry in entries.items():
        record = entry.record
        if record is not None and record.total_timesteps > 0:
            levels.setdefault(level(name), []).append(
                (name.rpartition("@")[0] or name, record.wall_time_s, record.total_timesteps, record.primitive_steps))
    return levels


def fit(jobs: list[Job]) -> tuple[float, float, float, int]:
    """Microseconds per decision = a + b x moves per decision over the nodes of ``jobs`` (each node's seconds,
    decisions and moves summed over its seeds), the nodes above 3 times the median per decision left out:
    ``(a, b, R^2, nodes left out)``."""
    nodes: dict[str, list[float]] = {}
    for node, seconds, decisions, moves in jobs:
        total = nodes.setdefault(node, [0.0, 0.0, 0.0])
        total[0] += seconds
        total[1] += decisions
        total[2] += moves
    sums = np.array(list(nodes.values()))
    us, per_decision = 1e6 * sums[:, 0] / sums[:, 1], sums[:, 2] / sums[:, 1]
    kept = us <= 3 * np.median(us)
    us, per_decision = us[kept], per_decision[kept]
    design = np.c_[np.ones(len(us)), per_decision]
    (a, b), *_ = np.linalg.lstsq(design, us, rcond=None)
    spread = float(((us - us.mean()) ** 2).sum())
    r2 = 1.0 - float(((design @ (a, b) - us) ** 2).sum()) / spread if spread else 1.0
    return float(a), float(b), r2, int((~kept).sum())


def table(run: Path, levels: dict[int, list[Job]]) -> list[str]:
    """The run's table, level by level (see the module's docstring)."""
    lines = [f"{run}", "", "| level | jobs | median job (s) | median us per decision | moves per decision "
             "| x flat per job | x flat per decision | fit over nodes: us per decision + us per move (R^2; left out) |",
             "|---|---:|---:|---:|---:|---:|---:|---|"]

    def medians(jobs: list[Job]) -> tuple[float, float]:
        return (float(np.median([j[1] for j in jobs])), float(np.median([1e6 * j[1] / j[2] for j in jobs])))

    flat = medians(levels[1]) if 1 in levels else None
    for level in sorted(levels):
        jobs = levels[level]
        per_job, per_decision = medians(jobs)
        moves = sum(j[3] for j in jobs) / sum(j[2] for j in jobs)
        ratios = (f"{per_job / flat[0]:.2f}", f"{per_decision / flat[1]:.2f}") if flat else ("", "")
        fitted = ""
        if level > 1 and len({j[0] for j in jobs}) > 2:
            a, b, r2, left_out = fit(jobs)
            fitted = f"{a:.1f} + {b:.2f} x moves ({r2:.2f}; {left_out})"
        lines.append(f"| {level} | {len(jobs)} | {per_job:.1f} | {per_decision:.1f} | {moves:.1f} | {ratios[0]} "
                     f"| {ratios[1]} | {fitted} |")
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("runs", type=Path, nargs="+", help="run directories of sb3-smc experiment or train")
    args = parser.parse_args(argv)
    read = []
    for run in args.runs:
        try:
            entries = storage.checked_entries(run / "library")[0]
        except (OSError, SMCError) as error:
            parser.error(f"{run}: not a run with a library ({error})")
        levels = jobs_by_level(entries)
        if not levels:
            parser.error(f"{run}/library: no SMC with a training record")
        read.append((run, levels))
    for run, levels in read:
        print("\n".join(table(run, levels)) + "\n")
    if len(read) > 1:
        pooled: dict[int, list[Job]] = {}
        for run, levels in read:
            for level, jobs in levels.items():
                pooled.setdefault(level, []).extend((f"{run}/{node}", seconds, decisions, moves)
                                                    for node, seconds, decisions, moves in jobs)
        print("\n".join(table(Path(f"the {len(read)} runs pooled"), pooled)) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
