"""The table of task kinds (:mod:`pixelworld_env.core.kinds`): every step path reads it, so every path gives the same
rewards and outcomes for every kind, and a kind not in the table is an error everywhere."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces

from pixelworld_env import PixelWorldEnv, Scene
from pixelworld_env.concepts import Concept
from pixelworld_env.core.kinds import KINDS, TASK_KINDS, signal_outcomes
from pixelworld_env.core.world import World
from pixelworld_env.envs.registration import register_worlds
from pixelworld_env.envs.vector import PixelWorldVectorEnv
from pixelworld_env.errors import PixelWorldError
from pixelworld_env.generation.dataset_spec import DatasetSpec
from pixelworld_env.generation.oracle import ReachabilityLimit, can_bring_about, plan_moves
from sb3_smc.core.layout import smc_action_names
from sb3_smc.envs.hierarchical_vec_env import HierarchicalSMCVecEnv
from sb3_smc.envs.vec_env import SMCVecEnv
from sb3_smc.envs.wrapper import HierarchicalSMCWrapper
from sb3_smc.errors import SMCError
from sb3_smc.learning.training import make_vec_env
from sb3_smc.records import TrainingSpec
from sb3_smc.tasks.task import SMCTask
from tests.helpers import IN_CONTAINER, step_side_by_side
from tests.test_compiled_calls import compare, directed_smc, random_smc

POSSIBLE = """
###########
#b.b..S...#
#bbb......#
#...a...a.#
#...a...a.#
#...aaaaa.#
#=========#
#.........#
###########
"""
WALLED_IN = POSSIBLE.replace("#b.b..S...#", "#bSb......#")
SHAPES = {"a": "container"}
MOVES = ("DOWN", "RIGHT", "UP", "LEFT")


def scenes() -> list[Scene]:
    return [Scene.from_ascii(POSSIBLE, SHAPES), Scene.from_ascii(WALLED_IN, SHAPES)]


def labels_for(kind: str) -> list[int] | None:
    """The two scenes' labels: the concept holds in neither at the start; the goal is possible in the first only."""
    return {"classification": [1, 0], "bring-about": None, "bring-about-or-cannot": [1, 0]}[kind]


def env_of(kind: str, **kwargs) -> PixelWorldEnv:
    return PixelWorldEnv(scenes(), kind=kind, concept=IN_CONTAINER, labels=labels_for(kind), **kwargs)


def test_the_exhaustive_search_certifies_the_walled_in_world() -> None:
    concept = Concept(IN_CONTAINER)
    possible, walled = scenes()
    assert can_bring_about(concept, possible) and not can_bring_about(concept, walled)
    assert plan_moves(World(possible), concept) == ["DOWN", "DOWN", "DOWN"]
    with pytest.raises(ReachabilityLimit, match="more than 3 states"):  # a search cut short does not answer
        can_bring_about(concept, possible, max_states=3)
    assert not can_bring_about(concept, walled, max_states=2)  # its one cell: searched to the end
    # without labels, the cannot kind asks the search
    assert PixelWorldEnv(scenes(), kind="bring-about-or-cannot", concept=IN_CONTAINER).labels == (1, 0)


def test_the_table_gives_each_signal_one_outcome_and_every_wrong_signal_minus_one() -> None:
    assert signal_outcomes() == {"SIG0": -1.0, "SIG1": 1.0, "CANNOT": -1.0}
    cannot = TASK_KINDS["bring-about-or-cannot"]
    sig1, no = cannot.signal_names.index("SIG1"), cannot.signal_names.index("CANNOT")
    potential = 0.5
    assert cannot.reward(sig1, 1, True) + potential == 1.0 and cannot.reward(sig1, 1, False) == 0.0
    assert cannot.reward(no, 0, False) == 1.0 and cannot.reward(no, 1, False) == -1.0
    assert cannot.reward(no, 1, True) + potential == -1.0  # a wrong cannot gives the collected potential back
    assert [k.cut_outcome for k in TASK_KINDS.values()] == [0.0, 0.0, -0.5]


@pytest.mark.parametrize("make", [
    lambda: PixelWorldEnv(scenes(), kind="bringabout", concept=IN_CONTAINER),
    lambda: SMCTask(gym.make("CartPole-v1"), "bringabout", goal=lambda e: True),
    lambda: smc_action_names("bringabout"),
    lambda: DatasetSpec(name="d", kind="cannot", concept=IN_CONTAINER, generators=(("g", "x"),)),
    lambda: register_worlds("Kinds-unknown-v0", kind="cannot", concept=IN_CONTAINER, train=[POSSIBLE],
                            test=[POSSIBLE], kinds=SHAPES),
])
def test_an_unknown_kind_is_an_error_everywhere(make) -> None:
    with pytest.raises((PixelWorldError, SMCError), match="kind must be one of"):
        make()


class MovesOnly(gym.Env):
    """The worlds of a PixelWorld env with only its four moves: an environment for ``SMCTask``."""

    def __init__(self, env: PixelWorldEnv) -> None:
        self.pw = env
        self.action_space = spaces.Discrete(4)
        self.observation_space = env.observation_space

    def reset(self, *, seed=None, options=None):
        return self.pw.reset(seed=seed, options=options)

    def step(self, action):
        self.pw.apply_move(self.pw.action_names.index(MOVES[int(action)]))
        return self.pw.hand_observation(), 0.0, False, False, {}


def smc_task(kind: str) -> SMCTask:
    world = MovesOnly(env_of("bring-about"))
    label = labels_for(kind)
    functions = {"goal": lambda e: e.pw.goal_holds(), "label": lambda e: label[e.pw._index],
                 "possible": lambda e: bool(label[e.pw._index])}
    kind_ = TASK_KINDS[kind]
    given = {name: functions[name] for name in ("goal", kind_.label) if name is not None
             and (name != "goal" or kind_.tracks_goal)}
    return SMCTask(world, kind, primitive_names=MOVES, **given)


def returns_on_every_path(kind: str, scene: int, actions: list[str]) -> list[list[float]]:
    """The rewards of ``actions`` (names) from ``scene``'s start on the single env, the native vector env, an
    SMCTask over the same worlds and the SMC wrapper's top level."""
    single = env_of(kind)
    vector = PixelWorldVectorEnv(env_of(kind), 2)
    task = smc_task(kind)
    wrapper = HierarchicalSMCWrapper(env_of(kind), [])
    out = []
    for path in ("single", "vector", "task", "wrapper"):
        env = {"single": single, "task": task, "wrapper": wrapper}.get(path)
        if path == "vector":
            vector.reset(seed=0, options={"index": scene})
        else:
            env.reset(seed=0, options={"index": scene})
        names = env.action_names if env is not None else single.action_names
        rewards = []
        for name in actions:
            if path == "vector":
                _, reward, *_ = vector.step(np.full(2, names.index(name)))
                rewards.append(float(reward[0]))
            else:
                rewards.append(float(env.step(names.index(name))[1]))
        out.append(rewards)
    return out


@pytest.mark.parametrize("kind", KINDS)
def test_every_step_path_gives_the_same_rewards(kind: str) -> None:
    moves = ["DOWN", "DOWN", "DOWN", "UP", "DOWN"]
    for scene in (0, 1):
        for signal in TASK_KINDS[kind].signal_names:
            paths = returns_on_every_path(kind, scene, [*moves, signal])
            assert all(p == paths[0] for p in paths), (scene, signal, paths)
            total = sum(paths[0])
            expected = {  # the episode's return, shaping included
                ("classification", 0, "SIG1"): 1.0, ("classification", 0, "SIG0"): -1.0,
                ("classification", 1, "SIG1"): -1.0, ("classification", 1, "SIG0"): 1.0,
                ("bring-about", 0, "SIG1"): 1.0, ("bring-about", 1, "SIG1"): 0.0,
                ("bring-about-or-cannot", 0, "SIG1"): 1.0, ("bring-about-or-cannot", 0, "CANNOT"): -1.0,
                ("bring-about-or-cannot", 1, "SIG1"): 0.0, ("bring-about-or-cannot", 1, "CANNOT"): 1.0,
            }[kind, scene, signal]
            assert total == expected
    shaping = returns_on_every_path(kind, 0, moves)[0]
    assert shaping == ([0.0] * 5 if kind == "classification" else [0.0, 0.0, 0.5, -0.5, 0.5])


@pytest.mark.parametrize("record_cells", [False, True])  # the compiled call and the Python loop
def test_a_parent_tells_done_cannot_cut_and_not_called_apart(record_cells: bool) -> None:
    kids = [directed_smc(name, action, kind) for name, action, kind in (
        ("cannot", "CANNOT", "bring-about-or-cannot"), ("done", "SIG1", "bring-about-or-cannot"),
        ("cut", "LEFT", "bring-about-or-cannot"), ("cut_ba", "LEFT", "bring-about"),
        ("never", "SIG1", "bring-about-or-cannot"))]
    wrapper = HierarchicalSMCWrapper(env_of("bring-about-or-cannot"), kids, record_cells=record_cells)
    wrapper.reset(seed=0, options={"index": 1})
    for kid in kids[:4]:
        wrapper.step(wrapper.action_names.index(f"SMC:{kid.name}"))
    np.testing.assert_array_equal(wrapper.outcomes, [-1.0, 1.0, -0.5, 0.0, 0.0])


@pytest.mark.parametrize("kind", KINDS)
def test_compiled_calls_and_the_native_vector_env_agree_for_every_kind(kind: str) -> None:
    """Children of every kind, on a task of every kind: the compiled leaf call is the wrapper's Python loop, and
    HierarchicalSMCVecEnv's compiled steps are SMCVecEnv's over wrappers."""
    kids = tuple(random_smc(f"k{i}", k, "lstm", seed=i) for i, k in enumerate(KINDS))
    assert compare(lambda: env_of(kind, max_steps=30), kids, seed=1, steps=200) > 30
    env_id = register_worlds(f"PW-kinds-{kind}-v0", kind=kind, concept=IN_CONTAINER, train=[POSSIBLE, WALLED_IN],
                             test=[POSSIBLE, WALLED_IN], train_labels=labels_for(kind), test_labels=labels_for(kind),
                             kinds=SHAPES) if f"PW-kinds-{kind}-v0" not in gym.registry else f"PW-kinds-{kind}-v0"
    spec = TrainingSpec.create(env_id, seed=3, n_envs=4, children=[c.name for c in kids])
    reference, native = make_vec_env(spec, kids, native=False), make_vec_env(spec, kids)
    assert isinstance(reference.unwrapped, SMCVecEnv) and isinstance(native.unwrapped, HierarchicalSMCVecEnv)
    ended, infos = step_side_by_side(native, reference, 200, ("is_success", "primitive_steps", "smc_calls",
                                                              "TimeLimit.truncated"))
    assert ended > 50 and sum(len(info["smc_calls"]) for info in infos) > 200
