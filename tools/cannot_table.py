"""Run (or resume) the cannot table: python tools/cannot_table.py --out runs/cannot [--seeds 5] [--targets ...]

Every cell is recorded as it finishes (runs/cannot/records/...); re-running the same command resumes. The parents'
children are kept in runs/cannot/library. One torch thread per process (set OMP_NUM_THREADS=1)."""

from __future__ import annotations

import argparse

from sb3_smc.common.threads import compute_threads
from sb3_smc.experiments.cannot import CANNOT_PARENTS, CANNOT_TARGETS, run_cannot


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", required=True)
    parser.add_argument("--targets", default=",".join(CANNOT_TARGETS))
    parser.add_argument("--parents", default=",".join(CANNOT_PARENTS), help="comma-separated; empty: none")
    parser.add_argument("--seeds", type=int, default=5, help="seeds 0 to N-1")
    parser.add_argument("--only-seeds", default=None, help="comma-separated seeds of those (a second process: 3,4)")
    parser.add_argument("--timesteps", type=int, default=None)
    args = parser.parse_args()
    settings = {"total_timesteps": args.timesteps} if args.timesteps else {}
    with compute_threads(1):
        path = run_cannot(args.out, targets=args.targets.split(","),
                          parents=[p for p in args.parents.split(",") if p],
                          seeds=[int(s) for s in args.only_seeds.split(",")] if args.only_seeds else args.seeds,
                          **settings)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
