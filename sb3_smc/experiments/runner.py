"""``run_experiment``: curricula -> trained SMCs -> the paper's test protocol -> ``results.csv`` / ``results.json``.

1. Every SMC method's nodes (:func:`sb3_smc.experiments.design.plan`) are trained with every seed by the curriculum
   trainer into ``DIR`` (``DIR/library``; lower-level nodes once, shared by every method; resumable, parallel, Ray).
2. Every target x method x curriculum node x seed is evaluated on the test split with the paper's protocol
   (10 repeats, stochastic policy, the snapshot selected by training return): :func:`sb3_smc.evaluate`. Each
   evaluation is saved as ``DIR/evaluations/<node>@<seed>.json`` (``/`` in node names as ``%2F``; atomically)
   and not repeated by a later run. An SMC with a saved evaluation is not trained again either, even when
   ``DIR/library`` is gone, unless an SMC still to train needs it as a child: a run directory reduced to its
   records (``run.json``, ``evaluations/``, ``cnn/``: no model files) resumes with only the SMCs it still lacks and
   the lower-level nodes they need, retrained alike on the same kind of CPU (training is deterministic for a seed;
   other CPUs take other floating-point paths, ``docs/training.md``).
3. The CNN baseline (``cnn``) is trained and tested per classification target and seed
   (``DIR/cnn/<target>@<seed>.json``).
4. ``DIR/results.csv`` / ``results.json``: one row per target x method x curriculum x seed (training return,
   selected update, test score, wall time), and the reported score per target x method as the paper reports it:
   the best seed (for ``curr`` and ``curr-noprim`` also the best curriculum), and ``commits``: every commit the
   directory's SMCs were trained at, with the jobs trained at each, accumulated over its runs
   (:func:`record_commits`; ``copied``: the jobs copied from a ``--reuse-from`` library instead).
"""

from __future__ import annotations

import json
import os
import platform
import shlex
import subprocess
import time
from collections.abc import Callable, Collection, Mapping, Sequence
from functools import partial
from pathlib import Path
from typing import Any

from pixelworld_env.atomic import atomic_write
from pixelworld_env.datasets import catalog
from sb3_smc.common.threads import compute_threads
from sb3_smc.core.hyperparameters import DEFAULT_ALGORITHM, DEFAULT_TIMESTEPS
from sb3_smc.curricula.executors import map_unordered
from sb3_smc.curricula.jobs import DEFAULT_REUSE, DEFAULT_SEEDS, file_stem, job_name, name_of_file
from sb3_smc.curricula.options import BACKENDS, DEFAULT_GROUP_SIZE, RunOptions
from sb3_smc.curricula.run_directory import RunFileError, RunSettingsError, read_json
from sb3_smc.curricula.trainer import finished_jobs, train_curriculum
from sb3_smc.errors import SMCError, SMCRuntimeError
from sb3_smc.experiments.cnn import train_cnn
from sb3_smc.experiments.design import (
    DEFAULT_METHODS,
    DEFAULT_REPEATS,
    METHOD_REGISTRY,
    ExperimentPlan,
    level2_targets,
    plan,
)
from sb3_smc.experiments.tabular import csv_text
from sb3_smc.experiments.wall_clock import UNKNOWN_COMMIT, WallClock, lower_bound
from sb3_smc.learning.evaluation import MAX_REPEATS, evaluate
from sb3_smc.library import SMCLibrary, storage
from sb3_smc.records import package_versions

__all__ = ["RESULT_FIELDS", "evaluation_path", "read_evaluation", "read_results", "record_commits", "run_experiment"]

RESULT_FIELDS = ("target", "kind", "category", "method", "curriculum", "seed", "training_return", "selected_update",
                 "test_score", "wall_time_s")


def run_experiment(
    out: str | Path,
    *,
    methods: Sequence[str] = DEFAULT_METHODS,
    targets: Sequence[str] | None = None,
    category: str | None = None,
    seeds: int = DEFAULT_SEEDS,
    timesteps: int | None = None,
    repeats: int = DEFAULT_REPEATS,
    workers: int = 1,
    group_size: int = DEFAULT_GROUP_SIZE,
    backend: str = BACKENDS[0],
    ray_address: str | None = None,
    algo: str | None = None,
    rnn: str | None = None,
    lean_update: bool = False,
    train: bool = True,
    progress: bool = True,
    printer: Callable[[str], None] = print,
    reuse_from: str | Path | None = None,
    options: RunOptions | None = None,
) -> dict[str, Any]:
    """Run the paper's protocol (train, test, tabulate) into ``out``; resumable: run it again to continue.

    :param out: the experiment directory (new, or one of this experiment).
    :param methods: names of :data:`~sb3_smc.experiments.design.METHOD_REGISTRY` (default: the paper's six).
    :param targets: level-2 dataset names; give these or ``category``, not both.
    :param category: ``containment``, ``objcon``, ``objects``, ``search``, ``pushable`` or ``all`` (the default: the
        paper's 51 targets).
    :param seeds: seeds per node (the paper's 5).
    :param timesteps: the budget of every SMC (default: each node's own, else 400,000).
    :param repeats: test episodes per test environment and SMC (the paper's 10; at most
        :data:`~sb3_smc.learning.evaluation.MAX_REPEATS`).
    :param workers: jobs trained at once.
    :param group_size: the most seeds of a flat node trained together in one worker (1: every SMC alone); the
        results are the same whatever the grouping.
    :param backend: ``local`` (a process pool) or ``ray``.
    :param ray_address: the Ray cluster to connect to (with ``backend="ray"``; default: a local instance).
    :param algo: the learner of every SMC (default: RecurrentPPO; the paper's is RecurrentTRPO); a method with a
        learner of its own (``base-gru``) refuses it.
    :param rnn: the recurrent cell, ``lstm`` (default) or ``gru`` (the paper's); refused as ``algo`` is.
    :param lean_update: train every SMC with the lean update (:func:`train_curriculum`'s; equal up to float rounding,
        not bit for bit); every method's learner must be RecurrentPPO or RecurrentTRPO with one LSTM or GRU layer
        (checked before training).
    :param train: ``False`` trains nothing: it tabulates what the directory's run has finished so far (while it may
        still be training): the finished SMCs are evaluated (and the CNN trained), the rest are listed in
        ``missing`` and the results are marked ``"complete": false`` (the report says so).
    :param progress: print progress lines through ``printer``.
    :param printer: where progress lines go.
    :param reuse_from: a library whose SMCs the run copies instead of training them (:func:`train_curriculum`), such
        as the pretrained library: the results are the same.
    :param options: the run's options whole (:class:`~sb3_smc.curricula.options.RunOptions`), instead of the
        keywords ``seeds``, ``timesteps``, ``workers``, ``group_size``, ``backend``, ``ray_address``, ``algo``,
        ``rnn``, ``lean_update`` and ``reuse_from`` (which must then be left out); an experiment calls the two best
        seeds (its ``reuse`` is the default).
    :return: the ``results.json`` content.
    """
    if targets is not None and category is not None:
        raise SMCError("give targets or a category, not both")
    if isinstance(repeats, bool) or not isinstance(repeats, int) or repeats < 1:
        raise SMCError(f"repeats must be a positive integer, got {repeats!r}")
    if repeats > MAX_REPEATS:
        raise SMCError(f"repeats must be at most {MAX_REPEATS:,}, got {repeats:,}")
    options = RunOptions.of(options, seeds=seeds, timesteps=timesteps, workers=workers, group_size=group_size,
                            backend=backend, ray_address=ray_address, algo=algo, rnn=rnn, lean_update=lean_update,
                            reuse_from=reuse_from)
    if options.reuse != DEFAULT_REUSE:
        raise SMCError(f"an experiment's SMCs call the nodes they use with reuse {DEFAULT_REUSE!r} (the paper's), got "
                       f"{options.reuse!r}: train such a run with train_curriculum")
    own = [m for m in methods if m in METHOD_REGISTRY and METHOD_REGISTRY[m].own_learner]
    if own and (options.algo is not None or options.rnn is not None):
        raise SMCError(f"method {own[0]} has a learner of its own, which --algo / --rnn would replace: run it without "
                       "them (in a directory of its own), or run base with them")
    chosen = list(targets) if targets is not None else level2_targets(category or "all")
    design = plan(chosen, list(methods))
    directory = Path(out)
    if directory.exists() and not directory.is_dir():
        raise RunSettingsError(f"{directory} is a file, not an experiment directory: give a new directory or one of "
                               "this experiment")
    if progress and design.cnn_skipped:
        printer(f"cnn skipped for {len(design.cnn_skipped)} bring-about target(s) (it classifies only): "
                f"{', '.join(design.cnn_skipped)}")
    _previous_results(directory)  # its commits record checked before any work (read again at the end)
    commit = code_commit()
    with WallClock(directory, train=train, commit=commit) as clock:  # this run's wall time, kept as it goes
        held_before = _library_jobs(directory)
        kept = _kept_evaluations(directory, design.training_targets, options, repeats) \
            if design.curriculum is not None else {}
        finished: set[str] | None = None
        if design.curriculum is not None and not train:
            finished = set(kept) | finished_jobs(design.curriculum, directory, targets=design.training_targets,
                                                 options=options)
        elif design.curriculum is not None:
            run = train_curriculum(design.curriculum, directory, targets=design.training_targets, options=options,
                                   progress=progress, printer=printer, skip=set(kept))
            if run.failed:
                raise SMCRuntimeError(f"{len(run.failed)} training job(s) failed ("
                                      f"{', '.join(sorted(run.failed)[:5])}; tracebacks in {directory / 'failed'}): "
                                      "nothing evaluated; run the same command again to retry them")
        rows, missing = _tabulate(directory, design, options, repeats, kept, finished, progress, printer)
        new = _library_jobs(directory) - held_before if train else set()
        earlier = clock.earlier_commit()
    previous = _previous_results(directory)
    copied = (set(previous.get("copied") or ()) - new) | _copies(directory, new, options.reuse_from)
    evaluated = {job_name(r["curriculum"], r["seed"]) for r in rows if METHOD_REGISTRY[r["method"]].smc}
    commits = record_commits(previous.get("commits") or {}, (_library_jobs(directory) | evaluated) - copied,
                             new - copied, commit, earlier)
    settings = {"methods": list(methods), "targets": chosen, "seeds": options.seeds,
                "timesteps": options.timesteps or DEFAULT_TIMESTEPS, "repeats": repeats, "workers": options.workers,
                "backend": options.backend, "algo": options.algo or DEFAULT_ALGORITHM, "rnn": options.rnn or "lstm",
                **({"lean_update": True} if options.lean_update else {})}
    results = {
        "format": "sb3-smc-results", "version": 1,
        "settings": settings,
        "command": experiment_command(out, methods=methods, targets=targets,
                                      category=category or ("all" if targets is None else None), seeds=options.seeds,
                                      timesteps=options.timesteps, repeats=repeats, workers=options.workers,
                                      backend=options.backend, algo=options.algo, rnn=options.rnn,
                                      lean_update=options.lean_update, train=train),
        "machine": machine(),
        "code": {"versions": package_versions(), "commit": commit},
        "commits": commits,
        "copied": sorted(copied),
        **({"commits_note": previous["commits_note"]} if isinstance(previous.get("commits_note"), str) else {}),
        "wall_time_s": clock.entry["seconds"],
        "wall_time_total_s": clock.total(),
        "wall_time_lower_bound": lower_bound(directory),
        "complete": not missing,
        "missing": missing,
        "rows": rows,
        "reported": reported(rows),
    }
    atomic_write(directory / "results.json", json.dumps(results, indent=2) + "\n")
    atomic_write(directory / "results.csv", _csv(rows))
    if progress:
        printer(f"results: {directory / 'results.csv'} ({len(rows)} rows"
                + (f"; partial: {len(missing)} SMC(s) not trained yet)" if missing else ")"))
    return results


def record_commits(previous: Mapping[str, Sequence[str]], jobs: Collection[str], trained: Collection[str],
                   commit: str | None, earlier: str | None) -> dict[str, list[str]]:
    """``results.json``'s ``commits``: each commit the directory's SMC jobs were trained at -> those jobs (sorted;
    :data:`UNKNOWN_COMMIT` for the jobs whose commit its records cannot tell). ``previous``: what it recorded before
    (kept, so that the record accumulates over resumed runs); ``trained``: the jobs this run trained, at ``commit``
    (a job trained again moves there); ``jobs``: every job the directory holds now (library and evaluations), those
    not recorded yet being the last earlier training run's, at ``earlier`` (a run stopped before it wrote its
    results, or one training beside a ``--no-train`` run; its wall-time ledger entry), or of a commit unknown."""
    at = {job: key for key, names in previous.items() for job in names}
    for job in jobs:
        at.setdefault(job, earlier or UNKNOWN_COMMIT)
    for job in trained:
        at[job] = commit or UNKNOWN_COMMIT
    out: dict[str, list[str]] = {}
    for job, key in sorted(at.items()):
        out.setdefault(key, []).append(job)
    return out


def _library_jobs(directory: Path) -> set[str]:
    """The SMC jobs the directory's library holds (its manifest, checked; no model read)."""
    library = directory / "library"
    if not (library / storage.MANIFEST).is_file():
        return set()
    return set(storage.checked_entries(library)[0])


def _copies(directory: Path, jobs: set[str], reuse_from: Path | None) -> set[str]:
    """Of ``jobs``, new in the directory's library, those copied from the ``reuse_from`` library (the same model
    file): trained elsewhere, not by this run."""
    if reuse_from is None or not jobs:
        return set()
    source = storage.checked_entries(Path(reuse_from))[0]
    held = storage.checked_entries(directory / "library")[0]
    return {job for job in jobs if job in source and job in held and held[job].sha256 == source[job].sha256}


def _previous_results(directory: Path) -> dict[str, Any]:
    """The directory's ``results.json`` as an earlier run wrote it (empty without one, or a damaged one: it is
    written again); :class:`RunFileError` for one that cannot be read (not allowed, a folder in its place), which
    would be lost or fail the run's end."""
    path = directory / "results.json"
    try:
        previous = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        return {}
    except OSError as err:
        raise RunFileError(f"cannot read {path} ({err.strerror or err}): the results of earlier runs, which this "
                           "run adds to; make it readable (or move it away to start the results again)") from None
    except ValueError:
        return {}
    if not isinstance(previous, dict):
        return {}
    commits = previous.get("commits")
    if commits is not None and not (isinstance(commits, dict) and all(
            isinstance(names, list) and all(isinstance(n, str) for n in names) for names in commits.values())):
        raise RunFileError(f"{directory / 'results.json'}: 'commits' must map each commit to the job names trained "
                           f"at it, got {str(commits)[:200]}; restore it, or delete the key to count its jobs as of "
                           "a commit unknown")
    return previous


def _tabulate(directory: Path, design: ExperimentPlan, options: RunOptions, repeats: int,
              kept: dict[str, dict[str, Any]], finished: set[str] | None, progress: bool, printer: Callable[[str], None]
              ) -> tuple[list[dict[str, Any]], list[str]]:
    """Every target x method x curriculum x seed's row (its evaluation or CNN result: :func:`_results`) and the jobs
    still missing (those not ``finished``, when tabulating without training)."""
    results = _results(directory, design, options, repeats, kept, finished, progress, printer)
    rows: list[dict[str, Any]] = []
    missing: list[str] = []
    for (target, method), nodes in sorted(design.nodes.items()):
        info = catalog.dataset(target)
        if not METHOD_REGISTRY[method].smc:
            for seed in range(options.seeds):
                result = results[("cnn", target, seed)]
                rows.append(_row(target, info, method, "cnn", seed, None, None, result["test_score"],
                                 result["wall_time_s"]))
            continue
        for job in options.jobs(nodes):
            name = str(job)
            if finished is not None and name not in finished:
                missing.append(name)
                continue
            evaluation = results[("smc", name, 0)]
            rows.append(_row(target, info, method, job.node, job.seed, evaluation["training_return"],
                             evaluation["selected_update"], evaluation["test_score"], evaluation["wall_time_s"]))
    return rows, missing


Work = tuple[str, str, int]
"""What an experiment computes after training: ``("smc", job name, 0)`` an SMC's evaluation, ``("cnn", target,
seed)`` a CNN trained and tested."""


def _result_path(directory: Path, work: Work) -> Path:
    """Where the result of ``work`` is saved: ``evaluations/<node>@<seed>.json`` or ``cnn/<target>@<seed>.json``."""
    kind, name, seed = work
    return evaluation_path(directory, name) if kind == "smc" else directory / "cnn" / f"{name}@{seed}.json"


def _saved_result(directory: Path, work: Work, repeats: int, kept: dict[str, dict[str, Any]]) -> dict[str, Any] | None:
    """The saved result of ``work`` (an evaluation ``kept`` or saved with ``repeats``; a CNN's, checked), or None."""
    path = _result_path(directory, work)
    if work[0] == "smc":
        return kept.get(work[1]) or _saved_evaluation(path, repeats)
    if not path.is_file():
        return None
    saved = read_json(path, "a CNN result; delete it to train that CNN again")
    if not isinstance(saved, dict) or not isinstance(saved.get("test_score"), int | float):
        raise RunFileError(f"{path} is not a CNN result (no test_score); delete it to train that CNN again")
    return saved


def _results(directory: Path, design: ExperimentPlan, options: RunOptions, repeats: int,
             kept: dict[str, dict[str, Any]], finished: set[str] | None, progress: bool,
             printer: Callable[[str], None]) -> dict[Work, dict[str, Any]]:
    """Every evaluation and CNN result the table needs: those saved read (each once, every one checked before any
    work), the others computed on the run's workers (:func:`~sb3_smc.curricula.executors.map_unordered`: the run's
    backend) and saved as each finishes (the same results in any process: each is seeded on its own)."""
    found: dict[Work, dict[str, Any]] = {}
    work: list[Work] = []
    for (target, method), nodes in sorted(design.nodes.items()):
        items: list[Work] = [("cnn", target, seed) for seed in range(options.seeds)] \
            if not METHOD_REGISTRY[method].smc else \
            [("smc", str(job), 0) for job in options.jobs(nodes) if finished is None or str(job) in finished]
        for item in items:
            saved = _saved_result(directory, item, repeats, kept)
            if saved is None:
                work.append(item)
            else:
                found[item] = saved
    if progress and work:
        printer(f"evaluating {sum(w[0] == 'smc' for w in work)} SMC(s), training {sum(w[0] == 'cnn' for w in work)} "
                f"CNN(s), {options.workers} at a time")
    every = max(1, len(work) // 20)
    started = time.perf_counter()
    for done, (item, result) in enumerate(map_unordered(partial(_compute, directory, repeats), work, options), 1):
        atomic_write(_result_path(directory, item), json.dumps(result, indent=2) + "\n")
        found[item] = result
        if progress and (done % every == 0 or done == len(work)):
            left = (time.perf_counter() - started) / done * (len(work) - done)
            printer(f"evaluated {done}/{len(work)}" + (f", about {left / 60:.1f} min left" if done < len(work) else ""))
    return found


def _compute(directory: Path, repeats: int, work: Work) -> dict[str, Any]:
    """One item of :data:`Work`: the evaluation record of an SMC of the directory's library (tested on the test
    split with ``repeats``), or a CNN's result."""
    kind, name, seed = work
    if kind == "cnn":
        return train_cnn(name, seed).to_dict()
    smc = SMCLibrary.load(directory / "library", names=[name])[name]
    with compute_threads(1):
        result = evaluate(smc, repeats=repeats, seed=0, record_cells=False)
    record = smc.record
    return {"smc": name, "repeats": repeats, "test_score": result.score,
            "training_return": record.selected_return if record is not None else None,
            "selected_update": record.selected_update if record is not None else None,
            "wall_time_s": record.wall_time_s if record is not None else None,
            "spec": smc.spec.to_dict() if smc.spec is not None else None,
            "digest": smc.digest, "children_digests": [child.digest for child in smc.children],
            "evaluation": result.record.to_dict()}


def experiment_command(out: str | Path, *, methods: Sequence[str], targets: Sequence[str] | None = None,
                       category: str | None = None, seeds: int, timesteps: int | None = None,
                       repeats: int = DEFAULT_REPEATS, workers: int = 1, backend: str = BACKENDS[0],
                       algo: str | None = None, rnn: str | None = None, lean_update: bool = False,
                       train: bool = True) -> str:
    """The ``sb3-smc experiment`` command line of a run with these options (as given: ``None`` options are left
    out, as ``run.json`` records them), which runs it again or resumes it."""
    chosen = f"--category {category}" if category else f"--targets {','.join(targets or ())}"
    optional = "".join(f" --{name} {value}" for name, value in (("timesteps", timesteps), ("algo", algo),
                                                                  ("rnn", rnn)) if value is not None)
    return (f"sb3-smc experiment --out {shlex.quote(str(out))} --methods {','.join(methods)} {chosen} "
            f"--seeds {seeds}{optional} --repeats {repeats} --workers {workers} --backend {backend}"
            + (" --lean-update" if lean_update else "") + ("" if train else " --no-train"))


def cpu_model(cpuinfo: str | Path = "/proc/cpuinfo") -> str | None:
    """The CPU's model name from ``cpuinfo`` with its family and model numbers where it gives them (``"AMD
    EPYC (family 25, model 1)"``; None where there is no model name): training is deterministic for a seed on one CPU
    model, and other models take other floating-point paths. Two generations of a vendor's CPUs may share a name
    (two "AMD EPYC" machines trained different SMCs from the same seed and code), so the numbers are part of it."""
    fields: dict[str, str] = {}
    try:
        with open(cpuinfo, encoding="utf-8") as lines:
            for line in lines:
                if not line.strip():
                    break  # the first processor's block
                key, _, value = line.partition(":")
                fields.setdefault(key.strip(), value.strip())
    except OSError:
        return None
    name = fields.get("model name")
    if not name:
        return None
    numbers = [f"{label} {fields[key]}" for key, label in (("cpu family", "family"), ("model", "model"))
               if key in fields]
    return f"{name} ({', '.join(numbers)})" if numbers else name


def machine() -> dict[str, Any]:
    """What a result was measured on: platform, Python, the CPU model (:func:`cpu_model`, else the processor) and
    the number of cores."""
    return {"platform": platform.platform(), "python": platform.python_version(),
            "processor": cpu_model() or platform.processor() or platform.machine(), "cores": os.cpu_count()}


def code_commit() -> str | None:
    """The git commit of the sb3_smc code that runs (``None`` outside a git checkout), with ``+changes`` when its
    tracked files differ from that commit: what a resumed run's SMCs were trained with."""
    here = Path(__file__).resolve().parent
    try:
        commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=here, capture_output=True, text=True, timeout=10,
                                check=True).stdout.strip()
        changed = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=here,
                                 capture_output=True, text=True, timeout=10, check=True).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return None
    return commit + ("+changes" if changed else "") if commit else None


def _row(target: str, info: Any, method: str, curriculum: str, seed: int, training_return: float | None,
         selected_update: int | None, test_score: float, wall: float) -> dict[str, Any]:
    return {"target": target, "kind": info.kind, "category": info.category, "method": method,
            "curriculum": curriculum, "seed": seed, "training_return": training_return,
            "selected_update": selected_update, "test_score": test_score, "wall_time_s": wall}


def reported(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per target x method: the best test score over seeds and curricula (the paper's "best seed", and for curr
    the best of the 1-3 curricula), with the seed and curriculum it came from."""
    best: dict[tuple[str, str], dict[str, Any]] = {}
    for row in rows:
        key = (row["target"], row["method"])
        if key not in best or row["test_score"] > best[key]["test_score"]:
            best[key] = row
    return [{"target": t, "kind": r["kind"], "category": r["category"], "method": m, "test_score": r["test_score"],
             "seed": r["seed"], "curriculum": r["curriculum"]} for (t, m), r in sorted(best.items())]


def _csv(rows: Sequence[dict[str, Any]]) -> str:
    return csv_text(rows, RESULT_FIELDS)


def evaluation_path(directory: Path, name: str) -> Path:
    """Where an experiment in ``directory`` saves the evaluation of its SMC ``name`` (``node@seed``)."""
    return directory / "evaluations" / f"{file_stem(name)}.json"


def read_evaluation(path: Path) -> dict[str, Any]:
    """The SMC evaluation an experiment saved at ``path`` (its test score, training record and spec), checked."""
    if not path.is_file():
        raise SMCError(f"{path} not found: an SMC's evaluation (sb3-smc experiment writes it)")
    try:
        saved = json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as err:
        raise SMCError(f"{path} is not valid JSON ({err}); delete it to evaluate that SMC again") from None
    if not isinstance(saved, dict) or not isinstance(saved.get("test_score"), int | float):
        raise SMCError(f"{path} is not an sb3-smc evaluation (no test_score); delete it to evaluate that SMC again")
    return saved


def _saved_evaluation(path: Path, repeats: int) -> dict[str, Any] | None:
    """The evaluation saved at ``path`` if it used ``repeats`` (else None: it is made again)."""
    if not path.is_file():
        return None
    saved = read_evaluation(path)
    return saved if saved.get("repeats") == repeats else None


def _kept_evaluations(directory: Path, training_targets: Sequence[str], options: RunOptions, repeats: int
                      ) -> dict[str, dict[str, Any]]:
    """The saved evaluations with ``repeats`` of the results table's jobs, by job name: those jobs need no training
    (unless a job still to train uses their node)."""
    folder = directory / "evaluations"
    if not folder.is_dir():
        return {}
    wanted = {str(job) for job in options.jobs(training_targets)}
    saved = {name_of_file(p.stem): _saved_evaluation(p, repeats) for p in sorted(folder.glob("*.json"))
             if name_of_file(p.stem) in wanted}
    return {name: evaluation for name, evaluation in saved.items() if evaluation is not None}


def read_results(directory: str | Path) -> dict[str, Any]:
    """The ``results.json`` of an experiment directory (errors say which file and what to do)."""
    directory = Path(directory)
    path = directory / "results.json"
    quoted = shlex.quote(str(directory))
    if not path.is_file():
        if (directory / "run.json").is_file():
            raise FileNotFoundError(
                f"{path} not found: {directory} holds a curriculum run (run.json) but no experiment results. If "
                f"`sb3-smc experiment --out {quoted} ...` made it, run that command again (the same options) to "
                f"finish it; a run of `sb3-smc train` has no results to report (`sb3-smc status {quoted}` shows what "
                "it holds)")
        raise FileNotFoundError(f"{path} not found: run `sb3-smc experiment --out {quoted} ...` first")
    holds = ("the results of sb3-smc experiment; its command with the same options writes it again from the saved "
             "evaluations")
    results = read_json(path, holds)
    if not isinstance(results, dict) or not isinstance(results.get("rows"), list) \
            or not isinstance(results.get("reported"), list):
        raise RunFileError(f"{path} is not the results of an sb3-smc experiment: it should hold {holds}")
    return results
