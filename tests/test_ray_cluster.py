"""The tests that start Ray (one module, so that a parallel test run keeps them on one worker): the same library on
Ray as in one process (``test_workers_groups_and_ray_give_the_same_library``), and a Ray node lost while it trains a
curriculum job (or a group of a flat node's seeds): on a local cluster of two nodes (loopback, one CPU each), the
node running a job is removed mid-run; the run goes on without that job, which fails with an error saying what
happened and what to do, and the same command run again trains it, once, keeping every finished job as it was.

The order of events is forced, not timed, so that a loaded machine (slow workers, slow node start and removal)
changes only how long the test takes: the job on the head waits (on a file) until the second node is gone, so the
other level-1 job can only run on the second node (the head's one CPU stays busy), the node is removed while it runs
and the head's job goes on after the loss; the flag files are written whole (renamed into place)."""

from __future__ import annotations

import collections
import json
import math
import os
import shutil
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest

from sb3_smc.curricula import jobs, trainer
from sb3_smc.curricula.executors import map_unordered
from sb3_smc.curricula.options import RunOptions
from sb3_smc.curricula.trainer import status, train_curriculum
from tests.test_curricula import _library_state, _tiny, assert_same_library

ray = pytest.importorskip("ray", reason="needs Ray (pip install 'sb3-smc[ray]')")
from ray.cluster_utils import Cluster  # noqa: E402 - only where Ray is installed

TINY = """\
curriculum: tiny
nodes:
  - name: left
    task: cl_self-in-left-corner_vs_on-hline
  - name: above
    task: ba_self-on-something_from_directly-above
  - name: container
    task: cl_self-in-container_vs_noncontainer
    uses: [left, above]
"""
NODE = {"node_ip_address": "127.0.0.1", "num_cpus": 1, "object_store_memory": 80 * 2**20}
WAIT_S = 120.0
"""The most a step of the test waits for the cluster (far more than it takes: a loaded machine is slow)."""


@pytest.fixture
def two_nodes(monkeypatch: pytest.MonkeyPatch) -> Iterator[tuple[Cluster, Any]]:
    """A head and a second node on this machine's loopback, each with one CPU, shut down whatever the test does.
    Ray's files (and the address file through which ``ray.init()`` finds a running cluster) go to a folder of the
    test's own, so that no other Ray session on the machine connects to this cluster; its workers run at this
    process's niceness (Ray's default, 15, starves them beside other work). Ray replaces an address of 127.0.0.1 with
    the machine's own, where nothing listens on a loopback cluster, unless this process runs Ray as on one machine
    (its ``ENABLE_RAY_CLUSTER`` off, which only turns off that replacement)."""
    folder = tempfile.mkdtemp(prefix="ray-", dir="/tmp")  # short: Ray's socket paths must stay under 108 bytes
    monkeypatch.setenv("RAY_TMPDIR", folder)
    monkeypatch.setenv("RAY_worker_niceness", "0")
    monkeypatch.delenv("RAY_ADDRESS", raising=False)
    monkeypatch.setattr("ray._private.ray_constants.ENABLE_RAY_CLUSTER", False)
    cluster = Cluster(initialize_head=True, head_node_args={**NODE, "include_dashboard": False})
    try:
        second = cluster.add_node(**NODE)
        cluster.wait_for_nodes(timeout=WAIT_S)
        yield cluster, second
    finally:
        ray.shutdown()
        cluster.shutdown()
        shutil.rmtree(folder, ignore_errors=True)


@pytest.mark.parametrize(("seeds", "group_size"), [(1, 1), (2, 5)], ids=["job", "group"])
def test_a_job_on_a_lost_node_fails_clearly_and_the_rerun_trains_it_once(tmp_path, monkeypatch, two_nodes, seeds,
                                                                        group_size):
    """One job at a time, or the seeds of a flat node as one group (one Ray task; lost together)."""
    cluster, second = two_nodes
    path = tmp_path / "tiny.yml"
    path.write_text(TINY)
    out = tmp_path / "run"
    lost_flag, gone_flag, trainings = tmp_path / "lost", tmp_path / "gone", tmp_path / "trainings.txt"
    doomed = second.node_id

    def write_whole(flag: Any, text: str) -> None:
        """``text`` into ``flag`` in one step (renamed into place): whoever sees the file sees all of it."""
        part = flag.with_name(flag.name + ".part")
        part.write_text(text)
        os.replace(part, flag)

    def on_the_cluster(train: Any, names: Callable[[Any], list[str]]) -> Any:
        """``train`` on the second node: say which jobs run there and wait to be removed with them; elsewhere: wait
        until the second node is gone (at once in the rerun), then train, counted. (A closure: Ray pickles it by value,
        with what it names.)"""
        def run(work: Any) -> Any:
            if ray.get_runtime_context().get_node_id() == doomed:
                write_whole(lost_flag, " ".join(names(work)))
                time.sleep(WAIT_S)
                raise RuntimeError("the test did not remove this node")
            deadline = time.monotonic() + 2 * WAIT_S
            while not gone_flag.is_file() and time.monotonic() < deadline:
                time.sleep(0.05)
            with trainings.open("a") as log:
                log.write("".join(f"{name}\n" for name in names(work)))
            return train(work)
        return run

    remover_errors: list[BaseException] = []

    def remove_the_second_node() -> None:
        """Once a job runs on the second node: remove the node and wait until the cluster no longer lists it (so that
        nothing is sent to it any more); then (or on giving up, or on an error) let the head's jobs go on."""
        try:
            deadline = time.monotonic() + WAIT_S
            while not lost_flag.is_file() and time.monotonic() < deadline:
                time.sleep(0.05)
            if lost_flag.is_file():
                cluster.remove_node(second)
                cluster.wait_for_nodes(timeout=WAIT_S)
        except BaseException as err:  # noqa: BLE001 - reported by the test
            remover_errors.append(err)
        finally:
            write_whole(gone_flag, "")

    monkeypatch.setattr(trainer, "run_job", on_the_cluster(jobs.run_job, lambda job: [job.spec.name]))
    monkeypatch.setattr(trainer, "run_group", on_the_cluster(jobs.run_group, lambda group: [j.spec.name
                                                                                           for j in group]))
    remover = threading.Thread(target=remove_the_second_node, daemon=True)
    remover.start()
    lines: list[str] = []
    settings = {"seeds": seeds, "timesteps": 2000, "workers": 2, "backend": "ray", "ray_address": cluster.address,
                "tensorboard": False, "group_size": group_size}
    try:
        first = train_curriculum(str(path), out, printer=lines.append, **settings)
    finally:
        remover.join(timeout=3 * WAIT_S)
    assert not remover_errors, f"removing the second node failed: {remover_errors[0]!r}"
    assert lost_flag.is_file(), "no job ran on the second node"
    lost = lost_flag.read_text().split()
    level_1 = [f"{node}@{seed}" for node in ("left", "above") for seed in range(seeds)]
    kept = [name for name in level_1 if name not in lost]  # the level-1 jobs trained on the head meanwhile
    # the lost jobs (one, or a node's seeds) fail with what happened and what to do (Ray's error kept in their
    # files); the run goes on
    assert sorted(first.failed) == sorted(lost) and len(lost) == seeds, (lost, first.failed, lines)
    assert {name.partition("@")[0] for name in lost} in ({"left"}, {"above"})
    for name in lost:
        assert first.failed[name].startswith("sb3_smc.errors.SMCRuntimeError: the Ray cluster lost this job before "
                                             "it finished (")
        assert "running the same command again trains it anew" in first.failed[name]
        text = (out / "failed" / f"{name}.txt").read_text()
        assert "ray.exceptions." in text and "The above exception was the direct cause" in text
    assert f"{seeds} job(s) failed" in lines[-1] and "run the same command again to retry" in lines[-1]
    containers = [f"container@{seed}" for seed in range(seeds)]
    state = status(out)
    assert (state["done"], sorted(state["failed"]), state["left"], state["running"]) == (
        kept, sorted(lost), containers, [])
    manifest = out / "library" / "manifest.json"
    before = json.loads(manifest.read_text())["smcs"]
    models = {name: out / "library" / before[name]["model"] for name in kept}
    stamps = {name: model.stat().st_mtime_ns for name, model in models.items()}

    # the same command again, on the node left: the lost jobs and those waiting for them are trained, nothing else
    lines.clear()
    again = train_curriculum(str(path), out, printer=lines.append, **settings)
    assert not again.failed and not any((out / "failed" / f"{name}.txt").exists() for name in lost)
    assert f"({len(kept)} already done)" in lines[0]
    after = json.loads(manifest.read_text())["smcs"]
    assert sorted(after) == sorted(level_1 + containers)  # each job once
    assert all(after[n] == before[n] and models[n].stat().st_mtime_ns == stamps[n] for n in kept)  # untouched
    assert collections.Counter(trainings.read_text().split()) == dict.fromkeys(level_1 + containers, 1)
    state = status(out)
    assert state["done"] == level_1 + containers and state["failed"] == state["left"] == []


def test_workers_groups_and_ray_give_the_same_library(tmp_path):
    """One job at a time, seeds in groups in this process, and groups on 2 workers and on Ray: the same SMCs
    (weights and records), and a progress line per round of finished jobs, counting SMCs."""
    path = _tiny(tmp_path)
    logs: dict[str, list[str]] = {"one": [], "grouped": [], "two": []}
    sequential = train_curriculum(str(path), tmp_path / "one", seeds=2, timesteps=2000, group_size=1,
                                  printer=logs["one"].append)
    grouped = train_curriculum(str(path), tmp_path / "grouped", seeds=2, timesteps=2000,
                               printer=logs["grouped"].append)
    parallel = train_curriculum(str(path), tmp_path / "two", seeds=2, timesteps=2000, workers=2,
                                printer=logs["two"].append)
    # a log line per round of finished jobs, counting the jobs running once the finished ones' places are refilled
    progress = {key: [line.split(",")[:2] for line in lines if line.startswith("jobs ")] for key, lines in logs.items()}
    # one worker: the next job is running when a line is written (the last line: none)
    assert progress["one"] == [[f"jobs {k}/6", " running 1"] for k in range(1, 6)] + [["jobs 6/6", " running 0"]]
    # groups: left@0-1 together, then above@0-1 (running 2: the group's SMCs), then container@0-1 (level 2 over
    # flat nodes: their calls in the group's one vector env)
    assert progress["grouped"] == [["jobs 2/6", " running 2"], ["jobs 4/6", " running 2"], ["jobs 6/6", " running 0"]]
    assert logs["grouped"][0].endswith("1 worker, seeds in groups of up to 5") and logs["one"][0].endswith(
        "1 worker")
    # two workers: left's and above's seeds, a group each, side by side
    assert progress["two"][0] in (["jobs 2/6", " running 2"], ["jobs 4/6", " running 2"])
    assert progress["two"][-1] == ["jobs 6/6", " running 0"]
    # Ray's workers run at niceness 15 unless told otherwise: beside other work they would crawl
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False, _system_config={"worker_niceness": 0})
    try:
        on_ray = train_curriculum(str(path), tmp_path / "ray", seeds=2, timesteps=2000, workers=2, backend="ray",
                                  progress=False)
        # other work (an experiment's evaluations) on the same cluster: every item's result, an item's error raised
        ray_options = RunOptions(workers=2, backend="ray")
        assert sorted(map_unordered(math.factorial, [3, 4, 5], ray_options)) == [(3, 6), (4, 24), (5, 120)]
        with pytest.raises(Exception, match="negative values"):
            list(map_unordered(math.factorial, [3, -1], ray_options))
    finally:
        ray.shutdown()
    expected = _library_state(sequential.library)
    assert len(expected) == 6
    for run in (grouped, parallel, on_ray):
        assert_same_library(_library_state(run.library), expected)
        assert sorted(p.name for p in (run.directory / "tensorboard").iterdir()) == sorted(
            p.name for p in (tmp_path / "one" / "tensorboard").iterdir())
