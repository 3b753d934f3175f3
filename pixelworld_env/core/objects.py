"""World objects: an engine class, a colour, a position and a rigid template of cells (docs/design.md, "The
world")."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

from pixelworld_env.core.constants import MAX_WORLD_CELLS, MOVEABLE_CLASSES, Color, ObjectClass
from pixelworld_env.errors import PixelWorldError
from pixelworld_env.validation import check_int

Cell = tuple[int, int]


@dataclass(frozen=True)
class WorldObject:
    """One object of a scene.

    ``position`` is the ``(row, col)`` of the top-left corner of the object's template, ``cells`` the
    ``(drow, dcol)`` offsets of its pixels and ``size`` the ``(height, width)`` of the template array. The
    template may contain empty rows or columns (clipped containers), so ``size`` is stored, not derived:
    every bounding-box relation of the concept language uses it.
    """

    cls: ObjectClass
    color: int
    position: Cell
    cells: tuple[Cell, ...] = ((0, 0),)
    size: Cell = (1, 1)
    family: str | None = "pixel"
    shape_idx: int = 0
    pushable: bool = False
    is_target: bool = False
    name: str = field(default="", compare=False)

    def __post_init__(self) -> None:
        if not self.cells:
            raise PixelWorldError(f"object of class {self.cls!s} has no cells")
        height, width = self.size
        for dr, dc in self.cells:
            if not (0 <= dr < height and 0 <= dc < width):
                raise PixelWorldError(f"cell offset {(dr, dc)} lies outside the template size {self.size}")

    @property
    def is_self(self) -> bool:
        return self.cls is ObjectClass.SELF

    @property
    def is_frame(self) -> bool:
        return self.cls is ObjectClass.FRAME

    @property
    def moveable(self) -> bool:
        """Whether a move plan may shift this object (the self, ``basic`` and ``complex`` objects)."""
        return self.cls in MOVEABLE_CLASSES

    @cached_property
    def template(self) -> np.ndarray:
        """The template array (``size``), 1 on the object's cells; read-only."""
        array = np.zeros(self.size, dtype=np.uint8)
        rows, cols = zip(*self.cells, strict=True)
        array[list(rows), list(cols)] = 1
        array.flags.writeable = False
        return array

    @cached_property
    def pixels(self) -> frozenset[Cell]:
        """Absolute ``(row, col)`` cells occupied in the world."""
        row, col = self.position
        return frozenset((row + dr, col + dc) for dr, dc in self.cells)

    def moved_to(self, position: Cell) -> WorldObject:
        """A copy of this object at another position."""
        return replace(self, position=(int(position[0]), int(position[1])))


def cell_extent(cells: tuple[Cell, ...]) -> Cell:
    """The smallest template size that holds ``cells`` (offsets counted from the template's corner)."""
    return (max(r for r, _ in cells) + 1, max(c for _, c in cells) + 1)


def object_class(family: str, *, is_self: bool = False, pushable: bool = False) -> ObjectClass:
    """The engine class of an object (docs/design.md, "The world"): ``self``, else ``basic``/``complex`` when
    pushable, else ``immoveable``/``immoveable_big`` (one-pixel ``pixel`` family vs any other family)."""
    if is_self:
        return ObjectClass.SELF
    if pushable:
        return ObjectClass.BASIC if family == "pixel" else ObjectClass.COMPLEX
    return ObjectClass.IMMOVEABLE if family == "pixel" else ObjectClass.IMMOVEABLE_BIG


def check_world_size(height: object, width: object, what: str) -> tuple[int, int]:
    """A world's ``height`` and ``width`` as ints: integers >= 1 (bools and floats refused) of at most
    :data:`~pixelworld_env.core.constants.MAX_WORLD_CELLS` cells; ``what`` names the world in the message."""
    height, width = check_int(height, f"{what}: height", 1), check_int(width, f"{what}: width", 1)
    if height * width > MAX_WORLD_CELLS:
        raise PixelWorldError(f"{what}: a {height} x {width} world has {height * width:,} cells, more than the limit "
                              f"of {MAX_WORLD_CELLS:,} (pixelworld_env.core.constants.MAX_WORLD_CELLS)")
    return height, width


def frame_object(height: int, width: int) -> WorldObject:
    """The frame of a ``height`` x ``width`` world: the border ring, colour 7 (the size checked by
    :func:`check_world_size`)."""
    check_world_size(height, width, "frame")
    cells = tuple((r, c) for r in range(height) for c in range(width) if r in (0, height - 1) or c in (0, width - 1))
    return WorldObject(cls=ObjectClass.FRAME, color=Color.PURPLE, position=(0, 0), cells=cells, size=(height, width),
                       family=None, name=ObjectClass.FRAME.value)
