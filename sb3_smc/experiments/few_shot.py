"""The few-shot table: each target concept learned from ``N`` of its training worlds, with and without the pretrained
library's SMCs as actions (docs/few_shot.md).

Declared before any run: :data:`FEW_SHOT_TARGETS` (24 of the paper's 51 level-2 targets: both kinds, the four
categories, the two headline targets), :data:`FEW_SHOT_WORLDS` (1, 2, 4, 8 and every training world) and
:data:`FEW_SHOT_METHODS`: ``cnn`` (the paper's passive CNN on the same worlds, classification targets only),
``base`` (a flat SMC, no library), ``curr`` (the children of the target's first smc-curr
entry, their two best pretrained seeds), ``canon`` (its smc-canon entry's; both less any SMC trained on the target's
own datasets, which the held-out rule bars), ``auto`` (the automatic choice from the
``N`` examples, :func:`sb3_smc.fewshot.choose_smcs`, over the whole pretrained library, held out). Each cell is
:func:`sb3_smc.fewshot.learn_concept` with the paper's protocol (best training update, every test world 10 times, seed
0; the seeds of one target, method and ``N`` trained together by :func:`sb3_smc.fewshot.learn_concepts`, each the SMC
``learn_concept`` gives), its records written to ``<out>/records/<target>/<method>-n<N>@<seed>.json`` as its
group finishes (a stopped run resumes where it stopped, losing at most the group it was training), and
``<out>/results.csv`` holds one row a cell: ``target, kind, category, method, train_worlds, seed, test_score,
offered, primitive_steps``.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from itertools import groupby
from pathlib import Path
from typing import TYPE_CHECKING, Any

from pixelworld_env.atomic import atomic_write
from sb3_smc.curricula import shipped_curricula
from sb3_smc.errors import SMCError
from sb3_smc.experiments.tabular import csv_text

if TYPE_CHECKING:
    from sb3_smc.library import SMCLibrary

__all__ = ["FEW_SHOT_METHODS", "FEW_SHOT_TARGETS", "FEW_SHOT_WORLDS", "children_of", "group_records", "offer_for",
           "record_score", "record_training_s", "results_csv", "results_rows", "run_few_shot", "write_results"]

FEW_SHOT_TARGETS = (
    # containment: 5 bring-about, 5 classification (the first: a headline target)
    "ba_self-in-container_from_between-potential-containers", "ba_self-in-container_from_on-floor",
    "ba_self-in-container_from_between-container-and-noncontainer", "ba_self-inside-container_from_on-floor",
    "ba_self-in-potential-container_from_on-floor",
    "cl_self-in-container_vs_noncontainer", "cl_self-in-container_vs_corner", "cl_container-on-floor_vs_corner",
    "cl_self-touches-container_vs_noncontainer", "cl_self-inside-container_vs_noncontainer",
    # objcon: 7 classification (the first: a headline target)
    "cl_self-left-of-two-objects-vs-one", "cl_self-right-of-two-objects-vs-one", "cl_self-inside-container_vs_rest",
    "cl_self-left-of-container_vs_object", "cl_self-right-touches-container_vs_object",
    "cl_self-left-touches-container_vs_non-container", "cl_self-inside-enclosure_vs_rest",
    # objects: 3 bring-about, 3 classification
    "ba_self-left-of-two-objects_from_not-left-on-floor", "ba_self-ontop-object_from_anywhere-on-floor",
    "ba_self-right-of-two-objects_from_not-right-on-floor",
    "cl_object-on-floor_vs_no-object", "cl_object-above-floor_vs_no-object", "cl_object-on-floor_vs_not-on-floor",
    # search: its one target (no smc-curr entry in the pretrained library: canon and auto only)
    "ba_self-in-target-container_from_nontarget-container",
)
FEW_SHOT_WORLDS: tuple[int | None, ...] = (1, 2, 4, 8, None)
"""Training worlds of each cell (``None``: every world of the training split, 25 for bring-about, 50 for
classification)."""
FEW_SHOT_METHODS = ("cnn", "base", "curr", "canon", "auto")
FIELDS = ("target", "kind", "category", "method", "train_worlds", "seed", "test_score", "offered", "primitive_steps")


def children_of(target: str, method: str) -> list[str] | None:
    """The pretrained SMCs a ``curr`` or ``canon`` cell of ``target`` offers: the two best seeds of every node its
    first smc-curr / smc-canon entry uses; ``None`` where the pretrained library lacks them (search has no curr)."""
    from sb3_smc.library.pretrained import pretrained_index, pretrained_names

    held = pretrained_index()["nodes"]
    for curriculum in shipped_curricula().values():
        if curriculum.method != f"smc-{method}":
            continue
        for name in curriculum.targets:
            node = curriculum.node(name)
            if node.task == target and all(u in held for u in node.uses):
                return [smc for used in node.uses for smc in pretrained_names(used)]
    return None


def offer_for(target: str, method: str, library: Mapping[str, Any]) -> str | list[str] | None:
    """What a cell of ``method`` offers ``target`` (``learn_concept``'s ``offer``): ``"none"`` (base), ``"auto"``,
    or curr's / canon's pretrained SMCs less those the held-out rule bars; ``None`` where the pretrained library has
    no such entry for the target (the cell is not run)."""
    from sb3_smc.fewshot import held_out

    if method in ("base", "auto"):
        return {"base": "none", "auto": "auto"}[method]
    allowed = set(held_out(library, (target,)))
    offer = [name for name in children_of(target, method) or [] if name in allowed]  # none trained on its worlds
    return offer or None


def _cell(out: Path, target: str, method: str, worlds: int | None, seed: int) -> Path:
    return out / "records" / target / f"{method}-n{worlds or 'all'}@{seed}.json"


def run_few_shot(out: str | Path, *, targets: Sequence[str] = FEW_SHOT_TARGETS,
                 worlds: Sequence[int | None] = FEW_SHOT_WORLDS, methods: Sequence[str] = FEW_SHOT_METHODS,
                 seeds: int = 5, lean_update: bool = True, printer: Callable[[str], None] = print,
                 **settings: Any) -> Path:
    """Run every cell not recorded yet (targets x worlds x methods x seeds, in that order of nesting: the smallest
    ``N`` of a target first), then write ``results.csv``. ``settings``: :func:`~sb3_smc.fewshot.learn_concept`'s
    (``total_timesteps`` ...)."""
    from pixelworld_env.datasets import catalog
    from sb3_smc.library import SMCLibrary
    from sb3_smc.library.pretrained import pretrained_root

    unknown = sorted(set(methods) - set(FEW_SHOT_METHODS))
    if unknown:
        raise SMCError(f"few-shot methods are {FEW_SHOT_METHODS}, got {unknown}")
    out = Path(out)
    library = SMCLibrary.load(pretrained_root())
    cells = [(t, m, n, s) for t in targets for n in worlds for m in methods for s in range(seeds)
             if m != "cnn" or catalog.dataset(t).kind == "classification"]
    todo = [c for c in cells if not _cell(out, *c).is_file()]
    printer(f"{out}: {len(cells)} cells, {len(cells) - len(todo)} recorded, {len(todo)} to run")
    started, done = time.monotonic(), 0
    for (target, method, n), group in groupby(todo, key=lambda cell: cell[:3]):
        seeds_left = [seed for *_, seed in group]
        records = group_records(target, method, n, seeds_left, library, lean_update=lean_update, **settings)
        for trained, record in enumerate(records, 1):
            atomic_write(_cell(out, target, method, n, record["seed"]), json.dumps(record, indent=1) + "\n")
            _progress(printer, done + trained, len(todo), started,
                      f"{target} {method} N={n or 'all'} seed {record['seed']}", record_score(record))
        done += len(seeds_left)  # a group without an entry in the pretrained library is skipped
    return write_results(out)


def group_records(target: str, method: str, worlds: int | None, seeds: Sequence[int], library: SMCLibrary, *,
                  lean_update: bool = True, **settings: Any) -> Iterator[dict[str, Any]]:
    """Train one group of the table (a target, a method, ``N`` and its seeds) as :func:`run_few_shot` does and yield
    each seed's record as it is done: the CNN seed by seed; the SMCs' seeds together in one
    :func:`~sb3_smc.fewshot.learn_concepts` call, then one by one; nothing where ``library`` has no entry of
    ``method`` for ``target``."""
    from sb3_smc.experiments.cnn import train_cnn
    from sb3_smc.fewshot import learn_concepts

    cell = {"target": target, "method": method, "train_worlds": worlds}
    if method == "cnn":
        for seed in seeds:
            yield {**cell, "seed": seed, "cnn": train_cnn(target, seed, train_worlds=worlds).to_dict()}
        return
    offer = offer_for(target, method, library)
    if offer is None:
        return
    learned = learn_concepts(f"PW-{target}-v0", seeds=seeds, library=library, offer=offer, train_worlds=worlds,
                             names=[f"{target}-{method}-n{worlds or 'all'}@{seed}" for seed in seeds],
                             lean_update=lean_update, **settings)
    for seed, one in zip(seeds, learned, strict=True):
        smc = one.smc
        assert smc.record is not None and smc.spec is not None and smc.test_score is not None  # trained and tested
        yield {**cell, "seed": seed, "offered": list(one.offered), "spec": smc.spec.to_dict(),
               "record": smc.record.to_dict(), "evaluations": [e.to_dict() for e in smc.evaluations],
               "choice": one.choice.scores if one.choice is not None else None}


def record_score(record: Mapping[str, Any]) -> float:
    """A cell record's test score (:func:`group_records`)."""
    if record["method"] == "cnn":
        return float(record["cnn"]["test_score"])
    (test,) = [e for e in record["evaluations"] if e["split"] == "test"]
    return float(test["score"])


def record_training_s(record: Mapping[str, Any]) -> float:
    """A cell record's training seconds (:func:`group_records`)."""
    return float(record["cnn" if record["method"] == "cnn" else "record"]["wall_time_s"])


def _progress(printer: Callable[[str], None], done: int, total: int, started: float, cell: str, score: float) -> None:
    rate = (time.monotonic() - started) / done
    printer(f"[{done}/{total}] {cell}: test {score:.3f} (about {rate * (total - done) / 60:.0f} min left)")


def results_rows(out: str | Path) -> list[dict[str, Any]]:
    """One row a recorded cell of the table in ``out`` (its records), sorted."""
    from pixelworld_env.datasets import catalog

    rows = []
    for file in sorted(Path(out).glob("records/*/*.json")):
        data = json.loads(file.read_text(encoding="utf-8"))
        info = catalog.dataset(data["target"])
        row = {"target": data["target"], "kind": info.kind, "category": info.category, "method": data["method"],
               "train_worlds": data["train_worlds"] or "all", "seed": data["seed"]}
        cnn = data["method"] == "cnn"
        rows.append({**row, "test_score": record_score(data), "offered": 0 if cnn else len(data["offered"]),
                     "primitive_steps": 0 if cnn else data["record"]["primitive_steps"]})
    return sorted(rows, key=lambda r: (r["target"], r["method"], str(r["train_worlds"]), r["seed"]))


def results_csv(out: str | Path) -> str:
    """The text of ``<out>/results.csv``: one row a recorded cell (:func:`results_rows`)."""
    return csv_text(results_rows(out), FIELDS)


def write_results(out: str | Path) -> Path:
    """``<out>/results.csv`` written from the records in ``out`` (:func:`results_csv`)."""
    return atomic_write(Path(out) / "results.csv", results_csv(out))
