"""Writes the PLY meshes of scenes/ply.xml:

- scenes/meshes/torus.ply: binary little endian; a torus (major radius 1, minor 0.35, 48 x 24
  quads as triangles) with analytic normals, uvs (u around the ring, v around the tube) and
  float vertex colours red/green/blue (a hue wheel around the ring), for a `mesh_attribute`
  texture on `vertex_color`;
- scenes/meshes/pedestal.ply: ascii; a hexagonal prism without normals (the readers compute
  them after to_world) whose triangles carry a face attribute `shade_x` (`face_shade`), 0.2 on
  the sides and 0.8 on the caps.

Deterministic; plain Python (struct).
"""
import colorsys
import math
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))


def torus():
    nu, nv, R, r = 48, 24, 1.0, 0.35
    verts, faces = [], []
    for j in range(nv + 1):
        for i in range(nu + 1):
            u, v = i / nu, j / nv
            phi, theta = 2 * math.pi * u, 2 * math.pi * v
            n = (math.cos(theta) * math.cos(phi), math.cos(theta) * math.sin(phi), math.sin(theta))
            p = ((R + r * math.cos(theta)) * math.cos(phi), (R + r * math.cos(theta)) * math.sin(phi), r * math.sin(theta))
            c = colorsys.hsv_to_rgb(u, 0.8, 0.9)
            verts.append(p + n + (u, v) + c)
    for j in range(nv):
        for i in range(nu):
            a = j * (nu + 1) + i
            b, c, d = a + 1, a + nu + 2, a + nu + 1
            faces += [(a, b, c), (a, c, d)]
    head = ("ply\nformat binary_little_endian 1.0\ncomment torus for scenes/ply.xml\n"
            "element vertex %d\n" % len(verts)
            + "".join("property float %s\n" % n for n in ("x", "y", "z", "nx", "ny", "nz", "u", "v", "red", "green", "blue"))
            + "element face %d\nproperty list uchar int vertex_indices\nend_header\n" % len(faces))
    body = b"".join(struct.pack("<11f", *v) for v in verts)
    body += b"".join(struct.pack("<B3i", 3, *f) for f in faces)
    with open(os.path.join(HERE, "torus.ply"), "wb") as f:
        f.write(head.encode() + body)


def pedestal():
    k = 6
    ring = [(math.cos(2 * math.pi * i / k), math.sin(2 * math.pi * i / k)) for i in range(k)]
    verts = [(x, y, 0.0) for x, y in ring] + [(x, y, 1.0) for x, y in ring] + [(0, 0, 0.0), (0, 0, 1.0)]
    faces = []
    for i in range(k):
        j = (i + 1) % k
        faces += [((i, j, k + j), 0.2), ((i, k + j, k + i), 0.2)]
        faces += [((2 * k, j, i), 0.8), ((2 * k + 1, k + i, k + j), 0.8)]
    lines = ["ply", "format ascii 1.0", "comment pedestal for scenes/ply.xml",
             "element vertex %d" % len(verts), "property float x", "property float y", "property float z",
             "element face %d" % len(faces), "property list uchar int vertex_indices", "property float shade_x",
             "end_header"]
    lines += ["%g %g %g" % v for v in verts]
    lines += ["3 %d %d %d %g" % (t + (s,)) for t, s in faces]
    with open(os.path.join(HERE, "pedestal.ply"), "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    torus()
    pedestal()
