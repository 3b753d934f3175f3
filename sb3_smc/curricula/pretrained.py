"""Building a pretrained library (:mod:`sb3_smc.library.pretrained`) from the libraries of curriculum or experiment
runs: the two best seeds of each lower-level node of the given curricula, evaluated on the test split and stored
compact, with the index that loads them by curriculum name (``tools/build_pretrained.py``)."""

from __future__ import annotations

import json
import tempfile
from collections.abc import Sequence
from pathlib import Path

from pixelworld_env.atomic import atomic_write, replace_directory
from sb3_smc.curricula.format import Curriculum
from sb3_smc.curricula.jobs import job_name, node_of, node_records, rank_seeds
from sb3_smc.curricula.run_directory import read_settings
from sb3_smc.curricula.shipped import resolve_curriculum, shipped_curricula
from sb3_smc.library import SMCLibrary, storage
from sb3_smc.library.errors import LibraryError
from sb3_smc.library.pretrained import INDEX, pretrained_index, pretrained_root

__all__ = ["PRETRAINED_SEEDS", "build_pretrained", "compact_model", "lower_level"]

PRETRAINED_SEEDS = 2
"""Seeds shipped per node: the two best, as the paper's SMC filter gives a caller (docs/design.md, "Curricula:
reuse of the best seeds")."""
_OPTIMIZER_STATE = "policy.optimizer/state/"


def lower_level(curriculum: Curriculum) -> list[str]:
    """The nodes a curriculum's targets call (its lower-level SMCs), in the order of its file."""
    used = {name for target in curriculum.targets for name in curriculum.node(target).uses}
    return [node.name for node in curriculum.nodes if node.name in used]


def compact_model(data: bytes, where: str = "model") -> bytes:
    """A model file's bytes (:mod:`sb3_smc.library.model_file`) without the optimiser's running state (its parameter
    groups kept: the model still loads and trains), the weights untouched."""
    from safetensors.torch import load, save

    from sb3_smc.library.model_file import METADATA_KEY, check_model_bytes

    metadata = check_model_bytes(data, None, where)
    tensors = {key: value for key, value in load(data).items() if not key.startswith(_OPTIMIZER_STATE)}
    metadata["optimizer"] = {**metadata["optimizer"], "scalars": {}}
    return save(tensors, metadata={METADATA_KEY: json.dumps(metadata, sort_keys=True, allow_nan=False)})


def build_pretrained(runs: Sequence[str | Path], curricula: Sequence[str | Curriculum],
                     out: str | Path | None = None, *, repeats: int = 10, finished_only: bool = False,
                     trust: bool = False) -> Path:
    """Collect the two best seeds of every lower-level node of ``curricula`` from the libraries of ``runs`` (run
    directories holding ``library/``), evaluate each on its test split (``repeats``, seed 0), and write them, with
    what ``out`` already holds (default: the package's pretrained library), as a compact library to ``out``.

    A node is ranked over all its seeds (the trainer's rule: best selected training return, ties to the lower
    seed), so every seed of the run (``run.json``'s ``seeds``) must be in one run's library. A node already in
    ``out`` is replaced by its new best seeds, unless it holds those seeds with the same specs (the same SMCs), tested
    with the same ``repeats``; the others are kept byte for byte; ``finished_only`` leaves out,
    instead of refusing, the nodes whose seeds are not all trained yet (a run still going: its finished nodes now,
    the rest in a later build). ``out`` must be missing, empty or a library. The index
    (:data:`~sb3_smc.library.pretrained.INDEX`) then lists ``curricula``, the curricula it listed before and every
    shipped curriculum whose lower-level nodes are all held. ``trust``: ``out`` is an old library of pickled models
    that you trust (:meth:`SMCLibrary.load`'s ``trust``); it is written in the current format.
    """
    from sb3_smc.learning.evaluation import evaluate  # loads torch and SB3: only when a library is built

    resolved = [resolve_curriculum(c) for c in curricula]
    target = Path(out) if out is not None else pretrained_root()
    if target.exists() and (not target.is_dir() or (any(target.iterdir())
                                                    and not (target / storage.MANIFEST).is_file())):
        raise LibraryError(f"refusing to write the pretrained library to {target}: it is a file or a non-empty "
                           f"directory without {storage.MANIFEST} (not an SMC library)")
    runs_ = [Path(run) for run in runs]
    entries = {run: storage.checked_entries(run / "library")[0] for run in runs_}
    chosen: list[tuple[str, Path, list[str]]] = []
    ranked_among: dict[str, int] = {}
    for node in dict.fromkeys(n for c in resolved for n in lower_level(c)):
        found = [(run, node_records(held, node)) for run, held in entries.items()]
        run, records = max(found, key=lambda item: len(item[1]))
        settings = read_settings(run)
        if settings is None:
            raise LibraryError(f"{run} holds no run (no run.json); build_pretrained takes run directories of "
                               "sb3-smc train or experiment")
        seeds = settings["seeds"]
        trained = {seed: record for seed, record in records.items() if record is not None}
        if len(trained) != seeds:
            if finished_only:
                continue
            raise LibraryError(f"node {node!r}: {run / 'library'} holds {len(trained)} of the run's {seeds} seeds "
                               "with training records; the two best can only be chosen among all of them")
        chosen.append((node, run, [job_name(node, seed) for seed in rank_seeds(trained)[:PRETRAINED_SEEDS]]))
        ranked_among[node] = seeds
    held = target / storage.MANIFEST
    before = pretrained_index(target) if (target / INDEX).is_file() else {"curricula": {}, "seeds": {}}
    library = SMCLibrary.load(target, trust=trust) if held.is_file() else SMCLibrary()
    previous = storage.checked_entries(target)[0] if held.is_file() else {}

    def held_alike(node: str, run: Path, names: list[str]) -> bool:
        """Whether ``out`` holds the same best seeds of ``node`` with the same specs and the same update (a run that
        copied them, or trained them again: the same SMCs, training being deterministic), tested as this build would
        test them: kept as they are."""
        mine = {name for name in previous if node_of(name) == node}
        return mine == set(names) and all(
            previous[name].spec == entries[run][name].spec
            and _lean(previous[name]) == _lean(entries[run][name])
            and any((e.split, e.repeats, e.evaluation_seed) == ("test", repeats, 0) for e in library[name].evaluations)
            for name in names)

    chosen = [(node, run, names) for node, run, names in chosen if not held_alike(node, run, names)]
    rebuilt = {name for _, _, names in chosen for name in names}
    for node, run, names in chosen:
        for stale in [name for name in library.names if node_of(name) == node]:
            library.remove(stale)
        loaded = SMCLibrary.load(run / "library", names=names)
        for name in names:
            smc = loaded[name]
            evaluate(smc, repeats=repeats, seed=0, record_cells=False)
            library.add(smc)
    models = {}
    for name in library.names:
        if name in previous and name not in rebuilt and not storage.is_pickled(previous[name]):
            models[name] = storage.check_model_file(target, name, previous[name])  # kept as it was, byte for byte
        else:
            models[name] = compact_model(storage.model_bytes(library[name].model), f"SMC {name!r}")
    target.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=target.parent) as tmp:
        staged = Path(tmp) / "library"
        storage.save_library(staged, {name: library.entry(name) for name in library.names}, models, {})
        index = _index(library.names, before["curricula"], resolved, {**before["seeds"], **ranked_among})
        atomic_write(staged / INDEX, json.dumps(index, indent=1) + "\n")
        SMCLibrary.load(staged)  # the compact copy loads and checks out before it replaces anything
        pretrained_index(staged)
        (staged / storage.LOCK).unlink(missing_ok=True)
        replace_directory(staged, target)
    return target


def _index(names: Sequence[str], before: dict[str, list[str]], built: Sequence[Curriculum],
           ranked_among: dict[str, int]) -> dict:
    """The index of a library holding ``names``: the curricula of ``before``, ``built`` and the shipped ones whose
    lower-level nodes it all holds, each node's SMCs, the number of seeds each node's were ranked among, and the
    curricula whose lower-level nodes it holds only some of."""
    nodes: dict[str, list[str]] = {}
    for name in names:
        nodes.setdefault(node_of(name), []).append(name)
    wanted = {**{name: lower_level(c) for name, c in shipped_curricula().items()}, **before,
              **{c.name: lower_level(c) for c in built}}
    curricula = {name: lower for name, lower in wanted.items() if lower and set(lower) <= set(nodes)}
    partial = {name: lower for name, lower in wanted.items() if set(lower) & set(nodes) and name not in curricula}
    return {"curricula": curricula, "nodes": nodes, "seeds": {node: ranked_among[node] for node in nodes},
            "partial": partial}


def _lean(entry: storage.LibraryEntry) -> bool:
    """Whether a library entry's SMC was trained with the lean update (its record says so)."""
    return entry.record is not None and entry.record.lean_update
