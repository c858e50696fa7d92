#!/usr/bin/env python3
"""bench/bounce_error.py - how far a run's bounce light is from a reference's.

    bench/bounce_error.py REF_TOTAL REF_DIRECT RUN_TOTAL RUN_DIRECT

Each argument is a radiance.h5 written by `ilf relight` for the same scene
and cell size: a run with bounces and the same run with `--bounces 0` (same
seed and direct settings, so that its direct pass is the same). The bounce
light of a pair is the difference of their irradiance, averaged over the RGB
channels. Prints the reference's area-weighted mean bounce light, the run's
mean against it, and the area-weighted RMSE and the largest difference over
every cell, both as shares of that mean (BENCHMARKS-journal.md, section 2d).
"""
import sys

import numpy as np

from radmap_cells import cells as map_cells


def cells(path):
    """Irradiance (mean of RGB) and area of every cell, in patch order (either format of radiance.h5)."""
    e = map_cells(path, "irradiance").astype(np.float64).mean(axis=1)
    return e, map_cells(path, "cell_area").astype(np.float64)


def main(argv):
    if len(argv) != 5:
        sys.stderr.write(__doc__.split("\n\n")[1] + "\n")
        return 2
    (ref_t, area), (ref_d, _), (run_t, _), (run_d, _) = (cells(p) for p in argv[1:])
    if not (len(ref_t) == len(ref_d) == len(run_t) == len(run_d)):
        sys.stderr.write("bounce_error.py: the four files do not have the same cells\n")
        return 2
    w = area / area.sum()
    ref, run = ref_t - ref_d, run_t - run_d
    mean = float((w * ref).sum())
    if not mean > 0:
        sys.stderr.write("bounce_error.py: %s and %s hold no bounce light to compare with\n" % (argv[1], argv[2]))
        return 2
    rmse = float(np.sqrt((w * (run - ref) ** 2).sum()))
    print("bounce light mean %.6g W/m2; run's mean %+.3f%%; RMSE %.2f%% of the mean; largest difference %.1f%%"
          % (mean, 100 * ((w * run).sum() / mean - 1), 100 * rmse / mean, 100 * np.abs(run - ref).max() / mean))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
