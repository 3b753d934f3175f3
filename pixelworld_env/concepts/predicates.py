"""The predicate vocabulary of the concept language (docs/design.md, "Vocabulary").

Every predicate is a function of world objects (and an :class:`EvalContext`). Geometry uses each object's
template bounding box (``position`` + ``size``, which may include empty rows or columns) and its pixels.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cache

from pixelworld_env.core.constants import Color
from pixelworld_env.core.objects import WorldObject
from pixelworld_env.core.regions import inside_masks
from pixelworld_env.core.shapes import FAMILIES


@dataclass(frozen=True)
class EvalContext:
    """What predicates need beyond the objects: the floor row and the ``dir_above`` compatibility flag."""

    floor_row: int
    dir_above_quirk: bool = False


Predicate = Callable[..., bool]


@dataclass(frozen=True)
class PredicateSpec:
    """A predicate of the vocabulary: its ``name``, ``arity`` and function ``fn(objects..., ctx)``. ``reads`` (unary
    predicates) names the attributes of an object it depends on, among generation's ``shape``, ``shape_idx``,
    ``color``, ``is_target``, ``x``, ``y``: the constraint problem of dataset generation
    (:mod:`pixelworld_env.generation.csp`) constrains only those; ``None`` means any of them."""

    name: str
    arity: int
    fn: Predicate
    reads: tuple[str, ...] | None = None


# ---------------------------------------------------------------------------------------------- geometry


def _bbox(o: WorldObject) -> tuple[int, int, int, int]:
    """(top, left, bottom, right), inclusive."""
    (top, left), (h, w) = o.position, o.size
    return top, left, top + h - 1, left + w - 1


@cache
def _ball(radius_sq: int, chebyshev: bool) -> tuple[tuple[int, int], ...]:
    r = int(radius_sq**0.5) if not chebyshev else radius_sq
    return tuple(
        (dr, dc)
        for dr in range(-r, r + 1)
        for dc in range(-r, r + 1)
        if (max(abs(dr), abs(dc)) <= radius_sq if chebyshev else dr * dr + dc * dc <= radius_sq)
    )


def _within(a: WorldObject, b: WorldObject, radius_sq: int, chebyshev: bool = False) -> bool:
    """Whether some pixel of ``a`` and some pixel of ``b`` are within the distance (squared for Euclid)."""
    reach = radius_sq if chebyshev else int(radius_sq**0.5)
    at, al, ab, ar = _bbox(a)
    bt, bl, bb, br = _bbox(b)
    if at > bb + reach or bt > ab + reach or al > br + reach or bl > ar + reach:
        return False
    small, large = (a.pixels, b.pixels) if len(a.pixels) <= len(b.pixels) else (b.pixels, a.pixels)
    offsets = _ball(radius_sq, chebyshev)
    return any((r + dr, c + dc) in large for r, c in small for dr, dc in offsets)


def touches(a: WorldObject, b: WorldObject, ctx: EvalContext) -> bool:
    return _within(a, b, 1, chebyshev=True)


def adjacent(a: WorldObject, b: WorldObject, ctx: EvalContext) -> bool:
    return _within(a, b, 1)


def near(a: WorldObject, b: WorldObject, ctx: EvalContext) -> bool:
    return _within(a, b, 4)


def far(a: WorldObject, b: WorldObject, ctx: EvalContext) -> bool:
    return not _within(a, b, 16)


def left_of(a: WorldObject, b: WorldObject, ctx: EvalContext) -> bool:
    return a.position[1] + a.size[1] <= b.position[1]


def right_of(a: WorldObject, b: WorldObject, ctx: EvalContext) -> bool:
    return b.position[1] + b.size[1] <= a.position[1]


def above(a: WorldObject, b: WorldObject, ctx: EvalContext) -> bool:
    return a.position[0] + a.size[0] <= b.position[0]


def below(a: WorldObject, b: WorldObject, ctx: EvalContext) -> bool:
    return b.position[0] + b.size[0] <= a.position[0]


def h_aligned(a: WorldObject, b: WorldObject, ctx: EvalContext) -> bool:
    at, _, ab, _ = _bbox(a)
    bt, _, bb, _ = _bbox(b)
    return at <= bb and bt <= ab


def v_aligned(a: WorldObject, b: WorldObject, ctx: EvalContext) -> bool:
    _, al, _, ar = _bbox(a)
    _, bl, _, br = _bbox(b)
    return al <= br and bl <= ar


def _lines(cells: list[tuple[int, int]]) -> dict[int, tuple[int, int]]:
    """Map each line index (first coordinate) to the (min, max) of the second coordinate."""
    spans: dict[int, tuple[int, int]] = {}
    for line, pos in cells:
        lo, hi = spans.get(line, (pos, pos))
        spans[line] = (min(lo, pos), max(hi, pos))
    return spans


def _strictly_before(a: WorldObject, b: WorldObject, axis: int,
                     lines: Callable[[WorldObject], dict[int, tuple[int, int]]]) -> bool:
    """``a`` before ``b`` along ``axis`` (1: columns, left of; 0: rows, above) on the lines they share.

    The bboxes must share lines across ``axis``. If they are separated along ``axis`` the bboxes decide;
    otherwise, on every shared line (``lines`` maps line -> (min, max) position along ``axis``), every cell of
    ``a`` must precede every cell of ``b``, on at least one line where both have cells.
    """
    across = 1 - axis
    a_lo, b_lo = a.position, b.position
    a_hi = (a_lo[0] + a.size[0] - 1, a_lo[1] + a.size[1] - 1)
    b_hi = (b_lo[0] + b.size[0] - 1, b_lo[1] + b.size[1] - 1)
    if a_lo[across] > b_hi[across] or b_lo[across] > a_hi[across]:
        return False
    if a_hi[axis] < b_lo[axis]:
        return True
    if b_hi[axis] < a_lo[axis]:
        return False
    a_lines, b_lines = lines(a), lines(b)
    found = False
    for line in range(max(a_lo[across], b_lo[across]), min(a_hi[across], b_hi[across]) + 1):
        a_span, b_span = a_lines.get(line), b_lines.get(line)
        if a_span and b_span:
            if a_span[1] >= b_span[0]:
                return False
            found = True
    return found


def _rows(o: WorldObject) -> dict[int, tuple[int, int]]:
    return _lines(list(o.pixels))


def _columns(o: WorldObject) -> dict[int, tuple[int, int]]:
    return _lines([(c, r) for r, c in o.pixels])


def _columns_aaai18(o: WorldObject) -> dict[int, tuple[int, int]]:
    """The original's columns: template cell (i, j) counted as column i + x, row j + y (the ``dir_above`` quirk)."""
    top, left = o.position
    return _lines([(i + left, j + top) for i, j in o.cells])


def dir_left_of(a: WorldObject, b: WorldObject, ctx: EvalContext) -> bool:
    return _strictly_before(a, b, 1, _rows)


def dir_right_of(a: WorldObject, b: WorldObject, ctx: EvalContext) -> bool:
    return dir_left_of(b, a, ctx)


def dir_above(a: WorldObject, b: WorldObject, ctx: EvalContext) -> bool:
    return _strictly_before(a, b, 0, _columns_aaai18 if ctx.dir_above_quirk else _columns)


def dir_below(a: WorldObject, b: WorldObject, ctx: EvalContext) -> bool:
    return dir_above(b, a, ctx)


def on_top(a: WorldObject, b: WorldObject, ctx: EvalContext) -> bool:
    return above(a, b, ctx) and adjacent(a, b, ctx)


def on_bottom(a: WorldObject, b: WorldObject, ctx: EvalContext) -> bool:
    return below(a, b, ctx) and adjacent(a, b, ctx)


def on_left(a: WorldObject, b: WorldObject, ctx: EvalContext) -> bool:
    return left_of(a, b, ctx) and adjacent(a, b, ctx)


def on_right(a: WorldObject, b: WorldObject, ctx: EvalContext) -> bool:
    return right_of(a, b, ctx) and adjacent(a, b, ctx)


def h_between(c: WorldObject, a: WorldObject, b: WorldObject, ctx: EvalContext) -> bool:
    """``c`` lies between ``a`` (left) and ``b`` (right), sharing rows with both (middle argument first)."""
    return left_of(a, c, ctx) and h_aligned(a, c, ctx) and left_of(c, b, ctx) and h_aligned(c, b, ctx)


def v_between(c: WorldObject, a: WorldObject, b: WorldObject, ctx: EvalContext) -> bool:
    """``c`` lies between ``a`` (above) and ``b`` (below), sharing columns with both."""
    return above(a, c, ctx) and v_aligned(a, c, ctx) and above(c, b, ctx) and v_aligned(c, b, ctx)


def _in_region(a: WorldObject, b: WorldObject, supported: bool) -> bool:
    if b.family is None:
        return False
    masks = inside_masks(b.template, b.family)
    mask = masks[1] if supported else masks[0]
    top, left = b.position
    h, w = b.size
    for r, c in a.pixels:
        i, j = r - top, c - left
        if 0 <= i < h and 0 <= j < w and mask[i, j]:
            return True
    return False


def inside(a: WorldObject, b: WorldObject, ctx: EvalContext) -> bool:
    return _in_region(a, b, supported=False)


def inside_supported(a: WorldObject, b: WorldObject, ctx: EvalContext) -> bool:
    return _in_region(a, b, supported=True)


# ---------------------------------------------------------------------------------------------- registry

_GROUPS: dict[str, frozenset[str]] = {
    "lower_corner": frozenset({"lower_left_corner", "lower_right_corner"}),
    "corner": frozenset({"lower_left_corner", "lower_right_corner", "upper_left_corner", "upper_right_corner"}),
    "potential_container": frozenset({"container", "noncontainer", "lower_left_corner", "lower_right_corner"}),
    "object": frozenset({"blob", "small_blob", "convex_blob", "container", "noncontainer", "enclosure",
                         "nonenclosure"}),
}
_COLORS = {"white": Color.WHITE, "red": Color.RED, "blue": Color.BLUE, "green": Color.GREEN,
           "yellow": Color.YELLOW, "orange": Color.ORANGE}


def _family_is(family: str) -> Predicate:
    return lambda a, ctx: a.family == family


def _family_in(families: frozenset[str]) -> Predicate:
    return lambda a, ctx: a.family in families


def _color_is(color: int) -> Predicate:
    return lambda a, ctx: a.color == color


def _floor(a: WorldObject, ctx: EvalContext) -> bool:
    return a.family == "floor_shape" and a.position[0] == ctx.floor_row


def _build_registry() -> dict[str, PredicateSpec]:
    unary: dict[str, Predicate] = {family: _family_is(family) for family in FAMILIES}
    unary.update({name: _family_in(group) for name, group in _GROUPS.items()})
    unary.update({name: _color_is(color) for name, color in _COLORS.items()})
    unary["floor"] = _floor
    unary["target"] = lambda a, ctx: a.is_target
    unary["pushable"] = lambda a, ctx: a.pushable
    binary: dict[str, Predicate] = {
        f.__name__: f
        for f in (touches, adjacent, near, far, left_of, right_of, above, below, h_aligned, v_aligned,
                  dir_left_of, dir_right_of, dir_above, dir_below, on_top, on_bottom, on_left, on_right,
                  inside, inside_supported)
    }
    binary.update({
        "bottom_aligned": lambda a, b, ctx: a.position[0] == b.position[0],  # tops equal (original naming)
        "top_aligned": lambda a, b, ctx: a.position[0] + a.size[0] == b.position[0] + b.size[0],
        "left_aligned": lambda a, b, ctx: a.position[1] == b.position[1],
        "right_aligned": lambda a, b, ctx: a.position[1] + a.size[1] == b.position[1] + b.size[1],
        "taller": lambda a, b, ctx: a.size[0] > b.size[0],
        "wider": lambda a, b, ctx: a.size[1] > b.size[1],
        "same_height": lambda a, b, ctx: a.size[0] == b.size[0],
        "same_width": lambda a, b, ctx: a.size[1] == b.size[1],
        "same_color": lambda a, b, ctx: a.color == b.color,
        "diff_color": lambda a, b, ctx: a.color != b.color,
        "same_kind": lambda a, b, ctx: a.family == b.family,
        "diff_kind": lambda a, b, ctx: a.family != b.family,
        "same_shape": lambda a, b, ctx: a.family == b.family and a.shape_idx == b.shape_idx,
    })
    reads: dict[str, tuple[str, ...]] = {
        **{name: ("shape",) for name in (*FAMILIES, *_GROUPS)},
        **{name: ("color",) for name in _COLORS},
        "floor": ("shape", "y"),
        "target": ("is_target",),
    }
    registry = {name: PredicateSpec(name, 1, fn, reads.get(name)) for name, fn in unary.items()}
    registry.update({name: PredicateSpec(name, 2, fn) for name, fn in binary.items()})
    registry.update({f.__name__: PredicateSpec(f.__name__, 3, f) for f in (h_between, v_between)})
    return registry


PREDICATES: dict[str, PredicateSpec] = _build_registry()
"""Every predicate of the vocabulary by name."""
