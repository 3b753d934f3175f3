"""A task resolved once (sb3_smc.tasks.resolved_task): what an env id names, its environments, and the one look-up of
the id on the way from train_smc / train_smcs / make_smc_env to a step; the records stay free of Gymnasium."""

from __future__ import annotations

import ast
import dataclasses
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import pixelworld_env  # noqa: F401  (registers the PW-* ids)
import sb3_smc.tasks.resolved_task as resolver
from pixelworld_env.envs.env import PixelWorldEnv
from pixelworld_env.envs.vector import PixelWorldVectorEnv
from sb3_smc.core.layout import PIXELWORLD_LAYOUT, Layout
from sb3_smc.envs.factory import make_smc_env
from sb3_smc.envs.hierarchical_vec_env import HierarchicalSMCVecEnv
from sb3_smc.envs.vec_env import FlatSMCVecEnv, SMCVecEnv
from sb3_smc.errors import SMCError
from sb3_smc.learning.batched import train_smcs
from sb3_smc.learning.training import make_vec_env, untrained_smc
from sb3_smc.records import TaskSpec, TrainingSpec
from sb3_smc.tasks.resolved_task import TaskSource, resolve_task
from sb3_smc.tasks.task import SMCTask

ROOT = Path(__file__).resolve().parents[1]
ID = "PW-ba_self-in-container-v0"
CLASSIFY_ID = "PW-cl_self-in-container_vs_noncontainer-v0"
CORRIDOR_ID = "ResolvedTaskCorridor-v0"


class _Corridor(gym.Env):
    """Five cells in a row; actions left, right, stay."""

    def __init__(self) -> None:
        self.observation_space = gym.spaces.Box(0.0, 1.0, shape=(5,), dtype=np.float32)
        self.action_space = gym.spaces.Discrete(3)
        self.pos = 0

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.pos = int(self.np_random.integers(0, 4))
        return np.eye(5, dtype=np.float32)[self.pos], {}

    def step(self, action):
        self.pos = min(4, max(0, self.pos + (-1, 1, 0)[int(action)]))
        return np.eye(5, dtype=np.float32)[self.pos], 0.0, False, False, {}


def _corridor_id() -> str:
    if CORRIDOR_ID not in gym.registry:
        gym.register(CORRIDOR_ID, entry_point=lambda max_steps=100: SMCTask(
            _Corridor(), "bring-about", goal=lambda env: env.pos == 4, primitive_names=("L", "R", "S"),
            max_steps=max_steps))
    return CORRIDOR_ID


@pytest.fixture
def look_ups(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """The ids looked up in Gymnasium's registry, one entry per look-up."""
    seen: list[str] = []
    look_up = resolver._look_up

    def counting(env_id: str):
        seen.append(env_id)
        return look_up(env_id)

    monkeypatch.setattr(resolver, "_look_up", counting)
    return seen


def test_a_pixelworld_id_resolves_to_its_datasets_kind_layout_and_native_vector_env() -> None:
    task = resolve_task(TaskSpec(ID, split="test"))
    assert task.source is TaskSource.PIXELWORLD and task.native_vector
    assert task.kind == "bring-about" and len(task.datasets) > 1 and task.layout == PIXELWORLD_LAYOUT
    assert task.spec_fields == {"kind": "bring-about", "datasets": task.datasets, "layout": None}
    env = task.make_env(9, smc="x")
    assert isinstance(env.unwrapped, PixelWorldEnv) and env.unwrapped.split == "test" and env.unwrapped.max_steps == 9
    assert task.make_env(9, smc="x", split="train").unwrapped.split == "train"
    vector = task.make_vector_env(3, 9)
    assert isinstance(vector, PixelWorldVectorEnv) and vector.num_envs == 3 and vector.max_steps == 9
    buggy = resolve_task(TaskSpec(ID, env_kwargs={"aaai18_reset_bug": True}))
    assert buggy.source is TaskSource.PIXELWORLD and not buggy.native_vector
    with pytest.raises(SMCError, match="native vector env hosts PW-\\* ids without aaai18_reset_bug"):
        buggy.make_vector_env(2, 9)


def test_a_registered_task_is_described_once_and_only_when_asked(monkeypatch: pytest.MonkeyPatch) -> None:
    env_id = _corridor_id()
    described: list[str] = []
    describe = resolver.describe_task
    monkeypatch.setattr(resolver, "describe_task", lambda *args: described.append(args[0]) or describe(*args))
    task = resolve_task(TaskSpec(env_id))
    assert task.source is TaskSource.REGISTERED and not task.native_vector and task.datasets == ()
    assert isinstance(task.make_env(20, smc="walker").unwrapped, _Corridor) and described == []  # building: no need
    assert task.kind == "bring-about" and task.layout == Layout(5, ("L", "R", "S"))
    assert task.spec_fields["layout"] == Layout(5, ("L", "R", "S")) and described == [env_id]  # once, then kept
    given = resolve_task(TaskSpec(env_id, kind="bring-about", layout=Layout(5, ("L", "R", "S"))))
    assert given.kind == "bring-about" and described == [env_id]  # kind and layout given: no instance built


def test_task_spec_resolved_delegates_to_the_resolver() -> None:
    for spec in (TaskSpec(ID), TaskSpec(CLASSIFY_ID, split="test"), TaskSpec(_corridor_id()),
                 TaskSpec("NoSuchEnvAnywhere-v0"), TaskSpec(ID, kind="bring-about")):
        resolved = spec.resolved()
        assert resolved.to_dict() == dataclasses.replace(spec, **resolve_task(spec).spec_fields).to_dict()
    unknown = resolve_task(TaskSpec("NoSuchEnvAnywhere-v0"))
    assert unknown.source is TaskSource.UNREGISTERED and unknown.kind is None and not unknown.native_vector
    assert TaskSpec(ID).resolved().to_dict() == {"env_id": ID, "split": "train", "kind": "bring-about",
                                                 "datasets": list(resolve_task(TaskSpec(ID)).datasets),
                                                 "env_kwargs": {}}


def test_bad_ids_and_kwargs_are_refused_with_their_messages() -> None:
    with pytest.raises(SMCError, match=r"SMC 'x': unknown environment id 'CartPole-v9': .*\[ `v0`, `v1` \]"):
        resolve_task(TaskSpec("CartPole-v9"), smc="x")
    with pytest.raises(SMCError, match=r"SMC 'x': unknown environment id 'ba_self-in-container': .*PixelWorld's "
                                       r"'ba_self-in-container' is the id 'PW-ba_self-in-container-v0'"):
        resolve_task(TaskSpec("ba_self-in-container"), smc="x")
    with pytest.raises(SMCError, match=rf"env_kwargs: {ID} takes no argument 'obsrvation' .*did you mean "
                                       "'observation'"):
        resolve_task(TaskSpec(ID, env_kwargs={"obsrvation": "hand"}))
    lenient = resolve_task(TaskSpec("CartPole-v9"))  # a record may name an id registered later
    with pytest.raises(SMCError, match="SMC 'y': unknown environment id 'CartPole-v9'"):
        lenient.make_env(10, smc="y")
    task = resolve_task(TaskSpec(ID))
    with pytest.raises(SMCError, match=r"env_kwargs \['split'\]: the split is make_smc_env's split="):
        task.make_env(10, smc="x", env_kwargs={"split": "test"})
    assert resolve_task(TaskSpec("CartPole")).registration.id == "CartPole-v1"  # gym.make's latest version


def test_train_smc_refuses_a_bad_id_or_kwarg_before_any_work(monkeypatch: pytest.MonkeyPatch) -> None:
    import sb3_smc.learning.training as training

    def no_work(*args, **kwargs):
        raise AssertionError("work started")

    monkeypatch.setattr(training, "check_model_settings", no_work)
    monkeypatch.setattr(training, "make_vec_env", no_work)
    with pytest.raises(SMCError, match="SMC 'CartPole': unknown environment id 'CartPole-v9'"):
        training.train_smc("CartPole-v9", total_timesteps=10, n_envs=1)
    with pytest.raises(SMCError, match="takes no argument 'spilt'"):
        training.train_smc(ID, total_timesteps=10, n_envs=1, env_kwargs={"spilt": "test"})
    spec = TrainingSpec(name="typo", task=TaskSpec("PW-ba_self-in-containr-v0", kind="bring-about"))
    with pytest.raises(SMCError, match="SMC 'typo': unknown environment id .*Did you mean"):
        training.train_smc(spec)


def test_train_smc_looks_the_id_up_once(look_ups: list[str]) -> None:
    flat = untrained_smc(ID, n_envs=3)
    assert isinstance(flat.model.get_env().unwrapped, FlatSMCVecEnv) and look_ups == [ID]
    look_ups.clear()
    untrained_smc(flat.spec)
    assert look_ups == [ID]
    look_ups.clear()
    parent = untrained_smc(CLASSIFY_ID, children=[flat], n_envs=3)  # a compiled leaf's caller: the native env
    assert isinstance(parent.model.get_env().unwrapped, HierarchicalSMCVecEnv) and look_ups == [CLASSIFY_ID]
    look_ups.clear()
    assert parent.spec is not None
    wrapped = make_vec_env(parent.spec, [flat], native=False)  # three wrapped environments, one look-up
    assert isinstance(wrapped.unwrapped, SMCVecEnv) and wrapped.num_envs == 3 and look_ups == [CLASSIFY_ID]
    look_ups.clear()
    walker = untrained_smc(_corridor_id(), algo="PPO", n_envs=2, n_steps=64, batch_size=64)
    assert walker.spec.task.layout == Layout(5, ("L", "R", "S")) and look_ups == [CORRIDOR_ID]


def test_train_smcs_looks_a_group_task_up_once(look_ups: list[str]) -> None:
    specs = [TrainingSpec.create(ID, total_timesteps=64, n_envs=2, n_steps=32, seed=seed) for seed in (0, 1, 2)]
    look_ups.clear()
    smcs = train_smcs(specs)
    assert [smc.spec.seed for smc in smcs] == [0, 1, 2] and look_ups == [ID]


def test_make_smc_env_builds_with_a_resolved_task_without_looking_up(look_ups: list[str]) -> None:
    spec = TrainingSpec.create(ID, max_steps=7)
    task = resolve_task(spec.task, smc=spec.name)
    look_ups.clear()
    envs = [make_smc_env(spec, task=task) for _ in range(3)]
    assert look_ups == [] and all(env.unwrapped.max_steps == 7 for env in envs)
    make_smc_env(spec, env_id=CLASSIFY_ID, task=task)  # another id: resolved for itself
    assert look_ups == [CLASSIFY_ID]
    with pytest.raises(SMCError, match="give either env, or env_id / split / env_kwargs / task"):
        make_smc_env(spec, env=gym.make(ID), task=task)


def test_the_records_import_no_gymnasium_and_resolve_through_the_resolver() -> None:
    """No module of sb3_smc.records imports Gymnasium, numba, torch or a module that builds environments, at any
    level; ``TaskSpec.resolved`` imports only the resolver, inside the function."""
    heavy = ("gymnasium", "numba", "torch", "stable_baselines3", "sb3_contrib", "pixelworld_env.envs",
             "pixelworld_env.datasets", "sb3_smc.tasks.task", "sb3_smc.envs.factory", "sb3_smc.learning.training")
    found = {}
    for path in sorted((ROOT / "sb3_smc" / "records").glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = ([alias.name for alias in node.names] if isinstance(node, ast.Import)
                     else [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            bad = [name for name in names if any(name == h or name.startswith(h + ".") for h in heavy)]
            if bad:
                found.setdefault(path.name, []).extend(bad)
    assert found == {}
    resolved = TaskSpec.resolved
    assert "sb3_smc.tasks.resolved_task" in ast.dump(ast.parse(_source(resolved)))


def _source(function) -> str:
    import inspect
    import textwrap

    return textwrap.dedent(inspect.getsource(function))
