"""Untrusted files and arguments: each is refused with the package's specific error (naming the file, the line or the
field, and what is expected) before any work starts, instead of a hang, exhausted memory, a silently wrong reading or
a foreign traceback. Every input here would hang or misread without its check; none does any real work."""

from __future__ import annotations

import io
from pathlib import Path

import gymnasium as gym
import pytest

import pixelworld_env  # noqa: F401  (registers the PW-* ids)
from pixelworld_env.cli import main as pixelworld_main
from pixelworld_env.concepts import Concept, MacroExpansionError, expand, parse
from pixelworld_env.concepts.parser import MAX_EXPANDED_CLAUSES
from pixelworld_env.core.constants import MAX_WORLD_CELLS, ObjectClass
from pixelworld_env.core.objects import WorldObject, frame_object
from pixelworld_env.core.scene import Scene
from pixelworld_env.envs.vector import MAX_VECTOR_ENVS, PixelWorldVectorEnv
from pixelworld_env.errors import PixelWorldError, PixelWorldTypeError
from pixelworld_env.generation.dataset import MAX_DRAWS, generate
from pixelworld_env.generation.dataset_spec import MAX_NUM_SAMPLES, DatasetSpec
from pixelworld_env.generation.definitions import DefinitionError, load_definitions
from pixelworld_env.generation.experiment_files import load_experiments
from pixelworld_env.yaml_loading import (
    MAX_YAML_DEPTH,
    MAX_YAML_SIZE,
    YAMLInputError,
    safe_yaml_compose,
    safe_yaml_load,
)
from tests.helpers import classification_env

ID = "PW-ba_self-in-container_from_directly-above-v0"


def _write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


# -- macros that double at every level ------------------------------------------------------------------------------


def _doubling_macros(levels: int) -> dict[str, str]:
    """``m0`` one clause, each ``m<k>`` two uses of ``m<k-1>``: ``m<k>`` expands to ``2**k`` clauses."""
    return {"m0": "?x red(x)", **{f"m{k}": f"?x m{k - 1}(x) & m{k - 1}(x)" for k in range(1, levels)}}


def test_a_small_definition_file_of_doubling_macros_is_refused_at_load(tmp_path: Path) -> None:
    """40 levels in 1.5 KB stand for 2**39 clauses: refused at the first concept over the limit (m10, 1,024
    clauses), with its file and line, instead of expanding for ever."""
    lines = ["concepts:"] + [f"  {name}: {{logic: '{logic}'}}" for name, logic in _doubling_macros(40).items()]
    lines += ["  c: {logic: '?y m39(y)'}", "generators:", "  g: {logic: 'red(self)'}", "datasets:", "  cl_x: [c, [g]]"]
    path = _write(tmp_path, "doubling.concepts", "\n".join(lines) + "\n")
    assert path.stat().st_size < 2000
    with pytest.raises(DefinitionError) as info:
        load_definitions(path)
    message = str(info.value)
    assert message.startswith(f"{path}, line 12: concept 'm10': the expression expands to 1,024 clauses, more than "
                              f"the limit of {MAX_EXPANDED_CLAUSES:,}")
    assert "MAX_EXPANDED_CLAUSES" in message


def test_expansion_names_the_first_macro_over_the_limit() -> None:
    macros = _doubling_macros(40)
    with pytest.raises(MacroExpansionError) as info:
        Concept("?y m39(y)", macros)
    assert info.value.chain[0] == "m39" and info.value.chain[-1] == "m10" and info.value.size == 1024
    assert str(info.value).startswith("macro 'm10' (reached through m39 -> m38 -> ")
    assert isinstance(info.value, PixelWorldError)
    within = expand(parse("?y m9(y)"), macros)  # 512 clauses: under the limit, expanded as before
    assert len(within.positives) == 512 and set(within.positives) == {parse("?y red(y)").positives[0]}
    too_long = " & ".join(["red(self)"] * (MAX_EXPANDED_CLAUSES + 1))  # no macro: the expression itself
    with pytest.raises(MacroExpansionError, match=rf"^the expression expands to {MAX_EXPANDED_CLAUSES + 1:,} "):
        expand(parse(too_long), {})


# -- YAML: aliases, nesting -----------------------------------------------------------------------------------------


LAUGHS = 'a0: &a0 ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]\n' + "".join(
    f"a{k}: &a{k} [{', '.join([f'*a{k - 1}'] * 9)}]\n" for k in range(1, 12)
) + "concepts:\n  c: {logic: '?x red(x)', desc: *a11}\n"


def test_billion_laughs_are_refused_in_definition_and_experiment_files(tmp_path: Path) -> None:
    path = _write(tmp_path, "laughs.concepts", LAUGHS)
    for load in (load_definitions, load_experiments):
        with pytest.raises(DefinitionError) as info:
            load(path)
        assert str(info.value).startswith(f"{path}, line 2: YAML alias *a0 refused: aliases are not supported")


def test_safe_yaml_load_names_where_and_the_line() -> None:
    assert safe_yaml_load("a: [1, 2]\nb: {c: true}\n", "x.yml") == {"a": [1, 2], "b": {"c": True}}
    assert safe_yaml_load("", "x.yml") is None and safe_yaml_compose("# nothing\n", "x.yml") is None
    assert safe_yaml_load("a: &anchor 1\n", "x.yml") == {"a": 1}  # an anchor no alias uses repeats nothing
    cases = [
        ("a: 1\nb: *a\n", 2, "YAML alias *a refused"),
        ("a:\n  b: " + "[" * (MAX_YAML_DEPTH + 1) + "]" * (MAX_YAML_DEPTH + 1), 2,
         f"more than {MAX_YAML_DEPTH} nested mappings or lists"),
        ("a: [1\nb: 2\n", 2, "invalid YAML: while parsing a flow sequence"),
        ("a: 1\n---\nb: 2\n", 2, "invalid YAML: expected a single document"),
        ("a: !!python/object/apply:os.system [ls]\n", 1, "invalid YAML: could not determine a constructor"),
    ]
    for text, line, words in cases:
        with pytest.raises(YAMLInputError) as info:
            safe_yaml_load(text, "my/file.yml")
        assert str(info.value).startswith(f"my/file.yml, line {line}: {words}"), str(info.value)
        assert (info.value.where, info.value.line) == ("my/file.yml", line)
        assert isinstance(info.value, PixelWorldError)


def test_a_definition_file_that_is_not_text_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "binary.datasets"
    path.write_bytes(b"concepts:\n\xff\xfe\n")
    with pytest.raises(DefinitionError, match=r"binary\.datasets: not UTF-8 text \(byte 0xff at position 10\)"):
        load_definitions(path)


def test_a_yaml_file_is_read_no_further_than_the_limit(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    assert MAX_YAML_SIZE == 10 * 2**20
    monkeypatch.setattr("pixelworld_env.yaml_loading.MAX_YAML_SIZE", 1000)
    path = _write(tmp_path, "long.concepts", "concepts:\n" + "".join(f"  c{k}: {{logic: 'red(self)'}}\n"
                                                                    for k in range(100)))
    with pytest.raises(DefinitionError, match=rf"^{path}: more than 1,000 bytes \(the limit "
                                              r"pixelworld_env\.yaml_loading\.MAX_YAML_SIZE\)$"):
        load_definitions(path)
    with pytest.raises(YAMLInputError, match=r"^x\.yml: 1,001 characters, more than 1,000 "):
        safe_yaml_load("#" * 1001, "x.yml")
    if Path("/dev/zero").exists():  # endless: read up to the limit, then refused
        with pytest.raises(DefinitionError, match="^/dev/zero: more than 1,000 bytes"):
            load_definitions("/dev/zero")


# -- sizes with no bound --------------------------------------------------------------------------------------------


def _spec(**fields) -> DatasetSpec:
    return DatasetSpec(name="cl_x", kind="classification", concept="?x red(x)", generators=(("g", "?x red(x)"),),
                       **fields)


def test_vector_envs_beyond_the_limit_are_refused_before_any_dataset_is_loaded() -> None:
    with pytest.raises(PixelWorldError, match=rf"^num_envs must be at most {MAX_VECTOR_ENVS:,} \(the limit "
                                              r"pixelworld_env\.envs\.vector\.MAX_VECTOR_ENVS\), got 10,000,000$"):
        gym.make_vec(ID, 10**7)
    with pytest.raises(PixelWorldError, match="num_envs must be at most"):
        PixelWorldVectorEnv(classification_env(), MAX_VECTOR_ENVS + 1)
    with pytest.raises(PixelWorldTypeError, match=r"num_envs must be an integer, got 2\.0 \(float\)"):
        PixelWorldVectorEnv(classification_env(), 2.0)


def test_quotas_and_draw_budgets_beyond_the_limits_are_refused_before_the_first_draw() -> None:
    with pytest.raises(PixelWorldError, match=rf"^dataset 'cl_x': num_samples must be at most {MAX_NUM_SAMPLES:,} "
                                              r"\(the limit pixelworld_env\.generation\.dataset_spec\.MAX_NUM_SAMPLES\)"
                                              r", got 1,000,000,000$"):
        _spec(num_samples=10**9)
    assert _spec(num_samples=MAX_NUM_SAMPLES).size == 2 * MAX_NUM_SAMPLES
    with pytest.raises(PixelWorldError, match=rf"^max_draws must be at most {MAX_DRAWS:,} \(the limit "
                                              r"pixelworld_env\.generation\.dataset\.MAX_DRAWS\), got "
                                              r"1,000,000,000,000$"):
        generate(_spec(), max_draws=10**12)
    with pytest.raises(PixelWorldTypeError, match=r"max_draws must be an integer, got 1000000\.0 \(float\)"):
        generate(_spec(), max_draws=1e6)


def test_worlds_beyond_the_cell_limit_are_refused_before_anything_is_built() -> None:
    cells = "more than the limit of 1,000,000 (pixelworld_env.core.constants.MAX_WORLD_CELLS)"
    assert MAX_WORLD_CELLS == 1_000_000
    with pytest.raises(PixelWorldError) as info:
        _spec(height=10**5, width=10**5)
    assert str(info.value) == f"dataset 'cl_x': a 100000 x 100000 world has 10,000,000,000 cells, {cells}"
    with pytest.raises(PixelWorldError, match=r"^frame: a 100000 x 100000 world has 10,000,000,000 cells"):
        frame_object(10**5, 10**5)
    me = WorldObject(cls=ObjectClass.SELF, color=2, position=(1, 1))
    with pytest.raises(PixelWorldError, match=r"^scene: a 3 x 1000000 world has 3,000,000 cells"):
        Scene(height=3, width=10**6, objects=(me,))
    with pytest.raises(PixelWorldTypeError, match=r"^scene: height must be an integer, got 12\.5 \(float\)$"):
        Scene(height=12.5, width=12, objects=(me,))
    with pytest.raises(PixelWorldError, match=r"^frame: a 10 x 10000000000 world"):
        Scene.from_dict({"height": 10, "width": 10**10, "objects": [{"class": "frame"}]})


# -- settings read strictly -----------------------------------------------------------------------------------------


def test_dataset_spec_fields_must_have_their_types() -> None:
    cases = [
        ({"settings": {"allow_targets": "false"}},
         "dataset 'cl_x': setting 'allow_targets' must be a bool (True or False), got 'false' (str)"),
        ({"settings": {"allow_pushable": 1}},
         "dataset 'cl_x': setting 'allow_pushable' must be a bool (True or False), got 1 (int)"),
        ({"num_samples": 2.5}, "dataset 'cl_x': num_samples must be an integer, got 2.5 (float)"),
        ({"num_samples": "3"}, "dataset 'cl_x': num_samples must be an integer, got '3' (str)"),
        ({"num_samples": True}, "dataset 'cl_x': num_samples must be an integer, got True (bool)"),
        ({"width": 12.5}, "dataset 'cl_x': width must be an integer, got 12.5 (float)"),
        ({"height": "18"}, "dataset 'cl_x': height must be an integer, got '18' (str)"),
        ({"padding": None}, "dataset 'cl_x': padding must be an integer, got None (NoneType)"),
        ({"settings": ["allow_targets"]},
         "dataset 'cl_x': settings must be a mapping of names to bools, got ['allow_targets'] (list)"),
    ]
    for fields, message in cases:
        with pytest.raises(PixelWorldTypeError) as info:
            _spec(**fields)
        assert str(info.value) == message
    spec = _spec(settings={"allow_targets": False, "allow_pushable": True})
    assert spec.allow_targets is False and spec.allow_pushable is True


DATASETS = """\
concepts:
    c1: {logic: "?x container(x) & inside(self,x)"}
generators:
    g1: {logic: "?x container(x)"}
datasets:
    cl_one:
        - c1
        - [g1]
        - allow_pushable: true
          allow_targets: SETTING
"""


@pytest.mark.parametrize(("value", "words"), [
    ('"false"', "setting 'allow_targets' must be true or false (unquoted), got 'false' (str)"),
    ("0", "setting 'allow_targets' must be true or false (unquoted), got 0 (int)"),
])
def test_definition_settings_must_be_yaml_bools(tmp_path: Path, value: str, words: str) -> None:
    path = _write(tmp_path, "a.datasets", DATASETS.replace("SETTING", value))
    with pytest.raises(DefinitionError) as info:
        load_definitions(path)
    assert str(info.value) == f"{path}, line 10: dataset 'cl_one': {words}"


def test_definition_settings_must_be_known(tmp_path: Path) -> None:
    path = _write(tmp_path, "a.datasets", DATASETS.replace("allow_targets: SETTING", "allow_target: true"))
    with pytest.raises(DefinitionError) as info:
        load_definitions(path)
    assert str(info.value) == (f"{path}, line 10: dataset 'cl_one': unknown setting 'allow_target'; the settings "
                               "are allow_pushable, allow_targets")
    defs = load_definitions(_write(tmp_path, "b.datasets", DATASETS.replace("SETTING", "false")))
    assert defs.datasets["cl_one"].settings == {"allow_pushable": True, "allow_targets": False}


EXPERIMENT = ("overrideable_dataset_kwargs: {num_samples: NUM}\ncommon: {test_size: .5}\noverrideable_variant_vals:\n"
              "    vals_dataset_size: [big]\n    vals_goal: [c]\n    vals_embodiment: [hand]\n"
              "    vals_currname: [curr]\n    vals_filter: [[two_best, max_training_reward, {k: 2}]]\n"
              "    vals_policy: [gru32_init]\n    vals_algorithm: [npo]\n    num_smcs: 5\n"
              "base_env: {env: {kwargs: {include_base_nonsignals: FLAG}}}\n")


@pytest.mark.parametrize(("num", "flag", "words"), [
    ("2.5", "true", "setting 'num_samples' must be an integer, got 2.5 (float)"),
    ("'50'", "true", "setting 'num_samples' must be an integer, got '50' (str)"),
    ("50", '"false"', "setting 'include_base_nonsignals' must be true or false (unquoted), got 'false' (str)"),
])
def test_experiment_settings_must_have_their_types(tmp_path: Path, num: str, flag: str, words: str) -> None:
    _write(tmp_path, "test.curriculum", "curriculum: {}\n")
    _write(tmp_path, "common.exp", EXPERIMENT.replace("NUM", num).replace("FLAG", flag))
    exp = _write(tmp_path, "my-exp", "__include__: [common.exp, test.curriculum]\n")
    with pytest.raises(DefinitionError) as info:
        load_experiments(exp)
    assert str(info.value) == f"{exp}: {words}"


# -- the pixelworld command -----------------------------------------------------------------------------------------


@pytest.fixture
def small_env(monkeypatch: pytest.MonkeyPatch) -> None:
    """The command's environments: two scenes made here (no dataset to load or generate)."""
    monkeypatch.setattr("pixelworld_env.cli.make_env",
                        lambda members, *, split, seed, render_mode: classification_env(render_mode=render_mode))


@pytest.mark.usefixtures("small_env")
def test_play_says_the_valid_scene_range_and_seeds() -> None:
    for argv, message in [
        (["play", ID, "--index", "99999"],
         f"pixelworld play: error: --index 99999 out of range: the train split of {ID} has 2 scenes, 0..1"),
        (["play", ID, "--index", "-1", "--split", "test"],
         f"pixelworld play: error: --index -1 out of range: the test split of {ID} has 2 scenes, 0..1"),
        (["play", ID, "--episode-seed", "-1"],
         "pixelworld play: error: --episode-seed must be in [0, 2**63 - 1], got -1"),
        (["show", ID, "--index", "2"],
         f"pixelworld show: error: --index 2 out of range: the train split of {ID} has 2 scenes, 0..1"),
    ]:
        with pytest.raises(SystemExit) as info:
            pixelworld_main(argv, out=io.StringIO(), keys=io.StringIO("q\n"))
        assert info.value.code == message
    out = io.StringIO()
    pixelworld_main(["play", ID, "--index", "1", "--episode-seed", "3"], out=out, keys=io.StringIO("q\n"))
    assert out.getvalue().rstrip().endswith("quit")
