"""The run's scheduler (:class:`Scheduler`): which jobs of a curriculum run are done, ready, running, failed or
blocked, the units they run in (one job, or a group of a flat node's ready seeds), and each job's spec. Used by
:func:`~sb3_smc.curricula.trainer.train_curriculum`, which owns the run directory; nothing here writes."""

from __future__ import annotations

import shutil
from pathlib import Path

from sb3_smc.curricula.format import Curriculum, Node
from sb3_smc.curricula.jobs import Job, job_name, node_budget, node_of, node_spec, rank_seeds
from sb3_smc.curricula.run_directory import glob_escape
from sb3_smc.records import TrainingRecord

__all__ = ["Scheduler"]


class Scheduler:
    """Which jobs of a run are done, ready, running, failed or blocked, and the units they run in (a job, or a
    group of a flat node's seeds); the run's ``order`` of nodes, ``seeds`` per node, ``timesteps`` and the ``k`` best
    seeds of a used node that a job calls."""

    def __init__(self, curriculum: Curriculum, order: list[str], seeds: int, timesteps: int | None, k: int,
                 algo: str | None, directory: Path, rnn: str | None = None, skip: frozenset[str] = frozenset()
                 ) -> None:
        self.curriculum, self.order, self.seeds, self.timesteps, self.k = curriculum, order, seeds, timesteps, k
        self.algo, self.rnn, self.skip = algo, rnn, skip
        self.directory = directory
        self.library = directory / "library"
        self.records: dict[str, dict[int, TrainingRecord]] = {name: {} for name in order}
        self.best_of: dict[str, list[int]] = {}  # nodes reused with their best seeds only (curricula.reuse)
        self.running: set[str] = set()
        self.failed: dict[str, str] = {}
        self.damaged: dict[str, TrainingRecord] = {}  # finished jobs whose model file is damaged: their old records
        self.height = _heights(curriculum, order)
        self.below = {name: curriculum.closure([name]) - {name} for name in order}
        self._groupable: dict[str, bool] = {}

    def jobs(self) -> list[tuple[str, int]]:
        return [(node, seed) for node in self.order for seed in range(self.seeds)]

    def done(self, node: str, seed: int) -> bool:
        return seed in self.records[node] or job_name(node, seed) in self.skip

    def budget(self, node: Node) -> int:
        return node_budget(node, self.timesteps)

    def children(self, node: Node) -> tuple[str, ...]:
        names: list[str] = []
        for used in node.uses:
            best = self.best_of.get(used) or rank_seeds(self.records[used])[: min(self.k, self.seeds)]
            names.extend(job_name(used, seed) for seed in best)
        return tuple(names)

    def complete(self, node: str) -> bool:
        """Whether every job of ``node`` that others use is done: all its seeds, or its reused best seeds."""
        held = self.records[node]
        return len(held) == self.seeds or node in self.best_of and all(s in held for s in self.best_of[node])

    def ready(self) -> list[tuple[str, int]]:
        """The jobs that can start, those with the longest chain of nodes still above them first (then in
        ``order``): a deep curriculum's critical path starts at once, and top-level nodes (a flat baseline, say)
        fill idle workers. Which job runs when does not change what is trained. Nothing above a damaged job being
        trained again starts before it is done (it may be trained again itself when it is stored)."""
        repairing = {node_of(name) for name in self.damaged}
        out = []
        for node_name, seed in sorted(self.jobs(), key=lambda job: -self.height[job[0]]):
            name = job_name(node_name, seed)
            if self.done(node_name, seed) or name in self.running or name in self.failed:
                continue
            node = self.curriculum.node(node_name)
            if all(self.complete(u) for u in node.uses) and not self.below[node_name] & repairing:
                out.append((node_name, seed))
        return out

    def groupable(self, node_name: str) -> bool:
        """Whether the jobs of ``node_name`` train in groups: a flat node whose SMCs
        :func:`~sb3_smc.batched.train_smcs` trains in one vector env (for any other it would train them one after
        another in one worker: no faster, and fewer jobs in parallel)."""
        if node_name not in self._groupable:
            from sb3_smc.batched import batchable  # torch: once grouping is asked for

            node = self.curriculum.node(node_name)
            spec = node_spec(node, 0, (), timesteps=self.timesteps, algo=self.algo, rnn=self.rnn)
            self._groupable[node_name] = not node.uses and batchable(spec)
        return self._groupable[node_name]

    def units(self, ready: list[tuple[str, int]], group_size: int, workers: int) -> list[tuple[tuple[str, int], ...]]:
        """The ``ready`` jobs as units of execution, in ``ready``'s order: the ready seeds of a groupable node in
        groups of at most ``group_size``, as even as can be, any other job alone; while the units are fewer than
        ``workers``, the largest group is halved, so that a lone node's seeds (or a run's last ones) spread over
        the workers. What is trained does not depend on the units."""
        if group_size == 1:
            return [(job,) for job in ready]
        by_node: dict[str, list[tuple[str, int]]] = {}
        nodes: list[list[tuple[str, int]]] = []
        for job in ready:
            if not self.groupable(job[0]):
                nodes.append([job])
            elif job[0] in by_node:
                by_node[job[0]].append(job)
            else:
                nodes.append(by_node.setdefault(job[0], [job]))
        units = [part for jobs in nodes for part in _split(jobs, -(-len(jobs) // group_size))]
        while 0 < len(units) < workers:
            largest = max(range(len(units)), key=lambda i: len(units[i]))
            if len(units[largest]) == 1:
                break
            units[largest:largest + 1] = _split(units[largest], 2)
        return [tuple(unit) for unit in units]

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
            for stale in folder.glob(f"{glob_escape(name)}_*"):  # a half-finished earlier attempt
                shutil.rmtree(stale, ignore_errors=True)
            log = str(folder)
        return Job(spec=spec, library=str(self.library.absolute()), tensorboard_log=log)


def _split(jobs: list[tuple[str, int]], parts: int) -> list[list[tuple[str, int]]]:
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
