"""How long the whole few-shot table trains on 2 cores, measured on a sample of its groups and projected, beside
what its committed records say they took.

The table (``sb3_smc.experiments.few_shot``) is 475 groups of five seeds (a target, a method and ``N``; the search
target has no curr entry) and 75 CNN cells a ``N``. Its strata are ``N`` x method x kind (and ``N`` for the CNN);
from each, ``--per-stratum`` groups are drawn (seeded, the same on every machine) and trained exactly as
``tools/few_shot_table.py`` trains them (``learn_concepts``: the seeds in one ``train_smcs`` group, the lean update,
one torch thread), in ``--workers`` processes side by side, as the table runs. Each stratum's mean group time times
its number of groups in the table, summed and divided by the workers, is the projection for the whole table on that
many cores (training, the automatic choice and the test; the training alone beside it). Each drawn group's test
scores are checked against the committed records (``docs/results/few_shot/records``): the same seeds must give the
same scores on any machine. The records' own training times (the cells' ``wall_time_s``, from runs beside other
work) are summed beside the projection, and their ratio to the measured training on the drawn groups is given.

Run: ``OMP_NUM_THREADS=1 python benchmarks/bench_few_shot_table.py [--per-stratum 1] [--workers 2] [--seed 0]
[--worlds 1,2]`` (``--worlds``: those ``N`` only, the projection theirs); pause any background run first.
"""

from __future__ import annotations

import argparse
import json
import random
import time
from collections import defaultdict
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

RECORDS = Path(__file__).resolve().parent.parent / "docs" / "results" / "few_shot" / "records"
SEEDS = tuple(range(5))


def _groups() -> dict[tuple[Any, str, str], list[str]]:
    """The table's groups by stratum (N, method, kind) -> targets; the CNN as method ``cnn``."""
    from pixelworld_env.datasets import catalog
    from sb3_smc.experiments.few_shot import FEW_SHOT_METHODS, FEW_SHOT_TARGETS, FEW_SHOT_WORLDS, offer_for
    from sb3_smc.library import SMCLibrary
    from sb3_smc.library.pretrained import pretrained_root

    library = SMCLibrary.load(pretrained_root())
    strata: dict[tuple[Any, str, str], list[str]] = defaultdict(list)
    for n in FEW_SHOT_WORLDS:
        for method in FEW_SHOT_METHODS:
            for target in FEW_SHOT_TARGETS:
                kind = catalog.dataset(target).kind
                if method == "cnn" and kind != "classification":
                    continue
                if method != "cnn" and offer_for(target, method, library) is None:
                    continue
                strata[(n, method, kind)].append(target)
    return strata


def _recorded(target: str, method: str, n: int | None) -> tuple[list[float] | None, float | None]:
    """The committed records' test scores and summed training seconds of a group (``None`` where not recorded)."""
    from sb3_smc.experiments.few_shot import record_score, record_training_s

    files = [RECORDS / target / f"{method}-n{n or 'all'}@{seed}.json" for seed in SEEDS]
    if not all(f.is_file() for f in files):
        return None, None
    data = [json.loads(f.read_text(encoding="utf-8")) for f in files]
    return [record_score(d) for d in data], sum(record_training_s(d) for d in data)


def _time_group(target: str, method: str, n: int | None) -> tuple[float, float, list[float]]:
    """Wall seconds of one group as the table trains it (``group_records``), its training seconds and test scores."""
    from sb3_smc.common.threads import compute_threads
    from sb3_smc.experiments.few_shot import group_records, record_score, record_training_s
    from sb3_smc.library import SMCLibrary
    from sb3_smc.library.pretrained import pretrained_root

    library = SMCLibrary.load(pretrained_root())
    with compute_threads(1):
        start = time.perf_counter()
        records = list(group_records(target, method, n, SEEDS, library, printer=lambda _: None))
        seconds = time.perf_counter() - start
    assert len(records) == len(SEEDS)  # drawn from the groups the table runs
    return seconds, sum(map(record_training_s, records)), [record_score(r) for r in records]


def _warm(_: int) -> None:
    """Compile the kernels in a worker, outside the timings."""
    from sb3_smc.fewshot import learn_concept

    learn_concept("PW-cl_self-in-container_vs_noncontainer-v0", library="pretrained", offer="none", train_worlds=2,
                  total_timesteps=2000, printer=lambda _: None)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--per-stratum", type=int, default=1, help="groups drawn from each stratum")
    parser.add_argument("--workers", type=int, default=2, help="processes side by side (the table runs two)")
    parser.add_argument("--seed", type=int, default=0, help="the draw's seed")
    parser.add_argument("--worlds", help="comma-separated N to measure (all: every world; default: the table's)")
    args = parser.parse_args()
    if args.per_stratum < 1 or args.workers < 1:
        parser.error("--per-stratum and --workers must be at least 1")
    strata = _groups()
    if args.worlds:
        wanted = {None if w == "all" else int(w) for w in args.worlds.split(",")}
        strata = {s: targets for s, targets in strata.items() if s[0] in wanted}  # the projection: those N only
    rng = random.Random(args.seed)
    drawn = [(stratum, target) for stratum, targets in strata.items()
             for target in rng.sample(targets, min(args.per_stratum, len(targets)))]
    print(f"{len(drawn)} groups drawn from {len(strata)} strata ({sum(map(len, strata.values()))} groups in the "
          f"table), {args.workers} workers", flush=True)
    measured: dict[tuple[Any, str, str], list[tuple[float, float]]] = defaultdict(list)
    rows, same, compared, ratio_parts = [], 0, 0, [0.0, 0.0]
    with ProcessPoolExecutor(args.workers) as pool:
        list(pool.map(_warm, range(args.workers)))
        futures = [(stratum, target, pool.submit(_time_group, target, stratum[1], stratum[0]))
                   for stratum, target in drawn]
        for done, (stratum, target, future) in enumerate(futures, 1):
            seconds, training, scores = future.result()
            measured[stratum].append((seconds, training))
            recorded_scores, recorded_training = _recorded(target, stratum[1], stratum[0])
            agrees = "-" if recorded_scores is None else ("yes" if recorded_scores == scores else "NO")
            if recorded_scores is not None:
                compared += 1
                same += agrees == "yes"
            if recorded_training is not None:
                ratio_parts[0] += recorded_training
                ratio_parts[1] += training
            n, method, kind = stratum
            rows.append(f"| {n or 'all'} | {method} | {kind} | {target} | {seconds:.0f} | {training:.0f} | "
                        f"{'-' if recorded_training is None else f'{recorded_training:.0f}'} | {agrees} |")
            print(f"[{done}/{len(drawn)}] {rows[-1]}", flush=True)
    total = sum(len(strata[s]) * sum(t for t, _ in v) / len(v) for s, v in measured.items()) / args.workers
    training = sum(len(strata[s]) * sum(t for _, t in v) / len(v) for s, v in measured.items()) / args.workers
    recorded_all = sum(_recorded(t, s[1], s[0])[1] or 0.0 for s, targets in strata.items() for t in targets)
    print("\n| N | method | kind | target | group (s) | training (s) | recorded training (s) | same scores |\n"
          "|---|---|---|---|---:|---:|---:|---|\n" + "\n".join(rows))
    print(f"\nprojected for the whole table on {args.workers} cores: {total / 3600:.2f} h "
          f"(training alone {training / 3600:.2f} h)")
    print(f"the committed records' training, summed: {recorded_all / 3600:.2f} core-hours "
          f"({recorded_all / 3600 / args.workers:.2f} h on {args.workers} cores)")
    if ratio_parts[1]:
        print(f"on the drawn groups the records' training took {ratio_parts[0] / ratio_parts[1]:.2f}x the measured")
    print(f"test scores equal to the records' on {same} of {compared} recorded groups")


if __name__ == "__main__":
    main()
