"""The jobs of a real run, trained again for a few updates: this tree beside a baseline checkout, in one run.

A run directory of ``sb3-smc experiment`` or ``sb3-smc train`` (for example ``/work/runs/paper-readings`` of
``tools/paper_table.sh``) holds every trained SMC's spec and, in its library, the children it called. This takes the
seeds of one node, shortens their budget to ``--updates`` updates and trains them as the curriculum trainer does
(``train_smcs``: one group, children from the run's library, the lean update where the run's records say it trained
with it, one torch and one BLAS thread), each tree in its own
subprocess (``PYTHONPATH`` = the tree), alternating, ``--repeats`` rounds. Reported per round: wall seconds of the
group's training, decisions per second and the primitive moves made, which must be the same in both trees where
the change keeps the SMCs.

Run: ``python benchmarks/bench_run_jobs.py RUN NODE [--seeds 0 1 2 3 4] [--updates 6] [--repeats 3]
[--baseline PATH]``; make a baseline checkout with ``git worktree add /tmp/baseline <commit>``. ``NODE`` is a job
name without its seed (``curr-cap50/search2/ba_self-in-target-container_from_nontarget-container``).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]

_JOB = """
import dataclasses, json, sys, time, torch
torch.set_num_threads(1)
from sb3_smc.learning.batched import train_smcs
from sb3_smc.library import SMCLibrary
from sb3_smc.records import TrainingSpec
root, node, updates = sys.argv[1], sys.argv[2], int(sys.argv[3])
manifest = json.loads(open(root + "/library/manifest.json").read())["smcs"]
specs = [TrainingSpec.from_dict(manifest[f"{node}@{seed}"]["spec"]) for seed in sys.argv[4:]]
lean = {"lean_update": True} if manifest[f"{node}@{sys.argv[4]}"]["record"].get("lean_update") else {}
specs = [dataclasses.replace(s, budget=dataclasses.replace(s.budget, total_timesteps=2000 * updates)) for s in specs]
children = sorted({c for s in specs for c in s.children})
library = SMCLibrary.load(root + "/library", names=children) if children else None
warm = [dataclasses.replace(s, budget=dataclasses.replace(s.budget, total_timesteps=2000)) for s in specs[:1]]
train_smcs(warm, children=library, log_every=0, **lean)  # compilation and first-time set-up
begin = time.perf_counter()
smcs = train_smcs(specs, children=library, log_every=0, **lean)
seconds = time.perf_counter() - begin
print(json.dumps({"seconds": seconds, "lean": bool(lean), "decisions": sum(s.record.total_timesteps for s in smcs),
                  "primitive": sum(s.record.primitive_steps for s in smcs)}))
"""


def run_group(tree: Path, run: Path, node: str, seeds: list[int], updates: int) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree), OMP_NUM_THREADS="1")
    out = subprocess.run([sys.executable, "-c", _JOB, str(run), node, str(updates), *map(str, seeds)],
                         env=env, capture_output=True, text=True, check=True, cwd=tree)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("run", type=Path, help="a run directory (its library/manifest.json holds the specs)")
    parser.add_argument("node", help="the job name without its seed")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    parser.add_argument("--updates", type=int, default=6, help="updates (2,000 steps) per SMC")
    parser.add_argument("--repeats", type=int, default=3, help="rounds, alternating between the trees")
    parser.add_argument("--baseline", type=Path, help="a checkout of the code to compare with")
    args = parser.parse_args()
    manifest = args.run / "library" / "manifest.json"
    if not manifest.is_file():
        raise SystemExit(f"{manifest}: not found (RUN must be a run directory with a library)")
    names = json.loads(manifest.read_text())["smcs"]
    missing = [seed for seed in args.seeds if f"{args.node}@{seed}" not in names]
    if missing:
        raise SystemExit(f"{manifest}: no SMC {args.node}@<seed> for seeds {missing}")
    trees = ([("baseline", args.baseline.resolve())] if args.baseline else []) + [("this tree", HERE)]
    rows: dict[str, list[dict]] = {label: [] for label, _ in trees}
    for repeat in range(args.repeats):
        for label, tree in trees:
            row = run_group(tree, args.run.resolve(), args.node, args.seeds, args.updates)
            rows[label].append(row)
            print(f"[{repeat + 1}/{args.repeats}] {label:9s} {row['seconds']:6.2f} s  "
                  f"{row['decisions'] / row['seconds']:,.0f} decisions/s  {row['primitive']:,} moves", flush=True)
    update = "the lean update" if rows[trees[-1][0]][0]["lean"] else "the default update"
    print(f"\n{args.node}, seeds {args.seeds} in one group, {args.updates} updates each, {update}, one torch thread\n")
    print("| code | seconds (rounds) | median | decisions/s (median) | primitive moves |")
    print("|---|---|---:|---:|---:|")
    for label, _ in trees:
        seconds = [row["seconds"] for row in rows[label]]
        middle = statistics.median(seconds)
        moves = sorted({row["primitive"] for row in rows[label]})
        print(f"| {label} | {' / '.join(f'{s:.2f}' for s in seconds)} | {middle:.2f} "
              f"| {rows[label][0]['decisions'] / middle:,.0f} | {', '.join(f'{m:,}' for m in moves)} |")


if __name__ == "__main__":
    main()
