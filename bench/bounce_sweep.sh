#!/bin/sh
# bench/bounce_sweep.sh - the error and time of bounce settings against a
# converged reference (BENCHMARKS-journal.md, section 2g; docs/methods.md, Bounces).
#
#   bench/bounce_sweep.sh SCENE BOUNCES OUT [SETTINGS ...]
#
# SETTINGS are ilf relight options for one variant, quoted together, e.g.
# "--bounce-cell-factor 4 --bounce-rays 256"; "" is the scene's defaults.
# The reference gathers every cell with 4096 rays (seed 7, 16 direct rays per
# solid angle), once, kept in OUT/ref (remove it to rebuild; on 'beams' at
# 46,961 cells it takes about a minute on 2 cores). Each variant runs at
# seeds 1 and 2 beside a direct-only run of the same seed, and its line gives
# the RMSE of the bounce light (bench/bounce_error.py) and the wall time of
# its bounce passes (stats.json). Environment: ILF (default
# build/tools/ilf), SEEDS (default "1 2").
set -eu
[ $# -ge 3 ] || { sed -n '4,7p' "$0" >&2; exit 2; }
scene=$1 bounces=$2 out=$3
shift 3
ILF=${ILF:-build/tools/ilf}
SEEDS=${SEEDS:-1 2}
here=$(dirname "$0")
py=/usr/bin/python3
mkdir -p "$out"
run() { # DIR OPTIONS...
    d=$1
    shift
    [ -f "$d/radiance.h5" ] || "$ILF" relight "$scene" -o "$d" --no-view --quiet "$@"
}
run "$out/ref" --bounces "$bounces" --rays 16 --bounce-cell-factor 1 --bounce-rays 4096 --seed 7
run "$out/ref0" --bounces 0 --rays 16 --seed 7
for s in $SEEDS; do
    run "$out/direct-$s" --bounces 0 --seed "$s"
done
k=0
for v in "$@"; do
    k=$((k + 1))
    for s in $SEEDS; do
        d="$out/v$k-$s"
        rm -rf "$d"
        # shellcheck disable=SC2086 # a variant's options are split on purpose
        run "$d" --bounces "$bounces" --seed "$s" $v
        err=$($py "$here/bounce_error.py" "$out/ref/radiance.h5" "$out/ref0/radiance.h5" "$d/radiance.h5" \
            "$out/direct-$s/radiance.h5" | sed 's/.*RMSE \([0-9.]*\)%.*/\1/')
        t=$($py -c "import json, sys; p = json.load(open(sys.argv[1]))['passes'][1:]; \
print('%.2f s, %d cells on their own' % (sum(x['wall_seconds'] for x in p), max([x.get('cells_direct', 0) for x in p] + [0])))" \
            "$d/stats.json")
        echo "${v:-defaults} | seed $s | RMSE $err% | bounce passes $t"
    done
done
