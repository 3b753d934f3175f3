"""The pretrained library shipped with the package: the lower-level SMCs of the paper's curricula (the two best seeds
of each node, as a caller of the curriculum gets them), loaded by curriculum name and put on an environment as
actions without training anything::

    library = SMCLibrary.pretrained("search2-canon")       # its 13 canonical SMCs x their 2 best seeds
    env = library.wrap(gym.make("PW-ba_self-in-target-container_from_nontarget-container-v0"), library.names)

Each SMC keeps its training spec, training record and test evaluation (the paper's protocol: every test environment
10 times, seed 0). The models are compact: the optimiser state that only further training would use is dropped and
the archive compressed; the policy's weights are exactly those trained, so an SMC acts as it did in its run.
:func:`build_pretrained` collects them from the libraries of experiment or curriculum runs
(``tools/build_pretrained.py``); ``docs/library.md`` lists what is shipped and its size.
"""

from __future__ import annotations

import io
import json
import tempfile
import zipfile
from collections.abc import Sequence
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING

from pixelworld_env.atomic import atomic_write, replace_directory
from sb3_smc.curricula.format import SEED_SEPARATOR
from sb3_smc.curricula.jobs import job_name, node_of, rank_seeds
from sb3_smc.curricula.run_directory import read_settings
from sb3_smc.library import storage
from sb3_smc.library.errors import LibraryError, suggest
from sb3_smc.library.library import SMCLibrary

if TYPE_CHECKING:
    from sb3_smc.curricula.format import Curriculum

__all__ = ["PRETRAINED_SEEDS", "build_pretrained", "compact_model", "load_pretrained", "pretrained_curricula",
           "pretrained_names"]

PRETRAINED_SEEDS = 2
"""Seeds shipped per node: the two best, as the paper's SMC filter gives a caller (docs/design.md, "Curricula:
reuse of the best seeds")."""
_OPTIMIZER = "policy.optimizer.pth"


def _root() -> Path:
    return Path(str(resources.files("sb3_smc.library").joinpath("data", "pretrained")))


def _lower_level(curriculum: str | Curriculum) -> list[str]:
    """The nodes a curriculum's targets call (its lower-level SMCs), in the order of its file."""
    from sb3_smc.curricula import shipped_curriculum

    shipped = shipped_curriculum(curriculum) if isinstance(curriculum, str) else curriculum
    used = {name for target in shipped.targets for name in shipped.node(target).uses}
    return [node.name for node in shipped.nodes if node.name in used]


def _shipped_entries(root: Path) -> dict[str, storage.LibraryEntry]:
    if not (root / storage.MANIFEST).is_file():
        return {}
    manifest, where = storage.read_manifest(root)
    return storage.check_manifest(manifest, where)


def pretrained_curricula(root: str | Path | None = None) -> list[str]:
    """The shipped curricula whose every lower-level node is in the pretrained library (``root``: another
    pretrained library directory than the package's)."""
    from sb3_smc.curricula import shipped_curricula

    nodes = {node_of(name) for name in _shipped_entries(_root() if root is None else Path(root))}
    out = []
    for name, curriculum in shipped_curricula().items():
        lower = _lower_level(curriculum)
        if curriculum.targets and lower and set(lower) <= nodes:
            out.append(name)
    return out


def pretrained_names(curriculum: str, root: str | Path | None = None) -> list[str]:
    """The SMC names (``<node>@<seed>``) the pretrained library holds for ``curriculum``'s lower-level nodes."""
    from sb3_smc.curricula import shipped_curricula

    root = _root() if root is None else Path(root)
    entries = _shipped_entries(root)
    shipped = shipped_curricula()
    lower = set(_lower_level(shipped[curriculum])) if curriculum in shipped else set()
    held = [name for name in entries if node_of(name) in lower]
    if not lower or {node_of(name) for name in held} != lower:
        available = pretrained_curricula(root)
        raise LibraryError(f"no pretrained SMCs for curriculum {curriculum!r}"
                           f"{suggest(curriculum, available, ' (none is shipped yet)')}; pretrained: "
                           f"{', '.join(available) or 'none'}")
    return held


def load_pretrained(curriculum: str, root: str | Path | None = None) -> SMCLibrary:
    """The pretrained lower-level SMCs of ``curriculum`` (a shipped curriculum's name, e.g. ``"search2-canon"``;
    :func:`pretrained_curricula` lists them), as a library (checked like any other: checksums, layouts)."""
    root = _root() if root is None else Path(root)
    return SMCLibrary.load(root, names=pretrained_names(curriculum, root))


def compact_model(path: Path) -> None:
    """Rewrite the SB3 archive ``path`` without the optimiser's running state (an empty state of the same
    parameter groups: loading still matches the model's parameters) and compressed, atomically."""
    import torch

    buffer = io.BytesIO()
    with zipfile.ZipFile(path) as source, zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED, compresslevel=9) as out:
        for item in source.infolist():
            data = source.read(item.filename)
            if item.filename == _OPTIMIZER:
                state = torch.load(io.BytesIO(data), map_location="cpu", weights_only=True)
                state["state"] = {}
                stripped = io.BytesIO()
                torch.save(state, stripped)
                data = stripped.getvalue()
            out.writestr(item.filename, data)
    atomic_write(path, buffer.getvalue())


def build_pretrained(runs: Sequence[str | Path], curricula: Sequence[str | Curriculum],
                     out: str | Path | None = None, *, repeats: int = 10) -> Path:
    """Collect the two best seeds of every lower-level node of ``curricula`` from the libraries of ``runs`` (run
    directories holding ``library/``), evaluate each on its test split (``repeats``, seed 0), and write them, with
    what ``out`` already holds (default: the package's pretrained library), as a compact library to ``out``.

    A node is ranked over all its seeds (the trainer's rule: best selected training return, ties to the lower
    seed), so every seed of the run (``run.json``'s ``seeds``) must be in one run's library. A node already in
    ``out`` is replaced by its new best seeds. ``out`` must be missing, empty or a library.
    """
    from sb3_smc.evaluation import evaluate

    target = Path(out) if out is not None else _root()
    if target.exists() and (not target.is_dir() or (any(target.iterdir())
                                                    and not (target / storage.MANIFEST).is_file())):
        raise LibraryError(f"refusing to write the pretrained library to {target}: it is a file or a non-empty "
                           f"directory without {storage.MANIFEST} (not an SMC library)")
    runs_ = [Path(run) for run in runs]
    entries = {run: storage.check_manifest(*storage.read_manifest(run / "library")) for run in runs_}
    chosen: list[tuple[str, Path, list[str]]] = []
    for node in dict.fromkeys(n for c in curricula for n in _lower_level(c)):
        found = [(run, {int(name.rpartition(SEED_SEPARATOR)[2]): entry.record for name, entry in held.items()
                        if node_of(name) == node}) for run, held in entries.items()]
        run, records = max(found, key=lambda item: len(item[1]))
        settings = read_settings(run)
        if settings is None:
            raise LibraryError(f"{run} holds no run (no run.json); build_pretrained takes run directories of "
                               "sb3-smc train or experiment")
        seeds = settings["seeds"]
        trained = {seed: record for seed, record in records.items() if record is not None}
        if len(trained) != seeds:
            raise LibraryError(f"node {node!r}: {run / 'library'} holds {len(trained)} of the run's {seeds} seeds "
                               "with training records; the two best can only be chosen among all of them")
        chosen.append((node, run, [job_name(node, seed) for seed in rank_seeds(trained)[:PRETRAINED_SEEDS]]))
    library = SMCLibrary.load(target) if (target / storage.MANIFEST).is_file() else SMCLibrary()
    for node, run, names in chosen:
        for stale in [name for name in library.names if node_of(name) == node]:
            library.remove(stale)
        loaded = SMCLibrary.load(run / "library", names=names)
        for name in names:
            smc = loaded[name]
            evaluate(smc, repeats=repeats, seed=0, record_cells=False)
            library.add(smc)
    target.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=target.parent) as tmp:
        staged = library.save(Path(tmp) / "library")
        manifest = json.loads((staged / storage.MANIFEST).read_text(encoding="utf-8"))
        for entry in manifest["smcs"].values():
            compact_model(staged / entry["model"])
            entry["sha256"] = storage.sha256(staged / entry["model"])
        atomic_write(staged / storage.MANIFEST, json.dumps(manifest, indent=2, allow_nan=False) + "\n")
        SMCLibrary.load(staged)  # the compact copy loads and checks out before it replaces anything
        replace_directory(staged, target)
    return target
