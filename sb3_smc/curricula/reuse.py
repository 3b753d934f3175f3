"""SMCs a run takes from a library instead of training them again: a pretrained library (its nodes' best seeds,
ranked among all of a run's seeds) or another run's library.

A job is reused when the library holds its SMC with the very spec this run would train it with (same task, seed,
budget, hyperparameters, children): training is deterministic on the same CPU model, so the copy is what training
would produce. A node whose best seeds a pretrained library holds, ranked among as many seeds as this run has, needs
no other seed: the run's parents call those best seeds, and the node's other jobs are not trained (they count as
skipped).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from sb3_smc.curricula.format import Curriculum
from sb3_smc.curricula.jobs import JobId, node_records, rank_seeds
from sb3_smc.curricula.options import RunOptions
from sb3_smc.library import storage
from sb3_smc.library.errors import LibraryError
from sb3_smc.library.pretrained import INDEX, pretrained_index
from sb3_smc.records import TrainingRecord

if TYPE_CHECKING:
    from sb3_smc.curricula.scheduler import Scheduler

__all__ = ["ReuseLibrary"]


class ReuseLibrary:
    """The SMCs of library ``root`` that a run may reuse (its manifest checked; models are read when copied)."""

    def __init__(self, root: str | Path) -> None:
        self.root = Path(root)
        self.entries = storage.checked_entries(self.root)[0]
        index = pretrained_index(self.root, list(self.entries)) if (self.root / INDEX).is_file() else {"seeds": {}}
        self.ranked_among: dict[str, int] = dict(index["seeds"])
        """Node -> the number of seeds its held (best) seeds were ranked among, for a pretrained library."""

    def best_seeds(self, node: str, seeds: int, k: int) -> list[int] | None:
        """The ``k`` best of a run's ``seeds`` seeds of ``node``, when this pretrained library holds them (ranked
        among as many seeds); ``None`` otherwise."""
        if self.ranked_among.get(node) != seeds:
            return None
        held = {seed: record for seed, record in node_records(self.entries, node).items() if record is not None}
        return rank_seeds(held)[:k] if len(held) >= k else None

    def copy(self, curriculum: Curriculum, job: JobId, children: tuple[str, ...], library: Path, options: RunOptions
             ) -> TrainingRecord | None:
        """Copy ``job`` into the run's ``library`` if this library holds it with the spec the run (``options``) would
        train it with, calling ``children``, and trained with the run's update (lean or not); its training record, or
        ``None`` (nothing copied)."""
        name = str(job)
        entry = self.entries.get(name)
        if entry is None or entry.spec is None or entry.record is None:
            return None
        wanted = options.spec(curriculum.node(job.node), job.seed, children)
        if entry.spec != wanted or entry.record.lean_update != options.lean_update:
            return None
        if storage.is_pickled(entry):
            raise LibraryError(f"{self.root}: SMC {name!r} is stored as a pickled archive (a library of version 4 or "
                               "earlier), which a run does not copy: convert the library first, if you trust it, with "
                               f"sb3-smc library {self.root} --upgrade --trust")
        with storage.locked(self.root, exclusive=False):
            model = storage.check_model_file(self.root, name, entry)
        storage.add_to_library(library, name, storage.entry_json(name, entry.algo, entry.frame_stack, entry.spec,
                                                                 entry.record), model)
        return entry.record

    def reuse(self, scheduler: Scheduler, order: list[str], targets: set[str]) -> set[JobId]:
        """Copy what the run of ``scheduler`` can reuse into its library and its ``records`` (node -> seed -> record,
        those of the jobs done already included), nodes lower levels first (``order``). Nodes whose best seeds are
        known without their other seeds (not ``targets``, whose every seed is evaluated) go into the scheduler's
        ``best_of``; returns their other jobs, which are not to be trained."""
        options, records = scheduler.options, scheduler.records
        skipped: set[JobId] = set()
        for name in order:
            node = scheduler.curriculum.node(name)
            if not all(scheduler.complete(u) for u in node.uses):
                continue  # its children are not known before training: nothing to compare with
            best = None if name in targets else self.best_seeds(name, options.seeds, min(options.k, options.seeds))
            for seed in best if best is not None else range(options.seeds):
                if seed not in records[name]:
                    record = self.copy(scheduler.curriculum, JobId(name, seed), scheduler.children(node),
                                       scheduler.library, options)
                    if record is not None:
                        records[name][seed] = record
            if best is not None and all(seed in records[name] for seed in best):
                scheduler.best_of[name] = best
                skipped |= {JobId(name, seed) for seed in range(options.seeds) if seed not in records[name]}
        return skipped
