"""``write_report``: ``DIR/report.md`` and ``DIR/figures/*.png`` from an experiment's ``results.json``.

The report puts the paper's numbers (spec §6, :mod:`sb3_smc.experiments.paper`) beside ours: per concept where the
paper gives them, per kind (classification / bring-about) and per category for every method that ran, the paired
t-tests across concepts (scipy), the noprim table of §6.3 when those methods ran, and the settings, machine, wall
time and command. Figures (matplotlib, headless): Fig. 5-style bars per category and per concept with standard
errors (across concepts, resp. across seeds).
"""

from __future__ import annotations

import json
import math
from collections import defaultdict
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from pixelworld_env.atomic import atomic_write
from sb3_smc.experiments.design import CATEGORIES, METHODS, PAPER_CATEGORIES
from sb3_smc.experiments.figures import pyplot, save_figure
from sb3_smc.experiments.paper import PAPER_CONCEPTS, PAPER_MEANS, PAPER_NOPRIM, PAPER_TTESTS
from sb3_smc.experiments.runner import experiment_command, read_results

__all__ = ["paired_ttest", "pushable_levels", "write_report"]

KINDS = ("classification", "bring-about")
PAPER_COUNTS = {"classification": 34, "bring-about": 17}
"""How many level-2 concepts the paper's means are over (spec §6.1, §6.2)."""
COLORS = {"cnn": "#888888", "base": "#4c72b0", "curr": "#dd8452", "canon": "#55a868", "curr-noprim": "#f2b48a",
          "canon-noprim": "#a5d6a7"}


def paired_ttest(ours: Sequence[float], theirs: Sequence[float]) -> tuple[int, float, float] | None:
    """``(df, t, p)`` of the paired t-test of ``ours`` against ``theirs`` (two-sided); ``None`` below 2 pairs or
    when every difference is equal (t undefined)."""
    from scipy import stats

    a, b = np.asarray(ours, dtype=float), np.asarray(theirs, dtype=float)
    if len(a) < 2 or np.allclose(a - b, (a - b)[0]):
        return None
    result = stats.ttest_rel(a, b)
    return len(a) - 1, float(result.statistic), float(result.pvalue)


def _pct(value: float | None) -> str:
    return "-" if value is None or (isinstance(value, float) and math.isnan(value)) else f"{100 * value:.1f}"


def _diff(ours: float | None, paper: float | None) -> str:
    if ours is None or paper is None:
        return ""
    return f"{100 * ours - paper:+.1f}"


def write_report(directories: str | Path | Sequence[str | Path], *, trajectories: str | None = None,
                 behaviour: bool = True) -> list[Path]:
    """Write ``report.md`` and ``figures/`` into each experiment directory; returns the report paths.

    ``behaviour``: also draw the Fig. 4 trajectories of the best SMC of each method and the Fig. 1 timeline of the
    best hierarchical SMC, on ``trajectories`` (a target; default: the first one).
    """
    items = [directories] if isinstance(directories, str | Path) else list(directories)
    return [_write(Path(d), trajectories, behaviour) for d in items]


def _behaviour(directory: Path, reported: Sequence[dict[str, Any]], target: str) -> tuple[list[Path], str | None]:
    """The Fig. 4 / Fig. 1 pictures of the best SMCs of ``target``; or none and the reason, when the run directory
    does not hold their models (a run kept as records: ``docs/experiments.md``)."""
    from sb3_smc.curricula.trainer import job_name
    from sb3_smc.experiments.figures import timeline_figure, trajectory_figure
    from sb3_smc.library import SMCLibrary, storage

    best = {r["method"]: job_name(r["curriculum"], r["seed"]) for r in reported
            if r["target"] == target and r["method"] != "cnn"}
    if not best:
        return [], None
    library_dir = directory / "library"
    held = set(storage.read_manifest(library_dir)[0]["smcs"]) if (library_dir / storage.MANIFEST).is_file() else set()
    absent = sorted(set(best.values()) - held)
    if absent:
        return [], (f"The trajectory and timeline pictures of `{target}` need the models of its best SMCs; this "
                    f"directory does not hold {', '.join(f'`{n}`' for n in absent)} (trained in an earlier session "
                    "of a run kept as records). Delete their files in `evaluations/` and run the experiment again "
                    "to retrain them (alike on the same kind of CPU), then make the report again.")
    library = SMCLibrary.load(directory / "library", names=sorted(set(best.values())))
    smcs = {method: library[name] for method, name in best.items()}
    paths = [trajectory_figure(smcs, target, directory / "figures" / "trajectories.png")]
    hierarchical = [m for m in ("curr", "canon", "curr-noprim", "canon-noprim") if m in smcs]
    if hierarchical:
        paths.append(timeline_figure(smcs[hierarchical[0]], target, directory / "figures" / "timeline.png"))
    return paths, None


def _write(directory: Path, trajectories: str | None, behaviour: bool) -> Path:
    results = read_results(directory)
    reported = results["reported"]
    if not reported:
        raise ValueError(f"{directory / 'results.json'} holds no results")
    methods = [m for m in METHODS if any(r["method"] == m for r in reported)]
    score = {(r["target"], r["method"]): r["test_score"] for r in reported}
    targets = sorted({r["target"] for r in reported})
    kind_of = {r["target"]: r["kind"] for r in reported}
    category_of = {r["target"]: r["category"] for r in reported}
    figures = _figures(directory, results, methods, targets, score, category_of)
    behaviour_note = None
    if behaviour:
        chosen = trajectories or targets[0]
        if chosen not in targets:
            raise ValueError(f"--trajectories {chosen!r} is not a target of {directory} ({', '.join(targets)})")
        pictures, behaviour_note = _behaviour(directory, reported, chosen)
        figures += pictures
    settings = results["settings"]
    lines = [f"# Experiment report: {directory.name}", "",
             f"Methods {', '.join(methods)}; {len(targets)} target(s); {settings['seeds']} seed(s); "
             f"{settings['timesteps']:,} steps per SMC; test: {settings['repeats']} repeats per test environment, "
             "stochastic policy, the update with the best training return. Scores in %; the paper's numbers "
             "(Hay et al., AAAI-18, spec §6) beside ours where it gives them.", ""]
    if results.get("complete") is False:
        missing = results.get("missing", [])
        lines += [f"**Partial results**: {len(missing)} SMC(s) of the run were not trained yet when these were "
                  "tabulated (`sb3-smc experiment --no-train`); every score below is the best over the seeds and "
                  "curricula finished so far, and a target x method with none is absent. Not yet trained: "
                  + ", ".join(f"`{name}`" for name in missing[:12]) + (", ..." if len(missing) > 12 else "") + ".",
                  ""]
    # per concept
    lines += ["## Per concept (best seed; curr: best curriculum)", "",
              "| target | kind | category | " + " | ".join(methods) + " | paper (base / curr / canon) |",
              "|---|---|---|" + "---:|" * len(methods) + "---|"]
    for target in targets:
        cells = [_pct(score.get((target, m))) for m in methods]
        paper = PAPER_CONCEPTS.get(target)
        paper_text = " / ".join(f"{paper[m]:.1f}" for m in ("base", "curr", "canon")) if paper else ""
        lines.append(f"| {target} | {kind_of[target]} | {category_of[target]} | " + " | ".join(cells)
                     + f" | {paper_text} |")
    # differences to the paper per concept
    given = [t for t in targets if t in PAPER_CONCEPTS]
    if given:
        lines += ["", "Differences to the paper (ours - paper, points):", ""]
        for target in given:
            parts = [f"{m} {_diff(score.get((target, m)), PAPER_CONCEPTS[target].get(m))}"
                     for m in ("base", "curr", "canon") if (target, m) in score]
            lines.append(f"- {target}: " + ", ".join(parts))
    # per kind and category
    lines += ["", "## Means per kind and category", "",
              "| kind | category | concepts | " + " | ".join(methods) + " |",
              "|---|---|---:|" + "---:|" * len(methods)]
    for kind in KINDS:
        in_kind = [t for t in targets if kind_of[t] == kind]
        if not in_kind:
            continue
        groups = [(c, [t for t in in_kind if category_of[t] == c]) for c in CATEGORIES]
        for label, members in [*[(c, m) for c, m in groups if m], ("all", in_kind)]:
            means = [_mean([score.get((t, m)) for t in members]) for m in methods]
            lines.append(f"| {kind} | {label} | {len(members)} | " + " | ".join(_pct(x) for x in means) + " |")
        in_paper = [t for t in in_kind if category_of[t] in PAPER_CATEGORIES]
        if not in_paper:  # the designed pushable curriculum: the paper gives no numbers (Fig. 5c only)
            continue
        paper = PAPER_MEANS[kind]
        lines.append(f"| {kind} | **paper** (all) | {PAPER_COUNTS[kind]} | "
                     + " | ".join(f"{paper[m]:.1f}" if m in paper else "" for m in methods) + " |")
        if len(in_paper) == PAPER_COUNTS[kind]:  # the paper's whole set: its means
            lines.append(f"| {kind} | ours - paper ({len(in_paper)} concepts) | | " + " | ".join(
                _diff(_mean([score.get((t, m)) for t in in_paper]), paper.get(m)) for m in methods) + " |")
        else:  # a subset: only against the paper's own numbers for the same concepts, where it gives them
            lines.append(f"| {kind} | ours - paper (the same {len(in_paper)} concept(s), where the paper gives them) "
                         "| | " + " | ".join(_diff(_mean([score.get((t, m)) for t in in_paper]),
                                                   _mean([PAPER_CONCEPTS.get(t, {}).get(m) for t in in_paper]))
                                             for m in methods) + " |")
    # t-tests
    lines += ["", "## Paired t-tests across concepts", "",
              "| kind / category | comparison | concepts | t | df | p | paper |",
              "|---|---|---:|---:|---:|---:|---|"]
    for kind in KINDS:
        in_kind = [t for t in targets if kind_of[t] == kind]
        if not in_kind:
            continue
        for a, b in (("curr", "base"), ("canon", "base")):
            paper_test = PAPER_TTESTS[kind].get(f"{a} vs {b}") if all(
                category_of[t] in PAPER_CATEGORIES for t in in_kind) else None  # the paper tested its own concepts
            lines.append(_ttest_row(kind, f"{a} vs {b}", in_kind, a, b, score, paper_test))
        if kind == "classification":
            for category in CATEGORIES:
                members = [t for t in in_kind if category_of[t] == category]
                if members:
                    best_smc = "curr" if "curr" in methods else "canon"
                    lines.append(_ttest_row(f"{kind} / {category}", f"{best_smc} vs cnn", members, best_smc, "cnn",
                                            score, None))
    # noprim
    noprim = [m for m in ("curr-noprim", "canon-noprim") if m in methods]
    if noprim:
        lines += ["", "## The role of hierarchy: without primitive moves (spec §6.3)", "",
                  "| kind | method | with primitives | without | paper with | paper without |",
                  "|---|---|---:|---:|---:|---:|"]
        for kind in KINDS:
            in_kind = [t for t in targets if kind_of[t] == kind]
            for method in ("curr", "canon"):
                if f"{method}-noprim" not in methods or not in_kind:
                    continue
                paper = PAPER_NOPRIM[kind]
                lines.append(f"| {kind} | {method} | {_pct(_mean([score.get((t, method)) for t in in_kind]))} | "
                             f"{_pct(_mean([score.get((t, method + '-noprim')) for t in in_kind]))} | "
                             f"{paper[method]:.1f} | {paper[method + '-noprim']:.1f} |")
    # the designed pushable curriculum by level (Fig. 5c)
    pushable = [t for t in targets if category_of[t] == "pushable"]
    if pushable:
        level = pushable_levels()
        pushable.sort(key=lambda t: (level[t], t))
        figures.append(_pushable_figure(directory, results, pushable, methods, score, level))
        lines += ["", "## The pushable curriculum by level (Fig. 5c)", "",
                  "Ordered by level: the higher the level, the less the initial state tells (docs/curricula.md). "
                  "The paper gives no numbers here, only that the SMCs' advantage over the CNN is \"particularly "
                  "pronounced\", especially with the curriculum.", "",
                  "| level | target | kind | " + " | ".join(methods) + " |",
                  "|---:|---|---|" + "---:|" * len(methods)]
        for target in pushable:
            lines.append(f"| {level[target]} | {target} | {kind_of[target]} | "
                         + " | ".join(_pct(score.get((target, m))) for m in methods) + " |")
    # figures and provenance
    lines += ["", "## Figures", ""] + [f"![{p.stem}](figures/{p.name})" for p in figures]
    if behaviour_note:
        lines += ["", behaviour_note]
    machine = results.get("machine", {})
    lines += ["", "## How this was run", "",
              f"- budget: {settings['timesteps']:,} steps per SMC, seeds 0-{settings['seeds'] - 1}, "
              f"{settings['repeats']} test repeats; {settings['workers']} worker(s), backend {settings['backend']}",
              f"- learner: {_learner(settings)}",
              f"- machine: {_machine_line(machine)}",
              *_code_line(results.get("code")),
              f"- wall time of the last `sb3-smc experiment` run: {results.get('wall_time_s', 0) / 3600:.2f} h"
              + (f"; of all its runs recorded here: {results['wall_time_total_s'] / 3600:.2f} h"
                 if "wall_time_total_s" in results else ""),
              f"- command: `{results.get('command') or _command(directory, settings)}`",
              "- rows: `results.csv` (one per target x method x curriculum x seed), `results.json`"]
    path = directory / "report.md"
    atomic_write(path, "\n".join(lines) + "\n")
    return path


def _code_line(code: dict[str, Any] | None) -> list[str]:
    """The report's line on the code that made the results (absent from results of before that was recorded)."""
    if not code:
        return []
    versions = code.get("versions", {})
    commit = code.get("commit")
    return [f"- code: sb3-smc {versions.get('sb3_smc', '?')}" + (f", commit `{commit}`" if commit else "")
            + f"; torch {versions.get('torch', '?')}, stable-baselines3 {versions.get('stable_baselines3', '?')}, "
              f"sb3-contrib {versions.get('sb3_contrib', '?')} (a resumed run: the code of its last run)"]


def pushable_levels() -> dict[str, int]:
    """Dataset -> level (1 = flat) of every concept of the designed pushable curriculum."""
    from sb3_smc.curricula.designed import designed_curricula

    curriculum = designed_curricula()["pushable"]
    return {curriculum.node(name).task: depth for depth, names in enumerate(curriculum.levels(), start=1)
            for name in names}


def _pushable_figure(directory: Path, results: dict[str, Any], targets: Sequence[str], methods: Sequence[str],
                     score: dict[tuple[str, str], float], level: dict[str, int]) -> Path:
    """Fig. 5c: the pushable targets' reported scores ordered by level (error: s.e. across seeds)."""
    by_seed = _seed_scores(results)
    labels = [f"L{level[t]} {t}" for t in targets]
    return _bars(labels, methods, {m: [100 * score.get((t, m), np.nan) for t in targets] for m in methods},
                 {m: [_sem(by_seed[(t, m)]) for t in targets] for m in methods},
                 "the pushable curriculum by level (best seed; error: s.e. across seeds)",
                 directory / "figures" / "pushable.png",
                 size=(max(4.0, 0.9 * len(targets) * max(1, len(methods)) / 2), 3.8), rotate=True)


def _learner(settings: dict[str, Any]) -> str:
    """The algorithm and cell of the run's SMCs (runs from before the ``--algo`` / ``--rnn`` options: the
    defaults, RecurrentPPO with an LSTM)."""
    from sb3_smc.hyperparameters import RECURRENT_ALGORITHMS

    algo = settings.get("algo", "RecurrentPPO")
    return f"{algo} ({settings.get('rnn', 'lstm').upper() if algo in RECURRENT_ALGORITHMS else 'MLP'})"


def _command(directory: Path, settings: dict[str, Any]) -> str:
    """The command of results recorded before ``results.json`` kept it: the learner options as ``run.json`` has them
    (left out where the run took the defaults)."""
    try:
        run = json.loads((directory / "run.json").read_text())
    except (OSError, ValueError):
        run = {}
    return experiment_command("DIR", methods=settings["methods"], targets=settings["targets"],
                              seeds=settings["seeds"], timesteps=run.get("timesteps"),
                              repeats=settings.get("repeats", 10), workers=settings.get("workers", 1),
                              backend=settings.get("backend", "local"), algo=run.get("algo"), rnn=run.get("rnn"))


def _machine_line(machine: dict[str, Any]) -> str:
    cpu = f", {machine['processor']}" if machine.get("processor") else ""
    cores = f", {machine['cores']} cores" if machine.get("cores") else ""
    return f"{machine.get('platform', '?')}{cpu}{cores}, Python {machine.get('python', '?')}"


def _mean(values: Sequence[float | None]) -> float | None:
    present = [v for v in values if v is not None]
    return float(np.mean(present)) if present and len(present) == len(values) else None


def _ttest_row(label: str, comparison: str, members: Sequence[str], a: str, b: str,
               score: dict[tuple[str, str], float], paper: tuple[int, float, float] | None) -> str:
    pairs = [(score[(t, a)], score[(t, b)]) for t in members if (t, a) in score and (t, b) in score]
    test = paired_ttest([p[0] for p in pairs], [p[1] for p in pairs]) if pairs else None
    paper_text = f"t({paper[0]}) = {paper[1]}, p = {paper[2]}" if paper else ""
    if test is None:
        return f"| {label} | {comparison} | {len(pairs)} | - | - | - | {paper_text} |"
    df, t, p = test
    return f"| {label} | {comparison} | {len(pairs)} | {t:.2f} | {df} | {p:.2g} | {paper_text} |"


def _bars(labels: Sequence[str], methods: Sequence[str], values: dict[str, list[float]],
          errors: dict[str, list[float]], title: str, path: Path, *, size: tuple[float, float],
          rotate: bool = False) -> Path:
    """Grouped bars (one group per label, one bar per method) with error bars, in percent."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=size)
    width = 0.8 / max(1, len(methods))
    for k, method in enumerate(methods):
        ax.bar(np.arange(len(labels)) + k * width, values[method], width, yerr=errors[method], label=method,
               color=COLORS.get(method), capsize=2)
    ticks = np.arange(len(labels)) + width * (len(methods) - 1) / 2
    if rotate:
        ax.set_xticks(ticks, labels, rotation=30, ha="right", fontsize=6)
    else:
        ax.set_xticks(ticks, labels)
    ax.set_ylabel("test score (%)")
    ax.set_ylim(0, 100)
    ax.legend(fontsize=7, ncol=3)
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    return save_figure(fig, path)


def _seed_scores(results: dict[str, Any]) -> dict[tuple[str, str], list[float]]:
    """(target, method) -> the test scores of every seed of the reported curriculum."""
    by_seed: dict[tuple[str, str], list[float]] = defaultdict(list)
    best_curriculum = {(r["target"], r["method"]): r["curriculum"] for r in results["reported"]}
    for row in results["rows"]:
        if row["curriculum"] == best_curriculum.get((row["target"], row["method"])):
            by_seed[(row["target"], row["method"])].append(row["test_score"])
    return by_seed


def _sem(values: Sequence[float]) -> float:
    """Standard error of the mean, in percent (0 for fewer than two values)."""
    return 100 * float(np.std(values, ddof=1)) / math.sqrt(len(values)) if len(values) > 1 else 0.0


def _figures(directory: Path, results: dict[str, Any], methods: list[str], targets: list[str],
             score: dict[tuple[str, str], float], category_of: dict[str, str]) -> list[Path]:
    folder = directory / "figures"
    folder.mkdir(exist_ok=True)
    # per category: mean of the reported scores across concepts, standard error across concepts
    groups = [c for c in CATEGORIES if any(category_of[t] == c for t in targets)]
    members = {(c, m): [score[(t, m)] for t in targets if category_of[t] == c and (t, m) in score]
               for c in groups for m in methods}
    categories = _bars(
        groups, methods,
        {m: [100 * np.mean(members[(c, m)]) if members[(c, m)] else np.nan for c in groups] for m in methods},
        {m: [_sem(members[(c, m)]) for c in groups] for m in methods},
        "per category (best seed; error: s.e. across concepts)", folder / "categories.png",
        size=(1.8 + 1.4 * len(groups) * max(1, len(methods)) / 3, 3.2))
    # per concept: the reported score, standard error across seeds of the reported curriculum
    by_seed = _seed_scores(results)
    concepts = _bars(
        targets, methods,
        {m: [100 * score.get((t, m), np.nan) for t in targets] for m in methods},
        {m: [_sem(by_seed[(t, m)]) for t in targets] for m in methods},
        "per concept (best seed; error: s.e. across seeds)", folder / "concepts.png",
        size=(max(4.0, 0.9 * len(targets) * max(1, len(methods)) / 2), 3.6), rotate=True)
    return [categories, concepts]
