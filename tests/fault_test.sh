#!/usr/bin/env bash
# fault_test.sh - `ilf` under faults: interruptions, a full disk, damaged files.
#
# Usage: bash fault_test.sh ILF_BINARY TMPDIR
#
# (a) Interruptions. `ilf relight` on a small room and `ilf synth` of a
#     radiance-heavy slab are each timed once, then killed with SIGINT,
#     SIGTERM and SIGKILL, once at a random moment of that time and once as
#     soon as a temporary appears beside an output (mid-write). Outputs stay
#     in the folder from run to run, so each run starts over the previous
#     ones. After every kill, each file under a final name must be complete:
#     light fields pass `ilf verify`, radiance.h5 reads whole with h5py (when
#     present), stats.json parses, images end properly. SIGINT and SIGTERM
#     must leave no temporary (`ilf` removes them, cli.h); after SIGKILL a
#     temporary may remain, but only under a temporary name.
# (b) A full disk: a 200 KiB tmpfs when running as root and mount works,
#     else a file size limit (ulimit -f). Writing a light field, the radiance
#     maps, a view image and a captured light field must each fail with exit
#     1 and a message naming the cause, leave no temporary, and leave an
#     existing file untouched.
# (c) Damaged files: one byte flipped in the superblock, object headers and
#     data chunks (located with h5py when present, else spread over a
#     radiance-heavy file) must make `ilf verify` exit 2 naming a checksum.
# (d) Output sets (docs/cli.md): `ilf relight -o new/deep` interrupted by
#     SIGINT or SIGTERM leaves neither folder, and SIGINT says so in one line,
#     as it does for `ilf irradiance`, which writes no file;
#     with FAILRENAME_SHIM (tests/fault/failrename.c) one rename of the
#     placing fails: the folder must hold the earlier run's files, byte for
#     byte, and nothing else (the view of the earlier run included, when the
#     failing run wrote none).
# The last line is "N passed, M failed"; the exit status is nonzero if anything failed.
set -u

if [ $# -ne 2 ] && [ $# -ne 3 ]; then
    echo "usage: bash fault_test.sh ILF_BINARY TMPDIR [FAILRENAME_SHIM]" >&2
    exit 2
fi
ILF=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
TMP=$2
SHIM=${3:-}
LIMIT=120
rm -rf "$TMP"
mkdir -p "$TMP"
TMP=$(cd "$TMP" && pwd)
LOG=$TMP/log
# Leaks inside HDF5 on damaged files are HDF5's (tests/lsan.supp), not ours.
export LSAN_OPTIONS="suppressions=$(cd "$(dirname "$0")" && pwd)/lsan.supp${LSAN_OPTIONS:+:$LSAN_OPTIONS}"

# check DESCRIPTION COMMAND... and the counts $passed, $failed
. "$(dirname "$0")/checks.sh"

# expect CODE TEXT DESCRIPTION COMMAND...: runs COMMAND (output in $LOG) and checks that it ends
# within $LIMIT s with exit code CODE and, unless TEXT is empty, says TEXT (any letter case).
expect() {
    local code=$1 text=$2 what=$3 status
    shift 3
    timeout -k 5 "$LIMIT" "$@" >"$LOG" 2>&1
    status=$?
    if [ "$status" -eq "$code" ] && { [ -z "$text" ] || grep -q -i -F -- "$text" "$LOG"; }; then
        passed=$((passed + 1))
    else
        failed=$((failed + 1))
        echo "FAIL: $what: exit $status (expected $code)${text:+, looking for '$text'}"
        sed 's/^/    | /' "$LOG" | head -n 6
    fi
}

# The first python3 with h5py, else any python3; without one the content checks are skipped.
PY=""
H5PY=0
for candidate in python3 /usr/bin/python3; do
    if command -v "$candidate" >/dev/null && "$candidate" -c "import h5py, numpy" 2>/dev/null; then
        PY=$candidate
        H5PY=1
        break
    fi
done
[ -z "$PY" ] && PY=$(command -v python3 || true)
[ -z "$PY" ] && echo "note: python3 not found: stats.json, image and radiance.h5 contents are not checked"
[ -n "$PY" ] && [ "$H5PY" -eq 0 ] && echo "note: h5py not found: radiance.h5 contents are not checked"

# Reads a finished output whole and fails on anything incomplete: FILE KIND (json, image or radmap).
complete_py='
import sys
path, kind = sys.argv[1], sys.argv[2]
data = open(path, "rb").read()
if kind == "json":
    import json
    json.loads(data)
elif kind == "image" and path.endswith(".png"):
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and data[-12:-4] == b"\0\0\0\0IEND", "incomplete PNG"
elif kind == "image":
    import struct
    assert data[:4] == b"\x76\x2f\x31\x01", "not an EXR"
    pos = 8
    while data[pos] != 0:  # header attributes: name, type, size, value
        pos = data.index(b"\0", data.index(b"\0", pos) + 1) + 1
        size, = struct.unpack("<i", data[pos:pos + 4])
        pos += 4 + size
    pos, = struct.unpack("<Q", data[pos + 1:pos + 9])  # the first chunk, from the offset table
    while pos < len(data):  # scanline chunks: y, byte count, bytes
        count, = struct.unpack("<i", data[pos + 4:pos + 8])
        pos += 8 + count
    assert pos == len(data), "EXR chunks run past the end"
elif kind == "radmap":
    import h5py
    with h5py.File(path, "r") as f:
        assert f.attrs["format"].decode() == "ilfkit-radiance-maps"
        if int(f.attrs["format_version"]) == 1:
            groups = [f["patches"][str(k)] for k in range(int(f.attrs["patch_count"]))]
        else:
            groups = [f["patches"]]
        for g in groups:
            for name, d in g.items():
                d[...]
'

# complete FILE: the output FILE, under its final name, reads back whole.
complete() {
    local file=$1
    case $file in
    *.h5)
        if [ "$(basename "$file")" = radiance.h5 ]; then
            [ "$H5PY" -eq 0 ] || "$PY" -c "$complete_py" "$file" radmap >>"$LOG" 2>&1
        else
            "$ILF" verify "$file" >>"$LOG" 2>&1
        fi
        ;;
    *.json) [ -z "$PY" ] || "$PY" -c "$complete_py" "$file" json >>"$LOG" 2>&1 ;;
    *.exr | *.png) [ -z "$PY" ] || "$PY" -c "$complete_py" "$file" image >>"$LOG" 2>&1 ;;
    *) echo "unexpected file $file" >>"$LOG"; return 1 ;;
    esac
}

# temporaries DIR: lists the writers' temporaries in DIR (the one rule of ilf/atomic_file.h:
# ".x.tmp-<12 hex>" or ".x.tmp-<12 hex>.ext"; find's '*' also matches a leading dot).
temporaries() {
    find "$1" -maxdepth 1 -name '*.tmp-*'
}

# every_output_complete DIR: each file in DIR that is not a temporary reads back whole.
every_output_complete() {
    local file ok=0
    for file in "$1"/* "$1"/.[!.]*; do
        [ -e "$file" ] || continue
        case $(basename "$file") in *.tmp-*) continue ;; esac
        complete "$file" || { echo "    incomplete: $file"; ok=1; }
    done
    return $ok
}

no_temporaries() { [ -z "$(temporaries "$1")" ]; }

# ------------------------------------------------------------------ (a) interruptions

ROOM=$TMP/room.json
cat >"$ROOM" <<'EOF'
{
  "materials": {
    "lamp": {"albedo": [0, 0, 0], "emission": [10, 10, 10]},
    "floor": {"albedo": [0.5, 0.5, 0.5]},
    "wall": {"albedo": [0.7, 0.6, 0.5]}
  },
  "polygons": [
    {"material": "lamp", "vertices": [[1.5, 1.5, 2], [1.5, 2.5, 2], [2.5, 2.5, 2], [2.5, 1.5, 2]]},
    {"material": "floor", "vertices": [[0, 0, 0], [4, 0, 0], [4, 4, 0], [0, 4, 0]]},
    {"material": "wall", "vertices": [[0, 4, 0], [4, 4, 0], [4, 4, 2], [0, 4, 2]]}
  ],
  "radiance_maps": {"cell_size": 0.02},
  "sampling": {"method": "culled", "partition_n": 8, "rays_per_solid_angle": 1, "bounces": 1, "seed": 1},
  "camera": {"position": [2, -3, 1.5], "look_at": [2, 2, 0.5], "fov_deg": 60, "width": 320, "height": 240}
}
EOF

# job_command JOB DIR: sets CMD to the command line of JOB (relight or synth) writing into DIR.
job_command() {
    case $1 in
    relight) CMD=("$ILF" relight "$ROOM" -o "$2" --quiet --threads 2) ;;
    synth) CMD=("$ILF" synth --kind radial --cone 180 --grid 24x24 --n 24 --threads 2 -o "$2/slab.h5") ;;
    esac
}

now_ms() { date +%s%3N; }

# wait_for_temporary PID DIR: returns when a temporary appears in DIR or PID ends.
wait_for_temporary() {
    while kill -0 "$1" 2>/dev/null && no_temporaries "$2"; do
        sleep 0.01
    done
}

# stop PID: waits up to $LIMIT s for PID to end, killing it if it does not; its exit status goes to STATUS.
stop() {
    local waited=0
    while kill -0 "$1" 2>/dev/null && [ "$waited" -lt $((LIMIT * 10)) ]; do
        sleep 0.1
        waited=$((waited + 1))
    done
    kill -KILL "$1" 2>/dev/null
    { wait "$1"; STATUS=$?; } 2>/dev/null # also silences the shell's "Killed" notice
}

# interrupt JOB SIGNAL MOMENT DIR: runs JOB into DIR and sends SIGNAL at MOMENT ("temporary", or
# milliseconds), then checks the process ended and what it left in DIR.
interrupt() {
    local job=$1 sig=$2 moment=$3 dir=$4 pid code
    code=$((128 + $(kill -l "$sig")))
    mkdir -p "$dir"
    job_command "$job" "$dir"
    # Job control: without it a script's background commands start with SIGINT ignored.
    set -m
    "${CMD[@]}" >"$LOG" 2>&1 &
    pid=$!
    set +m
    if [ "$moment" = temporary ]; then
        wait_for_temporary "$pid" "$dir"
    else
        sleep "$(printf '%d.%03d' $((moment / 1000)) $((moment % 1000)))"
    fi
    kill -"$sig" "$pid" 2>/dev/null
    stop "$pid"
    local what="$job, SIG$sig at $moment"
    check "$what: ended by the signal or finished (exit $STATUS)" test "$STATUS" -eq "$code" -o "$STATUS" -eq 0
    check "$what: every output under its final name is complete" every_output_complete "$dir"
    if [ "$sig" = KILL ]; then
        temporaries "$dir" | xargs -r rm -rf -- # allowed leftovers (files, a staging folder); the next run must not see them
    else
        check "$what: no temporaries left ($(temporaries "$dir" | tr '\n' ' '))" no_temporaries "$dir"
    fi
}

# interrupt_job JOB: times JOB, then interrupts it with every signal at two moments.
interrupt_job() {
    local job=$1 dir=$TMP/$1 start took sig
    mkdir -p "$dir"
    job_command "$job" "$dir"
    start=$(now_ms)
    expect 0 "" "$job runs to the end" "${CMD[@]}"
    took=$(($(now_ms) - start))
    # stderr of the shell would carry its "Killed" notices for the jobs; check reports on stdout.
    for sig in INT TERM KILL; do
        interrupt "$job" "$sig" $((took * (5 + RANDOM % 95) / 100)) "$dir" 2>/dev/null
        interrupt "$job" "$sig" temporary "$dir" 2>/dev/null
    done
}

interrupt_job relight
interrupt_job synth

# ------------------------------------------------------------------ (b) a full disk

DISK=$TMP/disk
mkdir -p "$DISK"
LIMITED=()
MOUNTED=0
if [ "$(id -u)" -eq 0 ] && mount -t tmpfs -o size=200k ilf-fault-test "$DISK" 2>/dev/null; then
    MOUNTED=1
    trap 'umount "$DISK" 2>/dev/null' EXIT
    FULL_TEXT="No space left on device"
    echo "note: a full disk is a 200 KiB tmpfs"
    # leave_room KB: fills the disk up to about KB kilobytes of free space.
    leave_room() {
        rm -f "$DISK/filler"
        local avail
        avail=$(df -k --output=avail "$DISK" | tail -n 1)
        [ "$avail" -le "$1" ] || dd if=/dev/zero of="$DISK/filler" bs=1024 count=$((avail - $1)) status=none 2>/dev/null
    }
else
    FULL_TEXT="File too large"
    echo "note: not root or tmpfs unavailable: a full disk is a file size limit"
    # leave_room KB: limits the size of every file written to KB kilobytes (SIGXFSZ ignored,
    # so write() fails with EFBIG instead of killing the command).
    leave_room() {
        LIMITED=(bash -c "trap '' XFSZ; ulimit -f $1; exec \"\$@\"" limited)
    }
fi

# full KB TEXT SUBJECT COMMAND...: with about KB kilobytes left, COMMAND fails with exit 1 saying TEXT.
full() {
    local room=$1 text=$2 what=$3
    shift 3
    leave_room "$room"
    expect 1 "$text" "full disk: $what" "${LIMITED[@]}" "$@"
}

"$ILF" synth --kind constant --grid 2x2 --n 2 -o "$DISK/old.h5" >/dev/null
cp "$DISK/old.h5" "$TMP/old-copy.h5"
BIG=(--kind radial --cone 180 --grid 16x16 --n 16) # about 1.5 MiB
full 100 "$FULL_TEXT" "a light field over an existing one" "$ILF" synth "${BIG[@]}" -o "$DISK/old.h5"
check "full disk: the existing light field is untouched" cmp -s "$DISK/old.h5" "$TMP/old-copy.h5"
full 100 "$FULL_TEXT" "a new light field" "$ILF" synth "${BIG[@]}" -o "$DISK/new.h5"
check "full disk: no partial light field" test ! -e "$DISK/new.h5"
sed -e 's/"cell_size": 0.02/"cell_size": 0.04/' "$ROOM" >"$TMP/room_maps.json" # about 300 KiB of maps
full 100 "$FULL_TEXT" "the radiance maps" "$ILF" relight "$TMP/room_maps.json" -o "$DISK/maps" --quiet
check "full disk: no partial radiance maps" test ! -e "$DISK/maps/radiance.h5"
# Coarse maps (about 10 KiB) that fit, then a view image (about 100 KiB) that does not: the message
# names the image and gives the cause.
sed -e 's/"cell_size": 0.02/"cell_size": 0.5/' -e 's/"width": 320, "height": 240/"width": 1600, "height": 1200/' \
    "$ROOM" >"$TMP/room_view.json"
# LeakSanitizer's tracer crashed on this command in CI when it still loaded OpenImageIO (signal 11 while
# the image libraries' threads were exiting; never reproduced alone), failing the run with exit 134: its
# leak check is left out here.
ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0" \
    full 40 "$FULL_TEXT" "the view image" "$ILF" relight "$TMP/room_view.json" -o "$DISK/view" --quiet
check "full disk: no partial view image" test ! -e "$DISK/view/view.exr"
check "full disk: the radiance maps written before are complete" every_output_complete "$DISK/view"
# ilf capture writes its light field through the same atomic writer: the message must give the
# cause. A probe image (outside the disk) becomes an n = 64 slab of about 800 KiB.
if "$ILF" --help | grep -q '^  capture '; then
    "$ILF" synth --kind radial --cone 180 --grid 2x2 --n 8 -o "$TMP/probe_src.h5" >/dev/null
    "$ILF" slice "$TMP/probe_src.h5" --position 0,0 --layout latlong -o "$TMP/probe.exr" >/dev/null
    printf '{"plane": {"origin": [0, 0, 1], "u": [1, 0, 0], "v": [0, -1, 0]}, "grid": {"nu": 1, "nv": 1}, %s\n' \
        '"n": 64, "pattern": "probe.exr"}' >"$TMP/probe.json"
    full 100 "$FULL_TEXT" "a captured light field" "$ILF" capture "$TMP/probe.json" -o "$DISK/captured.h5" --quiet
    check "full disk: no partial captured light field" test ! -e "$DISK/captured.h5"
else
    echo "note: this ilf has no capture command: its full-disk case is skipped"
fi
check "full disk: no temporaries anywhere ($(find "$DISK" -name '*.tmp-*' | tr '\n' ' '))" \
    test -z "$(find "$DISK" -name '*.tmp-*')"
if [ "$MOUNTED" -eq 1 ]; then
    umount "$DISK" 2>/dev/null
    trap - EXIT
fi

# ------------------------------------------------------------------ (c) damaged files

DAMAGED=$TMP/damaged
mkdir -p "$DAMAGED"
SOURCE=$DAMAGED/source.h5
"$ILF" synth --kind radial --cone 180 --grid 16x16 --n 16 -o "$SOURCE" >/dev/null

# Offsets to damage, one "OFFSET PLACE" per line: the superblock, object headers (40 bytes in: past
# the longest header prefix, among its messages) and the middle of data chunks, or without h5py
# points spread over the file, most of which is compressed radiance.
offsets_py='
import sys, h5py
with h5py.File(sys.argv[1], "r") as f:
    print(20, "superblock")
    print(h5py.h5o.get_info(f.id).addr + 40, "root object header")
    def visit(name, obj):
        print(h5py.h5o.get_info(obj.id).addr + 40, name, "object header")
        if isinstance(obj, h5py.Dataset):
            n = obj.id.get_num_chunks()
            for k in sorted({0, n - 1}):
                c = obj.id.get_chunk_info(k)
                print(c.byte_offset + c.size // 2, name, "chunk", k)
    f.visititems(visit)
'
if [ "$H5PY" -eq 1 ]; then
    "$PY" -c "$offsets_py" "$SOURCE" >"$DAMAGED/offsets"
else
    size=$(wc -c <"$SOURCE")
    for percent in 30 45 60 75 90; do
        echo "$((size * percent / 100)) $percent% into the file"
    done >"$DAMAGED/offsets"
fi

# flip FILE OFFSET: inverts the byte at OFFSET of FILE.
flip() {
    local old
    old=$(od -A n -t u1 -j "$2" -N 1 "$1" | tr -d ' ')
    printf "\\$(printf '%03o' $((old ^ 255)))" | dd of="$1" bs=1 seek="$2" conv=notrunc status=none
}

while read -r offset place; do
    cp "$SOURCE" "$DAMAGED/flipped.h5"
    flip "$DAMAGED/flipped.h5" "$offset"
    expect 2 checksum "ilf verify catches a flipped byte at $offset ($place)" "$ILF" verify "$DAMAGED/flipped.h5"
done <"$DAMAGED/offsets"

# ------------------------------------------------------------------ (d) output sets

SETS=$TMP/sets
mkdir -p "$SETS"
job_command relight "$SETS/new/deep"
start=$(now_ms)
expect 0 "" "relight into new folders runs to the end" "${CMD[@]}"
took=$(($(now_ms) - start))
rm -rf "$SETS/new"
for sig in INT TERM; do
    for share in 20 50; do
        set -m
        "${CMD[@]}" >"$LOG" 2>&1 &
        pid=$!
        set +m
        sleep "$(printf '%d.%03d' $((took * share / 100000)) $((took * share / 100 % 1000)))"
        kill -"$sig" "$pid" 2>/dev/null
        stop "$pid"
        what="relight -o new/deep, SIG$sig at $share% of its time"
        if [ "$STATUS" -eq $((128 + $(kill -l "$sig"))) ]; then
            check "$what: leaves no folder it created" test ! -e "$SETS/new"
            [ "$sig" = INT ] && check "$what: says it was interrupted and what was kept" \
                grep -q "^ilf: interrupted; nothing written" "$LOG"
        else
            check "$what: finished instead (exit $STATUS)" test "$STATUS" -eq 0
        fi
        rm -rf "$SETS/new"
    done
done

# A command that writes no file says it was interrupted all the same (a point query that would take minutes).
printf '2 2 0 0 0 1\n' >"$SETS/points.txt"
set -m
"$ILF" irradiance "$ROOM" --points "$SETS/points.txt" --method area --samples 1048576 --bounces 3 >"$LOG" 2>&1 &
pid=$!
set +m
sleep 1
kill -INT "$pid" 2>/dev/null
stop "$pid"
check "irradiance, SIGINT: ends by it (exit $STATUS)" test "$STATUS" -eq 130
check "irradiance, SIGINT: says so in one line" grep -q "^ilf: interrupted$" "$LOG"

# placed_whole WHY FAILING ARGS...: a relight over $SETS/kept whose rename onto $SETS/kept/FAILING fails
# must exit 1 naming it and leave the earlier run's files exactly as they were.
placed_whole() {
    local why=$1 failing=$2
    shift 2
    ILFKIT_FAIL_RENAME="$SETS/kept/$failing" ASAN_OPTIONS="verify_asan_link_order=0${ASAN_OPTIONS:+:$ASAN_OPTIONS}" \
        LD_PRELOAD="$SHIM" expect 1 "$failing" "$why: exits 1 naming $failing" \
        "$ILF" relight "$ROOM" -o "$SETS/kept" --quiet --threads 2 "$@"
    check "$why: the folder holds the earlier run's files only ($(ls -A "$SETS/kept" | tr '\n' ' '))" \
        test "$(ls -A "$SETS/kept" | tr '\n' ' ')" = "radiance.h5 stats.json view.exr view.png "
    for f in radiance.h5 stats.json view.exr view.png; do
        check "$why: $f is the earlier run's" cmp -s "$SETS/kept/$f" "$SETS/earlier/$f"
    done
}

if [ -n "$SHIM" ] && [ -e "$SHIM" ]; then
    mkdir -p "$SETS/earlier"
    "$ILF" relight "$ROOM" -o "$SETS/kept" --quiet --threads 2 >/dev/null
    cp "$SETS/kept"/* "$SETS/earlier/"
    placed_whole "a view that cannot be placed" view.exr --seed 7
    placed_whole "stats.json that cannot be placed, no view" stats.json --seed 7 --no-view
    expect 0 "" "relight --no-view over the earlier run" "$ILF" relight "$ROOM" -o "$SETS/kept" --quiet --no-view
    check "relight --no-view removed the earlier run's view ($(ls -A "$SETS/kept" | tr '\n' ' '))" \
        test "$(ls -A "$SETS/kept" | tr '\n' ' ')" = "radiance.h5 stats.json "
else
    echo "note: no rename shim given: the placing of output sets is not tested here"
fi

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
