"""HierarchicalSMCVecEnv: an SMC whose children are compiled leaves, every environment's step (the children's calls
included) in one compiled call. It must give SMCVecEnv's transitions over HierarchicalSMCWrapper environments, with
the same seeds, and train_smc must give the same SMC in it."""

from __future__ import annotations

import functools

import gymnasium as gym
import numpy as np
import pytest

import pixelworld_env  # noqa: F401  (the PW-* ids)
from pixelworld_env.errors import PixelWorldError
from sb3_smc import SMC
from sb3_smc.envs.hierarchical_vec_env import HierarchicalSMCVecEnv, hosts
from sb3_smc.envs.vec_env import SMCVecEnv
from sb3_smc.errors import SMCError
from sb3_smc.learning.training import make_vec_env, train_smc
from sb3_smc.records import TrainingSpec
from tests.helpers import assert_same_smc, step_side_by_side
from tests.test_compiled_calls import random_smc

CLASSIFY = "PW-cl_self-in-container_vs_noncontainer-v0"
BRING_ABOUT = "PW-ba_self-in-container_from_on-floor-v0"
PUSHING = "PW-ba_pixel-touches-reference_from_left-on-floor-pushable-v0"


def children(cell: str = "lstm") -> tuple[SMC, ...]:
    """Two leaves of both kinds (five and six actions), with random compiled policies that favour moves."""
    return tuple(random_smc(f"child{i}", kind, cell, seed=i) for i, kind in enumerate(["bring-about",
                                                                                        "classification"]))


def spec_for(env_id: str, kids: tuple[SMC, ...], **settings) -> TrainingSpec:
    return TrainingSpec.create(env_id, seed=3, n_envs=5, children=[c.name for c in kids], **settings)


@pytest.mark.parametrize("env_id,cell,settings", [
    (CLASSIFY, "lstm", {}),
    (BRING_ABOUT, "lstm", {}),
    (BRING_ABOUT, "gru", {"count_primitive_steps": True, "call_step_cap": 30}),
    (CLASSIFY, "gru", {"include_primitives": False, "max_steps": 20}),
])
def test_it_steps_as_the_wrapper(env_id: str, cell: str, settings: dict) -> None:
    """Observations, rewards, dones, the info keys training reads (a call's record included) and the monitor's
    episodes equal SMCVecEnv's over many same-step resets, calls and goal tests."""
    kids = children(cell)
    spec = spec_for(env_id, kids, **settings)
    reference, native = make_vec_env(spec, kids, native=False), make_vec_env(spec, kids)
    assert isinstance(reference.unwrapped, SMCVecEnv) and isinstance(native.unwrapped, HierarchicalSMCVecEnv)
    assert native.unwrapped.action_names == reference.unwrapped.envs[0].action_names
    ended, infos = step_side_by_side(native, reference, 300, ("is_success", "primitive_steps", "smc_calls",
                                                              "TimeLimit.truncated"))
    calls = sum(len(info["smc_calls"]) for info in infos)
    assert ended > 150 and calls > 350


def test_train_smc_in_it_is_bit_identical(monkeypatch: pytest.MonkeyPatch) -> None:
    """A level-2 SMC trained in HierarchicalSMCVecEnv (train_smc's choice) is the one trained in SMCVecEnv."""
    import sb3_smc.learning.training as training

    kids = children()
    settings = dict(children=kids, total_timesteps=768, n_envs=4, n_steps=64, seed=5, stop_at_max_return=False)
    native = train_smc(BRING_ABOUT, **settings)
    assert isinstance(native.model.get_env().unwrapped, HierarchicalSMCVecEnv)
    monkeypatch.setattr(training, "make_vec_env", functools.partial(training.make_vec_env, native=False))
    reference = train_smc(BRING_ABOUT, **settings)
    assert isinstance(reference.model.get_env().unwrapped, SMCVecEnv)
    assert_same_smc(reference, native)


def test_what_it_cannot_host_keeps_smc_vec_env() -> None:
    """Children that are not compiled leaves of one recurrent cell and size, and worlds where objects besides the
    self move, train in SMCVecEnv; native=True refuses them."""
    lstm, gru = children("lstm"), children("gru")
    parent = random_smc("parent", "bring-about", "lstm", children=lstm[:1])
    assert hosts(lstm) and hosts(gru) and not hosts(())
    assert not hosts((lstm[0], gru[1]))  # two cells
    assert not hosts((parent,))  # a child with children
    for env_id, kids in [(BRING_ABOUT, (lstm[0], gru[1])), (BRING_ABOUT, (parent,)), (PUSHING, lstm)]:
        spec = spec_for(env_id, kids)
        assert isinstance(make_vec_env(spec, kids).unwrapped, SMCVecEnv)
        with pytest.raises(SMCError, match="hosts SMCs on PixelWorld ids only"):
            make_vec_env(spec, kids, native=True)


def test_bad_construction_and_options_are_refused() -> None:
    kids = children()
    with pytest.raises(SMCError, match="needs observation='hand', got 'full'"):
        HierarchicalSMCVecEnv(gym.make_vec(BRING_ABOUT, num_envs=2, observation="full"), kids)
    with pytest.raises(SMCError, match="call_step_cap must be >= 1"):
        HierarchicalSMCVecEnv(gym.make_vec(BRING_ABOUT, num_envs=2), kids, call_step_cap=0)
    with pytest.raises(SMCError, match="names must be unique"):
        HierarchicalSMCVecEnv(gym.make_vec(BRING_ABOUT, num_envs=2), (kids[0], kids[0]))
    with pytest.raises(SMCError, match="compiled leaf SMCs of one network shape: there are no children"):
        HierarchicalSMCVecEnv(gym.make_vec(BRING_ABOUT, num_envs=2), ())
    with pytest.raises(PixelWorldError, match="objects besides the self move in scenes"):
        HierarchicalSMCVecEnv(gym.make_vec(PUSHING, num_envs=2), kids)
    venv = HierarchicalSMCVecEnv(gym.make_vec(BRING_ABOUT, num_envs=2), kids)
    venv.set_options({"index": 0})
    with pytest.raises(SMCError, match="takes no reset options"):
        venv.reset()


def test_a_policy_without_probabilities_names_the_child() -> None:
    kids = children()
    kids[0].policy._compiled[-1][:] = np.nan  # the action head's bias: no finite probabilities
    venv = HierarchicalSMCVecEnv(gym.make_vec(BRING_ABOUT, num_envs=2), kids)
    venv.reset()
    call = venv.action_names.index("SMC:child0")
    with pytest.raises(SMCError, match="SMC 'child0': its policy gave action probabilities without a positive"):
        venv.step(np.array([call, call]))
