"""The lean update as a run option (``RunOptions.lean_update``, ``--lean-update``): every job of a run trains with it,
each SMC the one ``train_smc(spec, lean_update=True)`` gives; ``run.json`` and ``results.json`` record it; a run
whose learner it does not fit is refused before anything is written; a library's SMCs are reused only when trained
with the same update."""

from __future__ import annotations

import json

import pytest
import torch

from sb3_smc.cli import _resume_command
from sb3_smc.curricula import Curriculum, CurriculumError, Node
from sb3_smc.curricula.options import RunOptions
from sb3_smc.curricula.run_directory import RunSettingsError
from sb3_smc.curricula.trainer import train_curriculum
from sb3_smc.errors import SMCError, SMCTypeError
from sb3_smc.experiments.runner import experiment_command, run_experiment
from sb3_smc.learning.training import train_smc
from sb3_smc.library import SMCLibrary
from tests.helpers import sb3_smc_cli

LEFT, RIGHT = "cl_self-in-left-corner_vs_on-hline", "cl_self-in-right-corner_vs_on-hline"
TARGET = "ba_self-in-target-container_from_nontarget-container"
TINY = Curriculum("tiny", (Node(LEFT, LEFT), Node(RIGHT, RIGHT), Node("top", TARGET, (LEFT, RIGHT))), ("top",))


def _weights_equal(a, b) -> bool:
    one, two = a.model.policy.state_dict(), b.model.policy.state_dict()
    return one.keys() == two.keys() and all(torch.equal(one[k], two[k]) for k in one)


def test_a_lean_run_trains_every_smc_as_train_smc_with_the_lean_update(tmp_path):
    run = train_curriculum(TINY, tmp_path / "lean", seeds=2, timesteps=4000, lean_update=True, group_size=2,
                           progress=False)
    assert json.loads((tmp_path / "lean" / "run.json").read_text())["lean_update"] is True
    library = SMCLibrary.load(run.library)
    assert len(library.names) == 6 and all(library[name].record.lean_update for name in library.names)
    for name in (f"{LEFT}@1", "top@0"):  # a flat job trained in a group of two, a level-2 job alone
        smc = library[name]
        again = train_smc(smc.spec, children=library, lean_update=True, log_every=0)
        assert again.record.training_returns == smc.record.training_returns and _weights_equal(again, smc), name
    stock = train_curriculum(TINY, tmp_path / "stock", seeds=2, timesteps=4000, targets=[LEFT], progress=False)
    assert "lean_update" not in json.loads((tmp_path / "stock" / "run.json").read_text())  # as before the option
    plain = SMCLibrary.load(stock.library)[f"{LEFT}@1"]
    assert not plain.record.lean_update  # (the two updates differ only in rounding: test_lean_update.py)
    # the update decides every job: resuming with the other one is refused, naming it
    with pytest.raises(RunSettingsError, match="lean_update: True in the directory, None now"):
        train_curriculum(TINY, tmp_path / "lean", seeds=2, timesteps=4000, progress=False)
    with pytest.raises(RunSettingsError, match="lean_update: None in the directory, True now"):
        train_curriculum(TINY, tmp_path / "stock", seeds=2, timesteps=4000, targets=[LEFT], lean_update=True,
                         progress=False)


def test_a_library_is_reused_only_where_its_smcs_had_the_runs_update(tmp_path):
    first = train_curriculum(TINY, tmp_path / "stock", seeds=1, timesteps=256, targets=[LEFT], progress=False)
    lines: list[str] = []
    lean = train_curriculum(TINY, tmp_path / "lean", seeds=1, timesteps=256, targets=[LEFT], lean_update=True,
                            reuse_from=first.library, printer=lines.append)
    assert "= 1 jobs (0 already done)" in lines[0]  # the stock SMC is not a lean run's
    assert SMCLibrary.load(lean.library)[f"{LEFT}@0"].record.lean_update
    lines.clear()
    train_curriculum(TINY, tmp_path / "again", seeds=1, timesteps=256, targets=[LEFT], lean_update=True,
                     reuse_from=lean.library, printer=lines.append)
    assert "(1 already done)" in lines[0]  # a lean SMC is
    lines.clear()
    train_curriculum(TINY, tmp_path / "plain", seeds=1, timesteps=256, targets=[LEFT], reuse_from=lean.library,
                     printer=lines.append)
    assert "(0 already done)" in lines[0]  # and not a stock run's


def test_a_lean_run_of_the_paper_s_learner_trains_every_smc_as_train_smc_with_the_lean_update(tmp_path):
    """RecurrentTRPO with a GRU and the lean update: a curriculum's flat seeds train in a group and its level-2 SMC
    over compiled children, each the one ``train_smc(spec, lean_update=True)`` gives alone, its record saying so;
    ``base-gru`` (this learner whatever the run's) takes the option in an experiment."""
    run = train_curriculum(TINY, tmp_path / "lean", seeds=2, timesteps=2000, algo="RecurrentTRPO", rnn="gru",
                           lean_update=True, group_size=2, progress=False)
    library = SMCLibrary.load(run.library)
    assert len(library.names) == 6
    for name in (f"{LEFT}@1", "top@0"):
        smc = library[name]
        assert smc.record.lean_update and smc.spec.algo == "RecurrentTRPO"
        assert type(smc.model.policy).__name__ == "SequenceGruPolicy"
        again = train_smc(smc.spec, children=library, lean_update=True, log_every=0)
        assert again.record.training_returns == smc.record.training_returns and _weights_equal(again, smc), name
    run_experiment(tmp_path / "experiment", methods=["base-gru"], targets=[TARGET], seeds=1, timesteps=512,
                   lean_update=True, progress=False)
    experiment = SMCLibrary.load(tmp_path / "experiment" / "library")
    assert len(experiment.names) == 1 and all(experiment[name].record.lean_update for name in experiment.names)


def test_a_lean_run_whose_learner_it_does_not_fit_is_refused_before_anything_is_written(tmp_path):
    with pytest.raises(CurriculumError, match=f"node '{LEFT}': SMC '{LEFT}@0': lean_update needs RecurrentPPO"):
        train_curriculum(TINY, tmp_path / "trpo", seeds=1, timesteps=256, algo="TRPO", lean_update=True,
                         progress=False)
    assert not any(tmp_path.iterdir())
    with pytest.raises(SMCTypeError, match="lean_update must be True or False, got 'yes'"):
        RunOptions(lean_update="yes")  # type: ignore[arg-type]
    with pytest.raises(SMCError, match="lean_update given beside options"):
        train_curriculum(TINY, tmp_path / "both", options=RunOptions(), lean_update=True)


def test_the_commands_that_resume_a_lean_run_say_so(tmp_path):
    settings = {"curriculum": "con2-cl", "targets": ["x"], "seeds": 2, "lean_update": True}
    assert _resume_command(tmp_path, settings).endswith(" --seeds 2 --lean-update")
    assert "--lean-update" not in _resume_command(tmp_path, {**settings, "lean_update": False})
    command = experiment_command("DIR", methods=["base"], targets=["x"], seeds=5, lean_update=True)
    assert command.endswith("--backend local --lean-update")
    assert "--lean-update" not in experiment_command("DIR", methods=["base"], targets=["x"], seeds=5)
    code, _, err = sb3_smc_cli("train", "con2-cl", "--out", str(tmp_path / "cli"), "--targets", LEFT, "--seeds", "1",
                               "--timesteps", "256", "--no-tensorboard", "--lean-update")
    assert code == 0, err
    assert json.loads((tmp_path / "cli" / "run.json").read_text())["lean_update"] is True


def test_a_lean_experiment_records_its_update(tmp_path):
    """results.json's settings and command, and the report's learner line, say the SMCs had the lean update."""
    from sb3_smc.experiments.report import _learners

    results = run_experiment(tmp_path / "lean", methods=["base"], targets=[TARGET], seeds=1, timesteps=2000,
                             repeats=1, lean_update=True, progress=False)
    assert results["settings"]["lean_update"] is True and results["command"].endswith(" --lean-update")
    assert _learners(results["settings"]) == "RecurrentPPO (LSTM, the lean update)"
    library = SMCLibrary.load(tmp_path / "lean" / "library")
    assert all(library[name].record.lean_update for name in library.names)
    plain = run_experiment(tmp_path / "plain", methods=["base"], targets=[TARGET], seeds=1, timesteps=2000,
                           repeats=1, progress=False)
    assert "lean_update" not in plain["settings"] and _learners(plain["settings"]) == "RecurrentPPO (LSTM)"
