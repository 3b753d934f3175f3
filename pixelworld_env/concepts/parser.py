"""Parser of the concept language and macro expansion (docs/design.md, "Syntax" and "Macros").

Grammar (whitespace and line breaks are ignored)::

    expression := ("?" IDENT)* item ("&" item)*
    item       := clause | "~" clause | "~" "(" clause ("&" clause)* ")"
    clause     := IDENT "(" IDENT ("," IDENT)* ")"
    IDENT      := [A-Za-z0-9_-]+

``self`` is an implicit variable. A negated item is false for a binding only if all its clauses hold.
"""

from __future__ import annotations

import re
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from functools import lru_cache

from pixelworld_env.concepts.errors import (
    ArityError,
    ConceptSyntaxError,
    MacroExpansionError,
    MacroRecursionError,
    NegatedMacroError,
    UndeclaredVariableError,
)
from pixelworld_env.errors import PixelWorldTypeError

SELF = "self"
MAX_MACRO_DEPTH = 100
"""The most macros nested in one another (deeper is a :class:`MacroRecursionError`)."""
MAX_EXPANDED_CLAUSES = 1000
"""The most clauses an expression may have once its macros are expanded (the benchmark's largest has 25). Macros
that each use the next twice double at every level (18 doublings: 262,144 clauses), so :func:`expand` counts first and
refuses a larger expression before it expands anything."""

_TOKEN = re.compile(r"\s*(?:(?P<ident>[A-Za-z0-9_\-]+)|(?P<punct>[?(),~&]))")


@dataclass(frozen=True)
class Clause:
    """``name(args...)``; ``position`` is the offset of the name in the source text."""

    name: str
    args: tuple[str, ...]
    position: int = 0

    def __str__(self) -> str:
        return f"{self.name}({','.join(self.args)})"

    def renamed(self, mapping: Mapping[str, str]) -> Clause:
        return Clause(self.name, tuple(mapping.get(a, a) for a in self.args), self.position)


@dataclass(frozen=True)
class Expression:
    """A parsed expression: declared variables, positive clauses and negated groups."""

    variables: tuple[str, ...]
    positives: tuple[Clause, ...]
    negations: tuple[tuple[Clause, ...], ...]

    def __str__(self) -> str:
        parts = [f"?{v}" for v in self.variables]
        items = [str(c) for c in self.positives]
        for group in self.negations:
            items.append(f"~{group[0]}" if len(group) == 1 else "~(" + " & ".join(map(str, group)) + ")")
        return " ".join(parts + [" & ".join(items)])


def _tokenize(text: str) -> list[tuple[str, str, int]]:
    tokens: list[tuple[str, str, int]] = []
    pos = 0
    end = len(text.rstrip())  # trailing whitespace ends the text (checked once: slicing per token is quadratic)
    while pos < end:
        match = _TOKEN.match(text, pos)
        if match is None:
            start = len(text) - len(text[pos:].lstrip())
            raise ConceptSyntaxError(text, start, "an identifier or one of ? ( ) , ~ &", repr(text[start]))
        kind = "ident" if match.group("ident") else "punct"
        value = match.group(kind)
        tokens.append((kind, value, match.start(kind)))
        pos = match.end()
    tokens.append(("end", "", len(text)))
    return tokens


class _Parser:
    def __init__(self, text: str) -> None:
        self.text = text
        self.tokens = _tokenize(text)
        self.i = 0

    def _peek(self) -> tuple[str, str, int]:
        return self.tokens[self.i]

    def _describe(self, token: tuple[str, str, int]) -> str:
        kind, value, _ = token
        return "end of text" if kind == "end" else repr(value)

    def _expect(self, value: str | None, expected: str) -> str:
        kind, tok, pos = self._peek()
        ok = kind == "ident" if value is None else (kind == "punct" and tok == value)
        if not ok:
            raise ConceptSyntaxError(self.text, pos, expected, self._describe(self._peek()))
        self.i += 1
        return tok

    def _accept(self, value: str) -> bool:
        kind, tok, _ = self._peek()
        if kind == "punct" and tok == value:
            self.i += 1
            return True
        return False

    def parse(self) -> Expression:
        variables: list[str] = []
        while self._accept("?"):
            name = self._expect(None, "a variable name after '?'")
            if name == SELF:
                raise ConceptSyntaxError(self.text, self.tokens[self.i - 1][2], "a variable other than self",
                                         "'self' (self is implicit)")
            if name in variables:
                raise ConceptSyntaxError(self.text, self.tokens[self.i - 1][2], "a new variable name",
                                         f"{name!r}, declared twice")
            variables.append(name)
        positives: list[Clause] = []
        negations: list[tuple[Clause, ...]] = []
        while True:
            if self._accept("~"):
                if self._accept("("):
                    group = [self._clause()]
                    while self._accept("&"):
                        group.append(self._clause())
                    self._expect(")", "'&' or ')'")
                    negations.append(tuple(group))
                else:
                    negations.append((self._clause(),))
            else:
                positives.append(self._clause())
            if not self._accept("&"):
                break
        kind, _, pos = self._peek()
        if kind != "end":
            raise ConceptSyntaxError(self.text, pos, "'&' or end of text", self._describe(self._peek()))
        expression = Expression(tuple(variables), tuple(positives), tuple(negations))
        _check_declared(expression)
        return expression

    def _clause(self) -> Clause:
        kind, _, pos = self._peek()
        if kind != "ident":
            expected = "a relation name, '?' declarations must come first" if self._peek()[1] == "?" else \
                "a relation name"
            raise ConceptSyntaxError(self.text, pos, expected, self._describe(self._peek()))
        name = self._expect(None, "a relation name")
        self._expect("(", f"'(' after {name!r}")
        args = [self._expect(None, "an argument name")]
        while self._accept(","):
            args.append(self._expect(None, "an argument name"))
        self._expect(")", "',' or ')'")
        return Clause(name, tuple(args), pos)


def _check_declared(expression: Expression) -> None:
    declared = set(expression.variables) | {SELF}
    clauses = list(expression.positives) + [c for g in expression.negations for c in g]
    for clause in clauses:
        for arg in clause.args:
            if arg not in declared:
                raise UndeclaredVariableError(arg, str(clause))


def parse(text: str) -> Expression:
    """Parse concept text into an :class:`Expression` (macros not yet expanded)."""
    if not isinstance(text, str):
        raise PixelWorldTypeError(f"a concept expression must be a string, got {type(text).__name__}")
    return _parse_cached(text)


@lru_cache(maxsize=4096)
def _parse_cached(text: str) -> Expression:
    return _Parser(text).parse()


def expand(expression: Expression, macros: Mapping[str, str | Expression]) -> Expression:
    """Replace every macro call by the macro's clauses, recursively.

    The clauses are counted first (each macro once, so the count takes time linear in the macros' text): more than
    :data:`MAX_EXPANDED_CLAUSES` is a :class:`MacroExpansionError` naming the first macro over the limit, raised before
    anything is expanded.
    """
    sizes: dict[str, int] = {}
    size = sum(_expanded_size(clause, macros, (), sizes) for clause in _clauses(expression))
    if size > MAX_EXPANDED_CLAUSES:
        raise MacroExpansionError([], size, MAX_EXPANDED_CLAUSES)
    return _expand(expression, macros, ())


def _clauses(expression: Expression) -> Iterator[Clause]:
    """The positive clauses, then those of the negated groups."""
    yield from expression.positives
    for group in expression.negations:
        yield from group


def _expanded_size(clause: Clause, macros: Mapping[str, str | Expression], chain: tuple[str, ...],
                   sizes: dict[str, int]) -> int:
    """The number of clauses ``clause`` stands for once expanded (1 for a predicate); macros sized once, in
    ``sizes``."""
    if clause.name not in macros:
        return 1
    if clause.name not in sizes:
        chain = (*chain, clause.name)
        size = sum(_expanded_size(c, macros, chain, sizes) for c in _clauses(_macro(chain, macros)))
        if size > MAX_EXPANDED_CLAUSES:
            raise MacroExpansionError(list(chain), size, MAX_EXPANDED_CLAUSES)
        sizes[clause.name] = size
    return sizes[clause.name]


def _macro(chain: tuple[str, ...], macros: Mapping[str, str | Expression]) -> Expression:
    """The parsed macro ``chain[-1]``, reached through ``chain``; :class:`MacroRecursionError` if the chain cycles or
    is deeper than :data:`MAX_MACRO_DEPTH`."""
    if len(chain) > MAX_MACRO_DEPTH or chain[-1] in chain[:-1]:
        raise MacroRecursionError(list(chain))
    definition = macros[chain[-1]]
    return parse(definition) if isinstance(definition, str) else definition


def _expand(expression: Expression, macros: Mapping[str, str | Expression], chain: tuple[str, ...]) -> Expression:
    positives: list[Clause] = []
    negations: list[tuple[Clause, ...]] = []
    for clause in expression.positives:
        if clause.name in macros:
            body = _macro_body(clause, macros, chain)
            positives.extend(body.positives)
            negations.extend(body.negations)
        else:
            positives.append(clause)
    for group in expression.negations:
        spliced: list[Clause] = []
        for clause in group:
            if clause.name in macros:
                body = _macro_body(clause, macros, chain)
                if body.negations:
                    raise NegatedMacroError(clause.name)
                spliced.extend(body.positives)
            else:
                spliced.append(clause)
        negations.append(tuple(spliced))
    return Expression(expression.variables, tuple(positives), tuple(negations))


def _macro_body(clause: Clause, macros: Mapping[str, str | Expression], chain: tuple[str, ...]) -> Expression:
    chain = (*chain, clause.name)
    macro = _macro(chain, macros)
    if len(clause.args) != len(macro.variables):
        raise ArityError(clause.name, len(macro.variables), len(clause.args), kind="macro")
    mapping = dict(zip(macro.variables, clause.args, strict=True))
    mapping[SELF] = SELF
    body = _expand(macro, macros, chain)
    return Expression(
        (),
        tuple(c.renamed(mapping) for c in body.positives),
        tuple(tuple(c.renamed(mapping) for c in g) for g in body.negations),
    )
