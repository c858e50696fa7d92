#!/usr/bin/env python3
"""smooth_light_test.py - the demo's ceiling is smooth at default settings.

Usage: python3 smooth_light_test.py ILF_BINARY SOURCE_DIR TMPDIR

The README's demo (data/beams.json: a light field lamp under the ceiling,
two bounces) lights the ceiling inside the lamp's frame by bounces alone, and
a bounce estimate whose cells draw independent rays shows there as mottling:
each cell's error differs from its neighbour's. The test relights a small
version of the demo (10 cm cells instead of 5 cm, so it runs in seconds)
at the scene's own settings, and again with 4 times the bounce rays (the
reference: its noise half the default's), and compares the
mottling of the ceiling inside the frame: the root mean square, over the
cells, of a cell's second difference to its two neighbours (along rows and
along columns) relative to its value. Light that varies smoothly has a
second difference near 0; noise of relative deviation s gives about
1.2 s. The default must stay within MOTTLING_RATIO of the reference's.
It also checks the per-cell error stats.json reports for the bounce passes
(docs/cli.md): present, ordered, and in agreement with the measured
mottling of the default run.
"""
import json
import os
import shutil
import subprocess
import sys

import h5py
import numpy as np

# The default's mottling against the reference's (4 times the bounce rays),
# measured at 10 cm cells: 1.33 (two bounces of the default 256 rays a cell,
# up to 1024 for the cells near the frame, fewer once a cell's error is within
# 2% of its light, one sequence per map; 1.32 with 1024 always); with 256 rays for
# every cell 1.74; with independent sequences for each cell, 2.17. The
# reference's own is 1.8% of the light, 1.5% at 16 times the rays: what is
# left is the light's own curvature and the seam of the cells near the frame.
MOTTLING_RATIO = 1.6
REFERENCE_RAYS = 4
CELL = 0.10
FRAME = (1.55, 3.45)  # the ceiling inside the lamp's frame (x and y), clear of the frame's beams
CEILING = 1           # the ceiling's polygon in data/beams.json

failures = []


def check(cond, what):
    """Records a failed check with its description."""
    if not cond:
        failures.append(what)
        print("FAILED: " + what)


def relight(ilf, scene, out, *extra):
    """Relights scene into folder out with ilf (no view); returns the parsed stats.json."""
    subprocess.run([ilf, "relight", scene, "-o", out, "--no-view", "--quiet", "--threads", "2", *extra],
                   check=True)
    with open(os.path.join(out, "stats.json")) as f:
        return json.load(f)


def ceiling_grid(path):
    """The ceiling's cell irradiance (mean of the channels) as a grid, NaN outside the frame's inside."""
    with h5py.File(path, "r") as f:
        g = f["patches"]
        a, b = g["cell_offset"][CEILING], g["cell_offset"][CEILING + 1]
        e = g["irradiance"][a:b].mean(axis=1)
        ij = g["cell_ij"][a:b]
        c = g["cell_centre"][a:b]
        grid = np.full((g["nv"][CEILING], g["nu"][CEILING]), np.nan)
    inside = (c[:, 0] > FRAME[0]) & (c[:, 0] < FRAME[1]) & (c[:, 1] > FRAME[0]) & (c[:, 1] < FRAME[1])
    grid[ij[inside, 1], ij[inside, 0]] = e[inside]
    return grid


def mottling(grid):
    """RMS over the cells of the second difference to both neighbours along rows and columns, relative."""
    parts = [(grid[1:-1, :] - 0.5 * (grid[:-2, :] + grid[2:, :])) / grid[1:-1, :],
             (grid[:, 1:-1] - 0.5 * (grid[:, :-2] + grid[:, 2:])) / grid[:, 1:-1]]
    d = np.concatenate([p[np.isfinite(p)] for p in parts])
    return float(np.sqrt(np.mean(d * d))), d.size


def main():
    ilf, source, tmp = sys.argv[1], os.path.abspath(sys.argv[2]), sys.argv[3]
    shutil.rmtree(tmp, ignore_errors=True)
    os.makedirs(tmp)
    with open(os.path.join(source, "data", "beams.json")) as f:
        scene = json.load(f)
    scene["radiance_maps"]["cell_size"] = CELL
    scene["lightfields"][0]["file"] = os.path.join(source, "data", "beams_lightfield.h5")
    path = os.path.join(tmp, "beams_small.json")
    with open(path, "w") as f:
        json.dump(scene, f)
    rays = int(scene["sampling"].get("bounce_rays", 256))
    stats = relight(ilf, path, os.path.join(tmp, "default"))
    relight(ilf, path, os.path.join(tmp, "reference"), "--bounce-rays", str(REFERENCE_RAYS * rays))
    m_default, n = mottling(ceiling_grid(os.path.join(tmp, "default", "radiance.h5")))
    m_ref, _ = mottling(ceiling_grid(os.path.join(tmp, "reference", "radiance.h5")))
    print("ceiling inside the frame: mottling %.4f at defaults, %.4f at %d bounce rays (ratio %.2f, %d differences)"
          % (m_default, m_ref, REFERENCE_RAYS * rays, m_default / m_ref, n))
    check(n > 500, "enough cells inside the frame: %d second differences" % n)
    check(m_ref > 0, "the reference's ceiling varies at all: %g" % m_ref)
    check(m_default <= MOTTLING_RATIO * m_ref,
          "the ceiling at defaults is mottled: %.4f > %.1f x the reference's %.4f" % (m_default, MOTTLING_RATIO, m_ref))
    # the error stats.json reports per cell: the bounce passes have it, the direct (culled) pass none
    passes = stats["passes"]
    check(passes[0]["cell_error"]["cells"] == 0, "the direct pass reports no per-cell error")
    for p in passes[1:]:
        e = p["cell_error"]
        check(e["cells"] > 0 and 0 < e["median"] <= e["p95"] <= e["max"],
              "pass %d: cell_error present and ordered: %s" % (p["pass"], e))
    # the cells gathered on their own stop once their error is within 2% of their light (bounce.c): the
    # second bounce, which carries less light than the direct pass and the first bounce, casts fewer
    # rays than the first, which the ceiling (lit by bounces alone) keeps at its full count
    check(passes[2]["rays_cast"] < passes[1]["rays_cast"],
          "the second bounce stops sooner: %d rays against the first's %d"
          % (passes[2]["rays_cast"], passes[1]["rays_cast"]))
    # the ceiling's mottling is the bounce passes' noise: of relative deviation s it gives a second
    # difference of about 1.2 s, so what is measured cannot much exceed what the reported errors allow
    p95 = max(p["cell_error"]["p95"] for p in passes[1:])
    check(m_default <= 1.5 * p95 + m_ref,
          "mottling %.4f within what the reported errors allow (largest p95 %.4f)" % (m_default, p95))
    print("%d failed" % len(failures))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
