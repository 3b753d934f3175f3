"""Level-2 versus flat training time with trained children, this tree beside a baseline checkout, in one run.

The speed issue's measure: on ``cl_self-in-container_vs_noncontainer``, a flat RecurrentPPO job and a level-2 job
whose actions include the three trained SMCs of the level-2 test (``cl_self-in-left-corner_vs_on-hline``,
``cl_self-in-right-corner_vs_on-hline``, ``ba_self-on-something_from_directly-above``), both at the full budget
(400,000 steps, 16 environments, one torch thread). The children are trained once (seed 0, current code) into a
library under ``--cache`` and reused; every measured job runs in its own subprocess, alternating between the trees
(``PYTHONPATH`` = the tree), so both see the same machine state. ``--children untrained`` uses the same three
SMCs freshly initialised (signal bias only): calls of about 40 decisions, as early in a curriculum. Reported: wall
time of ``model.learn``, decisions per second, the level-2 / flat ratio, and the selected update and training
return.

``--entry NODE`` measures a real curriculum entry instead (a level-2 node of a shipped curriculum, such as the
headline's ``con2-ba/ba_self-in-container_from_between-potential-containers_curr-in``): its target, and as children
its lower-level nodes trained with seeds ``0 .. --child-seeds - 1`` (the trainer gives a level-2 node the two best
of five seeds of each; here the first ones, the same count of SMC actions), every job with the default
hyperparameters and primitive moves (what the shipped `curr` entries use). Its children walk across the world, so
its calls are long, as in the headline runs.

Run: ``python benchmarks/bench_level2.py [--baseline PATH] [--timesteps N] [--repeats R] [--children KIND]
[--entry NODE [--child-seeds K]]``; make a baseline checkout with ``git worktree add /tmp/baseline <commit>``.
Without ``--baseline`` only this tree is measured.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

TARGET = "cl_self-in-container_vs_noncontainer"
CHILDREN = ("cl_self-in-left-corner_vs_on-hline", "cl_self-in-right-corner_vs_on-hline",
            "ba_self-on-something_from_directly-above")
HERE = Path(__file__).resolve().parents[1]

_JOB = """
import json, sys, torch
torch.set_num_threads(1)
import pixelworld_env
from sb3_smc import SMCLibrary, train_smc
library_path, level2, timesteps = sys.argv[1], sys.argv[2] == "1", int(sys.argv[3])
children = list(SMCLibrary.load(library_path).values()) if level2 else None
smc = train_smc("PW-" + sys.argv[4] + "-v0", children=children, total_timesteps=timesteps, seed=0, log_every=0)
r = smc.record
print(json.dumps({"seconds": r.wall_time_s, "decisions": r.total_timesteps, "primitive": r.primitive_steps,
                  "selected_update": r.selected_update, "selected_return": r.selected_return}))
"""


def entry_tasks(node: str) -> tuple[str, tuple[str, ...]]:
    """A shipped curriculum node's target dataset and the datasets of the (flat) nodes it uses."""
    from sb3_smc.curricula import resolve_curriculum

    curriculum = resolve_curriculum(node.partition("/")[0])
    entry = curriculum.node(node)
    used = [curriculum.node(name) for name in entry.uses]
    if not used or any(u.uses for u in used):
        raise SystemExit(f"--entry {node}: needs a level-2 node whose children are flat nodes")
    return entry.task, tuple(u.task for u in used)


def train_children(cache: Path, trained: bool, tasks: tuple[str, ...] = CHILDREN, seeds: int = 1,
                   name: str | None = None) -> Path:
    """The children library (trained, or freshly initialised with the signal bias, with this tree on first use)."""
    library = cache / (name or ("children" if trained else "untrained-children"))
    if (library / "manifest.json").exists():
        return library
    import torch

    torch.set_num_threads(1)
    import pixelworld_env  # noqa: F401
    from sb3_smc import SMCLibrary, train_smc
    from sb3_smc.learning.training import untrained_smc

    smcs = []
    for task in tasks:
        for seed in range(seeds):
            print(f"{'training' if trained else 'initialising'} child {task} seed {seed} ...", flush=True)
            if trained:
                smcs.append(train_smc(f"PW-{task}-v0", seed=seed, log_every=0, name=f"{task}@{seed}"))
            else:
                smcs.append(untrained_smc(f"PW-{task}-v0", seed=seed, name=f"{task}@{seed}"))
    SMCLibrary(smcs).save(library)
    return library


def run_job(tree: Path, library: Path, level2: bool, timesteps: int, target: str = TARGET) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree), OMP_NUM_THREADS="1")
    out = subprocess.run([sys.executable, "-c", _JOB, str(library), "1" if level2 else "0", str(timesteps),
                          target],
                         env=env, capture_output=True, text=True, check=True, cwd=tree)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--baseline", type=Path, help="a checkout of the code to compare with")
    parser.add_argument("--timesteps", type=int, default=400_000)
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--children", choices=("trained", "untrained"), default="trained",
                        help="trained children (short calls) or freshly initialised ones (calls of ~40 decisions, "
                             "as early in a curriculum)")
    parser.add_argument("--cache", type=Path, default=Path(os.environ.get("TMPDIR", "/tmp")) / "sb3smc-bench-level2")
    parser.add_argument("--entry", help="a level-2 node of a shipped curriculum: its target and real children")
    parser.add_argument("--child-seeds", type=int, default=2, help="seeds per child node with --entry (default 2)")
    args = parser.parse_args()
    target = TARGET
    if args.entry:
        target, tasks = entry_tasks(args.entry)
        library = train_children(args.cache, args.children == "trained", tasks, args.child_seeds,
                                 f"{args.entry.replace('/', '%2F')}-{args.children}-{args.child_seeds}")
    else:
        library = train_children(args.cache, args.children == "trained")
    trees = ([("baseline", args.baseline.resolve())] if args.baseline else []) + [("this tree", HERE)]
    best: dict[tuple[str, str], dict] = {}
    for repeat in range(args.repeats):
        for case, level2 in (("flat", False), ("level-2", True)):
            for label, tree in trees:
                row = run_job(tree, library, level2, args.timesteps, target)
                print(f"[{repeat + 1}/{args.repeats}] {label:9s} {case:7s} {row['seconds']:7.1f} s  "
                      f"update {row['selected_update']}  return {row['selected_return']}", flush=True)
                key = (label, case)
                if key not in best or row["seconds"] < best[key]["seconds"]:
                    best[key] = row
    print(f"\n{args.timesteps:,} steps on {target}, {args.children} children, one torch thread, best of "
          f"{args.repeats}\n")
    print("| code | flat s | level-2 s | level-2 / flat | level-2 decisions/s | level-2 primitive steps/s |")
    print("|---|---|---|---|---|---|")
    for label, _ in trees:
        flat, level2 = best[(label, "flat")], best[(label, "level-2")]
        ratio = level2["seconds"] / flat["seconds"]
        print(f"| {label} | {flat['seconds']:.1f} | {level2['seconds']:.1f} | {ratio:.2f} "
              f"| {level2['decisions'] / level2['seconds']:,.0f} | {level2['primitive'] / level2['seconds']:,.0f} |")


if __name__ == "__main__":
    main()
