#!/bin/sh
# bench/points.sh - point queries (`ilf irradiance`) against Lambert's closed
# form and, when it is installed, against Radiance's `rtrace -I -ab 0`, on
# five cases; one thread each, time per point after start-up.
#
#   bench/points.sh [OUT]            (default OUT = out/points)
#
# Environment: ILF (default build/tools/ilf); RTRACE and OCONV (default: found
# on PATH; the rtrace column is skipped without them); N1, N2 (point counts,
# default 2000 and 20000: the time per point is the difference of the two
# runs' times over N2 - N1, so start-up cancels); REPEATS (default 3, medians).
# Radiance is not part of ilfkit: build it elsewhere (its CMake build, targets
# rtrace and oconv) and point RTRACE/OCONV at it (RAYPATH defaults to the lib/
# folder beside RTRACE's bin/).
#
# Cases (an emitter of radiance 10 W sr^-1 m^-2 in every channel):
#   floor     1 m square 1 m up, points on the floor under and around it
#   grazing   points 3 m from that square, 0.5 m below its plane, whose
#             normals are tilted 1e-6 .. 0.1 rad (log-uniform) from the plane
#             that holds the direction to the square's centre: the square
#             straddles their horizon
#   edge      a vertical 1 m square standing on the floor, points on the floor
#             1e-4 .. 1 m (log-uniform) from its lower edge, facing up
#   edge-on   points 1e-6 m under the square's plane, 1 .. 3 m from it, facing it
#   occluded  the floor case with a closed 0.4 m box halfway under the square
#             (reference: `ilf irradiance --method solidangle --samples 32768`)
# Errors are RMSE and largest error over the points, relative to the largest
# reference value.
set -eu
cd "$(dirname "$0")/.."
ILF=${ILF:-build/tools/ilf}
OUT=${1:-out/points}
N1=${N1:-2000}
N2=${N2:-20000}
REPEATS=${REPEATS:-3}
RTRACE=${RTRACE:-$(command -v rtrace || true)}
OCONV=${OCONV:-$(command -v oconv || true)}
py=/usr/bin/python3
[ -x "$ILF" ] || { echo "bench/points.sh: $ILF: not built (see README.md)" >&2; exit 2; }
$py -c 'import numpy' 2>/dev/null || { echo "bench/points.sh: $py needs numpy (python3-numpy)" >&2; exit 2; }
if [ -z "$RTRACE" ] || [ -z "$OCONV" ]; then
    echo "bench/points.sh: rtrace or oconv not found: the Radiance column is skipped" >&2
    RTRACE="" OCONV=""
fi
# rtrace finds its .cal files on RAYPATH; a build tree keeps them in lib/ beside bin/
if [ -n "$RTRACE" ] && [ -z "${RAYPATH:-}" ] && [ -d "$(dirname "$RTRACE")/../lib" ]; then
    RAYPATH=.:$(cd "$(dirname "$RTRACE")/../lib" && pwd)
    export RAYPATH
fi
mkdir -p "$OUT"

# The cases: scene JSON, Radiance description, and points files, written by one script.
$py - "$OUT" "$N1" "$N2" <<'EOF'
import json, math, sys
import numpy as np
out, n1, n2 = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
rng = np.random.default_rng(7)
L = 10.0
lamp = [[0.5, 0.5, 1], [0.5, 1.5, 1], [1.5, 1.5, 1], [1.5, 0.5, 1]]     # faces down (-z)
wall = [[0, 0.5, 0], [0, 1.5, 0], [0, 1.5, 1], [0, 0.5, 1]]             # at x = 0, faces +x
def box(c, h):
    (cx, cy, cz), (hx, hy, hz) = c, h
    x0, x1, y0, y1, z0, z1 = cx - hx, cx + hx, cy - hy, cy + hy, cz - hz, cz + hz
    return [[[x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]],   # top, +z
            [[x0, y0, z0], [x0, y1, z0], [x1, y1, z0], [x1, y0, z0]],   # bottom, -z
            [[x0, y0, z0], [x1, y0, z0], [x1, y0, z1], [x0, y0, z1]],   # -y
            [[x0, y1, z0], [x0, y1, z1], [x1, y1, z1], [x1, y1, z0]],   # +y
            [[x0, y0, z0], [x0, y0, z1], [x0, y1, z1], [x0, y1, z0]],   # -x
            [[x1, y0, z0], [x1, y1, z0], [x1, y1, z1], [x1, y0, z1]]]   # +x
def unit(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)
def points(case, n):
    p = np.zeros((n, 6))
    if case in ('floor', 'occluded'):
        p[:, 0] = rng.uniform(-0.5, 2.5, n); p[:, 1] = rng.uniform(-0.5, 2.5, n); p[:, 5] = 1
        if case == 'occluded':  # not inside the box's footprint
            inside = (abs(p[:, 0] - 1) < 0.2) & (abs(p[:, 1] - 1) < 0.2)
            p[inside, 0] += 0.5
    elif case == 'grazing':
        p[:, 0] = 4.0; p[:, 1] = rng.uniform(0.5, 1.5, n); p[:, 2] = 0.5
        for i in range(n):
            u = unit(np.array([1.0, 1.0, 1.0]) - p[i, :3])            # to the square's centre
            m = unit(np.cross(np.cross(u, [0, 0, 1]), u))                # perpendicular to u, upward
            a = 10 ** rng.uniform(-6, -1)
            p[i, 3:] = math.cos(a) * m + math.sin(a) * u
    elif case == 'edge':
        p[:, 0] = 10 ** rng.uniform(-4, 0, n); p[:, 1] = rng.uniform(0.5, 1.5, n); p[:, 5] = 1
    elif case == 'edge-on':
        p[:, 0] = rng.uniform(2.5, 4.5, n); p[:, 1] = rng.uniform(0.5, 1.5, n); p[:, 2] = 1 - 1e-6; p[:, 3] = -1
    return p
cases = {'floor': [lamp], 'grazing': [lamp], 'edge': [wall], 'edge-on': [lamp],
         'occluded': [lamp] + box((1, 1, 0.5), (0.2, 0.2, 0.2))}
floor = [[-3, -3, 0], [5, -3, 0], [5, 5, 0], [-3, 5, 0]]
for case, polys in cases.items():
    mats = {"lamp": {"albedo": [0, 0, 0], "emission": [L, L, L]}, "grey": {"albedo": [0.5, 0.5, 0.5]}}
    scene = {"materials": mats, "polygons": [{"material": "lamp", "vertices": polys[0]}] +
             [{"material": "grey", "vertices": q} for q in polys[1:]], "radiance_maps": {"cell_size": 1.0}}
    json.dump(scene, open(f"{out}/{case}.json", "w"))
    with open(f"{out}/{case}.rad", "w") as f:
        f.write(f"void light lampmat 0 0 3 {L} {L} {L}\nvoid plastic grey 0 0 5 .5 .5 .5 0 0\n")
        for k, q in enumerate(polys):
            f.write(f"{'lampmat' if k == 0 else 'grey'} polygon p{k} 0 0 {3 * len(q)} " +
                    " ".join("%.17g" % c for v in q for c in v) + "\n")
    for n in (n1, n2):
        np.savetxt(f"{out}/{case}-{n}.txt", points(case, n), fmt="%.17g")
EOF

# lambert CASE N: Lambert's closed form at the points (one value a line), for unoccluded cases
lambert() {
    $py - "$OUT/$1.json" "$OUT/$1-$2.txt" <<'EOF'
import json, math, sys
import numpy as np
s = json.load(open(sys.argv[1])); poly = np.array(s["polygons"][0]["vertices"], float)
L = s["materials"]["lamp"]["emission"][1]
ns = np.cross(poly[1] - poly[0], poly[2] - poly[0])
for row in np.loadtxt(sys.argv[2], ndmin=2):
    x, n = row[:3], row[3:] / np.linalg.norm(row[3:])
    if np.dot(x - poly[0], ns) <= 0:
        print(0.0); continue
    c = []
    for i in range(len(poly)):
        a, b = poly[i], poly[(i + 1) % len(poly)]
        da, db = np.dot(a - x, n), np.dot(b - x, n)
        if da >= 0: c.append(a)
        if (da >= 0) != (db >= 0): c.append(a + da / (da - db) * (b - a))
    t = 0.0
    for i in range(len(c)):
        a, b = c[i] - x, c[(i + 1) % len(c)] - x
        a, b = a / np.linalg.norm(a), b / np.linalg.norm(b)
        g = np.cross(a, b); sn = np.linalg.norm(g)
        if sn > 0: t += math.atan2(sn, np.dot(a, b)) * np.dot(g, n) / sn
    print("%.17g" % (0.5 * L * abs(t)))
EOF
}
# errors REF OUT: "RMSE max" of column 2 of OUT against REF, relative to max REF
errors() {
    $py - "$1" "$2" <<'EOF'
import sys
import numpy as np
r = np.loadtxt(sys.argv[1], ndmin=2)
r = r[:, 1] if r.shape[1] > 1 else r[:, 0]
a = np.loadtxt(sys.argv[2], ndmin=2)[:, 1]
e = a - r
print("%.3g%% %.3g%%" % (100 * np.sqrt(np.mean(e ** 2)) / r.max(), 100 * abs(e).max() / r.max()))
EOF
}
median() { $py -c "import sys,statistics; print(statistics.median(map(float, sys.argv[1:])))" "$@"; }
# per_point NAME COMMAND...: median microseconds per point (N2 - N1 points) over REPEATS; writes OUT/NAME-N2.out
per_point() {
    name=$1
    shift
    t1="" t2=""
    i=0
    while [ $i -lt "$REPEATS" ]; do
        for n in "$N1" "$N2"; do
            s=$($py -c 'import time; print(time.perf_counter())')
            "$@" < "$OUT/$case-$n.txt" > "$OUT/$name-$n.out"
            e=$($py -c 'import time; print(time.perf_counter())')
            if [ "$n" = "$N1" ]; then t1="$t1 $($py -c "print($e - $s)")"; else t2="$t2 $($py -c "print($e - $s)")"; fi
        done
        i=$((i + 1))
    done
    $py -c "print('%.3g' % (1e6 * ($(median $t2) - $(median $t1)) / ($N2 - $N1)))"
}

echo "# point queries, $(date -u +%Y-%m-%dT%H:%MZ), one thread; us per point (median of $REPEATS), RMSE and max of the peak"
echo "| case | method | us/point | RMSE | max |"
echo "|---|---|---:|---:|---:|"
for case in floor grazing edge edge-on occluded; do
    if [ $case = occluded ]; then
        "$ILF" irradiance "$OUT/$case.json" --points "$OUT/$case-$N2.txt" --method solidangle --samples 32768 \
            > "$OUT/$case-ref.txt"
    else
        lambert $case "$N2" > "$OUT/$case-ref.txt"
    fi
    for m in culled solidangle area; do
        us=$(per_point "$case-$m" "$ILF" irradiance "$OUT/$case.json" --points - --threads 1 --method $m)
        echo "| $case | ilf $m | $us | $(errors "$OUT/$case-ref.txt" "$OUT/$case-$m-$N2.out" | sed 's/ / | /') |"
    done
    if [ -n "$RTRACE" ]; then
        "$OCONV" "$OUT/$case.rad" > "$OUT/$case.oct"
        us=$(per_point "$case-rtrace" "$RTRACE" -h -I -ab 0 "$OUT/$case.oct")
        echo "| $case | rtrace -I -ab 0 | $us | $(errors "$OUT/$case-ref.txt" "$OUT/$case-rtrace-$N2.out" | sed 's/ / | /') |"
    fi
done
