"""Dataset generation: generators sampled as constraint problems, filtered by a concept (spec §3.7, §3.8).

A generator is a concept expression whose variables (plus ``self``) each become one object. Its objects
are sampled from a constraint problem: per term a shape family, a ``shape_idx`` (0..49, template =
``shape_idx mod family size``), a colour, a target flag and a position, subject to the generator's
positive clauses, a global no-overlap constraint and the frame / padding bounds. Negated groups are
checked by rejection on the finished assignment. :func:`generate` then draws from the generators
(uniformly at random), drops duplicates, labels each scene with the dataset's concept and fills the
label quotas (classification) or keeps only scenes in which the goal does not hold (bring-about).

Search method
-------------
The sampler is a **custom seeded randomized depth-first backtracking search** over exactly the domains
and constraints of spec §3.8 (the AAAI-18 sampler was itself a randomized DFS with restarts). It was
chosen over ``python-constraint2`` after prototyping both on this machine (2 slow cores, Python 3.11).
The ``python-constraint2`` 2.9 prototype used separate integer ``x``/``y`` variables, ``shape``,
``shape_idx`` and ``color`` variables, ``FunctionConstraint`` s calling the real predicates (and a
pixel no-overlap constraint per pair of terms), frame/padding constraints, and every domain shuffled by
the generator's seeded stream before each ``getSolution()``. Per-sample times (python-constraint2 with
shapes and the placement order below forced first through dummy constraints / this module):

* ``bfaw-self-on-floor``: 35 ms / 0.1 ms;
* ``bfaw-self-in-container-on-floor``: 84 ms / 0.2 ms;
* ``bfaw-self-touches-container-on-floor``: 89 ms / 0.2 ms;
* ``bfaw-self-between-container-and-noncontainer-on-floor``: 4.5 s, 6 of 15 runs over 5 s / 0.3 ms;
* ``bfaw-object-left-of-self-on-floor-with-distractors-in-between-right``: 3.0 s, 7 of 20 runs over
  5 s / 3 ms (mostly rejections by its negated ``touches`` clauses).

With the solver's own variable order (most constrained first, so positions before shapes) even the
one-container generators mostly ran over 5 s per sample. Forward checking only prunes a variable once
all other variables of a constraint are assigned, so relations are evaluated over whole position
domains, and the solver has no restarts to escape thrashing. The custom search generates the whole
catalog (136 datasets, 9,150 accepted scenes, ~10,900 draws) in about 7 s.

How the search works (``_GeneratorSampler``):

1. Unary clauses (family names and groups, colours, ``target``, ``floor``) are evaluated with the real
   predicates on probe objects to prune each term's (family, colour, target) combinations; a term with
   none left makes the generator unsatisfiable (reported at once). A negated *single* unary clause whose
   truth does not depend on position (e.g. ``~target(x)``) prunes the same way, which is equivalent to
   rejecting it.
2. Terms are placed one at a time in a fixed order: terms with a position-fixing unary clause (the floor)
   first, then greedily the term linked by clauses to the most already placed terms (non-self before
   self, then the term with fewer linked terms in all, then by name). The object order of the scene is unaffected
   (terms sorted by name, frame last).
3. For each term the search chooses, in this order and each from a freshly shuffled domain: the family,
   the ``shape_idx`` (a template that failed is not retried under another ``shape_idx`` of the same
   node), colour and target, and finally the position. Positions are drawn without replacement from a
   rectangle obtained by intersecting the frame / padding bounds with *necessary* bounding-box
   conditions of the clauses that link the term to placed terms (e.g. ``on_top(x,f)`` fixes
   ``x.y = f.y - h``; ``inside_supported(self,x)`` confines the self to the box of ``x``'s
   inside-supported mask). A candidate is kept if it overlaps no placed object (an integer bit mask test)
   and every clause whose terms are now all placed holds, evaluated by the real predicate functions of
   :data:`pixelworld_env.concepts.predicates.PREDICATES` on :class:`WorldObject` s (``dir_above`` with the
   AAAI-18 quirk). ``h_between``/``v_between`` with two of three terms placed are pre-checked by their
   defining conjuncts (``left_of`` and ``h_aligned``, resp. ``above`` and ``v_aligned``) and by the
   implied ``left_of(a,b)`` (resp. ``above(a,b)``) of the outer terms.
4. Every template and every position tried counts as one search step. After
   ``RESTART_STEPS`` steps the search restarts (the cap doubles after every 10 restarts); after
   ``MAX_SEARCH_STEPS`` steps for one sample, or when a search exhausts the whole tree, the generator is
   reported as unsatisfiable. A complete assignment that makes a negated group true is rejected and the
   search runs again; ``MAX_REJECTIONS`` rejections in a row are an error too.

Samples are random-DFS samples, not uniform over all solutions, as in the original: the first family
and ``shape_idx`` tried are uniform over the term's domain, so family frequencies follow the original
closely (checked against the 8,700 original samples by the slow fidelity test).

Determinism: only Python's :class:`random.Random` with integer seeds (portable) and integer arithmetic
are used. The generator choice and the final shuffle use ``random.Random(seed)``; each generator has
its own stream ``random.Random(int(sha256(f"{seed}:{generator name}")[:16], 16))`` — unlike the
original, where every generator stream started from the same seed, but like it in that the same
generator with the same seed gives the same sequence in every dataset that uses it.
"""

from __future__ import annotations

import difflib
import hashlib
import math
import random
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cache
from typing import TYPE_CHECKING, Any

import numpy as np

from pixelworld_env.concepts import Concept, ConceptError, expand, parse
from pixelworld_env.concepts.parser import SELF, Clause, Expression
from pixelworld_env.concepts.predicates import PREDICATES, EvalContext
from pixelworld_env.constants import FLOOR_HEIGHT, HEIGHT, PADDING, WIDTH, Color
from pixelworld_env.errors import PixelWorldError, PixelWorldKeyError
from pixelworld_env.objects import WorldObject, frame_object, object_class
from pixelworld_env.oracle import goal_reachable
from pixelworld_env.regions import inside_masks
from pixelworld_env.scene import Scene
from pixelworld_env.shapes import FAMILIES, check_family, shape_library
from pixelworld_env.validation import check_seed

if TYPE_CHECKING:
    from pixelworld_env.definitions import DefinitionSet

__all__ = [
    "COLORS",
    "GENERATOR_VERSION",
    "KINDS",
    "NUM_SHAPE_IDX",
    "DatasetSpec",
    "GeneratedDataset",
    "GenerationError",
    "GeneratorStats",
    "generate",
    "library_object",
    "split",
]

GENERATOR_VERSION = 2  # 2: bring-about scenes whose goal cannot be reached are dropped
"""Bump whenever a change of this module can change generated datasets (part of the cache key)."""

KINDS = ("classification", "bring-about")
COLORS: tuple[int, ...] = (1, 2, 3, 4, 5, 8)
"""Colour domain of generated objects (spec §3.8)."""
NUM_SHAPE_IDX = 50
"""``shape_idx`` domain is 0..49 (the largest family size); template = ``shape_idx mod family size``."""
FRAME_EXEMPT = frozenset({"floor_shape", "wall"})
"""Families that only need to lie inside the frame, not inside the padding."""
SUPPORTED_SETTINGS = frozenset({"allow_targets", "allow_pushable"})

RESTART_STEPS = 1000
"""Search steps before a restart; the cap doubles after every 10 restarts."""
MAX_SEARCH_STEPS = 200_000
"""Search steps for one sample before the generator is declared unsatisfiable."""
MAX_REJECTIONS = 1000
"""Consecutive solutions rejected by negated groups before the generator is declared unsatisfiable."""
DRAWS_PER_SAMPLE = 200
"""Default draw budget of :func:`generate`: this many draws per sample of the quota (``num_samples``)."""

# Predicates that read ``shape_idx`` itself (not only the template); with them, templates that failed
# under one shape_idx are retried under another.
_SHAPE_IDX_PREDICATES = frozenset({"same_shape"})


class GenerationError(PixelWorldError):
    """A generator is unsatisfiable, or a dataset cannot reach its quota within the budget."""


# ---------------------------------------------------------------------------------------------- specs


@dataclass(frozen=True)
class DatasetSpec:
    """Everything that determines a generated dataset (besides the seed).

    ``generators`` are ``(name, logic)`` pairs; ``macros`` is the merged concept + generator table
    used to expand both the concept and the generators. ``num_samples`` is the quota per label for
    classification (50 + 50) and the total for bring-about (50). The world is ``height`` x ``width``
    cells with the frame, the floor's top row is ``height - floor_height``, and generated objects keep
    ``padding`` cells from the border (spec §1.1).
    """

    name: str
    kind: str
    concept: str
    generators: tuple[tuple[str, str], ...]
    macros: Mapping[str, str] = field(default_factory=dict)
    settings: Mapping[str, Any] = field(default_factory=dict)
    num_samples: int = 50
    height: int = HEIGHT
    width: int = WIDTH
    floor_height: int = FLOOR_HEIGHT
    padding: int = PADDING

    def __post_init__(self) -> None:
        kind = {"bringabout": "bring-about", "bring_about": "bring-about"}.get(self.kind, self.kind)
        if kind not in KINDS:
            raise PixelWorldError(f"dataset {self.name!r}: kind must be one of {KINDS}, got {self.kind!r}")
        object.__setattr__(self, "kind", kind)
        generators = tuple((str(name), str(logic)) for name, logic in self.generators)
        if not generators:
            raise PixelWorldError(f"dataset {self.name!r} has no generators")
        object.__setattr__(self, "generators", generators)
        object.__setattr__(self, "macros", dict(self.macros))
        object.__setattr__(self, "settings", dict(self.settings or {}))
        unknown = sorted(set(self.settings) - SUPPORTED_SETTINGS)
        if unknown:
            raise PixelWorldError(f"dataset {self.name!r}: unsupported settings {unknown}; supported: "
                                  f"{sorted(SUPPORTED_SETTINGS)}")
        if self.num_samples < 1:
            raise PixelWorldError(f"dataset {self.name!r}: num_samples must be >= 1, got {self.num_samples}")
        if self.height < 3 or self.width < 3 or self.padding < 0 or not 0 < self.floor_height < self.height:
            raise PixelWorldError(f"dataset {self.name!r}: bad world size {self.height} x {self.width} "
                                  f"(floor_height {self.floor_height}, padding {self.padding})")

    def __hash__(self) -> int:  # equal specs hash equally (the mappings are left out)
        return hash((self.name, self.kind, self.concept, self.generators, self.num_samples, self.height, self.width,
                     self.floor_height, self.padding))

    @classmethod
    def from_definitions(cls, definitions: DefinitionSet, name: str, **overrides: Any) -> DatasetSpec:
        """The spec of dataset ``name`` of a :class:`~pixelworld_env.definitions.DefinitionSet`."""
        try:
            dataset = definitions.datasets[name]
        except KeyError:
            close = difflib.get_close_matches(name, list(definitions.datasets), n=3)
            hint = f"; did you mean {', '.join(close)}?" if close else ""
            raise PixelWorldKeyError(f"unknown dataset {name!r}{hint}") from None
        macros = definitions.macros
        values: dict[str, Any] = {
            "name": name, "kind": dataset.kind, "concept": definitions.concepts[dataset.concept].logic,
            "generators": tuple((g, definitions.generators[g].logic) for g in dataset.generators),
            "macros": macros, "settings": dict(dataset.settings),
        }
        values.update(overrides)
        return cls(**values)

    @property
    def allow_targets(self) -> bool:
        return bool(self.settings.get("allow_targets", False))

    @property
    def allow_pushable(self) -> bool:
        return bool(self.settings.get("allow_pushable", False))

    @property
    def size(self) -> int:
        """The number of scenes of the dataset (``2 * num_samples`` for classification)."""
        return 2 * self.num_samples if self.kind == "classification" else self.num_samples

    def used_macros(self) -> dict[str, str]:
        """The macros reachable from the concept and the generators (name -> logic), sorted by name."""
        used: dict[str, str] = {}
        todo = [self.concept, *(logic for _, logic in self.generators)]
        while todo:
            expression = parse(todo.pop())
            for clause in (*expression.positives, *(c for g in expression.negations for c in g)):
                if clause.name in self.macros and clause.name not in used:
                    used[clause.name] = self.macros[clause.name]
                    todo.append(self.macros[clause.name])
        return dict(sorted(used.items()))


@dataclass(frozen=True)
class GeneratorStats:
    """What one generator did during :func:`generate`.

    ``samples``: solutions delivered (each one a draw); ``kept``: of those, scenes in the dataset;
    ``duplicates``: delivered scenes identical to an earlier one; ``rejected``: complete assignments
    rejected by a negated group; ``search_steps`` and ``restarts``: search effort.
    """

    name: str
    samples: int = 0
    kept: int = 0
    duplicates: int = 0
    rejected: int = 0
    search_steps: int = 0
    restarts: int = 0


@dataclass(frozen=True)
class GeneratedDataset:
    """A generated dataset: scenes (objects in term order, frame last), labels and provenance.

    Bring-about labels are all 1. ``generator_of[i]`` names the generator that produced scene ``i``.
    ``draws`` counts generator samples taken, ``duplicates`` those identical to an earlier sample, and
    ``filtered`` those dropped by the concept filter (bring-about: goal already true; classification:
    label quota already full); ``unreachable`` counts bring-about scenes dropped because no sequence of moves
    reaches the goal (:func:`pixelworld_env.oracle.goal_reachable`).
    """

    spec: DatasetSpec
    seed: int
    scenes: tuple[Scene, ...]
    labels: tuple[int, ...]
    generator_of: tuple[str, ...]
    draws: int = 0
    duplicates: int = 0
    filtered: int = 0
    unreachable: int = 0
    generator_stats: tuple[GeneratorStats, ...] = ()

    def __len__(self) -> int:
        return len(self.scenes)

    @property
    def name(self) -> str:
        return self.spec.name

    @property
    def kind(self) -> str:
        return self.spec.kind

    __hash__ = None  # type: ignore[assignment]


# ---------------------------------------------------------------------------------------------- geometry


@cache
def _template_data(family: str, template_index: int) -> tuple[tuple[tuple[int, int], ...], tuple[int, int], int]:
    """(cells, (height, width), number of cells) of a library template."""
    tmpl = shape_library()[family][template_index]
    rows, cols = np.nonzero(tmpl)
    cells = tuple(zip(rows.tolist(), cols.tolist(), strict=True))
    return cells, (int(tmpl.shape[0]), int(tmpl.shape[1])), len(cells)


@cache
def _mask(family: str, template_index: int, width: int) -> int:
    cells, _, _ = _template_data(family, template_index)
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
def _make_object(is_self: bool, family: str, shape_idx: int, color: int, target: bool, pushable: bool,
                 y: int, x: int) -> WorldObject:
    n = len(shape_library()[family])
    cells, size, _ = _template_data(family, shape_idx % n)
    cls = object_class(family, is_self=is_self, pushable=pushable)
    return WorldObject(cls=cls, color=color, position=(y, x), cells=cells, size=size, family=family,
                       shape_idx=shape_idx, pushable=pushable, is_target=target, name=cls.value)


def library_object(family: str, shape_idx: int, color: int, position: tuple[int, int], *, is_self: bool = False,
                   is_target: bool = False, pushable: bool = False) -> WorldObject:
    """A generated object: library template ``shape_idx mod family size`` at ``position`` (row, col).

    The class follows spec §1.2: ``self`` for the self, ``basic``/``complex`` for pushable objects,
    else ``immoveable`` (pixels) or ``immoveable_big``.
    """
    check_family(family)
    return _make_object(is_self, family, int(shape_idx), int(color), bool(is_target), bool(pushable),
                        int(position[0]), int(position[1]))


# Bounds: necessary conditions on the top-left (x, y) of the object being placed, from a clause and the
# objects already placed. Each returns (xlo, xhi, ylo, yhi) (inclusive; may be empty) or None (no
# information). ``args`` holds the clause's objects with None for unplaced ones, ``role`` the argument
# position of the object being placed, ``probe`` that object at the origin (its template and size).

Box = tuple[int, int, int, int]
_NO = -(10**6)
_YES = 10**6
_BoundFn = Callable[[Sequence[WorldObject | None], int, WorldObject, int], Box | None]


def _reach(r: int) -> _BoundFn:
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


def _swap(fn: _BoundFn) -> _BoundFn:
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


def _region(supported: bool) -> _BoundFn:
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


def _between(horizontal: bool) -> _BoundFn:
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


_BOUNDS: dict[str, _BoundFn] = {
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
_CONJUNCTS: dict[str, tuple[tuple[str, tuple[int, int]], ...]] = {
    "h_between": (("left_of", (1, 0)), ("h_aligned", (1, 0)), ("left_of", (0, 2)), ("h_aligned", (0, 2)),
                  ("left_of", (1, 2))),  # implied: a left of c left of b
    "v_between": (("above", (1, 0)), ("v_aligned", (1, 0)), ("above", (0, 2)), ("v_aligned", (0, 2)),
                  ("above", (1, 2))),
}


# ---------------------------------------------------------------------------------------------- sampler


@dataclass
class _Check:
    fn: Callable[..., bool]
    slots: tuple[int, ...]  # term indices
    name: str


@dataclass
class _Bound:
    fn: _BoundFn
    slots: tuple[int, ...]  # term indices of the clause's arguments
    role: int  # argument position of the term being placed


@dataclass
class _Term:
    name: str
    is_self: bool
    families: list[str]
    combos: dict[str, list[tuple[int, bool, bool]]]  # family -> (colour, target, pushable)
    fixed_idx: bool  # the self: shape_idx 0 only
    checks: list[_Check] = field(default_factory=list)  # run when this term is placed
    bounds: list[_Bound] = field(default_factory=list)


class _Restart(Exception):
    pass


class _GeneratorSampler:
    """One generator compiled into a randomized search; ``sample()`` gives its next object tuple."""

    def __init__(self, name: str, logic: str, spec: DatasetSpec, seed: int) -> None:
        self.name = name
        self.spec = spec
        self.rng = random.Random(seed)
        try:
            expression = expand(parse(logic), spec.macros)
            Concept(expression, spec.macros)  # resolves every predicate name and arity (clear errors)
        except ConceptError as exc:
            raise GenerationError(f"dataset {spec.name!r}: generator {name!r}: {exc}") from exc
        self.expression = expression
        self.ctx = EvalContext(floor_row=spec.height - spec.floor_height, dir_above_quirk=True)
        self.term_names: tuple[str, ...] = tuple(sorted({*expression.variables, SELF}))
        self.samples = self.rejected = self.search_steps = self.restarts = 0
        self._compile(expression)

    # -------------------------------------------------------------- compile

    def _error(self, message: str) -> GenerationError:
        return GenerationError(f"dataset {self.spec.name!r}: generator {self.name!r} is unsatisfiable: {message}")

    def _compile(self, expression: Expression) -> None:
        slot = {t: i for i, t in enumerate(self.term_names)}
        unary: dict[int, list[Clause]] = {i: [] for i in range(len(slot))}
        forbidden: dict[int, list[Clause]] = {i: [] for i in range(len(slot))}
        relations: list[Clause] = []
        for clause in expression.positives:
            (unary[slot[clause.args[0]]] if len(clause.args) == 1 else relations).append(clause)
        self.negations: list[list[_Check]] = []
        for group in expression.negations:
            if len(group) == 1 and len(group[0].args) == 1 and not self._position_dependent(group[0].name):
                forbidden[slot[group[0].args[0]]].append(group[0])
            else:
                self.negations.append([_Check(PREDICATES[c.name].fn, tuple(slot[a] for a in c.args), c.name)
                                       for c in group])
        self.shape_idx_matters = any(c.name in _SHAPE_IDX_PREDICATES for c in expression.positives) or any(
            c.name in _SHAPE_IDX_PREDICATES for g in expression.negations for c in g)
        self.terms = [self._term(t, unary[i], forbidden[i]) for i, t in enumerate(self.term_names)]

        # placement order
        position_unary = {i for i, clauses in unary.items() if any(self._position_dependent(c.name) for c in clauses)}
        links = [(c, tuple(slot[a] for a in c.args)) for c in relations]
        neighbours: list[set[int]] = [set() for _ in self.terms]
        for _, slots in links:
            for t in slots:
                neighbours[t].update(o for o in slots if o != t)
        order: list[int] = []
        remaining = set(range(len(self.terms)))
        while remaining:
            def score(t: int) -> tuple:
                return (t in position_unary, len(neighbours[t] & set(order)), not self.terms[t].is_self,
                        -len(neighbours[t]), tuple(-ord(ch) for ch in self.term_names[t]))
            best = max(sorted(remaining), key=score)
            order.append(best)
            remaining.remove(best)
        self.order = order
        rank = {t: k for k, t in enumerate(order)}

        # checks and bounds per term
        for i, clauses in unary.items():
            for c in clauses:
                self.terms[i].checks.append(_Check(PREDICATES[c.name].fn, (i,), c.name))
                if self._position_dependent(c.name) and c.name in _BOUNDS:
                    self.terms[i].bounds.append(_Bound(_BOUNDS[c.name], (i,), 0))
        for clause, slots in links:
            last = max(slots, key=rank.__getitem__)
            self.terms[last].checks.append(_Check(PREDICATES[clause.name].fn, slots, clause.name))
            for role, t in enumerate(slots):
                # binary bounds need the other term placed; ternary ones use whichever terms are placed
                others = [o for o in slots if o != t]
                useful = others and (t == last or (len(slots) == 3 and any(rank[o] < rank[t] for o in others)))
                if clause.name in _BOUNDS and useful:
                    self.terms[t].bounds.append(_Bound(_BOUNDS[clause.name], slots, role))
            for name, (i, j) in _CONJUNCTS.get(clause.name, ()):
                pair = (slots[i], slots[j])
                closing = max(pair, key=rank.__getitem__)
                if closing != last:
                    self.terms[closing].checks.insert(0, _Check(PREDICATES[name].fn, pair, name))
        for term in self.terms:  # cheap bbox relations first
            term.checks.sort(key=lambda c: c.name in ("touches", "near", "adjacent", "inside", "inside_supported"))

    def _position_dependent(self, name: str) -> bool:
        return _position_dependent(name, self.ctx.floor_row)

    def _term(self, name: str, unary: list[Clause], forbidden: list[Clause]) -> _Term:
        is_self = name == SELF
        spec = self.spec
        if is_self:
            families, colors, targets, pushables = ["pixel"], [int(Color.RED)], [False], [False]
        else:
            families, colors = list(FAMILIES), list(COLORS)
            targets = [False, True] if spec.allow_targets else [False]
            pushables = [False, True] if spec.allow_pushable else [False]
        combos: dict[str, list[tuple[int, bool, bool]]] = {}
        for family in families:
            ok = []
            for color in colors:
                for target in targets:
                    for pushable in pushables:
                        probes = [_make_object(is_self, family, 0, color, target, pushable, r, 1)
                                  for r in (self.ctx.floor_row, 1)]
                        if all(any(PREDICATES[c.name].fn(p, self.ctx) for p in probes) for c in unary) and not any(
                                PREDICATES[c.name].fn(probes[0], self.ctx) for c in forbidden):
                            ok.append((color, target, pushable))
            if ok:
                combos[family] = ok
        if not combos:
            what = " & ".join([*(str(c) for c in unary), *(f"~{c}" for c in forbidden)]) or "the domains"
            raise self._error(f"no object satisfies {what} for term {name!r}")
        return _Term(name, is_self, list(combos), combos, fixed_idx=is_self)

    # -------------------------------------------------------------- search

    def sample(self) -> tuple[WorldObject, ...]:
        """The next solution (objects in term order) that no negated group rejects."""
        rejected = 0
        while True:
            objects = self._solve()
            if not any(all(c.fn(*(objects[s] for s in c.slots), self.ctx) for c in group) for group in self.negations):
                self.samples += 1
                return tuple(objects)
            rejected += 1
            self.rejected += 1
            if rejected >= MAX_REJECTIONS:
                raise self._error(f"{MAX_REJECTIONS} solutions in a row were rejected by its negated clauses")

    def _solve(self) -> list[WorldObject]:
        cap, attempts, spent = RESTART_STEPS, 0, 0
        while spent < MAX_SEARCH_STEPS:
            self._steps, self._cap = 0, min(cap, MAX_SEARCH_STEPS - spent)
            placed: list[WorldObject | None] = [None] * len(self.terms)
            try:
                found = self._place(0, 0, placed)
            except _Restart:
                found = False
            else:
                if not found:  # the whole tree was searched
                    self.search_steps += self._steps
                    raise self._error(f"the search space is exhausted after {self._steps} steps")
            spent += self._steps
            self.search_steps += self._steps
            if found:
                return placed  # type: ignore[return-value]
            attempts += 1
            self.restarts += 1
            if attempts % 10 == 0:
                cap *= 2
        raise self._error(f"no solution within {MAX_SEARCH_STEPS} search steps")

    def _tick(self) -> None:
        self._steps += 1
        if self._steps > self._cap:
            raise _Restart

    def _place(self, k: int, occupied: int, placed: list[WorldObject | None]) -> bool:
        t = self.order[k]
        term = self.terms[t]
        rng = self.rng
        spec = self.spec
        width, height = spec.width, spec.height
        last = k + 1 == len(self.order)
        families = term.families[:]
        rng.shuffle(families)
        for family in families:
            n_templates = len(shape_library()[family])
            failed: set[int] = set()
            idx_pool = [0] if term.fixed_idx else list(range(NUM_SHAPE_IDX))
            for i in range(len(idx_pool)):
                j = rng.randrange(i, len(idx_pool))
                idx_pool[i], idx_pool[j] = idx_pool[j], idx_pool[i]
                shape_idx = idx_pool[i]
                tid = shape_idx % n_templates
                if tid in failed:
                    continue
                self._tick()
                _, (h, w), _ = _template_data(family, tid)
                mask = _mask(family, tid, width)
                pad = 1 if family in FRAME_EXEMPT else max(1, spec.padding)
                box = [pad, width - pad - w, pad, height - pad - h]
                probe = _make_object(term.is_self, family, shape_idx, 1, False, False, 0, 0)
                for b in term.bounds:
                    got = b.fn([placed[s] for s in b.slots], b.role, probe, self.ctx.floor_row)
                    if got is not None:
                        box = [max(box[0], got[0]), min(box[1], got[1]), max(box[2], got[2]), min(box[3], got[3])]
                if box[0] > box[1] or box[2] > box[3]:
                    failed.add(tid)
                    continue
                combos = term.combos[family][:]
                rng.shuffle(combos)
                for color, target, pushable in combos:
                    if self._positions(k, t, term, family, shape_idx, color, target, pushable, box, mask,
                                       occupied, placed, last):
                        return True
                if not self.shape_idx_matters:
                    failed.add(tid)
        return False

    def _positions(self, k: int, t: int, term: _Term, family: str, shape_idx: int, color: int, target: bool,
                   pushable: bool, box: list[int], mask: int, occupied: int, placed: list[WorldObject | None],
                   last: bool) -> bool:
        x0, x1, y0, y1 = box
        nx = x1 - x0 + 1
        n = nx * (y1 - y0 + 1)
        pool = list(range(n))
        rng, width, ctx = self.rng, self.spec.width, self.ctx
        checks = term.checks
        for i in range(n):
            j = rng.randrange(i, n) if i + 1 < n else i
            pool[i], pool[j] = pool[j], pool[i]
            self._tick()
            dy, dx = divmod(pool[i], nx)
            y, x = y0 + dy, x0 + dx
            shifted = mask << (y * width + x)
            if occupied & shifted:
                continue
            obj = _make_object(term.is_self, family, shape_idx, color, target, pushable, y, x)
            placed[t] = obj
            if all(c.fn(*(placed[s] for s in c.slots), ctx) for c in checks) and (
                    last or self._place(k + 1, occupied | shifted, placed)):
                return True
            placed[t] = None
        return False


@cache
def _position_dependent(name: str, floor_row: int) -> bool:
    """Whether a unary predicate's truth depends on the object's position (e.g. ``floor``)."""
    fn = PREDICATES[name].fn
    ctx = EvalContext(floor_row=floor_row, dir_above_quirk=True)
    for family in FAMILIES:
        for color in COLORS:
            a = _make_object(False, family, 0, color, False, False, floor_row, 1)
            b = _make_object(False, family, 0, color, False, False, 1, 1)
            if fn(a, ctx) != fn(b, ctx):
                return True
    return False


def _stream_seed(seed: int, generator: str) -> int:
    return int(hashlib.sha256(f"{seed}:{generator}".encode()).hexdigest()[:16], 16)


# ---------------------------------------------------------------------------------------------- datasets


def generate(spec: DatasetSpec, seed: int = 0, *, max_draws: int | None = None,
             progress: Callable[[int, int, int], None] | None = None) -> GeneratedDataset:
    """Generate dataset ``spec`` with ``seed`` (spec §3.7).

    Each draw picks a generator uniformly with ``random.Random(seed)`` and takes its next sample (each
    generator has its own seeded stream); a scene identical to an earlier one (same objects, including
    ``shape_idx``) is counted as a duplicate and skipped. Classification keeps a scene if the quota
    (``num_samples``) of its label, the concept's truth, is not full and stops when both are full;
    bring-about keeps only scenes in which the concept does not hold but can be made to hold by moving (a
    breadth-first search over moves), until ``num_samples``, all labelled 1. The kept scenes are listed
    negatives first, then positives (each in the order they were drawn) and shuffled with the same
    ``random.Random(seed)`` stream.

    ``max_draws`` (default ``DRAWS_PER_SAMPLE * num_samples``) bounds the draws; reaching it, or an
    unsatisfiable generator, raises :class:`GenerationError`. ``progress(kept, target, draws)`` is
    called after every kept scene.
    """
    seed = check_seed(seed)
    if max_draws is None:
        max_draws = DRAWS_PER_SAMPLE * spec.num_samples
    try:
        concept = Concept(spec.concept, spec.macros)
    except ConceptError as exc:
        raise GenerationError(f"dataset {spec.name!r}: concept: {exc}") from exc
    kept: dict[int, list[tuple[Scene, int]]] = {0: [], 1: []}
    try:
        samplers = [_GeneratorSampler(name, logic, spec, _stream_seed(seed, name)) for name, logic in spec.generators]
    except GenerationError as exc:
        raise GenerationError(f"{exc} (before the first draw; kept {_counts(spec, kept)})") from None
    chooser = random.Random(seed)
    frame = frame_object(spec.height, spec.width)
    classification = spec.kind == "classification"
    quota = spec.num_samples
    seen: set[tuple] = set()
    draws = duplicates = filtered = unreachable = 0
    per_kept = [0] * len(samplers)
    per_dup = [0] * len(samplers)
    target = spec.size

    def total() -> int:
        return len(kept[0]) + len(kept[1])

    while total() < target:
        if draws >= max_draws:
            raise _quota_error(spec, samplers, kept, draws, duplicates, filtered, unreachable)
        draws += 1
        g = chooser.randrange(len(samplers))
        sampler = samplers[g]
        try:
            objects = sampler.sample()
        except GenerationError as exc:
            raise GenerationError(f"{exc} (after {draws - 1} draws; kept {_counts(spec, kept)})") from None
        key = tuple((o.family, o.shape_idx, o.color, o.position, o.is_target, o.pushable) for o in objects)
        if key in seen:
            duplicates += 1
            per_dup[g] += 1
            continue
        seen.add(key)
        scene = Scene(height=spec.height, width=spec.width, objects=(*objects, frame))
        truth = concept.holds(scene)
        if classification:
            label = int(truth)
            if len(kept[label]) >= quota:
                filtered += 1
                continue
        else:
            if truth:
                filtered += 1
                continue
            if not goal_reachable(scene, concept):
                unreachable += 1
                continue
            label = 1
        kept[label].append((scene, g))
        per_kept[g] += 1
        if progress is not None:
            progress(total(), target, draws)

    ordered = [(scene, label, g) for label in (0, 1) for scene, g in kept[label]]
    chooser.shuffle(ordered)
    stats = tuple(
        GeneratorStats(name=s.name, samples=s.samples, kept=per_kept[i], duplicates=per_dup[i], rejected=s.rejected,
                       search_steps=s.search_steps, restarts=s.restarts)
        for i, s in enumerate(samplers)
    )
    return GeneratedDataset(
        spec=spec, seed=seed, scenes=tuple(s for s, _, _ in ordered), labels=tuple(lab for _, lab, _ in ordered),
        generator_of=tuple(spec.generators[g][0] for _, _, g in ordered), draws=draws, duplicates=duplicates,
        filtered=filtered, unreachable=unreachable, generator_stats=stats,
    )


def _counts(spec: DatasetSpec, kept: Mapping[int, list]) -> str:
    if spec.kind == "classification":
        return f"{len(kept[1])} positive and {len(kept[0])} negative of {spec.num_samples} each"
    return f"{len(kept[1])} of {spec.num_samples} scenes in which the goal does not hold"


def _quota_error(spec: DatasetSpec, samplers: Iterable[_GeneratorSampler], kept: Mapping[int, list], draws: int,
                 duplicates: int, filtered: int, unreachable: int) -> GenerationError:
    names = ", ".join(repr(s.name) for s in samplers)
    return GenerationError(
        f"dataset {spec.name!r} (generators {names}) reached only {_counts(spec, kept)} within {draws} draws "
        f"({duplicates} duplicates, {filtered} dropped by the concept filter or a full quota, {unreachable} "
        "with an unreachable goal)"
    )


# ---------------------------------------------------------------------------------------------- split


def split(labels: Sequence[int], test_fraction: float = 0.5,
          seed: int = 521) -> tuple[tuple[int, ...], tuple[int, ...]]:
    """A stratified train/test split: ``(train indices, test indices)``, each sorted.

    Scheme (deterministic, numpy only): the test set has ``ceil(test_fraction * n)`` items (the sklearn
    rule); it is divided among the labels proportionally to their counts (floor of each share, the rest
    to the largest remainders, ties to the smaller label). Each label's indices are permuted with one
    legacy ``numpy.random.RandomState(seed)`` stream (labels in increasing order) and the first ones go
    to the test set. Classification 50+50 -> 50/50 with 25+25 each; bring-about 50 -> 25/25.
    """
    if not 0.0 < test_fraction < 1.0:
        raise PixelWorldError(f"test_fraction must lie strictly between 0 and 1, got {test_fraction}")
    labels = [int(v) for v in labels]
    n = len(labels)
    if n < 2:
        raise PixelWorldError(f"need at least 2 samples to split, got {n}")
    classes = sorted(set(labels))
    members = {c: [i for i, v in enumerate(labels) if v == c] for c in classes}
    n_test = min(n - 1, max(1, math.ceil(test_fraction * n)))
    shares = {c: n_test * len(members[c]) for c in classes}  # share * n (integer arithmetic)
    alloc = {c: shares[c] // n for c in classes}
    rest = n_test - sum(alloc.values())
    for c in sorted(classes, key=lambda c: (-(shares[c] % n), c))[:rest]:
        alloc[c] += 1
    rng = np.random.RandomState(seed)
    test: list[int] = []
    for c in classes:
        perm = rng.permutation(len(members[c]))
        test.extend(members[c][int(p)] for p in perm[:alloc[c]])
    test_set = set(test)
    return tuple(i for i in range(n) if i not in test_set), tuple(sorted(test_set))
