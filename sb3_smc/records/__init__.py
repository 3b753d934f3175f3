"""Typed records of SMC training, torch-free: what to train and what came out.

* :class:`TrainingSpec` — "train this SMC": the task (:class:`TaskSpec`), the wrapper settings
  (:class:`WrapperSettings`), the algorithm and its complete hyperparameters, the seed, the budget
  (:class:`Budget`), the signal-bias settings (:class:`SignalBias`), frame stacking, and the children **by name**
  (references into an :class:`~sb3_smc.library.SMCLibrary`, never objects).
* :class:`TrainingRecord` — what training produced: per-update training returns and success rates, the selected
  update and its return, wall time, primitive steps, the package versions it ran with.
* :class:`EvaluationRecord` — one run of the paper's test protocol: split, repeats, seed, score, per-environment
  scores.

All are frozen dataclasses of plain values: they pickle (to worker processes, to Ray), round-trip through JSON
(``to_dict`` / ``from_dict``, ``to_json`` / ``from_json``; ``from_dict`` rejects unknown or missing fields with
the field's name) and importing them imports neither torch nor Stable-Baselines3. :mod:`~sb3_smc.records.base`
holds the round trip and the field checks, :mod:`~sb3_smc.records.spec` what to train,
:mod:`~sb3_smc.records.results` what came out.
"""

from sb3_smc.records.base import RecordError, package_versions
from sb3_smc.records.results import EvaluationRecord, TrainingRecord, test_score_of
from sb3_smc.records.spec import Budget, SignalBias, TaskSpec, TrainingSpec, WrapperSettings, smc_name_from_env_id

__all__ = [
    "Budget",
    "EvaluationRecord",
    "RecordError",
    "SignalBias",
    "TaskSpec",
    "TrainingRecord",
    "TrainingSpec",
    "WrapperSettings",
    "package_versions",
    "smc_name_from_env_id",
    "test_score_of",
]
