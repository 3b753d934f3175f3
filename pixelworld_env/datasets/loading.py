"""``load_dataset``: the scenes and labels of a catalog dataset (generated on first use, then cached); ``few_worlds``:
the first ``N`` worlds of a training split in its fixed, nested, label-stratified order (``train_worlds=N``)."""

from __future__ import annotations

import hashlib
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from pixelworld_env.core.kinds import Kind
from pixelworld_env.core.scene import Scene
from pixelworld_env.datasets import catalog
from pixelworld_env.datasets.cache import load_or_generate
from pixelworld_env.errors import PixelWorldError
from pixelworld_env.generation.dataset import split as stratified_split
from pixelworld_env.generation.dataset_spec import DatasetSpec
from pixelworld_env.validation import check_int, check_seed

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


def check_train_worlds(train_worlds: Any, split: str) -> int | None:
    """``train_worlds`` of an environment checked before anything is loaded: ``None`` (every world of the split) or
    an integer >= 1 (a bool is not one), and only on the training split: test worlds are never cut."""
    if train_worlds is None:
        return None
    train_worlds = check_int(train_worlds, "train_worlds", 1)
    if split != "train":
        raise PixelWorldError(f"train_worlds={train_worlds} cuts the training split; split={split!r} is never cut "
                              "(evaluate on every test world)")
    return train_worlds


def _order_seed(name: str, label: int) -> int:
    """The seed of a dataset's order of its training worlds of one label: from the name, so a pool's member keeps its
    order whatever the other members are."""
    return int.from_bytes(hashlib.sha256(f"{name}\0{label}".encode()).digest()[:4], "little")


def training_order(datasets: Sequence[Dataset]) -> list[tuple[int, int]]:
    """The fixed order of a task's training worlds, ``(dataset index, scene index)`` pairs: the first ``N`` are its
    ``N`` training worlds (:func:`few_worlds`), so the worlds of 4 are among those of 8, on every machine.

    Each dataset's worlds of each label are shuffled with a seed of the dataset's name and the label (numpy's legacy
    ``RandomState``, stable across versions); the worlds of one label are taken from the datasets in turn (a pool's
    members as even as ``N`` allows); a classification task then alternates its labels, the positive one (1) first,
    so that ``N`` worlds hold ``ceil(N / 2)`` positive and ``floor(N / 2)`` negative ones while both last (an odd
    ``N``: one positive more); a bring-about task has one stream. A world that several members of a pool share comes
    once, where it first comes, so ``N`` worlds are ``N`` different worlds."""
    streams: dict[int, list[tuple[int, int]]] = {}
    for label in sorted({label for d in datasets for label in d.labels}, reverse=True):
        shuffled = []
        for k, dataset in enumerate(datasets):
            members = [i for i, value in enumerate(dataset.labels) if value == label]
            order = np.random.RandomState(_order_seed(dataset.name, label)).permutation(len(members))
            shuffled.append([(k, members[int(j)]) for j in order])
        seen: set[Scene] = set()
        streams[label] = []
        for turn in range(max(map(len, shuffled), default=0)):
            for k, i in (s[turn] for s in shuffled if turn < len(s)):
                if datasets[k].scenes[i] not in seen:  # a pool's members share worlds: each once, where it first comes
                    seen.add(datasets[k].scenes[i])
                    streams[label].append((k, i))
    queues = list(streams.values())
    return [item for turn in range(max(map(len, queues), default=0))
            for item in (q[turn] for q in queues if turn < len(q))]


def few_worlds(datasets: Sequence[Dataset], train_worlds: int | None) -> tuple[list[Scene], list[int]]:
    """The first ``train_worlds`` worlds of :func:`training_order` and their labels (``None``: every world of the
    datasets, in their own order); :class:`PixelWorldError` where the training split has fewer."""
    if train_worlds is None:
        return [s for d in datasets for s in d.scenes], [label for d in datasets for label in d.labels]
    order = training_order(datasets)
    if train_worlds > len(order):
        names = ", ".join(d.name for d in datasets)
        raise PixelWorldError(f"train_worlds={train_worlds}: the training split of {names} has {len(order)} worlds")
    chosen = order[:train_worlds]
    return ([datasets[k].scenes[i] for k, i in chosen], [datasets[k].labels[i] for k, i in chosen])

