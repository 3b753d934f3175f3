"""``python -m sb3_smc.demo`` (``make demo``): play PixelWorld episodes, then train, test, store and reload an SMC.

1. :func:`pixelworld_env.demo.play`: a hand-drawn scene played with a planner (bring-about) and at random
   (classification).
2. A short RecurrentPPO run (12 updates of 2,000 steps) of the SMC ``ba_self-on-something_from_directly-above``
   described by a :class:`~sb3_smc.records.TrainingSpec`, with the paper's signal-bias initialisation and
   best-update selection, tested with the paper's protocol before and after training.
3. The trained SMC saved in an :class:`~sb3_smc.library.SMCLibrary` (spec, training record and evaluation
   included) and loaded back.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from pixelworld_env.demo import play

DEMO_ENV = "PW-ba_self-on-something_from_directly-above-v0"


def train(seed: int = 0, total_timesteps: int = 24_000) -> tuple[float, float]:
    """Train a small flat SMC, return its test success rate before and after training; store it in a library."""
    import torch

    from sb3_smc import SMCLibrary, TrainingSpec, evaluate, train_smc

    torch.set_num_threads(1)
    spec = TrainingSpec.create(DEMO_ENV, seed=seed, total_timesteps=total_timesteps)
    untrained = train_smc(TrainingSpec.create(DEMO_ENV, seed=seed, total_timesteps=0))
    before = evaluate(untrained, repeats=4, seed=seed).score
    print(f"\ntraining SMC {spec.name!r} on {DEMO_ENV} for {spec.budget.total_timesteps:,} steps "
          f"({spec.algo}, {spec.budget.updates} updates of {spec.budget.steps_per_update:,} steps) ...")
    smc = train_smc(spec, log_every=2)
    result = evaluate(smc, repeats=4, seed=seed)
    record = smc.record
    print(f"test success rate (25 scenes x 4 runs): untrained {before:.2f} -> trained {result.score:.2f} "
          f"(selected update {record.selected_update}, training return {record.selected_return:.2f}, "
          f"{record.wall_time_s:.0f} s)")

    with tempfile.TemporaryDirectory() as tmp:
        path = SMCLibrary([smc]).save(Path(tmp) / "demo-library")
        loaded = SMCLibrary.load(path)[smc.name]
        print(f"saved to and loaded from an SMCLibrary: {loaded.name!r}, actions {list(loaded.action_names)}, "
              f"spec equal {loaded.spec == spec}, test score {loaded.test_score:.2f}")
    return before, result.score


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--quiet", action="store_true", help="print only the episode summaries")
    parser.add_argument("--no-train", action="store_true", help="only play the episodes")
    parser.add_argument("--timesteps", type=int, default=24_000, help="training budget of the demo SMC")
    args = parser.parse_args()
    play(seed=args.seed, quiet=args.quiet)
    if not args.no_train:
        train(seed=args.seed, total_timesteps=args.timesteps)


if __name__ == "__main__":
    main()
