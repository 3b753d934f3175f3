"""The project catalog: contents against the reference catalog, build idempotence, API behaviour."""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path

import pytest

from pixelworld_env.concepts import Concept, ConceptError, expand, parse
from pixelworld_env.datasets import catalog
from tests.helpers import REFERENCE, import_tool, require_reference

pytestmark = pytest.mark.reference  # reads the original data: the reference, or the fixture

#: The three generators of bfaw-search.generators that name the undefined `potential-container`.
BROKEN_GENERATORS = {
    "bfaw-self-and-two-potential-containers-in-nontarget",
    "bfaw-self-and-two-potential-containers-in-left-nontarget",
    "bfaw-self-and-two-potential-containers-in-right-nontarget",
}


@pytest.fixture(scope="module")
def ref() -> dict:
    require_reference()
    return json.loads((REFERENCE / "aaai18_catalog.json").read_text(encoding="utf-8"))


def _build_tool():
    return import_tool("build_catalog")


def _released() -> list[str]:
    """The datasets of the AAAI-18 release (the catalog also holds the designed pushable curriculum and the
    bring-about-or-cannot datasets)."""
    return [n for n in catalog.dataset_names() if catalog.dataset(n).category not in ("pushable", "cannot")]


def test_datasets_equal_the_reference_catalog(ref) -> None:
    assert _released() == sorted(d["name"] for d in ref["datasets"])
    for item in ref["datasets"]:
        info = catalog.dataset(item["name"])
        assert info.kind == item["kind"] and info.category == item["category"], info.name
        assert info.concept == item["concept"] and info.concept_logic == item["concept_logic"]
        assert list(info.generators) == [g["name"] for g in item["generators"]]
        assert [catalog.generators()[g] for g in info.generators] == [g["logic"] for g in item["generators"]]
        assert info.settings == item["extra_settings"]
        assert info.source_file == Path(item["source_file"]).name
        assert info.num_samples == 50 and info.num_envs == item["num_envs"]
        assert (info.train_size, info.test_size) == ((50, 50) if info.kind == "classification" else (25, 25))
        assert info.prefix == info.name[:2]


def test_counts() -> None:
    infos = [catalog.dataset(n) for n in _released()]
    assert Counter(i.prefix for i in infos) == {"cl": 47, "ba": 89}
    assert Counter(i.category for i in infos) == {"containment": 55, "objcon": 16, "objects": 54, "search": 11}
    assert {n for n in _released() if catalog.dataset(n).settings} == {
        n for n in _released() if catalog.dataset(n).category == "search"}
    pushable = [catalog.dataset(n) for n in catalog.dataset_names() if catalog.dataset(n).category == "pushable"]
    assert Counter(i.prefix for i in pushable) == {"cl": 6, "ba": 5}
    assert all(i.settings == {"allow_pushable": True} and i.source_file == "pushable.datasets" for i in pushable)
    cannot = [catalog.dataset(n) for n in catalog.dataset_names() if catalog.dataset(n).category == "cannot"]
    assert Counter(i.prefix for i in cannot) == {"bc": 8}
    assert all(i.kind == "bring-about-or-cannot" and (i.train_size, i.test_size) == (50, 50) for i in cannot)
    # 75 concepts and 167 generators of the release, 4 and 16 of the pushable curriculum, 1 generator for cannot
    assert (len(catalog.concepts()), len(catalog.generators())) == (75 + 4, 167 + 16 + 1)


def test_catalog_and_docs_are_what_the_build_writes() -> None:
    require_reference()
    tool = _build_tool()
    for path, text in tool.outputs(REFERENCE).items():
        assert path.read_text(encoding="utf-8") == text, f"{path} is stale: run python tools/build_catalog.py"
    assert tool.main(["--check", "--reference", str(REFERENCE)]) == 0


def test_check_fails_on_a_stale_file_and_a_rebuild_is_idempotent(tmp_path: Path, monkeypatch) -> None:
    require_reference()
    tool = _build_tool()
    monkeypatch.setattr(tool, "CATALOG_PATH", tmp_path / "catalog.json")
    monkeypatch.setattr(tool, "DOCS_PATH", tmp_path / "catalog.md")
    (tmp_path / "catalog.json").write_text("{}\n", encoding="utf-8")
    args = ["--reference", str(REFERENCE)]
    assert tool.main([*args, "--check"]) == 1
    assert tool.main(args) == 0
    first = (tmp_path / "catalog.json").read_bytes(), (tmp_path / "catalog.md").read_bytes()
    assert tool.main(args) == 0 and tool.main([*args, "--check"]) == 0
    assert ((tmp_path / "catalog.json").read_bytes(), (tmp_path / "catalog.md").read_bytes()) == first
    assert tool.main(["--reference", str(tmp_path / "nowhere"), "--check"]) == 2


def test_data_file_format() -> None:
    data = catalog._data()
    assert (data["format"], data["version"]) == ("pixelworld-catalog", 1)
    with pytest.raises(catalog.CatalogError, match="format/version"):
        catalog._validate({**data, "version": 2})
    with pytest.raises(catalog.CatalogError, match="format/version"):
        catalog._validate([])
    with pytest.raises(catalog.CatalogError, match="lacks the sections"):
        catalog._validate({"format": "pixelworld-catalog", "version": 1})


def test_unknown_names_suggest_close_matches() -> None:
    with pytest.raises(catalog.UnknownDatasetError) as info:
        catalog.dataset("cl_self-in-container_vs_noncontainr")
    assert info.value.suggestions[0] == "cl_self-in-container_vs_noncontainer" and len(info.value.suggestions) == 3
    assert "did you mean 'cl_self-in-container_vs_noncontainer'" in str(info.value)
    assert isinstance(info.value, KeyError) and isinstance(info.value, ValueError)
    with pytest.raises(KeyError, match="unknown curriculum entry"):
        catalog.curriculum_entry("con2-canon-class/cl_self-in-container_vs_corner_cano")


def test_concept_pools_cover_every_dataset_once() -> None:
    pools = catalog.concept_pools()
    members = [m for ms in pools.values() for m in ms]
    assert sorted(members) == catalog.dataset_names()
    assert not set(pools) & set(catalog.dataset_names())
    for pool, names in pools.items():
        assert names == tuple(sorted(names))
        infos = [catalog.dataset(n) for n in names]
        assert {i.pool for i in infos} == {pool} and pool == f"{infos[0].prefix}_{infos[0].concept}"
    assert pools["ba_self-in-container"] == tuple(
        n for n in catalog.dataset_names() if n.startswith("ba_self-in-container_from_"))


def test_every_macro_resolves() -> None:
    macros = catalog.macros()
    assert len(macros) == len(catalog.concepts()) + len(catalog.generators())
    assert set(catalog.unresolved_macros()) == BROKEN_GENERATORS
    assert all(names == ("potential-container",) for names in catalog.unresolved_macros().values())
    for name, logic in macros.items():
        if name in BROKEN_GENERATORS:
            with pytest.raises(ConceptError, match="potential-container"):
                Concept(logic, macros)
            continue
        expanded = expand(parse(logic), macros)
        assert not any(c.name in macros for c in expanded.positives), name
        Concept(logic, macros)
    used = {g for n in catalog.dataset_names() for g in catalog.dataset(n).generators}
    assert not used & BROKEN_GENERATORS


def test_experiment_groups_equal_the_reference(ref) -> None:
    groups = catalog.curricula()
    assert list(groups) == sorted(ref["experiments"])
    files = {Path(c["file"]).stem: c for c in ref["curricula"]}
    for name, group in groups.items():
        exp = ref["experiments"][name]
        assert group.curriculum == Path(exp["curriculum_file"]).stem
        assert group.noprim == exp["hierarchy"].startswith("level2-noprim")
        assert group.level == (1 if exp["hierarchy"].startswith("flat") else 2)
        assert group.method == exp["paper_method"].split(" ")[0] or group.goal == "bring-about-direct"
        assert group.num_seeds == 5 and group.smc_filters[-1] == ("two_best", 2)
        entries = files[group.curriculum]["entries"]
        assert [(e.name, e.dataset, e.lower_level) for e in group.entries] == [
            (e["entry"], e["target_dataset"], tuple((s["group"], s["dataset"]) for s in e["lower_level_smcs"]))
            for e in entries]
        assert {catalog.dataset(e.dataset).kind for e in group.entries} == {group.kind}


def test_curriculum_counts_match_the_paper_analysis(ref) -> None:
    files = catalog.curriculum_files()
    canonical = [e for entries in files.values() for e in entries if e.canonical]
    hand = [e for entries in files.values() for e in entries if e.level == 2 and not e.canonical]
    counts = ref["counts"]
    assert len(canonical) == counts["canonical_experiments"]["high_level_entries"] == 51
    assert len({s for e in canonical for s in e.lower_level}) == counts["canonical_experiments"]["low_level_smc_nodes"]
    assert len(hand) == 83 and len({e.dataset for e in hand}) == 51
    assert len({s for e in hand for s in e.lower_level}) == counts["hand_designed_experiments"]["low_level_smc_nodes"]
    level2 = [e for entries in files.values() for e in entries if e.level == 2]
    assert len({s for e in level2 for s in e.lower_level}) == counts["lower_level_smc_nodes_group_x_dataset"]
    assert len({e.dataset for e in level2}) == counts["datasets_trained_as_level2_targets"]
    trained = {e.dataset for g in catalog.curricula().values() for e in g.entries}
    assert sorted(set(_released()) - trained) == counts["datasets_never_trained"]


def test_canonical_smc_lists(ref) -> None:
    lists = catalog.canonical_smc_lists()
    for include in ref["canonical_includes"]:
        assert lists[include["list_name"]] == tuple((s["group"], s["dataset"]) for s in include["smcs"])
    assert {n: len(v) for n, v in lists.items()} == {
        "canonical_containment_curriculum": 13, "canonical_object_curriculum": 11,
        "obj-con2-canon-cl:1": 11, "obj-con2-canon-cl:2": 3, "obj-con2-canon-cl:3": 15}
    for entries in catalog.curriculum_files().values():
        for e in entries:
            assert (e.smc_list is not None) == (e.canonical and e.level == 2)
            if e.smc_list:
                assert e.lower_level == lists[e.smc_list]


def test_curriculum_entry_lookup() -> None:
    entry = catalog.curriculum_entry("con2-canon-class-noprim/cl_self-touches-container_vs_corner_canon")
    assert entry.dataset == "cl_self-touches-container_vs_noncontainer"  # the original file's typo, kept as written
    assert entry.smc_list == "canonical_containment_curriculum" and len(entry.lower_level) == 13
    assert catalog.curriculum_entry("cl_self-touches-container_vs_corner_canon") == entry
    assert str(entry.lower_level[0]) == "con1-class/cl_self-in-left-corner_vs_on-hline"
    bare = catalog.curriculum_entry("ba_self-ontop-object_from_anywhere-on-floor_curr1")
    assert bare.curriculum == "objects2-ba" and bare.level == 2 and not bare.canonical
    with pytest.raises(catalog.UnknownCurriculumEntryError, match="3 curriculum files") as info:
        catalog.curriculum_entry("cl_object-above-floor_vs_no-object")
    assert "objects2-canon-class/cl_object-above-floor_vs_no-object" in str(info.value)
    flat = catalog.curricula()["con1-class"].entry("cl_self-in-left-corner_vs_on-hline")
    assert flat.level == 1 and flat.lower_level == () and flat.smc_list is None
