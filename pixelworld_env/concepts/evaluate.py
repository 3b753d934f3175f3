"""Compiled concepts and their semantics (docs/design.md, "Semantics")."""

from __future__ import annotations

import difflib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from pixelworld_env.concepts.errors import ArityError, MacroNameError, UnknownPredicateError
from pixelworld_env.concepts.parser import SELF, Clause, Expression, expand, parse
from pixelworld_env.concepts.predicates import PREDICATES, EvalContext, Predicate
from pixelworld_env.core.objects import WorldObject
from pixelworld_env.core.scene import Scene
from pixelworld_env.errors import PixelWorldTypeError

Macros = Mapping[str, "str | Expression"]
FORWARD_CHECKING_FROM = 4
"""Concepts with this many variables (``self`` included) or more are searched with forward checking."""


@dataclass(frozen=True)
class _Check:
    fn: Predicate
    slots: tuple[int, ...]  # indices into the binding (variable order)


class Concept:
    """A concept expression compiled against a macro table (default: the benchmark catalog's), ready to test
    scenes.

    ``Concept(text, macros).holds(scene)`` is true if the variables (``self`` included) can be bound to
    pairwise distinct non-frame objects so that every positive clause holds and no negated group has all
    its clauses holding under the same binding. ``dir_above_quirk`` reproduces the AAAI-18 ``dir_above``
    transposition (docs/design.md, "Vocabulary"); it only matters for generators.
    """

    def __init__(self, text: str | Expression, macros: Macros | None = None, *,
                 dir_above_quirk: bool = False) -> None:
        if not isinstance(text, str | Expression):
            raise PixelWorldTypeError(f"a concept is an expression string (or a parsed Expression), got {text!r} "
                                      f"({type(text).__name__})")
        self._source = text
        expression = parse(text) if isinstance(text, str) else text
        self.text = str(text)
        if macros is None:
            from pixelworld_env.datasets.catalog import macros as catalog_macros

            macros = catalog_macros()
        if not isinstance(macros, Mapping):
            raise PixelWorldTypeError(f"macros must map names to expression strings, got {type(macros).__name__}")
        for name, body in macros.items():
            if not isinstance(name, str):
                raise PixelWorldTypeError(f"a macro's name must be a string, got {name!r} ({type(name).__name__})")
            if not isinstance(body, str | Expression):
                raise PixelWorldTypeError(f"macro {name!r} must be an expression string, got {body!r} "
                                          f"({type(body).__name__})")
            if name in PREDICATES:
                raise MacroNameError(name)
        self.macros = dict(macros)
        self.dir_above_quirk = dir_above_quirk
        self.expression = expand(expression, self.macros)
        self.variables: tuple[str, ...] = (SELF, *self.expression.variables)
        slot = {v: i for i, v in enumerate(self.variables)}
        self._unary: list[list[Predicate]] = [[] for _ in self.variables]
        # Positive clauses with two or more arguments, checked as soon as their last variable is bound.
        self._checks: list[list[_Check]] = [[] for _ in self.variables]
        self._negations: list[list[list[_Check]]] = [[] for _ in self.variables]
        for clause in self.expression.positives:
            spec = self._resolve(clause)
            slots = tuple(slot[a] for a in clause.args)
            if len(slots) == 1:
                self._unary[slots[0]].append(spec)
            else:
                self._checks[max(slots)].append(_Check(spec, slots))
        for group in self.expression.negations:
            checks = [_Check(self._resolve(c), tuple(slot[a] for a in c.args)) for c in group]
            self._negations[max(max(c.slots) for c in checks)].append(checks)
        # For the forward-checking search: the multi-variable clauses and negated groups touching each variable.
        self._clauses_of: list[list[_Check]] = [[] for _ in self.variables]
        self._groups_of: list[list[tuple[frozenset[int], list[_Check]]]] = [[] for _ in self.variables]
        for checks in self._checks:
            for check in checks:
                for s in set(check.slots):
                    self._clauses_of[s].append(check)
        for groups in self._negations:
            for negated in groups:
                touched = frozenset(s for c in negated for s in c.slots)
                for s in touched:
                    self._groups_of[s].append((touched, negated))

    def _resolve(self, clause: Clause) -> Predicate:
        spec = PREDICATES.get(clause.name)
        if spec is None:
            names = list(PREDICATES) + list(self.macros)
            raise UnknownPredicateError(clause.name, difflib.get_close_matches(clause.name, names, n=3))
        if spec.arity != len(clause.args):
            raise ArityError(clause.name, spec.arity, len(clause.args))
        return spec.fn

    def __repr__(self) -> str:
        return f"Concept({self.text!r})"

    def __reduce__(self):
        # Compiled predicates are closures: pickle the source and compile again.
        return _rebuild, (self._source, self.macros, self.dir_above_quirk)

    def holds(self, scene: Scene) -> bool:
        """Whether the concept holds in ``scene``."""
        return self.holds_objects(scene.objects, scene.floor_row)

    def holds_objects(self, objects: tuple[WorldObject, ...], floor_row: int) -> bool:
        """:meth:`holds` on a bare object list (the world's current state)."""
        me = next((o for o in objects if o.is_self), None)
        return me is not None and self.self_evaluator(objects, floor_row)(me)

    def self_evaluator(self, objects: Sequence[WorldObject], floor_row: int) -> SelfEvaluator:
        """A test of the concept for a given self object, the other ``objects`` held fixed.

        The non-self variables' candidates are filtered once, so testing many self positions (bring-about goals,
        planning) is cheaper than calling :meth:`holds_objects` for each.
        """
        return SelfEvaluator(self, objects, floor_row)

    def _satisfiable(self, domains: list[list[WorldObject]], ctx: EvalContext) -> bool:
        """Whether the variables (``self`` in slot 0) can be bound to distinct objects of their ``domains``.

        Up to two variables besides ``self``: depth-first in declaration order, each clause tested once its last
        variable is bound. More: forward checking (after each binding, the candidates of every variable that a
        clause now ties to bound variables alone are filtered) with the smallest remaining domain bound next, which
        keeps long chains of relations (5 variables over 50 objects) to milliseconds.
        """
        if len(domains) < FORWARD_CHECKING_FROM:
            return self._search(0, domains, [], ctx)
        return self._forward(domains, [None] * len(domains), set(), ctx)

    def _forward(self, domains: list[list[WorldObject]], binding: list[WorldObject | None], used: set[int],
                 ctx: EvalContext) -> bool:
        unbound = [v for v, obj in enumerate(binding) if obj is None]
        if not unbound:
            return True
        var = min(unbound, key=lambda v: len(domains[v]))
        for obj in domains[var]:
            if id(obj) in used:
                continue
            binding[var] = obj
            if self._consistent(var, binding, ctx):
                narrowed = self._narrow(var, domains, binding, ctx)
                if narrowed is not None:
                    used.add(id(obj))
                    if self._forward(narrowed, binding, used, ctx):
                        return True
                    used.discard(id(obj))
            binding[var] = None
        return False

    def _consistent(self, var: int, binding: list[WorldObject | None], ctx: EvalContext) -> bool:
        for check in self._clauses_of[var]:
            args = [binding[s] for s in check.slots]
            if None not in args and not check.fn(*args, ctx):
                return False
        for slots, group in self._groups_of[var]:
            if all(binding[s] is not None for s in slots) and all(
                    c.fn(*(binding[s] for s in c.slots), ctx) for c in group):
                return False
        return True

    def _narrow(self, var: int, domains: list[list[WorldObject]], binding: list[WorldObject | None],
                ctx: EvalContext) -> list[list[WorldObject]] | None:
        """``domains`` with the candidates of each unbound variable that a clause of ``var`` now determines
        filtered (a new list; ``None`` if one becomes empty)."""
        pending: dict[int, list[_Check]] = {}
        for check in self._clauses_of[var]:
            free = {s for s in check.slots if binding[s] is None}
            if len(free) == 1:
                pending.setdefault(free.pop(), []).append(check)
        if not pending:
            return domains
        narrowed = list(domains)
        for u, checks in pending.items():
            kept = []
            for candidate in domains[u]:
                binding[u] = candidate
                if all(c.fn(*(binding[s] for s in c.slots), ctx) for c in checks):
                    kept.append(candidate)
            binding[u] = None
            if not kept:
                return None
            narrowed[u] = kept
        return narrowed

    def _search(self, depth: int, domains: list[list[WorldObject]], binding: list[WorldObject],
                ctx: EvalContext) -> bool:
        if depth == len(domains):
            return True
        checks, negations = self._checks[depth], self._negations[depth]
        for obj in domains[depth]:
            if any(obj is bound for bound in binding):
                continue
            binding.append(obj)
            if (all(c.fn(*(binding[s] for s in c.slots), ctx) for c in checks)
                    and not any(all(c.fn(*(binding[s] for s in c.slots), ctx) for c in group)
                                for group in negations)
                    and self._search(depth + 1, domains, binding, ctx)):
                return True
            binding.pop()
        return False


class SelfEvaluator:
    """``evaluator(self_object) -> bool``: a concept over fixed other objects (see :meth:`Concept.self_evaluator`)."""

    def __init__(self, concept: Concept, objects: Sequence[WorldObject], floor_row: int) -> None:
        self.concept = concept
        self.ctx = EvalContext(floor_row=floor_row, dir_above_quirk=concept.dir_above_quirk)
        others = [o for o in objects if not o.is_frame and not o.is_self]
        self.domains: list[list[WorldObject]] = [[]]
        for tests in concept._unary[1:]:
            self.domains.append([o for o in others if all(t(o, self.ctx) for t in tests)])
        self.satisfiable = all(self.domains[1:])

    def __call__(self, me: WorldObject) -> bool:
        if not self.satisfiable or not all(t(me, self.ctx) for t in self.concept._unary[0]):
            return False
        self.domains[0] = [me]
        return self.concept._satisfiable(self.domains, self.ctx)


def _rebuild(source: str | Expression, macros: Macros, dir_above_quirk: bool) -> Concept:
    return Concept(source, macros, dir_above_quirk=dir_above_quirk)


def holds(expression: str | Concept, scene: Scene, macros: Macros | None = None) -> bool:
    """Whether a concept expression holds in a scene.

    ``macros`` maps macro names (concept or generator keys) to expressions; by default the benchmark
    catalog's table (every AAAI-18 concept and generator, :func:`pixelworld_env.datasets.catalog.macros`).
    """
    if not isinstance(scene, Scene):
        raise PixelWorldTypeError(f"holds needs a Scene, got {scene!r} ({type(scene).__name__})")
    concept = expression if isinstance(expression, Concept) else Concept(expression, macros)
    return concept.holds(scene)
