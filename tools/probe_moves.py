"""How many world moves a run's best SMCs make per test episode, and what they score when the episode's 100 steps
count moves instead of decisions (docs/results/paper/README.md, "Moves per episode").

An SMC call is one step of the episode's 100 (the package's default and, as far as the paper says, its choice), so
a hierarchical SMC may make far more than 100 moves in an episode, a flat one at most 100. For each target x method
of a run directory this tests the best seed (the run's ``reported`` row: the highest test score; curr over its
curricula) with the run's test (:func:`sb3_smc.evaluate`: test split, the run's repeats, 10 in the paper's
protocol, evaluation seed 0):

* as trained (its spec's ``count_primitive_steps``): the score (checked against the run's recorded one), how the
  other episodes ended (a wrong signal, or no signal: the steps or moves ran out), the moves per episode (mean,
  median, 90th percentile, the share of episodes over 100) and the score of the episodes that made at most 100
  moves;
* for an SMC trained with a call as one step, again with ``count_primitive_steps=True``: each call costs the moves
  it made and is cut at the budget left, so an episode makes at most 100 moves as a flat SMC's does (the policy is
  the same; it was not trained this way). A flat SMC, or one trained so (``curr-moves``), is not tested twice.

    python tools/probe_moves.py /work/runs/paper-containment --kind bring-about --methods base,curr,canon \\
        --out docs/results/paper/probes/moves-containment.csv
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import io
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np
import torch

from pixelworld_env.atomic import atomic_write
from sb3_smc.envs.factory import spec_for_smc
from sb3_smc.errors import SMCError
from sb3_smc.experiments.design import METHODS
from sb3_smc.experiments.runner import read_results
from sb3_smc.learning.evaluation import evaluate
from sb3_smc.library import SMCLibrary
from sb3_smc.library.errors import UnknownSMCError
from sb3_smc.smc.smc import SMC

FIELDS = ("target", "category", "method", "smc", "recorded", "score", "moves_mean", "moves_median", "moves_p90",
          "over_100", "score_within_100", "score_counting_moves", "wrong_signal", "no_signal")


def best_rows(results: dict[str, Any], kind: str, methods: list[str]) -> list[dict[str, Any]]:
    """The best seed's row of each target x method of ``kind`` (a run's ``results.json``: its ``reported`` rows), by
    target, then in the order of ``methods``."""
    chosen = [row for row in results["reported"] if row["kind"] == kind and row["method"] in methods]
    return sorted(chosen, key=lambda row: (row["target"], methods.index(row["method"])))


def test(smc: SMC, count_moves: bool, repeats: int) -> tuple[list[bool], list[int], list[bool]]:
    """Success, moves and whether it ended on a signal, of every test episode of the run's test, calls costing one
    step or their moves."""
    wrapper = dataclasses.replace(spec_for_smc(smc, smc.spec.task.env_id).wrapper, count_primitive_steps=count_moves)
    result = evaluate(smc, repeats=repeats, seed=0, record_cells=False, keep=False, wrapper=wrapper)
    return ([e.success for e in result.episodes], [e.primitive_steps for e in result.episodes],
            [e.signalled for e in result.episodes])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("runs", nargs="+", type=Path, help="experiment directories (results.json and library/)")
    parser.add_argument("--kind", default="bring-about", choices=("bring-about", "classification"))
    parser.add_argument("--methods", default="base,curr,canon")
    parser.add_argument("--out", type=Path, required=True, help="a CSV, written as rows finish (resumable)")
    args = parser.parse_args(argv)
    methods = args.methods.split(",")
    unknown = [m for m in methods if m not in METHODS]
    if unknown:
        parser.error(f"--methods: unknown {', '.join(unknown)} (methods: {', '.join(METHODS)})")
    results, repeats = {}, {}
    for run in args.runs:  # every run checked before any work
        if not (run / "results.json").is_file() or not (run / "library").is_dir():
            parser.error(f"{run}: not an experiment directory (it needs results.json and library/)")
        try:
            results[run] = read_results(run)
            repeats[run] = int(results[run]["settings"]["repeats"])
        except (SMCError, KeyError, TypeError, ValueError) as error:
            parser.error(f"{run / 'results.json'}: not the results of an sb3-smc experiment ({error})")
    torch.set_num_threads(1)
    done: list[dict[str, str]] = []
    if args.out.exists():
        with open(args.out, newline="") as handle:
            reader = csv.DictReader(handle)
            done = list(reader)
        if tuple(reader.fieldnames or ()) != FIELDS:
            parser.error(f"{args.out}: its columns are not this tool's ({', '.join(FIELDS)}); an older version "
                         "wrote it: give another --out, or move it away to test those SMCs again")
    finished = {(row["target"], row["method"]) for row in done}
    for run in args.runs:
        for row in best_rows(results[run], args.kind, methods):
            if (row["target"], row["method"]) in finished:
                continue
            name = f"{row['curriculum']}@{row['seed']}"
            try:
                smc = SMCLibrary.load(run / "library", names=[name])[name]
            except UnknownSMCError:  # a run resumed on another machine keeps records, not every model
                print(f"skipped {name}: not in {run / 'library'}", flush=True)
                continue
            counting = smc.spec.wrapper.count_primitive_steps  # as trained: curr-moves counts them
            successes, moves, signalled = test(smc, count_moves=counting, repeats=repeats[run])
            recorded = float(row["test_score"])
            if abs(float(np.mean(successes)) - recorded) > 1e-9:
                sys.exit(f"{name}: tested {np.mean(successes)}, the run recorded {recorded}: not the run's SMC or code")
            flat = not smc.spec.children  # a flat SMC's moves are its steps: counting them changes nothing
            counted = successes if flat or counting else test(smc, count_moves=True, repeats=repeats[run])[0]
            within = [s and m <= 100 for s, m in zip(successes, moves, strict=True)]
            wrong = [g and not s for s, g in zip(successes, signalled, strict=True)]  # the other episodes' ends
            silent = [not g and not s for s, g in zip(successes, signalled, strict=True)]
            done.append({"target": row["target"], "category": row["category"], "method": row["method"], "smc": name,
                         "recorded": f"{recorded:.3f}", "score": f"{np.mean(successes):.3f}",
                         "moves_mean": f"{np.mean(moves):.1f}", "moves_median": f"{np.median(moves):.0f}",
                         "moves_p90": f"{np.percentile(moves, 90):.0f}",
                         "over_100": f"{np.mean(np.array(moves) > 100):.3f}",
                         "score_within_100": f"{np.mean(within):.3f}",
                         "score_counting_moves": f"{np.mean(counted):.3f}",
                         "wrong_signal": f"{np.mean(wrong):.3f}",
                         "no_signal": f"{np.mean(silent):.3f}"})
            text = io.StringIO()
            writer = csv.DictWriter(text, fieldnames=FIELDS, lineterminator="\n")
            writer.writeheader()
            writer.writerows(done)
            atomic_write(args.out, text.getvalue())
            print(json.dumps(done[-1]), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
