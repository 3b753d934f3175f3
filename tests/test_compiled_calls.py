"""Compiled leaf calls (:func:`sb3_smc.envs.leaf_calls.leaf_call`): a call of a child without children of its own,
with the default compiled actor, in a world where only the self moves, runs as one compiled loop. It must make the
same moves, draws, rewards, outcomes and move budgets as the wrapper's Python loop, which still runs everything else
(``record_cells=True`` forces it, so the two are compared side by side)."""

from __future__ import annotations

import copy

import gymnasium as gym
import numpy as np
import pytest

import pixelworld_env  # noqa: F401  (the PW-* ids)
from pixelworld_env import PixelWorldEnv, Scene
from pixelworld_env.core.world import World
from sb3_smc import SMC
from sb3_smc.core.layout import observation_size, smc_action_names
from sb3_smc.envs.wrapper import HierarchicalSMCWrapper
from sb3_smc.smc.numpy_actors import NumpyGRUPolicy, NumpyLSTMPolicy
from sb3_smc.smc.policies import ScriptedPolicy
from tests.helpers import CONTAINER, IN_CONTAINER, classification_env, make


def random_smc(name: str, kind: str, cell: str, children: tuple[SMC, ...] = (), seed: int = 0,
               signal_bias: float = -2.5) -> SMC:
    """An SMC with a random compiled numpy policy that favours moves (calls last several decisions)."""
    rng = np.random.default_rng(seed)
    names = smc_action_names(kind, [c.name for c in children])
    size, hidden = observation_size(len(children), len(names)), 8
    bias = np.array([signal_bias if n.startswith("SIG") else 0.0 for n in names])
    head = [("linear", rng.normal(size=(hidden, len(names))), bias)]
    if cell == "gru":
        gru = [(rng.normal(size=(size, 3 * hidden)), rng.normal(size=(hidden, 3 * hidden)),
                rng.normal(size=3 * hidden), rng.normal(size=3 * hidden))]
        policy = NumpyGRUPolicy(gru, head, size)
    else:
        lstm = [(rng.normal(size=(size, 4 * hidden)), rng.normal(size=(hidden, 4 * hidden)),
                 rng.normal(size=4 * hidden))]
        policy = NumpyLSTMPolicy(lstm, head, size)
    assert policy.compiled_weights is not None
    return SMC(name, kind, policy, children=children)


def episodes(wrapper: HierarchicalSMCWrapper, seed: int, steps: int) -> list:
    """Random top-level actions from ``seed``: every step's observation, reward, ends and info (without the cells
    that only the Python loop records)."""
    rng = np.random.default_rng(seed)
    out = []
    obs, _ = wrapper.reset(seed=seed)
    for _ in range(steps):
        obs, reward, terminated, truncated, info = wrapper.step(int(rng.integers(wrapper.action_space.n)))
        info = {k: v for k, v in info.items() if k not in ("cells", "moves")}
        world = wrapper.base.world
        out.append((obs.copy(), world.grid.copy(), world.owner.copy(), wrapper.base.goal_cells().copy(), reward,
                    terminated, truncated, info, world.self_position, wrapper.base.goal,
                    wrapper._rng.bit_generator.state["state"]))
        if terminated or truncated:
            obs, _ = wrapper.reset()
    return out


def compare(make_env, smcs, seed: int = 0, steps: int = 150, **kwargs) -> int:
    """Run the compiled and the Python loop side by side; return how many calls the compiled loop made."""
    compiled = HierarchicalSMCWrapper(make_env(), smcs, **kwargs)
    made = []
    original = compiled._compiled_call
    compiled._compiled_call = lambda *a: made.append(a[0].name) or original(*a)
    python = HierarchicalSMCWrapper(make_env(), smcs, record_cells=True, **kwargs)
    fast, slow = episodes(compiled, seed, steps), episodes(python, seed, steps)
    for a, b in zip(fast, slow, strict=True):
        for k in range(4):  # observation, the world's arrays, the goal memo
            np.testing.assert_array_equal(a[k], b[k])
        assert a[4:] == b[4:]  # rewards, ends, infos, the self's cell, the goal, the generator's state
    return len(made)


@pytest.mark.parametrize("cell", ["lstm", "gru"])
@pytest.mark.parametrize("kind", ["classification", "bring-about"])
def test_a_compiled_leaf_call_is_the_python_loop(kind: str, cell: str) -> None:
    leaves = (random_smc("a", "classification", cell, seed=1), random_smc("b", "bring-about", cell, seed=2),
              random_smc("quick", "bring-about", cell, seed=3, signal_bias=1.0))
    make_env = (lambda: classification_env(max_steps=30)) if kind == "classification" else (lambda: make(max_steps=30))
    made = compare(make_env, leaves, seed=4)
    assert made > 30


def three_scenes(**kwargs) -> PixelWorldEnv:
    """A bring-about env over three scenes (the goal memo is per scene)."""
    texts = [CONTAINER, CONTAINER.replace("#...S...#", "#S......#"), CONTAINER.replace("#...S...#", "#......S#")]
    return PixelWorldEnv([Scene.from_ascii(t, {"a": "container"}) for t in texts], kind="bring-about",
                         concept=IN_CONTAINER, **kwargs)


def test_scenes_time_modes_and_gym_make_wrappers() -> None:
    leaves = (random_smc("a", "bring-about", "lstm", seed=11), random_smc("b", "bring-about", "gru", seed=12))
    assert compare(lambda: three_scenes(max_steps=40), leaves, seed=1, steps=200) > 30
    assert compare(lambda: three_scenes(max_steps=40), leaves, seed=2, steps=200, count_primitive_steps=True,
                   call_step_cap=9) > 30
    target = "cl_self-in-container_vs_noncontainer"
    classifier = (random_smc("c", "classification", "lstm", seed=13),)
    assert compare(lambda: gym.make(f"PW-{target}-v0"), classifier, seed=3, steps=100) > 10  # order checks between


def test_policies_without_a_compiled_step_keep_the_python_loop() -> None:
    leaf = random_smc("leaf", "classification", "lstm", seed=1)
    numpy_code = copy.copy(leaf.policy)
    numpy_code._compiled = None
    assert compare(lambda: classification_env(max_steps=30), [SMC("leaf", "classification", numpy_code)],
                   seed=0, steps=40) == 0
    wrapper = HierarchicalSMCWrapper(classification_env(), [leaf])
    assert wrapper._leaf_plan(leaf) is not None
    leaf.policy = numpy_code  # a replaced policy is looked at again
    assert wrapper._leaf_plan(leaf) is None


def directed_smc(name: str, move: str, kind: str = "bring-about") -> SMC:
    """A compiled leaf of ``kind`` that (almost surely) takes action ``move`` every decision (a move: until its call
    is cut)."""
    smc = random_smc(name, kind, "lstm", seed=0)
    _, w_out, b_out = smc.policy.head[0]
    w_out *= 1e-3
    b_out[:] = [40.0 if n == move else 0.0 for n in smc.action_names]
    return smc


def test_goal_shaping_and_new_cells_inside_a_compiled_call() -> None:
    """Bring-about shaping needs the goal's truth of every cell the self enters: the compiled loop stops at a cell
    not evaluated yet, the env evaluates it, and the loop resumes, with the Python loop's rewards."""
    down, up = directed_smc("down", "DOWN"), directed_smc("up", "UP")
    for wrapper in (HierarchicalSMCWrapper(make(), [down, up]),
                    HierarchicalSMCWrapper(make(), [down, up], record_cells=True)):
        env = wrapper.base
        wrapper.reset(seed=0)
        assert env.world.self_position == (1, 4) and not env.goal
        _, reward, _, _, info = wrapper.step(wrapper.action_names.index("SMC:down"))
        # two moves into the container (the goal), then DOWN is blocked by its bottom until the 100 moves are used
        assert (reward, info["primitive_steps"], env.world.self_position, env.goal) == (0.5, 100, (3, 4), True)
        _, reward, *_ = wrapper.step(wrapper.action_names.index("SMC:up"))
        assert (reward, env.world.self_position, env.goal) == (-0.5, (1, 4), False)  # the frame stops it
        cells = env.goal_cells()
        assert cells[3, 4] == 1 and cells[2, 4] == 0 and cells[1, 4] == 0
        redrawn = World(env.world.current_scene())  # the live arrays are what a full redraw gives
        np.testing.assert_array_equal(env.world.grid, redrawn.grid)
        np.testing.assert_array_equal(env.world.owner, redrawn.owner)


@pytest.mark.parametrize("cap", [3, 7, 100])
def test_nested_calls_share_the_move_budget(cap: int) -> None:
    """A level-2 child calls compiled leaves inside its Python loop: the move budget of the top-level call is
    shared, and a cap of a few moves cuts calls at every depth exactly as before."""
    left = random_smc("left", "classification", "lstm", seed=1)
    right = random_smc("right", "bring-about", "gru", seed=2)
    middle = random_smc("middle", "classification", "lstm", (left, right), seed=3)
    names = smc_action_names("bring-about", ["middle", "left"])
    script = SMC("script", "bring-about",
                 ScriptedPolicy(len(names), lambda obs, step: names.index("SMC:middle") if step < 3 else 0),
                 children=(middle, left))
    made = compare(lambda: classification_env(max_steps=30), [left, middle, script], seed=5, call_step_cap=cap)
    assert made > 30


def test_worlds_with_pushable_objects_and_the_reset_bug_use_the_python_loop() -> None:
    pushable = Scene.from_ascii("""
#########
#...S...#
#..A....#
#.......#
#=======#
#########
""")
    leaf = random_smc("leaf", "classification", "lstm", seed=1)
    assert compare(lambda: PixelWorldEnv([pushable], kind="classification", concept="?x pushable(x)",
                                         max_steps=30), [leaf], seed=0, steps=40) == 0
    # the stale pixel of the reset bug: Python until the first move redraws the world, compiled after
    made = compare(lambda: classification_env(max_steps=30, aaai18_reset_bug=True), [leaf], seed=0, steps=80)
    assert made > 0


def test_probabilities_without_a_positive_sum_are_an_error() -> None:
    leaf = random_smc("broken", "classification", "lstm", seed=1)
    w_ih, w_hh, bias, _, w_out, b_out = leaf.policy.compiled_weights
    b_out[:] = np.nan
    wrapper = HierarchicalSMCWrapper(classification_env(), [leaf])
    wrapper.reset(seed=0)
    with pytest.raises(ValueError, match="SMC 'broken': its policy gave action probabilities without a positive"):
        wrapper.step(wrapper.action_names.index("SMC:broken"))
