"""Every registered PW-* id: Gymnasium check_env, determinism, rendering, pickling, solvability."""

from __future__ import annotations

import pickle
import subprocess
import sys
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import pixelworld_env
from pixelworld_env import catalog
from pixelworld_env.oracle import plan_to_goal
from pixelworld_env.registration import registered_ids

IDS = sorted(registered_ids())
BRING_ABOUT = [i for i in IDS if registered_ids()[i][0].startswith("ba_") and len(registered_ids()[i]) == 1]


def test_every_dataset_and_concept_pool_is_registered() -> None:
    assert len([i for i in IDS if len(registered_ids()[i]) == 1 and i[3:-3] in catalog.dataset_names()]) == 136 + 11
    assert "PW-cl_self-in-container_vs_noncontainer-v0" in gym.registry
    pool = registered_ids()["PW-ba_self-in-container-v0"]
    assert pool == tuple(sorted(n for n in catalog.dataset_names() if n.startswith("ba_self-in-container_from_")))
    assert pixelworld_env.__name__ == "pixelworld_env"


def test_make_with_module_prefix_from_a_fresh_interpreter() -> None:
    code = ("import gymnasium as gym; env = gym.make('pixelworld_env:PW-cl_self-in-left-corner_vs_on-hline-v0', "
            "split='test'); print(len(env.unwrapped.scenes), env.unwrapped.action_names)")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout.strip() == "50 ('SIG0', 'SIG1', 'DOWN', 'RIGHT', 'UP', 'LEFT')"


def _rollout(env: gym.Env, seed: int, steps: int = 60) -> list:
    env.action_space.seed(seed)
    trace = []
    obs, info = env.reset(seed=seed)
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
        trace.append((obs.tobytes(), reward, terminated, truncated, info["scene_index"]))
        if terminated or truncated:
            obs, info = env.reset()
    return trace


@pytest.mark.parametrize("env_id", IDS)
def test_registered_env(env_id: str) -> None:
    members = registered_ids()[env_id]
    env = gym.make(env_id, split="test", render_mode="rgb_array")
    infos = [catalog.dataset(m) for m in members]
    assert len(env.unwrapped.scenes) == sum(i.test_size for i in infos)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env.unwrapped, skip_render_check=True)
    assert _rollout(env, 7) == _rollout(gym.make(env_id, split="test"), 7)
    env.reset(seed=0)
    assert env.render().shape == (180, 350, 3)
    text_env = gym.make(env_id, split="test", render_mode="ansi")
    text_env.reset(seed=0)
    assert text_env.render().count("\n") == 18
    clone = pickle.loads(pickle.dumps(env.unwrapped))
    np.testing.assert_array_equal(clone.step(1)[0], env.unwrapped.step(1)[0])


@pytest.mark.parametrize("env_id", BRING_ABOUT)
def test_bring_about_scenes_are_solvable(env_id: str) -> None:
    env = gym.make(env_id, split="all").unwrapped
    for index in range(len(env.scenes)):
        env.reset(options={"index": index})
        plan = plan_to_goal(env)
        assert plan, f"{env_id} scene {index}: the goal cannot be reached by moving the self"
        rewards = [env.step(a)[1] for a in plan]
        assert rewards[-1] == 0.5 and env.step(env.action_names.index("SIG1"))[1] == 0.5
