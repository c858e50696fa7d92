#!/usr/bin/env bash
# cli_test.sh - end-to-end test of the `ilf` command.
#
# Usage: bash cli_test.sh ILF_BINARY TMPDIR
#
# Runs ilf as a user would and checks exit codes (0 ok, 1 failure while
# running, 2 bad usage or input), messages, and files: help and version,
# synth of every kind, info as text and JSON, irradiance of a constant field,
# verify, slice in every mode and format, and the error paths (missing,
# foreign, truncated and corrupted inputs; bad numbers; unwritable outputs,
# which must leave no partial file and must not clobber an existing one);
# relight and irradiance on the example scenes (data/, tests/scenes/) with
# coarse settings, against a closed form, and their error paths.
# Every check is counted; the last line is "N passed, M failed" and the exit
# status is nonzero when anything failed. python3 (standard library only)
# parses the JSON and the image headers.
set -u

if [ $# -ne 2 ]; then
    echo "usage: bash cli_test.sh ILF_BINARY TMPDIR" >&2
    exit 2
fi
ILF=$1
TMP=$2
rm -rf "$TMP"
mkdir -p "$TMP"
OUT=$TMP/stdout
ERR=$TMP/stderr

# check DESCRIPTION COMMAND... and the counts $passed, $failed
. "$(dirname "$0")/checks.sh"
status=0

nonempty() { [ -s "$1" ]; }
absent() { [ ! -e "$1" ]; }
none_match() { ! compgen -G "$1" >/dev/null; }
# Nothing but the listed names is in folder $1 (no temporaries left behind).
only_files() {
    local dir=$1
    shift
    [ "$(cd "$dir" && ls -A | sort | tr '\n' ' ')" = "$(printf '%s\n' "$@" | sort | tr '\n' ' ')" ]
}

PYTHON=$(command -v python3 || true)
# py SCRIPT ARGS...: runs a python3 check, or passes with a note when python3 is missing.
py() {
    if [ -z "$PYTHON" ]; then
        echo "note: python3 not found, skipping a check"
        return 0
    fi
    "$PYTHON" -c "$@"
}

# Image header checks with the standard library: EXR channels must be 32-bit
# float (pixel type 2), PNG must be 8-bit; both must have the given size and channels.
image_header_py='
import struct, sys
path, width, height, channels = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
data = open(path, "rb").read()
if path.endswith(".png"):
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    w, h, depth, colour = struct.unpack(">IIBB", data[16:26])
    assert (w, h) == (width, height), (w, h)
    assert depth == 8, depth
    assert colour == {3: 2, 4: 6}[channels], colour
else:
    assert data[:4] == b"\x76\x2f\x31\x01", "not an EXR"
    pos, types, window = 8, [], None
    while data[pos] != 0:
        end = data.index(b"\0", pos); name = data[pos:end]; pos = end + 1
        end = data.index(b"\0", pos); kind = data[pos:end]; pos = end + 1
        size, = struct.unpack("<i", data[pos:pos + 4]); pos += 4
        value = data[pos:pos + size]; pos += size
        if name == b"channels":
            at = 0
            while value[at] != 0:
                at = value.index(b"\0", at) + 1
                types.append(struct.unpack("<i", value[at:at + 4])[0]); at += 16
        if name == b"dataWindow":
            x0, y0, x1, y1 = struct.unpack("<iiii", value)
            window = (x1 - x0 + 1, y1 - y0 + 1)
    assert window == (width, height), window
    assert types == [2] * channels, types
'
image_is() { py "$image_header_py" "$@"; }

# ------------------------------------------------------------------ help
expect 0 "ilf --help" "$ILF" --help
check "ilf --help shows Usage" stdout_has "Usage"
for sub in synth info verify slice relight irradiance; do
    check "ilf --help lists $sub" stdout_has "^  $sub "
done
# the project's version (ctest passes it; by hand, read from CMakeLists.txt)
ILF_EXPECTED_VERSION=${ILF_EXPECTED_VERSION:-$(sed -n 's/^project(ilfkit VERSION \([0-9.]*\).*/\1/p' "$(dirname "$0")/../CMakeLists.txt")}
expect 0 "ilf --version" "$ILF" --version
check "version line" stdout_has "^ilf (ilfkit) ${ILF_EXPECTED_VERSION//./\\.}, lfio ${ILF_EXPECTED_VERSION//./\\.}\$"
for sub in synth info verify slice relight irradiance; do
    expect 0 "ilf $sub --help" "$ILF" "$sub" --help
    check "ilf $sub --help shows Usage" stdout_has "^Usage: ilf $sub"
    check "ilf $sub --help shows an example" stdout_has "^Example"
done
expect 2 "no arguments" "$ILF"
expect 2 "unknown subcommand" "$ILF" frobnicate
check "unknown subcommand is named" stderr_has "frobnicate"
expect 2 "unknown top-level option" "$ILF" --frobnicate
for sub in synth info verify slice relight irradiance; do
    expect 2 "$sub: unknown option" "$ILF" "$sub" --frobnicate
    check "$sub: unknown option is named" stderr_has "--frobnicate"
done

# ------------------------------------------------------------------ synth
CONST=$TMP/constant.h5
RADIAL=$TMP/radial.h5
SPOT=$TMP/spot.h5
expect 0 "synth constant" "$ILF" synth --kind constant --grid 8x6 --n 4 --name flat --radiance 2,2,2 -o "$CONST"
check "synth constant wrote a file" nonempty "$CONST"
check "synth prints where it wrote" stdout_has "constant.h5"
expect 0 "synth radial" "$ILF" synth --kind radial --grid 8x8 --n 8 --cone 30 --supersample 2 -o "$RADIAL"
check "synth radial wrote a file" nonempty "$RADIAL"
expect 0 "synth radial again" "$ILF" synth --kind radial --grid 8x8 --n 8 --cone 30 --supersample 2 \
    -o "$TMP/radial-again.h5"
check "the same synth writes the same bytes" cmp "$RADIAL" "$TMP/radial-again.h5"
expect 0 "synth spot" "$ILF" synth --kind spot --grid 8x8 --n 8 --spot 0,0,-1:0,0,1:30:2:0.3 \
    --spot=0.2,0,-0.5:0,0,1:45:0 -o "$SPOT"
check "synth spot wrote a file" nonempty "$SPOT"
expect 0 "synth with --threads 1" "$ILF" synth --kind radial --grid 8x8 --n 8 --cone 30 --supersample 2 \
    --threads 1 -o "$TMP/radial-1thread.h5"
expect 0 "info of the one-thread file" "$ILF" info "$TMP/radial-1thread.h5"
cp "$OUT" "$TMP/info-1thread.txt"
expect 0 "info of the many-thread file" "$ILF" info "$RADIAL"
check "the result does not depend on the thread count" \
    diff <(grep -v -e '^file' -e 'creator' "$TMP/info-1thread.txt") <(grep -v -e '^file' -e 'creator' "$OUT")
# every command reads --threads by one parser: 0 (every processor) .. 1024
expect 0 "synth with --threads 0 (every processor)" "$ILF" synth --kind radial --grid 8x8 --n 8 --cone 30 \
    --supersample 2 --threads 0 -o "$TMP/radial-0threads.h5"
check "synth on every processor writes the same bytes" cmp "$RADIAL" "$TMP/radial-0threads.h5"
for cmd in synth relight irradiance capture reproject; do
    expect 2 "$cmd refuses --threads 1025" "$ILF" $cmd --threads 1025
    check "$cmd names the one thread range" stderr_has "must be from 0 to 1024"
done

# ------------------------------------------------------------------ info
expect 0 "info (text)" "$ILF" info "$CONST" --stats
check "info shows the grid" stdout_has "8x6 positions"
check "info shows n" stdout_has "n: *4 (64 directions)"
check "info shows the name" stdout_has "slab 0: flat"
check "info shows the radiance" stdout_has "radiance max: *2 2 2"
expect 0 "info --json" "$ILF" info "$CONST" --json --stats
check "info --json is JSON" py 'import json,sys; json.load(sys.stdin)' <"$OUT"
check "info --json has the values given" py '
import json, sys
d = json.load(sys.stdin)
s = d["slabs"][0]
assert s["name"] == "flat" and s["nu"] == 8 and s["nv"] == 6 and s["n"] == 4, s
assert s["directions"] == 64 and s["units"] == "W sr^-1 m^-2", s
assert s["radiance_min"] == [2, 2, 2] and s["zero_fraction"] == 0, s
assert s["mask"][-1] == {"n": 4, "set": 64, "total": 64}, s["mask"]
assert d["file_bytes"] > 0 and d["format_version"] >= 1 and "irradiance" not in s
' <"$OUT"
expect 0 "info without --stats" "$ILF" info "$CONST" --json
check "info reads headers only unless asked: no statistics" py '
import json, sys
s = json.load(sys.stdin)["slabs"][0]
assert s["nu"] == 8 and s["directions"] == 64, s
assert not any(k in s for k in ("radiance_min", "zero_fraction", "mask", "coverage")), s
' <"$OUT"
expect 0 "info --irradiance" "$ILF" info "$CONST" --json --irradiance 3,2
check "irradiance of constant radiance 2 is 2*pi" py '
import json, math, sys
s = json.load(sys.stdin)["slabs"][0]
assert s["position"] == [3, 2], s["position"]
assert all(abs(e - 2 * math.pi) < 1e-4 for e in s["irradiance"]), s["irradiance"]
' <"$OUT"
expect 0 "info --irradiance (text)" "$ILF" info "$CONST" --irradiance 0,0
check "text irradiance is 2*pi" stdout_has "irradiance (0,0): 6\.28318"
expect 0 "info --slab by name" "$ILF" info "$CONST" --slab flat
expect 0 "info --slab by index" "$ILF" info "$CONST" --slab 0
expect 2 "info --slab that does not exist" "$ILF" info "$CONST" --slab nosuch
check "missing slab is named" stderr_has "nosuch"
expect 2 "info --irradiance outside the grid" "$ILF" info "$CONST" --irradiance 8,0
expect 0 "info of the spot file" "$ILF" info "$SPOT" --json --stats
check "spot file has dark and bright samples" py '
import json, sys
s = json.load(sys.stdin)["slabs"][0]
assert 0 < s["zero_fraction"] < 1 and s["radiance_max"][0] > 0, s
assert s["mask"][-1]["set"] < s["mask"][-1]["total"], s["mask"]
' <"$OUT"

# The models against closed forms, at one position at the slab centre.
# radial: E = 2 pi / (1 - c) * ((1 - c^3)/3 - c (1 - c^2)/2), c = cos(cone).
expect 0 "synth radial at one position" "$ILF" synth --kind radial --grid 1x1 --n 32 -o "$TMP/one-radial.h5"
expect 0 "info --irradiance of radial" "$ILF" info "$TMP/one-radial.h5" --json --irradiance 0,0
check "radial irradiance matches the closed form" py '
import json, math, sys
e = json.load(sys.stdin)["slabs"][0]["irradiance"][0]
c = math.cos(math.radians(20))
exact = 2 * math.pi / (1 - c) * ((1 - c**3) / 3 - c * (1 - c * c) / 2)
assert abs(e / exact - 1) < 2e-3, (e, exact)
' <"$OUT"
# spot: a ball of radius R at distance D seen from x, lit in every direction
# (cone 180, falloff 0), gives E = pi (R/D)^2.
expect 0 "synth spot at one position" "$ILF" synth --kind spot --spot 0,0,-1:1,0,0:180:0:0.3 --grid 1x1 --n 32 \
    -o "$TMP/one-spot.h5"
expect 0 "info --irradiance of spot" "$ILF" info "$TMP/one-spot.h5" --json --irradiance 0,0
check "spot irradiance matches the closed form" py '
import json, math, sys
e = json.load(sys.stdin)["slabs"][0]["irradiance"][0]
assert abs(e / (math.pi * 0.09) - 1) < 5e-3, e
' <"$OUT"

# ------------------------------------------------------------------ verify
expect 0 "verify valid files" "$ILF" verify "$CONST" "$RADIAL" "$SPOT"
check "verify says ok" stdout_has "constant.h5: ok"

# ------------------------------------------------------------------ slice
expect 0 "slice unfold png" "$ILF" slice "$RADIAL" --position 3,4 --size 64 -o "$TMP/unfold.png"
check "unfold png exists" nonempty "$TMP/unfold.png"
check "unfold png is 8-bit RGBA 64x64" image_is "$TMP/unfold.png" 64 64 4
check "slice prints the scale" stdout_has "scale"
expect 0 "slice unfold exr" "$ILF" slice "$RADIAL" --position 3,4 --size 64 --layout unfold -o "$TMP/unfold.exr"
check "unfold exr is float RGBA 64x64" image_is "$TMP/unfold.exr" 64 64 4
expect 0 "slice latlong png" "$ILF" slice "$RADIAL" --position 0,0 --layout latlong --size 32 -o "$TMP/latlong.png"
check "latlong png is 64x32 RGB" image_is "$TMP/latlong.png" 64 32 3
expect 0 "slice latlong exr" "$ILF" slice "$RADIAL" --position 0,0 --layout latlong --size 32 -o "$TMP/latlong.EXR"
check "latlong exr is float 64x32 RGB" image_is "$TMP/latlong.EXR" 64 32 3
expect 0 "slice --direction png" "$ILF" slice "$SPOT" --direction 0 --exposure 1 -o "$TMP/dir.png"
check "direction png is nu x nv" image_is "$TMP/dir.png" 8 8 3
expect 0 "slice --direction exr" "$ILF" slice "$CONST" --direction 63 -o "$TMP/dir.exr"
check "direction exr is float nu x nv" image_is "$TMP/dir.exr" 8 6 3
expect 0 "slice --toward" "$ILF" slice "$SPOT" --toward 0,0.1,1 --slab 0 -o "$TMP/toward.png"
check "toward png exists" nonempty "$TMP/toward.png"
expect 2 "slice --toward behind the slab" "$ILF" slice "$SPOT" --toward 0,0,-1 -o "$TMP/behind.png"
expect 2 "slice --direction out of range" "$ILF" slice "$CONST" --direction 64 -o "$TMP/x.png"
expect 2 "slice --position out of range" "$ILF" slice "$CONST" --position 0,6 -o "$TMP/x.png"
expect 2 "slice with two modes" "$ILF" slice "$CONST" --position 0,0 --direction 1 -o "$TMP/x.png"
expect 2 "slice with no mode" "$ILF" slice "$CONST" -o "$TMP/x.png"
expect 2 "slice to an unknown image type" "$ILF" slice "$CONST" --direction 0 -o "$TMP/x.tiff"
expect 2 "slice --layout with --direction" "$ILF" slice "$CONST" --direction 0 --layout latlong -o "$TMP/x.png"
check "rejected slices wrote nothing" absent "$TMP/x.png"

# ------------------------------------------------------------------ bad inputs
MISSING=$TMP/does-not-exist.h5
TEXT=$TMP/notes.txt
TRUNC=$TMP/truncated.h5
FLIPPED=$TMP/flipped.h5
echo "this is not a light field" >"$TEXT"
head -c 3000 "$RADIAL" >"$TRUNC"
# Radiance without zeros compresses little, so the middle of this file is radiance data.
"$ILF" synth --kind radial --cone 180 --grid 16x16 --n 16 -o "$FLIPPED" >/dev/null
cp "$FLIPPED" "$TMP/unflipped.h5"
size=$(wc -c <"$FLIPPED")
middle=$((size / 2))
old=$(od -A n -t u1 -j "$middle" -N 1 "$FLIPPED" | tr -d ' ')
printf "\\$(printf '%03o' $((old ^ 255)))" | dd of="$FLIPPED" bs=1 seek="$middle" conv=notrunc status=none
check "the flipped copy differs" bash -c "! cmp -s '$TMP/unflipped.h5' '$FLIPPED'"

for bad in "$MISSING" "$TEXT" "$TRUNC"; do
    name=$(basename "$bad")
    expect 2 "info $name" "$ILF" info "$bad"
    check "info names $name" stderr_has "$name"
    check "info error starts with 'ilf info:'" grep -q "^ilf info: " "$ERR"
    expect 2 "verify $name" "$ILF" verify "$bad"
    check "verify reports $name" stdout_has "$name: "
    expect 2 "slice $name" "$ILF" slice "$bad" --position 0,0 -o "$TMP/never.png"
    check "slice names $name" stderr_has "$name"
done
check "failed slices wrote nothing" absent "$TMP/never.png"
expect 2 "verify a flipped byte" "$ILF" verify "$FLIPPED"
check "verify reports a problem count" stdout_has "flipped.h5: .*([0-9]* problems*)"
expect 2 "verify reports each file, failing if any fails" "$ILF" verify "$CONST" "$TRUNC"
check "verify still reports the good file" stdout_has "constant.h5: ok"

# ------------------------------------------------------------------ bad numbers
expect 2 "--grid 0x5" "$ILF" synth --kind constant --grid 0x5 -o "$TMP/bad.h5"
check "bad value is quoted" stderr_has "--grid '0x5'"
expect 2 "--grid 8x" "$ILF" synth --kind constant --grid 8x -o "$TMP/bad.h5"
expect 2 "--grid 8" "$ILF" synth --kind constant --grid 8 -o "$TMP/bad.h5"
expect 2 "--n 0" "$ILF" synth --kind constant --n 0 -o "$TMP/bad.h5"
expect 2 "--n abc" "$ILF" synth --kind constant --n abc -o "$TMP/bad.h5"
expect 2 "--n -4" "$ILF" synth --kind constant --n -4 -o "$TMP/bad.h5"
expect 2 "--n 4.5" "$ILF" synth --kind constant --n 4.5 -o "$TMP/bad.h5"
expect 2 "--u 1,0" "$ILF" synth --kind constant --u 1,0 -o "$TMP/bad.h5"
check "--u 1,0 explains the count" stderr_has "expected 3 comma-separated numbers"
expect 2 "--u 1,0,0,0" "$ILF" synth --kind constant --u 1,0,0,0 -o "$TMP/bad.h5"
expect 2 "--u 1,,0" "$ILF" synth --kind constant --u 1,,0 -o "$TMP/bad.h5"
expect 2 "--origin nan" "$ILF" synth --kind constant --origin nan,0,0 -o "$TMP/bad.h5"
expect 2 "--radiance 1e999" "$ILF" synth --kind constant --radiance 1e999,1,1 -o "$TMP/bad.h5"
expect 2 "--radiance negative" "$ILF" synth --kind constant --radiance -1,1,1 -o "$TMP/bad.h5"
expect 2 "u not orthogonal to v" "$ILF" synth --kind constant --u 1,0,0 --v 1,1,0 -o "$TMP/bad.h5"
expect 2 "--kind missing" "$ILF" synth -o "$TMP/bad.h5"
expect 2 "--kind unknown" "$ILF" synth --kind disco -o "$TMP/bad.h5"
expect 2 "-o missing" "$ILF" synth --kind constant
expect 2 "--grid without a value" "$ILF" synth --kind constant -o "$TMP/bad.h5" --grid
expect 2 "--spot without --kind spot" "$ILF" synth --kind constant --spot 0,0,-1:0,0,1:30:1 -o "$TMP/bad.h5"
expect 2 "--kind spot without --spot" "$ILF" synth --kind spot -o "$TMP/bad.h5"
expect 2 "--spot with three fields" "$ILF" synth --kind spot --spot 0,0,-1:0,0,1:30 -o "$TMP/bad.h5"
expect 2 "--spot with a zero axis" "$ILF" synth --kind spot --spot 0,0,-1:0,0,0:30:1 -o "$TMP/bad.h5"
expect 2 "--cone 0" "$ILF" synth --kind radial --cone 0 -o "$TMP/bad.h5"
expect 2 "--cone with constant" "$ILF" synth --kind constant --cone 10 -o "$TMP/bad.h5"
expect 2 "--name too long" "$ILF" synth --kind constant --name "$(printf 'x%.0s' $(seq 70))" -o "$TMP/bad.h5"
expect 2 "--name with a slash" "$ILF" synth --kind constant --name a/b -o "$TMP/bad.h5"
expect 2 "--irradiance 1" "$ILF" info "$CONST" --irradiance 1
expect 2 "--size 0" "$ILF" slice "$CONST" --position 0,0 --size 0 -o "$TMP/bad.png"
expect 2 "--exposure abc" "$ILF" slice "$CONST" --position 0,0 --exposure abc -o "$TMP/bad.png"
check "rejected commands wrote nothing" none_match "$TMP/bad.*"

# ------------------------------------------------------------------ unwritable outputs
expect 1 "synth into a missing folder" "$ILF" synth --kind constant --grid 2x2 --n 2 -o "$TMP/no/such/dir/x.h5"
check "synth into a missing folder names it" stderr_has "$TMP/no/such/dir"
check "no partial synth output" absent "$TMP/no"
expect 1 "slice into a missing folder" "$ILF" slice "$CONST" --direction 0 -o "$TMP/no/such/dir/x.exr"
check "no partial slice output" absent "$TMP/no"

# Outputs are checked before any work (docs/cli.md): each of these requests would compute for minutes
# if it started (an 805 MB slab, 7e10 evaluations), so the time limit catches a check made too late.
SLOW=(--kind radial --cone 180 --grid 128x128 --n 32 --supersample 32)
SRC_SQUARE=$(cd "$(dirname "$0")" && pwd)/scenes/cli_square.json
mkdir -p "$TMP/afolder"
expect 2 "synth onto a folder is refused before the work" timeout 20 "$ILF" synth "${SLOW[@]}" -o "$TMP/afolder"
check "synth onto a folder says so" stderr_has "is a folder, not a file"
expect 2 "synth onto a name ending in / is refused" timeout 20 "$ILF" synth "${SLOW[@]}" -o "$TMP/afolder/"
check "the folder is still empty" test -z "$(ls -A "$TMP/afolder")"
mkfifo "$TMP/fifo.h5"
expect 2 "synth onto a FIFO is refused before the work" timeout 20 "$ILF" synth "${SLOW[@]}" -o "$TMP/fifo.h5"
check "synth onto a FIFO says so" stderr_has "is a FIFO, not a regular file"
check "the FIFO is still a FIFO" test -p "$TMP/fifo.h5"
expect 1 "synth into a missing folder fails before the work" timeout 20 "$ILF" synth "${SLOW[@]}" -o "$TMP/no/x.h5"
expect 2 "relight into a FIFO is refused" "$ILF" relight "$SRC_SQUARE" -o "$TMP/fifo.h5" --quiet
check "relight into a FIFO says so" stderr_has "is a FIFO, not a folder"
mkdir -p "$TMP/fifodir"
mkfifo "$TMP/fifodir/view.png"
expect 2 "relight onto a FIFO named view.png is refused" "$ILF" relight "$SRC_SQUARE" -o "$TMP/fifodir" --quiet
check "relight onto a FIFO named view.png names it" stderr_has "fifodir/view.png: is a FIFO"
check "relight left the folder as it was" only_files "$TMP/fifodir" view.png
# Results on standard output are outputs too: a full device fails the run with the system's reason.
expect 1 "info with its standard output on /dev/full" bash -c '"$0" info "$1" >/dev/full' "$ILF" "$CONST"
check "info on /dev/full gives the reason" stderr_has "cannot write the standard output: No space left on device"

# A write that fails part-way (file size limit; SIGXFSZ ignored so write()
# returns an error) must leave an existing output exactly as it was.
KEEP=$TMP/keep
mkdir -p "$KEEP"
cp "$SPOT" "$KEEP/existing.h5"
cp "$SPOT" "$KEEP/original.h5"
expect 1 "synth failing mid-write" bash -c "trap '' XFSZ; ulimit -f 8; exec \"\$0\" \"\$@\"" \
    "$ILF" synth --kind radial --cone 180 --grid 16x16 --n 16 -o "$KEEP/existing.h5"
check "failed synth left the existing file alone" cmp -s "$KEEP/existing.h5" "$KEEP/original.h5"
check "failed synth left no temporary" only_files "$KEEP" existing.h5 original.h5
"$ILF" slice "$RADIAL" --direction 0 -o "$KEEP/existing.exr" >/dev/null 2>&1
cp "$KEEP/existing.exr" "$KEEP/original.exr"
expect 1 "slice failing mid-write" bash -c "trap '' XFSZ; ulimit -f 8; exec \"\$0\" \"\$@\"" \
    "$ILF" slice "$RADIAL" --position 0,0 --size 1024 -o "$KEEP/existing.exr"
check "failed slice left the existing image alone" cmp -s "$KEEP/existing.exr" "$KEEP/original.exr"
check "failed slice left no temporary" only_files "$KEEP" existing.h5 original.h5 existing.exr original.exr

# ------------------------------------------------------------------ relight, irradiance
SRC=$(cd "$(dirname "$0")/.." && pwd)
SQUARE=$SRC/tests/scenes/cli_square.json
FAST=(--partition-n 8 --rays 1)
RELIT=$TMP/relit
# A python3 with h5py (if any) reads radiance.h5 as docs/format.md shows.
H5PY=""
for candidate in python3 /usr/bin/python3; do
    if command -v "$candidate" >/dev/null && "$candidate" -c "import h5py, numpy" 2>/dev/null; then
        H5PY=$candidate
        break
    fi
done

expect 0 "relight the square" "$ILF" relight "$SQUARE" -o "$RELIT/square" "${FAST[@]}" --threads 2
check "relight wrote radiance.h5, stats.json and the view, nothing else" \
    only_files "$RELIT/square" radiance.h5 stats.json view.exr view.png
check "relight reports radiance.h5" stdout_has "^wrote .*radiance\.h5: 1 map, 64 cells"
check "relight reports the direct pass" stdout_has "^pass 0 (direct)"
check "relight reports the bounce pass" stdout_has "^pass 1 (bounce)"
check "view.exr is float 64x48 RGB" image_is "$RELIT/square/view.exr" 64 48 3
check "view.png is 8-bit 64x48 RGB" image_is "$RELIT/square/view.png" 64 48 3
check "stats.json has the schema of docs/cli.md" py '
import json, sys
s = json.load(open(sys.argv[1]))
assert s["scene"].endswith("cli_square.json") and s["method"] == "culled", s
assert s["settings"]["partition_n"] == 8 and s["settings"]["rays_per_solid_angle"] == 1, s["settings"]
assert s["settings"]["bounce_rays"] == 256 and "target_error" in s["settings"] and len(s["settings"]) == 13, s["settings"]
assert s["settings"]["bounces"] == 1 and s["threads"] == 2, s
assert s["maps"] == 1 and s["cells"] == 64, s
assert s["wall_seconds"] >= 0 and s["cpu_seconds"] >= 0, s
assert s["ranks"] == 1 and s["radiance_write_seconds"] > 0 and "exchanges" not in s, s
assert len(s["passes"]) == 2 and [p["pass"] for p in s["passes"]] == [0, 1], s["passes"]
keys = {"wall_seconds", "cpu_seconds", "samples", "rays_cast", "rays_kept", "rays_free", "solid_angles_considered",
        "solid_angles_culled", "pairs", "pairs_descended", "emitters", "cells_direct"}
assert all(keys <= set(p) for p in s["passes"]), s["passes"]
d = s["passes"][0]
# nothing lies between lamp and floor: every direct ray is known to arrive, none is traced
assert d["rays_cast"] == 0 and d["rays_kept"] == 0 and d["rays_free"] > 0 and d["emitters"] == 1, d
b = s["passes"][1]
assert b["rays_cast"] > 0 and b["rays_kept"] <= b["rays_cast"] and b["rays_free"] == 0, b  # first hits are all traced
assert d["solid_angles_culled"] <= d["solid_angles_considered"], d
m = s["memory"]
assert set(m) == {"accumulator_bytes", "lightfield_bytes", "peak_resident_bytes"}, m
# with a bounce: pass, previous pass and total (72 bytes a cell), and the 2 x 2 coarser cells of the 8 x 8
# (bounce cells 4 times the side) at 24 bytes each
c = s["cells"]
assert m["accumulator_bytes"] == 72 * c + 24 * (c // 16), m
assert m["lightfield_bytes"] == 0 and m["peak_resident_bytes"] > m["accumulator_bytes"], m
' "$RELIT/square/stats.json"
if [ -n "$H5PY" ]; then
    # The floor receives part of the lamp's power pi * 1 m^2 * 10 W sr^-1 m^-2.
    check "radiance.h5 reads as docs/format.md says" "$H5PY" -c '
import sys
import h5py, numpy as np
with h5py.File(sys.argv[1], "r") as f:
    assert f.attrs["format"].decode() == "ilfkit-radiance-maps" and int(f.attrs["format_version"]) == 2
    assert f.attrs["scene"].decode().endswith("cli_square.json") and int(f.attrs["patch_count"]) == 1
    maps = f["patches"]
    labels = maps["label"][:].tobytes().split(b"\0")[:-1]
    assert labels == [b"polygons[1]"], labels
    a, b = maps["cell_offset"][0:2]
    E = maps["irradiance"][a:b].astype(np.float64)
    A = maps["cell_area"][a:b]
    P = (E * A[:, None]).sum(axis=0)
    assert abs(A.sum() - 4.0) < 1e-9 and 5 < P[0] < np.pi * 10, (A.sum(), P)
    assert maps["irradiance"].attrs["axes"].decode() == "cell:rgb"
' "$RELIT/square/radiance.h5"
fi

expect 0 "relight --quiet" "$ILF" relight "$SQUARE" -o "$RELIT/quiet" "${FAST[@]}" --quiet
check "relight --quiet prints nothing" bash -c "[ ! -s '$OUT' ] && [ ! -s '$ERR' ]"
check "relight --quiet still writes everything" only_files "$RELIT/quiet" radiance.h5 stats.json view.exr view.png
expect 0 "relight again over the same folder" "$ILF" relight "$SQUARE" -o "$RELIT/quiet" "${FAST[@]}" --quiet \
    --bounces 0
check "rewriting leaves no temporaries" only_files "$RELIT/quiet" radiance.h5 stats.json view.exr view.png
expect 0 "relight --no-view" "$ILF" relight "$SQUARE" -o "$RELIT/noview" "${FAST[@]}" --quiet --no-view
check "relight --no-view writes no view" only_files "$RELIT/noview" radiance.h5 stats.json
cp -r "$RELIT/quiet" "$RELIT/quiet_again"
expect 0 "relight --no-view over a run with a view" "$ILF" relight "$SQUARE" -o "$RELIT/quiet_again" "${FAST[@]}" \
    --quiet --no-view
check "the earlier run's view is gone: the folder describes one run" only_files "$RELIT/quiet_again" radiance.h5 \
    stats.json
expect 0 "relight --no-view again elsewhere" "$ILF" relight "$SQUARE" -o "$RELIT/noview2" "${FAST[@]}" --quiet \
    --no-view
check "the same run writes the same radiance.h5, byte for byte" \
    cmp "$RELIT/noview/radiance.h5" "$RELIT/noview2/radiance.h5"
check "--bounces 0 runs the direct pass only" py '
import json, sys
s = json.load(open(sys.argv[1]))
assert s["settings"]["bounces"] == 0 and len(s["passes"]) == 1, s
assert s["memory"]["accumulator_bytes"] == 24 * s["cells"], s["memory"]  # one RGB double array a cell
' "$RELIT/quiet/stats.json"
expect 0 "relight the minimal scene (no light, no camera)" "$ILF" relight "$SRC/tests/scenes/good_minimal.json" \
    -o "$RELIT/minimal/a/b" --quiet
check "relight creates missing parent folders, writes no view without a camera" \
    only_files "$RELIT/minimal/a/b" radiance.h5 stats.json
if [ -e "$SRC/data/beams_diffuse.json" ]; then
    expect 0 "relight beams_diffuse" "$ILF" relight "$SRC/data/beams_diffuse.json" -o "$RELIT/beams" "${FAST[@]}" \
        --bounces 0 --quiet
    check "beams_diffuse: every map and a lit direct pass" py '
import json, sys
s = json.load(open(sys.argv[1]))
assert s["maps"] > 1 and s["cells"] > 1000 and s["passes"][0]["rays_cast"] > 0, s
' "$RELIT/beams/stats.json"
    check "beams_diffuse: the view was written" nonempty "$RELIT/beams/view.png"
fi
if [ -e "$SRC/data/classroom.json" ]; then
    expect 0 "relight classroom" "$ILF" relight "$SRC/data/classroom.json" -o "$RELIT/classroom" "${FAST[@]}" \
        --bounces 0 --quiet
    check "classroom: four emitters, rays cast" py '
import json, sys
s = json.load(open(sys.argv[1]))
d = s["passes"][0]
assert d["emitters"] == 4 and d["rays_cast"] > 0 and s["maps"] > 1000, s
' "$RELIT/classroom/stats.json"
fi
# classroom_lightfield.json: one slab referenced four times. Its file is generated, not kept in
# data/, so it is made here with the command gen_scenes.py runs, beside a copy of the scene.
if [ -e "$SRC/data/classroom_lightfield.json" ] && [ -n "$PYTHON" ]; then
    LFROOM=$TMP/classroom_lightfield
    mkdir -p "$LFROOM"
    cp "$SRC/data/classroom_lightfield.json" "$LFROOM/"
    mapfile -t SYNTH < <("$PYTHON" -B -c 'import sys; sys.path.insert(0, sys.argv[1]); import gen_scenes
print("\n".join(gen_scenes.CLASSROOM_LIGHTFIELD_COMMAND))' "$SRC/data")
    expect 0 "synth classroom_lightfield.h5 as gen_scenes.py does" "$ILF" "${SYNTH[@]}" \
        "$LFROOM/classroom_lightfield.h5"
    # 1.19 m below the centre of each lamp (at z = 3.19), facing up: desks and chairs are lower
    printf '3.5 2.5 2 0 0 1\n3.5 5.5 2 0 0 1\n7 2.5 2 0 0 1\n7 5.5 2 0 0 1\n' >"$LFROOM/points.txt"
    expect 0 "irradiance below the four light field lamps" "$ILF" irradiance "$LFROOM/classroom_lightfield.json" \
        --points "$LFROOM/points.txt"
    cp "$OUT" "$LFROOM/culled.txt"
    expect 0 "the same without zero-radiance culling" "$ILF" irradiance "$LFROOM/classroom_lightfield.json" \
        --points "$LFROOM/points.txt" --zero-culling 0
    check "zero-radiance culling does not change the irradiance" cmp -s "$OUT" "$LFROOM/culled.txt"
    # The slab's radial model (ilf synth --help), integrated over the slab: c = 100, cone 35
    # degrees, p half the diagonal behind the centre; the other lamps are outside their cones.
    check "each of the four slabs lights the point below it as its radial light field does" py '
import math, sys
c, ca, h, depth, n = 100.0, math.cos(math.radians(35)), 1.19, 0.4 * math.sqrt(2), 100
e = 0.0
for i in range(n):
    for j in range(n):
        x, y = 0.8 * ((i + 0.5) / n - 0.5), 0.8 * ((j + 0.5) / n - 0.5)
        d2 = x * x + y * y + h * h
        cosine = (h * depth - x * x - y * y) / math.sqrt((x * x + y * y + depth * depth) * d2)
        e += c * max(0.0, (cosine - ca) / (1 - ca)) * h * h / (d2 * d2) * 0.64 / (n * n)
got = [float(line.split()[1]) for line in sys.stdin]
assert len(got) == 4 and all(abs(g / e - 1) < 0.02 for g in got), (got, e)
' <"$LFROOM/culled.txt"
fi

# irradiance: the centre of the floor, 1 m below a 1 m square of radiance 10,
# receives E = 4 L X / sqrt(1 + X^2) atan(X / sqrt(1 + X^2)), X = 0.5: 7.5225 W m^-2.
POINTS=$TMP/points.txt
printf '# x y z nx ny nz\n1 1 0 0 0 1\n\n   # indented comment\n0.25 0.25 0 0 0 2\n1 1 0.5 0 0 1\n' >"$POINTS"
expect 0 "irradiance of three points" "$ILF" irradiance "$SQUARE" --points "$POINTS" --method area --samples 4096
check "irradiance prints one line per point" bash -c "[ \$(wc -l <'$OUT') -eq 3 ]"
check "each line is three numbers" py '
import sys
rows = [line.split() for line in sys.stdin]
assert all(len(r) == 3 for r in rows) and all(float(x) >= 0 for r in rows for x in r), rows
' <"$OUT"
check "irradiance at the centre matches the closed form" py '
import math, sys
e = float(sys.stdin.readline().split()[0])
x = 0.5 / math.sqrt(1.25)
exact = 4 * 10 * x * math.atan(x)
assert abs(e / exact - 1) < 0.01, (e, exact)
' <"$OUT"
cp "$OUT" "$TMP/irradiance-2threads.txt"
expect 0 "irradiance on one thread" "$ILF" irradiance "$SQUARE" --points "$POINTS" --method area --samples 4096 \
    --threads 1
check "irradiance does not depend on the thread count" cmp -s "$OUT" "$TMP/irradiance-2threads.txt"
expect 0 "irradiance from stdin" bash -c "printf '1 1 0 0 0 1\n' | \"\$0\" irradiance \"\$1\" --points - ${FAST[*]}" \
    "$ILF" "$SQUARE"
check "stdin gives one line" bash -c "[ \$(wc -l <'$OUT') -eq 1 ]"
printf '1 1 0 0 0 1\n\n1 1 0 0 0\n' >"$TMP/points_short.txt"
expect 2 "irradiance of a line with five numbers" "$ILF" irradiance "$SQUARE" --points "$TMP/points_short.txt"
check "the bad line is named FILE:LINE" stderr_has "points_short.txt:3:"
printf '1 1 0 0 0 1\n1 1 zero 0 0 1\n' >"$TMP/points_word.txt"
expect 2 "irradiance of a line with a word" "$ILF" irradiance "$SQUARE" --points "$TMP/points_word.txt"
check "the word is named with FILE:LINE" stderr_has "points_word.txt:2:"
printf '1 1 0 0 0 0\n' >"$TMP/points_zero.txt"
expect 2 "irradiance with a zero normal" "$ILF" irradiance "$SQUARE" --points "$TMP/points_zero.txt"
check "the zero normal is named FILE:LINE" stderr_has "points_zero.txt:1:"
expect 2 "irradiance of a missing points file" "$ILF" irradiance "$SQUARE" --points "$TMP/no-points.txt"
check "the missing points file is named" stderr_has "no-points.txt"
expect 2 "irradiance without --points" "$ILF" irradiance "$SQUARE"

# relight and irradiance: bad scenes, bad values, unwritable outputs.
expect 2 "relight a missing scene" "$ILF" relight "$TMP/no-scene.json" -o "$RELIT/never"
check "the missing scene is named" stderr_has "no-scene.json"
check "a failed relight creates no folder" absent "$RELIT/never"
expect 2 "irradiance of a missing scene" "$ILF" irradiance "$TMP/no-scene.json" --points "$POINTS"
check "irradiance names the missing scene" stderr_has "no-scene.json"
expect 2 "relight an invalid scene" "$ILF" relight "$SRC/tests/scenes/bad_nonconvex.json" -o "$RELIT/never"
check "the invalid scene is named" stderr_has "bad_nonconvex.json"
# a scene with a mesh when the mesh module (LIBDIR/ilfkit/libilfkit_assimp.so) cannot be loaded: bad input,
# naming the scene, the mesh file and the module path tried; the same scene relights with the module
expect 2 "relight a mesh scene without the mesh module" env ILFKIT_MESH_MODULE="$TMP/no-such/libilfkit_assimp.so" \
    "$ILF" relight "$SRC/tests/scenes/good_mesh_lshape.json" -o "$RELIT/never" --quiet
check "the missing module's message names the scene" stderr_has "good_mesh_lshape.json"
check "the missing module's message names the mesh" stderr_has "lshape.obj"
check "the missing module's message names the path tried" stderr_has "$TMP/no-such/libilfkit_assimp.so"
check "the missing module's message says what is missing" stderr_has "mesh support is not available"
expect 0 "relight the same mesh scene with the module" "$ILF" relight "$SRC/tests/scenes/good_mesh_lshape.json" \
    -o "$RELIT/lshape" --quiet
expect 2 "relight a file that is not a scene" "$ILF" relight "$TEXT" -o "$RELIT/never"
expect 2 "relight without -o" "$ILF" relight "$SQUARE"
expect 2 "relight --partition-n 3" "$ILF" relight "$SQUARE" -o "$RELIT/never" --partition-n 3
check "--partition-n 3 is explained" stderr_has "power of two"
expect 2 "relight --method fast" "$ILF" relight "$SQUARE" -o "$RELIT/never" --method fast
expect 2 "relight --rays 0" "$ILF" relight "$SQUARE" -o "$RELIT/never" --rays 0
expect 2 "relight --seed -1" "$ILF" relight "$SQUARE" -o "$RELIT/never" --seed -1
expect 2 "irradiance --bounces 65" "$ILF" irradiance "$SQUARE" --points "$POINTS" --bounces 65
check "rejected relights wrote nothing" absent "$RELIT/never"
expect 1 "relight into a folder under a regular file" "$ILF" relight "$SQUARE" -o "$TEXT/out" "${FAST[@]}"
check "the unusable folder is named" stderr_has "notes.txt"

# ------------------------------------------------------------------ capture
# render-probes -> capture -> reproject on the example scene (data/capture/), the real
# probe end to end, and the documented outcomes of bad manifests, images and proxies.
CAP=$TMP/capture
mkdir -p "$CAP"
for sub in capture render-probes reproject; do
    check "ilf --help lists $sub" grep -q -e "^  $sub " <("$ILF" --help)
    expect 0 "ilf $sub --help" "$ILF" "$sub" --help
    check "ilf $sub --help shows Usage" stdout_has "^Usage: ilf $sub"
    check "ilf $sub --help shows an example" stdout_has "^Example"
    expect 2 "$sub: unknown option" "$ILF" "$sub" --frobnicate
done
PLANE=-0.5,0.5,1.5:1,0,0:0,-1,0
expect 0 "render-probes on the example scene" "$ILF" render-probes "$SRC/data/capture/scene.json" --plane "$PLANE" \
    --grid 2x2 --size 64x32 --n 8 --partition-n 8 --rays 1 -o "$CAP/probes"
check "render-probes writes the probes and the manifest" only_files "$CAP/probes" manifest.json probe_0_0.exr \
    probe_0_1.exr probe_1_0.exr probe_1_1.exr
check "probes are 64x32 float EXR" image_is "$CAP/probes/probe_1_1.exr" 64 32 3
check "the manifest names the pattern" grep -q 'probe_{i}_{j}.exr' "$CAP/probes/manifest.json"
cp -r "$CAP/probes" "$CAP/probes_again"
expect 0 "render-probes of a smaller grid over the earlier probes" "$ILF" render-probes "$SRC/data/capture/scene.json" \
    --plane "$PLANE" --grid 1x2 --size 64x32 --n 8 --partition-n 8 --rays 1 -o "$CAP/probes_again" --quiet
check "the probes outside the new grid are gone" only_files "$CAP/probes_again" manifest.json probe_0_0.exr \
    probe_0_1.exr
expect 2 "render-probes past the work limit is refused" "$ILF" render-probes "$SRC/data/capture/scene.json" \
    --plane "$PLANE" --grid 1024x1024 --size 4096x2048 -o "$CAP/never"
check "render-probes past the work limit names the limit" stderr_has "ilf/limits.h"
check "render-probes past the work limit created nothing" absent "$CAP/never"
expect 0 "capture the rendered probes" "$ILF" capture "$CAP/probes/manifest.json" -o "$CAP/probes.h5" --threads 2
check "capture reports energy" stdout_has "^energy: .* differs by at most"
check "capture names the output" stdout_has "^wrote .*probes.h5: slab 'probes'"
expect 0 "the captured file verifies" "$ILF" verify "$CAP/probes.h5"
expect 0 "capture on one thread" "$ILF" capture "$CAP/probes/manifest.json" -o "$CAP/probes-1.h5" --threads 1 --quiet
check "--quiet prints nothing" bash -c "[ ! -s '$OUT' ]"
check "the capture does not depend on the thread count" \
    diff <("$ILF" info "$CAP/probes.h5" | grep -v '^file') <("$ILF" info "$CAP/probes-1.h5" | grep -v '^file')
expect 0 "capture the real probe" "$ILF" capture "$SRC/data/capture/studio.json" -o "$CAP/studio.h5"
check "one warning line for the real probe's negative values" \
    bash -c "[ \$(grep -c 'warning: .*studio.exr: 2028 negative values' '$ERR') -eq 1 ]"
check "the real probe conserves energy within 0.5%" py '
import re, sys
pct = float(re.search(r"differs by at most ([0-9.]+)%", sys.stdin.read()).group(1))
assert pct < 0.5, pct
' <"$OUT"
expect 0 "reproject onto the lamp" "$ILF" reproject "$CAP/probes.h5" --proxy "$SRC/data/capture/proxy.json" \
    -o "$CAP/lamp.h5" --n 8
check "reproject prints the coverage" stdout_has "^slab 'lamp': 12x12 positions, n 8, coverage [0-9.]*%"
check "reproject writes no sidecar file" absent "$CAP/lamp.coverage.json"
cp "$OUT" "$CAP/lamp.stdout"
expect 0 "the reprojected file verifies" "$ILF" verify "$CAP/lamp.h5"
expect 0 "info on the reprojected file" "$ILF" info "$CAP/lamp.h5" --json --stats
check "info reads the coverage stored in the file" py '
import json, re, sys
info = json.load(open(sys.argv[1]))
rays = float(re.search(r"coverage ([0-9.]+)%", open(sys.argv[2]).read()).group(1)) / 100
cov = info["slabs"][0]["coverage"]
assert cov["samples"] == 12 * 12 * 256 and 0 < cov["covered"] < cov["samples"], cov
# a sample is covered when any of its rays is: at least the share of covered rays, and close to it
assert rays <= cov["fraction"] + 1e-4 and cov["fraction"] < rays + 0.1, (cov, rays)
' "$OUT" "$CAP/lamp.stdout"
expect 0 "info text shows the coverage" "$ILF" info "$CAP/lamp.h5" --stats
check "info text has a coverage line" stdout_has "^  coverage: .*% of the etendue"
expect 0 "info on a captured file" "$ILF" info "$CAP/probes.h5" --stats
check "a file without coverage shows none" bash -c "! grep -q coverage '$OUT'"
printf 'v -0.3 0.3 2\nv 0.3 0.3 2\nv 0.3 -0.3 2\nv -0.3 -0.3 2\nf 1 4 3 2\n' >"$CAP/lamp.obj"
expect 0 "reproject onto a mesh quad" "$ILF" reproject "$CAP/probes.h5" --proxy "$CAP/lamp.obj" -o "$CAP/mesh.h5" \
    --grid 4x4 --n 4 --plain --quiet
check "the mesh quad becomes slab face0" grep -q "^slab 0: face0" <("$ILF" info "$CAP/mesh.h5")
printf 'v -0.3 0.3 2\nv 0.3 0.3 2\nv 0.3 -0.3 2\nv -0.3 -0.3 2\nf 1 4 3\nf 1 3 2\n' >"$CAP/lamp_tri.obj"
expect 0 "reproject onto the triangulated quad" "$ILF" reproject "$CAP/probes.h5" --proxy "$CAP/lamp_tri.obj" \
    -o "$CAP/mesh_tri.h5" --grid 4x4 --n 4 --plain --quiet
check "two triangles make the quad's slab, radiance and coverage alike" \
    diff <("$ILF" info "$CAP/mesh.h5" | grep -v '^file') <("$ILF" info "$CAP/mesh_tri.h5" | grep -v '^file')
# Proxies take what scenes take, through the same importer: the same quad as PLY, and the triangulated
# quad as STL and as binary glTF, give the OBJ's reprojection.
printf 'ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n' >"$CAP/lamp.ply"
printf 'element face 1\nproperty list uchar int vertex_indices\nend_header\n' >>"$CAP/lamp.ply"
printf -- '-0.3 0.3 2\n0.3 0.3 2\n0.3 -0.3 2\n-0.3 -0.3 2\n4 0 3 2 1\n' >>"$CAP/lamp.ply"
{
    echo "solid lamp"
    for tri in "-0.3 0.3 2|-0.3 -0.3 2|0.3 -0.3 2" "-0.3 0.3 2|0.3 -0.3 2|0.3 0.3 2"; do
        echo " facet normal 0 0 1"
        echo "  outer loop"
        IFS='|' read -r a b c <<<"$tri"
        printf '   vertex %s\n   vertex %s\n   vertex %s\n' "$a" "$b" "$c"
        echo "  endloop"
        echo " endfacet"
    done
    echo "endsolid lamp"
} >"$CAP/lamp.stl"
for ext in ply stl; do
    expect 0 "reproject onto the quad as ${ext^^}" "$ILF" reproject "$CAP/probes.h5" --proxy "$CAP/lamp.$ext" \
        -o "$CAP/mesh_$ext.h5" --grid 4x4 --n 4 --plain --quiet
    check "the ${ext^^} proxy gives the OBJ's slab, radiance and coverage" \
        diff <("$ILF" info "$CAP/mesh.h5" | grep -v '^file') <("$ILF" info "$CAP/mesh_$ext.h5" | grep -v '^file')
done

# Several capture planes: render-probes writes a manifest naming each, capture a slab per plane,
# reproject merges them (coverage the union: at least the one plane's) and stores each proxy
# slab's covered share as its coverage_fraction attribute, which info shows.
expect 0 "render-probes on two planes" "$ILF" render-probes "$SRC/data/capture/scene.json" --plane "$PLANE" \
    --plane 0.5,-0.5,1.5:0,1,0:0,0,0.5:2x1 --grid 2x2 --size 32x16 --n 8 --partition-n 8 --rays 1 -o "$CAP/box"
check "render-probes writes each plane's probes and one manifest" only_files "$CAP/box" manifest.json \
    probe_0_0_0.exr probe_0_0_1.exr probe_0_1_0.exr probe_0_1_1.exr probe_1_0_0.exr probe_1_1_0.exr
expect 0 "capture the two planes" "$ILF" capture "$CAP/box/manifest.json" -o "$CAP/box.h5"
check "capture writes a slab per plane" stdout_has "^wrote .*box.h5: slabs 'probes0' (2x2, n 8), 'probes1' (2x1, n 8)"
expect 0 "the two-plane capture verifies" "$ILF" verify "$CAP/box.h5"
expect 0 "reproject the first plane alone" "$ILF" reproject "$CAP/box.h5" --slab 0 \
    --proxy "$SRC/data/capture/proxy.json" -o "$CAP/box0.h5" --n 8
cp "$OUT" "$CAP/box0.stdout"
check "the first plane alone covers what the one-plane capture covers" \
    diff <(grep -o 'coverage .*' "$CAP/box0.stdout") <(grep -o 'coverage .*' "$CAP/lamp.stdout")
printf '[{"name": "lamp", "origin": [-0.3, 0.3, 2.0], "u": [0.6, 0, 0], "v": [0, -0.6, 0], "grid": {"nu": 6, "nv": 6}},
 {"name": "rim", "origin": [0.3, -0.3, 2.0], "u": [0, 0.6, 0], "v": [0.2, 0, 0], "grid": {"nu": 6, "nv": 2}}]\n' \
    >"$CAP/box_proxy.json"
expect 0 "reproject merges both planes" "$ILF" reproject "$CAP/box.h5" --proxy "$CAP/box_proxy.json" \
    -o "$CAP/boxlamp.h5" --n 8
cp "$OUT" "$CAP/boxlamp.stdout"
check "reproject prints the whole proxy's coverage" stdout_has "^coverage of the whole proxy: [0-9.]*% of its etendue"
expect 0 "the merged file verifies" "$ILF" verify "$CAP/boxlamp.h5"
expect 0 "info on the merged file" "$ILF" info "$CAP/boxlamp.h5" --json
check "each slab's coverage_fraction is the printed coverage, and two planes cover more than one" py '
import json, re, sys
info = json.load(open(sys.argv[1]))
printed = [float(x) / 100 for x in re.findall(r"coverage ([0-9.]+)% \(", open(sys.argv[2]).read())]
one = float(re.search(r"coverage ([0-9.]+)%", open(sys.argv[3]).read()).group(1)) / 100
stored = [s["coverage_fraction"] for s in info["slabs"]]
assert len(stored) == 2 and all(abs(a - b) < 5e-5 for a, b in zip(stored, printed)), (stored, printed)
assert stored[0] > one + 0.05, (stored[0], one)
' "$OUT" "$CAP/boxlamp.stdout" "$CAP/lamp.stdout"
expect 0 "info text on the merged file" "$ILF" info "$CAP/boxlamp.h5"
check "info text shows the stored share" \
    stdout_has "^  covered rays: .*% of the etendue covered, .*% not (attribute coverage_fraction)"

# capture and reproject: bad inputs are named and leave no output.
printf '{"plane": {"origin": [0, 0, 0], "u": [1, 0, 0], "v": [0, 1, 0]}, "grid": {"nu": 1, "nv": 1},\n' >"$CAP/m_key.json"
printf ' "pattern": "probes/probe_0_0.exr", "colour": "srgb"}\n' >>"$CAP/m_key.json"
expect 2 "a manifest with an unknown key" "$ILF" capture "$CAP/m_key.json" -o "$CAP/never.h5"
check "the unknown key and file are named" stderr_has "m_key.json: unknown key 'colour'"
sed 's/, "colour": "srgb"//; s/probe_0_0/probe_9_9/' "$CAP/m_key.json" >"$CAP/m_missing.json"
expect 2 "a manifest naming a missing image" "$ILF" capture "$CAP/m_missing.json" -o "$CAP/never.h5"
check "the missing image and element are named" stderr_has "m_missing.json: pattern: '$CAP/probes/probe_9_9.exr'"
cp "$TEXT" "$CAP/fake.exr"
sed 's/, "colour": "srgb"//; s|probes/probe_0_0.exr|fake.exr|' "$CAP/m_key.json" >"$CAP/m_fake.json"
expect 2 "a manifest naming a file that is not an image" "$ILF" capture "$CAP/m_fake.json" -o "$CAP/never.h5"
check "the unreadable image is named" stderr_has "fake.exr"
printf '{"plane": {"origin": [0, 0, 0], "u": [1, 0, 0], "v": [0, 1, 0]}, "grid": {"nu": 1, "nv": 1},\n' \
    >"$CAP/m_bracket.json"
printf ' "positions": [{"i": 0, "j": 0, "bracket": [{"file": "probes/probe_0_0.exr", "exposure": 1},\n' \
    >>"$CAP/m_bracket.json"
printf '   {"file": "studio.exr", "exposure": 4}]}]}\n' >>"$CAP/m_bracket.json"
cp "$SRC/data/capture/probes/studio.exr" "$CAP/studio.exr"
expect 2 "a bracket of mismatched sizes" "$ILF" capture "$CAP/m_bracket.json" -o "$CAP/never.h5"
check "both sizes are named" stderr_has "studio.exr is 512x256 but"
check "failed captures wrote nothing" absent "$CAP/never.h5"
expect 1 "capture into a missing folder" "$ILF" capture "$CAP/probes/manifest.json" -o "$CAP/no/out.h5"
mkdir -p "$CAP/keep"
cp "$CAP/probes.h5" "$CAP/keep/existing.h5"
expect 1 "capture failing mid-write" bash -c "trap '' XFSZ; ulimit -f 8; exec \"\$0\" \"\$@\"" \
    "$ILF" capture "$SRC/data/capture/studio.json" -o "$CAP/keep/existing.h5" --quiet
check "a failed capture keeps the old file" cmp -s "$CAP/probes.h5" "$CAP/keep/existing.h5"
check "a failed capture leaves no temporary" only_files "$CAP/keep" existing.h5
printf '[{"origin": [0, 0, 2], "u": [1, 0, 0], "v": [0, 1, 0], "size": 3}]\n' >"$CAP/proxy_bad.json"
expect 2 "a proxy with an unknown key" "$ILF" reproject "$CAP/probes.h5" --proxy "$CAP/proxy_bad.json" \
    -o "$CAP/never.h5"
check "the proxy element is named" stderr_has "proxy_bad.json: [0]: unknown key 'size'"
printf 'v 0 0 2\nv 1 0 2\nv 0 1 2\nf 1 2 3\n' >"$CAP/tri.obj"
expect 2 "a proxy mesh with a lone triangle" "$ILF" reproject "$CAP/probes.h5" --proxy "$CAP/tri.obj" -o "$CAP/never.h5"
check "the lone triangle is refused by name" stderr_has "face 0 (mesh 0 face 0): 3 vertices: is a triangle without"
printf 'ply\nformat ascii 1.0\nelement vertex 4000000000\nproperty float x\nend_header\n' >"$CAP/huge.ply"
expect 2 "a hostile PLY proxy (its header's counts would be trusted)" "$ILF" reproject "$CAP/probes.h5" \
    --proxy "$CAP/huge.ply" -o "$CAP/never.h5"
check "the PLY check refuses it by name, as for scenes" \
    stderr_has "huge.ply: cannot read '$CAP/huge.ply': PLY header declares 4000000000 'vertex' elements"
cp "$SRC/tests/hostile/mesh/count_absurd.dae" "$CAP/absurd.dae"
expect 2 "a Collada proxy (its reader trusts a header's counts)" "$ILF" reproject "$CAP/probes.h5" \
    --proxy "$CAP/absurd.dae" -o "$CAP/never.h5"
check "the proxy format is refused by name" stderr_has "absurd.dae': mesh format not supported"
expect 2 "render-probes with a bad plane grid" "$ILF" render-probes "$SRC/data/capture/scene.json" \
    --plane "$PLANE:2y2" -o "$CAP/never"
check "the plane grid is explained" stderr_has "grid NUxNV"
expect 2 "render-probes without --plane" "$ILF" render-probes "$SRC/data/capture/scene.json" -o "$CAP/never"
expect 2 "render-probes with a skew plane" "$ILF" render-probes "$SRC/data/capture/scene.json" \
    --plane 0,0,1:1,0,0:1,1,0 -o "$CAP/never"
check "the skew plane is explained" stderr_has "orthogonal"
check "rejected runs made no folder or file" absent "$CAP/never"

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
