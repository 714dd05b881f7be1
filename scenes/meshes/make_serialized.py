"""Writes scenes/meshes/preview.serialized, the meshes of scenes/serialized.xml, in Mitsuba's
serialized format (version 4: per mesh the u16 identifier 0x041C and u16 version, then a zlib
stream of u32 flags, the NUL-terminated name, u64 vertex and triangle counts, the arrays, u32
indices; after the meshes a table of u64 offsets and the u32 mesh count).

Three meshes, in the layout of Mitsuba's matpreview scene (0: backdrop, 1: object inside,
2: object outside), each exercising another part of the format:
  0  "backdrop": a curved sheet (a floor bending up into a wall), single precision, uvs, no
     normals (the readers compute them);
  1  "core": a low-polygon sphere, double precision, no normals, no uvs;
  2  "shell": a UV sphere of radius 1 with a band cut out, single precision, analytic normals
     and uvs (u along the azimuth, v from pole to pole).
Deterministic; plain Python (struct, zlib).
"""
import math
import os
import struct
import zlib

F_NORMALS, F_UVS, F_SINGLE, F_DOUBLE = 0x1, 0x2, 0x1000, 0x2000


def mesh_record(name, positions, indices, normals=None, uvs=None, double=False):
    flags = (F_DOUBLE if double else F_SINGLE) | (F_NORMALS if normals else 0) | (F_UVS if uvs else 0)
    real = "d" if double else "f"
    out = struct.pack("<I", flags) + name.encode() + b"\0"
    out += struct.pack("<QQ", len(positions), len(indices))
    for arr in (positions, normals, uvs):
        if arr:
            for v in arr:
                out += struct.pack("<%d%s" % (len(v), real), *v)
    for t in indices:
        out += struct.pack("<3I", *t)
    return struct.pack("<HH", 0x041C, 4) + zlib.compress(out, 9)


def grid(nu, nv, point):
    """Vertices point(i / nu, j / nv) and two triangles per cell, counter-clockwise."""
    verts = [point(i / nu, j / nv) for j in range(nv + 1) for i in range(nu + 1)]
    tris = []
    for j in range(nv):
        for i in range(nu):
            a = j * (nu + 1) + i
            b, c, d = a + 1, a + nu + 2, a + nu + 1
            tris += [(a, b, c), (a, c, d)]
    return verts, tris


def backdrop():
    # A floor z = 0 for y < 0 that bends up (a quarter circle of radius 0.5) into a wall at
    # y = 0.5; x in [-1, 1]. uv = (x, arc length) normalised.
    def point(s, t):
        x = 2 * s - 1
        arc = 3.0 * t  # 0..3: floor 1.5, bend 0.785, wall the rest
        if arc < 1.5:
            y, z = -1.5 + arc, 0.0
        elif arc < 1.5 + math.pi / 4:
            a = (arc - 1.5) / 0.5
            y, z = 0.5 * math.sin(a), 0.5 - 0.5 * math.cos(a)
        else:
            y, z = 0.5, 0.5 + (arc - 1.5 - math.pi / 4)
        return (x, y, z)
    verts, tris = grid(8, 24, point)
    uvs = [(0.5 * (p[0] + 1), j / 24) for j in range(25) for p in verts[j * 9:(j + 1) * 9]]
    return mesh_record("backdrop", verts, tris, uvs=uvs)


def sphere(nu, nv, cut=None):
    def point(s, t):
        phi, theta = 2 * math.pi * s, math.pi * t
        return (math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta))
    verts, tris = grid(nu, nv, point)
    # With u along the azimuth and v from the +z pole down, the grid's cells wind clockwise
    # seen from outside: reverse them so that the spheres face out.
    tris = [(a, c, b) for a, b, c in tris]
    if cut:
        # Drop the triangles of rows cut[0] <= j < cut[1] (a band around the equator).
        tris = [t for k, t in enumerate(tris) if not (cut[0] <= (k // 2) // nu < cut[1])]
    return verts, tris


def main():
    core_v, core_t = sphere(12, 6)
    shell_v, shell_t = sphere(48, 24, cut=(11, 13))
    shell_uv = [(i / 48, j / 24) for j in range(25) for i in range(49)]
    records = [
        backdrop(),
        mesh_record("core", core_v, core_t, double=True),
        mesh_record("shell", shell_v, shell_t, normals=shell_v, uvs=shell_uv),
    ]
    data, offsets = b"", []
    for r in records:
        offsets.append(len(data))
        data += r
    data += b"".join(struct.pack("<Q", o) for o in offsets) + struct.pack("<I", len(records))
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "preview.serialized")
    with open(path, "wb") as f:
        f.write(data)
    print(path, len(data), "bytes")


if __name__ == "__main__":
    main()
