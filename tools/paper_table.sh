#!/bin/bash
# The paper's whole table (docs/results/paper/README.md), one run directory per category, from a worktree at a fixed
# commit with its own environment. Rerun to resume (finished jobs and evaluations are kept).
#   tools/paper_table.sh run [categories...]     train + evaluate (default: search objects containment objcon;
#                                                base-gru: the second flat baseline, method base-gru on all 51 targets;
#                                                canon-scaled: canon with its budget x SMC actions / 8, all 51;
#                                                curr-moves, curr-moves-cl: curr whose calls cost their moves,
#                                                the 17 bring-about, the 34 classification targets;
#                                                base-400: the flat SMC with 400 moves an episode, all 51;
#                                                readings: the sweep of each reading's free parameter, SWEEP_METHODS
#                                                on SWEEP_TARGETS of sb3_smc.experiments.design;
#                                                experience: the flat SMC with 1, 4 and 16 x the budget,
#                                                EXPERIENCE_METHODS on SWEEP_TARGETS;
#                                                readings-all: curr-cap10 and curr-moves-200, experience-all: base-x1
#                                                and base-x4 (base-x1: base retrained, so that its moves are recorded),
#                                                each on the 39 level-2 targets outside SWEEP_TARGETS, so that with
#                                                readings and experience they cover all 51;
#                                                experience-cap10: curr-cap10 on SWEEP_TARGETS again, its moves
#                                                recorded (the sweep's run of it predates them), replacing the sweep's;
#                                                experience-x16, experience-x64: base-x16 / base-x64 on the targets
#                                                whose flat SMC's curve must go on, from the complete kept categories
#                                                (python -m sb3_smc.experiments.extension; nothing to run: skipped))
#   tools/paper_table.sh continue                the queue (docs/results/paper/queue.txt: category, commit, reuse, and
#                                                any further options of its sb3-smc experiment, e.g. --lean-update),
#                                                on this machine or a new one:
#                                                waits for a running `run`, then for each category whose records are not
#                                                complete sets up its commit's worktree and venv (once), restores its run
#                                                directory from the kept records (once) and runs it
#   tools/paper_table.sh checkpoint              at a session's end: keep every queued category this machine has run
#                                                (partial while unfinished), then the report
#   tools/paper_table.sh keep <category> [repo]   copy a run's records (no models) into docs/results/paper/<category>,
#                                                with its SMCs' primitive moves (experience.json)
#   tools/paper_table.sh partial <category>       at a session's end: tabulate what the running category has finished
#                                                (--no-train), keep it and make its partial report (nothing kept
#                                                while it has no evaluated SMC)
#   tools/paper_table.sh report                  one report over every complete kept directory (a partial one keeps
#                                                its records and its own report.md until it is complete):
#                                                docs/results/paper/report.md,
#                                                its means (and, in the results' README, its t-tests) copied into
#                                                both READMEs (tools/readme_table.py)
# Environment: RUNS (default /work/runs), RUN_ENV (default /work/run-env: a venv with the worktree installed),
# REUSE_FROM (optional: --reuse-from for the runs, e.g. "pretrained": lower-level SMCs copied, not trained again).
set -eu
RUNS=${RUNS:-/work/runs}; RUN_ENV=${RUN_ENV:-/work/run-env}
repo=$(cd "$(dirname "$0")/.." && pwd)

selection() {  # the experiment options of a category (base-gru, canon-scaled, base-400: that method on all 51
  # targets; curr-moves: on the 17 bring-about targets; curr-moves-cl: on the 34 classification targets; readings:
  # the sweep's methods on its 12 targets; experience: base-x1, base-x4 and base-x16 on the sweep's targets)
  case $1 in
    base-gru|canon-scaled|base-400) echo "--methods $1 --category all" ;;
    readings) "$RUN_ENV/bin/python" -I -c 'from sb3_smc.experiments.design import SWEEP_METHODS, SWEEP_TARGETS
print("--methods", ",".join(SWEEP_METHODS), "--targets", ",".join(SWEEP_TARGETS))' ;;
    experience) "$RUN_ENV/bin/python" -I -c 'from sb3_smc.experiments.design import EXPERIENCE_METHODS, SWEEP_TARGETS
print("--methods", ",".join(EXPERIENCE_METHODS), "--targets", ",".join(SWEEP_TARGETS))' ;;
    experience-cap10) "$RUN_ENV/bin/python" -I -c 'from sb3_smc.experiments.design import SWEEP_TARGETS
print("--methods curr-cap10 --targets", ",".join(SWEEP_TARGETS))' ;;
    readings-all|experience-all) "$RUN_ENV/bin/python" -I -c 'import sys
from sb3_smc.experiments import level2_targets
from sb3_smc.experiments.design import SWEEP_TARGETS
methods = "curr-cap10,curr-moves-200" if sys.argv[1] == "readings-all" else "base-x1,base-x4"
print("--methods", methods, "--targets", ",".join(t for t in level2_targets() if t not in SWEEP_TARGETS))' "$1" ;;
    experience-x16|experience-x64)  # from the kept records of the categories before it (complete ones only)
      "$repo/.venv/bin/python" -m sb3_smc.experiments.extension "base-${1#experience-}" $(complete_dirs "$1") \
        $(rerun_options "$1") ;;
    curr-moves|curr-moves-cl) echo "--methods curr-moves --targets $("$RUN_ENV/bin/python" -I -c 'import sys
from pixelworld_env.datasets import catalog
from sb3_smc.experiments import level2_targets
kind = "classification" if sys.argv[1] == "curr-moves-cl" else "bring-about"
print(",".join(t for t in level2_targets() if catalog.dataset(t).kind == kind))' "$1")" ;;
    *) echo "--category $1" ;;
  esac
}

queue() {  # the queue's lines: category, commit, --reuse-from, then any further options of its experiment
  grep -v '^#' "$repo/docs/results/paper/queue.txt"
}

options() {  # the further sb3-smc experiment options of category $1 (its queue line from the fourth column on)
  queue | awk -v c="$1" '$1 == c {for (i = 4; i <= NF; i++) printf "%s ", $i}'
}

holds() {  # whether the JSON file $1 exists and its key $2 is true (not false, empty or absent)
  [ -f "$1" ] && python3 -c 'import json, sys; sys.exit(not json.load(open(sys.argv[1])).get(sys.argv[2]))' "$1" "$2"
}

complete() {  # whether the results.json $1 says its run is complete
  holds "$1" complete
}

complete_dirs() {  # the kept directories of the queue's complete categories (before category $1, if given)
  for cat in $(queue | awk '{print $1}'); do
    if [ "$cat" = "${1:-}" ]; then break; fi
    if complete "$repo/docs/results/paper/$cat/results.json"; then echo "$repo/docs/results/paper/$cat"; fi
  done
}

RERUNS="experience-cap10"  # categories that run target x method pairs of earlier ones again: their rows replace those

rerun_options() {  # --rerun for each complete category of RERUNS (before category $1, if given)
  local dir
  for dir in $(complete_dirs "${1:-}"); do
    case " $RERUNS " in *" $(basename "$dir") "*) echo "--rerun $dir" ;; esac
  done
}

environment() {  # the venv of commit $1 (a worktree of it, found or added, installed into $RUNS/env-$1, once)
  local commit=$1 src env
  src=$(git -C "$repo" worktree list --porcelain | awk -v c="$commit" '/^worktree /{w=$2} /^HEAD /{if (index($2, c) == 1) print w}' | head -1)
  if [ -z "$src" ]; then src=$RUNS/src-$commit; git -C "$repo" worktree add --detach "$src" "$commit" >&2; fi
  env=$RUNS/env-$commit
  if [ ! -x "$env/bin/sb3-smc" ]; then
    python3 -m venv "$env" >&2 && "$env/bin/pip" install -q torch==2.13.0 >&2 && "$env/bin/pip" install -q -e "$src" >&2
  fi
  echo "$env"
}

reuse_path() {  # --reuse-from of a queue line: - (none), pretrained, or pretrained@<commit> (extracted once)
  case $1 in
    -) echo "" ;;
    pretrained@*)
      local commit=${1#pretrained@} dst=$RUNS/pretrained-${1#pretrained@}
      if [ ! -f "$dst/manifest.json" ]; then
        rm -rf "$dst.tmp" && mkdir -p "$dst.tmp"
        git -C "$repo" archive "$commit" sb3_smc/library/data/pretrained | tar -x -C "$dst.tmp"
        mv "$dst.tmp/sb3_smc/library/data/pretrained" "$dst" && rm -rf "$dst.tmp"
      fi
      echo "$dst" ;;
    *) echo "$1" ;;
  esac
}

case ${1:-} in
  continue)
    mkdir -p "$RUNS" && exec 9>"$RUNS/.paper_table.lock"
    flock -n 9 || { echo "another 'paper_table.sh continue' is running" >&2; exit 1; }
    while pgrep -f "paper_table.sh run" >/dev/null; do sleep 60; done
    queue | while read -r cat commit reuse _; do
      [ -n "$cat" ] || continue
      if complete "$RUNS/paper-$cat/results.json" || complete "$repo/docs/results/paper/$cat/results.json"; then
        echo "=== $cat: complete"; continue
      fi
      env=$(environment "$commit")
      kept=$repo/docs/results/paper/$cat; dir=$RUNS/paper-$cat
      if [ ! -f "$dir/run.json" ] && [ -f "$kept/run.json" ]; then  # a new machine: resume from the kept records
        mkdir -p "$dir" && cp "$kept/run.json" "$dir/"
        if [ -d "$kept/evaluations" ]; then cp -r "$kept/evaluations" "$dir/"; fi
        for f in wall_time.json results.json; do  # its wall time so far goes on from the kept ledger
          if [ -f "$kept/$f" ]; then cp "$kept/$f" "$dir/"; fi
        done
      fi
      RUN_ENV=$env REUSE_FROM=$(reuse_path "$reuse") nice -n 5 "$0" run "$cat" < /dev/null
      if complete "$dir/results.json"; then "$0" keep "$cat"; fi  # kept as it completes: a later category reads it
    done ;;
  checkpoint)
    queue | while read -r cat commit reuse _; do
      if [ -z "$cat" ] || [ ! -f "$RUNS/paper-$cat/run.json" ] || complete "$repo/docs/results/paper/$cat/results.json"
      then continue; fi
      echo "=== checkpoint $cat $(date -Is)"
      RUN_ENV=$(environment "$commit") "$0" partial "$cat" < /dev/null  # a complete run: tabulated again, kept
    done
    "$0" report ;;
  run)
    shift
    export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
    for cat in ${@:-search objects containment objcon}; do
      chosen=$(selection "$cat")
      if [ -z "$chosen" ]; then echo "=== $cat: no target needs it, nothing to run"; continue; fi
      echo "=== $cat start $(date -Is)"
      rc=0
      # shellcheck disable=SC2086
      "$RUN_ENV/bin/sb3-smc" experiment --out "$RUNS/paper-$cat" $chosen --seeds 5 --workers 2 \
        ${REUSE_FROM:+--reuse-from "$REUSE_FROM"} $(options "$cat") || rc=$?
      echo "=== $cat end $(date -Is) rc=$rc"
    done ;;
  keep)
    cat=$2; repo=${3:-$repo}
    src=$RUNS/paper-$cat; dst=$repo/docs/results/paper/$cat
    mkdir -p "$dst"
    cp "$src/run.json" "$dst/"
    for f in results.csv results.json wall_time.json; do if [ -f "$src/$f" ]; then cp "$src/$f" "$dst/"; fi; done
    for d in evaluations cnn; do if [ -d "$src/$d" ]; then rm -rf "${dst:?}/$d"; cp -r "$src/$d" "$dst/$d"; fi; done
    if [ -f "$src/library/manifest.json" ]; then  # every trained SMC's primitive moves (the equal-experience section)
      "$(dirname "$0")/../.venv/bin/python" -m sb3_smc.experiments.experience "$src" --out "$dst/experience.json"
    fi
    du -sh "$dst" ;;
  partial)
    cat=$2
    export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
    # shellcheck disable=SC2046
    if ! "$RUN_ENV/bin/sb3-smc" experiment --out "$RUNS/paper-$cat" $(selection "$cat") --seeds 5 --workers 2 \
        --no-train $(options "$cat"); then echo "=== $cat: not tabulated (the error above), not kept"; exit 0; fi
    if ! holds "$RUNS/paper-$cat/results.json" rows; then echo "=== $cat: nothing evaluated yet, not kept"; exit 0; fi
    "$0" keep "$cat"
    "$repo/.venv/bin/sb3-smc" report "$repo/docs/results/paper/$cat" --no-behaviour ;;
  report)
    mapfile -t dirs < <(complete_dirs)  # complete categories only: a partial one is kept, not reported
    # shellcheck disable=SC2046
    "$repo/.venv/bin/sb3-smc" report "${dirs[@]}" --out "$repo/docs/results/paper" --no-behaviour $(rerun_options)
    "$repo/.venv/bin/python" "$repo/tools/readme_table.py" --brief
    "$repo/.venv/bin/python" "$repo/tools/readme_table.py" --readme "$repo/docs/results/paper/README.md" ;;
  *) echo "usage: $0 run [categories...] | continue | checkpoint | keep <category> [repo] | partial <category> | report" >&2
     exit 2 ;;
esac
