"""Property-based fuzz tests (Hypothesis) of the readers of untrusted input and of the concept language.

1. ``holds`` / ``Concept`` against a brute-force evaluator written here from the documented semantics
   (docs/design.md, "Semantics" and "Vocabulary"), over random well-formed formulas (with macros) and random scenes;
2. random and mutated concept texts and macro tables: only the package's errors, within a time bound;
3. definition files (``load_definitions``) and curriculum files (``parse_curriculum``): random and adversarial YAML;
4. the library loader (``SMCLibrary.load``) and the model file reader (``check_model_bytes`` / ``decode_model``):
   damaged bytes, forged content with its checksums recomputed, forged pickles and classes from untrusted modules.

"Only the package's errors" means a ``PixelWorldError`` / ``SMCError`` (library: ``LibraryError``): anything else
(a bare ``TypeError``, ``RecursionError``, a PyYAML error ...) fails, and so does a call running over
:data:`TIME_LIMIT_S`. What the fuzz tests found (21 foreign exceptions and one slow path, fixed 2026-12-01) is kept in
:data:`FOUND`, each with its minimal reproducer, as regression tests (``test_what_the_fuzz_tests_found_stays_fixed``).
A bug found and not fixed yet goes into :data:`KNOWN_BUGS` with its reproducer: while listed, the fuzz tests let
exactly that exception at exactly that place pass, and hunt for others; its regression test is ``xfail(strict=True)``
until it is fixed (then move it to :data:`FOUND`).

The number of examples comes from the Hypothesis profile (``tests/conftest.py``: ``HYPOTHESIS_PROFILE=default`` or
``nightly``).
"""

from __future__ import annotations

import base64
import contextlib
import copy
import functools
import hashlib
import io
import itertools
import json
import pickle
import re
import shutil
import signal
import string
import sys
import tempfile
import time
import traceback
import zipfile
from collections.abc import Callable, Iterator
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import pytest
import yaml
from hypothesis import assume, event, given, note
from hypothesis import strategies as st
from safetensors.torch import load as load_tensors
from safetensors.torch import save as save_tensors

from pixelworld_env.concepts import Concept, ConceptError, NegatedMacroError, parse
from pixelworld_env.concepts.evaluate import holds
from pixelworld_env.core.constants import Color, ObjectClass
from pixelworld_env.core.objects import WorldObject, frame_object
from pixelworld_env.core.scene import Scene
from pixelworld_env.datasets import catalog
from pixelworld_env.errors import PixelWorldError
from pixelworld_env.generation.definitions import DefinitionSet, load_definitions
from sb3_smc.core.hyperparameters import SAFE_CLASS_MODULES
from sb3_smc.curricula.format import Curriculum, parse_curriculum
from sb3_smc.errors import SMCError
from sb3_smc.library import CorruptModelError, LibraryError, SMCLibrary, UntrustedModelError, storage
from sb3_smc.library.manifest import seal
from sb3_smc.library.model_file import METADATA_KEY, check_model_bytes, decode_model

REPO = Path(__file__).resolve().parent.parent
PACKAGE_ERRORS = (PixelWorldError, SMCError)
TIME_LIMIT_S = 5.0
"""The most one call of the package under test may take (wall clock; a hang or a blow-up fails the test)."""


# ================================================================================================================
# Shared machinery: the time bound, "only the package's errors", the known bugs
# ================================================================================================================


class _Alarm(BaseException):
    """Raised by the alarm inside the code under test (a BaseException: no ``except Exception`` there catches it)."""


class TimeLimitExceeded(AssertionError):
    """A call ran longer than its time limit (its cause, an :class:`_Alarm`, holds where it was interrupted)."""


@contextlib.contextmanager
def time_limit(what: str, seconds: float = TIME_LIMIT_S) -> Iterator[None]:
    """:class:`TimeLimitExceeded` if the body runs longer than ``seconds`` (SIGALRM interrupts a hang; the elapsed
    time is checked too)."""
    def alarm(signum: int, frame: Any) -> None:
        raise _Alarm

    previous = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    start = time.perf_counter()
    try:
        yield
    except _Alarm as interrupted:
        raise TimeLimitExceeded(f"{what}: still running after {seconds} s (a hang or a blow-up)") from interrupted
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    elapsed = time.perf_counter() - start
    if elapsed >= seconds:
        raise TimeLimitExceeded(f"{what}: took {elapsed:.1f} s, more than {seconds} s")


def _package_frames(exc: BaseException) -> list[tuple[str, str]]:
    """``(file relative to the repository, function)`` of each frame of the packages under test in the traceback of
    ``exc`` (of the interrupted code, for a :class:`TimeLimitExceeded`), outermost first."""
    if isinstance(exc, TimeLimitExceeded) and exc.__cause__ is not None:
        exc = exc.__cause__
    frames = []
    for frame in traceback.extract_tb(exc.__traceback__):
        path = Path(frame.filename)
        if path.is_relative_to(REPO / "pixelworld_env") or path.is_relative_to(REPO / "sb3_smc"):
            frames.append((path.relative_to(REPO).as_posix(), frame.name))
    return frames


def _escape_point(exc: BaseException) -> tuple[str, str]:
    """Where ``exc`` left the package's code: its innermost frame of the packages (``("", "")`` if none)."""
    frames = _package_frames(exc)
    return frames[-1] if frames else ("", "")


@dataclass(frozen=True)
class KnownBug:
    """A foreign exception the fuzz tests found, not fixed yet: its type and where it escapes the package (file,
    function; ``match``: a regex its message matches), a summary and a minimal reproducer (a callable). A
    :class:`TimeLimitExceeded` matches where the function was running when it was stopped (at any depth)."""

    key: str
    exc: type[BaseException] | tuple[type[BaseException], ...]
    file: str
    function: str
    summary: str
    reproduce: Callable[[], Any]
    match: str = ""

    def matches(self, exc: BaseException) -> bool:
        where = (self.file, self.function)
        place = where in _package_frames(exc) if isinstance(exc, TimeLimitExceeded) else _escape_point(exc) == where
        return isinstance(exc, self.exc) and place and re.search(self.match, str(exc)) is not None


KNOWN_BUGS: list[KnownBug] = []
"""Bugs found and not fixed yet (none)."""
FOUND: list[KnownBug] = []  # filled below, beside the readers they concern: found, fixed, kept as regressions


def every(*triggers: Callable[[], Any]) -> Callable[[], None]:
    """A reproducer running several triggers of one bug: the first foreign exception propagates (the bug is fixed
    when none raises one); ``run.triggers`` are the triggers, each checked on its own."""
    def run() -> None:
        for trigger in triggers:
            with contextlib.suppress(*PACKAGE_ERRORS):
                trigger()
    run.triggers = triggers  # type: ignore[attr-defined]
    return run


def known_bug(exc: BaseException) -> KnownBug | None:
    return next((bug for bug in KNOWN_BUGS if bug.matches(exc)), None)


def outcome(fn: Callable[..., Any], *args: Any, allowed: tuple[type[BaseException], ...], what: str,
            **kwargs: Any) -> tuple[str, Any]:
    """Call ``fn`` within :data:`TIME_LIMIT_S`: ``("ok", result)`` or ``("error", the exception)`` for one of
    ``allowed`` (the package's errors); a known bug is ``("known", bug)``; any other exception, and running over the
    time limit, fails the test."""
    try:
        with time_limit(what):
            return "ok", fn(*args, **kwargs)
    except allowed as err:
        return "error", err
    except Exception as exc:  # noqa: BLE001 - the point: nothing else may come out
        bug = known_bug(exc)
        if bug is None:
            if isinstance(exc, TimeLimitExceeded):
                raise
            where = ":".join(_escape_point(exc)) or "outside the packages"
            raise AssertionError(f"{what}: foreign exception {type(exc).__module__}.{type(exc).__name__} "
                                 f"(escaping at {where}): {str(exc)[:500]}") from exc
        with contextlib.suppress(Exception):  # outside a Hypothesis test there is no event to record
            event(f"known bug {bug.key}")
        return "known", bug


# ================================================================================================================
# 1. The concept language against a brute-force evaluator
# ================================================================================================================
#
# The reference semantics (docs/design.md): ``self`` is the scene's self object; the declared variables are bound to
# pairwise distinct objects other than the self and the frame; the expression holds if some binding makes every
# positive clause hold and no negated group hold in all its clauses. A macro call stands for the macro's body with
# its declared variables replaced by the call's arguments. The predicates are recomputed below from the objects'
# pixels and template boxes, independently of pixelworld_env.concepts.predicates.


def _box(o: WorldObject) -> tuple[int, int, int, int]:
    """(top, left, bottom, right) of the template box, inclusive."""
    return o.position[0], o.position[1], o.position[0] + o.size[0] - 1, o.position[1] + o.size[1] - 1


def _pixels(o: WorldObject) -> set[tuple[int, int]]:
    return {(o.position[0] + dr, o.position[1] + dc) for dr, dc in o.cells}


def _some_pair(a: WorldObject, b: WorldObject, close: Callable[[int, int], bool]) -> bool:
    return any(close(abs(r1 - r2), abs(c1 - c2)) for r1, c1 in _pixels(a) for r2, c2 in _pixels(b))


def _ref_left_of(a, b, scene):
    return _box(a)[3] < _box(b)[1]


def _ref_above(a, b, scene):
    return _box(a)[2] < _box(b)[0]


def _ref_rows_overlap(a, b, scene):
    (at, _, ab, _), (bt, _, bb, _) = _box(a), _box(b)
    return not (ab < bt or bb < at)


def _ref_cols_overlap(a, b, scene):
    (_, al, _, ar), (_, bl, _, br) = _box(a), _box(b)
    return not (ar < bl or br < al)


def _ref_touches(a, b, scene):
    return _some_pair(a, b, lambda dr, dc: max(dr, dc) <= 1)


def _ref_adjacent(a, b, scene):
    return _some_pair(a, b, lambda dr, dc: dr + dc <= 1)


def _ref_near(a, b, scene):
    return _some_pair(a, b, lambda dr, dc: dr * dr + dc * dc <= 4)


def _ref_far(a, b, scene):
    return not _some_pair(a, b, lambda dr, dc: dr * dr + dc * dc <= 16)


def _ref_dir_before(a, b, horizontal: bool) -> bool:
    """dir_left_of (horizontal) / dir_above, as docs/design.md words it: the boxes share lines (rows / columns);
    a's box wholly before b's: true; b's wholly before a's: false; otherwise on every shared line on which both have
    pixels all of a's come before all of b's, with at least one such line."""
    line, pos = (0, 1) if horizontal else (1, 0)
    (at, al, ab, ar), (bt, bl, bb, br) = _box(a), _box(b)
    a_lines, b_lines = ((at, ab), (bt, bb)) if horizontal else ((al, ar), (bl, br))
    a_span, b_span = ((al, ar), (bl, br)) if horizontal else ((at, ab), (bt, bb))
    shared = range(max(a_lines[0], b_lines[0]), min(a_lines[1], b_lines[1]) + 1)
    if not shared:
        return False
    if a_span[1] < b_span[0]:
        return True
    if b_span[1] < a_span[0]:
        return False
    lines_with_both = 0
    for k in shared:
        mine = [p[pos] for p in _pixels(a) if p[line] == k]
        theirs = [p[pos] for p in _pixels(b) if p[line] == k]
        if mine and theirs:
            if max(mine) >= min(theirs):
                return False
            lines_with_both += 1
    return lines_with_both > 0


_FLOOR_ROWS_FROM_BOTTOM = 3  # docs: the floor's top row is height - 3

REFERENCE: dict[str, tuple[int, Callable[..., bool]]] = {
    # unary
    "pixel": (1, lambda a, s: a.family == "pixel"),
    "blob": (1, lambda a, s: a.family == "blob"),
    "container": (1, lambda a, s: a.family == "container"),
    "hline": (1, lambda a, s: a.family == "hline"),
    "noncontainer": (1, lambda a, s: a.family == "noncontainer"),
    "corner": (1, lambda a, s: a.family in {"lower_left_corner", "lower_right_corner", "upper_left_corner",
                                            "upper_right_corner"}),
    "potential_container": (1, lambda a, s: a.family in {"container", "noncontainer", "lower_left_corner",
                                                         "lower_right_corner"}),
    "object": (1, lambda a, s: a.family in {"blob", "small_blob", "convex_blob", "container", "noncontainer",
                                            "enclosure", "nonenclosure"}),
    "white": (1, lambda a, s: a.color == Color.WHITE),
    "red": (1, lambda a, s: a.color == Color.RED),
    "blue": (1, lambda a, s: a.color == Color.BLUE),
    "target": (1, lambda a, s: a.is_target),
    "pushable": (1, lambda a, s: a.pushable),
    "floor": (1, lambda a, s: a.family == "floor_shape" and a.position[0] == s.height - _FLOOR_ROWS_FROM_BOTTOM),
    # binary
    "left_of": (2, _ref_left_of),
    "right_of": (2, lambda a, b, s: _ref_left_of(b, a, s)),
    "above": (2, _ref_above),
    "below": (2, lambda a, b, s: _ref_above(b, a, s)),
    "h_aligned": (2, _ref_rows_overlap),
    "v_aligned": (2, _ref_cols_overlap),
    "touches": (2, _ref_touches),
    "adjacent": (2, _ref_adjacent),
    "near": (2, _ref_near),
    "far": (2, _ref_far),
    "on_top": (2, lambda a, b, s: _ref_above(a, b, s) and _ref_adjacent(a, b, s)),
    "on_bottom": (2, lambda a, b, s: _ref_above(b, a, s) and _ref_adjacent(a, b, s)),
    "on_left": (2, lambda a, b, s: _ref_left_of(a, b, s) and _ref_adjacent(a, b, s)),
    "on_right": (2, lambda a, b, s: _ref_left_of(b, a, s) and _ref_adjacent(a, b, s)),
    "dir_left_of": (2, lambda a, b, s: _ref_dir_before(a, b, True)),
    "dir_right_of": (2, lambda a, b, s: _ref_dir_before(b, a, True)),
    "dir_above": (2, lambda a, b, s: _ref_dir_before(a, b, False)),
    "dir_below": (2, lambda a, b, s: _ref_dir_before(b, a, False)),
    "same_color": (2, lambda a, b, s: a.color == b.color),
    "diff_color": (2, lambda a, b, s: a.color != b.color),
    "same_kind": (2, lambda a, b, s: a.family == b.family),
    "diff_kind": (2, lambda a, b, s: a.family != b.family),
    "same_shape": (2, lambda a, b, s: (a.family, a.shape_idx) == (b.family, b.shape_idx)),
    "taller": (2, lambda a, b, s: a.size[0] > b.size[0]),
    "wider": (2, lambda a, b, s: a.size[1] > b.size[1]),
    "same_height": (2, lambda a, b, s: a.size[0] == b.size[0]),
    "same_width": (2, lambda a, b, s: a.size[1] == b.size[1]),
    "bottom_aligned": (2, lambda a, b, s: _box(a)[0] == _box(b)[0]),  # the original's name: the tops
    "top_aligned": (2, lambda a, b, s: _box(a)[2] == _box(b)[2]),  # and the bottoms
    # ternary, the middle object first
    "h_between": (3, lambda c, a, b, s: _ref_left_of(a, c, s) and _ref_left_of(c, b, s)
                  and _ref_rows_overlap(a, c, s) and _ref_rows_overlap(c, b, s)),
    "v_between": (3, lambda c, a, b, s: _ref_above(a, c, s) and _ref_above(c, b, s)
                  and _ref_cols_overlap(a, c, s) and _ref_cols_overlap(c, b, s)),
}

SCENE_FAMILIES = ("pixel", "blob", "container", "hline", "noncontainer", "floor_shape", "lower_left_corner",
                  "upper_right_corner", "small_blob")
OTHER_CLASSES = (ObjectClass.BASIC, ObjectClass.COMPLEX, ObjectClass.IMMOVEABLE, ObjectClass.IMMOVEABLE_BIG)


@st.composite
def world_objects(draw: st.DrawFn, height: int, width: int, cls: ObjectClass, largest: int = 3) -> WorldObject:
    """An object inside a ``height`` x ``width`` world: a template box of up to ``largest`` x ``largest`` (possibly
    with empty rows or columns) with some cells, a family, colour and flags."""
    h, w = draw(st.integers(1, min(largest, height))), draw(st.integers(1, min(largest, width)))
    cells = draw(st.sets(st.tuples(st.integers(0, h - 1), st.integers(0, w - 1)), min_size=1))
    top, left = draw(st.integers(0, height - h)), draw(st.integers(0, width - w))
    return WorldObject(cls=cls, color=draw(st.sampled_from([Color.WHITE, Color.RED, Color.BLUE, Color.GREEN])),
                       position=(top, left), cells=tuple(sorted(cells)), size=(h, w),
                       family=draw(st.sampled_from(SCENE_FAMILIES)), shape_idx=draw(st.integers(0, 1)),
                       pushable=draw(st.booleans()), is_target=draw(st.booleans()))


@st.composite
def scenes(draw: st.DrawFn, min_others: int = 0, max_others: int = 5, max_height: int = 9, max_width: int = 10,
           largest: int = 3) -> Scene:
    """A small scene: one self, ``min_others`` to ``max_others`` other objects (overlaps allowed) of up to
    ``largest`` x ``largest`` cells, maybe a frame, in a random order."""
    height, width = draw(st.integers(4, max_height)), draw(st.integers(4, max_width))
    objects = [draw(world_objects(height, width, ObjectClass.SELF, largest))]
    objects += draw(st.lists(st.sampled_from(OTHER_CLASSES).flatmap(lambda c: world_objects(height, width, c,
                                                                                             largest)),
                             min_size=min_others, max_size=max_others))
    if draw(st.booleans()):
        objects.append(frame_object(height, width))
    order = draw(st.permutations(range(len(objects))))
    return Scene(height=height, width=width, objects=tuple(objects[i] for i in order))


# A formula: declared variables and items; an item is ("pos", atom) or ("neg", (atoms...)); an atom is (name, args)
# naming a predicate of REFERENCE or a macro.
Atom = tuple[str, tuple[str, ...]]
Item = tuple[str, Any]


@dataclass(frozen=True)
class Formula:
    variables: tuple[str, ...]
    items: tuple[Item, ...]


@dataclass(frozen=True)
class Macro:
    name: str
    body: Formula  # body.variables are the parameters
    negation_free: bool  # no negation in its expansion: the body's nor those of the macros it calls


VARIABLE_NAMES = ("x", "y", "z", "w", "v1", "B_2", "-q", "0", "pixel", "left_of")
"""Declared variable names: identifiers of every kind, also the names of predicates (a name's role is its place)."""
MACRO_NAMES = ("m-one", "m_two", "M3", "4m", "mac-ro")
WHITESPACE = (" ", "\n", "\t", "  ", "\r\n", "\u00a0", "\u2003", "\x0b", "\x0c")


@st.composite
def atoms(draw: st.DrawFn, names: tuple[str, ...], macros: tuple[Macro, ...], negation_free_only: bool) -> Atom:
    usable = [m for m in macros if m.negation_free or not negation_free_only]
    choices = [(name, arity) for name, (arity, _) in REFERENCE.items()]
    if usable and draw(st.booleans()):
        macro = draw(st.sampled_from(usable))
        name, arity = macro.name, len(macro.body.variables)
    else:
        name, arity = draw(st.sampled_from(choices))
    return name, tuple(draw(st.sampled_from(names)) for _ in range(arity))


@st.composite
def formulas(draw: st.DrawFn, macros: tuple[Macro, ...] = (), max_variables: int = 4,
             min_variables: int = 0, negations: bool = True, guide: Scene | None = None) -> Formula:
    """A well-formed formula: 0-4 declared variables, 1-3 items, each a clause, a negated clause or a negated
    conjunction, over predicates of REFERENCE and calls of ``macros`` (only negation-free ones inside a negation).

    ``guide``: a scene in which the formula is to hold for a witness binding drawn first (each item is the first of a
    few candidates that holds for the witness, where one does), but for one item in half the formulas, which is to
    fail for it: random formulas are mostly false, and the truth of a wrong clause would rarely decide theirs."""
    if guide is not None:
        max_variables = min(max_variables, len(_self_and_others(guide)[1]))
    count = draw(st.integers(min_variables, max(min_variables, max_variables)))
    variables = tuple(draw(st.lists(st.sampled_from(VARIABLE_NAMES), unique=True, min_size=count, max_size=count)))
    names = ("self", *variables)
    witness = None
    if guide is not None:
        me, others = _self_and_others(guide)
        witness = {"self": me, **dict(zip(variables, draw(st.permutations(others)), strict=False))}
    by_name = {m.name: m for m in macros}

    def candidate(kind: str) -> Item:
        if kind == "neg":
            return "neg", tuple(draw(st.lists(atoms(names, macros, True), min_size=1, max_size=3)))
        return "pos", draw(atoms(names, macros, False))

    items: list[Item] = []
    size = draw(st.integers(1, 3))
    spoiled = draw(st.integers(-size, size - 1)) if witness is not None else -1  # >= 0: that item is false
    for index in range(size):
        kind = "neg" if negations and draw(st.integers(0, 2)) == 0 else "pos"
        item = candidate(kind)
        for _ in range(8 if witness is not None else 0):
            if _items_hold((item,), witness, guide, by_name) is (index != spoiled):
                break
            item = candidate(kind)
        items.append(item)
    return Formula(variables, tuple(items))


@st.composite
def macro_tables(draw: st.DrawFn) -> tuple[Macro, ...]:
    """0-3 macros, each with 1-3 parameters, each using only the macros before it (no cycles)."""
    macros: list[Macro] = []
    count = draw(st.integers(0, 3))
    for name in draw(st.lists(st.sampled_from(MACRO_NAMES), unique=True, min_size=count, max_size=count)):
        body = draw(formulas(tuple(macros), max_variables=3, min_variables=1))
        free = {m.name for m in macros if m.negation_free}
        negation_free = all(kind == "pos" and (atom[0] in REFERENCE or atom[0] in free) for kind, atom in body.items)
        macros.append(Macro(name, body, negation_free))
    return tuple(macros)


def _tokens(formula: Formula) -> list[str]:
    def atom(a: Atom) -> list[str]:
        name, args = a
        out = [name, "("]
        for i, arg in enumerate(args):
            out += ([","] if i else []) + [arg]
        return out + [")"]

    tokens: list[str] = []
    for v in formula.variables:
        tokens += ["?", v]
    for i, (kind, body) in enumerate(formula.items):
        tokens += ["&"] if i else []
        if kind == "pos":
            tokens += atom(body)
        elif len(body) == 1 and body[0][0] in REFERENCE:  # "~p(x)"; a macro call or a group: "~(m(x) & p(x))"
            tokens += ["~", *atom(body[0])]
        else:
            tokens += ["~", "("]
            for j, a in enumerate(body):
                tokens += (["&"] if j else []) + atom(a)
            tokens += [")"]
    return tokens


@st.composite
def rendered(draw: st.DrawFn, formula: Formula) -> str:
    """The formula's text with random whitespace (unicode spaces and line breaks too) between tokens; two
    identifiers in a row get at least one space."""
    tokens = _tokens(formula)
    out = [draw(st.sampled_from(("", *WHITESPACE)))]
    for i, token in enumerate(tokens):
        out.append(token)
        if i + 1 < len(tokens):
            both_idents = token[-1] not in "?(),~&" and tokens[i + 1][0] not in "?(),~&"
            out.append(draw(st.sampled_from(WHITESPACE if both_idents else ("", "", *WHITESPACE))))
    out.append(draw(st.sampled_from(("", *WHITESPACE))))
    return "".join(out)


def _self_and_others(scene: Scene) -> tuple[WorldObject, list[WorldObject]]:
    """The self, and the objects the variables range over: neither the self nor the frame."""
    me = next(o for o in scene.objects if o.cls is ObjectClass.SELF)
    return me, [o for o in scene.objects if o.cls not in (ObjectClass.SELF, ObjectClass.FRAME)]


def _atom_holds(a: Atom, env: dict[str, WorldObject], scene: Scene, macros: dict[str, Macro]) -> bool:
    """A clause under a binding; a macro call is its body with the parameters bound to the call's objects."""
    name, args = a
    objects = [env[arg] for arg in args]
    if name in macros:
        body = macros[name].body
        inner = {"self": env["self"], **dict(zip(body.variables, objects, strict=True))}
        return _items_hold(body.items, inner, scene, macros)
    return REFERENCE[name][1](*objects, scene)


def _items_hold(items: tuple[Item, ...], env: dict[str, WorldObject], scene: Scene,
                macros: dict[str, Macro]) -> bool:
    """Every positive clause holds and no negated group holds in all its clauses."""
    return all(_atom_holds(body, env, scene, macros) if kind == "pos"
               else not all(_atom_holds(a, env, scene, macros) for a in body) for kind, body in items)


def brute_force(formula: Formula, macros: dict[str, Macro], scene: Scene) -> bool:
    """The reference semantics: every injective binding of the variables to the objects that are neither the self
    nor the frame, tried one by one."""
    me, others = _self_and_others(scene)
    for chosen in itertools.permutations(others, len(formula.variables)):
        env = {"self": me, **dict(zip(formula.variables, chosen, strict=True))}
        if _items_hold(formula.items, env, scene, macros):
            return True
    return False


@given(data=st.data(), scene=scenes(min_others=1))
def test_holds_agrees_with_brute_force(data: st.DataObject, scene: Scene) -> None:
    """``holds`` / ``Concept.holds`` give the brute-force evaluator's truth for random formulas (with macros) and
    scenes, whatever the whitespace; so do the parsed Expression and a pickled copy of the Concept."""
    macros = data.draw(macro_tables(), label="macros")
    guided = data.draw(st.booleans(), label="guided")
    formula = data.draw(formulas(macros, guide=scene if guided else None), label="formula")
    text = data.draw(rendered(formula), label="text")
    table = {m.name: data.draw(rendered(m.body), label=f"macro {m.name}") for m in macros}
    expected = brute_force(formula, {m.name: m for m in macros}, scene)
    note(f"scene:\n{scene.to_ascii()}\nobjects: {scene.objects}")
    event(f"holds: {expected}")
    with time_limit("holds"):
        concept = Concept(text, table)
        assert concept.holds(scene) is expected
        assert holds(text, scene, table) is expected
        assert Concept(parse(text), table).holds(scene) is expected
        assert pickle.loads(pickle.dumps(concept)).holds(scene) is expected


PARAMETER_NAMES = ("a", "b", "x", "y", "z", "w")
"""Macro parameters: some named like the variables of the formulas, so that a call's renaming must be simultaneous
(``m(y,x)`` of ``?x ?y left_of(x,y)``)."""


@st.composite
def folded(draw: st.DrawFn, formula: Formula, name: str, macros: dict[str, Macro]) -> tuple[Formula, Macro]:
    """``formula`` with some of its items (or some clauses of one negated group) moved into a new macro ``name``,
    replaced by a call of it: the same concept, by the definition of a macro."""
    groups = [i for i, (kind, _) in enumerate(formula.items) if kind == "neg"]
    inside = draw(st.sampled_from((None, *groups)))
    pool = list(formula.items) if inside is None else [("pos", a) for a in formula.items[inside][1]]
    chosen = sorted(draw(st.sets(st.integers(0, len(pool) - 1), min_size=1)))
    part = [pool[i] for i in chosen]
    used = list(dict.fromkeys(arg for kind, body in part for _, args in ((body,) if kind == "pos" else body)
                              for arg in args if arg != "self"))
    arguments = used or ["self"]  # a macro declares one parameter at least (here unused)
    parameters = draw(st.permutations(PARAMETER_NAMES))[:len(arguments)]
    rename = dict(zip(used, parameters, strict=False))

    def renamed(item: Item) -> Item:
        kind, body = item
        atom = lambda a: (a[0], tuple(rename.get(arg, arg) for arg in a[1]))  # noqa: E731
        return (kind, atom(body)) if kind == "pos" else (kind, tuple(atom(a) for a in body))

    body = Formula(tuple(parameters), tuple(renamed(item) for item in part))
    free = all(kind == "pos" and (body[0] not in macros or macros[body[0]].negation_free) for kind, body in part)
    macro = Macro(name, body, free)
    call = ("pos", (name, tuple(arguments)))
    rest = [item for i, item in enumerate(pool) if i not in chosen]
    rest.insert(draw(st.integers(0, len(rest))), call)
    if inside is None:
        return Formula(formula.variables, tuple(rest)), macro
    items = list(formula.items)
    items[inside] = ("neg", tuple(atom for _, atom in rest))
    return Formula(formula.variables, tuple(items)), macro


@given(data=st.data(), scene=scenes(min_others=1))
def test_macros_expand_to_what_they_stand_for(data: st.DataObject, scene: Scene) -> None:
    """A formula with parts folded into macros (1-3, nested, inside negations too, parameters named like the
    variables): ``holds`` gives the truth of the formula without macros."""
    formula = data.draw(formulas(guide=scene), label="formula")
    expected = brute_force(formula, {}, scene)
    macros: dict[str, Macro] = {}
    for name in MACRO_NAMES[:data.draw(st.integers(1, 3), label="folds")]:
        formula, macro = data.draw(folded(formula, name, macros), label=f"fold {name}")
        macros[name] = macro
    assert brute_force(formula, macros, scene) is expected  # the reference agrees with itself
    text = data.draw(rendered(formula), label="text")
    table = {name: data.draw(rendered(m.body), label=f"macro {name}") for name, m in macros.items()}
    event(f"holds: {expected}")
    with time_limit("holds"):
        assert holds(text, scene, table) is expected


TEMPLATES = {
    1: ("{p}(self)", "?x {p}(x)", "?x ?y {p}(x) & {p}(y)", "?x {p}(x) & ~{p}(self)", "?x ~{p}(x)"),
    2: ("{p}(self,self)", "?x {p}(self,x)", "?x {p}(x,self)", "?x ?y {p}(x,y)", "?x ?y {p}(x,y) & {p}(y,x)",
        "?x ~{p}(self,x)", "?x ?y {p}(x,y) & ~{p}(self,y)", "?x ?y ?z {p}(x,y) & ~({p}(y,z) & {p}(z,x))"),
    3: ("?x ?y {p}(self,x,y)", "?x ?y {p}(x,self,y)", "?x ?y {p}(x,y,self)", "?x ?y ?z {p}(x,y,z)",
        "?x ?y ~{p}(y,self,x)"),
}
"""Formulas of one predicate, each deciding on its truth for some pair or triple of objects (and on distinctness:
``?x ?y p(x) & p(y)`` needs two objects)."""


@given(scene=scenes(min_others=2, max_others=3, max_height=8, max_width=8, largest=2))
def test_every_predicate_agrees_with_brute_force(scene: Scene) -> None:
    """Each predicate of REFERENCE, in formulas of that predicate alone, in crowded little scenes (so that touching,
    alignment and betweenness are frequent): ``holds`` gives the brute-force truth."""
    note(f"scene:\n{scene.to_ascii()}\nobjects: {scene.objects}")
    with time_limit("holds"):
        for name, (arity, _) in REFERENCE.items():
            for template in TEMPLATES[arity]:
                text = template.format(p=name)
                formula = Formula(parse(text).variables, _items(parse(text)))
                assert holds(text, scene, {}) is brute_force(formula, {}, scene), text


def _items(expression: Any) -> tuple[Item, ...]:
    """The items of a parsed expression (without macros) as a Formula's."""
    return (*(("pos", (c.name, c.args)) for c in expression.positives),
            *(("neg", tuple((c.name, c.args) for c in group)) for group in expression.negations))


@given(scene=scenes(), data=st.data())
def test_a_formula_and_its_printed_expression_hold_alike(scene: Scene, data: st.DataObject) -> None:
    """``str(parse(text))`` parses to the same Expression (positions aside) and holds where ``text`` holds."""
    formula = data.draw(formulas(), label="formula")
    text = data.draw(rendered(formula), label="text")
    expression = parse(text)
    printed = str(expression)
    again = parse(printed)
    strip = lambda e: (e.variables, [(c.name, c.args) for c in e.positives],  # noqa: E731
                       [[(c.name, c.args) for c in g] for g in e.negations])
    assert strip(again) == strip(expression)
    assert holds(printed, scene, {}) is holds(text, scene, {}) is brute_force(formula, {}, scene)


def test_brute_force_evaluator_is_not_trivial() -> None:
    """The reference itself: distinct bindings, negated conjunctions, macros and the frame's exclusion."""
    scene = Scene.from_ascii("""
        ######
        #S.a.#
        #....#
        #==..#
        #....#
        ######
    """)  # the floor's top is row 3 = height - 3
    f = lambda items, variables=(): Formula(tuple(variables), tuple(items))  # noqa: E731
    assert brute_force(f([("pos", ("left_of", ("self", "x")))], ["x"]), {}, scene)  # x = a
    assert not brute_force(f([("pos", ("left_of", ("x", "self")))], ["x"]), {}, scene)
    assert brute_force(f([("pos", ("blob", ("x",)))], ["x", "y"]), {}, scene)  # x = a, y = the floor
    assert not brute_force(f([("pos", ("blob", ("x",))), ("pos", ("blob", ("y",)))], ["x", "y"]), {}, scene)
    assert not brute_force(f([("pos", ("pixel", ("self",)))], ["x", "y", "z"]), {}, scene)  # 3 objects needed
    assert not brute_force(f([("neg", (("red", ("self",)), ("pixel", ("self",))))]), {}, scene)  # self: red pixel
    assert brute_force(f([("neg", (("red", ("self",)), ("blob", ("self",))))]), {}, scene)
    macro = Macro("m", f([("pos", ("above", ("self", "a")))], ["a"]), True)
    assert brute_force(f([("pos", ("m", ("x",))), ("pos", ("floor", ("x",)))], ["x"]), {"m": macro}, scene)
    assert not brute_force(f([("pos", ("m", ("x",))), ("pos", ("blob", ("x",)))], ["x"]), {"m": macro}, scene)


# ================================================================================================================
# 2. The parser and the compiler on random and mutated text
# ================================================================================================================

CONCEPT_ALPHABET = "?~&(),_- \n\tselfxyzpixelft_oabvc0129\u00a0é\x00$#"


@st.composite
def mutated(draw: st.DrawFn, text: str, alphabet: str) -> str:
    """``text`` with 1-4 random edits: a character inserted, deleted or replaced, a slice doubled or cut off."""
    chars = list(text)
    for _ in range(draw(st.integers(1, 4))):
        op = draw(st.sampled_from(("insert", "delete", "replace", "double", "truncate")))
        i = draw(st.integers(0, len(chars)))
        if op == "insert":
            chars.insert(i, draw(st.sampled_from(alphabet)))
        elif op == "delete" and i < len(chars):
            del chars[i]
        elif op == "replace" and i < len(chars):
            chars[i] = draw(st.sampled_from(alphabet))
        elif op == "double":
            j = draw(st.integers(i, len(chars)))
            chars[i:i] = chars[i:j]
        elif op == "truncate":
            chars = chars[:i]
    return "".join(chars)


@st.composite
def concept_texts(draw: st.DrawFn) -> str:
    """Arbitrary text, text over the language's characters, or a valid formula with a few edits."""
    kind = draw(st.sampled_from(("any", "alphabet", "mutated")))
    if kind == "any":
        return draw(st.text(max_size=60))
    if kind == "alphabet":
        return draw(st.text(alphabet=CONCEPT_ALPHABET, max_size=60))
    return draw(mutated(draw(rendered(draw(formulas()))), CONCEPT_ALPHABET))


@given(text=concept_texts(), scene=scenes())
def test_concept_text_gives_a_concept_or_a_concept_error(text: str, scene: Scene) -> None:
    """Random and mutated expressions: parse, compile and evaluate, or a ConceptError; nothing else, and quickly."""
    kind, parsed = outcome(parse, text, allowed=(ConceptError,), what="parse")
    compiled = outcome(Concept, text, {}, allowed=(ConceptError,), what="Concept")
    if kind == "error":
        assert compiled[0] == "error", "parse refused what Concept accepted"
    if compiled[0] == "ok":
        assert outcome(compiled[1].holds, scene, allowed=(), what="holds")[1] in (True, False)


@given(value=st.one_of(st.none(), st.integers(), st.binary(max_size=5), st.lists(st.text(max_size=3), max_size=2),
                       st.floats(), st.dictionaries(st.text(max_size=3), st.text(max_size=3), max_size=2)))
def test_concepts_of_other_types_are_a_pixelworld_type_error(value: Any) -> None:
    """Not a string: the package's TypeError (a PixelWorldError), from parse, Concept and holds."""
    for fn in (parse, Concept, lambda v: holds(v, Scene.from_ascii("###\n#S#\n###"), {})):
        kind, err = outcome(fn, value, allowed=(PixelWorldError,), what=f"{fn.__name__}({value!r})")
        assert kind == "error" and isinstance(err, TypeError)


@st.composite
def wild_macro_tables(draw: st.DrawFn) -> dict[Any, Any]:
    """Macro tables that may be cyclic, doubling, of wrong arity, syntactically wrong, named like predicates or not
    strings at all."""
    names = draw(st.lists(st.sampled_from((*MACRO_NAMES, "pixel", "touches", 1)), unique=True, min_size=1,
                          max_size=4))
    table: dict[Any, Any] = {}
    for name in names:
        parameters = draw(st.lists(st.sampled_from(("a", "b", "c")), unique=True, max_size=3))
        clauses = []
        for _ in range(draw(st.integers(1, 4))):
            callee = draw(st.sampled_from((*names, "pixel", "left_of", "unknown_p")))
            args = draw(st.lists(st.sampled_from(("self", *parameters, "undeclared")), min_size=1, max_size=3))
            clauses.append(("~" if draw(st.booleans()) else "") + f"{callee}({','.join(args)})")
        text = " ".join(f"?{p}" for p in parameters) + " " + " & ".join(clauses)
        table[name] = draw(st.one_of(st.just(text), mutated(text, CONCEPT_ALPHABET), st.integers(), st.none()))
    return table


@given(table=wild_macro_tables(), expression=st.sampled_from(
    ("m-one(self)", "?x m_two(self,x)", "?x ~M3(x)", "?x ?y 4m(x,y) & ~mac-ro(y)", "pixel(self)", "?x touches(x,x)")))
def test_wild_macro_tables_give_a_concept_or_a_concept_error(table: dict[Any, Any], expression: str) -> None:
    """Cyclic, doubling, ill-formed macro tables: a Concept or the package's error, never more than the time bound
    (macro expansion is bounded: MAX_EXPANDED_CLAUSES, MAX_MACRO_DEPTH)."""
    scene = Scene.from_ascii("######\n#S.a.#\n#==..#\n######")
    kind, concept = outcome(Concept, expression, table, allowed=(PixelWorldError,), what="Concept")
    if kind == "ok":
        assert outcome(concept.holds, scene, allowed=(), what="holds")[1] in (True, False)


def test_a_macro_with_a_negation_used_inside_a_negation_is_refused() -> None:
    """The one ill-formed use the formula generator never makes (formulas keep such macros out of negations)."""
    with pytest.raises(NegatedMacroError):
        Concept("?x ~(m(x))", {"m": "?a ~pixel(a)"})


# ================================================================================================================
# 3. Definition files and curriculum files
# ================================================================================================================

HOLE = "__FUZZ_HOLE__"
RAW_YAML = (
    # tags, PyYAML's and unknown ones
    "!foo x", "!!python/object/apply:os.system [echo]", "!!python/name:os.system ''", "!!binary aGVsbG8=",
    "!!set {a, b}", "!!omap [a: 1]", "!!pairs [a: 1]", "!!timestamp 2001-12-14", "!!float x", "!!int x",
    "!!str 5", "!!null ''", "!!bool maybe", "!<tag:yaml.org,2002:int> 3",
    # anchors and aliases
    "&a [1, 2]", "*a", "&a [1, *a]", "[&b x, *b]",
    # merge keys, complex keys
    "{<<: {a: 1}}", "{<<: [{a: 1}]}", "{? [1, 2] : 3}", "{? {a: 1} : 3}", "{1: a, 1.5: b, ~: c, true: d}",
    # numbers
    "9" * 5000, "1" + "0" * 400, "-" + "9" * 400, "1e400", "-1e400", ".nan", ".inf", "-.inf", "0x1F", "0o17",
    "0b101", "1_000", "190:20:30", "0", "-1", "1.5", "2001-12-14", "2001-12-14t21:59:43.10-05:00",
    # strings and empties
    "''", '""', "~", "[]", "{}", "yes", "off", "'\u2028x\u2029'", '"\\ud800"', '"\\x00"', '"\\U0001F600"',
    "'" + "x" * 3000 + "'", "\u202e\u0644\u064a", "'\ufeff'", "'a: b'", "'- x'", "'+@'", "'+@missing'",
    # nesting
    "[" * 150 + "]" * 150, "[" * 99 + "]" * 99, "{a: " * 120 + "x" + "}" * 120,
)
"""Fragments of YAML (flow style, one line) put where a value was."""

YAML_SCALARS = st.one_of(
    st.none(), st.booleans(), st.integers(), st.integers(min_value=-(10**500), max_value=10**500),
    st.floats(), st.text(max_size=20), st.sampled_from(("+@fuzz_list", "pixel(self)", "cl_fuzz", "out/a/b/c/d")),
    st.binary(max_size=4), st.dates())
YAML_KEYS = st.one_of(st.text(max_size=8), st.integers(), st.none(), st.booleans(), st.floats(allow_nan=False))
YAML_VALUES = st.recursive(YAML_SCALARS, lambda inner: st.one_of(
    st.lists(inner, max_size=3), st.dictionaries(YAML_KEYS, inner, max_size=3)), max_leaves=10)


@st.composite
def places(draw: st.DrawFn, document: Any) -> tuple[Any, ...]:
    """A path into JSON-like data, by a random walk from the top: at each mapping or list, stop (one time in four)
    or go on into one of its items, each as likely (so a top-level field is as likely as a number in a long list)."""
    path: list[Any] = []
    node = document
    while isinstance(node, dict | list) and node and draw(st.integers(0, 3)):
        key = draw(st.sampled_from(list(node) if isinstance(node, dict) else range(len(node))))
        path.append(key)
        node = node[key]
    return tuple(path)


def _nested(depth: int) -> Any:
    value: Any = "x"
    for _ in range(depth):
        value = [value]
    return value


@st.composite
def edited(draw: st.DrawFn, document: Any, values: st.SearchStrategy) -> Any:
    """A copy of ``document`` (JSON-like data) with one place changed: its value replaced (by one of ``values``),
    removed, or given a new sibling key."""
    doc = copy.deepcopy(document)
    path = draw(places(doc))
    note(f"edited at {path!r}")
    if not path:
        return draw(values)
    parent = doc
    for key in path[:-1]:
        parent = parent[key]
    op = draw(st.sampled_from(("replace", "replace", "delete", "add")))
    if op == "replace":
        parent[path[-1]] = draw(values)
    elif op == "delete":
        del parent[path[-1]]
    elif isinstance(parent, dict):
        parent[draw(st.text(max_size=6))] = draw(values)
    else:
        parent.insert(path[-1], draw(values))
    return doc


def _dump(document: Any) -> str:
    return yaml.safe_dump(document, sort_keys=False, allow_unicode=True, width=10**6)


@st.composite
def yaml_texts(draw: st.DrawFn, base: dict[str, Any]) -> str:
    """Adversarial YAML from a valid ``base`` document: a field changed to a random value (of another type, huge,
    nested), to a raw YAML fragment (tags, aliases, merge keys, deep nesting ...), the text edited character by
    character, a random document, or random text."""
    kind = draw(st.sampled_from(("edit", "raw", "chars", "document", "text")))
    if kind == "edit":
        return _dump(draw(edited(base, YAML_VALUES)))
    if kind == "raw":
        return _dump(draw(edited(base, st.just(HOLE)))).replace(HOLE, draw(st.sampled_from(RAW_YAML)), 1)
    if kind == "chars":
        return draw(mutated(_dump(base), ":-?[]{}!&*|>'\"#%@`,~ \n\t\\x0é\u2028"))
    if kind == "document":
        return _dump(draw(YAML_VALUES))
    return draw(st.text(max_size=200))


# ---------------------------------------------------------------------------------------------- definition files


DEFINITIONS: dict[str, Any] = {
    "__include__": ["extra.include"],
    "concepts": {
        "c-one": {"desc": "a pixel right of the self", "logic": "?x pixel(x) & left_of(self,x)"},
        "c-two": {"logic": "?x ?y c-one(x) & ~touches(x,y) & blue(y)"},
    },
    "generators": {
        "g-one": {"name": "ignored", "logic": "?x c-one(x) & ~(touches(self,x) & red(x))"},
    },
    "datasets": {
        "cl_fuzz": ["c-one", ["g-one"], {"allow_pushable": True}],
        "ba_fuzz": ["c-two", ["g-one"]],
    },
    "curriculum": {
        "entry-one": ["cl_fuzz", ["out/aaai18/group/cl_fuzz/variant"]],
        "entry-two": ["ba_fuzz", "+@extra_list"],
    },
    "fuzz_list": ["out/aaai18/g/ba_fuzz/v1", "out/aaai18/g/cl_fuzz/v2"],
    "__gen_block": {"call": "tools:generate_pattern",
                    "kwargs": {"name": "curriculum", "cfg": {"entry-three": ["cl_fuzz", "+@local"]},
                               "bindings": {"local": "+@fuzz_list"}}},
}
"""A valid definition file using every part of the format (``extra.include`` lies beside it)."""


@pytest.fixture(scope="module")
def definitions_folder() -> Iterator[Path]:
    folder = Path(tempfile.mkdtemp(prefix="fuzz-definitions-"))
    (folder / "extra.include").write_text("extra_list: [out/aaai18/g/ba_fuzz/v3]\n", encoding="utf-8")
    yield folder
    shutil.rmtree(folder, ignore_errors=True)


def test_the_base_definition_file_is_valid(definitions_folder: Path) -> None:
    """The documents the fuzz tests start from load (so that an edit is what makes them fail)."""
    path = definitions_folder / "base.datasets"
    path.write_text(_dump(DEFINITIONS), encoding="utf-8")
    loaded = load_definitions(path)
    assert set(loaded.datasets) == {"cl_fuzz", "ba_fuzz"} and len(loaded.curricula["base"]) == 3


@given(text=yaml_texts(DEFINITIONS))
def test_definition_files_load_or_give_a_pixelworld_error(definitions_folder: Path, text: str) -> None:
    """Random and adversarial definition files: a DefinitionSet or a PixelWorldError, within the time bound."""
    path = definitions_folder / "fuzz.datasets"
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    kind, result = outcome(load_definitions, path, allowed=(PixelWorldError,), what="load_definitions")
    if kind == "ok":
        assert isinstance(result, DefinitionSet)


@given(data=st.binary(max_size=200))
def test_definition_files_of_random_bytes(definitions_folder: Path, data: bytes) -> None:
    """Bytes that may not be UTF-8 at all: a DefinitionSet or a PixelWorldError."""
    path = definitions_folder / "bytes.datasets"
    path.write_bytes(data)
    outcome(load_definitions, path, allowed=(PixelWorldError,), what="load_definitions")


def _definitions(text: str) -> Callable[[], Any]:
    def load() -> Any:
        with tempfile.TemporaryDirectory() as folder:
            path = Path(folder) / "bug.datasets"
            path.write_text(text, encoding="utf-8")
            return load_definitions(path)
    return load


FOUND += [
    KnownBug("yaml-constructor-errors", (ValueError, KeyError, AttributeError), "pixelworld_env/yaml_loading.py",
             "construct_node",
             "construct_node catches only yaml.YAMLError, but PyYAML's safe constructors raise others for scalars "
             "they cannot read: ValueError for 'a: !!int x', 'a: !!float x' and an integer of more than 4300 digits "
             "(int_max_str_digits), KeyError for 'a: !!bool maybe', AttributeError for 'a: !!timestamp x' (definition "
             "and experiment files: load_yaml, safe_yaml_load)",
             every(*(_definitions(f"a: {value}\n") for value in
                     ("!!int x", "!!float x", "!!bool maybe", "!!timestamp x", "9" * 4301)))),
    KnownBug("definitions-clash-not-str", TypeError, "pixelworld_env/generation/definitions.py", "load_definitions",
             "a non-string name defined both as concept and as generator: ', '.join(clash) raises TypeError",
             _definitions("concepts:\n  1: {logic: 'pixel(self)'}\ngenerators:\n  1: {logic: 'pixel(self)'}\n")),
    KnownBug("definitions-name-not-str", TypeError, "pixelworld_env/concepts/evaluate.py", "_resolve",
             "a concept or generator named by a number (keys are not checked to be strings) and an unknown predicate "
             "anywhere: difflib.get_close_matches over the macro names raises TypeError in Concept._resolve (also "
             "Concept('x(self)', {1: 'pixel(self)'}) directly)",
             _definitions("concepts:\n  1: {logic: 'x(self)'}\n")),
    KnownBug("definitions-include-path-unchecked", (OSError, ValueError), "pixelworld_env/generation/definitions.py",
             "_read_file",
             "an __include__ path the file system cannot take: Path.is_file() in _read_file raises OSError "
             "(ENAMETOOLONG) for a name of 300 characters and ValueError ('embedded null byte') for \"\\x00\"",
             every(_definitions("__include__: ['" + "a" * 300 + "']\n"), _definitions('__include__: "\\x00"\n'))),
]


# ---------------------------------------------------------------------------------------------- curriculum files


_DATASETS = catalog.dataset_names()
CURRICULUM: dict[str, Any] = {
    "curriculum": "fuzz",
    "method": "smc-curr",
    "description": "a curriculum using every field",
    "defaults": {"timesteps": 1000, "max_steps": 80},
    "nodes": [
        {"name": "low", "task": _DATASETS[0]},
        {"name": "high", "task": _DATASETS[1], "uses": ["low"], "primitives": False, "algo": "PPO",
         "timesteps": 5000, "budget_scale": 2.5, "count_primitive_steps": True, "max_steps": 50,
         "call_step_cap": 20, "hyperparameters": {"gamma": 0.9, "policy_kwargs": {"net_arch": [8]}}},
    ],
    "targets": ["high"],
}


def test_the_base_curriculum_is_valid() -> None:
    """The curriculum the fuzz tests start from parses (so that an edit is what makes it fail)."""
    curriculum = parse_curriculum(_dump(CURRICULUM), "base")
    assert [n.name for n in curriculum.nodes] == ["low", "high"] and curriculum.targets == ("high",)


@given(text=yaml_texts(CURRICULUM))
def test_curriculum_files_parse_or_give_an_smc_error(text: str) -> None:
    """Random and adversarial curriculum files: a Curriculum or the package's error, within the time bound."""
    kind, result = outcome(parse_curriculum, text, "fuzz.yml", allowed=PACKAGE_ERRORS, what="parse_curriculum")
    if kind == "ok":
        assert isinstance(result, Curriculum) and result.nodes


def _curriculum(text: str) -> Callable[[], Any]:
    return lambda: parse_curriculum(text, "bug.yml")


_NODE = "curriculum: x\nnodes: [{{name: a, task: {}}}]\n"
FOUND += [
    KnownBug("curriculum-constructor-errors", (yaml.YAMLError, ValueError, KeyError, AttributeError),
             "sb3_smc/curricula/format.py", "_plain",
             "_plain calls PyYAML's construct_object unguarded: yaml.constructor.ConstructorError for a tag the safe "
             "loader does not know ('!foo x') or a merge key ('<<: {a: 1}'), ValueError for '!!int x', '!!float x' "
             "and an integer of more than 4300 digits (int_max_str_digits), KeyError for '!!bool maybe', "
             "AttributeError for '!!timestamp x'",
             every(*(_curriculum(f"curriculum: {value}\n") for value in
                     ("!foo x", "{<<: {a: 1}}", "!!int x", "!!float x", "!!bool maybe", "!!timestamp x",
                      "9" * 4301)))),
    KnownBug("curriculum-unhashable-key", TypeError, "sb3_smc/curricula/format.py", "_plain",
             "a mapping key that is a list or a mapping (? [a]): 'key in out' raises TypeError: unhashable type",
             _curriculum("? [a]\n: 1\n"), "unhashable"),
    KnownBug("curriculum-huge-budget-scale", OverflowError, "sb3_smc/curricula/format.py", "_node",
             "budget_scale an integer beyond float range (1 followed by 400 zeros): math.isfinite raises "
             "OverflowError in _node",
             _curriculum(f"curriculum: x\nnodes: [{{name: a, task: {_DATASETS[0]}, budget_scale: 1{'0' * 400}}}]\n")),
    KnownBug("curriculum-relative-module", TypeError, "sb3_smc/curricula/format.py", "_registered",
             "a task 'module:Name-v0' whose module is relative ('..:Foo-v0', '.x:Foo-v0'): importlib.import_module "
             "raises TypeError (no package), which _registered does not catch",
             _curriculum(_NODE.format("'..:Foo-v0'"))),
    KnownBug("curriculum-env-id-long-version", ValueError, "sb3_smc/curricula/format.py", "_registered",
             "a task 'Foo-v<4301 digits>': gymnasium's parse_env_id raises ValueError (int_max_str_digits), which "
             "_registered does not catch",
             _curriculum(_NODE.format("Foo-v" + "9" * 4301)), "Exceeds the limit"),
]


# ================================================================================================================
# 4. The library loader and the model file reader
# ================================================================================================================




@dataclass(frozen=True)
class Pristine:
    """A saved one-SMC library: its folder, the SMC's name, the manifest as JSON and the model file's bytes."""

    root: Path
    name: str
    manifest: dict[str, Any]
    model: bytes
    algo: str

    @property
    def metadata(self) -> dict[str, Any]:
        size = int.from_bytes(self.model[:8], "little")
        return json.loads(json.loads(self.model[8:8 + size])["__metadata__"][METADATA_KEY])


@pytest.fixture(scope="module")
def pristine() -> Iterator[Pristine]:
    """One pretrained SMC (no children) saved alone as a library; nothing is trained."""
    pretrained = SMCLibrary.pretrained("search2-canon")
    name = next(n for n in pretrained.names if not pretrained[n].children)
    folder = Path(tempfile.mkdtemp(prefix="fuzz-library-"))
    root = SMCLibrary([pretrained[name]]).save(folder / "pristine")
    manifest = json.loads((root / "manifest.json").read_text(encoding="utf-8"))
    entry = manifest["smcs"][name]
    model = (root / entry["model"]).read_bytes()
    SMCLibrary.load(root)  # warm: later loads import nothing new
    yield Pristine(root, name, manifest, model, entry["spec"]["algo"])
    shutil.rmtree(folder, ignore_errors=True)


@contextlib.contextmanager
def library_copy(pristine: Pristine) -> Iterator[Path]:
    """A fresh folder holding the pristine library's files, removed afterwards."""
    folder = Path(tempfile.mkdtemp(prefix="fuzz-copy-"))
    try:
        shutil.copytree(pristine.root, folder / "lib", ignore=shutil.ignore_patterns(".lock"))
        yield folder / "lib"
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def _seal(path: Path, manifest: Any) -> bool:
    """Write ``manifest`` with its checksums recomputed (storage.write_manifest; for data nested too deep for its
    indented text, the same content sealed, written compact) where its shape allows it; else as plain JSON. False
    where even that cannot be written (the test harness's limit, not the package's)."""
    try:
        smcs = manifest.get("smcs") if isinstance(manifest, dict) else None
        if isinstance(smcs, dict) and all(isinstance(e, dict) for e in smcs.values()):
            try:
                storage.write_manifest(path, manifest)
            except RecursionError:
                path.write_text(json.dumps(seal(manifest)), encoding="utf-8")
        else:
            path.write_text(json.dumps(manifest), encoding="utf-8")
    except (RecursionError, ValueError):
        return False
    return True


def _with_model(root: Path, manifest: dict[str, Any], name: str, data: bytes, suffix: str = ".safetensors") -> None:
    """Put ``data`` in as SMC ``name``'s model file (named by its SHA-256) and recompute every checksum."""
    digest = hashlib.sha256(data).hexdigest()
    relative = f"models/{digest}{suffix}" if suffix == ".safetensors" else f"models/forged{suffix}"
    (root / relative).write_bytes(data)
    manifest["smcs"][name].update(model=relative, sha256=digest)
    storage.write_manifest(root / "manifest.json", manifest)


def _load(root: Path, **kwargs: Any) -> tuple[str, Any]:
    kind, result = outcome(SMCLibrary.load, root, allowed=(LibraryError,), what="SMCLibrary.load", **kwargs)
    if kind == "ok":
        assert isinstance(result, SMCLibrary)
    return kind, result


@st.composite
def damaged_bytes(draw: st.DrawFn, data: bytes, hot: int = 0) -> bytes:
    """``data`` with 1-3 random byte edits (flip, insert, delete a range, truncate), half of them in the first
    ``hot`` bytes (a header) where ``hot`` is given."""
    out = bytearray(data)
    for _ in range(draw(st.integers(1, 3))):
        limit = hot if hot and draw(st.booleans()) else len(out)
        i = draw(st.integers(0, max(0, min(limit, len(out)) - 1)))
        op = draw(st.sampled_from(("flip", "insert", "delete", "truncate")))
        if op == "flip" and out:
            out[i] ^= draw(st.integers(1, 255))
        elif op == "insert":
            out[i:i] = draw(st.binary(min_size=1, max_size=8))
        elif op == "delete":
            del out[i:i + draw(st.integers(1, 16))]
        else:
            del out[i:]
    return bytes(out)


JSON_VALUES = st.recursive(
    st.one_of(st.none(), st.booleans(), st.integers(), st.integers(min_value=-(10**30), max_value=10**30),
              st.floats(allow_nan=False, allow_infinity=False), st.text(max_size=10),
              st.sampled_from(("", "lin_", "lin_0.5", "PPO", "RecurrentPPO", "classification", "bring-about",
                               "models/x.zip", "../x", "/etc/passwd", "a" * 64, "0" * 64, "float64",
                               "torch.nn.ReLU", "os.system", 10**400, -(2**63), 2**64, _nested(300),
                               _nested(700)))),
    lambda inner: st.one_of(st.lists(inner, max_size=3), st.dictionaries(st.text(max_size=6), inner, max_size=3),
                            st.builds(lambda v: {"__class__": v}, st.text(max_size=12) | st.sampled_from((
                                "os.system", "torch.nn.ReLU", "torch.nn.Module", "sb3_smc.library.storage.Path",
                                "sb3_smcevil.X", "torch.nnx.X", "builtins.eval")))),
    max_leaves=6)


@given(data=st.data())
def test_damaged_manifest_bytes_load_or_give_a_library_error(pristine: Pristine, data: st.DataObject) -> None:
    """Bytes of the manifest flipped, inserted, deleted, truncated: the library or a LibraryError."""
    raw = (pristine.root / "manifest.json").read_bytes()
    with library_copy(pristine) as root:
        (root / "manifest.json").write_bytes(data.draw(damaged_bytes(raw), label="manifest"))
        _load(root)


@given(data=st.data())
def test_forged_manifests_with_recomputed_checksums_load_or_give_a_library_error(pristine: Pristine,
                                                                               data: st.DataObject) -> None:
    """Valid JSON, one field changed (or removed, or added), the checksums recomputed as write_manifest does: the
    edit reaches the checks behind the checksums (fields, records, versions and their conversions, children,
    layouts, the model file): the library or a LibraryError."""
    manifest = {k: v for k, v in pristine.manifest.items() if k != "manifest_sha256"}
    forged = data.draw(edited(manifest, JSON_VALUES), label="manifest")
    with library_copy(pristine) as root:
        assume(_seal(root / "manifest.json", forged))
        kind, result = _load(root)
        event(f"forged manifest: {kind} {type(result).__name__ if kind == 'error' else ''}")


@given(data=st.data())
def test_damaged_model_files_load_or_give_a_library_error(pristine: Pristine, data: st.DataObject) -> None:
    """The model file's bytes damaged, with or without its SHA-256 (and the manifest's checksums) recomputed: a
    stale checksum is a CorruptModelError; a recomputed one reaches the model file's checks."""
    size = int.from_bytes(pristine.model[:8], "little")
    damaged = data.draw(damaged_bytes(pristine.model, hot=8 + size), label="model")
    recompute = data.draw(st.booleans(), label="recompute")
    with library_copy(pristine) as root:
        entry = pristine.manifest["smcs"][pristine.name]
        if recompute:
            _with_model(root, copy.deepcopy(pristine.manifest), pristine.name, damaged)
        else:
            (root / entry["model"]).write_bytes(damaged)
        kind, err = _load(root)
        if not recompute and damaged != pristine.model:
            assert kind == "error" and isinstance(err, CorruptModelError)
    outcome(check_model_bytes, damaged, pristine.algo, "w", allowed=(CorruptModelError,), what="check_model_bytes")


def _model_file(metadata: Any, tensors: dict[str, Any]) -> bytes:
    return save_tensors(tensors, metadata={METADATA_KEY: json.dumps(metadata)})


@st.composite
def forged_tensors(draw: st.DrawFn, tensors: dict[str, Any]) -> dict[str, Any]:
    """The model's tensors with one changed: another dtype or shape, removed, or one added."""
    import torch

    out = dict(tensors)
    name = draw(st.sampled_from(sorted(out)))
    op = draw(st.sampled_from(("dtype", "shape", "delete", "add")))
    if op == "dtype":
        dtype = draw(st.sampled_from((torch.float16, torch.bfloat16, torch.float64, torch.int64, torch.int8,
                                      torch.bool, torch.uint8)))
        out[name] = out[name].to(dtype)
    elif op == "shape":
        out[name] = torch.zeros(draw(st.lists(st.integers(0, 4), max_size=3)))
    elif op == "delete":
        del out[name]
    else:
        out[draw(st.sampled_from(("policy/", "space/", "policy.optimizer/state/")))
            + draw(st.text(string.ascii_letters + "/.0", max_size=8))] = torch.zeros(2)
    return out


@pytest.mark.filterwarnings("ignore::UserWarning")  # SB3 warns about some forged settings it then accepts
@given(data=st.data())
def test_forged_model_files_give_a_model_or_a_corrupt_model_error(pristine: Pristine, data: st.DataObject) -> None:
    """Well-formed safetensors files with forged metadata (one field changed) or tensors (dtype, shape, names):
    decode_model builds the model or raises CorruptModelError; through a library whose checksums are recomputed,
    the library or a LibraryError."""
    metadata, tensors = pristine.metadata, load_tensors(pristine.model)
    if data.draw(st.booleans(), label="forge metadata"):
        metadata = data.draw(edited(metadata, JSON_VALUES), label="metadata")
    else:
        tensors = data.draw(forged_tensors(tensors), label="tensors")
    try:
        forged = _model_file(metadata, tensors)
    except (ValueError, TypeError):  # JSON or safetensors refuse to write it (the harness's limit)
        assume(False)
    kind, result = outcome(decode_model, forged, pristine.algo, "w", allowed=(CorruptModelError,),
                           what="decode_model")
    event(f"forged model file: {kind}" + (f" ({str(result).split(': ', 1)[-1][:40]})" if kind == "error" else ""))
    with library_copy(pristine) as root:
        _with_model(root, copy.deepcopy(pristine.manifest), pristine.name, forged)
        _load(root)


class _Payload:
    """Unpickled, it creates the file ``marker`` (a harmless stand-in for any code an attacker would run)."""

    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self) -> tuple[Any, ...]:
        return Path.touch, (self.marker,)


def _forged_archive(marker: Path) -> bytes:
    """An SB3 ``model.save``-style zip whose ``data`` member holds a serialized (pickled) payload."""
    serialized = base64.b64encode(pickle.dumps(_Payload(marker))).decode("ascii")
    data = {"policy_class": {":type:": "<class 'abc.ABCMeta'>", ":serialized:": serialized}}
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        archive.writestr("data", json.dumps(data))
        archive.writestr("policy.pth", b"")
        archive.writestr("_stable_baselines3_version", "2.0.0")
    return buffer.getvalue()


def test_a_forged_pickled_archive_is_not_loaded_without_trust(pristine: Pristine, tmp_path: Path) -> None:
    """An old-format (version 4) library whose model is a zip with a pickled payload, its checksums all recomputed
    as a forger would: SMCLibrary.load without trust raises UntrustedModelError and the payload never runs."""
    proof = tmp_path / "proof"
    pickle.loads(pickle.dumps(_Payload(proof)))  # the payload is live: unpickling it runs it
    assert proof.exists()
    marker = tmp_path / "marker"
    with library_copy(pristine) as root:
        manifest = copy.deepcopy(pristine.manifest)
        manifest["version"] = 4
        _with_model(root, manifest, pristine.name, _forged_archive(marker), suffix=".zip")
        kind, err = _load(root)
        assert kind == "error" and isinstance(err, UntrustedModelError), err
        kind, err = outcome(SMCLibrary.load, root, [pristine.name], allowed=(LibraryError,), what="load")
        assert kind == "error" and isinstance(err, UntrustedModelError), err  # asked for by name: the same
    assert not marker.exists()


_MARKER_MODULES = ("sb3_smc_fuzz_marker", "torch_nn_fuzz_marker", "fuzz_marker.torch.nn")
"""Modules that exist (written by the test) but lie outside SAFE_CLASS_MODULES, two of them named with a safe
module's name as a prefix (``sb3_smc`` + ``_fuzz_marker``)."""


@pytest.fixture(scope="module")
def marker_modules() -> Iterator[tuple[Path, Path]]:
    """``(folder on sys.path, marker)``: importing any of :data:`_MARKER_MODULES` creates the file ``marker``."""
    folder = Path(tempfile.mkdtemp(prefix="fuzz-modules-"))
    marker = folder / "imported"
    body = f"import pathlib\npathlib.Path({str(marker)!r}).touch()\nclass Policy:\n    pass\n"
    for module in _MARKER_MODULES:
        path = folder.joinpath(*module.split("."))
        path.parent.mkdir(parents=True, exist_ok=True)
        for parent in path.relative_to(folder).parents:
            if parent != Path("."):
                (folder / parent / "__init__.py").write_text(body, encoding="utf-8")
        path.with_suffix(".py").write_text(body, encoding="utf-8")
    sys.path.insert(0, str(folder))
    yield folder, marker
    sys.path.remove(str(folder))
    for module in list(sys.modules):
        if module.split(".")[0] in {m.split(".")[0] for m in _MARKER_MODULES}:
            del sys.modules[module]
    shutil.rmtree(folder, ignore_errors=True)


def _class_places(metadata: dict[str, Any]) -> list[tuple[Any, ...]]:
    """Where a class may stand in a model file's metadata: the policy class, the policy's keyword arguments (a
    feature extractor, an activation, an optimiser), any attribute, inside the optimiser's parameter groups."""
    return [("policy_class",), ("attributes", "policy_kwargs", "features_extractor_class"),
            ("attributes", "policy_kwargs", "activation_fn"), ("attributes", "policy_kwargs", "optimizer_class"),
            ("attributes", "policy_kwargs", "net_arch"), ("attributes", "gamma"), ("attributes", "learning_rate"),
            ("optimizer", "param_groups", 0, "betas")]


@given(data=st.data(), module=st.sampled_from((*_MARKER_MODULES, "os", "subprocess", "builtins", "shutil",
                                               "importlib", "pickle", "sb3_smcx", "torch.nnx", "torch")),
       attribute=st.sampled_from(("Policy", "system", "Popen", "eval", "rmtree", "import_module", "loads",
                                  "Module")))
def test_model_files_naming_classes_of_untrusted_modules_are_refused(
        pristine: Pristine, marker_modules: tuple[Path, Path], data: st.DataObject, module: str,
        attribute: str) -> None:
    """A safetensors model whose metadata names a class of a module outside SAFE_CLASS_MODULES (``os.system`` as
    the policy class or in policy_kwargs, a module named like a safe one, one that runs code when imported) is
    refused with CorruptModelError, by decode_model and by SMCLibrary.load (checksums recomputed), and the module is
    never imported."""
    _, marker = marker_modules
    assert not any(module == safe or module.startswith(safe + ".") for safe in SAFE_CLASS_MODULES)
    metadata = pristine.metadata
    place = data.draw(st.sampled_from(_class_places(metadata)), label="place")
    parent = metadata
    for key in place[:-1]:
        parent = parent[key]
    path = f"{module}.{attribute}"
    parent[place[-1]] = path if place == ("policy_class",) else {"__class__": path}
    forged = _model_file(metadata, load_tensors(pristine.model))
    kind, err = outcome(decode_model, forged, pristine.algo, "w", allowed=(CorruptModelError,), what="decode_model")
    assert kind == "error", f"a model naming {module}.{attribute} at {place} was built"
    assert "not from a module loaded without trust" in str(err)
    with library_copy(pristine) as root:
        _with_model(root, copy.deepcopy(pristine.manifest), pristine.name, forged)
        kind, err = _load(root)
        assert kind == "error" and isinstance(err, CorruptModelError)
    assert not marker.exists()
    assert module not in _MARKER_MODULES or module not in sys.modules


def test_the_marker_modules_would_run_if_imported(marker_modules: tuple[Path, Path]) -> None:
    """The modules of the test above are live: importing one runs its code (so "never imported" is checked)."""
    import importlib

    folder, _ = marker_modules
    marker = folder / "imported"
    if marker.exists():
        marker.unlink()
    module = importlib.import_module("torch_nn_fuzz_marker")
    try:
        assert marker.exists() and hasattr(module, "Policy")
    finally:
        del sys.modules["torch_nn_fuzz_marker"]
        marker.unlink()


def test_os_system_as_the_policy_class_or_in_policy_kwargs_is_refused(pristine: Pristine) -> None:
    """The brief's two cases, spelled out: CorruptModelError, naming the class and SAFE_CLASS_MODULES."""
    for place in (("policy_class",), ("attributes", "policy_kwargs", "features_extractor_class")):
        metadata = pristine.metadata
        parent = metadata
        for key in place[:-1]:
            parent = parent[key]
        parent[place[-1]] = "os.system" if len(place) == 1 else {"__class__": "os.system"}
        with pytest.raises(CorruptModelError, match=r"'os\.system' is not from a module loaded without trust"):
            decode_model(_model_file(metadata, load_tensors(pristine.model)), pristine.algo, "w")


def _manifest_text(text: bytes) -> Callable[[], Any]:
    def load() -> Any:
        with tempfile.TemporaryDirectory() as folder:
            (Path(folder) / "manifest.json").write_bytes(text)
            return SMCLibrary.load(folder)
    return load


def _model_header(header: bytes) -> Callable[[], Any]:
    return lambda: check_model_bytes(len(header).to_bytes(8, "little") + header, None, "w")


@functools.cache
def _pretrained_smc() -> Any:
    library = SMCLibrary.pretrained("search2-canon")
    return library[library.names[0]]


def _pretrained_model_file() -> tuple[bytes, str]:
    """The model file of the first pretrained SMC and its algorithm."""
    smc = _pretrained_smc()
    return storage.model_bytes(smc.model), type(smc.model).__name__


def _load_forged_manifest(change: Callable[[dict[str, Any]], None]) -> Callable[[], Any]:
    """A reproducer: a library of the first pretrained SMC whose manifest is changed by ``change(manifest)`` (its one
    entry is ``manifest["smcs"]["smc"]``), sealed again (written compact: the content is what counts), loaded."""
    def run() -> Any:
        with tempfile.TemporaryDirectory() as folder:
            root = SMCLibrary([replace(_pretrained_smc(), name="smc")]).save(Path(folder) / "lib")
            manifest = json.loads((root / "manifest.json").read_text(encoding="utf-8"))
            change(manifest)
            (root / "manifest.json").write_text(json.dumps(seal(manifest)), encoding="utf-8")
            return SMCLibrary.load(root)
    return run


def _set(path: tuple[Any, ...], value: Any) -> Callable[[Any], None]:
    def change(data: Any) -> None:
        for key in path[:-1]:
            data = data[key]
        data[path[-1]] = value
    return change


def _decode_forged(change: Callable[[dict[str, Any], dict[str, Any]], None]) -> Callable[[], Any]:
    """A reproducer: the first pretrained SMC's model file with ``change(metadata, tensors)`` applied, decoded."""
    def run() -> Any:
        data, algo = _pretrained_model_file()
        size = int.from_bytes(data[:8], "little")
        metadata = json.loads(json.loads(data[8:8 + size])["__metadata__"][METADATA_KEY])
        tensors = load_tensors(data)
        change(metadata, tensors)
        return decode_model(_model_file(metadata, tensors), algo, "w")
    return run


def _within_time_limit(fn: Callable[[], Any], seconds: float = 2) -> Any:
    with time_limit(getattr(fn, "__name__", "call"), seconds):
        return fn()


def _bfloat16(metadata: dict[str, Any], tensors: dict[str, Any]) -> None:
    import torch

    tensors["space/low"] = tensors["space/low"].to(torch.bfloat16)


FOUND += [
    KnownBug("manifest-deep-json", RecursionError, "sb3_smc/library/storage.py", "_parse_manifest",
             "a manifest of JSON nested 100,000 deep: json.loads raises RecursionError, not caught in "
             "_parse_manifest (only UnicodeDecodeError, JSONDecodeError)",
             _manifest_text(b"[" * 100_000 + b"]" * 100_000)),
    KnownBug("manifest-created-with-not-mapping", (TypeError, ValueError), "sb3_smc/library/storage.py",
             "checked_entries",
             "a manifest (its checksums recomputed) whose created_with is not a mapping: dict(created_with) raises "
             "TypeError ([1]) or ValueError ('ab') in checked_entries",
             every(_load_forged_manifest(_set(("created_with",), [1])),
                   _load_forged_manifest(_set(("created_with",), "ab")))),
    KnownBug("manifest-deep-hyperparameters", RecursionError, "sb3_smc/core/hyperparameters.py", "encode_value",
             "a manifest (its checksums recomputed) whose spec's hyperparameter gamma is a list nested 600 deep "
             "(well within json's limits): RecursionError from encode_value while the spec is read (parse_entry)",
             _load_forged_manifest(_set(("smcs", "smc", "spec", "hyperparameters", "gamma"), _nested(600)))),
    KnownBug("manifest-long-int", ValueError, "sb3_smc/library/storage.py", "_parse_manifest",
             "a manifest holding an integer of more than 4300 digits: json.loads raises a plain ValueError "
             "(int_max_str_digits), not a JSONDecodeError, in _parse_manifest",
             _manifest_text(b'{"version": ' + b"9" * 4301 + b"}"), "Exceeds the limit"),
    KnownBug("model-header-deep-json", RecursionError, "sb3_smc/library/model_file.py", "_header",
             "a model file whose safetensors header (or its sb3_smc metadata string) is JSON nested 100,000 deep: "
             "RecursionError from json.loads in _header",
             _model_header(b"[" * 100_000 + b"]" * 100_000)),
    KnownBug("model-header-long-int", ValueError, "sb3_smc/library/model_file.py", "_header",
             "a model file header (or metadata) holding an integer of more than 4300 digits: plain ValueError from "
             "json.loads in _header",
             _model_header(b'{"x": ' + b"9" * 4301 + b"}"), "Exceeds the limit"),
    KnownBug("model-bounds-unchecked", (TypeError, ValueError), "sb3_smc/library/model_file.py", "_space",
             "the observation bounds are not checked before gymnasium's Box is built: space/low (or space/high) "
             "stored as bfloat16 makes tensor.numpy() raise TypeError ('Got unsupported ScalarType BFloat16'); "
             "space/low above space/high (e.g. space/low = space/high + 1, or cast to uint8) makes Box raise "
             "ValueError ('low values must be less than or equal to high'), both in _space",
             every(_decode_forged(_bfloat16),
                   _decode_forged(lambda m, t: t.update({"space/low": t["space/high"] + 1})))),
    KnownBug("model-action-space-unchecked", (OverflowError, TypeError), "sb3_smc/library/model_file.py", "_space",
             "action_space.start is only checked with isinstance(start, int): 10**30 makes gymnasium's Discrete "
             "raise OverflowError, true makes it raise TypeError, in _space",
             every(_decode_forged(lambda m, t: m["action_space"].update(start=10**30)),
                   _decode_forged(lambda m, t: m["action_space"].update(start=True)))),
    KnownBug("model-policy-size-unbounded", TimeLimitExceeded, "sb3_smc/library/model_file.py", "decode_model",
             "the policy's size in a model file's settings is not bounded before the meta-device probe is built: "
             "policy_kwargs n_lstm_layers=20000 (or a net_arch of 20,000 layers) in a file of a few KB keeps "
             "decode_model (SMCLibrary.load) busy for minutes, the time growing with the square of the layers "
             "(5,000 layers: 5 s), before it finds that the weights do not fit",
             lambda: _within_time_limit(_decode_forged(
                 lambda m, t: m["attributes"]["policy_kwargs"].update(n_lstm_layers=20_000)))),
    KnownBug("model-deep-settings", RecursionError, "sb3_smc/core/hyperparameters.py", "decode_value",
             "a model file whose attributes (gamma, policy_kwargs, optimizer param_groups) hold a list nested 500 "
             "deep: RecursionError from decode_value, which decode_model catches only as SMCError",
             _decode_forged(lambda m, t: m["attributes"].update(gamma=_nested(500)))),
    KnownBug("model-counter-huge", OverflowError, "sb3_smc/library/model_file.py", "decode_model",
             "the float counter _current_progress_remaining an integer beyond float range (10**400): "
             "float() raises OverflowError in decode_model's check of the counters",
             _decode_forged(lambda m, t: m["attributes"].update(_current_progress_remaining=10**400))),
    KnownBug("model-policy-kwargs-not-mapping", (TypeError, ValueError), "sb3_smc/library/model_file.py",
             "decode_model",
             "attributes.policy_kwargs not a mapping: dict(...) raises TypeError ([1]) or ValueError ('ab') in "
             "decode_model before the policy is built",
             every(_decode_forged(lambda m, t: m["attributes"].update(policy_kwargs=[1])),
                   _decode_forged(lambda m, t: m["attributes"].update(policy_kwargs="ab")))),
]


# ================================================================================================================
# 5. What the fuzz tests found, one minimal reproducer each
# ================================================================================================================


@pytest.mark.parametrize("bug", [*(pytest.param(b, id=b.key) for b in FOUND),
                                 *(pytest.param(b, id=b.key, marks=pytest.mark.xfail(strict=True, reason=b.summary))
                                   for b in KNOWN_BUGS)])
def test_what_the_fuzz_tests_found_stays_fixed(bug: KnownBug) -> None:
    """The reproducer gives a result or the package's error, each of its triggers."""
    if bug.key == "model-policy-size-unbounded":
        _pretrained_model_file()  # the library's first load is not what the time limit measures
    for trigger in getattr(bug.reproduce, "triggers", (bug.reproduce,)):
        with contextlib.suppress(*PACKAGE_ERRORS):
            trigger()
