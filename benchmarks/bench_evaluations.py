"""An experiment's evaluations, computed again: this tree beside a baseline checkout, in one run.

After training, ``sb3-smc experiment`` evaluates every SMC of its results table, each loaded from the run's library
by name and tested with the paper's protocol. This takes the first ``--smcs`` SMCs of a finished experiment directory
(its ``evaluations/``, in name order), and computes their evaluations in one process as a worker of the experiment
does, one after another (each loaded from the library, then tested; one torch thread), in each tree in its own
subprocess (``PYTHONPATH`` = the tree), alternating, ``--repeats`` rounds. Reported per round: the seconds, the
seconds per SMC, and whether the test scores equal the saved ones (they must: the evaluation is seeded).

Run: ``python benchmarks/bench_evaluations.py RUN [--smcs 40] [--repeats 3] [--baseline PATH]``; make a baseline
checkout with ``git worktree add /tmp/baseline <commit>``.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]

_EVALUATE = """
import json, sys, time, torch
from pathlib import Path
torch.set_num_threads(1)
from sb3_smc.experiments.runner import evaluation_path, read_evaluation
from sb3_smc.learning.evaluation import evaluate
from sb3_smc.library import SMCLibrary
root, names = sys.argv[1], sys.argv[2:]
begin = time.perf_counter()
scores = []
for name in names:
    smc = SMCLibrary.load(root + "/library", names=[name])[name]
    scores.append(evaluate(smc, repeats=10, seed=0, record_cells=False).score)
seconds = time.perf_counter() - begin
saved = [read_evaluation(evaluation_path(Path(root), name))["test_score"] for name in names]
print(json.dumps({"seconds": seconds, "same": scores == saved}))
"""


def evaluate_in(tree: Path, run: Path, names: list[str]) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree), OMP_NUM_THREADS="1")
    out = subprocess.run([sys.executable, "-c", _EVALUATE, str(run), *names], env=env, capture_output=True,
                         text=True, check=True, cwd=tree)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("run", type=Path, help="a finished experiment directory (library/ and evaluations/)")
    parser.add_argument("--smcs", type=int, default=40, help="how many of its SMCs (the first by name)")
    parser.add_argument("--repeats", type=int, default=3, help="rounds, each tree once a round")
    parser.add_argument("--baseline", type=Path, default=None, help="a checkout to time beside this tree")
    args = parser.parse_args()
    sys.path.insert(0, str(HERE))
    from sb3_smc.experiments.runner import read_evaluation

    saved = sorted((args.run / "evaluations").glob("*.json"))
    names = [read_evaluation(path)["smc"] for path in saved[:args.smcs]]
    if not names:
        parser.error(f"{args.run / 'evaluations'} holds no evaluations: give a finished experiment directory")
    trees = [("this tree", HERE)] + ([("baseline", args.baseline.resolve())] if args.baseline else [])
    rounds: dict[str, list[dict]] = {label: [] for label, _ in trees}
    for _ in range(args.repeats):
        for label, tree in trees:
            rounds[label].append(evaluate_in(tree, args.run, names))
    print(f"{len(names)} SMCs of {args.run}, one process each round\n")
    print("| tree | rounds: s | median s per SMC | scores as saved |\n|---|---|---:|---|")
    for label, results in rounds.items():
        seconds = [r["seconds"] for r in results]
        print(f"| {label} | {' / '.join(f'{s:.2f}' for s in seconds)} | "
              f"{statistics.median(seconds) / len(names):.3f} | {'yes' if all(r['same'] for r in results) else 'NO'} |")


if __name__ == "__main__":
    main()
