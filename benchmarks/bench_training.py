"""SMC training throughput: environment steps per second, side by side in one run.

Cases (all from freshly initialised, signal-biased policies, ``train_smc`` defaults: 16 envs x 125 steps = 2,000
steps per update, paper-sized networks):

* flat RecurrentPPO (LSTM 32) and flat TRPO (MLP 32) on ``cl_self-in-left-corner_vs_on-hline``, with 1 and 2
  torch threads; the same task with the other recurrent learners (RecurrentPPO GRU 32, RecurrentTRPO LSTM and
  GRU 32; docs/learners.md), 1 thread;
* level-2 RecurrentPPO on ``cl_self-in-container_vs_noncontainer`` with the 13 SMCs of the canonical containment
  curriculum as actions (untrained children: freshly initialised RecurrentPPO models with the bias rule, so a
  call lasts about 41 decisions, as early in the paper's training), and with the three SMCs of the level-2 test.

Reported: decisions (SB3 environment steps: a move, a signal or a whole SMC call) per second and primitive
environment steps per second (primitive actions executed on the world: moves, those made inside calls included,
and the SMC's own signals; for a flat SMC the two are equal). The timing covers
``model.learn`` only (environment construction and model set-up excluded), best of ``--repeats`` runs.

Run: ``python benchmarks/bench_training.py [--updates N] [--repeats R] [--quick]``.
"""

from __future__ import annotations

import argparse

import torch

import pixelworld_env  # noqa: F401  (registers the PW-* ids)
from pixelworld_env.datasets import catalog
from sb3_smc.learning.training import train_smc, untrained_smc

FLAT = "PW-cl_self-in-left-corner_vs_on-hline-v0"
LEVEL2 = "PW-cl_self-in-container_vs_noncontainer-v0"
LEVEL2_CHILDREN = ("cl_self-in-left-corner_vs_on-hline", "cl_self-in-right-corner_vs_on-hline",
                   "ba_self-on-something_from_directly-above")


def canonical_children() -> list[str]:
    return [dataset for _, dataset in catalog.canonical_smc_lists()["canonical_containment_curriculum"]]


def untrained(names: list[str] | tuple[str, ...]):
    return [untrained_smc(f"PW-{name}-v0", n_envs=1, seed=k) for k, name in enumerate(names)]


def measure(env_id: str, *, algo: str, updates: int, threads: int, repeats: int, children=None,
            rnn: str | None = None) -> dict:
    torch.set_num_threads(threads)
    best = None
    for repeat in range(repeats):
        smc = train_smc(env_id, algo=algo, total_timesteps=2000 * updates, seed=repeat, children=children, rnn=rnn)
        record = smc.record
        row = {"decisions/s": record.total_timesteps / record.wall_time_s,
               "primitive/s": record.primitive_steps / record.wall_time_s, "seconds": record.wall_time_s}
        if best is None or row["decisions/s"] > best["decisions/s"]:
            best = row
    torch.set_num_threads(1)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--updates", type=int, default=10, help="updates (2,000 steps each) per measurement")
    parser.add_argument("--repeats", type=int, default=2, help="runs per case (the best is reported)")
    parser.add_argument("--quick", action="store_true", help="skip the 2-thread and 3-children cases")
    args = parser.parse_args()
    torch.set_num_threads(1)

    cases: list[tuple[str, dict]] = []
    for algo in ("RecurrentPPO", "TRPO"):
        for threads in (1,) if args.quick else (1, 2):
            cases.append((f"flat {algo}, {threads} thread{'s' * (threads > 1)}",
                          {"env_id": FLAT, "algo": algo, "threads": threads}))
    for algo, rnn in (("RecurrentPPO", "gru"), ("RecurrentTRPO", "lstm"), ("RecurrentTRPO", "gru")):
        cases.append((f"flat {algo} {rnn.upper()}, 1 thread", {"env_id": FLAT, "algo": algo, "threads": 1, "rnn": rnn}))
    children13 = untrained(canonical_children())
    cases.append(("level-2 RecurrentPPO, 13 untrained children, 1 thread",
                  {"env_id": LEVEL2, "algo": "RecurrentPPO", "threads": 1, "children": children13}))
    if not args.quick:
        children3 = untrained(LEVEL2_CHILDREN)
        cases.append(("level-2 RecurrentPPO, 3 untrained children, 1 thread",
                      {"env_id": LEVEL2, "algo": "RecurrentPPO", "threads": 1, "children": children3}))

    results = []
    for label, case in cases:
        row = measure(updates=args.updates, repeats=args.repeats, **case)
        results.append((label, row))
        print(f"{label}: {row['decisions/s']:,.0f} decisions/s, {row['primitive/s']:,.0f} primitive steps/s",
              flush=True)

    flat_rate = results[0][1]["decisions/s"]
    print(f"\n{args.updates} updates x 2,000 decisions per case, best of {args.repeats}; "
          f"torch {torch.__version__}\n")
    print("| case | decisions/s | primitive steps/s | primitive / flat RecurrentPPO |")
    print("|---|---:|---:|---:|")
    for label, row in results:
        print(f"| {label} | {row['decisions/s']:,.0f} | {row['primitive/s']:,.0f} | "
              f"{row['primitive/s'] / flat_rate:.2f} |")


if __name__ == "__main__":
    main()
