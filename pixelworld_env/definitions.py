"""Reader for concept, generator and dataset definition files in the original AAAI-18 YAML format.

A file may hold the sections ``concepts:``, ``generators:`` (name -> ``{name, desc, logic}``) and
``datasets:`` (name -> ``[concept, [generators...], {settings}]``), and include other files with
``__include__: [paths relative to the file]``. Names are the dictionary keys (the ``name:`` fields are
ignored, spec §7 item 22). Concepts and generators together form the macro table (spec §3.2).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml


class DefinitionError(ValueError):
    """A definition file is malformed; the message names the file, the line and the entry."""


@dataclass(frozen=True)
class Definition:
    """A named concept or generator expression and where it was defined."""

    key: str
    logic: str
    desc: str = ""
    source: str = ""
    line: int = 0


@dataclass(frozen=True)
class DatasetDefinition:
    """A dataset: a concept, the generators that produce its environments and extra settings."""

    name: str
    concept: str
    generators: tuple[str, ...]
    settings: dict[str, Any] = field(default_factory=dict)
    source: str = ""
    line: int = 0

    @property
    def kind(self) -> str:
        """``classification`` for ``cl_`` names, ``bring-about`` for ``ba_`` names."""
        return "bring-about" if self.name.startswith("ba_") else "classification"


@dataclass
class DefinitionSet:
    """Everything read from a set of definition files."""

    concepts: dict[str, Definition] = field(default_factory=dict)
    generators: dict[str, Definition] = field(default_factory=dict)
    datasets: dict[str, DatasetDefinition] = field(default_factory=dict)
    files: list[str] = field(default_factory=list)

    @property
    def macros(self) -> dict[str, str]:
        """The merged macro table: every concept and generator key -> its logic."""
        table = {key: d.logic for key, d in self.concepts.items()}
        table.update({key: d.logic for key, d in self.generators.items()})
        return table


def _where(path: Path, node: yaml.Node) -> str:
    return f"{path}, line {node.start_mark.line + 1}"


def _load_yaml(path: Path) -> tuple[Any, yaml.Node | None]:
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise DefinitionError(f"cannot read definition file {path}: {exc.strerror}") from None
    loader = yaml.SafeLoader(text)
    try:
        node = loader.get_single_node()
        data = loader.construct_document(node) if node is not None else None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f", line {mark.line + 1}" if mark else ""
        raise DefinitionError(f"{path}{where}: invalid YAML: {getattr(exc, 'problem', exc)}") from None
    finally:
        loader.dispose()
    return data, node


def _entries(section_node: yaml.Node) -> dict[str, yaml.Node]:
    """Key -> key node of a mapping node (for line numbers)."""
    if not isinstance(section_node, yaml.MappingNode):
        return {}
    return {k.value: k for k, _ in section_node.value if isinstance(k, yaml.ScalarNode)}


def load_definitions(paths: str | Path | Iterable[str | Path]) -> DefinitionSet:
    """Read definition files (following ``__include__``, each file once) into a :class:`DefinitionSet`."""
    result = DefinitionSet()
    todo = [Path(paths)] if isinstance(paths, str | Path) else [Path(p) for p in paths]
    for path in todo:
        _read_file(path.resolve(), result, set())
    for name, dataset in result.datasets.items():
        where = f"{dataset.source}, line {dataset.line}"
        if dataset.concept not in result.concepts:
            raise DefinitionError(f"{where}: dataset {name!r} names unknown concept {dataset.concept!r}")
        for generator in dataset.generators:
            if generator not in result.generators:
                raise DefinitionError(f"{where}: dataset {name!r} names unknown generator {generator!r}")
    clash = sorted(set(result.concepts) & set(result.generators))
    if clash:
        raise DefinitionError(f"names defined both as concept and as generator: {', '.join(clash)}")
    return result


def _read_file(path: Path, result: DefinitionSet, stack: set[Path]) -> None:
    if str(path) in result.files:
        return
    if path in stack:
        raise DefinitionError(f"{path}: circular __include__")
    data, node = _load_yaml(path)
    result.files.append(str(path))
    if data is None:
        return
    if not isinstance(data, dict):
        raise DefinitionError(f"{path}: expected a mapping of sections at the top level")
    sections = {k.value: v for k, v in node.value} if isinstance(node, yaml.MappingNode) else {}
    includes = data.get("__include__") or []
    if isinstance(includes, str):
        includes = [includes]
    for include in includes:
        _read_file((path.parent / include).resolve(), result, stack | {path})
    for section in ("concepts", "generators"):
        target = getattr(result, section)
        lines = _entries(sections.get(section))
        for key, entry in (data.get(section) or {}).items():
            key_node = lines.get(key)
            where = _where(path, key_node) if key_node else str(path)
            if not isinstance(entry, dict) or not isinstance(entry.get("logic"), str):
                raise DefinitionError(f"{where}: {section[:-1]} {key!r} needs a 'logic' string")
            target[key] = Definition(key=key, logic=entry["logic"], desc=str(entry.get("desc", "")),
                                     source=str(path), line=key_node.start_mark.line + 1 if key_node else 0)
    lines = _entries(sections.get("datasets"))
    for name, entry in (data.get("datasets") or {}).items():
        key_node = lines.get(name)
        where = _where(path, key_node) if key_node else str(path)
        if not (isinstance(entry, list) and 2 <= len(entry) <= 3 and isinstance(entry[0], str)
                and isinstance(entry[1], list) and all(isinstance(g, str) for g in entry[1])):
            raise DefinitionError(
                f"{where}: dataset {name!r} must be [concept, [generators...]] or [concept, [generators...], "
                "{settings}]"
            )
        settings = entry[2] if len(entry) == 3 and entry[2] else {}
        if not isinstance(settings, dict):
            raise DefinitionError(f"{where}: dataset {name!r}: settings must be a mapping")
        result.datasets[name] = DatasetDefinition(
            name=name, concept=entry[0], generators=tuple(entry[1]), settings=dict(settings), source=str(path),
            line=key_node.start_mark.line + 1 if key_node else 0,
        )
