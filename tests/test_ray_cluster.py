"""A Ray node lost while it trains a curriculum job: on a local cluster of two nodes (loopback, one CPU each), the
node running a job is removed mid-run; the run goes on without that job, which fails with an error saying what
happened and what to do, and the same command run again trains it, once, keeping every finished job as it was."""

from __future__ import annotations

import collections
import json
import shutil
import tempfile
import threading
import time
from collections.abc import Iterator
from typing import Any

import pytest

from sb3_smc.curricula import jobs, trainer
from sb3_smc.curricula.trainer import status, train_curriculum

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
    test's own, so that no other Ray session on the machine connects to this cluster. Ray replaces an address of
    127.0.0.1 with the machine's own, where nothing listens on a loopback cluster, unless this process runs Ray as
    on one machine (its ``ENABLE_RAY_CLUSTER`` off, which only turns off that replacement)."""
    folder = tempfile.mkdtemp(prefix="ray-", dir="/tmp")  # short: Ray's socket paths must stay under 108 bytes
    monkeypatch.setenv("RAY_TMPDIR", folder)
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


def test_a_job_on_a_lost_node_fails_clearly_and_the_rerun_trains_it_once(tmp_path, monkeypatch, two_nodes):
    cluster, second = two_nodes
    path = tmp_path / "tiny.yml"
    path.write_text(TINY)
    out = tmp_path / "run"
    lost_flag, trainings = tmp_path / "lost", tmp_path / "trainings.txt"
    doomed, train = second.node_id, jobs.run_job

    def run_job(job: jobs.Job) -> jobs.JobResult:
        """On the second node: say which job runs there and wait to be removed with it; elsewhere: train, counted.
        (A closure: Ray pickles it by value, with what it names.)"""
        if ray.get_runtime_context().get_node_id() == doomed:
            lost_flag.write_text(job.spec.name)
            time.sleep(WAIT_S)
            raise RuntimeError("the test did not remove this node")
        with trainings.open("a") as log:
            log.write(job.spec.name + "\n")
        return train(job)

    def remove_the_second_node() -> None:
        deadline = time.monotonic() + WAIT_S
        while not lost_flag.is_file() and time.monotonic() < deadline:
            time.sleep(0.05)
        if lost_flag.is_file():
            cluster.remove_node(second)

    monkeypatch.setattr(trainer, "run_job", run_job)
    remover = threading.Thread(target=remove_the_second_node, daemon=True)
    remover.start()
    lines: list[str] = []
    settings = {"seeds": 1, "timesteps": 2000, "workers": 2, "backend": "ray", "ray_address": cluster.address,
                "tensorboard": False}
    first = train_curriculum(str(path), out, printer=lines.append, **settings)
    remover.join()
    assert lost_flag.is_file(), "no job ran on the second node"
    lost = lost_flag.read_text()
    kept = ({"left@0", "above@0"} - {lost}).pop()  # the level-1 job trained on the head meanwhile
    # the lost job fails with what happened and what to do (Ray's error kept in its file); the run goes on
    assert set(first.failed) == {lost}
    assert first.failed[lost].startswith("sb3_smc.errors.SMCRuntimeError: the Ray cluster lost this job before it "
                                         "finished (")
    assert "running the same command again trains it anew" in first.failed[lost]
    text = (out / "failed" / f"{lost}.txt").read_text()
    assert "ray.exceptions." in text and "The above exception was the direct cause" in text
    assert "1 job(s) failed" in lines[-1] and "run the same command again to retry" in lines[-1]
    state = status(out)
    assert (state["done"], state["failed"], state["left"], state["running"]) == ([kept], [lost], ["container@0"], [])
    manifest = out / "library" / "manifest.json"
    before = json.loads(manifest.read_text())["smcs"]
    model = out / "library" / before[kept]["model"]
    stamp = model.stat().st_mtime_ns

    # the same command again, on the node left: the lost job and the one waiting for it are trained, nothing else
    lines.clear()
    again = train_curriculum(str(path), out, printer=lines.append, **settings)
    assert not again.failed and not (out / "failed" / f"{lost}.txt").exists()
    assert "(1 already done)" in lines[0]
    after = json.loads(manifest.read_text())["smcs"]
    assert sorted(after) == ["above@0", "container@0", "left@0"]  # each job once
    assert after[kept] == before[kept] and model.stat().st_mtime_ns == stamp  # the finished job untouched
    assert collections.Counter(trainings.read_text().split()) == {"left@0": 1, "above@0": 1, "container@0": 1}
    state = status(out)
    assert state["done"] == ["left@0", "above@0", "container@0"] and state["failed"] == state["left"] == []
