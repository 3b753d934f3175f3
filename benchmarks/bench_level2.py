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

Run: ``python benchmarks/bench_level2.py [--baseline PATH] [--timesteps N] [--repeats R] [--children KIND]``;
make a baseline checkout with ``git worktree add /tmp/baseline <commit>``. Without ``--baseline`` only this tree
is measured.
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


def train_children(cache: Path, trained: bool) -> Path:
    """The children library (trained, or freshly initialised with the signal bias, with this tree on first use)."""
    library = cache / ("children" if trained else "untrained-children")
    if (library / "manifest.json").exists():
        return library
    import torch

    torch.set_num_threads(1)
    import pixelworld_env  # noqa: F401
    from sb3_smc import SMCLibrary, train_smc

    smcs = []
    for name in CHILDREN:
        print(f"{'training' if trained else 'initialising'} child {name} ...", flush=True)
        smcs.append(train_smc(f"PW-{name}-v0", seed=0, log_every=0, **({} if trained else {"total_timesteps": 0})))
    SMCLibrary(smcs).save(library)
    return library


def run_job(tree: Path, library: Path, level2: bool, timesteps: int) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree), OMP_NUM_THREADS="1")
    out = subprocess.run([sys.executable, "-c", _JOB, str(library), "1" if level2 else "0", str(timesteps),
                          TARGET],
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
    args = parser.parse_args()
    library = train_children(args.cache, args.children == "trained")
    trees = ([("baseline", args.baseline.resolve())] if args.baseline else []) + [("this tree", HERE)]
    best: dict[tuple[str, str], dict] = {}
    for repeat in range(args.repeats):
        for case, level2 in (("flat", False), ("level-2", True)):
            for label, tree in trees:
                row = run_job(tree, library, level2, args.timesteps)
                print(f"[{repeat + 1}/{args.repeats}] {label:9s} {case:7s} {row['seconds']:7.1f} s  "
                      f"update {row['selected_update']}  return {row['selected_return']}", flush=True)
                key = (label, case)
                if key not in best or row["seconds"] < best[key]["seconds"]:
                    best[key] = row
    print(f"\n{args.timesteps:,} steps on {TARGET}, {args.children} children, one torch thread, best of "
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
