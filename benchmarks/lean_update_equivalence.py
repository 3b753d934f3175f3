"""Is ``train_smc(..., lean_update=True)`` statistically the same learner as the default update? (issue 44)

For each target (two classification tasks, one bring-about task) and each seed, one SMC is trained with the default
update and one with the lean update (:mod:`sb3_smc.common.recurrent.lean_update`), the same spec otherwise
(``--timesteps`` steps, the defaults, stopping at the largest return), and tested with
:func:`sb3_smc.learning.evaluation.evaluate` (the test split, the paper's 10 repeats, evaluation seed 0). Per target it
compares the means of the selected training return and of the test score over seeds: a paired t-test (same seed,
same start), Welch's t-test (each also Holm-adjusted over the table's comparisons, a family of tests of "no
difference"), and equivalence by two one-sided paired t-tests (TOST) within ``--margin`` (0.05: five points of a test
score in percent, five hundredths of the return, whose largest value is 1).

Run: ``python benchmarks/lean_update_equivalence.py [--timesteps N] [--seeds S] [--targets ENV_IDS]
[--algo RecurrentTRPO --rnn gru] [--out runs.jsonl]``; each finished SMC is appended to ``--out`` as one JSON line
(with the commit that trained it), and a run skips the SMCs already there (so a stopped run resumes, a run with more
seeds adds only the new ones, and a second process with ``--last-seed-first`` on the same file shares the work).
``--updates default`` or ``lean`` trains one update's SMCs only; ``--algo`` / ``--rnn`` train another learner than
the default (the paper's: RecurrentTRPO with a GRU), recorded in its rows. The table covers every target and seed in
the file that both updates trained with the run's learner and budget.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats

from sb3_smc.experiments.statistics import holm

TARGETS = ("PW-cl_self-in-left-corner_vs_on-hline-v0", "PW-cl_self-in-container_vs_noncontainer-v0",
           "PW-ba_self-in-container_from_on-floor-v0")
MEASURES = ("selected_return", "test_score")


def train_and_test(env_id: str, seed: int, lean: bool, timesteps: int, learner: dict[str, str] | None = None
                   ) -> dict[str, Any]:
    """One SMC trained and tested (``learner``: ``algo`` / ``rnn`` of ``train_smc``, default its own): its selected
    training return, test score, steps and wall time."""
    import torch

    from sb3_smc.experiments.runner import code_commit
    from sb3_smc.learning.evaluation import evaluate
    from sb3_smc.learning.training import train_smc

    torch.set_num_threads(1)
    start = time.perf_counter()
    smc = train_smc(env_id, total_timesteps=timesteps, seed=seed, lean_update=lean, log_every=0, **(learner or {}))
    record = smc.record
    assert record is not None
    score = evaluate(smc, record_cells=False, keep=False).score
    return {"env_id": env_id, "seed": seed, "lean": lean, "timesteps": timesteps,
            "selected_return": record.selected_return, "test_score": score, "steps": record.total_timesteps,
            "train_s": record.wall_time_s, "seconds": time.perf_counter() - start, "commit": code_commit(),
            **(learner or {})}


def tost_paired(differences: np.ndarray, margin: float) -> float:
    """The p-value of two one-sided paired t-tests that the mean difference lies within ``(-margin, margin)``."""
    n, mean = len(differences), float(differences.mean())
    se = float(differences.std(ddof=1)) / math.sqrt(n)
    if se == 0.0:
        return 0.0 if abs(mean) < margin else 1.0
    lower = stats.t.sf((mean + margin) / se, n - 1)
    upper = stats.t.cdf((mean - margin) / se, n - 1)
    return float(max(lower, upper))


def compare(rows: Sequence[dict[str, Any]], margin: float) -> list[dict[str, Any]]:
    """Per target and measure: the seeds both updates finished, their means, the paired and Welch p-values of a
    difference (each also Holm-adjusted over the comparisons returned: ``paired_holm``, ``welch_holm``), the 90 %
    interval of the mean paired difference and the TOST p-value of equivalence within ``margin`` (below 0.05 exactly
    when that interval lies within ``(-margin, margin)``)."""
    result = []
    for env_id in TARGETS:
        runs = {(r["seed"], r["lean"]): r for r in rows if r["env_id"] == env_id}
        seeds = sorted(s for s, lean in runs if not lean and (s, True) in runs)
        if len(seeds) < 2:
            continue
        for measure in MEASURES:
            default = np.array([runs[s, False][measure] for s in seeds], dtype=float)
            lean = np.array([runs[s, True][measure] for s in seeds], dtype=float)
            diff = lean - default
            same = bool(np.all(diff == 0.0))
            half = float(stats.t.ppf(0.95, len(seeds) - 1) * diff.std(ddof=1) / math.sqrt(len(seeds)))
            result.append({
                "env_id": env_id, "measure": measure, "n": len(seeds), "default": float(default.mean()),
                "default_sd": float(default.std(ddof=1)), "lean": float(lean.mean()),
                "lean_sd": float(lean.std(ddof=1)), "difference": float(diff.mean()),
                "interval": (float(diff.mean()) - half, float(diff.mean()) + half),
                "paired_p": 1.0 if same else float(stats.ttest_rel(lean, default).pvalue),
                "welch_p": 1.0 if same else float(stats.ttest_ind(lean, default, equal_var=False).pvalue),
                "tost_p": tost_paired(diff, margin)})
    for test in ("paired", "welch"):
        for c, adjusted in zip(result, holm([c[f"{test}_p"] for c in result]), strict=True):
            c[f"{test}_holm"] = adjusted
    return result


def table(comparisons: Sequence[dict[str, Any]], margin: float) -> str:
    """The comparisons as a markdown table."""
    lines = [f"| target | measure | seeds | default: mean (sd) | lean: mean (sd) | lean - default (90 % interval) | "
             f"paired p (Holm) | Welch p (Holm) | TOST p (+-{margin}) |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|"]
    for c in comparisons:
        name = c["env_id"].removeprefix("PW-").removesuffix("-v0")
        lines.append(f"| `{name}` | {c['measure']} | {c['n']} | {c['default']:.3f} ({c['default_sd']:.3f}) | "
                     f"{c['lean']:.3f} ({c['lean_sd']:.3f}) | {c['difference']:+.3f} ({c['interval'][0]:+.3f}, "
                     f"{c['interval'][1]:+.3f}) | {c['paired_p']:.2f} ({c['paired_holm']:.2f}) | "
                     f"{c['welch_p']:.2f} ({c['welch_holm']:.2f}) | {_p(c['tost_p'])} |")
    return "\n".join(lines)


def _p(p: float) -> str:
    """A TOST p-value as the tables give it."""
    return "< 0.001" if p < 0.001 else f"{p:.3f}"


def _rows(path: Path) -> list[dict[str, Any]]:
    """The SMCs already in ``path``."""
    return [json.loads(line) for line in path.read_text().splitlines()] if path.exists() else []


def _key(row: dict[str, Any]) -> tuple[Any, ...]:
    return row["env_id"], row["seed"], row["lean"], row["timesteps"], row.get("algo"), row.get("rnn")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--timesteps", type=int, default=400_000, help="steps per SMC")
    parser.add_argument("--seeds", type=int, default=10, help="seeds per target and update")
    parser.add_argument("--updates", choices=("both", "default", "lean"), default="both",
                        help="train the SMCs of both updates, or of one (the other's rows may come from another run)")
    parser.add_argument("--targets", default=",".join(TARGETS),
                        help=f"comma-separated env ids to train, of {', '.join(TARGETS)} (default: all)")
    parser.add_argument("--margin", type=float, default=0.05, help="equivalence margin of the means")
    parser.add_argument("--out", type=Path, default=Path("lean_update_equivalence.jsonl"), help="one JSON line per SMC")
    parser.add_argument("--last-seed-first", action="store_true",
                        help="take the seeds in reverse order (a second process on the same --out meets the first)")
    parser.add_argument("--algo", default=None,
                        help="the learner (default: train_smc's); RecurrentTRPO for the paper's")
    parser.add_argument("--rnn", default=None, help="the recurrent cell (default: train_smc's); gru for the paper's")
    args = parser.parse_args()
    learner = {key: value for key, value in (("algo", args.algo), ("rnn", args.rnn)) if value is not None}
    targets = [t for t in args.targets.split(",") if t]
    unknown = sorted(set(targets) - set(TARGETS))
    if unknown:
        parser.error(f"--targets: {', '.join(unknown)} not among {', '.join(TARGETS)}")
    seeds = range(args.seeds)
    for seed in reversed(seeds) if args.last_seed_first else seeds:
        for env_id in targets:
            for lean in {"both": (False, True), "default": (False,), "lean": (True,)}[args.updates]:
                if (env_id, seed, lean, args.timesteps, args.algo, args.rnn) in {_key(r) for r in _rows(args.out)}:
                    continue  # finished here, or by another process on the same file
                row = train_and_test(env_id, seed, lean, args.timesteps, learner)
                with args.out.open("a") as out:
                    out.write(json.dumps(row) + "\n")
                print(json.dumps(row), flush=True)
    rows = list({_key(r): r for r in _rows(args.out)}.values())
    rows = [r for r in rows
            if r["timesteps"] == args.timesteps and (r.get("algo"), r.get("rnn")) == (args.algo, args.rnn)]
    seconds = {lean: sum(r["train_s"] for r in rows if r["lean"] == lean) for lean in (False, True)}
    commits = {lean: sorted({str(r.get("commit")) for r in rows if r["lean"] == lean}) for lean in (False, True)}
    print(f"\n{args.timesteps:,} steps per SMC{', learner ' + json.dumps(learner) if learner else ''}, stopping at the "
          f"largest return; training time: default "
          f"{seconds[False]:.0f} s, lean {seconds[True]:.0f} s; trained at: default {', '.join(commits[False])}, "
          f"lean {', '.join(commits[True])} (None: the first run's rows, 2026-11-27)\n")
    print(table(compare(rows, args.margin), args.margin))


if __name__ == "__main__":
    main()
