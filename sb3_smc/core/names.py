"""What a name is (torch-free): the one rule for the names of SMCs, curriculum nodes, curricula and runs, which become
parts of paths (``DIR/tensorboard/<name>_1``, ``DIR/failed/<name>.txt``) and keys of a library's manifest.

A name is 1 to :data:`MAX_NAME_LENGTH` characters of any script, in one or more parts joined by ``/`` (a namespace,
as the paper's experiments name their nodes: ``con2-ba-canon-noprim/ba_self-in-container_from_on-floor_canon``),
each part non-empty and not starting with ``.`` (so never ``.`` or ``..``, nor a hidden file), with no ``\\``, no
NUL or other control character, and not starting or ending with white space. So a name joined to a folder stays
inside it. :func:`check_name` applies it where a name enters: a curriculum file, an SMC, a manifest.
"""

from __future__ import annotations

import unicodedata

from sb3_smc.errors import SMCError, SMCTypeError

__all__ = ["MAX_NAME_LENGTH", "check_name", "name_problem"]

MAX_NAME_LENGTH = 200
"""The most characters a name has (the longest of the package's SMC names has 62)."""


def name_problem(name: object) -> str | None:
    """What is wrong with ``name`` as a name (``None``: nothing)."""
    if not isinstance(name, str):
        return f"a name is a string, not a {type(name).__name__}"
    if not name:
        return "a name cannot be empty"
    if len(name) > MAX_NAME_LENGTH:
        return f"{len(name)} characters, more than a name may have ({MAX_NAME_LENGTH})"
    bad = next((c for c in name if c == "\\" or unicodedata.category(c) in ("Cc", "Cs")), None)
    if bad is not None:
        return f"it holds {bad!r} (a name may not hold a backslash or a control character)"
    for part in name.split("/"):
        if not part:
            return "it has an empty part (a '/' at its start or end, or '//')"
        if part.startswith("."):
            return f"its part {part!r} starts with '.' (a part of a name is never '.', '..' or a hidden file)"
    if name != name.strip():
        return "it starts or ends with white space"
    return None


def check_name(name: object, what: str) -> str:
    """``name`` if it is a name (see the module's docstring); otherwise :class:`~sb3_smc.errors.SMCError` (a
    non-string: :class:`~sb3_smc.errors.SMCTypeError`) saying which ``what`` (``"SMC name"``, ``"node name"`` ...)
    and why."""
    problem = name_problem(name)
    if problem is not None:
        error = SMCTypeError if not isinstance(name, str) else SMCError
        raise error(f"{what} {name!r} is not a name: {problem}")
    assert isinstance(name, str)
    return name
