"""Many SMCs per process (``sb3_smc.learning.batched.train_smcs``) beside ``train_smc`` and stock sb3-contrib, in one
run.

Cases, each in its own subprocess (one torch thread), on ``cl_self-in-left-corner_vs_on-hline``, ``--timesteps``
steps per SMC, the whole budget (no early stop), the defaults otherwise (16 environments x 125 steps, LSTM 32, one
2,000-step minibatch, 4 epochs):

* stock: sb3-contrib ``RecurrentPPO`` with ``MlpLstmPolicy`` and its own rollout buffer, the same hyperparameters
  and environment (``train_smc``'s vector env); ``learn`` timed;
* ``train_smc``: ``learn`` timed (the record's ``wall_time_s``) and the whole call (model set-up included);
* ``train_smcs`` with K = 1 and K = 5 seeds: the whole call (vector env and models built inside);
* with ``--lean``, also ``train_smc`` and ``train_smcs`` with ``lean_update=True`` (compared with ``train_smc``'s
  lean SMC of the same seed);
* with ``--algo RecurrentTRPO --rnn gru``, the ``train_smc`` / ``train_smcs`` cases (``--lean`` ones included)
  with the paper's learner (stock stays sb3-contrib's ``RecurrentPPO``, the issue's yardstick).

Each case first runs once with ``--warm-up`` steps per SMC in the same process, untimed (its time is reported):
the process's one-time costs (the lazy imports, among them torch's dynamo at the first optimizer, about 3 s;
numba's cached kernels) are then paid, as they are in a curriculum run's worker after its first job, and the timed
run is the training's own rate. ``--warm-up 0`` times a fresh process's first call instead.

Reported: environment steps per second over all SMCs of a case (per core: one process, one thread), the ratio to
stock, the peak resident memory of the process, and whether each batched SMC equals ``train_smc``'s of its seed
(training returns; the tests compare the weights).

With ``--baseline DIR`` (a checkout of an earlier commit, such as ``git worktree add /tmp/base <commit>``), the
``train_smcs`` cases (the lean ones with ``--lean``) also run from it, alternating with this tree's: a before/after
pair in one run.

Run: ``python benchmarks/bench_batched.py [--timesteps N] [--repeats R] [--k K ...] [--lean] [--algo A --rnn R]
[--baseline DIR]``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]
ENV_ID = "PW-cl_self-in-left-corner_vs_on-hline-v0"

_JOB = """
import json, resource, sys, time, torch
torch.set_num_threads(1)
from sb3_smc.records import TrainingSpec
from sb3_smc.learning.training import train_smc
from sb3_smc.learning.batched import train_smcs
case, env_id, steps, k, learner = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), json.loads(sys.argv[5])
warm_up = int(sys.argv[6])
lean = case.endswith("-lean")

def run(steps):
    \"\"\"The case for ``steps`` per SMC: seconds, steps in all, training returns, learn's seconds.\"\"\"
    specs = [TrainingSpec.create(env_id, total_timesteps=steps, seed=s, **learner) for s in range(k)]
    if case == "stock":
        from sb3_contrib import RecurrentPPO
        from stable_baselines3.common.logger import Logger
        from sb3_smc.core.hyperparameters import constructor_arguments
        from sb3_smc.learning.training import make_vec_env
        _, settings = constructor_arguments(TrainingSpec.create(env_id).hyperparameters)  # stock: RecurrentPPO
        model = RecurrentPPO("MlpLstmPolicy", make_vec_env(specs[0]), n_steps=specs[0].budget.env_steps, seed=0,
                             device="cpu", verbose=0, **settings)
        model.set_logger(Logger(folder=None, output_formats=[]))
        start = time.perf_counter()
        model.learn(steps)
        return time.perf_counter() - start, model.num_timesteps, [], None
    if case.startswith("train_smc") and not case.startswith("train_smcs"):
        start = time.perf_counter()
        smc = train_smc(specs[0], log_every=0, stop_at_max_return=False, lean_update=lean)
        seconds = time.perf_counter() - start
        return seconds, smc.record.total_timesteps, [smc.record.training_returns], smc.record.wall_time_s
    start = time.perf_counter()
    smcs = train_smcs(specs, stop_at_max_return=False, lean_update=lean)
    seconds = time.perf_counter() - start
    return seconds, sum(s.record.total_timesteps for s in smcs), [s.record.training_returns for s in smcs], None

cold = run(warm_up)[0] if warm_up else None
seconds, total, returns, learn = run(steps)
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(json.dumps({"seconds": seconds, "steps": total, "peak_mib": peak, "returns": returns, "learn": learn,
                  "cold": cold}))
"""


def run(case: str, timesteps: int, k: int = 1, learner: dict | None = None, root: Path = HERE,
        warm_up: int = 2_000) -> dict:
    env = {**os.environ, "PYTHONPATH": str(root), "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    out = subprocess.run([sys.executable, "-c", _JOB, case, ENV_ID, str(timesteps), str(k), json.dumps(learner or {}),
                          str(warm_up)],
                         env=env,
                         capture_output=True, text=True, check=True)
    return json.loads([line for line in out.stdout.splitlines() if line.startswith("{")][-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--timesteps", type=int, default=64_000, help="steps per SMC")
    parser.add_argument("--repeats", type=int, default=1, help="runs per case, alternating (the best is kept)")
    parser.add_argument("--k", type=int, nargs="+", default=[1, 5], help="group sizes of train_smcs")
    parser.add_argument("--lean", action="store_true", help="also the cases with lean_update=True")
    parser.add_argument("--algo", default=None, help="the learner of the train_smc(s) cases (stock stays "
                        "RecurrentPPO): RecurrentTRPO for the paper's")
    parser.add_argument("--rnn", default=None, help="their recurrent cell: gru for the paper's")
    parser.add_argument("--baseline", type=Path, default=None, help="a checkout of an earlier commit (a git "
                        "worktree): its train_smcs cases (the lean ones with --lean) run too, alternating")
    parser.add_argument("--warm-up", type=int, default=2_000, help="steps per SMC of a first, untimed run of each "
                        "case in its process (0: none, the timed run pays the process's one-time costs)")
    args = parser.parse_args()
    learner = {key: value for key, value in (("algo", args.algo), ("rnn", args.rnn)) if value is not None}
    cases = [("stock", 1), ("train_smc", 1), *(("train_smcs", k) for k in args.k)]
    if args.lean:
        cases += [("train_smc-lean", 1), *(("train_smcs-lean", k) for k in args.k)]
    if args.baseline is not None:
        cases += [("before:train_smcs" + ("-lean" if args.lean else ""), k) for k in args.k]
    best: dict[tuple[str, int], dict] = {}
    for _ in range(args.repeats):
        for case, k in cases:
            root = args.baseline if case.startswith("before:") else HERE
            result = run(case.removeprefix("before:"), args.timesteps, k, None if case == "stock" else learner,
                         root.resolve(), args.warm_up)
            if (case, k) not in best or result["seconds"] < best[case, k]["seconds"]:
                best[case, k] = result
    alone = {"": best["train_smc", 1]["returns"][0]}
    if args.lean:
        alone["-lean"] = best["train_smc-lean", 1]["returns"][0]
    stock = best["stock", 1]["steps"] / best["stock", 1]["seconds"]
    print(f"{args.timesteps:,} steps per SMC, {ENV_ID}, one torch thread, best of {args.repeats}"
          f"{', learner ' + json.dumps(learner) if learner else ''}, "
          + (f"after a warm-up of {args.warm_up:,} steps per SMC in the same process\n" if args.warm_up
             else "no warm-up\n"))
    print("| case | SMCs | seconds | steps/s (per core) | x stock | peak memory (MiB) | same as train_smc "
          "| warm-up: s |")
    print("|---|---:|---:|---:|---:|---:|---|---:|")
    for case, k in cases:
        row = best[case, k]
        rate = row["steps"] / row["seconds"]
        before = case.startswith("before:")
        base, lean = case.removeprefix("before:").removesuffix("-lean"), "-lean" if case.endswith("-lean") else ""
        label = {"stock": "stock sb3-contrib RecurrentPPO (`learn`)", "train_smc": "`train_smc` (whole call)",
                 "train_smcs": f"`train_smcs`, K = {k} (whole call)"}[base]
        label += ", `lean_update=True`" if lean else ""
        label += f" (baseline `{args.baseline}`)" if before else ""
        same = "" if case == "stock" or before else ("yes" if row["returns"][0] == alone[lean] else "NO")
        cold = f"{row['cold']:.2f}" if row["cold"] is not None else ""
        print(f"| {label} | {k} | {row['seconds']:.2f} | {rate:,.0f} | {rate / stock:.2f} | {row['peak_mib']:.0f} | "
              f"{same} | {cold} |")
        if base == "train_smc":
            learn = best[case, k]["learn"]
            print(f"| `train_smc` (`learn` only){', lean' if lean else ''} | 1 | {learn:.2f} | "
                  f"{row['steps'] / learn:,.0f} | "
                  f"{row['steps'] / learn / stock:.2f} | | | |")


if __name__ == "__main__":
    main()
