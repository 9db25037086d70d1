#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# under_load.sh -- run the test suite beside CPU hogs, as on a busy laptop or CI runner:
# the suite must stay green when it gets a fraction of the machine.
#
#   tests/under_load.sh [--hogs N] [--runs R] [--fresh] [-- COMMAND ARGS...]
#
# Starts N busy loops (default 8), runs COMMAND (default: make test) R times (default 1)
# beside them, stops the hogs whatever happens (Ctrl-C, a failed run), and prints one
# line per run and "K of R runs passed". --fresh runs each time in a fresh clone of this
# repository's HEAD (under $TMPDIR, removed afterwards): a cold build and nothing left
# over, as a newcomer has it. Each run's output goes to build-load/run-K.log. Exit status:
# 0 only when every run passed.
set -uo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
hogs=8 runs=1 fresh=0
while (($#)); do
    case $1 in
        --hogs) hogs=${2:?}; shift 2 ;;
        --runs) runs=${2:?}; shift 2 ;;
        --fresh) fresh=1; shift ;;
        --) shift; break ;;
        -h | --help) sed -n '2,12p' "$0"; exit 0 ;;
        *) echo "under_load.sh: unknown option $1 (see --help)" >&2; exit 2 ;;
    esac
done
((hogs >= 0 && runs >= 1)) 2>/dev/null || { echo "under_load.sh: bad --hogs/--runs" >&2; exit 2; }
command=("$@")
((${#command[@]})) || command=(make test)

logs=$root/build-load
mkdir -p "$logs"
hog_pids=()
clones=()
run_pid=
stop_hogs() {
    # a run still going (Ctrl-C): its whole session, which setsid gave it
    [[ -n $run_pid ]] && kill -TERM -- -"$run_pid" 2>/dev/null && wait "$run_pid" 2>/dev/null
    ((${#hog_pids[@]})) && kill "${hog_pids[@]}" 2>/dev/null
    ((${#hog_pids[@]})) && wait "${hog_pids[@]}" 2>/dev/null
    hog_pids=()
    for d in "${clones[@]}"; do rm -rf "$d"; done
    clones=()
}
trap stop_hogs EXIT
trap 'exit 130' INT TERM

for ((i = 0; i < hogs; i++)); do
    (exec -a under_load-hog bash -c 'while :; do :; done') &
    hog_pids+=($!)
done
echo "under_load.sh: $hogs CPU hogs on $(nproc) cores; ${command[*]}, $runs run(s)$( ((fresh)) && echo ", each in a fresh clone")"

passed=0
results=()
for ((run = 1; run <= runs; run++)); do
    dir=$root
    if ((fresh)); then
        dir=$(mktemp -d "${TMPDIR:-/tmp}/canola-fresh.XXXXXX")
        clones+=("$dir")
        git clone -q "$root" "$dir" && git -C "$dir" checkout -q "$(git -C "$root" rev-parse HEAD)"
    fi
    log=$logs/run-$run.log
    start=$SECONDS
    rc=0
    (cd "$dir" && exec setsid "${command[@]}") >"$log" 2>&1 </dev/null &
    run_pid=$!
    wait "$run_pid" || rc=$?
    run_pid=
    took=$((SECONDS - start))
    load=$(cut -d' ' -f1-3 /proc/loadavg)
    if ((rc == 0)); then
        passed=$((passed + 1))
        results+=("run $run: PASS in $((took / 60))m$((took % 60))s (load $load)")
    else
        results+=("run $run: FAIL (exit $rc) in $((took / 60))m$((took % 60))s (load $load), log: $log")
    fi
    echo "${results[-1]}"
    # the run's own summary table, when it printed one
    sed -n '/^== summary/,$p' "$log"
    if ((fresh)); then
        rm -rf "$dir"
        clones=()
    fi
done
stop_hogs
echo "under_load.sh: $passed of $runs runs passed beside $hogs CPU hogs"
((passed == runs))
