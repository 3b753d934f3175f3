"""Reader for the definition and experiment files of the original AAAI-18 release (YAML).

Definition files (:func:`load_definitions`) may hold the sections

* ``concepts:`` and ``generators:`` -- name -> ``{name, desc, logic}``;
* ``datasets:`` -- name -> ``[concept, [generators...], {settings}]``, the settings ``allow_targets`` and
  ``allow_pushable``, each ``true`` or ``false`` (a YAML bool, never a string);
* ``curriculum:`` -- entry name -> ``[dataset, [lower-level experiments...]]`` (``*.curriculum`` files), where a
  lower-level experiment is an output path ``out/aaai18/<group>/<dataset>/<variant>`` and the list may instead
  be a reference ``+@list_name`` to a named list;
* named lists -- any other top-level key whose value is a list of strings (the ``*.include`` files, e.g.
  ``canonical_containment_curriculum: [paths...]``);
* ``__gen_<anything>:`` blocks that call ``generate_pattern`` with ``name: curriculum`` (the canonical
  curriculum files): their ``kwargs.cfg`` mapping is read as a ``curriculum:`` section, with ``+@name``
  resolved through ``kwargs.bindings`` (``local: +@global``) or directly against the named lists;

and include other files with ``__include__: [paths relative to the file]`` (each file is read once). Names are
the dictionary keys (the ``name:`` fields are ignored: docs/design.md, choices). Concepts and generators together
form the macro table (docs/design.md, "Macros"). A ``+@name`` reference must name a list defined in the curriculum
file itself or in a file it includes (directly or not). Curriculum entries are grouped by the stem of the file that
defines them (:attr:`DefinitionSet.curricula`).

The experiment files that use these definitions are read by :mod:`pixelworld_env.generation.experiment_files`.

Every error is a :class:`DefinitionError` whose message names the file and, where there is one, the line.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath
from typing import TYPE_CHECKING, Any, cast

import yaml

from pixelworld_env.concepts import PREDICATES, Concept, ConceptError, parse
from pixelworld_env.core.kinds import kind_of_name, task_kind
from pixelworld_env.errors import PixelWorldError, PixelWorldKeyError
from pixelworld_env.generation.dataset import generate
from pixelworld_env.generation.dataset import split as stratified_split
from pixelworld_env.generation.dataset_spec import SUPPORTED_SETTINGS, DatasetSpec
from pixelworld_env.yaml_loading import YAMLInputError, construct_node, read_yaml_file, safe_yaml_compose

if TYPE_CHECKING:
    from pixelworld_env.core.kinds import Kind
    from pixelworld_env.envs.env import PixelWorldEnv

#: Top-level keys with a meaning of their own (everything else that is a list of strings is a named list).
SECTIONS = ("concepts", "generators", "datasets", "curriculum")
#: The one defect of the AAAI-18 release that loads: three generators of ``bfaw-search.generators`` name
#: ``potential-container``, a relation defined nowhere (the predicate is ``potential_container``), and no dataset
#: uses them. Exactly these (key and unknown names) are recorded in :attr:`DefinitionSet.unresolved`; any other
#: definition naming an unknown relation is an error at load, whether a dataset uses it or not.
RELEASE_UNRESOLVED: dict[str, tuple[str, ...]] = {
    f"bfaw-self-and-two-potential-containers-in-{side}nontarget": ("potential-container",)
    for side in ("left-", "", "right-")
}


class DefinitionError(PixelWorldError):
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
        """The kind its name's prefix says: ``cl_`` classification, ``ba_`` bring-about, ``bc_``
        bring-about-or-cannot (:func:`pixelworld_env.core.kinds.kind_of_name`)."""
        return kind_of_name(self.name, f"{self.source}, line {self.line}: dataset").name


@dataclass(frozen=True)
class NamedList:
    """A top-level list of strings, e.g. a canonical SMC list of a ``*.include`` file."""

    name: str
    items: tuple[str, ...]
    source: str = ""
    line: int = 0
    item_lines: tuple[int, ...] = ()


@dataclass(frozen=True)
class CurriculumEntryDefinition:
    """One entry of a ``*.curriculum`` file: an experiment training ``dataset`` on top of lower-level SMCs.

    ``lower_level`` holds one ``(group, dataset)`` pair per lower-level experiment path
    ``out/aaai18/<group>/<dataset>/<variant>``, in file order; ``variants`` holds the ``<variant>`` of each.
    ``list_name`` is the named list the paths were taken from (``+@name``), or ``None`` when they are written
    into the entry.
    """

    entry: str
    dataset: str
    lower_level: tuple[tuple[str, str], ...]
    source: str = ""
    line: int = 0
    variants: tuple[str, ...] = ()
    list_name: str | None = None

    @property
    def curriculum(self) -> str:
        """The stem of the defining file (e.g. ``con2-cl-canon``)."""
        return Path(self.source).stem

    @property
    def level(self) -> int:
        """1 for a flat entry (no lower-level SMCs), 2 otherwise (every released SMC is level 1)."""
        return 2 if self.lower_level else 1


@dataclass
class DefinitionSet:
    """Everything read from a set of definition files."""

    concepts: dict[str, Definition] = field(default_factory=dict)
    generators: dict[str, Definition] = field(default_factory=dict)
    datasets: dict[str, DatasetDefinition] = field(default_factory=dict)
    files: list[str] = field(default_factory=list)
    #: Curriculum file stem -> its entries in file order.
    curricula: dict[str, list[CurriculumEntryDefinition]] = field(default_factory=dict)
    #: Named lists (name -> list); a later definition of the same name replaces an earlier one.
    lists: dict[str, NamedList] = field(default_factory=dict)
    #: File -> the files it includes directly (all paths resolved).
    includes: dict[str, list[str]] = field(default_factory=dict)
    #: Concepts/generators defined more than once, as (replaced, replacing) pairs; the later one is kept.
    redefinitions: list[tuple[Definition, Definition]] = field(default_factory=list)
    #: The release's generators that name a relation defined nowhere -> those names (:data:`RELEASE_UNRESOLVED`:
    #: loaded because no dataset uses them; a dataset that uses one is an error).
    unresolved: dict[str, tuple[str, ...]] = field(default_factory=dict)

    @property
    def macros(self) -> dict[str, str]:
        """The merged macro table: every concept and generator key -> its logic."""
        table = {key: d.logic for key, d in self.concepts.items()}
        table.update({key: d.logic for key, d in self.generators.items()})
        return table

    def dataset_spec(self, name: str, **overrides: Any) -> DatasetSpec:
        """The generation spec of dataset ``name`` (for :func:`pixelworld_env.generation.dataset.generate`);
        ``overrides`` replace its fields (``num_samples``, the world's size ...)."""
        if name not in self.datasets:
            close = difflib.get_close_matches(name, list(self.datasets), n=3)
            hint = f"; did you mean {', '.join(repr(c) for c in close)}?" if close else ""
            raise PixelWorldKeyError(f"no dataset {name!r} in these definitions{hint}")
        dataset = self.datasets[name]
        macros = self.macros
        values: dict[str, Any] = {
            "name": name, "kind": dataset.kind, "concept": macros[dataset.concept],
            "generators": tuple((g, macros[g]) for g in dataset.generators), "macros": macros,
            "settings": dict(dataset.settings), **overrides}
        return DatasetSpec(**values)

    def make_env(self, name: str, *, split: str = "train", seed: int = 0, num_samples: int = 50,
                 **kwargs: Any) -> PixelWorldEnv:
        """A :class:`~pixelworld_env.envs.env.PixelWorldEnv` over dataset ``name``: generated with ``seed`` (not
        cached), split 50/50 stratified like the catalog's (``split`` "train", "test" or "all"); ``kwargs`` go to
        the environment."""
        from pixelworld_env.envs.env import PixelWorldEnv

        if split not in ("train", "test", "all"):
            raise PixelWorldError(f"split must be 'train', 'test' or 'all', got {split!r}")
        spec = self.dataset_spec(name, num_samples=num_samples)
        generated = generate(spec, seed)
        indices = range(len(generated.scenes)) if split == "all" else \
            stratified_split(generated.labels)[0 if split == "train" else 1]
        scenes = [generated.scenes[i] for i in indices]
        labels = [generated.labels[i] for i in indices] if task_kind(spec.kind).label is not None else None
        kind = cast("Kind", spec.kind)  # DatasetSpec checked it
        return PixelWorldEnv(scenes, kind=kind, concept=spec.concept, labels=labels, macros=self.macros,
                             **kwargs)

    def scope(self, source: str) -> set[str]:
        """``source`` and every file it includes, directly or not."""
        seen: set[str] = set()
        todo = [source]
        while todo:
            path = todo.pop()
            if path not in seen:
                seen.add(path)
                todo.extend(self.includes.get(path, ()))
        return seen


def _where(path: Path | str, node: yaml.Node | None) -> str:
    return f"{path}, line {node.start_mark.line + 1}" if node is not None else str(path)


def _line(node: yaml.Node | None) -> int:
    return node.start_mark.line + 1 if node is not None else 0


def load_yaml(path: Path) -> tuple[Any, yaml.Node | None]:
    """The file's data and its node tree (for line numbers), read safely (:mod:`pixelworld_env.yaml_loading`: at most
    10 MiB, no aliases); :class:`DefinitionError` naming the file (and the line) if unreadable."""
    try:
        node = safe_yaml_compose(read_yaml_file(path), str(path))
        return (construct_node(node, str(path)) if node is not None else None), node
    except OSError as exc:
        raise DefinitionError(f"cannot read definition file {path}: {exc.strerror}") from None
    except YAMLInputError as exc:
        raise DefinitionError(str(exc)) from None


def _entries(section_node: yaml.Node | None) -> dict[str, yaml.Node]:
    """Key -> key node of a mapping node (for line numbers)."""
    if not isinstance(section_node, yaml.MappingNode):
        return {}
    return {k.value: k for k, _ in section_node.value if isinstance(k, yaml.ScalarNode)}


def _pairs(node: yaml.Node | None) -> list[tuple[yaml.Node, yaml.Node]]:
    return list(node.value) if isinstance(node, yaml.MappingNode) else []


def _child(node: yaml.Node | None, key: str) -> yaml.Node | None:
    """The value node under ``key`` of a mapping node (the last one, as YAML loading keeps the last)."""
    found = None
    for k, v in _pairs(node):
        if isinstance(k, yaml.ScalarNode) and k.value == key:
            found = v
    return found


def _is_str(node: yaml.Node) -> bool:
    return isinstance(node, yaml.ScalarNode) and node.tag == "tag:yaml.org,2002:str"


def _str_list(node: yaml.Node | None) -> tuple[str, ...] | None:
    """The strings of a sequence node of plain strings, else ``None``."""
    if not isinstance(node, yaml.SequenceNode) or not all(_is_str(item) for item in node.value):
        return None
    return tuple(item.value for item in node.value)


def load_definitions(paths: str | Path | Iterable[str | Path]) -> DefinitionSet:
    """Read definition files (following ``__include__``, each file once) into a :class:`DefinitionSet`.

    Checks after reading (once every macro is known): every concept and generator compiles (syntax, predicates
    and macros, arities; whether a dataset uses it or not, except :data:`RELEASE_UNRESOLVED`), every dataset names
    a known concept and known generators, no name is both a concept and a generator, every curriculum entry
    targets a known dataset and every ``+@name`` reference resolves to a named list within the referring file's
    includes.
    """
    result = DefinitionSet()
    pending: list[_PendingEntry] = []
    todo = [Path(paths)] if isinstance(paths, str | Path) else [Path(p) for p in paths]
    for path in todo:
        _read_file(path.resolve(), result, (), pending)
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
    _check_expressions(result)
    for item in pending:
        entry = item.resolve(result)
        if entry.dataset not in result.datasets:
            raise DefinitionError(
                f"{entry.source}, line {entry.line}: curriculum entry {entry.entry!r} names unknown dataset "
                f"{entry.dataset!r}"
            )
        entries = result.curricula.setdefault(entry.curriculum, [])
        if entries and entries[0].source != entry.source:
            raise DefinitionError(f"{entry.source}: curriculum files {entries[0].source} and {entry.source} have the "
                                  "same stem (curricula are keyed by file stem)")
        entries.append(entry)
    return result


def _check_expressions(result: DefinitionSet) -> None:
    """Compile every concept and generator against the complete macro table (syntax, predicates and macros,
    arities), used by a dataset or not; errors name the file and line of the definition. Only the release's
    known defect (:data:`RELEASE_UNRESOLVED`, unused) is recorded instead."""
    macros = result.macros
    used = {name for d in result.datasets.values() for name in (d.concept, *d.generators)}
    for section in ("concepts", "generators"):
        for key, definition in getattr(result, section).items():
            try:
                if key in RELEASE_UNRESOLVED and key not in used:
                    expression = parse(definition.logic)
                    names = {c.name for c in expression.positives} | {c.name for g in expression.negations
                                                                       for c in g}
                    unknown = tuple(sorted(n for n in names if n not in PREDICATES and n not in macros))
                    if unknown == RELEASE_UNRESOLVED[key]:
                        result.unresolved[key] = unknown
                        continue
                Concept(definition.logic, macros)
            except ConceptError as err:
                raise DefinitionError(f"{definition.source}, line {definition.line}: {section[:-1]} {key!r}: "
                                      f"{err}") from None


def _read_file(path: Path, result: DefinitionSet, stack: tuple[Path, ...], pending: list[_PendingEntry]) -> None:
    if str(path) in result.files:
        return
    data, node = load_yaml(path)
    result.files.append(str(path))
    result.includes[str(path)] = []
    if data is None:
        return
    if not isinstance(data, dict):
        raise DefinitionError(f"{path}: expected a mapping of sections at the top level")
    sections = {k.value: v for k, v in node.value} if isinstance(node, yaml.MappingNode) else {}
    keys = _entries(node)
    includes = data.get("__include__") or []
    if isinstance(includes, str):
        includes = [includes]
    if not isinstance(includes, list) or not all(isinstance(i, str) for i in includes):
        raise DefinitionError(f"{_where(path, keys.get('__include__'))}: __include__ must be a list of paths")
    include_nodes = sections.get("__include__")
    for index, include in enumerate(includes):
        item = include_nodes.value[index] if isinstance(include_nodes, yaml.SequenceNode) else include_nodes
        try:
            target = (path.parent / include).resolve()
            found = target.is_file()
        except (OSError, ValueError) as err:  # a name the file system cannot take (too long, a NUL)
            raise DefinitionError(f"{_where(path, item)}: included file {include!r} cannot be a path ({err})") \
                from None
        if not found:
            raise DefinitionError(f"{_where(path, item)}: included file {include!r} not found ({target})")
        if target == path or target in stack:
            chain = " -> ".join(p.name for p in (*stack, path, target))
            raise DefinitionError(f"{_where(path, item)}: circular __include__ of {include!r} ({chain})")
        result.includes[str(path)].append(str(target))
        _read_file(target, result, (*stack, path), pending)
    for section in ("concepts", "generators"):
        table = getattr(result, section)
        if data.get(section) is not None and not isinstance(data.get(section), dict):
            raise DefinitionError(f"{_where(path, keys.get(section))}: {section!r} must be a mapping")
        # Walk the nodes rather than the loaded mapping, so that a key repeated in one file is seen too.
        for key_node, value_node in _pairs(sections.get(section)):
            key = construct_node(key_node, str(path))
            entry = construct_node(value_node, str(path))
            where = _where(path, key_node)
            if not isinstance(key, str):
                raise DefinitionError(f"{where}: a {section[:-1]}'s name must be a string, got {key!r}")
            if not isinstance(entry, dict) or not isinstance(entry.get("logic"), str):
                raise DefinitionError(f"{where}: {section[:-1]} {key!r} needs a 'logic' string")
            definition = Definition(key=key, logic=entry["logic"], desc=str(entry.get("desc", "")),
                                    source=str(path), line=_line(key_node))
            if key in table:
                result.redefinitions.append((table[key], definition))
            table[key] = definition
    if data.get("datasets") is not None and not isinstance(data.get("datasets"), dict):
        raise DefinitionError(f"{_where(path, keys.get('datasets'))}: 'datasets' must be a mapping")
    lines = _entries(sections.get("datasets"))
    for name, entry in (data.get("datasets") or {}).items():
        key_node = lines.get(name)
        where = _where(path, key_node)
        if not (isinstance(name, str) and isinstance(entry, list) and 2 <= len(entry) <= 3 and isinstance(entry[0], str)
                and isinstance(entry[1], list) and all(isinstance(g, str) for g in entry[1])):
            raise DefinitionError(
                f"{where}: dataset {name!r} must be [concept, [generators...]] or [concept, [generators...], "
                "{settings}]"
            )
        settings = entry[2] if len(entry) == 3 and entry[2] else {}
        if not isinstance(settings, dict):
            raise DefinitionError(f"{where}: dataset {name!r}: settings must be a mapping")
        _check_settings(path, name, settings, _child(sections.get("datasets"), name), key_node)
        result.datasets[name] = DatasetDefinition(
            name=name, concept=entry[0], generators=tuple(entry[1]), settings=dict(settings), source=str(path),
            line=_line(key_node),
        )
    for key_node, value_node in _pairs(node):
        key = key_node.value if isinstance(key_node, yaml.ScalarNode) else None
        if not key or key in SECTIONS or key.startswith("__"):
            continue
        if not isinstance(value_node, yaml.SequenceNode):
            close = difflib.get_close_matches(str(key), SECTIONS, n=1, cutoff=0.6)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise DefinitionError(f"{_where(path, key_node)}: unknown section {key!r} (the sections are "
                                  f"{', '.join(SECTIONS)}; other top-level keys are named lists){hint}")
        items = _str_list(value_node)
        if items is not None:
            item_lines = tuple(_line(item) for item in value_node.value)
            result.lists[key] = NamedList(key, items, str(path), _line(key_node), item_lines)
    _read_curricula(path, node, pending)


def _check_settings(path: Path, name: str, settings: dict[Any, Any], entry_node: yaml.Node | None,
                    key_node: yaml.Node | None) -> None:
    """A dataset's settings: names of :data:`SUPPORTED_SETTINGS`, each ``true`` or ``false`` (YAML bools: the string
    ``"false"`` would be true); errors name the line of the setting."""
    setting_node = entry_node.value[2] if isinstance(entry_node, yaml.SequenceNode) and len(entry_node.value) == 3 \
        else None
    lines = _entries(setting_node)
    for key, value in settings.items():
        where = _where(path, lines.get(key, key_node))
        if key not in SUPPORTED_SETTINGS:
            raise DefinitionError(f"{where}: dataset {name!r}: unknown setting {key!r}; the settings are "
                                  f"{', '.join(sorted(SUPPORTED_SETTINGS))}")
        if not isinstance(value, bool):
            raise DefinitionError(f"{where}: dataset {name!r}: setting {key!r} must be true or false (unquoted), got "
                                  f"{value!r} ({type(value).__name__})")


# -- curricula -------------------------------------------------------------------------------------------------


@dataclass
class _Reference:
    """A ``+@name`` reference (through the bindings of a ``generate_pattern`` call, if any)."""

    name: str
    node: yaml.Node


@dataclass
class _PendingEntry:
    """A curriculum entry read from a file, resolved once every file has been read."""

    entry: str
    dataset: str
    paths: tuple[tuple[str, yaml.Node], ...] | _Reference
    source: Path
    key_node: yaml.Node

    def resolve(self, result: DefinitionSet) -> CurriculumEntryDefinition:
        list_name = None
        if isinstance(self.paths, _Reference):
            ref = self.paths
            named = result.lists.get(ref.name)
            if named is None or named.source not in result.scope(str(self.source)):
                raise DefinitionError(
                    f"{_where(self.source, ref.node)}: curriculum entry {self.entry!r} refers to +@{ref.name}, "
                    "which is not a list of paths defined in this file or the files it includes"
                )
            list_name = named.name
            lines = named.item_lines or (named.line,) * len(named.items)
            paths = [(item, named.source, line) for item, line in zip(named.items, lines, strict=True)]
        else:
            paths = [(item, str(self.source), _line(node)) for item, node in self.paths]
        lower: list[tuple[str, str]] = []
        variants: list[str] = []
        for item, source, line in paths:
            parts = PurePosixPath(item.strip()).parts
            if len(parts) < 3 or any(not p.strip() for p in parts[-3:]):
                raise DefinitionError(
                    f"{source}, line {line}: curriculum entry {self.entry!r}: lower-level experiment {item!r} is "
                    "not a path <...>/<group>/<dataset>/<variant>"
                )
            lower.append((parts[-3], parts[-2]))
            variants.append(parts[-1])
        return CurriculumEntryDefinition(
            entry=self.entry, dataset=self.dataset, lower_level=tuple(lower), source=str(self.source),
            line=_line(self.key_node), variants=tuple(variants), list_name=list_name,
        )


def _reference(node: yaml.Node, bindings: dict[str, yaml.Node], path: Path) -> _Reference | None:
    """The list named by a ``+@name`` scalar, following ``bindings``; ``None`` if ``node`` is no reference."""
    if not (_is_str(node) and node.value.startswith("+@")):
        return None
    name = node.value[2:].strip()
    if not name or "+" in name or "[" in name:
        raise DefinitionError(f"{_where(path, node)}: unsupported reference {node.value!r} (expected +@list_name)")
    bound = bindings.get(name)
    if bound is None:
        return _Reference(name, node)
    target = _reference(bound, {}, path)
    if target is None:
        raise DefinitionError(f"{_where(path, bound)}: binding {name!r} must be +@list_name")
    return target


def _read_curricula(path: Path, node: yaml.Node | None, pending: list[_PendingEntry]) -> None:
    """Collect the entries of the ``curriculum:`` section and of ``generate_pattern`` curriculum blocks."""
    blocks: list[tuple[yaml.Node, dict[str, yaml.Node]]] = []
    seen: dict[str, yaml.Node] = {}
    for key_node, value_node in _pairs(node):
        key = key_node.value if isinstance(key_node, yaml.ScalarNode) else ""
        if key == "curriculum":
            if not isinstance(value_node, yaml.MappingNode):
                raise DefinitionError(f"{_where(path, key_node)}: 'curriculum' must map entry names to "
                                      "[dataset, [lower-level experiments...]]")
            blocks.append((value_node, {}))
        elif key.startswith("__gen") and isinstance(value_node, yaml.MappingNode):
            call = _child(value_node, "call")
            kwargs = _child(value_node, "kwargs")
            name = _child(kwargs, "name")
            if not (call is not None and _is_str(call) and call.value.endswith(":generate_pattern")
                    and name is not None and _is_str(name) and name.value == "curriculum"):
                continue
            cfg = _child(kwargs, "cfg")
            if not isinstance(cfg, yaml.MappingNode):
                raise DefinitionError(f"{_where(path, key_node)}: {key}: kwargs.cfg must map entry names to "
                                      "[dataset, [lower-level experiments...]]")
            binding_node = _child(kwargs, "bindings")
            if binding_node is not None and not isinstance(binding_node, yaml.MappingNode):
                raise DefinitionError(f"{_where(path, binding_node)}: {key}: kwargs.bindings must be a mapping")
            bindings = {k.value: v for k, v in _pairs(binding_node) if isinstance(k, yaml.ScalarNode)}
            blocks.append((cfg, bindings))
    for mapping, bindings in blocks:
        for key_node, value_node in mapping.value:
            where = _where(path, key_node)
            if not _is_str(key_node):
                raise DefinitionError(f"{where}: curriculum entry names must be strings")
            entry = key_node.value
            if entry in seen:
                raise DefinitionError(
                    f"{where}: curriculum entry {entry!r} is defined twice (first at line {_line(seen[entry])})"
                )
            seen[entry] = key_node
            shape = f"{where}: curriculum entry {entry!r} must be [dataset, [lower-level experiments...]]"
            if not (isinstance(value_node, yaml.SequenceNode) and len(value_node.value) == 2
                    and _is_str(value_node.value[0])):
                raise DefinitionError(shape)
            dataset_node, lower_node = value_node.value
            ref = _reference(lower_node, bindings, path)
            paths: tuple[tuple[str, yaml.Node], ...] | _Reference
            if ref is not None:
                paths = ref
            elif isinstance(lower_node, yaml.SequenceNode):
                for item in lower_node.value:
                    if not _is_str(item):
                        raise DefinitionError(
                            f"{_where(path, item)}: curriculum entry {entry!r}: lower-level experiments must be "
                            "path strings"
                        )
                paths = tuple((item.value, item) for item in lower_node.value)
            else:
                raise DefinitionError(shape)
            pending.append(_PendingEntry(entry, dataset_node.value.strip(), paths, path, key_node))
