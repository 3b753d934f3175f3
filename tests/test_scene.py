"""Scene value type: sample JSON round trip, the text format and its errors."""

from __future__ import annotations

import re

import pytest

from pixelworld_env import Color, ObjectClass, Scene
from tests.helpers import read_samples, sample_files

pytestmark = pytest.mark.reference  # reads the original data: the reference, or the fixture

ROOM = """
#########
#.......#
#..S....#
#.a...bb#
#.aaa.A.#
#=======#
#.......#
#########
"""


def test_from_ascii_objects() -> None:
    scene = Scene.from_ascii(ROOM, kinds={"a": "lower_left_corner", "b": "hline"})
    assert (scene.height, scene.width) == (8, 9)
    kinds = {o.family: o for o in scene.objects}
    floor = kinds["floor_shape"]
    assert floor.color == Color.BLUE and floor.cls is ObjectClass.IMMOVEABLE_BIG
    assert floor.position == (5, 1) and floor.size == (1, 7)
    corner = kinds["lower_left_corner"]
    assert corner.position == (3, 2) and corner.size == (2, 3)
    assert set(corner.cells) == {(0, 0), (1, 0), (1, 1), (1, 2)}
    assert not corner.moveable and corner.color == Color.WHITE
    pushable = [o for o in scene.objects if o.pushable]
    assert len(pushable) == 1 and pushable[0].cls is ObjectClass.COMPLEX and pushable[0].family == "blob"
    assert scene.self_object.position == (2, 3)
    assert scene.objects[-1].is_frame
    assert scene.grid()[0].tolist() == [Color.PURPLE] * 9


def test_ascii_round_trip() -> None:
    scene = Scene.from_ascii(ROOM, kinds={"a": "lower_left_corner", "b": "hline"})
    text = scene.to_ascii()
    assert text == ROOM.strip()
    again = Scene.from_ascii(text, kinds=scene.ascii_kinds())
    assert again == scene


@pytest.mark.parametrize(
    ("text", "kinds", "message"),
    [
        ("###\n#S#\n##", None, "ragged scene text: row 2 has 2 characters"),
        ("####\n#SS#\n####", None, "exactly one self 'S', found 2 at row 1 column 1, row 1 column 2"),
        ("###\n#.#\n###", None, "exactly one self 'S', found none"),
        ("####\n#S*#\n####", None, "unknown character '*' at row 1, column 2"),
        ("####\n#Sa#\n####", {"a": "contianer"}, "kinds['a']: unknown shape family 'contianer'; did you mean "
                                                 "container"),
        ("####\n#Sa#\n####", {"b": "container"}, "letters that do not appear in the scene: b"),
        ("####\n#S##\n####", None, "'#' is the frame and must fill exactly the border ring; row 1, column 2"),
    ],
)
def test_bad_ascii(text: str, kinds: dict | None, message: str) -> None:
    with pytest.raises(ValueError, match=re.escape(message)):
        Scene.from_ascii(text, kinds)


def test_sample_dicts_round_trip_unchanged() -> None:
    for path in sample_files():
        _, samples = read_samples(path)
        for sample in samples:
            scene = Scene.from_dict(sample)
            out = scene.to_dict()
            assert out["objects"] == sample["objects"], f"{path.name} sample {sample['index']}"
            assert (out["height"], out["width"]) == (sample["height"], sample["width"])


def test_sample_objects_use_their_library_template_size() -> None:
    from pixelworld_env.core.shapes import shape_library

    for path in sample_files():
        for sample in read_samples(path)[1]:
            for obj in Scene.from_dict(sample).objects:
                if not obj.is_frame:
                    templates = shape_library()[obj.family]
                    assert obj.size == templates[obj.shape_idx % len(templates)].shape


def test_explicit_template_size_survives_a_round_trip() -> None:
    """A template with an empty last column (a clipped wall) keeps its bbox through to_dict/from_dict."""
    data = {"height": 8, "width": 8, "objects": [
        {"class": "self", "name": "self", "color": 2, "position": [1, 1],
         "meta": {"is_self": True, "pushable": False, "is_target": False, "shape": "pixel", "shape_idx": 0}},
        {"class": "immoveable_big", "name": "immoveable_big", "color": 1, "position": [3, 2],
         "shape": [[0, 0], [1, 0], [1, 1], [1, 2]], "size": [2, 4],
         "meta": {"is_self": False, "pushable": False, "is_target": False, "shape": "noncontainer",
                  "shape_idx": 0}}]}
    scene = Scene.from_dict(data)
    assert scene.objects[1].size == (2, 4)
    assert scene.to_dict() == data
    del data["objects"][1]["size"]
    assert Scene.from_dict(data).objects[1].size == (2, 3)


def test_from_dict_errors() -> None:
    base = {"height": 5, "width": 5, "objects": [
        {"class": "self", "color": 2, "position": [2, 2], "meta": {"shape": "pixel"}}]}
    assert Scene.from_dict(base).self_object.position == (2, 2)
    with pytest.raises(ValueError, match="unknown class 'robot'"):
        Scene.from_dict({**base, "objects": [{"class": "robot", "color": 2, "position": [1, 1]}]})
    with pytest.raises(ValueError, match="lacks the field 'width'"):
        Scene.from_dict({"height": 5, "objects": []})
    with pytest.raises(ValueError, match="outside the 5 x 5 world"):
        Scene.from_dict({**base, "objects": [{"class": "self", "color": 2, "position": [7, 2]}]})
    with pytest.raises(ValueError, match="exactly one self"):
        Scene.from_dict({**base, "objects": []})
