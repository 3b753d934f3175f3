"""The files of a curriculum run directory, and what they say (:func:`status`)::

    DIR/run.json        the settings; re-running with other settings is refused (the differences are listed)
                        unless node changes are accepted (``accept_changes``)
    DIR/library/        an SMCLibrary: one SMC per finished job, with its spec and training record
    DIR/tensorboard/    SB3 and SMC curves, one run per job (``<node>@<seed>_1``)
    DIR/failed/         ``<job>.txt``: the traceback of a job that raised (retried by the next run; ``/`` as ``%2F``)
    DIR/state.json      the jobs running now and the coordinator's pid (for ``sb3-smc status``)
    DIR/replaced/       ``<time>-<random>/``: the library (and run.json) as it was before SMCs were replaced
    DIR/.lock           held by the coordinator while it runs (a second one on the same directory is refused)

:func:`run_settings` and :func:`read_settings` write and read ``run.json``, :class:`SettingsChanges` compares a run
with the one a directory holds, :func:`library_jobs` checks the library's model files, :func:`replace_jobs` moves
SMCs to ``replaced/`` to be trained again, :func:`write_state` writes ``state.json``.
"""

from __future__ import annotations

import json
import os
import shutil
import time
from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pixelworld_env.atomic import atomic_write, make_temporary_directory
from sb3_smc.curricula.format import Curriculum
from sb3_smc.curricula.jobs import JobId, job_name, name_of_file, node_of
from sb3_smc.curricula.options import MAX_SEEDS, RunOptions
from sb3_smc.errors import SMCError
from sb3_smc.library import storage
from sb3_smc.library.errors import CorruptModelError

__all__ = ["CHECKPOINTS", "PENDING_RETRAIN", "RUN_FORMAT", "RUN_VERSION", "RunFileError", "RunSettingsError",
           "SettingsChanges", "glob_escape", "library_jobs", "read_json", "read_settings", "replace_jobs",
           "run_settings", "status", "write_state"]

CHECKPOINTS = "checkpoints"
"""A run directory's folder of groups' trainings saved between two updates (resumed after a stop, removed when the run
is complete)."""
PENDING_RETRAIN = "retrain.json"
"""A run directory's note of the jobs to take out of the library after a repaired job trained differently, written
before the repaired job is stored and removed once they are out (a run that dies in between finishes it first)."""
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


def run_settings(curriculum: Curriculum, nodes: Sequence[str], targets: Sequence[str], options: RunOptions
                 ) -> dict[str, Any]:
    """What decides a run's SMCs (``DIR/run.json``): the ``nodes``, ``targets`` and the options that decide every
    job; backend and worker count do not (``rnn`` and ``lean_update`` are written only when given, so run directories
    from before these options resume)."""
    settings = {"format": RUN_FORMAT, "version": RUN_VERSION, "curriculum": curriculum.name,
                "targets": list(targets), "seeds": options.seeds, "timesteps": options.timesteps,
                "reuse": options.reuse, "algo": options.algo,
                "nodes": {name: curriculum.node(name).settings() for name in nodes}}
    if options.rnn is not None:
        settings["rnn"] = options.rnn
    if options.lean_update:
        settings["lean_update"] = True
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


def read_settings(directory: Path) -> dict[str, Any] | None:
    """The settings in ``directory/run.json``; ``None`` where ``directory`` holds no run yet (missing or empty).
    :class:`RunSettingsError` for a file, or a directory that holds other things; :class:`RunFileError` for a
    ``run.json`` that is not one."""
    if directory.exists() and not directory.is_dir():
        raise RunSettingsError(f"{directory} is a file, not a run directory: give a new directory or one of this run")
    path = directory / "run.json"
    if not path.is_file():
        if directory.is_dir() and any(p.name != ".lock" for p in directory.iterdir()):
            kept = " (a run kept as records resumes from its run.json and evaluations/: copy its run.json too)" \
                if (directory / "evaluations").is_dir() else ""
            raise RunSettingsError(f"{directory} is not empty and holds no run.json: not a curriculum run directory"
                                   + kept)
        return None
    settings = read_json(path, "the settings of a curriculum run (sb3-smc train writes it)")
    if not isinstance(settings, dict) or settings.get("format") != RUN_FORMAT \
            or not isinstance(settings.get("nodes"), dict) or "seeds" not in settings:
        raise RunFileError(f"{path} is not the settings of an sb3-smc run (a JSON object of format {RUN_FORMAT!r} "
                           "with its nodes and seeds)")
    seeds = settings["seeds"]
    if type(seeds) is not int or not 1 <= seeds <= MAX_SEEDS:  # bools are not counts
        raise RunFileError(f"{path}: seeds must be an integer in [1, {MAX_SEEDS:,}] (the seeds of every node), got "
                           f"{seeds!r}")
    return settings


_NODE_KEYS = ("targets", "nodes")
"""Settings that ``accept_changes`` takes; the others (the curriculum's name, seeds, timesteps, reuse, algo, rnn,
lean_update) decide every job, or which run the directory holds."""


@dataclass(frozen=True)
class SettingsChanges:
    """How a run's settings differ from those its directory holds."""

    differences: list[str]
    every_job: list[str]  # differing settings that decide every job
    changed: list[str]  # nodes of both, with other settings
    removed: list[str]  # nodes of the directory, not of this run
    retrained: list[str]  # nodes of both whose jobs are trained again: the changed ones and every node using one

    @classmethod
    def between(cls, old: dict[str, Any], new: dict[str, Any], curriculum: Curriculum) -> SettingsChanges:
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
        ``run.json`` is written): :func:`replace_jobs`."""
        library = directory / "library"
        names = [n for n in library_jobs(library) if node_of(n) in set(self.retrained)]
        lines = [f"accepting the changes in {directory}:", *(f"  {d}" for d in self.differences)]
        for name in self.retrained:
            why = "changed" if name in self.changed else "uses a changed node"
            lines.append(f"  node {name!r} is trained again ({why})")
        if self.removed:
            lines.append(f"  not in this run, kept in the library as they are: {', '.join(self.removed)}")
        if names:
            lines.append(replace_jobs(directory, names))
        if printer is not None:
            printer("\n".join(lines))


def replace_jobs(directory: Path, names: Sequence[str]) -> str:
    """Take the SMCs ``names`` out of the run's library, to be trained again; the library as it was, ``run.json``
    and their TensorBoard folders are kept in ``DIR/replaced/<time>-<random>/`` (nothing trained is lost). Returns
    a line saying so."""
    library = directory / "library"
    (directory / "replaced").mkdir(exist_ok=True)
    kept = make_temporary_directory(directory / "replaced", time.strftime("%Y%m%d-%H%M%S-"))
    shutil.copy2(directory / "run.json", kept / "run.json")
    storage.link_copy(library, kept / "library")
    for name in names:
        for folder in (directory / "tensorboard").glob(f"{glob_escape(name)}_*"):
            (kept / "tensorboard").mkdir(exist_ok=True)
            folder.rename(kept / "tensorboard" / folder.name)
    storage.remove_from_library(library, names)
    shown = ", ".join(names[:6]) + (", ..." if len(names) > 6 else "")
    return f"  {len(names)} trained SMC(s) to train again ({shown}); the library as it was: {kept / 'library'}"


def library_jobs(library: Path) -> dict[str, tuple[storage.LibraryEntry, str | None]]:
    """Every SMC of a run's library: its manifest entry, and what is wrong with its model file (``None``: nothing;
    :func:`sb3_smc.library.storage.check_model_file`)."""
    if not (library / storage.MANIFEST).is_file():
        return {}
    manifest, where = storage.read_manifest(library)
    out: dict[str, tuple[storage.LibraryEntry, str | None]] = {}
    for name, entry in storage.check_manifest(manifest, where).items():
        try:
            storage.check_model_file(library, name, entry)
            out[name] = (entry, None)
        except CorruptModelError as err:
            out[name] = (entry, str(err))
    return out


def glob_escape(text: str) -> str:
    return "".join(f"[{c}]" if c in "*?[" else c for c in text)


def write_state(directory: Path, running: Collection[JobId], started: float, skipped: Collection[JobId]) -> None:
    """``DIR/state.json``: the coordinator's pid, the jobs ``running`` and ``skipped`` (by name, sorted)."""
    atomic_write(directory / "state.json", json.dumps({"pid": os.getpid(), "running": sorted(map(str, running)),
                                                      "skipped": sorted(map(str, skipped)), "started": started,
                                                      "updated": time.time()}) + "\n")


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
    library = {name: problem for name, (_, problem) in library_jobs(directory / "library").items()}
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
