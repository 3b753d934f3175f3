"""``World.move`` in this tree beside a baseline checkout, in one run: worlds with a pushable object and worlds where
only the self moves.

Walks of 20 moves right then 20 left from every start of the first 20 scenes of each dataset, best of 5 repeats,
each tree in its own subprocess (``PYTHONPATH`` = the tree), alternating. Both trees must give the same arrays
(``tests/test_pushable.py`` checks every move against a full redraw). Run: ``python benchmarks/bench_pushing.py
[--baseline PATH]``; make a baseline checkout with ``git worktree add /tmp/baseline <commit>``. Without
``--baseline`` only this tree is measured.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]
DATASETS = ("ba_pixel-touches-reference_from_left-on-floor-pushable", "cl_pushable-floor-pixel_vs_unpushable",
            "ba_self-in-container_from_on-floor")

_JOB = """
import sys, timeit
from pixelworld_env.datasets.cache import load_or_generate
from pixelworld_env.datasets.loading import dataset_spec
from pixelworld_env.core.world import MOVES, World
worlds = [World(scene) for scene in load_or_generate(dataset_spec(sys.argv[1]), 0).scenes[:20]]
right, left = MOVES["RIGHT"], MOVES["LEFT"]
def walk():
    for world in worlds:
        world.reset()
        for _ in range(20):
            world.move(right)
        for _ in range(20):
            world.move(left)
walk()
print(1e6 * min(timeit.repeat(walk, number=10, repeat=5)) / (10 * len(worlds) * 40))
"""


def microseconds_per_move(tree: Path, name: str) -> float:
    env = {**os.environ, "PYTHONPATH": str(tree)}
    out = subprocess.run([sys.executable, "-c", _JOB, name], env=env, capture_output=True, text=True, check=True)
    return float(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", type=Path, help="a checkout of the code to compare with")
    args = parser.parse_args()
    if args.baseline is None:
        print("| dataset | µs/move |\n|---|---:|")
        for name in DATASETS:
            print(f"| `{name}` | {microseconds_per_move(HERE, name):.2f} |")
        return
    print("| dataset | baseline (µs/move) | this tree (µs/move) | speed-up |\n|---|---:|---:|---:|")
    for name in DATASETS:
        before = microseconds_per_move(args.baseline, name)
        after = microseconds_per_move(HERE, name)
        print(f"| `{name}` | {before:.2f} | {after:.2f} | {before / after:.2f}x |", flush=True)


if __name__ == "__main__":
    main()
