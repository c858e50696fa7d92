#!/bin/sh
# bench/reproduce.sh - every measurement behind BENCHMARKS-journal.md, in one run.
#
#   bench/reproduce.sh [OUT]      (default OUT = out/benchmarks; needs a built build/tools/ilf)
#
# Environment: ILF (default build/tools/ilf), QUICK=1 for a fast rehearsal
# (fewer repeats, small sweeps), REPEATS (default 5), RTRACE and OCONV for
# the Radiance column of the point queries (bench/points.sh; skipped
# without), SECTIONS for some sections only (SECTIONS="3b 3d": their
# numbers as in the headings; default all). Every number BENCHMARKS-journal.md quotes is in
# OUT/results.txt or in the bench folders below it. Runs that are compared
# run alternately, so machine noise hits both sides alike; the medians of
# the repeats are reported. Takes about an hour on 2 cores.
set -eu
cd "$(dirname "$0")/.."
ILF=${ILF:-build/tools/ilf}
OUT=${1:-out/benchmarks}
QUICK=${QUICK:-0}
REPEATS=${REPEATS:-5}
[ "$QUICK" = 1 ] && REPEATS=1
mkdir -p "$OUT/relight"
RES="$OUT/results.txt"
: > "$RES"
say() { echo "$*" | tee -a "$RES"; }
# want SECTION: whether SECTIONS (default: every section) names it
want() { [ -z "${SECTIONS:-}" ] || case " $SECTIONS " in *" $1 "*) true ;; *) false ;; esac; }
for s in ${SECTIONS:-}; do
    case " 1 2 3 3b 3c 3d 4 5 6 7 " in
    *" $s "*) ;;
    *) echo "bench/reproduce.sh: SECTIONS: no section '$s' (sections: 1 2 3 3b 3c 3d 4 5 6 7, separated by spaces)" >&2
       exit 2 ;;
    esac
done
py=/usr/bin/python3

say "# ilfkit benchmarks, $(date -u +%Y-%m-%dT%H:%MZ), commit $(git rev-parse --short HEAD 2>/dev/null || echo unknown)"
say "machine: $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) cores, $(free -g | awk '/Mem:/ {print $2}') GiB"
[ -z "${SECTIONS:-}" ] || say "sections: $SECTIONS only"

# classroom_lightfield.h5 is generated, not kept: written (with the scenes, into OUT) by gen_scenes.py if missing;
# sections 3b, 3c, 3d and 5 read it
[ -e data/classroom_lightfield.h5 ] || {
    $py data/gen_scenes.py --out "$OUT/scenes" --ilf "$ILF" > /dev/null
    cp "$OUT/scenes/classroom_lightfield.h5" data/
}

# scene variants at the paper's cell counts: a copy with another cell size, beside the original
# so that relative file names still resolve
variant() { # SRC CELL_SIZE DST
    sed "s/\"cell_size\": *[0-9.]*/\"cell_size\": $2/" "$1" > "$3"
}
variant data/beams.json 0.0325 data/.bench_beams_paper.json
variant data/beams_diffuse.json 0.0325 data/.bench_beams_diffuse_paper.json
variant data/classroom.json 0.018 data/.bench_classroom_paper.json
variant data/classroom_lightfield.json 0.018 data/.bench_classroom_lightfield_paper.json
trap 'rm -f data/.bench_*.json' EXIT

# stat FILE KEY...: a number from a stats.json
stat() { $py -c "import json,sys; d=json.load(open(sys.argv[1])); [d := d[k] if not k.isdigit() else d[int(k)] for k in sys.argv[2:]]; print(d)" "$@"; }
# median of the arguments
median() { $py -c "import sys,statistics; print('%.4g' % statistics.median(map(float, sys.argv[1:])))" "$@"; }

# relight_pair NAME SCENE OPTS_A -- OPTS_B: REPEATS alternating runs of A and B (no view images);
# prints the median direct-pass and total wall and CPU seconds of each
relight_pair() {
    name=$1 scene=$2
    shift 2
    a="" b="" side=a
    for x in "$@"; do
        if [ "$x" = "--" ]; then side=b; continue; fi
        if [ $side = a ]; then a="$a $x"; else b="$b $x"; fi
    done
    for s in a b; do eval "w_$s='' c_$s='' d_$s='' p_$s=''"; done
    i=0
    while [ $i -lt $REPEATS ]; do
        for s in a b; do
            eval "opts=\$$s"
            dir="$OUT/relight/$name-$s-$i"
            # shellcheck disable=SC2086
            /usr/bin/time -f %M -o "$dir.rss" "$ILF" relight "$scene" -o "$dir" --quiet --no-view $opts
            eval "w_$s=\"\$w_$s $(stat "$dir/stats.json" wall_seconds)\""
            eval "c_$s=\"\$c_$s $(stat "$dir/stats.json" cpu_seconds)\""
            eval "d_$s=\"\$d_$s $(stat "$dir/stats.json" passes 0 wall_seconds)\""
            eval "p_$s=\"\$p_$s $(cat "$dir.rss")\""
        done
        i=$((i + 1))
    done
    for s in a b; do
        eval "opts=\$$s; w=\$w_$s; c=\$c_$s; d=\$d_$s; p=\$p_$s"
        dir="$OUT/relight/$name-$s-0"
        # shellcheck disable=SC2086
        say "$name [$opts ]: cells $(stat "$dir/stats.json" cells); median of $REPEATS: direct pass $(median $d) s wall;" \
            "total $(median $w) s wall, $(median $c) s cpu; samples $(stat "$dir/stats.json" passes 0 samples)," \
            "rays $(stat "$dir/stats.json" passes 0 rays_cast) (direct); peak RSS $(median $p) KiB"
    done
}

if want 1; then
    say ""
    say "## 1. Paper settings, direct light (culled, n = 32, 4 rays), with and without zero-radiance culling"
    relight_pair beams_direct data/.bench_beams_paper.json --bounces 0 -- --bounces 0 --zero-culling 0
    # the same run as a user makes it, writing the camera's view (without OpenImageIO since f05a584): peak memory
    /usr/bin/time -f %M -o "$OUT/relight/beams_view.rss" "$ILF" relight data/.bench_beams_paper.json \
        -o "$OUT/relight/beams_view" --quiet --bounces 0
    say "beams_direct with view.exr/png: peak RSS $(cat "$OUT/relight/beams_view.rss") KiB"
    say "ilf info (no image, no scene): peak RSS $( /usr/bin/time -f %M "$ILF" info data/beams_lightfield.h5 2>&1 >/dev/null | tail -1) KiB"
fi
if want 2; then
    say ""
    say "## 2. Paper settings, 2 bounces (the paper's 36.85 s -> 20.39 s run): bounces by first-hit rays (the default)"
    say "   and by the method's transfer from every lit polygon (--bounce-rays 0, the gather before 2026-11-25's evening)"
    [ "$QUICK" = 1 ] || relight_pair beams_bounces data/.bench_beams_paper.json --bounces 2 -- --bounces 2 --bounce-rays 0
fi
if want 3; then
    say ""
    say "## 3. classroom, direct: default cells, and the paper's 1.5 million"
    relight_pair classroom data/classroom.json --bounces 0 -- --bounces 0 --threads 1
    [ "$QUICK" = 1 ] || { REPEATS=1 relight_pair classroom_paper data/.bench_classroom_paper.json --bounces 0 -- --bounces 0 --partition-n 16; }
fi
if want 3b; then
    say ""
    say "## 3b. classroom lit by four light fields, direct, with and without zero-radiance culling (the paper's 51.83 -> 10.01 min)"
    relight_pair classroom_lf data/classroom_lightfield.json --bounces 0 -- --bounces 0 --zero-culling 0
    [ "$QUICK" = 1 ] || { REPEATS=1 relight_pair classroom_lf_paper data/.bench_classroom_lightfield_paper.json --bounces 0 -- --bounces 0 --zero-culling 0; }
fi
if want 3c; then
    say ""
    say "## 3c. One core against two (whole processes): one thread pinned to one processor, against two threads"
    say "   (a direct run writes radiance.h5 on a thread of its own: --threads 1 alone would lend it the second core)"
    # cores_pair NAME SCENE OPTS...: REPEATS alternating runs of 'taskset -c 0 ilf ... --threads 1' and
    # 'ilf ... --threads 2'; prints the median wall seconds of each and their ratio
    cores_pair() {
        name=$1 scene=$2
        shift 2
        one="" two=""
        i=0
        while [ $i -lt $REPEATS ]; do
            /usr/bin/time -f %e -o "$OUT/relight/$name-1core.t" taskset -c 0 "$ILF" relight "$scene" \
                -o "$OUT/relight/$name-1core" --quiet --no-view --threads 1 "$@"
            /usr/bin/time -f %e -o "$OUT/relight/$name-2cores.t" "$ILF" relight "$scene" \
                -o "$OUT/relight/$name-2cores" --quiet --no-view --threads 2 "$@"
            one="$one $(cat "$OUT/relight/$name-1core.t")" two="$two $(cat "$OUT/relight/$name-2cores.t")"
            i=$((i + 1))
        done
        m1=$(median $one) m2=$(median $two)
        say "$name: one core $m1 s, two $m2 s: $($py -c "print('%.2fx' % ($m1 / $m2))")"
    }
    if [ "$QUICK" != 1 ] && command -v taskset > /dev/null; then
        cores_pair classroom_lf_paper data/.bench_classroom_lightfield_paper.json --bounces 0
        cores_pair beams_bounces data/.bench_beams_paper.json --bounces 2
    fi
    say "the program image, no scene (ilf --help): peak RSS $( /usr/bin/time -f %M "$ILF" --help 2>&1 >/dev/null | tail -1) KiB"
fi
if want 3d; then
    say ""
    say "## 3d. Memory against the light a run holds (stats.json's memory: accumulators and light fields)"
    say "   anon: the process's own pages (RssAnon: heap, stacks, relocated data); file: the program's and its"
    say "   libraries' pages (RssFile, shared with every process that maps them); whole: the peak of both together"
    # memory_line NAME SCENE OPTS...: one run, sampled by bench/memory_split.py, its peaks against the light held
    memory_line() {
        name=$1 scene=$2
        shift 2
        dir="$OUT/relight/$name-memory"
        # an assignment, so that a failing run stops the script (set -e)
        line=$($py bench/memory_split.py --stats "$dir/stats.json" --name "$name" \
            "$ILF" relight "$scene" -o "$dir" --quiet --no-view "$@")
        say "$line"
    }
    if [ "$QUICK" != 1 ]; then
        memory_line classroom_lf_paper data/.bench_classroom_lightfield_paper.json --bounces 0
        memory_line beams_bounces data/.bench_beams_paper.json --bounces 2
    else
        memory_line classroom_lf data/classroom_lightfield.json --bounces 0
    fi
fi
if want 4; then
    say ""
    say "## 4. The ray ceiling"
    for s in beams classroom; do
        "$ILF" bench --rays "data/$s.json" -o "$OUT/rays_$s" --rays-count 10000000 | tee -a "$RES"
    done
    "$ILF" bench --rays data/beams.json -o "$OUT/rays_beams_1thread" --rays-count 10000000 --threads 1 | tee -a "$RES"
fi
if want 5; then
    say ""
    say "## 5. Sweeps (speed against accuracy)"
    SWEEP_OPTS="--time-limit 60 --reference-samples 8192"
    [ "$QUICK" = 1 ] && SWEEP_OPTS="--quick --time-limit 10"
    for s in beams_diffuse beams classroom classroom_lightfield; do
        # shellcheck disable=SC2086
        "$ILF" bench "data/$s.json" -o "$OUT/sweep_$s" --cache "$OUT/cache" --quiet $SWEEP_OPTS || true
        say "sweep $s: $OUT/sweep_$s/summary.md"
    done
fi
if want 6; then
    say ""
    say "## 6. Scaling"
    # shellcheck disable=SC2086
    "$ILF" bench --scaling data/beams.json -o "$OUT/scaling_beams" --quiet --time-limit 120 || true
    say "scaling: $OUT/scaling_beams"
fi
if want 7; then
    say ""
    say "## 7. Point queries (ilf irradiance; Radiance's rtrace -I beside it when RTRACE is set)"
    ILF="$ILF" REPEATS=$([ "$QUICK" = 1 ] && echo 1 || echo 3) sh bench/points.sh "$OUT/points" | tee -a "$RES"
fi
say "done"
