#!/usr/bin/env bash
# alloc_fault_test.sh - out-of-memory paths taken on purpose: each `ilf` run
# below is repeated with its N-th allocation made to fail (tests/fault/failalloc.c,
# loaded with LD_PRELOAD), as SQLite's tests do.
#
# Usage: bash alloc_fault_test.sh ILF_BINARY FAILALLOC_SO SOURCE_DIR TMPDIR
#
# The runs: writing a light field (synth), reading one (info, verify), a
# radiance map's headers (info),
# loading a scene with a mesh and a light field and relighting it with one
# bounce and a view, and with direct light alone, a capture of a 2x2 probe grid, a depth correction, and
# point queries. Each is first run untouched to count its allocations M (by
# ilfkit's own code: libraries' are not counted). Then for N in 1..M, every N
# when ILFKIT_FAULT_WALK=full, else every N up to W and W more spread evenly
# over the rest (W = ILFKIT_FAULT_WALK, default 40; the sanitizer build uses
# 20; ILFKIT_FAULT_ONLY=TEXT walks only the runs whose name holds TEXT), the
# run with the N-th allocation failing must:
#   - exit 1 (a failed run, not bad input: cli.h), saying "memory" or
#     "allocat", with no crash, no sanitizer report and no leak (when built
#     with ILFKIT_SANITIZE, LeakSanitizer turns a leak into a failing exit);
#   - leave no output and no temporary in its folder (the listing is as before).
# The last line is "N passed, M failed"; the exit status is nonzero if anything failed.
set -u

if [ $# -ne 4 ]; then
    echo "usage: bash alloc_fault_test.sh ILF_BINARY FAILALLOC_SO SOURCE_DIR TMPDIR" >&2
    exit 2
fi
ILF=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
SHIM=$(cd "$(dirname "$2")" && pwd)/$(basename "$2")
SRC=$(cd "$3" && pwd)
TMP=$4
rm -rf "$TMP"
mkdir -p "$TMP"
TMP=$(cd "$TMP" && pwd)
LOG=$TMP/log
COUNT=$TMP/count
WALK=${ILFKIT_FAULT_WALK:-40}
JOBS=$(nproc 2>/dev/null || echo 2)
# Under the sanitizers the shim is preloaded ahead of libasan, which must be told that is fine;
# leaks inside HDF5 and assimp are theirs (lsan.supp).
export ASAN_OPTIONS="verify_asan_link_order=0${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
export LSAN_OPTIONS="suppressions=$SRC/tests/lsan.supp:print_suppressions=0${LSAN_OPTIONS:+:$LSAN_OPTIONS}"

. "$SRC/tests/checks.sh"

# The folder every run works in, with its inputs.
WORK=$TMP/work
mkdir -p "$WORK"
cp "$SRC/tests/fault/room.json" "$SRC/tests/fault/box.obj" "$WORK/"
cp -r "$SRC/data/capture/synthetic" "$WORK/probes"
cp "$SRC/data/capture/proxy.json" "$WORK/"
printf '1 1 0.1 0 0 1\n0.5 0.5 0.2 0 0 1\n1.5 1.9 1 0 -1 0\n' >"$WORK/points.txt"
cd "$WORK" || exit 1
"$ILF" synth --kind spot --grid 4x4 --n 4 -o slab.h5 --spot 0,0,-1:0,0,1:30:2 -q >/dev/null 2>&1 ||
    "$ILF" synth --kind spot --grid 4x4 --n 4 -o slab.h5 --spot 0,0,-1:0,0,1:30:2 >/dev/null
"$ILF" capture probes/manifest.json -o captured.h5 --threads 1 -q >/dev/null
"$ILF" relight room.json -o relit --bounces 0 --no-view --threads 1 -q >/dev/null

# run N LOG COUNT COMMAND...: runs COMMAND in the current folder with allocation N failing (0: none),
# its output in LOG and the shim's "COUNT FIRED" in COUNT.
run() {
    local n=$1 log=$2 count=$3
    shift 3
    rm -f "$count"
    # env, not the shell, preloads the shim: only the command itself is counted, not timeout
    timeout -k 5 120 env ILFKIT_FAIL_ALLOC="$n" ILFKIT_FAIL_ALLOC_LOG="$count" LD_PRELOAD="$SHIM" "$@" >"$log" 2>&1
}

# one N OUTPUT COMMAND...: in a copy of $WORK of its own, runs COMMAND with allocation N failing
# and prints nothing if all is as it must be, else the problem and the start of the output.
one() {
    local n=$1 out=$2 dir=$TMP/run.$1 status fired before after why=""
    shift 2
    cp -r "$WORK" "$dir"
    cd "$dir" || return
    before=$(ls -A)
    run "$n" "$dir.log" "$dir.count" "$@"
    status=$?
    fired=$(cut -d' ' -f2 "$dir.count" 2>/dev/null || echo 0)
    after=$(ls -A)
    if [ "$fired" != 1 ]; then
        why="allocation $n was never made (exit $status)"
    elif [ "$status" -ne 1 ]; then
        why="exit $status, expected 1"
    elif ! grep -q -i -E 'memory|allocat' "$dir.log"; then
        why="no message about memory"
    elif grep -q -E 'Sanitizer|runtime error' "$dir.log"; then
        why="a sanitizer report"
    elif [ "$before" != "$after" ]; then
        why="left files behind: $(comm -13 <(echo "$before") <(echo "$after") | tr '\n' ' ')"
    fi
    if [ -n "$why" ]; then
        echo "allocation $n: $why"
        sed 's/^/    | /' "$dir.log" | grep -v '^    | *$' | head -n 8
    fi
    cd "$TMP" && rm -rf "$dir" "$dir.log" "$dir.count"
}

# walk NAME OUTPUT COMMAND...: the walk of one run whose output (file or folder) is OUTPUT,
# or - for a run that prints its result. Runs go $JOBS at a time, each in its own folder.
walk() {
    local name=$1 out=$2 status count n bad runs=0
    shift 2
    case $name in *"${ILFKIT_FAULT_ONLY:-}"*) ;; *) return ;; esac
    cd "$WORK" || return
    run 0 "$LOG" "$COUNT" "$@"
    status=$?
    count=$(cut -d' ' -f1 "$COUNT" 2>/dev/null || echo 0)
    if [ "$status" -ne 0 ] || { [ "$out" != - ] && [ ! -e "$out" ]; } || [ "$count" -lt 1 ]; then
        failed=$((failed + 1))
        echo "FAIL: $name: the untouched run exited $status with $count allocations"
        sed 's/^/    | /' "$LOG" | head -n 6
        return
    fi
    [ "$out" = - ] || rm -rf "$out"
    local ns
    if [ "$WALK" = full ] || [ "$count" -le $((2 * WALK)) ]; then
        ns=$(seq 1 "$count")
    else
        ns=$( (seq 1 "$WALK"; seq 1 "$WALK" | awk -v m="$count" -v w="$WALK" '{ print w + int(($1 * (m - w)) / w) }') |
            sort -n -u)
    fi
    rm -f "$TMP"/result.*
    for n in $ns; do
        one "$n" "$out" "$@" >"$TMP/result.$n" &
        runs=$((runs + 1))
        while [ "$(jobs -rp | wc -l)" -ge "$JOBS" ]; do
            wait -n
        done
    done
    wait
    bad=$(cat "$TMP"/result.* | grep -c '^allocation')
    if [ "$bad" -gt 0 ]; then
        echo "FAIL: $name, $bad of $runs runs wrong; the first:"
        for n in $ns; do cat "$TMP/result.$n"; done | head -n 30 | sed 's/^/    /'
    fi
    rm -f "$TMP"/result.*
    echo "$name: $runs of $count allocations failed in turn, $bad wrong"
    if [ "$bad" -eq 0 ]; then passed=$((passed + 1)); else failed=$((failed + 1)); fi
}

walk "write a light field" out.h5 "$ILF" synth --kind radial --grid 4x4 --n 4 -o out.h5
walk "read a light field (info)" - "$ILF" info captured.h5 --stats
walk "read a light field (verify)" - "$ILF" verify slab.h5
walk "read a radiance map's headers (info)" - "$ILF" info relit/radiance.h5 --maps
walk "capture a probe grid" cap.h5 "$ILF" capture probes/manifest.json -o cap.h5 --threads 1 -q
walk "depth correction" lamp.h5 "$ILF" reproject captured.h5 --proxy proxy.json -o lamp.h5 --threads 1 -q
# radiance.h5 is written beside the engine, which may fail while the writer waits: with a bounce (its maps
# told in its last pass) and with direct light alone (told as the one pass goes)
walk "relight with a bounce and a view" out "$ILF" relight room.json -o out --threads 1 -q
walk "relight, direct light written beside the engine" out "$ILF" relight room.json -o out --bounces 0 --no-view --threads 1 -q
walk "point queries with a bounce" - "$ILF" irradiance room.json --points points.txt --threads 1

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
