"""The paper's curricula, shipped as YAML in ``sb3_smc/curricula/data/`` and derived from the catalog.

One file per original curriculum file (``con1-cl``, ``con2-cl``, ``obj-con2-canon-cl``, ...: the flat baselines of
smc-base, the hand-designed smc-curr and the canonical smc-canon curricula) and one ``<name>-noprim`` variant per
two-level file (the paper's noprim ablation), plus the curricula sb3-smc designed
(:mod:`sb3_smc.curricula.designed`: ``pushable``). Naming:

* a flat (level-1) node is named after its dataset and trains it with the primitive moves; every curriculum that
  uses the dataset as a lower-level SMC names the same node, so it is trained once per seed in a run directory
  (the original's 68 lower-level (experiment group x dataset) references are 62 such nodes: the same dataset
  trained flat in two groups is the same training);
* a two-level node is named ``<curriculum>/<entry>`` (the original entry name) and uses the flat nodes of its
  entry's lower-level SMCs, in the original order.

Regenerate after a catalog change: ``python -m sb3_smc.curricula`` (a test checks the files equal what
this module writes).
"""

from __future__ import annotations

import argparse
import difflib
from importlib import resources
from pathlib import Path

from sb3_smc.curricula.designed import designed_curricula
from sb3_smc.curricula.format import Curriculum, CurriculumError, Node, load_curriculum, parse_curriculum

__all__ = ["DATA", "build_shipped", "resolve_curriculum", "shipped_curricula", "shipped_curriculum", "write_shipped"]

DATA = "data"
CANON_SUFFIX = "_canon"
INTENDED_SUFFIX = "-intended"
"""A canonical entry that trains another dataset than the one it is named after is shipped twice: as written
(not a target: its training is that of the other dataset's entry) and as ``<entry>-intended`` on its own dataset."""
HEADER = ("# sb3-smc curriculum (format: docs/curricula.md). Generated from the catalog by\n"
          "# `python -m sb3_smc.curricula`; do not edit by hand.\n")


def _methods() -> dict[str, tuple[str, str]]:
    """Curriculum file stem -> (method, goal) of the experiment groups that use it (noprim groups aside)."""
    from pixelworld_env.datasets import catalog

    out: dict[str, tuple[str, str]] = {}
    for group in catalog.curricula().values():
        if not group.noprim and group.goal != "bring-about-direct":
            out.setdefault(group.curriculum, (group.method, group.goal))
    return out


def _intended_dataset(entry: str, dataset: str) -> str | None:
    """The dataset a canonical entry ``<dataset>_canon`` is named after when it trains another one (the original
    file's ``cl_self-touches-container_vs_corner_canon`` trains ``..._vs_noncontainer``), else ``None``."""
    from pixelworld_env.datasets import catalog

    named = entry.removesuffix(CANON_SUFFIX)
    if named in (entry, dataset) or named not in catalog.dataset_names():
        return None
    return named


def build_shipped() -> dict[str, Curriculum]:
    """Every shipped curriculum, built from the catalog (name -> curriculum)."""
    from pixelworld_env.datasets import catalog

    methods = _methods()
    out: dict[str, Curriculum] = {}
    for stem, entries in catalog.curriculum_files().items():
        method, goal = methods.get(stem, ("smc-base", "bring-about-direct"))
        two_level = any(entry.level == 2 for entry in entries)
        variants = [(stem, True), (f"{stem}-noprim", False)] if two_level else [(stem, True)]
        for name, primitives in variants:
            flat: dict[str, Node] = {}
            upper: list[Node] = []
            as_written: list[Node] = []
            for entry in entries:
                if entry.level == 1:
                    flat.setdefault(entry.dataset, Node(entry.dataset, entry.dataset))
                    continue
                uses = tuple(dict.fromkeys(smc.dataset for smc in entry.lower_level))
                for dataset in uses:
                    flat.setdefault(dataset, Node(dataset, dataset))
                node = Node(f"{name}/{entry.name}", entry.dataset, uses, include_primitives=primitives)
                intended = _intended_dataset(entry.name, entry.dataset)
                if intended is None:
                    upper.append(node)
                    continue
                # kept as written (a second training of another entry's dataset), but the target trained is the
                # evident intent: the same lower-level SMCs on the dataset the entry is named after
                as_written.append(node)
                upper.append(Node(f"{name}/{entry.name}{INTENDED_SUFFIX}", intended, uses,
                                  include_primitives=primitives))
            targets = [n.name for n in upper] if two_level else list(flat)
            upper.extend(as_written)
            lists = sorted({entry.smc_list for entry in entries if entry.smc_list})
            description = (f"{method} ({goal}) from the AAAI-18 curriculum file {stem}.curriculum"
                           + (f"; canonical SMC lists {', '.join(lists)}" if lists else "")
                           + ("; noprim: the two-level nodes have no primitive moves" if not primitives else ""))
            out[name] = Curriculum(name=name, nodes=(*flat.values(), *upper), targets=tuple(targets),
                                   method=method + ("-noprim" if not primitives else ""), description=description,
                                   source=f"shipped curriculum {name!r}")
    out.update(designed_curricula())
    return dict(sorted(out.items()))


def render(curriculum: Curriculum) -> str:
    return HEADER + curriculum.to_yaml()


def write_shipped(directory: str | Path | None = None) -> list[Path]:
    """Write every shipped curriculum as ``<name>.yml`` into ``directory`` (default: the package's data folder)."""
    from pixelworld_env.atomic import atomic_write

    folder = Path(directory) if directory is not None else Path(__file__).parent / DATA
    built = build_shipped()
    stale = [p for p in folder.glob("*.yml") if p.stem not in built]
    for path in stale:
        path.unlink()
    return [atomic_write(folder / f"{name}.yml", render(c)) for name, c in built.items()]


def shipped_curricula() -> dict[str, Curriculum]:
    """Every shipped curriculum, read from the package's YAML files (name -> curriculum)."""
    folder = resources.files("sb3_smc.curricula").joinpath(DATA)
    out = {}
    for item in sorted(folder.iterdir(), key=lambda p: p.name):
        if item.name.endswith(".yml"):
            curriculum = parse_curriculum(item.read_text(encoding="utf-8"), f"sb3_smc/curricula/data/{item.name}")
            out[curriculum.name] = curriculum
    return dict(sorted(out.items()))


def shipped_curriculum(name: str) -> Curriculum:
    """The shipped curriculum ``name`` (``CurriculumError`` with close names otherwise)."""
    curricula = shipped_curricula()
    if name not in curricula:
        close = difflib.get_close_matches(name, list(curricula), n=3, cutoff=0.5)
        hint = f"; did you mean {' or '.join(repr(c) for c in close)}?" if close else \
            f" (shipped: {', '.join(curricula)})"
        raise CurriculumError(f"no shipped curriculum named {name!r}{hint}; a path to a .yml file also works")
    return curricula[name]



def resolve_curriculum(curriculum: str | Path | Curriculum) -> Curriculum:
    """A curriculum object, a path to a curriculum file, or the name of a shipped curriculum."""
    if isinstance(curriculum, Curriculum):
        return curriculum
    text = str(curriculum)
    if text.endswith((".yml", ".yaml")) or Path(text).is_file():
        return load_curriculum(text)
    return shipped_curriculum(text)


def main() -> None:
    parser = argparse.ArgumentParser(description="Write the shipped curricula (sb3_smc/curricula/data/*.yml).")
    parser.add_argument("directory", nargs="?", default=None)
    for path in write_shipped(parser.parse_args().directory):
        print(f"wrote {path}")
