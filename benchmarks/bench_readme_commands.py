"""How long the README's and the docs' commands take: each run as a user types it (``full``) and with the quick
settings the page gives beside it (``quick``), one after the other in fresh temporary directories, wall-clock seconds.

The commands are the pages', with what they leave to the user filled in (output folders under the temporary
directory, a child trained first where a snippet starts from one). Left out, with where their time is given instead:
``sb3-smc experiment --category objects`` and ``run_experiment(..., category="objects")`` in full (hours: the whole
table's recorded wall time), ``benchmarks/compare_learners.py`` (hours: its page's table says what it ran), the
Minigrid examples (their own results page) and ``pixelworld play`` (interactive).

Run: ``python benchmarks/bench_readme_commands.py [--pages readme,docs] [--only quick] [--commands name,...]``; pause
any background run first, or lower its priority (timings on a shared machine are not comparable).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from pixelworld_env.datasets.cache import CACHE_ENV

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
README: dict[str, dict[str, list[list[str]]]] = {  # name -> variant -> the commands run in turn (timed together)
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

CORNER = 'from sb3_smc import train_smc\ncorner = train_smc("PW-cl_self-in-left-corner_vs_on-hline-v0", seed=0{more})\n'
SPEC = CORNER + """from sb3_smc import SMCLibrary, TrainingSpec
library = SMCLibrary([corner])
spec = TrainingSpec.create("PW-cl_self-in-container_vs_noncontainer-v0", seed=2, algo="TRPO",
                           children=["cl_self-in-left-corner_vs_on-hline"], total_timesteps={steps})
smc = train_smc(spec, children=library)
"""
GROUP = """from sb3_smc.learning.batched import train_smcs
from sb3_smc.records import TrainingSpec
specs = [TrainingSpec.create("PW-cl_self-in-left-corner_vs_on-hline-v0", seed=s, name=f"corner@{{s}}"{more})
         for s in range(5)]
smcs = train_smcs(specs)
"""
LIBRARY = CORNER + """import gymnasium as gym
from sb3_smc import SMCLibrary, evaluate
library = SMCLibrary()
library.add(corner)
library.save("smcs/")
library = SMCLibrary.load("smcs/")
parent = train_smc("PW-ba_self-in-container-v0", children=(library, library.names){more})
library.add(parent)
evaluate(parent)
library.save()
again = train_smc(parent.spec, children=library)
"""
PRETRAINED = """import gymnasium as gym
import pixelworld_env
from sb3_smc import SMCLibrary
from sb3_smc.library.pretrained import pretrained_curricula
pretrained_curricula()
library = SMCLibrary.pretrained("search2-canon")
env = library.wrap(gym.make("PW-ba_self-in-target-container_from_nontarget-container-v0"), library.names)
print(library["cl_self-in-left-corner_vs_on-hline@0"].test_score)
"""
MY_PPO = """import sb3_smc
from sb3_contrib import RecurrentPPO
class MyPPO(RecurrentPPO):
    ...
sb3_smc.register_algorithm("MyPPO", MyPPO)
smc = sb3_smc.train_smc("PW-cl_self-in-left-corner_vs_on-hline-v0", algo="MyPPO"{more})
sb3_smc.SMCLibrary([smc]).save("my-library")
sb3_smc.SMCLibrary.load("my-library")["cl_self-in-left-corner_vs_on-hline"].model
"""
TRPO = """import gymnasium as gym
import pixelworld_env
from sb3_smc.recurrent_trpo import RecurrentTRPO
env = gym.make("PW-cl_self-in-left-corner_vs_on-hline-v0")
model = RecurrentTRPO("MlpGruPolicy", env, n_steps=125, target_kl=0.01, baseline="linear_feature", seed=0)
model.learn({steps})
model.save("trpo_gru")
model = RecurrentTRPO.load("trpo_gru")
obs, _ = env.reset(seed=0)
action, state = model.predict(obs, state=None, episode_start=None)
"""
CURRICULUM = """import torch; torch.set_num_threads(1)
from sb3_smc import SMCLibrary, evaluate
from sb3_smc.curricula import train_curriculum
run = train_curriculum("con2-cl", "runs/con2-cl", targets=["cl_self-in-container_vs_noncontainer"], {more})
library = SMCLibrary.load(run.library)
print(evaluate(library["con2-cl/cl_self-in-container_vs_noncontainer@0"]).score)
"""
OBJECTS = """from sb3_smc.experiments import run_experiment, write_report
results = run_experiment("runs/objects", methods=["cnn", "base", "curr", "canon"], category="objects", {more})
write_report("runs/objects")
"""
TWO_CONCEPTS = """from sb3_smc.fewshot import learn_concept
learned = learn_concept("PW-cl_self-in-container_vs_noncontainer-v0", train_worlds=4,
                        library="pretrained", offer="auto", add_to="my-smcs/"{more})
next_one = learn_concept("PW-ba_self-in-container_from_on-floor-v0", train_worlds=4,
                         library=["pretrained", "my-smcs/"], add_to="my-smcs/"{more})
"""
VECTOR = """import gymnasium as gym
import numpy as np
import pixelworld_env
envs = gym.make_vec("PW-ba_self-in-container-v0", num_envs=1024)
obs, info = envs.reset(seed=0)
actions = np.random.default_rng(0).integers(envs.single_action_space.n, size=1024)
obs, rewards, terminated, truncated, info = envs.step(actions)
"""
PIXELWORLD = str(Path(PY).with_name("pixelworld"))
ZOO_ENV = "PW-cl_self-in-left-corner_vs_on-hline-v0"
ZOO_PPO = [PY, "-m", "rl_zoo3.train", "--algo", "ppo_lstm", "--env", ZOO_ENV, "-conf", "sb3_smc.zoo.ppo_lstm",
           "--num-threads", "1", "-f", "logs", "--tensorboard-log", "tb"]
ZOO_AFTER = [[PY, "-m", "rl_zoo3.enjoy", "--algo", "ppo_lstm", "--env", ZOO_ENV, "-f", "logs", "--no-render",
              "--env-kwargs", "split:'test'", "-n", "1000"],
             [PY, "-m", "rl_zoo3.record_video", "--algo", "ppo_lstm", "--env", ZOO_ENV, "-f", "logs", "-n", "100",
              "-o", "videos"],
             [SB3_SMC, "import-zoo", f"logs/ppo_lstm/{ZOO_ENV}_1", "--library", "smcs", "--name", "left-corner"]]
ZOO_TRPO = [PY, "-m", "rl_zoo3.train", "--algo", "recurrent_trpo", "--env", ZOO_ENV,
            "-conf", "sb3_smc.zoo.recurrent_trpo", "--log-folder", "logs"]
QUICK = ", total_timesteps=20_000"
GENERATE = [PIXELWORLD, "generate", "--all"]
EMPTY_CACHE = (GENERATE,)
"""Commands timed on an empty datasets cache of their own (what they time is the generation)."""


def _py(code: str) -> list[list[str]]:
    return [[PY, "-c", code]]


DOCS: dict[str, dict[str, list[list[str]]]] = {  # the docs' pages, by page and snippet
    "training.md: TrainingSpec, TRPO, 200,000 steps (its child trained first)": {
        "full": _py(SPEC.format(more="", steps=200_000)), "quick": _py(SPEC.format(more=QUICK, steps=20_000))},
    "training.md: train_smcs, five seeds": {"full": _py(GROUP.format(more="")),
                                            "quick": _py(GROUP.format(more=QUICK))},
    "library.md: save, load, a parent, evaluate, train again": {"full": _py(LIBRARY.format(more="")),
                                                                "quick": _py(LIBRARY.format(more=QUICK))},
    "library.md: SMCLibrary.pretrained": {"full": _py(PRETRAINED)},
    "library.md: rl_zoo3 train ppo_lstm -conf, then enjoy, record_video, import-zoo": {
        "full": [ZOO_PPO, *ZOO_AFTER], "quick": [[*ZOO_PPO, "-n", "20000"], *ZOO_AFTER]},
    "library.md: rl_zoo3 train recurrent_trpo -conf": {"full": [ZOO_TRPO], "quick": [[*ZOO_TRPO, "-n", "20000"]]},
    "learners.md: register_algorithm, train, save, load": {"full": _py(MY_PPO.format(more="")),
                                                          "quick": _py(MY_PPO.format(more=QUICK))},
    "learners.md: RecurrentTRPO learn(400_000)": {"full": _py(TRPO.format(steps=400_000)),
                                                  "quick": _py(TRPO.format(steps=20_000))},
    "curricula.md: train_curriculum, seeds=5": {"full": _py(CURRICULUM.format(more="seeds=5")),
                                                "quick": _py(CURRICULUM.format(more="seeds=1, timesteps=20_000"))},
    "experiments.md: run_experiment, category objects": {
        "quick": _py(OBJECTS.format(more="seeds=1, timesteps=20_000, workers=2"))},
    "few_shot.md: two concepts, the second calling the first": {"full": _py(TWO_CONCEPTS.format(more="")),
                                                                 "quick": _py(TWO_CONCEPTS.format(more=QUICK))},
    "pixelworld.md: make_vec, 1,024 envs, one step": {"full": _py(VECTOR)},
    "pixelworld.md: pixelworld list, show, show --png": {"full": [
        [PIXELWORLD, "list"], [PIXELWORLD, "show", "PW-ba_self-in-container-v0", "--split", "test", "--index", "3"],
        [PIXELWORLD, "show", "PW-ba_self-in-container-v0", "--png", "sheet.png", "--count", "16"]]},
    "pixelworld.md: pixelworld generate --all (an empty cache)": {"full": [GENERATE]},
}
PAGES = {"readme": README, "docs": DOCS}


def timed(commands: list[list[str]], *, own_cache: bool = False) -> float:
    """Seconds for ``commands`` run in turn in a fresh temporary directory (a failure stops the benchmark); with
    ``own_cache`` the datasets' cache is an empty folder in it."""
    with tempfile.TemporaryDirectory() as folder:
        env = {**os.environ, "OMP_NUM_THREADS": "1", "MPLBACKEND": "Agg"}
        if own_cache:
            env[CACHE_ENV] = str(Path(folder) / "cache")
        start = time.perf_counter()
        for command in commands:
            done = subprocess.run(command, cwd=folder, capture_output=True, text=True, env=env)
            if done.returncode != 0:
                raise SystemExit(f"{' '.join(command)[:200]} failed ({done.returncode}):\n{done.stderr[-2000:]}")
        return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--pages", default="readme", help="comma-separated: readme, docs (default: readme)")
    parser.add_argument("--only", choices=("full", "quick"), help="one variant only")
    parser.add_argument("--commands", help="comma-separated start of the command names to run (default: all)")
    args = parser.parse_args()
    unknown = sorted(set(args.pages.split(",")) - set(PAGES))
    if unknown:
        parser.error(f"--pages takes {', '.join(PAGES)}, got {', '.join(unknown)}")
    commands_of = {name: variants for page in args.pages.split(",") for name, variants in PAGES[page].items()}
    chosen = [name for name in commands_of
              if not args.commands or any(name.startswith(c) for c in args.commands.split(","))]
    rows = []
    for name in chosen:
        for variant, commands in commands_of[name].items():
            if args.only and variant != args.only:
                continue
            print(f"{name} ({variant}) ...", file=sys.stderr, flush=True)
            seconds = timed(commands, own_cache=any(command in EMPTY_CACHE for command in commands))
            print(f"  {seconds:.0f} s", file=sys.stderr, flush=True)
            rows.append(f"| {name} | {variant} | {seconds:,.0f} |")
    print("| command | variant | seconds |\n|---|---|---:|\n" + "\n".join(rows))


if __name__ == "__main__":
    main()
