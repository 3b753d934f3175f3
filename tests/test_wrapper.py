"""HierarchicalSMCWrapper semantics with scripted SMCs on hand-drawn worlds."""

from __future__ import annotations

from types import SimpleNamespace

import gymnasium as gym
import numpy as np
import pytest

from pixelworld_env import PixelWorldEnv, Scene
from sb3_smc import SMC
from sb3_smc.core.layout import smc_action_names
from sb3_smc.envs.wrapper import HierarchicalSMCWrapper
from sb3_smc.smc.policies import ScriptedPolicy, SequencePolicy
from tests.helpers import UniformPolicy

CONTAINER = """
#########
#...S...#
#.a...a.#
#.a...a.#
#.aaaaa.#
#=======#
#.......#
#########
"""
IN_CONTAINER = "?x container(x) & inside_supported(self,x)"
OUTCOME = 81  # index of the first outcome entry in an observation


def base_env(kind: str = "bring-about", **kwargs) -> PixelWorldEnv:
    return PixelWorldEnv([Scene.from_ascii(CONTAINER, {"a": "container"})], kind=kind, concept=IN_CONTAINER,
                         **kwargs)


def scripted(name: str, kind: str, names: list[str], children: tuple[SMC, ...] = (),
             include_primitives: bool = True) -> SMC:
    """An SMC that plays the named actions in order (then repeats the last)."""
    actions = smc_action_names(kind, [c.name for c in children], include_primitives)
    return SMC(name, kind, SequencePolicy(len(actions), [actions.index(n) for n in names]), children=children,
               include_primitives=include_primitives)


def act(env: HierarchicalSMCWrapper, name: str):
    return env.step(env.action_names.index(name))


def test_action_names_and_spaces() -> None:
    down = scripted("down", "bring-about", ["DOWN", "SIG1"])
    env = HierarchicalSMCWrapper(base_env(), [down])
    assert env.action_names == ("SIG1", "DOWN", "RIGHT", "UP", "LEFT", "SMC:down")
    assert env.observation_space.shape == (81 + 1 + 6,)
    noprim = HierarchicalSMCWrapper(base_env("classification"), [down], include_primitives=False)
    assert noprim.action_names == ("SIG0", "SIG1", "SMC:down")
    assert noprim.action_space == gym.spaces.Discrete(3)
    with pytest.raises(TypeError, match="a PixelWorld environment or an SMCTask .* got CartPoleEnv without one"):
        HierarchicalSMCWrapper(gym.make("CartPole-v1"))


def test_call_runs_to_the_signal_sums_rewards_and_records_the_outcome() -> None:
    into = scripted("into", "bring-about", ["DOWN", "DOWN", "SIG1"])
    env = HierarchicalSMCWrapper(base_env(), [into])
    obs, info = env.reset(seed=0)
    assert obs[OUTCOME] == 0 and info["smc_calls"] == []
    obs, reward, terminated, truncated, info = act(env, "SMC:into")
    assert (reward, terminated, truncated) == (0.5, False, False)  # its SIG1 does not end the episode
    assert obs[OUTCOME] == 1.0 and env.outcomes.tolist() == [1.0]
    assert info["smc_calls"] == [{"smc": "into", "depth": 1, "primitive_steps": 2, "outcome": 1, "reward": 0.5}]
    assert info["primitive_steps"] == 2 and info["elapsed_steps"] == 1 and info["goal"] is True
    assert env.base.world.self_position == (3, 4)
    np.testing.assert_array_equal(obs[82:], np.eye(6)[5])  # previous action: the call
    _, reward, terminated, _, info = act(env, "SIG1")
    assert (reward, terminated, info["is_success"]) == (0.5, True, True)
    with pytest.raises(RuntimeError, match="reset"):
        act(env, "DOWN")


def test_cells_of_every_move_are_recorded_on_request() -> None:
    into = scripted("into", "bring-about", ["DOWN", "DOWN", "SIG1"])
    env = HierarchicalSMCWrapper(base_env(), [into], record_cells=True)
    env.reset(seed=0)
    assert act(env, "LEFT")[4]["cells"] == [(1, 3)]
    assert act(env, "RIGHT")[4]["cells"] == [(1, 4)]
    assert act(env, "SMC:into")[4]["cells"] == [(2, 4), (3, 4)]
    assert act(env, "DOWN")[4]["cells"] == [(3, 4)]  # a blocked move still reports where the self is
    assert act(env, "SIG1")[4]["cells"] == []
    plain = HierarchicalSMCWrapper(base_env(), [into])
    plain.reset(seed=0)
    assert "cells" not in act(plain, "SMC:into")[4]


def test_shaping_telescopes_inside_a_call_and_outcomes_reset() -> None:
    bounce = scripted("bounce", "bring-about", ["DOWN", "DOWN", "UP", "SIG1"])
    probe = scripted("probe", "classification", ["DOWN", "SIG0"])
    env = HierarchicalSMCWrapper(base_env(), [bounce, probe])
    env.reset(seed=0)
    obs, reward, *_ = act(env, "SMC:bounce")  # +0.5 entering, -0.5 leaving
    assert reward == 0.0 and obs[OUTCOME] == 1.0
    obs, reward, *_ = act(env, "SMC:probe")  # from (2, 4) down into the goal, then SIG0
    assert reward == 0.5 and obs[OUTCOME : OUTCOME + 2].tolist() == [1.0, -1.0]
    obs, _ = env.reset(seed=1)
    assert obs[OUTCOME : OUTCOME + 2].tolist() == [0.0, 0.0] and not obs[83:].any()


def test_time_accounting_modes_and_the_per_call_cap() -> None:
    wander = scripted("wander", "bring-about", ["RIGHT", "LEFT"])  # never signals
    calls = HierarchicalSMCWrapper(base_env(max_steps=3), [wander], call_step_cap=5)
    calls.reset(seed=0)
    _, _, _, truncated, info = act(calls, "SMC:wander")
    assert info["smc_calls"][0]["primitive_steps"] == 5 and info["smc_calls"][0]["outcome"] == 0
    assert info["elapsed_steps"] == 1 and not truncated
    act(calls, "SMC:wander")
    _, _, _, truncated, info = act(calls, "SMC:wander")
    assert truncated and info["elapsed_steps"] == 3 and not info["is_success"]

    primitive = HierarchicalSMCWrapper(base_env(max_steps=12), [wander], call_step_cap=5,
                                       count_primitive_steps=True)
    primitive.reset(seed=0)
    _, _, _, truncated, info = act(primitive, "SMC:wander")
    assert info["elapsed_steps"] == 5 and not truncated
    act(primitive, "DOWN")
    _, _, _, truncated, info = act(primitive, "SMC:wander")
    assert info["elapsed_steps"] == 11 and not truncated
    _, _, _, truncated, info = act(primitive, "SMC:wander")  # cut at the one remaining step
    assert info["primitive_steps"] == 1 and info["elapsed_steps"] == 12 and truncated


def test_the_move_cap_is_shared_by_nested_calls() -> None:
    """A call runs until a signal or ``call_step_cap`` primitive steps, its nested calls' included (not
    ``call_step_cap`` moves per nested call: that would let a level-k call make ``cap ** k`` moves; docs/design.md,
    "Hierarchy: SMC calls")."""
    wander = scripted("wander", "bring-about", ["RIGHT", "LEFT"])  # never signals
    checker = scripted("checker", "classification", ["RIGHT", "SMC:wander"], children=(wander,))
    env = HierarchicalSMCWrapper(base_env(), [checker, wander], call_step_cap=5)
    env.reset(seed=0)
    _, _, _, _, info = act(env, "SMC:checker")
    assert [(c["smc"], c["depth"], c["outcome"], c["primitive_steps"]) for c in info["smc_calls"]] == [
        ("wander", 2, 0, 4), ("checker", 1, 0, 5)]  # one move of its own, then wander gets the 4 left
    assert info["primitive_steps"] == 5
    _, _, _, _, info = act(env, "SMC:wander")  # a new top-level call: a new budget
    assert [(c["smc"], c["primitive_steps"]) for c in info["smc_calls"]] == [("wander", 5)]
    # a call that makes no moves is bounded by its own decisions: 5 calls of a child that signals at once
    quiet = scripted("quiet", "bring-about", ["SIG1"])
    caller = scripted("caller", "classification", ["SMC:quiet"], children=(quiet,))
    env = HierarchicalSMCWrapper(base_env(), [caller], call_step_cap=5)
    env.reset(seed=0)
    _, _, _, _, info = act(env, "SMC:caller")
    assert [c["smc"] for c in info["smc_calls"]] == ["quiet"] * 5 + ["caller"]
    assert info["smc_calls"][-1]["outcome"] == 0 and info["primitive_steps"] == 0


def test_three_levels_of_nesting() -> None:
    into = scripted("into", "bring-about", ["DOWN", "DOWN", "SIG1"])
    names = smc_action_names("classification", ["into"])

    def check(obs: np.ndarray, step: int) -> int:  # call `into`, then report its outcome
        return names.index("SMC:into") if step == 0 else names.index("SIG1" if obs[OUTCOME] > 0 else "SIG0")

    checker = SMC("checker", "classification", ScriptedPolicy(len(names), check), children=(into,))
    assert checker.depth == 2
    top_names = smc_action_names("bring-about", ["checker"])
    top = SMC("top", "bring-about", SequencePolicy(len(top_names), [top_names.index("SMC:checker"), 0]),
              children=(checker,))
    env = HierarchicalSMCWrapper(base_env(), [top])
    env.reset(seed=0)
    obs, reward, terminated, _, info = act(env, "SMC:top")
    assert [(c["smc"], c["depth"], c["outcome"], c["primitive_steps"]) for c in info["smc_calls"]] == [
        ("into", 3, 1, 2), ("checker", 2, 1, 2), ("top", 1, 1, 2)]
    assert reward == 0.5 and not terminated and obs[OUTCOME] == 1.0


def test_primitives_can_be_removed() -> None:
    into = scripted("into", "bring-about", ["DOWN", "DOWN", "SIG1"])
    env = HierarchicalSMCWrapper(base_env("classification"), [into], include_primitives=False)
    env.reset(seed=0)
    _, reward, terminated, _, info = act(env, "SMC:into")
    assert reward == 0.0 and not terminated and env.base.world.self_position == (3, 4)
    _, reward, terminated, _, info = act(env, "SIG1")  # the scene's label is 0: the self starts outside
    assert (reward, terminated) == (-1.0, True)


def test_stochastic_calls_are_seeded() -> None:
    def trace(seed: int) -> list:
        random_smc = SMC("random", "classification", UniformPolicy(len(smc_action_names("classification"))))
        env = HierarchicalSMCWrapper(base_env(), [random_smc])
        env.reset(seed=seed)
        out = []
        for _ in range(5):
            _, reward, _, _, info = act(env, "SMC:random")
            out.append((reward, env.base.world.self_position, info["smc_calls"][0]["primitive_steps"]))
        return out

    assert trace(3) == trace(3)
    assert trace(3) != trace(4)


def test_policy_with_the_wrong_number_of_actions_is_reported() -> None:
    bad = SMC("bad", "bring-about", SequencePolicy(3, [0]))
    with pytest.raises(ValueError, match="SMC 'bad': its policy gives 3 action probabilities"):
        HierarchicalSMCWrapper(base_env(), [bad])  # when the wrapper is built, not at the first call

    class Undeclared:  # declares neither n_actions nor observation_size: caught at its first call
        def initial_state(self):
            return None

        def probabilities(self, observation, state):
            return np.full(3, 1 / 3), None

    env = HierarchicalSMCWrapper(base_env(), [SMC("bad", "bring-about", Undeclared())])
    env.reset(seed=0)
    with pytest.raises(ValueError, match="SMC 'bad': its policy gives 3 action probabilities"):
        act(env, "SMC:bad")


def test_children_with_the_wrong_observation_layout_are_refused_at_construction() -> None:
    """A child (at any depth) whose policy was built for other children is named with what it expects and gets."""
    from sb3_smc.smc.policies import FrameStackPolicy

    walker = SMC("walker", "bring-about", SequencePolicy(5, [1]))
    mlp = SimpleNamespace(observation_size=90, n_actions=6, initial_state=lambda: None)
    parent = SMC("parent", "bring-about", mlp, children=[walker])  # gets 81 + 1 + 6 = 88 values
    with pytest.raises(ValueError, match=r"SMC 'parent': its policy expects observations of 90 values, but as an "
                                         r"SMC it gets 88 \(81 window \+ 1 outcome \+ 6 previous action\)"):
        HierarchicalSMCWrapper(base_env(), [parent])
    deep = SMC("deep", "bring-about", SequencePolicy(6, [1]), children=[parent])
    with pytest.raises(ValueError, match=r"SMC 'parent' \(called by 'deep'\): its policy expects observations of 90"):
        HierarchicalSMCWrapper(base_env(), [deep])
    stacked = SMC("stacked", "bring-about", FrameStackPolicy(SimpleNamespace(observation_size=170, n_actions=5), 2, 86))
    with pytest.raises(ValueError, match="stacks 2 frames of 86 values into 170 inputs"):
        HierarchicalSMCWrapper(base_env(), [SMC("x", "bring-about", SequencePolicy(6, [1]), children=[stacked])])
    ok = SMC("ok", "bring-about", FrameStackPolicy(SimpleNamespace(observation_size=172, n_actions=5), 2, 86))
    assert HierarchicalSMCWrapper(base_env(), [ok]).smcs == (ok,)


def test_the_wrapper_needs_the_one_hot_window() -> None:
    with pytest.raises(ValueError, match="needs observation='hand', got 'full'"):
        HierarchicalSMCWrapper(base_env(observation="full"), [])


def test_wrapper_passes_gymnasium_and_sb3_checks() -> None:
    import warnings

    from gymnasium.utils.env_checker import check_env as gym_check_env
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    into = scripted("into", "bring-about", ["DOWN", "DOWN", "SIG1"])
    for kind in ("classification", "bring-about"):
        env = HierarchicalSMCWrapper(gym.make("PW-cl_self-in-left-corner_vs_on-hline-v0") if kind == "classification"
                                     else base_env(), [into])
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # every warning fails, except Gymnasium's note that this is a wrapper
            warnings.filterwarnings("ignore", message=".*is different from the unwrapped version")
            gym_check_env(env, skip_render_check=True)
            sb3_check_env(env)


def test_wrapping_a_trained_smc_shares_it() -> None:
    import copy

    from sb3_contrib import RecurrentPPO

    from sb3_smc.smc.policies import policy_from_model

    env = HierarchicalSMCWrapper(base_env())
    model = RecurrentPPO("MlpLstmPolicy", env, n_steps=32, batch_size=32, seed=0, device="cpu",
                         policy_kwargs={"lstm_hidden_size": 8})
    model.learn(32)
    child = SMC("trained", "bring-about", policy_from_model(model), model=model)
    wrapped = HierarchicalSMCWrapper(gym.make("PW-ba_self-in-container_from_directly-above-v0"), [child])
    assert copy.deepcopy(child) is child
    assert wrapped.spec.additional_wrappers[-1].kwargs["smcs"][0] is child  # the spec shares, never copies
    wrapped.reset(seed=0)
    _, _, _, _, info = act(wrapped, "SMC:trained")
    assert info["smc_calls"][0]["smc"] == "trained"
