#!/usr/bin/env bash
# hostile_test.sh - runs the hostile-input corpus (tests/hostile/) through `ilf`.
#
# Usage: bash hostile_test.sh ILF_BINARY CORPUS_DIR TMPDIR
#
# CORPUS_DIR is tests/hostile: cases.txt lists every case (kind, exit code,
# file, problem), the small text cases sit beside it, and gen_hostile.py
# writes the big and binary ones at test time (the edited light field files
# only when a python3 with h5py exists; their cases are skipped otherwise).
# Each case runs the commands that read its kind of file (cases.txt says
# which) and checks each run: it ends within 20 s, is neither killed by a
# signal nor reports a sanitizer error, exits with the listed code, names
# the file (its basename) and the problem in its output, and leaves no
# output behind. Cases run as many at a time as there are processors. The
# last line is "N passed, M failed"; the exit status is nonzero if anything
# failed. Leaks inside third-party libraries are suppressed (tests/lsan.supp).
#
# Readers without a command of their own are reported as skipped: radiance-map
# files (no `ilf` command reads them; tests/fuzz/fuzz_radmap.c covers their
# reader) and, with an `ilf` that has no capture command, manifests and images.
set -u

if [ $# -ne 3 ]; then
    echo "usage: bash hostile_test.sh ILF_BINARY CORPUS_DIR TMPDIR" >&2
    exit 2
fi
ILF=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
CORPUS=$2
TMP=$3
LIMIT=20
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
    local log=$TMP/logs/$(basename "$result") status why="" shown="$*"
    timeout -k 5 "$LIMIT" "$@" >"$log" 2>&1
    status=$?
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
    fi
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
        "${expect[@]}" - "$ILF" info "$path"
        "${expect[@]}" - "$ILF" verify "$path"
        "${expect[@]}" "$out.png" "$ILF" slice "$path" --position 0,0 -o "$out.png"
        "${expect[@]}" "$out" "$ILF" relight "$(wrap lightfield "$path" "$n")" -o "$out" --quiet
        ;;
    verify) "${expect[@]}" - "$ILF" verify "$path" ;;
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
elif ! "$PY" "$WORK/gen_hostile.py" "$WORK/gen" "$WORK/gen/base.h5"; then
    echo "FAIL: gen_hostile.py failed" >"$TMP/results/gen"
fi

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

echo "skip: radiance-map files: no ilf command reads them (tests/fuzz/fuzz_radmap.c covers lfio_radmap_read)"
[ "$CAPTURE" -eq 1 ] || echo "skip: capture manifests and images: this ilf has no capture command"

passed=$(cat "$TMP"/results/* 2>/dev/null | grep -c '^pass$')
failed=$(cat "$TMP"/results/* 2>/dev/null | grep -c '^FAIL')
grep -h -v '^pass$' "$TMP"/results/* 2>/dev/null
[ "$skipped" -gt 0 ] && echo "$skipped cases skipped"
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ] && [ "$passed" -gt 0 ]
