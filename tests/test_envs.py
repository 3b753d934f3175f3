"""The one environment factory (sb3_smc.envs.factory.make_smc_env): what training, evaluation, the library and the
rl_zoo3 entry build is the same environment, with the spec's settings."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import pixelworld_env  # noqa: F401  (registers the PW-* ids)
from sb3_smc.envs.factory import make_smc_env, pixelworld_base, spec_for_smc
from sb3_smc.envs.wrapper import HierarchicalSMCWrapper
from sb3_smc.learning.evaluation import make_evaluation_env
from sb3_smc.learning.training import make_vec_env
from sb3_smc.records import TrainingSpec, WrapperSettings
from sb3_smc.smc.policies import ScriptedPolicy
from sb3_smc.smc.smc import SMC
from sb3_smc.zoo import smc_env

CONTAINER_ID = "PW-cl_self-in-container_vs_noncontainer-v0"


def _children() -> list[SMC]:
    return [SMC("left", "bring-about", ScriptedPolicy(5, lambda obs, step: 4 if step < 3 else 0)),
            SMC("down", "classification", ScriptedPolicy(6, lambda obs, step: 2 if step < 2 else 1))]


def _spec(**wrapper) -> TrainingSpec:
    return TrainingSpec.create(CONTAINER_ID, children=["left", "down"], call_step_cap=2, max_steps=7,
                               include_primitives=False, **wrapper)


def _trace(env: gym.Env, actions: list[int], seed: int = 3) -> list:
    observation, _ = env.reset(seed=seed, options={"index": 4})
    trace = [observation]
    for action in actions:
        observation, reward, terminated, truncated, info = env.step(action)
        trace.append((observation, reward, terminated, truncated, info["primitive_steps"], info["elapsed_steps"]))
        if terminated or truncated:
            break
    return trace


def test_the_spec_decides_the_environment():
    children = _children()
    env = make_smc_env(_spec(), children)
    assert isinstance(env, HierarchicalSMCWrapper) and env.smcs == tuple(children)
    assert env.action_names == ("SIG0", "SIG1", "SMC:left", "SMC:down")  # noprim
    assert env.call_step_cap == 2 and env.unwrapped.max_steps == 7 and not env.count_primitive_steps
    assert env.observation_space.shape == (_spec().observation_size,)
    assert env.unwrapped.scenes is not None and len(env.unwrapped.scenes) == 50  # the training split
    test = make_smc_env(_spec(), children, split="test")
    assert test.unwrapped.scenes != env.unwrapped.scenes
    env.reset(seed=0)
    info = env.step(2)[4]
    assert info["smc_calls"][0]["primitive_steps"] == 2  # the call was cut at call_step_cap=2


def test_training_evaluation_library_and_zoo_build_the_same_environment(tmp_path):
    """Same seed, same actions: the same observations, rewards and call lengths from every builder."""
    from sb3_smc.learning.training import untrained_smc
    from sb3_smc.library import SMCLibrary

    children = [untrained_smc("PW-ba_self-on-something_from_directly-above-v0", n_envs=1, seed=1),
                untrained_smc("PW-cl_self-in-left-corner_vs_on-hline-v0", n_envs=1, seed=2)]
    names = [c.name for c in children]
    spec = TrainingSpec.create(CONTAINER_ID, children=names, call_step_cap=5, max_steps=7, include_primitives=False,
                               total_timesteps=0, n_envs=1)
    smc = untrained_smc(spec, children=children)
    library = SMCLibrary.load(SMCLibrary([smc]).save(tmp_path / "library"))
    actions = [2, 3, 2, 3, 0]
    reference = _trace(make_smc_env(spec, children), actions)
    built = {
        # the wrapper training builds where the native env does not host the SMC (which steps as it: its own test)
        "training": make_vec_env(spec, children, native=False).unwrapped.envs[0],
        "evaluation": make_evaluation_env(smc, split="train"),
        "library": library.env_for(spec.name, gym.make(CONTAINER_ID, max_steps=7)),
        "zoo": smc_env(gym.make(CONTAINER_ID, max_steps=7), library=str(tmp_path / "library"), names=names,
                       include_primitives=False, call_step_cap=5),
    }
    assert any(step[4] > 0 for step in reference[1:])  # the calls moved the self
    for label, env in built.items():
        got = _trace(env, actions)
        np.testing.assert_array_equal(got[0], reference[0], err_msg=label)
        assert len(got) == len(reference), label
        for a, b in zip(got[1:], reference[1:], strict=True):
            np.testing.assert_array_equal(a[0], b[0], err_msg=label)
            assert a[1:] == b[1:], label


def test_children_must_match_the_spec():
    children = _children()
    with pytest.raises(ValueError, match=r"calls the children \['left', 'down'\] \(in that order\), but was given "
                                         r"\['down', 'left'\]"):
        make_smc_env(_spec(), children[::-1])
    with pytest.raises(ValueError, match="give either env, or env_id"):
        make_smc_env(_spec(), children, env=gym.make(CONTAINER_ID), split="test")
    wrapped = make_smc_env(_spec(), children)
    with pytest.raises(ValueError, match="already wrapped with SMC actions"):
        make_smc_env(_spec(), children, env=wrapped)
    with pytest.raises(TypeError, match="SMCs act on a PixelWorld environment or an SMCTask .* got CartPoleEnv"):
        pixelworld_base(gym.make("CartPole-v1"))


def test_wrapper_settings_can_be_replaced_and_smcs_without_spec_get_defaults():
    children = _children()
    env = make_smc_env(_spec(), children, wrapper=WrapperSettings(include_primitives=False, call_step_cap=9))
    assert env.call_step_cap == 9 and env.unwrapped.max_steps == 100
    scripted = SMC("walker", "bring-about", ScriptedPolicy(5, lambda obs, step: 0))
    spec = spec_for_smc(scripted, "PW-ba_self-in-container-v0")
    assert spec.wrapper == WrapperSettings() and spec.task.kind == "bring-about" and spec.children == ()
