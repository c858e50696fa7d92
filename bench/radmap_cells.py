"""bench/radmap_cells.py - one cell array of a radiance.h5, either format.

radiance.h5 (docs/format.md, section 6) stores each cell array once for all
patches in format version 2, and one group a patch in format version 1
(files of older builds). `cells(path, name)` gives dataset `name`
("irradiance", "cell_area", ...) of every patch concatenated in patch order,
which is what the format-2 dataset already is, so that the bench scripts
compare runs of old and new builds alike.
"""
import h5py
import numpy as np


def cells(path, name):
    """Dataset `name` of every patch of the radiance.h5 at `path`, concatenated in patch order."""
    with h5py.File(path, "r") as f:
        if f.attrs["format"].decode() != "ilfkit-radiance-maps":
            raise ValueError(path + ": not a radiance-map file")
        version = int(f.attrs["format_version"])
        if version >= 2:
            return f["patches"][name][()]
        groups = [f["patches"][str(k)] for k in range(int(f.attrs["patch_count"]))]
        parts = [g[name][()] for g in groups]
        return np.concatenate(parts) if parts else np.zeros((0,))
