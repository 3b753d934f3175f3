"""SMCs a run takes from a library instead of training them again: a pretrained library (its nodes' best seeds,
ranked among all of a run's seeds) or another run's library.

A job is reused when the library holds its SMC with the very spec this run would train it with (same task, seed,
budget, hyperparameters, children): training is deterministic on the same CPU model, so the copy is what training
would produce. A node whose best seeds a pretrained library holds, ranked among as many seeds as this run has, needs
no other seed: the run's parents call those best seeds, and the node's other jobs are not trained (they count as
skipped).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from sb3_smc.curricula.format import Curriculum
from sb3_smc.curricula.jobs import job_name, node_of, node_records, node_spec, rank_seeds
from sb3_smc.library import storage
from sb3_smc.library.pretrained import INDEX, pretrained_index
from sb3_smc.records import TrainingRecord

__all__ = ["ReuseLibrary"]


class ReuseLibrary:
    """The SMCs of library ``root`` that a run may reuse (its manifest checked; models are read when copied)."""

    def __init__(self, root: str | Path) -> None:
        self.root = Path(root)
        self.entries = storage.check_manifest(*storage.read_manifest(self.root))
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

    def copy(self, curriculum: Curriculum, name: str, seed: int, children: tuple[str, ...], library: Path, *,
             timesteps: int | None, algo: str | None, rnn: str | None) -> TrainingRecord | None:
        """Copy job ``name`` (``<node>@<seed>``) into the run's ``library`` if this library holds it with the spec
        the run would train it with; its training record, or ``None`` (nothing copied)."""
        entry = self.entries.get(name)
        if entry is None or entry.spec is None or entry.record is None:
            return None
        wanted = node_spec(curriculum.node(node_of(name)), seed, children, timesteps=timesteps, algo=algo, rnn=rnn)
        if entry.spec != wanted:
            return None
        storage.check_model_file(self.root, name, entry)
        model = (self.root / entry.model).read_bytes()
        storage.add_to_library(library, name, storage.entry_json(name, entry.algo, entry.frame_stack, entry.spec,
                                                                 entry.record), model)
        return entry.record


    def reuse(self, curriculum: Curriculum, order: list[str], targets: set[str], seeds: int, k: int,
              records: dict[str, dict[int, TrainingRecord]], best_of: dict[str, list[int]],
              complete: Callable[[str], bool], children: Callable[[str], tuple[str, ...]], library: Path, *,
              timesteps: int | None, algo: str | None, rnn: str | None) -> set[str]:
        """Copy what the run can reuse into its ``library`` and ``records`` (node -> seed -> record, those of the
        jobs done already included), nodes lower levels first (``order``; ``complete`` and ``children`` are the
        scheduler's: whether a node's jobs that others use are done, the children of a node's jobs). Nodes whose
        best seeds are known without their other seeds (not ``targets``, whose every seed is evaluated) go into
        ``best_of``; returns their other jobs, which are not to be trained."""
        skipped: set[str] = set()
        for node in order:
            if not all(complete(u) for u in curriculum.node(node).uses):
                continue  # its children are not known before training: nothing to compare with
            best = None if node in targets else self.best_seeds(node, seeds, min(k, seeds))
            for seed in best if best is not None else range(seeds):
                if seed not in records[node]:
                    record = self.copy(curriculum, job_name(node, seed), seed, children(node), library,
                                       timesteps=timesteps, algo=algo, rnn=rnn)
                    if record is not None:
                        records[node][seed] = record
            if best is not None and all(seed in records[node] for seed in best):
                best_of[node] = best
                skipped |= {job_name(node, seed) for seed in range(seeds) if seed not in records[node]}
        return skipped
