"""``train_curriculum``: every node x seed of a curriculum trained level by level into one SMC library.

The run schedules jobs (:mod:`sb3_smc.curricula.jobs`: one node with one seed, calling the ``k`` best seeds of every
node it uses) on an executor (:mod:`sb3_smc.curricula.executors`: this process, local processes or Ray) and keeps
its state in the run directory (:mod:`sb3_smc.curricula.run_directory`: ``run.json``, the library, ``failed/``,
``state.json``, ``replaced/``, ``.lock``). A job becomes ready once every seed of every node it uses is trained;
jobs with the longest chain of nodes above them start first. The ready seeds of a flat node train together, in
groups of up to ``group_size`` (:func:`~sb3_smc.curricula.jobs.run_group`, :func:`~sb3_smc.batched.train_smcs`,
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

import fcntl
import json
import sys
import time
import traceback
from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pixelworld_env.atomic import atomic_write
from sb3_smc.curricula.executors import BACKENDS, Outcome, make_executor
from sb3_smc.curricula.format import SEED_SEPARATOR, Curriculum, describe, merge
from sb3_smc.curricula.jobs import (
    DEFAULT_REUSE,
    DEFAULT_SEEDS,
    REUSE,
    Job,
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
from sb3_smc.curricula.reuse import ReuseLibrary
from sb3_smc.curricula.run_directory import (
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
from sb3_smc.errors import SMCError, SMCTypeError
from sb3_smc.hyperparameters import STEPS_PER_UPDATE, algorithm, recurrent_policy
from sb3_smc.library import storage
from sb3_smc.records import TrainingRecord

__all__ = ["BACKENDS", "DEFAULT_GROUP_SIZE", "DEFAULT_REUSE", "DEFAULT_SEEDS", "REUSE", "Job", "JobResult",
           "RunFileError", "RunSettingsError", "TrainingRun", "check_curriculum", "check_run_options",
           "describe", "file_stem", "finished_jobs", "job_name", "name_of_file", "node_of", "node_spec",
           "rank_seeds", "read_json", "read_settings", "run_group", "run_job", "run_settings", "status",
           "train_curriculum"]

DEFAULT_GROUP_SIZE = 5
"""The most seeds of a flat node trained together in one worker (``group_size``; 1: one job per worker, as before
issue 44). docs/benchmarks.md, "Grouped jobs in the curriculum trainer", has the measurement behind it."""


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
    ray_address: str | None = None,
    group_size: int = DEFAULT_GROUP_SIZE,
    tensorboard: bool = True,
    progress: bool = True,
    printer: Callable[[str], None] = print,
    skip: Collection[str] = (),
    accept_changes: bool = False,
    reuse_from: str | Path | None = None,
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
    :return: the :class:`TrainingRun`. Jobs that fail are reported (``DIR/failed/``) and retried by the next run;
        jobs needing them wait. A finished job whose model file is missing or damaged is trained again.
    """
    check_run_options(workers=workers, backend=backend, ray_address=ray_address, group_size=group_size)
    source = ReuseLibrary(reuse_from) if reuse_from is not None else None
    merged, order, settings = _resolve_run(curriculum, targets, seeds, timesteps, reuse, algo, rnn)
    directory = Path(out)
    order, skipped = _plan_skip(merged, order, settings["targets"], seeds, skip)
    # the jobs of nodes left out of the plan count as skipped too (sb3-smc status shows them so, not as "left")
    skipped |= {job_name(n, s) for n in settings["nodes"] if n not in order for s in range(seeds)}
    scheduler = Scheduler(merged, order, seeds, timesteps, REUSE[reuse], algo, directory, rnn, skipped)
    check_curriculum(merged, order, timesteps=timesteps, algo=algo, rnn=rnn, reuse=reuse)
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
        return _run(merged, scheduler, order, directory, seeds, backend, workers, group_size, ray_address,
                    tensorboard, progress, printer, source, settings)
    finally:
        lock.close()


def check_run_options(*, seeds: int = DEFAULT_SEEDS, timesteps: int | None = None, reuse: str = DEFAULT_REUSE,
                      workers: int = 1, backend: str = BACKENDS[0], ray_address: str | None = None,
                      algo: str | None = None, rnn: str | None = None, group_size: int = DEFAULT_GROUP_SIZE) -> None:
    """``ValueError`` naming the first option of a run that is out of range (before anything is done)."""
    for name, value, optional in (("seeds", seeds, False), ("workers", workers, False), ("timesteps", timesteps, True),
                                  ("group_size", group_size, False)):
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
    SettingsChanges.between(old, settings, merged).check(directory, accept=False)
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
    check_run_options(seeds=seeds, timesteps=timesteps, reuse=reuse, algo=algo, rnn=rnn)
    items = curriculum if isinstance(curriculum, list | tuple) else [curriculum]
    merged = merge([resolve_curriculum(item) for item in items])
    selected = merged.select(targets)
    order = merged.order(selected)
    return merged, order, run_settings(merged, order, selected, seeds, timesteps, reuse, algo, rnn)


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


def _run(merged: Curriculum, scheduler: Scheduler, order: list[str], directory: Path, seeds: int, backend: str,
         workers: int, group_size: int, ray_address: str | None, tensorboard: bool, progress: bool,
         printer: Callable[[str], None], source: ReuseLibrary | None, settings: dict[str, Any]) -> TrainingRun:
    _finish_pending_retrain(directory, printer)
    damaged = _load_done(scheduler)
    if source is not None:
        to_train = [n for n in order if not all(scheduler.done(n, s) for s in range(seeds))]
        # a node whose jobs are all done or skipped needs nothing, and its children may be out of the plan
        reused = source.reuse(merged, to_train, set(settings["targets"]), seeds, scheduler.k, scheduler.records,
                              scheduler.best_of, scheduler.complete, lambda n: scheduler.children(merged.node(n)),
                              scheduler.library, timesteps=scheduler.timesteps, algo=scheduler.algo,
                              rnn=scheduler.rnn)
        scheduler.skip = scheduler.skip | reused
    failed_dir = directory / "failed"
    total = len(scheduler.jobs())
    done_before = sum(scheduler.done(n, s) for n, s in scheduler.jobs())
    skipped = sum(scheduler.done(n, s) and s not in scheduler.records[n] for n, s in scheduler.jobs())
    steps_total = sum(_rounded(scheduler.budget(merged.node(n))) for n, _ in scheduler.jobs())
    steps_done = sum(_rounded(scheduler.budget(merged.node(n))) for n, s in scheduler.jobs() if scheduler.done(n, s))
    if progress:
        printer(f"{merged.name}: {len(order)} nodes x {seeds} seeds = {total} jobs ({done_before} already done"
                f"{f', {skipped} of them skipped' if skipped else ''}) "
                f"in {directory}, backend {backend}, {workers} worker{'s' * (workers > 1)}"
                f"{f', flat seeds in groups of up to {group_size}' if group_size > 1 else ''}")
        for why in damaged.values():
            printer(f"{why}: it is trained again")
    started = time.time()
    # run_job, run_group: this module's, at each run
    executor = make_executor(backend, workers, ray_address, run_job, run_group)
    bar = _Progress(total, done_before, steps_total, steps_done, printer if progress else None)
    try:
        pending: dict[Any, tuple[str, ...]] = {}
        while True:
            for unit in scheduler.units(scheduler.ready(), group_size, workers):
                if len(pending) >= workers:
                    break
                jobs = tuple(scheduler.job(node_name, seed, tensorboard) for node_name, seed in unit)
                names = tuple(job.spec.name for job in jobs)
                for name in names:
                    (failed_dir / f"{file_stem(name)}.txt").unlink(missing_ok=True)
                scheduler.running.update(names)
                grouped = group_size > 1 and scheduler.groupable(unit[0][0])  # train_smcs, also for one SMC
                pending[executor.submit(jobs if grouped else jobs[0])] = names
            write_state(directory, scheduler.running, started, scheduler.skip)
            bar.show(len(scheduler.running))
            if not pending:
                break
            for handle, outcome in executor.wait(list(pending)):
                names = pending.pop(handle)
                scheduler.running.difference_update(names)
                _finish(scheduler, merged, names, outcome, bar)
    finally:
        executor.shutdown()
        write_state(directory, [], started, scheduler.skip)
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


def _finish(scheduler: Scheduler, merged: Curriculum, names: tuple[str, ...], outcome: Outcome | BaseException,
            bar: _Progress) -> None:
    """Record the outcome of the unit that trained the jobs ``names``: each result stored as it comes (the model
    file, then the manifest entry), or the unit's exception as the failure of each job."""
    directory = scheduler.directory
    if isinstance(outcome, BaseException):
        text = "".join(traceback.format_exception(outcome))
        for name in names:
            scheduler.failed[name] = text.strip().splitlines()[-1]
            atomic_write(directory / "failed" / f"{file_stem(name)}.txt", text)
            bar.note(f"job {name} failed: {scheduler.failed[name]}")
        return
    for result in outcome if isinstance(outcome, list) else [outcome]:
        name = result.spec.name
        node_name, _, seed_text = name.rpartition(SEED_SEPARATOR)
        earlier = scheduler.damaged.get(name)
        differs = earlier is not None and not _trained_alike(earlier, result.record)
        above = _above(scheduler, node_name) if differs else []
        if differs:  # what was trained with the damaged copy goes, even if the run dies after storing
            atomic_write(directory / PENDING_RETRAIN, json.dumps(
                {"repaired": name, "jobs": [job_name(n, seed) for n, seed in above]}, indent=1))
        _store(scheduler, result)
        scheduler.records[node_name][int(seed_text)] = result.record
        bar.running = len(scheduler.running)
        bar.finished(_rounded(scheduler.budget(merged.node(node_name))))
        if differs:
            for undone in _retrain_above(scheduler, above, name, bar.note):
                bar.undone(_rounded(scheduler.budget(merged.node(undone))))
            (directory / PENDING_RETRAIN).unlink()


def _rounded(timesteps: int) -> int:
    return -(-timesteps // STEPS_PER_UPDATE) * STEPS_PER_UPDATE


def _load_done(scheduler: Scheduler) -> dict[str, str]:
    """Read the finished jobs from the library manifest (the only record of what is done), each checked against its
    model file: a job whose file is missing or damaged is not done (it is trained again and replaces its entry).
    Returns those jobs, with what is wrong with each."""
    damaged: dict[str, str] = {}
    for name, (entry, problem) in library_jobs(scheduler.library).items():
        node_name, sep, seed_text = name.rpartition(SEED_SEPARATOR)
        if sep and node_name in scheduler.records and seed_text.isdigit() and entry.record is not None:
            if problem is None:
                scheduler.records[node_name][int(seed_text)] = entry.record
            elif name not in scheduler.skip:
                scheduler.damaged[name] = entry.record
                damaged[name] = problem
    return damaged


def _store(scheduler: Scheduler, result: JobResult) -> None:
    """Add a finished job to the library (replacing the entry of a damaged one)."""
    spec = result.spec
    entry = storage.entry_json(spec.name, result.algo, spec.frame_stack, spec, result.record)
    earlier = scheduler.damaged.pop(spec.name, None)
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


def _above(scheduler: Scheduler, node_name: str) -> list[tuple[str, int]]:
    """The finished (or damaged) jobs of every node above ``node_name``."""
    above = [n for n in scheduler.order if node_name in scheduler.below[n]]
    return [(n, seed) for n in above for seed in range(scheduler.seeds)
            if seed in scheduler.records[n] or job_name(n, seed) in scheduler.damaged]


def _retrain_above(scheduler: Scheduler, jobs: list[tuple[str, int]], name: str, note: Callable[[str], None]
                   ) -> list[str]:
    """A damaged job ``name`` trained again differs from its earlier record (another CPU or code): the finished jobs
    above its node (``jobs``, :func:`_above`) were trained with the earlier one and are taken out of the library to
    be trained again (:func:`replace_jobs`). Returns the node of each such job that counted as done."""
    if not jobs:
        return []
    line = replace_jobs(scheduler.directory, [job_name(n, seed) for n, seed in jobs])
    finished = [n for n, seed in jobs if scheduler.records[n].pop(seed, None) is not None]
    for n, seed in jobs:  # a damaged one is trained afresh too: its entry is gone
        scheduler.damaged.pop(job_name(n, seed), None)
    note(f"{name} trained again differs from its damaged copy's training (another CPU or code?); the SMCs above it "
         f"were trained with that copy:\n{line}")
    return finished


def _rows(scheduler: Scheduler) -> list[dict[str, Any]]:
    rows = []
    for node_name, seed in scheduler.jobs():
        record = scheduler.records[node_name].get(seed)
        if record is not None:
            rows.append({"node": node_name, "seed": seed, "selected_update": record.selected_update,
                         "training_return": record.selected_return, "wall_time_s": record.wall_time_s})
    return rows


# ---------------------------------------------------------------------------------------------------------------
# Progress
# ---------------------------------------------------------------------------------------------------------------

class _Progress:
    """One live line: jobs done / total, running, budget steps/s, ETA (``\\r``-refreshed on a terminal, else one line
    per round of finished jobs, once their places are refilled (:meth:`show`), so that it counts the jobs running
    then). A finished job counts its whole budget, also when its training stopped at the largest return, so that
    the rate and the jobs left are in the same units."""

    def __init__(self, total: int, done: int, steps_total: int, steps_done: int,
                 printer: Callable[[str], None] | None) -> None:
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
        return (f"jobs {self.done}/{self.total}, running {self.running}, {rate:,.0f} budget steps/s, "
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


