"""The run's scheduler (:class:`Scheduler`): which jobs of a curriculum run are done, ready, running, failed or
blocked, the units they run in (one job, or a group of a flat node's ready seeds), and each job's spec. Used by
:func:`~sb3_smc.curricula.trainer.train_curriculum`, which owns the run directory; nothing here writes. Jobs are
:class:`~sb3_smc.curricula.jobs.JobId` s; their names are made only for the specs (and the TensorBoard folders)."""

from __future__ import annotations

import shutil
from collections.abc import Sequence
from pathlib import Path

from pixelworld_env.atomic import path_inside
from sb3_smc.curricula.format import Curriculum, Node
from sb3_smc.curricula.jobs import Job, JobId, planned_children, rank_seeds
from sb3_smc.curricula.options import RunOptions
from sb3_smc.curricula.run_directory import CHECKPOINTS, glob_escape
from sb3_smc.records import TrainingRecord

__all__ = ["Scheduler"]


class Scheduler:
    """Which jobs of a run are done, ready, running, failed or blocked, and the units they run in (a job, or a
    group of a flat node's seeds).

    :param curriculum: the run's (merged) curriculum.
    :param order: the nodes to train, lower levels first.
    :param options: the run's options: ``seeds`` per node, each job's spec (``timesteps``, ``algo``, ``rnn``), the
        ``k`` best seeds of a used node that a job calls (``reuse``), TensorBoard logs.
    :param directory: the run directory (nothing here writes to it).
    :param skip: jobs not to train (done as far as the scheduler is concerned).
    """

    def __init__(self, curriculum: Curriculum, order: list[str], options: RunOptions, directory: Path,
                 skip: frozenset[JobId] = frozenset()) -> None:
        self.curriculum, self.order, self.options, self.skip = curriculum, order, options, skip
        self.directory = directory
        self.library = directory / "library"
        self.records: dict[str, dict[int, TrainingRecord]] = {name: {} for name in order}
        self.best_of: dict[str, list[int]] = {}  # nodes reused with their best seeds only (curricula.reuse)
        self.running: set[JobId] = set()
        self.failed: dict[JobId, str] = {}
        self.damaged: dict[JobId, TrainingRecord] = {}  # finished jobs whose model file is damaged: their old records
        self.height = _heights(curriculum, order)
        self.below = {name: curriculum.closure([name]) - {name} for name in order}
        self._groupable: dict[str, bool] = {}

    def jobs(self) -> list[JobId]:
        """Every job of the run: its nodes in order, each with every seed."""
        return self.options.jobs(self.order)

    def done(self, job: JobId) -> bool:
        """Whether ``job`` is trained (its record is known) or skipped."""
        return job.seed in self.records[job.node] or job in self.skip

    def children(self, node: Node) -> tuple[str, ...]:
        """The library names of the SMCs that a job of ``node`` calls: the ``k`` best seeds of each node it uses."""
        names: list[str] = []
        for used in node.uses:
            best = self.best_of.get(used) or rank_seeds(self.records[used])[: min(self.options.k, self.options.seeds)]
            names.extend(str(JobId(used, seed)) for seed in best)
        return tuple(names)

    def complete(self, node: str) -> bool:
        """Whether every job of ``node`` that others use is done: all its seeds, or its reused best seeds."""
        held = self.records[node]
        return len(held) == self.options.seeds or node in self.best_of and all(s in held for s in self.best_of[node])

    def ready(self) -> list[JobId]:
        """The jobs that can start, those with the longest chain of nodes still above them first (then in
        ``order``): a deep curriculum's critical path starts at once, and top-level nodes (a flat baseline, say)
        fill idle workers. Which job runs when does not change what is trained. Nothing above a damaged job being
        trained again starts before it is done (it may be trained again itself when it is stored)."""
        repairing = {job.node for job in self.damaged}
        out = []
        for job in sorted(self.jobs(), key=lambda job: -self.height[job.node]):
            if self.done(job) or job in self.running or job in self.failed:
                continue
            node = self.curriculum.node(job.node)
            if all(self.complete(u) for u in node.uses) and not self.below[job.node] & repairing:
                out.append(job)
        return out

    def groupable(self, node_name: str) -> bool:
        """Whether the jobs of ``node_name`` train in groups: a flat node, or a level-2 node whose children are flat
        (its seeds call the same children: compiled leaves), whose SMCs :func:`~sb3_smc.learning.batched.train_smcs`
        trains in one vector env (for any other it would train them one after another in one worker: no faster, and
        fewer jobs in parallel)."""
        if node_name not in self._groupable:
            from sb3_smc.learning.batched import batchable  # torch: once grouping is asked for

            node = self.curriculum.node(node_name)
            flat_children = all(not self.curriculum.node(used).uses for used in node.uses)
            spec = self.options.spec(node, 0, planned_children(node, self.options.k))
            self._groupable[node_name] = flat_children and batchable(spec)
        return self._groupable[node_name]

    def units(self, ready: list[JobId], group_size: int, workers: int) -> list[tuple[JobId, ...]]:
        """The ``ready`` jobs as units of execution, in ``ready``'s order: the ready seeds of a groupable node in
        groups of at most ``group_size``, as even as can be, any other job alone; while the units are fewer than
        ``workers``, the largest group is halved, so that a lone node's seeds (or a run's last ones) spread over
        the workers, unless its training is saved in the run's checkpoints (it goes on from there whole). What is
        trained does not depend on the units."""
        if group_size == 1:
            return [(job,) for job in ready]
        by_node: dict[str, list[JobId]] = {}
        nodes: list[list[JobId]] = []
        for job in ready:
            if not self.groupable(job.node):
                nodes.append([job])
            elif job.node in by_node:
                by_node[job.node].append(job)
            else:
                nodes.append(by_node.setdefault(job.node, [job]))
        units = [part for jobs in nodes for part in _split(jobs, -(-len(jobs) // group_size))]
        while 0 < len(units) < workers:
            halve = [i for i, unit in enumerate(units) if len(unit) > 1 and not self.saved(unit)]
            if not halve:
                break
            largest = max(halve, key=lambda i: len(units[i]))
            units[largest:largest + 1] = _split(units[largest], 2)
        return [tuple(unit) for unit in units]

    def saved(self, unit: Sequence[JobId]) -> bool:
        """Whether the group ``unit`` has a checkpoint in the run (halved, it would train from the start)."""
        from sb3_smc.learning.group_checkpoint import checkpoint_path  # torch: only where a group may be halved

        return checkpoint_path(self.directory / CHECKPOINTS, [str(job) for job in unit]).is_file()

    def blocked(self) -> list[JobId]:
        """Jobs that cannot run because a node they need has a failed job."""
        bad = {job.node for job in self.failed}
        return [job for job in self.jobs()
                if not self.done(job) and job not in self.failed and self.below[job.node] & bad]

    def job(self, job: JobId, *, resumed: bool = False) -> Job:
        """What a worker trains for ``job``: its spec (calling the best seeds of the nodes it uses) and where its
        TensorBoard curves go (an earlier attempt's removed, unless the job's group is ``resumed`` from its
        checkpoint: :meth:`saved`)."""
        node = self.curriculum.node(job.node)
        spec = self.options.spec(node, job.seed, self.children(node))
        name = spec.name
        log = None
        if self.options.tensorboard:
            folder = self.directory / "tensorboard"
            path_inside(self.directory, "tensorboard", f"{name}_1")  # one folder inside DIR/tensorboard, no link
            if not resumed:
                for stale in folder.glob(f"{glob_escape(name)}_*"):  # a half-finished earlier attempt
                    shutil.rmtree(path_inside(self.directory, "tensorboard", stale.name), ignore_errors=True)
            log = str(folder)
        return Job(spec=spec, library=str(self.library.absolute()), tensorboard_log=log,
                   lean_update=self.options.lean_update, checkpoints=str((self.directory / CHECKPOINTS).absolute()))


def _split(jobs: list[JobId], parts: int) -> list[list[JobId]]:
    """``jobs`` in ``parts`` consecutive runs as even as can be, the longer ones first."""
    size, extra = divmod(len(jobs), parts)
    bounds = [0]
    for i in range(parts):
        bounds.append(bounds[-1] + size + (i < extra))
    return [jobs[a:b] for a, b in zip(bounds[:-1], bounds[1:], strict=True)]


def _heights(curriculum: Curriculum, order: list[str]) -> dict[str, int]:
    """For each node of ``order`` (lower levels first), the length of the longest chain of nodes of ``order`` that
    use it, directly or not (0 for a node nothing in the run uses)."""
    height = dict.fromkeys(order, 0)
    for name in reversed(order):
        for used in curriculum.node(name).uses:
            if used in height:
                height[used] = max(height[used], height[name] + 1)
    return height
