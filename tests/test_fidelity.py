"""The catalog's concepts and generators against the 8,700 environments of the original AAAI-18 generator (the full
reference), or the 1,000 of them the repository carries (the fixture, ``tools/build_fixture.py``)."""

from __future__ import annotations

import collections
import json
from pathlib import Path

import pytest

from pixelworld_env import Concept, Scene
from pixelworld_env.datasets import catalog
from tests.helpers import FIXTURE, REFERENCE, import_tool, read_samples, require_reference, sample_files

pytestmark = pytest.mark.reference

FILES = sample_files()


def test_reference_is_complete() -> None:
    require_reference()
    assert len(FILES) == 126, f"expected 126 decoded dataset files under {REFERENCE}"
    total = sum(len(read_samples(path)[1]) for path in FILES)
    assert total == 8700


def test_fixture_is_what_the_tool_builds_from_the_reference(tmp_path: Path) -> None:
    reference = require_reference()
    tool = import_tool("build_fixture")
    assert tool.main(["--check", "--reference", str(reference)]) == 0
    assert tool.main(["--check", "--reference", str(reference), "--out", str(tmp_path / "other")]) == 1
    assert tool.main(["--reference", str(tmp_path / "nowhere"), "--check"]) == 2


def test_fixture_holds_every_released_dataset() -> None:
    manifest = json.loads((FIXTURE / "manifest.json").read_text(encoding="utf-8"))
    assert (manifest["format"], manifest["version"], manifest["per_label"]) == ("pixelworld-reference-fixture", 1, 4)
    files = sorted((FIXTURE / "samples").glob("*.jsonl.gz"))
    assert len(files) == 125 and len(manifest["sources"]) == 126  # the shape library and 125 datasets
    names = set()
    for path in files:
        header, samples = read_samples(path)
        names.add(header["dataset"])
        counts = collections.Counter(s["label"] for s in samples)
        wanted = {1: 4, 0: 4} if header["kind"] == "classification" else {1: 4}
        assert counts == wanted, path.name
        assert header["source"]["sha256"] == manifest["sources"][path.name]
    assert len(names) == 125 and names <= set(catalog.dataset_names())


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
