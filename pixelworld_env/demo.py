"""``python -m pixelworld_env.demo``: play PixelWorld episodes (no learning; ``python -m sb3_smc.demo`` adds it).

A hand-drawn scene played with a breadth-first planner (bring-about) and at random (classification).
"""

from __future__ import annotations

import argparse

import numpy as np

from pixelworld_env.core.scene import Scene
from pixelworld_env.envs.env import PixelWorldEnv
from pixelworld_env.generation.oracle import plan_to_goal

DEMO_SCENE = """
###################################
#.................................#
#.................................#
#...S.............................#
#.................................#
#.................................#
#.................................#
#.................................#
#.................................#
#.................................#
#.....................a......a....#
#.....................a......a....#
#...........bbb.......a......a....#
#............b........aaaaaaaa....#
#.................................#
#=================================#
#.................................#
###################################
"""
DEMO_KINDS = {"a": "container", "b": "small_blob"}
DEMO_CONCEPT = "?x container(x) & inside_supported(self,x)"


def _show(env: PixelWorldEnv, header: str) -> None:
    print(header)
    print(env.render(), end="")


def play(seed: int = 0, quiet: bool = False) -> tuple[float, float]:
    """Play a bring-about episode with the oracle planner and a classification episode at random."""
    scene = Scene.from_ascii(DEMO_SCENE, DEMO_KINDS)
    env = PixelWorldEnv([scene], kind="bring-about", concept=DEMO_CONCEPT, render_mode="ansi")
    env.reset(seed=seed)
    if not quiet:
        _show(env, f"bring-about: {DEMO_CONCEPT}\nactions {env.action_names}; start:")
    plan = plan_to_goal(env)
    assert plan is not None, "the demo scene is solvable"
    ret = 0.0
    for step, action in enumerate([*plan, env.action_names.index("SIG1")], start=1):
        _, reward, terminated, truncated, info = env.step(action)
        ret += reward
        if not quiet and (reward or terminated):
            _show(env, f"step {step}: {env.action_names[action]} reward {reward:+.1f} goal {info['goal']}")
    print(f"bring-about episode: {len(plan) + 1} steps, return {ret:+.1f}, success {info['is_success']}")

    cl = PixelWorldEnv([scene], kind="classification", concept=DEMO_CONCEPT, render_mode="ansi")
    cl.reset(seed=seed)
    rng = np.random.default_rng(seed)
    total, steps = 0.0, 0
    while True:
        _, reward, terminated, truncated, info = cl.step(int(rng.integers(len(cl.action_names))))
        total += reward
        steps += 1
        if terminated or truncated:
            break
    if not quiet:
        _show(cl, "classification, random policy, final state:")
    print(f"classification episode (label {info['label']}): {steps} steps, return {total:+.1f}, "
          f"success {info['is_success']}")
    return ret, total


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--quiet", action="store_true", help="print only the episode summaries")
    args = parser.parse_args()
    play(seed=args.seed, quiet=args.quiet)


if __name__ == "__main__":
    main()
