#!/usr/bin/env python
"""Build the project's benchmark catalog from the original AAAI-18 definition and experiment files.

Reads ``<reference>/aaai18/DATA/*.datasets`` and ``*.curriculum`` (with everything they include) through
:mod:`pixelworld_env.generation.definitions`, the 33 experiment files ``<reference>/aaai18/*``, and the definitions
sb3-smc designed in the same format (``pixelworld_env/data/definitions/*.datasets``: the pushable curriculum,
category ``pushable``), and writes

* ``pixelworld_env/data/catalog.json`` -- the catalog (format ``pixelworld-catalog``, version 1), and
* ``docs/catalog.md`` -- tables generated from it.

Usage::

    python tools/build_catalog.py [--reference DIR]           # (re)write both files
    python tools/build_catalog.py [--reference DIR] --check   # exit 1 if either file differs from a rebuild

``--reference`` defaults to ``$PIXELWORLD_REFERENCE`` or ``../shared/reference`` beside the checkout.
The build is deterministic (sorted keys, no paths or dates), so a rebuild of unchanged inputs is a no-op.
"""

from __future__ import annotations

import argparse
import difflib
import json
import math
import os
import sys
from collections import defaultdict
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from pixelworld_env.concepts import ConceptError, parse  # noqa: E402
from pixelworld_env.concepts.predicates import PREDICATES  # noqa: E402
from pixelworld_env.core.kinds import task_kind  # noqa: E402
from pixelworld_env.generation.definitions import load_definitions  # noqa: E402
from pixelworld_env.generation.experiment_files import GOALS, load_experiments  # noqa: E402

CATALOG_PATH = ROOT / "pixelworld_env" / "data" / "catalog.json"
DESIGNED_PATH = ROOT / "pixelworld_env" / "data" / "definitions"
DOCS_PATH = ROOT / "docs" / "catalog.md"
FORMAT = "pixelworld-catalog"
VERSION = 1
#: Category of a dataset by the name of its defining ``*.datasets`` file (first matching prefix wins).
CATEGORY_BY_FILE = (
    ("bfaw-containment-", "containment"),
    ("bfaw-obj-containment-", "objcon"),
    ("bfaw-objects-", "objects"),
    ("bfaw-search-", "search"),
    ("pushable", "pushable"),
    ("cannot", "cannot"),
)
KIND_BY_GOAL = {"classification": "classification", "bring-about-signal": "bring-about",
                "bring-about-direct": "bring-about"}
WIDTH = 120


class BuildError(RuntimeError):
    """The original files are inconsistent in a way the catalog cannot represent."""


def default_reference() -> Path:
    """``$PIXELWORLD_REFERENCE`` or ``../shared/reference`` beside the checkout."""
    return Path(os.environ.get("PIXELWORLD_REFERENCE", ROOT.parent / "shared" / "reference"))


def _norm(text: str) -> str:
    """Whitespace collapsed (the concept language ignores it; YAML folding leaves trailing newlines)."""
    return " ".join(str(text).split())


def _category(source: str) -> str:
    name = Path(source).name
    for prefix, category in CATEGORY_BY_FILE:
        if name.startswith(prefix):
            return category
    raise BuildError(f"{source}: no category rule matches this datasets file")


def _split_sizes(kind: str, num_samples: int, test_fraction: float) -> tuple[int, int]:
    """(train, test): a kind with labels has num_samples per label, bring-about num_samples in all.

    The test part is ``ceil(test_fraction * n)`` as in sklearn's ``train_test_split``.
    """
    total = 2 * num_samples if task_kind(kind).label is not None else num_samples
    test = math.ceil(test_fraction * total)
    return total - test, test


def _unresolved(logic: str, macros: dict[str, str], where: str) -> list[str]:
    """Relation names of ``logic`` that are neither predicates nor macros."""
    try:
        expression = parse(logic)
    except ConceptError as exc:
        raise BuildError(f"{where}: {exc}") from None
    names = {c.name for c in expression.positives}
    names.update(c.name for group in expression.negations for c in group)
    return sorted(n for n in names if n not in PREDICATES and n not in macros)


def build_catalog(reference: Path) -> dict[str, Any]:
    """The catalog as a JSON-ready mapping, built from ``reference/aaai18``."""
    root = reference / "aaai18"
    data = root / "DATA"
    if not data.is_dir():
        raise BuildError(f"original definition files not found at {data} (pass --reference)")
    defs = load_definitions(sorted(data.glob("*.datasets")) + sorted(data.glob("*.curriculum"))
                            + sorted(DESIGNED_PATH.glob("*.datasets")))
    experiments = load_experiments(sorted(p for p in root.iterdir() if p.is_file()))
    if not experiments:
        raise BuildError(f"no experiment files in {root}")

    for old, new in defs.redefinitions:
        if _norm(old.logic) != _norm(new.logic):
            raise BuildError(f"{new.source}, line {new.line}: {new.key!r} redefined with a different logic "
                             f"(first at {old.source}, line {old.line})")
    for quantity in ("num_samples", "test_size"):
        values = {getattr(e, quantity) for e in experiments.values()}
        if len(values) != 1:
            raise BuildError(f"experiment files disagree on {quantity}: {sorted(values)}")
    num_samples = next(iter(experiments.values())).num_samples
    test_fraction = next(iter(experiments.values())).test_size

    macros = defs.macros
    unresolved: dict[str, dict[str, list[str]]] = {"concepts": {}, "generators": {}}
    tables: dict[str, dict[str, Any]] = {}
    for section in ("concepts", "generators"):
        table = {}
        for key, d in sorted(getattr(defs, section).items()):
            table[key] = {"desc": _norm(d.desc), "file": Path(d.source).name, "logic": _norm(d.logic)}
            missing = _unresolved(d.logic, macros, f"{d.source}, line {d.line}")
            if missing:
                unresolved[section][key] = missing
        tables[section] = table

    datasets: dict[str, Any] = {}
    for name, d in sorted(defs.datasets.items()):
        broken = [g for g in (d.concept, *d.generators) if g in unresolved["concepts"] or g in
                  unresolved["generators"]]
        if broken:
            raise BuildError(f"{d.source}, line {d.line}: dataset {name!r} uses {broken} with undefined macros")
        train, test = _split_sizes(d.kind, num_samples, test_fraction)
        datasets[name] = {
            "category": _category(d.source), "concept": d.concept, "file": Path(d.source).name,
            "generators": list(d.generators), "kind": d.kind, "num_samples": num_samples,
            "settings": dict(sorted(d.settings.items())), "test_size": test, "train_size": train,
        }

    pools: dict[str, list[str]] = defaultdict(list)
    for name, info in datasets.items():
        pools[f"{task_kind(info['kind']).prefix}_{info['concept']}"].append(name)
    clash = sorted(set(pools) & set(datasets))
    if clash:
        raise BuildError(f"concept pool names equal dataset names (their env ids would clash): {clash}")

    curricula, canonical_lists = _curricula(defs)
    groups = _experiments(experiments, curricula, canonical_lists, datasets)
    return {
        "format": FORMAT,
        "version": VERSION,
        "source": "experiments/aaai18 of vicariousinc/pixelworld (AAAI-18 release): DATA/*.datasets, "
                  "DATA/*.curriculum and the files they include, and the 33 experiment files; the pushable "
                  "curriculum: pixelworld_env/data/definitions/*.datasets (designed by sb3-smc)",
        "split_rule": {"num_samples": num_samples, "stratified": True, "test_fraction": test_fraction},
        "concepts": tables["concepts"],
        "generators": tables["generators"],
        "datasets": datasets,
        "concept_pools": {pool: sorted(members) for pool, members in sorted(pools.items())},
        "curricula": curricula,
        "canonical_smc_lists": canonical_lists,
        "experiments": groups,
        "unresolved_macros": {k: v for k, v in unresolved.items()},
        "redefinitions": {
            new.key: {"kept": f"{Path(new.source).name}:{new.line}", "replaced": f"{Path(old.source).name}:{old.line}"}
            for old, new in defs.redefinitions
        },
    }


def _is_canonical(stem: str) -> bool:
    return "canon" in stem.split("-")


def _curricula(defs: Any) -> tuple[dict[str, Any], dict[str, Any]]:
    curricula: dict[str, Any] = {}
    lists: dict[str, dict[str, Any]] = {}
    for stem, entries in sorted(defs.curricula.items()):
        canonical = _is_canonical(stem)
        inline: dict[tuple[tuple[str, str], ...], str] = {}
        rows = []
        for e in entries:
            smcs = [f"{group}/{dataset}" for group, dataset in e.lower_level]
            smc_list = None
            if canonical and e.lower_level:
                if e.list_name is not None:
                    smc_list = e.list_name
                    source = Path(defs.lists[e.list_name].source).name
                else:
                    smc_list = inline.setdefault(e.lower_level, f"{stem}:{len(inline) + 1}")
                    source = Path(e.source).name
                known = lists.setdefault(smc_list, {"file": source, "smcs": smcs, "used_by": []})
                if known["smcs"] != smcs:
                    raise BuildError(f"canonical SMC list {smc_list!r} differs between its uses")
                if stem not in known["used_by"]:
                    known["used_by"].append(stem)
            # A canonical entry names its shared list instead of repeating it; a flat entry has neither key.
            row = {"dataset": e.dataset, "name": e.entry}
            if smc_list is not None:
                row["smc_list"] = smc_list
            elif smcs:
                row["lower_level"] = smcs
            rows.append(row)
        curricula[stem] = {"canonical": canonical, "entries": rows, "file": Path(entries[0].source).name}
    for info in lists.values():
        info["used_by"].sort()
    return curricula, dict(sorted(lists.items()))


def _experiments(experiments: dict[str, Any], curricula: dict[str, Any], lists: dict[str, Any],
                 datasets: dict[str, Any]) -> dict[str, Any]:
    groups: dict[str, Any] = {}
    for name, exp in sorted(experiments.items()):
        stem = Path(exp.curriculum).stem
        if stem not in curricula:
            raise BuildError(f"{exp.source}: curriculum {stem!r} was not read from DATA/*.curriculum")
        entries = curricula[stem]["entries"]
        goal = GOALS[exp.goal]
        for e in entries:
            if datasets[e["dataset"]]["kind"] != KIND_BY_GOAL[goal]:
                raise BuildError(f"{exp.source}: entry {e['name']!r} trains {datasets[e['dataset']]['kind']} "
                                 f"dataset {e['dataset']!r} with goal {goal}")
        level = 2 if any("lower_level" in e or "smc_list" in e for e in entries) else 1
        canonical = curricula[stem]["canonical"]
        groups[name] = {
            "canonical": canonical, "curriculum": stem, "goal": goal, "level": level,
            "method": "smc-base" if level == 1 else "smc-canon" if canonical else "smc-curr",
            "noprim": exp.noprim, "num_seeds": exp.num_seeds, "smc_filters": dict(exp.smc_filters),
            "test_schedule": [list(pair) for pair in exp.test_schedule], "variants": list(exp.variants),
        }
    # Every lower-level SMC must be an entry of a flat group training that very dataset.
    for info in curricula.values():
        for e in info["entries"]:
            for smc in lists[e["smc_list"]]["smcs"] if "smc_list" in e else e.get("lower_level", []):
                group, dataset = smc.split("/")
                provider = groups.get(group)
                where = f"{info['file']}: entry {e['name']!r}: lower-level SMC {smc!r}"
                if provider is None:
                    raise BuildError(f"{where}: no experiment group {group!r}")
                trained = {x["name"]: x for x in curricula[provider["curriculum"]]["entries"]}
                if dataset not in trained or trained[dataset]["dataset"] != dataset or provider["level"] != 1:
                    raise BuildError(f"{where}: not a flat entry of {group!r} training that dataset")
    return groups


# -- rendering -------------------------------------------------------------------------------------------------


def _render(value: Any, level: int = 0, column: int = 0) -> str:
    """JSON with sorted keys; a value stays on one line when it fits in WIDTH columns, else it is expanded."""
    flat = json.dumps(value, sort_keys=True, ensure_ascii=False, separators=(", ", ": "))
    if column + len(flat) <= WIDTH or not isinstance(value, dict | list) or not value:
        return flat
    pad = "  " * (level + 1)
    if isinstance(value, dict):
        items = []
        for key in sorted(value):
            prefix = f"{pad}{json.dumps(key, ensure_ascii=False)}: "
            items.append(prefix + _render(value[key], level + 1, len(prefix)))
    else:
        items = [pad + _render(item, level + 1, len(pad)) for item in value]
    return "{\n" + ",\n".join(items) + "\n" + "  " * level + "}" if isinstance(value, dict) else (
        "[\n" + ",\n".join(items) + "\n" + "  " * level + "]")


def render_json(catalog: dict[str, Any]) -> str:
    """The catalog file's text."""
    return _render(catalog) + "\n"


def _table(header: list[str], rows: list[list[Any]]) -> list[str]:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join(" --- " for _ in header) + "|"]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return lines


def _smcs(catalog: dict[str, Any], entry: dict[str, Any]) -> list[str]:
    """The lower-level SMCs of a catalog entry (from its shared list, if it names one)."""
    if "smc_list" in entry:
        return catalog["canonical_smc_lists"][entry["smc_list"]]["smcs"]
    return entry.get("lower_level", [])


def _pushable_section(catalog: dict[str, Any]) -> list[str]:
    """The designed pushable curriculum: its datasets by level with one line each, and why the levels are ordered
    as they are (the hierarchy itself is ``sb3_smc.curricula.designed.PUSHABLE``)."""
    from sb3_smc.curricula.designed import PUSHABLE, designed_curricula

    curriculum = designed_curricula()["pushable"]
    level = {curriculum.node(name).task: k for k, names in enumerate(curriculum.levels(), 1) for name in names}
    missing = sorted(set(PUSHABLE) ^ {n for n, i in catalog["datasets"].items() if i["category"] == "pushable"})
    if missing:
        raise BuildError(f"the pushable curriculum and the pushable datasets disagree on {missing}")
    out = ["## The pushable curriculum (designed by sb3-smc)", "",
           "The paper's 11-concept, 6-level pushable curriculum (Fig. 3, Fig. 5c) was never released. "
           "sb3-smc's design: a white pixel P lies on the floor; it may be pushable (engine class `basic`) or "
           "immoveable, and both look the same. An immoveable reference object R (a white small blob on the "
           "floor) lies to its right; the top level adds a floating distractor. With a 3 x 3 view that moves "
           "with the self, pushing P looks the same whether P moves or not, so the agent can only tell by "
           "pushing P towards R and then checking whether P touches R. Every dataset has `allow_pushable`; "
           "the hierarchy is `sb3_smc.curricula.designed.PUSHABLE`, shipped as the curriculum `pushable`.", "",
           "**Why this order.** The levels follow how much of a classification the initial state gives away "
           "without acting (the paper's ordering of Fig. 5c): at level 1 the agent's first 3 x 3 view decides "
           "it; at levels 2-3 the full initial grid decides it (the information is there for a passive learner, "
           "although the paper's small CNN, trained on 50 grids, gets only 68-70 %) but the agent's first view "
           "does not; at levels 5-6 not even the full grid does, because pushable and immoveable pixels are "
           "the same pixels. The bring-about nodes are the behaviours the classifiers above them call. "
           "`docs/curricula.md` reports the measurement.", ""]
    rows = [[level[name], f"`{name}`", catalog["datasets"][name]["kind"],
             "<br>".join(f"`{u}`" for u in PUSHABLE[name].uses) or "(flat)", PUSHABLE[name].summary]
            for name in sorted(PUSHABLE, key=lambda n: (level[n], n))]
    return out + _table(["level", "dataset", "kind", "calls", "what it asks"], rows)


def render_docs(catalog: dict[str, Any]) -> str:
    """``docs/catalog.md``: tables of datasets, concept pools, experiment groups, curricula and SMC lists."""
    datasets = catalog["datasets"]
    by_kind = defaultdict(int)
    by_category = defaultdict(int)
    for info in datasets.values():
        by_kind[info["kind"]] += 1
        by_category[info["category"]] += 1
    split = catalog["split_rule"]
    out = [
        "# PixelWorld benchmark catalog",
        "",
        "<!-- Generated by tools/build_catalog.py from pixelworld_env/data/catalog.json; do not edit by hand. "
        "`python tools/build_catalog.py --check` verifies that it is current. -->",
        "",
        f"The catalog (`pixelworld_env/data/catalog.json`, format `{catalog['format']}` version "
        f"{catalog['version']}) lists the {len(datasets)} datasets of the AAAI-18 release and of the pushable "
        "curriculum sb3-smc designed "
        f"({', '.join(f'{n} {k}' for k, n in sorted(by_kind.items()))}; "
        f"{', '.join(f'{k} {n}' for k, n in sorted(by_category.items()))}), "
        f"{len(catalog['concepts'])} concepts, {len(catalog['generators'])} generators, "
        f"{len(catalog['experiments'])} experiment groups and their curricula. It is read by "
        "`pixelworld_env.datasets.catalog` and built from the original definition files by `tools/build_catalog.py`.",
        "",
        "* **Kind**: `cl_` classification, `ba_` bring-about. **Category**: by the defining `*.datasets` file "
        "(`bfaw-containment-*` containment, `bfaw-obj-containment-cl` objcon, `bfaw-objects-*` objects, "
        "`bfaw-search-ba` search; `pixelworld_env/data/definitions/pushable.datasets` pushable, designed by "
        "sb3-smc: [below](#the-pushable-curriculum-designed-by-sb3-smc)).",
        f"* **Sizes**: `num_samples` = {split['num_samples']}: classification datasets have "
        f"{split['num_samples']} positive + {split['num_samples']} negative environments, bring-about datasets "
        f"{split['num_samples']} (all with the goal initially false); each is split "
        f"{1 - split['test_fraction']:.0%} / {split['test_fraction']:.0%} stratified by label "
        "([design choices](design.md#sizes-and-the-split)).",
        "* **Python**: `pixelworld_env.datasets.catalog` -- `dataset_names()`, `dataset(name)` (a `DatasetInfo`), "
        "`concepts()`, `generators()`, `macros()`, `concept_pools()`, `curricula()` (experiment groups with "
        "their entries), `curriculum_files()`, `curriculum_entry(\"<group>/<entry>\")`, "
        "`canonical_smc_lists()`.",
        "* **File format**: see the docstring of `pixelworld_env/datasets/catalog.py`. Lower-level SMCs are written "
        "`group/dataset`: the flat experiment group that trains the SMC and its dataset.",
        "* **Environment ids**: `PW-<dataset>-v0` for every dataset and `PW-<cl|ba>_<concept>-v0` for every "
        "concept pool (all datasets of one kind sharing a concept). No pool name equals a dataset name (the "
        "build fails otherwise).",
        "",
        f"## Datasets ({len(datasets)})",
        "",
    ]
    rows = [[f"`{name}`", info["kind"], info["category"], f"`{info['concept']}`", len(info["generators"]),
             f"{info['train_size']}/{info['test_size']}"] for name, info in datasets.items()]
    out += _table(["dataset", "kind", "category", "concept", "generators", "train/test"], rows)
    out += ["", *_pushable_section(catalog)]
    pools = catalog["concept_pools"]
    out += ["", f"## Concept pools ({len(pools)})", "",
            "Each pool is one environment over the scenes of all its member datasets (their train or test "
            "splits together).", ""]
    rows = []
    for pool, members in pools.items():
        info = datasets[members[0]]
        train = sum(datasets[m]["train_size"] for m in members)
        test = sum(datasets[m]["test_size"] for m in members)
        rows.append([f"`PW-{pool}-v0`", info["kind"], f"`{info['concept']}`", f"{train}/{test}",
                     "<br>".join(f"`{m}`" for m in members)])
    out += _table(["id", "kind", "concept", "train/test", "datasets"], rows)
    groups = catalog["experiments"]
    out += ["", f"## Experiment groups ({len(groups)})", "",
            "One per experiment file. *method*: smc-base = flat (level 1), smc-curr = hand-designed level-2 "
            "curriculum, smc-canon = canonical SMC lists; *noprim*: primitive moves removed from the "
            "higher-level action set. The `bring-about-direct` groups are not reported in the paper.", ""]
    rows = [[f"`{g}`", f"`{info['curriculum']}`", info["goal"], info["level"], info["method"],
             "yes" if info["noprim"] else "", ", ".join(f"{k} (k={v})" for k, v in info["smc_filters"].items()),
             info["num_seeds"], len(catalog["curricula"][info["curriculum"]]["entries"])]
            for g, info in groups.items()]
    out += _table(["group", "curriculum", "goal", "level", "method", "noprim", "SMC filters", "seeds", "entries"],
                  rows)
    out += ["", "## Level-2 curricula", "",
            "Entries with lower-level SMCs, written `group/dataset` (the flat experiment group that trained "
            "the SMC and its dataset). Canonical entries name their shared list (next section).", ""]
    for stem, info in catalog["curricula"].items():
        entries = [e for e in info["entries"] if "lower_level" in e or "smc_list" in e]
        if not entries:
            continue
        users = ", ".join(f"`{g}`" for g, x in groups.items() if x["curriculum"] == stem)
        kind = "canonical" if info["canonical"] else "hand-designed"
        out += [f"### `{stem}` ({kind}; {len(entries)} entries; used by {users})", ""]
        rows = [[f"`{e['name']}`", f"`{e['dataset']}`", len(_smcs(catalog, e)),
                 f"`{e['smc_list']}`" if "smc_list" in e else "<br>".join(f"`{s}`" for s in e["lower_level"])]
                for e in entries]
        out += _table(["entry", "target dataset", "SMCs", "lower-level SMCs"], rows) + [""]
    lists = catalog["canonical_smc_lists"]
    out += [f"## Canonical SMC lists ({len(lists)})", ""]
    rows = [[f"`{name}`", f"`{info['file']}`", len(info["smcs"]), ", ".join(f"`{u}`" for u in info["used_by"]),
             "<br>".join(f"`{s}`" for s in info["smcs"])] for name, info in lists.items()]
    out += _table(["list", "defined in", "SMCs", "used by", "SMCs (group/dataset)"], rows)
    out += ["", "## Unresolved macros", "",
            "Definitions that name a relation that is neither a predicate nor a concept/generator. No dataset "
            "uses them (the build fails otherwise).", ""]
    rows = [[section[:-1], f"`{key}`", ", ".join(f"`{n}`" for n in names)]
            for section, table in catalog["unresolved_macros"].items() for key, names in table.items()]
    out += _table(["kind", "name", "undefined"], rows) if rows else ["None."]
    out += ["", "## Other quirks of the original files", "",
            "Curriculum entries whose name does not start with their target dataset's name (kept as written):", ""]
    rows = [[f"`{stem}`", f"`{e['name']}`", f"`{e['dataset']}`"] for stem, info in catalog["curricula"].items()
            for e in info["entries"] if not e["name"].startswith(e["dataset"])]
    out += _table(["curriculum", "entry", "target dataset"], rows) if rows else ["None."]
    out += ["", "Concepts/generators defined twice (same logic up to whitespace; the later definition is kept):",
            ""]
    rows = [[f"`{key}`", f"`{info['replaced']}`", f"`{info['kept']}`"]
            for key, info in catalog["redefinitions"].items()]
    out += _table(["name", "first definition", "kept definition"], rows) if rows else ["None."]
    return "\n".join(out) + "\n"


def outputs(reference: Path) -> dict[Path, str]:
    """Path -> the text a fresh build would write there."""
    catalog = build_catalog(reference)
    return {CATALOG_PATH: render_json(catalog), DOCS_PATH: render_docs(catalog)}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--reference", type=Path, default=None,
                        help="folder holding aaai18/ (default: $PIXELWORLD_REFERENCE or ../shared/reference)")
    parser.add_argument("--check", action="store_true", help="only compare; exit 1 if a file is out of date")
    args = parser.parse_args(argv)
    reference = args.reference or default_reference()
    try:
        texts = outputs(reference)
    except (BuildError, ValueError) as exc:
        print(f"build_catalog: {exc}", file=sys.stderr)
        return 2
    stale = []
    for path, text in texts.items():
        current = path.read_text(encoding="utf-8") if path.is_file() else None
        if current == text:
            continue
        stale.append(path)
        if args.check:
            diff = difflib.unified_diff((current or "").splitlines(), text.splitlines(), str(path), "rebuild",
                                        lineterm="", n=1)
            print("\n".join(list(diff)[:40]), file=sys.stderr)
        else:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(text, encoding="utf-8")
    rel = ", ".join(str(p.relative_to(ROOT)) if p.is_relative_to(ROOT) else str(p) for p in stale)
    if args.check:
        if stale:
            print(f"build_catalog: out of date: {rel} (run python tools/build_catalog.py)", file=sys.stderr)
            return 1
        print("build_catalog: catalog and docs are up to date")
        return 0
    print(f"build_catalog: wrote {rel}" if stale else "build_catalog: nothing to do (already up to date)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
