"""What came out: :class:`TrainingRecord` (a training run) and :class:`EvaluationRecord` (one run of the test
protocol)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, ClassVar

from sb3_smc.core.layout import SIGNALS
from sb3_smc.records.base import (
    Record,
    RecordError,
    bool_field,
    float_field,
    int_field,
    mapping_field,
    names_field,
    nan_to_none,
    none_to_nan,
    set_field,
    str_field,
)
from sb3_smc.records.spec import SPLITS, TrainingSpec

__all__ = ["EvaluationRecord", "TrainingRecord", "test_score_of"]


def test_score_of(spec: TrainingSpec | None, evaluations: Sequence[EvaluationRecord]) -> float | None:
    """The latest test-split score on the spec's own task (else on any task); ``None`` without one."""
    tests = [e for e in evaluations if e.split == "test"]
    own = [e for e in tests if spec is not None and e.env_id == spec.task.env_id]
    chosen = own or tests
    return chosen[-1].score if chosen else None



# ---------------------------------------------------------------------------------------------------------------
# What came out
# ---------------------------------------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class TrainingRecord(Record):
    """What a training run produced (the selection of docs/design.md, "Selection and test", included).

    ``training_returns[k]`` is the mean undiscounted return of the episodes that ended in rollout ``k`` (NaN when
    none did; ``null`` in JSON), ``success_rates[k]`` the fraction of them with a final reward > 0. The selected
    update is the earliest one with the highest return; its policy is the SMC's. ``lean_update``: the updates were
    :func:`~sb3_smc.common.recurrent.lean_update.lean_train`'s (equal up to float rounding, not bit for bit); in
    JSON only when true.
    """

    training_returns: tuple[float, ...]
    success_rates: tuple[float, ...]
    selected_update: int | None
    selected_return: float | None
    total_timesteps: int
    primitive_steps: int
    wall_time_s: float
    action_names: tuple[str, ...] = ()
    initial_action_probabilities: tuple[float, ...] | None = None
    torch_threads: int = 1
    versions: dict[str, str] = field(default_factory=dict)
    lean_update: bool = False

    def __post_init__(self) -> None:
        set_field(self, "training_returns", none_to_nan(self.training_returns, "training_returns"))
        set_field(self, "success_rates", none_to_nan(self.success_rates, "success_rates"))
        if len(self.success_rates) != len(self.training_returns):
            raise RecordError(f"success_rates has {len(self.success_rates)} values for "
                              f"{len(self.training_returns)} updates")
        if self.selected_update is not None:
            update = int_field(self.selected_update, "selected_update", 0)
            if update >= len(self.training_returns):
                raise RecordError(f"selected_update {update} is past the last update "
                                  f"({len(self.training_returns)} updates)")
            set_field(self, "selected_update", update)
            set_field(self, "selected_return", float_field(self.selected_return, "selected_return"))
        elif self.selected_return is not None:
            raise RecordError("selected_return is set but selected_update is not")
        set_field(self, "total_timesteps", int_field(self.total_timesteps, "total_timesteps", 0))
        set_field(self, "primitive_steps", int_field(self.primitive_steps, "primitive_steps", 0))
        set_field(self, "wall_time_s", float_field(self.wall_time_s, "wall_time_s"))
        set_field(self, "action_names", names_field(self.action_names, "action_names"))
        if self.initial_action_probabilities is not None:
            set_field(self, "initial_action_probabilities",
                 none_to_nan(self.initial_action_probabilities, "initial_action_probabilities"))
        set_field(self, "torch_threads", int_field(self.torch_threads, "torch_threads", 1))
        set_field(self, "versions", {str(k): str(v) for k, v in mapping_field(self.versions, "versions").items()})
        bool_field(self.lean_update, "lean_update")

    @property
    def updates(self) -> int:
        return len(self.training_returns)

    @property
    def final_return(self) -> float | None:
        return self.training_returns[-1] if self.training_returns else None

    def to_dict(self) -> dict[str, Any]:
        out = super().to_dict()
        out["training_returns"] = nan_to_none(self.training_returns)
        out["success_rates"] = nan_to_none(self.success_rates)
        if self.initial_action_probabilities is not None:
            out["initial_action_probabilities"] = nan_to_none(self.initial_action_probabilities)
        if not self.lean_update:  # records of the default update stay as they were
            del out["lean_update"]
        return out


@dataclass(frozen=True, eq=False)
class EvaluationRecord(Record):
    """One run of the paper's test of SMC ``smc`` on ``env_id``'s ``split`` (docs/design.md, "Selection and test").

    ``environment_scores[i]``: the success fraction over the repeats of environment ``i``; ``score``: the mean over
    environments x repeats. ``evaluation_seed`` is the seed of the test (:func:`~sb3_smc.learning.evaluation.evaluate`'s
    ``seed``, 0 in the paper's protocol), not the SMC's training seed (its spec's ``seed``). ``repeats`` and
    ``evaluation_seed`` are ``None`` only for a score converted from a version-1 library, which did not record them
    (its ``environment_scores`` are then empty).

    Records saved before the field was renamed call it ``seed``; :meth:`from_dict` reads them (:data:`OLD_KEYS`), and
    ``to_dict`` writes ``evaluation_seed``.
    """

    smc: str
    env_id: str
    split: str
    kind: str
    repeats: int | None
    evaluation_seed: int | None
    score: float
    environment_scores: tuple[float, ...] = ()
    mean_length: float | None = None
    call_counts: dict[str, int] = field(default_factory=dict)
    train_worlds: int | None = None
    """``N`` where the test ran the first ``N`` worlds of the training split (an SMC trained on ``N`` worlds,
    evaluated on ``split="train"``); ``None``: every world of ``split`` (in JSON only when set). With ``env_id`` (its
    datasets), ``split`` and ``len(environment_scores)``, the record says which worlds it ran."""

    def __post_init__(self) -> None:
        str_field(self.smc, "smc")
        str_field(self.env_id, "env_id")
        str_field(self.split, "split", SPLITS)
        str_field(self.kind, "kind", tuple(SIGNALS))
        if self.repeats is not None:
            set_field(self, "repeats", int_field(self.repeats, "repeats", 1))
        if self.evaluation_seed is not None:
            set_field(self, "evaluation_seed", int_field(self.evaluation_seed, "evaluation_seed"))
        set_field(self, "score", float_field(self.score, "score"))
        set_field(self, "environment_scores", none_to_nan(self.environment_scores, "environment_scores"))
        if self.mean_length is not None:
            set_field(self, "mean_length", float_field(self.mean_length, "mean_length"))
        counts = mapping_field(self.call_counts, "call_counts")
        set_field(self, "call_counts", {k: int_field(v, f"call_counts.{k}", 0) for k, v in counts.items()})
        if self.train_worlds is not None:
            set_field(self, "train_worlds", int_field(self.train_worlds, "train_worlds", 1))

    OLD_KEYS: ClassVar[dict[str, str]] = {"seed": "evaluation_seed"}
    """Keys of records saved by earlier versions -> the fields they are now (``seed``: before issue 46)."""

    def to_dict(self) -> dict[str, Any]:
        out = super().to_dict()
        out["environment_scores"] = nan_to_none(self.environment_scores)
        if self.train_worlds is None:
            del out["train_worlds"]
        return out

    @classmethod
    def from_dict(cls, data: Any, where: str | None = None) -> EvaluationRecord:
        """The record of ``data``, one saved with an old key (:data:`OLD_KEYS`) included; a dict with both an old
        key and its new one is refused."""
        if isinstance(data, Mapping) and any(old in data for old in cls.OLD_KEYS):
            for old, new in cls.OLD_KEYS.items():
                if old in data and new in data:
                    raise RecordError(f"{where or cls.__name__}: both {old!r} (the old name) and {new!r} are given")
            data = {cls.OLD_KEYS.get(key, key): value for key, value in data.items()}
        return super().from_dict(data, where)

    @property
    def key(self) -> tuple[str, str]:
        """``(env_id, split)``: an SMC keeps one evaluation per key (the latest)."""
        return self.env_id, self.split
