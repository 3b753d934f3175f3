#!/usr/bin/env bash
# The few-shot table in the background, from a worktree at a fixed commit, resumable on any machine:
#
#   tools/few_shot_table.sh continue [WORLDS...]   # default WORLDS: 1 2 4 8 all; two processes, one per core
#   tools/few_shot_table.sh checkpoint             # copy the records back, rewrite results.csv and the report
#
# `continue` adds a worktree of HEAD at $FEW_SHOT_SRC (default $RUNS/few-shot-src, RUNS /work/runs; an existing one is
# kept, at its commit), seeds its run directory with the committed records (docs/results/few_shot/records: every recorded
# cell is skipped) and starts two processes at `nice 15`, the targets split between them (FEW_SHOT_TARGETS[0::2] and
# [1::2]), each running the WORLDS in turn with the methods base, curr, canon and auto (`--methods cnn` is a separate,
# quick column). Logs: $FEW_SHOT_SRC/log_A.txt and log_B.txt. `checkpoint` copies the run's new records into
# docs/results/few_shot/records/ and writes results.csv, report.md and the figure from them; then commit.
set -euo pipefail
repo="$(cd "$(dirname "$0")/.." && pwd)"
runs="${RUNS:-/work/runs}"
src="${FEW_SHOT_SRC:-$runs/few-shot-src}"
py="$repo/.venv/bin/python"
case "${1:-}" in
  continue)
    shift
    worlds="${*:-1 2 4 8 all}"
    if pgrep -f "tools/few_shot_table.py --out $src/" > /dev/null; then
      echo "the few-shot table is already running from $src" >&2; exit 1
    fi
    mkdir -p "$runs"
    [ -d "$src" ] || git -C "$repo" worktree add -f "$src" HEAD -q
    mkdir -p "$src/runs/few-shot/records"
    cp -rn "$repo/docs/results/few_shot/records/." "$src/runs/few-shot/records/"
    for half in A B; do
      start=$([ "$half" = A ] && echo 0 || echo 1)
      targets=$("$py" -c "from sb3_smc.experiments.few_shot import FEW_SHOT_TARGETS as T; print(','.join(T[$start::2]))")
      nohup bash -c "for w in $worlds; do OMP_NUM_THREADS=1 PYTHONPATH='$src' nice -n 15 '$py' '$src/tools/few_shot_table.py' \
        --out '$src/runs/few-shot' --worlds \$w --methods base,curr,canon,auto --targets '$targets'; done" \
        > "$src/log_$half.txt" 2>&1 &
    done
    echo "started from $(git -C "$src" log --oneline -1 | cut -c1-60); logs: $src/log_A.txt, $src/log_B.txt" ;;
  checkpoint)
    [ -d "$src/runs/few-shot/records" ] || { echo "no run at $src" >&2; exit 1; }
    cp -rn "$src/runs/few-shot/records/." "$repo/docs/results/few_shot/records/"
    cd "$repo"
    "$py" -c "
from sb3_smc.experiments.few_shot import write_results
from sb3_smc.experiments.few_shot_report import read_results, write_report
out = 'docs/results/few_shot'
cells = len(read_results(write_results(out)))
write_report(out)
print(f'{out}: {cells} cells; results.csv, report.md and few_shot.png written')" ;;
  *) echo "usage: $0 continue [WORLDS...] | checkpoint" >&2; exit 2 ;;
esac
