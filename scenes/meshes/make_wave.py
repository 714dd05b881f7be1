"""Writes scenes/meshes/wave.obj: a uv-mapped, non-planar sheet for scenes/texture-bitmap.xml.

The sheet spans x, y in [-1, 1] with height z = 0.18 sin(1.5 pi x) cos(0.5 pi y) (a saddle-like
wave), 24 x 18 quads split into triangles, with analytic unit normals (`vn`, the +z side is the
front) and texture coordinates written in the OBJ convention (`vt` v = 0 at the bottom,
y = -1): Mitsuba's OBJ loader flips v by default (flip_tex_coords = true), and so does pt, so
the image's first row (v = 0 after the flip) lands at y = +1 and the texture appears upright.
u runs with x but is stretched (u = ((x + 1) / 2)^1.3), so the texel grid is not uniform over
the sheet. Deterministic; plain Python.
"""
import math
import os

NX, NY = 24, 18
A = 0.18


def height(x, y):
    return A * math.sin(1.5 * math.pi * x) * math.cos(0.5 * math.pi * y)


def normal(x, y):
    dzdx = A * 1.5 * math.pi * math.cos(1.5 * math.pi * x) * math.cos(0.5 * math.pi * y)
    dzdy = -A * 0.5 * math.pi * math.sin(1.5 * math.pi * x) * math.sin(0.5 * math.pi * y)
    n = (-dzdx, -dzdy, 1.0)
    l = math.sqrt(sum(c * c for c in n))
    return tuple(c / l for c in n)


lines = ["# wave.obj: written by scenes/meshes/make_wave.py (uv-mapped wavy sheet)"]
for j in range(NY + 1):
    for i in range(NX + 1):
        x, y = -1 + 2 * i / NX, -1 + 2 * j / NY
        lines.append(f"v {x:.6f} {y:.6f} {height(x, y):.6f}")
for j in range(NY + 1):
    for i in range(NX + 1):
        lines.append(f"vt {(i / NX) ** 1.3:.6f} {j / NY:.6f}")
for j in range(NY + 1):
    for i in range(NX + 1):
        x, y = -1 + 2 * i / NX, -1 + 2 * j / NY
        lines.append("vn {:.6f} {:.6f} {:.6f}".format(*normal(x, y)))


def idx(i, j):
    return j * (NX + 1) + i + 1


for j in range(NY):
    for i in range(NX):
        a, b, c, d = idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)
        lines.append(f"f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}")
        lines.append(f"f {a}/{a}/{a} {c}/{c}/{c} {d}/{d}/{d}")
out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "wave.obj")
with open(out, "w") as f:
    f.write("\n".join(lines) + "\n")
print("wrote", out)
