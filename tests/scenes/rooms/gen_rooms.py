#!/usr/bin/env python3
"""gen_rooms.py - one small room written in every mesh format ilfkit reads,
for test_scene's check that every format gives the same light.

The room (scene frame: metres, +z up) is a 2 m cube seen from inside: six
walls of material Wall (albedo 0.5) whose fronts face inward, and a 0.8 m
square lamp (material Lamp, albedo 0) 0.1 m under the ceiling, facing down,
emitting 20 W sr^-1 m^-2. Each format carries the lamp the way its usual
exporter does:

  room.obj, room.mtl    quads, Z-up as stored, Ke 20 20 20
  room.gltf, room.glb   triangles (every quad two triangles, as glTF
                        exporters write them), Y-up as glTF requires,
                        emissiveFactor [1, 1, 1] times
                        KHR_materials_emissive_strength 20, as Blender does
  room_walls.ply, room_lamp.ply, room_walls.stl, room_lamp.stl
                        no materials (neither format has any in assimp's
                        readers): the scene's entries give them
  room.fbx, room.3ds    written by assimp's own exporters (libassimp through
                        ctypes; no other dependency) when the library is
                        found: 3DS Z-up in triangles, FBX (ASCII) Y-up in
                        metres with EmissiveColor 1 times EmissiveFactor 20,
                        as Blender writes them (write_by_assimp() says how)

and room_<format>.json is the scene that reads each. Run from anywhere:
python3 gen_rooms.py writes next to itself.
"""
import base64
import ctypes
import ctypes.util
import json
import os
import re
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
SIZE = 2.0
LAMP = (0.6, 1.4, 1.9)  # lamp square from LAMP[0] to LAMP[1] in x and y, at height LAMP[2]
RADIANCE = 20.0
ALBEDO = 0.5


def quads():
    """The room's quads as (material, [4 corners]) in the scene frame, counter-clockwise seen from the front."""
    s = SIZE
    walls = [
        [(0, 0, 0), (s, 0, 0), (s, s, 0), (0, s, 0)],  # floor, facing +z
        [(0, 0, s), (0, s, s), (s, s, s), (s, 0, s)],  # ceiling, facing -z
        [(0, 0, 0), (0, 0, s), (s, 0, s), (s, 0, 0)],  # y = 0, facing +y
        [(0, s, 0), (s, s, 0), (s, s, s), (0, s, s)],  # y = s, facing -y
        [(0, 0, 0), (0, s, 0), (0, s, s), (0, 0, s)],  # x = 0, facing +x
        [(s, 0, 0), (s, 0, s), (s, s, s), (s, s, 0)],  # x = s, facing -x
    ]
    a, b, h = LAMP
    lamp = [(a, a, h), (a, b, h), (b, b, h), (b, a, h)]  # facing -z
    return [("Wall", w) for w in walls] + [("Lamp", lamp)]


def y_up(p):
    """Scene (+z up) to glTF's frame (+y up, -z forward): (x, y, z) -> (x, z, -y)."""
    return (p[0], p[2], -p[1])


def write(name, data):
    mode = "wb" if isinstance(data, bytes) else "w"
    with open(os.path.join(HERE, name), mode) as f:
        f.write(data)


def write_obj():
    write("room.mtl", "newmtl Wall\nKd {0} {0} {0}\nnewmtl Lamp\nKd 0 0 0\nKe {1} {1} {1}\n".format(ALBEDO, RADIANCE))
    lines, n = ["mtllib room.mtl"], 0
    for mat, q in quads():
        lines += ["v %g %g %g" % p for p in q]
        lines += ["usemtl " + mat, "f %d %d %d %d" % (n + 1, n + 2, n + 3, n + 4)]
        n += 4
    write("room.obj", "\n".join(lines) + "\n")


def gltf_document():
    """@return (the glTF JSON as a dict without buffer uri, the binary buffer)."""
    binary, views, accessors, prims = b"", [], [], []
    for m, mat in enumerate(("Wall", "Lamp")):
        pos, idx = [], []
        for name, q in quads():
            if name != mat:
                continue
            k = len(pos)
            pos += [y_up(p) for p in q]
            idx += [k, k + 1, k + 2, k, k + 2, k + 3]  # the quad as two triangles
        pb = b"".join(struct.pack("<3f", *p) for p in pos)
        ib = b"".join(struct.pack("<H", i) for i in idx)
        ib += b"\0" * (-len(ib) % 4)
        for data, target in ((pb, 34962), (ib, 34963)):
            views.append({"buffer": 0, "byteOffset": len(binary), "byteLength": len(data), "target": target})
            binary += data
        lo = [min(p[c] for p in pos) for c in range(3)]
        hi = [max(p[c] for p in pos) for c in range(3)]
        accessors.append({"bufferView": 2 * m, "componentType": 5126, "count": len(pos), "type": "VEC3",
                          "min": lo, "max": hi})
        accessors.append({"bufferView": 2 * m + 1, "componentType": 5123, "count": len(idx), "type": "SCALAR"})
        prims.append({"attributes": {"POSITION": 2 * m}, "indices": 2 * m + 1, "material": m})
    materials = [
        {"name": "Wall", "pbrMetallicRoughness": {"baseColorFactor": [ALBEDO, ALBEDO, ALBEDO, 1],
                                                  "metallicFactor": 0}},
        {"name": "Lamp", "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0},
         "emissiveFactor": [1, 1, 1], "extensions": {"KHR_materials_emissive_strength":
                                                     {"emissiveStrength": RADIANCE}}},
    ]
    doc = {"asset": {"version": "2.0", "generator": "ilfkit gen_rooms.py"},
           "extensionsUsed": ["KHR_materials_emissive_strength"],
           "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0, "name": "Room"}],
           "meshes": [{"name": "Room", "primitives": prims}], "materials": materials,
           "accessors": accessors, "bufferViews": views, "buffers": [{"byteLength": len(binary)}]}
    return doc, binary


def write_gltf():
    doc, binary = gltf_document()
    doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(binary).decode()
    write("room.gltf", json.dumps(doc, indent=1) + "\n")
    doc, binary = gltf_document()
    text = json.dumps(doc, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    binary += b"\0" * (-len(binary) % 4)
    body = struct.pack("<I4s", len(text), b"JSON") + text + struct.pack("<I4s", len(binary), b"BIN\0") + binary
    write("room.glb", struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body)


def write_ply_stl():
    for part, mats in (("walls", ("Wall",)), ("lamp", ("Lamp",))):
        qs = [q for m, q in quads() if m in mats]
        head = ["ply", "format ascii 1.0", "element vertex %d" % (4 * len(qs)), "property float x",
                "property float y", "property float z", "element face %d" % len(qs),
                "property list uchar int vertex_indices", "end_header"]
        body = ["%g %g %g" % p for q in qs for p in q] + ["4 %d %d %d %d" % tuple(range(4 * k, 4 * k + 4))
                                                        for k in range(len(qs))]
        write("room_%s.ply" % part, "\n".join(head + body) + "\n")
        stl = ["solid " + part]
        for q in qs:
            for t in ((q[0], q[1], q[2]), (q[0], q[2], q[3])):
                stl += [" facet normal 0 0 0", "  outer loop"] + ["   vertex %g %g %g" % p for p in t]
                stl += ["  endloop", " endfacet"]
        write("room_%s.stl" % part, "\n".join(stl + ["endsolid " + part]) + "\n")


def write_by_assimp():
    """room.fbx and room.3ds by libassimp's exporters. @return the formats written.

    room.3ds is room.obj converted (3DS is Z-up, as the scene). room.fbx is
    written the way Blender writes FBX: the geometry turned Y-up (its
    GlobalSettings say UpAxis 1, +Y) in metres (UnitScaleFactor 100: FBX
    counts centimetres per unit; assimp writes 1), and the lamp's colour 1
    with EmissiveFactor 20. assimp's writer puts the emission in the legacy
    Emissive property alone (its reader then reports the template's black
    EmissiveColor), so the lamp's EmissiveColor and EmissiveFactor lines are
    added to its ASCII output."""
    name = ctypes.util.find_library("assimp")
    if not name:
        print("gen_rooms.py: libassimp not found: room.fbx and room.3ds not written")
        return []
    lib = ctypes.CDLL(name)
    lib.aiImportFile.restype = ctypes.c_void_p
    lib.aiImportFile.argtypes = [ctypes.c_char_p, ctypes.c_uint]
    lib.aiExportScene.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_char_p, ctypes.c_uint]
    lib.aiReleaseImport.argtypes = [ctypes.c_void_p]
    written = []

    def convert(source, fmt, target):
        scene = lib.aiImportFile(os.path.join(HERE, source).encode(), 0)
        ok = scene and lib.aiExportScene(scene, fmt, os.path.join(HERE, target).encode(), 0) == 0
        if scene:
            lib.aiReleaseImport(scene)
        return ok

    if convert("room.obj", b"3ds", "room.3ds"):
        written.append("3ds")
    yup = ["mtllib room.mtl"]
    with open(os.path.join(HERE, "room.obj")) as f:
        for line in f.read().splitlines()[1:]:
            if line.startswith("v "):
                line = "v %g %g %g" % y_up(tuple(float(x) for x in line.split()[1:]))
            yup.append(line)
    write("room_yup.obj", "\n".join(yup) + "\n")
    if convert("room_yup.obj", b"fbxa", "room.fbx"):
        with open(os.path.join(HERE, "room.fbx")) as f:
            text = f.read()
        lamp = text.index('Material::Lamp')
        head, body = text[:lamp], text[lamp:]
        legacy = 'P: "Emissive", "Vector3D", "Vector", "", %g, %g, %g' % ((RADIANCE,) * 3)
        assert legacy in body
        body = body.replace(legacy, 'P: "EmissiveColor", "Color", "", "A", 1, 1, 1\n\t\t\t'
                            'P: "EmissiveFactor", "Number", "", "A", %g\n\t\t\t%s' % (RADIANCE, legacy), 1)
        for key in ("UnitScaleFactor", "OriginalUnitScaleFactor"):  # centimetres per unit: metres
            unit = 'P: "%s", "double", "Number", "", ' % key
            assert unit + "1\n" in head
            head = head.replace(unit + "1\n", unit + "100\n", 1)
        stamp = re.compile(r"(CreationTimeStamp:  \{.*?\n\t\})", re.S)  # the writer's clock: fixed, so
        fixed = "Year: 2000\n\t\tMonth: 1\n\t\tDay: 1\n\t\tHour: 0\n\t\tMinute: 0\n\t\tSecond: 0"  # reruns match
        head = stamp.sub(lambda m: re.sub(r"Year: \d+.*Second: \d+", fixed, m.group(1), flags=re.S), head)
        write("room.fbx", head + body)
        written.append("fbx")
    os.remove(os.path.join(HERE, "room_yup.obj"))
    return written


def write_scenes(extra):
    query = {"radiance_maps": {"cell_size": 0.25}, "sampling": {"bounces": 1, "bounce_rays": 64},
             "camera": {"position": [1, 0.15, 1], "look_at": [1, 2, 0.7], "fov_deg": 90, "width": 48, "height": 36}}
    entries = {
        "obj": [{"file": "room.obj"}],
        "gltf": [{"file": "room.gltf"}],
        "glb": [{"file": "room.glb", "up": "y"}],  # the default, written out
        "ply": [{"file": "room_walls.ply", "material": "Wall"}, {"file": "room_lamp.ply", "material": "Lamp"}],
        "stl": [{"file": "room_walls.stl", "material": "Wall"}, {"file": "room_lamp.stl", "material": "Lamp"}],
    }
    for ext in extra:
        entries[ext] = [{"file": "room." + ext}]
    for fmt, meshes in entries.items():
        scene = {}
        if fmt in ("ply", "stl"):
            scene["materials"] = {"Wall": {"albedo": [ALBEDO] * 3},
                                  "Lamp": {"albedo": [0, 0, 0], "emission": [RADIANCE] * 3}}
        scene["meshes"] = meshes
        scene.update(query)
        write("room_%s.json" % fmt, json.dumps(scene) + "\n")


if __name__ == "__main__":
    write_obj()
    write_gltf()
    write_ply_stl()
    write_scenes(write_by_assimp())
