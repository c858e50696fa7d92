#!/bin/sh
# bench/profile.sh - where a whole `ilf relight` spends its time, per data/ scene:
# a perf profile, its flame graph and a table of the top functions, beside the
# run's rays per CPU second against `ilf bench --rays`'s ceiling
# (BENCHMARKS.md, Rays and memory; BENCHMARKS-journal.md, section 4b).
#
#   bench/profile.sh [OUT [SCENE.json ...]]
#
# OUT (default out/profile) gets, per scene S: S.perf.data (perf record), S.svg
# (the flame graph, bench/flamegraph.py), S.txt (the table of the top functions by
# inclusive share, then the rays line), S/ (the run's radiance.h5 and stats.json);
# and summary.txt, one rays line a scene. The scenes default to every data/*.json,
# each at its own settings (its file's sampling, bounces included), without the
# view. A scene whose light field file is missing is made by the command in its
# made_by (data/README.md).
#
# Call graphs are unwound from DWARF (--call-graph dwarf): the Release build, like
# Debian's Embree, omits frame pointers, so `perf record -g` would lose the callers.
# The samples are of CPU time (cpu-clock, which a container allows; cycles where
# the kernel lets perf read them: EVENT=cycles), so a loaded machine shifts wall
# time but not the shares.
#
# The rays line: rays cast per CPU second of the whole run (every pass, and the
# loading), and with the rays an exact test found free (which cost a little
# work, not a ray), against the ceiling: `ilf bench --rays SCENE` (random
# shadow rays through the engine's packet calls, timed alone), measured right
# after the run, one run each. Environment: ILF (default
# build/tools/ilf), THREADS (default 2), FREQ (samples per second, default 499),
# RAYS (ceiling rays, default 4000000), EVENT (default cpu-clock).
set -eu
out=${1:-out/profile}
[ $# -gt 0 ] && shift
ILF=${ILF:-build/tools/ilf}
THREADS=${THREADS:-2}
FREQ=${FREQ:-499}
RAYS=${RAYS:-4000000}
EVENT=${EVENT:-cpu-clock}
here=$(dirname "$0")
py=/usr/bin/python3
command -v perf > /dev/null || { echo "profile.sh: perf is not installed (Debian: linux-perf)" >&2; exit 2; }
[ $# -gt 0 ] || set -- "$here"/../data/*.json
mkdir -p "$out"
: > "$out/summary.txt"
for scene in "$@"; do
    name=$(basename "$scene" .json)
    # a light field the scene needs and the repository does not keep: made as its made_by says
    $py - "$scene" "$ILF" << 'EOF'
import json, os, shlex, subprocess, sys
scene, ilf = sys.argv[1], sys.argv[2]
root = os.path.dirname(os.path.abspath(scene))
for lf in json.load(open(scene)).get("lightfields", []):
    path = os.path.join(root, lf["file"])
    if not os.path.exists(path) and lf.get("made_by", "").startswith("ilf "):
        args = shlex.split(lf["made_by"])
        args[0] = ilf
        args[args.index("-o") + 1] = path
        subprocess.run(args, check=True, stdout=subprocess.DEVNULL)
EOF
    perf record -q -e "$EVENT" -F "$FREQ" --call-graph dwarf,32768 -o "$out/$name.perf.data" -- \
        "$ILF" relight "$scene" -o "$out/$name" --no-view --quiet --threads "$THREADS"
    perf script -i "$out/$name.perf.data" 2> /dev/null |
        $py "$here/flamegraph.py" --svg "$out/$name.svg" --title "ilf relight $name ($THREADS threads)" \
            --top 25 > "$out/$name.txt"
    ceiling=$("$ILF" bench --rays "$scene" --rays-count "$RAYS" --threads "$THREADS" 2>&1 |
        sed -n 's/.*, \([0-9.e+]*\) rays per cpu second.*/\1/p' | head -1)
    $py - "$out/$name/stats.json" "$name" "${ceiling:-0}" << 'EOF' | tee -a "$out/summary.txt" >> "$out/$name.txt"
import json, sys
s, name, ceiling = json.load(open(sys.argv[1])), sys.argv[2], float(sys.argv[3])
cast = sum(p["rays_cast"] for p in s["passes"])
free = sum(p["rays_free"] for p in s["passes"])
cpu = s["cpu_seconds"]
frac = lambda r: "%.0f%%" % (100 * r / ceiling) if ceiling > 0 else "no ceiling"
print("%s: %.2f s CPU; rays cast %.2f M/CPU s (%s of the ceiling %.2f M/CPU s); with the free %.2f M/CPU s (%s)"
      % (name, cpu, cast / cpu / 1e6, frac(cast / cpu), ceiling / 1e6, (cast + free) / cpu / 1e6,
         frac((cast + free) / cpu)))
EOF
done
cat "$out/summary.txt"
