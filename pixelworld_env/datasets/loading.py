"""``load_dataset``: the scenes and labels of a catalog dataset (generated on first use, then cached)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from pixelworld_env.core.constants import Kind
from pixelworld_env.core.scene import Scene
from pixelworld_env.datasets import catalog
from pixelworld_env.datasets.cache import load_or_generate
from pixelworld_env.errors import PixelWorldError
from pixelworld_env.generation.dataset import split as stratified_split
from pixelworld_env.generation.dataset_spec import DatasetSpec
from pixelworld_env.validation import check_seed

Split = Literal["all", "train", "test"]
SPLITS = ("all", "train", "test")


@dataclass(frozen=True)
class Dataset:
    """One split of a generated dataset."""

    name: str
    kind: Kind
    concept: str
    split: str
    seed: int
    scenes: tuple[Scene, ...]
    labels: tuple[int, ...]

    def __len__(self) -> int:
        return len(self.scenes)


def dataset_spec(name: str) -> DatasetSpec:
    """The generation spec of a catalog dataset."""
    info = catalog.dataset(name)
    macros = catalog.macros()
    return DatasetSpec(
        name=info.name, kind=info.kind, concept=info.concept_logic,
        generators=tuple((g, macros[g]) for g in info.generators), macros=macros, settings=info.settings,
        num_samples=info.num_samples,
    )


def load_dataset(name: str, split: Split = "all", seed: int = 0) -> Dataset:
    """The scenes and labels of dataset ``name`` (``split`` "all", "train" or "test").

    Generated with ``seed`` (an integer in ``[0, 2**63 - 1]``; nothing else is converted) on first use and cached
    on disk (``$PIXELWORLD_CACHE`` or the user cache directory). The train/test split is stratified by label, 50/50,
    with the fixed split seed 521 (docs/design.md, "Sizes and the split").
    """
    if split not in SPLITS:
        raise PixelWorldError(f"split must be one of {SPLITS}, got {split!r}")
    seed = check_seed(seed, "dataset seed")
    info = catalog.dataset(name)
    generated = load_or_generate(dataset_spec(name), seed)
    if split == "all":
        indices: tuple[int, ...] = tuple(range(len(generated.scenes)))
    else:
        train, test = stratified_split(generated.labels)
        indices = train if split == "train" else test
    return Dataset(
        name=name, kind=info.kind, concept=info.concept_logic, split=split, seed=seed,
        scenes=tuple(generated.scenes[i] for i in indices), labels=tuple(generated.labels[i] for i in indices),
    )

