#!/usr/bin/env python3
"""gen_hostile.py - writes the hostile inputs too big or too binary to commit.

Usage: gen_hostile.py OUTDIR BASE_H5

OUTDIR receives scene/, mesh/, lf/, manifest/ and image/ folders of broken
inputs that tests/hostile_test.sh runs through `ilf` as
tests/hostile/cases.txt lists them: deeply nested and huge JSON, binary
garbage, truncated and absurd PLY files, directories where files belong,
images claiming absurd sizes, and light field files derived from BASE_H5 (a
small valid file from `ilf synth`): truncated, garbage, and, when h5py can be
imported, edited to carry absurd sizes, wrong types and shapes, NaN and Inf,
duplicated slab names, huge strings and link cycles. The EXR cases are cut
and patched from OUTDIR/image/valid.exr when the driver has written one.
Without h5py (or valid.exr) those files are not written, and the driver skips
their cases with a message. Everything is deterministic (a fixed random seed).
"""
import json
import os
import random
import shutil
import struct
import sys
import zlib

try:
    import h5py
    import numpy as np
except ImportError:  # the driver reports the skipped cases
    h5py = None

RNG = random.Random(20240606)


def write(path, data):
    """Writes bytes or text to path, creating its folder."""
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb") as f:
        f.write(data.encode() if isinstance(data, str) else data)


def garbage(size, allow_nul=True):
    """size random bytes; without NUL bytes unless allow_nul."""
    low = 0 if allow_nul else 1
    return bytes(RNG.randint(low, 255) for _ in range(size))


def folder(path):
    """A directory where a file is expected."""
    os.makedirs(path, exist_ok=True)


# ---------------------------------------------------------------- scenes

def scenes(out):
    d = os.path.join(out, "scene")
    depth = 100000
    write(os.path.join(d, "deep_arrays.json"), "[" * depth + "]" * depth)
    write(os.path.join(d, "deep_in_section.json"), '{"materials": ' + '{"a": ' * depth + "{}" + "}" * depth + "}")
    write(os.path.join(d, "garbage.json"), garbage(4096))
    write(os.path.join(d, "garbage_no_nul.json"), garbage(4096, allow_nul=False))
    write(os.path.join(d, "huge_material_name.json"), '{"materials": {"' + "m" * (10 << 20) + '": {}}}')
    write(os.path.join(d, "huge_key.json"), '{"' + "k" * (1 << 20) + '": 1}')
    write(os.path.join(d, "huge_mesh_path.json"),
          '{"materials": {"g": {}}, "meshes": [{"file": "' + "p/" * 50000 + 'x.obj", "material": "g"}]}')
    write(os.path.join(d, "huge_method.json"), '{"sampling": {"method": "' + "x" * (10 << 20) + '"}}')
    write(os.path.join(d, "huge_number.json"), '{"radiance_maps": {"cell_size": ' + "9" * 100000 + "}}")
    vertices = ", ".join("[%d, 0, 0]" % k for k in range(100000))
    write(os.path.join(d, "many_vertices.json"),
          '{"materials": {"g": {}}, "polygons": [{"material": "g", "vertices": [' + vertices + "]}]}")
    folder(os.path.join(d, "directory.json"))


# ---------------------------------------------------------------- meshes

PLY_BINARY_HEADER = (b"ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\n"
                     b"property float y\nproperty float z\nelement face %d\n"
                     b"property list uchar int vertex_indices\nend_header\n")


def meshes(out):
    d = os.path.join(out, "mesh")
    body = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 1, 1, 0) + bytes([3]) + struct.pack("<3i", 0, 1, 2)
    write(os.path.join(d, "truncated_binary.ply"), PLY_BINARY_HEADER % (3, 1) + body[:-5])
    write(os.path.join(d, "vertices_absurd_binary.ply"), PLY_BINARY_HEADER % (10 ** 9, 10 ** 9) + body)
    write(os.path.join(d, "garbage.ply"), b"ply\n" + garbage(4096))
    # a valid file whose first vertex's x, 0.01, opens the data with byte 0x0a: assimp 5.2 skips it
    opens = struct.pack("<9f", 0.01, 0, 0, 1, 0, 0, 1, 1, 0) + bytes([3]) + struct.pack("<3i", 0, 1, 2)
    assert opens[0] == 0x0a
    write(os.path.join(d, "binary_opens_with_line_end.ply"), PLY_BINARY_HEADER % (3, 1) + opens)
    write(os.path.join(d, "garbage.obj"), garbage(4096))
    write(os.path.join(d, "deep.gltf"), "[" * 100000 + "]" * 100000)
    face = " ".join(str(k + 1) for k in range(100000))
    ring = "".join("v %d %d 0\n" % (k % 300, k // 300) for k in range(100000))
    write(os.path.join(d, "huge_face.obj"), ring + "f " + face + "\n")
    folder(os.path.join(d, "directory.obj"))


def glb(gltf_json, buffer):
    """A binary glTF: header, a JSON chunk and a BIN chunk, each padded to 4 bytes."""
    js = gltf_json.encode()
    js += b" " * (-len(js) % 4)
    bn = buffer + b"\0" * (-len(buffer) % 4)
    body = struct.pack("<I", len(js)) + b"JSON" + js + struct.pack("<I", len(bn)) + b"BIN\0" + bn
    return b"glTF" + struct.pack("<II", 2, 12 + len(body)) + body


GLB_JSON = ('{"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "scene": 0, "nodes": [{"mesh": 0}], '
            '"meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}], '
            '"buffers": [{"byteLength": 44}], "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, '
            '{"buffer": 0, "byteOffset": 36, "byteLength": 6}], "accessors": [{"bufferView": 0, '
            '"componentType": 5126, "count": 3, "type": "VEC3", "max": [1, 1, 0], "min": [0, 0, 0]}, '
            '{"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]}')


def other_formats(out):
    """Broken files of the other formats assimp reads: STL, glTF binary, 3DS, FBX, Collada.
    Its own generator, so that these cases do not move the others' random bytes."""
    rng = random.Random(20240607)
    d = os.path.join(out, "mesh")
    facet = struct.pack("<12fH", 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0)
    write(os.path.join(d, "truncated_binary.stl"), b"x" * 80 + struct.pack("<I", 1) + facet[:16])
    write(os.path.join(d, "count_absurd.stl"), b"x" * 80 + struct.pack("<I", 4000000000) + facet)
    write(os.path.join(d, "garbage.stl"), bytes(rng.randint(1, 255) for _ in range(3000)))
    vertices = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0) + struct.pack("<3H", 0, 1, 2) + b"\0\0"
    whole = glb(GLB_JSON, vertices)
    write(os.path.join(d, "truncated.glb"), whole[:len(whole) // 2])
    write(os.path.join(d, "chunk_absurd.glb"), whole[:12] + struct.pack("<I", 0x7FFFFFFF) + whole[16:])
    write(os.path.join(d, "position_ushort.glb"),
          glb(GLB_JSON.replace('"componentType": 5126', '"componentType": 5123'), vertices))
    # 3DS: a main chunk and an editor chunk claiming a megabyte in a 22-byte file
    write(os.path.join(d, "truncated.3ds"),
          struct.pack("<HI", 0x4D4D, 1000000) + struct.pack("<HI", 0x3D3D, 999990) + b"\0" * 10)
    write(os.path.join(d, "garbage.3ds"), bytes(rng.randint(0, 255) for _ in range(3000)))
    # FBX binary: the header and the start of a node record, then the end of the file
    write(os.path.join(d, "truncated.fbx"),
          b"Kaydara FBX Binary  \x00\x1a\x00" + struct.pack("<I", 7400) + struct.pack("<I", 16))
    write(os.path.join(d, "garbage.fbx"), bytes(rng.randint(1, 255) for _ in range(3000)))
    write(os.path.join(d, "garbage.dae"), bytes(rng.randint(1, 255) for _ in range(3000)))


# ---------------------------------------------------------------- capture manifests and images

def manifests(out):
    d = os.path.join(out, "manifest")
    depth = 100000
    write(os.path.join(d, "deep.json"), '{"plane": ' + "[" * depth + "]" * depth + "}")
    write(os.path.join(d, "garbage.json"), garbage(4096, allow_nul=False))
    write(os.path.join(d, "huge_slab_name.json"),
          '{"plane": {"origin": [0, 0, 1], "u": [1, 0, 0], "v": [0, -1, 0]}, "grid": {"nu": 1, "nv": 1}, '
          '"slab": "' + "s" * (10 << 20) + '", "pattern": "../image/valid.exr"}')
    folder(os.path.join(d, "directory.json"))


def png_chunk(kind, data):
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


def png(width, height, raw):
    """An 8-bit RGB PNG whose header claims width x height, holding the pixel rows raw."""
    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + png_chunk(b"IHDR", header) + png_chunk(b"IDAT", zlib.compress(raw))
            + png_chunk(b"IEND", b""))


def exr_windows(data, xmax, ymax):
    """data, an EXR file, with its data and display windows set to [0, xmax] x [0, ymax]."""
    out, pos = bytearray(data), 8
    while data[pos] != 0:  # header attributes: name, type, size, value
        name_end = data.index(b"\0", pos)
        type_end = data.index(b"\0", name_end + 1)
        size, = struct.unpack("<i", data[type_end + 1:type_end + 5])
        if data[pos:name_end] in (b"dataWindow", b"displayWindow"):
            out[type_end + 5:type_end + 21] = struct.pack("<iiii", 0, 0, xmax, ymax)
        pos = type_end + 5 + size
    return bytes(out)


def images(out):
    d = os.path.join(out, "image")
    small = png(2, 2, b"\0" * 14)
    write(os.path.join(d, "empty.exr"), b"")
    write(os.path.join(d, "text.exr"), "this is not an image\n")
    write(os.path.join(d, "garbage.png"), b"\x89PNG\r\n\x1a\n" + garbage(2000))
    write(os.path.join(d, "garbage.exr"), b"\x76\x2f\x31\x01" + garbage(2000))
    write(os.path.join(d, "truncated.png"), small[:len(small) - 20])
    write(os.path.join(d, "dims_absurd.png"), png(1000000, 1000000, b"\0" * 100))
    write(os.path.join(d, "dims_max.png"), png(2 ** 31 - 1, 2 ** 31 - 1, b"\0" * 100))
    write(os.path.join(d, "dims_absurd.hdr"),
          b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1000000 +X 1000000\n" + b"\x02\x02\x00\x10" * 10)
    folder(os.path.join(d, "directory.exr"))
    valid = os.path.join(d, "valid.exr")
    if os.path.exists(valid):
        data = open(valid, "rb").read()
        write(os.path.join(d, "truncated.exr"), data[:len(data) // 2])
        write(os.path.join(d, "window_absurd.exr"), exr_windows(data, 2 ** 30, 2 ** 30))
        write(os.path.join(d, "window_negative.exr"), exr_windows(data, -5, -5))


# ---------------------------------------------------------------- the samples a capture reads

def repeated_image(out):
    """A valid 16384 x 8192 gray PNG of 130 KB (2^27 samples, zeros compressed 1000:1) named in brackets of 16
    at 33 positions: 528 reads, 2^27 * 528 samples, over capture's 2^36."""
    rows = zlib.compressobj(9)
    row = b"\0" * (1 + 16384)
    data = b"".join(rows.compress(row) for _ in range(8192)) + rows.flush()
    header = struct.pack(">IIBBBBB", 16384, 8192, 8, 0, 0, 0, 0)
    write(os.path.join(out, "image", "compressed_large.png"),
          b"\x89PNG\r\n\x1a\n" + png_chunk(b"IHDR", header) + png_chunk(b"IDAT", data) + png_chunk(b"IEND", b""))
    bracket = [{"file": "../image/compressed_large.png", "exposure": k + 1} for k in range(16)]
    positions = [{"i": i, "j": j, "bracket": bracket} for j in range(3) for i in range(11)]
    write(os.path.join(out, "manifest", "repeated_image.json"), json.dumps(
        {"plane": {"origin": [0, 0, 1], "u": [1, 0, 0], "v": [0, -1, 0]}, "grid": {"nu": 11, "nv": 3},
         "positions": positions}))


# ---------------------------------------------------------------- light fields

def stdlib_lightfields(out, base):
    d = os.path.join(out, "lf")
    data = open(base, "rb").read()
    write(os.path.join(d, "empty.h5"), b"")
    write(os.path.join(d, "garbage.h5"), garbage(len(data)))
    write(os.path.join(d, "text.h5"), "this is a text file, not a light field\n")
    for name, cut in (("truncated_10", len(data) // 10), ("truncated_50", len(data) // 2),
                      ("truncated_90", len(data) * 9 // 10), ("truncated_last", len(data) - 1)):
        write(os.path.join(d, name + ".h5"), data[:cut])
    # HDF5's signature kept, the superblock behind it scrambled.
    write(os.path.join(d, "superblock_garbage.h5"), data[:8] + garbage(56) + data[64:])
    folder(os.path.join(d, "directory.h5"))


def radiance_maps(out, base):
    """Damaged copies of a valid radiance map (radiance.h5 of ilf relight), under rm/: cut, scrambled, and
    with h5py a value and a cell index the reader must refuse."""
    d = os.path.join(out, "rm")
    data = open(base, "rb").read()
    for name, cut in (("truncated_50", len(data) // 2), ("truncated_last", len(data) - 1)):
        write(os.path.join(d, name + ".h5"), data[:cut])
    write(os.path.join(d, "superblock_garbage.h5"), data[:8] + garbage(56) + data[64:])
    if h5py is None:
        return

    def poke(dataset, index, value):
        """Sets one value of patch 0's rows (format 2: each array concatenated over the patches, patch 0 first;
        format 1: patch 0's own group)."""
        def edit(f):
            name = "patches/" + dataset if f.attrs["format_version"] >= 2 else "patches/0/" + dataset
            f[name][index] = value
        return edit
    edited(d, base, "irradiance_nan.h5", poke("irradiance", (0, 0), np.nan))
    edited(d, base, "radiosity_negative.h5", poke("radiosity", (1, 2), -1.0))
    edited(d, base, "cell_outside.h5", poke("cell_ij", (0, 0), 1000000))
    edited(d, base, "vertex_inf.h5", poke("vertices", (0, 0), np.inf))
    with h5py.File(base, "r") as f:
        if f.attrs["format_version"] < 2:
            return

    def cell_offset_start(f):
        """Patch 0's cells said to start at 1: a table the header read checks before it sizes anything by it."""
        f["patches/cell_offset"][0] = 1
    edited(d, base, "cell_offset_start.h5", cell_offset_start)
    # irradiance one cell shorter than cell_offset says: the shape a header read checks without reading it
    edited(d, base, "irradiance_short.h5",
           lambda f: replace_dataset(f["patches"], "irradiance", f["patches/irradiance"][:-1]))


def edited(d, base, name, edit, libver=None):
    """Copies base to d/name and applies edit(h5py.File) to the copy, opened with libver (h5py's default
    when None: objects it creates then take HDF5 1.8's formats, 'v110' gives HDF5 1.10's)."""
    path = os.path.join(d, name)
    shutil.copyfile(base, path)
    with h5py.File(path, "r+", libver=libver) as f:
        edit(f)
    return path


def set_attr(obj, name, value, dtype=None):
    """Replaces attribute name of obj (a group or file) by value, optionally of dtype."""
    if name in obj.attrs:
        del obj.attrs[name]
    if dtype is None:
        obj.attrs[name] = value
    else:
        obj.attrs.create(name, value, dtype=dtype)


def fixed_string(text):
    """text as a fixed-length ASCII HDF5 string, the way lfio writes strings."""
    return np.bytes_(text.encode())


def replace_dataset(group, name, data):
    """Replaces dataset name of group by data, keeping its units and axes attributes."""
    old = group[name]
    attrs = {k: old.attrs[k] for k in old.attrs}
    del group[name]
    new = group.create_dataset(name, data=data, chunks=True, fletcher32=True)
    for k, v in attrs.items():
        new.attrs[k] = v


def poke_radiance(value):
    """An edit that writes value into one radiance sample, through HDF5 (checksums stay valid)."""
    def edit(f):
        f["slabs/0/radiance"][0, 0, 0, 1] = value
    return edit


def h5py_lightfields(out, base):
    d = os.path.join(out, "lf")
    u32, i32 = np.uint32, np.int32
    cases = {
        "positions_2e40.h5": lambda f: (set_attr(f["slabs/0"], "nu", u32(1 << 20)),
                                        set_attr(f["slabs/0"], "nv", u32(1 << 20))),
        "n_2e20.h5": lambda f: set_attr(f["slabs/0"], "n", u32(1 << 20)),
        "slab_count_huge.h5": lambda f: set_attr(f, "slab_count", i32(2 ** 31 - 1)),
        "slab_count_zero.h5": lambda f: set_attr(f, "slab_count", i32(0)),
        "slab_count_negative.h5": lambda f: set_attr(f, "slab_count", i32(-5)),
        "format_version_2.h5": lambda f: set_attr(f, "format_version", i32(2)),
        "format_other.h5": lambda f: set_attr(f, "format", fixed_string("ilfkit-radiance-maps")),
        "nu_float.h5": lambda f: set_attr(f["slabs/0"], "nu", np.float64(4.0)),
        "nu_array.h5": lambda f: set_attr(f["slabs/0"], "nu", np.array([4, 4], dtype=u32)),
        "name_integer.h5": lambda f: set_attr(f["slabs/0"], "name", i32(7)),
        "origin_2.h5": lambda f: set_attr(f["slabs/0"], "origin", np.array([0.0, 0.0])),
        "origin_nan.h5": lambda f: set_attr(f["slabs/0"], "origin", np.array([np.nan, 0.0, 0.0])),
        "u_inf.h5": lambda f: set_attr(f["slabs/0"], "u", np.array([np.inf, 0.0, 0.0])),
        "threshold_nan.h5": lambda f: set_attr(f["slabs/0"], "mask_threshold", np.float32(np.nan)),
        "radiance_nan.h5": poke_radiance(np.nan),
        "radiance_inf.h5": poke_radiance(np.inf),
        "radiance_negative.h5": poke_radiance(-1.0),
        "radiance_float64.h5": lambda f: replace_dataset(f["slabs/0"], "radiance",
                                                         f["slabs/0/radiance"][...].astype(np.float64)),
        "radiance_shape.h5": lambda f: replace_dataset(f["slabs/0"], "radiance",
                                                       f["slabs/0/radiance"][...].reshape(-1, 3)),
        "radiance_missing.h5": lambda f: f["slabs/0"].__delitem__("radiance"),
        "radiance_group.h5": lambda f: (f["slabs/0"].__delitem__("radiance"),
                                        f["slabs/0"].create_group("radiance")),
        "creator_huge.h5": lambda f: set_attr(f, "creator", fixed_string("c" * (1 << 20))),
        "name_huge.h5": lambda f: set_attr(f["slabs/0"], "name", fixed_string("s" * 10000)),
        "frame_huge_vlen.h5": lambda f: set_attr(f["slabs/0"], "frame", "f" * (10 << 20),
                                                 dtype=h5py.string_dtype()),
        "units_huge.h5": lambda f: set_attr(f["slabs/0/radiance"], "units", fixed_string("u" * 100000)),
        "duplicate_slab_names.h5": duplicate_slab,
        "slab_link_loop.h5": lambda f: (f["slabs"].__delitem__("0"),
                                        f["slabs"].__setitem__("0", h5py.SoftLink("/slabs/0"))),
        "slabs_link_root.h5": lambda f: (f.__delitem__("slabs"), f.__setitem__("slabs", h5py.SoftLink("/"))),
        "slab_external_self.h5": lambda f: (f["slabs"].__delitem__("0"),
                                            f["slabs"].__setitem__("0", h5py.ExternalLink(
                                                "slab_external_self.h5", "/slabs/0"))),
        "mask_level_n.h5": lambda f: set_attr(f["slabs/0/mask/level_2"], "n", u32(3)),
    }
    for name, edit in cases.items():
        edited(d, base, name, edit)
    # Only a complete check sees these: stored derived data that lies, a cycle inside a slab.
    edited(d, base, "verify_solid_angle.h5",
           lambda f: f["slabs/0/solid_angle"].__setitem__(0, f["slabs/0/solid_angle"][0] * 2))
    edited(d, base, "verify_mask_cycle.h5",
           lambda f: f["slabs/0/mask"].__setitem__("loop", f["slabs/0"]))


# ---------------------------------------------------------------- crafted HDF5 storage
# What lfio must not trust in an HDF5 file (docs/robustness.md, "HDF5 features"): where a dataset's
# bytes come from, its filters, its chunk index, each chunk's size and filter mask, and a size declared
# with nothing stored behind it. Each edit keeps the radiance dataset's type, shape, units and axes, so
# that only the storage is wrong.

RADIANCE = "slabs/0/radiance"


def swap_radiance(f, make):
    """Replaces the radiance dataset by make(group, name, values), keeping its units and axes."""
    group, old = f["slabs/0"], f[RADIANCE]
    values, attrs = old[...], {k: old.attrs[k] for k in old.attrs}
    del group["radiance"]
    new = make(group, "radiance", values)
    for k, v in attrs.items():
        new.attrs[k] = v


def lowlevel_radiance(f, configure):
    """Replaces radiance by a dataset made with h5py's low-level API, configure(dcpl) setting its
    layout and filters, holding the same values."""
    def make(group, name, values):
        dcpl = h5py.h5p.create(h5py.h5p.DATASET_CREATE)
        configure(dcpl, values.shape)
        space = h5py.h5s.create_simple(values.shape)
        dset = h5py.h5d.create(group.id, name.encode(), h5py.h5t.IEEE_F32LE, space, dcpl=dcpl)
        dset.write(h5py.h5s.ALL, h5py.h5s.ALL, values)
        return group[name]
    swap_radiance(f, make)


def shuffled(values):
    """values (float32) as HDF5's shuffle filter stores them: byte k of every value together."""
    return np.ascontiguousarray(values.astype("<f4")).view(np.uint8).reshape(-1, 4).T.tobytes()


def fletcher32(data):
    """HDF5's Fletcher-32 of data (16-bit big-endian words, an odd last byte as the high half)."""
    if len(data) % 2:
        data = data + b"\0"
    a = b = 0
    for (word,) in struct.iter_unpack(">H", data):
        a = (a + word) % 65535
        b = (b + a) % 65535
    return struct.pack("<I", (b << 16) | a)


def store_chunk(f, data, mask=0):
    """Stores data as radiance's first chunk, with filter mask mask."""
    dset = f[RADIANCE]
    dset.id.write_direct_chunk((0,) * dset.ndim, data, mask)


def skipped_checksum(f):
    """Radiance in four chunks, the first stored with a changed value and a mask saying that its
    Fletcher-32 filter was skipped, so that nothing checks it."""
    swap_radiance(f, lambda g, n, v: g.create_dataset(n, data=v, dtype="<f4", chunks=(4, 3, 4, 3), shuffle=True,
                                                      compression="gzip", fletcher32=True))
    values = f[RADIANCE][0:4, ...]
    values[0, 0, 0, :] = 7.0
    store_chunk(f, zlib.compress(shuffled(values), 4), mask=4)


def resize_slab(f, nu, nv, chunk):
    """Declares nu x nv positions, with a radiance dataset of that shape in chunks of chunk and a
    position dataset to match (the other datasets do not depend on the positions), nothing written:
    no chunk stored behind a slab of 16 * nu * nv * 12 bytes."""
    set_attr(f["slabs/0"], "nu", np.uint32(nu))
    set_attr(f["slabs/0"], "nv", np.uint32(nv))
    swap_radiance(f, lambda g, n, v: g.create_dataset(n, shape=(16, nv, nu, 3), dtype="<f4", chunks=chunk,
                                                      shuffle=True, compression="gzip", fletcher32=True))
    old = f["slabs/0/position"]
    attrs = {k: old.attrs[k] for k in old.attrs}
    del f["slabs/0"]["position"]
    new = f["slabs/0"].create_dataset("position", shape=(nv, nu, 3), dtype="<f8", chunks=(min(nv, 64), min(nu, 64), 3),
                                      fletcher32=True)
    for k, v in attrs.items():
        new.attrs[k] = v


def btree_cycle(path, node_type):
    """Makes the first v1 B-tree node of path of node_type (0: a group's links, 1: a rank-4 dataset's
    chunks) a node of level 1 whose children are itself: HDF5 1.10.8 follows the cycle until its stack
    overflows."""
    data = bytearray(open(path, "rb").read())
    at = data.find(b"TREE")
    while at >= 0 and data[at + 4] != node_type:
        at = data.find(b"TREE", at + 4)
    if at < 0:
        raise RuntimeError("%s: no v1 B-tree node of type %d" % (path, node_type))
    used, = struct.unpack("<H", data[at + 6:at + 8])
    data[at + 5] = 1  # level
    # a key: a heap offset (group), or a chunk's size, filter mask, 4 offsets and the element offset
    key = 8 if node_type == 0 else 8 + 8 * 5
    child = at + 24 + key
    for _ in range(used):
        data[child:child + 8] = struct.pack("<Q", at)
        child += 8 + key
    write(path, bytes(data))


def virtual_unlimited(source):
    """An edit making radiance a virtual dataset with an unlimited mapping onto dataset x of source: HDF5
    opens source as soon as the dataset's extent is asked for."""
    def make(g, n, v):
        shape, maxshape = v.shape, (None,) + v.shape[1:]
        layout = h5py.VirtualLayout(shape=shape, maxshape=maxshape, dtype="<f4")
        src = h5py.VirtualSource(source, "x", shape=shape, maxshape=maxshape)
        layout[0:h5py.h5s.UNLIMITED, ...] = src[0:h5py.h5s.UNLIMITED, ...]
        return g.create_virtual_dataset(n, layout)
    return lambda f: swap_radiance(f, make)


def hostile_storage(out, base):
    d = os.path.join(out, "lf")
    other = os.path.abspath(base)  # a file the user can read, as the source of another file's bytes
    fifo = os.path.abspath(os.path.join(d, "fifo_source.h5"))  # opening it for reading blocks
    if not os.path.exists(fifo):
        os.mkfifo(fifo)
    nbytes = 16 * 3 * 4 * 3 * 4
    cases = {
        # HDF5's Fletcher-32 filter reads 4 bytes before a buffer of fewer
        "chunk_under_checksum.h5": lambda f: store_chunk(f, b"\x01\x02"),
        # a 2 KB stream of 2 MB of zeros, under a right checksum: within the sizes a chunk of 2304 bytes
        # can take, it inflates a thousand times past the chunk
        "chunk_bomb.h5": lambda f: store_chunk(f, (lambda z: z + fletcher32(z))(zlib.compress(b"\0" * (2 << 20), 9))),
        # a chunk that says its checksum was skipped, holding a changed value
        "chunk_mask_skipped.h5": skipped_checksum,
        # one chunk of 12 MiB of zeros, stored in 13 KB
        "chunk_huge.h5": lambda f: (resize_slab(f, 256, 256, (16, 256, 256, 3)),
                                    store_chunk(f, (lambda z: z + fletcher32(z))(
                                        zlib.compress(b"\0" * (16 * 256 * 256 * 12), 9)))),
        "declared_805MB.h5": lambda f: resize_slab(f, 2048, 2048, (16, 16, 16, 3)),
        "declared_51GiB.h5": lambda f: resize_slab(f, 16896, 16896, (16, 16, 16, 3)),
        "radiance_external_file.h5": lambda f: swap_radiance(f, lambda g, n, v: g.create_dataset(
            n, shape=v.shape, dtype="<f4", external=[(other, 0, nbytes)])),
        "radiance_virtual.h5": lambda f: swap_radiance(f, lambda g, n, v: g.create_virtual_dataset(
            n, (lambda lay: (lay.__setitem__(slice(None), h5py.VirtualSource(other, RADIANCE, shape=v.shape)),
                             lay)[1])(h5py.VirtualLayout(shape=v.shape, dtype="<f4")))),
        "radiance_virtual_fifo.h5": virtual_unlimited(fifo),
        "radiance_external_link.h5": lambda f: (f["slabs/0"].__delitem__("radiance"),
                                                f["slabs/0"].__setitem__("radiance",
                                                                         h5py.ExternalLink(other, "/" + RADIANCE))),
        "radiance_soft_link.h5": lambda f: (f.copy(f[RADIANCE], f, name="elsewhere"),
                                            f["slabs/0"].__delitem__("radiance"),
                                            f["slabs/0"].__setitem__("radiance", h5py.SoftLink("/elsewhere"))),
        "radiance_compact.h5": lambda f: lowlevel_radiance(f, lambda dcpl, shape: dcpl.set_layout(h5py.h5d.COMPACT)),
        "radiance_contiguous_empty.h5": lambda f: swap_radiance(f, lambda g, n, v: g.create_dataset(
            n, shape=v.shape, dtype="<f4")),
        "radiance_scaleoffset.h5": lambda f: swap_radiance(f, lambda g, n, v: g.create_dataset(
            n, data=v, dtype="<f4", chunks=v.shape, scaleoffset=3)),
        "radiance_filter_order.h5": lambda f: lowlevel_radiance(
            f, lambda dcpl, shape: (dcpl.set_chunk(shape), dcpl.set_fletcher32(), dcpl.set_deflate(4))),
    }
    for name, edit in cases.items():
        edited(d, base, name, edit, libver="v110")
    # HDF5 1.8's format indexes chunks with a v1 B-tree, and HDF5's original format a group's links too
    # (h5py's default; a file with a 1.10 superblock keeps 1.10's formats): the base copied into a file
    # of 1.8's format, its radiance in four chunks, then a cycle in the chunks' tree; and the base
    # copied into a file of the original format (whose superblock, without a checksum, lfio refuses
    # before HDF5 reads further), with a cycle in its root group's tree.
    for name, node_type, libver in (("chunk_btree_cycle.h5", 1, "v108"), ("group_btree_cycle.h5", 0, "earliest")):
        path = os.path.join(d, name)
        with h5py.File(base, "r") as src, h5py.File(path, "w", libver=libver) as f:
            for k, v in src.attrs.items():
                f.attrs[k] = v
            src.copy(src["slabs"], f)
            swap_radiance(f, lambda g, n, v: g.create_dataset(n, data=v, dtype="<f4", chunks=(4, 3, 4, 3),
                                                              fletcher32=True))
        btree_cycle(path, node_type)


def duplicate_slab(f):
    """A second slab, a copy of the first under the same name."""
    f.copy(f["slabs/0"], f["slabs"], name="1")
    set_attr(f, "slab_count", np.int32(2))


def main():
    if len(sys.argv) not in (3, 4):
        sys.exit("usage: gen_hostile.py OUTDIR BASE_H5 [BASE_RADIANCE_H5]")
    out, base = sys.argv[1], sys.argv[2]
    scenes(out)
    meshes(out)
    manifests(out)
    images(out)
    repeated_image(out)
    other_formats(out)
    stdlib_lightfields(out, base)
    if len(sys.argv) == 4:
        radiance_maps(out, sys.argv[3])
    if h5py is None:
        print("gen_hostile.py: h5py not available: the edited light field files are not written")
    else:
        h5py_lightfields(out, base)
        hostile_storage(out, base)


if __name__ == "__main__":
    main()
