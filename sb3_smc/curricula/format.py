"""Curricula as data: a DAG of SMCs to train, read from the project's YAML format (``docs/curricula.md``).

A curriculum names **nodes**; each node is an SMC to train on a PixelWorld task (a catalog dataset or concept pool)
or on another environment's SMC task (a Gymnasium id, ``module:Name-v0``: :mod:`sb3_smc.tasks.task`), and may **use**
lower-level nodes as actions. Example::

    curriculum: my-containment
    method: smc-curr                 # optional: smc-base | smc-curr | smc-canon | anything (reports group by it)
    description: corners, then containment
    defaults: {timesteps: 200000}    # optional: algo, timesteps, budget_scale, primitives, count_primitive_steps,
                                     #           max_steps, call_step_cap, hyperparameters
    nodes:
      - name: cl_self-in-left-corner_vs_on-hline
        task: cl_self-in-left-corner_vs_on-hline
      - name: cl_self-in-right-corner_vs_on-hline
        task: cl_self-in-right-corner_vs_on-hline
      - name: container
        task: cl_self-in-container_vs_noncontainer
        uses: [cl_self-in-left-corner_vs_on-hline, cl_self-in-right-corner_vs_on-hline]
        primitives: false            # the "noprim" ablation: signals and SMCs only
    targets: [container]             # optional; default: the nodes no other node uses

:func:`load_curriculum` validates everything before any training and names the file, the line and the node in
every error (:class:`CurriculumError`). Nothing here imports torch.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import os
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from pixelworld_env.yaml_loading import YAMLInputError, construct_node, safe_yaml_compose
from sb3_smc.core.dag import CycleError, children_first, reachable
from sb3_smc.core.hyperparameters import ALGORITHMS, DEFAULT_TIMESTEPS, MAX_TIMESTEPS
from sb3_smc.core.names import name_problem
from sb3_smc.errors import SMCError
from sb3_smc.records import WrapperSettings
from sb3_smc.records.spec import MAX_EPISODE_STEPS

__all__ = ["FORMAT_KEYS", "NODE_KEYS", "SEED_SEPARATOR", "Curriculum", "CurriculumError", "Node", "describe",
           "is_env_id", "load_curriculum", "merge", "parse_curriculum"]

MAX_CURRICULUM_CHARS = 10 * 2**20
"""The longest curriculum file read (10 MiB; the shipped ones have 1-8 KB)."""
FORMAT_KEYS = ("curriculum", "method", "description", "defaults", "nodes", "targets")
"""Top-level keys of a curriculum file."""
NODE_KEYS = ("name", "task", "uses", "primitives", "algo", "timesteps", "budget_scale", "count_primitive_steps",
             "max_steps", "call_step_cap", "train_worlds", "hyperparameters")
"""Keys of a node (``defaults`` takes the last nine)."""
DEFAULT_MAX_STEPS = WrapperSettings.max_steps
"""An episode's steps (decisions, or moves where calls cost their moves): the paper's 100."""
DEFAULT_CALL_STEP_CAP = WrapperSettings.call_step_cap
"""The moves an SMC call may make (its nested calls' included) before it is cut off."""
SEED_SEPARATOR = "@"
"""SMC names in a curriculum's library are ``<node>@<seed>``; node names may not contain it."""


class CurriculumError(SMCError):
    """A curriculum file or object is malformed; the message names the file, the line where known, and the node."""


@dataclass(frozen=True)
class Node:
    """One SMC to train: ``task`` (a dataset or concept-pool name) with the nodes it ``uses`` as actions.

    ``algo`` / ``timesteps`` ``None``: the run's settings (``train_curriculum``'s ``algo`` and ``timesteps``).
    ``budget_scale`` multiplies the node's budget, whichever gives it (a node that calls many SMCs may need longer).
    ``count_primitive_steps``: a call of a used node costs the episode the moves it made instead of one step
    (:class:`~sb3_smc.envs.wrapper.HierarchicalSMCWrapper`). ``max_steps``: the episode's length (decisions, or moves
    where calls cost their moves); ``call_step_cap``: the moves a call of a used node may make (its nested calls'
    included) before it is cut off. ``line`` is where the node was defined (not part of its identity).
    """

    name: str
    task: str
    uses: tuple[str, ...] = ()
    include_primitives: bool = True
    algo: str | None = None
    timesteps: int | None = None
    hyperparameters: dict[str, Any] = field(default_factory=dict)
    budget_scale: float = 1.0
    count_primitive_steps: bool = False
    max_steps: int = DEFAULT_MAX_STEPS
    call_step_cap: int = DEFAULT_CALL_STEP_CAP
    train_worlds: int | None = None
    """Train on the first ``N`` worlds of the task's training split only (``None``: all of them)."""
    line: int | None = field(default=None, compare=False)

    @property
    def env_id(self) -> str:
        """``PW-<task>-v0`` for a PixelWorld dataset or pool; a Gymnasium id (``Name-vN``, ``module:Name-vN``) as
        it is."""
        return self.task if is_env_id(self.task) else f"PW-{self.task}-v0"

    def settings(self) -> dict[str, Any]:
        """What decides the trained SMCs (two nodes of the same name must agree on it); ``budget_scale``,
        ``count_primitive_steps``, ``max_steps``, ``call_step_cap`` and ``train_worlds`` only where not their defaults
        (so that the settings of runs from before them stay the same)."""
        scale = {"budget_scale": self.budget_scale} if self.budget_scale != 1 else {}
        count = {"count_primitive_steps": True} if self.count_primitive_steps else {}
        steps = {"max_steps": self.max_steps} if self.max_steps != DEFAULT_MAX_STEPS else {}
        cap = {"call_step_cap": self.call_step_cap} if self.call_step_cap != DEFAULT_CALL_STEP_CAP else {}
        worlds = {"train_worlds": self.train_worlds} if self.train_worlds is not None else {}
        return {"task": self.task, "uses": list(self.uses), "primitives": self.include_primitives,
                "algo": self.algo, "timesteps": self.timesteps, **scale, **count, **steps, **cap, **worlds,
                "hyperparameters": self.hyperparameters}


@dataclass(frozen=True)
class Curriculum:
    """A validated DAG of :class:`Node` s (in file order) with its ``targets``."""

    name: str
    nodes: tuple[Node, ...]
    targets: tuple[str, ...]
    method: str | None = None
    description: str = ""
    source: str | None = None

    def __post_init__(self) -> None:
        _validate(self)

    @property
    def by_name(self) -> dict[str, Node]:
        return {node.name: node for node in self.nodes}

    def node(self, name: str) -> Node:
        nodes = self.by_name
        if name not in nodes:
            raise CurriculumError(f"{self._where()}: no node named {name!r}{_suggest(name, nodes)}")
        return nodes[name]

    def level(self, name: str) -> int:
        """1 for a node that uses nothing, else 1 + the deepest used node's level."""
        node = self.node(name)
        return 1 + max((self.level(u) for u in node.uses), default=0)

    def levels(self) -> list[list[str]]:
        """Node names by level, lowest first (file order within a level)."""
        out: dict[int, list[str]] = {}
        for node in self.nodes:
            out.setdefault(self.level(node.name), []).append(node.name)
        return [out[k] for k in sorted(out)]

    def order(self, names: Iterable[str] | None = None) -> list[str]:
        """``names`` (default: every node) and the nodes they use, lower levels first (reverse topological)."""
        wanted = self.closure(self.by_name if names is None else names)
        return [n.name for n in sorted(self.nodes, key=lambda n: self.level(n.name)) if n.name in wanted]

    def closure(self, names: Iterable[str]) -> set[str]:
        """``names`` and every node they use, directly or not."""
        return reachable(names, lambda name: self.node(name).uses)

    def select(self, targets: Sequence[str] | None) -> list[str]:
        """Node names for ``targets``: target or node names, or dataset names (every target training that dataset;
        else the node of that name or the nodes training it). ``None``: the curriculum's targets."""
        if targets is None:
            return list(self.targets)
        if not targets:
            raise CurriculumError(f"{self._where()}: --targets names no node: give node or dataset names")
        chosen: list[str] = []
        nodes = self.by_name
        for target in targets:
            training = [n for n in self.targets if nodes[n].task == target]
            if target in self.targets or (target in nodes and not training):
                found = [target]
            else:
                found = training or [n.name for n in self.nodes if n.task == target]
            if not found:
                raise CurriculumError(f"{self._where()}: --targets {target!r} is neither a node nor the dataset of a "
                                      f"node{_suggest(target, [*nodes, *{n.task for n in self.nodes}])}")
            chosen.extend(n for n in found if n not in chosen)
        return chosen

    def _where(self) -> str:
        return self.source or f"curriculum {self.name!r}"

    def to_yaml(self) -> str:
        """The curriculum in the file format (round-trips through :func:`parse_curriculum`)."""
        nodes = []
        for node in self.nodes:
            item: dict[str, Any] = {"name": node.name, "task": node.task}
            if node.uses:
                item["uses"] = list(node.uses)
            if not node.include_primitives:
                item["primitives"] = False
            for key in ("algo", "timesteps"):
                if getattr(node, key) is not None:
                    item[key] = getattr(node, key)
            if node.budget_scale != 1:
                item["budget_scale"] = node.budget_scale
            if node.count_primitive_steps:
                item["count_primitive_steps"] = True
            if node.max_steps != DEFAULT_MAX_STEPS:
                item["max_steps"] = node.max_steps
            if node.call_step_cap != DEFAULT_CALL_STEP_CAP:
                item["call_step_cap"] = node.call_step_cap
            if node.train_worlds is not None:
                item["train_worlds"] = node.train_worlds
            if node.hyperparameters:
                item["hyperparameters"] = node.hyperparameters
            nodes.append(item)
        data: dict[str, Any] = {"curriculum": self.name}
        if self.method:
            data["method"] = self.method
        if self.description:
            data["description"] = self.description
        data["nodes"] = nodes
        data["targets"] = list(self.targets)
        return yaml.safe_dump(data, sort_keys=False, width=120)


# ---------------------------------------------------------------------------------------------------------------
# Reading
# ---------------------------------------------------------------------------------------------------------------

def _suggest(name: str, names: Iterable[str]) -> str:
    close = difflib.get_close_matches(name, list(dict.fromkeys(names)), n=3, cutoff=0.6)
    return f"; did you mean {' or '.join(repr(c) for c in close)}?" if close else ""


def _plain(node: yaml.Node, where: str) -> Any:
    """A composed YAML node as Python data; duplicate mapping keys are an error (PyYAML would keep the last), and so
    is a key that is not a scalar or a scalar its tag cannot read (``CurriculumError`` with the line)."""
    if isinstance(node, yaml.MappingNode):
        out: dict[Any, Any] = {}
        for key_node, value_node in node.value:
            key = _plain(key_node, where)
            if isinstance(key, list | dict):
                raise CurriculumError(f"{where}:{key_node.start_mark.line + 1}: a key must be a name, got {key!r}")
            if key in out:
                raise CurriculumError(f"{where}:{key_node.start_mark.line + 1}: key {key!r} given twice")
            out[key] = _plain(value_node, where)
        return out
    if isinstance(node, yaml.SequenceNode):
        return [_plain(item, where) for item in node.value]
    try:
        return construct_node(node, where)
    except YAMLInputError as err:
        raise CurriculumError(f"{where}:{node.start_mark.line + 1}: {err.problem}") from None


def load_curriculum(path: str | os.PathLike) -> Curriculum:
    """Read and validate the curriculum file ``path`` (errors name the file, the line and the node)."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as err:
        raise CurriculumError(f"cannot read curriculum file {path}: {err}") from None
    except UnicodeDecodeError as err:
        raise CurriculumError(f"{path}: not a curriculum file: not UTF-8 text (byte {err.object[err.start]:#04x} at "
                              f"position {err.start}); a curriculum is a YAML file (its format: python -m pydoc "
                              "sb3_smc.curricula.format)") from None
    return parse_curriculum(text, str(path))


def parse_curriculum(text: str, source: str = "<curriculum>") -> Curriculum:
    """Parse and validate curriculum YAML ``text``; ``source`` names it in errors."""
    if len(text) > MAX_CURRICULUM_CHARS:
        raise CurriculumError(f"{source}: {len(text)} characters, more than a curriculum file may have "
                              f"({MAX_CURRICULUM_CHARS})")
    try:
        root = safe_yaml_compose(text, source)
    except YAMLInputError as err:
        line = f":{err.line}" if err.line else ""
        said = err.problem.replace("invalid YAML: ", "malformed YAML: ", 1)
        raise CurriculumError(f"{source}{line}: {said}") from None
    if not isinstance(root, yaml.MappingNode):
        raise CurriculumError(f"{source}: a curriculum file is a mapping with the keys {list(FORMAT_KEYS)}")
    data = _plain(root, source)
    odd = [k for k in data if not isinstance(k, str)]
    if odd:
        raise CurriculumError(f"{source}: top-level keys must be names, got {odd[0]!r}")
    lines = {}
    for key_node, value_node in root.value:
        lines[key_node.value] = (key_node.start_mark.line + 1, value_node)
    unknown = [k for k in data if k not in FORMAT_KEYS]
    if unknown:
        key = unknown[0]
        raise CurriculumError(f"{source}:{lines[key][0]}: unknown key {key!r} (a curriculum file has "
                              f"{list(FORMAT_KEYS)}){_suggest(str(key), FORMAT_KEYS)}")
    for key in ("curriculum", "nodes"):
        if key not in data:
            raise CurriculumError(f"{source}: missing key {key!r}")
    name = data["curriculum"]
    problem = name_problem(name)
    if problem is not None:
        raise CurriculumError(f"{source}:{lines['curriculum'][0]}: 'curriculum' must be a name, got {name!r}: "
                              f"{problem}")
    defaults = data.get("defaults") or {}
    if not isinstance(defaults, dict):
        raise CurriculumError(f"{source}:{lines['defaults'][0]}: 'defaults' must be a mapping, got {defaults!r}")
    bad = [k for k in defaults if k not in NODE_KEYS[3:]]
    if bad:
        raise CurriculumError(f"{source}:{lines['defaults'][0]}: unknown default {bad[0]!r} (defaults may set "
                              f"{list(NODE_KEYS[3:])})")
    items = data["nodes"]
    if not isinstance(items, list) or not items:
        raise CurriculumError(f"{source}:{lines['nodes'][0]}: 'nodes' must be a non-empty list of nodes")
    item_nodes = lines["nodes"][1].value
    nodes = [_node(item, item_node.start_mark.line + 1, defaults, source)
             for item, item_node in zip(items, item_nodes, strict=True)]
    targets = data.get("targets")
    if targets is None:
        used = {u for node in nodes for u in node.uses}
        targets = [node.name for node in nodes if node.name not in used]
    elif not isinstance(targets, list) or not all(isinstance(t, str) for t in targets):
        raise CurriculumError(f"{source}:{lines['targets'][0]}: 'targets' must be a list of node names")
    method = data.get("method")
    if method is not None and not isinstance(method, str):
        raise CurriculumError(f"{source}:{lines['method'][0]}: 'method' must be a string, got {method!r}")
    description = data.get("description") or ""
    if not isinstance(description, str):
        raise CurriculumError(f"{source}:{lines['description'][0]}: 'description' must be a string, got "
                              f"{type(description).__name__}")
    return Curriculum(name=name, nodes=tuple(nodes), targets=tuple(targets), method=method,
                      description=description, source=source)


def _node(item: Any, line: int, defaults: Mapping[str, Any], source: str) -> Node:
    where = f"{source}:{line}"
    if not isinstance(item, dict):
        raise CurriculumError(f"{where}: a node is a mapping with the keys {list(NODE_KEYS)}, got {item!r}")
    name = item.get("name")
    label = f"node {name!r}" if isinstance(name, str) else "node"
    unknown = [k for k in item if k not in NODE_KEYS]
    if unknown:
        raise CurriculumError(f"{where}: {label}: unknown key {unknown[0]!r} (a node has {list(NODE_KEYS)})"
                              f"{_suggest(str(unknown[0]), NODE_KEYS)}")
    for key in ("name", "task"):
        if not isinstance(item.get(key), str) or not item.get(key):
            raise CurriculumError(f"{where}: {label}: {key!r} must be a non-empty string, got {item.get(key)!r}")
    settings = {**defaults, **{k: v for k, v in item.items() if k in NODE_KEYS[3:]}}
    uses = item.get("uses", [])
    if not isinstance(uses, list) or not all(isinstance(u, str) for u in uses):
        raise CurriculumError(f"{where}: {label}: 'uses' must be a list of node names, got {uses!r}")
    primitives = settings.get("primitives", True)
    count = settings.get("count_primitive_steps", False)
    for key, value in (("primitives", primitives), ("count_primitive_steps", count)):
        if not isinstance(value, bool):
            raise CurriculumError(f"{where}: {label}: {key!r} must be true or false, got {value!r}")
    timesteps = settings.get("timesteps")
    if timesteps is not None and (isinstance(timesteps, bool) or not isinstance(timesteps, int)
                                  or not 1 <= timesteps <= MAX_TIMESTEPS):
        raise CurriculumError(f"{where}: {label}: 'timesteps' must be a positive integer, got {timesteps!r} (at "
                              f"most {MAX_TIMESTEPS:,})")
    scale = settings.get("budget_scale", 1.0)
    if isinstance(scale, bool) or not isinstance(scale, int | float) or not 0 < scale < math.inf:
        raise CurriculumError(f"{where}: {label}: 'budget_scale' must be a positive number, got {scale!r}")
    if (timesteps or DEFAULT_TIMESTEPS) * scale > MAX_TIMESTEPS:
        shown = scale if not isinstance(scale, int) or scale < 10**20 else f"(an integer of {len(str(scale))} digits)"
        raise CurriculumError(f"{where}: {label}: 'budget_scale' {shown} makes a budget of more than "
                              f"{MAX_TIMESTEPS:,} timesteps")
    steps = {key: settings.get(key, default) for key, default in (("max_steps", DEFAULT_MAX_STEPS),
                                                                  ("call_step_cap", DEFAULT_CALL_STEP_CAP))}
    for key, value in steps.items():
        if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= MAX_EPISODE_STEPS:
            raise CurriculumError(f"{where}: {label}: {key!r} must be a positive integer, got {value!r} (at most "
                                  f"{MAX_EPISODE_STEPS:,})")
    hyper = settings.get("hyperparameters") or {}
    if not isinstance(hyper, dict):
        raise CurriculumError(f"{where}: {label}: 'hyperparameters' must be a mapping, got {hyper!r}")
    worlds = settings.get("train_worlds")
    if worlds is not None and (isinstance(worlds, bool) or not isinstance(worlds, int) or worlds < 1):
        raise CurriculumError(f"{where}: {label}: 'train_worlds' must be a positive integer, got {worlds!r}")
    try:
        return Node(name=item["name"], task=item["task"], uses=tuple(uses), include_primitives=primitives,
                    algo=settings.get("algo"), timesteps=timesteps, hyperparameters=hyper, budget_scale=float(scale),
                    count_primitive_steps=count, max_steps=steps["max_steps"],
                    call_step_cap=steps["call_step_cap"], train_worlds=worlds, line=line)
    except CurriculumError as err:
        raise CurriculumError(f"{where}: {label}: {err}") from None


# ---------------------------------------------------------------------------------------------------------------
# Validation (also of curricula built in Python)
# ---------------------------------------------------------------------------------------------------------------

def is_env_id(task: str) -> bool:
    """Whether a node's ``task`` is a Gymnasium id (of an :class:`~sb3_smc.tasks.task.SMCTask` on any environment)
    rather than a PixelWorld dataset or concept pool, whose names never end in a version."""
    return re.search(r"-v\d+$", task) is not None


def _registered(env_id: str) -> bool:
    """Whether ``env_id`` is registered (``module:`` imported first, as ``gym.make`` does)."""
    import importlib

    import gymnasium as gym

    module, _, name = env_id.rpartition(":")
    try:
        if module:
            importlib.import_module(module)
        gym.spec(name)
    except (ImportError, TypeError, ValueError, gym.error.Error):  # a relative module, a version of 4301 digits
        return False
    return True


def _tasks() -> set[str]:
    from pixelworld_env.datasets import catalog

    return {*catalog.dataset_names(), *catalog.concept_pools()}


def _validate(curriculum: Curriculum) -> None:
    source = curriculum.source or f"curriculum {curriculum.name!r}"

    def at(node: Node) -> str:
        return f"{source}:{node.line}" if node.line is not None else source

    problem = name_problem(curriculum.name) if "+" not in curriculum.name else None  # "+": curricula merged
    if problem is not None:
        raise CurriculumError(f"{source}: curriculum {curriculum.name!r} is not a name: {problem}")
    tasks = _tasks()
    seen: dict[str, Node] = {}
    for node in curriculum.nodes:
        if node.name in seen:
            first = seen[node.name]
            where = f" (first defined at line {first.line})" if first.line is not None else ""
            raise CurriculumError(f"{at(node)}: node {node.name!r} is defined twice{where}")
        seen[node.name] = node
        problem = name_problem(node.name)
        if problem is not None:
            raise CurriculumError(f"{at(node)}: node {node.name!r} is not a name: {problem}")
        if SEED_SEPARATOR in node.name:
            raise CurriculumError(f"{at(node)}: node {node.name!r}: names may not contain {SEED_SEPARATOR!r} "
                                  f"(library SMCs are named <node>{SEED_SEPARATOR}<seed>)")
        if is_env_id(node.task):
            if not _registered(node.task):
                raise CurriculumError(f"{at(node)}: node {node.name!r}: {node.task!r} is not a registered Gymnasium "
                                      "id (name the module that registers it: 'module:Name-v0')")
        elif node.task not in tasks:
            raise CurriculumError(f"{at(node)}: node {node.name!r}: unknown dataset or concept pool "
                                  f"{node.task!r}{_suggest(node.task, tasks)}")
        if node.algo is not None and node.algo not in ALGORITHMS:
            raise CurriculumError(f"{at(node)}: node {node.name!r}: algo must be one of {ALGORITHMS}, got "
                                  f"{node.algo!r}")
        if isinstance(node.budget_scale, bool) or not (isinstance(node.budget_scale, int | float)
                                                       and math.isfinite(node.budget_scale) and node.budget_scale > 0):
            raise CurriculumError(f"{at(node)}: node {node.name!r}: budget_scale must be a positive number, got "
                                  f"{node.budget_scale!r}")
        if not isinstance(node.count_primitive_steps, bool):
            raise CurriculumError(f"{at(node)}: node {node.name!r}: count_primitive_steps must be true or false, got "
                                  f"{node.count_primitive_steps!r}")
        for key in ("max_steps", "call_step_cap", "train_worlds"):
            value = getattr(node, key)
            if (value is not None or key != "train_worlds") and (
                    isinstance(value, bool) or not isinstance(value, int) or value < 1):
                raise CurriculumError(f"{at(node)}: node {node.name!r}: {key} must be a positive integer, got "
                                      f"{value!r}")
        if node.name in node.uses:
            raise CurriculumError(f"{at(node)}: node {node.name!r} uses itself")
        if len(set(node.uses)) != len(node.uses):
            twice = sorted({u for u in node.uses if node.uses.count(u) > 1})
            raise CurriculumError(f"{at(node)}: node {node.name!r} uses {twice} twice")
        if not node.include_primitives and not node.uses:
            raise CurriculumError(f"{at(node)}: node {node.name!r} has primitives: false (noprim) but uses no "
                                  "nodes: it could only signal")
    for node in curriculum.nodes:
        for used in node.uses:
            if used not in seen:
                raise CurriculumError(f"{at(node)}: node {node.name!r} uses an unknown node {used!r}"
                                      f"{_suggest(used, seen)}")
    _check_cycles(seen, at)
    for k, target in enumerate(curriculum.targets):
        if target not in seen:
            raise CurriculumError(f"{source}: target {target!r} is not a node{_suggest(target, seen)}")
        if target in curriculum.targets[:k]:
            raise CurriculumError(f"{source}: target {target!r} is listed twice")


def _check_cycles(by_name: Mapping[str, Node], at: Any) -> None:
    try:
        children_first({name: node.uses for name, node in by_name.items()})
    except CycleError as err:
        raise CurriculumError(f"{at(by_name[err.cycle[0]])}: nodes use each other in a cycle: {err}") from None


def merge(curricula: Sequence[Curriculum]) -> Curriculum:
    """One curriculum holding every node of ``curricula`` (a node defined by several must be defined alike)."""
    if len(curricula) == 1:
        return curricula[0]
    nodes: dict[str, Node] = {}
    origin: dict[str, str] = {}
    for curriculum in curricula:
        for node in curriculum.nodes:
            if node.name in nodes and nodes[node.name].settings() != node.settings():
                raise CurriculumError(
                    f"node {node.name!r} is defined differently by {origin[node.name]} and {curriculum.name} "
                    f"({nodes[node.name].settings()} vs {node.settings()})")
            if node.name not in nodes:
                nodes[node.name] = dataclasses.replace(node, line=None)
                origin[node.name] = curriculum.name
    targets = [t for c in curricula for t in c.targets]
    return Curriculum(name="+".join(c.name for c in curricula), nodes=tuple(nodes.values()),
                      targets=tuple(dict.fromkeys(targets)), method=None,
                      description="; ".join(c.description for c in curricula if c.description))


def describe(curriculum: Curriculum) -> str:
    """A curriculum's DAG by level (what ``sb3-smc curricula NAME`` prints)."""
    lines = [curriculum.name + (f" ({curriculum.method})" if curriculum.method else "")]
    if curriculum.description:
        lines.append(curriculum.description)
    targets = set(curriculum.targets)
    for level, names in enumerate(curriculum.levels(), start=1):
        lines.append(f"level {level}: {len(names)} node{'s' * (len(names) != 1)}")
        for name in names:
            node = curriculum.node(name)
            mark = "*" if name in targets else " "
            extra = []
            if node.task != name:
                extra.append(f"task {node.task}")
            if not node.include_primitives:
                extra.append("noprim")
            if node.algo:
                extra.append(node.algo)
            if node.timesteps:
                extra.append(f"{node.timesteps:,} steps")
            if node.budget_scale != 1:
                extra.append(f"budget x{node.budget_scale:g}")
            if node.count_primitive_steps:
                extra.append("calls cost their moves")
            if node.max_steps != DEFAULT_MAX_STEPS:
                extra.append(f"{node.max_steps} steps an episode")
            if node.call_step_cap != DEFAULT_CALL_STEP_CAP:
                extra.append(f"calls cut at {node.call_step_cap} moves")
            if node.train_worlds is not None:
                extra.append(f"{node.train_worlds} training worlds")
            head = f"  {mark} {name}" + (f" ({', '.join(extra)})" if extra else "")
            lines.append(head + (f" uses {', '.join(node.uses)}" if node.uses else ""))
    lines.append("(* = target)")
    return "\n".join(lines)
