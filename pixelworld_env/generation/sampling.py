"""The search that samples one generator's objects: a seeded randomized depth-first search over the constraint
problem of docs/design.md, "The constraint problem and the sampler" (:class:`GeneratorSampler`;
:func:`pixelworld_env.generation.dataset.generate` draws from it).

Search method
-------------
The sampler is a **custom seeded randomized depth-first backtracking search** over exactly the domains
and constraints of that problem (the AAAI-18 sampler was itself a randomized DFS with restarts). It was
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

How the search works (``GeneratorSampler``):

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
   inside-supported mask): each predicate's bound, conjuncts and cost are part of its entry in
   :data:`~pixelworld_env.concepts.predicates.PREDICATES` (``generation``, a
   :class:`~pixelworld_env.concepts.predicates.GenerationFacts`). A candidate is kept if it overlaps no placed
   object (an integer bit mask test) and every clause whose terms are now all placed holds, evaluated by the real
   predicate functions of :data:`pixelworld_env.concepts.predicates.PREDICATES` on :class:`WorldObject` s
   (``dir_above`` with the AAAI-18 quirk). ``h_between``/``v_between`` with two of three terms placed are
   pre-checked by their defining conjuncts (``left_of`` and ``h_aligned``, resp. ``above`` and ``v_aligned``) and
   by the implied ``left_of(a,b)`` (resp. ``above(a,b)``) of the outer terms.
4. Every template and every position tried counts as one search step. After
   ``RESTART_STEPS`` steps the search restarts (the cap doubles after every 10 restarts); after
   ``MAX_SEARCH_STEPS`` steps for one sample, or when a search exhausts the whole tree, the generator is
   reported as unsatisfiable. A complete assignment that makes a negated group true is rejected and the
   search runs again; ``MAX_REJECTIONS`` rejections in a row are an error too.

Samples are random-DFS samples, not uniform over all solutions, as in the original: the first family
and ``shape_idx`` tried are uniform over the term's domain, so family frequencies follow the original
closely (checked against the 8,700 original samples by the slow fidelity test).
"""

from __future__ import annotations

import random
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cache

from pixelworld_env.concepts import Concept, ConceptError, expand, parse
from pixelworld_env.concepts.parser import SELF, Clause, Expression
from pixelworld_env.concepts.predicates import PREDICATES, BoundFn, EvalContext, GenerationFacts
from pixelworld_env.core.constants import Color
from pixelworld_env.core.objects import WorldObject
from pixelworld_env.core.shapes import FAMILIES, shape_library
from pixelworld_env.errors import PixelWorldError
from pixelworld_env.generation.dataset_spec import DatasetSpec
from pixelworld_env.generation.placement import make_object, template_data, template_mask

__all__ = ["COLORS", "FRAME_EXEMPT", "MAX_REJECTIONS", "MAX_SEARCH_STEPS", "NUM_SHAPE_IDX", "RESTART_STEPS",
           "GenerationError", "GeneratorSampler"]

COLORS: tuple[int, ...] = (1, 2, 3, 4, 5, 8)
"""Colour domain of generated objects."""
NUM_SHAPE_IDX = 50
"""``shape_idx`` domain is 0..49 (the largest family size); template = ``shape_idx mod family size``."""
FRAME_EXEMPT = frozenset({"floor_shape", "wall"})
"""Families that only need to lie inside the frame, not inside the padding."""
RESTART_STEPS = 1000
"""Search steps before a restart; the cap doubles after every 10 restarts."""
MAX_SEARCH_STEPS = 200_000
"""Search steps for one sample before the generator is declared unsatisfiable."""
MAX_REJECTIONS = 1000
"""Consecutive solutions rejected by negated groups before the generator is declared unsatisfiable."""


class GenerationError(PixelWorldError):
    """A generator is unsatisfiable, or a dataset cannot reach its quota within the budget."""


@dataclass
class _Check:
    fn: Callable[..., bool]
    slots: tuple[int, ...]  # term indices
    name: str


@dataclass
class _Bound:
    fn: BoundFn
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


class GeneratorSampler:
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
        # a predicate that reads shape_idx itself: templates that failed under one shape_idx are retried
        self.shape_idx_matters = any(_facts(c.name).shape_idx for c in expression.positives) or any(
            _facts(c.name).shape_idx for g in expression.negations for c in g)
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
                bound = _facts(c.name).bound
                if self._position_dependent(c.name) and bound is not None:
                    self.terms[i].bounds.append(_Bound(bound, (i,), 0))
        for clause, slots in links:
            last = max(slots, key=rank.__getitem__)
            facts = _facts(clause.name)
            self.terms[last].checks.append(_Check(PREDICATES[clause.name].fn, slots, clause.name))
            for role, t in enumerate(slots):
                # binary bounds need the other term placed; ternary ones use whichever terms are placed
                others = [o for o in slots if o != t]
                useful = others and (t == last or (len(slots) == 3 and any(rank[o] < rank[t] for o in others)))
                if facts.bound is not None and useful:
                    self.terms[t].bounds.append(_Bound(facts.bound, slots, role))
            for name, (i, j) in facts.conjuncts:
                pair = (slots[i], slots[j])
                closing = max(pair, key=rank.__getitem__)
                if closing != last:
                    self.terms[closing].checks.insert(0, _Check(PREDICATES[name].fn, pair, name))
        for term in self.terms:  # cheap bbox relations first
            term.checks.sort(key=lambda c: _facts(c.name).expensive)

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
                        probes = [make_object(is_self, family, 0, color, target, pushable, r, 1)
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
                _, (h, w), _ = template_data(family, tid)
                mask = template_mask(family, tid, width)
                pad = 1 if family in FRAME_EXEMPT else max(1, spec.padding)
                box = [pad, width - pad - w, pad, height - pad - h]
                probe = make_object(term.is_self, family, shape_idx, 1, False, False, 0, 0)
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
            obj = make_object(term.is_self, family, shape_idx, color, target, pushable, y, x)
            placed[t] = obj
            if all(c.fn(*(placed[s] for s in c.slots), ctx) for c in checks) and (
                    last or self._place(k + 1, occupied | shifted, placed)):
                return True
            placed[t] = None
        return False


def _facts(name: str) -> GenerationFacts:
    """What the search knows of a predicate besides its function: its entry's :class:`GenerationFacts`."""
    return PREDICATES[name].generation


@cache
def _position_dependent(name: str, floor_row: int) -> bool:
    """Whether a unary predicate's truth depends on the object's position (e.g. ``floor``)."""
    fn = PREDICATES[name].fn
    ctx = EvalContext(floor_row=floor_row, dir_above_quirk=True)
    for family in FAMILIES:
        for color in COLORS:
            a = make_object(False, family, 0, color, False, False, floor_row, 1)
            b = make_object(False, family, 0, color, False, False, 1, 1)
            if fn(a, ctx) != fn(b, ctx):
                return True
    return False
