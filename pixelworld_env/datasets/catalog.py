"""The benchmark catalog: every AAAI-18 dataset, concept, generator, concept pool and curriculum.

The data live in ``pixelworld_env/data/catalog.json`` (format ``pixelworld-catalog``, version 1), which
``tools/build_catalog.py`` builds from the original definition files (see ``docs/catalog.md``). The file is
read once, on first use. Its top-level keys:

* ``concepts`` / ``generators``: key -> ``{logic, desc, file}`` (logic with whitespace collapsed);
* ``datasets``: name -> ``{kind, concept, generators, settings, category, num_samples, train_size, test_size,
  file}``;
* ``concept_pools``: pool name ``<cl|ba>_<concept>`` -> sorted member datasets;
* ``curricula``: curriculum file stem -> ``{canonical, file, entries: [{name, dataset, lower_level?,
  smc_list?}]}``; an entry's lower-level SMCs are ``"group/dataset"`` strings, written in ``lower_level``
  or, for canonical entries, taken from ``canonical_smc_lists[smc_list]``; a flat entry has neither key;
* ``canonical_smc_lists``: name -> ``{smcs, file, used_by}``; ``experiments``: group -> ``{curriculum, goal,
  level, method, canonical, noprim, smc_filters, num_seeds, variants, test_schedule}``;
* ``split_rule``; ``unresolved_macros`` (definitions naming undefined relations; no dataset uses them) and
  ``redefinitions`` (keys defined twice in the original files; the later definition is kept).

Pool names never equal dataset names (the build refuses to write such a catalog and :func:`concept_pools`
checks it again), so ``PW-<dataset>-v0`` and ``PW-<pool>-v0`` environment ids cannot collide.
"""

from __future__ import annotations

import copy
import difflib
import functools
import json
from dataclasses import dataclass, field
from importlib import resources
from typing import Any, NamedTuple

from pixelworld_env.core.kinds import Kind, task_kind
from pixelworld_env.errors import PixelWorldError, PixelWorldKeyError

FORMAT = "pixelworld-catalog"
VERSION = 1
DATA_FILE = "catalog.json"


class CatalogError(PixelWorldError):
    """The catalog file is missing, of another format/version, or inconsistent."""


class _UnknownName(PixelWorldKeyError):
    """An unknown name; catchable as ``KeyError`` and as ``ValueError``; ``suggestions`` are close names."""

    what = "name"

    def __init__(self, name: str, candidates: list[str]) -> None:
        self.name = name
        self.suggestions = difflib.get_close_matches(name, candidates, n=3, cutoff=0.0)
        hint = f"; did you mean {', '.join(repr(s) for s in self.suggestions)}?" if self.suggestions else ""
        self.message = f"unknown {self.what} {name!r}{hint}"
        super().__init__(self.message)

    def __str__(self) -> str:
        return self.message


class UnknownDatasetError(_UnknownName):
    """No dataset of that name; the message lists the 3 closest dataset names."""

    what = "dataset"


class UnknownCurriculumEntryError(_UnknownName):
    """No curriculum entry of that name (or a bare name used by several curricula); see the message."""

    what = "curriculum entry"


@dataclass(frozen=True)
class DatasetInfo:
    """One dataset of the catalog.

    ``concept`` is the concept key and ``concept_logic`` its (unexpanded) logic; expand it with
    :func:`macros`. ``num_samples`` is the generation quota (per label for classification); ``train_size`` and
    ``test_size`` are the sizes of the stratified split.
    """

    name: str
    kind: Kind
    concept: str
    concept_logic: str
    generators: tuple[str, ...]
    settings: dict[str, Any] = field(hash=False)
    category: str
    num_samples: int
    train_size: int
    test_size: int
    source_file: str = ""

    @property
    def prefix(self) -> str:
        """Its kind's name prefix: ``cl`` classification, ``ba`` bring-about, ``bc`` bring-about-or-cannot."""
        return task_kind(self.kind).prefix

    @property
    def num_envs(self) -> int:
        """Number of environments in the dataset (train + test)."""
        return self.train_size + self.test_size

    @property
    def pool(self) -> str:
        """The concept pool this dataset belongs to (``<prefix>_<concept>``)."""
        return f"{self.prefix}_{self.concept}"


class SMC(NamedTuple):
    """A lower-level SMC: the flat experiment group that trained it and its dataset (= its entry name)."""

    group: str
    dataset: str

    def __str__(self) -> str:
        return f"{self.group}/{self.dataset}"


@dataclass(frozen=True)
class CurriculumEntry:
    """An experiment of a curriculum: train ``dataset`` with the policies of ``lower_level`` as extra actions.

    ``curriculum`` is the curriculum file stem; ``smc_list`` names the shared canonical list the lower-level
    SMCs come from (``None`` for hand-designed and flat entries).
    """

    name: str
    dataset: str
    lower_level: tuple[SMC, ...]
    curriculum: str
    canonical: bool
    smc_list: str | None = None

    @property
    def level(self) -> int:
        """1 for a flat entry, 2 for an entry with lower-level SMCs."""
        return 2 if self.lower_level else 1


@dataclass(frozen=True)
class ExperimentGroup:
    """One experiment file of the release (e.g. ``con2-canon-class-noprim``) with its curriculum's entries.

    ``goal``: ``classification``, ``bring-about-signal`` or ``bring-about-direct`` (the latter not reported in
    the paper). ``method``: ``smc-base`` (flat), ``smc-curr`` (hand-designed level 2) or ``smc-canon``.
    ``noprim``: primitive moves are removed from the higher-level actions. ``smc_filters``: ``(name, k)``
    of every SMC selection variant (the k best seeds of each lower-level experiment). Seeds run from 0 to
    ``num_seeds - 1``; ``variants`` are the output variant strings of the original runs.
    """

    name: str
    curriculum: str
    goal: str
    level: int
    method: str
    canonical: bool
    noprim: bool
    smc_filters: tuple[tuple[str, int], ...]
    num_seeds: int
    variants: tuple[str, ...]
    entries: tuple[CurriculumEntry, ...]
    test_schedule: tuple[tuple[str, str], ...] = ()

    @property
    def kind(self) -> Kind:
        """``classification`` or ``bring-about``: the kind of every target dataset of the group."""
        return "classification" if self.goal == "classification" else "bring-about"

    def entry(self, name: str) -> CurriculumEntry:
        """The entry called ``name`` (:class:`UnknownCurriculumEntryError` if there is none)."""
        for entry in self.entries:
            if entry.name == name:
                return entry
        raise UnknownCurriculumEntryError(f"{self.name}/{name}", [f"{self.name}/{e.name}" for e in self.entries])


@functools.cache
def _data() -> dict[str, Any]:
    try:
        text = resources.files("pixelworld_env").joinpath("data", DATA_FILE).read_text(encoding="utf-8")
    except (FileNotFoundError, OSError) as exc:
        raise CatalogError(f"catalog file pixelworld_env/data/{DATA_FILE} not found ({exc}); rebuild it with "
                           "python tools/build_catalog.py") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise CatalogError(f"catalog file pixelworld_env/data/{DATA_FILE} is not valid JSON: {exc}") from None
    return _validate(data)


def _validate(data: Any) -> dict[str, Any]:
    """``data`` if it is a catalog of the format and version this module reads, else :class:`CatalogError`."""
    if not isinstance(data, dict) or data.get("format") != FORMAT or data.get("version") != VERSION:
        found = (data.get("format"), data.get("version")) if isinstance(data, dict) else type(data).__name__
        raise CatalogError(f"catalog file pixelworld_env/data/{DATA_FILE} has format/version {found}, this code "
                           f"reads ({FORMAT!r}, {VERSION}); rebuild it with python tools/build_catalog.py")
    missing = [k for k in ("concepts", "generators", "datasets", "concept_pools", "curricula", "experiments",
                           "canonical_smc_lists", "unresolved_macros") if not isinstance(data.get(k), dict)]
    if missing:
        raise CatalogError(f"catalog file pixelworld_env/data/{DATA_FILE} lacks the sections {missing}")
    return data


def dataset_names() -> list[str]:
    """Every dataset name, sorted."""
    return sorted(_data()["datasets"])


def dataset(name: str) -> DatasetInfo:
    """The dataset called ``name`` (:class:`UnknownDatasetError`, a ``KeyError``, if there is none)."""
    datasets = _data()["datasets"]
    info = datasets.get(name)
    if info is None:
        raise UnknownDatasetError(name, list(datasets))
    return DatasetInfo(
        name=name, kind=info["kind"], concept=info["concept"],
        concept_logic=_data()["concepts"][info["concept"]]["logic"], generators=tuple(info["generators"]),
        settings=copy.deepcopy(info["settings"]), category=info["category"], num_samples=info["num_samples"],
        train_size=info["train_size"], test_size=info["test_size"], source_file=info["file"],
    )


def concepts() -> dict[str, str]:
    """Every concept key -> its logic."""
    return {key: d["logic"] for key, d in _data()["concepts"].items()}


def generators() -> dict[str, str]:
    """Every generator key -> its logic (including the three unused ones with undefined macros)."""
    return {key: d["logic"] for key, d in _data()["generators"].items()}


def macros() -> dict[str, str]:
    """The merged concept + generator macro table; a name defined as both is an error."""
    return dict(_macro_table())


@functools.cache
def _macro_table() -> dict[str, str]:
    concept_table, generator_table = concepts(), generators()
    both = sorted(set(concept_table) & set(generator_table))
    if both:
        raise CatalogError(f"names defined both as concept and as generator: {', '.join(both)}")
    return {**concept_table, **generator_table}


def unresolved_macros() -> dict[str, tuple[str, ...]]:
    """Concepts/generators that name undefined relations -> those names (unused by every dataset)."""
    data = _data()["unresolved_macros"]
    return {key: tuple(names) for section in ("concepts", "generators") for key, names in data[section].items()}


def concept_pools() -> dict[str, tuple[str, ...]]:
    """Pool name ``<cl|ba>_<concept>`` -> the sorted datasets of that kind and concept, for every pair."""
    pools = {pool: tuple(members) for pool, members in _data()["concept_pools"].items()}
    clash = sorted(set(pools) & set(_data()["datasets"]))
    if clash:
        raise CatalogError(f"concept pool names equal dataset names: {', '.join(clash)}")
    return pools


def canonical_smc_lists() -> dict[str, tuple[SMC, ...]]:
    """The shared lower-level SMC lists of the canonical curricula (name -> SMCs, in file order).

    ``canonical_containment_curriculum`` (13) and ``canonical_object_curriculum`` (11) are the ``*.include``
    lists; ``obj-con2-canon-cl:1..3`` (11, 3, 15) are the lists written into ``obj-con2-canon-cl.curriculum``,
    numbered in order of first use.
    """
    return {name: _smcs(info["smcs"]) for name, info in _data()["canonical_smc_lists"].items()}


def _smcs(items: list[str]) -> tuple[SMC, ...]:
    return tuple(SMC(*item.split("/", 1)) for item in items)


@functools.cache
def _curriculum_entries() -> dict[str, tuple[CurriculumEntry, ...]]:
    data = _data()
    lists = canonical_smc_lists()
    result = {}
    for stem, info in data["curricula"].items():
        entries = []
        for e in info["entries"]:
            smc_list = e.get("smc_list")
            lower = lists[smc_list] if smc_list else _smcs(e.get("lower_level", []))
            entries.append(CurriculumEntry(name=e["name"], dataset=e["dataset"], lower_level=lower,
                                           curriculum=stem, canonical=info["canonical"], smc_list=smc_list))
        result[stem] = tuple(entries)
    return result


@functools.cache
def _groups() -> dict[str, ExperimentGroup]:
    entries = _curriculum_entries()
    return {
        name: ExperimentGroup(
            name=name, curriculum=g["curriculum"], goal=g["goal"], level=g["level"], method=g["method"],
            canonical=g["canonical"], noprim=g["noprim"], smc_filters=tuple(g["smc_filters"].items()),
            num_seeds=g["num_seeds"], variants=tuple(g["variants"]), entries=entries[g["curriculum"]],
            test_schedule=tuple(tuple(pair) for pair in g["test_schedule"]),
        )
        for name, g in sorted(_data()["experiments"].items())
    }


def curricula() -> dict[str, ExperimentGroup]:
    """Every experiment group (experiment file name, e.g. ``con2-canon-class``) with its entries, sorted."""
    return dict(_groups())


def curriculum_files() -> dict[str, tuple[CurriculumEntry, ...]]:
    """Curriculum file stem (e.g. ``con2-cl-canon``) -> its entries in file order."""
    return dict(_curriculum_entries())


def curriculum_entry(name: str) -> CurriculumEntry:
    """A curriculum entry by ``"<group>/<entry>"`` (e.g. ``"con2-canon-class/cl_self-in-container_vs_corner_canon"``)
    or by bare entry name when exactly one curriculum file defines it.

    Raises :class:`UnknownCurriculumEntryError` (a ``KeyError``) for unknown or ambiguous names.
    """
    groups = _groups()
    if "/" in name:
        group, _, entry = name.partition("/")
        if group not in groups:
            raise UnknownCurriculumEntryError(name, [f"{g}/{e.name}" for g, x in groups.items() for e in x.entries])
        return groups[group].entry(entry)
    found = [e for entries in _curriculum_entries().values() for e in entries if e.name == name]
    if len(found) == 1:
        return found[0]
    if not found:
        names = sorted({e.name for entries in _curriculum_entries().values() for e in entries})
        raise UnknownCurriculumEntryError(name, names)
    qualified = sorted(f"{g}/{name}" for g, x in groups.items() if any(e.name == name for e in x.entries))
    error = UnknownCurriculumEntryError(name, [])
    error.suggestions = qualified[:3]
    error.message = (f"curriculum entry {name!r} is defined in {len(found)} curriculum files; name it as "
                     f"<group>/<entry>: {', '.join(qualified)}")
    error.args = (error.message,)
    raise error
