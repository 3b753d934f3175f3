"""Reader for the experiment files of the original AAAI-18 release (YAML).

Experiment files (:func:`load_experiments`) are the 33 top-level files of ``experiments/aaai18``: their
``__include__`` chain (common settings, goal, ``level2``/``level2-noprim``, one ``DATA/*.curriculum``) is
deep-merged in include order and the settings that matter for the benchmark are read from the result. The
definition files they include are read by :mod:`pixelworld_env.generation.definitions`; every error is a
:class:`~pixelworld_env.generation.definitions.DefinitionError` naming the file.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pixelworld_env.generation.definitions import DefinitionError, load_yaml

__all__ = ["GOALS", "ExperimentDefinition", "load_experiments"]

#: Goal codes of the experiment files (``vals_goal``) -> the benchmark's words.
GOALS = {"c": "classification", "sig": "bring-about-signal", "dir": "bring-about-direct"}


@dataclass(frozen=True)
class ExperimentDefinition:
    """One top-level experiment file (an experiment group such as ``con2-canon-class``).

    ``goal`` is the ``vals_goal`` code (``c``, ``sig`` or ``dir``); ``smc_filters`` the ``(name, k)`` of every
    SMC filter variant; ``variants`` the output variant strings
    ``{dataset_size}+{goal}+{embodiment}+{currname}+{filter}+{policy}+{algorithm}``; ``num_seeds`` the
    number of training seeds (seeds ``0 .. num_seeds-1``); ``include_base_nonsignals`` is false in the
    ``-noprim`` files (primitive moves removed from the higher-level action set); ``test_schedule`` lists
    (trained-on, tested-on) entry pairs (``*.testing`` files).
    """

    name: str
    curriculum: str
    goal: str
    smc_filters: tuple[tuple[str, int], ...]
    variants: tuple[str, ...]
    num_seeds: int
    include_base_nonsignals: bool
    num_samples: int
    test_size: float
    test_schedule: tuple[tuple[str, str], ...] = ()
    source: str = ""

    @property
    def goal_name(self) -> str:
        """``classification``, ``bring-about-signal`` or ``bring-about-direct``."""
        return GOALS[self.goal]

    @property
    def noprim(self) -> bool:
        """True when the primitive moves are removed from the higher-level action set (``level2-noprim``)."""
        return not self.include_base_nonsignals


def _merge(base: dict[str, Any], override: dict[str, Any]) -> dict[str, Any]:
    merged = dict(base)
    for key, value in override.items():
        if isinstance(value, dict) and isinstance(merged.get(key), dict):
            merged[key] = _merge(merged[key], value)
        else:
            merged[key] = value
    return merged


def _merged_config(path: Path, cache: dict[Path, Any], stack: tuple[Path, ...] = ()) -> dict[str, Any]:
    """The file's mapping deep-merged over its includes (in include order, later ones winning)."""
    if path in stack:
        chain = " -> ".join(str(p) for p in (*stack, path))
        raise DefinitionError(f"{path}: circular __include__ ({chain})")
    if path not in cache:
        cache[path] = load_yaml(path)[0]
    data = cache[path]
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise DefinitionError(f"{path}: expected a mapping at the top level")
    includes = data.get("__include__") or []
    merged: dict[str, Any] = {}
    for include in [includes] if isinstance(includes, str) else includes:
        target = (path.parent / include).resolve()
        if not target.is_file():
            raise DefinitionError(f"{path}: included file {include!r} not found ({target})")
        merged = _merge(merged, _merged_config(target, cache, (*stack, path)))
    return _merge(merged, {k: v for k, v in data.items() if k != "__include__"})


def _get(config: dict[str, Any], path: str, where: str) -> Any:
    value: Any = config
    for part in path.split("."):
        if not isinstance(value, dict) or part not in value:
            raise DefinitionError(f"{where}: setting {path!r} not found in the file or its includes")
        value = value[part]
    return value


def _integer(value: Any, setting: str, where: str) -> int:
    """An integer setting (YAML ``true`` and ``2.5`` are no counts)."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise DefinitionError(f"{where}: setting {setting!r} must be an integer, got {value!r} "
                              f"({type(value).__name__})")
    return value


def _flag(value: Any, setting: str, where: str) -> bool:
    """A bool setting: YAML ``true`` or ``false`` (the string ``"false"`` would be true)."""
    if not isinstance(value, bool):
        raise DefinitionError(f"{where}: setting {setting!r} must be true or false (unquoted), got {value!r} "
                              f"({type(value).__name__})")
    return value


def load_experiments(paths: str | Path | Iterable[str | Path]) -> dict[str, ExperimentDefinition]:
    """Read experiment files (name -> :class:`ExperimentDefinition`, keyed by file name).

    Each file must include exactly one ``*.curriculum`` file directly; ``curriculum`` is its resolved path.
    """
    todo = [Path(paths)] if isinstance(paths, str | Path) else [Path(p) for p in paths]
    cache: dict[Path, Any] = {}
    result: dict[str, ExperimentDefinition] = {}
    for raw in todo:
        path = raw.resolve()
        where = str(path)
        config = _merged_config(path, cache)
        direct = (cache[path] if isinstance(cache[path], dict) else {}).get("__include__") or []
        curricula = [i for i in ([direct] if isinstance(direct, str) else direct) if str(i).endswith(".curriculum")]
        if len(curricula) != 1:
            raise DefinitionError(f"{where}: an experiment file must include exactly one *.curriculum file, "
                                  f"found {len(curricula)}")
        vals = _get(config, "overrideable_variant_vals", where)
        goals = _get(vals, "vals_goal", where)
        if not (isinstance(goals, list) and len(goals) == 1 and goals[0] in GOALS):
            raise DefinitionError(f"{where}: vals_goal must be one of {sorted(GOALS)} (got {goals!r})")
        filters = []
        for item in _get(vals, "vals_filter", where):
            if not (isinstance(item, list) and len(item) == 3 and isinstance(item[2], dict) and "k" in item[2]):
                raise DefinitionError(f"{where}: vals_filter entries must be [name, rule, {{k: n}}] (got {item!r})")
            filters.append((str(item[0]), _integer(item[2]["k"], "vals_filter k", where)))
        axes = [_get(vals, key, where) for key in ("vals_dataset_size", "vals_goal", "vals_embodiment",
                                                   "vals_currname")]
        axes += [[name for name, _ in filters], _get(vals, "vals_policy", where), _get(vals, "vals_algorithm", where)]
        variants = tuple("+".join(str(v) for v in combo) for combo in itertools.product(*axes))
        env_kwargs = config.get("base_env", {}).get("env", {}).get("kwargs", {}) or {}
        dataset_kwargs = _get(config, "overrideable_dataset_kwargs", where)
        schedule = tuple((str(a), str(b)) for a, b in config.get("test_schedule") or ())
        result[path.name] = ExperimentDefinition(
            name=path.name, curriculum=str((path.parent / curricula[0]).resolve()), goal=goals[0],
            smc_filters=tuple(filters), variants=variants,
            num_seeds=_integer(_get(vals, "num_smcs", where), "num_smcs", where),
            include_base_nonsignals=_flag(env_kwargs.get("include_base_nonsignals", True), "include_base_nonsignals",
                                          where),
            num_samples=_integer(_get(dataset_kwargs, "num_samples", where), "num_samples", where),
            test_size=float(_get(config, "common.test_size", where)), test_schedule=schedule, source=where,
        )
    return result
