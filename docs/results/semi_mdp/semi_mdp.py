"""Semi-MDP discounting against the default discounting (a call as one decision) on the headline bring-about target,
with the shipped pretrained children of its canonical curriculum (the two best seeds of each node it uses); default
RecurrentPPO, 400,000 steps, the paper's test. One JSON line per job:
``python docs/results/semi_mdp/semi_mdp.py 0 1 2 > results.jsonl``."""

import json
import sys
import time

import torch

from sb3_smc import SMCLibrary, evaluate, train_smc
from sb3_smc.curricula import resolve_curriculum

TARGET = "ba_self-in-container_from_between-potential-containers"


def main() -> None:
    torch.set_num_threads(1)
    library = SMCLibrary.pretrained("con2-ba-canon")
    node = resolve_curriculum("con2-ba-canon").node(f"con2-ba-canon/{TARGET}_canon")
    children = [library[n] for u in node.uses for n in library.names if n.rpartition("@")[0] == u]
    for seed in [int(s) for s in sys.argv[1:]] or [0, 1, 2]:
        for discount in ("decision", "semi-mdp"):
            start = time.time()
            smc = train_smc(f"PW-{TARGET}-v0", children=children, seed=seed, discount=discount, log_every=0)
            score = evaluate(smc).score
            print(json.dumps({"seed": seed, "discount": discount, "test": score,
                              "selected_update": smc.record.selected_update,
                              "selected_return": smc.record.selected_return, "wall_s": round(time.time() - start),
                              "children": len(children)}), flush=True)


if __name__ == "__main__":
    main()
