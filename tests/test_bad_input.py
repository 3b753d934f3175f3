"""Bad input never passes silently: actions, seeds, observation settings, reset options, environment arguments,
the options of ``sb3-smc experiment`` and ``report``, and ``train_smc`` / the wrapper / ``make_smc_env``.

Each case raises with a message that says what was given and what is expected (nothing is converted)."""

from __future__ import annotations

import dataclasses
import re

import gymnasium as gym
import numpy as np
import pytest

import pixelworld_env  # noqa: F401  (registers the PW-* ids)
from pixelworld_env import PixelWorldEnv, Scene
from pixelworld_env.datasets.loading import load_dataset
from pixelworld_env.validation import MAX_SEED, check_action, check_seed
from sb3_smc.envs.wrapper import HierarchicalSMCWrapper
from sb3_smc.smc.policies import SequencePolicy
from sb3_smc.smc.smc import SMC
from tests.helpers import CONTAINER, IN_CONTAINER, classification_env, make, sb3_smc_cli

DATASET = "cl_self-in-left-corner_vs_on-hline"
ENV_ID = f"PW-{DATASET}-v0"


# ------------------------------------------------------------------------------------------------ actions

@pytest.mark.parametrize("action", [-1, -5, 6, True, False, 1.0, "1", None, np.array([1]), np.float32(2)])
def test_actions_outside_the_action_space_raise(action):
    env = classification_env()
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"invalid action .*expected an integer in \[0, 6\)"):
        env.step(action)
    made = gym.make(ENV_ID)
    made.reset(seed=0)
    with pytest.raises(ValueError, match="invalid action"):
        made.step(action)
    wrapped = HierarchicalSMCWrapper(classification_env(), [SMC("walker", "bring-about", SequencePolicy(5, [1]))])
    wrapped.reset(seed=0)
    with pytest.raises(ValueError, match=r"invalid action .*expected an integer in \[0, 7\)"):
        wrapped.step(7 if isinstance(action, int) and action == 6 else action)  # 6 calls the SMC


@pytest.mark.parametrize("action", [0, 5, np.int64(3), np.uint8(2), np.array(4)])
def test_integer_actions_of_any_integer_type_work(action):
    env = classification_env()
    env.reset(seed=0)
    env.step(action)
    assert check_action(action, env.action_names) == int(action)


# ------------------------------------------------------------------------------------------------ seeds

@pytest.mark.parametrize(("seed", "error", "message"), [
    (1.5, TypeError, "dataset seed must be an integer, got 1.5"),
    ("1", TypeError, "dataset seed must be an integer, got '1'"),
    (True, TypeError, "dataset seed must be an integer, got True"),
    ("abc", TypeError, "dataset seed must be an integer, got 'abc'"),
    (None, TypeError, "dataset seed must be an integer, got None"),
    (-1, ValueError, r"dataset seed must be in \[0, 2\*\*63 - 1\], got -1"),
    (MAX_SEED + 1, ValueError, "dataset seed must be in"),
])
def test_seeds_are_integers_only(seed, error, message):
    with pytest.raises(error, match=message):
        load_dataset(DATASET, seed=seed)
    with pytest.raises(error, match=message):
        gym.make(ENV_ID, seed=seed)


def test_numpy_integer_seeds_are_seeds():
    assert load_dataset(DATASET, seed=np.int64(0)).scenes == load_dataset(DATASET, seed=0).scenes
    assert check_seed(np.uint32(7)) == 7 and type(check_seed(np.uint32(7))) is int


def test_training_and_evaluation_seeds_are_checked():
    from sb3_smc.learning.evaluation import evaluate
    from sb3_smc.records import RecordError, TrainingSpec

    with pytest.raises(RecordError, match="seed must be >= 0, got -2"):
        TrainingSpec.create(ENV_ID, seed=-2)
    smc = SMC("walker", "classification", SequencePolicy(6, [1]))
    with pytest.raises(TypeError, match="evaluation seed must be an integer, got 0.5"):
        evaluate(smc, ENV_ID, seed=0.5)
    with pytest.raises(TypeError, match="repeats must be an integer, got 2.0"):
        evaluate(smc, ENV_ID, repeats=2.0)


# ------------------------------------------------------------------------------------------------ observations

@pytest.mark.parametrize("observation", ["hand_raw", "full"])
def test_smcs_refuse_observations_they_cannot_use(observation):
    from sb3_smc.learning.training import untrained_smc

    with pytest.raises(ValueError, match=f"needs observation='hand', got '{observation}'"):
        untrained_smc(ENV_ID, n_envs=1, env_kwargs={"observation": observation})
    with pytest.raises(ValueError, match="needs observation='hand'"):
        HierarchicalSMCWrapper(gym.make(ENV_ID, observation=observation))


# ------------------------------------------------------------------------------------------------ environment arguments

def test_reset_options_max_steps_and_labels_are_checked():
    env = make()
    with pytest.raises(ValueError, match=r"unknown reset option\(s\) \['indx'\]"):
        env.reset(options={"indx": 0})
    with pytest.raises(TypeError, match="options\\['index'\\] must be an integer, got 0.5"):
        env.reset(options={"index": 0.5})
    with pytest.raises(TypeError, match="max_steps must be an integer, got 1.5"):
        make(max_steps=1.5)
    with pytest.raises(ValueError, match="max_steps must be >= 1, got 0"):
        make(max_steps=0)
    scenes = [Scene.from_ascii(CONTAINER, {"a": "container"})]
    with pytest.raises(ValueError, match="labels are for classification and bring-about-or-cannot tasks; a bring"):
        PixelWorldEnv(scenes, kind="bring-about", concept=IN_CONTAINER, labels=[1])


@pytest.mark.parametrize("index", [-1, [0, -1], np.int64(-1), np.array([-1, 0])])
def test_negative_scene_indices_are_refused_by_the_vector_env_as_by_the_single_env(index):
    """The vector env's -1 ("draw a scene") is its own: a user's -1 raises as in the single env and SyncVectorEnv
    (which passes the options to every env as they are)."""
    message = re.escape("scene index -1 out of range (0..49)")
    with pytest.raises(IndexError, match=message):
        gym.make(ENV_ID).reset(seed=0, options={"index": -1})
    with pytest.raises(IndexError, match=message):
        gym.make_vec(ENV_ID, 2, vectorization_mode="sync").reset(seed=0, options={"index": -1})
    with pytest.raises(IndexError, match=message):
        gym.make_vec(ENV_ID, 2).reset(seed=0, options={"index": index})


@pytest.mark.parametrize("options", [[1], "index", ("index", 1)])
def test_reset_options_must_be_a_dict(options):
    with pytest.raises(TypeError, match=re.escape(f"reset options must be a dict, got {options!r} "
                                                  f"({type(options).__name__}); PixelWorldEnv.reset takes "
                                                  "options={'index': i}")):
        gym.make(ENV_ID).reset(seed=0, options=options)
    with pytest.raises(TypeError, match=re.escape(f"reset options must be a dict, got {options!r} "
                                                  f"({type(options).__name__}); PixelWorldVectorEnv.reset takes "
                                                  "options={'index': i or [i, ...], 'reset_mask': mask}")):
        gym.make_vec(ENV_ID, 2).reset(seed=0, options=options)


def test_hand_drawn_scenes_need_their_frame():
    with pytest.raises(ValueError, match=re.escape("the scene has no frame: draw '#' on its whole border ring (rows 0 "
                                                   "and 2, columns 0 and 3); PixelWorld's worlds are framed")):
        Scene.from_ascii("....\n.S..\n....")


def test_environments_state_their_split():
    """What rl_zoo3 enjoy and any evaluation run on is visible: the split is in every reset's info and the repr."""
    env = gym.make(ENV_ID)
    _, info = env.reset(seed=0)
    assert info["split"] == "train" and env.unwrapped.split == "train"
    assert "split='train'" in repr(env.unwrapped)
    _, info = gym.make(ENV_ID, split="test").reset(seed=0)
    assert info["split"] == "test"
    assert "split" not in classification_env().reset(seed=0)[1]  # hand-made scenes have no split


# ------------------------------------------------------------------------------------------------ sb3-smc: experiments

BRING_ABOUT = "ba_self-in-container_from_directly-above"


@pytest.mark.parametrize(("argv", "message"), [
    (["--repeats", "0"], "argument --repeats: must be a positive integer, got 0"),
    (["--seeds", "-1"], "argument --seeds: must be a positive integer, got -1"),
    (["--workers", "x"], "argument --workers: must be a positive integer, got 'x'"),
    (["--methods", ""], "no methods: nothing to run"),
    (["--methods", "cnn", "--targets", BRING_ABOUT], f"nothing to run: the CNN \\(method cnn\\) classifies only, and "
                                                     f"{BRING_ABOUT} is a bring-about target"),
    (["--methods", "base,base", "--targets", DATASET], "method 'base' is given twice"),
    (["--ray-address", "auto"], "a Ray address \\('auto'\\) is for backend 'ray'"),
])
def test_experiment_options_are_checked_before_anything_runs(tmp_path, argv, message):
    import re

    out = tmp_path / "exp"
    code, stdout, err = sb3_smc_cli("experiment", "--out", str(out), *argv)
    assert code == 2 and re.search(message, err) and "Traceback" not in err and stdout == ""
    assert not out.exists()  # no empty directory left behind


def test_experiment_api_checks_options_and_says_what_it_leaves_out(tmp_path):
    from sb3_smc.curricula.trainer import RunSettingsError
    from sb3_smc.experiments.runner import run_experiment

    with pytest.raises(ValueError, match="repeats must be a positive integer, got 0"):
        run_experiment(tmp_path / "exp", methods=["base"], targets=[DATASET], repeats=0, progress=False)
    with pytest.raises(ValueError, match="workers must be a positive integer, got 0"):
        run_experiment(tmp_path / "exp", methods=["base"], targets=[DATASET], workers=0, progress=False)
    (tmp_path / "a-file").write_text("x")
    with pytest.raises(RunSettingsError, match="a-file is a file, not an experiment directory"):
        run_experiment(tmp_path / "a-file", methods=["cnn"], targets=[DATASET], progress=False)
    assert not (tmp_path / "exp").exists()
    lines: list[str] = []
    with pytest.raises(RunSettingsError, match="holds no run yet"):  # train=False on an empty directory: nothing
        run_experiment(tmp_path / "exp", methods=["cnn", "base"], targets=[DATASET, BRING_ABOUT], train=False,
                       printer=lines.append)
    assert lines == [f"cnn skipped for 1 bring-about target(s) (it classifies only): {BRING_ABOUT}"]


def test_report_errors_name_the_file_and_what_to_do(tmp_path, monkeypatch):
    import shlex

    truncated = tmp_path / "truncated"
    truncated.mkdir()
    (truncated / "results.json").write_text('{"rows": [')
    code, _, err = sb3_smc_cli("report", str(truncated))
    assert code == 2 and f"{truncated / 'results.json'} is not valid JSON (corrupt or truncated?)" in err
    assert "it should hold the results of sb3-smc experiment" in err
    trained = tmp_path / "trained only"  # a run of sb3-smc train: no results to report, and the report says why
    trained.mkdir()
    (trained / "run.json").write_text("{}")
    code, _, err = sb3_smc_cli("report", str(trained))
    assert code == 2 and "holds a curriculum run (run.json) but no experiment results" in err
    assert f"sb3-smc status {shlex.quote(str(trained))}" in err
    monkeypatch.setattr("sb3_smc.experiments.runner.run_experiment", lambda out, **kwargs: {})
    code, stdout, _ = sb3_smc_cli("experiment", "--out", str(trained), "--methods", "cnn", "--targets", DATASET)
    assert code == 0 and f"next: sb3-smc report {shlex.quote(str(trained))}\n" in stdout  # a path with a space


# ------------------------------------------------------------------------------------------------ sb3_smc's API

def test_train_smc_trains_or_says_why_not():
    from sb3_smc.envs.factory import make_smc_env
    from sb3_smc.learning.training import train_smc, untrained_smc
    from sb3_smc.records import TaskSpec, TrainingSpec

    with pytest.raises(ValueError, match=r"total_timesteps must be >= 1, got 0 \(nothing would be trained\); "
                                         r"untrained_smc\(...\)"):
        train_smc(ENV_ID, total_timesteps=0, n_envs=1)
    with pytest.raises(ValueError, match="total_timesteps must be >= 1"):
        train_smc(TrainingSpec.create(ENV_ID, total_timesteps=0, n_envs=1))
    untrained = untrained_smc(ENV_ID, n_envs=1, seed=3)
    assert untrained.spec.budget.total_timesteps == 0 and untrained.record.updates == 0
    with pytest.raises(TypeError, match="untrained_smc trains nothing"):
        untrained_smc(ENV_ID, total_timesteps=10)
    with pytest.raises(TypeError, match=r"smcs\[0\] must be an SMC, got str 'corner': SMCs are objects, not names; "
                                        r"take them from their library \(library.wrap\(env, names\)"):
        HierarchicalSMCWrapper(gym.make(ENV_ID), ["corner"])
    with pytest.raises(TypeError, match="smcs must be a sequence of SMCs, got str 'corner'"):
        HierarchicalSMCWrapper(gym.make(ENV_ID), "corner")
    spec = untrained.spec
    with pytest.raises(ValueError, match=r"env_kwargs \['split'\]: the split is make_smc_env's split="):
        make_smc_env(spec, env_kwargs={"split": "test"})
    with pytest.raises(ValueError, match=r"env_kwargs \['max_steps'\]: .*WrapperSettings\(max_steps=...\)"):
        make_smc_env(spec, env_kwargs={"max_steps": 5})
    with pytest.raises(ValueError, match=f"env_kwargs: {ENV_ID} takes no argument 'obsrvation' .*did you mean "
                                         "'observation'"):
        make_smc_env(spec, env_kwargs={"obsrvation": "hand"})
    with pytest.raises(TypeError, match="aaai18_reset_bug must be a bool"):  # values: the environment's own check
        make_smc_env(spec, env_kwargs={"aaai18_reset_bug": "yes"})
    with pytest.raises(TypeError, match="env_kwargs must be a mapping"):
        make_smc_env(spec, env_kwargs=["seed"])
    assert make_smc_env(spec, env_kwargs={"seed": 2, "aaai18_reset_bug": True}).unwrapped.aaai18_reset_bug
    # an id Gymnasium does not know: an SMCError naming the SMC, before any training (a dataset's name: its id)
    with pytest.raises(ValueError, match=rf"SMC '{DATASET}': unknown environment id '{DATASET}': .*PixelWorld's "
                                         rf"'{DATASET}' is the id '{ENV_ID}'"):
        train_smc(DATASET, total_timesteps=100, n_envs=1)
    with pytest.raises(ValueError, match=r"unknown environment id 'PW-cl_self-in-left-cornr_vs_on-hline-v0': .*Did "
                                         r"you mean: `PW-cl_self-in-left-corner_vs_on-hline`"):  # a PW-* id: not native
        train_smc("PW-cl_self-in-left-cornr_vs_on-hline-v0", total_timesteps=100, n_envs=1)
    with pytest.raises(ValueError, match=r"unknown environment id 'CartPole-v9': .*\[ `v0`, `v1` \]"):
        train_smc("CartPole-v9", total_timesteps=100, n_envs=1)

    class MakesAnother(gym.Env):  # a registered environment whose own construction fails keeps its own error
        def __init__(self, **_: object) -> None:
            gym.make("NotRegistered-v0")

    gym.register("BadInputMakesAnother-v0", entry_point=MakesAnother)
    try:
        with pytest.raises(gym.error.NameNotFound, match="`NotRegistered` doesn't exist"):
            make_smc_env(dataclasses.replace(spec, task=TaskSpec("BadInputMakesAnother-v0", kind="bring-about")))
    finally:
        gym.registry.pop("BadInputMakesAnother-v0")


def test_smc_tasks_say_what_their_functions_and_callers_got_wrong():
    from sb3_smc.tasks.task import SMCTask

    def answers_no(env: gym.Env) -> str:
        return "no"

    task = SMCTask(gym.make("CartPole-v1"), "bring-about", goal=answers_no)
    with pytest.raises(TypeError, match=re.escape("goal function test_smc_tasks_say_what_their_functions_and_callers_"
                                                  "got_wrong.<locals>.answers_no must return a bool (True or False, "
                                                  "numpy bools too), got 'no' (str)")):
        task.reset(seed=0)
    numpy_bool = SMCTask(gym.make("CartPole-v1"), "bring-about", goal=lambda env: np.bool_(env.state[0] > 9))
    assert numpy_bool.reset(seed=0)[1]["goal"] is False
    with pytest.raises(RuntimeError, match=re.escape("no episode has started: call reset() before step()")):
        SMCTask(gym.make("CartPole-v1"), "bring-about", goal=lambda env: False).step(0)
    with pytest.raises(RuntimeError, match=re.escape("no episode has started: call reset() before apply_primitive()")):
        SMCTask(gym.make("CartPole-v1"), "bring-about", goal=lambda env: False).apply_primitive(1)
    numpy_bool.step(0)  # SIG1 ends the episode
    with pytest.raises(RuntimeError, match=re.escape("the episode has ended: call reset() before step()")):
        numpy_bool.step(1)


def test_stepping_a_pixelworld_env_or_an_smc_wrapper_before_reset_says_so() -> None:
    env = make()
    for call, method in ((lambda: env.step(0), "step"), (lambda: env.apply_move(0), "apply_move")):
        with pytest.raises(RuntimeError, match=re.escape(f"no episode has started: call reset() before {method}()")):
            call()
    env.reset(seed=0)
    env.step(env.action_names.index("SIG1"))
    with pytest.raises(RuntimeError, match=re.escape("the episode has ended: call reset() before step()")):
        env.step(0)
    wrapper = HierarchicalSMCWrapper(make())
    with pytest.raises(RuntimeError, match=re.escape("no episode has started: call reset() before step()")):
        wrapper.step(0)


def test_train_smc_says_that_a_registered_task_must_take_max_steps():
    from sb3_smc.learning.training import train_smc
    from sb3_smc.tasks.task import SMCTask

    gym.register("BadInputNoMaxSteps-v0", entry_point=lambda: SMCTask(gym.make("CartPole-v1"), "bring-about",
                                                                      goal=lambda env: False))
    try:
        with pytest.raises(TypeError, match=re.escape(
                "SMC 'BadInputNoMaxSteps': sb3_smc makes its task with gym.make('BadInputNoMaxSteps-v0', "
                "max_steps=...) (the episode length, WrapperSettings.max_steps), and the entry point of "
                "'BadInputNoMaxSteps-v0' takes no max_steps: register an entry point that takes it and passes it on, "
                "e.g. entry_point=lambda max_steps=100: SMCTask(..., max_steps=max_steps)")):
            train_smc("BadInputNoMaxSteps-v0", algo="PPO", total_timesteps=64, n_envs=1, n_steps=32, log_every=0)
    finally:
        gym.registry.pop("BadInputNoMaxSteps-v0")
