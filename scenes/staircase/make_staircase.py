"""Writes scenes/staircase.xml and its data (scenes/staircase/models/MeshNNN.obj,
scenes/staircase/textures/*.png): a staircase scene laid out the way Benedikt Bitterli's rendering
resources are after conversion to Mitsuba 3 (one OBJ file per object, each placed by a 4x4
`matrix` to_world as exporters write them, materials declared once with ids and used by `ref`).

The scene: a straight flight of 14 steps (treads, risers, a closed stringer on each side) along a
wall, balusters on the open side under a copper handrail, a copper wall rail on brass brackets,
newel posts, a landing, a tiled floor and two walls, lit by two rectangle lights (a ceiling panel
over the landing, a "window" on the open side) and a dim constant sky; the camera stands at the
foot of the stairs and looks up them. Units are metres, y is up.

What it exercises in the readers:
- about 290 OBJ files in the styles exporters write: Blender's Z-up object space with the Z-up to
  Y-up rotation in the matrix; unit cubes scaled by the matrix; objects modelled in centimetres
  (uniform scale 0.01); `v/vt/vn` triangles with shared positions and per-face normals; `v//vn`;
  `v/vt` and bare `v` quads (normals computed by the reader, flat where the file splits its
  vertices per face, smooth around the octagonal baluster shafts); `o`, `g`, `s`, `usemtl` and
  `mtllib` lines the readers skip; an oval handrail whose `vn` must go through the inverse
  transpose of a non-uniform scale; one cylinder file shared by ten shapes; mirrored matrices
  (negative determinant) on the left stringer, which is two-sided; floor tiles turned by
  half turns and some with their u or v mirrored in the file, under a bump map (so the bump's
  dp/du and dp/dv orientation matters);
- materials: `twosided` textured `roughplastic` (ggx, wood bitmap), an untextured painted one,
  a `bumpmap` (raw height bitmap) over a textured roughplastic floor, `roughconductor` by name
  (Al balusters, Cu rails) and by eta/k (brass), a `diffuse` wall;
- `path` at max_depth 65 (as Bitterli's scenes), the default (gaussian) film filter.

Deterministic (an integer hash, no random module); needs Python 3 and numpy only (PNGs are
written with zlib). Run from anywhere, e.g. .venv/bin/python scenes/staircase/make_staircase.py
"""
import math
import os
import struct
import zlib

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
SCENES = os.path.dirname(HERE)
MODELS = os.path.join(HERE, "models")
TEXTURES = os.path.join(HERE, "textures")

# Stair dimensions (metres).
N_STEPS = 14
RISE = 0.18  # riser height
GOING = 0.28  # tread depth, front to front
NOSING = 0.03  # tread overhang in front of its riser
TREAD_T = 0.04  # tread thickness
X_WALL = -1.0  # the left wall's plane
X_OPEN = 0.0  # the open side of the flight
TOP = N_STEPS * RISE  # landing level
Z_TOP = -N_STEPS * GOING  # back of the last tread
Z_BACK = -5.0  # back wall
RAIL_H = 0.9  # handrail centre above the nosing line


def nosing_y(z):
    """Height of the line through the tread nosings at depth z (stairs rise towards -z)."""
    return RISE * (1.0 + (NOSING - z) / GOING)


# ---------------------------------------------------------------------------------------------
# Deterministic pseudo-random numbers (splitmix64 of a counter).
_state = [0x5EED5EED]


def rand():
    _state[0] = (_state[0] + 0x9E3779B97F4A7C15) & 0xFFFFFFFFFFFFFFFF
    z = _state[0]
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & 0xFFFFFFFFFFFFFFFF
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & 0xFFFFFFFFFFFFFFFF
    z ^= z >> 31
    return (z >> 11) / float(1 << 53)


# ---------------------------------------------------------------------------------------------
# Matrices (4x4, column vectors: p_world = M p_object).
def translate(x, y, z):
    m = np.eye(4)
    m[:3, 3] = (x, y, z)
    return m


def scale(x, y=None, z=None):
    if y is None:
        y = z = x
    return np.diag([x, y, z, 1.0])


def rot_x(deg):
    a = math.radians(deg)
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1.0]])


def rot_y(deg):
    a = math.radians(deg)
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s, 0], [0, 1, 0, 0], [-s, 0, c, 0], [0, 0, 0, 1.0]])


# Blender's Z-up object space to Mitsuba's Y-up world: object (x, y, z) -> world (x, z, -y).
Z_UP = rot_x(-90.0)


def fmt(x):
    s = "%.7g" % x
    return "0" if s in ("-0", "0") else s


def matrix_str(m):
    return " ".join(fmt(v) for v in m.reshape(-1))


# ---------------------------------------------------------------------------------------------
# OBJ writing. A face is a list of corners (position index, uv index or None, normal index or
# None), 1-based, counter-clockwise seen from the front.
class Obj:
    def __init__(self, comment):
        self.header = [comment]
        self.v, self.vt, self.vn, self.f = [], [], [], []
        self.extra = []  # lines placed before the faces (o, g, usemtl, s)

    def add_v(self, p):
        self.v.append(tuple(p))
        return len(self.v)

    def add_vt(self, uv):
        self.vt.append(tuple(uv))
        return len(self.vt)

    def add_vn(self, n):
        n = np.asarray(n, float)
        self.vn.append(tuple(n / np.linalg.norm(n)))
        return len(self.vn)

    def text(self):
        out = ["# " + h for h in self.header]
        out += ["v %s %s %s" % tuple(fmt(c) for c in p) for p in self.v]
        out += ["vt %s %s" % tuple(fmt(c) for c in t) for t in self.vt]
        out += ["vn %s %s %s" % tuple(fmt(c) for c in n) for n in self.vn]
        out += self.extra
        for face in self.f:
            corners = []
            for (p, t, n) in face:
                if t is None and n is None:
                    corners.append("%d" % p)
                elif n is None:
                    corners.append("%d/%d" % (p, t))
                elif t is None:
                    corners.append("%d//%d" % (p, n))
                else:
                    corners.append("%d/%d/%d" % (p, t, n))
            out.append("f " + " ".join(corners))
        return "\n".join(out) + "\n"


def oriented(quad_pts, normal):
    """Indices 0..3 of a planar quad's corners ordered counter-clockwise about `normal`."""
    p = [np.asarray(q, float) for q in quad_pts]
    n = np.cross(p[1] - p[0], p[2] - p[0])
    return [0, 1, 2, 3] if np.dot(n, normal) > 0 else [0, 3, 2, 1]


CUBE_FACES = [  # (normal, axis of the normal, the two in-plane axes (u, v))
    ((1, 0, 0), 0, (1, 2)), ((-1, 0, 0), 0, (1, 2)),
    ((0, 1, 0), 1, (0, 2)), ((0, -1, 0), 1, (0, 2)),
    ((0, 0, 1), 2, (0, 1)), ((0, 0, -1), 2, (0, 1)),
]


def box_corners(lo, hi):
    """The 8 corners of an axis-aligned box, index = bit x + 2 bit y + 4 bit z."""
    return [(hi[0] if i & 1 else lo[0], hi[1] if i & 2 else lo[1], hi[2] if i & 4 else lo[2])
            for i in range(8)]


def box_face_corners(normal, axis):
    """Corner indices (into box_corners) of the face with this outward normal, CCW."""
    side = 1 if normal[axis] > 0 else 0
    idx = [i for i in range(8) if ((i >> axis) & 1) == side]
    # order the four around the face: by angle in the plane
    others = [a for a in range(3) if a != axis]
    ring = sorted(idx, key=lambda i: math.atan2(((i >> others[1]) & 1) - 0.5,
                                                ((i >> others[0]) & 1) - 0.5))
    return ring


def write_box(obj, lo, hi, style, uv_dims=None, uv_off=(0.0, 0.0), triangles=True):
    """A box as 6 quads. style: 'vtn' (shared positions, per-face vt and vn), 'vn' (v//vn),
    'split' (bare v, 4 own positions per face), 'v' (bare v, 8 shared positions)."""
    corners = box_corners(lo, hi)
    size = np.asarray(hi, float) - np.asarray(lo, float)
    dims = size if uv_dims is None else np.asarray(uv_dims, float)
    base = len(obj.v)
    if style != "split":
        for c in corners:
            obj.add_v(c)
    for normal, axis, (ua, va) in CUBE_FACES:
        ring = box_face_corners(normal, axis)
        pts = [corners[i] for i in ring]
        order = oriented(pts, normal)
        ring = [ring[k] for k in order]
        if style == "split":
            ids = [obj.add_v(corners[i]) for i in ring]
        else:
            ids = [base + 1 + i for i in ring]
        tids = [None] * 4
        nid = None
        if style == "vtn":
            for k, i in enumerate(ring):
                c = corners[i]
                u = (c[ua] - lo[ua]) / size[ua] * dims[ua] + uv_off[0]
                v = (c[va] - lo[va]) / size[va] * dims[va] + uv_off[1]
                tids[k] = obj.add_vt((u, v))
        if style in ("vtn", "vn"):
            nid = obj.add_vn(normal)
        corners4 = [(ids[k], tids[k], nid) for k in range(4)]
        if triangles:
            obj.f.append([corners4[0], corners4[1], corners4[2]])
            obj.f.append([corners4[0], corners4[2], corners4[3]])
        else:
            obj.f.append(corners4)


# ---------------------------------------------------------------------------------------------
# The scene's objects: (file name, material id, to_world matrix), and the files' texts.
shapes = []
files = {}
counter = [0]


def new_mesh(obj_text):
    name = "Mesh%03d.obj" % counter[0]
    counter[0] += 1
    files[name] = obj_text
    return name


def place(name, material, m):
    shapes.append((name, material, m))


# Treads: Blender's default cube ([-1, 1]^3, Z-up) scaled by the matrix; shared positions with
# per-face uvs (grain along the width, a different plank offset per step) and normals, as
# 12 triangles. Every other tread is turned by 180 degrees about the vertical.
TREAD_W = (X_OPEN - X_WALL) - 0.035  # from the left stringer to the open side
for i in range(N_STEPS):
    o = Obj("Blender v2.79 (sub 0) OBJ File: 'staircase.blend'")
    o.header.append("www.blender.org")
    o.extra = ["mtllib staircase.mtl", "o Tread_%02d" % i, "usemtl Wood", "s off"]
    depth = GOING + NOSING
    write_box(o, (-1, -1, -1), (1, 1, 1), "vtn", uv_dims=(TREAD_W, depth, TREAD_T),
              uv_off=(rand(), rand()))
    name = new_mesh(o.text())
    cx = X_WALL + 0.035 + TREAD_W / 2
    cz = -i * GOING + NOSING - depth / 2
    cy = (i + 1) * RISE - TREAD_T / 2
    yaw = 180.0 if i % 2 else 0.0
    place(name, "Wood", translate(cx, cy, cz) @ rot_y(yaw) @ Z_UP
          @ scale(TREAD_W / 2, depth / 2, TREAD_T / 2))

# Risers: bare `v` quads with 4 own positions per face (flat normals computed by the reader),
# modelled in place in metres around their own centre; the matrix only translates.
RISER_T = 0.02
for i in range(N_STEPS):
    o = Obj("riser %d: positions only, split per face" % i)
    o.extra = ["g Riser_%02d" % i]
    h = RISE - TREAD_T + 0.005 + (0.01 if i == 0 else 0.0)  # into the tread below / the floor
    w = TREAD_W - 0.01
    write_box(o, (-w / 2, -h / 2, -RISER_T / 2), (w / 2, h / 2, RISER_T / 2), "split",
              triangles=False)
    name = new_mesh(o.text())
    y0 = i * RISE - 0.005 - (0.01 if i == 0 else 0.0)
    place(name, "Paint", translate(X_WALL + 0.035 + TREAD_W / 2, y0 + h / 2,
                                   -i * GOING - RISER_T / 2 + 0.004))

# Stringers: a parallelogram slab per step (the closed stringer, its top edge 5 cm above the
# nosing line), `v/vt/vn` quads, in a Z-up local frame. Right side as modelled; the left side
# is the same object mirrored across its thickness (negative determinant) against the wall.
STR_T = 0.04
STR_DEPTH = 0.32  # vertical extent of the slab
SLOPE = RISE / GOING


def slab_obj(label, thickness, depth, with_normals, material):
    """A parallelogram slab along the flight: `v/vt/vn` quads, or `v/vt` quads whose positions
    are shared but whose uvs are per face (so the reader's computed normals stay flat)."""
    o = Obj("%s: parallelogram slab, Z-up, metres" % label)
    o.extra = ["o %s" % label, "usemtl %s" % material]
    # local: x thickness, y run [0, GOING] (world -z), z up; the top edge at z = 0 where y = 0
    pts = {}
    for ix, x in enumerate((0.0, thickness)):
        for iy, y in enumerate((0.0, GOING)):
            for iz, zz in enumerate((-depth, 0.0)):
                pts[(ix, iy, iz)] = (x, y, zz + SLOPE * y)
    keys = list(pts)
    ids = {k: o.add_v(pts[k]) for k in keys}
    u0, v0 = rand(), rand()
    faces = [  # (outward normal, corner keys)
        ((1, 0, 0), [(1, 0, 0), (1, 1, 0), (1, 1, 1), (1, 0, 1)]),
        ((-1, 0, 0), [(0, 0, 0), (0, 1, 0), (0, 1, 1), (0, 0, 1)]),
        ((0, -1, 0), [(0, 0, 0), (1, 0, 0), (1, 0, 1), (0, 0, 1)]),
        ((0, 1, 0), [(0, 1, 0), (1, 1, 0), (1, 1, 1), (0, 1, 1)]),
        ((0, -SLOPE, 1), [(0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]),
        ((0, SLOPE, -1), [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]),
    ]
    for normal, ks in faces:
        order = oriented([pts[k] for k in ks], normal)
        ks = [ks[k] for k in order]
        nid = o.add_vn(normal) if with_normals else None
        corners = []
        for k in ks:
            p = pts[k]
            # grain along the slope: u along the run, v across it
            tid = o.add_vt((u0 + (p[1] + p[0]) / math.cos(math.atan(SLOPE)),
                            v0 + (p[2] - SLOPE * p[1]) + 0.5 * p[0]))
            corners.append((ids[k], tid, nid))
        o.f.append(corners)
    return o.text()


for side in ("R", "L"):
    for i in range(N_STEPS):
        name = new_mesh(slab_obj("Stringer%s_%02d" % (side, i), STR_T, STR_DEPTH, True, "Wood"))
        z0 = -i * GOING + NOSING
        ytop = nosing_y(z0) + 0.05
        if side == "R":
            m = translate(X_OPEN - 0.01, ytop, z0) @ Z_UP
        else:
            m = translate(X_WALL + 0.045, ytop, z0) @ Z_UP @ scale(-1, 1, 1)
        place(name, "Wood", m)

# Spandrel under the right stringer down to the floor: bare `v` quads (normals computed), in
# world units, one per step where the stringer's underside is above the floor, and one under
# the landing. Facing +x.
for i in range(N_STEPS + 1):
    if i < N_STEPS:
        za, zb = -i * GOING + NOSING, -(i + 1) * GOING + NOSING
        ya = nosing_y(za) + 0.05 - STR_DEPTH + 0.02
        yb = nosing_y(zb) + 0.05 - STR_DEPTH + 0.02
    else:
        za, zb = -N_STEPS * GOING + NOSING, Z_BACK + 0.005
        ya = yb = TOP - TREAD_T + 0.005
    if yb <= 0.0:
        continue
    ya = max(ya, 0.0)
    o = Obj("spandrel panel %d: positions only" % i)
    # modelled with the depth axis reversed (local (0, y, -z)); the matrix turns it back by a
    # half turn about y, which also turns the local -x face to world +x
    quad = [(0.0, -0.01, -za), (0.0, -0.01, -zb), (0.0, yb, -zb), (0.0, ya, -za)]
    order = oriented(quad, (-1, 0, 0))
    ids = [o.add_v(quad[k]) for k in order]
    o.f.append([(k, None, None) for k in ids])
    name = new_mesh(o.text())
    place(name, "Wall", translate(X_OPEN + 0.005, 0, 0) @ rot_y(180.0))

# Wainscot on the left wall (paint): 1.5 cm slabs, up to 0.78 m above the nosing line along
# the flight (parallelogram slabs, `v/vt` quads) and three boards in front of it (unit cubes,
# bare `v` quads split per face).
WAINSCOT = 0.78
for i in range(N_STEPS):
    name = new_mesh(slab_obj("Wainscot_%02d" % i, 0.015, WAINSCOT - 0.02, False, "Paint"))
    z0 = -i * GOING + NOSING
    place(name, "Paint", translate(X_WALL - 0.005, nosing_y(z0) + WAINSCOT, z0) @ Z_UP)
y_w = nosing_y(NOSING) + WAINSCOT
for b in range(3):
    z0, z1 = 3.0 - (3.0 - NOSING) * b / 3, 3.0 - (3.0 - NOSING) * (b + 1) / 3
    o = Obj("wainscot board %d" % b)
    o.extra = ["g Wainscot"]
    write_box(o, (-1, -1, -1), (1, 1, 1), "split", triangles=False)
    name = new_mesh(o.text())
    place(name, "Paint", translate(X_WALL + 0.0025, y_w / 2 - 0.005, (z0 + z1) / 2) @ rot_y(90.0)
          @ Z_UP @ scale((z0 - z1) / 2 + 0.0005, 0.0075, y_w / 2 + 0.005))

# Balusters: two per step on the right stringer, each a brass base block (`v//vn`, modelled in
# centimetres) and an aluminium octagonal shaft (bare `v` triangles, smooth normals computed
# around the sides, caps with their own positions; centimetres, a twist of its own).
BASE = (4.6, 4.6, 7.0)  # cm
SHAFT_R = 1.4  # cm
for i in range(N_STEPS):
    for k in range(2):
        z = -i * GOING + NOSING - GOING * (0.25 + 0.5 * k)
        x = X_OPEN + 0.01
        y_base = nosing_y(z) + 0.05 - 0.02  # sunk 2 cm into the sloped stringer top
        yaw = 360.0 * rand()
        o = Obj("baluster base %d.%d (cm)" % (i, k))
        o.extra = ["o BalusterBase_%02d_%d" % (i, k)]
        write_box(o, (-BASE[0] / 2, -BASE[1] / 2, 0.0), (BASE[0] / 2, BASE[1] / 2, BASE[2]), "vn")
        name = new_mesh(o.text())
        place(name, "Brass", translate(x, y_base, z) @ rot_y(yaw) @ Z_UP @ scale(0.01))

        y0 = y_base + BASE[2] / 100.0 - 0.01
        y1 = nosing_y(z) + RAIL_H - 0.01
        length_cm = (y1 - y0) * 100.0
        twist = 45.0 * rand()
        o = Obj("baluster shaft %d.%d: octagonal prism, cm, positions only" % (i, k))
        o.extra = ["s 1"]
        ring0, ring1 = [], []
        for j in range(8):
            a = math.radians(twist + 45.0 * j)
            ring0.append(o.add_v((SHAFT_R * math.cos(a), SHAFT_R * math.sin(a), 0.0)))
        for j in range(8):
            a = math.radians(twist + 45.0 * j)
            ring1.append(o.add_v((SHAFT_R * math.cos(a), SHAFT_R * math.sin(a), length_cm)))
        for j in range(8):
            a0, a1, b0, b1 = ring0[j], ring0[(j + 1) % 8], ring1[j], ring1[(j + 1) % 8]
            o.f.append([(a0, None, None), (a1, None, None), (b1, None, None)])
            o.f.append([(a0, None, None), (b1, None, None), (b0, None, None)])
        o.extra.append("s off")
        for zc, up in ((0.0, False), (length_cm, True)):
            cap = []
            for j in range(8):
                a = math.radians(twist + 45.0 * j)
                cap.append(o.add_v((SHAFT_R * math.cos(a), SHAFT_R * math.sin(a), zc)))
            for j in range(1, 7):
                tri = [cap[0], cap[j], cap[j + 1]] if up else [cap[0], cap[j + 1], cap[j]]
                o.f.append([(t, None, None) for t in tri])
        name = new_mesh(o.text())
        place(name, "Aluminium", translate(x, y0, z) @ rot_y(360.0 * rand()) @ Z_UP
              @ scale(0.01))

# The shared rail: a unit cylinder (radius 1, z in [0, 1], 32 segments, open ends) with
# `v/vt/vn` quads. Right handrail: an oval section (6 x 4.5 cm), so its normals need the
# inverse transpose of the matrix; wall rail: round, 4.4 cm.
o = Obj("rail: unit cylinder, 32 segments, shared by every rail segment")
o.extra = ["o Rail", "usemtl Copper", "s 1"]
SEG = 32
bot, top, nrm, uvb, uvt = [], [], [], [], []
for j in range(SEG):
    a = 2 * math.pi * j / SEG
    c, s = math.cos(a), math.sin(a)
    bot.append(o.add_v((c, s, 0.0)))
    top.append(o.add_v((c, s, 1.0)))
    nrm.append(o.add_vn((c, s, 0.0)))
for j in range(SEG + 1):
    uvb.append(o.add_vt((j / SEG, 0.0)))
    uvt.append(o.add_vt((j / SEG, 1.0)))
for j in range(SEG):
    j1 = (j + 1) % SEG
    o.f.append([(bot[j], uvb[j], nrm[j]), (bot[j1], uvb[j + 1], nrm[j1]),
                (top[j1], uvt[j + 1], nrm[j1]), (top[j], uvt[j], nrm[j])])
RAIL = new_mesh(o.text())


def rail_matrix(p0, p1, rx, ry):
    """Cylinder from p0 to p1 with semi-axes rx (horizontal) and ry (in the vertical plane)."""
    p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
    d = p1 - p0
    length = np.linalg.norm(d)
    ez = d / length
    ex = np.array([-1.0, 0.0, 0.0]) if abs(ez[0]) < 0.9 else np.array([0.0, 0.0, 1.0])
    ex = ex - ez * np.dot(ex, ez)
    ex /= np.linalg.norm(ex)
    ey = np.cross(ez, ex)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = ex * rx, ey * ry, ez * length, p0
    return m


Z_NEWEL_LO, Z_NEWEL_HI = 0.02, Z_TOP + 0.02
for seg in range(7):
    za = Z_NEWEL_LO + (Z_NEWEL_HI - Z_NEWEL_LO) * seg / 7
    zb = Z_NEWEL_LO + (Z_NEWEL_HI - Z_NEWEL_LO) * (seg + 1) / 7
    x = X_OPEN + 0.01
    place(RAIL, "Copper", rail_matrix((x, nosing_y(za) + RAIL_H, za),
                                      (x, nosing_y(zb) + RAIL_H, zb), 0.03, 0.0225))
X_WALLRAIL = X_WALL + 0.085
for seg in range(3):
    za = 0.25 - 4.1 * seg / 3
    zb = 0.25 - 4.1 * (seg + 1) / 3
    place(RAIL, "Copper", rail_matrix((X_WALLRAIL, nosing_y(za) + 0.86, za),
                                      (X_WALLRAIL, nosing_y(zb) + 0.86, zb), 0.022, 0.022))
# Wall rail brackets: brass blocks from the wall to under the rail (`v//vn`, unit cube, scaled).
for b in range(7):
    z = 0.1 - 0.58 * b
    y = nosing_y(z) + 0.86 - 0.022 - 0.03
    o = Obj("wall rail bracket %d" % b)
    write_box(o, (-1, -1, -1), (1, 1, 1), "vn")
    name = new_mesh(o.text())
    place(name, "Brass", translate((X_WALL + X_WALLRAIL) / 2 + 0.005, y, z) @ Z_UP
          @ scale((X_WALLRAIL - X_WALL) / 2, 0.012, 0.035))

# Newel posts (brass, `v/vt/vn` quads, modelled in metres from the floor up), wooden caps.
for label, z, y_foot, y_head in (("Bottom", Z_NEWEL_LO, -0.01, nosing_y(Z_NEWEL_LO) + 1.05),
                                 ("Top", Z_NEWEL_HI, -0.01, nosing_y(Z_NEWEL_HI) + 1.05)):
    o = Obj("newel post %s" % label)
    o.extra = ["o Newel%s" % label]
    hgt = y_head - y_foot
    write_box(o, (-0.05, -0.05, 0.0), (0.05, 0.05, hgt), "vtn", uv_dims=(0.3, 0.3, hgt),
              uv_off=(rand(), rand()), triangles=False)
    name = new_mesh(o.text())
    place(name, "Brass", translate(X_OPEN + 0.01, y_foot, z) @ rot_y(90.0) @ Z_UP)
    o = Obj("newel cap %s" % label)
    write_box(o, (-1, -1, -1), (1, 1, 1), "vn")
    name = new_mesh(o.text())
    place(name, "Wood", translate(X_OPEN + 0.01, y_head + 0.02, z) @ rot_y(45.0) @ Z_UP
          @ scale(0.06, 0.06, 0.025))

# Landing: one wooden slab (unit cube scaled).
o = Obj("landing")
write_box(o, (-1, -1, -1), (1, 1, 1), "vtn", uv_dims=(1.0, 1.1, 0.04), uv_off=(rand(), rand()))
name = new_mesh(o.text())
land_d = Z_TOP + 0.01 - (Z_BACK + 0.005)  # under the last tread's back by 1 cm, 1 mm lower
place(name, "Wood", translate(X_WALL + 0.035 + TREAD_W / 2, TOP - 0.001 - TREAD_T / 2,
                              Z_BACK + 0.005 + land_d / 2) @ rot_y(180.0) @ Z_UP
      @ scale(TREAD_W / 2, land_d / 2, TREAD_T / 2))

# Skirting along the left wall in front of the stairs (wood, `v/vt/vn`, cube scaled).
for b in range(5):
    z0, z1 = 3.0 - 0.6 * b, 3.0 - 0.6 * (b + 1) + 0.001
    if z1 < 0.0:
        z1 = 0.0
    o = Obj("skirting board %d" % b)
    write_box(o, (-1, -1, -1), (1, 1, 1), "vtn", uv_dims=(abs(z1 - z0), 0.015, 0.12),
              uv_off=(rand(), rand()))
    name = new_mesh(o.text())
    place(name, "Wood", translate(X_WALL + 0.0075, 0.055, (z0 + z1) / 2) @ rot_y(90.0) @ Z_UP
          @ scale(abs(z1 - z0) / 2, 0.0075 + 0.001, 0.065))

# Walls: panels of Blender's default plane ([-1, 1]^2, normal +z), `v/vt` quads (normals
# computed), turned to face the room. Left wall (x = X_WALL, facing +x): 4 x 5 panels; back
# wall (z = Z_BACK, facing +z): 4 x 2. Both 5 m high, so that no sky shows in the frame: a
# constant background next to an edge has pixels whose own samples do not vary but whose
# splatted value does (their neighbours' samples land on the edge), which makes block z-tests
# with per-pixel variances overconfident in small blocks.
plane = Obj("Blender default plane, v/vt")
plane_pts = [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)]
for p in plane_pts:
    plane.add_v(p)
for p in plane_pts:
    plane.add_vt(((p[0] + 1) / 2, (p[1] + 1) / 2))
plane.f.append([(1, 1, None), (2, 2, None), (3, 3, None), (4, 4, None)])
for r in range(5):
    for c in range(4):
        o = Obj("left wall panel %d.%d" % (r, c))
        o.v, o.vt, o.f = plane.v, plane.vt, plane.f
        name = new_mesh(o.text())
        zc = 3.0 - 2.0 * (c + 0.5)
        yc = 1.0 * (r + 0.5)
        place(name, "Wall", translate(X_WALL, yc, zc) @ rot_y(90.0) @ scale(1.0, 0.5, 1.0))
for r in range(2):
    for c in range(4):
        o = Obj("back wall panel %d.%d" % (r, c))
        o.v, o.vt, o.f = plane.v, plane.vt, plane.f
        name = new_mesh(o.text())
        place(name, "Wall", translate(X_WALL + 1.0 * (c + 0.5), 2.5 * (r + 0.5), Z_BACK)
              @ scale(0.5, 1.25, 1.0))

# Floor tiles, 0.5 m: one `v/vt/vn` quad each (normal written in the file), in a Z-up
# object space, some turned by a half turn, every third one with its u and every fifth with its
# v mirrored in the file (the bump map's dp/du or dp/dv then points the other way). Not turned
# by quarter turns: Mitsuba 3.9.1's bumpmap builds its tangent as normalize(dp/du - n (n . dp/du))
# from the world-space dp/du and the bumped normal in the *local* frame, which is 0/0 = NaN
# wherever the height's gradient is 0 and the world dp/du is along z (a quarter-turned tile),
# and roughplastic's half vector then makes the whole sample NaN. None under the stairs.
TILE = 0.5
for r in range(16):  # along z, from the back wall
    for c in range(8):  # along x
        x0, z0 = X_WALL + TILE * c, Z_BACK + TILE * r
        if x0 < X_OPEN and z0 + TILE <= NOSING + 0.001:
            continue  # under the stairs and the landing
        turn = 2 * int(2 * rand())
        mirror_u = (r * 8 + c) % 3 == 0
        mirror_v = (r * 8 + c) % 5 == 0
        o = Obj("floor tile %d.%d%s%s" % (r, c, ", u mirrored" if mirror_u else "",
                                          ", v mirrored" if mirror_v else ""))
        for p in plane_pts:
            o.add_v(p)
        for p in plane_pts:
            u, v = (p[0] + 1) / 2, (p[1] + 1) / 2
            o.add_vt((1 - u if mirror_u else u, 1 - v if mirror_v else v))
        nid = o.add_vn((0, 0, 1))
        o.f.append([(k, k, nid) for k in (1, 2, 3, 4)])
        name = new_mesh(o.text())
        place(name, "Tiles", translate(x0 + TILE / 2, 0.0, z0 + TILE / 2)
              @ rot_y(90.0 * turn) @ Z_UP @ scale(TILE / 2))


# ---------------------------------------------------------------------------------------------
# Textures: 64x64 8-bit PNGs, periodic in u and v (the bitmaps repeat).
def write_png(path, img):
    img = np.ascontiguousarray(img, np.uint8)
    h, w = img.shape[:2]
    colour_type = 0 if img.ndim == 2 else 2
    raw = b"".join(b"\x00" + img[y].tobytes() for y in range(h))

    def chunk(tag, data):
        return (struct.pack(">I", len(data)) + tag + data
                + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF))

    data = (b"\x89PNG\r\n\x1a\n"
            + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, colour_type, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))
    with open(path, "wb") as f:
        f.write(data)


def write_textures():
    S = 64
    uu, vv = np.meshgrid((np.arange(S) + 0.5) / S, (np.arange(S) + 0.5) / S)
    tau = 2 * np.pi

    # wood.png (sRGB): growth rings running along u (the tread's width), wavy, with fine streaks.
    rings = 7 * vv + 0.25 * np.sin(tau * (2 * uu + 0.3)) + 0.12 * np.sin(tau * (5 * uu + 3 * vv))
    t = 0.5 + 0.5 * np.cos(tau * rings)
    t = t ** 3 + 0.08 * np.sin(tau * (29 * vv + uu))
    light = np.array([0.78, 0.55, 0.33])
    dark = np.array([0.45, 0.27, 0.13])
    wood = light + (dark - light) * np.clip(t, 0, 1)[..., None]
    write_png(os.path.join(TEXTURES, "wood.png"), np.round(255 * np.clip(wood, 0, 1)))

    # tiles-height.png (linear, read raw): grout lines (0) at the tile's border, a 3-texel bevel up
    # to the tile's face (0.75), and on the face a gentle pattern that is not symmetric under a
    # quarter turn or a mirror, so a wrong bump orientation changes the image.
    edge = np.minimum(np.minimum(uu, 1 - uu), np.minimum(vv, 1 - vv)) * S  # texels from the border
    bevel = np.clip((edge - 2.0) / 3.0, 0, 1)
    face = 0.75 + 0.12 * np.sin(tau * (2 * uu + vv)) + 0.06 * np.sin(tau * 3 * uu)
    height = bevel * face
    write_png(os.path.join(TEXTURES, "tiles-height.png"), np.round(255 * np.clip(height, 0, 1)))

    # tiles.png (sRGB): warm grey stone with a darker vein and an off-centre light patch, grout
    # dark grey, matching the height map's border.
    vein = np.exp(-((uu - 0.8 * vv - 0.15) ** 2) / 0.004)
    patch = np.exp(-((uu - 0.3) ** 2 + (vv - 0.7) ** 2) / 0.03)
    stone = np.array([0.72, 0.67, 0.58]) * (0.92 + 0.06 * np.sin(tau * (3 * uu + 2 * vv)))[..., None]
    stone = stone * (1 - 0.35 * vein)[..., None] + 0.12 * patch[..., None]
    grout = np.array([0.33, 0.32, 0.31])
    w = bevel[..., None]
    tiles = grout + (stone - grout) * w
    write_png(os.path.join(TEXTURES, "tiles.png"), np.round(255 * np.clip(tiles, 0, 1)))


# ---------------------------------------------------------------------------------------------
# Camera: Mitsuba's lookat written out as a matrix (columns left, up, forward, origin).
def look_at(origin, target, up):
    origin, target, up = (np.asarray(a, float) for a in (origin, target, up))
    d = target - origin
    d /= np.linalg.norm(d)
    left = np.cross(up, d)
    left /= np.linalg.norm(left)
    new_up = np.cross(d, left)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = left, new_up, d, origin
    return m


CAMERA = look_at((1.5, 1.55, 2.4), (-0.5, 1.2, -1.8), (0, 1, 0))
FOV = 70.0

LIGHTS = [  # (matrix of the rectangle [-1, 1]^2 with normal +z, radiance)
    (translate(-0.5, 3.9, -4.3) @ rot_x(90.0) @ scale(0.5, 0.35, 1.0), (9.0, 8.4, 7.4)),
    (translate(2.9, 1.8, -1.6) @ rot_y(-90.0) @ scale(0.45, 0.6, 1.0), (7.0, 7.6, 8.4)),
]

materials = """    <bsdf type="twosided" id="Wood">
        <bsdf type="roughplastic">
            <string name="distribution" value="ggx"/>
            <float name="alpha" value="0.12"/>
            <float name="int_ior" value="1.5"/>
            <texture type="bitmap" name="diffuse_reflectance">
                <string name="filename" value="staircase/textures/wood.png"/>
                <string name="filter_type" value="bilinear"/>
            </texture>
        </bsdf>
    </bsdf>
    <bsdf type="twosided" id="Paint">
        <bsdf type="roughplastic">
            <string name="distribution" value="ggx"/>
            <float name="alpha" value="0.3"/>
            <float name="int_ior" value="1.5"/>
            <rgb name="diffuse_reflectance" value="0.22, 0.33, 0.42"/>
        </bsdf>
    </bsdf>
    <bsdf type="bumpmap" id="Tiles">
        <texture type="bitmap">
            <string name="filename" value="staircase/textures/tiles-height.png"/>
            <boolean name="raw" value="true"/>
        </texture>
        <float name="scale" value="0.008"/>
        <bsdf type="roughplastic">
            <string name="distribution" value="ggx"/>
            <float name="alpha" value="0.2"/>
            <float name="int_ior" value="1.5"/>
            <texture type="bitmap" name="diffuse_reflectance">
                <string name="filename" value="staircase/textures/tiles.png"/>
            </texture>
        </bsdf>
    </bsdf>
    <bsdf type="roughconductor" id="Aluminium">
        <string name="material" value="Al"/>
        <string name="distribution" value="ggx"/>
        <float name="alpha" value="0.25"/>
    </bsdf>
    <bsdf type="roughconductor" id="Copper">
        <string name="material" value="Cu"/>
        <string name="distribution" value="ggx"/>
        <float name="alpha" value="0.2"/>
    </bsdf>
    <bsdf type="roughconductor" id="Brass">
        <string name="distribution" value="ggx"/>
        <float name="alpha" value="0.3"/>
        <rgb name="eta" value="0.444, 0.527, 1.094"/>
        <rgb name="k" value="3.695, 2.765, 1.829"/>
    </bsdf>
    <bsdf type="diffuse" id="Wall">
        <rgb name="reflectance" value="0.7, 0.68, 0.62"/>
    </bsdf>
    <bsdf type="diffuse" id="Light">
        <rgb name="reflectance" value="0"/>
    </bsdf>
"""

HEADER = """<?xml version="1.0" encoding="utf-8"?>
<!-- A staircase laid out as Benedikt Bitterli's rendering resources are after conversion to
     Mitsuba 3: %d OBJ shapes from %d files (staircase/models/MeshNNN.obj), each placed by a 4x4
     matrix as exporters write them (Blender's Z-up objects turned to Y-up, unit cubes scaled,
     centimetre models scaled by 0.01, mirrored stringers), one rail file shared by ten shapes,
     and materials declared once and used by ref: two-sided textured rough plastic (wood), a
     painted one, a bump-mapped textured rough plastic floor (tiles turned and uv-mirrored), rough
     conductors by name (Al, Cu) and by eta/k (brass), a diffuse wall. Lit by two rectangle
     lights and a dim sky; path tracing at max_depth 65 as in Bitterli's scenes; the default
     (gaussian) film filter. Written by staircase/make_staircase.py (which describes every
     file); edit that, not this. -->
<scene version="3.0.0">
    <default name="spp" value="64"/>
    <default name="max_depth" value="65"/>
    <default name="width" value="160"/>
    <default name="height" value="120"/>
    <integrator type="path">
        <integer name="max_depth" value="$max_depth"/>
    </integrator>
    <sensor type="perspective">
        <float name="fov" value="%s"/>
        <transform name="to_world">
            <matrix value="%s"/>
        </transform>
        <sampler type="independent">
            <integer name="sample_count" value="$spp"/>
        </sampler>
        <film type="hdrfilm">
            <integer name="width" value="$width"/>
            <integer name="height" value="$height"/>
            <string name="file_format" value="openexr"/>
            <string name="pixel_format" value="rgb"/>
        </film>
    </sensor>
"""


def scene_xml():
    out = [HEADER % (len(shapes), len(files), fmt(FOV), matrix_str(CAMERA))]
    out.append(materials)
    for name, material, m in shapes:
        out.append('    <shape type="obj">\n'
                   '        <string name="filename" value="staircase/models/%s"/>\n'
                   '        <transform name="to_world">\n'
                   '            <matrix value="%s"/>\n'
                   '        </transform>\n'
                   '        <ref id="%s"/>\n'
                   '    </shape>\n' % (name, matrix_str(m), material))
    for m, radiance in LIGHTS:
        out.append('    <shape type="rectangle">\n'
                   '        <transform name="to_world">\n'
                   '            <matrix value="%s"/>\n'
                   '        </transform>\n'
                   '        <ref id="Light"/>\n'
                   '        <emitter type="area">\n'
                   '            <rgb name="radiance" value="%s"/>\n'
                   '        </emitter>\n'
                   '    </shape>\n' % (matrix_str(m), ", ".join(fmt(c) for c in radiance)))
    out.append('    <emitter type="constant">\n'
               '        <rgb name="radiance" value="0.04, 0.045, 0.055"/>\n'
               '    </emitter>\n'
               '</scene>\n')
    return "".join(out)


def main():
    os.makedirs(MODELS, exist_ok=True)
    os.makedirs(TEXTURES, exist_ok=True)
    write_textures()
    for old in os.listdir(MODELS):
        if old.endswith(".obj") and old not in files:
            os.remove(os.path.join(MODELS, old))
    for name, text in files.items():
        with open(os.path.join(MODELS, name), "w", newline="\n") as f:
            f.write(text)
    with open(os.path.join(SCENES, "staircase.xml"), "w", newline="\n") as f:
        f.write(scene_xml())
    total = sum(len(t) for t in files.values())
    print("wrote scenes/staircase.xml: %d shapes, %d OBJ files (%d bytes), 3 textures"
          % (len(shapes) + len(LIGHTS), len(files), total))


if __name__ == "__main__":
    main()
