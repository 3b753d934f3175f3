"""Training many flat SMCs at once (:mod:`sb3_smc.learning.batched`): each SMC is the one ``train_smc`` gives, bit for
bit."""

from __future__ import annotations

from pathlib import Path

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
    environments), on the array path and, with a critic LSTM, on SB3's path with info dicts: each is train_smc's SMC,
    with the same statistics of its calls; children the group cannot host (one with children of its own) are
    trained by train_smc."""
    import sb3_smc.learning.batched as batched_module
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
    specs.append(TrainingSpec.create(target, children=["parent"], total_timesteps=1_000, n_envs=4, n_steps=125,
                                     seed=4, name="level3"))
    hosted: list[int] = []
    group = batched_module._EnvGroup.__init__
    monkeypatch.setattr(batched_module._EnvGroup, "__init__", lambda self, vector, sizes, *rest: hosted.append(
        len(sizes)) or group(self, vector, sizes, *rest))
    together = train_smcs(specs, children=library)
    assert hosted == [4]  # the level-2 SMCs in one group; the level-3 one alone
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
