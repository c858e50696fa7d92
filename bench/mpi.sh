#!/usr/bin/env bash
# bench/mpi.sh - ilf-mpi against ilf on one machine (BENCHMARKS-journal.md, section 6).
#
# Usage: bench/mpi.sh BUILD_MPI_DIR OUT [REPEATS]
#
# For each case, alternating runs (one process x 2 threads, then 2 ranks x
# 1 thread, REPEATS times, default 3): the whole run's wall time (stats.json
# of ilf, /usr/bin/time of mpirun, so MPI start-up counts), each pass's wall
# time, the bytes each exchange gathered and its time (waiting for the
# slowest rank, then moving), and the time of writing radiance.h5. Checks
# that both give the same maps (h5diff). Prints one table row per run and
# medians to OUT/mpi.txt.
#
# Cases: the classroom at its own 51,140 cells with 2 bounces, and at the
# paper's size (0.018 m cells, 1.3 M cells), direct only.
set -eu
if [ $# -lt 2 ]; then
    echo "usage: bench/mpi.sh BUILD_MPI_DIR OUT [REPEATS]" >&2
    exit 2
fi
root=$(cd "$(dirname "$0")/.." && pwd)
build=$(cd "$1" && pwd)
out=$2
repeats=${3:-3}
mkdir -p "$out"
out=$(cd "$out" && pwd)
ilf=$build/tools/ilf
ilf_mpi=$build/tools/ilf-mpi
mpirun=(mpirun --oversubscribe)
[ "$(id -u)" -eq 0 ] && mpirun+=(--allow-run-as-root)
sed 's/"cell_size": *[0-9.]*/"cell_size": 0.018/' "$root/data/classroom.json" > "$root/data/.bench_classroom_paper.json"

report=$out/mpi.txt
: > "$report"
say() { echo "$*" | tee -a "$report"; }

# One run: LABEL DIR COMMAND... ; appends "label wall passes exchanges write" to $out/runs.txt
run() {
    local label=$1 dir=$2
    shift 2
    rm -rf "$dir"
    local t0 t1
    t0=$(date +%s.%N)
    "$@" -o "$dir" --quiet --no-view
    t1=$(date +%s.%N)
    python3 - "$label" "$dir/stats.json" "$t0" "$t1" >> "$out/runs.txt" <<'EOF'
import json, sys
label, path, t0, t1 = sys.argv[1], sys.argv[2], float(sys.argv[3]), float(sys.argv[4])
d = json.load(open(path))
passes = ",".join("%.3f" % p["wall_seconds"] for p in d["passes"])
ex = d.get("exchanges", [])
exch = ",".join("%d:%.4f:%.4f" % (x["bytes"], x["wait_seconds"], x["move_seconds"]) for x in ex) or "-"
print("%s %.3f %.3f %s %s %.4f %d" % (label, t1 - t0, d["wall_seconds"], passes, exch, d["radiance_write_seconds"], d["cells"]))
EOF
}

: > "$out/runs.txt"
for case in "classroom $root/data/classroom.json --bounces 2" \
            "classroom_paper $root/data/.bench_classroom_paper.json --bounces 0"; do
    set -- $case
    name=$1 scene=$2
    shift 2
    for r in $(seq "$repeats"); do
        run "$name:1x2" "$out/$name-1x2" "$ilf" relight "$scene" "$@" --threads 2
        run "$name:2x1" "$out/$name-2x1" "${mpirun[@]}" -n 2 "$ilf_mpi" relight "$scene" "$@" --threads 1
    done
    if h5diff -q "$out/$name-1x2/radiance.h5" "$out/$name-2x1/radiance.h5" >/dev/null; then
        say "$name: the same maps from 1 x 2 and 2 x 1"
    else
        say "$name: THE MAPS DIFFER"
    fi
done

echo "" >> "$report"
echo "label | runs | whole run (median, s) | engine (median, s) | passes (last run, s) | exchanges (bytes:wait:move) | radiance.h5 write (s) | cells" >> "$report"
python3 - "$out/runs.txt" >> "$report" <<'EOF'
import sys, statistics, collections
rows = collections.OrderedDict()
for line in open(sys.argv[1]):
    f = line.split()
    rows.setdefault(f[0], []).append(f)
for label, rs in rows.items():
    print("%s | %d | %.2f | %.2f | %s | %s | %s | %s" % (label, len(rs), statistics.median(float(r[1]) for r in rs),
          statistics.median(float(r[2]) for r in rs), rs[-1][3], rs[-1][4], rs[-1][5], rs[-1][6]))
EOF
cat "$report"
