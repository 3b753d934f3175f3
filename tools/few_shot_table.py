"""Run (or resume) the few-shot table: python tools/few_shot_table.py --out runs/few-shot [--worlds 4] [--targets ...]

Every cell is recorded as it finishes (runs/few-shot/records/...); re-running the same command resumes. One torch
thread per process (set OMP_NUM_THREADS=1)."""

from __future__ import annotations

import argparse

from sb3_smc.common.threads import compute_threads
from sb3_smc.experiments.few_shot import FEW_SHOT_METHODS, FEW_SHOT_TARGETS, FEW_SHOT_WORLDS, run_few_shot


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", required=True)
    parser.add_argument("--targets", default=",".join(FEW_SHOT_TARGETS))
    parser.add_argument("--worlds", default=",".join(str(n or "all") for n in FEW_SHOT_WORLDS),
                        help="comma-separated N (all: every training world)")
    parser.add_argument("--methods", default=",".join(FEW_SHOT_METHODS))
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--timesteps", type=int, default=None)
    args = parser.parse_args()
    worlds = [None if w == "all" else int(w) for w in args.worlds.split(",")]
    settings = {"total_timesteps": args.timesteps} if args.timesteps else {}
    with compute_threads(1):
        path = run_few_shot(args.out, targets=args.targets.split(","), worlds=worlds,
                            methods=args.methods.split(","), seeds=args.seeds, **settings)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
