"""Exceptions of the concept language; all are ``ValueError``s that name the offending item."""

from __future__ import annotations

from pixelworld_env.errors import PixelWorldError


class ConceptError(PixelWorldError):
    """Base class of every concept-language error."""


class ConceptSyntaxError(ConceptError):
    """The text does not follow the grammar; ``position`` is the 0-based character offset."""

    def __init__(self, text: str, position: int, expected: str, found: str) -> None:
        self.text, self.position, self.expected, self.found = text, position, expected, found
        pointer = " " * position + "^"
        super().__init__(
            f"syntax error at position {position}: expected {expected}, found {found}\n  {text}\n  {pointer}"
        )


class UnknownPredicateError(ConceptError):
    """A relation name is neither a predicate of the vocabulary nor a macro."""

    def __init__(self, name: str, suggestions: list[str]) -> None:
        self.name = name
        hint = f"; did you mean {', '.join(suggestions)}?" if suggestions else ""
        super().__init__(f"unknown predicate or macro {name!r}{hint}")


class ArityError(ConceptError):
    """A predicate or macro is called with the wrong number of arguments."""

    def __init__(self, name: str, expected: int, got: int, kind: str = "predicate") -> None:
        self.name, self.expected, self.got = name, expected, got
        super().__init__(f"{kind} {name!r} takes {expected} argument(s), got {got}")


class UndeclaredVariableError(ConceptError):
    """An argument is neither ``self`` nor declared with ``?``."""

    def __init__(self, variable: str, clause: str) -> None:
        self.variable = variable
        super().__init__(f"variable {variable!r} in {clause} is not declared (declare it with ?{variable})")


class NegatedMacroError(ConceptError):
    """A macro used inside a negation itself contains a negation."""

    def __init__(self, name: str) -> None:
        self.name = name
        super().__init__(f"macro {name!r} is used inside a negation but itself contains a negation")


class MacroRecursionError(ConceptError):
    """Macros reference each other in a cycle (or more than 100 levels deep)."""

    def __init__(self, chain: list[str]) -> None:
        self.chain = chain
        super().__init__(f"macro expansion does not terminate: {' -> '.join(chain)}")


class MacroExpansionError(ConceptError):
    """An expression would have more clauses than ``limit`` once its macros are expanded (macros that use each other
    several times grow exponentially); ``chain`` is the path of macros to the one named, empty for the expression."""

    def __init__(self, chain: list[str], size: int, limit: int) -> None:
        self.chain, self.size, self.limit = chain, size, limit
        what = "the expression" if not chain else f"macro {chain[-1]!r}" + (
            f" (reached through {' -> '.join(chain)})" if len(chain) > 1 else "")
        super().__init__(f"{what} expands to {size:,} clauses, more than the limit of {limit:,} "
                         "(pixelworld_env.concepts.parser.MAX_EXPANDED_CLAUSES); a macro that uses another several "
                         "times multiplies its clauses")


class MacroNameError(ConceptError):
    """A macro is named like a built-in predicate (it would shadow it)."""

    def __init__(self, name: str) -> None:
        self.name = name
        super().__init__(f"macro {name!r} has the name of a built-in predicate (it would shadow the predicate); "
                         "rename the macro")
