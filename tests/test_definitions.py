"""The definition-file reader: the original AAAI-18 files, curricula, experiment files and error messages."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from pixelworld_env.generation.definitions import DefinitionError, load_definitions
from pixelworld_env.generation.experiment_files import load_experiments
from tests.helpers import REFERENCE, require_reference

pytestmark = pytest.mark.reference  # reads the original data: the reference, or the fixture

AAAI18 = REFERENCE / "aaai18"
DATA = AAAI18 / "DATA"


@pytest.fixture(scope="module")
def ref_catalog() -> dict:
    require_reference()
    return json.loads((REFERENCE / "aaai18_catalog.json").read_text(encoding="utf-8"))


@pytest.fixture(scope="module")
def definitions():
    require_reference()
    return load_definitions(sorted(DATA.glob("*.datasets")) + sorted(DATA.glob("*.curriculum")))


def test_reference_datasets() -> None:
    require_reference()
    defs = load_definitions(sorted(DATA.glob("*.datasets")))
    assert len(defs.datasets) == 136
    kinds = [d.kind for d in defs.datasets.values()]
    assert kinds.count("classification") == 47 and kinds.count("bring-about") == 89
    assert (len(defs.concepts), len(defs.generators), len(defs.files)) == (75, 167, 15)
    # The one key defined twice (same logic up to whitespace, different desc) is recorded, the later one kept.
    [(old, new)] = defs.redefinitions
    assert old.key == new.key == "bfaw-adjacent-object-and-self-on-floor"
    assert (Path(old.source).name, old.line, new.line) == ("bfaw-objects.generators", 52, 184)
    assert old.logic.split() == new.logic.split() and defs.generators[new.key] is new


def test_reference_curricula_equal_the_reference_catalog(definitions, ref_catalog) -> None:
    assert len(ref_catalog["curricula"]) == len(definitions.curricula) == 19
    for curriculum in ref_catalog["curricula"]:
        entries = definitions.curricula[Path(curriculum["file"]).stem]
        assert [e.entry for e in entries] == [e["entry"] for e in curriculum["entries"]], curriculum["file"]
        for mine, ref in zip(entries, curriculum["entries"], strict=True):
            assert mine.dataset == ref["target_dataset"], mine.entry
            assert list(mine.lower_level) == [(s["group"], s["dataset"]) for s in ref["lower_level_smcs"]]
            assert mine.level == ref["level"]
            assert sorted(set(mine.variants)) == sorted(ref["lower_level_variant"])


def test_canonical_files_take_their_lists_from_the_includes(definitions, ref_catalog) -> None:
    includes = {Path(i["file"]).stem: i for i in ref_catalog["canonical_includes"]}
    for stem, list_name in [("con2-cl-canon", "canonical_containment_curriculum"),
                            ("con2-ba-canon", "canonical_containment_curriculum"),
                            ("search2-canon", "canonical_containment_curriculum"),
                            ("objects2-cl-canon", "canonical_object_curriculum"),
                            ("objects2-ba-canon", "canonical_object_curriculum")]:
        entries = definitions.curricula[stem]
        assert {e.list_name for e in entries} == {list_name}
        named = definitions.lists[list_name]
        [ref] = [i for i in includes.values() if i["list_name"] == list_name]
        assert [(s["group"], s["dataset"]) for s in ref["smcs"]] == list(entries[0].lower_level)
        assert len(named.items) == ref["n_smcs"]
    # obj-con2-canon-cl writes its lists into the entries; the canonical typo entry is read as written.
    assert {e.list_name for e in definitions.curricula["obj-con2-canon-cl"]} == {None}
    canon = {e.entry: e for e in definitions.curricula["con2-cl-canon"]}
    typo = canon["cl_self-touches-container_vs_corner_canon"]
    assert typo.dataset == "cl_self-touches-container_vs_noncontainer"


def test_experiment_files(ref_catalog) -> None:
    experiments = load_experiments(sorted(p for p in AAAI18.iterdir() if p.is_file()))
    assert sorted(experiments) == sorted(ref_catalog["experiments"])
    for name, ref in ref_catalog["experiments"].items():
        exp = experiments[name]
        assert Path(exp.curriculum).name == ref["curriculum_file"]
        goal = "c" if ref["goal"].startswith("classification") else "dir" if "direct" in ref["goal"] else "sig"
        assert exp.goal == goal
        assert exp.noprim == ref["hierarchy"].startswith("level2-noprim")
        assert [n for n, _ in exp.smc_filters] == (["one_best", "two_best"] if "one_best" in
                                                    ref["smc_filter_variants"] else ["two_best"])
        assert exp.num_seeds == len(ref["seeds"]) and (exp.num_samples, exp.test_size) == (50, 0.5)
        assert exp.variants[-1] == f"big+{exp.goal}+hand+curr+two_best+gru32_init+npo"
    assert experiments["objects2-dir"].goal_name == "bring-about-direct"
    assert dict(experiments["objects1-sig"].test_schedule) == dict(
        ref_catalog["test_schedule_objects1_ba_testing"]["pairs_train_then_test"])


# -- error messages name the file and the line ---------------------------------------------------------------

GOOD = """\
concepts:
    c1:
        desc: a concept
        logic: "?x container(x) & inside(self,x)"
generators:
    g1:
        logic: "?x container(x)"
datasets:
    cl_one:
        - c1
        - [g1]
"""


def _write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def _error(paths) -> str:
    with pytest.raises(DefinitionError) as info:
        load_definitions(paths)
    return str(info.value)


def test_good_file_loads(tmp_path: Path) -> None:
    defs = load_definitions(_write(tmp_path, "good.datasets", GOOD))
    assert defs.datasets["cl_one"].generators == ("g1",) and defs.macros == {
        "c1": "?x container(x) & inside(self,x)", "g1": "?x container(x)"}


def test_invalid_yaml(tmp_path: Path) -> None:
    path = _write(tmp_path, "bad.datasets", "datasets:\n    cl_one: [c1, [g1]\n    cl_two: x\n")
    message = _error(path)
    assert str(path) in message and "line 3" in message and "invalid YAML" in message


def test_unknown_concept_and_generator(tmp_path: Path) -> None:
    path = _write(tmp_path, "a.datasets", GOOD.replace("- c1\n", "- c2\n"))
    message = _error(path)
    assert f"{path}, line 9" in message and "unknown concept 'c2'" in message
    path = _write(tmp_path, "b.datasets", GOOD.replace("[g1]", "[g1, g9]"))
    message = _error(path)
    assert f"{path}, line 9" in message and "unknown generator 'g9'" in message


def test_concept_without_logic(tmp_path: Path) -> None:
    path = _write(tmp_path, "c.concepts", "concepts:\n\n    c1:\n        desc: no logic here\n")
    message = _error(path)
    assert f"{path}, line 3" in message and "'c1' needs a 'logic' string" in message


def test_circular_include(tmp_path: Path) -> None:
    _write(tmp_path, "a.concepts", "__include__:\n  - b.concepts\nconcepts: {}\n")
    b = _write(tmp_path, "b.concepts", "__include__:\n  - other.concepts\n  - a.concepts\n")
    _write(tmp_path, "other.concepts", "concepts: {}\n")
    message = _error(tmp_path / "a.concepts")
    assert f"{b}, line 3" in message and "circular __include__" in message and "a.concepts -> b.concepts" in message
    message = _error(_write(tmp_path, "self.concepts", "__include__: [self.concepts]\n"))
    assert "self.concepts, line 1" in message and "circular" in message


def test_missing_include(tmp_path: Path) -> None:
    path = _write(tmp_path, "a.concepts", "__include__:\n  - nowhere.concepts\n")
    assert f"{path}, line 2" in _error(path) and "not found" in _error(path)


CURRICULUM = """\
__include__: [good.datasets, lists.include]
curriculum:
    cl_one:
        - cl_one
        - []
    cl_one_curr:
        - cl_one
        - - out/aaai18/group-a/cl_x/big+c+hand+curr+two_best+gru32_init+npo
          - out/aaai18/group-b/ba_y/big+sig+hand+curr+two_best+gru32_init+npo
__gen_curriculum:
    call: +pixelworld.exp_tools:generate_pattern
    kwargs:
        bindings:
            local: +@shared_list
        name: curriculum
        cfg:
            cl_one_canon:
                - cl_one
                - +@local
            cl_one_direct:
                - cl_one
                - +@shared_list
"""
LISTS = "shared_list:\n  - out/aaai18/g/ba_z/big+sig+v\n  - out/aaai18/h/cl_w/big+c+v\nnot_a_list: [[1, 2]]\n"


def _curriculum(tmp_path: Path, text: str) -> Path:
    _write(tmp_path, "good.datasets", GOOD)
    _write(tmp_path, "lists.include", LISTS)
    return _write(tmp_path, "test.curriculum", text)


def test_curriculum_sections_and_generate_pattern(tmp_path: Path) -> None:
    defs = load_definitions(_curriculum(tmp_path, CURRICULUM))
    entries = {e.entry: e for e in defs.curricula["test"]}
    assert list(entries) == ["cl_one", "cl_one_curr", "cl_one_canon", "cl_one_direct"]
    assert entries["cl_one"].level == 1 and entries["cl_one"].lower_level == ()
    assert entries["cl_one_curr"].lower_level == (("group-a", "cl_x"), ("group-b", "ba_y"))
    assert entries["cl_one_curr"].line == 6 and entries["cl_one_curr"].curriculum == "test"
    assert entries["cl_one_canon"].lower_level == (("g", "ba_z"), ("h", "cl_w"))
    assert entries["cl_one_canon"].list_name == entries["cl_one_direct"].list_name == "shared_list"
    assert entries["cl_one_canon"].variants == ("big+sig+v", "big+c+v")


@pytest.mark.parametrize(
    ("old", "new", "line", "words"),
    [
        ("        - cl_one\n        - []\n", "        - cl_one\n", 3, "must be [dataset, [lower-level"),
        ("        - []\n", "        - [a, b]\n", 5, "is not a path"),
        ("        - []\n", "        - [[a]]\n", 5, "must be path strings"),
        ("        - []\n", "        - 7\n", 3, "must be [dataset, [lower-level"),
        ("    cl_one:\n        - cl_one\n", "    cl_one:\n        - cl_nine\n", 3, "unknown dataset 'cl_nine'"),
        ("- +@local", "- +@nowhere", 19, "+@nowhere, which is not a list"),
        ("- +@local", "- +@not_a_list", 19, "+@not_a_list, which is not a list"),
        ("- +@local", "- +@local+[key]", 19, "unsupported reference"),
        ("local: +@shared_list", "local: [a]", 14, "binding 'local' must be +@list_name"),
        ("cl_one_direct:", "cl_one_curr:", 20, "defined twice (first at line 6)"),
    ],
)
def test_malformed_curriculum_entries(tmp_path: Path, old: str, new: str, line: int, words: str) -> None:
    assert old in CURRICULUM
    path = _curriculum(tmp_path, CURRICULUM.replace(old, new, 1))
    message = _error(path)
    assert f"{path}, line {line}" in message and words in message, message


def test_named_list_must_be_in_scope(tmp_path: Path) -> None:
    _curriculum(tmp_path, CURRICULUM)
    other = _write(tmp_path, "other.curriculum",
                   "__include__: [good.datasets]\ncurriculum:\n    e:\n        - cl_one\n        - +@shared_list\n")
    message = _error([tmp_path / "test.curriculum", other])
    assert f"{other}, line 5" in message and "+@shared_list" in message


def test_curriculum_stems_must_be_unique(tmp_path: Path) -> None:
    first = _curriculum(tmp_path, CURRICULUM)
    (tmp_path / "sub").mkdir()
    _write(tmp_path / "sub", "good.datasets", GOOD)
    text = "__include__: [good.datasets]\ncurriculum: {e: [cl_one, []]}\n"
    second = _write(tmp_path / "sub", "test.curriculum", text)
    assert "same stem" in _error([first, second])


def test_malformed_lower_level_path_in_a_named_list(tmp_path: Path) -> None:
    path = _curriculum(tmp_path, CURRICULUM)
    _write(tmp_path, "lists.include", LISTS.replace("out/aaai18/h/cl_w/big+c+v", "cl_w"))
    message = _error(path)
    assert f"{tmp_path / 'lists.include'}, line 3" in message and "'cl_w' is not a path" in message


def test_experiment_file_errors(tmp_path: Path) -> None:
    _curriculum(tmp_path, CURRICULUM)
    common = ("overrideable_dataset_kwargs: {num_samples: 50}\ncommon: {test_size: .5}\noverrideable_variant_vals:\n"
              "    vals_dataset_size: [big]\n    vals_goal: [c]\n    vals_embodiment: [hand]\n"
              "    vals_currname: [curr]\n    vals_filter: [[two_best, max_training_reward, {k: 2}]]\n"
              "    vals_policy: [gru32_init]\n    vals_algorithm: [npo]\n    num_smcs: 5\n")
    _write(tmp_path, "common.exp", common)
    exp = _write(tmp_path, "my-exp", "__include__: [common.exp, test.curriculum]\n")
    [(name, definition)] = load_experiments(exp).items()
    assert name == "my-exp" and definition.variants == ("big+c+hand+curr+two_best+gru32_init+npo",)
    assert definition.goal_name == "classification" and not definition.noprim
    _write(tmp_path, "common.exp", common.replace("[c]", "[xyz]"))
    with pytest.raises(DefinitionError, match="vals_goal"):
        load_experiments(exp)
    with pytest.raises(DefinitionError, match="exactly one"):
        load_experiments(_write(tmp_path, "no-curr", "__include__: [common.exp]\n"))


@pytest.mark.parametrize(("old", "new", "words"), [
    ('logic: "?x container(x) & inside(self,x)"', 'logic: "?x container(x) &"',
     "good.datasets, line 2: concept 'c1': syntax error"),
    ('logic: "?x container(x) & inside(self,x)"', 'logic: "?x contianer(x)"',
     "good.datasets, line 2: concept 'c1': unknown predicate or macro 'contianer'"),
    ('logic: "?x container(x)"', 'logic: "?x container(x,x)"',
     "good.datasets, line 6: generator 'g1': predicate 'container' takes 1 argument"),
    ("concepts:\n", "concept:\n", "good.datasets, line 1: unknown section 'concept' .*did you mean 'concepts'"),
])
def test_expressions_and_sections_are_checked_at_load_time(tmp_path: Path, old: str, new: str, words: str) -> None:
    assert old in GOOD
    message = _error(_write(tmp_path, "good.datasets", GOOD.replace(old, new, 1)))
    assert re.search(words, message), message


@pytest.mark.parametrize(("section", "logic", "words"), [
    ("concepts", "?x contianer(x)", "concept 'draft': unknown predicate or macro 'contianer'"),
    ("generators", "?x container(x,x)", "generator 'draft': predicate 'container' takes 1 argument"),
    ("concepts", "?x later(x,x)", "concept 'draft': macro 'later' takes 1 argument"),
])
def test_definitions_no_dataset_uses_are_checked_too(tmp_path: Path, section: str, logic: str, words: str) -> None:
    """Every definition is compiled once all files are read (macros defined later, in an included file, count)."""
    _write(tmp_path, "later.generators", 'generators:\n    later:\n        logic: "?y container(y)"\n')
    text = f'__include__: [later.generators]\n{section}:\n    ok:\n        logic: "?x later(x)"\n' \
           f'    draft:\n        logic: "{logic}"\n'
    path = _write(tmp_path, "drafts.concepts", text)
    assert re.search(f"{re.escape(str(path))}, line 5: {re.escape(words)}", _error(path))
    defs = load_definitions(_write(tmp_path, "fine.concepts", text.replace(logic, "?x later(x)")))
    assert set(getattr(defs, section)) >= {"ok", "draft"} and not defs.unresolved


def test_only_the_release_generators_naming_an_undefined_relation_load(tmp_path: Path) -> None:
    """The original files define three generators over a relation defined nowhere; no dataset uses them."""
    name = "bfaw-self-and-two-potential-containers-in-nontarget"
    unused = f'generators:\n    {name}:\n        logic: "?x potential-container(x)"\n'
    defs = load_definitions(_write(tmp_path, "good.datasets", GOOD.replace("generators:\n", unused, 1)))
    assert defs.unresolved == {name: ("potential-container",)}
    used = GOOD.replace("generators:\n", unused, 1).replace("        - [g1]", f"        - [g1, {name}]")
    assert f"generator '{name}': unknown predicate or macro 'potential-container'" in _error(
        _write(tmp_path, "used.datasets", used))
    other = GOOD.replace("generators:\n", unused.replace("potential-container(x)", "potential-containr(x)"), 1)
    assert f"good.datasets, line 6: generator '{name}': unknown predicate or macro 'potential-containr'" in _error(
        _write(tmp_path, "good.datasets", other))
    require_reference()
    reference = load_definitions(sorted(DATA.glob("*.datasets")))
    assert sorted(reference.unresolved) == ["bfaw-self-and-two-potential-containers-in-left-nontarget",
                                            "bfaw-self-and-two-potential-containers-in-nontarget",
                                            "bfaw-self-and-two-potential-containers-in-right-nontarget"]


MINE = """\
concepts:
  self-left-of-container:
    logic: "?x container(x) & left_of(self,x)"
generators:
  container-on-floor:
    logic: "?f ?x floor(f) & container(x) & on_top(x,f)"
datasets:
  cl_self-left-of-container:
    - self-left-of-container
    - [container-on-floor]
"""


def test_a_definitions_file_becomes_an_environment(tmp_path: Path) -> None:
    from pixelworld_env.concepts import Concept

    defs = load_definitions(_write(tmp_path, "my.datasets", MINE))
    spec = defs.dataset_spec("cl_self-left-of-container", num_samples=4)
    assert spec.kind == "classification" and spec.generators == (
        ("container-on-floor", "?f ?x floor(f) & container(x) & on_top(x,f)"),)
    train = defs.make_env("cl_self-left-of-container", num_samples=4, seed=3)
    test = defs.make_env("cl_self-left-of-container", split="test", num_samples=4, seed=3)
    assert len(train.scenes) == len(test.scenes) == 4 and sorted(train.labels) == [0, 0, 1, 1]
    concept = Concept("?x container(x) & left_of(self,x)")
    assert [int(concept.holds(s)) for s in train.scenes] == list(train.labels)
    assert set(train.scenes).isdisjoint(test.scenes)
    with pytest.raises(KeyError, match="no dataset 'cl_self-left-of-containr'.*did you mean"):
        defs.dataset_spec("cl_self-left-of-containr")
