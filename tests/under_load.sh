#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# under_load.sh -- run the test suite beside CPU hogs, as on a busy laptop or CI runner:
# the suite must stay green when it gets a fraction of the machine.
#
#   tests/under_load.sh [--hogs N] [--runs R] [--at-once P] [--fresh] [--logs DIR]
#                       [-- COMMAND ARGS...]
#
# Starts N busy loops (default 8), runs COMMAND (default: make test) R times (default 1)
# beside them, stops the hogs whatever happens (Ctrl-C, a failed run), and prints one
# line per run and "K of R runs passed". --fresh runs each time in a fresh clone of this
# repository's HEAD (under $TMPDIR, removed afterwards): a cold build and nothing left
# over, as a newcomer has it. --at-once P runs P of them side by side (default 1): each
# run then has the other runs beside it as well as the hogs, a harsher load than one at a
# time (--at-once needs --fresh: runs in one checkout would share its build folders).
# Each run's output goes to DIR/run-K.log (default build-load/); its line gives the 1-minute
# load average's mean and peak over the run (sampled every 10 s). Exit status: 0 only when
# every run passed.
set -uo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
clones=${TMPDIR:-/tmp}/canola-fresh-$$ # CLONES-K: run K's clone
hogs=8 runs=1 at_once=1 fresh=0 logs=$root/build-load
while (($#)); do
    case $1 in
        --hogs) hogs=${2:?}; shift 2 ;;
        --runs) runs=${2:?}; shift 2 ;;
        --at-once) at_once=${2:?}; shift 2 ;;
        --fresh) fresh=1; shift ;;
        --logs) logs=${2:?}; shift 2 ;;
        --) shift; break ;;
        -h | --help) sed -n '2,18p' "$0"; exit 0 ;;
        *) echo "under_load.sh: unknown option $1 (see --help)" >&2; exit 2 ;;
    esac
done
[[ $hogs =~ ^[0-9]+$ && $runs =~ ^[1-9][0-9]*$ && $at_once =~ ^[1-9][0-9]*$ ]] || {
    echo "under_load.sh: --hogs is 0 or more, --runs and --at-once 1 or more" >&2
    exit 2
}
((at_once == 1 || fresh)) || {
    echo "under_load.sh: --at-once $at_once needs --fresh (one checkout's build folders are shared)" >&2
    exit 2
}
command=("$@")
((${#command[@]})) || command=(make test)

mkdir -p "$logs" && logs=$(cd "$logs" && pwd) || exit 2
rm -f "$logs"/.result-* "$logs"/.load-*
hog_pids=()
run_pids=() # the runs going, each the leader of its own session (setsid)
loadavg() { cut -d' ' -f1-3 /proc/loadavg; }
# sample_load FILE: the 1-minute load average into FILE, one line every 10 s, until killed
# (its sleep goes with it: nothing of the script's is left running)
sample_load() {
    local nap
    trap 'kill $nap 2>/dev/null; exit 0' TERM
    while :; do
        sleep 10 &
        nap=$!
        wait $nap
        cut -d' ' -f1 /proc/loadavg >>"$1"
    done
}
# load_over FILE: the samples' mean and peak, as the run's line shows them
load_over() {
    awk '{ s += $1; if ($1 > m) m = $1 } END { printf "mean %.1f, peak %.1f", s / NR, m }' "$1"
}
stop_all() {
    # runs still going (Ctrl-C): each whole session
    local pid
    for pid in "${run_pids[@]}"; do
        kill -TERM -- -"$pid" 2>/dev/null
        wait "$pid" 2>/dev/null
    done
    run_pids=()
    ((${#hog_pids[@]})) && kill "${hog_pids[@]}" 2>/dev/null
    ((${#hog_pids[@]})) && wait "${hog_pids[@]}" 2>/dev/null
    hog_pids=()
    rm -rf "$clones"-*
}
trap stop_all EXIT
trap 'exit 130' INT TERM

# one_run K: run COMMAND once (in a fresh clone with --fresh), its output in run-K.log, and
# its one-line result in .result-K.
one_run() {
    local k=$1 dir=$root log=$logs/run-$1.log start=$SECONDS rc=0 took sampler load
    if ((fresh)); then
        dir=$clones-$k
        rm -rf "$dir"
        git clone -q "$root" "$dir" && git -C "$dir" checkout -q "$(git -C "$root" rev-parse HEAD)" ||
            { echo "run $k: FAIL (cannot clone $root)" >"$logs/.result-$k"; return; }
    fi
    cut -d' ' -f1 /proc/loadavg >"$logs/.load-$k" # one sample however short the run
    sample_load "$logs/.load-$k" </dev/null >/dev/null 2>&1 &
    sampler=$!
    (cd "$dir" && "${command[@]}") >"$log" 2>&1 </dev/null || rc=$?
    kill "$sampler" 2>/dev/null
    wait "$sampler" 2>/dev/null
    took=$((SECONDS - start))
    load="1-min load $(load_over "$logs/.load-$k") over the run; now $(loadavg)"
    if ((rc == 0)); then
        echo "run $k: PASS in $((took / 60))m$((took % 60))s ($load)" >"$logs/.result-$k"
    else
        echo "run $k: FAIL (exit $rc) in $((took / 60))m$((took % 60))s ($load), log: $log" \
            >"$logs/.result-$k"
    fi
    ((fresh)) && rm -rf "$dir"
}

for ((i = 0; i < hogs; i++)); do
    (exec -a under_load-hog bash -c 'while :; do :; done') &
    hog_pids+=($!)
done
echo "under_load.sh: $hogs CPU hogs on $(nproc) cores; ${command[*]}, $runs run(s), $at_once at a time$( ((fresh)) && echo ", each in a fresh clone")"

# report K: the run's line and its own summary table, when it printed one
report() {
    cat "$logs/.result-$1"
    sed -n '/^== summary/,$p' "$logs/run-$1.log" 2>/dev/null
}

next=1 reported=1
while ((reported <= runs)); do
    while ((${#run_pids[@]} < at_once && next <= runs)); do
        # In a subshell, not a plain `cmd &`: bash starts a background command with Ctrl-C
        # (SIGINT) ignored, and the run's processes would inherit that (a test's Ctrl-C to
        # the program it runs would do nothing); the subshell takes back the default.
        (exec setsid bash -c "$(declare -f one_run loadavg sample_load load_over); $(declare -p root clones logs fresh command); one_run $next") \
            </dev/null &
        run_pids+=($!)
        next=$((next + 1))
    done
    wait -n "${run_pids[@]}" 2>/dev/null
    alive=()
    for pid in "${run_pids[@]}"; do kill -0 "$pid" 2>/dev/null && alive+=("$pid"); done
    run_pids=("${alive[@]}")
    # in order of the runs, as each one's result is in
    while ((reported < next)) && [[ -s $logs/.result-$reported ]]; do
        report "$reported"
        reported=$((reported + 1))
    done
    # a run that left no result (killed): report it as failed rather than wait for ever
    if ((${#run_pids[@]} == 0 && next > runs)); then
        for ((k = reported; k <= runs; k++)); do
            [[ -s $logs/.result-$k ]] || echo "run $k: FAIL (no result)" >"$logs/.result-$k"
            report "$k"
        done
        reported=$((runs + 1))
    fi
done
passed=$(grep -l ': PASS in' "$logs"/.result-* 2>/dev/null | wc -l)
stop_all
echo "under_load.sh: $passed of $runs runs passed beside $hogs CPU hogs, $at_once at a time (load $(loadavg))"
((passed == runs))
