#!/usr/bin/env bash
# bench_smoke.sh - a smoke run of `ilf bench` (seconds): the sweep writes its
# CSV, JSON, summary and plots, the reference is cached and reused, and
# `--rays` reports a ray rate.
#
# Usage: bash bench_smoke.sh ILF_BINARY [TMPDIR]
#
# The scene is written here: a 4 m floor, a 1 m blocker 1 m above it and a
# 1 m emitter 2 m above it, cells of 0.25 m (272 cells). Every check is
# counted; the last line is "N passed, M failed" and the exit status is
# nonzero when anything failed. Needs bash and awk only; the PNG check runs
# when gnuplot is installed.
set -u

if [ $# -lt 1 ] || [ $# -gt 2 ]; then
    echo "usage: bash bench_smoke.sh ILF_BINARY [TMPDIR]" >&2
    exit 2
fi
ILF=$1
TMP=${2:-$(mktemp -d "${TMPDIR:-/tmp}/bench_smoke.XXXXXX")}
rm -rf "$TMP"
mkdir -p "$TMP"

# check DESCRIPTION COMMAND... and the counts $passed, $failed
. "$(dirname "$0")/checks.sh"

# csv_ok FILE MIN_ROWS: the header names the columns and at least MIN_ROWS rows follow,
# each with a method name and then only finite numbers.
csv_ok() {
    awk -F, -v min="$2" '
        NR == 1 { ok = ($1 == "method" && $0 ~ /wall_seconds/ && $0 ~ /rmse/ && $0 ~ /snr_db/); cols = NF; next }
        {
            rows++
            if (NF != cols || $1 !~ /^[a-z]+$/) ok = 0
            for (i = 2; i <= NF; i++)
                if ($i !~ /^-?[0-9]+(\.[0-9]+)?([eE][-+]?[0-9]+)?$/) ok = 0
        }
        END { exit !(ok && rows >= min) }' "$1"
}

cat >"$TMP/tiny.json" <<'EOF'
{
  "materials": {
    "floor": {"albedo": [0.5, 0.5, 0.5]},
    "lamp": {"albedo": [0, 0, 0], "emission": [10, 10, 10]}
  },
  "polygons": [
    {"material": "floor", "vertices": [[0, 0, 0], [4, 0, 0], [4, 4, 0], [0, 4, 0]]},
    {"material": "floor", "vertices": [[1.5, 1.5, 1], [1.5, 2.5, 1], [2.5, 2.5, 1], [2.5, 1.5, 1]]},
    {"material": "lamp", "vertices": [[1.5, 1.5, 2], [1.5, 2.5, 2], [2.5, 2.5, 2], [2.5, 1.5, 2]]}
  ],
  "radiance_maps": {"cell_size": 0.25},
  "sampling": {"partition_n": 16, "rays_per_solid_angle": 4, "seed": 1},
  "camera": {"position": [2, -3, 3], "look_at": [2, 2, 0], "fov_deg": 60, "width": 160, "height": 120}
}
EOF

OUT=$TMP/out
CACHE=$TMP/cache
bench() {
    "$ILF" bench "$TMP/tiny.json" -o "$OUT" --quick --methods culled,area,adaptive --time-limit 5 --cache "$CACHE" "$@"
}

# First run: computes and caches the reference.
bench >"$TMP/run1.out" 2>"$TMP/run1.err"
code=$?
check "first run exits 0 (got $code)" [ "$code" -eq 0 ]
check "first run computes the reference" grep -q '^reference: computing' "$TMP/run1.out"
check "bench.csv has a header and >= 6 rows of finite numbers (adaptive too)" csv_ok "$OUT/bench.csv" 6
check "bench.json written" [ -s "$OUT/bench.json" ]
check "summary.md has the comparisons" grep -q '^## Comparisons' "$OUT/summary.md"
check "the reference is cached" compgen -G "$CACHE/ref-*.h5" >/dev/null
check "error_vs_time.gp written" [ -s "$OUT/error_vs_time.gp" ]
check "error images' data written" [ -s "$OUT/error_culled.bin" ]
if command -v gnuplot >/dev/null 2>&1; then
    check "error_vs_time.png drawn" [ -s "$OUT/error_vs_time.png" ]
    check "error_area.png drawn" [ -s "$OUT/error_area.png" ]
else
    echo "note: gnuplot not installed: PNG checks skipped"
fi
# temporaries are hidden files (ilf/atomic_file.h: .NAME.tmp-TAG[.EXT]), which '*' does not match
check "no temporaries left" bash -c "! compgen -G '$OUT/*tmp*' >/dev/null && ! compgen -G '$OUT/.*.tmp-*' >/dev/null && ! compgen -G '$OUT/.error-run*' >/dev/null"

# Second run: the reference comes from the cache.
bench >"$TMP/run2.out" 2>"$TMP/run2.err"
code=$?
check "second run exits 0 (got $code)" [ "$code" -eq 0 ]
check "second run reuses the cached reference" grep -q '^reference: cached' "$TMP/run2.out"
check "second run does not compute it" bash -c "! grep -q '^reference: computing' '$TMP/run2.out'"

# pareto_resolved FILE: no row on a front has a reference that does not resolve it.
pareto_resolved() {
    awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) col[$i] = i; next }
             $col["pareto"] == 1 && $col["ref_adequate"] != 1 { bad = 1 }
             END { exit bad }' "$1"
}
check "fronts hold only runs the reference resolves" pareto_resolved "$OUT/bench.csv"

# A coarse reference (2 samples) resolves none of the runs: they are listed, not compared.
bench --reference-samples 2 --methods culled -o "$TMP/coarse" >"$TMP/coarse.out" 2>&1
code=$?
check "coarse-reference run exits 0 (got $code)" [ "$code" -eq 0 ]
check "coarse reference: runs marked unresolved" grep -q 'unresolved' "$TMP/coarse/summary.md"
check "coarse reference: no run on a front" awk -F, 'NR > 1 && $21 == 1 { bad = 1 } END { exit bad }' \
    "$TMP/coarse/bench.csv"

# The independent reference: path tracing on 32 sampled cells, one run at the scene's own settings.
ptbench() {
    "$ILF" bench "$TMP/tiny.json" -o "$TMP/pt" --reference pathtrace --reference-cells 32 --reference-samples 256 \
        --scene-settings --cache "$CACHE" "$@"
}
ptbench >"$TMP/pt1.out" 2>&1
code=$?
check "--reference pathtrace exits 0 (got $code)" [ "$code" -eq 0 ]
check "pathtrace: computes its reference" grep -q '^reference: computing: pathtrace, 32 cells' "$TMP/pt1.out"
check "pathtrace: cached as a .pt file" compgen -G "$CACHE/ref-*.pt" >/dev/null
check "pathtrace: bench.json names the method and its 32 cells" \
    bash -c "grep -q '\"method\":[[:space:]]*\"pathtrace\"' '$TMP/pt/bench.json' &&
             grep -q '\"cells_with_values\":[[:space:]]*32' '$TMP/pt/bench.json'"
check "pathtrace: --scene-settings runs one setting" csv_ok "$TMP/pt/bench.csv" 1
check "pathtrace: the summary says what the reference is" grep -q 'Independent path tracing' "$TMP/pt/summary.md"
ptbench >"$TMP/pt2.out" 2>&1
check "pathtrace: the second run reuses it" grep -q '^reference: cached .*\.pt: pathtrace' "$TMP/pt2.out"
"$ILF" bench "$TMP/tiny.json" -o "$TMP/pt" --reference nosuch >/dev/null 2>&1
code=$?
check "an unknown --reference is bad usage (got $code)" [ "$code" -eq 2 ]

# The ray ceiling.
"$ILF" bench --rays "$TMP/tiny.json" --rays-count 100000 -o "$TMP/rays" >"$TMP/rays.out" 2>&1
code=$?
check "--rays exits 0 (got $code)" [ "$code" -eq 0 ]
check "--rays prints a rate" grep -Eq 'rays: [0-9]+ in .* rays/s' "$TMP/rays.out"
check "--rays writes rays.json" grep -q '"rays_per_second"' "$TMP/rays/rays.json"

# Scaling: both series run (five cell sizes and the partition levels), and both fits are written.
"$ILF" bench --scaling "$TMP/tiny.json" -o "$TMP/scaling" --time-limit 5 --quiet >"$TMP/scaling.out" 2>&1
code=$?
check "--scaling exits 0 (got $code)" [ "$code" -eq 0 ]
check "--scaling runs every cell size" test "$(grep -c '^cells,' "$TMP/scaling/scaling.csv")" -eq 5
check "--scaling runs the partition series" grep -q '^partition_n,' "$TMP/scaling/scaling.csv"
check "--scaling fits both series" grep -q '"time_exponent"' "$TMP/scaling/scaling.json"

# Bad usage is exit 2.
"$ILF" bench "$TMP/tiny.json" >/dev/null 2>&1
code=$?
check "a sweep without -o is bad usage (got $code)" [ "$code" -eq 2 ]

# `ilf bench` is the program ilf-bench beside ilf: the same help by either name; an ilf without it beside
# says so and fails (exit 1).
check "ilf-bench --help is ilf bench --help" cmp -s <("$ILF" bench --help) <("$(dirname "$ILF")/ilf-bench" --help)
mkdir -p "$TMP/alone"
cp "$ILF" "$TMP/alone/ilf"
"$TMP/alone/ilf" bench --help >/dev/null 2>"$TMP/alone.err"
code=$?
check "ilf without ilf-bench beside it fails (got $code)" [ "$code" -eq 1 ]
check "and names the program it looked for" grep -q "ilf bench: cannot run $TMP/alone/ilf-bench: No such file" "$TMP/alone.err"

if [ "$failed" -gt 0 ]; then
    for f in run1.err run2.err rays.out scaling.out; do
        sed "s/^/    $f: /" "$TMP/$f" | head -n 10
    done
fi
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
