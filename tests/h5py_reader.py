#!/usr/bin/env python3
"""h5py_reader.py - reads ilfkit light field files with h5py and numpy only,
following nothing but docs/format.md, to prove that the documentation is
enough to use the files without lfio.

Usage: python3 h5py_reader.py ILF_BINARY TMPDIR

It writes files with `ILF synth`, then checks every attribute and dataset the
format page lists (type, shape, units, axes, filters), recomputes the derived
data from the page's formulas (partition ids, lattice triangles, centroids,
solid angles, projected solid angles, positions, mask), and compares the
irradiance computed from the file alone with `ILF info --json --irradiance`
and, for a constant field c, with pi * c. It also captures the synthetic
probes of data/capture and reprojects them onto data/capture/proxy.json, and
checks the optional coverage dataset such a file holds (and that files
without one have none). Prints "N passed, M failed" and exits nonzero on
any failure.
"""
import json
import math
import os
import re
import subprocess
import sys

import h5py
import numpy as np

passed = 0
failed = 0


def check(cond, what):
    """Counts one check; prints the failing ones with their description."""
    global passed, failed
    if cond:
        passed += 1
    else:
        failed += 1
        if failed <= 60:
            print("FAILED:", what, flush=True)


def close(a, b, rel=0.0, abs_tol=0.0):
    """True if every element of a and b agrees within max(abs_tol, rel*|b|)."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    return a.shape == b.shape and bool(np.all(np.abs(a - b) <= np.maximum(abs_tol, rel * np.abs(b))))


# ------------------------------------------------------------ format.md, section 1

def partition_id(n, d):
    """Partition ids at level n of slab-frame directions d (..., 3): the formula of section 1."""
    a = np.abs(d)
    s = a.sum(axis=-1)
    X, Z = n * a[..., 0] / s, n * a[..., 2] / s
    xi = np.minimum(np.floor(X), n - 1).astype(np.int64)
    zi = np.minimum(np.floor(Z), n - 1).astype(np.int64)
    o = (d[..., 0] < 0).astype(np.int64) + 2 * (d[..., 1] < 0) + 4 * (d[..., 2] < 0)
    edge = xi + zi > n - 1
    xi = np.where(edge, n - 1 - zi, xi)
    upper = ~edge & ((X - xi) + (Z - zi) > 1) & (xi + zi + 2 <= n)
    return o * n * n + zi * (2 * n - zi) + 2 * xi + upper.astype(np.int64)


def decode_ids(n, ids):
    """Inverts the id formula: (octant, xi, zi, upper) of each id, by listing the cells of one octant."""
    zi, xi, up = [], [], []
    for z in range(n):                 # row z holds 2(n-z)-1 triangles starting at z(2n-z)
        for r in range(2 * (n - z) - 1):
            zi.append(z), xi.append(r // 2), up.append(r % 2)
    local = ids % (n * n)
    return ids // (n * n), np.array(xi)[local], np.array(zi)[local], np.array(up)[local]


def lattice_corners(n, ids):
    """The three signed lattice corners (a, n-a-b, b) of each id's triangle: shape (D, 3, 3)."""
    o, xi, zi, up = decode_ids(n, ids)
    ab = np.where(up[:, None, None] == 0,
                  np.stack([np.stack([xi, zi], -1), np.stack([xi + 1, zi], -1), np.stack([xi, zi + 1], -1)], 1),
                  np.stack([np.stack([xi + 1, zi + 1], -1), np.stack([xi, zi + 1], -1),
                            np.stack([xi + 1, zi], -1)], 1)).astype(np.float64)
    p = np.stack([ab[..., 0], n - ab[..., 0] - ab[..., 1], ab[..., 1]], -1)
    signs = np.stack([np.where(o & 1, -1.0, 1.0), np.where(o & 2, -1.0, 1.0), np.where(o & 4, -1.0, 1.0)], -1)
    return p * signs[:, None, :]


def unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def triangle_solid_angles(corners):
    """Van Oosterom and Strackee for unit corners a, b, c."""
    a, b, c = (unit(corners[:, k]) for k in range(3))
    triple = np.abs(np.einsum("ij,ij->i", a, np.cross(b, c)))
    denom = 1 + np.einsum("ij,ij->i", a, b) + np.einsum("ij,ij->i", b, c) + np.einsum("ij,ij->i", c, a)
    return 2 * np.arctan2(triple, denom)


def triangle_projected(corners):
    """Lambert's formula about +z (the slab normal in the slab frame)."""
    total = np.zeros(len(corners))
    for k in range(3):
        p, q = unit(corners[:, k]), unit(corners[:, (k + 1) % 3])
        cr = np.cross(p, q)
        length = np.linalg.norm(cr, axis=-1)
        angle = np.arctan2(length, np.einsum("ij,ij->i", p, q))
        total += angle * cr[:, 2] / length
    return 0.5 * np.abs(total)


def mask_levels(n):
    levels = [n]
    while levels[-1] % 2 == 0:
        levels.append(levels[-1] // 2)
    return levels[::-1]


# ------------------------------------------------------------------- checks

def text(value):
    """A string attribute as str (fixed-length strings come back as bytes)."""
    return value.decode() if isinstance(value, (bytes, np.bytes_)) else str(value)


def check_attr(obj, name, kind, shape, where):
    """Checks that attribute name exists, of numpy dtype kind ('S', 'i', 'u', 'f') and shape. @return its value."""
    if name not in obj.attrs:
        check(False, f"{where}: missing attribute {name}")
        return None
    value = obj.attrs[name]
    dt = obj.attrs.get_id(name).dtype
    check(dt.kind == kind, f"{where}@{name}: dtype {dt}, expected kind {kind}")
    check(np.shape(value) == shape, f"{where}@{name}: shape {np.shape(value)}, expected {shape}")
    return value


def check_dataset(group, name, dtype, shape, units, axes, where):
    """Checks a dataset's dtype, shape, units, axes and checksum filter. @return the h5py dataset."""
    if name not in group:
        check(False, f"{where}/{name}: missing")
        return None
    ds = group[name]
    check(ds.dtype == np.dtype(dtype), f"{where}/{name}: dtype {ds.dtype}, expected {dtype}")
    check(ds.shape == shape, f"{where}/{name}: shape {ds.shape}, expected {shape}")
    check(text(check_attr(ds, "units", "S", (), f"{where}/{name}")) == units, f"{where}/{name}: units")
    check(text(check_attr(ds, "axes", "S", (), f"{where}/{name}")) == axes, f"{where}/{name}: axes")
    check(ds.chunks is not None and ds.fletcher32, f"{where}/{name}: chunked with fletcher32")
    return ds


def check_slab(g, where, expect):
    """Checks one slab group against format.md; expect holds the synth options. @return facts for the caller."""
    name = text(check_attr(g, "name", "S", (), where))
    origin = check_attr(g, "origin", "f", (3,), where)
    u = check_attr(g, "u", "f", (3,), where)
    v = check_attr(g, "v", "f", (3,), where)
    check(text(check_attr(g, "length_units", "S", (), where)) == "m", f"{where}: length_units")
    nu = int(check_attr(g, "nu", "u", (), where))
    nv = int(check_attr(g, "nv", "u", (), where))
    n = int(check_attr(g, "n", "u", (), where))
    units = text(check_attr(g, "radiance_units", "S", (), where))
    check(text(check_attr(g, "colour_space", "S", (), where)) == "linear Rec.709", f"{where}: colour_space")
    threshold = float(check_attr(g, "mask_threshold", "f", (), where))
    check(g.attrs.get_id("mask_threshold").dtype == np.float32, f"{where}: mask_threshold is float32")
    for k in ("nu", "nv", "n"):
        check(g.attrs.get_id(k).dtype == np.uint32, f"{where}@{k} is uint32")
    frame = text(check_attr(g, "frame", "S", (), where))
    check("e3 = e1 x e2" in frame and "propagation" in frame, f"{where}: frame text: {frame}")

    check(name == expect["name"], f"{where}: name {name}")
    check(close(origin, expect["origin"]) and close(u, expect["u"]) and close(v, expect["v"]), f"{where}: geometry")
    check((nu, nv, n) == (expect["nu"], expect["nv"], expect["n"]), f"{where}: sizes {(nu, nv, n)}")
    check(units == expect["units"], f"{where}: units {units}")
    check(threshold == np.float32(expect["threshold"]), f"{where}: threshold {threshold}")

    D = 4 * n * n
    e1, e2 = u / np.linalg.norm(u), v / np.linalg.norm(v)
    e3 = np.cross(e1, e2)
    frame_m = np.stack([e1, e2, e3])            # rows: world -> slab coordinates

    rad = check_dataset(g, "radiance", np.float32, (D, nv, nu, 3), units, "dir:v:u:rgb", where)
    dirs = check_dataset(g, "direction", np.float64, (D, 3), "1", "dir:xyz", where)
    sa = check_dataset(g, "solid_angle", np.float64, (D,), "sr", "dir", where)
    psa = check_dataset(g, "projected_solid_angle", np.float64, (D,), "sr", "dir", where)
    pos = check_dataset(g, "position", np.float64, (nv, nu, 3), "m", "v:u:xyz", where)
    if rad is not None:
        check(rad.compression == "gzip" and rad.compression_opts == 4 and rad.shuffle,
              f"{where}/radiance: shuffle + deflate 4")
        check(rad.chunks == (min(D, 32), min(nv, 16), min(nu, 16), 3), f"{where}/radiance: chunks {rad.chunks}")
    if None in (rad, dirs, sa, psa, pos):
        return None
    L, W, SA, PSA, P = rad[...], dirs[...], sa[...], psa[...], pos[...]

    check(bool(np.all(np.isfinite(L)) and np.all(L >= 0)), f"{where}: radiance finite and >= 0")
    check(close(np.linalg.norm(W, axis=1), np.ones(D), abs_tol=1e-12), f"{where}: directions are unit")
    check(bool(np.all(W @ e3 >= 0)), f"{where}: directions in the front hemisphere of e3")
    check(close(SA.sum(), 2 * math.pi, rel=1e-9), f"{where}: solid angles sum {SA.sum()}")
    check(close(PSA.sum(), math.pi, rel=1e-9), f"{where}: projected solid angles sum {PSA.sum()}")
    local = W @ frame_m.T
    ids = partition_id(n, local)
    check(bool(np.array_equal(ids, np.arange(D))), f"{where}: partition id of direction[d] is d")

    # The derived data from section 1's triangle formulas.
    corners = lattice_corners(n, np.arange(D))
    check(close(local, unit(corners.sum(axis=1)), abs_tol=1e-12), f"{where}: directions are the centroids")
    check(close(SA, triangle_solid_angles(corners), rel=1e-9), f"{where}: solid angles by Van Oosterom-Strackee")
    check(close(PSA, triangle_projected(corners), rel=1e-9), f"{where}: projected solid angles by Lambert")
    ii, jj = np.meshgrid(np.arange(nu), np.arange(nv))
    want = origin + ((ii + 0.5) / nu)[..., None] * u + ((jj + 0.5) / nv)[..., None] * v
    check(close(P, want, abs_tol=1e-12), f"{where}: positions at cell centres")

    # The mask: which level-n directions carry light, then their ancestors by centroid lookup.
    check("mask" in g and sorted(g["mask"].keys()) == sorted(f"level_{m}" for m in mask_levels(n)),
          f"{where}: mask levels {list(g['mask'].keys()) if 'mask' in g else None}")
    lit = (L.max(axis=3) > threshold).reshape(D, -1).any(axis=1)
    for m in mask_levels(n):
        ds = check_dataset(g["mask"], f"level_{m}", np.uint8, (4 * m * m,), "1", "dir", f"{where}/mask")
        if ds is None:
            continue
        check(int(check_attr(ds, "n", "u", (), f"{where}/mask/level_{m}")) == m, f"{where}/mask/level_{m}@n")
        want_bits = np.zeros(4 * m * m, dtype=np.uint8)
        want_bits[partition_id(m, local[lit])] = 1
        check(bool(np.array_equal(ds[...], want_bits)), f"{where}/mask/level_{m}: bits differ from the radiance")
    cov = None
    if "coverage" in g:
        ds = check_dataset(g, "coverage", np.uint8, (D, nv, nu), "1", "dir:v:u", where)
        if ds is not None:
            check(ds.compression == "gzip" and ds.compression_opts == 4 and ds.shuffle,
                  f"{where}/coverage: shuffle + deflate 4")
            cov = ds[...]
            check(bool(np.all(cov <= 1)), f"{where}/coverage: values are 0 or 1")
    return {"nu": nu, "nv": nv, "L": L, "psa": PSA, "units": units, "coverage": cov}


def irradiance(slab_group, i, j):
    """Section 5: E_c = sum_dir radiance[dir, j, i, c] * projected_solid_angle[dir], reading one position only."""
    L = slab_group["radiance"][:, j, i, :].astype(np.float64)
    return (L * slab_group["projected_solid_angle"][:][:, None]).sum(axis=0)


def run(cmd):
    """Runs a command. @return (exit status, stdout)."""
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if p.returncode != 0:
        print("command failed:", " ".join(cmd), p.stderr.strip(), flush=True)
    return p.returncode, p.stdout


def main():
    if len(sys.argv) != 3:
        print("usage: h5py_reader.py ILF_BINARY TMPDIR", file=sys.stderr)
        return 2
    ilf, tmp = sys.argv[1], sys.argv[2]
    os.makedirs(tmp, exist_ok=True)

    # Each case: synth options and what format.md says the file must then contain.
    cases = [
        dict(file="constant.h5", kind="constant", radiance=(0.5, 1.0, 2.0), name="synth", n=4, nu=5, nv=3,
             origin=(-0.5, -0.5, 0.0), u=(1.0, 0.0, 0.0), v=(0.0, 1.0, 0.0), units="W sr^-1 m^-2", threshold=0.0),
        dict(file="radial.h5", kind="radial", radiance=(1.0, 1.0, 1.0), name="rad.rot", n=3, nu=7, nv=4,
             origin=(0.2, -0.1, 0.3), u=(0.6, 0.8, 0.0), v=(0.0, 0.0, 1.5), units="relative", threshold=0.1),
        dict(file="spot.h5", kind="spot", radiance=(3.0, 2.0, 1.0), name="spot_8", n=8, nu=6, nv=5,
             origin=(0.0, 0.0, 1.0), u=(0.0, 2.0, 0.0), v=(0.0, 0.0, -1.0), units="W sr^-1 m^-2", threshold=0.05,
             extra=["--spot", "1,0.3,1.5:-1,0,0:30:2:0.4"]),
    ]
    for case in cases:
        path = os.path.join(tmp, case["file"])
        cmd = [ilf, "synth", "--kind", case["kind"], "-o", path, "--n", str(case["n"]),
               "--grid", f"{case['nu']}x{case['nv']}", "--name", case["name"],
               "--origin", ",".join(map(repr, case["origin"])), "--u", ",".join(map(repr, case["u"])),
               "--v", ",".join(map(repr, case["v"])), "--radiance", ",".join(map(repr, case["radiance"])),
               "--units", "relative" if case["units"] == "relative" else "radiance", "--mask-threshold", repr(case["threshold"]),
               "--supersample", "2"] + case.get("extra", [])
        status, _ = run(cmd)
        check(status == 0, f"{case['file']}: synth")
        if status != 0:
            continue
        where = case["file"]
        with h5py.File(path, "r") as f:
            check(text(check_attr(f, "format", "S", (), where)) == "ilfkit-lightfield", f"{where}: format")
            check(int(check_attr(f, "format_version", "i", (), where)) == 1, f"{where}: format_version")
            check(f.attrs.get_id("format_version").dtype == np.int32, f"{where}: format_version is int32")
            check(len(text(check_attr(f, "creator", "S", (), where))) > 0, f"{where}: creator")
            count = int(check_attr(f, "slab_count", "i", (), where))
            check(f.attrs.get_id("slab_count").dtype == np.int32, f"{where}: slab_count is int32")
            check(count == 1 and sorted(f["slabs"].keys()) == ["0"], f"{where}: one slab group")
            slab = f["slabs"]["0"]
            check("coverage" not in slab, f"{where}: synth writes no coverage")
            facts = check_slab(slab, f"{where}:/slabs/0", case)
            if facts is None:
                continue
            nu, nv = facts["nu"], facts["nv"]
            for i, j in ((0, 0), (nu // 2, nv // 2), (nu - 1, nv - 1)):
                E = irradiance(slab, i, j)
                full = (facts["L"][:, j, i, :].astype(np.float64) * facts["psa"][:, None]).sum(axis=0)
                check(close(E, full, rel=1e-12), f"{where}: partial read at ({i},{j}) equals the full array")
                status, out = run([ilf, "info", path, "--json", "--irradiance", f"{i},{j}"])
                info = json.loads(out) if status == 0 else {}
                slabs = info.get("slabs", [{}])
                got = slabs[0].get("irradiance") if slabs else None
                check(got is not None and close(E, got, rel=1e-6),
                      f"{where}: irradiance at ({i},{j}): file {E} vs ilf info {got}")
                check(slabs and slabs[0].get("position") == [i, j], f"{where}: info position")
                if case["kind"] == "constant":
                    check(close(E, math.pi * np.array(case["radiance"]), rel=1e-6),
                          f"{where}: constant field irradiance {E} vs pi*c")
    check_reprojected(ilf, tmp)
    print(f"{passed} passed, {failed} failed")
    return 1 if failed else 0


def check_reprojected(ilf, tmp):
    """A file with coverage: the synthetic probes of data/capture reprojected onto its proxy."""
    data = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data", "capture")
    room, lamp = os.path.join(tmp, "room.h5"), os.path.join(tmp, "lamp.h5")
    status, _ = run([ilf, "capture", os.path.join(data, "synthetic", "manifest.json"), "-o", room, "--quiet"])
    check(status == 0, "capture the synthetic probes")
    status, out_reproject = run([ilf, "reproject", room, "--proxy", os.path.join(data, "proxy.json"), "-o", lamp,
                                 "--n", "8"])
    check(status == 0, "reproject onto the proxy")
    if status != 0:
        return
    with open(os.path.join(data, "proxy.json")) as pf:
        rect = json.load(pf)[0]
    expect = dict(name=rect["name"], origin=rect["origin"], u=rect["u"], v=rect["v"], nu=rect["grid"]["nu"],
                  nv=rect["grid"]["nv"], n=8, units="W sr^-1 m^-2", threshold=0.0)
    with h5py.File(lamp, "r") as f:
        facts = check_slab(f["slabs"]["0"], "lamp.h5:/slabs/0", expect)
    if facts is None or facts["coverage"] is None:
        check(False, "lamp.h5: a reprojected slab has a coverage dataset")
        return
    cov, L, psa = facts["coverage"], facts["L"], facts["psa"]
    # ilf reproject stores zero radiance where no ray of a sample meets the capture.
    check(bool(np.all(L[cov == 0] == 0)), "lamp.h5: uncovered samples carry zero radiance")
    check(0 < int(cov.sum()) < cov.size, "lamp.h5: some samples covered, some not")
    # The covered share of the etendue, from the file alone, as `ilf info --json` reports it.
    share = float((cov * psa[:, None, None]).sum() / (psa.sum() * cov.shape[1] * cov.shape[2]))
    status, out = run([ilf, "info", lamp, "--json", "--stats"])
    got = json.loads(out)["slabs"][0].get("coverage", {}) if status == 0 else {}
    check(close(share, got.get("fraction", -1), rel=1e-9) and got.get("covered") == int(cov.sum()),
          f"lamp.h5: covered share {share} vs ilf info {got}")
    # The coverage_fraction attribute: a float64 scalar in [0, 1], the share reproject printed, at most the
    # samples' share (a partly covered sample counts whole there).
    printed = re.search(r"coverage ([0-9.]+)%", out_reproject)
    with h5py.File(lamp, "r") as f:
        attrs = f["slabs"]["0"].attrs
        frac = attrs.get("coverage_fraction")
        check(frac is not None and np.asarray(frac).dtype == np.float64 and np.asarray(frac).shape == (),
              f"lamp.h5:/slabs/0@coverage_fraction: float64 scalar ({frac!r})")
    if frac is not None and printed is not None:
        frac = float(frac)
        check(0 <= frac <= share + 1e-12 and abs(100 * frac - float(printed.group(1))) < 0.005,
              f"lamp.h5: coverage_fraction {frac} vs printed {printed.group(1)}% and samples' share {share}")


if __name__ == "__main__":
    sys.exit(main())
