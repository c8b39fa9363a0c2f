#!/usr/bin/env python3
"""make_interiors.py: writes the OBJ+MTL meshes of the interior test scenes (README.md beside this file).

    python3 scenes/interiors/make_interiors.py        # rewrites door-ajar, sky-room, stair-hall .obj/.mtl

Python 3 standard library only; the output is deterministic (same script, same bytes). Units are metres,
+y is up. Every solid is a closed box (walls, floors and ceilings have thickness), each face wound so that
its normal points out of the box: surfaces never leak light through a crack between two planes, and the
one-sided emitters face the way their winding says (docs/scene-format.md). A wall with openings is cut
into boxes around them. The JSON scene files beside the meshes (camera, sky, render settings) are written
by hand.
"""

import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def scale(a, s):
    return (a[0] * s, a[1] * s, a[2] * s)


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


class Mesh:
    """Vertices, quads grouped by object and material; written as one OBJ and its MTL."""

    def __init__(self, name):
        self.name = name
        self.vertices = []
        self.index = {}
        self.groups = []        # (object name, material, [faces])
        self.materials = {}     # name -> (kd, ke)

    def material(self, name, kd, ke=None):
        self.materials[name] = (kd, ke)
        return name

    def _vertex(self, p):
        key = tuple(round(c, 5) for c in p)
        if key not in self.index:
            self.vertices.append(key)
            self.index[key] = len(self.vertices)
        return self.index[key]

    def _group(self, obj, mat):
        if not self.groups or self.groups[-1][0] != obj or self.groups[-1][1] != mat:
            self.groups.append((obj, mat, []))
        return self.groups[-1][2]

    def quad(self, obj, mat, corners, outward):
        """A planar quad (corners in order around it), wound so that its normal points along `outward`."""
        n = cross(sub(corners[1], corners[0]), sub(corners[2], corners[0]))
        if dot(n, outward) < 0:
            corners = corners[::-1]
        self._group(obj, mat).append([self._vertex(p) for p in corners])

    def solid(self, obj, mat, origin, a, b, c, mats=None):
        """The parallelepiped origin + s a + t b + u c (s, t, u in [0, 1]), faces wound outwards.
        mats: optional per-face materials keyed '-a', '+a', '-b', '+b', '-c', '+c'."""
        centre = add(origin, scale(add(add(a, b), c), 0.5))
        p = lambda s, t, u: add(add(add(origin, scale(a, s)), scale(b, t)), scale(c, u))  # noqa: E731
        faces = {
            "-a": [p(0, 0, 0), p(0, 1, 0), p(0, 1, 1), p(0, 0, 1)],
            "+a": [p(1, 0, 0), p(1, 1, 0), p(1, 1, 1), p(1, 0, 1)],
            "-b": [p(0, 0, 0), p(1, 0, 0), p(1, 0, 1), p(0, 0, 1)],
            "+b": [p(0, 1, 0), p(1, 1, 0), p(1, 1, 1), p(0, 1, 1)],
            "-c": [p(0, 0, 0), p(1, 0, 0), p(1, 1, 0), p(0, 1, 0)],
            "+c": [p(0, 0, 1), p(1, 0, 1), p(1, 1, 1), p(0, 1, 1)],
        }
        for key, corners in faces.items():
            face_centre = scale(add(add(corners[0], corners[1]), add(corners[2], corners[3])), 0.25)
            self.quad(obj, (mats or {}).get(key, mat), corners, sub(face_centre, centre))

    def box(self, obj, mat, lo, hi, mats=None):
        """Axis-aligned box [lo, hi]; mats keys: '-x', '+x', '-y', '+y', '-z', '+z'."""
        m = None
        if mats:
            m = {k.replace("x", "a").replace("y", "b").replace("z", "c"): v for k, v in mats.items()}
        self.solid(obj, mat, lo, (hi[0] - lo[0], 0, 0), (0, hi[1] - lo[1], 0), (0, 0, hi[2] - lo[2]), m)

    def wall(self, obj, mat, axis, lo, hi, holes=(), mats=None):
        """An axis-aligned box wall [lo, hi] whose thickness runs along `axis` (0 = x, 2 = z), cut through by
        rectangular holes given as (u0, u1, y0, y1) along the other horizontal axis and y."""
        u_axis = 2 if axis == 0 else 0
        cuts = sorted({lo[u_axis], hi[u_axis]} | {h[0] for h in holes} | {h[1] for h in holes})
        for u0, u1 in zip(cuts, cuts[1:]):
            in_column = sorted((h[2], h[3]) for h in holes if h[0] <= u0 and h[1] >= u1)
            spans, y = [], lo[1]
            for y0, y1 in in_column:
                if y0 > y:
                    spans.append((y, y0))
                y = max(y, y1)
            if y < hi[1]:
                spans.append((y, hi[1]))
            for y0, y1 in spans:
                a, b = list(lo), list(hi)
                a[u_axis], b[u_axis], a[1], b[1] = u0, u1, y0, y1
                self.box(obj, mat, tuple(a), tuple(b), mats)

    def emitter(self, obj, mat, centre, sx, sz):
        """A horizontal quad of sx by sz centred at `centre`, emitting downwards."""
        x0, x1, z0, z1 = centre[0] - sx / 2, centre[0] + sx / 2, centre[2] - sz / 2, centre[2] + sz / 2
        y = centre[1]
        self.quad(obj, mat, [(x0, y, z0), (x1, y, z0), (x1, y, z1), (x0, y, z1)], (0, -1, 0))

    def triangles(self):
        return sum(len(f) - 2 for g in self.groups for f in g[2])

    def write(self, folder, about):
        def num(x):
            s = ("%.4f" % x).rstrip("0").rstrip(".")
            return "0" if s in ("-0", "") else s

        obj_path = os.path.join(folder, self.name + ".obj")
        mtl_path = os.path.join(folder, self.name + ".mtl")
        lines = ["# %s" % self.name, "# %s" % about,
                 "# Written by scenes/interiors/make_interiors.py (irrcache's own, same licence as the "
                 "repository).", "mtllib %s.mtl" % self.name]
        lines += ["v %s %s %s" % tuple(num(c) for c in v) for v in self.vertices]
        for obj, mat, faces in self.groups:
            lines += ["o %s" % obj, "usemtl %s" % mat]
            lines += ["f " + " ".join(str(i) for i in f) for f in faces]
        with open(obj_path, "w", newline="\n") as f:
            f.write("\n".join(lines) + "\n")
        mtl = ["# Materials of %s.obj (make_interiors.py); Lambertian: Kd only, Ke for the emitter." % self.name]
        for name in sorted(self.materials):
            kd, ke = self.materials[name]
            mtl += ["", "newmtl %s" % name, "Kd %s %s %s" % tuple(num(c) for c in kd), "Ks 0 0 0", "illum 1"]
            if ke:
                mtl.append("Ke %s %s %s" % tuple(num(c) for c in ke))
        with open(mtl_path, "w", newline="\n") as f:
            f.write("\n".join(mtl) + "\n")
        return obj_path, self.triangles()


def room_shell(m, name, lo, hi, t, mats, holes=None, skip=()):
    """The closed shell around the interior box [lo, hi]: floor, ceiling and four walls of thickness t, the
    walls overlapping at the corners. holes: {'-x': [...], ...} openings per wall, as for Mesh.wall.
    mats: {'floor', 'ceiling', 'wall'} or per-wall keys '-x', '+x', '-z', '+z'. skip: walls left out (a
    wall shared with the next room, built by the caller)."""
    holes = holes or {}
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    # under a skipped +x or +z wall the slabs stop at the interior: the next room's slabs cover the wall
    xe, ze = (0 if "+x" in skip else t), (0 if "+z" in skip else t)
    m.box(name + "_floor", mats["floor"], (x0 - t, y0 - t, z0 - t), (x1 + xe, y0, z1 + ze))
    m.box(name + "_ceiling", mats["ceiling"], (x0 - t, y1, z0 - t), (x1 + xe, y1 + t, z1 + ze))
    walls = {
        "-x": (0, (x0 - t, y0, z0 - t), (x0, y1, z1 + t)),
        "+x": (0, (x1, y0, z0 - t), (x1 + t, y1, z1 + t)),
        "-z": (2, (x0, y0, z0 - t), (x1, y1, z0)),
        "+z": (2, (x0, y0, z1), (x1, y1, z1 + t)),
    }
    for key, (axis, a, b) in walls.items():
        if key in skip:
            continue
        m.wall("%s_wall%s" % (name, key.replace("-", "m").replace("+", "p")), mats.get(key, mats["wall"]),
               axis, a, b, holes.get(key, ()))


# ------------------------------------------------------------------------------------------------------
# door-ajar: two rooms, the only light in the far one, a door left ajar by 5 cm between them


def door_ajar():
    m = Mesh("door-ajar")
    pink = m.material("wall_pink", (0.78, 0.52, 0.52))
    door = m.material("door_orange", (0.85, 0.42, 0.12))
    floor_a = m.material("floor_wood", (0.45, 0.33, 0.22))
    ceiling = m.material("ceiling_white", (0.8, 0.8, 0.78))
    wall_b = m.material("wall_blue", (0.45, 0.55, 0.72))
    floor_b = m.material("floor_grey", (0.4, 0.4, 0.42))
    trim = m.material("trim_cream", (0.82, 0.78, 0.65))
    light = m.material("light", (0.8, 0.8, 0.8), (6400, 5760, 4800))
    t, h = 0.15, 2.6
    # near room A: x in [0, 4]; the dividing wall x in [4, 4.15]; far room B: x in [4.15, 8.15]; z in [0, 4]
    room_shell(m, "roomA", (0, 0, 0), (4, h, 4), t,
               {"floor": floor_a, "ceiling": ceiling, "wall": pink}, skip=("+x",))
    room_shell(m, "roomB", (4.15, 0, 0), (8.15, h, 4), t,
               {"floor": floor_b, "ceiling": ceiling, "wall": wall_b}, skip=("-x",))
    # the dividing wall with the doorway: 1.0 m wide (z in [2.2, 3.2]), 2.1 m tall; pink on A's side
    dz0, dz1, dh = 2.2, 3.2, 2.1
    m.wall("dividing_wall", pink, 0, (4.0, 0, -t), (4.15, h, 4 + t), [(dz0, dz1, 0, dh)],
           mats={"+x": wall_b})
    # a door frame (architrave) on A's side: two jambs and a head, 6 cm wide, 2 cm proud of the wall
    m.box("frame_left", trim, (3.98, 0, dz0 - 0.06), (4.0, dh + 0.06, dz0))
    m.box("frame_right", trim, (3.98, 0, dz1), (4.0, dh + 0.06, dz1 + 0.06))
    m.box("frame_head", trim, (3.98, dh, dz0), (4.0, dh + 0.06, dz1))
    # the door leaf, 4 cm thick, flush with B's face of the wall when closed, hinged at z = dz0 on B's side
    # and swung into room B until the corner of its latch edge on A's side clears the jamb by 5 cm:
    # width sin(angle) - thick cos(angle) = gap
    width, thick, gap = dz1 - dz0, 0.04, 0.05
    angle = math.atan2(thick, width) + math.asin(gap / math.hypot(width, thick))
    hinge = (4.15, 0.0, dz0)
    along = (math.sin(angle) * width, 0, math.cos(angle) * width)          # hinge to latch, in the plan
    across = (-math.cos(angle) * thick, 0, math.sin(angle) * thick)        # B's face to A's face
    m.solid("door", door, add(hinge, across), along, (0, dh, 0), scale(across, -1))
    # a handle on A's side, so the door reads as a door
    latch = add(hinge, scale(along, 0.9))
    m.box("handle", trim, (latch[0] - thick - 0.06, 0.98, latch[2] - 0.1), (latch[0] - thick, 1.02, latch[2]))
    # something in room A for the gap's light to land on: a low cabinet against the far wall
    m.box("cabinet", trim, (1.2, 0, 0.0), (2.4, 0.8, 0.45))
    # the light: a 0.7 m square panel in B's ceiling, away from the line of sight through the gap
    m.emitter("ceiling_light", light, (6.8, h - 0.002, 1.2), 0.7, 0.7)
    return m, "Two rooms joined by a doorway whose door is ajar by 5 cm; the only emitter is in the far room."


# ------------------------------------------------------------------------------------------------------
# sky-room: a room lit by a constant sky through two open windows


def sky_room():
    m = Mesh("sky-room")
    wall = m.material("wall_warm", (0.75, 0.7, 0.62))
    ceiling = m.material("ceiling_white", (0.82, 0.82, 0.8))
    floor = m.material("floor_oak", (0.5, 0.36, 0.22))
    sofa = m.material("sofa_green", (0.22, 0.45, 0.3))
    cushion = m.material("cushion_red", (0.7, 0.18, 0.15))
    rug = m.material("rug_blue", (0.2, 0.28, 0.5))
    ground = m.material("ground", (0.3, 0.32, 0.25))
    outside = m.material("outside_render", (0.6, 0.6, 0.6))
    t, h, w, d = 0.25, 2.7, 5.0, 4.0
    # windows in the z = 0 wall: 1.1 m wide, 1.3 m tall, sill at 0.85 m
    windows = [(0.8, 1.9, 0.85, 2.15), (3.1, 4.2, 0.85, 2.15)]
    room_shell(m, "room", (0, 0, 0), (w, h, d), t, {"floor": floor, "ceiling": ceiling, "wall": wall},
               holes={"-z": windows})
    # a ground plane outside, below the floor: through the windows the ceiling sees it, never the sky
    m.box("ground", ground, (-60, -t - 0.1, -60), (60, -t, 60))
    m.box("roof_overhang", outside, (-t - 0.3, h + t, -t - 0.6), (w + t + 0.3, h + t + 0.1, d + t))
    # the sofa against the back wall (z = d): seat, back and two arms, with two cushions
    sx0, sx1, sz0, sz1 = 1.3, 3.7, d - 0.95, d - 0.05
    m.box("sofa_base", sofa, (sx0, 0, sz0), (sx1, 0.42, sz1))
    m.box("sofa_back", sofa, (sx0, 0.42, sz1 - 0.22), (sx1, 0.9, sz1))
    m.box("sofa_arm_left", sofa, (sx0, 0.42, sz0), (sx0 + 0.2, 0.65, sz1 - 0.22))
    m.box("sofa_arm_right", sofa, (sx1 - 0.2, 0.42, sz0), (sx1, 0.65, sz1 - 0.22))
    m.box("cushion_left", cushion, (sx0 + 0.35, 0.42, sz1 - 0.34), (sx0 + 0.8, 0.8, sz1 - 0.22))
    m.box("cushion_right", cushion, (sx1 - 0.8, 0.42, sz1 - 0.34), (sx1 - 0.35, 0.8, sz1 - 0.22))
    m.box("rug", rug, (1.5, 0, 1.2), (3.5, 0.01, 2.7))
    # a low table on the rug
    m.box("table_top", wall, (2.0, 0.38, 1.6), (3.0, 0.42, 2.2))
    for x, z in ((2.05, 1.65), (2.91, 1.65), (2.05, 2.11), (2.91, 2.11)):
        m.box("table_leg", wall, (x, 0.01, z), (x + 0.04, 0.38, z + 0.04))
    return m, "A room lit only by a constant sky through two open windows; a sofa; the ceiling sees no sky."


# ------------------------------------------------------------------------------------------------------
# stair-hall: a tall hall with an open staircase of thin treads and balusters, one small ceiling light


def stair_hall():
    m = Mesh("stair-hall")
    wall = m.material("wall_plaster", (0.72, 0.7, 0.66))
    floor = m.material("floor_stone", (0.45, 0.43, 0.4))
    ceiling = m.material("ceiling_white", (0.8, 0.8, 0.8))
    tread = m.material("tread_walnut", (0.42, 0.26, 0.14))
    metal = m.material("baluster_black", (0.06, 0.06, 0.06))
    rail = m.material("rail_oak", (0.55, 0.38, 0.2))
    frame = m.material("frame_gold", (0.7, 0.55, 0.2))
    canvas = [m.material("canvas_blue", (0.15, 0.3, 0.65)), m.material("canvas_red", (0.7, 0.2, 0.15))]
    light = m.material("light", (0.8, 0.8, 0.8), (120, 110, 95))
    t, w, h, d = 0.2, 6.0, 5.2, 5.0
    room_shell(m, "hall", (0, 0, 0), (w, h, d), t, {"floor": floor, "ceiling": ceiling, "wall": wall})
    # a gallery (upper floor) along the back wall (z = d), 1.3 m deep, its floor at 2.4 m
    rise, run, treads, thick = 0.2, 0.28, 12, 0.03
    top, gz = rise * treads, d - 1.3
    m.box("gallery", floor, (0, top - 0.2, gz), (w, top, d))
    # the staircase against the right wall (x = w), 1 m wide, climbing in +z to the gallery's front edge:
    # 12 open treads 3 cm thick (2 cm nosing over the next), two 3 cm square posts on each, a sloped rail
    sx0, z_start = w - 1.0, gz - run * treads
    for i in range(treads):
        z0, y1 = z_start + i * run, rise * (i + 1)
        m.box("tread%02d" % (i + 1), tread, (sx0, y1 - thick, z0 - 0.02), (w, y1, z0 + run))
        for k in (0.25, 0.75):
            bz = z0 + k * run - 0.015
            rail_y = 0.9 + rise * (i + 1) + (k - 0.5) * rise
            m.box("baluster", metal, (sx0 + 0.02, y1, bz), (sx0 + 0.05, rail_y, bz + 0.03))
    length = run * treads
    m.solid("handrail", rail, (sx0 + 0.01, 0.9 + 0.5 * rise, z_start), (0, length * rise / run, length),
            (0, 0.05, 0), (0.05, 0, 0))
    # the gallery's balustrade: 3 cm posts every 12 cm along its front edge, from the left wall to the stair
    px = 0.1
    while px + 0.03 < sx0:
        m.box("gallery_post", metal, (px, top, gz + 0.02), (px + 0.03, top + 0.95, gz + 0.05))
        px += 0.12
    m.box("gallery_rail", rail, (0, top + 0.95, gz), (sx0 + 0.06, top + 1.0, gz + 0.07))
    # two picture frames on the wall over the stair (x = w): gilt frames, coloured canvases
    for j, (zc, yc, fw, fh) in enumerate(((1.4, 2.1, 0.9, 0.7), (2.6, 2.9, 0.6, 0.9))):
        z0, z1, y0, y1, b = zc - fw / 2, zc + fw / 2, yc - fh / 2, yc + fh / 2, 0.06
        fx = w - 0.04
        m.box("frame%d" % j, frame, (fx, y0, z0), (w, y0 + b, z1))
        m.box("frame%d" % j, frame, (fx, y1 - b, z0), (w, y1, z1))
        m.box("frame%d" % j, frame, (fx, y0 + b, z0), (w, y1 - b, z0 + b))
        m.box("frame%d" % j, frame, (fx, y0 + b, z1 - b), (w, y1 - b, z1))
        m.box("canvas%d" % j, canvas[j], (w - 0.02, y0 + b, z0 + b), (w, y1 - b, z1 - b))
    # one small light panel high up in the ceiling
    m.emitter("ceiling_light", light, (3.0, h - 0.002, 2.0), 0.45, 0.45)
    return m, "A two-storey hall: 12 thin treads with square balusters, a gallery, two frames, one small ceiling light."


def main():
    for make in (door_ajar, sky_room, stair_hall):
        mesh, about = make()
        path, tris = mesh.write(HERE, about)
        print("%s: %d triangles, %d bytes" % (os.path.relpath(path), tris, os.path.getsize(path)))


if __name__ == "__main__":
    main()
