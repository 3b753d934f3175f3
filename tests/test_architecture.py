"""The structure docs/architecture.md describes: no module imports one that imports it back (imports inside
functions and under TYPE_CHECKING included), no module of either package over 600 lines, and a predicate's facts
in its own entry of ``PREDICATES`` (generation keeps no table keyed by predicate names)."""

from __future__ import annotations

import ast
import importlib
from pathlib import Path

import pytest

from sb3_smc.core.dag import CycleError, children_first

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("pixelworld_env", "sb3_smc")


def _modules() -> dict[str, Path]:
    out = {}
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            parts = path.relative_to(ROOT).with_suffix("").parts
            out[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return out


def import_graph() -> dict[str, list[str]]:
    """Module -> the package modules it imports anywhere in its file (``from a import b`` names the module ``a.b``
    where there is one, else ``a``)."""
    modules = _modules()
    graph: dict[str, list[str]] = {}
    for name, path in modules.items():
        edges: list[str] = []
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                edges += [alias.name for alias in node.names if alias.name in modules]
            elif isinstance(node, ast.ImportFrom) and node.module in modules and node.level == 0:
                edges += [f"{node.module}.{a.name}" if f"{node.module}.{a.name}" in modules else node.module
                          for a in node.names]
        graph[name] = sorted(set(edges) - {name})
    return graph


def test_the_import_graph_has_no_cycle():
    try:
        children_first(import_graph())
    except CycleError as err:
        pytest.fail(f"modules import each other: {err}")


LAYERS = (("pixelworld_env",), ("sb3_smc.common",), ("sb3_smc.core", "sb3_smc.recurrent_trpo"), ("sb3_smc.tasks",),
          ("sb3_smc.records", "sb3_smc.examples"), ("sb3_smc.smc",), ("sb3_smc.envs",),
          ("sb3_smc.learning", "sb3_smc.library"), ("sb3_smc.curricula", "sb3_smc.zoo", "sb3_smc.fewshot"),
          ("sb3_smc.experiments",),
          ("sb3_smc.cli", "sb3_smc.demo"))
"""The stages of docs/architecture.md, lowest first (the packages of one stage do not import each other)."""


def _stage(module: str) -> tuple[int, str] | None:
    """The stage of ``module`` (its index in :data:`LAYERS`) and its package there; ``None`` outside them."""
    found = [(k, p) for k, stage in enumerate(LAYERS) for p in stage if module == p or module.startswith(p + ".")]
    return found[0] if found else None


def test_the_data_flows_one_way_through_the_stages():
    """No module of a stage imports one of a later stage, or of another package of its own stage (the library does
    not import the curricula, training does not import the library, ...)."""
    against = []
    for module, edges in import_graph().items():
        here = _stage(module)
        against += [f"{module} -> {e}" for e in edges if here is not None and (there := _stage(e)) is not None
                    and (there[0] > here[0] or (there[0] == here[0] and there[1] != here[1]))]
    assert against == [], f"imports against the flow: {against}"
    assert _stage("sb3_smc.library.pretrained") == (7, "sb3_smc.library")
    assert _stage("sb3_smc.curricula.shipped") == (8, "sb3_smc.curricula") and _stage("sb3_smc.errors") is None


def test_the_cycle_check_sees_imports_inside_functions():
    graph = import_graph()
    assert "sb3_smc.smc.policies" in graph["sb3_smc.library.library"]  # imported in SMCLibrary.load (it loads torch)
    graph["sb3_smc.library.storage"].append("sb3_smc.library.library")  # what an import back inside a function adds
    with pytest.raises(CycleError, match=r"sb3_smc\.library\.library -> .*sb3_smc\.library\.storage -> "
                                         r"sb3_smc\.library\.library"):
        children_first(graph)


def test_no_module_is_over_600_lines():
    long = {name: n for name, path in _modules().items()
            if (n := len(path.read_text(encoding="utf-8").splitlines())) > 600}
    assert long == {}


def _predicate_names_in(path: Path) -> list[tuple[int, str]]:
    """(line, name) of every string literal of the file that names a predicate (docstrings aside), but the shape
    families: a family is a fact of the shape library (``sampling.FRAME_EXEMPT``: the families that may touch the
    frame) before it is a predicate."""
    from pixelworld_env.concepts.predicates import PREDICATES
    from pixelworld_env.core.shapes import FAMILIES

    names = set(PREDICATES) - set(FAMILIES)
    tree = ast.parse(path.read_text(encoding="utf-8"))
    docstrings = {id(node.body[0].value) for node in ast.walk(tree)
                  if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef)
                  and node.body and isinstance(node.body[0], ast.Expr) and isinstance(node.body[0].value, ast.Constant)}
    return [(node.lineno, node.value) for node in ast.walk(tree)
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value in names
            and id(node) not in docstrings]


def test_generation_keeps_no_table_keyed_by_predicate_names():
    """Everything generation knows of a predicate (its placement bound, its conjuncts, whether it is expensive,
    whether it reads ``shape_idx``) is in the predicate's entry (``PredicateSpec.generation``): no module of
    ``pixelworld_env/generation`` names a predicate in its code, so adding a predicate is one entry in
    ``concepts/predicates.py``."""
    found = {path.name: hits for path in sorted((ROOT / "pixelworld_env" / "generation").glob("*.py"))
             if (hits := _predicate_names_in(path))}
    assert found == {}, f"generation names predicates (their facts belong in the entry's GenerationFacts): {found}"
    placement = importlib.import_module("pixelworld_env.generation.placement")
    sampling = importlib.import_module("pixelworld_env.generation.sampling")
    assert not {"BOUNDS", "CONJUNCTS"} & set(vars(placement)), "the old tables are back in generation/placement.py"
    assert "_SHAPE_IDX_PREDICATES" not in vars(sampling)


def test_the_scan_sees_a_table_keyed_by_predicate_names(tmp_path):
    module = tmp_path / "table.py"
    module.write_text('"""A docstring naming touches."""\n\nBOUNDS = {"touches": None}\n'
                      'CHEAP = lambda c: c.name in ("near", "inside")\nEXEMPT = frozenset({"floor_shape", "wall"})\n')
    assert _predicate_names_in(module) == [(3, "touches"), (4, "near"), (4, "inside")]


def test_every_predicate_entry_has_its_generation_facts():
    from pixelworld_env.concepts.predicates import PREDICATES, GenerationFacts

    for name, spec in PREDICATES.items():
        assert spec.name == name and isinstance(spec.generation, GenerationFacts), name
        facts = spec.generation
        assert facts.bound is None or callable(facts.bound), name
        assert isinstance(facts.expensive, bool) and isinstance(facts.shape_idx, bool), name
        for conjunct, positions in facts.conjuncts:  # a binary predicate at two of the clause's argument positions
            assert PREDICATES[conjunct].arity == 2 and len(positions) == 2, (name, conjunct)
            assert all(0 <= i < spec.arity for i in positions), (name, conjunct, positions)
    with_bounds = {name for name, spec in PREDICATES.items() if spec.generation.bound is not None}
    assert {"floor", "touches", "on_top", "inside_supported", "h_between"} <= with_bounds
    assert {name for name, spec in PREDICATES.items() if spec.generation.conjuncts} == {"h_between", "v_between"}
