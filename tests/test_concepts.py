"""Concept language: predicate truth on hand-drawn scenes, semantics and errors."""

from __future__ import annotations

import pytest

from pixelworld_env import (
    ArityError,
    Concept,
    ConceptSyntaxError,
    NegatedMacroError,
    Scene,
    UndeclaredVariableError,
    UnknownPredicateError,
    holds,
)
from pixelworld_env.concepts import PREDICATES, MacroNameError, MacroRecursionError, parse

CONTAINER = """
#########
#.......#
#.a...a.#
#.a.S.a.#
#.aaaaa.#
#=======#
#.......#
#########
"""
KINDS = {"a": "container"}


def scene(text: str, kinds: dict[str, str] | None = None) -> Scene:
    return Scene.from_ascii(text, kinds if kinds is not None else KINDS)


def moved(text: str, row: int, col: int) -> str:
    """The same drawing with the self moved to (row, col)."""
    grid = [list(line) for line in text.strip().splitlines()]
    for line in grid:
        for j, ch in enumerate(line):
            if ch == "S":
                line[j] = "."
    grid[row][col] = "S"
    return "\n".join("".join(line) for line in grid)


@pytest.mark.parametrize(
    ("cell", "inside", "supported"),
    [((3, 4), True, True), ((2, 4), True, False), ((1, 4), False, False), ((3, 7), False, False)],
)
def test_inside_regions_of_a_drawn_container(cell: tuple[int, int], inside: bool, supported: bool) -> None:
    s = scene(moved(CONTAINER, *cell))
    assert holds("?x container(x) & inside(self,x)", s) is inside
    assert holds("?x container(x) & inside_supported(self,x)", s) is supported


def test_floor_on_top_and_above() -> None:
    s = scene(CONTAINER)
    assert holds("?f ?x floor(f) & container(x) & on_top(x,f)", s)
    assert not holds("?f floor(f) & on_top(self,f)", s)
    assert holds("?f floor(f) & above(self,f)", s)
    assert holds("?f floor(f) & on_top(self,f)", scene(moved(CONTAINER, 4, 7)))
    # floor(f) needs the floor's top on row height - 3
    shifted = CONTAINER.replace("#=======#\n#.......#", "#.......#\n#=======#")
    assert not holds("?f floor(f)", scene(shifted))


@pytest.mark.parametrize(
    ("cell", "touches", "adjacent", "near"),
    [((1, 2), True, True, True), ((1, 1), True, False, True), ((2, 4), False, False, True),
     ((6, 7), False, False, False)],
)
def test_distance_predicates(cell: tuple[int, int], touches: bool, adjacent: bool, near: bool) -> None:
    s = scene(moved(CONTAINER, *cell))
    assert holds("?x container(x) & touches(self,x)", s) is touches
    assert holds("?x container(x) & adjacent(self,x)", s) is adjacent
    assert holds("?x container(x) & near(self,x)", s) is near


def test_left_right_of_and_directional() -> None:
    left = scene(moved(CONTAINER, 3, 1))
    assert holds("?x container(x) & left_of(self,x)", left)
    assert holds("?x container(x) & dir_left_of(self,x)", left)
    assert holds("?x container(x) & on_left(self,x)", left)
    assert not holds("?x container(x) & right_of(self,x)", left)
    inner = scene(CONTAINER)
    # inside the bbox: not left_of, but left of the right wall in shared rows only if left of every cell
    assert not holds("?x container(x) & left_of(self,x)", inner)
    assert not holds("?x container(x) & dir_left_of(self,x)", inner)
    above = scene(moved(CONTAINER, 1, 3))
    assert not holds("?x container(x) & dir_left_of(self,x)", above)  # no shared rows
    assert holds("?x container(x) & dir_above(self,x)", above)


def test_dir_above_quirk() -> None:
    """Inside a container's bbox, above its floor: correct dir_above is true, the AAAI-18 quirk says false."""
    s = scene(CONTAINER)
    assert Concept("?x container(x) & dir_above(self,x)").holds(s)
    assert not Concept("?x container(x) & dir_above(self,x)", dir_above_quirk=True).holds(s)


def test_h_between() -> None:
    text = """
    ##########
    #........#
    #.a.S..b.#
    #========#
    #........#
    ##########
    """
    s = scene(text, {"a": "small_blob", "b": "small_blob"})
    assert holds("?x ?y small_blob(x) & small_blob(y) & h_between(self,x,y)", s)
    assert not holds("?x ?y small_blob(x) & small_blob(y) & h_between(x,self,y)", s)


def test_variables_bind_distinct_non_frame_objects() -> None:
    s = scene(CONTAINER)
    assert holds("?x container(x)", s)
    assert not holds("?x ?y container(x) & container(y)", s)  # only one container
    assert not holds("?x red(x)", s)  # x never binds the self
    # the frame (purple) is never a candidate: only the floor and the container remain
    assert not holds("?x ?y ?z white(x) & blue(y) & touches(z,y)", s)


def test_negation_is_per_binding() -> None:
    text = """
    ##########
    #........#
    #.aS....b#
    #========#
    #........#
    ##########
    """
    s = scene(text, {"a": "small_blob", "b": "small_blob"})
    assert holds("?x small_blob(x) & ~touches(self,x)", s)  # b does not touch, a does
    assert holds("?x small_blob(x) & touches(self,x)", s)
    assert not holds("?x small_blob(x) & ~(near(self,x) & small_blob(x)) & ~(far(self,x) & small_blob(x))", s)


def test_macros_expand_positionally() -> None:
    macros = {
        "on-floor": "?f ?x floor(f) & on_top(x,f)",
        "container-on-floor": "?f ?x on-floor(f,x) & container(x)",
        "self-in": "?x container(x) & inside_supported(self,x)",
    }
    s = scene(CONTAINER)
    assert holds("?f ?x container-on-floor(f,x) & self-in(x)", s, macros)
    assert not holds("?f ?x container-on-floor(f,x) & ~self-in(x)", s, macros)


@pytest.mark.parametrize(
    ("text", "position", "expected"),
    [
        ("?x container(x) &", 17, "a relation name"),
        ("?x container(x", 14, "',' or ')'"),
        ("?x container x)", 13, "'(' after 'container'"),
        ("?x container(x) touches(self,x)", 16, "'&' or end of text"),
        ("?x ~(container(x) & touches(self,x)", 35, "'&' or ')'"),
        ("container(self) ?x", 16, "'&' or end of text"),
        ("?x container(x) $ blob(x)", 16, "an identifier or one of"),
    ],
)
def test_syntax_errors_report_position_and_expectation(text: str, position: int, expected: str) -> None:
    with pytest.raises(ConceptSyntaxError) as info:
        parse(text)
    assert info.value.position == position
    assert expected in str(info.value)


def test_named_errors() -> None:
    s = scene(CONTAINER)
    with pytest.raises(UnknownPredicateError, match="'containr'.*did you mean container"):
        holds("?x containr(x)", s)
    with pytest.raises(ArityError, match="predicate 'touches' takes 2 argument"):
        holds("touches(self)", s)
    with pytest.raises(ArityError, match="macro 'm' takes 2 argument"):
        holds("m(self)", s, {"m": "?a ?b touches(a,b)"})
    with pytest.raises(UndeclaredVariableError, match="variable 'x' in container\\(x\\)"):
        holds("container(x)", s)
    with pytest.raises(NegatedMacroError, match="'m'"):
        holds("?x ~m(x)", s, {"m": "?a blob(a) & ~touches(self,a)"})
    with pytest.raises(MacroRecursionError, match="m -> n -> m"):
        holds("?x m(x)", s, {"m": "?a n(a)", "n": "?a m(a)"})
    with pytest.raises(ConceptSyntaxError, match="self is implicit"):
        parse("?self blob(self)")


def test_catalog_macros_are_the_default() -> None:
    s = scene(CONTAINER)
    assert holds("?f ?x container-on-floor(f,x)", s)
    assert holds("?x self-in-container(x)", s)
    with pytest.raises(UnknownPredicateError, match="container-on-floor"):
        holds("?f ?x container-on-floor(f,x)", s, macros={})


@pytest.mark.parametrize(("call", "error", "message"), [
    (lambda scene: holds(None, scene), TypeError, "a concept is an expression string .*got None"),
    (lambda scene: holds(b"?x container(x)", scene), TypeError, "got b'\\?x container\\(x\\)' \\(bytes\\)"),
    (lambda scene: holds("?x container(x)", None), TypeError, "holds needs a Scene, got None"),
    (lambda scene: Scene.from_ascii(123), TypeError, "needs the scene drawn as a string, got int"),
    (lambda scene: Concept("?x container(x)", {"m": 3}), TypeError, "macro 'm' must be an expression string, got 3"),
    (lambda scene: Concept("?x container(x)", ["m"]), TypeError, "macros must map names to expression strings"),
    (lambda scene: Concept("?x ?x container(x)", {}), ConceptSyntaxError, "'x', declared twice"),
    (lambda scene: Concept("?x container(x)", {"container": "?y hline(y)"}), MacroNameError,
     "macro 'container' has the name of a built-in predicate"),
])
def test_bad_arguments_raise_clear_errors(call, error, message):
    scene = Scene.from_ascii("#####\n#.S.#\n#####\n")
    with pytest.raises(error, match=message):
        call(scene)


def _random_scene(rng, n_objects: int) -> Scene:
    letters = [chr(x) for x in range(ord("a"), ord("z") + 1)] + [chr(x) for x in range(ord("A"), ord("Z") + 1)
                                                                  if chr(x) != "S"]
    cells = rng.sample([(r, c) for r in range(1, 9) for c in range(1, 20)], n_objects + 1)
    grid = [["."] * 21 for _ in range(10)]
    for k, (r, c) in enumerate(cells):
        grid[r][c] = "S" if k == 0 else letters[k - 1]
    return Scene.from_ascii("#" * 23 + "\n" + "\n".join("#" + "".join(row) + "#" for row in grid) + "\n" + "#" * 23)


def test_forward_checking_agrees_with_the_plain_search():
    """Random 3-5-variable concepts over random scenes: both searches give the same answer."""
    import random

    rng = random.Random(7)
    binary = ["left_of", "right_of", "above", "below", "touches", "adjacent", "near", "far", "left_aligned",
              "top_aligned"]
    assert all(PREDICATES[name].arity == 2 for name in binary)
    agree = {True: 0, False: 0}
    for _ in range(300):
        scene = _random_scene(rng, rng.randint(3, 14))
        names = ["a", "b", "c", "d", "e"][: rng.randint(3, 5)]
        clauses = []
        for _ in range(rng.randint(2, 6)):
            x, y = rng.sample(["self", *names], 2)
            clause = f"{rng.choice(binary)}({x},{y})"
            clauses.append(f"~{clause}" if rng.random() < 0.2 else clause)
        clauses += [f"blob({v})" for v in names if rng.random() < 0.3]
        text = " ".join(f"?{v}" for v in names) + " " + " & ".join(clauses)
        concept = Concept(text, {})
        evaluator = concept.self_evaluator(scene.objects, scene.floor_row)
        me = next(o for o in scene.objects if o.is_self)
        evaluator.domains[0] = [me]
        plain = evaluator.satisfiable and concept._search(0, evaluator.domains, [], evaluator.ctx)
        forward = evaluator.satisfiable and concept._forward(evaluator.domains, [None] * len(evaluator.domains),
                                                             set(), evaluator.ctx)
        assert plain == forward, text
        assert concept.holds(scene) == plain
        agree[plain] += 1
    assert agree[True] > 30 and agree[False] > 30  # both answers were exercised


def test_five_variables_over_fifty_objects():
    """A chain of relations that is false only at its last clause (benchmarks/bench_concepts.py times it)."""
    import random

    scene = _random_scene(random.Random(0), 50)
    assert len([o for o in scene.objects if not o.is_frame]) == 51
    concept = Concept("?a ?b ?c ?d ?e left_of(a,b) & left_of(b,c) & left_of(c,d) & left_of(d,e) & touches(e,a)",
                      {})
    assert concept.holds(scene) is False
    assert Concept("?a ?b ?c ?d ?e left_of(a,b) & left_of(b,c) & left_of(c,d) & left_of(d,e)", {}).holds(scene)
