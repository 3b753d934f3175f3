"""Shape templates of the AAAI-18 PixelWorld concept data (spec section 4).

Every family is *generated* the way the original ``pattern_generator`` did it: its own legacy
``numpy.random.RandomState(seed)``, candidates drawn until ``num_samples`` distinct arrays exist,
kept in order of first appearance.  With the default :class:`LibraryParams` the result is
bit-identical to the original library (``shape_library.json.gz``, id ``7301d12e1d77``).

Three families are fixed shapes in the original source itself and are written out here the same
way: ``pixel``, ``small_container`` and ``small_table``.  No template is copied from reference data.

Two details of the original code are reproduced on purpose:

* ``blob`` growth used ``scipy.ndimage.maximum_filter`` with its default ``reflect`` border, so a
  set border cell stays set through its reflected neighbour;
* ``convex_blob`` rasterised each convex-hull edge of ``scipy.spatial.ConvexHull`` with an early
  release of the ``bresenham`` package, from the edge's first to its second vertex.  Qhull lists an
  edge's more recently inserted vertex first, so :class:`_Quickhull` re-enacts Qhull's 2-D
  insertion order (initial simplex, outside sets, furthest points, coplanar-horizon merges and its
  floating-point distances).
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from functools import cache, partial

import numpy as np

from pixelworld_env.errors import PixelWorldError

__all__ = ["FAMILIES", "LibraryParams", "build_library", "check_family", "shape_library", "template"]

FAMILIES: tuple[str, ...] = (
    "blob", "box", "chair", "container", "convex_blob", "cross", "d_slob", "enclosure",
    "floor_shape", "hline", "large_blob", "left_container", "left_noncontainer", "line",
    "lower_left_corner", "lower_right_corner", "noncontainer", "nonenclosure", "pixel",
    "rect_container", "right_container", "right_noncontainer", "small_blob", "small_container",
    "small_table", "sym_container", "table", "top_container", "top_noncontainer",
    "upper_left_corner", "upper_right_corner", "vline", "wall",
)
"""The 33 template families, in alphabetical order (the reference library's key order)."""

Sampler = Callable[[np.random.RandomState], np.ndarray]
Point = tuple[int, int]

_MAX_DRAWS = 10_000  # the original generator gave up after this many candidates


@dataclass(frozen=True)
class LibraryParams:
    """Sizes and seed of the shape library; the defaults are those of the AAAI-18 data."""

    container_width: int = 9
    container_height: int = 5
    box_width: int = 7
    box_height: int = 7
    max_width: int = 33  # floor_shape is 1 x max_width
    max_height: int = 16  # wall is max_height x 1
    seed: int = 42
    default_num_samples: int = 20  # template count of the container families


# --------------------------------------------------------------------------- simple families


def _fixed(rows: list[list[int]], rng: np.random.RandomState) -> np.ndarray:
    return np.array(rows, dtype=np.uint8)


def _hline(min_width: int, max_width: int, rng: np.random.RandomState) -> np.ndarray:
    return np.ones((1, rng.randint(min_width, max_width + 1)), dtype=np.uint8)


def _vline(min_height: int, max_height: int, rng: np.random.RandomState) -> np.ndarray:
    return np.ones((rng.randint(min_height, max_height + 1), 1), dtype=np.uint8)


def _line(max_width: int, max_height: int, rng: np.random.RandomState) -> np.ndarray:
    if rng.random_sample() < 0.5:
        return _hline(2, max_width, rng)
    return _vline(2, max_height, rng)


def _container(
    max_width: int,
    max_height: int,
    rng: np.random.RandomState,
    *,
    symmetric: bool = False,
    clip: bool = False,
    hole: bool = False,
    rotations: int = 0,
) -> np.ndarray:
    """Floor plus two walls (uncropped); optional hole, clipped corners and CCW rotations."""
    length = rng.randint(3, max_width + 1)
    left = rng.randint(2, max_height + 1)
    right = left if symmetric else rng.randint(2, max_height + 1)
    height = max(left, right)
    floor = height - 1
    arr = np.zeros((height, length), dtype=np.uint8)
    arr[floor, :] = 1
    arr[height - left : floor, 0] = 1
    arr[height - right : floor, length - 1] = 1
    if hole:
        k = rng.randint(length)
        if 0 < k < length - 1:
            arr[floor, k] = 0
        else:
            arr[floor - 1, k] = 0
    if clip:
        for col in (0, length - 1):
            if rng.uniform() < 0.5:
                arr[floor, col] = 0
    return np.ascontiguousarray(np.rot90(arr, rotations))


def _corner(
    max_width: int, max_height: int, row: int, col: int, rng: np.random.RandomState
) -> np.ndarray:
    """L shape: full row ``row`` and column ``col``; their shared cell is cleared with p = 1/2."""
    arr = np.zeros((rng.randint(2, max_height), rng.randint(2, max_width)), dtype=np.uint8)
    arr[row, :] = 1
    arr[:, col] = 1
    if rng.random_sample() < 0.5:
        arr[row, col] = 0
    return arr


def _enclosure(
    max_width: int,
    max_height: int,
    rng: np.random.RandomState,
    *,
    min_size: int = 3,
    clip: bool = False,
    hole: bool = False,
) -> np.ndarray:
    """Rectangle outline; optional hole in one side and clipped corners."""
    width = rng.randint(min_size, max_width + 1)
    height = rng.randint(min_size, max_height + 1)
    arr = np.zeros((height, width), dtype=np.uint8)
    arr[[0, -1], :] = 1
    arr[:, [0, -1]] = 1
    if hole:
        if rng.uniform() < 0.5:
            k = rng.randint(1, height - 1)
            arr[k, 0 if rng.uniform() < 0.5 else -1] = 0
        else:
            k = rng.randint(1, width - 1)
            arr[0 if rng.uniform() < 0.5 else -1, k] = 0
    if clip:
        for r, c in ((0, 0), (0, -1), (-1, -1), (-1, 0)):
            if rng.uniform() < 0.5:
                arr[r, c] = 0
    return arr


def _cross(max_width: int, max_height: int, rng: np.random.RandomState) -> np.ndarray:
    rows = rng.randint(3, max_width)  # the original swapped width and height here
    cols = rng.randint(3, max_height)
    arr = np.zeros((rows, cols), dtype=np.uint8)
    arr[rng.randint(1, rows - 1), :] = 1
    arr[:, rng.randint(1, cols - 1)] = 1
    return arr


def _chair(max_width: int, max_height: int, rng: np.random.RandomState) -> np.ndarray:
    back_height = rng.randint(1, max_height // 2)
    seat_width = rng.randint(3, max_width)
    leg_height = rng.randint(1, max_height - back_height - 1)
    back_col = 0 if rng.random_sample() < 0.5 else seat_width - 1
    leg = rng.randint(seat_width // 2)
    arr = np.zeros((back_height + leg_height + 1, seat_width), dtype=np.uint8)
    arr[leg_height, :] = 1  # the original put the seat at row leg_height
    arr[:leg_height, back_col] = 1
    arr[leg_height:, [leg, seat_width - leg - 1]] = 1
    return arr


def _table(max_width: int, max_height: int, rng: np.random.RandomState) -> np.ndarray:
    width = rng.randint(3, max_width)
    leg_height = rng.randint(1, max_height - 1)
    leg = rng.randint(width // 2)
    arr = np.zeros((leg_height + 1, width), dtype=np.uint8)
    arr[0, :] = 1
    arr[:, [leg, width - leg - 1]] = 1
    return arr


def _crop(arr: np.ndarray) -> np.ndarray:
    mask = arr > 0
    return arr[np.ix_(mask.any(1), mask.any(0))]


# --------------------------------------------------------------------------- blobs


def _is_connected(arr: np.ndarray) -> bool:
    """True iff the set cells form exactly one 4-connected component."""
    cells = set(zip(*np.nonzero(arr), strict=True))
    stack = [cells.pop()]
    while stack:
        r, c = stack.pop()
        for nb in ((r - 1, c), (r + 1, c), (r, c - 1), (r, c + 1)):
            if nb in cells:
                cells.remove(nb)
                stack.append(nb)
    return not cells


def _blob(size: int, rng: np.random.RandomState) -> np.ndarray:
    """Two random seeds on a size x size canvas, grown until 4-connected, then cropped."""
    arr = np.zeros((size, size), dtype=np.uint8)

    def add_pixel() -> None:
        row = rng.randint(0, size)
        arr[row, rng.randint(0, size)] = 1

    add_pixel()
    add_pixel()
    while not _is_connected(arr):
        # 4-neighbour maximum without the centre; edge padding = scipy's 'reflect' border
        pad = np.pad(arr, 1, mode="edge")
        arr = pad[:-2, 1:-1] | pad[2:, 1:-1] | pad[1:-1, :-2] | pad[1:-1, 2:]
        if rng.uniform() <= 0.1:
            add_pixel()
    return _crop(arr)


# --------------------------------------------------------------------------- convex blobs


@dataclass(eq=False, slots=True)
class _Edge:
    """A Qhull facet in 2-D: its two vertices (point indices, newest first) and outward plane."""

    verts: tuple[int, int]
    normal: tuple[float, float]
    offset: float
    nbrs: list[_Edge] = field(default_factory=list)  # nbrs[j]: the facet sharing verts[1 - j]
    outside: list[int] = field(default_factory=list)  # outside points, furthest last
    furthest: float = 0.0
    visible: bool = False
    new: bool = False
    replace: _Edge | None = None


class _Quickhull:
    """2-D re-enactment of the Qhull behind ``scipy.spatial.ConvexHull`` (default options).

    It gave the same edges, vertex order included, as SciPy 1.17 on 10^5 random point sets of up
    to 8 x 8 cells.  It follows Qhull's choices that decide which hull vertex is inserted first:
    the initial simplex (``qh_maxmin``/``qh_maxsimplex``), outside sets (``qh_partitionall``,
    ``qh_partitionpoint``), processing order (``qh_furthestnext``, ``qh_nextfurthest``), horizons,
    merges of new facets into coplanar horizon facets, and Qhull's floating-point distances.
    """

    _EPS = 1e-9  # integer points: real distances are either 0 or far above this
    _RATIO_MAXSIMPLEX = 1e-3

    def __init__(self, points: list[Point]) -> None:
        self.pts = points
        self.rank: dict[int, int] = {}  # point index -> insertion order (Qhull's vertex id)
        self.facets: list[_Edge] = []
        self.next = 0  # index of qh.facet_next in self.facets
        self.interior = (0.0, 0.0)

    def edges(self) -> list[tuple[Point, Point]]:
        """The hull edges as (newer vertex, older vertex)."""
        simplex = self._initial_simplex()
        if simplex is None:  # collinear input (Qhull would fail): the segment between the ends
            return [(self.pts[0], self.pts[-1])]
        for i in simplex:
            self.rank[i] = len(self.rank)
        self.interior = (
            sum(self.pts[i][0] for i in simplex) / 3,
            sum(self.pts[i][1] for i in simplex) / 3,
        )
        v2, v1, v0 = reversed(simplex)
        initial = [self._edge(v1, v0), self._edge(v2, v0), self._edge(v2, v1)]
        for f in initial:
            f.nbrs = [g for v in reversed(f.verts) for g in initial if g is not f and v in g.verts]
        self.facets = initial
        self._partition_all([i for i in range(len(self.pts)) if i not in simplex])
        with_outside = [f for f in self.facets if f.outside]
        if with_outside:  # qh_furthestnext: start with the furthest of all outside points
            first = max(with_outside, key=lambda f: f.furthest)
            self.facets.remove(first)
            self.facets.insert(0, first)
        while True:
            while self.next < len(self.facets) and not self.facets[self.next].outside:
                self.next += 1
            if self.next == len(self.facets):
                return [(self.pts[f.verts[0]], self.pts[f.verts[1]]) for f in self.facets]
            facet = self.facets[self.next]
            self._add_point(facet.outside.pop(), facet)

    def _initial_simplex(self) -> list[int] | None:
        pts = self.pts
        extremes = []  # qh_maxmin: first point with the min / max of each coordinate
        for k in range(2):
            lo = hi = 0
            for i, p in enumerate(pts):
                if pts[hi][k] < p[k]:
                    hi = i
                elif pts[lo][k] > p[k]:
                    lo = i
            extremes += [lo, hi]
        lo = min(extremes, key=lambda i: pts[i][0])
        hi = max(extremes, key=lambda i: pts[i][0])
        if pts[lo][0] == pts[hi][0]:
            return None
        width = max(max(p[k] for p in pts) - min(p[k] for p in pts) for k in range(2))
        target = (pts[hi][0] - pts[lo][0]) * width
        best, best_det = None, -1

        def det(i: int) -> int:
            return abs(_det(pts[lo], pts[hi], pts[i]))

        for i in extremes:
            if i not in (lo, hi) and det(i) > best_det:
                best, best_det = i, det(i)
        if best is None or best_det == 0 or best_det < self._RATIO_MAXSIMPLEX * target:
            for i in range(len(pts)):
                if i not in extremes and det(i) > best_det:
                    best, best_det = i, det(i)
                    if best_det > 10 * self._RATIO_MAXSIMPLEX * target:
                        break
        return None if best is None or best_det == 0 else [lo, hi, best]

    def _edge(self, a: int, b: int) -> _Edge:
        """Facet through points a and b, planes computed as qh_sethyperplane_det does."""
        if self.rank[a] < self.rank[b]:
            a, b = b, a
        (ax, ay), (bx, by) = self.pts[a], self.pts[b]
        nx, ny = float(by - ay), float(ax - bx)
        norm = math.sqrt(nx * nx + ny * ny)
        nx, ny = nx / norm, ny / norm
        offset = -(ax * nx + ay * ny)
        if offset + self.interior[0] * nx + self.interior[1] * ny > 0:
            nx, ny, offset = -nx, -ny, -offset
        return _Edge((a, b), (nx, ny), offset)

    def _dist(self, i: int, f: _Edge) -> float:
        x, y = self.pts[i]
        return f.offset + x * f.normal[0] + y * f.normal[1]

    def _move_to_end(self, f: _Edge) -> None:
        idx = self.facets.index(f)
        if idx < self.next:
            self.next -= 1
        del self.facets[idx]
        self.facets.append(f)

    def _partition_all(self, remaining: list[int]) -> None:
        for f in self.facets:
            inside, best, best_dist = [], None, 0.0
            for i in remaining:
                d = self._dist(i, f)
                if d < self._EPS:
                    inside.append(i)
                elif best is None or d > best_dist:
                    if best is not None:
                        f.outside.append(best)
                    best, best_dist = i, d
                else:
                    f.outside.append(i)
            if best is not None:
                f.outside.append(best)
                f.furthest = best_dist
            remaining = inside

    def _add_point(self, p: int, facet: _Edge) -> None:
        visible, coplanar = self._horizon(p, facet)
        self.rank[p] = len(self.rank)
        for f in self.facets:
            f.new = False
        cone = []
        for v in visible:  # qh_makenew_simplicial: one new facet per horizon vertex
            for j, nb in enumerate(v.nbrs):
                if not nb.visible:
                    nf = self._edge(p, v.verts[1 - j])
                    nf.new = True
                    nb.nbrs[nb.nbrs.index(v)] = nf
                    self.facets.append(nf)
                    cone.append((nf, nb))
                    v.replace = nf
        (a, a_horizon), (b, b_horizon) = cone
        a.nbrs, b.nbrs = [a_horizon, b], [b_horizon, a]
        for nf, horizon in cone:
            if horizon in coplanar:
                self._merge_into_horizon(nf, p)
        first_new = next(f for f in self.facets if f.new and not f.visible)
        for v in visible:  # qh_partitionvisible
            start = v.replace
            while start is not None and start.visible:
                start = start.replace
            for i in v.outside:
                self._partition_point(i, start or first_new)
        self.next = sum(not f.visible for f in self.facets[: self.next])
        self.facets = [f for f in self.facets if not f.visible]

    def _horizon(self, p: int, facet: _Edge) -> tuple[list[_Edge], list[_Edge]]:
        """qh_findhorizon: visible facets (moved to the list's end) and coplanar horizon facets."""
        facet.visible = True
        self._move_to_end(facet)
        visible, coplanar, seen = [facet], [], {id(facet)}
        for v in visible:
            for nb in v.nbrs:
                if id(nb) in seen:
                    continue
                seen.add(id(nb))
                d = self._dist(p, nb)
                if d > self._EPS:
                    nb.visible = True
                    visible.append(nb)
                    self._move_to_end(nb)
                elif d > -self._EPS:
                    coplanar.append(nb)
        return visible, coplanar

    def _merge_into_horizon(self, nf: _Edge, apex: int) -> None:
        """Merge new facet ``nf`` (apex, shared) into its collinear horizon facet (shared, other)."""
        horizon, shared = nf.nbrs[0], nf.verts[1]
        other = horizon.verts[0] if horizon.verts[1] == shared else horizon.verts[1]
        across_other = horizon.nbrs[horizon.verts.index(shared)]
        horizon.verts = (apex, other)
        horizon.nbrs = [across_other, nf.nbrs[1]]
        nf.nbrs[1].nbrs[nf.nbrs[1].nbrs.index(nf)] = horizon
        nf.visible = True
        nf.replace = horizon
        horizon.new = True
        self._move_to_end(horizon)

    def _partition_point(self, i: int, start: _Edge) -> None:
        """qh_partitionpoint with qh_findbest: first new facet found above ``i``, else drop it."""
        best, best_dist = start, self._dist(i, start)
        facet: _Edge | None = start
        seen = {id(start)}
        while facet is not None and best_dist < self._EPS:
            facet = None
            for nb in best.nbrs:
                if nb.new and id(nb) not in seen:
                    seen.add(id(nb))
                    d = self._dist(i, nb)
                    if d > best_dist:
                        best, best_dist, facet = nb, d, nb
                        break
        if best_dist < self._EPS:
            for nb in best.nbrs:  # qh_findbesthorizon
                d = self._dist(i, nb)
                if d > best_dist:
                    best, best_dist = nb, d
            if best_dist < self._EPS:
                return
        if not best.outside:
            best.outside.append(i)
            best.furthest = best_dist
            if not best.new:
                self._move_to_end(best)
        elif best_dist > best.furthest:
            best.outside.append(i)
            best.furthest = best_dist
        else:
            best.outside.insert(len(best.outside) - 1, i)


def _det(o: Point, a: Point, b: Point) -> int:
    """Twice the signed area of the triangle o, a, b."""
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


def _raster_line(start: Point, end: Point) -> Iterator[Point]:
    """Cells of the segment start -> end as the early ``bresenham`` package drew them."""
    (x0, y0), (x1, y1) = start, end
    dx, dy = x1 - x0, y1 - y0
    sx, sy = (1 if dx > 0 else -1), (1 if dy > 0 else -1)
    dx, dy = abs(dx), abs(dy)
    if dx > dy:
        xx, xy, yx, yy = sx, 0, 0, sy
    else:
        dx, dy = dy, dx
        xx, xy, yx, yy = 0, sy, sx, 0
    err, y = 2 * dy - dx, 0
    for x in range(dx + 1):
        yield x0 + x * xx + y * yx, y0 + x * xy + y * yy
        if err > 0:
            y += 1
            err -= dx
        err += dy


def _convex_blob(size: int, rng: np.random.RandomState) -> np.ndarray:
    """5-10 random points, hull edges rasterised, cropped, each row filled between its ends."""
    arr = np.zeros((size, size), dtype=np.uint8)
    for _ in range(rng.randint(5, 11)):
        row = rng.randint(0, size)
        arr[row, rng.randint(0, size)] = 1
    points = [(int(r), int(c)) for r, c in zip(*np.nonzero(arr), strict=True)]
    for start, end in _Quickhull(points).edges():
        for r, c in _raster_line(start, end):
            arr[r, c] = 1
    arr = _crop(arr)
    for line in arr:
        cols = np.flatnonzero(line)
        line[cols[0] : cols[-1] + 1] = 1
    return arr


# --------------------------------------------------------------------------- the library


def _family_specs(p: LibraryParams) -> dict[str, tuple[Sampler, int]]:
    """Every family's candidate sampler and template count, as the original ``make_shapes``."""
    cw, ch, bw, bh = p.container_width, p.container_height, p.box_width, p.box_height
    n = p.default_num_samples
    container = partial(_container, cw, ch)
    specs: dict[str, tuple[Sampler, int]] = {
        "pixel": (partial(_fixed, [[1]]), 1),
        "small_blob": (partial(_blob, 3), 20),
        "blob": (partial(_blob, 5), 30),
        "d_slob": (partial(_blob, 3), 20),
        "large_blob": (partial(_blob, 7), 50),
        "convex_blob": (partial(_convex_blob, 7), 50),
        "line": (partial(_line, bw, bh), bw - 2 + bh - 2),
        "hline": (partial(_hline, 2, bw), bw - 2),
        "vline": (partial(_vline, 2, bh), bh - 2),
        "floor_shape": (partial(_hline, p.max_width, p.max_width), 1),
        "wall": (partial(_vline, p.max_height, p.max_height), 1),
        "sym_container": (partial(container, symmetric=True), n),
        "rect_container": (container, n),
        "small_container": (partial(_fixed, [[1, 0, 0, 1], [1, 1, 1, 1]]), 1),
        "small_table": (partial(_fixed, [[1, 1, 1, 1], [1, 0, 0, 1]]), 1),
        "lower_left_corner": (partial(_corner, cw, ch, -1, 0), 20),
        "lower_right_corner": (partial(_corner, cw, ch, -1, -1), 20),
        "upper_left_corner": (partial(_corner, cw, ch, 0, 0), 20),
        "upper_right_corner": (partial(_corner, cw, ch, 0, -1), 20),
        "box": (partial(_enclosure, bw, bh), 10),
        "enclosure": (partial(_enclosure, bw, bh, min_size=4, clip=True), 20),
        "nonenclosure": (partial(_enclosure, bw, bh, min_size=4, clip=True, hole=True), 20),
        "cross": (partial(_cross, bw, bh), 20),
        "chair": (partial(_chair, 5, 8), 20),
        "table": (partial(_table, 8, 5), 20),
    }
    # counter-clockwise quarter turns: the closed side ends up left / right / top
    for prefix, rotations in (("", 0), ("left_", 3), ("right_", 1), ("top_", 2)):
        specs[f"{prefix}container"] = (partial(container, clip=True, rotations=rotations), n)
        specs[f"{prefix}noncontainer"] = (partial(container, clip=True, hole=True, rotations=rotations), n)
    return specs


def _distinct(family: str, sampler: Sampler, count: int, seed: int) -> tuple[np.ndarray, ...]:
    """Draw from a fresh ``RandomState(seed)`` until ``count`` distinct arrays are collected."""
    rng = np.random.RandomState(seed)
    found: dict[tuple[tuple[int, ...], bytes], np.ndarray] = {}
    draws = 0
    while len(found) < count:
        if draws == _MAX_DRAWS:
            raise RuntimeError(
                f"{family}: only {len(found)} distinct templates of {count} in {_MAX_DRAWS} draws"
            )
        draws += 1
        arr = np.ascontiguousarray(sampler(rng), dtype=np.uint8)
        found.setdefault((arr.shape, arr.tobytes()), arr)
    for arr in found.values():
        arr.flags.writeable = False
    return tuple(found.values())


def build_library(params: LibraryParams = LibraryParams()) -> dict[str, tuple[np.ndarray, ...]]:
    """Generate every family's templates (read-only uint8 arrays of 0/1), keyed in FAMILIES order."""
    specs = _family_specs(params)
    return {name: _distinct(name, *specs[name], params.seed) for name in FAMILIES}


@cache
def shape_library() -> dict[str, tuple[np.ndarray, ...]]:
    """The default (AAAI-18) library, built once."""
    return build_library()


def check_family(family: str) -> str:
    """``family`` if it is one of :data:`FAMILIES`, else a ``ValueError`` naming it and the closest names."""
    if family not in FAMILIES:
        close = difflib.get_close_matches(family, FAMILIES, n=3)
        hint = f"; did you mean {', '.join(close)}?" if close else f"; known families: {', '.join(FAMILIES)}"
        raise PixelWorldError(f"unknown shape family {family!r}{hint}")
    return family


def template(family: str, shape_idx: int) -> np.ndarray:
    """Template ``shape_idx`` of ``family``, taken modulo the family size (spec section 3.8)."""
    templates = shape_library()[check_family(family)]
    return templates[shape_idx % len(templates)]
