"""The structure docs/architecture.md describes: no module imports one that imports it back (imports inside
functions and under TYPE_CHECKING included), and no module of either package over 600 lines."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from sb3_smc.dag import CycleError, children_first

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


def test_the_cycle_check_sees_imports_inside_functions():
    graph = import_graph()
    assert "sb3_smc.policies" in graph["sb3_smc.library.library"]  # imported in SMCLibrary.load (it loads torch)
    graph["sb3_smc.library.storage"].append("sb3_smc.library.library")  # what an import back inside a function adds
    with pytest.raises(CycleError, match=r"sb3_smc\.library\.library -> .*sb3_smc\.library\.storage -> "
                                         r"sb3_smc\.library\.library"):
        children_first(graph)


def test_no_module_is_over_600_lines():
    long = {name: n for name, path in _modules().items()
            if (n := len(path.read_text(encoding="utf-8").splitlines())) > 600}
    assert long == {}
