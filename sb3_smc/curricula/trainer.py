"""``train_curriculum``: every node x seed of a curriculum trained level by level into one SMC library.

The run's options are one checked record (:class:`~sb3_smc.curricula.options.RunOptions`, given whole or as
keywords), made here and passed whole to the layers below. The run schedules jobs (:mod:`sb3_smc.curricula.jobs`:
one node with one seed, a :class:`~sb3_smc.curricula.jobs.JobId`, calling the ``k`` best seeds of every node it
uses) on an executor (:mod:`sb3_smc.curricula.executors`: this process, local processes or Ray) and keeps
its state in the run directory (:mod:`sb3_smc.curricula.run_directory`: ``run.json``, the library, ``failed/``,
``state.json``, ``replaced/``, ``.lock``). A job becomes ready once every seed of every node it uses is trained;
jobs with the longest chain of nodes above them start first. The ready seeds of a flat node train together, in
groups of up to ``group_size`` (:func:`~sb3_smc.curricula.jobs.run_group`, :func:`~sb3_smc.learning.batched.train_smcs`,
also for a group of one): a group is a unit of execution only, each of its SMCs the one its job alone trains, stored
as a job's is. ``group_size=1`` trains every job alone with :func:`~sb3_smc.curricula.jobs.run_job`.

Jobs whose results are kept elsewhere can be skipped (``skip``: e.g. the evaluated SMCs of an experiment whose run
directory lost its library); a skipped job is trained all the same when a job still to train needs its node as a
child (the ranking of a node's seeds needs every seed), and nodes that only skipped jobs need are not trained.

Crash safety: a finished job is one whose SMC is in the library manifest; the model file and then the manifest are
written atomically by the coordinator (the only writer), so killing the process at any moment loses at most the jobs
that were running (all of a running group), which the next run starts again from scratch. Finished jobs are never
trained again and their files never rewritten, except that a job whose model file is missing or damaged (checked
against the manifest's SHA-256 by every run and by :func:`~sb3_smc.curricula.run_directory.status`) is trained
again, replacing its entry, and so are the jobs above it when that training differs from the recorded one
(``DIR/retrain.json`` names them from before the repaired job is stored until they are out, so a kill in between
loses nothing); accepted node changes replace the jobs of the changed nodes and of the nodes above them. The working
SMCs so replaced stay in ``DIR/replaced/``.

The names of the modules above that this one offered before it was split are imported from here as before.
"""

from __future__ import annotations

import dataclasses
import fcntl
import json
import shutil
import sys
import time
import traceback
from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pixelworld_env.atomic import atomic_write
from sb3_smc.core.hyperparameters import STEPS_PER_UPDATE
from sb3_smc.curricula.executors import Outcome, make_executor
from sb3_smc.curricula.format import SEED_SEPARATOR, Curriculum, describe, merge
from sb3_smc.curricula.jobs import (
    DEFAULT_REUSE,
    DEFAULT_SEEDS,
    REUSE,
    Job,
    JobId,
    JobResult,
    check_curriculum,
    file_stem,
    job_name,
    name_of_file,
    node_of,
    node_spec,
    rank_seeds,
    run_group,
    run_job,
)
from sb3_smc.curricula.options import BACKENDS, DEFAULT_GROUP_SIZE, RunOptions
from sb3_smc.curricula.reuse import ReuseLibrary
from sb3_smc.curricula.run_directory import (
    CHECKPOINTS,
    PENDING_RETRAIN,
    RunFileError,
    RunSettingsError,
    SettingsChanges,
    library_jobs,
    read_json,
    read_settings,
    replace_jobs,
    run_settings,
    status,
    write_state,
)
from sb3_smc.curricula.scheduler import Scheduler
from sb3_smc.curricula.shipped import resolve_curriculum
from sb3_smc.errors import SMCError, SMCRuntimeError, SMCTypeError
from sb3_smc.library import storage
from sb3_smc.records import TrainingRecord

__all__ = ["BACKENDS", "DEFAULT_GROUP_SIZE", "DEFAULT_REUSE", "DEFAULT_SEEDS", "REUSE", "Job", "JobId", "JobResult",
           "RunFileError", "RunOptions", "RunSettingsError", "TrainingRun", "check_curriculum", "check_run_options",
           "describe", "file_stem", "finished_jobs", "job_name", "name_of_file", "node_of", "node_spec",
           "rank_seeds", "read_json", "read_settings", "run_group", "run_job", "run_settings", "status",
           "train_curriculum"]


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
    lean_update: bool = False,
    ray_address: str | None = None,
    group_size: int = DEFAULT_GROUP_SIZE,
    tensorboard: bool = True,
    progress: bool = True,
    printer: Callable[[str], None] = print,
    skip: Collection[str] = (),
    accept_changes: bool = False,
    reuse_from: str | Path | None = None,
    options: RunOptions | None = None,
) -> TrainingRun:
    """Train a curriculum into ``out``, resuming whatever ``out`` already holds. Every setting and node is checked
    before anything is written or trained; the trained SMCs are the same whatever the backend, worker count and
    group size.

    :param curriculum: a shipped name, a file, a :class:`Curriculum`, or several (their nodes are merged, a node
        shared by several is trained once).
    :param out: the run directory.
    :param targets: node or dataset names (default: the curriculum's targets); they and every node they use are
        trained.
    :param seeds: seeds ``0 .. seeds-1`` of every node.
    :param timesteps: replaces every node's own budget.
    :param reuse: how many of a used node's best seeds a node calls: ``"two_best"`` or ``"one_best"``.
    :param workers: jobs in parallel (local processes; with Ray, the jobs in flight).
    :param backend: ``"local"`` or ``"ray"``.
    :param algo: replaces every node's learner.
    :param rnn: the recurrent cell of every node (``"lstm"`` or ``"gru"``; recurrent algorithms only).
    :param lean_update: train every SMC with the lean update (equal up to float rounding, not bit for bit;
        RecurrentPPO or RecurrentTRPO with one LSTM or GRU layer, checked for every node first); ``run.json``
        records it, and a library's SMCs are reused only when trained with the same update.
    :param ray_address: the Ray cluster (default: ``RAY_ADDRESS``, else a local instance).
    :param group_size: the most ready seeds of a flat node trained together as one unit (one worker process or Ray
        task, :func:`~sb3_smc.curricula.jobs.run_group`; 1: every job alone;
        :meth:`~sb3_smc.curricula.scheduler.Scheduler.units`).
    :param tensorboard: write each job's curves under ``DIR/tensorboard``.
    :param progress: print progress lines through ``printer``.
    :param printer: where progress lines go.
    :param skip: job names not to train (their results are kept elsewhere); one whose node a job still to train
        uses is trained all the same, and nodes that only skipped jobs use are not trained.
    :param accept_changes: ``out`` holds this run with other node settings (or other nodes): the jobs of the changed
        nodes and of every node above them are trained again (the SMCs they replace are kept in
        ``DIR/replaced/``), the other nodes keep theirs.
    :param reuse_from: a library whose SMCs this run copies instead of training them where it holds them with the
        very spec the run would train (a pretrained library: a node's best seeds, its other seeds then not trained;
        :mod:`sb3_smc.curricula.reuse`).
    :param options: the run's options whole (:class:`~sb3_smc.curricula.options.RunOptions`), instead of the
        keywords ``seeds`` to ``group_size``, ``tensorboard`` and ``reuse_from`` (which must then be left out).
    :return: the :class:`TrainingRun`. Jobs that fail are reported (``DIR/failed/``) and retried by the next run;
        jobs needing them wait. A finished job whose model file is missing or damaged is trained again.
    """
    options = RunOptions.of(options, seeds=seeds, timesteps=timesteps, reuse=reuse, workers=workers, backend=backend,
                            algo=algo, rnn=rnn, lean_update=lean_update, ray_address=ray_address,
                            group_size=group_size,
                            tensorboard=tensorboard, reuse_from=reuse_from)
    source = ReuseLibrary(options.reuse_from) if options.reuse_from is not None else None
    merged, order, settings = _resolve_run(curriculum, targets, options)
    directory = Path(out)
    order, skipped = _plan_skip(merged, order, settings["targets"], options, skip)
    # the jobs of nodes left out of the plan count as skipped too (sb3-smc status shows them so, not as "left")
    skipped |= {job for job in options.jobs(settings["nodes"]) if job.node not in order}
    scheduler = Scheduler(merged, order, options, directory, skipped)
    options.check(merged, order)
    old = read_settings(directory)
    changes = SettingsChanges.between(old, settings, merged) if old is not None else None
    if changes is not None and changes.differences:
        changes.check(directory, accept_changes)
    directory.mkdir(parents=True, exist_ok=True)
    lock = _lock(directory)
    try:
        if old is None or changes is not None and changes.differences:
            if changes is not None:
                changes.apply(directory, printer if progress else None)
            atomic_write(directory / "run.json", json.dumps(settings, indent=2) + "\n")
        return _run(scheduler, progress, printer, source, settings)
    finally:
        lock.close()


def check_run_options(*, seeds: int = DEFAULT_SEEDS, timesteps: int | None = None, reuse: str = DEFAULT_REUSE,
                      workers: int = 1, backend: str = BACKENDS[0], ray_address: str | None = None,
                      algo: str | None = None, rnn: str | None = None, group_size: int = DEFAULT_GROUP_SIZE,
                      lean_update: bool = False) -> RunOptions:
    """The :class:`~sb3_smc.curricula.options.RunOptions` of these keywords: ``ValueError`` naming the first option
    of a run that is out of range (before anything is done). The check is the record's own."""
    return RunOptions(seeds=seeds, timesteps=timesteps, reuse=reuse, workers=workers, backend=backend,
                      ray_address=ray_address, algo=algo, rnn=rnn, group_size=group_size, lean_update=lean_update)


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
    lean_update: bool = False,
    options: RunOptions | None = None,
) -> set[str]:
    """The job names (``<node>@<seed>``) that the run :func:`train_curriculum` would resume in ``out`` has finished,
    without training or writing anything (the run may be training meanwhile). ``RunSettingsError`` when ``out``
    holds no run or a run with other settings. The arguments are :func:`train_curriculum`'s (``options``: those
    that decide the SMCs, whole; the others are not used)."""
    options = RunOptions.of(options, seeds=seeds, timesteps=timesteps, reuse=reuse, algo=algo, rnn=rnn,
                            lean_update=lean_update)
    merged, _, settings = _resolve_run(curriculum, targets, options)
    directory = Path(out)
    old = read_settings(directory)
    if old is None:
        raise RunSettingsError(f"{directory} holds no run yet (no run.json): nothing is trained")
    SettingsChanges.between(old, settings, merged).check(directory, accept=False)
    return set(status(directory)["done"])


def _plan_skip(curriculum: Curriculum, order: list[str], targets: Sequence[str], options: RunOptions,
               skip: Collection[str]) -> tuple[list[str], frozenset[JobId]]:
    """The nodes to schedule and the jobs to skip (``skip``: names, read here). A target job not in ``skip`` is
    wanted; every node that a wanted job's node uses (at any depth) is trained with every seed, skipped or not; the
    other skipped jobs are skipped, and nodes that no wanted job needs are left out."""
    if isinstance(skip, str):
        raise SMCTypeError(f"skip must be a collection of job names, got the string {skip!r}")
    known = set(order)
    jobs = set()
    for name in frozenset(skip):
        job = JobId.of(name) if isinstance(name, str) else None
        if job is None or job.node not in known or job.seed >= options.seeds:
            raise SMCError(f"skip: {name!r} is not a job of this run (<node>{SEED_SEPARATOR}<seed> with one of its "
                           f"{len(order)} nodes and a seed below {options.seeds})")
        jobs.add(job)
    wanted = [n for n in targets if any(JobId(n, s) not in jobs for s in range(options.seeds))]
    required: set[str] = set()
    for name in wanted:
        required |= curriculum.closure([name]) - {name}
    skipped = frozenset(job for job in jobs if job.node not in required)
    every_seed_skipped = {n for n in order if all(JobId(n, s) in skipped for s in range(options.seeds))}
    return [n for n in order if n in required or n in wanted or n in every_seed_skipped], skipped


def _resolve_run(curriculum: Any, targets: Sequence[str] | None, options: RunOptions
                 ) -> tuple[Curriculum, list[str], dict[str, Any]]:
    """The merged curriculum, the nodes to train (lower levels first) and the settings of a run (checked)."""
    items = curriculum if isinstance(curriculum, list | tuple) else [curriculum]
    merged = merge([resolve_curriculum(item) for item in items])
    selected = merged.select(targets)
    if options.train_worlds is not None:  # the targets learn from a few worlds; their lower levels from all
        merged = dataclasses.replace(merged, nodes=tuple(
            dataclasses.replace(node, train_worlds=options.train_worlds) if node.name in selected else node
            for node in merged.nodes))
    order = merged.order(selected)
    return merged, order, run_settings(merged, order, selected, options)


def _lock(directory: Path) -> Any:
    """Hold ``DIR/.lock`` for the run: a second coordinator on the same directory is refused (it would write the
    same manifest)."""
    handle = open(directory / ".lock", "a+")  # noqa: SIM115 - held open for the whole run
    try:
        fcntl.flock(handle.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        handle.close()
        raise RunSettingsError(f"{directory} is being trained by another process (sb3-smc status {directory} shows "
                               "it); wait for it or stop it first") from None
    return handle


def _run(scheduler: Scheduler, progress: bool, printer: Callable[[str], None], source: ReuseLibrary | None,
         settings: dict[str, Any]) -> TrainingRun:
    """Train the jobs of ``scheduler`` that are not done (copying from ``source`` what it holds), as
    :func:`train_curriculum` describes."""
    merged, options, directory = scheduler.curriculum, scheduler.options, scheduler.directory
    _finish_pending_retrain(directory, printer)
    damaged = _load_done(scheduler)
    jobs = scheduler.jobs()
    if source is not None:
        to_train = [n for n in scheduler.order if not all(scheduler.done(JobId(n, s)) for s in range(options.seeds))]
        # a node whose jobs are all done or skipped needs nothing, and its children may be out of the plan
        scheduler.skip = scheduler.skip | source.reuse(scheduler, to_train, set(settings["targets"]))
    failed_dir = directory / "failed"
    done_before = sum(scheduler.done(job) for job in jobs)
    skipped = sum(scheduler.done(job) and job.seed not in scheduler.records[job.node] for job in jobs)
    steps_total = sum(_rounded(options.budget(merged.node(job.node))) for job in jobs)
    steps_done = sum(_rounded(options.budget(merged.node(job.node))) for job in jobs if scheduler.done(job))
    if progress:
        workers, group_size = options.workers, options.group_size
        printer(f"{merged.name}: {len(scheduler.order)} nodes x {options.seeds} seeds = {len(jobs)} jobs "
                f"({done_before} already done{f', {skipped} of them skipped' if skipped else ''}) "
                f"in {directory}, backend {options.backend}, {workers} worker{'s' * (workers > 1)}"
                f"{f', seeds in groups of up to {group_size}' if group_size > 1 else ''}")
        for why in damaged.values():
            printer(f"{why}: it is trained again")
    started = time.time()
    # run_job, run_group: this module's, at each run
    executor = make_executor(options, run_job, run_group)
    bar = _Progress(len(jobs), done_before, steps_total, steps_done, printer if progress else None)
    pending: dict[Any, tuple[JobId, ...]] = {}
    try:
        while True:
            for unit in scheduler.units(scheduler.ready(), options.group_size, options.workers):
                if len(pending) >= options.workers:
                    break
                grouped = options.group_size > 1 and scheduler.groupable(unit[0].node)  # train_smcs, also for one
                resumed = grouped and scheduler.saved(unit)  # its TensorBoard curves go on
                work = tuple(scheduler.job(job, resumed=resumed) for job in unit)
                for job in unit:
                    (failed_dir / f"{file_stem(str(job))}.txt").unlink(missing_ok=True)
                scheduler.running.update(unit)
                pending[executor.submit(work if grouped else work[0])] = unit
            write_state(directory, scheduler.running, started, scheduler.skip)
            bar.show(len(scheduler.running))
            if not pending:
                break
            for handle, outcome in executor.wait(list(pending)):
                unit = pending.pop(handle)
                scheduler.running.difference_update(unit)
                _finish(scheduler, unit, outcome, bar)
    finally:
        executor.shutdown(now=bool(pending))  # jobs still training: stopped (interrupted, terminated) or failed
        write_state(directory, [], started, scheduler.skip)
        bar.close()
    if all(scheduler.done(job) for job in jobs):  # groups saved in an earlier attempt and then split otherwise
        shutil.rmtree(directory / CHECKPOINTS, ignore_errors=True)
    run = TrainingRun(directory=directory, library=scheduler.library, rows=_rows(scheduler),
                      failed={str(job): why for job, why in scheduler.failed.items()})
    blocked = scheduler.blocked()
    if progress:
        printer(run.table())
        if scheduler.failed:
            printer(f"{len(scheduler.failed)} job(s) failed (tracebacks in {failed_dir}); {len(blocked)} job(s) wait "
                    "for them; run the same command again to retry")
    return run


def _finish(scheduler: Scheduler, unit: tuple[JobId, ...], outcome: Outcome | BaseException, bar: _Progress) -> None:
    """Record the outcome of the unit that trained the jobs ``unit``: each result stored as it comes (the model
    file, then the manifest entry), or the unit's exception as the failure of each job."""
    directory = scheduler.directory
    if isinstance(outcome, BaseException):
        text = "".join(traceback.format_exception(outcome))
        for job in unit:
            scheduler.failed[job] = text.strip().splitlines()[-1]
            atomic_write(directory / "failed" / f"{file_stem(str(job))}.txt", text)
            bar.note(f"job {job} failed: {scheduler.failed[job]}")
        return
    results = outcome if isinstance(outcome, list) else [outcome]
    if [result.spec.name for result in results] != [str(job) for job in unit]:  # run_group keeps the order
        raise SMCRuntimeError(f"a unit trained {[r.spec.name for r in results]} for the jobs {list(map(str, unit))}")
    for job, result in zip(unit, results, strict=True):
        earlier = scheduler.damaged.get(job)
        differs = earlier is not None and not _trained_alike(earlier, result.record)
        above = _above(scheduler, job.node) if differs else []
        if differs:  # what was trained with the damaged copy goes, even if the run dies after storing
            atomic_write(directory / PENDING_RETRAIN, json.dumps(
                {"repaired": str(job), "jobs": [str(j) for j in above]}, indent=1))
        _store(scheduler, job, result)
        scheduler.records[job.node][job.seed] = result.record
        bar.running = len(scheduler.running)
        bar.finished(_rounded(scheduler.options.budget(scheduler.curriculum.node(job.node))))
        if differs:
            for undone in _retrain_above(scheduler, above, job, bar.note):
                bar.undone(_rounded(scheduler.options.budget(scheduler.curriculum.node(undone))))
            (directory / PENDING_RETRAIN).unlink()


def _rounded(timesteps: int) -> int:
    return -(-timesteps // STEPS_PER_UPDATE) * STEPS_PER_UPDATE


def _load_done(scheduler: Scheduler) -> dict[JobId, str]:
    """Read the finished jobs from the library manifest (the only record of what is done), each checked against its
    model file: a job whose file is missing or damaged is not done (it is trained again and replaces its entry).
    Returns those jobs, with what is wrong with each."""
    damaged: dict[JobId, str] = {}
    for name, (entry, problem) in library_jobs(scheduler.library).items():
        job = JobId.of(name)
        if job is not None and job.node in scheduler.records and entry.record is not None:
            if problem is None:
                scheduler.records[job.node][job.seed] = entry.record
            elif job not in scheduler.skip:
                scheduler.damaged[job] = entry.record
                damaged[job] = problem
    return damaged


def _store(scheduler: Scheduler, job: JobId, result: JobResult) -> None:
    """Add finished ``job`` to the library (replacing the entry of a damaged one)."""
    spec = result.spec
    entry = storage.entry_json(spec.name, result.algo, spec.frame_stack, spec, result.record)
    earlier = scheduler.damaged.pop(job, None)
    storage.add_to_library(scheduler.library, spec.name, entry, result.model, replace=earlier is not None)


def _finish_pending_retrain(directory: Path, note: Callable[[str], None]) -> None:
    """A run that died between storing a repaired job that trained differently and taking out the jobs trained with
    its damaged copy (``PENDING_RETRAIN`` says which) takes them out now, before anything counts as done."""
    marker = directory / PENDING_RETRAIN
    if not marker.is_file():
        return
    try:
        pending = json.loads(marker.read_text(encoding="utf-8"))
        repaired, jobs = pending["repaired"], list(pending["jobs"])
    except (ValueError, KeyError, TypeError) as err:
        raise RunFileError(f"{marker} is damaged ({type(err).__name__}: {err}); it names the jobs to train again "
                           f"after a repaired one: delete them from the library by hand (or the whole run), then "
                           "the file") from None
    present = [name for name in jobs if name in library_jobs(directory / "library")]
    if present:
        line = replace_jobs(directory, present)
        note(f"{repaired} was trained again differently before the last run stopped; the SMCs trained with its "
             f"damaged copy are trained again:\n{line}")
    marker.unlink()


def _trained_alike(a: TrainingRecord, b: TrainingRecord) -> bool:
    """The same selected SMC by the record: the same selection and the same returns up to it, whatever came after
    (a run that stopped at the largest return against one that ran its whole budget), wall time and versions."""
    def selection(record: TrainingRecord) -> tuple[Any, ...]:
        returns = record.to_dict()["training_returns"]  # NaN as None: comparable
        end = len(returns) if record.selected_update is None else record.selected_update + 1
        return (record.selected_update, record.selected_return, returns[:end], record.action_names,
                record.initial_action_probabilities)

    return selection(a) == selection(b)


def _above(scheduler: Scheduler, node_name: str) -> list[JobId]:
    """The finished (or damaged) jobs of every node above ``node_name``."""
    above = [n for n in scheduler.order if node_name in scheduler.below[n]]
    return [job for job in scheduler.options.jobs(above)
            if job.seed in scheduler.records[job.node] or job in scheduler.damaged]


def _retrain_above(scheduler: Scheduler, jobs: list[JobId], repaired: JobId, note: Callable[[str], None]
                   ) -> list[str]:
    """A damaged job ``repaired`` trained again differs from its earlier record (another CPU or code): the finished
    jobs above its node (``jobs``, :func:`_above`) were trained with the earlier one and are taken out of the
    library to be trained again (:func:`replace_jobs`). Returns the node of each such job that counted as done."""
    if not jobs:
        return []
    line = replace_jobs(scheduler.directory, [str(job) for job in jobs])
    finished = [job.node for job in jobs if scheduler.records[job.node].pop(job.seed, None) is not None]
    for job in jobs:  # a damaged one is trained afresh too: its entry is gone
        scheduler.damaged.pop(job, None)
    note(f"{repaired} trained again differs from its damaged copy's training (another CPU or code?); the SMCs above it "
         f"were trained with that copy:\n{line}")
    return finished


def _rows(scheduler: Scheduler) -> list[dict[str, Any]]:
    rows = []
    for job in scheduler.jobs():
        record = scheduler.records[job.node].get(job.seed)
        if record is not None:
            rows.append({"node": job.node, "seed": job.seed, "selected_update": record.selected_update,
                         "training_return": record.selected_return, "wall_time_s": record.wall_time_s})
    return rows


# ---------------------------------------------------------------------------------------------------------------
# Progress
# ---------------------------------------------------------------------------------------------------------------

class _Progress:
    """Progress of a run: jobs done / total, running, budget steps/s and the ETA. On a terminal a tqdm bar over the
    run's budget steps (its description the jobs done and running); else one line per round of finished jobs, once
    their places are refilled (:meth:`show`), so that it counts the jobs running then. A finished job counts its
    whole budget, also when its training stopped at the largest return, so that the rate and the jobs left are in
    the same units."""

    def __init__(self, total: int, done: int, steps_total: int, steps_done: int,
                 printer: Callable[[str], None] | None) -> None:
        self.total, self.done, self.steps_total, self.steps_done = total, done, steps_total, steps_done
        self.printer = printer
        self.start = time.perf_counter()
        self.steps_at_start = steps_done
        self.running = 0
        self.shown = done  # jobs done at the last log line
        self.bar: Any = None
        if printer is print and sys.stdout.isatty():
            from tqdm import tqdm

            self.bar = tqdm(total=steps_total, initial=steps_done, unit="step", unit_scale=True, dynamic_ncols=True,
                            desc=self._jobs(), file=sys.stdout)

    def _jobs(self) -> str:
        return f"jobs {self.done}/{self.total}, running {self.running}"

    def line(self) -> str:
        elapsed = time.perf_counter() - self.start
        rate = (self.steps_done - self.steps_at_start) / elapsed if elapsed > 0 else 0.0
        left = self.steps_total - self.steps_done
        eta = f"{left / rate / 60:.0f} min" if rate > 0 else "?"
        return f"{self._jobs()}, {rate:,.0f} budget steps/s, ETA {eta if left else '0 min'}"

    def show(self, running: int) -> None:
        self.running = running
        if self.bar is not None:
            self.bar.set_description(self._jobs(), refresh=False)
            self.bar.update(self.steps_done - self.bar.n)
            self.bar.refresh()  # also when only the jobs running changed (update draws at most every 0.1 s)
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
        if self.bar is not None:
            self.bar.write(text)
        elif self.printer is not None:
            self.printer(text)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


