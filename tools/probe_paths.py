"""The fewest moves from each world's start to a cell where the concept holds, for bring-about datasets whose worlds
only the self moves in: a breadth-first search over the free cells (``PixelWorldEnv.goal_at``), per dataset and
split, as a Markdown table (docs/results/paper/README.md, "Where a method fails": are the worlds of one target
harder to reach than its mirror image's?).

    python tools/probe_paths.py ba_self-second_from_left_from_anywhere-on-floor \\
        ba_self-second_from_right_from_anywhere-on-floor
"""

from __future__ import annotations

import argparse
import sys
from collections import deque

import gymnasium as gym
import numpy as np

import pixelworld_env  # noqa: F401  (registers the PW-* ids)
from pixelworld_env import PixelWorldEnv
from pixelworld_env.core.constants import EMPTY
from pixelworld_env.datasets import catalog

MOVES = ((0, 1), (0, -1), (1, 0), (-1, 0))


def fewest_moves(env: PixelWorldEnv) -> int | None:
    """The fewest moves from the self's position in ``env``'s current world (after a reset) to a cell where the
    concept holds, or ``None`` when no free cell it can reach does. Only for worlds where the self alone moves (a
    move then succeeds iff the target cell is free)."""
    world = env.world
    if not world.self_only:
        raise ValueError("fewest_moves needs a world where only the self moves (a pushable object moves too)")

    def free(cell: tuple[int, int]) -> bool:  # the owner array is padded by one ring of outside cells
        return int(world.owner[cell[0] + 1, cell[1] + 1]) in (EMPTY, world.self_index)

    start = world.self_position
    distance = {start: 0}
    queue = deque([start])
    while queue:
        cell = queue.popleft()
        if env.goal_at(cell):
            return distance[cell]
        for dr, dc in MOVES:
            step = (cell[0] + dr, cell[1] + dc)
            if step not in distance and free(step):
                distance[step] = distance[cell] + 1
                queue.append(step)
    return None


def table(datasets: list[str]) -> list[str]:
    """The Markdown rows: per dataset and split, the worlds, how many have no reachable goal, and the mean, median
    and largest fewest moves over the others."""
    rows = ["| dataset | split | worlds | unreachable | mean | median | max |", "|---|---|---:|---:|---:|---:|---:|"]
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
