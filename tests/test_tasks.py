"""SMCs on any Gymnasium environment: SMCTask's rules, observations and errors; SMC calls on a foreign environment;
train_smc on a registered task; Minigrid."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces

from sb3_smc import SMC, HierarchicalSMCWrapper, train_smc
from sb3_smc.core.layout import Layout
from sb3_smc.errors import SMCError, SMCTypeError
from sb3_smc.smc.policies import ScriptedPolicy
from sb3_smc.tasks.task import SMCTask, TaskEnv, layout_of, task_layer

LEFT, RIGHT, STAY = 0, 1, 2


class Corridor(gym.Env):
    """Cells 0..length-1, the agent starts at ``start`` (or a drawn cell); actions left, right, stay. The
    environment's own reward (ignored by tasks) is -1 per step; it terminates at the last cell when
    ``end_at_last`` is set. Observation: the cell, one-hot (Discrete)."""

    def __init__(self, length: int = 5, start: int | None = 0, end_at_last: bool = False) -> None:
        self.length, self.start, self.end_at_last = length, start, end_at_last
        self.observation_space = spaces.Discrete(length)
        self.action_space = spaces.Discrete(3)
        self.position = 0

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        self.position = self.start if self.start is not None else int(self.np_random.integers(self.length))
        return self.position, {}

    def step(self, action):
        self.position = int(np.clip(self.position + (-1, 1, 0)[action], 0, self.length - 1))
        return self.position, -1.0, self.end_at_last and self.position == self.length - 1, False, {}


def at_end(env: gym.Env) -> bool:
    return env.position == env.length - 1


def right_half(env: gym.Env) -> int:
    return int(env.position >= env.length // 2)


def bring_about(**kwargs: Any) -> SMCTask:
    return SMCTask(Corridor(**kwargs), "bring-about", goal=at_end, primitive_names=("L", "R", "S"))


def test_bring_about_rewards_are_the_papers() -> None:
    task = bring_about()
    obs, info = task.reset(seed=0)
    assert task.action_names == ("SIG1", "L", "R", "S") and task.sensor_size == 5
    assert obs.tolist() == [1, 0, 0, 0, 0] and obs.dtype == np.float32 and info["goal"] is False
    rewards = [task.step(task.action_names.index(name))[1] for name in ("R", "R", "R", "R")]
    assert rewards == [0.0, 0.0, 0.0, 0.5]  # the goal became true: +0.5 (the environment's -1 is dropped)
    assert task.step(task.action_names.index("L"))[1] == -0.5  # and false again
    task.step(task.action_names.index("R"))
    _, reward, terminated, truncated, info = task.step(0)  # SIG1 with the goal true
    assert (reward, terminated, truncated, info["is_success"], info["signalled"]) == (0.5, True, False, True, True)
    task.reset(seed=0)
    _, reward, terminated, _, info = task.step(0)  # SIG1 without the goal
    assert (reward, terminated, info["is_success"]) == (0.0, True, False)


def test_classification_label_and_episode_limit() -> None:
    task = SMCTask(Corridor(start=None), "classification", label=right_half, max_steps=3)
    assert task.action_names == ("SIG0", "SIG1", "A0", "A1", "A2")  # the environment names no actions
    for seed in range(6):
        _, info = task.reset(seed=seed)
        label = info["label"]
        assert label == right_half(task.unwrapped)
        _, reward, terminated, _, _ = task.step(label)  # SIG<label>
        assert (reward, terminated) == (1.0, True)
        task.reset(seed=seed)
        assert task.step(1 - label)[1] == -1.0
    task.reset(seed=0)
    results = [task.step(4)[1:4] for _ in range(3)]  # three primitives: 0 reward, cut at max_steps
    assert results == [(0.0, False, False), (0.0, False, False), (0.0, False, True)]


def test_an_environment_that_ends_its_episode_ends_the_tasks() -> None:
    task = bring_about(end_at_last=True)
    task.reset(seed=0)
    for _ in range(3):
        task.step(2)
    _, reward, terminated, truncated, info = task.step(2)  # reaches the last cell: the env terminates
    assert (reward, terminated, truncated) == (1.0, True, False)  # +0.5 shaping, +0.5 as SIG1 would pay
    assert info["is_success"] and not info["signalled"]


def test_observations_are_flattened_or_refused_by_name() -> None:
    dict_env = gym.make("CartPole-v1")
    assert SMCTask(dict_env, "bring-about", goal=lambda env: False).sensor_size == 4

    class Talker(Corridor):
        def __init__(self) -> None:
            super().__init__()
            self.observation_space = spaces.Dict({"cell": spaces.Discrete(5), "words": spaces.Text(10)})

        def reset(self, *, seed=None, options=None):
            cell, info = super().reset(seed=seed)
            return {"cell": cell, "words": "hi"}, info

        def step(self, action):
            cell, *rest = super().step(action)
            return ({"cell": cell, "words": "hi"}, *rest)

    with pytest.raises(SMCError, match=r"the environment's observation\['words'\] is Text.*observation=\[keys\]"):
        SMCTask(Talker(), "bring-about", goal=at_end)
    task = SMCTask(Talker(), "bring-about", goal=at_end, observation=["cell"])
    assert task.sensor_size == 5 and task.reset(seed=0)[0].tolist() == [1, 0, 0, 0, 0]
    with pytest.raises(SMCError, match=r"observation keys \['cells'\] are not in .* \['cell', 'words'\]"):
        SMCTask(Talker(), "bring-about", goal=at_end, observation=["cells"])
    custom = SMCTask(Talker(), "bring-about", goal=at_end, observation=lambda obs: [obs["cell"] / 4])
    assert custom.sensor_size == 1
    with pytest.raises(SMCError, match="Discrete action space"):
        SMCTask(gym.make("Pendulum-v1"), "bring-about", goal=lambda env: False)
    with pytest.raises(SMCTypeError, match="a classification task needs label=function"):
        SMCTask(Corridor(), "classification", goal=at_end)
    with pytest.raises(SMCError, match="primitive_names has 2 names, but the environment has 3 actions"):
        SMCTask(Corridor(), "bring-about", goal=at_end, primitive_names=("L", "R"))


def test_smc_calls_on_a_foreign_environment() -> None:
    """A child that walks right until the goal holds, then signals, called by the wrapper over an SMCTask: its
    moves step the environment, its shaping is the call's reward, its signal the outcome."""
    task = bring_about()
    layout = layout_of(task)
    assert task_layer(gym.wrappers.OrderEnforcing(task)) is task and isinstance(task, TaskEnv)
    names = ("SIG1", "L", "R", "S")
    walker = SMC("walker", "bring-about", ScriptedPolicy(4, lambda obs, step: 2 if obs[4] == 0 else 0),
                 layout=layout)
    env = HierarchicalSMCWrapper(task, [walker])
    assert env.action_names == (*names, "SMC:walker")
    assert env.observation_space.shape == (5 + 1 + 5,)
    obs, _ = env.reset(seed=0)
    obs, reward, terminated, truncated, info = env.step(4)  # the call
    assert reward == 0.5 and not terminated and not truncated and info["primitive_steps"] == 4
    assert info["smc_calls"] == [{"smc": "walker", "depth": 1, "primitive_steps": 4, "outcome": 1, "reward": 0.5}]
    assert obs[:5].tolist() == [0, 0, 0, 0, 1] and obs[5] == 1.0 and obs[6 + 4] == 1.0  # sensor, outcome, previous
    assert env.step(0)[1] == 0.5  # SIG1 with the goal true


def test_a_call_ends_when_the_environment_ends_the_episode() -> None:
    task = bring_about(end_at_last=True)
    walker = SMC("walker", "bring-about", ScriptedPolicy(4, lambda obs, step: 2), layout=layout_of(task))
    env = HierarchicalSMCWrapper(task, [walker])
    env.reset(seed=0)
    _, reward, terminated, truncated, info = env.step(4)
    assert (reward, terminated, truncated) == (1.0, True, False) and info["primitive_steps"] == 4
    assert info["smc_calls"][0]["outcome"] == 0  # ended without a signal


def test_children_of_another_layout_are_refused() -> None:
    pixel = SMC("pixel", "bring-about", ScriptedPolicy(5, lambda obs, step: 0))  # PixelWorld's layout
    with pytest.raises(SMCError, match=r"SMC 'pixel' acts on another environment layout .* trained on another"):
        HierarchicalSMCWrapper(bring_about(), [pixel])
    other = SMC("other", "bring-about", ScriptedPolicy(4, lambda obs, step: 0), layout=Layout(7, ("L", "R", "S")))
    with pytest.raises(SMCError, match="another environment layout"):
        HierarchicalSMCWrapper(bring_about(), [other])


def _register_corridor() -> str:
    env_id = "TestCorridorAtEnd-v0"
    if env_id not in gym.registry:
        gym.register(env_id, entry_point=lambda max_steps=100: SMCTask(
            Corridor(start=None), "bring-about", goal=at_end, primitive_names=("L", "R", "S"), max_steps=max_steps))
    return env_id


def test_train_smc_on_a_registered_task_learns_and_records_its_layout() -> None:
    env_id = _register_corridor()
    smc = train_smc(env_id, algo="PPO", total_timesteps=6_000, n_envs=4, n_steps=128, seed=0, max_steps=20,
                    batch_size=128, log_every=0)
    assert smc.layout == Layout(5, ("L", "R", "S")) and smc.spec.task.layout == smc.layout
    assert smc.spec.task.kind == "bring-about" and smc.action_names == ("SIG1", "L", "R", "S")
    assert smc.spec.task.to_dict()["layout"] == {"sensor_size": 5, "primitives": ["L", "R", "S"]}
    assert type(smc.spec).from_json(smc.spec.to_json()) == smc.spec
    returns = smc.record.training_returns
    assert max(returns[-3:]) > returns[0] + 0.3  # learns to walk right and signal (return 1 at best)
    again = train_smc(env_id, algo="PPO", total_timesteps=6_000, n_envs=4, n_steps=128, seed=0, max_steps=20,
                      batch_size=128, log_every=0)
    assert again.record.training_returns == returns  # the same seed, the same run


minigrid = pytest.importorskip("minigrid")


def has_key(env: gym.Env) -> bool:
    return env.carrying is not None and env.carrying.type == "key"


def test_minigrid_doorkey_as_an_smc_task() -> None:
    task = SMCTask(gym.make("MiniGrid-DoorKey-5x5-v0"), "bring-about", goal=has_key, observation=("image", "direction"))
    assert task.primitive_names == ("left", "right", "forward", "pickup", "drop", "toggle", "done")
    assert task.sensor_size == 7 * 7 * 3 + 4
    obs, info = task.reset(seed=3)
    assert obs.shape == (151,) and info["goal"] is False
    assert np.array_equal(obs[-4:], np.eye(4)[task.unwrapped.agent_dir])
    with pytest.raises(SMCError, match=r"observation\['mission'\] is MissionSpace.*observation=\[keys\]"):
        SMCTask(gym.make("MiniGrid-DoorKey-5x5-v0"), "bring-about", goal=has_key)
    random = SMC("random", "bring-about", ScriptedPolicy(8, lambda obs, step: 1 + step % 7), layout=layout_of(task))
    env = HierarchicalSMCWrapper(task, [random], call_step_cap=20)
    env.reset(seed=3)
    _, _, _, _, info = env.step(len(env.action_names) - 1)
    assert info["smc_calls"][0]["primitive_steps"] == 20  # never signals: cut at the cap


def test_evaluate_on_a_task_without_datasets_uses_start_seeds() -> None:
    from sb3_smc import evaluate
    from sb3_smc.learning.evaluation import FOREIGN_TEST_SEED, start_seed
    from sb3_smc.records import TaskSpec, TrainingSpec

    env_id = _register_corridor()
    layout = Layout(5, ("L", "R", "S"))
    spec = TrainingSpec(name="walker", task=TaskSpec(env_id, kind="bring-about", layout=layout))
    walker = SMC("walker", "bring-about", ScriptedPolicy(4, lambda obs, step: 2 if obs[4] == 0 else 0),
                 layout=layout, spec=spec)
    result = evaluate(walker, starts=7, repeats=2, seed=3)
    assert result.score == 1.0 and len(result.environments) == 7 and result.n_episodes == 14
    starts = [Corridor(start=None).reset(seed=start_seed("test", i))[0] for i in range(7)]
    assert [e.length for e in result.episodes] == [5 - s for s in starts for _ in range(2)]  # moves + SIG1
    assert start_seed("test", 2) == FOREIGN_TEST_SEED + 2 and start_seed("train", 2) == 2
    assert walker.evaluations[-1].score == 1.0 and walker.evaluations[-1].split == "test"
    assert evaluate(walker, starts=7, repeats=2, seed=3).episodes == result.episodes  # deterministic
    with pytest.raises(SMCError, match="splits .*'train', 'test'.* got 'all'"):
        evaluate(walker, split="all", starts=2)


def test_the_doorkey_example_tasks_start_where_they_say() -> None:
    from sb3_smc.examples.minigrid_doorkey import door_open, register, task_id

    ids = register(5)
    assert ids == [task_id(5, t) for t in ("get-key", "open-door", "reach-goal", "doorkey")]
    starts = {}
    for env_id in ids:
        task = gym.make(env_id, max_steps=30)
        task.reset(seed=4)
        base = task.unwrapped
        starts[env_id] = (has_key(base), door_open(base))
        assert task_layer(task).max_steps == 30 and layout_of(task_layer(task)) == Layout(151, (
            "left", "right", "forward", "pickup", "drop", "toggle", "done"))
    assert list(starts.values()) == [(False, False), (True, False), (True, True), (False, False)]


def test_foreign_smcs_round_trip_through_a_library(tmp_path) -> None:
    import json

    from sb3_smc import SMCLibrary
    from sb3_smc.library import storage
    from sb3_smc.library.errors import LayoutMismatchError

    env_id = _register_corridor()
    settings = dict(algo="PPO", total_timesteps=256, n_envs=2, n_steps=128, batch_size=128, max_steps=20,
                    log_every=0)
    child = train_smc(env_id, seed=0, name="walk", **settings)
    parent = train_smc(env_id, seed=1, name="walk-twice", children=[child], **settings)
    library = SMCLibrary([parent])
    library.save(tmp_path / "lib")
    manifest = json.loads((tmp_path / "lib" / "manifest.json").read_text())
    assert manifest["smcs"]["walk-twice"]["spec"]["task"]["layout"] == {"sensor_size": 5, "primitives": ["L", "R", "S"]}
    entry = storage.check_manifest(manifest, tmp_path / "lib" / "manifest.json")["walk-twice"]
    assert entry.observation == {"size": 5 + 1 + 5, "sensor": 5, "outcomes": 1, "previous_action": 5}
    loaded = SMCLibrary.load(tmp_path / "lib")
    assert loaded["walk-twice"].layout == parent.layout and loaded["walk"].layout == child.layout
    assert loaded["walk-twice"].spec == parent.spec and loaded["walk-twice"].action_names == parent.action_names
    env = HierarchicalSMCWrapper(gym.make(env_id, max_steps=20), [loaded["walk"]])
    obs, _ = env.reset(seed=0)
    probabilities, _ = loaded["walk-twice"].policy.probabilities(obs, loaded["walk-twice"].policy.initial_state())
    ours, _ = parent.policy.probabilities(obs, parent.policy.initial_state())
    np.testing.assert_allclose(probabilities, ours)
    manifest["smcs"]["walk"]["spec"]["task"].pop("layout")  # the child now claims PixelWorld's layout
    storage.write_manifest(tmp_path / "lib" / "manifest.json", manifest)  # an edit meant to be kept
    with pytest.raises(LayoutMismatchError, match=r"SMC 'walk-twice' .* calls \['walk'\], which act on another"):
        SMCLibrary.load(tmp_path / "lib")


def test_a_curriculum_of_minigrid_tasks_trains_level_by_level(tmp_path) -> None:
    from sb3_smc import SMCLibrary
    from sb3_smc.curricula import load_curriculum, train_curriculum
    from sb3_smc.curricula.format import CurriculumError

    module = "sb3_smc.examples.minigrid_doorkey"
    path = tmp_path / "doorkey.yml"
    path.write_text(f"""curriculum: doorkey-tiny
defaults: {{timesteps: 1000, algo: PPO, hyperparameters: {{batch_size: 125}}}}
nodes:
  - name: get-key
    task: {module}:DoorKey5-get-key-v0
  - name: doorkey
    task: {module}:DoorKey5-doorkey-v0
    uses: [get-key]
""")
    run = train_curriculum(str(path), tmp_path / "run", seeds=1, reuse="one_best", progress=False)
    assert not run.failed
    library = SMCLibrary.load(tmp_path / "run" / "library")
    top = library["doorkey@0"]
    assert top.children == (library["get-key@0"],) and top.layout.sensor_size == 151
    assert top.action_names[-1] == "SMC:get-key@0" and top.spec.task.env_id == f"{module}:DoorKey5-doorkey-v0"
    bad = tmp_path / "bad.yml"
    bad.write_text("curriculum: bad\nnodes:\n  - name: x\n    task: NoSuchTask-v0\n")
    with pytest.raises(CurriculumError, match=r"bad.yml:3: node 'x': 'NoSuchTask-v0' is not a registered Gymnasium"):
        load_curriculum(str(bad))
