"""The generator CSP (docs/design.md, "The constraint problem and the sampler") written for python-constraint
(``python-constraint2``).

:mod:`pixelworld_env.generation.sampling` samples generators with its own randomized backtracking search because
python-constraint's solvers are 100-10,000x slower on the positional constraints (measurements in that
module's docstring). This module states the same problem independently, variable by variable, so that the
fast sampler can be checked against it (:func:`satisfies_generator`) and small generators can be sampled
with python-constraint itself (:func:`sample_generator`, a random-DFS sample: domains shuffled, first
solution).

Variables per term (``self`` and every declared variable): ``<t>.shape`` (family), ``<t>.shape_idx``
(0..49; template = ``shape_idx mod family size``), ``<t>.color``, ``<t>.is_target``, ``<t>.x`` and ``<t>.y``
(top-left). Constraints: the self is a red pixel with ``shape_idx`` 0 and never a target; every bbox inside
the frame and, except ``floor_shape`` and ``wall``, inside the padding; no two objects share a cell; every
positive clause, evaluated by the predicates of :mod:`pixelworld_env.concepts.predicates` (``dir_above``
with the AAAI-18 quirk, as generators need). Negated groups are not part of the CSP: they reject solutions.
"""

from __future__ import annotations

import random
from collections.abc import Mapping, Sequence
from typing import Any

import constraint

from pixelworld_env.concepts import Concept, expand, parse
from pixelworld_env.concepts.parser import SELF
from pixelworld_env.concepts.predicates import PREDICATES, EvalContext
from pixelworld_env.core.constants import FLOOR_HEIGHT, HEIGHT, PADDING, WIDTH, Color
from pixelworld_env.core.objects import WorldObject, frame_object
from pixelworld_env.core.scene import Scene
from pixelworld_env.core.shapes import FAMILIES, shape_library
from pixelworld_env.generation.placement import library_object
from pixelworld_env.generation.sampling import COLORS, NUM_SHAPE_IDX

ATTRIBUTES = ("shape", "shape_idx", "color", "is_target", "x", "y")
_UNPADDED = frozenset({"floor_shape", "wall"})


def _object(term: str, shape: str, shape_idx: int, color: int, is_target: bool, x: int, y: int) -> WorldObject:
    return library_object(shape, shape_idx, color, (y, x), is_self=term == SELF, is_target=is_target)


def _inside(height: int, width: int, padding: int):
    def check(shape: str, shape_idx: int, x: int, y: int) -> bool:
        templates = shape_library()[shape]
        h, w = templates[shape_idx % len(templates)].shape
        pad = 1 if shape in _UNPADDED else padding
        return x >= pad and y >= pad and x + w <= width - pad and y + h <= height - pad

    return check


def generator_problem(logic: str, macros: Mapping[str, str] | None = None, *, height: int = HEIGHT,
                      width: int = WIDTH, padding: int = PADDING, allow_targets: bool = False,
                      domains: Mapping[str, Sequence] | None = None) -> tuple[constraint.Problem, tuple[str, ...]]:
    """The generator's CSP and its terms (sorted by name, the object order of a scene).

    ``domains`` overrides variable domains by name (e.g. ``{"self.x": [4]}``).
    """
    expression = expand(parse(logic), macros if macros is not None else Concept("?x pixel(x)").macros)
    terms = tuple(sorted((SELF, *expression.variables)))
    ctx = EvalContext(floor_row=height - FLOOR_HEIGHT, dir_above_quirk=True)
    problem = constraint.Problem(constraint.BacktrackingSolver())
    domains = dict(domains or {})
    for term in terms:
        is_self = term == SELF
        default: dict[str, list[Any]] = {
            "shape": ["pixel"] if is_self else list(FAMILIES),
            "shape_idx": [0] if is_self else list(range(NUM_SHAPE_IDX)),
            "color": [int(Color.RED)] if is_self else list(COLORS),
            "is_target": [False, True] if allow_targets and not is_self else [False],
            "x": list(range(width)),
            "y": list(range(height)),
        }
        for attribute in ATTRIBUTES:
            name = f"{term}.{attribute}"
            problem.addVariable(name, list(domains.get(name, default[attribute])))
        corner = [f"{term}.{a}" for a in ("shape", "shape_idx", "x", "y")]
        problem.addConstraint(_inside(height, width, padding), corner)

    def variables(names: Sequence[str]) -> list[str]:
        return [f"{t}.{a}" for t in names for a in ATTRIBUTES]

    def objects(names: Sequence[str], values: Sequence) -> list[WorldObject]:
        n = len(ATTRIBUTES)
        return [_object(t, *values[k * n : (k + 1) * n]) for k, t in enumerate(names)]

    for clause in expression.positives:
        fn = PREDICATES[clause.name].fn
        args = clause.args
        reads = PREDICATES[clause.name].reads if len(args) == 1 else None  # what the predicate table says it reads
        if reads is not None:  # a unary predicate of a few attributes: a small constraint prunes early
            probe = {"shape": "pixel", "shape_idx": 0, "color": 0, "is_target": False, "x": 0, "y": 0}

            def unary(*values, fn=fn, term=args[0], reads=reads, probe=probe) -> bool:
                return fn(_object(term, **{**probe, **dict(zip(reads, values, strict=True))}), ctx)

            problem.addConstraint(unary, [f"{args[0]}.{a}" for a in reads])
        else:
            problem.addConstraint(lambda *values, fn=fn, args=args: fn(*objects(args, values), ctx),
                                  variables(args))
    for i, a in enumerate(terms):
        for b in terms[i + 1 :]:
            pair = (a, b)
            problem.addConstraint(
                lambda *values, pair=pair: not (objects(pair[:1], values[:6])[0].pixels
                                                & objects(pair[1:], values[6:])[0].pixels),
                variables(pair))
    return problem, terms


def _negations_hold(logic: str, macros: Mapping[str, str] | None, objects: Sequence[WorldObject],
                    terms: Sequence[str], floor_row: int) -> bool:
    expression = expand(parse(logic), macros if macros is not None else Concept("?x pixel(x)").macros)
    ctx = EvalContext(floor_row=floor_row, dir_above_quirk=True)
    bound = dict(zip(terms, objects, strict=True))
    return any(all(PREDICATES[c.name].fn(*(bound[a] for a in c.args), ctx) for c in group)
               for group in expression.negations)


def satisfies_generator(scene: Scene, logic: str, macros: Mapping[str, str] | None = None, *,
                        allow_targets: bool = False) -> bool:
    """Whether ``scene`` is a solution of the generator's CSP with its objects bound in term order.

    The scene's non-frame objects must be the generator's terms sorted by name (as generated scenes are);
    negated groups must not hold.
    """
    objects = [o for o in scene.objects if not o.is_frame]
    pinned = {}
    terms = tuple(sorted((SELF, *parse(logic).variables)))
    if len(objects) != len(terms):
        return False
    for term, obj in zip(terms, objects, strict=True):
        values = (obj.family, obj.shape_idx, int(obj.color), obj.is_target, obj.position[1], obj.position[0])
        pinned.update({f"{term}.{a}": [v] for a, v in zip(ATTRIBUTES, values, strict=True)})
    problem, terms = generator_problem(logic, macros, height=scene.height, width=scene.width,
                                       allow_targets=allow_targets, domains=pinned)
    if problem.getSolution() is None:
        return False
    return not _negations_hold(logic, macros, objects, terms, scene.floor_row)


def sample_generator(logic: str, macros: Mapping[str, str] | None = None, *, seed: int = 0, height: int = HEIGHT,
                     width: int = WIDTH, allow_targets: bool = False, max_tries: int = 100) -> Scene | None:
    """One scene from the generator, solved by python-constraint with every domain shuffled (random DFS).

    Solutions whose negated groups hold are rejected (up to ``max_tries``). Practical only for small
    generators: use :func:`pixelworld_env.generation.dataset.generate` for datasets.
    """
    rng = random.Random(seed)
    problem, terms = generator_problem(logic, macros, height=height, width=width, allow_targets=allow_targets)
    for _ in range(max_tries):
        for domain in problem._variables.values():  # noqa: SLF001 - python-constraint keeps domains here
            rng.shuffle(domain)
        solution = problem.getSolution()
        if solution is None:
            return None
        objects = [_object(t, *(solution[f"{t}.{a}"] for a in ATTRIBUTES)) for t in terms]
        if not _negations_hold(logic, macros, objects, terms, height - FLOOR_HEIGHT):
            return Scene(height=height, width=width, objects=(*objects, frame_object(height, width)))
    return None
