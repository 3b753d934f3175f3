"""The few-shot table's cells with their seeds trained together (``learn_concepts``, as ``tools/few_shot_table.py``
trains them) beside the same seeds one by one (``learn_concept`` per seed), in one run, which goes first
alternating cell by cell: wall seconds for the five
seeds of a target, method and ``N`` (the choice, training and the test together), and whether both give the same
test scores (they must: each grouped SMC is the one ``learn_concept`` gives).

Run: ``OMP_NUM_THREADS=1 python benchmarks/bench_few_shot_groups.py [--worlds 8] [--seeds 5] [--targets a,b]
[--methods base,curr]``; pause any background run first.
"""

from __future__ import annotations

import argparse
import time
from typing import Any

from sb3_smc.common.threads import compute_threads
from sb3_smc.experiments.few_shot import offer_for
from sb3_smc.fewshot import learn_concept, learn_concepts
from sb3_smc.library import SMCLibrary
from sb3_smc.library.pretrained import pretrained_root

TARGETS = ("cl_self-in-container_vs_noncontainer", "ba_self-in-container_from_on-floor")


def _scores(task: str, seeds: list[int], settings: dict[str, Any], *, together: bool) -> list[float | None]:
    """The test scores of ``seeds``, learned together (``learn_concepts``) or one by one (``learn_concept``)."""
    if together:
        return [one.smc.test_score for one in learn_concepts(task, seeds=seeds, **settings)]
    return [learn_concept(task, seed=seed, **settings).smc.test_score for seed in seeds]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--worlds", type=int, default=8)
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--targets", default=",".join(TARGETS))
    parser.add_argument("--methods", default="base,curr")
    args = parser.parse_args()
    library = SMCLibrary.load(pretrained_root())
    seeds = list(range(args.seeds))
    print("| target | method | N | seeds | one by one (s) | together (s) | ratio | same scores |\n"
          "|---|---|---:|---:|---:|---:|---:|---|")
    cell = 0
    with compute_threads(1):
        learn_concept(f"PW-{TARGETS[0]}-v0", library=library, offer="none", train_worlds=2,
                      total_timesteps=2000)  # compiles the kernels once, outside the timings
        for target in args.targets.split(","):
            for method in args.methods.split(","):
                offer = offer_for(target, method, library)
                if offer is None:
                    continue  # the pretrained library has no such entry for this target
                settings = {"library": library, "offer": offer, "train_worlds": args.worlds, "lean_update": True}
                cell += 1
                timed = {}
                for way in ("apart", "together") if cell % 2 else ("together", "apart"):  # alternating first
                    start = time.perf_counter()
                    scores = _scores(f"PW-{target}-v0", seeds, settings, together=way == "together")
                    timed[way] = (scores, time.perf_counter() - start)
                (alone, apart), (grouped, together) = timed["apart"], timed["together"]
                print(f"| {target} | {method} | {args.worlds} | {len(seeds)} | {apart:.0f} | {together:.0f} | "
                      f"{apart / together:.2f} | {'yes' if alone == grouped else 'NO'} |", flush=True)


if __name__ == "__main__":
    main()
