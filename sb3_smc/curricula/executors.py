"""Where a curriculum run's jobs train: in this process, in local worker processes, or as Ray tasks.

Each executor takes the functions that train a job (:func:`~sb3_smc.curricula.jobs.run_job`) and a group of jobs
(:func:`~sb3_smc.curricula.jobs.run_group`) and offers ``submit(work) -> handle`` (``work``: a :class:`Job`, or a
tuple of jobs trained as one unit, one worker process or one Ray task), ``wait(handles) -> [(handle, outcome)]``
(at least one; the outcome is a job's :class:`JobResult`, a group's list of them, or the exception) and
``shutdown()``; :func:`make_executor` picks the one of a run's options. An exception is the outcome of the whole
unit, reported as the failure of each of its jobs by the trainer. :func:`map_unordered` runs any other independent
work on the same backend and workers (an experiment's evaluations and CNNs).
"""

from __future__ import annotations

import multiprocessing
import os
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, as_completed, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Any, TypeVar

from sb3_smc.curricula.jobs import Job, JobResult
from sb3_smc.curricula.options import BACKENDS, RunOptions
from sb3_smc.errors import SMCRuntimeError

__all__ = ["BACKENDS", "Outcome", "Work", "make_executor", "map_unordered"]

Work = Job | tuple[Job, ...]
"""What is submitted: one job, or a group of jobs trained together."""
Outcome = JobResult | list[JobResult]
RunJob = Callable[[Job], JobResult]
RunGroup = Callable[[Sequence[Job]], list[JobResult]]


class _InProcess:
    """Trains a job in this process when it is waited for (as a worker would meanwhile), so the state file and the
    progress line count it as running while it trains."""

    def __init__(self, run: RunJob, run_group: RunGroup) -> None:
        self._run, self._run_group = run, run_group
        self._work: dict[int, Work] = {}
        self._next = 0

    def submit(self, work: Work) -> int:
        handle = self._next
        self._next += 1
        self._work[handle] = work
        return handle

    def wait(self, handles: list[int]) -> list[tuple[int, Outcome | Exception]]:
        handle = handles[0]
        work = self._work.pop(handle)
        try:
            return [(handle, self._run(work) if isinstance(work, Job) else self._run_group(work))]
        except Exception as err:  # noqa: BLE001 - reported as the job's failure
            return [(handle, err)]

    def shutdown(self, now: bool = False) -> None:
        self._work.clear()


def _exit_with(parent: int) -> None:
    """A worker's initializer: end the worker (within a second) once ``parent``, the run's process, is gone: a
    killed run leaves no worker training on for nothing."""
    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(1.0)
        os._exit(1)

    threading.Thread(target=watch, name="exit-with-run", daemon=True).start()


def _process_pool(workers: int) -> ProcessPoolExecutor:
    """``workers`` spawned processes, each ending once this process is gone."""
    return ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"),
                               initializer=_exit_with, initargs=(os.getpid(),))


class _Processes:
    """Trains jobs in ``workers`` spawned processes; a worker that dies fails its jobs, and the pool is made
    again. A worker ends when the run's process does, however it ended."""

    def __init__(self, run: RunJob, run_group: RunGroup, workers: int) -> None:
        self._run, self._run_group = run, run_group
        self._make = lambda: _process_pool(workers)
        self._pool = self._make()

    def submit(self, work: Work) -> Future[Outcome]:
        if isinstance(work, Job):
            return self._pool.submit(self._run, work)
        return self._pool.submit(self._run_group, work)

    def wait(self, handles: list[Future[Outcome]]) -> list[tuple[Future[Outcome], Outcome | BaseException]]:
        done, _ = wait(handles, return_when=FIRST_COMPLETED)
        out: list[tuple[Future[Outcome], Outcome | BaseException]] = []
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
        if broken:  # a worker died (e.g. killed for memory): its jobs (all of a group) fail, the run goes on
            self._pool.shutdown(wait=False, cancel_futures=True)
            self._pool = self._make()
        return out

    def shutdown(self, now: bool = False) -> None:
        """Wait for the workers to end; ``now`` (the run stopped with jobs still training: interrupted, terminated or
        failed): end them first, their jobs lost (a resumed run trains them again). Either way the pool's queues are
        closed here, so that no semaphore is left to the resource tracker."""
        if now:
            for worker in list((getattr(self._pool, "_processes", None) or {}).values()):  # no public way in 3.11
                worker.terminate()
        self._pool.shutdown(wait=True, cancel_futures=True)


def _lost(error: Exception, ray: Any) -> Exception:
    """``error`` of a Ray task as the job's outcome: an error of Ray's for a task the cluster lost (its node or worker
    process died, or its result with its node) as one saying so and what to do, with Ray's as its cause; any other
    (the job's own exception) as it is."""
    known = ray.exceptions
    if not isinstance(error, (known.NodeDiedError, known.WorkerCrashedError, known.OutOfMemoryError,
                              known.LocalRayletDiedError, known.ObjectLostError)):
        return error
    lost = SMCRuntimeError(
        f"the Ray cluster lost this job before it finished ({type(error).__name__}: the node or worker process "
        "training it died, e.g. a node removed, preempted or out of memory, or its result was lost with its node); "
        "the other jobs go on, and running the same command again trains it anew, keeping every finished job")
    lost.__cause__ = error
    return lost


def _ray_session(address: str | None) -> Any:
    """The ``ray`` module, connected to the cluster at ``address`` (else ``$RAY_ADDRESS``) unless it is already."""
    try:
        import ray
    except ImportError:
        raise SMCRuntimeError("backend='ray' needs Ray: pip install 'sb3-smc[ray]'") from None
    if not ray.is_initialized():
        address = address or os.environ.get("RAY_ADDRESS")
        if address is None:
            raise SMCRuntimeError("backend='ray' runs on an existing Ray cluster: pass ray_address (--ray-address) "
                                  "or set RAY_ADDRESS (e.g. 'auto' on a node of the cluster, or ray://host:10001)")
        ray.init(address=address, log_to_driver=False)
    return ray


class _Ray:
    """Trains jobs as tasks of an existing Ray cluster (one CPU each, a group of jobs one task; no retries: a job the
    cluster loses fails, and the next run trains it, as a job whose local worker died)."""

    def __init__(self, run: RunJob, run_group: RunGroup, address: str | None) -> None:
        self._ray = ray = _ray_session(address)
        self._remote = ray.remote(num_cpus=1, max_retries=0)(run)
        self._remote_group = ray.remote(num_cpus=1, max_retries=0)(run_group)
        self._pending: set[Any] = set()

    def submit(self, work: Work) -> Any:
        ref = self._remote.remote(work) if isinstance(work, Job) else self._remote_group.remote(work)
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
                out.append((ref, _lost(err, self._ray)))
        return out

    def shutdown(self, now: bool = False) -> None:
        for ref in self._pending:  # after an interrupt or an error: free the cluster
            self._ray.cancel(ref)
        self._pending.clear()


def make_executor(options: RunOptions, run: RunJob, run_group: RunGroup) -> _InProcess | _Processes | _Ray:
    """The executor of a run's ``options.backend`` (``options.workers`` local processes, or this process for one
    worker; Ray tasks on the cluster at ``options.ray_address``), training each job with ``run`` and each group of
    jobs with ``run_group``."""
    if options.backend == "ray":
        return _Ray(run, run_group, options.ray_address)
    return _Processes(run, run_group, options.workers) if options.workers > 1 else _InProcess(run, run_group)


Item = TypeVar("Item")
Result = TypeVar("Result")


def _call(function: Callable[[Item], Result], item: Item) -> Result:
    """``function(item)``: a Ray task (Ray's tasks are functions; ``function`` may be a ``functools.partial``)."""
    return function(item)


def map_unordered(function: Callable[[Item], Result], items: Sequence[Item], options: RunOptions
                  ) -> Iterator[tuple[Item, Result]]:
    """``(item, function(item))`` for each of ``items``, as each finishes, on ``options``' backend: in this process in
    order for one local worker, else ``options.workers`` spawned processes, or Ray tasks of one CPU each. ``function``
    must be importable by a worker (a module's function, or a ``functools.partial`` of one). The first exception of
    an item is raised here, the items not started cancelled; those yielded before it stay done."""
    if not items:
        return
    if options.backend == "ray":
        ray = _ray_session(options.ray_address)
        remote = ray.remote(num_cpus=1, max_retries=0)(_call)
        pending = {remote.remote(function, item): item for item in items}
        try:
            while pending:
                ready, _ = ray.wait(list(pending), num_returns=1)
                for ref in ready:
                    item = pending.pop(ref)
                    try:
                        result = ray.get(ref)
                    except Exception as err:  # noqa: BLE001 - a task the cluster lost says so
                        lost = _lost(err, ray)
                        if lost is err:
                            raise
                        raise lost from err
                    yield item, result
        finally:
            for ref in pending:
                ray.cancel(ref)
        return
    if options.workers == 1:
        for item in items:
            yield item, function(item)
        return
    pool = _process_pool(min(options.workers, len(items)))
    try:
        futures = {pool.submit(function, item): item for item in items}
        for future in as_completed(futures):
            yield futures[future], future.result()
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
