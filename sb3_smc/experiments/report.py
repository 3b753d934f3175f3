"""``write_report``: ``report.md`` and ``figures/*.png`` from the ``results.json`` of one experiment directory, or of
several at once (the paper's whole table, run as one directory per category).

The report puts the paper's numbers (:mod:`sb3_smc.experiments.paper`) beside ours: per concept (best seed,
and mean ± s.d. over seeds) where the paper gives them, per kind and category (mean ± standard error across
concepts) for every method that ran, the paired t-tests across concepts (also read at the paper's degrees of
freedom), how often a hierarchical SMC beats the flat one, the same means and tests from each concept's mean over
its seeds, a claims table of every quantitative claim of the paper, the noprim table when those methods ran, and the
settings, machine, wall time and command of every directory. Figures (matplotlib, headless): Fig. 5a/5d category
means and Fig. 5b/5e every concept in panels by kind and category. The sections of numbers:
:mod:`sb3_smc.experiments.tables`; the statistics: :mod:`sb3_smc.experiments.statistics`.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from pixelworld_env.atomic import atomic_write
from sb3_smc.core.hyperparameters import ALGORITHM_REGISTRY
from sb3_smc.curricula.designed import designed_curricula
from sb3_smc.curricula.jobs import job_name, node_of
from sb3_smc.errors import SMCError
from sb3_smc.experiments.design import CATEGORIES, METHOD_REGISTRY, METHODS, SMC_METHODS, plan
from sb3_smc.experiments.experience import EXPERIENCE_FILE, Experience, Experiences
from sb3_smc.experiments.figures import Panel, bar_panels, timeline_figure, trajectory_figure
from sb3_smc.experiments.runner import evaluation_path, experiment_command, read_evaluation, read_results
from sb3_smc.experiments.tables import KINDS, ResultTable, number_sections
from sb3_smc.experiments.wall_clock import UNKNOWN_COMMIT, lower_bound
from sb3_smc.library import SMCLibrary, storage
from sb3_smc.smc.smc import SMC

__all__ = ["pushable_levels", "read_table", "write_report"]


def write_report(directories: str | Path | Sequence[str | Path], *, out: str | Path | None = None,
                 trajectories: str | None = None, behaviour: bool = True,
                 reruns: Sequence[str | Path] = ()) -> list[Path]:
    """Write ``report.md`` and ``figures/`` for experiment directories (every directory is read and checked before
    anything is written).

    :param directories: one experiment directory or several.
    :param out: one report over all of them into this folder (default: a report in each directory).
    :param trajectories: the target whose behaviour is drawn (default: the first one).
    :param behaviour: also draw the Fig. 4 trajectories of the best SMC of each method and the Fig. 1 timeline of
        the best hierarchical SMC (they need the directories' libraries).
    :param reruns: those of ``directories`` that ran some target x method pairs of the others again: theirs replace
        the others' (:func:`read_table`; one report over all, ``out``).
    :return: the report paths.
    """
    items = [Path(directories)] if isinstance(directories, str | Path) else [Path(d) for d in directories]
    if not items:
        raise SMCError("no experiment directories to report on")
    sources = [(d, read_results(d)) for d in items]  # every directory read before anything is written
    if out is None:
        if reruns:
            raise SMCError("reruns replace another directory's pairs in one report over all of them: give --out")
        return [_write([source], source[0], trajectories, behaviour) for source in sources]
    sources, replaced = _replaced(sources, reruns)
    return [_write(sources, Path(out), trajectories, behaviour, replaced)]


Replaced = dict[Path, dict[Path, list[tuple[str, str]]]]
"""Of each directory, the target x method pairs a rerun replaced there, by rerun."""


def _replaced(sources: Sequence[tuple[Path, dict[str, Any]]], reruns: Sequence[str | Path]
              ) -> tuple[list[tuple[Path, dict[str, Any]]], Replaced]:
    """``sources`` without the rows and reported scores of the pairs a rerun ran again, and which those were. A rerun
    not among the directories, a pair that two reruns ran, or a partial directory with pairs replaced is refused."""
    chosen = [Path(r) for r in reruns]
    directories = [d for d, _ in sources]
    for rerun in chosen:
        if rerun not in directories:
            raise SMCError(f"the rerun {rerun} is not one of the directories reported on: "
                           + ", ".join(map(str, directories)))
    owner: dict[tuple[str, str], Path] = {}
    for directory, results in sources:
        if directory in chosen:
            for entry in results["reported"]:
                key = (entry["target"], entry["method"])
                if key in owner and owner[key] != directory:
                    raise SMCError(f"{key[0]} with {key[1]} is in two reruns, {owner[key]} and {directory}: keep one")
                owner[key] = directory
    out: list[tuple[Path, dict[str, Any]]] = []
    replaced: Replaced = {}
    for directory, results in sources:
        if directory in chosen:
            out.append((directory, results))
            continue
        gone = {(e["target"], e["method"]) for e in results["reported"] if (e["target"], e["method"]) in owner}
        for key in sorted(gone):
            replaced.setdefault(directory, {}).setdefault(owner[key], []).append(key)
        if gone and results.get("missing"):
            raise SMCError(f"{directory / 'results.json'} is partial: a rerun replaces pairs of complete directories "
                           "only (report it when its run is complete)")
        kept = {**results,
                "rows": [r for r in results["rows"] if (r["target"], r["method"]) not in gone],
                "reported": [e for e in results["reported"] if (e["target"], e["method"]) not in gone]}
        out.append((directory, kept))
    return out, replaced


def _merge(sources: Sequence[tuple[Path, dict[str, Any]]]) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """The rows and reported scores of several directories; a target x method in two of them is refused."""
    rows: list[dict[str, Any]] = []
    reported: list[dict[str, Any]] = []
    seen: dict[tuple[str, str], Path] = {}
    for directory, results in sources:
        for entry in results["reported"]:
            key = (entry["target"], entry["method"])
            if key in seen:
                raise SMCError(f"{key[0]} with {key[1]} is in both {seen[key]} and {directory}: report them "
                               "separately, or keep one")
            seen[key] = directory
        rows += results["rows"]
        reported += results["reported"]
    return rows, reported


def _unfinished(sources: Sequence[tuple[Path, dict[str, Any]]]) -> set[tuple[str, str]]:
    """The target x method pairs with SMCs not trained yet in a partial tabulation (``missing``), found through the
    directory's plan; a missing SMC no pair of the plan trains is refused."""
    pairs: set[tuple[str, str]] = set()
    for directory, results in sources:
        missing = results.get("missing") or []
        if not missing:
            continue
        settings = results["settings"]
        design = plan(settings["targets"], settings["methods"])
        pair_of = {node: key for key, nodes in design.nodes.items() for node in nodes}
        for name in missing:
            if node_of(name) not in pair_of:
                raise SMCError(f"{directory / 'results.json'}: the untrained SMC {name!r} of 'missing' belongs to no "
                               "target x method of the run's plan (its curricula changed since): tabulate the run "
                               "again (sb3-smc experiment --no-train) with the code that runs it")
            pairs.add(pair_of[node_of(name)])
    return pairs


def _behaviour(sources: Sequence[tuple[Path, dict[str, Any]]], figures: Path, target: str
               ) -> tuple[list[Path], str | None]:
    """The Fig. 4 / Fig. 1 pictures of the best SMCs of ``target``, each loaded from the directory that trained it,
    into ``figures``; or none and the reason, when a run directory does not hold their models (a run kept as
    records: ``docs/experiments.md``)."""
    best = {r["method"]: (directory, job_name(r["curriculum"], r["seed"])) for directory, results in sources
            for r in results["reported"] if r["target"] == target and r["method"] in SMC_METHODS}
    if not best:
        return [], None
    loaded: dict[str, SMC] = {}
    for directory in dict.fromkeys(d for d, _ in best.values()):
        names = sorted({name for d, name in best.values() if d == directory})
        library_dir = directory / "library"
        held = set(storage.read_manifest(library_dir)[0]["smcs"]) if (library_dir / storage.MANIFEST).is_file() \
            else set()
        absent = [name for name in names if name not in held]
        if absent:
            return [], (f"The trajectory and timeline pictures of `{target}` need the models of its best SMCs; "
                        f"{directory} does not hold {', '.join(f'`{n}`' for n in absent)} (trained in an earlier "
                        "session of a run kept as records). Delete their files in that directory's `evaluations/` and "
                        "run its experiment again to retrain them (alike on the same kind of CPU), then make the "
                        "report again.")
        library = SMCLibrary.load(library_dir, names=names)
        loaded.update({method: library[name] for method, (d, name) in best.items() if d == directory})
    smcs = {method: loaded[method] for method in METHODS if method in loaded}
    paths = [trajectory_figure(smcs, target, figures / "trajectories.png")]
    hierarchical = [m for m in smcs if METHOD_REGISTRY[m].curricula is not None]
    if hierarchical:
        paths.append(timeline_figure(smcs[hierarchical[0]], target, figures / "timeline.png"))
    return paths, None


def _with_worlds(sources: Sequence[tuple[Path, dict[str, Any]]]) -> list[tuple[Path, dict[str, Any]]]:
    """``sources`` with each row's per-world test scores (``worlds``) from its saved evaluation, where there is one
    (the claims' bootstrap draws test worlds; a row without them counts with its test score)."""
    out = []
    for directory, results in sources:
        rows = []
        for row in results["rows"]:
            path = evaluation_path(directory, job_name(row["curriculum"], row["seed"]))
            saved = read_evaluation(path) if path.is_file() else {}
            worlds = (saved.get("evaluation") or {}).get("environment_scores") or ()
            rows.append({**row, "worlds": tuple(worlds)})
        out.append((directory, {**results, "rows": rows}))
    return out


def read_table(directories: Sequence[str | Path], reruns: Sequence[str | Path] = ()
               ) -> tuple[ResultTable, Experiences | None]:
    """The merged results of experiment directories (every one read and checked) and their kept experience: what a
    report over them reads. A target x method in two directories is refused, unless one of them is among ``reruns``
    (those of ``directories`` that ran some of the others' pairs again): the rerun's rows replace the others'."""
    if not directories:
        raise SMCError("no experiment directories to read")
    return _table(_replaced([(Path(d), read_results(Path(d))) for d in directories], reruns)[0])


def _table(sources: Sequence[tuple[Path, dict[str, Any]]]) -> tuple[ResultTable, Experiences | None]:
    rows, reported = _merge(_with_worlds(sources))
    table = ResultTable(rows, reported, _unfinished(sources))
    runs = tuple((Experience.load(d / EXPERIENCE_FILE), frozenset((r["target"], r["method"]) for r in results["rows"]))
                 for d, results in sources if (d / EXPERIENCE_FILE).is_file())  # a bad file: refused before any figure
    return table, Experiences(runs) if runs else None


def _write(sources: Sequence[tuple[Path, dict[str, Any]]], out: Path, trajectories: str | None,
           behaviour: bool, replaced: Replaced | None = None) -> Path:
    table, experience = _table(sources)
    methods, targets = table.methods, table.targets
    figures_dir = out / "figures"
    figures_dir.mkdir(parents=True, exist_ok=True)
    figures = _figures(figures_dir, table)
    behaviour_note = None
    if behaviour:
        chosen = trajectories or targets[0]
        if chosen not in targets:
            raise SMCError(f"--trajectories {chosen!r} is not a target of the report ({', '.join(targets)})")
        pictures, behaviour_note = _behaviour(sources, figures_dir, chosen)
        figures += pictures
    settings = [results["settings"] for _, results in sources]
    budget = {(s["seeds"], s["timesteps"], s["repeats"]) for s in settings}
    seeds, timesteps, repeats = next(iter(budget)) if len(budget) == 1 else (None, None, None)
    lines = [f"# Experiment report: {out.name}", "",
             f"Methods {', '.join(methods)}; {len(targets)} target(s)"
             + (f" from {len(sources)} run directories" if len(sources) > 1 else "") + "; "
             + (f"{seeds} seed(s); {timesteps:,} steps per SMC"
                + _target_rules(list(dict.fromkeys(m for s in settings for m in s["methods"])))
                + f"; test: {repeats} repeats per test environment"
                if seeds is not None else "seeds, budgets and repeats per directory below")
             + ", stochastic policy, the update with the best training return. Scores in %; the paper's numbers "
               "(Hay et al., AAAI-18) beside ours where it gives them.", ""]
    for directory, results in sources:
        if results.get("complete") is False:
            missing = results.get("missing", [])
            where = f" ({directory.name})" if len(sources) > 1 else ""
            lines += [f"**Partial results**{where}: {len(missing)} SMC(s) of the run were not trained "
                      "yet when these were tabulated (`sb3-smc experiment --no-train`); every score below is the best "
                      "over the seeds and curricula finished so far, and a target x method with none is absent; a "
                      "number over a target x method with SMCs not trained yet is marked (partial), and no claim is "
                      "judged on it. Not yet trained: " + ", ".join(f"`{name}`" for name in missing[:12])
                      + (", ..." if len(missing) > 12 else "") + ".", ""]
    lines += number_sections(table, experience)
    pushable = [t for t in targets if table.category_of[t] == "pushable"]
    if pushable:
        level = pushable_levels()
        pushable.sort(key=lambda t: (level[t], t))
        figures.append(_pushable_figure(figures_dir, table, pushable, level))
        lines += ["", "## The pushable curriculum by level (Fig. 5c)", "",
                  "Ordered by level: the higher the level, the less the initial state tells (docs/curricula.md). "
                  "The paper gives no numbers here, only that the SMCs' advantage over the CNN is \"particularly "
                  "pronounced\", especially with the curriculum. Best seed (mean ± s.d. over seeds).", "",
                  "| level | target | kind | " + " | ".join(methods) + " |",
                  "|---:|---|---|" + "---:|" * len(methods)]
        for target in pushable:
            lines.append(f"| {level[target]} | {target} | {table.kind_of[target]} | "
                         + " | ".join(table.cell(target, m) for m in methods) + " |")
    lines += ["", "## Figures", ""] + [f"![{p.stem}](figures/{p.name})" for p in figures]
    if behaviour_note:
        lines += ["", behaviour_note]
    lines += _provenance(sources, out, replaced or {})
    path = out / "report.md"
    atomic_write(path, "\n".join(lines) + "\n")
    return path


def _provenance(sources: Sequence[tuple[Path, dict[str, Any]]], out: Path, replaced: Replaced) -> list[str]:
    """How each directory was run: budget, learner, machine, code and the commits its SMCs were trained at, wall time
    (marked ``≥`` where it is a lower bound: :func:`_wall_time_is_lower_bound`), command, and the pairs a rerun
    replaced there."""
    lines = ["", "## How this was run", ""]
    total = 0.0
    bounded = 0
    for directory, results in sources:
        settings = results["settings"]
        machine = results.get("machine", {})
        if len(sources) > 1:
            lines += [f"### {os.path.relpath(directory, out)}", ""]
        lines += [f"- budget: {settings['timesteps']:,} steps per SMC{_target_rules(settings['methods'])}, seeds "
                  f"0-{settings['seeds'] - 1}, {settings['repeats']} test repeats; {settings['workers']} worker(s), "
                  f"backend {settings['backend']}",
                  f"- learner: {_learners(settings)}",
                  f"- machine: {_machine_line(machine)}",
                  *_code_line(results),
                  *_commits_lines(results),
                  _wall_time_line(directory, results),
                  f"- command: `{results.get('command') or _command(directory, settings)}`",
                  "- rows: `results.csv` (one per target x method x curriculum x seed), `results.json`",
                  *_replaced_lines(replaced.get(directory, {}), out), ""]
        total += results.get("wall_time_total_s", results.get("wall_time_s", 0))
        bounded += _wall_time_is_lower_bound(directory, results)
    if len(sources) > 1:
        lines.append(f"Wall time of all runs of the {len(sources)} directories: "
                     + (f"≥ {total / 3600:.2f} h (a lower bound: {bounded} of them recorded without the wall-time "
                        "ledger `wall_time.json`, so without the runs that stopped before their end, at a working "
                        "session's end say)." if bounded else f"{total / 3600:.2f} h."))
    return lines


def _replaced_lines(by_rerun: dict[Path, list[tuple[str, str]]], out: Path) -> list[str]:
    """The pairs of a directory its reruns replaced, by method, in the report's provenance."""
    lines = []
    for rerun, pairs in by_rerun.items():
        methods = dict.fromkeys(m for _, m in pairs)
        for method in methods:
            targets = [t for t, m in pairs if m == method]
            lines.append(f"- replaced by the rerun `{os.path.relpath(rerun, out)}` (not in this report): {method} on "
                         f"{len(targets)} target(s), {', '.join(targets)}")
    return lines


def _wall_time_is_lower_bound(directory: Path, results: dict[str, Any]) -> bool:
    """Whether a directory's recorded wall time is only a lower bound: as its results say
    (``wall_time_lower_bound``), or, for results from before they said so, as its ledger says
    (:func:`sb3_smc.experiments.wall_clock.lower_bound`: none, or one begun from a total recorded without it)."""
    said = results.get("wall_time_lower_bound")
    return said if isinstance(said, bool) else lower_bound(directory)


def _wall_time_line(directory: Path, results: dict[str, Any]) -> str:
    """The report's line on a directory's wall time: its last run's and its total, ``≥`` where that is a lower
    bound."""
    line = f"- wall time of the last `sb3-smc experiment` run: {results.get('wall_time_s', 0) / 3600:.2f} h"
    total = results.get("wall_time_total_s", results.get("wall_time_s", 0)) / 3600
    if not _wall_time_is_lower_bound(directory, results):
        return line + (f"; of all its runs recorded here: {total:.2f} h" if "wall_time_total_s" in results else "")
    return (line + f"; of all its runs recorded here: ≥ {total:.2f} h (a lower bound: recorded without the "
            "wall-time ledger, which alone counts a run stopped before its end)")


def _commits_lines(results: dict[str, Any]) -> list[str]:
    """The report's line on every commit the directory's SMCs were trained at (``results.json``'s ``commits``, with
    the jobs copied from a ``--reuse-from`` library and the note of a record reconstructed by hand), or that its
    results do not say (written before ``commits`` was recorded)."""
    commits = results.get("commits")
    if not isinstance(commits, dict):
        return ["- trained at: not recorded per SMC (results written before `commits`): the commit above is that of "
                "the last run"] if results.get("code") else []
    parts = [f"{'a commit unknown' if key == UNKNOWN_COMMIT else f'`{key[:7]}{key[40:]}`'} ({len(jobs)} SMC job"
             + "s" * (len(jobs) != 1) + ")"
             for key, jobs in sorted(commits.items(), key=lambda item: (item[0] == UNKNOWN_COMMIT, -len(item[1])))]
    copied = results.get("copied") or []
    line = "- trained at: " + (", ".join(parts) or "nothing trained") + (
        f"; {len(copied)} SMC job{'s' * (len(copied) != 1)} copied from a `--reuse-from` library" if copied else "")
    note = results.get("commits_note")
    return [line + (f"; {note}" if isinstance(note, str) and note else "")]


def _target_rules(names: Sequence[str]) -> str:
    """Those of the methods ``names`` that train otherwise than the run says (``canon-scaled``: longer,
    ``curr-moves``: calls costing their moves, ...), each once, and how
    (:attr:`~sb3_smc.experiments.design.ExperimentMethod.change`)."""
    methods = [METHOD_REGISTRY[m] for m in names if m in METHOD_REGISTRY]
    return "".join(f" ({m.name}: {m.change})" for m in methods if m.change)


def _code_line(results: dict[str, Any]) -> list[str]:
    """The report's line on the code that made the results (absent from results of before that was recorded); a
    directory of several runs (a resumed one) says that this is the code of the last."""
    code = results.get("code")
    if not code:
        return []
    versions = code.get("versions", {})
    commit = code.get("commit")
    resumed = results.get("wall_time_total_s", 0.0) > results.get("wall_time_s", 0.0)
    return [f"- code: sb3-smc {versions.get('sb3_smc', '?')}" + (f", commit `{commit}`" if commit else "")
            + f"; torch {versions.get('torch', '?')}, stable-baselines3 {versions.get('stable_baselines3', '?')}, "
              f"sb3-contrib {versions.get('sb3_contrib', '?')}"
            + (" (a resumed run: the code of its last run)" if resumed else "")]


def pushable_levels() -> dict[str, int]:
    """Dataset -> level (1 = flat) of every concept of the designed pushable curriculum."""
    curriculum = designed_curricula()["pushable"]
    return {curriculum.node(name).task: depth for depth, names in enumerate(curriculum.levels(), start=1)
            for name in names}


def _pushable_figure(folder: Path, table: ResultTable, targets: Sequence[str], level: dict[str, int]) -> Path:
    """Fig. 5c: the pushable targets' reported scores ordered by level (error bars: s.d. across seeds)."""
    panel = _concept_panel(table, "the pushable curriculum by level", targets)
    labels = [f"L{level[t]} {t}" for t in targets]
    return bar_panels([Panel(panel.title, labels, panel.values, panel.errors)], table.methods,
                      "test score per concept, ordered by level (best seed; error bars: standard deviation across "
                      "seeds)", folder / "pushable.png", horizontal=True)


def _learner(settings: dict[str, Any]) -> str:
    """The algorithm and cell of the run's SMCs (runs from before the ``--algo`` / ``--rnn`` options: the
    defaults, RecurrentPPO with an LSTM), and whether they were updated with the lean update."""
    algo = settings.get("algo", "RecurrentPPO")
    recurrent = algo in ALGORITHM_REGISTRY and ALGORITHM_REGISTRY[algo].recurrent
    lean = ", the lean update" if settings.get("lean_update") else ""
    return f"{algo} ({settings.get('rnn', 'lstm').upper() if recurrent else 'MLP'}{lean})"


def _learners(settings: dict[str, Any]) -> str:
    """The run's learner (:func:`_learner`), unless every SMC method of the run has its own, and each method's own
    (``base-gru``)."""
    methods = [METHOD_REGISTRY[m] for m in settings["methods"] if m in METHOD_REGISTRY]
    own = [m for m in methods if m.own_learner]
    parts = [] if own and all(m.own_learner for m in methods if m.smc) else [_learner(settings)]
    parts += [f"{m.name}: its own, {_learner({k: v for k, v in (('algo', m.algo), ('rnn', m.rnn)) if v})}"
              for m in own]
    return "; ".join(parts)


def _command(directory: Path, settings: dict[str, Any]) -> str:
    """The command of results recorded before ``results.json`` kept it: the learner options as ``run.json`` has them
    (left out where the run took the defaults; all left out without a ``run.json``, or with a damaged one; one that
    cannot be read raises its ``OSError``)."""
    try:
        run = json.loads((directory / "run.json").read_text())
    except (FileNotFoundError, ValueError):
        run = {}
    return experiment_command("DIR", methods=settings["methods"], targets=settings["targets"],
                              seeds=settings["seeds"], timesteps=run.get("timesteps"),
                              repeats=settings.get("repeats", 10), workers=settings.get("workers", 1),
                              backend=settings.get("backend", "local"), algo=run.get("algo"), rnn=run.get("rnn"),
                              lean_update=bool(run.get("lean_update")))


def _machine_line(machine: dict[str, Any]) -> str:
    cpu = f", {machine['processor']}" if machine.get("processor") else ""
    cores = f", {machine['cores']} cores" if machine.get("cores") else ""
    return f"{machine.get('platform', '?')}{cpu}{cores}, Python {machine.get('python', '?')}"


def _figures(folder: Path, table: ResultTable) -> list[Path]:
    """Fig. 5a/5d (the category means of each kind, s.e. across concepts) and Fig. 5b/5e (every concept of a kind in
    panels by category, s.d. across seeds)."""
    methods = table.methods
    panels = []
    for kind in KINDS:
        groups = [c for c in CATEGORIES if table.of_kind(kind, c)]
        if not groups:
            continue
        members = {c: table.of_kind(kind, c) for c in groups}
        if len(groups) > 1:
            members["all"] = table.of_kind(kind)
        values: dict[str, list[float]] = {m: [] for m in methods}
        errors: dict[str, list[float | None]] = {m: [] for m in methods}
        for targets in members.values():
            for m in methods:
                mean, se = table.mean_se(targets, m) or (math.nan, None)
                values[m].append(100 * mean)
                errors[m].append(None if se is None else 100 * se)
        panels.append(Panel(kind, list(members), values, errors))
    partial = {m for _, m in table.unfinished}
    bars = ("error bars: standard error across the concepts" if any(e is not None for p in panels
                                                                     for v in p.errors.values() for e in v)
            else "one concept behind each bar: no error bars")
    paths = [bar_panels(panels, methods, f"Mean test score per category and kind (best seed of each concept; {bars})",
                        folder / "categories.png", partial=partial)]
    for kind in KINDS:
        groups = [c for c in CATEGORIES if table.of_kind(kind, c)]
        if not groups:
            continue
        ran = [m for m in methods if any((t, m) in table.score for t in table.of_kind(kind))]  # the CNN classifies only
        concept_panels = [_concept_panel(table, f"{kind} / {c}", table.of_kind(kind, c), ran) for c in groups]
        paths.append(bar_panels(concept_panels, ran, f"{kind}: test score per concept (best seed; error bars: "
                                "standard deviation across the seeds of the reported curriculum)",
                                folder / f"concepts-{kind}.png", horizontal=True, partial=partial))
    return paths


def _concept_panel(table: ResultTable, title: str, targets: Sequence[str],
                   methods: Sequence[str] | None = None) -> Panel:
    """Every target's reported score per method (all the table's methods unless given), s.d. across seeds."""
    methods = table.methods if methods is None else methods
    values = {m: [100 * table.score.get((t, m), math.nan) for t in targets] for m in methods}
    errors = {m: [_sd(table.seeds.get((t, m), [])) for t in targets] for m in methods}
    return Panel(title, list(targets), values, errors)


def _sd(scores: Sequence[float]) -> float | None:
    """Sample standard deviation in percent; ``None`` (no error bar) below two seeds."""
    return 100 * float(np.std(scores, ddof=1)) if len(scores) > 1 else None
