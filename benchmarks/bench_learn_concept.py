"""``learn_concept`` from a few worlds with the pretrained library, beside the flat SMC at the same number of worlds,
in one run: seconds per concept on one core (the choice, training and the test together) and the test score.

Targets: the two headline targets and three more of the few-shot table (both kinds), each learned from ``--worlds``
training worlds (default 4) with the automatic choice of pretrained SMCs (``auto``) and without SMCs (``flat``), the
two alternating target by target, one torch thread, the paper's budget unless ``--timesteps`` says otherwise.
Reported: a row per target and method, then the median seconds per concept of each method.

Run: ``OMP_NUM_THREADS=1 python benchmarks/bench_learn_concept.py [--worlds 4] [--timesteps N] [--targets a,b]``.
"""

from __future__ import annotations

import argparse
import statistics
import time

from sb3_smc.common.threads import compute_threads
from sb3_smc.fewshot import learn_concept
from sb3_smc.library import SMCLibrary
from sb3_smc.library.pretrained import pretrained_root

TARGETS = ("cl_self-left-of-two-objects-vs-one", "ba_self-in-container_from_between-potential-containers",
           "cl_self-in-container_vs_noncontainer", "ba_self-ontop-object_from_anywhere-on-floor",
           "cl_object-on-floor_vs_no-object")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--worlds", type=int, default=4)
    parser.add_argument("--timesteps", type=int, default=None)
    parser.add_argument("--targets", default=",".join(TARGETS))
    args = parser.parse_args()
    settings = {"total_timesteps": args.timesteps} if args.timesteps else {}
    library = SMCLibrary.load(pretrained_root())
    learn_concept("PW-cl_self-in-container_vs_noncontainer-v0", library=library, offer="auto", train_worlds=2,
                  total_timesteps=2000)  # compiles the kernels once, outside the timings
    seconds: dict[str, list[float]] = {"auto": [], "flat": []}
    print("| target | method | N | offered | seconds | steps trained | test % |\n|---|---|---|---|---|---|---|")
    with compute_threads(1):
        for target in args.targets.split(","):
            for method, offer in (("auto", "auto"), ("flat", "none")):
                begin = time.perf_counter()
                learned = learn_concept(f"PW-{target}-v0", library=library, offer=offer, train_worlds=args.worlds,
                                        lean_update=True, **settings)
                took = time.perf_counter() - begin
                seconds[method].append(took)
                smc = learned.smc
                assert smc.record is not None and smc.test_score is not None
                print(f"| {target} | {method} | {args.worlds} | {len(learned.offered)} | {took:.1f} | "
                      f"{smc.record.total_timesteps:,} | {100 * smc.test_score:.1f} |", flush=True)
    print()
    for method, values in seconds.items():
        print(f"{method}: median {statistics.median(values):.1f} s per concept over {len(values)} targets")


if __name__ == "__main__":
    main()
