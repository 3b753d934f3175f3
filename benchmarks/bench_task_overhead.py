"""The SMC layer's cost per primitive step on a foreign environment (Minigrid), beside the bare environment, in one run.

On ``MiniGrid-DoorKey-8x8-v0`` with random primitive actions drawn in advance (no signals, so episodes end by the
environment's own limit or ``max_steps``), one process: the bare environment (``gym.make``), the same in an
:class:`~sb3_smc.tasks.task.SMCTask` (goal test and flat sensor after every step), in a
:class:`~sb3_smc.HierarchicalSMCWrapper` over it (SMC observation: sensor, outcomes, previous action), and the
primitive steps made inside SMC calls (a scripted child that takes random primitives for its whole call of 100 moves).
Prints steps per second and microseconds per step over the bare environment. Needs ``pip install minigrid``.
Run: ``python benchmarks/bench_task_overhead.py [--steps N] [--repeats R]``.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import gymnasium as gym
import numpy as np

from sb3_smc import SMC, HierarchicalSMCWrapper
from sb3_smc.examples.minigrid_doorkey import OBSERVATION, at_goal
from sb3_smc.smc.policies import ScriptedPolicy
from sb3_smc.tasks.task import SMCTask, layout_of

ENV = "MiniGrid-DoorKey-8x8-v0"


def rate(run: Callable[[], int], repeats: int) -> float:
    best = 0.0
    for _ in range(repeats):
        start = time.perf_counter()
        steps = run()
        best = max(best, steps / (time.perf_counter() - start))
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=50_000)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    import minigrid  # noqa: F401

    actions = np.random.default_rng(0).integers(7, size=args.steps)

    def bare() -> int:
        env = gym.make(ENV)
        env.reset(seed=0)
        for a in actions:
            _, _, terminated, truncated, _ = env.step(int(a))
            if terminated or truncated:
                env.reset()
        return args.steps

    def task(wrapped: bool) -> Callable[[], int]:
        def run() -> int:
            env: gym.Env = SMCTask(gym.make(ENV), "bring-about", goal=at_goal, observation=OBSERVATION)
            if wrapped:
                env = HierarchicalSMCWrapper(env)
            env.reset(seed=0)
            for a in actions:
                _, _, terminated, truncated, _ = env.step(int(a) + 1)  # after SIG1
                if terminated or truncated:
                    env.reset()
            return args.steps
        return run

    def calls() -> int:
        base = SMCTask(gym.make(ENV), "bring-about", goal=at_goal, observation=OBSERVATION)
        rng = np.random.default_rng(1)
        walker = SMC("walker", "bring-about", ScriptedPolicy(8, lambda obs, step: int(rng.integers(1, 8))),
                     layout=layout_of(base))
        env = HierarchicalSMCWrapper(base, [walker])
        env.reset(seed=0)
        made = 0
        while made < args.steps:
            _, _, terminated, truncated, info = env.step(8)  # the call
            made += info["primitive_steps"]
            if terminated or truncated:
                env.reset()
        return made

    cases = [("bare environment (gym.make)", bare), ("SMCTask", task(False)),
             ("HierarchicalSMCWrapper, primitive actions", task(True)),
             ("primitive steps inside SMC calls (scripted child)", calls)]
    rates = [(name, rate(run, args.repeats)) for name, run in cases]
    base_rate = rates[0][1]
    print(f"{ENV}, {args.steps:,} primitive steps, best of {args.repeats}\n")
    print("| case | steps/s | µs per step over the bare env |\n|---|---:|---:|")
    for name, value in rates:
        print(f"| {name} | {value:,.0f} | {1e6 / value - 1e6 / base_rate:.1f} |")


if __name__ == "__main__":
    main()
