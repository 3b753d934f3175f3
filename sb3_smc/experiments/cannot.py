"""The "cannot" table: SMCs that may say a concept cannot be brought about (kind ``bring-about-or-cannot``,
docs/results/cannot/README.md).

Declared before any run: :data:`CANNOT_TARGETS` (the 8 ``bc_`` datasets, each beside its ordinary ``ba_`` dataset)
and :data:`CANNOT_PARENTS` (classification concepts above them). Cells, 5 seeds each:

- ``bc``: a flat SMC on ``PW-bc_X-v0``; its test (every world 10 times) is kept episode by episode: the world's
  label (1: the goal can be brought about), the signal that ended the episode and its moves.
- ``ba``: a flat SMC on ``PW-ba_X-v0`` (the same concept and starts, every world possible), tested on its own test
  split and on the ``bc_`` test split's possible worlds (the same worlds the ``bc`` SMC's success is read on).
- ``bc-ba``: a ``bc`` SMC on ``PW-bc_X-v0`` with one child, that seed's ``ba`` SMC (moves and signals besides):
  what a cannot signal is worth when the bring-about is already learned (scored as ``bc``).
- ``parent-bc`` / ``parent-ba``: each parent trained with one child, ``bc_self-in-container_from_on-floor@s``
  against ``ba_self-in-container_from_on-floor@s`` (the same seed ``s``), so the pair differs only in the child's
  third outcome.

Every cell is :func:`sb3_smc.fewshot.learn_concept` with the paper's protocol (best training update, every test world
10 times, evaluation seed 0) and the lean update, its record written to ``<out>/records/<target>/<cell>@<seed>.json``
as it finishes (a stopped run resumes where it stopped); the SMCs other cells call live in ``<out>/library`` (not
committed; a lost one is trained again, the same SMC). :func:`results_rows` derives one row a cell from the records.
"""

from __future__ import annotations

import csv
import json
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from pixelworld_env.atomic import atomic_write
from sb3_smc.errors import SMCError
from sb3_smc.experiments.statistics import hierarchical_interval, paired_ttest, seed_summary, ttest_text
from sb3_smc.experiments.tabular import csv_text

if TYPE_CHECKING:
    from sb3_smc.learning.evaluation import EvaluationResult

__all__ = ["CANNOT_CHILD", "CANNOT_PARENTS", "CANNOT_TARGETS", "FIELDS", "episode_rows", "ordinary", "results_rows",
           "run_cannot", "write_report"]

CANNOT_TARGETS = (
    "bc_self-in-container_from_on-floor", "bc_self-inside-container_from_on-floor",
    "bc_self-in-container_from_directly-above", "bc_self-inside-container_from_directly-above",
    "bc_self-in-container_from_adjacent-on-floor", "bc_self-in-container_from_left-touches-on-floor",
    "bc_self-in-container_from_right-touches-on-floor", "bc_self-in-container_from_between-potential-containers",
)
CANNOT_CHILD = "bc_self-in-container_from_on-floor"
"""The child the parents call (``parent-bc``), or its ordinary twin (``parent-ba``)."""
CANNOT_PARENTS = ("cl_container-on-floor_vs_noncontainer", "cl_container-on-floor_vs_corner")
FIELDS = ("target", "cell", "seed", "test_score", "cannot_accuracy", "cannot_on_impossible", "cannot_on_possible",
          "success_on_possible", "moves_to_cannot", "moves_per_episode", "primitive_steps")
"""The columns of ``results.csv``; a cell leaves empty those that are not its own (``cannot_*`` for ``ba``)."""


def ordinary(target: str) -> str:
    """The ordinary bring-about dataset of a ``bc_`` target (``bc_X`` -> ``ba_X``)."""
    if not target.startswith("bc_"):
        raise SMCError(f"{target!r} is not a bring-about-or-cannot dataset (bc_...)")
    return "ba_" + target[3:]


def episode_rows(result: EvaluationResult) -> list[list[Any]]:
    """A test's episodes as ``[world, label, signal, success, primitive_steps]`` (``signal``: the action that ended
    the episode, ``None`` for a time-out)."""
    rows = []
    for world in result.environments:
        for episode in world.episodes:
            signal = result.action_names[episode.actions[-1]] if episode.signalled else None
            rows.append([world.index, world.label, signal, bool(episode.success), episode.primitive_steps])
    return rows


def _record(out: Path, target: str, cell: str, seed: int) -> Path:
    return out / "records" / target / f"{cell}@{seed}.json"


FLAT_CELLS = ("bc", "ba", "bc-ba")
PARENT_CELLS = ("parent-bc", "parent-ba")


def _cells(targets: Sequence[str], parents: Sequence[str], seeds: Sequence[int]) -> list[tuple[str, str, int]]:
    """Seed by seed the flat ``bc`` and ``ba`` cells, then the parents (which call that seed's SMCs of
    :data:`CANNOT_CHILD`); the ``bc-ba`` cells (each after the ``ba`` it calls) last."""
    return ([cell for s in seeds for cell in [(t, c, s) for t in targets for c in ("bc", "ba")]
             + [(p, c, s) for p in parents for c in PARENT_CELLS]]
            + [(t, "bc-ba", s) for s in seeds for t in targets])


def _smc_name(target: str, cell: str, seed: int) -> str:
    return f"{target[3:]}-{cell}@{seed}"


def _called(target: str, cell: str, seed: int, parents: bool) -> bool:
    """Whether another cell calls the SMC of this cell (so the run's library keeps it)."""
    return cell == "ba" or (parents and target == CANNOT_CHILD and cell == "bc")


def _children(target: str, cell: str, seed: int) -> list[str]:
    """The library names a cell calls."""
    if cell == "bc-ba":
        return [_smc_name(target, "ba", seed)]
    if cell in PARENT_CELLS:
        return [_smc_name(CANNOT_CHILD, cell.removeprefix("parent-"), seed)]
    return []


def _possible_worlds_id(target: str) -> str:
    """A ``register_worlds`` bring-about id over the possible worlds of ``target``'s splits (registered once)."""
    import gymnasium as gym

    from pixelworld_env import register_worlds
    from pixelworld_env.datasets import catalog
    from pixelworld_env.datasets.loading import load_dataset

    env_id = f"SMCCannotPossible-{target[3:]}-v0"
    if env_id not in gym.registry:
        train, test = ([w for w, label in zip(d.scenes, d.labels, strict=True) if label == 1]
                       for d in (load_dataset(target, "train"), load_dataset(target, "test")))
        register_worlds(env_id, kind="bring-about", concept=catalog.dataset(target).concept_logic, train=train,
                        test=test)
    return env_id


def run_cannot(out: str | Path, *, targets: Sequence[str] = CANNOT_TARGETS,
               parents: Sequence[str] = CANNOT_PARENTS, seeds: int | Sequence[int] = 5, lean_update: bool = True,
               printer: Callable[[str], None] = print, **settings: Any) -> Path:
    """Run every cell not recorded yet (seed by seed: the flat cells, then the parents, whose children are that
    seed's flat ``bc`` / ``ba`` SMCs of :data:`CANNOT_CHILD`; ``bc-ba`` last), then write ``results.csv``. ``seeds``: a
    count (seeds 0 to ``seeds - 1``) or the seeds themselves (two processes may share a run on disjoint seeds: the
    library's save merges their SMCs). ``settings``:
    :func:`~sb3_smc.fewshot.learn_concept`'s (``total_timesteps`` ...)."""
    from sb3_smc.fewshot import learn_concept
    from sb3_smc.learning.evaluation import evaluate
    from sb3_smc.library import SMCLibrary

    unknown = sorted(set(targets) - set(CANNOT_TARGETS))
    if unknown:
        raise SMCError(f"cannot-table targets are {CANNOT_TARGETS}, got {unknown}")
    if parents and CANNOT_CHILD not in targets:
        raise SMCError(f"the parents call {CANNOT_CHILD}'s SMCs: keep it among the targets")
    out = Path(out)
    library_path = out / "library"
    library = SMCLibrary.load(library_path) if (library_path / "manifest.json").is_file() else None
    cells = _cells(targets, parents, range(seeds) if isinstance(seeds, int) else seeds)
    # a called SMC's cell reruns where the library lost it (training is deterministic: the same SMC and record)
    todo = [c for c in cells if not _record(out, *c).is_file()
            or (_called(*c, bool(parents)) and (library is None or _smc_name(*c) not in library))]
    printer(f"{out}: {len(cells)} cells, {len(cells) - len(todo)} recorded, {len(todo)} to run")
    started = time.monotonic()
    for done, (target, cell, seed) in enumerate(todo, 1):
        children = _children(target, cell, seed)
        task = f"PW-{ordinary(target) if cell == 'ba' else target}-v0"
        assert not children or library is not None  # the cells they call come first in the order of the cells
        learned = learn_concept(task, library=library if children else None, offer=children or "none", seed=seed,
                                name=_smc_name(target, cell, seed), lean_update=lean_update, **settings)
        smc = learned.smc
        assert smc.record is not None and smc.spec is not None
        record: dict[str, Any] = {"target": target, "cell": cell, "seed": seed, "offered": list(learned.offered),
                                  "spec": smc.spec.to_dict(), "record": smc.record.to_dict(),
                                  "evaluations": [e.to_dict() for e in smc.evaluations]}
        test = evaluate(smc, repeats=10, seed=0, record_cells=False, keep=False)  # learn_concept's test, per episode
        record["episodes"] = episode_rows(test)
        if cell == "ba":
            possible = evaluate(smc, _possible_worlds_id(target), repeats=10, seed=0, record_cells=False, keep=False)
            record["possible_episodes"] = episode_rows(possible)
        if _called(target, cell, seed, bool(parents)):
            library = library or SMCLibrary(path=library_path)
            library.add(smc, replace=True)
            library.save()
        atomic_write(_record(out, target, cell, seed), json.dumps(record, indent=1) + "\n")
        rate = (time.monotonic() - started) / done
        printer(f"[{done}/{len(todo)}] {target} {cell}@{seed}: test {smc.test_score:.3f} "
                f"(about {rate * (len(todo) - done) / 60:.0f} min left)")
    path = out / "results.csv"
    atomic_write(path, _csv(results_rows(out)))
    return path


def _mean(values: Sequence[float]) -> float | str:
    return round(float(np.mean(values)), 6) if len(values) else ""


def results_rows(out: str | Path) -> list[dict[str, Any]]:
    """One row a recorded cell in ``out``: ``test_score`` (the cell's own test), for ``bc`` the verdict's accuracy
    (CANNOT signalled exactly on the impossible worlds), the CANNOT rate on impossible and on possible worlds, the
    success rate on the possible worlds and the mean moves before a CANNOT on impossible worlds (the same for
    ``bc-ba``); for ``ba`` its success rate on the ``bc`` test split's possible worlds; for every cell the mean
    moves of a test episode."""
    rows = []
    for file in sorted(Path(out).glob("records/*/*.json")):
        data = json.loads(file.read_text(encoding="utf-8"))
        episodes = data["episodes"]
        (test,) = [e for e in data["evaluations"] if e["split"] == "test"]
        row: dict[str, Any] = {name: "" for name in FIELDS}
        row.update(target=data["target"], cell=data["cell"], seed=data["seed"], test_score=test["score"],
                   moves_per_episode=_mean([e[4] for e in episodes]),
                   primitive_steps=data["record"]["primitive_steps"])
        if data["cell"] in ("bc", "bc-ba"):
            impossible = [e for e in episodes if e[1] == 0]
            possible = [e for e in episodes if e[1] == 1]
            row.update(cannot_accuracy=_mean([(e[2] == "CANNOT") == (e[1] == 0) for e in episodes]),
                       cannot_on_impossible=_mean([e[2] == "CANNOT" for e in impossible]),
                       cannot_on_possible=_mean([e[2] == "CANNOT" for e in possible]),
                       success_on_possible=_mean([e[3] for e in possible]),
                       moves_to_cannot=_mean([e[4] for e in impossible if e[2] == "CANNOT"]))
        elif data["cell"] == "ba":
            row.update(success_on_possible=_mean([e[3] for e in data["possible_episodes"]]))
        rows.append(row)
    return sorted(rows, key=lambda r: (r["target"], r["cell"], r["seed"]))


def _csv(rows: Sequence[dict[str, Any]]) -> str:
    return csv_text(rows, FIELDS)


def _by(rows: Sequence[dict[str, Any]], cell: str, field: str) -> dict[str, dict[int, float]]:
    """``{target: {seed: value}}`` of one cell's column (cells without the value left out)."""
    table: dict[str, dict[int, float]] = {}
    for row in rows:
        if row["cell"] == cell and row[field] != "":
            table.setdefault(row["target"], {})[int(row["seed"])] = float(row[field])
    return table


def _summary(values: Sequence[float], scale: float = 100.0) -> str:
    s = seed_summary(values)
    sd = f" ± {scale * s.sd:.1f}" if s.sd is not None else ""
    return f"{scale * s.mean:.1f}{sd}"


def _paired(a: dict[int, float], b: dict[int, float]) -> tuple[list[float], list[float]]:
    seeds = sorted(set(a) & set(b))
    return [a[s] for s in seeds], [b[s] for s in seeds]


_TITLES = {"bc": "Flat SMCs (bc, beside the ordinary flat SMC ba), per target",
           "bc-ba": "bc SMCs calling the ordinary SMC (bc-ba: the seed's ba SMC as a child), per target"}


def _target_table(rows: Sequence[dict[str, Any]], cell: str) -> tuple[list[str], dict[str, list[float]]]:
    """The per-target table of a ``bc`` or ``bc-ba`` cell and, per target, its seeds' success on possible worlds
    minus the ``ba`` SMC's (points)."""
    lines = ["", f"### {_TITLES[cell]}", "",
             "| target | n | cannot accuracy | CANNOT on impossible | CANNOT on possible | success on possible "
             "| ba: success on possible | difference | moves to CANNOT | ba: on its own test |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    column = {field: _by(rows, cell, field) for field in FIELDS[4:9]}
    ba_possible, ba_test = _by(rows, "ba", "success_on_possible"), _by(rows, "ba", "test_score")
    differences: dict[str, list[float]] = {}
    for target in [t for t in CANNOT_TARGETS if t in column["cannot_accuracy"]]:
        own_possible = column["success_on_possible"][target]
        ours, theirs = _paired(own_possible, ba_possible.get(target, {}))
        differences[target] = [100 * (x - y) for x, y in zip(ours, theirs, strict=True)]
        diff = f"{np.mean(differences[target]):+.1f}" if differences[target] else "-"
        moves = column["moves_to_cannot"].get(target, {})
        own = [_summary(list(column[f][target].values())) for f in FIELDS[4:8]]
        ba = [_summary(list(d[target].values())) if target in d else "-" for d in (ba_possible, ba_test)]
        lines.append(f"| {target[3:]} | {len(own_possible)} | {' | '.join(own)} | {ba[0]} | {diff} | "
                     f"{_summary(list(moves.values()), 1.0) if moves else '-'} | {ba[1]} |")
    lines += ["", "Across targets:", ""]
    for field, title in (("cannot_accuracy", "cannot accuracy"), ("cannot_on_impossible", "CANNOT on impossible"),
                         ("cannot_on_possible", "CANNOT on possible")):
        values = {t: [100 * v for v in seeds.values()] for t, seeds in column[field].items()}
        if values:
            mean, low, high = hierarchical_interval(values)
            lines.append(f"- {title}: {mean:.1f} % [{low:.1f}, {high:.1f}] over {len(values)} targets")
    complete = {t: d for t, d in differences.items() if d}
    if len(complete) >= 2:
        mean, low, high = hierarchical_interval(complete)
        test = paired_ttest([float(np.mean(list(column["success_on_possible"][t].values()))) for t in complete],
                            [float(np.mean(list(ba_possible[t].values()))) for t in complete])
        lines.append(f"- success on possible worlds, {cell} minus ba: {mean:+.1f} points [{low:+.1f}, {high:+.1f}] "
                     f"over {len(complete)} targets" + (f", {ttest_text(test)}" if test else ""))
    return lines, differences


INTRO = """# Bring about, or say it cannot be done: the cannot table

The paper's second limitation: "bring-about SMCs are only used in situations where it is possible to bring about the
concept. An extension to cases where it cannot, allowing the SMC to signal whether it cannot achieve the concept,
would increase the power of this representation." The kind `bring-about-or-cannot` (docs/pixelworld.md, "Kinds of
task") adds a `CANNOT` signal: +1 where the world allows no goal, -1 in all where it does; `SIG1` and the shaping
are bring-about's. Its 8 `bc_` datasets mix worlds where the concept can be brought about with worlds where it
cannot (no container), each labelled by an exhaustive search of the world's moves
(`pixelworld_env.generation.oracle.can_bring_about`), 25 of each in each split.

Cells, 5 seeds each, the paper's protocol (best training update, every test world 10 times, evaluation seed 0), the
lean update, the paper's budget (400,000 steps):

- **bc**: a flat SMC on `PW-bc_X-v0`. *Cannot accuracy*: the share of test episodes whose verdict (CANNOT signalled
  or not) matches the world's label; *success on possible*: the share of episodes on possible worlds that end with
  SIG1 in the goal; *moves to CANNOT*: the primitive moves before a CANNOT on impossible worlds.
- **ba**: the ordinary flat SMC on `PW-ba_X-v0` (the same concept and starts, every world possible), tested on its
  own test split and on the `bc_` test split's 25 possible worlds (the worlds bc's success is read on).
- **bc-ba**: a bc SMC calling that seed's ba SMC (moves and signals besides).
- **parents**: `cl_container-on-floor_vs_noncontainer` and `cl_container-on-floor_vs_corner`, each trained with one
  child, `bc_self-in-container_from_on-floor`'s bc SMC (parent-bc) or its ba SMC (parent-ba) of the same seed:
  the pair differs only in the child's third outcome (a cannot is -1 in the parent's outcome vector, a cut call
  -0.5 for bc and 0 for ba, done +1).

Run or resume: `python tools/cannot_table.py --out runs/cannot` (about 4 hours on one core; `--only-seeds 3,4` in
a second process shares the run); this page: `sb3_smc.experiments.cannot.write_report`, from `results.csv` and
the records in `records/` (one JSON file a cell, with every test episode).
"""


def write_report(out: str | Path) -> Path:
    """``<out>/README.md``: :data:`INTRO`, then from ``<out>/results.csv`` (:func:`results_rows`' columns) a table
    per target for ``bc`` and ``bc-ba`` (means ± s.d. over seeds) with their comparison on possible worlds against
    ``ba`` across targets (paired t-test on the targets' seed means, and a hierarchical interval over targets and
    seeds), ``bc-ba`` against ``bc`` on the cannot accuracy, and the parents' paired comparison over seeds."""
    out = Path(out)
    with open(out / "results.csv", newline="", encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle))
    planned = len(_cells(CANNOT_TARGETS, CANNOT_PARENTS, range(5)))
    status = f"{len(rows)} cells" if len(rows) >= planned else f"**Partial**: {len(rows)} of the {planned} cells"
    lines = [INTRO, "## Results", "",
             f"{status}. Scores in percent, mean ± s.d. over seeds (n: seeds); moves are primitive moves of a test "
             "episode."]
    for cell in ("bc", "bc-ba"):
        if any(row["cell"] == cell for row in rows):
            lines += _target_table(rows, cell)[0]
    flat, called = _by(rows, "bc", "cannot_accuracy"), _by(rows, "bc-ba", "cannot_accuracy")
    both = {t: [100 * (a - b) for a, b in zip(*_paired(called[t], flat[t]), strict=True)]
            for t in flat if t in called}
    both = {t: d for t, d in both.items() if d}
    if len(both) >= 2:
        mean, low, high = hierarchical_interval(both)
        test = paired_ttest([float(np.mean(list(called[t].values()))) for t in both],
                            [float(np.mean(list(flat[t].values()))) for t in both])
        lines += ["", f"- cannot accuracy, bc-ba minus bc: {mean:+.1f} points [{low:+.1f}, {high:+.1f}] over "
                  f"{len(both)} targets" + (f", {ttest_text(test)}" if test else "")]
    lines += ["", "Intervals: 95 % hierarchical bootstrap (targets, then seeds within each target); the t-test pairs "
              "the targets' seed means.", "", "### Parents", "",
              "| parent | n | accuracy, bc child | accuracy, ba child | difference | paired t | moves, bc child "
              "| moves, ba child | paired t (moves) |", "|---|---|---|---|---|---|---|---|---|"]
    for parent in CANNOT_PARENTS:
        with_bc, with_ba = (_by(rows, cell, "test_score").get(parent) for cell in ("parent-bc", "parent-ba"))
        if not with_bc or not with_ba:
            continue
        a, b = _paired(with_bc, with_ba)
        moves_bc, moves_ba = (_by(rows, c, "moves_per_episode")[parent] for c in ("parent-bc", "parent-ba"))
        ma, mb = _paired(moves_bc, moves_ba)
        test, moves_test = paired_ttest(a, b), paired_ttest(ma, mb)
        lines.append(f"| {parent[3:]} | {len(a)} | {_summary(a)} | {_summary(b)} | "
                     f"{100 * (np.mean(a) - np.mean(b)):+.1f} | {ttest_text(test) if test else '-'} | "
                     f"{_summary(ma, 1.0)} | {_summary(mb, 1.0)} | {ttest_text(moves_test) if moves_test else '-'} |")
    path = out / "README.md"
    atomic_write(path, "\n".join(lines) + "\n")
    return path
