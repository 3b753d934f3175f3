"""YAML from files that may not be trusted, read safely: :func:`read_yaml_file` (the text), :func:`safe_yaml_load`
(the data) and :func:`safe_yaml_compose` (the node tree, for line numbers), the one place pixelworld_env reads YAML
(the definition and experiment files; sb3_smc's curricula too).

Besides PyYAML's safe loader (plain data only, no Python objects), three rules, checked before any node is built:

* at most :data:`MAX_YAML_SIZE` characters (a file: bytes, read no further);
* no aliases (``*name``): an alias repeats the node of its anchor, and a few lines of aliases of aliases ("billion
  laughs") stand for billions of nodes to whoever walks the data; no file of the benchmark uses one;
* at most :data:`MAX_YAML_DEPTH` nested collections (the readers walk the data recursively).

Every error is a :class:`YAMLInputError` naming the text (``where``) and the line.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from pixelworld_env.errors import PixelWorldError

__all__ = ["MAX_YAML_DEPTH", "MAX_YAML_SIZE", "YAMLInputError", "construct_node", "read_yaml_file", "safe_yaml_compose",
           "safe_yaml_load"]

MAX_YAML_DEPTH = 100
"""The most collections (mappings, lists) nested in one another in a YAML text; the benchmark's files nest 6 deep."""
MAX_YAML_SIZE = 10 * 2**20
"""The longest YAML text read: 10 MiB (characters of a text, bytes of a file); the benchmark's files have at most
27 KB."""

#: The libyaml parser when PyYAML has it (same results, several times faster), else the pure-Python one.
_Loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


class YAMLInputError(PixelWorldError):
    """A YAML text that cannot be read safely: too long, not UTF-8, malformed, an alias, nested too deep. ``where``
    names the text (a file), ``line`` is 1-based (0: unknown), ``problem`` says what is wrong."""

    def __init__(self, where: str, line: int, problem: str) -> None:
        self.where, self.line, self.problem = where, line, problem
        super().__init__(f"{where}, line {line}: {problem}" if line else f"{where}: {problem}")


def _invalid(exc: yaml.YAMLError, where: str) -> YAMLInputError:
    """PyYAML's error as a :class:`YAMLInputError`: its line and what it says."""
    mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
    said = ": ".join(part for part in (getattr(exc, "context", None), getattr(exc, "problem", None)) if part)
    return YAMLInputError(where, mark.line + 1 if mark is not None else 0, f"invalid YAML: {said or exc}")


def read_yaml_file(path: Path) -> str:
    """The UTF-8 text of the file ``path``, read no further than :data:`MAX_YAML_SIZE` bytes; :class:`YAMLInputError`
    if it is longer or not UTF-8 text, ``OSError`` if it cannot be read."""
    with path.open("rb") as handle:
        data = handle.read(MAX_YAML_SIZE + 1)
    if len(data) > MAX_YAML_SIZE:
        raise YAMLInputError(str(path), 0, f"more than {MAX_YAML_SIZE:,} bytes (the limit "
                                           "pixelworld_env.yaml_loading.MAX_YAML_SIZE)")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise YAMLInputError(str(path), 0, f"not UTF-8 text (byte {data[exc.start]:#04x} at position {exc.start}); "
                                           "a YAML file is UTF-8 text") from None


def _check_events(text: str, where: str) -> None:
    """Refuse an alias or collections nested deeper than :data:`MAX_YAML_DEPTH` (the first one, with its line)."""
    loader = _Loader(text)
    depth = 0
    try:
        while loader.check_event():
            event = loader.get_event()
            if isinstance(event, yaml.AliasEvent):
                raise YAMLInputError(where, event.start_mark.line + 1,
                                     f"YAML alias *{event.anchor} refused: aliases are not supported (they can "
                                     "make a short file stand for a huge one); write the value out")
            if isinstance(event, yaml.CollectionStartEvent):
                depth += 1
                if depth > MAX_YAML_DEPTH:
                    raise YAMLInputError(where, event.start_mark.line + 1,
                                         f"more than {MAX_YAML_DEPTH} nested mappings or lists (the limit "
                                         "pixelworld_env.yaml_loading.MAX_YAML_DEPTH)")
            elif isinstance(event, yaml.CollectionEndEvent):
                depth -= 1
    except yaml.YAMLError as exc:
        raise _invalid(exc, where) from None
    finally:
        loader.dispose()


def safe_yaml_compose(text: str, where: str) -> yaml.Node | None:
    """The node tree of the one YAML document ``text`` (``None`` if empty), after the checks of this module;
    :class:`YAMLInputError` naming ``where`` and the line otherwise."""
    if len(text) > MAX_YAML_SIZE:
        raise YAMLInputError(where, 0, f"{len(text):,} characters, more than {MAX_YAML_SIZE:,} (the limit "
                                       "pixelworld_env.yaml_loading.MAX_YAML_SIZE)")
    _check_events(text, where)
    loader = _Loader(text)
    try:
        return loader.get_single_node()
    except yaml.YAMLError as exc:
        raise _invalid(exc, where) from None
    finally:
        loader.dispose()


def construct_node(node: yaml.Node, where: str) -> Any:
    """The plain Python data of a node of :func:`safe_yaml_compose`'s tree (safe constructors only)."""
    try:
        return yaml.constructor.SafeConstructor().construct_document(node)
    except yaml.YAMLError as exc:
        raise _invalid(exc, where) from None
    except (ValueError, KeyError, AttributeError, TypeError, OverflowError) as exc:  # a scalar its tag cannot read
        line = node.start_mark.line + 1 if node.start_mark is not None else 0
        raise YAMLInputError(where, line, f"invalid YAML value ({type(exc).__name__}: {exc})") from None


def safe_yaml_load(text: str, where: str) -> Any:
    """The data of the one YAML document ``text`` (``None`` if empty), read as :func:`safe_yaml_compose` reads it."""
    node = safe_yaml_compose(text, where)
    return None if node is None else construct_node(node, where)
