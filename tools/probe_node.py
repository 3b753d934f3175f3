"""Train one curriculum node with changed settings and test it with the paper's protocol: what the investigation of
a failing method tries (docs/results/paper/README.md, "Where a method fails").

The node's children are the two best seeds of each node it uses in a run's library (as the curriculum trainer
picks them; ``--children worst``: the two worst, as the original release's selection helper picks them, sorting the
seeds by training return in ascending order and keeping the first two); the node is trained with each ``--seeds``
seed, with ``--timesteps`` / ``--algo`` / ``--rnn`` / ``--smc-weight`` (the signal bias's weight of the SMC actions
together) / ``--count-moves`` (a call costs the episode its moves) changed, and evaluated on the test split (10
repeats). One JSON record per seed goes to ``--out`` (the spec, the training returns, selected update, test score,
wall time); a seed whose record is there is not trained again.

    python tools/probe_node.py --curriculum obj-con2-canon-cl \\
        --node obj-con2-canon-cl/cl_self-left-of-two-objects-vs-one-curr --library runs/probe-canon/library \\
        --seeds 0,1 --timesteps 1200000 --out docs/results/paper/probes/canon-left-of-1.2M
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time
from pathlib import Path

import torch

from pixelworld_env.atomic import atomic_write
from sb3_smc.curricula import resolve_curriculum
from sb3_smc.curricula.jobs import DEFAULT_REUSE, REUSE, file_stem, node_records, node_spec, rank_seeds
from sb3_smc.learning.evaluation import evaluate
from sb3_smc.learning.training import train_smc
from sb3_smc.library import SMCLibrary, storage
from sb3_smc.records import TrainingRecord


def chosen_seeds(records: dict[int, TrainingRecord], which: str) -> list[int]:
    """The seeds a caller gets: the best (:func:`rank_seeds`) or the worst; the worst as a stable ascending sort by
    training return over the seeds in order keeps them (a seed that never selected an update first)."""
    k = REUSE[DEFAULT_REUSE]
    if which == "best":
        return rank_seeds(records)[:k]

    def key(seed: int) -> tuple[int, float, int]:
        value = records[seed].selected_return
        return (0, 0.0, seed) if value is None else (1, value, seed)
    return sorted(records, key=key)[:k]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--curriculum", required=True, help="a shipped curriculum name or a .yml file")
    parser.add_argument("--node", required=True)
    parser.add_argument("--library", required=True, help="the run library holding the children's seeds")
    parser.add_argument("--seeds", default="0,1")
    parser.add_argument("--timesteps", type=int, default=None)
    parser.add_argument("--algo", default=None)
    parser.add_argument("--rnn", default=None)
    parser.add_argument("--smc-weight", type=float, default=None,
                        help="signal-bias weight of the SMC actions together (default 20: with moves, 20/41 of the "
                             "initial probability)")
    parser.add_argument("--count-moves", action="store_true",
                        help="a call costs the episode the moves it made, not one step (count_primitive_steps)")
    parser.add_argument("--children", choices=("best", "worst"), default="best",
                        help="which seeds of each node it uses: the best (the paper's text, the package's rule) or the "
                             "worst (the original release's selection helper)")
    parser.add_argument("--out", required=True)
    args = parser.parse_args()
    torch.set_num_threads(1)

    node = resolve_curriculum(args.curriculum).node(args.node)
    manifest, where = storage.read_manifest(Path(args.library))
    library_entries = storage.check_manifest(manifest, where)
    children = tuple(f"{used}@{seed}" for used in node.uses
                     for seed in chosen_seeds({s: r for s, r in node_records(library_entries, used).items()
                                               if r is not None}, args.children))
    library = SMCLibrary.load(args.library, names=list(children))
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for seed in (int(s) for s in args.seeds.split(",")):
        spec = node_spec(node, seed, children, timesteps=args.timesteps, algo=args.algo, rnn=args.rnn)
        if args.smc_weight is not None:
            spec = dataclasses.replace(spec, signal_bias=dataclasses.replace(spec.signal_bias,
                                                                             smc_weight=args.smc_weight))
        if args.count_moves:
            spec = dataclasses.replace(spec, wrapper=dataclasses.replace(spec.wrapper, count_primitive_steps=True))
        path = out / f"{file_stem(spec.name)}.json"
        if path.is_file():
            print(f"{spec.name}: kept {path}")
            continue
        start = time.perf_counter()
        smc = train_smc(spec, children=library, printer=print, log_every=25)
        result = evaluate(smc, repeats=10, seed=0, record_cells=False)
        record = smc.record
        assert record is not None
        atomic_write(path, json.dumps({
            "smc": spec.name, "test_score": result.score, "selected_update": record.selected_update,
            "training_return": record.selected_return, "updates": record.updates,
            "training_returns": [None if r != r else r for r in record.training_returns],
            "wall_time_s": time.perf_counter() - start, "children": list(children), "spec": spec.to_dict(),
        }, indent=1) + "\n")
        print(f"{spec.name}: test {100 * result.score:.1f} %, selected update {record.selected_update} "
              f"(return {record.selected_return:.3f}) of {record.updates}")


if __name__ == "__main__":
    main()
