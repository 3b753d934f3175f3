"""Where a generated object may go: library templates as objects and bit masks, and the bounding boxes that a
clause and the objects already placed leave for the top-left of the object being placed (:data:`BOUNDS`, used by
the search of :mod:`pixelworld_env.generation.sampling`)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from functools import cache

import numpy as np

from pixelworld_env.core.objects import WorldObject, object_class
from pixelworld_env.core.regions import inside_masks
from pixelworld_env.core.shapes import check_family, shape_library

__all__ = ["BOUNDS", "CONJUNCTS", "Box", "BoundFn", "library_object", "make_object", "template_data", "template_mask"]


@cache
def template_data(family: str, template_index: int) -> tuple[tuple[tuple[int, int], ...], tuple[int, int], int]:
    """(cells, (height, width), number of cells) of a library template."""
    tmpl = shape_library()[family][template_index]
    rows, cols = np.nonzero(tmpl)
    cells = tuple(zip(rows.tolist(), cols.tolist(), strict=True))
    return cells, (int(tmpl.shape[0]), int(tmpl.shape[1])), len(cells)


@cache
def template_mask(family: str, template_index: int, width: int) -> int:
    cells, _, _ = template_data(family, template_index)
    mask = 0
    for r, c in cells:
        mask |= 1 << (r * width + c)
    return mask


@cache
def _region_box(family: str, template_index: int, supported: bool) -> tuple[int, int, int, int] | None:
    """(top, left, bottom, right) of the inside (or inside_supported) mask of a template, or None if empty."""
    tmpl = shape_library()[family][template_index]
    mask = inside_masks(tmpl, family)[1 if supported else 0]
    rows, cols = np.nonzero(mask)
    if not len(rows):
        return None
    return int(rows.min()), int(cols.min()), int(rows.max()), int(cols.max())


@cache
def make_object(is_self: bool, family: str, shape_idx: int, color: int, target: bool, pushable: bool,
                 y: int, x: int) -> WorldObject:
    n = len(shape_library()[family])
    cells, size, _ = template_data(family, shape_idx % n)
    cls = object_class(family, is_self=is_self, pushable=pushable)
    return WorldObject(cls=cls, color=color, position=(y, x), cells=cells, size=size, family=family,
                       shape_idx=shape_idx, pushable=pushable, is_target=target, name=cls.value)


def library_object(family: str, shape_idx: int, color: int, position: tuple[int, int], *, is_self: bool = False,
                   is_target: bool = False, pushable: bool = False) -> WorldObject:
    """A generated object: library template ``shape_idx mod family size`` at ``position`` (row, col).

    The class: ``self`` for the self, ``basic``/``complex`` for pushable objects,
    else ``immoveable`` (pixels) or ``immoveable_big``.
    """
    check_family(family)
    return make_object(is_self, family, int(shape_idx), int(color), bool(is_target), bool(pushable),
                        int(position[0]), int(position[1]))


Box = tuple[int, int, int, int]
_NO = -(10**6)
_YES = 10**6
BoundFn = Callable[[Sequence[WorldObject | None], int, WorldObject, int], Box | None]


def _reach(r: int) -> BoundFn:
    """Some cells within distance r: per-axis bbox distance <= r."""
    def bound(args: Sequence[WorldObject | None], role: int, probe: WorldObject, floor_row: int) -> Box | None:
        other = args[1 - role]
        assert other is not None  # a bound is only used once the clause's other argument is placed
        (oy, ox), (oh, ow) = other.position, other.size
        h, w = probe.size
        return (ox - w + 1 - r, ox + ow - 1 + r, oy - h + 1 - r, oy + oh - 1 + r)
    return bound


def _rows_overlap(other: WorldObject, h: int) -> tuple[int, int]:
    return other.position[0] - h + 1, other.position[0] + other.size[0] - 1


def _cols_overlap(other: WorldObject, w: int) -> tuple[int, int]:
    return other.position[1] - w + 1, other.position[1] + other.size[1] - 1


def _swap(fn: BoundFn) -> BoundFn:
    """The bound of ``P(b, a)`` from that of ``P(a, b)``."""
    def bound(args: Sequence[WorldObject | None], role: int, probe: WorldObject, floor_row: int) -> Box | None:
        return fn((args[1], args[0]), 1 - role, probe, floor_row)
    return bound


def _on_top(args, role, probe, floor_row):  # a above b, touching: a.y + a.h == b.y and columns overlap
    other = args[1 - role]
    h, w = probe.size
    xlo, xhi = _cols_overlap(other, w)
    y = other.position[0] - h if role == 0 else other.position[0] + other.size[0]
    return (xlo, xhi, y, y)


def _on_left(args, role, probe, floor_row):  # a left of b, touching: a.x + a.w == b.x and rows overlap
    other = args[1 - role]
    h, w = probe.size
    ylo, yhi = _rows_overlap(other, h)
    x = other.position[1] - w if role == 0 else other.position[1] + other.size[1]
    return (x, x, ylo, yhi)


def _left_of(args, role, probe, floor_row):  # a.x + a.w <= b.x
    other = args[1 - role]
    w = probe.size[1]
    if role == 0:
        return (_NO, other.position[1] - w, _NO, _YES)
    return (other.position[1] + other.size[1], _YES, _NO, _YES)


def _above(args, role, probe, floor_row):  # a.y + a.h <= b.y
    other = args[1 - role]
    h = probe.size[0]
    if role == 0:
        return (_NO, _YES, _NO, other.position[0] - h)
    return (_NO, _YES, other.position[0] + other.size[0], _YES)


def _h_aligned(args, role, probe, floor_row):
    ylo, yhi = _rows_overlap(args[1 - role], probe.size[0])
    return (_NO, _YES, ylo, yhi)


def _v_aligned(args, role, probe, floor_row):
    xlo, xhi = _cols_overlap(args[1 - role], probe.size[1])
    return (xlo, xhi, _NO, _YES)


def _dir_left_of(args, role, probe, floor_row):  # rows overlap and a.left < b.right
    other = args[1 - role]
    h, w = probe.size
    ylo, yhi = _rows_overlap(other, h)
    if role == 0:
        return (_NO, other.position[1] + other.size[1] - 2, ylo, yhi)
    return (other.position[1] - w + 2, _YES, ylo, yhi)


def _dir_above(args, role, probe, floor_row):  # columns overlap and a.top <= b.bottom (true with the quirk too)
    other = args[1 - role]
    h, w = probe.size
    xlo, xhi = _cols_overlap(other, w)
    if role == 0:
        return (xlo, xhi, _NO, other.position[0] + other.size[0] - 1)
    return (xlo, xhi, other.position[0] - h + 1, _YES)


def _region(supported: bool) -> BoundFn:
    """inside / inside_supported(a, b): some cell of a in b's region, so the bboxes overlap."""
    def bound(args: Sequence[WorldObject | None], role: int, probe: WorldObject, floor_row: int) -> Box | None:
        container = args[1] if role == 0 else probe
        assert container is not None  # a bound is only used once the clause's other argument is placed
        if container.family is None:
            return (1, 0, 1, 0)
        n = len(shape_library().get(container.family, ())) or 1
        box = _region_box(container.family, container.shape_idx % n, supported)
        if box is None:
            return (1, 0, 1, 0)
        top, left, bottom, right = box
        if role == 0:  # the object inside is placed now
            (by, bx), (h, w) = container.position, probe.size
            return (bx + left - w + 1, bx + right, by + top - h + 1, by + bottom)
        inside = args[0]
        assert inside is not None
        (ay, ax), (ah, aw) = inside.position, inside.size
        return (ax - right, ax + aw - 1 - left, ay - bottom, ay + ah - 1 - top)
    return bound


def _between(horizontal: bool) -> BoundFn:
    """h_between(c, a, b): left_of(a, c), rows of a and c overlap, left_of(c, b), rows of c and b overlap."""
    before, aligned = (_left_of, _h_aligned) if horizontal else (_above, _v_aligned)

    def bound(args: Sequence[WorldObject | None], role: int, probe: WorldObject, floor_row: int) -> Box | None:
        c, a, b = args
        boxes: list[Box] = []
        if role == 0:
            if a is not None:
                boxes += [before((a, None), 1, probe, floor_row), aligned((a, None), 1, probe, floor_row)]
            if b is not None:
                boxes += [before((None, b), 0, probe, floor_row), aligned((None, b), 0, probe, floor_row)]
        else:
            if c is not None:
                pair = (None, c) if role == 1 else (c, None)
                inner = 0 if role == 1 else 1
                boxes += [before(pair, inner, probe, floor_row), aligned(pair, inner, probe, floor_row)]
            outer = b if role == 1 else a
            if outer is not None:  # a and b are separated by c, which is at least one cell wide
                box = before((None, outer) if role == 1 else (outer, None), 0 if role == 1 else 1, probe, floor_row)
                boxes.append(_grow(box, role == 1, horizontal))
        if not boxes:
            return None
        return (max(b[0] for b in boxes), min(b[1] for b in boxes), max(b[2] for b in boxes),
                min(b[3] for b in boxes))
    return bound


def _grow(box: Box, lower: bool, horizontal: bool) -> Box:
    """Tighten a one-sided bound by one cell (upper bound down if ``lower``, else lower bound up)."""
    xlo, xhi, ylo, yhi = box
    if horizontal:
        return (xlo, xhi - 1, ylo, yhi) if lower else (xlo + 1, xhi, ylo, yhi)
    return (xlo, xhi, ylo, yhi - 1) if lower else (xlo, xhi, ylo + 1, yhi)


def _floor(args, role, probe, floor_row):
    return (_NO, _YES, floor_row, floor_row)


BOUNDS: dict[str, BoundFn] = {
    "touches": _reach(1), "adjacent": _reach(1), "near": _reach(2),
    "on_top": _on_top, "on_bottom": _swap(_on_top), "on_left": _on_left, "on_right": _swap(_on_left),
    "left_of": _left_of, "right_of": _swap(_left_of), "above": _above, "below": _swap(_above),
    "h_aligned": _h_aligned, "v_aligned": _v_aligned,
    "dir_left_of": _dir_left_of, "dir_right_of": _swap(_dir_left_of),
    "dir_above": _dir_above, "dir_below": _swap(_dir_above),
    "inside": _region(False), "inside_supported": _region(True),
    "h_between": _between(True), "v_between": _between(False),
    "floor": _floor,
}
"""Necessary position bounds per predicate (pruning only: every clause is still checked exactly)."""


# Necessary conditions of the ternary predicates: their conjuncts (and one implied relation), as
# (predicate, (argument positions)), checked as soon as both of their terms are placed.
CONJUNCTS: dict[str, tuple[tuple[str, tuple[int, int]], ...]] = {
    "h_between": (("left_of", (1, 0)), ("h_aligned", (1, 0)), ("left_of", (0, 2)), ("h_aligned", (0, 2)),
                  ("left_of", (1, 2))),  # implied: a left of c left of b
    "v_between": (("above", (1, 0)), ("v_aligned", (1, 0)), ("above", (0, 2)), ("v_aligned", (0, 2)),
                  ("above", (1, 2))),
}
