#!/usr/bin/env python
"""Add the lower-level SMCs of curricula (shipped ones by name, or curriculum files) to the package's pretrained
library (``sb3_smc/library/data/pretrained``) from the libraries of finished runs: the two best seeds of each node,
evaluated on the test split and stored compact, with the index that loads them by curriculum name
(:func:`sb3_smc.curricula.pretrained.build_pretrained`).

Usage::

    python tools/build_pretrained.py --run runs/paper-search --curricula search2-canon [--out DIR] [--finished-only]

A run is an experiment or curriculum directory whose ``library/`` holds every seed of the curricula's lower-level
nodes (the ranking needs all of them); with ``--finished-only``, of a run still going, only the nodes whose seeds are
all trained are taken. What the pretrained library already holds is kept.
"""

from __future__ import annotations

import argparse
import sys

from sb3_smc.common.threads import compute_threads
from sb3_smc.curricula.pretrained import build_pretrained
from sb3_smc.library.pretrained import pretrained_index


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--run", action="append", required=True, help="a run directory (repeatable)")
    parser.add_argument("--curricula", required=True,
                        help="comma-separated curricula: shipped names or curriculum files")
    parser.add_argument("--out", default=None, help="the library directory (default: the package's)")
    parser.add_argument("--finished-only", action="store_true",
                        help="take only the nodes whose every seed is trained (of a run still going)")
    args = parser.parse_args(argv)
    with compute_threads(1):
        path = build_pretrained(args.run, [c for c in args.curricula.split(",") if c], args.out,
                                finished_only=args.finished_only)
    nodes = pretrained_index(path)["nodes"]
    print(f"wrote {path}: {sum(map(len, nodes.values()))} SMCs of {len(nodes)} nodes")
    return 0


if __name__ == "__main__":
    sys.exit(main())
