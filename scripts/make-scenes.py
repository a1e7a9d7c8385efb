#!/usr/bin/env python3
"""Writes the visibility stress scenes into assets/<name>/ (OBJ + MTL + scene.toml, scene contract v1).

Each scene isolates one way a voxel march goes wrong against exact visibility:
  box-on-floor  a box standing on the floor of a closed room: wall junctions, and the base of the box,
                where conservative cells of two surfaces meet and the march's 2-cell end skip runs out;
  doorway       a closed room split by a zero-thickness wall with an off-centre doorway, the light on the
                far side: thin geometry the grid must neither thicken into a closed door nor leak through;
  clutter       a room with a 5x5 grid of crates, three hanging zero-thickness panels and two lights.
With --suite DIR it writes the generated suite instead: FAMILIES × --per-family scenes (default 5 each,
50 in all) of the kinds a VPL method meets in the wild, each room randomized from --seed and then scaled
by a factor from millimetres to kilometres and, for every other scene, moved far from the origin:
  boxes           a closed room with 2-10 random boxes on the floor;
  furniture       tables (a top on four thin legs), shelves and hanging zero-thickness panels;
  thin-walls      a room split by one or two zero-thickness walls with doorways, the light in any part;
  light-wall      the light a few centimetres from a wall;
  light-corner    the light a few centimetres from a corner;
  light-occluded  the light above a wide table or behind a panel that hides it from most of the room;
  other-room      two rooms joined by a doorway, the light in the one the camera is not in;
  multi-light     two to four lights of different colours and powers;
  textured        checkered walls and floor (map_Kd PNGs) with boxes;
  dark-room       two rooms joined by a doorway, the camera in the unlit one looking away from the door or
                  along the shared wall: most of what the pixels see lies beyond a wall (the team's two
                  rooms' kind of view, where nearly all of the unshadowed transport is blocked).
Each suite scene also gets light-path.toml, a loop of keyframes for `bench --animate` that moves every
light and keeps it where its family put it: along its wall, along its corner's edge, under its table or
behind its panel, in its part of the room or the far room (an orbit about its start, the bench's default
motion, takes a light by a wall through the wall, and the rest of the run is dark).
The suite is generated, not committed; `bounce suite DIR` runs it. The same seed writes the same files.
Standard library only; the output is deterministic (rerun it and `git diff` shows nothing).
Usage: python3 scripts/make-scenes.py [assets-dir]
       python3 scripts/make-scenes.py --suite DIR [--per-family N] [--seed S] [--size PIXELS]
"""
import math
import os
import random
import struct
import sys
import zlib


class Mesh:
    def __init__(self):
        self.lines = []
        self.nv = 0
        self.mat = None

    def use(self, mat):
        if mat != self.mat:
            self.lines.append(f"usemtl {mat}")
            self.mat = mat

    def quad(self, a, b, c, d):
        """One quad, its normal by the right-hand rule a -> b -> c (faces are fan-triangulated)."""
        for p in (a, b, c, d):
            self.lines.append("v " + " ".join(fmt(x) for x in p))
        n = self.nv
        self.lines.append(f"f {n + 1} {n + 2} {n + 3} {n + 4}")
        self.nv += 4

    def room(self, lo, hi, mat):
        """A closed box seen from inside (normals point inwards)."""
        self.use(mat)
        box_faces(self, lo, hi, inward=True)

    def box(self, lo, hi, mat):
        """A closed box seen from outside."""
        self.use(mat)
        box_faces(self, lo, hi, inward=False)


def fmt(x):
    s = f"{x:.4f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def box_faces(m, lo, hi, inward):
    x0, y0, z0 = lo
    x1, y1, z1 = hi
    faces = [
        # outward winding: -y, +y, -x, +x, -z, +z
        ((x0, y0, z0), (x1, y0, z0), (x1, y0, z1), (x0, y0, z1)),
        ((x0, y1, z0), (x0, y1, z1), (x1, y1, z1), (x1, y1, z0)),
        ((x0, y0, z0), (x0, y0, z1), (x0, y1, z1), (x0, y1, z0)),
        ((x1, y0, z0), (x1, y1, z0), (x1, y1, z1), (x1, y0, z1)),
        ((x0, y0, z0), (x0, y1, z0), (x1, y1, z0), (x1, y0, z0)),
        ((x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)),
    ]
    for f in faces:
        m.quad(*(reversed(f) if inward else f))


MATERIALS = {
    "white": (0.75, 0.75, 0.75),
    "red": (0.7, 0.15, 0.12),
    "green": (0.15, 0.6, 0.2),
    "wood": (0.6, 0.45, 0.3),
    "panel": (0.3, 0.4, 0.7),
}


def toml_vec(v):
    return "[" + ", ".join(f"{x:.2f}" for x in v) + "]"


def write(root, name, title, mesh, camera, lights):
    d = os.path.join(root, name)
    os.makedirs(d, exist_ok=True)
    used = sorted({l.split()[1] for l in mesh.lines if l.startswith("usemtl")})
    with open(os.path.join(d, f"{name}.mtl"), "w") as f:
        f.write("# Generated by scripts/make-scenes.py (public domain).\n")
        for m in used:
            f.write(f"newmtl {m}\nKd {' '.join(f'{c:.2f}' for c in MATERIALS[m])}\n")
    with open(os.path.join(d, f"{name}.obj"), "w") as f:
        f.write(f"# {title} Generated by scripts/make-scenes.py (public domain).\nmtllib {name}.mtl\n")
        f.write("\n".join(mesh.lines) + "\n")
    eye, target, fov = camera
    s = [f"# {title}", "# Generated by scripts/make-scenes.py: edit the script, not this file.", f'mesh = "{name}.obj"', ""]
    s += ["[camera]", f"eye    = {toml_vec(eye)}", f"target = {toml_vec(target)}", "up     = [0.00, 1.00, 0.00]"]
    s += [f"fov_y  = {fov:.1f}", ""]
    for pos, w in lights:
        s += ["[[light]]", f"position  = {toml_vec(pos)}", f"intensity = {toml_vec((w, w, w))}", ""]
    s += ["[render]", "width  = 128", "height = 128"]
    with open(os.path.join(d, "scene.toml"), "w") as f:
        f.write("\n".join(s) + "\n")


def box_on_floor(root):
    m = Mesh()
    m.room((-2, 0, -2), (2, 2.5, 2), "white")
    m.use("red")
    # A coloured skin 1 mm in front of the left wall. (It was in the wall's plane: two coincident faces
    # of different albedo, which each renderer resolves its own way; the Mitsuba comparison saw 4.5 %.)
    m.quad((-1.999, 0, -2), (-1.999, 2.5, -2), (-1.999, 2.5, 2), (-1.999, 0, 2))
    m.box((-0.6, 0, -0.8), (0.4, 1.0, 0.2), "green")
    m.box((0.7, 0, 0.3), (1.3, 0.6, 0.9), "white")
    write(root, "box-on-floor", "Two boxes standing on the floor of a closed room: wall junctions and box bases.",
          m, ((0.0, 1.4, 1.9), (0.0, 0.5, -1.0), 60.0), [((0.3, 2.2, 0.6), 4.0)])


def doorway(root):
    m = Mesh()
    m.room((-3, 0, -1.5), (3, 2.5, 1.5), "white")
    # The dividing wall at x = 0: zero thickness, a doorway z in [0.3, 1.0], y in [0, 2.0].
    m.use("red")
    for a, b in (((-1.5, 0), (0.3, 2.5)), ((1.0, 0), (1.5, 2.5)), ((0.3, 2.0), (1.0, 2.5))):
        (z0, y0), (z1, y1) = a, b
        m.quad((0, y0, z0), (0, y1, z0), (0, y1, z1), (0, y0, z1))
    write(root, "doorway", "A closed room split by a zero-thickness wall with a doorway; the light is on the far side.",
          m, ((-2.8, 1.3, -1.3), (0.0, 0.9, 0.6), 70.0), [((1.8, 1.6, -0.6), 6.0)])


def clutter(root):
    m = Mesh()
    m.room((-3, 0, -3), (3, 3, 3), "white")
    for i in range(5):
        for k in range(5):
            x, z = -2.2 + 1.1 * i, -2.2 + 1.1 * k
            h = 0.3 + 0.1 * ((i * 3 + k * 7) % 5)
            m.box((x - 0.25, 0, z - 0.25), (x + 0.25, h, z + 0.25), "wood")
    m.use("panel")
    # Hanging zero-thickness panels at different heights and orientations.
    m.quad((-1.5, 1.2, -0.5), (-1.5, 2.2, -0.5), (-0.3, 2.2, -0.5), (-0.3, 1.2, -0.5))
    m.quad((0.8, 1.0, -1.6), (0.8, 2.0, -1.6), (0.8, 2.0, -0.2), (0.8, 1.0, -0.2))
    m.quad((0.2, 1.6, 0.6), (1.6, 1.6, 0.6), (1.6, 1.6, 1.8), (0.2, 1.6, 1.8))
    write(root, "clutter", "A room with a 5x5 grid of crates, three hanging zero-thickness panels and two lights.",
          m, ((-2.6, 2.4, 2.7), (0.3, 0.4, -0.8), 65.0), [((-1.0, 2.6, 1.5), 5.0), ((1.8, 2.4, -1.9), 4.0)])



# ---- The generated suite --------------------------------------------------------------------------------

# New families go at the end: the scenes before them keep their random numbers, so their figures stand.
FAMILIES = ["boxes", "furniture", "thin-walls", "light-wall", "light-corner", "light-occluded", "other-room",
            "multi-light", "textured", "dark-room"]
SCALES = [0.001, 0.01, 1.0, 100.0, 1000.0]
SUITE_MATERIALS = {
    "wall": (0.75, 0.75, 0.72), "floor": (0.55, 0.5, 0.45), "red": (0.7, 0.15, 0.12), "green": (0.15, 0.6, 0.2),
    "blue": (0.2, 0.3, 0.7), "wood": (0.6, 0.45, 0.3), "dark": (0.1, 0.1, 0.1), "white": (0.85, 0.85, 0.85),
    "checker_floor": (1.0, 1.0, 1.0), "checker_wall": (1.0, 1.0, 1.0),
}


class SuiteMesh(Mesh):
    """A mesh whose coordinates are scaled and moved on output (`place`), with UVs on every quad."""

    def __init__(self, scale, offset):
        super().__init__()
        self.scale, self.offset = scale, offset

    def place(self, p):
        return tuple(self.offset[k] + self.scale * p[k] for k in range(3))

    def quad(self, a, b, c, d):
        for p in (a, b, c, d):
            self.lines.append("v " + " ".join(f"{x:.9g}" for x in self.place(p)))
        # UVs from the quad's own side lengths: one checker period a unit (room units, before scaling).
        du = max(1e-6, ((b[0] - a[0]) ** 2 + (b[1] - a[1]) ** 2 + (b[2] - a[2]) ** 2) ** 0.5)
        dv = max(1e-6, ((d[0] - a[0]) ** 2 + (d[1] - a[1]) ** 2 + (d[2] - a[2]) ** 2) ** 0.5)
        for uv in ((0, 0), (du, 0), (du, dv), (0, dv)):
            self.lines.append(f"vt {uv[0]:.4f} {uv[1]:.4f}")
        n = self.nv
        self.lines.append(f"f {n + 1}/{n + 1} {n + 2}/{n + 2} {n + 3}/{n + 3} {n + 4}/{n + 4}")
        self.nv += 4


def png_checker(path, a, b, n=8, cell=4):
    """An n × n checker of RGB colours a and b, cell × cell pixels a square (PNG, stdlib only)."""
    size = n * cell
    raw = b""
    for y in range(size):
        row = bytearray([0])
        for x in range(size):
            c = a if ((x // cell) + (y // cell)) % 2 == 0 else b
            row += bytes(c)
        raw += bytes(row)
    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)
    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", size, size, 8, 2, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(png)


def room_walls(m, lo, hi, floor="floor", wall="wall", ceiling="wall"):
    """A closed room seen from inside, its floor, walls and ceiling in their own materials."""
    x0, y0, z0 = lo
    x1, y1, z1 = hi
    m.use(floor)
    m.quad((x0, y0, z1), (x1, y0, z1), (x1, y0, z0), (x0, y0, z0))
    m.use(ceiling)
    m.quad((x0, y1, z0), (x1, y1, z0), (x1, y1, z1), (x0, y1, z1))
    m.use(wall)
    m.quad((x0, y0, z0), (x0, y1, z0), (x0, y1, z1), (x0, y0, z1))
    m.quad((x1, y0, z1), (x1, y1, z1), (x1, y1, z0), (x1, y0, z0))
    m.quad((x1, y0, z0), (x1, y1, z0), (x0, y1, z0), (x0, y0, z0))
    m.quad((x0, y0, z1), (x0, y1, z1), (x1, y1, z1), (x1, y0, z1))


def inside(p, lo, hi, margin=0.0):
    return all(lo[k] - margin <= p[k] <= hi[k] + margin for k in range(3))


def random_boxes(rng, m, lo, hi, count, keep_out, mats=("red", "green", "blue", "wood", "white")):
    """Up to `count` boxes on the floor of the room [lo, hi], none within 0.3 of a point of keep_out."""
    placed = []
    for _ in range(count * 8):
        if len(placed) == count:
            break
        w, d = rng.uniform(0.3, 1.2), rng.uniform(0.3, 1.2)
        h = rng.uniform(0.2, 0.6) * (hi[1] - lo[1])
        x = rng.uniform(lo[0] + 0.1, hi[0] - 0.1 - w)
        z = rng.uniform(lo[2] + 0.1, hi[2] - 0.1 - d)
        b0, b1 = (x, lo[1], z), (x + w, lo[1] + h, z + d)
        if any(inside(p, b0, b1, 0.3) for p in keep_out):
            continue
        if any(not (b1[0] < q0[0] or q1[0] < b0[0] or b1[2] < q0[2] or q1[2] < b0[2]) for q0, q1 in placed):
            continue
        m.box(b0, b1, rng.choice(mats))
        placed.append((b0, b1))
    return placed


def wall_with_door(m, z, door, w, h, mat):
    """A zero-thickness wall across the room at z (x in [0, w], y in [0, h]) with a 0.9 × 2.0 doorway at x = door."""
    m.use(mat)
    for (x0, y0), (x1, y1) in (((0, 0), (door, h)), ((door + 0.9, 0), (w, h)), ((door, 2.0), (door + 0.9, h))):
        if x1 > x0 + 1e-3 and y1 > y0 + 1e-3:
            m.quad((x0, y0, z), (x1, y0, z), (x1, y1, z), (x0, y1, z))


def table(m, x, z, w, d, h, mat="wood", leg=0.05):
    m.box((x, h - 0.05, z), (x + w, h, z + d), mat)
    for lx, lz in ((x, z), (x + w - leg, z), (x, z + d - leg), (x + w - leg, z + d - leg)):
        m.box((lx, 0, lz), (lx + leg, h - 0.05, lz + leg), mat)


def suite_scene(rng, family, scale, offset):
    """(mesh, camera, lights, motions) of one suite scene in room units (the mesh places it); a motion per
    light, (steps, lo, hi): how its path moves it (see light_keys) and the box it stays in."""
    m = SuiteMesh(scale, offset)
    W, H, D = rng.uniform(3, 8), rng.uniform(2.4, 4), rng.uniform(3, 8)
    lo, hi = (0.0, 0.0, 0.0), (W, H, D)
    eye = (rng.uniform(0.3, 0.7) * W, rng.uniform(1.0, 1.7), 0.25 * D * rng.uniform(0.4, 1.0))
    target = (rng.uniform(0.3, 0.7) * W, rng.uniform(0.3, 1.2), 0.85 * D)
    fov = rng.uniform(50, 75)
    light = (rng.uniform(0.2, 0.8) * W, H * rng.uniform(0.6, 0.9), rng.uniform(0.3, 0.8) * D)
    power = rng.uniform(4, 10)
    lights = [(light, (power, power, power))]
    walls = ("floor", "wall", "wall")
    # Every light circles its start horizontally (radius a tenth of the room's diagonal) inside its room.
    r = 0.1 * math.sqrt(W * W + H * H + D * D)
    circle = ((r, 0, 0), (0, 0, r))
    margin = 0.1
    room = ((margin, margin, margin), (W - margin, H - margin, D - margin))
    motions = None
    if family == "boxes":
        room_walls(m, lo, hi, *walls)
        random_boxes(rng, m, lo, hi, rng.randint(2, 10), [eye, light, target])
    elif family == "furniture":
        room_walls(m, lo, hi, *walls)
        for _ in range(rng.randint(1, 3)):
            w, d = rng.uniform(0.8, 1.6), rng.uniform(0.6, 1.0)
            x, z = rng.uniform(0.2, W - w - 0.2), rng.uniform(0.35 * D, D - d - 0.2)
            table(m, x, z, w, d, rng.uniform(0.7, 0.9))
        # A shelf against the back wall: two sides and three boards.
        x = rng.uniform(0.2, W - 1.4)
        for px in (x, x + 1.2):
            m.box((px, 0, D - 0.4), (px + 0.03, 1.8, D - 0.05), "wood")
        for y in (0.4, 1.0, 1.6):
            m.box((x, y, D - 0.4), (x + 1.23, y + 0.03, D - 0.05), "wood")
        m.use("blue")
        for _ in range(rng.randint(1, 3)):
            px, pz, py = rng.uniform(0.5, W - 1.5), rng.uniform(0.4 * D, 0.9 * D), rng.uniform(1.2, H - 0.3)
            m.quad((px, py, pz), (px + 1.0, py, pz), (px + 1.0, py - 0.8, pz), (px, py - 0.8, pz))
    elif family == "thin-walls":
        room_walls(m, lo, hi, *walls)
        zs = [D * (0.45 + 0.25 * i) for i in range(rng.randint(1, 2))]
        for z in zs:
            wall_with_door(m, z, rng.uniform(0.1, 0.7) * W, W, H, "red")
        p = (rng.uniform(0.2, 0.8) * W, H * 0.8, rng.uniform(0.1, 0.95) * D)
        lights = [(p, (power, power, power))]
        # In the light's part of the room, between the walls either side of it.
        z0, z1 = max([0.0] + [z for z in zs if z < p[2]]), min([D] + [z for z in zs if z > p[2]])
        motions = [(circle, (margin, margin, z0 + margin), (W - margin, H - margin, z1 - margin))]
    elif family == "light-wall":
        room_walls(m, lo, hi, *walls)
        gap = rng.uniform(0.01, 0.04)
        side = rng.randrange(3)
        p = list(light)
        if side == 0:
            p[0] = gap
        elif side == 1:
            p[2] = D - gap
        else:
            p[1] = H - gap
        lights = [(tuple(p), (power, power, power))]
        # Along the wall, at the same gap: a circle in the wall's plane.
        plane = [(r, 0, 0), (0, r, 0), (0, 0, r)]
        del plane[(0, 2, 1)[side]]
        motions = [(tuple(plane), room[0], room[1])]
        random_boxes(rng, m, lo, hi, rng.randint(1, 4), [eye, p, target])
    elif family == "light-corner":
        room_walls(m, lo, hi, *walls)
        g = rng.uniform(0.02, 0.06)
        p = (g if rng.random() < 0.5 else W - g, H - g if rng.random() < 0.7 else g, D - g)
        lights = [(p, (power, power, power))]
        # Along the corner's horizontal edge, at the same gaps from the other two walls.
        motions = [(((r if p[0] < W / 2 else -r, 0, 0), "out"), room[0], room[1])]
        random_boxes(rng, m, lo, hi, rng.randint(1, 4), [eye, p, target])
    elif family == "light-occluded":
        room_walls(m, lo, hi, *walls)
        lx, lz = light[0], light[2]
        if rng.random() < 0.5:
            # Under a wide table: the light shines down on the floor beneath it only, and up at the top.
            table(m, lx - 1.0, lz - 0.8, 2.0, 1.6, 1.0)
            lights = [((lx, 0.6, lz), (power, power, power))]
            # Under the table's top, whatever the circle.
            motions = [(circle, (lx - 0.8, 0.6, lz - 0.6), (lx + 0.8, 0.6, lz + 0.6))]
        else:
            # Behind a tall panel, facing the back wall.
            m.use("wall")
            m.quad((lx - 1.2, 0.2, lz - 0.3), (lx + 1.2, 0.2, lz - 0.3), (lx + 1.2, H - 0.2, lz - 0.3),
                   (lx - 1.2, H - 0.2, lz - 0.3))
            lights = [((lx, H * 0.6, min(lz + 0.2, D - 0.1)), (power, power, power))]
            # Behind the panel: a circle in its plane, inside its outline.
            motions = [(((r, 0, 0), (0, r, 0)), (lx - 1.0, 0.4, 0), (lx + 1.0, H - 0.4, D))]
        eye = (eye[0], eye[1], min(eye[2], max(0.2, lz - 1.2)))
    elif family == "other-room":
        # Two rooms along z joined by a doorway in the shared zero-thickness wall.
        D2 = rng.uniform(3, 6)
        room_walls(m, lo, (W, H, D + D2), *walls)
        door = rng.uniform(0.1, 0.7) * W
        wall_with_door(m, D, door, W, H, "wall")
        p = (rng.uniform(0.2, 0.8) * W, H * rng.uniform(0.5, 0.85), D + rng.uniform(0.3, 0.8) * D2)
        lights = [(p, (power, power, power))]
        target = (door + 0.45, 1.0, D)
        # In the far room.
        motions = [(circle, (margin, margin, D + margin), (W - margin, H - margin, D + D2 - margin))]
    elif family == "multi-light":
        room_walls(m, lo, hi, *walls)
        lights = []
        for _ in range(rng.randint(2, 4)):
            c = [rng.uniform(0.2, 1.0) for _ in range(3)]
            w = rng.uniform(2, 10)
            p = (rng.uniform(0.15, 0.85) * W, H * rng.uniform(0.4, 0.9), rng.uniform(0.3, 0.9) * D)
            lights.append((p, tuple(w * x for x in c)))
        random_boxes(rng, m, lo, hi, rng.randint(2, 6), [eye, target] + [p for p, _ in lights])
    elif family == "textured":
        room_walls(m, lo, hi, "checker_floor", "checker_wall", "wall")
        random_boxes(rng, m, lo, hi, rng.randint(2, 6), [eye, light, target])
    elif family == "dark-room":
        # other-room's two rooms, the camera in the near one (z < D) with the doorway behind it or at its
        # side, the light in the far one, mostly off the doorway's line: the near room is lit by the
        # floor patch the doorway lets light onto and by the far room's VPLs through the doorway alone.
        D2 = rng.uniform(3, 6)
        room_walls(m, lo, (W, H, D + D2), *walls)
        door = rng.uniform(0.1, 0.7) * W
        wall_with_door(m, D, door, W, H, "wall")
        away = rng.uniform(0.05, 0.3) * W
        lx = door + 0.45 + (away if door + 0.45 < W / 2 else -away) * (1 if rng.random() < 0.75 else -1)
        p = (min(max(lx, 0.1 * W), 0.9 * W), H * rng.uniform(0.5, 0.85), D + rng.uniform(0.2, 0.6) * D2)
        # 40 times as strong: the unlit room's indirect light is then of the other families' order, as a
        # photographer would expose it (at their powers it is 0.001-0.003, where relMSE's absolute epsilon
        # turns relMSE into a plain mean squared error).
        lights = [(p, (40 * power, 40 * power, 40 * power))]
        # `bench --camera-path orbit`'s first quarter turn (16 frames of 60) moves the eye by up to r0 in -x
        # and +z (r0: a tenth of the scene's diagonal): it stays in the near room, clear of the boxes.
        r0 = 0.1 * math.sqrt(W * W + H * H + (D + D2) ** 2)
        eye = (rng.uniform(r0 + 0.25, max(0.8 * W, r0 + 0.3)), rng.uniform(1.2, 1.7), D - r0 - rng.uniform(0.25, 0.6))
        arc = [(eye[0] + r0 * (math.cos(t) - 1), eye[1], eye[2] + r0 * math.sin(t)) for t in
               [i * math.pi / 16 for i in range(9)]]
        if rng.random() < 0.6:
            # Away from the door: the back wall and floor.
            target = (rng.uniform(0.2, 0.8) * W, rng.uniform(0.3, 1.2), 0.0)
        else:
            # Along the shared wall, at the side wall the doorway is farther from.
            side = 0.0 if door + 0.45 > W / 2 else W
            target = (side, rng.uniform(0.5, 1.5), D - rng.uniform(0.5, 1.5))
        random_boxes(rng, m, lo, (W, H, D), rng.randint(0, 3), arc + [(door + 0.45, 1.0, D - 0.3)])
        motions = [(circle, (margin, margin, D + margin), (W - margin, H - margin, D + D2 - margin))]
    else:
        raise ValueError(family)
    if motions is None:
        motions = [(circle, room[0], room[1])] * len(lights)
    return m, (eye, target, fov), lights, motions


# The light path's keyframes: every PATH_STEP frames of a loop of PATH_PERIOD (bench --animate FILE).
PATH_PERIOD, PATH_STEP = 60, 5


def light_keys(p, motion):
    """Room-unit positions of a light at frames 0, PATH_STEP, ..., PATH_PERIOD: from its start p along a
    circle p + (cos θ - 1) a + sin θ b (or, for ((a), "out"), p + (1 - cos θ) a / 2, out and back along
    a), clamped per axis into the motion's box widened to hold p."""
    steps, lo, hi = motion
    keys = []
    for k in range(0, PATH_PERIOD + 1, PATH_STEP):
        t = 2 * math.pi * k / PATH_PERIOD
        if steps[-1] == "out":
            q = [p[i] + (1 - math.cos(t)) / 2 * steps[0][i] for i in range(3)]
        else:
            a, b = steps
            q = [p[i] + (math.cos(t) - 1) * a[i] + math.sin(t) * b[i] for i in range(3)]
        keys.append((k, tuple(min(max(q[i], min(lo[i], p[i])), max(hi[i], p[i])) for i in range(3))))
    return keys


def write_suite_scene(d, name, m, camera, lights, motions, scale, size, textured):
    os.makedirs(d, exist_ok=True)
    used = sorted({l.split()[1] for l in m.lines if l.startswith("usemtl")})
    with open(os.path.join(d, f"{name}.mtl"), "w") as f:
        f.write("# Generated by scripts/make-scenes.py --suite (public domain).\n")
        for mat in used:
            f.write(f"newmtl {mat}\nKd {' '.join(f'{c:.2f}' for c in SUITE_MATERIALS[mat])}\n")
            if mat.startswith("checker"):
                f.write(f"map_Kd {mat}.png\n")
    if textured:
        png_checker(os.path.join(d, "checker_floor.png"), (180, 170, 150), (60, 55, 50))
        png_checker(os.path.join(d, "checker_wall.png"), (200, 200, 195), (120, 150, 190), n=4, cell=8)
    with open(os.path.join(d, f"{name}.obj"), "w") as f:
        f.write(f"# {name}: generated by scripts/make-scenes.py --suite (public domain).\nmtllib {name}.mtl\n")
        f.write("\n".join(m.lines) + "\n")
    eye, target, fov = camera
    vec = lambda v: "[" + ", ".join(f"{x:.9g}" for x in v) + "]"
    s = [f"# {name}: generated by scripts/make-scenes.py --suite.", f'mesh = "{name}.obj"', ""]
    s += ["[camera]", f"eye    = {vec(m.place(eye))}", f"target = {vec(m.place(target))}", "up     = [0, 1, 0]"]
    s += [f"fov_y  = {fov:.1f}", ""]
    for p, w in lights:
        # Radiance does not depend on the scale: intensity grows with its square.
        s += ["[[light]]", f"position  = {vec(m.place(p))}", f"intensity = {vec(tuple(x * scale * scale for x in w))}", ""]
    s += ["[render]", f"width  = {size}", f"height = {size}"]
    with open(os.path.join(d, "scene.toml"), "w") as f:
        f.write("\n".join(s) + "\n")
    # A light path that keeps each light in its room and its family's place (by a wall, in a corner,
    # under a table, in the far room): `bench --animate light-path.toml`.
    s = [f"# {name}: every light's path, a loop of {PATH_PERIOD} frames; generated by scripts/make-scenes.py --suite.", ""]
    for i, ((p, _), motion) in enumerate(zip(lights, motions)):
        for k, q in light_keys(p, motion):
            s += ["[[key]]", f"frame = {k}", f"light = {i}", f"position = {vec(m.place(q))}", ""]
    with open(os.path.join(d, "light-path.toml"), "w") as f:
        f.write("\n".join(s))


def suite(root, per_family, seed, size):
    rng = random.Random(seed)
    n = 0
    for family in FAMILIES:
        for k in range(per_family):
            scale = SCALES[(n + k) % len(SCALES)]
            far = n % 2 == 1
            offset = tuple(rng.uniform(2e3, 2e4) * scale * rng.choice((-1, 1)) for _ in range(3)) if far else (0.0, 0.0, 0.0)
            m, camera, lights, motions = suite_scene(rng, family, scale, offset)
            name = f"{family}-{k}"
            write_suite_scene(os.path.join(root, name), name, m, camera, lights, motions, scale, size,
                              family == "textured")
            n += 1
    return n


def main():
    args = sys.argv[1:]
    if args[:1] in (["-h"], ["--help"]):
        print(__doc__)
        return
    # An option where the assets folder goes would be taken for a folder name (`--help` once wrote the
    # stress scenes into ./--help).
    if args and args[0].startswith("-") and args[0] != "--suite":
        sys.exit(f"error: unknown option {args[0]}: make-scenes.py [assets-dir] | --suite DIR [--per-family N] [--seed S] [--size PIXELS]")
    if len(args) > 1 and args[0] != "--suite":
        sys.exit(f"error: one assets folder expected, got {args}")
    if args[:1] == ["--suite"]:
        if len(args) < 2:
            sys.exit("error: --suite needs a folder: make-scenes.py --suite DIR [--per-family N] [--seed S] [--size PIXELS]")
        opts = dict(zip(args[2::2], args[3::2]))
        unknown = set(opts) - {"--per-family", "--seed", "--size"}
        if unknown or len(args[2:]) % 2:
            sys.exit(f"error: unknown or incomplete options {sorted(unknown) or args[2:]}")
        try:
            per, seed, size = int(opts.get("--per-family", 5)), int(opts.get("--seed", 1)), int(opts.get("--size", 128))
        except ValueError as e:
            sys.exit(f"error: {e}")
        if per < 1 or size < 1:
            sys.exit("error: --per-family and --size must be at least 1")
        n = suite(args[1], per, seed, size)
        print(f"wrote {n} scenes to {args[1]}")
        return
    root = args[0] if args else os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "assets")
    for make in (box_on_floor, doorway, clutter):
        make(root)


if __name__ == "__main__":
    main()
