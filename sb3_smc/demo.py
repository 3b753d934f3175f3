"""``python -m sb3_smc.demo`` (``make demo``): from a pixel world to a report of the paper's experiment, in minutes.

1. :func:`pixelworld_env.demo.play`: a hand-drawn scene played with a planner (bring-about) and at random
   (classification).
2. The paper's experiment on one level-2 concept, ``cl_self-in-container_vs_noncontainer``, at a reduced budget
   (two seeds, 100,000 steps per SMC instead of five and 400,000; two workers): the CNN baseline, a flat SMC
   (base) and the hand-designed curricula (curr: two curricula calling the corner and on-something SMCs, trained
   first), every SMC tested with the paper's protocol (50 test environments x 10 stochastic repeats).
3. The report: ``<out>/report.md`` with the paper's numbers beside ours and the figures (bars, trajectories, the
   timeline of a hierarchical episode) in ``<out>/figures/``.

Re-running continues where it stopped (the run is resumable); ``--out`` chooses the folder (default
``demo-output``), ``--no-train`` only plays the episodes.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from pixelworld_env.demo import play
from sb3_smc.curricula.run_directory import RunSettingsError
from sb3_smc.experiments.report import write_report
from sb3_smc.experiments.runner import run_experiment

TARGET = "cl_self-in-container_vs_noncontainer"
METHODS = ("cnn", "base", "curr")


def experiment(out: str | Path = "demo-output", seed_count: int = 2, timesteps: int = 100_000,
               workers: int = 2) -> Path:
    """Run the small experiment into ``out`` and write its report; returns the report's path."""
    import torch  # only for the experiment: the play-only demo loads no torch

    torch.set_num_threads(1)
    start = time.perf_counter()
    print(f"\nthe paper's experiment on {TARGET}: methods {', '.join(METHODS)}, {seed_count} seed(s), "
          f"{timesteps:,} steps per SMC (the paper: 5 seeds, 400,000 steps) -> {out}/")
    try:
        results = run_experiment(out, methods=METHODS, targets=[TARGET], seeds=seed_count, timesteps=timesteps,
                                 workers=workers)
    except RunSettingsError as error:
        raise SystemExit(f"{out} holds a demo run with other settings (an earlier version's budget?): remove it "
                         f"(rm -rf {out}) or pass --out DIR.\n{error}") from None
    [report] = write_report(out)
    print(f"\n{'method':8s} {'test score':>10s}  (best seed; curr: best of its curricula)")
    for row in results["reported"]:
        print(f"{row['method']:8s} {100 * row['test_score']:9.1f}%  {row['curriculum']}")
    print(f"\nreport: {report} (figures in {Path(out) / 'figures'}); library of trained SMCs: {Path(out) / 'library'}; "
          f"{time.perf_counter() - start:.0f} s")
    return report


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seed", type=int, default=0, help="episode seed of the played episodes")
    parser.add_argument("--quiet", action="store_true", help="print only the episode summaries")
    parser.add_argument("--no-train", action="store_true", help="only play the episodes")
    parser.add_argument("--out", default="demo-output", help="the experiment folder (default demo-output)")
    parser.add_argument("--timesteps", type=int, default=100_000, help="steps per SMC (default 100,000)")
    parser.add_argument("--seeds", type=int, default=2, help="seeds per SMC (default 2)")
    parser.add_argument("--workers", type=int, default=2, help="training processes (default 2)")
    args = parser.parse_args()
    play(seed=args.seed, quiet=args.quiet)
    if not args.no_train:
        experiment(args.out, seed_count=args.seeds, timesteps=args.timesteps, workers=args.workers)


if __name__ == "__main__":
    main()
