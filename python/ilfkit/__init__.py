"""ilfkit: incident light fields, relighting and radiance maps from Python (docs/python.md).

A thin layer over the C extension ``_ilfkit``, which runs ilfkit's libraries (lfio and relight):

- ``ilfkit.open(path)`` / ``LightField.read(path)``: a light field file; its slabs, each with its
  description and its radiance as a NumPy array of shape ``(4 n^2, nv, nu, 3)`` (direction, then
  position along v, then along u, then r g b).
- ``Partition(n)``: the sphere partition's lookups, direction to id and id to direction and solid angle.
- ``relight(scene, ...)``: relights a scene file and returns its radiance maps as arrays.
- ``irradiance(scene, points, normals, ...)``: the irradiance at points, an ``(N, 3)`` array.
- ``read_radiance(path)``: a radiance-map file (``radiance.h5``, what ``ilf relight`` writes).

Units as in the C libraries: metres, radiance in W sr^-1 m^-2, irradiance and radiosity in W m^-2,
linear Rec.709 RGB. A failure of the libraries raises ``ilfkit.Error`` (a RuntimeError) with their
message, which names the file and the problem. Reading files and relighting release the GIL, so other
Python threads run meanwhile.
"""

import numpy as _np

from . import _ilfkit
from ._ilfkit import Error

__all__ = ["Error", "LightField", "Slab", "Partition", "Map", "Solution", "RadianceMaps", "open", "relight",
           "irradiance", "read_radiance", "lfio_version"]


def lfio_version():
    """@return the version of the lfio library the module runs on, for example "0.2.0"."""
    return _ilfkit.version()


# ------------------------------------------------------------------ the partition

class Partition:
    """The sphere partition of level n (lfio/partition.h): 8 n^2 solid angles over the sphere, ids
    0 .. 4 n^2 - 1 for the hemisphere around +z (a slab stores those, in its own frame).

    Each lookup takes one item or an array of them and answers in the same shape::

        p = Partition(4)
        p.index([0, 0, 1])            # the id of a direction (need not be unit length)
        p.direction(p.index(dirs))    # representative (centroid) directions, unit vectors
        p.solid_angle(range(p.count)).sum()   # 4 pi
    """

    def __init__(self, n):
        n = int(n)
        _ilfkit.part_solid_angle(n, [0])  # checks the level: ValueError for one out of range
        self.n = n

    @property
    def count(self):
        """Solid angles over the whole sphere, 8 n^2."""
        return 8 * self.n * self.n

    @property
    def hemisphere_count(self):
        """Solid angles over the +z hemisphere, 4 n^2: the directions a slab stores."""
        return 4 * self.n * self.n

    def index(self, directions):
        """@return the id (uint64) of each direction: shape (3,) gives a scalar, (N, 3) gives (N,)."""
        d = _np.asarray(directions, dtype=_np.float64)
        ids = _ilfkit.part_id(self.n, d.reshape(-1, 3))
        return ids[0] if d.ndim == 1 else ids

    def _per_id(self, fn, ids):
        a = _np.asarray(ids, dtype=_np.uint64)
        out = fn(self.n, a.reshape(-1))
        return out[0] if a.ndim == 0 else out

    def direction(self, ids):
        """@return the unit centroid direction of each id: a scalar id gives (3,), shape (N,) gives (N, 3)."""
        return self._per_id(_ilfkit.part_centroid, ids)

    def vertices(self, ids):
        """@return the three corner directions of each id, counter-clockwise from outside: (3, 3) or (N, 3, 3)."""
        return self._per_id(_ilfkit.part_vertices, ids)

    def solid_angle(self, ids):
        """@return the exact solid angle of each id in steradians: a float or an (N,) array."""
        return self._per_id(_ilfkit.part_solid_angle, ids)

    def __repr__(self):
        return "Partition(%d)" % self.n


# ------------------------------------------------------------------ light fields

class Slab:
    """One slab of a light field: the rectangle origin + s u + t v (s, t in [0, 1]) with nu x nv
    positions at cell centres, each with radiance for the 4 n^2 directions of its front hemisphere
    (partition level n, in the slab frame e1 = u/|u|, e2 = v/|v|, e3 = e1 x e2).

    Attributes: name, origin, u, v (NumPy (3,) arrays, metres, world frame), nu, nv, n, units
    ("radiance" for W sr^-1 m^-2 or "relative"), mask_threshold, frame (the rows e1, e2, e3),
    partition (Partition(n), whose directions are in the slab frame: to_world() turns them) and
    radiance, a read-only float32 array of shape (4 n^2, nv, nu, 3): radiance[d, j, i] is the r g b of
    direction id d at position (i, j). It is a view of the light field's memory, not a copy.
    """

    def __init__(self, lightfield, k):
        self._lf, self._k = lightfield, k
        desc = lightfield.slab_desc(k)
        self.name = desc["name"]
        self.origin, self.u, self.v = (_np.array(desc[key]) for key in ("origin", "u", "v"))
        self.nu, self.nv, self.n = desc["nu"], desc["nv"], desc["n"]
        self.units, self.mask_threshold = desc["units"], desc["mask_threshold"]
        self.partition = Partition(self.n)
        self.radiance = lightfield.slab_radiance(k)
        e1, e2 = self.u / _np.linalg.norm(self.u), self.v / _np.linalg.norm(self.v)
        self.frame = _np.array([e1, e2, _np.cross(e1, e2)])

    def to_world(self, local):
        """@return slab-frame directions (3,) or (N, 3) in the world frame: x e1 + y e2 + z e3, with
        frame = [e1, e2, e3] as rows (e3 the slab's front)."""
        return _np.asarray(local, dtype=_np.float64) @ self.frame

    def directions(self):
        """@return the world-frame unit directions of the stored ids 0 .. 4 n^2 - 1, shape (4 n^2, 3): row d is
        the centroid direction of radiance[d]."""
        return self.to_world(self.partition.direction(_np.arange(self.partition.hemisphere_count)))

    def position(self, i, j):
        """@return the world centre of position (i, j): origin + (i+0.5)/nu u + (j+0.5)/nv v."""
        return _np.array(self._lf.slab_position(self._k, i, j))

    def irradiance(self, s=0.5, t=0.5):
        """@return the irradiance (W m^-2, r g b) through the slab's front at slab coordinates (s, t)."""
        return _np.array(self._lf.slab_irradiance(self._k, s, t))

    def radiance_at(self, s, t, direction, interpolate=True):
        """@return the radiance (r g b) at slab coordinates (s, t) in world direction `direction`,
        interpolated over positions and directions (or the nearest sample, interpolate=False); 0 for
        a direction behind the slab."""
        return _np.array(self._lf.slab_radiance_at(self._k, s, t, tuple(float(x) for x in direction),
                                                   bool(interpolate)))

    def __repr__(self):
        return "Slab(%r, %dx%d positions, n=%d)" % (self.name, self.nu, self.nv, self.n)


class LightField:
    """A light field file (lfio's HDF5 format, docs/format.md), read whole and checked (checksums,
    values). ``len(lf)`` is its number of slabs; ``lf[k]`` or ``lf["name"]`` is a Slab; ``lf.slabs``
    lists them; ``lf.creator`` names the program that wrote it."""

    def __init__(self, handle):
        self._handle = handle
        self.slabs = [Slab(handle, k) for k in range(handle.slab_count())]
        self.creator = handle.creator()

    @classmethod
    def read(cls, path):
        """Reads the light field file at path. Raises Error (naming the file and the problem) if it
        cannot be read or is not a valid light field file."""
        return cls(_ilfkit.read_lightfield(path))

    def __len__(self):
        return len(self.slabs)

    def __iter__(self):
        return iter(self.slabs)

    def __getitem__(self, key):
        if isinstance(key, str):
            for s in self.slabs:
                if s.name == key:
                    return s
            raise KeyError("no slab named %r" % key)
        return self.slabs[key]

    def __repr__(self):
        return "LightField(%d slabs: %s)" % (len(self.slabs), ", ".join(s.name for s in self.slabs))


def open(path):
    """Reads a light field file: the same as LightField.read(path)."""
    return LightField.read(path)


# ------------------------------------------------------------------ radiance maps

class Map:
    """The radiance map of one receiving polygon: a grid of square cells in the polygon's frame,
    clipped to it; only cells of nonzero clipped area are kept.

    Geometry: label (the polygon's element in the scene file, e.g. "polygons[3]"), polygon (its index),
    vertices (nverts, 3), origin, e1, e2, normal (3,), cell_size, u0, v0 (metres), nu, nv; cell (i, j)
    covers origin + [u0 + i cell_size, u0 + (i+1) cell_size] e1 + [v0 + j cell_size, ...] e2.
    Material: albedo, emission (3,). Cells, one row each: ij (ncells, 2) uint32, area (ncells,) m^2,
    centre (ncells, 3) world centroid, irradiance and radiosity (ncells, 3) float32 W m^-2.
    """

    def __init__(self, fields):
        self.__dict__.update(fields)

    @property
    def ncells(self):
        return len(self.area)

    def mean_irradiance(self):
        """@return the area-weighted mean irradiance (r g b, W m^-2) over the polygon's cells."""
        if self.ncells == 0:
            return _np.zeros(3)
        return (self.irradiance * self.area[:, None]).sum(axis=0) / self.area.sum()

    def __repr__(self):
        return "Map(%r, %d cells of %g m)" % (self.label, self.ncells, self.cell_size)


class Solution:
    """What relight() returns: maps, one Map per receiving polygon, and passes, one dict of
    statistics per pass (the direct pass, then each bounce: wall_seconds, cpu_seconds, samples,
    rays_cast, rays_kept, rays_free)."""

    def __init__(self, result):
        self.maps = [Map(m) for m in result["maps"]]
        self.passes = result["passes"]

    def __repr__(self):
        return "Solution(%d maps, %d passes)" % (len(self.maps), len(self.passes))


class RadianceMaps:
    """A radiance-map file (radiance.h5): maps (a list of Map), creator, scene (the scene file it
    relit, as stored) and format_version."""

    def __init__(self, result):
        self.maps = [Map(m) for m in result["maps"]]
        self.creator, self.scene, self.format_version = result["creator"], result["scene"], result["format_version"]

    def __repr__(self):
        return "RadianceMaps(%d maps, from %r)" % (len(self.maps), self.scene)


def read_radiance(path):
    """Reads a radiance-map file (what `ilf relight` writes as radiance.h5) into a RadianceMaps.
    Raises Error (naming the file and the problem) if it cannot be read or is not valid."""
    return RadianceMaps(_ilfkit.read_radiance(path))


# ------------------------------------------------------------------ relighting

def _settings(given, extra):
    """@return the sampling settings to apply: the named keywords that are not None, then extra."""
    out = {key: value for key, value in given.items() if value is not None}
    out.update(extra)
    return out


def relight(scene, *, method=None, partition_n=None, rays=None, bounces=None, seed=None, threads=0, **settings):
    """Relights the scene file `scene` (docs/scene.md) and returns a Solution.

    Settings replace the scene's own "sampling" values: method ("culled", "naive", "area",
    "solidangle" or "adaptive"), partition_n (a power of two), rays (rays per solid angle, the key
    rays_per_solid_angle), bounces, seed, and any other key of the scene's "sampling" object given by
    its name (samples_per_cell=..., bounce_rays=..., ...). threads: worker threads, 0 for every core;
    the result does not depend on it. Raises Error for a scene that cannot be loaded or run (the
    message names the file and element), ValueError for a setting that is unknown or out of range.
    """
    chosen = _settings({"method": method, "partition_n": partition_n, "rays_per_solid_angle": rays,
                        "bounces": bounces, "seed": seed}, settings)
    return Solution(_ilfkit.relight(scene, chosen, int(threads)))


def irradiance(scene, points, normals, *, method=None, partition_n=None, rays=None, bounces=None, seed=None,
               threads=0, **settings):
    """The irradiance (W m^-2, r g b) at points of the scene file `scene`, as `ilf irradiance`: each point
    is a receiver of zero area facing its normal (which need not be unit length). points and normals
    are arrays of shape (N, 3) (or (3,) for one point); the result has shape (N, 3) (or (3,)). With
    bounces > 0 the light the scene reflects is included. Settings and threads as in relight()."""
    p = _np.asarray(points, dtype=_np.float64)
    n = _np.asarray(normals, dtype=_np.float64)
    if p.shape[-1:] != (3,) or n.shape != p.shape or p.ndim > 2:
        raise ValueError("points and normals must both have shape (N, 3), not %s and %s" % (p.shape, n.shape))
    chosen = _settings({"method": method, "partition_n": partition_n, "rays_per_solid_angle": rays,
                        "bounces": bounces, "seed": seed}, settings)
    rows = _np.hstack([p.reshape(-1, 3), n.reshape(-1, 3)])
    out = _ilfkit.irradiance(scene, rows, chosen, int(threads))
    return out[0] if p.ndim == 1 else out
