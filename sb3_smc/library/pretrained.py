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
"seeds": {node: n}}``: the nodes each curriculum calls, the SMCs (best seeds) that stand for each node, and how many
seeds of its run those were ranked among."""


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
        return {"curricula": {}, "nodes": {}, "seeds": {}}
    try:
        index = json.loads(path.read_text(encoding="utf-8"))
        curricula, nodes, seeds = index["curricula"], index["nodes"], index["seeds"]
        ok = all(isinstance(v, list) and all(isinstance(n, str) and n in nodes for n in v) for v in curricula.values())
        ok = ok and all(isinstance(v, list) and all(isinstance(n, str) for n in v) for v in nodes.values())
        ok = ok and set(seeds) == set(nodes) and all(type(n) is int and n >= len(nodes[k]) for k, n in seeds.items())
    except (ValueError, KeyError, TypeError, AttributeError) as err:
        raise ManifestError(f"{path} is damaged ({type(err).__name__}: {err})") from None
    if not ok:
        raise ManifestError(f"{path}: expected {{'curricula': {{name: [nodes]}}, 'nodes': {{node: [SMC names]}}, "
                            "'seeds': {node: seeds ranked among}}, every node of a curriculum among 'nodes'")
    held = set(_names(root) if names is None else names)
    missing = sorted({name for names in nodes.values() for name in names} - held)
    if missing:
        raise ManifestError(f"{path} names SMCs that are not in the library: {missing}")
    return index


def pretrained_curricula(root: str | Path | None = None) -> list[str]:
    """The curricula whose lower-level SMCs the pretrained library in ``root`` (the package's by default) holds."""
    return list(pretrained_index(root)["curricula"])


def pretrained_names(curriculum: str, root: str | Path | None = None) -> list[str]:
    """The SMC names (``<node>@<seed>``) the pretrained library holds for ``curriculum``'s lower-level nodes, in the
    library's order."""
    root = pretrained_root() if root is None else Path(root)
    names = _names(root) if (root / storage.MANIFEST).is_file() else []
    index = pretrained_index(root, names)
    if curriculum not in index["curricula"]:
        available = list(index["curricula"])
        raise LibraryError(f"no pretrained SMCs for curriculum {curriculum!r}"
                           f"{suggest(curriculum, available, ' (none is shipped yet)')}; pretrained: "
                           f"{', '.join(available) or 'none'}")
    wanted = {name for node in index["curricula"][curriculum] for name in index["nodes"][node]}
    return [name for name in names if name in wanted]


def _names(root: Path) -> list[str]:
    """The SMC names of the library in ``root``, in its order (its manifest checked)."""
    return list(storage.check_manifest(*storage.read_manifest(root)))
