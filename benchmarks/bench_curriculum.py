"""What the paper's whole protocol costs on this machine: measured jobs, then the estimated wall time.

Measures ``--updates`` updates (2,000 steps each, one torch thread) of three kinds of curriculum job, through the
same ``run_job`` the curriculum trainer ships to workers:

* a flat job (``cl_self-in-container_vs_noncontainer``, no children);
* a hand-designed level-2 job: 4 lower-level nodes x 2 seeds (``two_best``) = 8 SMC actions, the median size of
  the smc-curr entries;
* a canonical level-2 job: the 13 nodes of the canonical containment list x 2 seeds = 26 SMC actions.

Children are untrained (signal-biased) SMCs, whose calls last ~41 decisions as early in training: trained children
answer in a few steps, so level-2 rates later in training are higher and the estimate is an upper bound.

Then it counts the jobs of the paper's protocol from the shipped curricula (every level-2 target; the flat
lower-level nodes and the flat baseline of every target (smc-base), smc-curr, smc-canon and both noprim variants;
5 seeds; 400,000 steps per job) and prints the estimated wall time with 1 and 2 workers (jobs packed perfectly, a
second worker on the second core).

Every kind is measured as the trainer runs it: ``--group`` seeds (default 5, the trainer's ``--group-size``) in one
group (``run_group``; decisions per second over the group; flat and level-2 nodes over flat ones group), or one job
alone with ``--group 1``. With ``--lean`` every job trains with the lean update (``lean_update=True``, the run
option ``--lean-update``).

With ``--trained`` the level-2 jobs are real entries with trained children instead: the first target of the shipped
``con2-ba`` (smc-curr, 4 nodes x 2 seeds) and of ``con2-ba-canon`` (smc-canon, 13 nodes x 2 seeds), calling the
shipped pretrained SMCs of their nodes (``SMCLibrary.pretrained``): the calls of real trained children, which walk
across the world (longer than the untrained children's in these entries).

Run: ``python benchmarks/bench_curriculum.py [--updates N] [--group K] [--lean] [--trained]``.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
from pathlib import Path

import torch

from pixelworld_env.datasets import catalog
from sb3_smc.curricula import shipped_curricula
from sb3_smc.curricula.designed import designed_curricula
from sb3_smc.curricula.format import SEED_SEPARATOR, Curriculum
from sb3_smc.curricula.jobs import Job, job_name, node_spec, run_group, run_job
from sb3_smc.learning.training import untrained_smc
from sb3_smc.library import SMCLibrary
from sb3_smc.library.pretrained import pretrained_names, pretrained_root
from sb3_smc.records import Budget, TaskSpec, TrainingSpec

TARGET = "cl_self-in-container_vs_noncontainer"
SEEDS = 5
TIMESTEPS = 400_000


def measure(library: Path, children: tuple[str, ...], updates: int, lean: bool = False, group: int = 1,
            entry: tuple[Curriculum, str] | None = None) -> float:
    """Decisions per second of a job with ``children`` (names in ``library``); ``group`` seeds of it trained
    together (``run_group``: the decisions of all over the group's time); ``entry``: the job is that curriculum's
    node (else a job on the flat target)."""
    def spec(seed: int) -> TrainingSpec:
        if entry is not None:
            return node_spec(entry[0].node(entry[1]), seed, children, timesteps=2000 * updates)
        return TrainingSpec(name=f"bench@{seed}", task=TaskSpec(f"PW-{TARGET}-v0").resolved(), seed=seed,
                            children=children, budget=Budget(2000 * updates))

    jobs = [Job(spec=spec(seed), library=str(library), lean_update=lean) for seed in range(group)]
    results = run_group(jobs) if group > 1 else [run_job(jobs[0])]
    return sum(r.record.total_timesteps for r in results) / sum(r.record.wall_time_s for r in results)


def pretrained_entry(name: str) -> tuple[tuple[Curriculum, str], tuple[str, ...]]:
    """The first target of the shipped curriculum ``name`` and the pretrained SMCs of the nodes it uses."""
    curriculum = shipped_curricula()[name]
    target = curriculum.targets[0]
    held = pretrained_names(name, pretrained_root())
    children = tuple(smc for used in curriculum.node(target).uses for smc in held
                     if smc.rsplit(SEED_SEPARATOR, 1)[0] == used)
    return (curriculum, target), children


def paper_curricula() -> dict[str, Curriculum]:
    """The shipped curricula of the paper's protocol (not those sb3-smc designed, such as ``pushable``)."""
    designed = designed_curricula()
    return {name: c for name, c in shipped_curricula().items() if name not in designed}


def protocol_jobs() -> dict[str, int]:
    """Jobs (node x seed) of the paper's whole protocol, by kind (the noprim curricula included)."""
    curricula = paper_curricula()
    two_level = [c for c in curricula.values() if c.method and c.method.split("-")[1] in ("curr", "canon")]
    targets = {c.node(t).task for c in two_level for t in c.targets}
    flat = {u for c in two_level for t in c.targets for u in c.node(t).uses} | targets  # + the smc-base of targets
    curr = sum(len(c.targets) for c in two_level if c.method.startswith("smc-curr"))
    canon = sum(len(c.targets) for c in two_level if c.method.startswith("smc-canon"))
    return {"flat": len(flat) * SEEDS, "curr": curr * SEEDS, "canon": canon * SEEDS}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--updates", type=int, default=10, help="updates (2,000 steps) per measured job")
    parser.add_argument("--group", type=int, default=SEEDS, help="seeds of a node trained together (1: alone)")
    parser.add_argument("--lean", action="store_true", help="the lean update")
    parser.add_argument("--trained", action="store_true", help="level-2 entries with trained (pretrained) children")
    args = parser.parse_args()
    torch.set_num_threads(1)
    canonical = [dataset for _, dataset in catalog.canonical_smc_lists()["canonical_containment_curriculum"]]
    curr_sizes = [len(c.node(t).uses) for c in paper_curricula().values() if c.method == "smc-curr"
                  for t in c.targets]
    with tempfile.TemporaryDirectory() as tmp:
        library = SMCLibrary()
        for k, name in enumerate(canonical):
            for seed in (0, 1):
                smc = untrained_smc(f"PW-{name}-v0", n_envs=1, seed=10 * k + seed,
                                name=job_name(name, seed))
                library.add(smc)
        path = library.save(Path(tmp) / "library")
        curr_children = tuple(job_name(n, s) for n in canonical[:4] for s in (0, 1))
        canon_children = tuple(job_name(n, s) for n in canonical for s in (0, 1))
        rates = {"flat": measure(path, (), args.updates, args.lean, args.group)}
        if args.trained:
            for kind, name in (("curr", "con2-ba"), ("canon", "con2-ba-canon")):
                entry, children = pretrained_entry(name)
                rates[kind] = measure(pretrained_root(), children, args.updates, args.lean, args.group, entry)
        else:
            rates["curr"] = measure(path, curr_children, args.updates, args.lean, args.group)
            rates["canon"] = measure(path, canon_children, args.updates, args.lean, args.group)
    jobs = protocol_jobs()
    seconds = {kind: TIMESTEPS / rates[kind] for kind in rates}
    print(f"\nmeasured: {args.updates} updates of 2,000 steps per job, 1 torch thread, torch {torch.__version__}"
          f"{', the lean update' if args.lean else ''}, seeds in groups of {args.group}; "
          f"smc-curr entries use {statistics.median(curr_sizes):.0f} nodes (median; {min(curr_sizes)}-"
          f"{max(curr_sizes)})\n")
    print("| job | decisions/s | s per 400k-step job | jobs in the protocol (x 5 seeds) | CPU hours |")
    print("|---|---:|---:|---:|---:|")
    labels = {"flat": "flat (lower-level nodes + smc-base targets)", "curr": "smc-curr (+ noprim), 8 SMC actions",
              "canon": "smc-canon (+ noprim), 26 SMC actions"}
    if args.trained:
        labels = {**labels, "curr": "smc-curr (+ noprim): con2-ba's first entry, 8 trained SMC actions",
                  "canon": "smc-canon (+ noprim): con2-ba-canon's first entry, 26 trained SMC actions"}
    total = 0.0
    for kind in ("flat", "curr", "canon"):
        count = jobs[kind]
        hours = count * seconds[kind] / 3600
        total += hours
        print(f"| {labels[kind]} | {rates[kind]:,.0f} | {seconds[kind]:,.0f} | {count} | {hours:,.1f} |")
    bound = "real entries, trained children" if args.trained else "untrained children"
    print(f"\nestimated wall time of the whole protocol: {total:,.1f} h with 1 worker, {total / 2:,.1f} h with 2 "
          f"workers ({bound})")


if __name__ == "__main__":
    main()
