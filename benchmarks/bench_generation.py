"""Dataset generation of the whole catalog from a cold cache, then loading it from the warm cache.

Single process. A temporary ``PIXELWORLD_CACHE`` is used (and removed afterwards unless ``--keep``), so
the first pass generates every dataset and writes its cache file, and the second pass only reads. Prints
one progress line per dataset, then a table: datasets/s, accepted samples/s, draws, time per dataset
(median, max, the slowest five) and the time to load the whole catalog from the warm cache.

The datasets come from the original AAAI-18 definition files (``../shared/reference/aaai18/DATA``), via
:func:`specs_from_reference`, or with ``--from-catalog`` from the project catalog
(:func:`specs_from_catalog`). Run:
``python benchmarks/bench_generation.py [--seed S] [--only SUBSTRING] [--keep DIR] [--from-catalog]``.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

from pixelworld_env.generation.dataset_spec import DatasetSpec
from pixelworld_env.generation.definitions import load_definitions

REFERENCE = Path(os.environ.get("PIXELWORLD_REFERENCE", Path(__file__).resolve().parents[2] / "shared" / "reference"))


def specs_from_reference(reference: Path = REFERENCE) -> list[DatasetSpec]:
    """One spec per dataset of the original definition files (136), sorted by name."""
    files = sorted((reference / "aaai18" / "DATA").glob("*.datasets"))
    if not files:
        raise SystemExit(f"no *.datasets files under {reference / 'aaai18' / 'DATA'} (set PIXELWORLD_REFERENCE)")
    definitions = load_definitions(files)
    return [definitions.dataset_spec(name) for name in sorted(definitions.datasets)]


def specs_from_catalog() -> list[DatasetSpec]:
    """One spec per dataset of the project catalog (``pixelworld_env.datasets.catalog``), sorted by name."""
    from pixelworld_env.datasets import catalog
    from pixelworld_env.datasets.loading import dataset_spec

    return [dataset_spec(name) for name in sorted(catalog.dataset_names())]


def run(specs: list[DatasetSpec], seed: int, out=sys.stdout) -> dict[str, float]:
    # Imported here so that PIXELWORLD_CACHE (set by main) is in force; cache_dir() reads it on every call.
    from pixelworld_env.datasets import cache

    times: list[tuple[float, str]] = []
    samples = draws = 0
    start = time.perf_counter()
    for i, spec in enumerate(specs, 1):
        t0 = time.perf_counter()
        dataset = cache.load_or_generate(spec, seed)
        elapsed = time.perf_counter() - t0
        times.append((elapsed, spec.name))
        samples += len(dataset)
        draws += dataset.draws
        print(f"[{i:3d}/{len(specs)}] {elapsed:6.3f} s  {len(dataset):3d} scenes  {dataset.draws:5d} draws  "
              f"{dataset.duplicates:3d} dup  {spec.name}", file=out, flush=True)
    total = time.perf_counter() - start

    t0 = time.perf_counter()
    loaded = [cache.load_or_generate(spec, seed) for spec in specs]
    load_time = time.perf_counter() - t0
    assert sum(len(d) for d in loaded) == samples

    per = sorted(t for t, _ in times)
    rows = [
        ("datasets", f"{len(specs)}"),
        ("accepted samples", f"{samples}"),
        ("generator draws", f"{draws}"),
        ("generation + cache write, total", f"{total:.2f} s"),
        ("datasets / s", f"{len(specs) / total:.2f}"),
        ("accepted samples / s", f"{samples / total:.0f}"),
        ("time per dataset, median", f"{statistics.median(per) * 1000:.0f} ms"),
        ("time per dataset, max", f"{per[-1] * 1000:.0f} ms"),
        ("load whole catalog from warm cache", f"{load_time:.2f} s"),
    ]
    width = max(len(k) for k, _ in rows)
    print("\n" + "\n".join(f"{k:<{width}}  {v}" for k, v in rows), file=out)
    print("slowest datasets:", file=out)
    for elapsed, name in sorted(times, reverse=True)[:5]:
        print(f"  {elapsed * 1000:7.0f} ms  {name}", file=out)
    return {"total_s": total, "load_s": load_time, "samples": samples, "datasets": len(specs)}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0, help="dataset generation seed (default 0)")
    parser.add_argument("--only", default="", help="only datasets whose name contains this text")
    parser.add_argument("--keep", type=Path, help="use (and keep) this cache folder instead of a temporary one")
    parser.add_argument("--from-catalog", action="store_true",
                        help="take the datasets from the project catalog instead of the reference definition files")
    args = parser.parse_args(argv)

    specs = [s for s in (specs_from_catalog() if args.from_catalog else specs_from_reference()) if args.only in s.name]
    if not specs:
        raise SystemExit(f"no dataset name contains {args.only!r}")
    folder = args.keep or Path(tempfile.mkdtemp(prefix="pixelworld-bench-"))
    if args.keep and args.keep.exists() and any(args.keep.iterdir()):
        raise SystemExit(f"--keep {args.keep}: the folder must be empty (the benchmark starts from a cold cache)")
    os.environ["PIXELWORLD_CACHE"] = str(folder)
    print(f"cold cache: {folder}; {len(specs)} datasets, seed {args.seed}, one process")
    try:
        run(specs, args.seed)
    finally:
        if args.keep is None:
            shutil.rmtree(folder, ignore_errors=True)


if __name__ == "__main__":
    main()
