"""The catalog's concepts and generators against the 8,700 environments of the original AAAI-18 generator."""

from __future__ import annotations

from pathlib import Path

import pytest

from pixelworld_env import Concept, Scene
from pixelworld_env.datasets import catalog
from tests.helpers import REFERENCE, read_samples, require_reference, sample_files

FILES = sample_files()


def test_reference_is_complete() -> None:
    require_reference()
    assert len(FILES) == 126, f"expected 126 decoded dataset files under {REFERENCE}"
    total = sum(len(read_samples(path)[1]) for path in FILES)
    assert total == 8700


@pytest.mark.parametrize("path", FILES, ids=[p.name.removesuffix(".jsonl.gz") for p in FILES])
def test_catalog_concept_reproduces_original_labels(path: Path) -> None:
    """Every label (classification) and every "goal false at the start" (bring-about), and the generators."""
    header, samples = read_samples(path)
    dataset = catalog.dataset(header["dataset"])
    assert dataset.kind == header["kind"].replace("bringabout", "bring-about")
    concept = Concept(dataset.concept_logic)
    generators = {g: Concept(catalog.generators()[g], dir_above_quirk=True) for g in dataset.generators}
    for sample in samples:
        scene = Scene.from_dict(sample)
        truth = concept.holds(scene)
        if dataset.kind == "classification":
            assert truth == bool(sample["label"]), f"sample {sample['index']}: label {sample['label']}"
        else:
            assert not truth, f"sample {sample['index']}: the goal holds in the initial state"
        explained = {name for name, generator in generators.items() if generator.holds(scene)}
        assert set(sample["generators_consistent"]) <= explained, f"sample {sample['index']}"
        assert explained, f"sample {sample['index']} satisfies none of its generators"
