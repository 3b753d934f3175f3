"""Training many flat SMCs at once (:mod:`sb3_smc.learning.batched`): each SMC is the one ``train_smc`` gives, bit for
bit."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch
from sb3_contrib import RecurrentPPO

import pixelworld_env  # noqa: F401  (registers the PW-* ids)
from sb3_smc.errors import SMCError
from sb3_smc.learning.batched import batchable, train_smcs
from sb3_smc.learning.training import train_smc
from sb3_smc.records import TrainingSpec
from tests.helpers import assert_same_smc

CORNER_ID = "PW-cl_self-in-left-corner_vs_on-hline-v0"
ABOVE_ID = "PW-ba_self-on-something_from_directly-above-v0"
OUTSIDE_ID = "PW-cl_self-in-container_vs_outside-v0"


def test_one_smc_is_train_smcs_bit_for_bit() -> None:
    spec = TrainingSpec.create(CORNER_ID, total_timesteps=8_000, seed=3)
    (batched,) = train_smcs([spec])
    assert_same_smc(train_smc(spec, log_every=0), batched)


def test_seeds_trained_together_are_each_their_own_training(monkeypatch: pytest.MonkeyPatch) -> None:
    """Five seeds in one vector env, their policies' steps in one compiled call per step; seed 1 stops early at
    return 1 (update 18), the others run their budget (a group goes on without the SMCs that left it)."""
    from sb3_smc.common import kernels

    calls: list[int] = []
    group_step = kernels.lstm_collection_steps
    monkeypatch.setattr(kernels, "lstm_collection_steps", lambda *args: calls.append(len(args[6])) or group_step(*args))
    specs = [TrainingSpec.create(OUTSIDE_ID, total_timesteps=40_000, seed=s, name=f"outside@{s}") for s in range(5)]
    batched = train_smcs(specs)
    monkeypatch.undo()
    assert len(calls) == 20 * 125 and calls[0] == 5 and calls[-1] == 4  # every step one call, seed 1 gone
    assert [smc.name for smc in batched] == [spec.name for spec in specs]
    stopped = batched[1].record
    assert stopped is not None and stopped.selected_return == 1.0 and stopped.total_timesteps == 19 * 2000 + 16
    for spec, smc in zip(specs, batched, strict=True):
        assert_same_smc(train_smc(spec, log_every=0), smc)


def test_recurrent_trpo_gru_and_mixed_groups() -> None:
    """RecurrentTRPO-GRU SMCs and RecurrentPPO SMCs of another task and size train in their own groups (one of
    them on the generic path); a spec no group hosts (memoryless TRPO) is trained by train_smc, in its place in the
    list."""
    specs = [TrainingSpec.create(ABOVE_ID, algo="RecurrentTRPO", rnn="gru", total_timesteps=4_000, seed=s)
             for s in (0, 1)]
    specs.append(TrainingSpec.create(CORNER_ID, total_timesteps=2_048, n_envs=8, seed=2))
    # the same group: a critic LSTM takes SB3's own collection step and info dicts beside the compiled step
    specs.append(TrainingSpec.create(CORNER_ID, total_timesteps=4_000, n_envs=8, seed=3,
                                     policy_kwargs={"enable_critic_lstm": True}))
    specs.append(TrainingSpec.create(CORNER_ID, algo="TRPO", total_timesteps=1_024, n_envs=4, n_steps=64, seed=0))
    assert [batchable(spec) for spec in specs] == [True, True, True, True, False]
    batched = train_smcs(specs)
    for spec, smc in zip(specs, batched, strict=True):
        assert_same_smc(train_smc(spec, log_every=0), smc)


def test_batched_smcs_save_load_and_go_into_a_library(tmp_path: Path) -> None:
    from sb3_smc.learning.evaluation import evaluate
    from sb3_smc.library import SMCLibrary

    specs = [TrainingSpec.create(CORNER_ID, total_timesteps=4_000, seed=s, name=f"corner@{s}") for s in (0, 1)]
    smcs = train_smcs(specs)
    smcs[0].model.save(tmp_path / "model.zip")
    loaded = RecurrentPPO.load(tmp_path / "model.zip", device="cpu")  # plain sb3-contrib
    weights, again = smcs[0].model.policy.state_dict(), loaded.policy.state_dict()
    assert all(torch.equal(weights[name], again[name]) for name in weights)
    obs = np.zeros((3, int(np.prod(loaded.observation_space.shape or ()))), dtype=np.float32)
    obs[:, [0, 10, 20]] = 1.0
    actions = [model.predict(obs, state=None, episode_start=np.ones(3), deterministic=True)
               for model in (smcs[0].model, loaded)]
    assert np.array_equal(actions[0][0], actions[1][0])
    assert np.array_equal(np.asarray(actions[0][1]), np.asarray(actions[1][1]))
    SMCLibrary(smcs).save(tmp_path / "lib")
    library = SMCLibrary.load(tmp_path / "lib")
    assert set(library) == {"corner@0", "corner@1"}
    for smc in smcs:
        assert evaluate(smc, repeats=1).to_dict() == evaluate(library[smc.name], repeats=1).to_dict()


def test_lean_update_in_a_group_is_train_smc_with_lean_update() -> None:
    """With ``lean_update`` each SMC of a group is ``train_smc(spec, lean_update=True)``'s, bit for bit (the same
    compiled update on the same rollouts), and differs from the stock update's; a spec the lean update does not fit
    is refused, naming the SMC, before its group trains."""
    specs = [TrainingSpec.create(CORNER_ID, total_timesteps=6_000, seed=s, name=f"corner@{s}") for s in (0, 1, 2)]
    batched = train_smcs(specs, lean_update=True)
    for spec, smc in zip(specs, batched, strict=True):
        assert smc.record is not None and smc.record.lean_update
        assert "lean_collection" not in vars(smc.model.policy)  # the lean collection's flag is the training's only
        assert_same_smc(train_smc(spec, log_every=0, lean_update=True), smc)
    stock = train_smcs(specs[:1])[0].model.policy.state_dict()
    lean = batched[0].model.policy.state_dict()
    assert not all(torch.equal(stock[name], lean[name]) for name in stock)
    critic = TrainingSpec.create(CORNER_ID, total_timesteps=2_000, seed=0, name="with-critic",
                                 policy_kwargs={"enable_critic_lstm": True})
    with pytest.raises(SMCError, match="'with-critic': lean_update needs RecurrentPPO"):
        train_smcs([specs[0], critic], lean_update=True)


def test_lean_gru_seeds_take_one_policy_step_for_the_group(monkeypatch: pytest.MonkeyPatch) -> None:
    """Lean GRU SMCs of a group (RecurrentPPO and RecurrentTRPO) take their policy steps in one compiled call per
    step (``gru_collection_steps``), and each is ``train_smc(spec, lean_update=True)``'s SMC."""
    from sb3_smc.common import kernels

    calls: list[int] = []
    group_step = kernels.gru_collection_steps
    monkeypatch.setattr(kernels, "gru_collection_steps", lambda *args: calls.append(len(args[5])) or group_step(*args))
    specs = [TrainingSpec.create(CORNER_ID, rnn="gru", total_timesteps=4_000, seed=s, name=f"gru@{s}")
             for s in (0, 1)]
    specs += [TrainingSpec.create(ABOVE_ID, algo="RecurrentTRPO", rnn="gru", total_timesteps=4_000, seed=s,
                                  name=f"trpo@{s}") for s in (0, 1)]
    batched = train_smcs(specs, lean_update=True)
    monkeypatch.undo()
    assert calls == [2] * (2 * 2 * 125)  # two groups of two, two rollouts of 125 steps each
    for spec, smc in zip(specs, batched, strict=True):
        assert_same_smc(train_smc(spec, log_every=0, lean_update=True), smc)


def test_networks_of_other_shapes_take_their_own_policy_steps(monkeypatch: pytest.MonkeyPatch) -> None:
    """Two SMCs of one task whose LSTMs differ in size share the vector env but not the group's policy step; each is
    still train_smc's SMC."""
    from sb3_smc.common import kernels

    calls: list[int] = []
    group_step = kernels.lstm_collection_steps
    monkeypatch.setattr(kernels, "lstm_collection_steps", lambda *args: calls.append(1) or group_step(*args))
    specs = [TrainingSpec.create(CORNER_ID, total_timesteps=4_000, seed=0),
             TrainingSpec.create(CORNER_ID, total_timesteps=4_000, seed=1, policy_kwargs={"lstm_hidden_size": 16})]
    batched = train_smcs(specs)
    monkeypatch.undo()
    assert not calls
    for spec, smc in zip(specs, batched, strict=True):
        assert_same_smc(train_smc(spec, log_every=0), smc)


def test_level2_seeds_trained_together_are_each_their_own_training(monkeypatch: pytest.MonkeyPatch) -> None:
    """SMCs whose children are compiled leaves train in one group (HierarchicalSMCVecEnv over all their
    environments), on the array path and, with a critic LSTM, on SB3's path with info dicts, and without primitives
    (noprim): each is train_smc's SMC, with the same statistics of its calls; children the group cannot host (one
    with children of its own) are trained by train_smc."""
    import sb3_smc.learning.batched as batched_module
    import sb3_smc.learning.env_group as env_group_module
    import sb3_smc.learning.training as training_module
    from sb3_smc.envs.hierarchical_vec_env import HierarchicalSMCVecEnv
    from tests.test_compiled_calls import random_smc

    histories: dict[str, list[list[dict]]] = {}
    original = training_module.training_callbacks

    def capture(spec, *args, **kwargs):
        stats, callbacks = original(spec, *args, **kwargs)
        histories.setdefault(spec.name, []).append(stats.history)
        return stats, callbacks

    monkeypatch.setattr(training_module, "training_callbacks", capture)
    monkeypatch.setattr(batched_module, "training_callbacks", capture)
    kids = [random_smc(f"child{i}", kind, "lstm", seed=i) for i, kind in enumerate(["bring-about", "classification"])]
    kids.append(random_smc("parent", "bring-about", "lstm", children=tuple(kids[:1]), seed=5))
    library = {smc.name: smc for smc in kids}  # a mapping name -> SMC, as a library is
    target = "PW-ba_self-in-container_from_on-floor-v0"
    specs = [TrainingSpec.create(target, children=["child0", "child1"], total_timesteps=4_000, n_envs=8,
                                 n_steps=125, seed=s, name=f"level2@{s}") for s in range(3)]
    specs.append(TrainingSpec.create(target, children=["child0", "child1"], total_timesteps=2_000, n_envs=8,
                                     n_steps=125, seed=3, name="level2-critic",
                                     policy_kwargs={"enable_critic_lstm": True}))
    specs.append(TrainingSpec.create(target, children=["child0", "child1"], total_timesteps=2_000, n_envs=8,
                                     n_steps=125, seed=6, name="level2-noprim", include_primitives=False))
    specs.append(TrainingSpec.create(target, children=["parent"], total_timesteps=1_000, n_envs=4, n_steps=125,
                                     seed=4, name="level3"))
    hosted: list[int] = []
    group = env_group_module.EnvGroup.__init__
    monkeypatch.setattr(env_group_module.EnvGroup, "__init__", lambda self, vector, sizes, *rest: hosted.append(
        len(sizes)) or group(self, vector, sizes, *rest))
    together = train_smcs(specs, children=library)
    assert hosted == [4, 1]  # the level-2 SMCs in one group, the noprim one in its own (other actions); level 3 alone
    for spec, smc in zip(specs, together, strict=True):
        alone = train_smc(spec, children=library, log_every=0)
        if spec.name != "level3":
            assert isinstance(alone.model.get_env().unwrapped, HierarchicalSMCVecEnv)
        assert_same_smc(alone, smc)
        grouped, single = histories[spec.name]
        strip = [{k: v for k, v in row.items() if not k.startswith("time/")} for row in grouped]
        assert strip == [{k: v for k, v in row.items() if not k.startswith("time/")} for row in single]
        child = "parent" if spec.name == "level3" else "child1"
        assert any(row[f"smc_calls/{child}/calls_per_episode"] > 0 for row in grouped)


class _Killed(Exception):
    """The process stops in the middle of a group's training."""


def _stopped(monkeypatch: pytest.MonkeyPatch, after: int, **train: Any) -> None:
    """``train_smcs(**train)`` stopped in the rollout after its update ``after`` (saved after every update)."""
    import sb3_smc.learning.batched as batched_module

    end_rollout = batched_module._Job.end_rollout

    def killed(job: batched_module._Job) -> None:
        if job.iteration == after:
            raise _Killed
        end_rollout(job)

    monkeypatch.setattr(batched_module._Job, "end_rollout", killed)
    with pytest.raises(_Killed):
        train_smcs(checkpoint_every=0, **train)
    monkeypatch.undo()


@pytest.mark.parametrize(("target", "steps", "lean", "updates"), [(OUTSIDE_ID, 40_000, False, (20, 19)),
                                                                 (CORNER_ID, 10_000, True, (5, 5))])
def test_a_group_stopped_between_updates_resumes_from_its_checkpoint(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                                     target: str, steps: int, lean: bool,
                                                                     updates: tuple[int, int]) -> None:
    """A group killed in its fourth rollout goes on from the checkpoint saved after its third update: only the
    updates after it are trained again, and each SMC is the one an uninterrupted training gives (weights, records,
    selection; seed 1 of the outside classifier stops early, in its 20th rollout, in both), with the stock and the
    lean update; the file is removed at the end. A damaged one is reported and the group trained from the start;
    another group leaves it alone."""
    import sb3_smc.learning.batched as batched_module

    specs = [TrainingSpec.create(target, total_timesteps=steps, seed=s, name=f"smc@{s}") for s in (0, 1)]
    uninterrupted = train_smcs(specs, lean_update=lean)
    _stopped(monkeypatch, 3, specs=specs, lean_update=lean, checkpoints=tmp_path)
    (saved,) = tmp_path.glob("group-*.pkl")
    counted: list[int] = []
    end_rollout = batched_module._Job.end_rollout
    monkeypatch.setattr(batched_module._Job, "end_rollout", lambda job: counted.append(1) or end_rollout(job))
    resumed = train_smcs(specs, lean_update=lean, checkpoints=tmp_path, checkpoint_every=0)
    monkeypatch.undo()
    assert len(counted) == sum(updates) - 2 * 3
    for before, after in zip(uninterrupted, resumed, strict=True):
        assert_same_smc(before, after)
        assert after.record is not None and after.record.lean_update is lean
    assert not saved.exists()
    saved.write_bytes(b"not a pickle")
    lines: list[str] = []
    train_smcs(specs[:1], lean_update=lean, printer=lines.append, checkpoints=tmp_path)
    assert list(tmp_path.glob("group-*.pkl")) == [saved] and not lines
    again = train_smcs(specs, lean_update=lean, printer=lines.append, checkpoints=tmp_path)
    assert len(lines) == 1 and f"{saved}: cannot resume from it" in lines[0] and not saved.exists()
    for before, after in zip(uninterrupted, again, strict=True):
        assert_same_smc(before, after)
    with pytest.raises(SMCError, match="checkpoint_every must be >= 0 seconds, got -1"):
        train_smcs(specs, checkpoints=tmp_path, checkpoint_every=-1)


def test_a_level2_group_resumes_with_the_children_it_is_given(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A checkpoint refers to the children by name (and to the module of their compiled calls): a level-2 group
    resumes with the children of the call, the same SMCs as without a break, its TensorBoard curves going on in the
    same folder."""
    from tests.test_compiled_calls import random_smc

    kids = {smc.name: smc for smc in (random_smc(f"child{i}", kind, "lstm", seed=i)
                                      for i, kind in enumerate(["bring-about", "classification"]))}
    specs = [TrainingSpec.create("PW-ba_self-in-container_from_on-floor-v0", children=["child0", "child1"],
                                 total_timesteps=4_000, n_envs=8, n_steps=125, seed=s, name=f"level2@{s}")
             for s in (0, 1)]
    uninterrupted = train_smcs(specs, children=kids)
    _stopped(monkeypatch, 2, specs=specs, children=kids, checkpoints=tmp_path, tensorboard_log=str(tmp_path))
    assert len(list(tmp_path.glob("group-*.pkl"))) == 1
    other = {**kids, "child0": random_smc("child0", "bring-about", "lstm", seed=7)}  # retrained under its name
    lines: list[str] = []
    assert len(train_smcs(specs[:1], children=other, checkpoints=tmp_path, printer=lines.append)) == 1
    assert not lines  # another group: its file is not read
    resumed = train_smcs(specs, children=kids, checkpoints=tmp_path, tensorboard_log=str(tmp_path))
    for before, after in zip(uninterrupted, resumed, strict=True):
        assert_same_smc(before, after)
    assert len(list((tmp_path / "level2@0_1").glob("events.out.tfevents.*"))) == 2  # the curves go on in its folder
    _stopped(monkeypatch, 2, specs=specs, children=kids, checkpoints=tmp_path)
    retrained = train_smcs(specs, children=other, checkpoints=tmp_path, printer=lines.append)
    assert len(lines) == 1 and "cannot resume from it" in lines[0]  # a child with other weights: from the start
    for fresh, after in zip(train_smcs(specs, children=other), retrained, strict=True):
        assert_same_smc(fresh, after)


def test_a_linear_schedule_is_saved_and_a_failed_save_does_not_fail_the_training(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A ``"lin_<x>"`` learning rate (a function made at run time) is saved by value and resumed; a save that fails
    (a full disk) is reported once and the group trains on without saving, to the same SMCs."""
    import sb3_smc.learning.group_checkpoint as checkpoint_module

    specs = [TrainingSpec.create(CORNER_ID, total_timesteps=8_000, seed=s, name=f"lin@{s}", learning_rate="lin_1e-3")
             for s in (0, 1)]
    uninterrupted = train_smcs(specs)
    _stopped(monkeypatch, 2, specs=specs, checkpoints=tmp_path)
    for before, after in zip(uninterrupted, train_smcs(specs, checkpoints=tmp_path), strict=True):
        assert_same_smc(before, after)

    def full(path: Path, data: bytes) -> None:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(checkpoint_module, "atomic_write", full)
    lines: list[str] = []
    for before, after in zip(uninterrupted, train_smcs(specs, checkpoints=tmp_path, checkpoint_every=0,
                                                       printer=lines.append), strict=True):
        assert_same_smc(before, after)
    assert len(lines) == 1 and "cannot save the group's training (OSError" in lines[0]
    assert not any(tmp_path.iterdir())
