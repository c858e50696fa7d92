#!/usr/bin/env bash
# run.sh - runs one libFuzzer target of tests/fuzz for a while on its corpus.
#
# Usage: tests/fuzz/run.sh TARGET SECONDS [BUILD_DIR]
#
#   TARGET     fuzz_scene, fuzz_mesh, fuzz_lightfield, fuzz_radmap, fuzz_h5read, fuzz_manifest or fuzz_points
#   SECONDS    how long to fuzz
#   BUILD_DIR  a build configured with ILFKIT_FUZZ=ON (default build-fuzz):
#                CC=clang CXX=clang++ cmake -S . -B build-fuzz -DILFKIT_FUZZ=ON
#                cmake --build build-fuzz --target TARGET
#
# The committed seeds (tests/fuzz/corpus/TARGET) are only read: new inputs go
# to BUILD_DIR/fuzz/TARGET/corpus, which later runs start from, and any input
# that crashes, leaks, overflows or hangs (10 s) is saved in
# BUILD_DIR/fuzz/TARGET/ as crash-*, leak-* or timeout-*, named in the log.
# Exit status: 0 when the time ran out without a finding, nonzero otherwise.
# FUZZ_SEED=S fixes libFuzzer's random seed (CI uses 1, so that a short run
# tries the same inputs on every commit and a finding there is one of them).
set -eu

if [ $# -lt 2 ] || [ $# -gt 3 ]; then
    echo "usage: tests/fuzz/run.sh TARGET SECONDS [BUILD_DIR]" >&2
    exit 2
fi
TARGET=$1
SECONDS_TO_RUN=$2
HERE=$(cd "$(dirname "$0")" && pwd)
BUILD=${3:-$HERE/../../build-fuzz}
BINARY=$BUILD/tests/fuzz/$TARGET
SEEDS=$HERE/corpus/$TARGET
WORK=$BUILD/fuzz/$TARGET

if [ ! -x "$BINARY" ]; then
    echo "run.sh: $BINARY not found; build it with ILFKIT_FUZZ=ON (see the top of this script)" >&2
    exit 2
fi
if [ ! -d "$SEEDS" ]; then
    echo "run.sh: no seed corpus $SEEDS" >&2
    exit 2
fi
mkdir -p "$WORK/corpus"
# Leaks inside HDF5 and assimp are theirs (see tests/lsan.supp); ours are still findings.
export LSAN_OPTIONS="suppressions=$HERE/../lsan.supp${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
# Full stacks for every allocation: a leak inside assimp's C++ shows only operator new with the
# fast unwinder, which the suppression of libassimp cannot match (fuzz_mesh found one in its ASCII
# STL reader; corpus/fuzz_mesh/stl_assimp_leak.bin keeps it).
export ASAN_OPTIONS="fast_unwind_on_malloc=0${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
SEED=()
[ -n "${FUZZ_SEED:-}" ] && SEED=(-seed="$FUZZ_SEED")
DICT=()
[ -f "$HERE/$TARGET.dict" ] && DICT=(-dict="$HERE/$TARGET.dict")
# One worker: the machine is shared. rss_limit keeps a runaway allocation a finding, not an OOM kill.
exec "$BINARY" "$WORK/corpus" "$SEEDS" -max_total_time="$SECONDS_TO_RUN" -timeout=10 -rss_limit_mb=2048 \
    -max_len=65536 -artifact_prefix="$WORK/" -print_final_stats=1 "${SEED[@]}" "${DICT[@]}"
