"""What stopping at the largest return saves: the same jobs with and without the stop, side by side.

``train_smc`` ends training once an update's mean training return is 1 (``sb3_smc.tasks.task.MAX_RETURN``): no later
update can be selected then, so the SMC is the one the whole budget gives, bit for bit. This measures, in one run,
400,000-step jobs trained both ways (one torch thread):

* a flat lower-level node, ``cl_self-in-container_vs_outside`` seed 1 (its whole budget selects update 18);
* a hand-designed level-2 node, ``con2-ba/ba_self-in-container_from_on-floor_curr-in`` seed 0, its children the
  shipped pretrained SMCs of ``con2-ba`` (8 SMC actions).

and checks that both ways select the same update with the same weights. Then, from the records of the paper's
table in ``docs/results/paper/*/results.csv`` (top-level jobs), the share of each method's training time that came
after the selected update in jobs whose selected return is 1: what the stop would have saved there.

Run: ``python benchmarks/bench_early_stop.py [--timesteps N]`` (about 5 minutes on an idle core).
"""

from __future__ import annotations

import argparse
import csv
import time
from collections import defaultdict
from pathlib import Path

import torch

from sb3_smc.curricula import shipped_curricula
from sb3_smc.curricula.jobs import node_spec
from sb3_smc.learning.training import train_smc
from sb3_smc.library import SMCLibrary
from sb3_smc.records import TrainingSpec
from sb3_smc.smc.smc import SMC
from sb3_smc.tasks.task import MAX_RETURN

ROOT = Path(__file__).resolve().parents[1]
FLAT = "PW-cl_self-in-container_vs_outside-v0"
LEVEL2 = ("con2-ba", "con2-ba/ba_self-in-container_from_on-floor_curr-in")


def level2_job(timesteps: int) -> tuple[TrainingSpec, list[SMC]]:
    """The level-2 node's spec (seed 0) and its children, the pretrained library's two best seeds of each node."""
    curriculum, name = LEVEL2
    library = SMCLibrary.pretrained(curriculum)
    node = shipped_curricula()[curriculum].node(name)
    children = tuple(n for use in node.uses for n in library.names if n.rsplit("@", 1)[0] == use)
    return node_spec(node, 0, children, timesteps=timesteps), [library[n] for n in children]


def both_ways(label: str, train) -> list[str]:
    """Train with and without the stop; the table row."""
    runs = {}
    for stop in (False, True):
        start = time.perf_counter()
        smc = train(stop)
        runs[stop] = (smc, time.perf_counter() - start)
    (whole, whole_s), (stopped, stopped_s) = runs[False], runs[True]
    first, second = whole.model.policy.state_dict(), stopped.model.policy.state_dict()
    same = (whole.record.selected_update == stopped.record.selected_update
            and all(torch.equal(first[k], second[k]) for k in first))
    return [label, f"{whole.record.selected_update}", f"{whole.record.selected_return:.3f}",
            f"{whole.record.updates} / {stopped.record.updates}", f"{whole_s:.1f}", f"{stopped_s:.1f}",
            f"{whole_s / stopped_s:.2f}x", "yes" if same else "NO"]


def saved_in_records() -> list[list[str]]:
    """Per method: top-level jobs of the committed table records, those selecting return 1, and the share of their
    training time after the selected update (200 updates per job)."""
    totals: dict[str, list[float]] = defaultdict(lambda: [0, 0, 0.0, 0.0])
    for path in sorted((ROOT / "docs" / "results" / "paper").glob("*/results.csv")):
        for row in csv.DictReader(path.open()):
            if row["method"] == "cnn" or not row["wall_time_s"]:
                continue
            entry = totals[row["method"]]
            wall = float(row["wall_time_s"])
            entry[0] += 1
            entry[2] += wall
            if row["training_return"] and float(row["training_return"]) >= MAX_RETURN:
                entry[1] += 1
                entry[3] += wall * (199 - int(row["selected_update"])) / 200
    return [[method, f"{int(n)}", f"{int(solved)}", f"{wall / 3600:.2f}", f"{saved / wall:.0%}"]
            for method, (n, solved, wall, saved) in sorted(totals.items())]


def table(header: list[str], rows: list[list[str]]) -> str:
    return "\n".join(["| " + " | ".join(header) + " |", "|" + "---|" * len(header),
                      *("| " + " | ".join(r) + " |" for r in rows)])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--timesteps", type=int, default=400_000)
    args = parser.parse_args()
    torch.set_num_threads(1)
    quiet = {"printer": lambda _: None, "log_every": 0}
    spec, children = level2_job(args.timesteps)
    rows = [
        both_ways("flat: cl_self-in-container_vs_outside@1",
                  lambda stop: train_smc(FLAT, seed=1, total_timesteps=args.timesteps, stop_at_max_return=stop,
                                         **quiet)),
        both_ways("level 2: ..._from_on-floor_curr-in@0 (8 SMC actions)",
                  lambda stop: train_smc(spec, children=children, stop_at_max_return=stop, **quiet)),
    ]
    print(table(["job", "selected update", "selected return", "updates run (whole / stopped)", "whole budget s",
                 "stopped s", "speed-up", "same SMC"], rows))
    print()
    print(table(["method (table records)", "top-level jobs", "selecting return 1", "training h",
                 "after the selected update"], saved_in_records()))


if __name__ == "__main__":
    main()
