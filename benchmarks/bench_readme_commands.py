"""How long the README's commands take: each run as a user types it (``full``) and with the quick settings the README
gives beside it (``quick``), one after the other in fresh temporary directories, wall-clock seconds.

The commands are the README's, with what it leaves to the user filled in (output folders under the temporary
directory). Left out, with where their time is given instead: ``sb3-smc experiment --category objects`` (hours: the
whole table's recorded wall time) and the Minigrid example (its own results page).

Run: ``python benchmarks/bench_readme_commands.py [--only quick] [--commands name,...]``; pause any background run
first (timings on a shared machine are not comparable).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

PY = sys.executable
SB3_SMC = str(Path(PY).with_name("sb3-smc"))
SNIPPET = """
import torch; torch.set_num_threads(1)
from sb3_smc import evaluate, train_smc
steps = {steps}
left = train_smc("PW-cl_self-in-left-corner_vs_on-hline-v0", seed=0, total_timesteps=steps)
right = train_smc("PW-cl_self-in-right-corner_vs_on-hline-v0", seed=0, total_timesteps=steps)
container = train_smc("PW-cl_self-in-container_vs_noncontainer-v0", children=[left, right], total_timesteps=steps)
print(evaluate(container).score)
"""
LEARN = """
from sb3_smc.fewshot import learn_concept
learned = learn_concept("PW-cl_self-in-container_vs_noncontainer-v0", train_worlds=4, library="pretrained",
                        offer="auto", add_to="my-smcs/"{more})
print(learned.smc.test_score, learned.offered)
"""
ZOO = ["-m", "rl_zoo3.train", "--algo", "trpo", "--env", "PW-ba_self-in-container-v0", "-conf", "sb3_smc.zoo.trpo",
       "--log-folder", "logs"]
CON2 = [SB3_SMC, "train", "con2-cl", "--out", "runs/con2-cl", "--targets", "cl_self-in-container_vs_noncontainer",
        "--workers", "2"]
EXPERIMENT = [SB3_SMC, "experiment", "--out", "runs/objects", "--targets", "cl_object-on-floor_vs_no-object",
              "--workers", "2", "--seeds", "1", "--timesteps", "20000"]
COMMANDS: dict[str, dict[str, list[list[str]]]] = {  # name -> variant -> the commands run in turn (timed together)
    "demo (python -m sb3_smc.demo)": {"full": [[PY, "-m", "sb3_smc.demo"]]},
    "train_smc x 3 + evaluate (SMCs as actions)": {"full": [[PY, "-c", SNIPPET.format(steps=400_000)]],
                                                   "quick": [[PY, "-c", SNIPPET.format(steps=20_000)]]},
    "learn_concept, 4 worlds, auto": {"full": [[PY, "-c", LEARN.format(more="")]],
                                      "quick": [[PY, "-c", LEARN.format(more=", total_timesteps=20_000")]]},
    "sb3-smc train con2-cl --targets ... --seeds 5 --workers 2": {
        "full": [[*CON2, "--seeds", "5"]], "quick": [[*CON2, "--seeds", "1", "--timesteps", "20000"]]},
    "sb3-smc experiment + report, one target": {
        "quick": [EXPERIMENT, [SB3_SMC, "report", "runs/objects"]]},
    "rl_zoo3 train --algo trpo ... -conf sb3_smc.zoo.trpo": {"full": [[PY, *ZOO]],
                                                            "quick": [[PY, *ZOO, "-n", "20000"]]},
}


def timed(commands: list[list[str]]) -> float:
    """Seconds for ``commands`` run in turn in a fresh temporary directory (a failure stops the benchmark)."""
    with tempfile.TemporaryDirectory() as folder:
        start = time.perf_counter()
        for command in commands:
            done = subprocess.run(command, cwd=folder, capture_output=True, text=True,
                                  env={**os.environ, "OMP_NUM_THREADS": "1", "MPLBACKEND": "Agg"})
            if done.returncode != 0:
                raise SystemExit(f"{' '.join(command)[:200]} failed ({done.returncode}):\n{done.stderr[-2000:]}")
        return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", choices=("full", "quick"), help="one variant only")
    parser.add_argument("--commands", help="comma-separated start of the command names to run (default: all)")
    args = parser.parse_args()
    chosen = [name for name in COMMANDS
              if not args.commands or any(name.startswith(c) for c in args.commands.split(","))]
    rows = []
    for name in chosen:
        for variant, commands in COMMANDS[name].items():
            if args.only and variant != args.only:
                continue
            print(f"{name} ({variant}) ...", file=sys.stderr, flush=True)
            seconds = timed(commands)
            print(f"  {seconds:.0f} s", file=sys.stderr, flush=True)
            rows.append(f"| {name} | {variant} | {seconds:,.0f} |")
    print("| command | variant | seconds |\n|---|---|---:|\n" + "\n".join(rows))


if __name__ == "__main__":
    main()
