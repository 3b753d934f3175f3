"""Adding SMCs one by one to a large library, as a run's process does after each finished job: this tree beside a
baseline checkout, in one run.

Copies the library of a run (``RUN/library``) to a temporary folder and adds ``--adds`` SMCs to it with
``storage.add_to_library`` (each a copy of the library's first entry under a new name, its model file the same), in
each tree in its own subprocess (``PYTHONPATH`` = the tree), alternating, ``--repeats`` rounds; then checks that
both trees wrote the same manifest bytes. Reported: seconds per add, median over the rounds.

Run: ``python benchmarks/bench_library_add.py RUN [--adds 5] [--repeats 3] [--baseline PATH]``; make a baseline
checkout with ``git worktree add /tmp/baseline <commit>``.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]

_ADD = """
import json, sys, time
from pathlib import Path
from sb3_smc.library import storage
root, adds = Path(sys.argv[1]), int(sys.argv[2])
saved = json.loads((root / "manifest.json").read_text())["smcs"]
first = saved[next(iter(saved))]
entry = {k: v for k, v in first.items() if k not in ("model", "sha256", "entry_sha256")}
model = (root / first["model"]).read_bytes()
begin = time.perf_counter()
for k in range(adds):
    storage.add_to_library(root, f"added-{k}", {**entry, "spec": {**entry["spec"], "name": f"added-{k}"}}, model)
print(json.dumps({"seconds": (time.perf_counter() - begin) / adds}))
"""


def add_in(tree: Path, library: Path, adds: int) -> tuple[float, str]:
    with tempfile.TemporaryDirectory() as folder:
        copy = Path(shutil.copytree(library, Path(folder) / "library"))
        env = dict(os.environ, PYTHONPATH=str(tree), OMP_NUM_THREADS="1")
        out = subprocess.run([sys.executable, "-c", _ADD, str(copy), str(adds)], env=env, capture_output=True,
                             text=True, check=True, cwd=tree)
        digest = hashlib.sha256((copy / "manifest.json").read_bytes()).hexdigest()
        return json.loads(out.stdout.strip().splitlines()[-1])["seconds"], digest


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("run", type=Path, help="a run directory (its library/ is copied)")
    parser.add_argument("--adds", type=int, default=5)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--baseline", type=Path, default=None, help="a checkout to time beside this tree")
    args = parser.parse_args()
    library = args.run / "library"
    if not (library / "manifest.json").is_file():
        parser.error(f"{library / 'manifest.json'} not found: give a run directory")
    entries = len(json.loads((library / "manifest.json").read_text())["smcs"])
    trees = [("this tree", HERE)] + ([("baseline", args.baseline.resolve())] if args.baseline else [])
    rounds: dict[str, list[float]] = {label: [] for label, _ in trees}
    digests = set()
    for _ in range(args.repeats):
        for label, tree in trees:
            seconds, digest = add_in(tree, library, args.adds)
            rounds[label].append(seconds)
            digests.add(digest)
    print(f"{args.adds} adds to a library of {entries} SMCs; the same manifest bytes in every run: "
          f"{'yes' if len(digests) == 1 else 'NO'}\n")
    print("| tree | rounds: s per add | median |\n|---|---|---:|")
    for label, values in rounds.items():
        print(f"| {label} | {' / '.join(f'{v:.3f}' for v in values)} | {statistics.median(values):.3f} |")


if __name__ == "__main__":
    main()
