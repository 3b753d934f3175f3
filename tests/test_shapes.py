"""Shape templates: the generated library against the original AAAI-18 library, and the API."""

from __future__ import annotations

import gzip
import json
from functools import cache

import numpy as np
import pytest

from pixelworld_env.core.shapes import FAMILIES, LibraryParams, build_library, shape_library, template
from tests.helpers import shape_library_file

pytestmark = pytest.mark.reference  # reads the original data: the reference, or the fixture

LIBRARY_ID = "7301d12e1d77"

COUNTS = {  # spec section 4
    "blob": 30, "box": 10, "chair": 20, "container": 20, "convex_blob": 50, "cross": 20, "d_slob": 20,
    "enclosure": 20, "floor_shape": 1, "hline": 5, "large_blob": 50, "left_container": 20,
    "left_noncontainer": 20, "line": 10, "lower_left_corner": 20, "lower_right_corner": 20,
    "noncontainer": 20, "nonenclosure": 20, "pixel": 1, "rect_container": 20, "right_container": 20,
    "right_noncontainer": 20, "small_blob": 20, "small_container": 1, "small_table": 1,
    "sym_container": 20, "table": 20, "top_container": 20, "top_noncontainer": 20,
    "upper_left_corner": 20, "upper_right_corner": 20, "vline": 5, "wall": 1,
}


@cache
def load_reference() -> dict[str, list[np.ndarray]]:
    """The original templates, family -> list of arrays (from the reference, or the fixture: the same file)."""
    with gzip.open(shape_library_file(), "rt", encoding="utf-8") as handle:
        templates = json.load(handle)["libraries"][LIBRARY_ID]["templates"]
    return {family: [np.array(t, dtype=np.uint8) for t in grids] for family, grids in templates.items()}


def test_families_are_the_reference_families_in_order() -> None:
    assert len(FAMILIES) == 33
    assert tuple(load_reference()) == FAMILIES
    assert tuple(sorted(FAMILIES)) == FAMILIES


@pytest.mark.parametrize("family", FAMILIES)
def test_family_is_bit_identical_to_reference(family: str) -> None:
    generated, expected = shape_library()[family], load_reference()[family]
    assert len(generated) == len(expected)
    for idx, (got, want) in enumerate(zip(generated, expected, strict=True)):
        assert got.shape == want.shape, f"{family}[{idx}]: shape {got.shape} != {want.shape}"
        assert np.array_equal(got, want), f"{family}[{idx}]:\n{got}\n!=\n{want}"


@pytest.mark.parametrize("family", FAMILIES)
def test_family_count_and_array_form(family: str) -> None:
    templates = shape_library()[family]
    assert len(templates) == COUNTS[family]
    assert len({(t.shape, t.tobytes()) for t in templates}) == len(templates)
    for arr in templates:
        assert arr.dtype == np.uint8 and arr.ndim == 2
        assert set(np.unique(arr)) <= {0, 1} and arr.any()
        assert not arr.flags.writeable
        with pytest.raises(ValueError):
            arr[0, 0] = 1


def test_fixed_sizes_follow_params() -> None:
    library = shape_library()
    assert library["floor_shape"][0].shape == (1, 33)
    assert library["wall"][0].shape == (16, 1)
    assert library["pixel"][0].shape == (1, 1)
    small = build_library(LibraryParams(max_width=20, max_height=10))
    assert small["floor_shape"][0].shape == (1, 20)
    assert small["wall"][0].shape == (10, 1)


@pytest.mark.parametrize("family", ["pixel", "hline", "container", "blob", "convex_blob"])
def test_template_index_is_taken_modulo_family_size(family: str) -> None:
    templates = shape_library()[family]
    for shape_idx in range(-3, 60):
        assert template(family, shape_idx) is templates[shape_idx % len(templates)]


def test_unknown_family_names_it_and_suggests_close_matches() -> None:
    with pytest.raises(ValueError, match=r"'contaner'.*container"):
        template("contaner", 0)
    with pytest.raises(ValueError, match="unknown shape family 'zzz'"):
        template("zzz", 0)


def test_library_is_deterministic_and_cached() -> None:
    assert shape_library() is shape_library()
    again = build_library(LibraryParams())
    assert list(again) == list(FAMILIES)
    for family, templates in shape_library().items():
        assert len(again[family]) == len(templates)
        assert all(np.array_equal(a, b) for a, b in zip(again[family], templates, strict=True))


def test_seed_changes_random_families_only() -> None:
    other = build_library(LibraryParams(seed=7))
    default = shape_library()
    for family in ("blob", "convex_blob", "container", "enclosure"):
        assert any(
            a.shape != b.shape or not np.array_equal(a, b)
            for a, b in zip(other[family], default[family], strict=True)
        ), family
    for family in ("pixel", "floor_shape", "wall", "small_container", "small_table"):
        assert np.array_equal(other[family][0], default[family][0])
