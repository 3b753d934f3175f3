"""Colour codes, object classes and world dimensions of the AAAI-18 PixelWorld (docs/design.md, "The world")."""

from __future__ import annotations

from enum import IntEnum, StrEnum

HEIGHT = 18
"""World height in cells, frame included (the paper's 20 counts one more ring around the frame)."""
WIDTH = 35
"""World width in cells, frame included."""
FLOOR_HEIGHT = 3
"""The floor's top row is ``height - FLOOR_HEIGHT`` (row 15 in an 18-row world)."""
PADDING = 2
"""Generated objects keep this distance from the world border (docs/design.md, "The constraint problem and the
sampler")."""
MAX_WORLD_CELLS = 1_000_000
"""The most cells of a world (``height x width``, frame included; the benchmark's worlds have 18 x 35 = 630): the
engine keeps arrays of a world's cells per scene and per environment, so a larger world is refused before anything
is built (scenes, frames, dataset specs)."""

class Color(IntEnum):
    """Colour codes of the state array."""

    EMPTY = 0
    WHITE = 1
    RED = 2
    BLUE = 3
    GREEN = 4
    YELLOW = 5
    MAGENTA = 6
    PURPLE = 7
    ORANGE = 8


NUM_COLORS = len(Color)


class ObjectClass(StrEnum):
    """Engine classes of the minimal PixelWorld (docs/design.md, "The world")."""

    SELF = "self"
    BASIC = "basic"
    COMPLEX = "complex"
    IMMOVEABLE = "immoveable"
    IMMOVEABLE_BIG = "immoveable_big"
    FRAME = "frame"


MOVEABLE_CLASSES = frozenset({ObjectClass.SELF, ObjectClass.BASIC, ObjectClass.COMPLEX})

EMPTY = -1
"""Owner-array entry of an empty cell (the world's arrays are padded by one ring of ``OUTSIDE`` cells)."""
OUTSIDE = -2
"""Owner-array entry of a cell outside the world."""
