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
from gymnasium.wrappers import TimeLimit

import pixelworld_env
from pixelworld_env.datasets import catalog
from pixelworld_env.envs import registration
from pixelworld_env.envs.registration import make_env, registered_ids
from pixelworld_env.generation.oracle import plan_to_goal

IDS = sorted(registered_ids())
BRING_ABOUT = [i for i in IDS if registered_ids()[i][0].startswith("ba_") and len(registered_ids()[i]) == 1]


def test_every_dataset_and_concept_pool_is_registered() -> None:
    datasets = [i for i in IDS if len(registered_ids()[i]) == 1 and i[3:-3] in catalog.dataset_names()]
    assert len(datasets) == 136 + 11 + 8  # the release, the pushable curriculum, bring-about-or-cannot
    assert "PW-bc_self-in-container_from_on-floor-v0" in datasets and "PW-bc_self-in-container-v0" in IDS
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


def _wrappers(env: gym.Env) -> list[type]:
    chain = []
    while isinstance(env, gym.Wrapper):
        chain.append(type(env))
        env = env.env
    return chain


def _time_limited(env: gym.Env) -> bool:
    """Whether a ``TimeLimit`` wraps ``env`` (rl_zoo3, once imported, makes gym.make use its subclass)."""
    return any(issubclass(wrapper, TimeLimit) for wrapper in _wrappers(env))


def test_the_spec_states_the_limit_and_make_adds_no_time_limit() -> None:
    """``env.spec.max_episode_steps`` is the env's own limit; gym.make wraps no ``TimeLimit`` around it, so the
    episodes are those of the bare env (one limit, truncating at the same step)."""
    env_id = "PW-ba_self-in-container-v0"
    made = gym.make(env_id)
    assert made.spec.max_episode_steps == made.unwrapped.spec.max_episode_steps == 100
    assert not _time_limited(made) and gym.spec(env_id).max_episode_steps is None
    assert gym.make(env_id, max_steps=40).spec.max_episode_steps == 40
    limited = gym.make(env_id, max_episode_steps=30)  # asked for: gym.make's TimeLimit, and the spec says so
    assert _time_limited(limited) and limited.spec.max_episode_steps == 30
    bare = make_env(registered_ids()[env_id])
    assert bare.spec is None
    for env in (made, bare):  # only moves: every episode runs into the limit
        env.action_space.seed(3)
    traces = []
    for env in (made, bare):
        env.reset(seed=5)
        trace = []
        for _ in range(350):
            obs, reward, terminated, truncated, info = env.step(int(env.action_space.sample()) % 4 + 1)
            trace.append((obs.tobytes(), reward, terminated, truncated, info["scene_index"],
                          env.unwrapped.elapsed_steps))
            if terminated or truncated:
                env.reset()
        traces.append(trace)
    assert traces[0] == traces[1]
    assert [i for i, step in enumerate(traces[0]) if step[3]] == [99, 199, 299]


@pytest.mark.parametrize(("kwargs", "error", "message"), [
    ({"aaai18_reset_bug": "yes"}, TypeError, r"aaai18_reset_bug must be a bool \(True or False\), got 'yes' \(str\)"),
    ({"aaai18_reset_bug": 1}, TypeError, r"aaai18_reset_bug must be a bool \(True or False\), got 1 \(int\)"),
    ({"max_steps": 0}, ValueError, "max_steps must be >= 1, got 0"),
    ({"observation": "imag"}, ValueError, "observation must be one of .*'image'.*got 'imag'"),
    ({"render_mode": "window"}, ValueError, "render_mode must be None or one of"),
    ({"max_step": 5}, TypeError, "unexpected keyword argument 'max_step'"),
])
def test_settings_are_checked_before_any_dataset_is_loaded(monkeypatch: pytest.MonkeyPatch, kwargs: dict,
                                                          error: type, message: str) -> None:
    def no_loading(*args, **kw):
        raise AssertionError("a dataset was loaded before the settings were checked")

    monkeypatch.setattr(registration, "load_dataset", no_loading)
    with pytest.raises(error, match=message):
        gym.make("PW-cl_self-in-left-corner_vs_on-hline-v0", **kwargs)


def test_numpy_bools_are_bools() -> None:
    env = gym.make("PW-cl_self-in-left-corner_vs_on-hline-v0", aaai18_reset_bug=np.bool_(True))
    assert env.unwrapped.aaai18_reset_bug
