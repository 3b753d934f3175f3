"""Generated objects: library templates as objects and as bit masks, for the search of
:mod:`pixelworld_env.generation.sampling`. Where a clause lets an object go (its placement bound, its conjuncts) is
part of the predicate's own entry: :class:`pixelworld_env.concepts.predicates.GenerationFacts`."""

from __future__ import annotations

from functools import cache

import numpy as np

from pixelworld_env.core.objects import WorldObject, object_class
from pixelworld_env.core.shapes import check_family, shape_library

__all__ = ["library_object", "make_object", "template_data", "template_mask"]


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
