#!/usr/bin/env python3
"""Writes the example scenes of ilfkit: beams, beams_diffuse, classroom, classroom_lightfield.

The scenes follow docs/scene.md. Everything is computed from the constants
below, so the output is the same on every run (Python 3 standard library
only). Every polygon is built planar, convex and counter-clockwise seen from
the side it faces, and is checked again here (Newell normal, planarity to
1e-7 of its diameter, ten times stricter than the loader, strict convexity,
area) after the coordinates are rounded, before anything is written.

  beams.json          Cornell-type room, 5 m x 5 m x 3 m, floor at z = 0, five
                      diagonal beams, lit by an incident light field hung just
                      below the ceiling, facing down (42 polygons).
  beams_diffuse.json  the same room lit by one diffuse square emitter in the
                      light field's place (43 polygons).
  classroom.json      10 m x 8 m x 3.2 m room, 42 desks and chairs, four
                      diffuse ceiling emitters, direct light only.
  classroom_lightfield.json
                      the same classroom, its four lamps replaced by four
                      incident light fields in their places, facing down (the
                      paper's classroom was lit by four light fields).

In each scene the first five polygons are the floor, the ceiling and three
walls, all facing into the room (the test program relies on it).

beams.json needs beams_lightfield.h5 beside it. It is made by `ilf synth`:

  ilf synth --kind radial --grid 16x16 --n 16 --name light \\
      --origin -1,-1,0 --u 2,0,0 --v 0,2,0 --radiance 20,20,20 --cone 35 \\
      --seed 1 -o data/beams_lightfield.h5

which `--ilf PATH/TO/ilf` runs too. The slab lies in the z = 0 plane facing
+z; the scene's transform turns it over (180 degrees about x) and lifts it to
just below the ceiling, facing down.

classroom_lightfield.json needs classroom_lightfield.h5 beside it, one slab
that its four entries reference with four transforms; `--ilf` writes it too:

  ilf synth --kind radial --grid 16x16 --n 16 --name lamp \
      --origin -0.4,-0.4,0 --u 0.8,0,0 --v 0,0.8,0 --radiance 100,100,100 \
      --cone 35 --seed 1 -o data/classroom_lightfield.h5

  building_NXxNY.json (only with --building NX NY)
                      a building floor of NX x NY classrooms side by side,
                      each closed and lit by its own lamps (10 x 10: 303,500
                      polygons, 100 times the classroom), for docs/cluster.md.

Usage: python3 data/gen_scenes.py [--out DIR] [--ilf PATH] [--building NX NY]
"""

import argparse
import json
import math
import os
import subprocess
import sys

DIGITS = 9  # decimals kept in coordinates: far below the 1e-6 planarity tolerance

# ---------------------------------------------------------------- vectors


def add(a, b):
    return [a[0] + b[0], a[1] + b[1], a[2] + b[2]]


def sub(a, b):
    return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]


def scale(a, s):
    return [a[0] * s, a[1] * s, a[2] * s]


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def norm(a):
    return math.sqrt(dot(a, a))


def unit(a):
    return scale(a, 1.0 / norm(a))


# --------------------------------------------------------------- geometry


def rect(corner, u, v):
    """The rectangle corner + s*u + t*v; its front faces u x v."""
    return [corner, add(corner, u), add(add(corner, u), v), add(corner, v)]


def box(centre, axes, half):
    """The six outward-facing faces of a box with a right-handed frame of unit axes."""
    faces = []
    for k in range(3):
        i, j = (k + 1) % 3, (k + 2) % 3
        for sign in (1, -1):
            # (a_i, a_j) spans a face whose normal a_i x a_j = a_k; swap them for -a_k.
            u_axis, v_axis = (axes[i], axes[j]) if sign > 0 else (axes[j], axes[i])
            hu, hv = (half[i], half[j]) if sign > 0 else (half[j], half[i])
            centre_of_face = add(centre, scale(axes[k], sign * half[k]))
            corner = sub(sub(centre_of_face, scale(u_axis, hu)), scale(v_axis, hv))
            faces.append(rect(corner, scale(u_axis, 2 * hu), scale(v_axis, 2 * hv)))
    return faces


AXES = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]


def aabox(lo, hi):
    """The six outward-facing faces of the axis-aligned box [lo, hi]."""
    centre = scale(add(lo, hi), 0.5)
    return box(centre, AXES, scale(sub(hi, lo), 0.5))


def rounded(vertices):
    out = []
    for v in vertices:
        out.append([round(x, DIGITS) + 0.0 for x in v])  # + 0.0 turns -0.0 into 0.0
    return out


def check_polygon(vertices, where):
    """Asserts what the loader demands: planar, strictly convex, area > 0."""
    n = len(vertices)
    diameter = max(norm(sub(a, b)) for a in vertices for b in vertices)
    newell = [0.0, 0.0, 0.0]
    for k in range(n):
        newell = add(newell, cross(vertices[k], vertices[(k + 1) % n]))
    area = norm(newell) / 2
    assert area > 1e-12 * diameter * diameter, where + ": no area"
    normal = unit(newell)
    centre = scale([sum(v[k] for v in vertices) for k in range(3)], 1.0 / n)
    for v in vertices:
        assert abs(dot(sub(v, centre), normal)) <= 1e-7 * diameter, where + ": not planar"
    for k in range(n):
        a, b, c = vertices[k - 1], vertices[k], vertices[(k + 1) % n]
        turn = dot(cross(sub(b, a), sub(c, b)), normal)
        assert turn > 1e-9 * diameter * diameter, where + ": not strictly convex"
    return normal, centre


class Scene:
    """Collects materials and polygons, checking each polygon as it comes."""

    def __init__(self):
        self.materials = {}
        self.polygons = []

    def material(self, name, albedo=None, emission=None):
        entry = {}
        if albedo is not None:
            entry["albedo"] = list(albedo)
        if emission is not None:
            entry["emission"] = list(emission)
        self.materials[name] = entry

    def add(self, material, vertices, facing=None):
        """Adds a polygon; facing, if given, is a point its front must see."""
        vertices = rounded(vertices)
        where = "polygon %d (%s)" % (len(self.polygons), material)
        normal, centre = check_polygon(vertices, where)
        if facing is not None:
            assert dot(sub(facing, centre), normal) > 0, where + ": faces away"
        self.polygons.append({"material": material, "vertices": vertices})

    def add_all(self, material, faces):
        for f in faces:
            self.add(material, f)


# ------------------------------------------------------------------ JSON


def number(x):
    if isinstance(x, bool):
        return "true" if x else "false"
    if isinstance(x, int) or float(x).is_integer():
        return str(int(x))
    return repr(float(x))


def compact(value):
    """One-line JSON with short numbers."""
    if isinstance(value, dict):
        return "{" + ", ".join(json.dumps(k) + ": " + compact(v) for k, v in value.items()) + "}"
    if isinstance(value, list):
        return "[" + ", ".join(compact(v) for v in value) + "]"
    if isinstance(value, str):
        return json.dumps(value)
    return number(value)


def write_scene(path, sections):
    """Writes the top-level object one key per block, one material or polygon per line."""
    blocks = []
    for key, value in sections.items():
        if key in ("polygons", "lightfields") or (key == "materials" and value):
            if isinstance(value, dict):
                lines = ["    %s: %s" % (json.dumps(k), compact(v)) for k, v in value.items()]
                blocks.append('  "%s": {\n%s\n  }' % (key, ",\n".join(lines)))
            else:
                lines = ["    " + compact(v) for v in value]
                blocks.append('  "%s": [\n%s\n  ]' % (key, ",\n".join(lines)))
        else:
            blocks.append('  "%s": %s' % (key, compact(value)))
    with open(path, "w", encoding="ascii", newline="\n") as f:
        f.write("{\n" + ",\n".join(blocks) + "\n}\n")


# ----------------------------------------------------------------- beams

ROOM = (5.0, 5.0, 3.0)  # x, y, z extent; the camera side is y = 0
LIGHT_Z = 2.9  # height of the emitter (light field slab or diffuse square)
LIGHT_HALF = 1.0  # the emitter is 2 m x 2 m, centred over the room
BEAM_LENGTH = 2.8
BEAM_WIDTH = 0.15
# centre, yaw about the vertical (degrees), tilt above the horizontal (degrees)
BEAMS = [
    ([1.4, 1.8, 1.2], 30.0, 25.0),
    ([3.6, 1.9, 1.5], -40.0, 28.0),
    ([2.3, 3.3, 0.6], 80.0, 10.0),
    ([1.5, 3.8, 1.9], -15.0, -22.0),
    ([3.6, 3.5, 2.0], 55.0, -20.0),
]

LIGHTFIELD_COMMAND = [
    "synth", "--kind", "radial", "--grid", "16x16", "--n", "16", "--name", "light",
    "--origin", "-1,-1,0", "--u", "2,0,0", "--v", "0,2,0", "--radiance", "20,20,20",
    "--cone", "35", "--seed", "1", "-o",
]


def made_by(command, name):
    """The scene's "made_by" for a light field file: the command that writes it, which the loader
    quotes when the file is missing (it is generated, and classroom_lightfield.h5 is not kept)."""
    return "ilf " + " ".join(command) + " data/" + name


def beam_frame(yaw_deg, tilt_deg):
    """A right-handed frame: the beam's axis, a horizontal side, and their cross product."""
    yaw, tilt = math.radians(yaw_deg), math.radians(tilt_deg)
    axis = [math.cos(tilt) * math.cos(yaw), math.cos(tilt) * math.sin(yaw), math.sin(tilt)]
    side = [-math.sin(yaw), math.cos(yaw), 0.0]
    return [axis, side, cross(axis, side)]


def segment_distance(p0, p1, q0, q1, steps=200):
    """Smallest distance between two segments, by dense sampling (ample for a check)."""
    best = float("inf")
    for i in range(steps + 1):
        a = add(p0, scale(sub(p1, p0), i / steps))
        for j in range(steps + 1):
            b = add(q0, scale(sub(q1, q0), j / steps))
            best = min(best, norm(sub(a, b)))
    return best


def beam_segments():
    out = []
    for centre, yaw, tilt in BEAMS:
        axis = beam_frame(yaw, tilt)[0]
        half = scale(axis, BEAM_LENGTH / 2)
        out.append((sub(centre, half), add(centre, half)))
    return out


def check_beams():
    """Beams stay inside the room, below the light, and clear of each other."""
    margin = BEAM_WIDTH * math.sqrt(2) / 2 + 0.02
    segments = beam_segments()
    for k, (a, b) in enumerate(segments):
        for p in (a, b):
            assert margin < p[0] < ROOM[0] - margin and margin < p[1] < ROOM[1] - margin, "beam %d leaves the room" % k
            assert margin < p[2] < LIGHT_Z - 0.1 - margin, "beam %d reaches the floor or the light" % k
    for i in range(len(segments)):
        for j in range(i + 1, len(segments)):
            gap = segment_distance(*segments[i], *segments[j])
            assert gap > BEAM_WIDTH * math.sqrt(2) + 0.05, "beams %d and %d touch (%.3f m)" % (i, j, gap)


def beams_room(scene):
    """Floor, ceiling, back, left and right walls, a front wall with a wide opening, a light housing."""
    X, Y, Z = ROOM
    inside = [X / 2, Y / 2, Z / 2]
    scene.material("white", albedo=[0.7, 0.7, 0.7])
    scene.material("red", albedo=[0.6, 0.1, 0.1])
    scene.material("green", albedo=[0.1, 0.6, 0.1])
    scene.material("beam", albedo=[0.7, 0.7, 0.7])
    scene.add("white", rect([0, 0, 0], [X, 0, 0], [0, Y, 0]), inside)  # floor, faces +z
    scene.add("white", rect([0, 0, Z], [0, Y, 0], [X, 0, 0]), inside)  # ceiling, faces -z
    scene.add("white", rect([0, Y, 0], [X, 0, 0], [0, 0, Z]), inside)  # back wall, faces -y
    scene.add("red", rect([0, 0, 0], [0, Y, 0], [0, 0, Z]), inside)  # left wall, faces +x
    scene.add("green", rect([X, 0, 0], [0, 0, Z], [0, Y, 0]), inside)  # right wall, faces -x
    # front wall (y = 0, facing +y) around an opening 2.6 m wide and 2.2 m high
    left, right, top = 1.2, X - 1.2, 2.2
    scene.add("white", rect([0, 0, 0], [0, 0, Z], [left, 0, 0]), inside)
    scene.add("white", rect([right, 0, 0], [0, 0, Z], [X - right, 0, 0]), inside)
    scene.add("white", rect([left, 0, top], [0, 0, Z - top], [right - left, 0, 0]), inside)
    # a housing around the emitter: four panels from the ceiling to 5 cm below the emitter.
    # Surfaces are one-sided, so each panel has an outer and an inner face, 1 cm apart
    # (coincident faces would leave a ray free to hit either).
    for gap, inward in ((0.02, False), (0.01, True)):
        lo = [X / 2 - LIGHT_HALF - gap, Y / 2 - LIGHT_HALF - gap]
        hi = [X / 2 + LIGHT_HALF + gap, Y / 2 + LIGHT_HALF + gap]
        z0, h = LIGHT_Z - 0.05, Z - (LIGHT_Z - 0.05)
        for outward in (rect([lo[0], lo[1], z0], [hi[0] - lo[0], 0, 0], [0, 0, h]),   # faces -y
                        rect([hi[0], hi[1], z0], [lo[0] - hi[0], 0, 0], [0, 0, h]),   # faces +y
                        rect([hi[0], lo[1], z0], [0, hi[1] - lo[1], 0], [0, 0, h]),   # faces +x
                        rect([lo[0], hi[1], z0], [0, lo[1] - hi[1], 0], [0, 0, h])):  # faces -x
            scene.add("white", list(reversed(outward)) if inward else outward)
    check_beams()
    for centre, yaw, tilt in BEAMS:
        scene.add_all("beam", box(centre, beam_frame(yaw, tilt), [BEAM_LENGTH / 2, BEAM_WIDTH / 2, BEAM_WIDTH / 2]))


def beams_settings():
    return {
        "radiance_maps": {"cell_size": 0.05},
        "sampling": {"method": "culled", "partition_n": 32, "rays_per_solid_angle": 4,
                     "bounces": 2, "seed": 1},
        "camera": {"position": [2.5, -1.5, 1.5], "look_at": [2.5, 2.5, 1.4], "up": [0, 0, 1],
                   "fov_deg": 50, "width": 640, "height": 480},
    }


def beams_scenes():
    """@return (beams.json, beams_diffuse.json) as dicts of sections."""
    lit = Scene()
    beams_room(lit)
    transform = [[1, 0, 0, ROOM[0] / 2], [0, -1, 0, ROOM[1] / 2], [0, 0, -1, LIGHT_Z], [0, 0, 0, 1]]
    beams = {"materials": lit.materials, "polygons": lit.polygons,
             "lightfields": [{"file": "beams_lightfield.h5", "slab": "light", "transform": transform,
                              "made_by": made_by(LIGHTFIELD_COMMAND, "beams_lightfield.h5")}]}
    beams.update(beams_settings())

    diffuse = Scene()
    beams_room(diffuse)
    diffuse.material("lamp", albedo=[0, 0, 0], emission=[10, 10, 10])
    c = [ROOM[0] / 2 - LIGHT_HALF, ROOM[1] / 2 - LIGHT_HALF, LIGHT_Z]
    diffuse.add("lamp", rect(c, [0, 2 * LIGHT_HALF, 0], [2 * LIGHT_HALF, 0, 0]), [2.5, 2.5, 0])  # faces -z
    beams_diffuse = {"materials": diffuse.materials, "polygons": diffuse.polygons}
    beams_diffuse.update(beams_settings())
    return beams, beams_diffuse


# ------------------------------------------------------------- classroom

CLASS = (10.0, 8.0, 3.2)
ROWS, COLUMNS = 7, 6  # desks along x (students face -x, the blackboard) and along y
ROW_X0, ROW_STEP = 2.0, 1.1
COLUMN_Y0, COLUMN_STEP = 0.875, 1.25
LAMPS = [(3.5, 2.5), (3.5, 5.5), (7.0, 2.5), (7.0, 5.5)]
LAMP_SIZE = 0.8
LAMP_DROP = 0.01  # the lamps hang this far below the ceiling

# classroom_lightfield.json: one slab, the size of a lamp, in the z = 0 plane facing +z, centred
# on the origin; each lamp's transform turns it over and moves it to the lamp's place. Its radial
# light leaves each position within 35 degrees of the direction away from a point 0.57 m behind
# the slab's centre (half its diagonal), so about four fifths of the directions carry nothing.
CLASSROOM_LIGHTFIELD = "classroom_lightfield.h5"
CLASSROOM_LIGHTFIELD_COMMAND = [
    "synth", "--kind", "radial", "--grid", "16x16", "--n", "16", "--name", "lamp",
    "--origin", "%g,%g,0" % (-LAMP_SIZE / 2, -LAMP_SIZE / 2), "--u", "%g,0,0" % LAMP_SIZE,
    "--v", "0,%g,0" % LAMP_SIZE, "--radiance", "100,100,100", "--cone", "35", "--seed", "1", "-o",
]


def desk(scene, x, y):
    """A desk centred at (x, y): top, four legs and a footrest bar (36 faces)."""
    w, d, top, thick, leg = 1.0, 0.6, 0.76, 0.04, 0.04
    scene.add_all("desk", aabox([x - d / 2, y - w / 2, top - thick], [x + d / 2, y + w / 2, top]))
    for sx in (-1, 1):
        for sy in (-1, 1):
            cx, cy = x + sx * (d / 2 - 0.03 - leg / 2), y + sy * (w / 2 - 0.03 - leg / 2)
            scene.add_all("metal", aabox([cx - leg / 2, cy - leg / 2, 0], [cx + leg / 2, cy + leg / 2, top - thick]))
    bar_x = x - (d / 2 - 0.03 - leg / 2)  # between the front legs
    inner = w / 2 - 0.03 - leg
    scene.add_all("metal", aabox([bar_x - 0.015, y - inner, 0.10], [bar_x + 0.015, y + inner, 0.13]))


def chair(scene, x, y):
    """A chair centred at (x, y), its back towards +x: seat, back and four legs (36 faces)."""
    s, seat, thick, leg = 0.42, 0.46, 0.03, 0.03
    scene.add_all("chair", aabox([x - s / 2, y - s / 2, seat - thick], [x + s / 2, y + s / 2, seat]))
    scene.add_all("chair", aabox([x + s / 2 - thick, y - s / 2, seat], [x + s / 2, y + s / 2, seat + 0.40]))
    for sx in (-1, 1):
        for sy in (-1, 1):
            cx, cy = x + sx * (s / 2 - leg / 2 - 0.01), y + sy * (s / 2 - leg / 2 - 0.01)
            scene.add_all("metal", aabox([cx - leg / 2, cy - leg / 2, 0], [cx + leg / 2, cy + leg / 2, seat - thick]))


def classroom_scene(lightfield=False):
    """classroom.json, or with lightfield classroom_lightfield.json: the same polygons but the
    four lamps, which become light field slabs in their places."""
    X, Y, Z = CLASS
    inside = [X / 2, Y / 2, Z / 2]
    scene = Scene()
    scene.material("wall", albedo=[0.75, 0.73, 0.68])
    scene.material("floor", albedo=[0.35, 0.25, 0.18])
    scene.material("ceiling", albedo=[0.85, 0.85, 0.85])
    scene.material("board", albedo=[0.08, 0.15, 0.1])
    scene.material("desk", albedo=[0.6, 0.45, 0.3])
    scene.material("chair", albedo=[0.2, 0.3, 0.5])
    scene.material("metal", albedo=[0.5, 0.5, 0.5])
    if not lightfield:
        scene.material("lamp", albedo=[0.8, 0.8, 0.8], emission=[15, 15, 15])
    scene.add("floor", rect([0, 0, 0], [X, 0, 0], [0, Y, 0]), inside)
    scene.add("ceiling", rect([0, 0, Z], [0, Y, 0], [X, 0, 0]), inside)
    scene.add("wall", rect([0, 0, 0], [0, Y, 0], [0, 0, Z]), inside)  # front (blackboard) wall, faces +x
    scene.add("wall", rect([X, 0, 0], [0, 0, Z], [0, Y, 0]), inside)  # back wall, faces -x
    scene.add("wall", rect([0, 0, 0], [0, 0, Z], [X, 0, 0]), inside)  # faces +y
    scene.add("wall", rect([0, Y, 0], [X, 0, 0], [0, 0, Z]), inside)  # faces -y
    scene.add("board", rect([0.01, 1.5, 0.9], [0, Y - 3.0, 0], [0, 0, 1.2]), inside)
    lightfields = []
    for lx, ly in LAMPS:
        if lightfield:
            # 180 degrees about x, then up to the lamp: the slab faces -z
            transform = [[1, 0, 0, lx], [0, -1, 0, ly], [0, 0, -1, round(Z - LAMP_DROP, DIGITS)], [0, 0, 0, 1]]
            lightfields.append({"file": CLASSROOM_LIGHTFIELD, "slab": "lamp", "transform": transform,
                                "made_by": made_by(CLASSROOM_LIGHTFIELD_COMMAND, CLASSROOM_LIGHTFIELD)})
            continue
        c = [lx - LAMP_SIZE / 2, ly - LAMP_SIZE / 2, Z - LAMP_DROP]
        scene.add("lamp", rect(c, [0, LAMP_SIZE, 0], [LAMP_SIZE, 0, 0]), [lx, ly, 0])  # faces -z
    for r in range(ROWS):
        for c in range(COLUMNS):
            x, y = ROW_X0 + r * ROW_STEP, COLUMN_Y0 + c * COLUMN_STEP
            desk(scene, x, y)
            chair(scene, x + 0.55, y)
    out = {"materials": scene.materials, "polygons": scene.polygons}
    if lightfield:
        out["lightfields"] = lightfields
    out.update({
           "radiance_maps": {"cell_size": 0.1},
           "sampling": {"method": "culled", "partition_n": 32, "rays_per_solid_angle": 4,
                        "bounces": 0, "seed": 1},
           "camera": {"position": [9.7, 7.6, 2.6], "look_at": [1.0, 2.0, 0.8], "up": [0, 0, 1],
                      "fov_deg": 60, "width": 800, "height": 600}})
    return out


def building_scene(nx, ny):
    """A building floor: nx x ny classrooms (each closed, its own lamps) 0.2 m apart, for the
    cluster measurements of docs/cluster.md (10 x 10 is 100 times the classroom)."""
    room = classroom_scene()
    X, Y, _ = CLASS
    polygons = []
    for i in range(nx):
        for j in range(ny):
            dx, dy = i * (X + 0.2), j * (Y + 0.2)
            for p in room["polygons"]:
                moved = rounded([[v[0] + dx, v[1] + dy, v[2]] for v in p["vertices"]])
                polygons.append({"material": p["material"], "vertices": moved})
    out = dict(room)
    out["polygons"] = polygons
    out["camera"] = dict(room["camera"])
    return out


# ------------------------------------------------------------------ main


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", default=os.path.dirname(os.path.abspath(__file__)),
                        help="folder to write into (default: this script's folder)")
    parser.add_argument("--ilf", help="path of the ilf command: also write the light field files with it "
                        "(beams_lightfield.h5, classroom_lightfield.h5)")
    parser.add_argument("--building", nargs=2, type=int, metavar=("NX", "NY"),
                        help="write only building_NXxNY.json: a floor of NX x NY classrooms")
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    if args.building:
        nx, ny = args.building
        if nx < 1 or ny < 1:
            parser.error("--building: NX and NY must be at least 1")
        scenes = {"building_%dx%d.json" % (nx, ny): building_scene(nx, ny)}
        args.ilf = None
    else:
        beams, beams_diffuse = beams_scenes()
        scenes = {"beams.json": beams, "beams_diffuse.json": beams_diffuse, "classroom.json": classroom_scene(),
                  "classroom_lightfield.json": classroom_scene(lightfield=True)}
    for name, sections in scenes.items():
        path = os.path.join(args.out, name)
        write_scene(path, sections)
        print("%s: %d polygons" % (path, len(sections["polygons"])))
    if args.ilf:
        for name, command in (("beams_lightfield.h5", LIGHTFIELD_COMMAND),
                              (CLASSROOM_LIGHTFIELD, CLASSROOM_LIGHTFIELD_COMMAND)):
            target = os.path.join(args.out, name)
            subprocess.run([args.ilf] + command + [target], check=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
