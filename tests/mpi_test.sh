#!/usr/bin/env bash
# mpi_test.sh - `ilf-mpi` (the MPI build, docs/cluster.md) against `ilf`.
#
# Usage: bash mpi_test.sh BUILD_DIR DATA_DIR TMPDIR [SLOWCLOCK_SO|-] [FAILALLOC_SO]
#
# (a) Identity. 'beams' (its light field and a diffuse lamp added, 0.15 m
#     cells, 2 bounces) relit by `ilf --threads 1` and by `mpirun -n K
#     ilf-mpi --threads T` for (K, T) = (1, 2), (2, 1), (2, 2), (3, 1): every
#     radiance.h5 must be the same file, byte for byte (cmp; h5diff and the
#     bytes of every array of format 2 say what differs if it is not), and
#     every view.exr the same bytes; the same for adaptive at K = 3, for a
#     direct pass of several chunks a cell dataset at K = 3, and for 2 ranks
#     of 2 and 1 threads (tiles claimed as ranks become free); with one rank
#     slowed by 0.25 s a tile (SLOWCLOCK_SO preloaded on it), the other claims
#     most of the tiles. Point queries
#     with a bounce, from a file and from standard input, K = 1, 2, 3: the
#     same lines as `ilf irradiance`.
# (b) Faults. The job must exit non-zero with the failing rank's message and
#     leave no output (nor a staging folder) when: one rank is given a scene
#     that does not exist (exit 2); one rank runs out of memory in the middle
#     of its run (FAILALLOC_SO preloaded on it alone; exit 1); one rank is
#     killed with SIGKILL during the run.
# The last line is "N passed, M failed"; the exit status is nonzero if anything failed.
set -u

if [ $# -lt 3 ]; then
    echo "usage: bash mpi_test.sh BUILD_DIR DATA_DIR TMPDIR [SLOWCLOCK_SO|-] [FAILALLOC_SO]" >&2
    exit 2
fi
build=$(cd "$1" && pwd)
data=$(cd "$2" && pwd)
tmp=$3
slowclock=${4:-}
[ "$slowclock" = "-" ] && slowclock=""
failalloc=${5:-}
ilf=$build/tools/ilf
ilf_mpi=$build/tools/ilf-mpi
. "$(dirname "$0")/checks.sh"

rm -rf "$tmp"
mkdir -p "$tmp"
cd "$tmp" || exit 2

# Open MPI refuses root unless told; a test machine's container often runs as root.
mpirun=(mpirun --oversubscribe)
[ "$(id -u)" -eq 0 ] && mpirun+=(--allow-run-as-root)
export OMPI_MCA_rmaps_base_oversubscribe=1
# Containers often forbid the cross-process copies of the shared-memory transport.
export OMPI_MCA_btl_vader_single_copy_mechanism=none

python3 - "$data" scene.json <<'EOF'
import json, sys
data, out = sys.argv[1], sys.argv[2]
s = json.load(open(data + "/beams.json"))
for lf in s["lightfields"]:
    lf["file"] = data + "/" + lf["file"]
s["radiance_maps"]["cell_size"] = 0.15
s["camera"]["width"], s["camera"]["height"] = 160, 120
s["materials"]["lamp"] = {"albedo": [0, 0, 0], "emission": [4, 4, 3]}
s["polygons"].append({"material": "lamp", "vertices": [[0.5, 4.2, 2.99], [0.5, 4.6, 2.99], [0.9, 4.6, 2.99], [0.9, 4.2, 2.99]]})
s["sampling"]["bounces"] = 2
json.dump(s, open(out, "w"), indent=1)
EOF

# ------------------------------------------------------------------ (a) identity

"$ilf" relight scene.json -o ref --threads 1 --quiet
"$ilf" relight scene.json -o ref_direct --threads 1 --quiet --no-view --bounces 0
check "ilf relight makes the reference" test -s ref/radiance.h5 -a -s ref/view.exr

same_image() { # A B: two EXR files with the same bytes but for the capDate stamp that OpenEXR writes
    python3 -c "
import re, sys
a, b = (re.sub(rb'capDate\0string\0.{4}[0-9: ]{19}', b'', open(f, 'rb').read(), count=1) for f in sys.argv[1:])
sys.exit(a != b)" "$1" "$2"
}
same_maps() { # DIR: its radiance.h5 and view.exr equal the reference's
    h5diff -q ref/radiance.h5 "$1/radiance.h5" >/dev/null && cmp -s ref/radiance.h5 "$1/radiance.h5" \
        && same_image ref/view.exr "$1/view.exr"
}
for kt in "1 2" "2 1" "2 2" "3 1"; do
    set -- $kt
    "${mpirun[@]}" -n "$1" "$ilf_mpi" relight scene.json -o "k$1t$2" --threads "$2" --quiet
    check "relight: $1 rank(s) x $2 thread(s) exits 0" test $? -eq 0
    check "relight: $1 rank(s) x $2 thread(s) gives the maps and view of one process" same_maps "k$1t$2"
done
# h5diff compares values; the arrays' bytes as read are compared too, and the files are format 2 (each array
# once for all maps, written by every rank collectively)
H5PY=""  # a python3 with h5py, if any (h5diff's comparison of values stands without it)
for candidate in python3 /usr/bin/python3; do
    if command -v "$candidate" >/dev/null && "$candidate" -c "import h5py" 2>/dev/null; then
        H5PY=$candidate
        break
    fi
done
same_arrays() { # A B: radiance.h5 files of format 2 whose every dataset holds the same bytes
    "$H5PY" -c "
import sys, h5py
a, b = (h5py.File(p, 'r') for p in sys.argv[1:])
assert int(a.attrs['format_version']) == 2 and int(b.attrs['format_version']) == 2
assert sorted(a['patches']) == sorted(b['patches'])
sys.exit(any(a['patches'][k][()].tobytes() != b['patches'][k][()].tobytes() for k in a['patches']))" "$1" "$2"
}
for kt in "1 2" "2 1" "3 1"; do
    set -- $kt
    [ -n "$H5PY" ] && check "relight: $1 rank(s) x $2 thread(s) writes format 2 with the bytes of one process" \
        same_arrays ref/radiance.h5 "k$1t$2/radiance.h5"
done
[ -z "$H5PY" ] && echo "note: no python3 with h5py: the arrays' bytes and the format version are not compared"
check "h5diff sees a different seed (the comparison can fail)" \
    bash -c "'$ilf' relight scene.json -o seed --threads 1 --quiet --seed 9 --no-view && ! h5diff -q ref/radiance.h5 seed/radiance.h5 >/dev/null"
# a bounce pass exchanges twice when it gathers some cells on their own (near an occluder) after the larger ones
check "stats.json of a 2-rank run names 2 ranks and an exchange per pass, two for a bounce pass with cells of its own" \
    python3 -c "import json; d = json.load(open('k2t1/stats.json')); assert d['ranks'] == 2 and len(d['exchanges']) == 1 + sum(1 + (p['cells_direct'] > 0) for p in d['passes'][1:]) > 3 and all(x['bytes'] > 0 for x in d['exchanges']), d"
# tiles are claimed as ranks become free (dealt up front, stats.json would say 0 claimed): rank 0 claims
# some of every pass's tiles
check "stats.json of 2 and 3 ranks: rank 0 claimed tiles in every pass" \
    python3 -c "import json; a, b = (json.load(open(p + '/stats.json')) for p in ('k2t1', 'k3t1')); assert all(x['tiles_claimed'] > 0 for x in a['exchanges'] + b['exchanges']), (a, b)"
"$ilf" relight scene.json -o ref_adaptive --threads 1 --quiet --method adaptive --no-view --bounces 1
"${mpirun[@]}" -n 3 "$ilf_mpi" relight scene.json -o adaptive3 --threads 1 --quiet --method adaptive --no-view --bounces 1
check "adaptive: 3 ranks give the maps of one process, byte for byte" cmp ref_adaptive/radiance.h5 adaptive3/radiance.h5
# Cells of 0.05 m: more than one chunk (16,384 cells) a cell dataset, so chunks straddle the ranks' runs.
python3 -c "import json; s = json.load(open('scene.json')); s['radiance_maps']['cell_size'] = 0.05; json.dump(s, open('fine.json', 'w'))"
"$ilf" relight fine.json -o ref_fine --threads 1 --quiet --no-view --bounces 0
"${mpirun[@]}" -n 3 "$ilf_mpi" relight fine.json -o fine3 --threads 1 --quiet --no-view --bounces 0
check "direct pass of 0.05 m cells: more than 16,384 cells" \
    python3 -c "import json; assert json.load(open('ref_fine/stats.json'))['cells'] > 16384"
check "direct pass of 0.05 m cells: 3 ranks write the file of one process, byte for byte" \
    cmp ref_fine/radiance.h5 fine3/radiance.h5
# each rank reads only its own chunks' cells from the solution: the count reported is still the file's
check "direct pass of 0.05 m cells: stats.json of 3 ranks counts the cells of one process" \
    python3 -c "import json; a, b = (json.load(open(p + '/stats.json'))['cells'] for p in ('ref_fine', 'fine3')); assert a == b, (a, b)"
# Ranks of unequal speed (2 threads and 1) claim unequal shares of the tiles as each becomes free: the
# maps must not depend on who claimed which.
"${mpirun[@]}" -n 1 "$ilf_mpi" relight scene.json -o uneven --threads 2 --quiet : \
    -n 1 "$ilf_mpi" relight scene.json -o uneven --threads 1 --quiet
check "relight: ranks of 2 and 1 threads give the maps and view of one process" same_maps uneven
if [ -n "$slowclock" ]; then
    # One rank slowed by 0.5 s a tile (two readings of its thread clock): the other claims most of the direct
    # pass's tiles, whichever rank is slow. Dealt up front, each would do its share, slow or not.
    for slow in 0 1; do
        ctx0=(-n 1) ctx1=(-n 1)
        [ "$slow" -eq 0 ] && ctx0+=(-x LD_PRELOAD="$slowclock" -x ILFKIT_SLOW_CLOCK=0.25)
        [ "$slow" -eq 1 ] && ctx1+=(-x LD_PRELOAD="$slowclock" -x ILFKIT_SLOW_CLOCK=0.25)
        "${mpirun[@]}" "${ctx0[@]}" "$ilf_mpi" relight scene.json -o "slow$slow" --threads 1 --quiet --no-view --bounces 0 : \
            "${ctx1[@]}" "$ilf_mpi" relight scene.json -o "slow$slow" --threads 1 --quiet --no-view --bounces 0
        check "relight with rank $slow slowed: the maps of one process" h5diff -q ref_direct/radiance.h5 "slow$slow/radiance.h5"
    done
    check "rank 0 claims at least 3 times the tiles when rank 1 is the slow one as when it is slow itself" \
        python3 -c "import json; f, s = (json.load(open(p + '/stats.json'))['exchanges'][0]['tiles_claimed'] for p in ('slow1', 'slow0')); assert f >= 3 * s and s > 0, (f, s)"
fi

python3 - > points.txt <<'EOF'
import random
random.seed(5)
for k in range(300):
    print("%.4f %.4f %.4f 0 0 1" % (random.uniform(0.1, 4.9), random.uniform(0.1, 4.9), random.uniform(0, 1.5)))
EOF
"$ilf" irradiance scene.json --points points.txt --bounces 1 --threads 1 > points_ref.txt
check "ilf irradiance answers every point" test "$(wc -l < points_ref.txt)" -eq 300
for k in 1 2 3; do
    "${mpirun[@]}" -n "$k" "$ilf_mpi" irradiance scene.json --points points.txt --bounces 1 --threads 1 > "points_$k.txt"
    check "irradiance: $k rank(s), points from a file, the same answers" cmp -s points_ref.txt "points_$k.txt"
done
"${mpirun[@]}" -n 2 "$ilf_mpi" irradiance scene.json --points - --bounces 1 --threads 1 < points.txt > points_stdin.txt
check "irradiance: 2 ranks, points from standard input, the same answers" cmp -s points_ref.txt points_stdin.txt

# ------------------------------------------------------------------ (b) faults

no_output() { # DIR: no radiance.h5, no staging folder left
    [ ! -e "$1/radiance.h5" ] && ! ls -a "$1" 2>/dev/null | grep -q '^\.relight\.tmp-'
}

"${mpirun[@]}" -n 1 "$ilf_mpi" relight scene.json -o bad --threads 1 --quiet : \
    -n 1 "$ilf_mpi" relight missing.json -o bad --threads 1 --quiet 2> bad.err
code=$?
check "a scene missing on one rank: the job exits 2 (got $code)" test "$code" -eq 2
check "a scene missing on one rank: its message names the file and the rank" grep -q 'rank 1 of 2.*missing.json' bad.err
check "a scene missing on one rank: no output" no_output bad

if [ -n "$failalloc" ]; then
    # Count rank 1's allocations in a whole run, then fail the one at 60% of them: in a pass.
    "${mpirun[@]}" -n 1 "$ilf_mpi" relight scene.json -o count --threads 1 --quiet --no-view : \
        -n 1 -x LD_PRELOAD="$failalloc" -x ILFKIT_FAIL_ALLOC_LOG="$tmp/count.log" \
        "$ilf_mpi" relight scene.json -o count --threads 1 --quiet --no-view
    total=$(cut -d' ' -f1 count.log 2>/dev/null)
    check "the allocation counter counted rank 1's run" test "${total:-0}" -gt 100
    n=$(( ${total:-0} * 6 / 10 ))
    timeout 300 "${mpirun[@]}" -n 1 "$ilf_mpi" relight scene.json -o oom --threads 1 --quiet --no-view : \
        -n 1 -x LD_PRELOAD="$failalloc" -x ILFKIT_FAIL_ALLOC="$n" \
        "$ilf_mpi" relight scene.json -o oom --threads 1 --quiet --no-view 2> oom.err
    code=$?
    check "rank 1 out of memory (allocation $n of $total): the job exits 1 (got $code)" test "$code" -eq 1
    check "rank 1 out of memory: its message says so" grep -q 'rank 1 of 2.*out of memory' oom.err
    check "rank 1 out of memory: no output" no_output oom
fi

# SIGKILL to rank 1 once rank 0 has made its staging folder (the engine is running).
big=$tmp/big.json
python3 -c "import json; s = json.load(open('scene.json')); s['radiance_maps']['cell_size'] = 0.04; json.dump(s, open('$big', 'w'))"
"${mpirun[@]}" -n 2 "$ilf_mpi" relight "$big" -o killed --threads 1 --quiet --no-view 2> killed.err &
job=$!
victim=""
for _ in $(seq 600); do
    if ls -a killed 2>/dev/null | grep -q '^\.relight\.tmp-'; then
        for pid in $(pgrep -f "ilf-mpi relight $big"); do
            if tr '\0' '\n' < "/proc/$pid/environ" 2>/dev/null | grep -qx 'OMPI_COMM_WORLD_RANK=1'; then
                victim=$pid
            fi
        done
        [ -n "$victim" ] && break
    fi
    sleep 0.05
done
check "found rank 1 of the run to kill" test -n "$victim"
[ -n "$victim" ] && kill -KILL "$victim"
wait "$job"
code=$?
check "rank 1 killed: the job exits non-zero (got $code)" test "$code" -ne 0
check "rank 1 killed: no radiance.h5 and no staging folder left" no_output killed

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
