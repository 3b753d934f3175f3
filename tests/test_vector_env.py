"""The native vector env (``gym.make_vec(id, n)``): step by step the transitions of ``SyncVectorEnv`` over
``gym.make``, Gymnasium's vector conventions, refusals, and the SB3 adapter."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode, SyncVectorEnv

import pixelworld_env  # noqa: F401  (registers the PW-* ids)
from pixelworld_env.envs.registration import registered_ids
from pixelworld_env.envs.vector import PixelWorldVectorEnv
from pixelworld_env.generation.oracle import plan_to_goal

CLASSIFICATION = "PW-cl_self-in-container_vs_noncontainer-v0"
BRING_ABOUT = "PW-ba_self-in-container_from_on-floor-v0"
POOL = "PW-ba_self-on-floor-v0"  # two datasets
LARGE_POOL = "PW-ba_self-in-container-v0"  # 300 scenes: more than a block of 256 draws
PUSHABLE_BA = "PW-ba_pixel-touches-reference_from_left-on-floor-pushable-v0"  # every scene pushes
PUSHABLE_MIXED = "PW-cl_pushable-floor-pixel-v0"  # pool: 85 of 150 scenes push, the others only move the self


def native(env_id: str, n: int, **kwargs) -> PixelWorldVectorEnv:
    env = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", **kwargs)
    assert isinstance(env, PixelWorldVectorEnv)
    return env


def sync(env_id: str, n: int, **kwargs) -> SyncVectorEnv:
    return gym.make_vec(env_id, num_envs=n, vectorization_mode="sync", **kwargs)


def assert_same(a, b) -> None:
    """Observations, rewards, flags and infos equal, dtypes included."""
    assert len(a) == len(b)
    for x, y in zip(a[:-1], b[:-1], strict=True):
        assert x.dtype == y.dtype and x.shape == y.shape
        np.testing.assert_array_equal(x, y)
    info_a, info_b = a[-1], b[-1]
    assert sorted(info_a) == sorted(info_b)
    for key in info_a:
        assert info_a[key].dtype == info_b[key].dtype, key
        assert info_a[key].tolist() == info_b[key].tolist(), key


def actions_for(env: gym.vector.VectorEnv, rng: np.random.Generator, signal_p: float) -> np.ndarray:
    """Random actions; signals (action 0, and 1 in classification) with probability ``signal_p`` in all."""
    names = env.unwrapped.get_attr("action_names")[0] if isinstance(env, SyncVectorEnv) else env.action_names
    signals = [i for i, name in enumerate(names) if name.startswith("SIG")]
    moves = [i for i in range(len(names)) if i not in signals]
    signal = rng.random(env.num_envs) < signal_p
    return np.where(signal, rng.choice(signals, env.num_envs), rng.choice(moves, env.num_envs)).astype(np.int64)


class Guide:
    """Bring-about actions that reach the goal: each env follows a plan to the goal (made from the SyncVectorEnv's
    copy of its state at the episode's start, memoised per scene), with a random action a fifth of the time, and
    signals when the plan is done."""

    def __init__(self, reference: SyncVectorEnv, rng: np.random.Generator) -> None:
        self.reference, self.rng = reference, rng
        self.plans: list[list[int]] = [[] for _ in range(reference.num_envs)]
        self.memo: dict[int, list[int]] = {}

    def __call__(self, random_actions: np.ndarray, done: np.ndarray) -> np.ndarray:
        actions = random_actions.copy()
        for k, env in enumerate(self.reference.envs):
            if done[k]:
                self.plans[k] = []
                continue
            if not self.plans[k]:  # the last plan ended with a signal: this is an episode's start
                unwrapped = env.unwrapped
                plan = self.memo.get(unwrapped.step_info()["scene_index"])
                if plan is None:
                    plan = self.memo[unwrapped.step_info()["scene_index"]] = (
                        (plan_to_goal(unwrapped) or []) + [unwrapped.action_names.index("SIG1")])
                self.plans[k] = list(plan)
            if self.rng.random() < 0.8:
                actions[k] = self.plans[k].pop(0)
        return actions


def run_both(env_id: str, n: int, steps: int, signal_p: float, guided: bool = False,
             **kwargs) -> dict[str, int]:
    """Drive both envs through resets with int seeds, seed lists, options and no seed, and compare every
    transition; returns counts of what happened. ``guided``: bring-about actions that often reach the goal."""
    a, b = native(env_id, n, **kwargs), sync(env_id, n, **kwargs)
    guide = Guide(b, np.random.default_rng(1)) if guided else None
    assert a.metadata["autoreset_mode"] == b.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP
    assert a.observation_space == b.observation_space and a.action_space == b.action_space
    assert a.single_observation_space == b.single_observation_space
    rng = np.random.default_rng(0)
    counts = {"terminated": 0, "truncated": 0, "reward": 0, "moves": 0}
    n_scenes = len(a.scenes)
    resets = [dict(seed=3), dict(seed=list(range(100, 100 + n))), dict(options={"index": n_scenes - 1}),
              dict(), dict(seed=[None] * (n - 1) + [7], options={"index": 0}), dict(seed=11)]
    for reset in resets:
        assert_same(a.reset(**reset), b.reset(**reset))
        done = np.zeros(n, dtype=bool)
        for _ in range(steps):
            actions = actions_for(a, rng, signal_p)
            if guide is not None:
                actions = guide(actions, done)
            result = a.step(actions)
            assert_same(result, b.step(actions))
            done = result[2] | result[3]
            counts["terminated"] += int(result[2].sum())
            counts["truncated"] += int(result[3].sum())
            counts["reward"] += int(np.count_nonzero(result[1]))
    return counts


@pytest.mark.parametrize("env_id", [CLASSIFICATION, BRING_ABOUT, POOL])
def test_same_transitions_as_sync_vector_env(env_id: str) -> None:
    counts = run_both(env_id, 5, 120, signal_p=0.05, guided=env_id != CLASSIFICATION, max_steps=12)
    assert counts["terminated"] > 20 and counts["truncated"] > 20 and counts["reward"] > 50


def test_same_transitions_over_many_blocks_of_scene_draws() -> None:
    """Short episodes: each env draws more than 256 scenes between seeded resets (a new block from its generator)."""
    counts = run_both(LARGE_POOL, 3, 700, signal_p=0.9)
    assert counts["terminated"] > 6 * 3 * 256


@pytest.mark.parametrize("observation", ["hand_raw", "full", "image"])
def test_same_transitions_with_other_observations(observation: str) -> None:
    assert run_both(BRING_ABOUT, 3, 60, signal_p=0.05, guided=True, observation=observation, max_steps=20)["reward"]


@pytest.mark.parametrize("env_id", [PUSHABLE_BA, PUSHABLE_MIXED])
def test_same_transitions_in_pushing_worlds(env_id: str) -> None:
    counts = run_both(env_id, 3, 40, signal_p=0.05, guided=env_id == PUSHABLE_BA, max_steps=12)
    assert counts["terminated"] > 5 and counts["truncated"] > 5 and counts["reward"] > 5


def test_reset_mask_and_one_index_per_env() -> None:
    """``options["index"]`` per environment equals SyncVectorEnv resetting each environment with its own index,
    and a partial reset (``reset_mask``) is SyncVectorEnv's."""
    a, b = native(BRING_ABOUT, 3, max_steps=9), sync(BRING_ABOUT, 3, max_steps=9)
    obs, info = a.reset(seed=[5, 6, 7], options={"index": [4, None, 2]})
    b.reset(seed=0)  # SyncVectorEnv needs a full reset first; the seeded resets below start over
    for k, index in enumerate([4, None, 2]):
        mask = np.arange(3) == k
        options = {"reset_mask": mask} if index is None else {"reset_mask": mask, "index": index}
        b.reset(seed=[5, 6, 7], options=options)
    expected = b.step(np.array([1, 1, 1]))
    assert_same(a.step(np.array([1, 1, 1])), expected)
    rng = np.random.default_rng(1)
    for _ in range(30):
        actions = actions_for(a, rng, 0.1)
        assert_same(a.step(actions), b.step(actions))
        mask = rng.random(3) < 0.3
        if mask.any():
            assert_same(a.reset(options={"reset_mask": mask.copy()}), b.reset(options={"reset_mask": mask.copy()}))
    assert info["scene_index"].tolist()[0::2] == [4, 2]
    assert obs.shape == (3, 81)


def test_every_id_registers_the_vector_entry_point() -> None:
    for env_id in registered_ids():
        assert gym.spec(env_id).vector_entry_point == "pixelworld_env.envs.registration:make_vector_env"
    env = gym.make_vec(CLASSIFICATION, num_envs=2)  # the default mode is the vector entry point
    assert isinstance(env, PixelWorldVectorEnv) and env.spec.id == CLASSIFICATION
    assert repr(env) == f"PixelWorldVectorEnv({CLASSIFICATION}, num_envs=2)"


def test_refusals_and_errors() -> None:
    with pytest.raises(ValueError, match="aaai18_reset_bug"):
        native(CLASSIFICATION, 2, aaai18_reset_bug=True)
    with pytest.raises(ValueError, match="render_mode='human'"):
        native(CLASSIFICATION, 2, render_mode="human")
    with pytest.raises(ValueError, match="render_envs"):
        native(CLASSIFICATION, 2, render_envs="some")
    with pytest.raises(ValueError, match="num_envs"):
        native(CLASSIFICATION, 0)
    env = native(CLASSIFICATION, 2)
    with pytest.raises(RuntimeError, match="reset"):
        env.step(np.array([0, 0]))
    with pytest.raises(RuntimeError, match="every environment"):
        env.reset(options={"reset_mask": np.array([True, False])})
    env.reset(seed=0)
    for bad in (np.array([0, 6]), np.array([-1, 0]), np.array([0.0, 1.0]), np.array([0, 1, 2])):
        with pytest.raises(ValueError, match="actions"):
            env.step(bad)
    with pytest.raises(ValueError, match="unknown reset option"):
        env.reset(options={"level": 1})
    with pytest.raises(IndexError, match="out of range"):
        env.reset(options={"index": [0, 50]})
    with pytest.raises(ValueError, match="one entry per environment"):
        env.reset(options={"index": [0]})
    with pytest.raises(ValueError, match="length must match"):
        env.reset(seed=[1])


@pytest.mark.parametrize("mode", ["rgb_array", "ansi"])
def test_render_first_or_all(mode: str) -> None:
    a, b = native(PUSHABLE_MIXED, 3, render_mode=mode), sync(PUSHABLE_MIXED, 3, render_mode=mode)
    first = native(PUSHABLE_MIXED, 3, render_mode=mode, render_envs="first")
    rng = np.random.default_rng(2)
    for env in (a, b, first):
        env.reset(seed=4)
    for _ in range(10):
        actions = actions_for(a, rng, 0.1)
        for env in (a, b, first):
            env.step(actions)
        frames, expected = a.render(), b.render()
        assert len(frames) == 3 and first.render()[0] is not None
        for frame, want, one in zip(frames, expected, first.render() + (None, None), strict=True):
            if mode == "ansi":
                assert frame == want and (one is None or one == want)
            else:
                np.testing.assert_array_equal(frame, want)
                assert one is None or np.array_equal(one, want)


def sb3_pair(env_id: str, n: int, **kwargs):
    from stable_baselines3.common.vec_env import DummyVecEnv

    from sb3_smc.envs.gymnasium_vec_env import GymnasiumVecEnv

    return (GymnasiumVecEnv(native(env_id, n, **kwargs)),
            DummyVecEnv([lambda: gym.make(env_id, **kwargs) for _ in range(n)]))


@pytest.mark.parametrize("env_id", [CLASSIFICATION, PUSHABLE_BA])
def test_sb3_adapter_steps_as_dummy_vec_env(env_id: str) -> None:
    a, b = sb3_pair(env_id, 4, max_steps=6)
    for venv in (a, b):
        venv.seed(9)
        venv.set_options({"index": 2})
    assert np.array_equal(a.reset(), b.reset()) and a.reset_infos == b.reset_infos
    a.seed(3)
    b.seed(3)
    assert np.array_equal(a.reset(), b.reset()) and a.reset_infos == b.reset_infos
    rng = np.random.default_rng(0)
    ended = 0
    for _ in range(60):
        actions = actions_for(a.env, rng, 0.1)
        (obs_a, rew_a, done_a, infos_a), (obs_b, rew_b, done_b, infos_b) = a.step(actions), b.step(actions)
        assert obs_a.dtype == obs_b.dtype and rew_a.dtype == rew_b.dtype and done_a.dtype == done_b.dtype
        np.testing.assert_array_equal(obs_a, obs_b)
        np.testing.assert_array_equal(rew_a, rew_b)
        np.testing.assert_array_equal(done_a, done_b)
        for info_a, info_b in zip(infos_a, infos_b, strict=True):
            terminal_a, terminal_b = info_a.pop("terminal_observation", None), info_b.pop("terminal_observation", None)
            assert info_a == info_b and (terminal_a is None) == (terminal_b is None)
            if terminal_a is not None:
                np.testing.assert_array_equal(terminal_a, terminal_b)
        assert a.reset_infos == b.reset_infos
        ended += int(done_a.sum())
    assert ended > 20
    assert a.get_attr("action_names") == [a.env.action_names] * 4 and a.env_is_wrapped(gym.Wrapper) == [False] * 4


def test_ppo_first_rollout_equals_dummy_vec_env_and_trains() -> None:
    import torch
    from stable_baselines3 import PPO

    def trained(venv):
        model = PPO("MlpPolicy", venv, n_steps=64, batch_size=64, n_epochs=2, seed=0, device="cpu")
        model.learn(256)
        return model

    a, b = (trained(venv) for venv in sb3_pair(BRING_ABOUT, 4, max_steps=12))
    for field in ("observations", "actions", "rewards", "episode_starts", "values", "log_probs", "returns"):
        np.testing.assert_array_equal(getattr(a.rollout_buffer, field), getattr(b.rollout_buffer, field))
    assert a.num_timesteps == b.num_timesteps == 256
    fresh = PPO("MlpPolicy", sb3_pair(BRING_ABOUT, 4, max_steps=12)[0], seed=0, device="cpu").policy.state_dict()
    for key, value in a.policy.state_dict().items():
        assert torch.equal(value, b.policy.state_dict()[key])
        if key.endswith("weight"):
            assert not torch.equal(value, fresh[key])  # it trained


OVERLAPPING = """
#########
#.S.B...#
#...C.a.#
#.......#
#..D....#
#=======#
#.......#
#########
"""


def test_pushing_with_overlapping_objects_redraws_as_world_move() -> None:
    """Objects that start on one cell (no generated scene has them) take ``World.move``'s full-redraw path."""
    from pixelworld_env import PixelWorldEnv, Scene

    scene = Scene.from_ascii(OVERLAPPING)
    positions = [obj.position for obj in scene.objects]
    pushable = [i for i, obj in enumerate(scene.objects) if obj.pushable]
    positions[pushable[1]] = positions[pushable[0]]  # C on B
    scenes = [scene.with_positions(positions), scene]

    def make_env() -> PixelWorldEnv:
        return PixelWorldEnv(scenes, kind="bring-about", concept="?x pushable(x) & touches(self,x)", max_steps=15)

    a, b = PixelWorldVectorEnv(make_env(), 3), SyncVectorEnv([make_env for _ in range(3)])
    rng = np.random.default_rng(5)
    assert_same(a.reset(seed=1, options={"index": 0}), b.reset(seed=1, options={"index": 0}))
    rewards = 0
    for _ in range(300):
        actions = np.where(rng.random(3) < 0.03, 0, rng.integers(1, 5, size=3))
        result = a.step(actions)
        assert_same(result, b.step(actions))
        rewards += int(np.count_nonzero(result[1]))
    assert rewards > 10 and not a._pushing[8][0] and a._pushing[8][1]


@pytest.mark.parametrize("algo", ["TRPO", "RecurrentPPO"])
def test_trpo_and_recurrent_ppo_train_on_the_adapter_as_on_dummy_vec_env(algo: str) -> None:
    """The other learners of the package take the adapter too: the same rollout and update as over DummyVecEnv."""
    import torch
    from sb3_contrib import TRPO, RecurrentPPO

    cls, policy = {"TRPO": (TRPO, "MlpPolicy"), "RecurrentPPO": (RecurrentPPO, "MlpLstmPolicy")}[algo]
    models = []
    for venv in sb3_pair(BRING_ABOUT, 4, max_steps=12):
        model = cls(policy, venv, n_steps=32, batch_size=64, seed=0, device="cpu")
        model.learn(128)
        models.append(model)
    a, b = models
    np.testing.assert_array_equal(a.rollout_buffer.rewards, b.rollout_buffer.rewards)
    np.testing.assert_array_equal(a.rollout_buffer.actions, b.rollout_buffer.actions)
    assert a.num_timesteps == b.num_timesteps == 128
    for key, value in a.policy.state_dict().items():
        assert torch.equal(value, b.policy.state_dict()[key])


def test_self_moves_are_the_live_state_of_a_caller_that_moves_the_self():
    """``self_moves()``: the arrays a compiled caller moves the self through (the vector env keeps reading them),
    ``goal_at`` the single env's goal test memoised per scene and cell, ``observe`` the observations now; refused
    where objects besides the self move."""
    vector = gym.make_vec(BRING_ABOUT, num_envs=3, vectorization_mode="vector_entry_point")
    assert vector.self_only
    first, _ = vector.reset(seed=4)
    state = vector.self_moves()
    np.testing.assert_array_equal(vector.observe(), first)
    single = gym.make(BRING_ABOUT).unwrapped
    single.reset(options={"index": int(state.scene[0])})
    for row in range(1, state.goal_table.shape[1] - 1):  # a column of cells: each tested as the single env does
        cell = (row, int(state.col[0]))
        assert vector.goal_at(int(state.scene[0]), *cell) == single.goal_at(cell)
        assert state.goal_table[state.scene[0], cell[0], cell[1]] == int(single.goal_at(cell))
    down = vector.action_names.index("DOWN")
    assert state.kinds[down] == 1 and tuple(state.deltas[down]) == (1, 0)
    state.row[1] -= 1  # the caller moved the self of environment 1 up a cell: the next observation shows it
    moved = vector.observe()
    np.testing.assert_array_equal(moved[0], first[0])
    assert not np.array_equal(moved[1], first[1])
    pushing = gym.make_vec(PUSHABLE_MIXED, num_envs=2, vectorization_mode="vector_entry_point")
    assert not pushing.self_only
    with pytest.raises(ValueError, match="objects besides the self move in scenes"):
        pushing.self_moves()
