"""The ``Scene`` value type: a world size and its objects, with the sample-JSON and text formats."""

from __future__ import annotations

import string
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from functools import cached_property
from typing import Any

import numpy as np

from pixelworld_env.core.constants import FLOOR_HEIGHT, Color, ObjectClass
from pixelworld_env.core.objects import Cell, WorldObject, cell_extent, check_world_size, frame_object, object_class
from pixelworld_env.core.shapes import check_family, shape_library
from pixelworld_env.errors import PixelWorldError, PixelWorldTypeError

_PIXEL_CLASSES = frozenset({ObjectClass.SELF, ObjectClass.BASIC, ObjectClass.IMMOVEABLE})
_DEFAULT_LETTER_FAMILY = "blob"

ASCII_LEGEND = {
    "#": "frame",
    "=": "floor (blue, family floor_shape)",
    "S": "self",
    ".": "empty",
    "a-z": "one immoveable white object per letter",
    "A-Z": "one pushable white object per letter (S excepted)",
}


def _known_family(family: str, what: str) -> str:
    try:
        return check_family(family)
    except ValueError as exc:
        raise PixelWorldError(f"{what}: {exc}") from None


def _template_size(family: str | None, shape_idx: int, cells: tuple[Cell, ...]) -> Cell:
    """The template size of an object read from a dict without an explicit ``size``.

    Library objects (the original samples) keep their library template's size, which may include empty
    rows or columns; anything else gets the extent of its cells.
    """
    templates = shape_library().get(family or "")
    if templates:
        tmpl = templates[shape_idx % len(templates)]
        rows, cols = np.nonzero(tmpl)
        if sorted(cells) == sorted(zip(rows.tolist(), cols.tolist(), strict=True)):
            return (int(tmpl.shape[0]), int(tmpl.shape[1]))
    return cell_extent(cells)


@dataclass(frozen=True)
class Scene:
    """A PixelWorld state: ``height`` x ``width`` cells (frame included) and the objects in spec order.

    Exactly one object is the self; at most one is the frame. The size is checked by
    :func:`~pixelworld_env.core.objects.check_world_size` (at most ``MAX_WORLD_CELLS`` cells). Scenes are immutable
    values: moving the self gives a new scene (see :meth:`with_positions`).
    """

    height: int
    width: int
    objects: tuple[WorldObject, ...]

    def __post_init__(self) -> None:
        check_world_size(self.height, self.width, "scene")
        selves = [i for i, obj in enumerate(self.objects) if obj.is_self]
        if len(selves) != 1:
            raise PixelWorldError(f"a scene needs exactly one self object, found {len(selves)}")
        if sum(obj.is_frame for obj in self.objects) > 1:
            raise PixelWorldError("a scene has at most one frame object")
        for i, obj in enumerate(self.objects):
            for r, c in obj.pixels:
                if not (0 <= r < self.height and 0 <= c < self.width):
                    raise PixelWorldError(
                        f"object {i} ({obj.family or obj.cls}) has a pixel at row {r}, column {c}, outside the "
                        f"{self.height} x {self.width} world"
                    )

    @cached_property
    def self_index(self) -> int:
        return next(i for i, obj in enumerate(self.objects) if obj.is_self)

    @property
    def self_object(self) -> WorldObject:
        return self.objects[self.self_index]

    @property
    def floor_row(self) -> int:
        """The row on which the ``floor`` predicate expects the floor's top (``height - 3``)."""
        return self.height - FLOOR_HEIGHT

    def grid(self) -> np.ndarray:
        """The state array of colour codes, objects drawn in order (later objects on top)."""
        grid = np.zeros((self.height, self.width), dtype=np.int8)
        for obj in self.objects:
            for r, c in obj.pixels:
                if 0 <= r < self.height and 0 <= c < self.width:
                    grid[r, c] = obj.color
        return grid

    def with_positions(self, positions: Sequence[Cell]) -> Scene:
        """A copy whose objects stand at ``positions`` (one per object, in order)."""
        objects = tuple(
            obj if obj.position == tuple(pos) else obj.moved_to(pos)
            for obj, pos in zip(self.objects, positions, strict=True)
        )
        return replace(self, objects=objects)

    # ------------------------------------------------------------------ sample JSON

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Scene:
        """Read a scene from the ``height``, ``width`` and ``objects`` fields of a sample line.

        Objects may carry an optional ``size`` (template height and width); without it, an object whose
        cells equal its library template (family, ``shape_idx`` modulo the family size) gets that
        template's size, otherwise the extent of its cells.
        """
        try:
            height, width = int(data["height"]), int(data["width"])
            raw_objects = data["objects"]
        except KeyError as exc:
            raise PixelWorldError(f"scene dict lacks the field {exc.args[0]!r}") from None
        objects = [_object_from_dict(raw, height, width, i) for i, raw in enumerate(raw_objects)]
        return cls(height=height, width=width, objects=tuple(objects))

    def to_dict(self) -> dict[str, Any]:
        """The inverse of :meth:`from_dict` (the sample format, plus ``size`` where it cannot be inferred)."""
        return {"height": self.height, "width": self.width, "objects": [_object_to_dict(o) for o in self.objects]}

    # ------------------------------------------------------------------ text format

    @classmethod
    def from_ascii(cls, text: str, kinds: Mapping[str, str] | None = None) -> Scene:
        """Read a scene drawn as text, frame included (legend in ``ASCII_LEGEND``): ``#`` must fill exactly the
        border ring, and a drawing without a frame is refused.

        ``kinds`` maps object letters to shape families (default ``blob``). Blank leading/trailing lines
        and surrounding whitespace of each row are ignored.
        """
        if not isinstance(text, str):
            raise PixelWorldTypeError(f"Scene.from_ascii needs the scene drawn as a string, got {type(text).__name__}")
        kinds = dict(kinds or {})
        rows = [line.strip() for line in text.strip("\n").splitlines()]
        while rows and not rows[0]:
            rows.pop(0)
        while rows and not rows[-1]:
            rows.pop()
        if not rows:
            raise PixelWorldError("empty scene text")
        width = len(rows[0])
        for r, row in enumerate(rows):
            if len(row) != width:
                raise PixelWorldError(f"ragged scene text: row {r} has {len(row)} characters, row 0 has {width}")
        height = len(rows)
        for letter, family in kinds.items():
            if len(letter) != 1 or letter not in string.ascii_letters or letter == "S":
                raise PixelWorldError(f"kinds: {letter!r} is not an object letter (a-z or A-Z except S)")
            _known_family(family, f"kinds[{letter!r}]")
        cells_of: dict[str, list[Cell]] = {}
        frame_cells: list[Cell] = []
        for r, row in enumerate(rows):
            for c, ch in enumerate(row):
                if ch == ".":
                    continue
                if ch == "#":
                    frame_cells.append((r, c))
                elif ch == "=" or ch in string.ascii_letters:
                    cells_of.setdefault(ch, []).append((r, c))
                else:
                    raise PixelWorldError(f"unknown character {ch!r} at row {r}, column {c}; legend: {ASCII_LEGEND}")
        unused = sorted(set(kinds) - set(cells_of))
        if unused:
            raise PixelWorldError(f"kinds names letters that do not appear in the scene: {', '.join(unused)}")
        selves = cells_of.get("S", [])
        if len(selves) != 1:
            where = ", ".join(f"row {r} column {c}" for r, c in selves)
            raise PixelWorldError("the scene needs exactly one self 'S'" + (f", found {len(selves)} at {where}"
                                                                           if selves else ", found none"))
        objects: list[WorldObject] = []
        for ch in sorted(cells_of, key=lambda k: (k != "=", k)):
            objects.append(_object_from_letter(ch, cells_of[ch], kinds))
        if not frame_cells:
            raise PixelWorldError(f"the scene has no frame: draw '#' on its whole border ring (rows 0 and "
                                  f"{height - 1}, columns 0 and {width - 1}); PixelWorld's worlds are framed")
        frame = frame_object(height, width)
        if set(frame_cells) != set(frame.cells):
            bad = sorted(set(frame_cells) - set(frame.cells)) or sorted(set(frame.cells) - set(frame_cells))
            raise PixelWorldError(
                f"'#' is the frame and must fill exactly the border ring; row {bad[0][0]}, column "
                f"{bad[0][1]} breaks that"
            )
        objects.append(frame)
        return cls(height=height, width=width, objects=tuple(objects))

    def ascii_letters(self) -> dict[int, str]:
        """The letter :meth:`to_ascii` draws for each object index."""
        lower = iter(string.ascii_lowercase)
        upper = iter(ch for ch in string.ascii_uppercase if ch != "S")
        letters: dict[int, str] = {}
        for i, obj in enumerate(self.objects):
            if obj.is_self:
                letters[i] = "S"
            elif obj.is_frame:
                letters[i] = "#"
            elif obj.family == "floor_shape" and obj.color == Color.BLUE and not obj.moveable:
                letters[i] = "="
            else:
                letter = next(upper if obj.moveable else lower, None)
                if letter is None:
                    raise PixelWorldError("too many objects for the text format (26 per kind)")
                letters[i] = letter
        return letters

    def ascii_kinds(self) -> dict[str, str]:
        """The ``kinds`` mapping that makes ``Scene.from_ascii(scene.to_ascii(), kinds)`` round-trip."""
        return {
            letter: self.objects[i].family or ""
            for i, letter in self.ascii_letters().items()
            if letter in string.ascii_letters and letter != "S"
        }

    def to_ascii(self) -> str:
        """The text drawing of this scene (frame included), one line per row."""
        canvas = [["."] * self.width for _ in range(self.height)]
        for i, letter in self.ascii_letters().items():
            for r, c in self.objects[i].pixels:
                if 0 <= r < self.height and 0 <= c < self.width:
                    canvas[r][c] = letter
        return "\n".join("".join(row) for row in canvas)


def _object_from_letter(ch: str, cells: list[Cell], kinds: Mapping[str, str]) -> WorldObject:
    top = min(r for r, _ in cells)
    left = min(c for _, c in cells)
    offsets = tuple(sorted((r - top, c - left) for r, c in cells))
    if ch == "S":
        return WorldObject(cls=ObjectClass.SELF, color=Color.RED, position=(top, left), name="self")
    if ch == "=":
        family = "floor_shape"
        return WorldObject(
            cls=ObjectClass.IMMOVEABLE_BIG, color=Color.BLUE, position=(top, left), cells=offsets,
            size=cell_extent(offsets), family=family, name=ObjectClass.IMMOVEABLE_BIG.value,
        )
    family = kinds.get(ch, _DEFAULT_LETTER_FAMILY)
    pushable = ch.isupper()
    klass = object_class(family, pushable=pushable)
    return WorldObject(
        cls=klass, color=Color.WHITE, position=(top, left), cells=offsets, size=cell_extent(offsets),
        family=family, pushable=pushable, name=klass.value,
    )


def _object_from_dict(raw: Mapping[str, Any], height: int, width: int, index: int) -> WorldObject:
    where = f"object {index}"
    try:
        klass = ObjectClass(raw["class"])
    except KeyError:
        raise PixelWorldError(f"{where} lacks the field 'class'") from None
    except ValueError:
        known = ", ".join(k.value for k in ObjectClass)
        raise PixelWorldError(f"{where}: unknown class {raw['class']!r}; expected one of {known}") from None
    meta = raw.get("meta", {})
    if klass is ObjectClass.FRAME:
        frame = frame_object(height, width)
        return replace(frame, color=int(raw.get("color", Color.PURPLE)), name=raw.get("name", "frame"))
    if "position" not in raw:
        raise PixelWorldError(f"{where} ({klass}) lacks the field 'position'")
    family = meta.get("shape", "pixel")
    shape_idx = int(meta.get("shape_idx", 0))
    cells = tuple((int(r), int(c)) for r, c in raw.get("shape", [[0, 0]]))
    if any(r < 0 or c < 0 for r, c in cells):
        raise PixelWorldError(f"{where}: shape offsets must be >= 0 (position is the template's top-left)")
    size = tuple(raw["size"]) if "size" in raw else _template_size(family, shape_idx, cells)
    return WorldObject(
        cls=klass, color=int(raw["color"]), position=(int(raw["position"][0]), int(raw["position"][1])),
        cells=cells, size=(int(size[0]), int(size[1])), family=family, shape_idx=shape_idx,
        pushable=bool(meta.get("pushable", False)), is_target=bool(meta.get("is_target", False)),
        name=raw.get("name", klass.value),
    )


def _object_to_dict(obj: WorldObject) -> dict[str, Any]:
    meta: dict[str, Any] = {"is_self": obj.is_self, "pushable": obj.pushable, "is_target": obj.is_target}
    out: dict[str, Any] = {"class": obj.cls.value, "name": obj.name or obj.cls.value, "color": int(obj.color)}
    if obj.is_frame:
        out["meta"] = meta
        return out
    out["position"] = [obj.position[0], obj.position[1]]
    if not (obj.cls in _PIXEL_CLASSES and obj.cells == ((0, 0),)):
        out["shape"] = [[r, c] for r, c in obj.cells]
    if obj.size != _template_size(obj.family, obj.shape_idx, obj.cells):
        out["size"] = [obj.size[0], obj.size[1]]
    meta["shape"] = obj.family
    meta["shape_idx"] = obj.shape_idx
    out["meta"] = meta
    return out
