"""The concept language: parser, macros, predicates and semantics (docs/design.md, "The concept language")."""

from pixelworld_env.concepts.errors import (
    ArityError,
    ConceptError,
    ConceptSyntaxError,
    MacroExpansionError,
    MacroNameError,
    MacroRecursionError,
    NegatedMacroError,
    UndeclaredVariableError,
    UnknownPredicateError,
)
from pixelworld_env.concepts.evaluate import Concept, holds
from pixelworld_env.concepts.parser import Clause, Expression, expand, parse
from pixelworld_env.concepts.predicates import PREDICATES

__all__ = [
    "PREDICATES",
    "ArityError",
    "Clause",
    "Concept",
    "ConceptError",
    "ConceptSyntaxError",
    "Expression",
    "MacroExpansionError",
    "MacroNameError",
    "MacroRecursionError",
    "NegatedMacroError",
    "UndeclaredVariableError",
    "UnknownPredicateError",
    "expand",
    "holds",
    "parse",
]
