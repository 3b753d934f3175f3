"""The jobs of a curriculum run: one node with one seed (:class:`JobId`), named ``<node>@<seed>`` where it is stored.

A job's :class:`~sb3_smc.records.TrainingSpec` calls, for every node its node uses, the ``k`` best seeds of that
node (``reuse="two_best"``: k = 2; :func:`rank_seeds`) as distinct SMC actions. A :class:`Job` carries
the picklable spec and the path of the run's library, where the worker loads the children by name (never torch
objects); :func:`run_job` trains it and returns the model as bytes, the same in this process, a local worker process
or a Ray task. :func:`run_group` trains several jobs of a node at once (:func:`~sb3_smc.learning.batched.train_smcs`),
each result the one :func:`run_job` gives. :func:`check_curriculum` checks every node's spec before a run trains
anything.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import NamedTuple

from sb3_smc.common.threads import compute_threads
from sb3_smc.core.hyperparameters import DEFAULT_ALGORITHM, DEFAULT_TIMESTEPS, recurrent_policy
from sb3_smc.curricula.format import SEED_SEPARATOR, Curriculum, CurriculumError, Node
from sb3_smc.errors import SMCError
from sb3_smc.library import SMCLibrary, storage
from sb3_smc.records import Budget, TaskSpec, TrainingRecord, TrainingSpec, WrapperSettings
from sb3_smc.smc.smc import SMC

__all__ = ["DEFAULT_REUSE", "DEFAULT_SEEDS", "REUSE", "Job", "JobId", "JobResult", "check_curriculum", "file_stem",
           "job_name", "name_of_file", "node_budget", "node_of", "node_records", "node_spec", "planned_children",
           "rank_seeds", "run_group", "run_job"]

REUSE = {"one_best": 1, "two_best": 2}
"""SMC filters of the paper: how many seeds of each lower-level node a caller gets."""
DEFAULT_REUSE = "two_best"
DEFAULT_SEEDS = 5
"""Seeds per node (the paper's)."""


class JobId(NamedTuple):
    """Which job: node ``node`` trained with ``seed``. The scheduler and the trainer know jobs by these; the job's
    name ``<node>@<seed>`` (``str(job)``, read back with :meth:`parse`) is made only where it is stored: the
    library's manifest, file names, ``state.json``, ``retrain.json``, the progress lines."""

    node: str
    seed: int

    def __str__(self) -> str:
        return f"{self.node}{SEED_SEPARATOR}{self.seed}"

    @classmethod
    def parse(cls, name: str) -> JobId:
        """The job named ``name`` (``str(job)``'s inverse); ``SMCError`` for a name that is not a job's."""
        job = cls.of(name)
        if job is None:
            raise SMCError(f"{name!r} is not a job name: <node>{SEED_SEPARATOR}<seed>, a node name and a seed 0, 1, "
                           "... (no sign or leading zero)")
        return job

    @classmethod
    def of(cls, name: str) -> JobId | None:
        """The job named ``name``, or ``None`` for any other name (a library may hold SMCs that are no job's)."""
        node, sep, seed = name.rpartition(SEED_SEPARATOR)
        if sep and node and seed.isascii() and seed.isdigit() and str(int(seed)) == seed:
            return cls(node, int(seed))
        return None


def job_name(node: str, seed: int) -> str:
    """The library name of node ``node`` trained with ``seed``: ``str(JobId(node, seed))``."""
    return str(JobId(node, seed))


def node_of(name: str) -> str:
    """The node of the library name ``name`` (:func:`job_name`'s inverse, for the node)."""
    return name.rpartition(SEED_SEPARATOR)[0]


def node_records(entries: Mapping[str, storage.LibraryEntry], node: str) -> dict[int, TrainingRecord | None]:
    """The training records (``None`` where an entry has none) of ``node``'s jobs among a library's ``entries``, by
    seed."""
    out: dict[int, TrainingRecord | None] = {}
    for name, entry in entries.items():
        job = JobId.of(name)
        if job is not None and job.node == node:
            out[job.seed] = entry.record
    return out


def file_stem(name: str) -> str:
    """A job name as a file name (``/`` and ``%`` percent-encoded: reversible, no collisions)."""
    return name.replace("%", "%25").replace("/", "%2F")


def name_of_file(stem: str) -> str:
    """The inverse of :func:`file_stem`."""
    return stem.replace("%2F", "/").replace("%25", "%")


@dataclass(frozen=True)
class Job:
    """One node x seed to train: picklable, torch-free (the worker loads the children from ``library`` by name)."""

    spec: TrainingSpec
    library: str
    tensorboard_log: str | None = None
    lean_update: bool = False
    """Train with the lean update (:class:`~sb3_smc.curricula.options.RunOptions`' ``lean_update``)."""
    checkpoints: str | None = None
    """Where a group's training is saved between two updates and resumed from after a stop (``train_smcs``'
    ``checkpoints``; the run directory's ``checkpoints/``)."""


@dataclass(frozen=True)
class JobResult:
    """What a worker returns: the spec, the training record and the SB3 model archive."""

    spec: TrainingSpec
    record: TrainingRecord
    algo: str
    model: bytes


def run_job(job: Job) -> JobResult:
    """Train ``job`` (one torch and one BLAS thread; the caller's counts are restored) and return its result; the
    same in any process or Ray worker."""
    from sb3_smc.learning.training import train_smc  # torch and Stable-Baselines3: in the worker only

    spec = job.spec
    children = SMCLibrary.load(job.library, names=spec.children) if spec.children else {}
    with compute_threads(1):
        smc = train_smc(spec, children=children, tensorboard_log=job.tensorboard_log, log_every=0,
                        lean_update=job.lean_update)
    return _result(smc)


CHECKPOINT_EVERY = 300.0
"""Seconds between two saves of a group's training in a run (a group stopped loses at most this much)."""


def run_group(jobs: Sequence[Job]) -> list[JobResult]:
    """Train ``jobs`` (one library, one TensorBoard folder and one ``lean_update`` for all) together with
    :func:`~sb3_smc.learning.batched.train_smcs` in one torch and one BLAS thread and return their results in order,
    each what :func:`run_job` returns for its job (bit-identical SMCs). The children they call are loaded once. The
    group's training is saved to the jobs' ``checkpoints`` every :data:`CHECKPOINT_EVERY` seconds, and resumed from
    there when the same group is trained again after a stop."""
    from sb3_smc.learning.batched import train_smcs  # torch and Stable-Baselines3: in the worker only

    names = sorted({name for job in jobs for name in job.spec.children})
    children = SMCLibrary.load(jobs[0].library, names=names) if names else {}
    with compute_threads(1):
        smcs = train_smcs([job.spec for job in jobs], children=children, tensorboard_log=jobs[0].tensorboard_log,
                          log_every=0, lean_update=jobs[0].lean_update, checkpoints=jobs[0].checkpoints,
                          checkpoint_every=CHECKPOINT_EVERY)
    return [_result(smc) for smc in smcs]


def _result(smc: SMC) -> JobResult:
    assert smc.spec is not None and smc.record is not None  # train_smc and train_smcs record both
    return JobResult(spec=smc.spec, record=smc.record, algo=smc.spec.algo,
                     model=storage.model_bytes(smc.model, where=f"SMC {smc.name!r}"))


def rank_seeds(records: dict[int, TrainingRecord]) -> list[int]:
    """Seeds best first: by selected training return (a seed that never selected an update last), ties to the
    lower seed (docs/design.md, "Curricula: reuse of the best seeds")."""
    def key(seed: int) -> tuple[int, float, int]:
        value = records[seed].selected_return
        return (1, 0.0, seed) if value is None else (0, -value, seed)

    return sorted(records, key=key)


def node_budget(node: Node, timesteps: int | None) -> int:
    """The steps a job of ``node`` trains: the run's ``timesteps``, else the node's own, else the default, times the
    node's ``budget_scale``."""
    return max(1, round(node.budget_scale * (timesteps or node.timesteps or DEFAULT_TIMESTEPS)))


def node_spec(node: Node, seed: int, children: tuple[str, ...], *, timesteps: int | None = None,
              algo: str | None = None, rnn: str | None = None) -> TrainingSpec:
    """The spec of job ``<node>@<seed>`` calling ``children``; ``timesteps`` / ``algo`` replace the node's own,
    ``rnn`` sets its recurrent cell (the run's settings)."""
    algo = algo or node.algo or DEFAULT_ALGORITHM
    hyperparameters = dict(node.hyperparameters)
    if rnn is not None:
        hyperparameters["policy"] = recurrent_policy(rnn, algo)
    cut = {"train_worlds": node.train_worlds} if node.train_worlds is not None else {}
    task = TaskSpec(node.env_id, env_kwargs=cut).resolved()
    return TrainingSpec(name=job_name(node.name, seed), task=task, algo=algo,
                        hyperparameters=hyperparameters, seed=seed, budget=Budget(node_budget(node, timesteps)),
                        wrapper=WrapperSettings(include_primitives=node.include_primitives,
                                                count_primitive_steps=node.count_primitive_steps,
                                                max_steps=node.max_steps, call_step_cap=node.call_step_cap),
                        children=children)


def planned_children(node: Node, k: int) -> tuple[str, ...]:
    """The children a job of ``node`` calls before its lower levels are ranked: seeds ``0..k-1`` of each node it
    uses. As many as it will call (``k`` best seeds of each), so a spec built from them is checked and judged as the
    job's own will be (a noprim node needs children)."""
    return tuple(job_name(used, seed) for used in node.uses for seed in range(k))


def check_curriculum(curriculum: Curriculum, names: Sequence[str] | None = None, *, timesteps: int | None = None,
                     algo: str | None = None, rnn: str | None = None, reuse: str = DEFAULT_REUSE,
                     lean_update: bool = False) -> None:
    """Check every node of ``names`` (default: all) as a run with these settings would train it, before anything is
    trained: its settings make a valid spec, and the algorithm takes its hyperparameters (the model is built on an
    environment with the SMC's spaces, :func:`sb3_smc.learning.training.check_model_settings`), and with
    ``lean_update`` the lean update computes its update. ``CurriculumError``
    naming the file, the line and the node. ``sb3-smc curricula FILE`` and :func:`train_curriculum` both check so."""
    from sb3_smc.learning.training import check_model_settings

    checked: set[str] = set()  # nodes alike in what builds their model are built once
    for name in curriculum.order() if names is None else names:
        node = curriculum.node(name)
        children = planned_children(node, REUSE[reuse])
        try:
            spec = node_spec(node, 0, children, timesteps=timesteps, algo=algo, rnn=rnn)
            key = json.dumps([spec.algo, spec.hyperparameters, spec.budget.to_dict(), spec.frame_stack,
                              spec.observation_size, len(spec.action_names)], sort_keys=True)
            if key not in checked:
                check_model_settings(spec, lean_update=lean_update)
                checked.add(key)
        except ValueError as err:
            where = f"{curriculum.source}:{node.line}: " if node.line is not None and curriculum.source else ""
            raise CurriculumError(f"{where}node {name!r}: {err}") from None
