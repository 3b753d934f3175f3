"""A flat SMC's training job in the native vector env (``FlatSMCVecEnv``, what ``train_smc`` uses) beside
``SMCVecEnv`` over ``HierarchicalSMCWrapper`` environments (what it used before), in one run.

Each job is ``train_smc(id, algo=..., total_timesteps=N, seed=0)`` with the defaults (16 environments, one torch
thread), run in its own subprocess, alternating between the two environments so that both see the same machine
state. Reported per id and algorithm: wall time of ``model.learn`` (the record's ``wall_time_s``), steps per second,
the ratio, and whether both trained the same SMC (the same training returns: they must, the transitions are the
same).

Run: ``python benchmarks/bench_flat_job.py [--timesteps N] [--repeats R] [--algos A ...] [--ids ID ...]``.
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
IDS = ("PW-cl_self-in-container_vs_noncontainer-v0", "PW-ba_self-in-container-v0")

_JOB = """
import functools, json, sys, torch
torch.set_num_threads(1)
import sb3_smc.learning.training as training
env_id, algo, timesteps, native = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4] == "1"
if not native:
    training.make_vec_env = functools.partial(training.make_vec_env, native=False)
smc = training.train_smc(env_id, algo=algo, total_timesteps=timesteps, seed=0, log_every=0)
print(json.dumps({"seconds": smc.record.wall_time_s, "returns": smc.record.training_returns}))
"""


def run_job(env_id: str, algo: str, timesteps: int, native: bool) -> dict:
    env = {**os.environ, "PYTHONPATH": str(HERE), "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    out = subprocess.run([sys.executable, "-c", _JOB, env_id, algo, str(timesteps), "1" if native else "0"],
                         env=env, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--timesteps", type=int, default=100_000)
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--algos", nargs="+", default=["RecurrentPPO", "TRPO"])
    parser.add_argument("--ids", nargs="+", default=list(IDS))
    args = parser.parse_args()
    print(f"{args.timesteps:,} steps per job, {args.repeats} repeats, one torch thread\n")
    print("| id | algorithm | SMCVecEnv (s) | FlatSMCVecEnv (s) | speed-up | steps/s native | same SMC |")
    print("|---|---|---:|---:|---:|---:|---|")
    for env_id in args.ids:
        for algo in args.algos:
            times: dict[bool, list[float]] = {False: [], True: []}
            returns: dict[bool, list] = {}
            for _ in range(args.repeats):
                for native in (False, True):
                    result = run_job(env_id, algo, args.timesteps, native)
                    times[native].append(result["seconds"])
                    returns[native] = result["returns"]
            before, after = statistics.median(times[False]), statistics.median(times[True])
            same = "yes" if returns[False] == returns[True] else "NO"
            print(f"| {env_id} | {algo} | {before:.2f} | {after:.2f} | {before / after:.2f}x | "
                  f"{args.timesteps / after:,.0f} | {same} |", flush=True)


if __name__ == "__main__":
    main()
