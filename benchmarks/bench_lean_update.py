"""The lean PPO update (``train_smc(..., lean_update=True)``) beside ``train_smc`` and stock sb3-contrib, in one run.

Cases, each in its own subprocess (one torch thread, ``OMP_NUM_THREADS=1``), on
``cl_self-in-left-corner_vs_on-hline``, ``--timesteps`` steps, the whole budget (no early stop), the defaults
otherwise (16 environments x 125 steps, LSTM 32, one 2,000-step minibatch, 4 epochs):

* stock: sb3-contrib ``RecurrentPPO`` with ``MlpLstmPolicy`` and its own rollout buffer, the same hyperparameters
  and environment (``train_smc``'s vector env); ``learn`` timed;
* ``train_smc`` and ``train_smc(..., lean_update=True)``: the whole call and ``learn`` (the record's
  ``wall_time_s``);
* the update alone: a model trained 8,000 steps, then ``model.train()`` and
  :func:`~sb3_smc.common.recurrent.lean_update.lean_train` timed on its last rollout, alternating, from the same
  weights (the median of ``--calls`` calls each).

Reported: environment steps per second (per core: one process, one thread) and the ratio to stock; milliseconds per
update.

Run: ``python benchmarks/bench_lean_update.py [--timesteps N] [--repeats R] [--calls C]``.
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
import copy, json, sys, time
import numpy as np, torch
torch.set_num_threads(1)
from sb3_smc.records import TrainingSpec
from sb3_smc.learning.training import train_smc
case, env_id, steps, calls = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
spec = TrainingSpec.create(env_id, total_timesteps=steps, seed=0)
if case == "stock":
    from sb3_contrib import RecurrentPPO
    from stable_baselines3.common.logger import Logger
    from sb3_smc.core.hyperparameters import constructor_arguments
    from sb3_smc.learning.training import make_vec_env
    _, settings = constructor_arguments(spec.hyperparameters)
    model = RecurrentPPO("MlpLstmPolicy", make_vec_env(spec), n_steps=spec.budget.env_steps, seed=0, device="cpu",
                         verbose=0, **settings)
    model.set_logger(Logger(folder=None, output_formats=[]))
    start = time.perf_counter()
    model.learn(steps)
    seconds = time.perf_counter() - start
    print(json.dumps({"seconds": seconds, "learn": seconds, "steps": model.num_timesteps}))
elif case in ("train_smc", "lean"):
    start = time.perf_counter()
    smc = train_smc(spec, log_every=0, stop_at_max_return=False, lean_update=case == "lean")
    print(json.dumps({"seconds": time.perf_counter() - start, "learn": smc.record.wall_time_s,
                      "steps": smc.record.total_timesteps}))
else:
    from sb3_smc.common.recurrent.lean_update import lean_train
    model = train_smc(env_id, total_timesteps=8000, seed=1, log_every=0, stop_at_max_return=False).model
    state = copy.deepcopy(model.policy.state_dict())
    optimizer = copy.deepcopy(model.policy.optimizer.state_dict())
    times = {"stock": [], "lean": []}
    for i in range(calls + 1):
        for name, train in (("stock", model.train), ("lean", lambda: lean_train(model))):
            model.policy.load_state_dict(state)
            model.policy.optimizer.load_state_dict(copy.deepcopy(optimizer))
            start = time.perf_counter()
            train()
            if i:  # the first call of each warms up
                times[name].append(time.perf_counter() - start)
    print(json.dumps({name: float(np.median(t)) for name, t in times.items()}))
"""


def run(case: str, timesteps: int, calls: int) -> dict:
    env = {**os.environ, "PYTHONPATH": str(HERE), "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    out = subprocess.run([sys.executable, "-c", _JOB, case, ENV_ID, str(timesteps), str(calls)], env=env,
                         capture_output=True, text=True, check=True)
    return json.loads([line for line in out.stdout.splitlines() if line.startswith("{")][-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--timesteps", type=int, default=64_000, help="steps per SMC")
    parser.add_argument("--repeats", type=int, default=1, help="runs per case, alternating (the best is kept)")
    parser.add_argument("--calls", type=int, default=20, help="timed calls of each update")
    args = parser.parse_args()
    cases = ("stock", "train_smc", "lean")
    best: dict[str, dict] = {}
    for _ in range(args.repeats):
        for case in cases:
            result = run(case, args.timesteps, args.calls)
            if case not in best or result["seconds"] < best[case]["seconds"]:
                best[case] = result
    update = run("update", args.timesteps, args.calls)
    stock = best["stock"]["steps"] / best["stock"]["learn"]
    print(f"{args.timesteps:,} steps, {ENV_ID}, one torch thread, best of {args.repeats}\n")
    print("| case | whole call: s | steps/s (per core) | x stock | `learn`: s | steps/s (per core) | x stock |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    labels = {"stock": "stock sb3-contrib `RecurrentPPO` + `MlpLstmPolicy`", "train_smc": "`train_smc`",
              "lean": "`train_smc(..., lean_update=True)`"}
    for case in cases:
        row = best[case]
        whole, learn = row["steps"] / row["seconds"], row["steps"] / row["learn"]
        first = ("| | | |" if case == "stock" else
                 f"| {row['seconds']:.2f} | {whole:,.0f} | {whole / stock:.2f} |")
        print(f"| {labels[case]} {first} {row['learn']:.2f} | {learn:,.0f} | {learn / stock:.2f} |")
    print(f"\nOne update (4 epochs over 2,000 steps), median of {args.calls} calls: `model.train()` "
          f"{1000 * update['stock']:.1f} ms, `lean_train` {1000 * update['lean']:.1f} ms "
          f"({update['stock'] / update['lean']:.2f}x)")


if __name__ == "__main__":
    main()
