"""test_ilfkit.py - the Python package ilfkit (python/, docs/python.md) against closed forms and the `ilf` command.

Run by ctest (test_python) with the build tree's package on PYTHONPATH and the built `ilf` in $ILF:
  /usr/bin/python3 -m pytest tests/python
Light fields come from `ilf synth` (a constant one has known radiance and irradiance); a square lamp over a
point has a closed-form irradiance; `ilf irradiance` and `ilf relight` are the C references, which the module
must match to their printed precision (the engine is deterministic).
"""

import math
import os
import subprocess
import threading
import time

import numpy as np
import pytest

import ilfkit

ILF = os.environ.get("ILF", "ilf")

# A unit square lamp 1 m above the centre of a 2 m floor, facing down; black everywhere else.
LAMP = (1.0, 2.0, 3.0)
SCENE = """{
  "materials": {"floor": {"albedo": [0.5, 0.5, 0.5]}, "lamp": {"albedo": [0.2, 0.2, 0.2], "emission": [%g, %g, %g]}},
  "polygons": [
    {"material": "floor", "vertices": [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]},
    {"material": "lamp", "vertices": [[-0.5, -0.5, 1], [-0.5, 0.5, 1], [0.5, 0.5, 1], [0.5, -0.5, 1]]}
  ],
  "radiance_maps": {"cell_size": 0.1},
  "sampling": {"partition_n": 8, "rays_per_solid_angle": 2, "bounces": 0, "seed": 3}
}
""" % LAMP


def ilf(*args, stdin=None):
    """@return the stdout of `ilf ARGS`, which must succeed."""
    return subprocess.run([ILF, *args], input=stdin, capture_output=True, text=True, check=True).stdout


def lamp_irradiance(x, y, h):
    """The irradiance per unit radiance at (x, y, 0) facing +z from the lamp square [-0.5, 0.5]^2 at height h:
    pi times the form factor of a parallel rectangle, summed over the four rectangles with a corner above
    the point (signed, for a point outside the square)."""
    def corner(a, b):  # rectangle a x b (in units of h) with a corner straight above the point
        sa, sb = math.sqrt(1 + a * a), math.sqrt(1 + b * b)
        return (a / sa * math.atan(b / sa) + b / sb * math.atan(a / sb)) / (2 * math.pi)
    total = 0.0
    for dx, sx in ((0.5 - x, 1), (0.5 + x, 1)):
        for dy, sy in ((0.5 - y, 1), (0.5 + y, 1)):
            total += sx * sy * math.copysign(1, dx) * math.copysign(1, dy) * corner(abs(dx) / h, abs(dy) / h)
    return math.pi * total


@pytest.fixture
def scene(tmp_path):
    path = tmp_path / "lamp.json"
    path.write_text(SCENE)
    return str(path)


@pytest.fixture
def constant_field(tmp_path):
    path = str(tmp_path / "constant.h5")
    ilf("synth", "--kind", "constant", "--grid", "3x2", "--n", "4", "--radiance", "0.25,0.5,2", "--name", "sky",
        "-o", path)
    return path


# ------------------------------------------------------------------ light fields

def test_constant_light_field(constant_field):
    lf = ilfkit.open(constant_field)
    assert len(lf) == 1 and lf[0] is lf["sky"]
    s = lf[0]
    assert (s.name, s.nu, s.nv, s.n, s.units) == ("sky", 3, 2, 4, "radiance")
    np.testing.assert_allclose(s.origin, [-0.5, -0.5, 0])
    np.testing.assert_allclose(s.u, [1, 0, 0])
    assert s.radiance.shape == (4 * 4 * 4, 2, 3, 3) and s.radiance.dtype == np.float32
    np.testing.assert_allclose(s.radiance, np.broadcast_to([0.25, 0.5, 2], s.radiance.shape), rtol=1e-6)
    # a constant hemisphere of radiance L gives pi L through the plane
    np.testing.assert_allclose(s.irradiance(0.5, 0.5), np.pi * np.array([0.25, 0.5, 2]), rtol=1e-4)
    np.testing.assert_allclose(s.radiance_at(0.2, 0.7, [0.3, -0.2, 1]), [0.25, 0.5, 2], rtol=1e-6)
    np.testing.assert_allclose(s.radiance_at(0.2, 0.7, [0, 0, -1]), [0, 0, 0])  # behind the slab
    np.testing.assert_allclose(s.position(2, 1), [-0.5 + 2.5 / 3, 0.25, 0])
    with pytest.raises(IndexError):
        lf[1]


def test_radiance_view_is_read_only_and_outlives_its_light_field(constant_field):
    radiance = ilfkit.open(constant_field)[0].radiance
    with pytest.raises(ValueError):
        radiance[0, 0, 0, 0] = 1
    np.testing.assert_allclose(radiance[:, 1, 2], np.broadcast_to([0.25, 0.5, 2], (64, 3)), rtol=1e-6)


def test_spot_light_field_against_lookups(tmp_path):
    """A non-constant field on a turned slab (front along -y): the array's direction d at position (i, j) is the
    sample lfio's nearest lookup gives in the world direction of d."""
    path = str(tmp_path / "spot.h5")
    ilf("synth", "--kind", "spot", "--spot", "0,1,0:0,-1,0:30:2", "--grid", "4x4", "--n", "4", "--origin", "-0.5,0,-0.5",
        "--u", "1,0,0", "--v", "0,0,1", "-o", path)
    s = ilfkit.open(path)[0]
    np.testing.assert_allclose(s.frame, [[1, 0, 0], [0, 0, 1], [0, -1, 0]], atol=1e-15)
    world = s.directions()
    assert world.shape == (64, 3) and (world[:, 1] < 0).all()  # the front hemisphere faces -y
    lit = np.argwhere(s.radiance.max(axis=3) > 0)
    assert len(lit) > 0 and len(lit) < s.radiance[..., 0].size  # a spot: some samples lit, not all
    for d, j, i in lit[:: max(1, len(lit) // 20)]:
        sample = s.radiance_at((i + 0.5) / 4, (j + 0.5) / 4, world[d], interpolate=False)
        np.testing.assert_array_equal(sample, s.radiance[d, j, i])


# ------------------------------------------------------------------ the partition

def test_partition_lookups():
    p = ilfkit.Partition(8)
    assert (p.count, p.hemisphere_count) == (512, 256)
    ids = np.arange(p.count, dtype=np.uint64)
    np.testing.assert_allclose(p.solid_angle(ids).sum(), 4 * np.pi, rtol=1e-12)
    np.testing.assert_array_equal(p.index(p.direction(ids)), ids)  # a centroid lies in its own solid angle
    assert p.index([0, 0, 1]) < p.hemisphere_count and p.index([0, 0, -1]) >= p.hemisphere_count
    v = p.vertices(5)
    assert v.shape == (3, 3) and np.linalg.det(v) > 0  # counter-clockwise seen from outside
    # the hierarchy: a solid angle of level 4 is the union of four of level 8
    coarse = ilfkit.Partition(4)
    np.testing.assert_allclose(coarse.solid_angle(np.arange(coarse.count)),
                               np.bincount(coarse.index(p.direction(ids)).astype(np.int64), weights=p.solid_angle(ids)), rtol=1e-9)


def test_partition_refusals():
    p = ilfkit.Partition(2)
    with pytest.raises(ValueError, match="direction 1 is zero"):
        p.index([[0, 0, 1], [0, 0, 0]])
    with pytest.raises(ValueError, match="id 32 .* level 2"):
        p.solid_angle([0, 32])
    with pytest.raises(ValueError, match="level 0"):
        ilfkit.Partition(0)


# ------------------------------------------------------------------ relighting

def test_irradiance_closed_form_and_command(scene):
    points = np.array([[0, 0, 0], [0.3, -0.2, 0], [0.9, 0.9, 0], [0.2, 0.1, 0.5]])
    normals = np.tile([0, 0, 1.0], (4, 1))
    e = ilfkit.irradiance(scene, points, normals, threads=2)
    assert e.shape == (4, 3)
    for p, row in zip(points, e):
        expected = np.array(LAMP) * lamp_irradiance(p[0], p[1], 1 - p[2])
        np.testing.assert_allclose(row, expected, rtol=2e-3)
    text = "".join("%r %r %r 0 0 1\n" % tuple(p) for p in points)
    printed = np.loadtxt(ilf("irradiance", scene, "--points", "-", "--quiet", stdin=text).splitlines()).reshape(-1, 3)
    np.testing.assert_allclose(e, printed, rtol=1e-5)
    # one point in, one row out; a normal facing away receives nothing
    np.testing.assert_allclose(ilfkit.irradiance(scene, [0, 0, 0], [0, 0, -1]), [0, 0, 0])


def test_relight_maps_match_the_command(scene, tmp_path):
    sol = ilfkit.relight(scene, partition_n=8, rays=2, bounces=1, threads=2)
    assert len(sol.maps) == 2 and len(sol.passes) == 2
    floor, lamp = sol.maps
    assert floor.label == "polygons[0]" and floor.ncells == 400
    np.testing.assert_allclose(floor.area.sum(), 4.0, rtol=1e-12)
    # radiosity is pi times emission plus albedo times irradiance (the lamp receives the floor's bounce)
    assert lamp.irradiance.min() > 0
    np.testing.assert_allclose(lamp.radiosity, np.pi * np.array(LAMP) + 0.2 * lamp.irradiance, rtol=1e-6)
    np.testing.assert_allclose(floor.radiosity, 0.5 * floor.irradiance, rtol=1e-6)
    # the brightest floor cell is under the lamp's centre, near the closed form there
    centre = floor.centre[np.argmax(floor.irradiance[:, 0])]
    assert abs(centre[0]) < 0.1 and abs(centre[1]) < 0.1
    np.testing.assert_allclose(floor.irradiance.max(axis=0), np.array(LAMP) * lamp_irradiance(0, 0, 1), rtol=0.02)
    # the command, with the same settings, writes the same maps: radiance.h5 read back equals them
    out = tmp_path / "out"
    ilf("relight", scene, "-o", str(out), "--partition-n", "8", "--rays", "2", "--bounces", "1", "--quiet",
        "--threads", "1")
    written = ilfkit.read_radiance(str(out / "radiance.h5"))
    assert len(written.maps) == 2 and written.scene.endswith("lamp.json")
    for a, b in zip(sol.maps, written.maps):
        assert a.label == b.label and (a.nu, a.nv) == (b.nu, b.nv)
        np.testing.assert_array_equal(a.ij, b.ij)
        np.testing.assert_array_equal(a.irradiance, b.irradiance)
        np.testing.assert_array_equal(a.radiosity, b.radiosity)
        np.testing.assert_allclose(a.centre, b.centre)


def test_relight_settings_are_checked(scene):
    with pytest.raises(ValueError, match="partition_n"):
        ilfkit.relight(scene, partition_n=6)
    with pytest.raises(ValueError, match="rays_per_solid_angle"):  # refused before the scene is even opened
        ilfkit.irradiance(scene + ".missing", [0, 0, 0], [0, 0, 1], rays=0)
    with pytest.raises(ValueError, match="'bogus' is not a sampling setting"):
        ilfkit.relight(scene, bogus=1)
    with pytest.raises(ValueError, match="method"):
        ilfkit.relight(scene, method="fastest")
    with pytest.raises(ValueError, match=r"shape \(N, 3\)"):
        ilfkit.irradiance(scene, [[0, 0, 0]], [[0, 0]])


def test_long_work_releases_the_gil(scene):
    """While irradiance() runs in another thread, this thread keeps running: its longest pause is a small part
    of the call (the call would block it throughout if it held the GIL). The points double until the call is
    long enough to tell, however fast the machine."""
    for points in (6000, 12000, 24000, 48000, 96000):
        done, span = [], {}

        def work():
            span["start"] = time.monotonic()
            done.append(ilfkit.irradiance(scene, np.zeros((points, 3)), np.tile([0, 0, 1.0], (points, 1)),
                                          method="naive", partition_n=16, rays=4, threads=1))
            span["end"] = time.monotonic()

        t = threading.Thread(target=work)
        last, longest = time.monotonic(), 0.0
        t.start()
        while t.is_alive():
            now = time.monotonic()
            longest, last = max(longest, now - last), now
        t.join()
        assert done, "irradiance() failed in its thread"
        if span["end"] - span["start"] > 0.2:
            break
    assert span["end"] - span["start"] > 0.2, "the call was too short to tell"
    assert longest < 0.5 * (span["end"] - span["start"])


# ------------------------------------------------------------------ errors

def test_errors_name_the_file(tmp_path, scene):
    missing = str(tmp_path / "nothere.h5")
    with pytest.raises(ilfkit.Error, match="nothere.h5") as e:
        ilfkit.open(missing)
    assert isinstance(e.value, RuntimeError) and e.value.status == "not found"
    text = tmp_path / "text.h5"
    text.write_text("not HDF5\n")
    with pytest.raises(ilfkit.Error, match="text.h5"):
        ilfkit.open(str(text))
    with pytest.raises(ilfkit.Error, match="text.h5"):
        ilfkit.read_radiance(str(text))
    with pytest.raises(ilfkit.Error, match="nothere.json"):
        ilfkit.relight(str(tmp_path / "nothere.json"))
    bad = tmp_path / "bad.json"
    bad.write_text('{"polygons": [{"vertices": [[0, 0, 0], [1, 0, 0]]}]}')
    with pytest.raises(ilfkit.Error, match=r"bad\.json: polygons\[0\]") as e:
        ilfkit.irradiance(str(bad), [0, 0, 0], [0, 0, 1])
    assert e.value.status == "invalid input"
