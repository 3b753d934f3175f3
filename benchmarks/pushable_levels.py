"""How much of each pushable classification the initial state gives away without acting (docs/curricula.md).

For every classification dataset of the designed pushable curriculum, by level:

* **first view**: a lookup table from the agent's first 3 x 3 view to the majority label of the training
  environments with that view (unseen views: the training majority), scored on the test split. What an agent
  could answer before its first move.
* **CNN**: the paper's passive baseline on the full initial grid (``sb3_smc.experiments.cnn``; best and mean test
  accuracy of seeds 0..N-1).

    python benchmarks/pushable_levels.py [--seeds 5]
"""

from __future__ import annotations

import argparse
import sys
from collections import Counter, defaultdict
from statistics import mean


def first_view_accuracy(name: str) -> float:
    """Test accuracy of the majority-label lookup table of the first 3 x 3 view, fitted on the training split."""
    from pixelworld_env.core.world import World
    from pixelworld_env.datasets.loading import load_dataset

    train, test = load_dataset(name, split="train"), load_dataset(name, split="test")
    votes: dict[bytes, Counter] = defaultdict(Counter)
    for scene, label in zip(train.scenes, train.labels, strict=True):
        votes[World(scene).window().tobytes()][label] += 1
    fallback = Counter(train.labels).most_common(1)[0][0]
    hits = 0
    for scene, label in zip(test.scenes, test.labels, strict=True):
        seen = votes.get(World(scene).window().tobytes())
        hits += (seen.most_common(1)[0][0] if seen else fallback) == label
    return hits / len(test.scenes)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=5)
    args = parser.parse_args()
    import torch

    from pixelworld_env.datasets import catalog
    from sb3_smc.curricula import shipped_curriculum
    from sb3_smc.experiments.cnn import train_cnn

    torch.set_num_threads(1)
    curriculum = shipped_curriculum("pushable")
    print("| level | dataset | first view | CNN best | CNN mean |")
    print("|---:|---|---:|---:|---:|")
    for level, names in enumerate(curriculum.levels(), 1):
        for node in names:
            task = curriculum.node(node).task
            if catalog.dataset(task).kind != "classification":
                continue
            cnn = [train_cnn(task, seed).test_score for seed in range(args.seeds)]
            print(f"| {level} | `{task}` | {100 * first_view_accuracy(task):.0f} % | {100 * max(cnn):.0f} % | "
                  f"{100 * mean(cnn):.0f} % |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
