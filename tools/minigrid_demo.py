#!/usr/bin/env python
"""SMCs on Minigrid: DoorKey trained flat and as a curriculum, with the paper's protocol, into one report.

The curriculum (``sb3_smc.examples.minigrid_doorkey``): ``get-key``, ``open-door`` (key in hand) and ``reach-goal``
(door open) as flat SMCs, then ``doorkey`` (reach the goal from DoorKey's own start) with the two best seeds of each
as SMC actions; beside it ``doorkey-flat``, the same task trained flat. Every node x ``--seeds`` seeds, the package's
defaults otherwise (RecurrentPPO, LSTM 32, 400,000 steps, best-update selection), trained by the curriculum trainer
(resumable: run the same command again). Then every SMC is tested on ``--starts`` held-out start states x
``--repeats`` repeats (``sb3_smc.evaluate``), and ``report`` writes the records (no models), ``report.md`` and the
figures into ``--results``.

Usage::

    python tools/minigrid_demo.py train --out /work/runs/minigrid [--seeds 5] [--workers 2] [--size 8]
    python tools/minigrid_demo.py report --out /work/runs/minigrid [--results docs/results/minigrid]
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import statistics
import sys
import time
from pathlib import Path
from typing import Any

from pixelworld_env.atomic import atomic_write

MODULE = "sb3_smc.examples.minigrid_doorkey"
CHILDREN = ("get-key", "open-door", "reach-goal")
METHODS = {"doorkey-flat": "flat", "doorkey": "curriculum"}


def curriculum_text(size: int) -> str:
    """The curriculum file of DoorKey-<size>x<size>."""
    lines = [f"curriculum: minigrid-doorkey{size}", f"description: DoorKey-{size}x{size}, flat and as a curriculum",
             "nodes:"]
    for child in CHILDREN:
        lines += [f"  - name: {child}", f"    task: {MODULE}:DoorKey{size}-{child}-v0"]
    lines += ["  - name: doorkey", f"    task: {MODULE}:DoorKey{size}-doorkey-v0", f"    uses: [{', '.join(CHILDREN)}]",
              "  - name: doorkey-flat", f"    task: {MODULE}:DoorKey{size}-doorkey-v0",
              "targets: [doorkey, doorkey-flat]"]
    return "\n".join(lines) + "\n"


def train(args: argparse.Namespace) -> int:
    from sb3_smc.curricula import train_curriculum

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    path = out / "doorkey.yml"
    text = curriculum_text(args.size)
    if path.exists() and path.read_text() != text:
        print(f"{path} exists with other settings: use another --out", file=sys.stderr)
        return 2
    atomic_write(path, text)
    start = time.time()
    run = train_curriculum(str(path), out / "run", seeds=args.seeds, workers=args.workers,
                           timesteps=args.timesteps)
    print(f"trained in {time.time() - start:.0f} s; {len(run.failed)} failed")
    return 1 if run.failed else 0


def _summary(scores: list[float]) -> tuple[float, float, float]:
    """Best seed, mean, s.d. (percent)."""
    best = max(scores)
    sd = statistics.stdev(scores) if len(scores) > 1 else 0.0
    return 100 * best, 100 * statistics.mean(scores), 100 * sd


def report(args: argparse.Namespace) -> int:
    import torch

    torch.set_num_threads(1)
    from sb3_smc import SMCLibrary, evaluate
    from sb3_smc.experiments.figures import pyplot, save_figure, timeline_figure

    out, results = Path(args.out), Path(args.results)
    library = SMCLibrary.load(out / "run" / "library")
    (results / "records").mkdir(parents=True, exist_ok=True)
    rows: list[dict[str, Any]] = []
    for name in library.names:
        smc = library[name]
        node, _, seed = name.rpartition("@")
        record_path = results / "records" / f"{name}.json"
        if record_path.exists():  # evaluated before: the records keep it
            saved = json.loads(record_path.read_text())
            score, length = saved["evaluation"]["score"], saved["evaluation"]["mean_length"]
        else:
            result = evaluate(smc, starts=args.starts, repeats=args.repeats, keep=False)
            score, length = result.score, result.mean_length
            atomic_write(record_path, json.dumps({"spec": smc.spec.to_dict(), "record": smc.record.to_dict(),
                                                  "evaluation": result.record.to_dict()}, indent=1))
            print(f"{name}: test {100 * score:.1f} %", flush=True)
        rows.append({"node": node, "seed": int(seed), "test_score": score, "mean_length": length,
                     "selected_update": smc.record.selected_update, "training_return": smc.record.selected_return,
                     "wall_time_s": smc.record.wall_time_s, "primitive_steps": smc.record.primitive_steps})
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=list(rows[0]))
    writer.writeheader()
    writer.writerows(rows)
    atomic_write(results / "results.csv", buffer.getvalue())

    by_node: dict[str, list[dict[str, Any]]] = {}
    for row in rows:
        by_node.setdefault(row["node"], []).append(row)
    lines = ["# SMCs on Minigrid: DoorKey flat and as a curriculum", "",
             f"`python tools/minigrid_demo.py` ({(out / 'doorkey.yml').read_text().splitlines()[1].split(': ', 1)[1]}"
             f"): test score = success rate on {args.starts} held-out start states x {args.repeats} repeats "
             "(`sb3_smc.evaluate`), best seed and mean ± s.d. over seeds.", ""]
    seeds = json.loads((out / "run" / "run.json").read_text())["seeds"]
    expected = (len(CHILDREN) + len(METHODS)) * seeds
    if len(rows) < expected:
        lines += [f"**Partial results**: {len(rows)} of the run's {expected} SMCs were trained when this was written; "
                  "the run goes on (`train` again resumes it).", ""]
    lines += ["| node | role | seeds | best seed | mean ± s.d. | per seed | mean decisions | training wall time (s) |",
              "|---|---|---:|---:|---:|---|---:|---:|"]
    for node, node_rows in sorted(by_node.items(), key=lambda kv: (kv[0] not in METHODS, kv[0])):
        node_rows.sort(key=lambda r: r["seed"])
        scores = [r["test_score"] for r in node_rows]
        best, mean, sd = _summary(scores)
        role = METHODS.get(node, "lower-level SMC")
        lengths = statistics.mean(r["mean_length"] for r in node_rows)
        wall = statistics.mean(r["wall_time_s"] for r in node_rows)
        per_seed = ", ".join(f"{100 * s:.0f}" for s in scores)
        lines.append(f"| `{node}` | {role} | {len(scores)} | {best:.1f} | {mean:.1f} ± {sd:.1f} | {per_seed} | "
                     f"{lengths:.1f} | {wall:.0f} |")

    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6, 3.5))
    for node, color in (("doorkey-flat", "#888888"), ("doorkey", "#1f77b4")):
        for k, row in enumerate(sorted(by_node.get(node, []), key=lambda r: r["seed"])):
            curve = library[f"{node}@{row['seed']}"].record.training_returns
            ax.plot(range(1, len(curve) + 1), curve, color=color, alpha=0.7, linewidth=1,
                    label=METHODS[node] if k == 0 else None)
    ax.set_xlabel("update (2,000 decisions each)")
    ax.set_ylabel("mean training return")
    ax.set_title("DoorKey: training return per update, every seed", fontsize=9)
    ax.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, results / "figures" / "learning_curves.png")
    lines += ["", "![learning curves](figures/learning_curves.png)", ""]
    curriculum_rows = by_node.get("doorkey", [])
    if curriculum_rows:
        best_row = max(curriculum_rows, key=lambda r: r["test_score"])
        smc = library[f"doorkey@{best_row['seed']}"]
        timeline_figure(smc, "doorkey", results / "figures" / "timeline.png", env_id=smc.spec.task.env_id)
        lines += [f"One test episode of the best curriculum seed (`doorkey@{best_row['seed']}`, test start 0): every "
                  "primitive step, coloured by the SMC that made it, each call's outcome at its end.", "",
                  "![timeline](figures/timeline.png)", ""]
    atomic_write(results / "report.md", "\n".join(lines) + "\n")
    print(f"wrote {results / 'report.md'}")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    run = commands.add_parser("train", help="train the curriculum and the flat baseline (resumable)")
    run.add_argument("--out", required=True)
    run.add_argument("--seeds", type=int, default=5)
    run.add_argument("--workers", type=int, default=1)
    run.add_argument("--size", type=int, default=8, choices=(5, 6, 8))
    run.add_argument("--timesteps", type=int, default=None, help="per job (default: the package's 400,000)")
    rep = commands.add_parser("report", help="evaluate every SMC and write the records, report and figures")
    rep.add_argument("--out", required=True)
    rep.add_argument("--results", default="docs/results/minigrid")
    rep.add_argument("--starts", type=int, default=100)
    rep.add_argument("--repeats", type=int, default=10)
    args = parser.parse_args(argv)
    return train(args) if args.command == "train" else report(args)


if __name__ == "__main__":
    sys.exit(main())
