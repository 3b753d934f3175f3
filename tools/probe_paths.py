"""The fewest moves from each world's start to a state where the concept holds, per bring-about dataset and split
(the breadth-first planner of ``pixelworld_env.generation.oracle``, pushing included), as a Markdown table
(docs/results/paper/README.md, "Where a method fails": are the worlds of one target harder to reach than its mirror
image's?).

    python tools/probe_paths.py ba_self-second_from_left_from_anywhere-on-floor \\
        ba_self-second_from_right_from_anywhere-on-floor
"""

from __future__ import annotations

import argparse
import sys

import gymnasium as gym
import numpy as np

import pixelworld_env  # noqa: F401  (registers the PW-* ids)
from pixelworld_env import PixelWorldEnv
from pixelworld_env.datasets import catalog
from pixelworld_env.generation.oracle import plan_to_goal


def fewest_moves(env: PixelWorldEnv) -> int | None:
    """The fewest moves from ``env``'s current state (after a reset) to one where its concept holds, or ``None``
    when the planner finds none (:func:`~pixelworld_env.generation.oracle.plan_to_goal`)."""
    plan = plan_to_goal(env)
    return None if plan is None else len(plan)


def table(datasets: list[str]) -> list[str]:
    """The Markdown rows: per dataset and split, the worlds, how many the planner finds no way to the goal in, and
    the mean, median and largest fewest moves over the others."""
    rows = ["| dataset | split | worlds | no plan | mean | median | max |", "|---|---|---:|---:|---:|---:|---:|"]
    for name in datasets:
        for split in ("train", "test"):
            env = gym.make(f"PW-{name}-v0", split=split).unwrapped
            assert isinstance(env, PixelWorldEnv)
            found = []
            for index in range(len(env.scenes)):
                env.reset(seed=0, options={"index": index})
                found.append(fewest_moves(env))
            reached = np.array([d for d in found if d is not None], dtype=float)
            summary = (f"{reached.mean():.1f} | {np.median(reached):.0f} | {reached.max():.0f}" if len(reached)
                       else "- | - | -")
            rows.append(f"| `{name}` | {split} | {len(found)} | {len(found) - len(reached)} | {summary} |")
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("datasets", nargs="+", help="bring-about dataset names (pixelworld list)")
    args = parser.parse_args(argv)
    for name in args.datasets:  # every name checked before any work
        try:
            info = catalog.dataset(name)
        except catalog.UnknownDatasetError as error:  # with the nearest names
            parser.error(str(error))
        if info.kind != "bring-about":
            parser.error(f"{name} is a {info.kind} dataset: only bring-about datasets have goal cells")
    print("\n".join(table(args.datasets)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
