"""The pretrained library shipped with the package: the lower-level SMCs of the paper's curricula (the two best seeds
of each node, as a caller of the curriculum gets them), loaded by curriculum name and put on an environment as
actions without training anything::

    library = SMCLibrary.pretrained("search2-canon")       # its 13 canonical SMCs x their 2 best seeds
    env = library.wrap(gym.make("PW-ba_self-in-target-container_from_nontarget-container-v0"), library.names)

Each SMC keeps its training spec, training record and test evaluation (the paper's protocol: every test environment
10 times, seed 0). The models are compact: the optimiser state that only further training would use is dropped and
the archive compressed; the policy's weights are exactly those trained, so an SMC acts as it did in its run.

Beside its manifest, a pretrained library holds ``pretrained.json``: for each curriculum, the nodes its targets
call, and for each node, the SMCs that stand for it (its best seeds). This module reads it;
:func:`sb3_smc.curricula.pretrained.build_pretrained` writes it (``tools/build_pretrained.py``); ``docs/library.md``
lists what is shipped and its size.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from importlib import resources
from pathlib import Path
from typing import Any

from sb3_smc.library import storage
from sb3_smc.library.errors import LibraryError, ManifestError, suggest

__all__ = ["INDEX", "pretrained_curricula", "pretrained_index", "pretrained_names", "pretrained_root"]

INDEX = "pretrained.json"
"""The index of a pretrained library: ``{"curricula": {curriculum: [nodes]}, "nodes": {node: [SMC names]},
"seeds": {node: n}, "partial": {curriculum: [nodes]}}``: the nodes each curriculum calls, the SMCs (best seeds) that
stand for each node, how many seeds of its run those were ranked among, and the lower-level nodes of each shipped
curriculum the library holds only some of (for the error that refuses it; absent in libraries built before it)."""


def pretrained_root() -> Path:
    """The package's pretrained library directory."""
    return Path(str(resources.files("sb3_smc.library").joinpath("data", "pretrained")))


def pretrained_index(root: str | Path | None = None, names: Sequence[str] | None = None) -> dict[str, Any]:
    """The index of the pretrained library in ``root`` (the package's by default; empty where there is none),
    checked against its manifest: every SMC it names is in the library (``names``: the library's SMC names, for a
    caller that has read its manifest already)."""
    root = pretrained_root() if root is None else Path(root)
    path = root / INDEX
    if not path.is_file():
        if (root / storage.MANIFEST).is_file():
            raise ManifestError(f"{root} is an SMC library without {INDEX} (the index of a pretrained library, "
                                "written by build_pretrained since manifest version 3): build it again with "
                                "tools/build_pretrained.py")
        return {"curricula": {}, "nodes": {}, "seeds": {}, "partial": {}}
    try:
        index = json.loads(path.read_text(encoding="utf-8"))
        curricula, nodes, seeds = index["curricula"], index["nodes"], index["seeds"]
        partial = index.setdefault("partial", {})
        ok = all(isinstance(v, list) and all(isinstance(n, str) and n in nodes for n in v) for v in curricula.values())
        ok = ok and all(isinstance(v, list) and all(isinstance(n, str) for n in v) for v in partial.values())
        ok = ok and all(isinstance(v, list) and all(isinstance(n, str) for n in v) for v in nodes.values())
        ok = ok and set(seeds) == set(nodes) and all(type(n) is int and n >= len(nodes[k]) for k, n in seeds.items())
    except (ValueError, KeyError, TypeError, AttributeError) as err:
        raise ManifestError(f"{path} is damaged ({type(err).__name__}: {err})") from None
    if not ok:
        raise ManifestError(f"{path}: expected {{'curricula': {{name: [nodes]}}, 'nodes': {{node: [SMC names]}}, "
                            "'seeds': {node: seeds ranked among}, 'partial': {name: [nodes]}}, every node of a "
                            "curriculum among 'nodes'")
    held = set(_names(root) if names is None else names)
    missing = sorted({name for names in nodes.values() for name in names} - held)
    if missing:
        raise ManifestError(f"{path} names SMCs that are not in the library: {missing}")
    return index


def pretrained_curricula(root: str | Path | None = None) -> list[str]:
    """The curricula whose lower-level SMCs the pretrained library in ``root`` (the package's by default) holds."""
    return list(pretrained_index(root)["curricula"])


def pretrained_names(curriculum: str, root: str | Path | None = None) -> list[str]:
    """The SMC names (``<node>@<seed>``) the pretrained library holds for ``curriculum``, in the library's order: a
    curriculum's lower-level nodes (one the index lists: it holds every node the curriculum's targets call), or the
    name of one node it holds (its best seeds; every shipped SMC is reachable so, also a node that no listed
    curriculum calls, such as ``cl_self-touches-container_vs_corner``). A shipped curriculum whose lower level the
    library holds in part (``con2-cl``) is refused with what is missing and the names that load."""
    root = pretrained_root() if root is None else Path(root)
    names = _names(root) if (root / storage.MANIFEST).is_file() else []
    index = pretrained_index(root, names)
    if curriculum in index["curricula"]:
        nodes = index["curricula"][curriculum]
    elif curriculum in index["nodes"]:
        nodes = [curriculum]
    else:
        raise LibraryError(_not_pretrained(curriculum, index))
    wanted = {name for node in nodes for name in index["nodes"][node]}
    return [name for name in names if name in wanted]


def _not_pretrained(name: str, index: dict[str, Any]) -> str:
    """Why ``name`` loads nothing: a shipped curriculum's lower level held in part (what is missing, and its nodes
    that load by name), or no curriculum or node of the library (close names); with the curricula that load."""
    available = list(index["curricula"])
    loads = (f"pretrained curricula: {', '.join(available) or 'none'}; or one of the {len(index['nodes'])} nodes "
             "it holds by name (pretrained_index()['nodes'])")
    lower = index["partial"].get(name)
    if lower is not None:
        held = [node for node in lower if node in index["nodes"]]
        missing = [node for node in lower if node not in index["nodes"]]
        return (f"no pretrained SMCs for curriculum {name!r}: the pretrained library holds {len(held)} of its "
                f"{len(lower)} lower-level nodes, not all (missing: {', '.join(missing)}), so it is not a pretrained "
                f"curriculum (a run of it with --reuse-from pretrained copies the nodes held and trains the rest); "
                + (f"load a node it holds by the node's name (held: {', '.join(held)}); " if held else "") + loads)
    hint = suggest(name, available, " (none is shipped yet)")
    return f"no pretrained SMCs for curriculum {name!r}{'' if hint.startswith('; it has') else hint}; {loads}"


def _names(root: Path) -> list[str]:
    """The SMC names of the library in ``root``, in its order (its manifest checked)."""
    return list(storage.checked_entries(root)[0])
