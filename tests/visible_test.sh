#!/usr/bin/env bash
# visible_test.sh - what a user of `ilf` sees tells them what they got.
#
# Usage: bash visible_test.sh ILF_BINARY TMPDIR
#
# Checks, end to end, on small scenes (tests/scenes/warn_room*.json: a room as
# modelled, turned inside out, without its lamp, without its camera):
#   - warnings ("ilf: warning: ...") for a scene without emitters, a room whose
#     normals point outwards (no receiver faces the lamp, every cell dark, the
#     camera on back faces), no camera, a light field of partial coverage (the
#     share given matches `info`'s), unlit points, an all-black --toward slice;
#     each kept in stats.json's "warnings", none on stderr with --quiet;
#   - the settings line of every long command (method, samples, bounces,
#     threads), and nothing on stderr with --quiet;
#   - the progress bar on a terminal (through script(1), when present);
#   - --lux is 179 lm/W times the Rec.709 luminance of the r g b printed;
#   - --exposure and --scale set view.png's and slice's levels, and clash;
#   - falsecolor.png: a legend beside the view, its colours set by the scale.
# The last line is "N passed, M failed"; the exit status is nonzero on a failure.
set -u

if [ $# -ne 2 ]; then
    echo "usage: bash visible_test.sh ILF_BINARY TMPDIR" >&2
    exit 2
fi
ILF=$1
TMP=$2
SRC=$(cd "$(dirname "$0")/.." && pwd)
SCENES=$SRC/tests/scenes
rm -rf "$TMP"
mkdir -p "$TMP"
OUT=$TMP/stdout
ERR=$TMP/stderr
. "$(dirname "$0")/checks.sh"
status=0

stderr_empty() { [ ! -s "$ERR" ]; }
absent_view() { [ ! -e "$1/view.png" ] && [ ! -e "$1/view.exr" ]; }
absent_dir() { [ ! -e "$1" ]; }
# share_above SHARE LIMIT: whether the share (a number) is above LIMIT.
share_above() { awk -v s="$1" -v l="$2" 'BEGIN { exit !(s > l) }'; }
warnings() { grep -c '^ilf: warning: ' "$ERR"; }
py() { python3 -c "$@"; }
# json_warnings FILE: the number of entries of stats.json's "warnings".
json_warnings() { python3 -c 'import json,sys; print(len(json.load(open(sys.argv[1]))["warnings"]))' "$1"; }

# PNG pixels, decoded with the standard library (8-bit RGB or RGBA, no interlace): png_stats FILE X0 Y0 X1 Y1
# prints the mean of r+g+b over the box and the share of magenta pixels in it.
PNG_READER='
import struct, sys, zlib
def read_png(path):
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, idat = 8, b""
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            w, h, depth, ctype = struct.unpack(">IIBB", body[:10])
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    assert depth == 8 and ctype in (2, 6), (depth, ctype)
    ch = 3 if ctype == 2 else 4
    raw, rows, prev = zlib.decompress(idat), [], bytearray(w * ch)
    for y in range(h):
        f, line = raw[y * (w * ch + 1)], bytearray(raw[y * (w * ch + 1) + 1:(y + 1) * (w * ch + 1)])
        for i in range(len(line)):
            a = line[i - ch] if i >= ch else 0
            b, c = prev[i], prev[i - ch] if i >= ch else 0
            if f == 1: line[i] = (line[i] + a) & 255
            elif f == 2: line[i] = (line[i] + b) & 255
            elif f == 3: line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c; pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append([tuple(line[x * ch:x * ch + 3]) for x in range(w)])
        prev = line
    return w, h, rows
'
png_stats() {
    python3 -c "$PNG_READER"'
w, h, rows = read_png(sys.argv[1])
x0, y0, x1, y1 = (int(v) for v in sys.argv[2:6])
px = [rows[y][x] for y in range(y0, y1) for x in range(x0, x1)]
magenta = sum(1 for r, g, b in px if r > 200 and g < 60 and b > 200)
print(sum(r + g + b for r, g, b in px) / len(px), magenta / len(px))
' "$@"
}

ROOM=$SCENES/warn_room.json
FAST=(--threads 2)

# ------------------------------------------------------------------ warnings of relight
expect 0 "relight the room as modelled" "$ILF" relight "$ROOM" -o "$TMP/room" "${FAST[@]}"
check "a good room gives no warning" [ "$(warnings)" -eq 0 ]
check "stats.json has an empty warnings list" [ "$(json_warnings "$TMP/room/stats.json")" -eq 0 ]
check "the settings line names method, rays, bounces and threads" \
    stderr_matches '^ilf relight: method culled, partition n 4, 1 ray per solid angle, 1 bounce (16 rays per bounce cell), 2 threads$'

expect 0 "relight the room turned inside out" "$ILF" relight "$SCENES/warn_room_outward.json" -o "$TMP/out" "${FAST[@]}"
check "no receiver faces the lamp" stderr_matches '^ilf: warning: .*warn_room_outward.json: none of the 6 receiving polygons faces any of the 1 emitter from its front'
check "every cell is dark, with the share" stderr_matches '^ilf: warning: .*100.0% of the cells (1280 of 1280) received no light'
check "the camera sees back faces, with the share" stderr_matches '^ilf: warning: .*camera sees mostly back faces, drawn black: 100.0%'
check "stats.json lists the three warnings" [ "$(json_warnings "$TMP/out/stats.json")" -eq 3 ]
expect 0 "the same, --quiet" "$ILF" relight "$SCENES/warn_room_outward.json" -o "$TMP/out-q" "${FAST[@]}" --quiet
check "--quiet: nothing on stderr" stderr_empty
check "--quiet: stats.json still lists the warnings" [ "$(json_warnings "$TMP/out-q/stats.json")" -eq 3 ]

expect 0 "relight a room without emitters" "$ILF" relight "$SCENES/warn_room_no_emitter.json" -o "$TMP/dark" "${FAST[@]}"
check "no emitter is told" stderr_matches '^ilf: warning: .*warn_room_no_emitter.json: no emitter'
expect 0 "relight a room without a camera" "$ILF" relight "$SCENES/warn_room_no_camera.json" -o "$TMP/nocam" "${FAST[@]}"
check "no camera, no view: told" stderr_matches '^ilf: warning: .*no camera, so there is no view'
check "and there is no view" absent_view "$TMP/nocam"
expect 0 "--no-view without a camera" "$ILF" relight "$SCENES/warn_room_no_camera.json" -o "$TMP/nocam2" --no-view "${FAST[@]}"
check "--no-view: the missing camera is no news" [ "$(warnings)" -eq 0 ]

# ------------------------------------------------------------------ a light field of partial coverage
CAP=$TMP/capture
mkdir -p "$CAP"
expect 0 "render probes" "$ILF" render-probes "$SRC/data/capture/scene.json" --plane -0.5,0.5,1.5:1,0,0:0,-1,0 \
    --grid 2x2 --size 64x32 --n 8 --partition-n 8 --rays 1 -o "$CAP/probes" "${FAST[@]}"
check "render-probes: settings of the relight and of the probes" \
    bash -c "grep -q '^ilf render-probes: method culled, partition n 8' '$ERR' && grep -q '^ilf render-probes: 2x2 probes of 64x32 pixels, 4 directions per pixel' '$ERR'"
expect 0 "capture them" "$ILF" capture "$CAP/probes/manifest.json" -o "$CAP/probes.h5" "${FAST[@]}"
check "capture: its settings line" stderr_matches '^ilf capture: 2x2 positions, n 8 (256 directions), 4 images, 2 threads$'
expect 0 "reproject onto the lamp" "$ILF" reproject "$CAP/probes.h5" --proxy "$SRC/data/capture/proxy.json" \
    -o "$CAP/lamp.h5" --n 8 "${FAST[@]}"
check "reproject: its settings line" stderr_matches '^ilf reproject: method depth-corrected, 1 rectangle, 2x2 rays per solid angle, .* rays, 2 threads$'
cat >"$CAP/lit.json" <<'EOF'
{"materials": {"grey": {"albedo": [0.5, 0.5, 0.5]}},
 "polygons": [{"material": "grey", "vertices": [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]}],
 "radiance_maps": {"cell_size": 0.25},
 "lightfields": [{"file": "lamp.h5"}],
 "sampling": {"method": "culled", "partition_n": 4, "rays_per_solid_angle": 1, "bounces": 0}}
EOF
expect 0 "relight with the reprojected lamp" "$ILF" relight "$CAP/lit.json" -o "$CAP/lit" --no-view "${FAST[@]}"
check "the uncovered etendue is told" stderr_matches "^ilf: warning: .*lightfields\[0\] (.*lamp.h5, slab 'lamp'): coverage"
"$ILF" info "$CAP/lamp.h5" --json --stats >"$CAP/info.json"
check "the share told is info's" py '
import json, re, sys
info = json.load(open(sys.argv[1]))["slabs"][0]["coverage"]["fraction"]
m = re.search(r"coverage ([0-9.]+)%: ([0-9.]+)% of its etendue was not captured", open(sys.argv[2]).read())
assert m, "no coverage warning"
assert abs(float(m.group(1)) - 100 * info) < 0.006 and abs(float(m.group(2)) - 100 * (1 - info)) < 0.006, (m.groups(), info)
' "$CAP/info.json" "$ERR"
check "stats.json lists it" [ "$(json_warnings "$CAP/lit/stats.json")" -eq 1 ]

# ------------------------------------------------------------------ irradiance
printf '2 2 0 0 0 1\n2 2 0.001 0 0 -1\n' >"$TMP/points.txt"
expect 0 "irradiance in the room" "$ILF" irradiance "$ROOM" --points "$TMP/points.txt" --method area --samples 64 "${FAST[@]}"
cp "$OUT" "$TMP/rgb.txt"
check "the settings line gives the samples and the bounces it takes from the scene" \
    stderr_matches '^ilf irradiance: method area, 64 samples per cell and emitter, 1 bounce (16 rays per bounce cell), 2 threads$'
expect 0 "--lux" "$ILF" irradiance "$ROOM" --points "$TMP/points.txt" --method area --samples 64 --lux --quiet "${FAST[@]}"
check "--quiet: nothing on stderr" stderr_empty
check "--lux is 179 lm/W times the Rec.709 luminance" py '
import sys
rgb = [[float(v) for v in line.split()] for line in open(sys.argv[1])]
lux = [float(line) for line in open(sys.argv[2])]
assert len(rgb) == len(lux) == 2 and lux[0] > 0, (rgb, lux)
for (r, g, b), e in zip(rgb, lux):
    want = 179 * (0.2126 * r + 0.7152 * g + 0.0722 * b)
    assert abs(e - want) <= 1e-5 * want + 1e-9, (e, want)
' "$TMP/rgb.txt" "$OUT"
printf '2 2 3.5 0 0 1\n2 2 3.6 0 0 1\n1 1 3.5 0 0 1\n' >"$TMP/up.txt"
expect 0 "irradiance at points facing away from everything" "$ILF" irradiance "$ROOM" --points "$TMP/up.txt" --bounces 0 "${FAST[@]}"
check "unlit points are told, with their share" stderr_matches '^ilf: warning: .*: 3 of the 3 points (100.0%) received no light'
expect 0 "irradiance with no emitter" "$ILF" irradiance "$SCENES/warn_room_no_emitter.json" --points "$TMP/points.txt" "${FAST[@]}"
check "irradiance: no emitter is told" stderr_matches '^ilf: warning: .*no emitter'
check "irradiance: no word of a camera" bash -c "! grep -q camera '$ERR'"

# ------------------------------------------------------------------ other commands' settings lines and --quiet
expect 0 "synth" "$ILF" synth --kind radial --cone 30 --grid 8x8 --n 8 -o "$TMP/radial.h5" --threads 2
check "synth: its settings line" stderr_matches '^ilf synth: kind radial, 8x8 positions, n 8 (256 directions), 16 strata per direction, 2 threads$'
expect 0 "synth --quiet" "$ILF" synth --kind radial --cone 30 --grid 8x8 --n 8 -o "$TMP/radial.h5" --quiet
check "synth --quiet: nothing at all" bash -c "[ ! -s '$OUT' ] && [ ! -s '$ERR' ]"
expect 0 "verify" "$ILF" verify "$TMP/radial.h5" "$CAP/lamp.h5"
check "verify: its settings line" stderr_matches '^ilf verify: 2 files, .* every byte read and checked$'
expect 0 "verify --quiet" "$ILF" verify --quiet "$TMP/radial.h5"
check "verify --quiet: nothing at all" bash -c "[ ! -s '$OUT' ] && [ ! -s '$ERR' ]"

# ------------------------------------------------------------------ progress on a terminal
if script -qec true /dev/null >/dev/null 2>&1; then
    script -qec "'$ILF' relight '$ROOM' -o '$TMP/tty' --threads 2 --no-view" /dev/null >"$TMP/tty.txt" 2>&1
    check "on a terminal, relight draws its bar to 100% with the time taken" \
        grep -q 'relight \[#*\] 100.0% [0-9.]* s' "$TMP/tty.txt"
    script -qec "'$ILF' irradiance '$ROOM' --points '$TMP/points.txt' --threads 2" /dev/null >"$TMP/tty.txt" 2>&1
    check "on a terminal, irradiance draws its bar" grep -q 'irradiance \[#*\] 100.0%' "$TMP/tty.txt"
    script -qec "'$ILF' irradiance '$ROOM' --points '$TMP/points.txt' --threads 2 --quiet" /dev/null >"$TMP/tty.txt" 2>&1
    check "--quiet: no bar even on a terminal" bash -c "! grep -q 'irradiance \[' '$TMP/tty.txt'"
fi

# ------------------------------------------------------------------ slice: grazing --toward, --scale
expect 0 "slice toward a grazing direction" "$ILF" slice "$TMP/radial.h5" --toward 1,0,0.05 -o "$TMP/graze.png"
check "an all-black grazing slice is told, with its elevation" \
    stderr_matches "^ilf: warning: --toward 1,0,0.05 is 2.9 degrees above the plane of slab 'synth' (grazing): every position of the slice is black"
expect 0 "slice straight up" "$ILF" slice "$TMP/radial.h5" --toward 0,0,1 -o "$TMP/up.png"
check "a lit slice gives no warning" stderr_empty
expect 0 "slice --scale" "$ILF" slice "$TMP/radial.h5" --toward 0,0,1 -o "$TMP/up.png" --scale 4
check "--scale W is scale 1/W" stdout_has 'scale 0.25 (from --scale: 4 shows as white)'
expect 2 "--scale and --exposure clash" "$ILF" slice "$TMP/radial.h5" --toward 0,0,1 -o "$TMP/up.png" --scale 4 --exposure 1
expect 2 "--scale 0 is refused" "$ILF" slice "$TMP/radial.h5" --toward 0,0,1 -o "$TMP/up.png" --scale 0

# ------------------------------------------------------------------ view levels and false colour
expect 0 "view at a fixed scale" "$ILF" relight "$ROOM" -o "$TMP/dim" "${FAST[@]}" --scale 100
check "view.png says its scale" stdout_has 'view.png: 64x48, sRGB, scale 0.01 (from --scale: 100 shows as white)'
expect 0 "view at an exposure" "$ILF" relight "$ROOM" -o "$TMP/bright" "${FAST[@]}" --exposure 2
check "view.png says its exposure" stdout_has 'view.png: 64x48, sRGB, scale 4 (from --exposure 2)'
check "a brighter exposure gives a brighter view.png" py '
import sys
exec(sys.argv[3])
dim = read_png(sys.argv[1])[2]; bright = read_png(sys.argv[2])[2]
s = lambda rows: sum(sum(p) for row in rows for p in row)
assert s(bright) > 2 * s(dim), (s(bright), s(dim))
' "$TMP/dim/view.png" "$TMP/bright/view.png" "$PNG_READER"
expect 0 "falsecolor" "$ILF" relight "$ROOM" -o "$TMP/fc" "${FAST[@]}" --falsecolor
check "falsecolor.png is the view plus its legend" stdout_has \
    '^wrote .*falsecolor.png: [0-9]*x[0-9]*, illuminance 0 to [0-9.]* lux (99th percentile rounded up), 179 lm/W'
check "the legend is beside the view" py '
import sys
exec(sys.argv[2])
w, h, rows = read_png(sys.argv[1])
assert w > 64 + 40 and h >= 48, (w, h)
legend = {p for row in rows for p in row[64:]}
assert (255, 255, 255) in legend, "no text or ticks"
assert any(r > 200 and g < 40 and b < 40 for r, g, b in legend), "no red top of the bar"
' "$TMP/fc/falsecolor.png" "$PNG_READER"
over=$(png_stats "$TMP/fc/falsecolor.png" 0 0 64 48 | awk '{print $2}')
check "with the automatic top, almost nothing of the view is above the scale ($over)" share_above 0.02 "$over"
expect 0 "falsecolor at 1 lux" "$ILF" relight "$ROOM" -o "$TMP/fc1" "${FAST[@]}" --falsecolor-max 1
over=$(png_stats "$TMP/fc1/falsecolor.png" 0 0 64 48 | awk '{print $2}')
check "at a top of 1 lux, most of the lit room shows magenta ($over)" share_above "$over" 0.5
expect 2 "--falsecolor with --no-view" "$ILF" relight "$ROOM" -o "$TMP/never" --falsecolor --no-view
check "nothing written for a refused falsecolor" absent_dir "$TMP/never"

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
