#!/usr/bin/env python3
"""bench/score_pathtrace.py - a radiance.h5's error against a cached path-traced reference.

Usage: /usr/bin/python3 bench/score_pathtrace.py REF.pt RADIANCE.h5 [RADIANCE.h5 ...]

`ilf bench --reference pathtrace` (docs/bench.md) caches its reference as a text file, ref-KEY.pt: a
header line, "key ...", a line with the cell count of the scene's maps, one "map" line a map, then a
"cell INDEX Y SE" line per sampled cell (the luminance of its mean irradiance and its standard error).
This scores any run's maps against it on those cells as `ilf bench` does (docs/bench.md, Metrics):
RMSE of the luminance over the sampled cells relative to the reference's mean there, the reference's
own RMS standard error SE, and the run's own part sqrt(RMSE^2 - SE^2). The run must have the same
cells (same scene and cell size); its radiance.h5 may be of any format version (radmap_cells.py), so
that runs of older builds are scored against the same reference as the current one.
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from radmap_cells import cells  # noqa: E402


def read_reference(path):
    """(total cells, [cell indices], [Y], [SE]) of a ref-KEY.pt file."""
    total, index, y, se = None, [], [], []
    with open(path) as f:
        if not f.readline().startswith("ilfkit pathtrace reference"):
            raise ValueError(path + ": not a path-traced reference")
        for line in f:
            w = line.split()
            if w and w[0] == "bounces":
                total = int(w[w.index("cells") + 1])
            elif w and w[0] == "cell":
                index.append(int(w[1]))
                y.append(float(w[2]))
                se.append(float(w[3]))
    if total is None or not index:
        raise ValueError(path + ": no cell count or no sampled cells")
    return total, index, y, se


def score(ref, radiance):
    """(RMSE relative, SE relative, own part relative, mean difference relative) of radiance.h5 against ref."""
    total, index, y, se = ref
    e = cells(radiance, "irradiance")
    if len(e) != total:
        raise ValueError("%s: %d cells, the reference's scene has %d" % (radiance, len(e), total))
    mean = sum(y) / len(y)
    diff = [0.2126 * e[c][0] + 0.7152 * e[c][1] + 0.0722 * e[c][2] - yr for c, yr in zip(index, y)]
    rmse = math.sqrt(sum(d * d for d in diff) / len(diff))
    s = math.sqrt(sum(v * v for v in se) / len(se))
    own = math.sqrt(max(0.0, rmse * rmse - s * s))
    return rmse / mean, s / mean, own / mean, sum(diff) / len(diff) / mean


def main():
    if len(sys.argv) < 3:
        sys.stderr.write(__doc__)
        return 2
    ref = read_reference(sys.argv[1])
    print("reference %s: %d of %d cells" % (sys.argv[1], len(ref[1]), ref[0]))
    for path in sys.argv[2:]:
        r, s, own, bias = score(ref, path)
        print("%s: RMSE %.3f%%, reference SE %.3f%%, own part %.3f%%, mean difference %+.3f%%"
              % (path, 100 * r, 100 * s, 100 * own, 100 * bias))
    return 0


if __name__ == "__main__":
    sys.exit(main())
