#!/bin/sh
# bench/compare.sh - two builds of ilf side by side on the data/ scenes: the
# time of each relighting (median of alternating repeats, so that machine
# noise hits both alike) and its error against a converged reference.
#
#   bench/compare.sh OLD_ILF NEW_ILF [OUT]     (default OUT = out/compare)
#
# OLD_ILF is typically a build of an earlier commit:
#   git worktree add /tmp/ilf-old <commit> && cmake -S /tmp/ilf-old -B /tmp/ilf-old/build \
#       -DCMAKE_BUILD_TYPE=Release && cmake --build /tmp/ilf-old/build -j --target ilf
# References are `ilf bench` references (two `solidangle` runs of
# REF_SAMPLES samples per cell and emitter, default 8192), computed by
# NEW_ILF once and cached in OUT/cache; the error is the RMSE of the
# luminance of irradiance over every cell, as in `ilf bench`. Environment:
# REPEATS (default 3), REF_SAMPLES. Writes OUT/results.txt.
set -eu
cd "$(dirname "$0")/.."
[ $# -ge 2 ] || { echo "usage: bench/compare.sh OLD_ILF NEW_ILF [OUT]" >&2; exit 2; }
OLD=$1 NEW=$2 OUT=${3:-out/compare}
REPEATS=${REPEATS:-3}
REF_SAMPLES=${REF_SAMPLES:-8192}
for b in "$OLD" "$NEW"; do
    [ -x "$b" ] || { echo "bench/compare.sh: $b: not an executable" >&2; exit 2; }
done
py=/usr/bin/python3
mkdir -p "$OUT/cache"
RES="$OUT/results.txt"
: > "$RES"
say() { echo "$*" | tee -a "$RES"; }
say "# ilf old vs new, $(date -u +%Y-%m-%dT%H:%MZ); old: $OLD; new: $NEW (commit $(git rev-parse --short HEAD 2>/dev/null || echo unknown))"
say "machine: $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) cores; $REPEATS alternating repeats, medians"

median() { $py -c "import sys,statistics; print('%.4g' % statistics.median(map(float, sys.argv[1:])))" "$@"; }
stat() { $py -c "import json,sys; d=json.load(open(sys.argv[1])); [d := d[k] if not k.isdigit() else d[int(k)] for k in sys.argv[2:]]; print(d)" "$@"; }
# rmse REF.h5 RUN.h5: RMSE of the luminance of irradiance over every cell
rmse() {
    PYTHONPATH="$PWD/bench${PYTHONPATH:+:$PYTHONPATH}" $py - "$1" "$2" <<'EOF'
import sys, numpy as np
from radmap_cells import cells
w = np.array([0.2126, 0.7152, 0.0722])
def y(p):
    return np.asarray(cells(p, 'irradiance'), dtype=float) @ w
a, b = y(sys.argv[1]), y(sys.argv[2])
print('%.5g' % np.sqrt(np.mean((a - b) ** 2)))
EOF
}
# reference SCENE BOUNCES: the path of the cached reference of SCENE (computed once)
reference() {
    d="$OUT/ref-$(basename "$1" .json)-b$2"
    "$NEW" bench "$1" -o "$d" --methods area --bounces "$2" --time-limit 0.01 --reference-samples "$REF_SAMPLES" \
        --cache "$OUT/cache" --quiet >/dev/null 2>&1 || true
    sed -n 's/.*`\([^`]*ref-[0-9a-f]*\.h5\)`.*/\1/p' "$d/summary.md" | head -1
}

# compare NAME SCENE OPTS: OLD and NEW alternately, REPEATS times each, then their medians, their errors
# against the reference (none with NOREF=1: scenes too large for one) and NEW's difference from OLD
compare() {
    name=$1 scene=$2
    shift 2
    ref=""
    [ "${NOREF:-0}" = 1 ] || ref=$(reference "$scene" 0)
    for s in old new; do eval "t_$s='' d_$s=''"; done
    i=0
    while [ $i -lt "$REPEATS" ]; do
        for s in old new; do
            eval "bin=\$$(echo $s | tr a-z A-Z)"
            dir="$OUT/$name-$s-$i"
            "$bin" relight "$scene" -o "$dir" --quiet --no-view "$@"
            eval "t_$s=\"\$t_$s $(stat "$dir/stats.json" wall_seconds)\""
            eval "d_$s=\"\$d_$s $(stat "$dir/stats.json" passes 0 wall_seconds)\""
        done
        i=$((i + 1))
    done
    for s in old new; do
        eval "t=\$t_$s; d=\$d_$s"
        e=n/a
        [ -n "$ref" ] && e=$(rmse "$ref" "$OUT/$name-$s-0/radiance.h5")
        # shellcheck disable=SC2086
        say "$name [$*] $s: total $(median $t) s, direct $(median $d) s wall; cells $(stat "$OUT/$name-$s-0/stats.json" cells); rays cast $(stat "$OUT/$name-$s-0/stats.json" passes 0 rays_cast); RMSE vs reference $e"
    done
    say "$name: RMSE of new against old $(rmse "$OUT/$name-old-0/radiance.h5" "$OUT/$name-new-0/radiance.h5")"
}

say ""
say "## direct light, default settings (error against the direct-light reference)"
compare beams_lightfield data/beams.json --bounces 0
compare beams_diffuse data/beams_diffuse.json --bounces 0
compare classroom data/classroom.json --bounces 0
# classroom_lightfield.h5 is generated, not kept (as in bench/reproduce.sh)
[ -e data/classroom_lightfield.h5 ] || {
    $py data/gen_scenes.py --out "$OUT/scenes" --ilf "$NEW" > /dev/null
    cp "$OUT/scenes/classroom_lightfield.h5" data/
}
NOREF=1 compare classroom_lightfield data/classroom_lightfield.json --bounces 0

say ""
say "## the classroom at the paper's 1.3 M cells, direct light (no reference: new against old)"
sed "s/\"cell_size\": *[0-9.]*/\"cell_size\": 0.018/" data/classroom.json > data/.compare_classroom_paper.json
sed "s/\"cell_size\": *[0-9.]*/\"cell_size\": 0.018/" data/classroom_lightfield.json > data/.compare_classroom_lf_paper.json
trap 'rm -f data/.compare_*.json' EXIT
NOREF=1 compare classroom_paper data/.compare_classroom_paper.json --bounces 0
NOREF=1 compare classroom_lf_paper data/.compare_classroom_lf_paper.json --bounces 0

say ""
say "## beams at the paper's cells with its 2 bounces; error of the total against a fine run of NEW"
say "## (every cell, bounce level 16, 8 rays: its own error is not negligible, a guide only)"
sed "s/\"cell_size\": *[0-9.]*/\"cell_size\": 0.0325/" data/beams.json > data/.compare_beams_paper.json
for s in old new; do eval "t_$s=''"; done
i=0
while [ $i -lt "$REPEATS" ]; do
    for s in old new; do
        eval "bin=\$$(echo $s | tr a-z A-Z)"
        "$bin" relight data/.compare_beams_paper.json -o "$OUT/beams_paper-$s-$i" --quiet --no-view
        eval "t_$s=\"\$t_$s $(stat "$OUT/beams_paper-$s-$i/stats.json" wall_seconds)\""
    done
    i=$((i + 1))
done
"$NEW" relight data/.compare_beams_paper.json -o "$OUT/beams_paper-ref" --quiet --no-view --bounce-cell-factor 1 \
    --bounce-partition-n 16 --rays 8 --seed 7
for s in old new; do
    eval "t=\$t_$s"
    # shellcheck disable=SC2086
    say "beams at the paper's cells, 2 bounces, $s: total $(median $t) s wall;" \
        "passes $(stat "$OUT/beams_paper-$s-0/stats.json" passes 0 wall_seconds) + $(stat "$OUT/beams_paper-$s-0/stats.json" passes 1 wall_seconds) + $(stat "$OUT/beams_paper-$s-0/stats.json" passes 2 wall_seconds) s;" \
        "RMSE of the total vs the fine reference $(rmse "$OUT/beams_paper-ref/radiance.h5" "$OUT/beams_paper-$s-0/radiance.h5")"
done
