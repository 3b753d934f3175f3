"""Environment step rate of PixelWorld next to Minigrid's MiniGrid-Empty-8x8-v0, in one run: single envs, the native
vector env (``gym.make_vec(id, n)``) beside ``SyncVectorEnv`` over ``gym.make``, the pushing worlds, and the vector
env's memory per environment.

Random actions (drawn in advance, the same way for every env), automatic reset, observations ("hand") and rewards
included, everything through ``gymnasium.make`` / ``gymnasium.make_vec``, one process (numba runs on one core).
Prints steps per second and the ratio to Minigrid. Needs ``pip install minigrid`` (``make bench`` does it). Run:
``python benchmarks/bench_env_steps.py [--steps N] [--repeats R] [--quick]``.
"""

from __future__ import annotations

import argparse
import gzip
import json
import time
import tracemalloc
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import pixelworld_env  # noqa: F401  (the PW-* ids)
from pixelworld_env import PixelWorldEnv, Scene
from pixelworld_env.envs.vector import PixelWorldVectorEnv
from pixelworld_env.generation.definitions import load_definitions

REFERENCE = Path(__file__).resolve().parents[2] / "shared" / "reference"
DATASETS = {
    "PWBench-classification-v0": "cl_self-in-container_vs_noncontainer",
    "PWBench-bring-about-v0": "ba_self-in-container_from_on-floor",
}
PUSHABLE = ["PW-cl_pushable-floor-pixel_vs_unpushable-v0",
            "PW-ba_pixel-touches-reference_from_left-on-floor-pushable-v0"]
SIZES = (1, 16, 256, 1024)
MINIGRID = "MiniGrid-Empty-8x8-v0"


def _vector_env(num_envs: int, **kwargs: Any) -> PixelWorldVectorEnv:
    return PixelWorldVectorEnv(PixelWorldEnv(**kwargs), num_envs)


def _register_reference_envs() -> None:
    defs = load_definitions(sorted((REFERENCE / "aaai18" / "DATA").glob("*.datasets")))
    for env_id, name in DATASETS.items():
        with gzip.open(REFERENCE / "aaai18_samples" / f"{name}.jsonl.gz", "rt") as handle:
            handle.readline()
            samples = [json.loads(line) for line in handle]
        dataset = defs.datasets[name]
        gym.register(env_id, entry_point=PixelWorldEnv, vector_entry_point=_vector_env, kwargs={
            "scenes": [Scene.from_dict(s) for s in samples],
            "labels": [s["label"] for s in samples] if dataset.kind == "classification" else None,
            "kind": dataset.kind, "concept": defs.concepts[dataset.concept].logic, "macros": defs.macros,
        })


def steps_per_second(env_id: str, steps: int, seed: int = 0) -> float:
    """One ``gym.make`` env: ``steps`` random actions with reset at the end of each episode."""
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


def vector_steps_per_second(env_id: str, num_envs: int, steps: int, mode: str, seed: int = 0) -> float:
    """``gym.make_vec(env_id, num_envs, vectorization_mode=mode)``: about ``steps`` environment steps in all (random
    actions drawn in advance, next-step autoreset), after a warm-up of a tenth as many."""
    env = gym.make_vec(env_id, num_envs=num_envs, vectorization_mode=mode)
    rounds = max(steps // num_envs, 20)
    actions = np.random.default_rng(seed).integers(env.single_action_space.n, size=(rounds, num_envs))
    env.reset(seed=seed)
    for row in actions[: max(rounds // 10, 5)]:
        env.step(row)
    start = time.perf_counter()
    for row in actions:
        env.step(row)
    elapsed = time.perf_counter() - start
    env.close()
    return rounds * num_envs / elapsed


def bytes_per_env(env_id: str, num_envs: int) -> float:
    """Memory the vector env allocates per environment (tracemalloc: built, reset and stepped once with
    ``num_envs`` environments, less the same with one)."""
    def allocated(n: int) -> int:
        tracemalloc.start()
        env = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point")
        env.reset(seed=0)
        env.step(np.zeros(n, dtype=np.int64))
        current = tracemalloc.get_traced_memory()[0]
        tracemalloc.stop()
        del env
        return current

    return (allocated(num_envs) - allocated(1)) / (num_envs - 1)


def best(measure, repeats: int) -> float:
    return max(measure(seed) for seed in range(repeats))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--steps", type=int, default=200_000)
    parser.add_argument("--repeats", type=int, default=3, help="best of this many runs per env")
    parser.add_argument("--quick", action="store_true", help="a tenth of the steps, best of 2")
    args = parser.parse_args()
    if args.quick:
        args.steps, args.repeats = args.steps // 10, 2
    import minigrid  # noqa: F401 - registers MiniGrid-*

    _register_reference_envs()
    rates: dict[str, float] = {}
    for env_id in [MINIGRID, *DATASETS, *PUSHABLE]:
        steps = args.steps if env_id.startswith("PW") else max(args.steps // 10, 10_000)
        rates[env_id] = best(lambda seed, e=env_id, s=steps: steps_per_second(e, s, seed), args.repeats)
        print(f"  measured {env_id}: {rates[env_id]:,.0f} steps/s", flush=True)
    base = rates[MINIGRID]
    print("\n| environment | steps/s | x Minigrid |\n|---|---:|---:|")
    for env_id, rate in rates.items():
        print(f"| {env_id} | {rate:,.0f} | {rate / base:.1f} |")

    print("\n| environment | N | native vector, steps/s | x Minigrid | SyncVectorEnv, steps/s | native / sync |")
    print("|---|---:|---:|---:|---:|---:|")
    for env_id in [*DATASETS, *PUSHABLE]:
        for n in SIZES:
            native = best(lambda seed, e=env_id, k=n: vector_steps_per_second(
                e, k, args.steps * (10 if k >= 256 else 1), "vector_entry_point", seed), args.repeats)
            synced = best(lambda seed, e=env_id, k=n: vector_steps_per_second(
                e, k, args.steps // 2, "sync", seed), max(args.repeats - 1, 1))
            print(f"| {env_id} | {n:,} | {native:,.0f} | {native / base:,.0f} | {synced:,.0f} | "
                  f"{native / synced:.1f} |", flush=True)

    for env_id in DATASETS:
        per_env = bytes_per_env(env_id, 65_536)
        print(f"\n{env_id}: {per_env:,.0f} bytes per environment; 65,536 environments: "
              f"{per_env * 65_536 / 2**20:,.0f} MiB", flush=True)


if __name__ == "__main__":
    main()
