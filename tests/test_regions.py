"""Tests of the inside-region annotations (docs/design.md, "Inside regions") against the AAAI-18 shape library."""

from __future__ import annotations

import gzip
import json

import numpy as np
import pytest

from pixelworld_env.core.regions import (
    ANNOTATED_FAMILIES,
    INSIDE_SUPPORTED,
    INTERIOR,
    SOLID,
    SPACE,
    annotate,
    inside_masks,
)
from tests.helpers import shape_library_file

pytestmark = pytest.mark.reference  # reads the original data: the reference, or the fixture

LIBRARY_ID = "7301d12e1d77"

_LABELS = {"#": SOLID, ".": SPACE, "i": INTERIOR, "s": INSIDE_SUPPORTED}


@pytest.fixture(scope="module")
def library() -> dict:
    with gzip.open(shape_library_file(), "rt", encoding="utf-8") as fh:
        return json.load(fh)["libraries"][LIBRARY_ID]


def drawing(text: str) -> tuple[np.ndarray, np.ndarray]:
    """Template (``#`` pixel; ``.``, ``i``, ``s`` empty) and label array of a drawn annotation."""
    rows = text.split()
    template = np.array([[int(ch == "#") for ch in row] for row in rows], dtype=np.int8)
    labels = np.array([[_LABELS[ch] for ch in row] for row in rows], dtype=np.int8)
    return template, labels


def regions(labels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return labels >= INTERIOR, labels == INSIDE_SUPPORTED


def test_library_has_exactly_the_annotated_families(library: dict) -> None:
    assert set(library["annotations"]) == ANNOTATED_FAMILIES


@pytest.mark.parametrize("family", sorted(ANNOTATED_FAMILIES))
def test_reference_annotations_reproduced(library: dict, family: str) -> None:
    templates, expected = library["templates"][family], library["annotations"][family]
    assert len(templates) == len(expected) > 0
    for idx, (template, annotation) in enumerate(zip(templates, expected, strict=True)):
        got = annotate(np.array(template), family)
        assert got.dtype == np.int8
        assert np.array_equal(got, np.array(annotation)), f"{family} template {idx}"


@pytest.mark.parametrize("family", sorted(ANNOTATED_FAMILIES))
def test_inside_masks_follow_the_reference_labels(library: dict, family: str) -> None:
    templates, annotations = library["templates"][family], library["annotations"][family]
    for template, annotation in zip(templates, annotations, strict=True):
        inside, supported = inside_masks(np.array(template), family)
        want_inside, want_supported = regions(np.array(annotation))
        assert np.array_equal(inside, want_inside)
        assert np.array_equal(supported, want_supported)


SPEC_EXAMPLES = {
    "container 0": (
        "container",
        """
        #........
        #........
        #........
        #sssssss#
        .########
        """,
    ),
    "container 1": (
        "container",
        """
        #......
        #iiiii#
        #sssss#
        .#####.
        """,
    ),
    "noncontainer 0": (
        "noncontainer",
        """
        #........
        #........
        #........
        #ssssssi#
        #######..
        """,
    ),
    "noncontainer 3": (
        "noncontainer",
        """
        #ii#
        #ii#
        #ii#
        .ss#
        ####
        """,
    ),
}


@pytest.mark.parametrize("name", sorted(SPEC_EXAMPLES))
def test_spec_worked_examples(name: str) -> None:
    family, text = SPEC_EXAMPLES[name]
    template, expected = drawing(text)
    assert all(map(np.array_equal, regions(annotate(template, family)), regions(expected)))


def test_spec_worked_example_lower_left_corner() -> None:
    template, _ = drawing("#.... #.... #.... #####")
    inside, supported = inside_masks(template, "lower_left_corner")
    expected = np.zeros(template.shape, dtype=bool)
    expected[2] = True  # the wall cell of row H-2 included
    assert np.array_equal(inside, expected)
    assert np.array_equal(supported, expected)


HAND_DRAWN = {
    "container": """
        #iiiii#
        #iisii#
        #ss#ss#
        #######
        """,
    "enclosure": """
        .####.
        #isii#
        #i#ii#
        #ssss#
        .####.
        """,
    "left_container": """
        ####
        #i..
        #s..
        ##..
        """,
    "top_container": """
        #####
        #iii#
        #sss#
        #....
        """,
}


@pytest.mark.parametrize("family", sorted(HAND_DRAWN))
def test_hand_drawn_shapes(family: str) -> None:
    template, expected = drawing(HAND_DRAWN[family])
    assert np.array_equal(annotate(template, family), expected)


def test_hand_drawn_container_with_taller_wall_blanks_wall_above_water() -> None:
    template, _ = drawing("#.... #.... #...# #####")
    _, expected = drawing("..... #.... #sss# #####")
    assert np.array_equal(annotate(template, "container"), expected)


@pytest.mark.parametrize(
    ("family", "text"),
    [("hline", "#####"), ("blob", "### #.# ##."), ("upper_left_corner", "### #.. #..")],
)
def test_unannotated_family_falls_back_to_empty_cells(family: str, text: str) -> None:
    template, _ = drawing(text)
    inside, supported = inside_masks(template, family)
    assert np.array_equal(inside, template == 0)
    assert np.array_equal(supported, template == 0)


def test_inside_masks_are_read_only_and_cached() -> None:
    template, _ = drawing("#...# #...# #####")
    inside, supported = inside_masks(template, "container")
    assert not inside.flags.writeable and not supported.flags.writeable
    again = inside_masks(template.astype(np.int64), "container")
    assert again[0] is inside and again[1] is supported


@pytest.mark.parametrize("family", ["hline", "blob", "no_such_family"])
def test_annotate_rejects_family_without_rule(family: str) -> None:
    with pytest.raises(ValueError, match=family):
        annotate(np.ones((2, 2), dtype=np.int8), family)
