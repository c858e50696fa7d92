#!/usr/bin/env bash
# hostile_test.sh - runs the hostile-input corpus (tests/hostile/) through `ilf`.
#
# Usage: bash hostile_test.sh ILF_BINARY CORPUS_DIR TMPDIR [--no-budget]
#
# CORPUS_DIR is tests/hostile: cases.txt lists every case (kind, exit code,
# file, problem), the small text cases sit beside it, and gen_hostile.py
# writes the big and binary ones at test time (the edited light field files
# only when a python3 with h5py exists; their cases are skipped otherwise).
# Each case runs the commands that read its kind of file (cases.txt says
# which) and checks each run: it ends within 20 s, is neither killed by a
# signal nor reports a sanitizer error, exits with the listed code, names
# the file (its basename) and the problem in its output, leaves no output
# behind, and stays within the budget of a bad file: 0.5 s of CPU time (user
# + system: unlike wall time, it does not grow when other work shares the
# machine) and 64 MiB of peak memory, both above the program's own baseline,
# the largest of the same commands on small valid inputs (measured first, in
# the same run: loading OpenImageIO alone costs about 0.55 s and 139 MiB). --no-budget
# (sanitizer builds, whose shadow memory and checks inflate both) keeps the
# measurements but not the budget. Every run's CPU time and memory are
# printed. Cases run as many at a time as there are processors. The last
# line is "N passed, M failed"; the exit status is nonzero if anything
# failed. Leaks inside third-party libraries are suppressed (tests/lsan.supp).
#
# Readers without a command of their own are reported as skipped: with an
# `ilf` that has no capture command, manifests and images.
set -u

if [ $# -lt 3 ] || [ $# -gt 4 ] || { [ $# -eq 4 ] && [ "$4" != --no-budget ]; }; then
    echo "usage: bash hostile_test.sh ILF_BINARY CORPUS_DIR TMPDIR [--no-budget]" >&2
    exit 2
fi
ILF=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
CORPUS=$2
TMP=$3
BUDGET=1
[ $# -eq 4 ] && BUDGET=0
LIMIT=20
CPU_BUDGET=0.5   # seconds of CPU time a bad file may cost above the baseline
MEM_BUDGET=65536 # KiB of peak memory above the commands' own baseline
MEASURE=$(cd "$(dirname "$0")" && pwd)/hostile/measure.py
MPY=/usr/bin/python3
[ -x "$MPY" ] || MPY=$(command -v python3)
PARALLEL=$(nproc 2>/dev/null || echo 2)

rm -rf "$TMP"
mkdir -p "$TMP/results" "$TMP/logs" "$TMP/wrap" "$TMP/out"
cp -r "$CORPUS" "$TMP/corpus"
WORK=$(cd "$TMP/corpus" && pwd)
# Leaks inside HDF5 and assimp on broken files are theirs (tests/lsan.supp), not ours.
export LSAN_OPTIONS="suppressions=$(cd "$(dirname "$0")" && pwd)/lsan.supp${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
POINTS=$TMP/points.txt
printf '0 0 0 0 0 1\n' >"$POINTS"

# ------------------------------------------------------------------ checking one run

# expect_failure RESULT EXIT FILE PROBLEM OUTPUT COMMAND...: runs COMMAND and appends to
# RESULT one line, "pass" or "FAIL: <why>", for the checks described at the top. OUTPUT
# must not exist afterwards ("-": nothing to check).
expect_failure() {
    local result=$1 want=$2 file=$3 problem=$4 output=$5
    shift 5
    local log=$TMP/logs/$(basename "$result") status why="" shown="$*" cpu rss
    "$MPY" "$MEASURE" "$LIMIT" "$log.usage" "$@" >"$log" 2>&1
    status=$?
    read -r cpu rss <"$log.usage" 2>/dev/null || { cpu=0 rss=0; }
    if [ "$status" -eq 124 ] || [ "$status" -eq 137 ]; then
        why="no answer within $LIMIT s"
    elif [ "$status" -ge 128 ]; then
        why="killed by signal $((status - 128))"
    elif grep -q -E "Sanitizer|runtime error:" "$log"; then
        why="sanitizer report"
    elif [ "$status" -ne "$want" ]; then
        why="exit $status, expected $want"
    elif ! grep -q -F -- "$(basename "$file")" "$log"; then
        why="the output does not name $(basename "$file")"
    elif ! grep -q -i -F -- "$problem" "$log"; then
        why="the output does not say '$problem'"
    elif [ "$output" != - ] && [ -e "$output" ]; then
        why="it left $output behind"
    elif [ "$BUDGET" -eq 1 ] && awk -v c="$cpu" -v b="$CPU_BUDGET" -v z="$BASE_CPU" 'BEGIN { exit !(c > z + b) }'; then
        why="it took $cpu s of CPU time, over the baseline $BASE_CPU s + $CPU_BUDGET s"
    elif [ "$BUDGET" -eq 1 ] && [ $((rss - BASELINE)) -gt "$MEM_BUDGET" ]; then
        why="it peaked at $((rss / 1024)) MiB, over the baseline $((BASELINE / 1024)) MiB + $((MEM_BUDGET / 1024)) MiB"
    fi
    printf '%6.3f s CPU %5d MiB (baseline %+4d MiB)  %s\n' "$cpu" $((rss / 1024)) $(((rss - BASELINE) / 1024)) \
        "${shown#"$ILF "}" >>"$TMP/costs"
    if [ -z "$why" ]; then
        echo "pass" >>"$result"
    else
        { echo "FAIL: ${shown#"$ILF "}: $why"; sed 's/^/    | /' "$log" | head -n 8; } >>"$result"
    fi
}

# ------------------------------------------------------------------ commands per kind

# wrap KIND PATH NAME: writes a scene whose only mesh or light field is PATH, or a capture
# manifest whose only image is PATH. @stdout its path.
wrap() {
    local file=$TMP/wrap/$3.json
    case $1 in
    mesh) printf '{"materials": {"grey": {}}, "meshes": [{"file": "%s", "material": "grey"}]}\n' "$2" ;;
    lightfield) printf '{"lightfields": [{"file": "%s"}]}\n' "$2" ;;
    image)
        printf '{"plane": {"origin": [0, 0, 1], "u": [1, 0, 0], "v": [0, -1, 0]}, "grid": {"nu": 1, "nv": 1}, '
        printf '"n": 2, "pattern": "%s"}\n' "$2"
        ;;
    esac >"$file"
    echo "$file"
}

# run_outputs N PATH EXPECT...: every command that writes an output, with PATH as its output (a special
# file); PATH must still be what it was afterwards (never replaced by a regular file).
run_outputs() {
    local n=$1 path=$2 out=$TMP/out/$1 before
    shift 2
    before=$(stat -L -c %F "$path")
    "$@" - "$ILF" synth --kind constant --grid 2x2 --n 2 -o "$path"
    "$@" - "$ILF" slice "$WORK/gen/base.h5" --position 0,0 -o "$path"
    "$@" - "$ILF" relight "$TMP/valid.json" -o "$path" --quiet
    "$@" - "$ILF" reproject "$WORK/gen/base.h5" --proxy "$PROXY" -o "$path" --quiet
    "$@" - "$ILF" render-probes "$TMP/valid.json" --plane 0,0,0.5:1,0,0:0,1,0 -o "$path" --quiet
    [ "$CAPTURE" -eq 1 ] && "$@" - "$ILF" capture "$STUDIO" -o "$path" --quiet
    if [ "$(stat -L -c %F "$path")" != "$before" ]; then
        echo "FAIL: $path was $before, is now $(stat -L -c %F "$path")" >>"$TMP/results/$n"
    fi
}

# run_case N KIND EXIT FILE PROBLEM: runs every command of KIND on FILE; results go to results/N.
run_case() {
    local n=$1 kind=$2 path=$WORK/$4 out=$TMP/out/$1
    local expect=(expect_failure "$TMP/results/$n" "$3" "$4" "$5")
    case $kind in
    scene)
        "${expect[@]}" "$out" "$ILF" relight "$path" -o "$out" --quiet
        "${expect[@]}" - "$ILF" irradiance "$path" --points "$POINTS"
        ;;
    mesh) "${expect[@]}" "$out" "$ILF" relight "$(wrap mesh "$path" "$n")" -o "$out" --quiet ;;
    lightfield)
        "${expect[@]}" - "$ILF" info "$path" --stats
        "${expect[@]}" - "$ILF" verify "$path"
        "${expect[@]}" "$out.png" "$ILF" slice "$path" --position 0,0 -o "$out.png"
        "${expect[@]}" "$out" "$ILF" relight "$(wrap lightfield "$path" "$n")" -o "$out" --quiet
        ;;
    verify) "${expect[@]}" - "$ILF" verify "$path" ;;
    radmap | radmaphead)
        if [ "$kind" = radmaphead ]; then
            "${expect[@]}" - "$ILF" info "$path"
            "${expect[@]}" - "$ILF" info "$path" --maps
        fi
        "${expect[@]}" - "$ILF" info "$path" --stats
        "${expect[@]}" - "$ILF" verify "$path"
        "${expect[@]}" "$out.glb" "$ILF" export "$path" -o "$out.glb"
        "${expect[@]}" "$out.png" "$ILF" view "$path" -o "$out.png" --position 1,1,2 --look-at 1,1,0 --up 0,1,0
        ;;
    points) "${expect[@]}" - "$ILF" irradiance "$TMP/valid.json" --points "$path" ;;
    proxy) "${expect[@]}" "$out.h5" "$ILF" reproject "$WORK/gen/base.h5" --proxy "$path" -o "$out.h5" --quiet ;;
    output) run_outputs "$n" "$path" "${expect[@]}" ;;
    manifest) "${expect[@]}" "$out.h5" "$ILF" capture "$path" -o "$out.h5" --quiet ;;
    image) "${expect[@]}" "$out.h5" "$ILF" capture "$(wrap image "$path" "$n")" -o "$out.h5" --quiet ;;
    *) echo "FAIL: cases.txt: unknown kind '$kind' for $4" >>"$TMP/results/$n" ;;
    esac
}

# ------------------------------------------------------------------ generated files

# The first python3 that imports h5py, else any python3 (gen_hostile.py then skips its HDF5 edits).
PY=""
for candidate in python3 /usr/bin/python3; do
    if command -v "$candidate" >/dev/null && "$candidate" -c "import h5py, numpy" 2>/dev/null; then
        PY=$candidate
        break
    fi
done
[ -z "$PY" ] && PY=$(command -v python3 || true)
CAPTURE=0
"$ILF" --help | grep -q '^  capture ' && CAPTURE=1
mkdir -p "$WORK/gen/image"
if ! "$ILF" synth --kind radial --grid 4x3 --n 2 --name base -o "$WORK/gen/base.h5" >/dev/null; then
    echo "FAIL: cannot write the base light field with ilf synth" >"$TMP/results/base"
elif [ "$CAPTURE" -eq 1 ] && ! "$ILF" slice "$WORK/gen/base.h5" --direction 0 -o "$WORK/gen/image/valid.exr" >/dev/null; then
    echo "FAIL: cannot write the valid image with ilf slice" >"$TMP/results/image"
elif [ -z "$PY" ]; then
    echo "note: python3 not found: the generated cases are skipped"
elif ! "$ILF" relight "$(dirname "$0")/scenes/cli_square.json" -o "$WORK/gen/relit" --no-view --quiet; then
    echo "FAIL: cannot write the base radiance map with ilf relight" >"$TMP/results/radmap"
elif ! "$PY" "$WORK/gen_hostile.py" "$WORK/gen" "$WORK/gen/base.h5" "$WORK/gen/relit/radiance.h5"; then
    echo "FAIL: gen_hostile.py failed" >"$TMP/results/gen"
fi

# ------------------------------------------------------------------ special files

# Special files where a file belongs, and files naming them (cp -r does not copy FIFOs, so they are made
# here, under gen/io): every input is opened without blocking and refused unless it is a regular file
# (a FIFO would otherwise hang the command), every output refused unless it is a regular file or nothing.
IO=$WORK/gen/io
mkdir -p "$IO"
for f in fifo.json fifo.obj fifo.mtl fifo.bin fifo.txt fifo.exr fifo.h5 fifo_out.png; do
    mkfifo "$IO/$f"
done
ln -s /dev/zero "$IO/zero.json"
ln -s /dev/null "$IO/null.png"
printf 'mtllib fifo.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n' >"$IO/mtllib_fifo.obj"
printf '{"asset": {"version": "2.0"}, "buffers": [{"uri": "fifo.bin", "byteLength": 48}],
  "bufferViews": [{"buffer": 0, "byteLength": 48}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                 "min": [0, 0, 0], "max": [1, 1, 0]}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
  "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}], "scene": 0}\n' >"$IO/buffer_fifo.gltf"
printf '0 0 1 0 0 1\n1 1 0 0\0000 1\n' >"$IO/nul_in_line.txt"
printf '{"pattern": "fifo.exr", "plane": {"origin": [0, 0, 1], "u": [1, 0, 0], "v": [0, -1, 0]},
  "grid": {"nu": 1, "nv": 1}, "n": 2}\n' >"$IO/image_fifo.json"
PROXY=$CORPUS/../../data/capture/proxy.json
STUDIO=$CORPUS/../../data/capture/studio.json

# ------------------------------------------------------------------ the baseline

# The commands' own peak memory on small valid inputs: the largest is what a bad file's run
# is measured against (relight and capture load Embree, HDF5 and, to read images, OpenImageIO:
# the capture of the repository's studio probe is the baseline of a run that reads one).
printf '{"materials": {"lamp": {"emission": [1, 1, 1]}, "grey": {}}, "polygons": [
  {"material": "lamp", "vertices": [[0, 0, 1], [0, 1, 1], [1, 1, 1], [1, 0, 1]]},
  {"material": "grey", "vertices": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]}],
  "radiance_maps": {"cell_size": 0.25}}\n' >"$TMP/valid.json"
BASELINE=0
BASE_CPU=0
baseline() {
    "$MPY" "$MEASURE" "$LIMIT" "$TMP/baseline.usage" "$@" >/dev/null 2>&1
    local cpu rss
    read -r cpu rss <"$TMP/baseline.usage" 2>/dev/null || { cpu=0 rss=0; }
    [ "$rss" -gt "$BASELINE" ] && BASELINE=$rss
    BASE_CPU=$(awk -v a="$BASE_CPU" -v b="$cpu" 'BEGIN { print (b > a ? b : a) }')
    echo "baseline: ${*#"$ILF "}: $cpu s CPU, $((rss / 1024)) MiB"
}
baseline "$ILF" relight "$TMP/valid.json" -o "$TMP/valid-out" --quiet
baseline "$ILF" irradiance "$TMP/valid.json" --points "$POINTS"
if [ -e "$WORK/gen/base.h5" ]; then
    baseline "$ILF" info "$WORK/gen/base.h5" --stats
    baseline "$ILF" verify "$WORK/gen/base.h5"
    baseline "$ILF" slice "$WORK/gen/base.h5" --position 0,0 -o "$TMP/valid-slice.png"
fi
if [ "$CAPTURE" -eq 1 ] && [ -e "$STUDIO" ]; then
    baseline "$ILF" capture "$STUDIO" -o "$TMP/valid-capture.h5" --quiet
fi
rm -rf "$TMP/valid-out" "$TMP/valid-slice.png" "$TMP/valid-capture.h5"

# ------------------------------------------------------------------ the corpus

skipped=0
running=0
n=0
while read -r kind want file problem; do
    case $kind in '' | '#'*) continue ;; esac
    n=$((n + 1))
    if [ "$CAPTURE" -eq 0 ] && { [ "$kind" = manifest ] || [ "$kind" = image ]; }; then
        skipped=$((skipped + 1))
        continue
    fi
    if [ ! -e "$WORK/$file" ]; then
        echo "skip: $file was not generated"
        skipped=$((skipped + 1))
        continue
    fi
    run_case "$(printf '%03d' "$n")" "$kind" "$want" "$file" "$problem" &
    running=$((running + 1))
    if [ "$running" -ge "$PARALLEL" ]; then
        wait -n
        running=$((running - 1))
    fi
done <"$WORK/cases.txt"
wait

[ "$CAPTURE" -eq 1 ] || echo "skip: capture manifests and images: this ilf has no capture command"

echo "what each run cost (CPU time, peak memory), most expensive first:"
sort -g -r "$TMP/costs" 2>/dev/null
passed=$(cat "$TMP"/results/* 2>/dev/null | grep -c '^pass$')
failed=$(cat "$TMP"/results/* 2>/dev/null | grep -c '^FAIL')
grep -h -v '^pass$' "$TMP"/results/* 2>/dev/null
[ "$skipped" -gt 0 ] && echo "$skipped cases skipped"
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ] && [ "$passed" -gt 0 ]
