"""Environment step rate of PixelWorld next to Minigrid's MiniGrid-Empty-8x8-v0, in one run.

Random actions (drawn in advance, the same way for every env), automatic reset, everything through
``gymnasium.make``. Prints steps per second and the ratio to Minigrid. Needs ``pip install minigrid``
(``make bench`` does it). Run: ``python benchmarks/bench_env_steps.py [--steps N] [--repeats R]``.
"""

from __future__ import annotations

import argparse
import gzip
import json
import time
from pathlib import Path

import gymnasium as gym
import numpy as np

from pixelworld_env import PixelWorldEnv, Scene
from pixelworld_env.definitions import load_definitions

REFERENCE = Path(__file__).resolve().parents[2] / "shared" / "reference"
DATASETS = {
    "PWBench-classification-v0": "cl_self-in-container_vs_noncontainer",
    "PWBench-bring-about-v0": "ba_self-in-container_from_on-floor",
}


def _register_reference_envs() -> None:
    defs = load_definitions(sorted((REFERENCE / "aaai18" / "DATA").glob("*.datasets")))
    for env_id, name in DATASETS.items():
        with gzip.open(REFERENCE / "aaai18_samples" / f"{name}.jsonl.gz", "rt") as handle:
            handle.readline()
            samples = [json.loads(line) for line in handle]
        dataset = defs.datasets[name]
        gym.register(env_id, entry_point=PixelWorldEnv, kwargs={
            "scenes": [Scene.from_dict(s) for s in samples],
            "labels": [s["label"] for s in samples] if dataset.kind == "classification" else None,
            "kind": dataset.kind, "concept": defs.concepts[dataset.concept].logic, "macros": defs.macros,
        })


def steps_per_second(env_id: str, steps: int, seed: int = 0) -> float:
    env = gym.make(env_id)
    actions = np.random.default_rng(seed).integers(env.action_space.n, size=steps).tolist()
    env.reset(seed=seed)
    for action in actions[:1000]:  # warm-up: memoised goal tests, caches, the passive checker's first step
        _, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            env.reset()
    start = time.perf_counter()
    for action in actions:
        _, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            env.reset()
    elapsed = time.perf_counter() - start
    env.close()
    return steps / elapsed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--steps", type=int, default=200_000)
    parser.add_argument("--repeats", type=int, default=3, help="best of this many runs per env")
    args = parser.parse_args()
    import minigrid  # noqa: F401 - registers MiniGrid-*

    _register_reference_envs()
    ids = ["MiniGrid-Empty-8x8-v0", *DATASETS]
    rates = {}
    for env_id in ids:
        steps = args.steps if env_id.startswith("PW") else max(args.steps // 10, 10_000)
        rates[env_id] = max(steps_per_second(env_id, steps, seed=r) for r in range(args.repeats))
        print(f"  measured {env_id}: {rates[env_id]:,.0f} steps/s", flush=True)
    base = rates["MiniGrid-Empty-8x8-v0"]
    print("\n| environment | steps/s | x Minigrid |\n|---|---:|---:|")
    for env_id in ids:
        print(f"| {env_id} | {rates[env_id]:,.0f} | {rates[env_id] / base:.1f} |")


if __name__ == "__main__":
    main()
