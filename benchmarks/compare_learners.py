"""Learner comparison (docs/learners.md): RecurrentPPO-LSTM, RecurrentPPO-GRU and RecurrentTRPO-GRU on six level-1
concepts and the two headline level-2 targets, seeds 0..N-1 at the paper's budget.

The level-2 SMCs get the children a curriculum run gave the same node and seed (its library, trained by the
curriculum trainer with the default learner), so the comparison isolates the learner of the SMC being trained.
RecurrentPPO-LSTM, the default learner, is not retrained: its SMCs are the curriculum run's own nodes, evaluated
here as the experiment evaluates them (same seed, so the level-2 scores equal the run's). ``--headline`` names the
run directories (repeat it): each SMC comes from the first whose library has it.

    python benchmarks/compare_learners.py --headline runs/headline --headline runs/headline-ba-curr-in \
        --out runs/learners --workers 2
    python benchmarks/compare_learners.py --out runs/learners --table

Every job's result is one JSON file in ``--out`` (re-run to resume); ``--table`` prints the markdown table.
Each worker uses one torch thread; wall times are those of ``--workers`` jobs side by side.
"""

from __future__ import annotations

import argparse
import json
import sys
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from statistics import mean

LEVEL1 = ("cl_self-in-left-corner_vs_on-hline", "cl_self-in-container_vs_outside",
          "cl_self-left-touches-container_vs_object", "ba_self-on-something_from_directly-above",
          "ba_self-in-container_from_adjacent-on-floor", "ba_self-left-touches-object_from_left-on-floor")
LEVEL2 = ("obj-con2-cl/cl_self-left-of-two-objects-vs-one-curr",
          "con2-ba/ba_self-in-container_from_between-potential-containers_curr-in")
LEARNERS = {"ppo-lstm": ("RecurrentPPO", "lstm"), "ppo-gru": ("RecurrentPPO", "gru"),
            "trpo-gru": ("RecurrentTRPO", "gru")}
REPEATS = 10


def result_path(out: str | Path, learner: str, node: str, seed: int) -> Path:
    """Where one job's result goes (``/`` of a node name encoded as the curriculum trainer encodes it)."""
    from sb3_smc.curricula.jobs import file_stem

    return Path(out) / f"{learner}__{file_stem(node)}__{seed}.json"


def library_with(headlines: list[str], job: str) -> Path:
    """The library of the first run directory in ``headlines`` that has the SMC ``job``."""
    from sb3_smc.library.storage import MANIFEST, check_manifest, read_manifest

    for headline in headlines:
        library = Path(headline) / "library"
        if (library / MANIFEST).is_file() and job in check_manifest(*read_manifest(library)):
            return library
    raise FileNotFoundError(f"no run in {headlines} has the SMC {job!r} in its library: train its curriculum first "
                            "(docs/learners.md)")


def run_one(headlines: list[str], out: str, learner: str, node: str, seed: int, timesteps: int) -> str:
    """Train (or, for ppo-lstm, take from the curriculum run) and evaluate one SMC; writes and returns its JSON."""
    import torch

    from pixelworld_env.atomic import atomic_write
    from sb3_smc.curricula.jobs import job_name
    from sb3_smc.learning.evaluation import evaluate
    from sb3_smc.learning.training import train_smc
    from sb3_smc.library import SMCLibrary

    torch.set_num_threads(1)
    path = result_path(out, learner, node, seed)
    if path.is_file():
        return str(path)
    headline_job = job_name(node, seed)
    library_dir = library_with(headlines, headline_job)
    if learner == "ppo-lstm":
        smc = SMCLibrary.load(library_dir, names=[headline_job])[headline_job]
    else:
        algo, rnn = LEARNERS[learner]
        env_id, children, primitives = f"PW-{node}-v0", None, True
        if node in LEVEL2:  # the children the headline run gave this node and seed
            reference = SMCLibrary.load(library_dir, names=[headline_job])[headline_job].spec
            library = SMCLibrary.load(library_dir, names=reference.children)
            env_id, primitives = reference.task.env_id, reference.wrapper.include_primitives
            children = [library[name] for name in reference.children]
        smc = train_smc(env_id, children=children, algo=algo, rnn=rnn, seed=seed, total_timesteps=timesteps,
                        include_primitives=primitives, name=f"{learner}:{headline_job}", log_every=0)
    result = evaluate(smc, repeats=REPEATS, seed=0, record_cells=False)
    record = smc.record
    row = {"learner": learner, "node": node, "seed": seed, "level": 2 if smc.spec.children else 1,
           "test_score": result.score, "training_return": record.selected_return,
           "wall_time_s": record.wall_time_s, "timesteps": record.total_timesteps,
           "steps_per_s": record.total_timesteps / record.wall_time_s}
    atomic_write(path, json.dumps(row, indent=2) + "\n")
    return str(path)


def table(out: Path) -> str:
    rows = [json.loads(p.read_text()) for p in sorted(out.glob("*.json"))]
    learners = [name for name in LEARNERS if any(r["learner"] == name for r in rows)]
    lines = ["| SMC | " + " | ".join(f"{name} best / mean" for name in learners) + " |",
             "|---|" + "---:|" * len(learners)]
    for node in (*LEVEL1, *LEVEL2):
        cells = []
        for name in learners:
            scores = [r["test_score"] for r in rows if r["learner"] == name and r["node"] == node]
            cells.append(f"{100 * max(scores):.1f} / {100 * mean(scores):.1f} ({len(scores)})" if scores else "-")
        lines.append(f"| {node.rpartition('/')[2]} | " + " | ".join(cells) + " |")
    for level in (1, 2):
        cells = []
        for name in learners:
            chosen = [r for r in rows if r["learner"] == name and r["level"] == level]
            nodes = sorted({r["node"] for r in chosen})
            best = [max(r["test_score"] for r in chosen if r["node"] == n) for n in nodes]
            cells.append(f"{100 * mean(best):.1f} / {100 * mean(r['test_score'] for r in chosen):.1f}"
                         if chosen else "-")
        lines.append(f"| **mean, level {level}** | " + " | ".join(cells) + " |")
    cells = []
    for name in learners:
        chosen = [r for r in rows if r["learner"] == name]
        cells.append(", ".join(f"L{lv}: {mean(r['steps_per_s'] for r in chosen if r['level'] == lv):,.0f}"
                               for lv in (1, 2) if any(r["level"] == lv for r in chosen)))
    lines.append("| steps/s (mean) | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--headline", action="append", default=[],
                        help="a curriculum run directory whose library has the SMCs (repeatable)")
    parser.add_argument("--out", required=True, help="where each job's JSON goes (re-run to resume)")
    parser.add_argument("--learners", default=",".join(LEARNERS))
    parser.add_argument("--nodes", default=",".join((*LEVEL2, *LEVEL1)), help="a subset of the SMCs compared")
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--timesteps", type=int, default=400_000)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--table", action="store_true", help="print the table of what is done and stop")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.table:
        print(table(out))
        return 0
    if not args.headline:
        parser.error("--headline DIR is needed to train (the run whose library has the SMCs and their children)")
    learners = [name for name in args.learners.split(",") if name]
    unknown = sorted(set(learners) - set(LEARNERS))
    if unknown:
        parser.error(f"unknown learner(s) {unknown}; learners are {list(LEARNERS)}")
    # the retrained learners first (slowest first), then the cheap evaluations of the headline's own SMCs
    nodes = [node for node in args.nodes.split(",") if node]
    if set(nodes) - {*LEVEL1, *LEVEL2}:
        parser.error(f"unknown node(s) {sorted(set(nodes) - {*LEVEL1, *LEVEL2})}")
    jobs = [(learner, node, seed) for node in nodes for learner in learners if learner != "ppo-lstm"
            for seed in range(args.seeds)]
    jobs += [("ppo-lstm", node, seed) for node in nodes if "ppo-lstm" in learners for seed in range(args.seeds)]
    todo = [job for job in jobs if not result_path(out, *job).is_file()]
    print(f"{len(jobs)} jobs, {len(jobs) - len(todo)} done, {args.workers} workers", flush=True)
    with ProcessPoolExecutor(args.workers) as pool:
        futures = {pool.submit(run_one, args.headline, str(out), *job, args.timesteps): job for job in todo}
        for done, future in enumerate(as_completed(futures), 1):
            row = json.loads(Path(future.result()).read_text())
            print(f"[{done}/{len(todo)}] {row['learner']} {row['node']}@{row['seed']}: test {row['test_score']:.3f}, "
                  f"{row['steps_per_s']:,.0f} steps/s", flush=True)
    print(table(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
