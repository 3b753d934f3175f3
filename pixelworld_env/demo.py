"""``python -m pixelworld_env.demo`` (``make demo``): play PixelWorld episodes, then train and test a small SMC.

The embedded default: a hand-drawn scene played with a planner (bring-about) and at random (classification),
then a short RecurrentPPO training run (12 updates of 2,000 steps) of the SMC
``ba_self-on-something_from_directly-above`` with the paper's signal-bias initialisation and best-update
selection, tested with the paper's protocol before and after training.
"""

from __future__ import annotations

import argparse

import numpy as np

from pixelworld_env.env import PixelWorldEnv
from pixelworld_env.oracle import plan_to_goal
from pixelworld_env.scene import Scene

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
        _, reward, terminated, truncated, info = cl.step(int(rng.integers(cl.action_space.n)))
        total += reward
        steps += 1
        if terminated or truncated:
            break
    if not quiet:
        _show(cl, "classification, random policy, final state:")
    print(f"classification episode (label {info['label']}): {steps} steps, return {total:+.1f}, "
          f"success {info['is_success']}")
    return ret, total


DEMO_ENV = "PW-ba_self-on-something_from_directly-above-v0"


def train(seed: int = 0, total_timesteps: int = 24_000) -> tuple[float, float]:
    """Train a small flat SMC and return its test success rate before and after training."""
    import torch

    from sb3_smc import evaluate, train_smc

    torch.set_num_threads(1)
    untrained = train_smc(DEMO_ENV, total_timesteps=0, seed=seed)
    before = evaluate(untrained, DEMO_ENV, repeats=4, seed=seed).score
    print(f"\ntraining an SMC on {DEMO_ENV} for {total_timesteps:,} steps (RecurrentPPO, LSTM 32) ...")
    smc = train_smc(DEMO_ENV, total_timesteps=total_timesteps, seed=seed, log_every=2)
    after = evaluate(smc, DEMO_ENV, repeats=4, seed=seed).score
    print(f"test success rate (25 scenes x 4 runs): untrained {before:.2f} -> trained {after:.2f} "
          f"(selected update {smc.metadata['selected_update']}, training return "
          f"{smc.metadata['training_return']:.2f})")
    return before, after


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
