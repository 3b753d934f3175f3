"""Inside regions of container-like shape templates (docs/design.md, "Inside regions").

The annotation of a template is computed by the "water" rule on the template array alone:

* Every empty cell starts filled with water. Water flows only in the family's flow directions;
  a water cell drains when one of its flow-direction neighbours lies outside the bbox or is an
  empty cell without water. The water left at the fixed point is ``W``.
* Cells of ``W`` with no water directly below (or in the last row) are inside_supported (5), the
  rest of ``W`` is interior (4); template pixels are solid (3), everything else space (2).
* "Holey" families are first plugged (noncontainer and lower corners: bottom row and side walls
  closed; nonenclosure: all four sides; left/right/top_noncontainer: the closed side and the arm
  cells next to it), ``W`` is computed on the plugged array and the plug cells revert to space.
  Noncontainers and lower corners then demote the cell above a floor hole to interior, and when a
  side column is empty above the bottom row, every cell above a bottom-row pixel becomes
  inside_supported. Oriented noncontainers have no inside_supported cells.
* Quirk of the original annotator, reproduced: for the unplugged families, solid cells more than one
  row above or one column left of ``W``'s bounding box are labelled space. It never changes ``W``.

Families without an annotation rule fall back to "the empty cells of the template bbox".
"""

from __future__ import annotations

from collections.abc import Callable
from functools import lru_cache

import numpy as np

from pixelworld_env.errors import PixelWorldError

SPACE, SOLID, INTERIOR, INSIDE_SUPPORTED = 2, 3, 4, 5

Flow = tuple[int, int]
UP: Flow = (-1, 0)
DOWN: Flow = (1, 0)
LEFT: Flow = (0, -1)
RIGHT: Flow = (0, 1)

_CONTAINER_FLOWS = (DOWN, LEFT, RIGHT)
_ENCLOSURE_FLOWS = (UP, DOWN, LEFT, RIGHT)
_LEFT_FLOWS = (UP, DOWN, LEFT)
_RIGHT_FLOWS = (UP, DOWN, RIGHT)
_TOP_FLOWS = (UP, LEFT, RIGHT)

_FLOWS: dict[str, tuple[Flow, ...]] = {
    "container": _CONTAINER_FLOWS,
    "sym_container": _CONTAINER_FLOWS,
    "rect_container": _CONTAINER_FLOWS,
    "noncontainer": _CONTAINER_FLOWS,
    "lower_left_corner": _CONTAINER_FLOWS,
    "lower_right_corner": _CONTAINER_FLOWS,
    "enclosure": _ENCLOSURE_FLOWS,
    "box": _ENCLOSURE_FLOWS,
    "nonenclosure": _ENCLOSURE_FLOWS,
    "left_container": _LEFT_FLOWS,
    "left_noncontainer": _LEFT_FLOWS,
    "right_container": _RIGHT_FLOWS,
    "right_noncontainer": _RIGHT_FLOWS,
    "top_container": _TOP_FLOWS,
    "top_noncontainer": _TOP_FLOWS,
}

ANNOTATED_FAMILIES: frozenset[str] = frozenset(_FLOWS)

_OPEN_BOTTOM_FAMILIES = frozenset({"noncontainer", "lower_left_corner", "lower_right_corner"})
_ORIENTED_NONCONTAINERS = frozenset({"left_noncontainer", "right_noncontainer", "top_noncontainer"})


def _water(solid: np.ndarray, flows: tuple[Flow, ...]) -> np.ndarray:
    """Largest set of empty cells whose flow-direction neighbours are in the bbox and solid or water."""
    h, w = solid.shape
    water = ~solid
    while True:
        held = np.pad(solid | water, 1)  # False beyond the bbox: an open drain
        kept = water.copy()
        for dr, dc in flows:
            kept &= held[1 + dr : 1 + dr + h, 1 + dc : 1 + dc + w]
        if np.array_equal(kept, water):
            return water
        water = kept


def _labels(solid: np.ndarray, water: np.ndarray) -> np.ndarray:
    """Label solid cells, interior water and water with no water directly below it."""
    labels = np.full(solid.shape, SPACE, dtype=np.int8)
    labels[solid] = SOLID
    water_below = np.zeros_like(water)
    water_below[:-1] = water[1:]
    labels[water] = np.where(water_below[water], INTERIOR, INSIDE_SUPPORTED)
    return labels


def _blank_beyond_water(labels: np.ndarray, solid: np.ndarray, water: np.ndarray) -> None:
    """Label space the solid cells above row ``top - 1`` or left of column ``left - 1`` of ``W``."""
    if not water.any():
        return
    top = max(int(np.flatnonzero(water.any(axis=1))[0]) - 1, 0)
    left = max(int(np.flatnonzero(water.any(axis=0))[0]) - 1, 0)
    labels[:top][solid[:top]] = SPACE
    labels[:, :left][solid[:, :left]] = SPACE


def _plug_open_bottom(t: np.ndarray) -> np.ndarray:
    """Close the bottom row and both side walls (from their top pixel, at least from row H-2).

    Equivalent to the original annotator's plugging, which closes the bottom row only between the outermost
    occupied columns: an empty side column gets a pixel at row H-2 first, so the plugged bottom row always spans
    the whole width.
    """
    h, w = t.shape
    plugged = t.copy()
    if h < 2:
        return plugged
    plugged[-1] = True
    for col in (0, w - 1):
        rows = np.flatnonzero(t[:-1, col])
        top = rows[0] if rows.size else h - 2
        plugged[top:, col] = True
    plugged[-1, [0, -1]] = t[-1, [0, -1]]  # clipped bottom corners stay clipped
    return plugged


def _plug_enclosure(t: np.ndarray) -> np.ndarray:
    """Close all four sides except the corner cells."""
    plugged = t.copy()
    plugged[[0, -1], 1:-1] = True
    plugged[1:-1, [0, -1]] = True
    return plugged


def _plug_left(t: np.ndarray) -> np.ndarray:
    """Close the left side (except its end cells) and the two arm cells next to it."""
    plugged = t.copy()
    plugged[1:-1, 0] = True
    plugged[[0, -1], 1:2] = True
    return plugged


_PLUGS: dict[str, Callable[[np.ndarray], np.ndarray]] = {
    "noncontainer": _plug_open_bottom,
    "lower_left_corner": _plug_open_bottom,
    "lower_right_corner": _plug_open_bottom,
    "nonenclosure": _plug_enclosure,
    "left_noncontainer": _plug_left,
    "right_noncontainer": lambda t: _plug_left(t[:, ::-1])[:, ::-1],
    "top_noncontainer": lambda t: _plug_left(t.T).T,
}


def _open_bottom_rules(labels: np.ndarray, t: np.ndarray) -> None:
    """Floor-hole demotion and the empty-side-column rule of noncontainers and lower corners."""
    if t.shape[0] < 2:
        return
    row = labels[-2]
    row[(row == INSIDE_SUPPORTED) & ~t[-1]] = INTERIOR
    if not t[:-1, 0].any() or not t[:-1, -1].any():
        row[t[-1]] = INSIDE_SUPPORTED


def _as_bool(template: np.ndarray) -> np.ndarray:
    t = np.asarray(template) != 0
    if t.ndim != 2:
        raise PixelWorldError(f"template must be a 2-D array, got shape {t.shape}")
    return t


def annotate(template: np.ndarray, family: str) -> np.ndarray:
    """Annotation of ``template`` (labels SPACE..INSIDE_SUPPORTED) by the water rule of ``family``."""
    if family not in _FLOWS:
        raise PixelWorldError(f"shape family {family!r} has no inside-region annotation rule")
    t = _as_bool(template)
    plug = _PLUGS.get(family)
    if plug is None:
        water = _water(t, _FLOWS[family])
        labels = _labels(t, water)
        _blank_beyond_water(labels, t, water)
        return labels
    plugged = plug(t)
    labels = _labels(plugged, _water(plugged, _FLOWS[family]))
    labels[plugged & ~t] = SPACE
    if family in _OPEN_BOTTOM_FAMILIES:
        _open_bottom_rules(labels, t)
    elif family in _ORIENTED_NONCONTAINERS:
        labels[labels == INSIDE_SUPPORTED] = INTERIOR
    return labels


@lru_cache(maxsize=4096)
def _cached_masks(family: str, shape: tuple[int, ...], data: bytes) -> tuple[np.ndarray, np.ndarray]:
    t = np.frombuffer(data, dtype=bool).reshape(shape)
    if family in ANNOTATED_FAMILIES:
        labels = annotate(t, family)
        inside, supported = labels >= INTERIOR, labels == INSIDE_SUPPORTED
    else:
        inside, supported = ~t, ~t
    inside.flags.writeable = False
    supported.flags.writeable = False
    return inside, supported


def inside_masks(template: np.ndarray, family: str) -> tuple[np.ndarray, np.ndarray]:
    """Read-only boolean masks ``(inside, inside_supported)`` over the template bbox (cached).

    Annotated families: interior or inside_supported cells, and inside_supported cells. Any other
    family: both masks are the empty cells of the template.
    """
    t = _as_bool(template)
    return _cached_masks(family, t.shape, t.tobytes())
