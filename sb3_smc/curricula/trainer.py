"""``train_curriculum``: every node x seed of a curriculum trained level by level into one SMC library.

A **job** is one node with one seed: a :class:`~sb3_smc.records.TrainingSpec` named ``<node>@<seed>`` whose children
are, for every node it uses, the ``k`` best seeds of that node (``reuse="two_best"``: k = 2; ranked by the
selected training return, ties to the lower seed; spec §5.5), as distinct SMC actions. A job becomes ready once
every seed of every node it uses is trained. Jobs carry picklable specs and the path of the run's library, where
the worker loads the children by name (never torch objects), and return the trained model as bytes: the same
function runs in this process, in local worker processes or as a Ray task, and gives the same SMC.

Run directory::

    DIR/run.json        the settings; re-running with other settings is refused (the differences are listed)
                        unless node changes are accepted (``accept_changes``)
    DIR/library/        an SMCLibrary: one SMC per finished job, with its spec and training record
    DIR/tensorboard/    SB3 and SMC curves, one run per job (``<node>@<seed>_1``)
    DIR/failed/         ``<job>.txt``: the traceback of a job that raised (retried by the next run; ``/`` as ``%2F``)
    DIR/state.json      the jobs running now and the coordinator's pid (for ``sb3-smc status``)
    DIR/replaced/       ``<time>-<random>/``: the library (and run.json) as it was before SMCs were replaced
    DIR/.lock           held by the coordinator while it runs (a second one on the same directory is refused)

Jobs whose results are kept elsewhere can be skipped (``skip``: e.g. the evaluated SMCs of an experiment whose run
directory lost its library); a skipped job is trained all the same when a job still to train needs its node as a
child (the ranking of a node's seeds needs every seed), and nodes that only skipped jobs need are not trained.

Crash safety: a finished job is one whose SMC is in the library manifest; the model file and then the manifest are
written atomically by the coordinator (the only writer), so killing the process at any moment loses at most the
jobs that were running, which the next run starts again from scratch. Finished jobs are never trained again and
their files never rewritten, except that a job whose model file is missing or damaged (checked against the
manifest's SHA-256 by every run and by :func:`status`) is trained again, replacing its entry, and so are the jobs
above it when that training differs from the recorded one; accepted node changes replace the jobs of the changed
nodes and of the nodes above them. The working SMCs so replaced stay in ``DIR/replaced/``.
"""

from __future__ import annotations

import io
import json
import os
import shutil
import time
import traceback
from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pixelworld_env.atomic import atomic_write, make_temporary_directory
from sb3_smc.curricula.format import SEED_SEPARATOR, Curriculum, CurriculumError, Node, merge
from sb3_smc.errors import SMCError, SMCRuntimeError, SMCTypeError
from sb3_smc.hyperparameters import (
    DEFAULT_ALGORITHM,
    DEFAULT_TIMESTEPS,
    STEPS_PER_UPDATE,
    algorithm,
    recurrent_policy,
)
from sb3_smc.library import storage
from sb3_smc.library.errors import CorruptModelError
from sb3_smc.records import Budget, TaskSpec, TrainingRecord, TrainingSpec, WrapperSettings

__all__ = ["BACKENDS", "DEFAULT_REUSE", "DEFAULT_SEEDS", "REUSE", "Job", "JobResult", "RunFileError",
           "RunSettingsError", "TrainingRun", "check_curriculum", "check_run_options", "describe", "file_stem",
           "finished_jobs", "job_name", "name_of_file", "node_of", "node_spec", "rank_seeds", "read_json",
           "read_settings", "run_job", "run_settings", "status", "train_curriculum"]

REUSE = {"one_best": 1, "two_best": 2}
"""SMC filters of the paper: how many seeds of each lower-level node a caller gets."""
DEFAULT_REUSE = "two_best"
DEFAULT_SEEDS = 5
"""Seeds per node (the paper's)."""
BACKENDS = ("local", "ray")
"""Where jobs run: local processes or Ray tasks."""
RUN_FORMAT = "sb3-smc-run"
RUN_VERSION = 1


class RunSettingsError(SMCError):
    """The run directory was started with other settings (the message lists the differences), or is not a run
    directory."""


class RunFileError(SMCError):
    """A file of a run or experiment directory is not what it should be (the message names it and what it should
    hold)."""


def read_json(path: Path, holds: str) -> Any:
    """The JSON content of ``path``; :class:`RunFileError` naming the file and what it ``holds`` when it is not
    JSON text."""
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as err:
        raise RunFileError(f"{path} is not valid JSON (corrupt or truncated?): {err}; it should hold {holds}") \
            from None


def job_name(node: str, seed: int) -> str:
    """The library name of node ``node`` trained with ``seed``."""
    return f"{node}{SEED_SEPARATOR}{seed}"


def node_of(name: str) -> str:
    """The node of the library name ``name`` (:func:`job_name`'s inverse, for the node)."""
    return name.rpartition(SEED_SEPARATOR)[0]


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


@dataclass(frozen=True)
class JobResult:
    """What a worker returns: the spec, the training record and the SB3 model archive."""

    spec: TrainingSpec
    record: TrainingRecord
    algo: str
    model: bytes


def run_job(job: Job) -> JobResult:
    """Train ``job`` (one torch thread; the caller's count is restored) and return its result; the same in any
    process or Ray worker."""
    from sb3_smc.common.threads import torch_threads
    from sb3_smc.library import SMCLibrary
    from sb3_smc.training import train_smc

    spec = job.spec
    children = SMCLibrary.load(job.library, names=spec.children) if spec.children else {}
    with torch_threads(1):
        smc = train_smc(spec, children=children, tensorboard_log=job.tensorboard_log, log_every=0)
    assert smc.spec is not None and smc.record is not None  # train_smc records both
    buffer = io.BytesIO()
    smc.model.save(buffer)
    return JobResult(spec=smc.spec, record=smc.record, algo=spec.algo, model=buffer.getvalue())


def rank_seeds(records: dict[int, TrainingRecord]) -> list[int]:
    """Seeds best first: by selected training return (a seed that never selected an update last), ties to the
    lower seed (spec §5.5)."""
    def key(seed: int) -> tuple[int, float, int]:
        value = records[seed].selected_return
        return (1, 0.0, seed) if value is None else (0, -value, seed)

    return sorted(records, key=key)


# ---------------------------------------------------------------------------------------------------------------
# Settings
# ---------------------------------------------------------------------------------------------------------------

def _budget(node: Node, timesteps: int | None) -> int:
    return timesteps or node.timesteps or DEFAULT_TIMESTEPS


def node_spec(node: Node, seed: int, children: tuple[str, ...], *, timesteps: int | None = None,
              algo: str | None = None, rnn: str | None = None) -> TrainingSpec:
    """The spec of job ``<node>@<seed>`` calling ``children``; ``timesteps`` / ``algo`` replace the node's own,
    ``rnn`` sets its recurrent cell (the run's settings)."""
    algo = algo or node.algo or DEFAULT_ALGORITHM
    hyperparameters = dict(node.hyperparameters)
    if rnn is not None:
        hyperparameters["policy"] = recurrent_policy(rnn, algo)
    return TrainingSpec(name=job_name(node.name, seed), task=TaskSpec(node.env_id).resolved(),
                        algo=algo, hyperparameters=hyperparameters, seed=seed, budget=Budget(_budget(node, timesteps)),
                        wrapper=WrapperSettings(include_primitives=node.include_primitives), children=children)


def check_curriculum(curriculum: Curriculum, names: Sequence[str] | None = None, *, timesteps: int | None = None,
                     algo: str | None = None, rnn: str | None = None, reuse: str = DEFAULT_REUSE) -> None:
    """Check every node of ``names`` (default: all) as a run with these settings would train it, before anything is
    trained: its settings make a valid spec, and the algorithm takes its hyperparameters (the model is built on an
    environment with the SMC's spaces, :func:`sb3_smc.training.check_model_settings`). ``CurriculumError`` naming
    the file, the line and the node. ``sb3-smc curricula FILE`` and :func:`train_curriculum` both check so."""
    from sb3_smc.training import check_model_settings

    checked: set[str] = set()  # nodes alike in what builds their model are built once
    for name in curriculum.order() if names is None else names:
        node = curriculum.node(name)
        children = tuple(job_name(u, seed) for u in node.uses for seed in range(REUSE[reuse]))
        try:
            spec = node_spec(node, 0, children, timesteps=timesteps, algo=algo, rnn=rnn)
            key = json.dumps([spec.algo, spec.hyperparameters, spec.budget.to_dict(), spec.frame_stack,
                              spec.observation_size, len(spec.action_names)], sort_keys=True)
            if key not in checked:
                check_model_settings(spec)
                checked.add(key)
        except ValueError as err:
            where = f"{curriculum.source}:{node.line}: " if node.line is not None and curriculum.source else ""
            raise CurriculumError(f"{where}node {name!r}: {err}") from None

def run_settings(curriculum: Curriculum, nodes: Sequence[str], targets: Sequence[str], seeds: int,
                 timesteps: int | None, reuse: str, algo: str | None, rnn: str | None = None) -> dict[str, Any]:
    """What decides a run's SMCs (``DIR/run.json``): backend and worker count do not (``rnn`` is written only when
    given, so run directories from before the option resume)."""
    settings = {"format": RUN_FORMAT, "version": RUN_VERSION, "curriculum": curriculum.name,
                "targets": list(targets), "seeds": seeds, "timesteps": timesteps, "reuse": reuse, "algo": algo,
                "nodes": {name: curriculum.node(name).settings() for name in nodes}}
    if rnn is not None:
        settings["rnn"] = rnn
    return settings


def _differences(old: dict[str, Any], new: dict[str, Any]) -> list[str]:
    out = []
    for key in sorted(set(old) | set(new)):
        if key == "nodes":
            continue
        if old.get(key) != new.get(key):
            out.append(f"{key}: {old.get(key)!r} in the directory, {new.get(key)!r} now")
    old_nodes, new_nodes = old.get("nodes", {}), new.get("nodes", {})
    for name in sorted(set(old_nodes) | set(new_nodes)):
        if name not in new_nodes:
            out.append(f"node {name!r}: in the directory, not in this run")
        elif name not in old_nodes:
            out.append(f"node {name!r}: new in this run")
        elif old_nodes[name] != new_nodes[name]:
            was, now = old_nodes[name], new_nodes[name]
            keys = [k for k in sorted(set(was) | set(now)) if was.get(k) != now.get(k)]
            out.append(f"node {name!r}: " + "; ".join(f"{k} {was.get(k)!r} in the directory, {now.get(k)!r} now"
                                                      for k in keys))
    return out


# ---------------------------------------------------------------------------------------------------------------
# The run
# ---------------------------------------------------------------------------------------------------------------

@dataclass
class TrainingRun:
    """The outcome of :func:`train_curriculum`: where the library is, and one row per job."""

    directory: Path
    library: Path
    rows: list[dict[str, Any]]
    failed: dict[str, str]

    def table(self) -> str:
        """The summary table (node, seed, selected update, training return, wall time)."""
        lines = ["| node | seed | selected update | training return | wall s |", "|---|---:|---:|---:|---:|"]
        for row in self.rows:
            ret = "-" if row["training_return"] is None else f"{row['training_return']:.3f}"
            upd = "-" if row["selected_update"] is None else str(row["selected_update"])
            lines.append(f"| {row['node']} | {row['seed']} | {upd} | {ret} | {row['wall_time_s']:.0f} |")
        return "\n".join(lines)


class _Scheduler:
    def __init__(self, curriculum: Curriculum, order: list[str], seeds: int, timesteps: int | None, k: int,
                 algo: str | None, directory: Path, rnn: str | None = None, skip: frozenset[str] = frozenset()
                 ) -> None:
        self.curriculum, self.order, self.seeds, self.timesteps, self.k = curriculum, order, seeds, timesteps, k
        self.algo, self.rnn, self.skip = algo, rnn, skip
        self.directory = directory
        self.library = directory / "library"
        self.records: dict[str, dict[int, TrainingRecord]] = {name: {} for name in order}
        self.running: set[str] = set()
        self.failed: dict[str, str] = {}
        self.damaged: dict[str, TrainingRecord] = {}  # finished jobs whose model file is damaged: their old records
        self.height = _heights(curriculum, order)
        self.below = {name: curriculum.closure([name]) - {name} for name in order}

    def jobs(self) -> list[tuple[str, int]]:
        return [(node, seed) for node in self.order for seed in range(self.seeds)]

    def done(self, node: str, seed: int) -> bool:
        return seed in self.records[node] or job_name(node, seed) in self.skip

    def budget(self, node: Node) -> int:
        return _budget(node, self.timesteps)

    def children(self, node: Node) -> tuple[str, ...]:
        names: list[str] = []
        for used in node.uses:
            best = rank_seeds(self.records[used])[: min(self.k, self.seeds)]
            names.extend(job_name(used, seed) for seed in best)
        return tuple(names)

    def ready(self) -> list[tuple[str, int]]:
        """The jobs that can start, those with the longest chain of nodes still above them first (then in
        ``order``): a deep curriculum's critical path starts at once, and top-level nodes (a flat baseline, say)
        fill idle workers. Which job runs when does not change what is trained. Nothing above a damaged job being
        trained again starts before it is done (it may be trained again itself: :func:`_store`)."""
        repairing = {node_of(name) for name in self.damaged}
        out = []
        for node_name, seed in sorted(self.jobs(), key=lambda job: -self.height[job[0]]):
            name = job_name(node_name, seed)
            if self.done(node_name, seed) or name in self.running or name in self.failed:
                continue
            node = self.curriculum.node(node_name)
            if all(len(self.records[u]) == self.seeds for u in node.uses) and not self.below[node_name] & repairing:
                out.append((node_name, seed))
        return out

    def blocked(self) -> list[str]:
        """Jobs that cannot run because a node they need has a failed job."""
        bad = {node_of(name) for name in self.failed}
        out = []
        for node_name, seed in self.jobs():
            name = job_name(node_name, seed)
            if not self.done(node_name, seed) and name not in self.failed and self.below[node_name] & bad:
                out.append(name)
        return out

    def job(self, node_name: str, seed: int, tensorboard: bool) -> Job:
        node = self.curriculum.node(node_name)
        name = job_name(node_name, seed)
        spec = node_spec(node, seed, self.children(node), timesteps=self.timesteps, algo=self.algo, rnn=self.rnn)
        log = None
        if tensorboard:
            folder = self.directory / "tensorboard"
            for stale in folder.glob(f"{_glob_escape(name)}_*"):  # a half-finished earlier attempt
                shutil.rmtree(stale, ignore_errors=True)
            log = str(folder)
        return Job(spec=spec, library=str(self.library.absolute()), tensorboard_log=log)


def _heights(curriculum: Curriculum, order: list[str]) -> dict[str, int]:
    """For each node of ``order`` (lower levels first), the length of the longest chain of nodes of ``order`` that
    use it, directly or not (0 for a node nothing in the run uses)."""
    height = dict.fromkeys(order, 0)
    for name in reversed(order):
        for used in curriculum.node(name).uses:
            if used in height:
                height[used] = max(height[used], height[name] + 1)
    return height


def _glob_escape(text: str) -> str:
    return "".join(f"[{c}]" if c in "*?[" else c for c in text)


def _write_state(directory: Path, running: Collection[str], started: float, skipped: Collection[str]) -> None:
    atomic_write(directory / "state.json", json.dumps({"pid": os.getpid(), "running": sorted(running),
                                                      "skipped": sorted(skipped), "started": started,
                                                      "updated": time.time()}) + "\n")


def train_curriculum(
    curriculum: str | Path | Curriculum | Sequence[str | Path | Curriculum],
    out: str | Path,
    *,
    targets: Sequence[str] | None = None,
    seeds: int = DEFAULT_SEEDS,
    timesteps: int | None = None,
    reuse: str = DEFAULT_REUSE,
    workers: int = 1,
    backend: str = BACKENDS[0],
    algo: str | None = None,
    rnn: str | None = None,
    ray_address: str | None = None,
    tensorboard: bool = True,
    progress: bool = True,
    printer: Callable[[str], None] = print,
    skip: Collection[str] = (),
    accept_changes: bool = False,
) -> TrainingRun:
    """Train ``curriculum`` (a shipped name, a file, a :class:`Curriculum`, or several: their nodes are merged, a
    node shared by several is trained once) into ``out``, resuming whatever ``out`` already holds.

    ``targets``: node or dataset names (default: the curriculum's targets); they and every node they use are
    trained, each with seeds ``0 .. seeds-1``. ``timesteps`` / ``algo`` replace every node's own, ``rnn``
    (``"lstm"`` or ``"gru"``) sets the recurrent cell of every node (recurrent algorithms only); ``reuse``:
    ``"two_best"`` or ``"one_best"``. ``workers`` > 1 runs independent jobs in that many local processes;
    ``backend="ray"`` submits them to a Ray cluster (``ray_address`` or ``RAY_ADDRESS``; ``workers`` caps the
    jobs in flight). The trained SMCs are the same whatever the backend and worker count. Jobs that fail are
    reported (``DIR/failed/``) and retried by the next run; jobs needing them wait. ``skip``: job names not to train
    (their results are kept elsewhere); one whose node a job still to train uses is trained all the same, and
    nodes that only skipped jobs use are not trained. A finished job whose model file is missing or damaged is
    trained again. ``accept_changes``: ``out`` holds this run with other node settings (or other nodes); the jobs
    of the changed nodes and of every node above them are trained again (the SMCs they replace are kept in
    ``DIR/replaced/``), the other nodes keep theirs. Every setting and node is checked before anything is written
    or trained. Returns a :class:`TrainingRun`.
    """
    check_run_options(workers=workers, backend=backend, ray_address=ray_address)
    merged, order, settings = _resolve_run(curriculum, targets, seeds, timesteps, reuse, algo, rnn)
    directory = Path(out)
    order, skipped = _plan_skip(merged, order, settings["targets"], seeds, skip)
    # the jobs of nodes left out of the plan count as skipped too (sb3-smc status shows them so, not as "left")
    skipped |= {job_name(n, s) for n in settings["nodes"] if n not in order for s in range(seeds)}
    scheduler = _Scheduler(merged, order, seeds, timesteps, REUSE[reuse], algo, directory, rnn, skipped)
    check_curriculum(merged, order, timesteps=timesteps, algo=algo, rnn=rnn, reuse=reuse)
    old = read_settings(directory)
    changes = _Changes.between(old, settings, merged) if old is not None else None
    if changes is not None and changes.differences:
        changes.check(directory, accept_changes)
    directory.mkdir(parents=True, exist_ok=True)
    lock = _lock(directory)
    try:
        if old is None or changes is not None and changes.differences:
            if changes is not None:
                changes.apply(directory, printer if progress else None)
            atomic_write(directory / "run.json", json.dumps(settings, indent=2) + "\n")
        return _run(merged, scheduler, order, directory, seeds, backend, workers, ray_address, tensorboard, progress,
                    printer)
    finally:
        lock.close()


def check_run_options(*, seeds: int = DEFAULT_SEEDS, timesteps: int | None = None, reuse: str = DEFAULT_REUSE,
                      workers: int = 1, backend: str = BACKENDS[0], ray_address: str | None = None,
                      algo: str | None = None, rnn: str | None = None) -> None:
    """``ValueError`` naming the first option of a run that is out of range (before anything is done)."""
    for name, value, optional in (("seeds", seeds, False), ("workers", workers, False), ("timesteps", timesteps, True)):
        if not (optional and value is None) and (isinstance(value, bool) or not isinstance(value, int) or value < 1):
            raise SMCError(f"{name} must be a positive integer, got {value!r}")
    if reuse not in REUSE:
        raise SMCError(f"reuse must be one of {list(REUSE)}, got {reuse!r}")
    if backend not in BACKENDS:
        raise SMCError(f"backend must be {' or '.join(map(repr, BACKENDS))}, got {backend!r}")
    if ray_address is not None and backend != "ray":
        raise SMCError(f"a Ray address ({ray_address!r}) is for backend 'ray', not {backend!r}")
    if algo is not None:
        algorithm(algo)  # a known algorithm
    if rnn is not None:
        recurrent_policy(rnn)  # a known cell (each node's algorithm is checked with its spec)


def finished_jobs(
    curriculum: str | Path | Curriculum | Sequence[str | Path | Curriculum],
    out: str | Path,
    *,
    targets: Sequence[str] | None = None,
    seeds: int = DEFAULT_SEEDS,
    timesteps: int | None = None,
    reuse: str = DEFAULT_REUSE,
    algo: str | None = None,
    rnn: str | None = None,
) -> set[str]:
    """The job names (``<node>@<seed>``) that the run :func:`train_curriculum` would resume in ``out`` has finished,
    without training or writing anything (the run may be training meanwhile). ``RunSettingsError`` when ``out``
    holds no run or a run with other settings."""
    merged, _, settings = _resolve_run(curriculum, targets, seeds, timesteps, reuse, algo, rnn)
    directory = Path(out)
    old = read_settings(directory)
    if old is None:
        raise RunSettingsError(f"{directory} holds no run yet (no run.json): nothing is trained")
    _Changes.between(old, settings, merged).check(directory, accept=False)
    return set(status(directory)["done"])


def _plan_skip(curriculum: Curriculum, order: list[str], targets: Sequence[str], seeds: int,
               skip: Collection[str]) -> tuple[list[str], frozenset[str]]:
    """The nodes to schedule and the jobs to skip. A target job not in ``skip`` is wanted; every node that a wanted
    job's node uses (at any depth) is trained with every seed, skipped or not; the other skipped jobs are skipped,
    and nodes that no wanted job needs are left out."""
    if isinstance(skip, str):
        raise SMCTypeError(f"skip must be a collection of job names, got the string {skip!r}")
    names = frozenset(skip)
    known = set(order)
    for name in names:
        node, sep, seed = name.rpartition(SEED_SEPARATOR)
        if not sep or node not in known or not seed.isdigit() or str(int(seed)) != seed or int(seed) >= seeds:
            raise SMCError(f"skip: {name!r} is not a job of this run (<node>{SEED_SEPARATOR}<seed> with one of its "
                           f"{len(order)} nodes and a seed below {seeds})")
    wanted = [n for n in targets if any(job_name(n, s) not in names for s in range(seeds))]
    required: set[str] = set()
    for name in wanted:
        required |= curriculum.closure([name]) - {name}
    skipped = frozenset(j for j in names if node_of(j) not in required)
    every_seed_skipped = {n for n in order if all(job_name(n, s) in skipped for s in range(seeds))}
    return [n for n in order if n in required or n in wanted or n in every_seed_skipped], skipped


def _resolve_run(curriculum: Any, targets: Sequence[str] | None, seeds: int, timesteps: int | None, reuse: str,
                 algo: str | None, rnn: str | None) -> tuple[Curriculum, list[str], dict[str, Any]]:
    """The merged curriculum, the nodes to train (lower levels first) and the settings of a run (checked)."""
    from sb3_smc.curricula import resolve_curriculum

    check_run_options(seeds=seeds, timesteps=timesteps, reuse=reuse, algo=algo, rnn=rnn)
    items = curriculum if isinstance(curriculum, list | tuple) else [curriculum]
    merged = merge([resolve_curriculum(item) for item in items])
    selected = merged.select(targets)
    order = merged.order(selected)
    return merged, order, run_settings(merged, order, selected, seeds, timesteps, reuse, algo, rnn)


def _lock(directory: Path) -> Any:
    """Hold ``DIR/.lock`` for the run: a second coordinator on the same directory is refused (it would write the
    same manifest)."""
    import fcntl

    handle = open(directory / ".lock", "a+")  # noqa: SIM115 - held open for the whole run
    try:
        fcntl.flock(handle.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        handle.close()
        raise RunSettingsError(f"{directory} is being trained by another process (sb3-smc status {directory} shows "
                               "it); wait for it or stop it first") from None
    return handle


def _run(merged: Curriculum, scheduler: _Scheduler, order: list[str], directory: Path, seeds: int, backend: str,
         workers: int, ray_address: str | None, tensorboard: bool, progress: bool,
         printer: Callable[[str], None]) -> TrainingRun:
    damaged = _load_done(scheduler)
    failed_dir = directory / "failed"
    total = len(scheduler.jobs())
    done_before = sum(scheduler.done(n, s) for n, s in scheduler.jobs())
    skipped = sum(scheduler.done(n, s) and s not in scheduler.records[n] for n, s in scheduler.jobs())
    steps_total = sum(_rounded(scheduler.budget(merged.node(n))) for n, _ in scheduler.jobs())
    steps_done = sum(_rounded(scheduler.budget(merged.node(n))) for n, s in scheduler.jobs() if scheduler.done(n, s))
    if progress:
        printer(f"{merged.name}: {len(order)} nodes x {seeds} seeds = {total} jobs ({done_before} already done"
                f"{f', {skipped} of them skipped' if skipped else ''}) "
                f"in {directory}, backend {backend}, {workers} worker{'s' * (workers > 1)}")
        for why in damaged.values():
            printer(f"{why}: it is trained again")
    started = time.time()
    executor = _executor(backend, workers, ray_address)
    bar = _Progress(total, done_before, steps_total, steps_done, printer if progress else None)
    try:
        pending: dict[Any, str] = {}
        while True:
            for node_name, seed in scheduler.ready():
                if len(pending) >= workers:
                    break
                job = scheduler.job(node_name, seed, tensorboard)
                name = job.spec.name
                (failed_dir / f"{file_stem(name)}.txt").unlink(missing_ok=True)
                scheduler.running.add(name)
                pending[executor.submit(job)] = name
            _write_state(directory, scheduler.running, started, scheduler.skip)
            bar.show(len(scheduler.running))
            if not pending:
                break
            for handle, outcome in executor.wait(list(pending)):
                name = pending.pop(handle)
                scheduler.running.discard(name)
                node_name, _, seed_text = name.rpartition(SEED_SEPARATOR)
                if isinstance(outcome, BaseException):
                    text = "".join(traceback.format_exception(outcome))
                    scheduler.failed[name] = text.strip().splitlines()[-1]
                    atomic_write(failed_dir / f"{file_stem(name)}.txt", text)
                    bar.note(f"job {name} failed: {scheduler.failed[name]}")
                    continue
                earlier = _store(scheduler, outcome)
                scheduler.records[node_name][int(seed_text)] = outcome.record
                bar.running = len(scheduler.running)
                bar.finished(_rounded(scheduler.budget(merged.node(node_name))))
                if earlier is not None and not _trained_alike(earlier, outcome.record):
                    for above in _retrain_above(scheduler, node_name, name, bar.note):
                        bar.undone(_rounded(scheduler.budget(merged.node(above))))
    finally:
        executor.shutdown()
        _write_state(directory, [], started, scheduler.skip)
        bar.close()
    run = TrainingRun(directory=directory, library=scheduler.library, rows=_rows(scheduler),
                      failed=dict(scheduler.failed))
    blocked = scheduler.blocked()
    if progress:
        printer(run.table())
        if scheduler.failed:
            printer(f"{len(scheduler.failed)} job(s) failed (tracebacks in {failed_dir}); {len(blocked)} job(s) wait "
                    "for them; run the same command again to retry")
    return run


def _rounded(timesteps: int) -> int:
    return -(-timesteps // STEPS_PER_UPDATE) * STEPS_PER_UPDATE


def read_settings(directory: Path) -> dict[str, Any] | None:
    """The settings in ``directory/run.json``; ``None`` where ``directory`` holds no run yet (missing or empty).
    :class:`RunSettingsError` for a file, or a directory that holds other things; :class:`RunFileError` for a
    ``run.json`` that is not one."""
    if directory.exists() and not directory.is_dir():
        raise RunSettingsError(f"{directory} is a file, not a run directory: give a new directory or one of this run")
    path = directory / "run.json"
    if not path.is_file():
        if directory.is_dir() and any(p.name != ".lock" for p in directory.iterdir()):
            raise RunSettingsError(f"{directory} is not empty and holds no run.json: not a curriculum run directory")
        return None
    settings = read_json(path, "the settings of a curriculum run (sb3-smc train writes it)")
    if not isinstance(settings, dict) or settings.get("format") != RUN_FORMAT \
            or not isinstance(settings.get("nodes"), dict) or not isinstance(settings.get("seeds"), int):
        raise RunFileError(f"{path} is not the settings of an sb3-smc run (a JSON object of format {RUN_FORMAT!r} "
                           "with its nodes and seeds)")
    return settings


_NODE_KEYS = ("targets", "nodes")
"""Settings that ``accept_changes`` takes; the others (the curriculum's name, seeds, timesteps, reuse, algo, rnn)
decide every job, or which run the directory holds."""


@dataclass(frozen=True)
class _Changes:
    """How a run's settings differ from those its directory holds."""

    differences: list[str]
    every_job: list[str]  # differing settings that decide every job
    changed: list[str]  # nodes of both, with other settings
    removed: list[str]  # nodes of the directory, not of this run
    retrained: list[str]  # nodes of both whose jobs are trained again: the changed ones and every node using one

    @classmethod
    def between(cls, old: dict[str, Any], new: dict[str, Any], curriculum: Curriculum) -> _Changes:
        old_nodes, new_nodes = old["nodes"], new["nodes"]
        changed = [n for n in new_nodes if n in old_nodes and old_nodes[n] != new_nodes[n]]
        keys = sorted(set(old) | set(new))
        return cls(differences=_differences(old, new),
                   every_job=[k for k in keys if k not in _NODE_KEYS and old.get(k) != new.get(k)],
                   changed=changed, removed=[n for n in old_nodes if n not in new_nodes],
                   retrained=[n for n in new_nodes if n in old_nodes and curriculum.closure([n]) & set(changed)])

    def check(self, directory: Path, accept: bool) -> None:
        """:class:`RunSettingsError` listing the differences, unless there are none or they are accepted."""
        if not self.differences or accept and not self.every_job:
            return
        listed = "\n  ".join(self.differences)
        if accept:
            raise RunSettingsError(f"{directory} holds a run with other settings:\n  {listed}\n--accept-changes takes "
                                   f"changed nodes only; {', '.join(self.every_job)} decide every job: use another "
                                   "--out directory, or the settings of that run")
        offer = ""
        experiment = (directory / "results.json").is_file() or (directory / "evaluations").is_dir()
        if not self.every_job and not experiment:  # an experiment's merged curriculum is not named on a command line
            trained = f"the jobs of {', '.join(self.retrained)} are trained again" if self.retrained else \
                "no trained job changes"
            offer = (f", or accept the changes (sb3-smc train --accept-changes; train_curriculum(..., "
                     f"accept_changes=True)): {trained}, the other nodes keep theirs")
        raise RunSettingsError(f"{directory} holds a run with other settings:\n  {listed}\nuse another --out "
                               f"directory, or the settings of that run{offer}")

    def apply(self, directory: Path, printer: Callable[[str], None] | None) -> None:
        """Take the jobs of the retrained nodes out of the library (under the run's lock, before the new
        ``run.json`` is written): :func:`_replace`."""
        library = directory / "library"
        names = [n for n in _library_jobs(library) if node_of(n) in set(self.retrained)]
        lines = [f"accepting the changes in {directory}:", *(f"  {d}" for d in self.differences)]
        for name in self.retrained:
            why = "changed" if name in self.changed else "uses a changed node"
            lines.append(f"  node {name!r} is trained again ({why})")
        if self.removed:
            lines.append(f"  not in this run, kept in the library as they are: {', '.join(self.removed)}")
        if names:
            lines.append(_replace(directory, names))
        if printer is not None:
            printer("\n".join(lines))


def _replace(directory: Path, names: Sequence[str]) -> str:
    """Take the SMCs ``names`` out of the run's library, to be trained again; the library as it was, ``run.json``
    and their TensorBoard folders are kept in ``DIR/replaced/<time>-<random>/`` (nothing trained is lost). Returns
    a line saying so."""
    library = directory / "library"
    (directory / "replaced").mkdir(exist_ok=True)
    kept = make_temporary_directory(directory / "replaced", time.strftime("%Y%m%d-%H%M%S-"))
    shutil.copy2(directory / "run.json", kept / "run.json")
    storage.link_copy(library, kept / "library")
    for name in names:
        for folder in (directory / "tensorboard").glob(f"{_glob_escape(name)}_*"):
            (kept / "tensorboard").mkdir(exist_ok=True)
            folder.rename(kept / "tensorboard" / folder.name)
    storage.remove_from_library(library, names)
    shown = ", ".join(names[:6]) + (", ..." if len(names) > 6 else "")
    return f"  {len(names)} trained SMC(s) to train again ({shown}); the library as it was: {kept / 'library'}"


def _load_done(scheduler: _Scheduler) -> dict[str, str]:
    """Read the finished jobs from the library manifest (the only record of what is done), each checked against its
    model file: a job whose file is missing or damaged is not done (it is trained again and replaces its entry).
    Returns those jobs, with what is wrong with each."""
    damaged: dict[str, str] = {}
    for name, (entry, problem) in _library_jobs(scheduler.library).items():
        node_name, sep, seed_text = name.rpartition(SEED_SEPARATOR)
        if sep and node_name in scheduler.records and seed_text.isdigit() and entry["record"] is not None:
            if problem is None:
                scheduler.records[node_name][int(seed_text)] = entry["record"]
            elif name not in scheduler.skip:
                scheduler.damaged[name] = entry["record"]
                damaged[name] = problem
    return damaged


def _library_jobs(library: Path) -> dict[str, tuple[dict[str, Any], str | None]]:
    """Every SMC of a run's library: its manifest entry, and what is wrong with its model file (``None``: nothing;
    :func:`sb3_smc.library.storage.check_model_file`)."""
    if not (library / storage.MANIFEST).is_file():
        return {}
    manifest, where = storage.read_manifest(library)
    out: dict[str, tuple[dict[str, Any], str | None]] = {}
    for name, entry in storage.check_manifest(manifest, where).items():
        try:
            storage.check_model_file(library, name, entry)
            out[name] = (entry, None)
        except CorruptModelError as err:
            out[name] = (entry, str(err))
    return out


def _store(scheduler: _Scheduler, result: JobResult) -> TrainingRecord | None:
    """Add a finished job to the library (replacing the entry of a damaged one); returns the damaged one's record."""
    spec = result.spec
    assert spec.task.kind is not None  # a trained SMC's spec names its task's kind
    entry = storage.make_entry(spec.task.kind, result.algo, spec.children, spec.wrapper.include_primitives,
                               spec.frame_stack, spec, result.record)
    earlier = scheduler.damaged.pop(spec.name, None)
    storage.add_to_library(scheduler.library, spec.name, entry, result.model, replace=earlier is not None)
    return earlier


def _trained_alike(a: TrainingRecord, b: TrainingRecord) -> bool:
    """The same training (returns, selection, steps), whatever the wall time and versions."""
    def trained(record: TrainingRecord) -> dict[str, Any]:
        return {k: v for k, v in record.to_dict().items() if k not in ("wall_time_s", "versions")}

    return trained(a) == trained(b)


def _retrain_above(scheduler: _Scheduler, node_name: str, name: str, note: Callable[[str], None]) -> list[str]:
    """A damaged job ``name`` trained again differs from its earlier record (another CPU or code): the finished jobs
    of every node above its node were trained with the earlier one and are taken out of the library to be trained
    again (:func:`_replace`). Returns the node of each such job that counted as done."""
    above = [n for n in scheduler.order if node_name in scheduler.below[n]]
    jobs = [(n, seed) for n in above for seed in range(scheduler.seeds)
            if seed in scheduler.records[n] or job_name(n, seed) in scheduler.damaged]
    if not jobs:
        return []
    line = _replace(scheduler.directory, [job_name(n, seed) for n, seed in jobs])
    finished = [n for n, seed in jobs if scheduler.records[n].pop(seed, None) is not None]
    for n, seed in jobs:  # a damaged one is trained afresh too: its entry is gone
        scheduler.damaged.pop(job_name(n, seed), None)
    note(f"{name} trained again differs from its damaged copy's training (another CPU or code?); the SMCs above it "
         f"were trained with that copy:\n{line}")
    return finished


def _rows(scheduler: _Scheduler) -> list[dict[str, Any]]:
    rows = []
    for node_name, seed in scheduler.jobs():
        record = scheduler.records[node_name].get(seed)
        if record is not None:
            rows.append({"node": node_name, "seed": seed, "selected_update": record.selected_update,
                         "training_return": record.selected_return, "wall_time_s": record.wall_time_s})
    return rows


# ---------------------------------------------------------------------------------------------------------------
# Executors: in process, local processes, Ray
# ---------------------------------------------------------------------------------------------------------------

class _InProcess:
    """Trains a job in this process when it is waited for (as a worker would meanwhile), so the state file and the
    progress line count it as running while it trains."""

    def __init__(self) -> None:
        self._jobs: dict[int, Job] = {}
        self._next = 0

    def submit(self, job: Job) -> int:
        handle = self._next
        self._next += 1
        self._jobs[handle] = job
        return handle

    def wait(self, handles: list[int]) -> list[tuple[int, Any]]:
        handle = handles[0]
        try:
            return [(handle, run_job(self._jobs.pop(handle)))]
        except Exception as err:  # noqa: BLE001 - reported as the job's failure
            return [(handle, err)]

    def shutdown(self) -> None:
        self._jobs.clear()


class _Processes:
    def __init__(self, workers: int) -> None:
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        def make() -> ProcessPoolExecutor:
            return ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"))

        self._make = make
        self._pool = make()

    def submit(self, job: Job) -> Any:
        return self._pool.submit(run_job, job)

    def wait(self, handles: list[Any]) -> list[tuple[Any, Any]]:
        from concurrent.futures import FIRST_COMPLETED, wait
        from concurrent.futures.process import BrokenProcessPool

        done, _ = wait(handles, return_when=FIRST_COMPLETED)
        out = []
        broken = False
        for future in done:
            error = future.exception()
            if isinstance(error, BrokenProcessPool):
                broken = True
                hint = RuntimeError(
                    "a worker process died abruptly: killed (e.g. for memory), crashed, or, when a script trains with "
                    "workers > 1, the script starts the run at its top level: workers are spawned and import the "
                    "script again, so put the call under `if __name__ == \"__main__\":`")
                hint.__cause__ = error
                error = hint
            out.append((future, error if error is not None else future.result()))
        if broken:  # a worker died (e.g. killed for memory): its jobs count as failed, the run goes on
            self._pool.shutdown(wait=False, cancel_futures=True)
            self._pool = self._make()
        return out

    def shutdown(self) -> None:
        self._pool.shutdown(wait=True, cancel_futures=True)


class _Ray:
    def __init__(self, address: str | None) -> None:
        try:
            import ray
        except ImportError:
            raise SMCRuntimeError("backend='ray' needs Ray: pip install 'sb3-smc[ray]'") from None
        self._ray = ray
        if not ray.is_initialized():
            address = address or os.environ.get("RAY_ADDRESS")
            if address is None:
                raise SMCRuntimeError("backend='ray' runs on an existing Ray cluster: pass ray_address (--ray-address) "
                                      "or set RAY_ADDRESS (e.g. 'auto' on a node of the cluster, or ray://host:10001)")
            ray.init(address=address, log_to_driver=False)
        self._remote = ray.remote(num_cpus=1, max_retries=0)(run_job)
        self._pending: set[Any] = set()

    def submit(self, job: Job) -> Any:
        ref = self._remote.remote(job)
        self._pending.add(ref)
        return ref

    def wait(self, handles: list[Any]) -> list[tuple[Any, Any]]:
        ready, _ = self._ray.wait(handles, num_returns=1)
        out = []
        for ref in ready:
            self._pending.discard(ref)
            try:
                out.append((ref, self._ray.get(ref)))
            except Exception as err:  # noqa: BLE001 - a task's error, reported as the job's failure
                out.append((ref, err))
        return out

    def shutdown(self) -> None:
        for ref in self._pending:  # after an interrupt or an error: free the cluster
            self._ray.cancel(ref)
        self._pending.clear()


def _executor(backend: str, workers: int, address: str | None) -> Any:
    if backend == "ray":
        return _Ray(address)
    return _Processes(workers) if workers > 1 else _InProcess()


# ---------------------------------------------------------------------------------------------------------------
# Progress
# ---------------------------------------------------------------------------------------------------------------

class _Progress:
    """One live line: jobs done / total, running, steps/s, ETA (``\\r``-refreshed on a terminal, else one line per
    round of finished jobs, once their places are refilled (:meth:`show`), so that it counts the jobs running
    then)."""

    def __init__(self, total: int, done: int, steps_total: int, steps_done: int,
                 printer: Callable[[str], None] | None) -> None:
        import sys

        self.total, self.done, self.steps_total, self.steps_done = total, done, steps_total, steps_done
        self.printer = printer
        self.start = time.perf_counter()
        self.steps_at_start = steps_done
        self.tty = printer is print and sys.stdout.isatty()
        self.running = 0
        self.shown = done  # jobs done at the last log line

    def line(self) -> str:
        elapsed = time.perf_counter() - self.start
        rate = (self.steps_done - self.steps_at_start) / elapsed if elapsed > 0 else 0.0
        left = self.steps_total - self.steps_done
        eta = f"{left / rate / 60:.0f} min" if rate > 0 else "?"
        return (f"jobs {self.done}/{self.total}, running {self.running}, {rate:,.0f} steps/s, "
                f"ETA {eta if left else '0 min'}")

    def show(self, running: int) -> None:
        self.running = running
        if self.printer is not None and self.tty:
            print("\r" + self.line() + " " * 8, end="", flush=True)
        elif self.printer is not None and self.done > self.shown:
            self.shown = self.done
            self.printer(self.line())

    def finished(self, steps: int) -> None:
        self.done += 1
        self.steps_done += steps

    def undone(self, steps: int) -> None:
        """A finished job is to be trained again."""
        self.done -= 1
        self.steps_done -= steps
        self.shown = min(self.shown, self.done)

    def note(self, text: str) -> None:
        if self.printer is not None:
            if self.tty:
                print()
            self.printer(text)

    def close(self) -> None:
        if self.printer is not None and self.tty:
            print()


def status(directory: str | Path) -> dict[str, Any]:
    """What a run directory holds: ``done``, ``running``, ``failed``, ``skipped`` (by the last run's ``skip``: kept
    elsewhere, such as an experiment's evaluation records), ``damaged`` (finished, but the model file is missing or
    damaged: job name -> what is wrong; the next run trains them again) and ``left`` job names (and the
    settings)."""
    directory = Path(directory)
    settings = read_settings(directory) if directory.is_dir() else None
    if settings is None:
        raise RunSettingsError(f"{directory} is not a curriculum run directory (no run.json)")
    jobs = [job_name(node, seed) for node in settings["nodes"] for seed in range(settings["seeds"])]
    library = {name: problem for name, (_, problem) in _library_jobs(directory / "library").items()}
    done = {name for name, problem in library.items() if problem is None}
    running: list[str] = []
    skipped: set[str] = set()
    state_path = directory / "state.json"
    if state_path.is_file():
        holds = "the coordinator's pid and running jobs; delete it, the next sb3-smc train writes it again"
        state = read_json(state_path, holds)
        if not isinstance(state, dict) or not isinstance(state.get("pid", -1), int) \
                or not isinstance(state.get("running", []), list) or not isinstance(state.get("skipped", []), list):
            raise RunFileError(f"{state_path} is not the state of an sb3-smc run: it should hold {holds}")
        if state.get("running") and _alive(state.get("pid", -1)):
            running = [n for n in state["running"] if n not in done]
        skipped = set(state.get("skipped", ())) - done
    failed = sorted(name_of_file(p.stem) for p in (directory / "failed").glob("*.txt")) \
        if (directory / "failed").is_dir() else []
    failed = [n for n in failed if n in jobs and n not in done and n not in running]
    damaged = {n: library[n] for n in jobs if library.get(n) is not None and n not in running}
    left = [n for n in jobs if n not in done and n not in running and n not in failed and n not in skipped
            and n not in damaged]
    return {"settings": settings, "jobs": jobs, "done": [n for n in jobs if n in done], "running": running,
            "failed": failed, "skipped": [n for n in jobs if n in skipped], "damaged": damaged, "left": left}


def _alive(pid: int) -> bool:
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def describe(curriculum: Curriculum) -> str:
    """A curriculum's DAG by level (what ``sb3-smc curricula NAME`` prints)."""
    lines = [curriculum.name + (f" ({curriculum.method})" if curriculum.method else "")]
    if curriculum.description:
        lines.append(curriculum.description)
    targets = set(curriculum.targets)
    for level, names in enumerate(curriculum.levels(), start=1):
        lines.append(f"level {level}: {len(names)} node{'s' * (len(names) != 1)}")
        for name in names:
            node = curriculum.node(name)
            mark = "*" if name in targets else " "
            extra = []
            if node.task != name:
                extra.append(f"task {node.task}")
            if not node.include_primitives:
                extra.append("noprim")
            if node.algo:
                extra.append(node.algo)
            if node.timesteps:
                extra.append(f"{node.timesteps:,} steps")
            head = f"  {mark} {name}" + (f" ({', '.join(extra)})" if extra else "")
            lines.append(head + (f" uses {', '.join(node.uses)}" if node.uses else ""))
    lines.append("(* = target)")
    return "\n".join(lines)

