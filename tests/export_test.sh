#!/usr/bin/env bash
# export_test.sh - `ilf` on what relighting leaves: info and verify on a
# radiance map (radiance.h5), `ilf export` to glTF binary, PLY and CSV (the
# glTF checked by the Khronos validator, npm's gltf-validator, when node can
# load it; required when CI=true), `ilf view` of a radiance map, `ilf slice
# --envmap` (read back by a standard-library .hdr decoder), the camera
# options of `ilf relight` on a scene without a camera and a constant light
# field seen straight on by `ilf view --scene`, and their error paths.
#
# Usage: bash export_test.sh ILF_BINARY TMPDIR
#
# The scene has a triangle and a pentagon whose edges cross the cells, so
# exported cells are clipped: the triangles of every export must add up to
# the area the file stores. python3 (standard library only) reads the
# outputs. The last line is "N passed, M failed"; the exit status is nonzero
# when anything failed.
set -u

if [ $# -ne 2 ]; then
    echo "usage: bash export_test.sh ILF_BINARY TMPDIR" >&2
    exit 2
fi
ILF=$1
TMP=$2
rm -rf "$TMP"
mkdir -p "$TMP"
OUT=$TMP/stdout
ERR=$TMP/stderr
. "$(dirname "$0")/checks.sh"
status=0

py() { python3 -c "$@"; }

cat >"$TMP/scene.json" <<'JSON'
{
  "materials": {
    "lamp": {"albedo": [0, 0, 0], "emission": [10, 10, 10]},
    "floor": {"albedo": [0.5, 0.4, 0.3]},
    "wall": {"albedo": [0.2, 0.6, 0.2]}
  },
  "polygons": [
    {"material": "lamp", "vertices": [[0.5, 0.5, 1], [0.5, 1.5, 1], [1.5, 1.5, 1], [1.5, 0.5, 1]]},
    {"material": "floor", "vertices": [[0, 0, 0], [2.1, 0, 0], [0, 2.3, 0]]},
    {"material": "wall", "vertices": [[0, 0, 0], [0, 0, 1.1], [0, 1, 1.3], [0, 2, 1.1], [0, 2, 0]]}
  ],
  "radiance_maps": {"cell_size": 0.25},
  "sampling": {"method": "culled", "partition_n": 8, "rays_per_solid_angle": 1, "bounces": 1, "seed": 1}
}
JSON
RAD=$TMP/relit/radiance.h5
expect 0 "relight the test scene" "$ILF" relight "$TMP/scene.json" -o "$TMP/relit" --no-view --threads 2 -q

# ------------------------------------------------------------------ info, verify
expect 0 "info on radiance.h5" "$ILF" info "$RAD"
check "info says it is a radiance map" stdout_has "^kind: *radiance map"
check "info counts the maps" stdout_has "^maps: *2$"
expect 0 "info --json --stats on radiance.h5" "$ILF" info "$RAD" --json --stats
cp "$OUT" "$TMP/info.json"
check "info --json: maps, cells and areas agree; the floor's area is its triangle's" py '
import json, sys
d = json.load(open(sys.argv[1]))
assert d["kind"] == "radiance map" and len(d["maps"]) == 2, d
assert d["cells"] == sum(m["cells"] for m in d["maps"]), d
assert abs(d["area"] - sum(m["area"] for m in d["maps"])) < 1e-9, d
floor = [m for m in d["maps"] if m["label"] == "polygons[1]"][0]
assert abs(floor["area"] - 0.5 * 2.1 * 2.3) < 1e-6, floor
assert floor["irradiance_max"][0] > floor["irradiance_mean"][0] > floor["irradiance_min"][0] >= 0, floor
assert d["irradiance_mean"][0] > 0, d
' "$TMP/info.json"
expect 0 "info without --stats has no statistics" "$ILF" info "$RAD" --json
check "no irradiance keys without --stats" py '
import json, sys
d = json.load(sys.stdin)
assert not any(k.startswith(("irradiance", "radiosity")) for k in d), d
' <"$OUT"
expect 2 "info --slab on a radiance map" "$ILF" info "$RAD" --slab 0
check "info says why" stderr_has "no slabs"
expect 0 "verify radiance.h5" "$ILF" verify "$RAD"
check "verify says ok" stdout_has ": ok$"
cp "$RAD" "$TMP/damaged.h5"
size=$(wc -c <"$TMP/damaged.h5")
printf '\xff\xff\xff\xff\xff\xff\xff\xff' | dd of="$TMP/damaged.h5" bs=1 seek=$((size - 200)) conv=notrunc status=none
expect 2 "verify a damaged radiance.h5" "$ILF" verify "$TMP/damaged.h5"
check "verify names the damaged file" stdout_has "damaged.h5: .*problem"
printf 'not hdf5\n' >"$TMP/text.h5"
expect 2 "info on a text file" "$ILF" info "$TMP/text.h5"
check "a file that is neither keeps the light field message" stderr_has "not an HDF5 file"

# A file of more maps than info details (10) and than lfio_radmap_headers holds at once (4096): 71 x 71 floor
# tiles of 1 m, four cells each (so that the cells and the maps differ in number), under a lamp. The text report
# is the summary (its cell count from the headers alone, no area), 10 maps and a line counting the rest;
# --maps and --json give every map, in order across the blocks, and the summary's area.
python3 -c '
import json, sys
polys = [{"material": "lamp", "vertices": [[0, 0, 5], [0, 1, 5], [1, 1, 5], [1, 0, 5]]}]
polys += [{"material": "floor", "vertices": [[i, j, 0], [i + 1, j, 0], [i + 1, j + 1, 0], [i, j + 1, 0]]}
          for i in range(71) for j in range(71)]
json.dump({"materials": {"lamp": {"albedo": [0, 0, 0], "emission": [10, 10, 10]}, "floor": {"albedo": [0.5, 0.5, 0.5]}},
           "polygons": polys, "radiance_maps": {"cell_size": 0.5},
           "sampling": {"partition_n": 2, "rays_per_solid_angle": 1, "bounces": 0}}, open(sys.argv[1], "w"))
' "$TMP/tiles.json"
MANY=$TMP/tiles/radiance.h5
expect 0 "relight 5041 tiles" "$ILF" relight "$TMP/tiles.json" -o "$TMP/tiles" --no-view --threads 2 -q
expect 0 "info on 5041 maps" "$ILF" info "$MANY"
check "info counts every map" stdout_has "^maps: *5041$"
check "info counts every cell, without the area (which needs every map)" stdout_has "^cells: *20164$"
cp "$OUT" "$TMP/many-info.txt"
check "info details the first 10 maps, in order" py '
import re, sys
maps = re.findall(r"^map (\d+): (\S+) ", sys.stdin.read(), re.M)
assert maps == [(str(k), "polygons[%d]" % (k + 1)) for k in range(10)], maps
' <"$OUT"
check "info counts the maps it leaves out" stdout_has "^\.\.\. and 5031 more maps: ilf info --maps lists them$"
expect 0 "info --maps on 5041 maps" "$ILF" info "$MANY" --maps
check "info --maps details every map, in order" py '
import re, sys
text = sys.stdin.read()
maps = re.findall(r"^map (\d+): (\S+) \(polygon (\d+)\)$", text, re.M)
assert maps == [(str(k), "polygons[%d]" % (k + 1), str(k + 1)) for k in range(5041)], len(maps)
assert len(re.findall(r"^  grid: +2x2 cells of 0.5 m, 4 stored, 1 m\^2$", text, re.M)) == 5041
assert "more maps" not in text
assert re.search(r"^cells: +20164, 5041 m\^2$", text, re.M)
' <"$OUT"
check "info's cell count is the sum of the cells --maps details" py '
import re, sys
default, every = open(sys.argv[1]).read(), sys.stdin.read()
total = int(re.search(r"^cells: +(\d+)$", default, re.M).group(1))
stored = [int(n) for n in re.findall(r"^  grid: .*, (\d+) stored, ", every, re.M)]
assert len(stored) == 5041 and total == sum(stored), (total, sum(stored))
' "$TMP/many-info.txt" <"$OUT"
expect 0 "info --json on 5041 maps" "$ILF" info "$MANY" --json
check "info --json lists every map, in order" py '
import json, sys
d = json.load(sys.stdin)
assert [m["label"] for m in d["maps"]] == ["polygons[%d]" % (k + 1) for k in range(5041)]
assert d["cells"] == 20164 == sum(m["cells"] for m in d["maps"]), d["cells"]
assert abs(sum(m["area"] for m in d["maps"]) - 5041) < 1e-6 and abs(d["area"] - 5041) < 1e-6, d["area"]
' <"$OUT"
"$ILF" synth --kind constant --grid 2x2 --n 2 -o "$TMP/field.h5" -q
expect 2 "info --maps on a light field" "$ILF" info "$TMP/field.h5" --maps
check "info says --maps is for radiance maps" stderr_has "--maps is for radiance-map files"

# ------------------------------------------------------------------ export
expect 0 "export CSV" "$ILF" export "$RAD" -o "$TMP/cells.csv"
check "CSV: one row per cell, areas and irradiance as info says" py '
import csv, json, sys
d = json.load(open(sys.argv[1]))
rows = list(csv.DictReader(open(sys.argv[2])))
assert len(rows) == d["cells"], (len(rows), d["cells"])
area = sum(float(r["area_m2"]) for r in rows)
assert abs(area - d["area"]) < 1e-6 * d["area"], (area, d["area"])
mean = sum(float(r["area_m2"]) * float(r["irradiance_r"]) for r in rows) / area
assert abs(mean - d["irradiance_mean"][0]) < 1e-5 * d["irradiance_mean"][0], (mean, d["irradiance_mean"])
assert {r["label"] for r in rows} == {m["label"] for m in d["maps"]}
' "$TMP/info.json" "$TMP/cells.csv"

# area TRIANGLES: the summed area of [[p, q, r], ...]
AREA='
def area(tris):
    s = 0.0
    for p, q, r in tris:
        a = [q[i] - p[i] for i in range(3)]
        b = [r[i] - p[i] for i in range(3)]
        c = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
        s += 0.5 * sum(x * x for x in c) ** 0.5
    return s
'
expect 0 "export PLY" "$ILF" export "$RAD" -o "$TMP/room.ply" --exposure 0
check "PLY: its triangles cover the stored area; sRGB bytes; irradiance as stored" py "$AREA"'
import json, sys
d = json.load(open(sys.argv[1]))
lines = open(sys.argv[2]).read().split("\n")
end = lines.index("end_header")
nv = int([l for l in lines if l.startswith("element vertex")][0].split()[2])
nf = int([l for l in lines if l.startswith("element face")][0].split()[2])
verts = [l.split() for l in lines[end + 1:end + 1 + nv]]
faces = [l.split() for l in lines[end + 1 + nv:end + 1 + nv + nf]]
pos = [[float(x) for x in v[:3]] for v in verts]
assert all(f[0] == "3" for f in faces)
a = area([[pos[int(i)] for i in f[1:]] for f in faces])
assert abs(a - d["area"]) < 1e-4 * d["area"], (a, d["area"])
assert all(0 <= int(c) <= 255 for v in verts for c in v[3:6])
assert max(int(v[3]) for v in verts) > 0
emax = max(float(v[6]) for v in verts)
assert abs(emax - max(m["irradiance_max"][0] for m in d["maps"])) < 1e-5 * emax, emax
' "$TMP/info.json" "$TMP/room.ply"

expect 0 "export glTF binary" "$ILF" export "$RAD" -o "$TMP/room.glb"
check "export prints what it wrote" stdout_has "^wrote .*room.glb: 2 maps"
check "GLB: header and chunks; triangles cover the stored area; COLOR_0 in [0, 1]; _IRRADIANCE per vertex" \
    py "$AREA"'
import json, struct, sys
d = json.load(open(sys.argv[1]))
b = open(sys.argv[2], "rb").read()
magic, version, length = struct.unpack_from("<4sII", b, 0)
assert magic == b"glTF" and version == 2 and length == len(b), (magic, version, length)
jlen, jtype = struct.unpack_from("<I4s", b, 12)
assert jtype == b"JSON" and jlen % 4 == 0
g = json.loads(b[20:20 + jlen])
blen, btype = struct.unpack_from("<I4s", b, 20 + jlen)
assert btype == b"BIN\0"
bin_ = b[28 + jlen:28 + jlen + blen]
def read(acc, fmt, n):
    a = g["accessors"][acc]
    v = g["bufferViews"][a["bufferView"]]
    return [struct.unpack_from("<" + fmt * n, bin_, v["byteOffset"] + k * 4 * n) for k in range(a["count"])]
total = 0.0
assert len(g["meshes"]) == 2 and "KHR_materials_unlit" in g["extensionsUsed"]
for m in g["meshes"]:
    pr = m["primitives"][0]
    pos = read(pr["attributes"]["POSITION"], "f", 3)
    idx = read(pr["indices"], "I", 1)
    col = read(pr["attributes"]["COLOR_0"], "f", 3)
    irr = read(pr["attributes"]["_IRRADIANCE"], "f", 3)
    assert len(col) == len(pos) == len(irr)
    assert all(0 <= c <= 1 for rgb in col for c in rgb)
    total += area([[pos[idx[3 * t][0]], pos[idx[3 * t + 1][0]], pos[idx[3 * t + 2][0]]] for t in range(len(idx) // 3)])
assert abs(total - d["area"]) < 1e-4 * d["area"], (total, d["area"])
' "$TMP/info.json" "$TMP/room.glb"

# The Khronos validator: optional on a developer machine, required in CI (.ci/run installs it).
VALIDATOR_JS='
const fs = require("fs");
const validator = require("gltf-validator");
validator.validateBytes(new Uint8Array(fs.readFileSync(process.argv[1]))).then((r) => {
  console.log(`errors ${r.issues.numErrors} warnings ${r.issues.numWarnings}`);
  for (const m of r.issues.messages) console.log(`${m.code} ${m.pointer || ""} ${m.message}`);
  process.exit(r.issues.numErrors === 0 ? 0 : 1);
}).catch((e) => { console.log(String(e)); process.exit(1); });
'
NODE_PATH=${NODE_PATH:-$(npm root -g 2>/dev/null)}
export NODE_PATH
if command -v node >/dev/null && node -e 'require("gltf-validator")' 2>/dev/null; then
    check "the Khronos glTF validator finds no error in room.glb" \
        bash -c 'node -e "$0" "$1" >"$2"' "$VALIDATOR_JS" "$TMP/room.glb" "$TMP/validator.txt"
    head -n 5 "$TMP/validator.txt" | sed 's/^/validator: /'
elif [ "${CI:-}" = true ]; then
    check "CI=true: the glTF validator (npm gltf-validator) must be installed" false
else
    echo "note: node or npm's gltf-validator is missing, so the glTF validator is not run (CI requires it)"
fi

expect 0 "--format overrides the extension" "$ILF" export "$RAD" -o "$TMP/cells.txt" --format csv
check "the .txt holds the CSV" cmp -s "$TMP/cells.txt" "$TMP/cells.csv"
expect 2 "export of a damaged radiance.h5" "$ILF" export "$TMP/damaged.h5" -o "$TMP/never.glb"
check "export names the damaged file" stderr_has "damaged.h5"
expect 2 "info of a damaged radiance.h5" "$ILF" info "$TMP/damaged.h5"
expect 2 "export of a light field" "$ILF" export "$TMP/text.h5" -o "$TMP/never.glb"
check "export names the bad input" stderr_has "text.h5"
expect 2 "export to an unknown extension" "$ILF" export "$RAD" -o "$TMP/never.obj"
check "export says which extensions it knows" stderr_has ".glb, .ply or .csv"
expect 2 "export with a bad --format" "$ILF" export "$RAD" -o "$TMP/never.glb" --format obj
expect 1 "export into a missing folder" "$ILF" export "$RAD" -o "$TMP/missing/room.glb"
cp "$TMP/room.glb" "$TMP/keep.glb"
expect 1 "export failing mid-write" bash -c "trap '' XFSZ; ulimit -f 8; exec \"\$0\" \"\$@\"" \
    "$ILF" export "$RAD" -o "$TMP/room.glb"
check "a failed export leaves the earlier file as it was" cmp -s "$TMP/room.glb" "$TMP/keep.glb"
check "a failed export leaves no temporary" bash -c "! compgen -G '$TMP/.room*' >/dev/null"

# ------------------------------------------------------------------ slice --envmap
# read_hdr PATH: a Radiance .hdr decoded with the standard library alone (flat and run-length scanlines)
HDR='
import math
def read_hdr(path):
    b = open(path, "rb").read()
    head, _, rest = b.partition(b"\n\n")
    assert head.startswith(b"#?RADIANCE") and b"FORMAT=32-bit_rle_rgbe" in head, head
    res, _, data = rest.partition(b"\n")
    _, h, _, w = res.split()
    h, w = int(h), int(w)
    at, rows = 0, []
    for y in range(h):
        if data[at] == 2 and data[at + 1] == 2:
            at += 4
            planes = []
            for c in range(4):
                plane = []
                while len(plane) < w:
                    n = data[at]; at += 1
                    if n > 128:
                        plane += [data[at]] * (n - 128); at += 1
                    else:
                        plane += list(data[at:at + n]); at += n
                planes.append(plane)
            px = list(zip(*planes))
        else:
            px = [tuple(data[at + 4 * x:at + 4 * x + 4]) for x in range(w)]; at += 4 * w
        rows.append([[0.0] * 3 if e == 0 else [(v + 0.5) * math.ldexp(1, e - 136) for v in (r, g, bb)]
                     for r, g, bb, e in px])
    assert at == len(data), (at, len(data))
    return rows
'
# Light travelling down (e3 = u x v = -z), up the +y axis (e3 = +y) and along +x: each lights the half of the
# sphere it comes from, and nothing else.
"$ILF" synth --kind constant --grid 2x2 --n 8 --u 0,1,0 --v 1,0,0 --radiance 1,2,3 -o "$TMP/down.h5" -q
"$ILF" synth --kind constant --grid 2x2 --n 8 --u 0,0,1 --v 1,0,0 -o "$TMP/north.h5" -q
"$ILF" synth --kind constant --grid 2x2 --n 8 --u 0,1,0 --v 0,0,1 -o "$TMP/east.h5" -q
expect 0 "slice --envmap to .hdr" "$ILF" slice "$TMP/down.h5" --position 0,0 --envmap --size 32 -o "$TMP/down.hdr"
check "slice says what the envmap is" stdout_has "64x32, environment map (equirectangular, +Z up)"
check "light travelling down fills the upper half of the envmap (+Z up), the lower half is black" py "$HDR"'
import sys
rows = read_hdr(sys.argv[1])
assert len(rows) == 32 and len(rows[0]) == 64
for y, row in enumerate(rows):
    for px in row:
        if y < 16:
            assert all(abs(v - c) < 0.01 * c for v, c in zip(px, (1, 2, 3))), (y, px)
        else:
            assert px == [0.0, 0.0, 0.0], (y, px)
' "$TMP/down.hdr"
expect 0 "slice --layout envmap to .hdr" "$ILF" slice "$TMP/north.h5" --position 1,1 --layout envmap --size 16 \
    -o "$TMP/north.hdr"
expect 0 "slice --envmap of light along +x" "$ILF" slice "$TMP/east.h5" --position 1,1 --envmap --size 16 \
    -o "$TMP/east.hdr"
check "longitude as Blender reads it: centre column +X, right half -Y" py "$HDR"'
import sys
north, east = read_hdr(sys.argv[1]), read_hdr(sys.argv[2])
# light travelling along +y comes from -y: the right half; along +x comes from -x: the outer quarters
for y in range(16):
    for x in range(32):
        assert (north[y][x][0] > 0.5) == (x >= 16), ("north", y, x, north[y][x])
        assert (east[y][x][0] > 0.5) == (x < 8 or x >= 24), ("east", y, x, east[y][x])
' "$TMP/north.hdr" "$TMP/east.hdr"
expect 0 "slice --envmap to EXR" "$ILF" slice "$TMP/down.h5" --position 0,0 --envmap --size 8 -o "$TMP/down.exr"
check "the EXR is written" test -s "$TMP/down.exr"
expect 2 "--envmap needs --position" "$ILF" slice "$TMP/down.h5" --direction 0 --envmap -o "$TMP/never.hdr"
check "slice says --envmap is for --position" stderr_has "--envmap"

# ------------------------------------------------------------------ view
expect 0 "view from above the floor to .hdr" "$ILF" view "$RAD" -o "$TMP/top.hdr" --position 0.6,0.6,3 \
    --look-at 0.6,0.6,0 --up 0,1,0 --fov 10 --size 33x21
check "view says what it wrote" stdout_has "^wrote .*top.hdr: 33x21, 2 maps, raw radiance"
check "the centre pixel shows the radiance (radiosity / pi) of the floor cell under it" py "$HDR"'
import csv, sys
rows = read_hdr(sys.argv[1])
assert len(rows) == 21 and len(rows[0]) == 33
cell = [r for r in csv.DictReader(open(sys.argv[2])) if r["label"] == "polygons[1]"
        and abs(float(r["x"]) - 0.6) < 0.125 and abs(float(r["y"]) - 0.6) < 0.125]
assert len(cell) == 1, cell
want = [float(cell[0]["radiosity_" + c]) / math.pi for c in "rgb"]
got = rows[10][16]
assert all(abs(g - w) <= 0.01 * max(want) for g, w in zip(got, want)), (got, want)
' "$TMP/top.hdr" "$TMP/cells.csv"
expect 0 "view from below the floor" "$ILF" view "$RAD" -o "$TMP/below.hdr" --position 0.6,0.6,-3 \
    --look-at 0.6,0.6,0 --up 0,1,0 --fov 10 --size 9x9
check "the back of the floor is black" py "$HDR"'
import sys
assert all(px == [0.0, 0.0, 0.0] for row in read_hdr(sys.argv[1]) for px in row)
' "$TMP/below.hdr"
expect 0 "view to PNG with --exposure" "$ILF" view "$RAD" -o "$TMP/room.png" --position 1.5,1.5,0.8 \
    --look-at 0,1,0.5 --size 64x48 --exposure 1
check "view to PNG says its scale" stdout_has "scale 2 (from --exposure 1)"
expect 2 "view without --look-at" "$ILF" view "$RAD" -o "$TMP/never.png" --position 1,1,1
check "view says what is missing" stderr_has "--look-at"
expect 2 "view with up along the view direction" "$ILF" view "$RAD" -o "$TMP/never.png" --position 0,0,3 \
    --look-at 0,0,0
expect 2 "view with --fov 180" "$ILF" view "$RAD" -o "$TMP/never.png" --position 1,1,1 --look-at 0,0,0 --fov 180
expect 2 "view of a damaged radiance.h5" "$ILF" view "$TMP/damaged.h5" -o "$TMP/never.png" --position 1,1,1 \
    --look-at 0,0,0
expect 2 "view of a light field" "$ILF" view "$TMP/down.h5" -o "$TMP/never.png" --position 1,1,1 --look-at 0,0,0
check "no output is left by failed views" bash -c "! compgen -G '$TMP/never*' >/dev/null"

# ------------------------------------------------------------------ camera options, light fields in views
# A constant light field (2 W sr^-1 m^-2, 1 m at z = 0, emitting up) over a glowing floor 1 m below it, in a
# scene without a camera: the camera options of relight make the view; view --scene sees the slab too.
mkdir -p "$TMP/lfview"
expect 0 "synth a constant light field" "$ILF" synth --kind constant --radiance 2,2,2 --grid 4x4 --n 2 \
    --supersample 1 -o "$TMP/lfview/const.h5" -q
cat >"$TMP/lfview/scene.json" <<'JSON'
{
  "materials": {"glow": {"albedo": [0.5, 0.5, 0.5], "emission": [0.25, 0.5, 0.75]}},
  "polygons": [{"material": "glow", "vertices": [[-4, -4, -1], [4, -4, -1], [4, 4, -1], [-4, 4, -1]]}],
  "lightfields": [{"file": "const.h5"}],
  "radiance_maps": {"cell_size": 1},
  "sampling": {"method": "culled", "partition_n": 2, "rays_per_solid_angle": 1}
}
JSON
CAM=(--position 0,0,2 --look-at 0,0,0 --up 0,1,0 --fov 90 --size 40x40)
expect 0 "relight a scene without a camera, the camera options making one" "$ILF" relight \
    "$TMP/lfview/scene.json" -o "$TMP/lfview/relit" --threads 2 "${CAM[@]}"
check "the view is written at --size" stdout_has "view.exr: 40x40"
check "no warning that the scene has no camera" bash -c "! grep -q 'no camera' '$ERR'"
expect 2 "relight with --look-at alone on a scene without a camera" "$ILF" relight "$TMP/lfview/scene.json" \
    -o "$TMP/lfview/never" --look-at 0,0,0
check "it says what is missing" stderr_has "--position X,Y,Z is required"
expect 2 "relight with camera options and --no-view" "$ILF" relight "$TMP/lfview/scene.json" \
    -o "$TMP/lfview/never" --no-view --position 0,0,2 --look-at 0,0,0
expect 2 "relight with a degenerate camera" "$ILF" relight "$TMP/lfview/scene.json" -o "$TMP/lfview/never" \
    --up 0,0,1 --position 0,0,2 --look-at 0,0,0
check "it says why" stderr_has "up must not be zero or parallel"
check "no output folder is left by refused relights" bash -c "[ ! -e '$TMP/lfview/never' ]"
expect 0 "view the constant slab straight on, with --scene" "$ILF" view "$TMP/lfview/relit/radiance.h5" \
    --scene "$TMP/lfview/scene.json" -o "$TMP/lfview/with.hdr" "${CAM[@]}"
check "view --scene counts the light fields" stdout_has "40x40, 1 maps, 1 light fields"
expect 0 "and without" "$ILF" view "$TMP/lfview/relit/radiance.h5" -o "$TMP/lfview/without.hdr" "${CAM[@]}"
check "inside the slab its constant, around it the floor; without --scene the floor throughout" py "$HDR"'
import sys
glow = [0.25, 0.5, 0.75]
# within one step of the RGBE encoding (8-bit mantissas): test_relight holds the float values to 1e-5
near = lambda px, want: all(abs(g - w) <= w / 128 for g, w in zip(px, want))
with_slab, without = read_hdr(sys.argv[1]), read_hdr(sys.argv[2])
# at the slab plane a pixel is 0.1 m: pixels 15 .. 24 lie inside [-0.5, 0.5], 0 .. 13 and 26 .. 39 outside
for y in range(40):
    for x in range(40):
        inside = 15 <= x <= 24 and 15 <= y <= 24
        outside = x <= 13 or x >= 26 or y <= 13 or y >= 26
        if inside:
            assert near(with_slab[y][x], [2.0, 2.0, 2.0]), (x, y, with_slab[y][x])
        if outside:
            assert near(with_slab[y][x], glow), (x, y, with_slab[y][x])
        assert near(without[y][x], glow), (x, y, without[y][x])
' "$TMP/lfview/with.hdr" "$TMP/lfview/without.hdr"

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
