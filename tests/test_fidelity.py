"""Concept and generator semantics against the 8,700 environments of the original AAAI-18 generator."""

from __future__ import annotations

from functools import cache
from pathlib import Path

import pytest

from pixelworld_env import Concept, Scene
from pixelworld_env.definitions import DefinitionSet, load_definitions
from tests.conftest import REFERENCE, read_samples, require_reference, sample_files

FILES = sample_files()


@cache
def definitions() -> DefinitionSet:
    return load_definitions(sorted((require_reference() / "aaai18" / "DATA").glob("*.datasets")))


def test_reference_is_complete() -> None:
    require_reference()
    assert len(FILES) == 126, f"expected 126 decoded dataset files under {REFERENCE}"
    total = sum(len(read_samples(path)[1]) for path in FILES)
    assert total == 8700


@pytest.mark.parametrize("path", FILES, ids=[p.name.removesuffix(".jsonl.gz") for p in FILES])
def test_concept_reproduces_original_labels(path: Path) -> None:
    defs = definitions()
    header, samples = read_samples(path)
    dataset = defs.datasets[header["dataset"]]
    concept = Concept(defs.concepts[dataset.concept].logic, defs.macros)
    generators = {g: Concept(defs.generators[g].logic, defs.macros, dir_above_quirk=True)
                  for g in dataset.generators}
    for sample in samples:
        scene = Scene.from_dict(sample)
        truth = concept.holds(scene)
        if header["kind"] == "classification":
            assert truth == bool(sample["label"]), f"sample {sample['index']}: label {sample['label']}"
        else:
            assert not truth, f"sample {sample['index']}: the goal holds in the initial state"
        explained = {name for name, generator in generators.items() if generator.holds(scene)}
        assert set(sample["generators_consistent"]) <= explained, f"sample {sample['index']}"
