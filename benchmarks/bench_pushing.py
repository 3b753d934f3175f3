"""Moves in worlds with a pushable object: ``World.move`` (redraws only the objects a move shifts) next to the
full redraw it replaced, side by side in one run.

In a world with any moveable object besides the one-pixel self, every successful move used to redraw the whole
state array (``World._draw``); the pushable curriculum's worlds all have one. The baseline here is the same
``World`` forced onto that full-redraw path. Both give the same arrays (``tests/test_pushable.py``). Walks of 20
moves right then 20 left from every start of the first 20 scenes of each dataset, best of 5 repeats.
Run: ``python benchmarks/bench_pushing.py``.
"""

from __future__ import annotations

import timeit

from pixelworld_env.datasets import load_or_generate
from pixelworld_env.loading import dataset_spec
from pixelworld_env.world import MOVES, World

DATASETS = ("ba_pixel-touches-reference_from_left-on-floor-pushable", "cl_pushable-floor-pixel_vs_unpushable")


class FullRedrawWorld(World):
    """The baseline: every successful move redraws the whole world."""

    def _draw(self) -> None:
        super()._draw()
        self._disjoint = False


def microseconds_per_move(world_class: type[World], name: str, repeats: int = 5) -> float:
    worlds = [world_class(scene) for scene in load_or_generate(dataset_spec(name), 0).scenes[:20]]
    right, left = MOVES["RIGHT"], MOVES["LEFT"]

    def walk() -> None:
        for world in worlds:
            world.reset()
            for _ in range(20):
                world.move(right)
            for _ in range(20):
                world.move(left)

    best = min(timeit.repeat(walk, number=10, repeat=repeats))
    return 1e6 * best / (10 * len(worlds) * 40)


def main() -> None:
    print("| dataset | full redraw (µs/move) | moved objects only (µs/move) | speed-up |")
    print("|---|---:|---:|---:|")
    for name in DATASETS:
        before = microseconds_per_move(FullRedrawWorld, name)
        after = microseconds_per_move(World, name)
        print(f"| `{name}` | {before:.1f} | {after:.1f} | {before / after:.1f}x |")


if __name__ == "__main__":
    main()
