"""The predicate vocabulary of the concept language (docs/design.md, "Vocabulary").

Every predicate is a function of world objects (and an :class:`EvalContext`). Geometry uses each object's
template bounding box (``position`` + ``size``, which may include empty rows or columns) and its pixels.

Each predicate has one entry in :data:`PREDICATES` (a :class:`PredicateSpec`), which holds everything known of
it: its function and arity, the attributes a unary one reads, and what dataset generation needs of it
(:class:`GenerationFacts`: the position bound that prunes the search, its conjuncts, whether it is expensive to
evaluate). Adding a predicate is one entry in :func:`_build_registry` (with its function and, optionally, its
bound in this file); generation keeps no table of its own keyed by predicate names.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import cache

import numpy as np

from pixelworld_env.core.constants import Color
from pixelworld_env.core.objects import WorldObject
from pixelworld_env.core.regions import inside_masks
from pixelworld_env.core.shapes import FAMILIES, shape_library


@dataclass(frozen=True)
class EvalContext:
    """What predicates need beyond the objects: the floor row and the ``dir_above`` compatibility flag."""

    floor_row: int
    dir_above_quirk: bool = False


Predicate = Callable[..., bool]

Box = tuple[int, int, int, int]
"""``(xlo, xhi, ylo, yhi)``, inclusive (empty when ``xlo > xhi`` or ``ylo > yhi``): where a top-left may go."""
BoundFn = Callable[[Sequence[WorldObject | None], int, WorldObject, int], Box | None]
"""A placement bound ``bound(args, role, probe, floor_row)``: the box that the top-left ``(x, y)`` of the clause's
argument ``role`` must lie in for the predicate to hold, given the arguments already placed (``args``, ``None``
for those not placed yet), ``probe`` (the object being placed, at the origin: its template and size) and the floor
row; ``None``: no information."""


@dataclass(frozen=True)
class GenerationFacts:
    """What dataset generation (:mod:`pixelworld_env.generation.sampling`) knows of a predicate besides its function.
    All of it only prunes or orders the search: every clause is still checked exactly by the predicate's function.

    ``bound``: the necessary position bound of a clause (a :data:`BoundFn`), or ``None`` (no pruning); a binary
    bound is used once the other argument is placed, a ternary one with whichever arguments are placed, a unary one
    for a position-dependent predicate (``floor``). ``conjuncts``: necessary relations, as ``(predicate, (argument
    positions))``, checked as soon as both of their arguments are placed (``h_between``: its ``left_of`` and
    ``h_aligned`` parts). ``expensive``: a pixel-level test, checked after the cheap box relations of the same
    term. ``shape_idx``: it reads ``shape_idx`` itself, not only the template (``same_shape``), so a template that
    failed under one ``shape_idx`` is tried again under another.

    **GENERATOR_VERSION.** :data:`pixelworld_env.generation.dataset.GENERATOR_VERSION` must change when a change
    alters the scenes generated for a given seed (it is part of the dataset cache's key). The search draws its
    random choices from the boxes the bounds leave and backtracks where a check fails, so a change of an existing
    predicate's function, ``bound``, ``conjuncts`` or ``shape_idx`` may alter them: bump the version if the
    byte-identity tests of ``tests/test_generation.py`` (or a comparison of the catalog's datasets before and
    after) show it does. ``expensive`` only orders the checks of one candidate position, never what they decide,
    and a new predicate alters no existing dataset (no generator names it yet): neither needs a bump."""

    bound: BoundFn | None = None
    conjuncts: tuple[tuple[str, tuple[int, int]], ...] = ()
    expensive: bool = False
    shape_idx: bool = False


@dataclass(frozen=True)
class PredicateSpec:
    """A predicate of the vocabulary: its ``name``, ``arity`` and function ``fn(objects..., ctx)``. ``reads`` (unary
    predicates) names the attributes of an object it depends on, among generation's ``shape``, ``shape_idx``,
    ``color``, ``is_target``, ``x``, ``y``: the constraint problem of dataset generation
    (:mod:`pixelworld_env.generation.csp`) constrains only those; ``None`` means any of them. ``generation``: what
    the generator's search needs of it (:class:`GenerationFacts`, where GENERATOR_VERSION is explained)."""

    name: str
    arity: int
    fn: Predicate
    reads: tuple[str, ...] | None = None
    generation: GenerationFacts = field(default_factory=GenerationFacts)


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


# ---------------------------------------------------------------------------------------------- placement bounds
# Generation's pruning (GenerationFacts.bound): necessary conditions on the top-left (x, y) of the object being
# placed, from a clause and the objects already placed. Each returns (xlo, xhi, ylo, yhi) (inclusive; may be empty)
# or None (no information). ``args`` holds the clause's objects with None for unplaced ones, ``role`` the argument
# position of the object being placed, ``probe`` that object at the origin (its template and size).


@cache
def _region_box(family: str, template_index: int, supported: bool) -> tuple[int, int, int, int] | None:
    """(top, left, bottom, right) of the inside (or inside_supported) mask of a template, or None if empty."""
    tmpl = shape_library()[family][template_index]
    mask = inside_masks(tmpl, family)[1 if supported else 0]
    rows, cols = np.nonzero(mask)
    if not len(rows):
        return None
    return int(rows.min()), int(cols.min()), int(rows.max()), int(cols.max())


_NO = -(10**6)
_YES = 10**6


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
        inner = args[0]
        assert inner is not None
        (ay, ax), (ah, aw) = inner.position, inner.size
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


def _on_floor_row(args, role, probe, floor_row):
    return (_NO, _YES, floor_row, floor_row)


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
    """Every predicate's entry: name, arity, function, what a unary one reads and its generation facts (the
    pruning bound, the conjuncts, ``expensive``, ``shape_idx``: :class:`GenerationFacts`)."""
    G = GenerationFacts
    entries = [
        # unary: shape families and groups, colours, the floor, the target and pushable flags
        *(PredicateSpec(family, 1, _family_is(family), ("shape",)) for family in FAMILIES),
        *(PredicateSpec(name, 1, _family_in(group), ("shape",)) for name, group in _GROUPS.items()),
        *(PredicateSpec(name, 1, _color_is(color), ("color",)) for name, color in _COLORS.items()),
        PredicateSpec("floor", 1, _floor, ("shape", "y"), G(bound=_on_floor_row)),
        PredicateSpec("target", 1, lambda a, ctx: a.is_target, ("is_target",)),
        PredicateSpec("pushable", 1, lambda a, ctx: a.pushable),
        # binary: distance, boxes, direction, contact, regions
        PredicateSpec("touches", 2, touches, generation=G(bound=_reach(1), expensive=True)),
        PredicateSpec("adjacent", 2, adjacent, generation=G(bound=_reach(1), expensive=True)),
        PredicateSpec("near", 2, near, generation=G(bound=_reach(2), expensive=True)),
        PredicateSpec("far", 2, far),
        PredicateSpec("left_of", 2, left_of, generation=G(bound=_left_of)),
        PredicateSpec("right_of", 2, right_of, generation=G(bound=_swap(_left_of))),
        PredicateSpec("above", 2, above, generation=G(bound=_above)),
        PredicateSpec("below", 2, below, generation=G(bound=_swap(_above))),
        PredicateSpec("h_aligned", 2, h_aligned, generation=G(bound=_h_aligned)),
        PredicateSpec("v_aligned", 2, v_aligned, generation=G(bound=_v_aligned)),
        PredicateSpec("dir_left_of", 2, dir_left_of, generation=G(bound=_dir_left_of)),
        PredicateSpec("dir_right_of", 2, dir_right_of, generation=G(bound=_swap(_dir_left_of))),
        PredicateSpec("dir_above", 2, dir_above, generation=G(bound=_dir_above)),
        PredicateSpec("dir_below", 2, dir_below, generation=G(bound=_swap(_dir_above))),
        PredicateSpec("on_top", 2, on_top, generation=G(bound=_on_top)),
        PredicateSpec("on_bottom", 2, on_bottom, generation=G(bound=_swap(_on_top))),
        PredicateSpec("on_left", 2, on_left, generation=G(bound=_on_left)),
        PredicateSpec("on_right", 2, on_right, generation=G(bound=_swap(_on_left))),
        PredicateSpec("inside", 2, inside, generation=G(bound=_region(False), expensive=True)),
        PredicateSpec("inside_supported", 2, inside_supported, generation=G(bound=_region(True), expensive=True)),
        # binary: alignment, size, colour and family comparisons (no bound)
        PredicateSpec("bottom_aligned", 2, lambda a, b, ctx: a.position[0] == b.position[0]),  # tops equal (original)
        PredicateSpec("top_aligned", 2, lambda a, b, ctx: a.position[0] + a.size[0] == b.position[0] + b.size[0]),
        PredicateSpec("left_aligned", 2, lambda a, b, ctx: a.position[1] == b.position[1]),
        PredicateSpec("right_aligned", 2, lambda a, b, ctx: a.position[1] + a.size[1] == b.position[1] + b.size[1]),
        PredicateSpec("taller", 2, lambda a, b, ctx: a.size[0] > b.size[0]),
        PredicateSpec("wider", 2, lambda a, b, ctx: a.size[1] > b.size[1]),
        PredicateSpec("same_height", 2, lambda a, b, ctx: a.size[0] == b.size[0]),
        PredicateSpec("same_width", 2, lambda a, b, ctx: a.size[1] == b.size[1]),
        PredicateSpec("same_color", 2, lambda a, b, ctx: a.color == b.color),
        PredicateSpec("diff_color", 2, lambda a, b, ctx: a.color != b.color),
        PredicateSpec("same_kind", 2, lambda a, b, ctx: a.family == b.family),
        PredicateSpec("diff_kind", 2, lambda a, b, ctx: a.family != b.family),
        PredicateSpec("same_shape", 2, lambda a, b, ctx: a.family == b.family and a.shape_idx == b.shape_idx,
                      generation=G(shape_idx=True)),
        # ternary: the middle argument first; conjuncts as (predicate, (argument positions)), the last one implied
        PredicateSpec("h_between", 3, h_between, generation=G(bound=_between(True), conjuncts=(
            ("left_of", (1, 0)), ("h_aligned", (1, 0)), ("left_of", (0, 2)), ("h_aligned", (0, 2)),
            ("left_of", (1, 2))))),  # implied: a left of c left of b
        PredicateSpec("v_between", 3, v_between, generation=G(bound=_between(False), conjuncts=(
            ("above", (1, 0)), ("v_aligned", (1, 0)), ("above", (0, 2)), ("v_aligned", (0, 2)),
            ("above", (1, 2))))),
    ]
    registry = {spec.name: spec for spec in entries}
    assert len(registry) == len(entries), "a predicate name is entered twice"
    for spec in entries:  # a conjunct names a binary predicate, at argument positions of the clause
        for name, positions in spec.generation.conjuncts:
            assert registry[name].arity == 2 and all(0 <= i < spec.arity for i in positions), (spec.name, name)
    return registry


PREDICATES: dict[str, PredicateSpec] = _build_registry()
"""Every predicate of the vocabulary by name."""
