"""Loading the pretrained library in its version-5 format (safetensors weights, the model rebuilt from its settings,
nothing unpickled) beside the same SMCs as a version-4 library of SB3 ``model.save`` archives (pickled, loaded with
``trust=True``), in one run.

The version-4 copy is written here from the loaded SMCs (``model.save``, the manifest's checksums recomputed); each
format is loaded ``--repeats`` times, alternating, each load in a fresh process (the manifest's per-process cache and
the imports paid in both). Reported: seconds per load (median), and that both give the same weights.

Run: ``OMP_NUM_THREADS=1 python benchmarks/bench_library_load.py [--repeats 5]``.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from sb3_smc.library import SMCLibrary, storage
from sb3_smc.library.pretrained import pretrained_root

_LOAD = """
import hashlib, json, sys, time
import torch
from sb3_smc.library import SMCLibrary
begin = time.perf_counter()
library = SMCLibrary.load(sys.argv[1], trust=sys.argv[2] == "trust")
seconds = time.perf_counter() - begin
digest = hashlib.sha256()
for name in sorted(library.names):
    for key, value in sorted(library[name].model.policy.state_dict().items()):
        digest.update(key.encode()); digest.update(value.numpy().tobytes())
print(json.dumps({"seconds": seconds, "digest": digest.hexdigest(), "smcs": len(library)}))
"""


def _old_copy(library: SMCLibrary, folder: Path) -> Path:
    (folder / "models").mkdir(parents=True)
    entries = {}
    for k, name in enumerate(library.names):
        file = folder / "models" / f"m{k}.zip"
        library[name].model.save(file)
        entries[name] = {"model": f"models/m{k}.zip", **storage.entry_for(library[name]),
                         "sha256": storage.sha256(file)}
    storage.write_manifest(folder / storage.MANIFEST, {**storage.new_manifest(entries), "version": 4})
    return folder


def _load(path: Path, trust: bool) -> dict:
    out = subprocess.run([sys.executable, "-c", _LOAD, str(path), "trust" if trust else "safe"], capture_output=True,
                         text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        old = _old_copy(SMCLibrary.load(pretrained_root()), Path(tmp) / "v4")
        times: dict[str, list[float]] = {"version 5 (safetensors, no pickle)": [], "version 4 (pickled, trust)": []}
        digests = set()
        for _ in range(args.repeats):
            for label, path, trust in ((next(iter(times)), pretrained_root(), False),
                                       (list(times)[1], old, True)):
                result = _load(path, trust)
                times[label].append(result["seconds"])
                digests.add(result["digest"])
        print(f"| format | seconds per load of the {result['smcs']} pretrained SMCs (median of {args.repeats}) |")
        print("|---|---|")
        for label, values in times.items():
            print(f"| {label} | {statistics.median(values):.2f} |")
        print(f"\nthe same weights in both: {len(digests) == 1}")


if __name__ == "__main__":
    main()
