#!/usr/bin/env python
"""Build the compact reference fixture that the test suite carries (``tests/data/reference/``).

The full reference (the original AAAI-18 shape library and 8,700 generated environments with their labels, decoded
to JSON: ``aaai18_samples/``) lies outside the repository. The tests of shapes, inside regions, scenes, generation
and label fidelity run on this fixture when it is missing, so that a fresh clone passes its tests:

* ``shape_library.json.gz`` -- the original shape templates and their inside-region annotations, whole;
* ``samples/<dataset>.jsonl.gz`` -- for each of the 125 datasets, a header (the dataset, its kind, its definition
  and the original file's size and checksum) and its first :data:`PER_LABEL` samples of each label, unchanged;
* ``manifest.json`` -- what was taken from where: every source file's SHA-256, so that ``--check`` finds a fixture
  that no longer matches the reference.

Usage::

    python tools/build_fixture.py [--reference DIR]           # (re)write the fixture
    python tools/build_fixture.py [--reference DIR] --check   # exit 1 if the fixture differs from a rebuild

``--reference`` defaults to ``$PIXELWORLD_REFERENCE`` or ``../shared/reference`` beside the checkout. The build is
deterministic (sorted keys, gzip without a time stamp), so a rebuild of unchanged inputs writes the same bytes.
"""

from __future__ import annotations

import argparse
import gzip
import hashlib
import io
import json
import shutil
import sys
import tempfile
from pathlib import Path
from typing import Any

TOOLS = Path(__file__).resolve().parent
if str(TOOLS) not in sys.path:
    sys.path.insert(0, str(TOOLS))

from build_catalog import ROOT, default_reference  # noqa: E402  (the one place the reference's default is)

FIXTURE = ROOT / "tests" / "data" / "reference"
FORMAT = "pixelworld-reference-fixture"
VERSION = 1
PER_LABEL = 4
"""Samples kept of each label of a dataset (bring-about datasets have one label)."""
HEADER_KEYS = ("record", "dataset", "kind", "num_samples", "num_positive", "num_negative", "world", "definition")
"""What a fixture file's header keeps of the original's (the rest describes how the original was decoded)."""


def _gzip(text: str) -> bytes:
    """``text`` gzipped with no file name or time stamp (the same bytes for the same text)."""
    buffer = io.BytesIO()
    with gzip.GzipFile(filename="", mode="wb", fileobj=buffer, mtime=0) as handle:
        handle.write(text.encode("utf-8"))
    return buffer.getvalue()


def _line(record: dict[str, Any]) -> str:
    return json.dumps(record, sort_keys=True, separators=(",", ":")) + "\n"


def _kept(samples: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The first :data:`PER_LABEL` samples of each label, in file order."""
    taken: dict[int, int] = {}
    kept = []
    for sample in samples:
        label = sample["label"]
        if taken.get(label, 0) < PER_LABEL:
            taken[label] = taken.get(label, 0) + 1
            kept.append(sample)
    return kept


def outputs(reference: Path) -> dict[str, bytes]:
    """Every fixture file (path relative to the fixture folder -> bytes) built from ``reference``."""
    samples_dir = reference / "aaai18_samples"
    index = samples_dir / "index.json"
    if not index.is_file():
        raise SystemExit(f"build_fixture: {index} not found: give --reference (the folder holding aaai18_samples/) "
                         "or set PIXELWORLD_REFERENCE")
    files: dict[str, bytes] = {}
    sources: dict[str, str] = {}
    library = samples_dir / "shape_library.json.gz"
    files["shape_library.json.gz"] = library.read_bytes()
    sources["shape_library.json.gz"] = hashlib.sha256(library.read_bytes()).hexdigest()
    for path in sorted(samples_dir.glob("*.jsonl.gz")):
        if "__cache-" in path.name:  # a second cache file of a dataset already taken (identical samples)
            continue
        raw = path.read_bytes()
        lines = gzip.decompress(raw).decode("utf-8").splitlines()
        header = json.loads(lines[0])
        if header.get("record") != "dataset":
            raise SystemExit(f"build_fixture: {path}: line 1 is not a dataset header (record {header.get('record')!r})")
        samples = [json.loads(line) for line in lines[1:]]
        kept = {key: header[key] for key in HEADER_KEYS if key in header}
        kept["source"] = {"file": path.name, "sha256": hashlib.sha256(raw).hexdigest(), "samples": len(samples)}
        chosen = _kept(samples)
        files[f"samples/{path.name}"] = _gzip("".join(_line(r) for r in [kept, *chosen]))
        sources[path.name] = kept["source"]["sha256"]
    manifest = {"format": FORMAT, "version": VERSION, "per_label": PER_LABEL,
                "built_by": "tools/build_fixture.py", "sources": sources}
    files["manifest.json"] = (json.dumps(manifest, indent=1, sort_keys=True) + "\n").encode("utf-8")
    return files


def _differences(files: dict[str, bytes], folder: Path) -> list[str]:
    """The fixture files that are missing, differ or are left over in ``folder``."""
    present = {p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file()} if folder.is_dir() else set()
    wrong = [name for name, data in files.items()
             if name not in present or (folder / name).read_bytes() != data]
    return sorted(wrong + sorted(present - set(files)))


def write(files: dict[str, bytes], folder: Path) -> None:
    """Replace ``folder`` with ``files``: written beside it, then renamed into place."""
    folder.parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".{folder.name}-", dir=folder.parent))
    for name, data in files.items():
        (staging / name).parent.mkdir(parents=True, exist_ok=True)
        (staging / name).write_bytes(data)
    old = folder.with_name(f".{folder.name}-old")
    if folder.exists():
        folder.rename(old)
    staging.rename(folder)
    shutil.rmtree(old, ignore_errors=True)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--reference", type=Path, default=None,
                        help="folder holding aaai18_samples/ (default: $PIXELWORLD_REFERENCE or ../shared/reference)")
    parser.add_argument("--out", type=Path, default=FIXTURE, help=f"the fixture folder (default: {FIXTURE})")
    parser.add_argument("--check", action="store_true", help="exit 1 if the fixture differs from a rebuild")
    args = parser.parse_args(argv)
    reference = args.reference or default_reference()
    if not (reference / "aaai18_samples" / "index.json").is_file():
        print(f"build_fixture: no reference at {reference} (aaai18_samples/index.json missing): give --reference "
              "or set PIXELWORLD_REFERENCE", file=sys.stderr)
        return 2
    files = outputs(reference)
    differences = _differences(files, args.out)
    if args.check:
        if differences:
            print(f"build_fixture: {args.out} differs from a rebuild from {reference}: {', '.join(differences[:5])}"
                  f"{' ...' if len(differences) > 5 else ''} ({len(differences)} file(s)); run tools/build_fixture.py",
                  file=sys.stderr)
            return 1
        print(f"build_fixture: {args.out} is up to date ({len(files)} files)")
        return 0
    if differences:
        write(files, args.out)
    size = sum(len(d) for d in files.values())
    print(f"build_fixture: {args.out}: {len(files)} files, {size / 1024:.0f} KiB "
          f"({len(differences)} changed)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
