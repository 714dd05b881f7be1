"""Writes the signed distance grids of scenes/sdfgrid.xml, in Mitsuba's `.vol` format
(`VOL`, version 3, encoding 1 = float32, x/y/z resolution, 1 channel, a bounding box, then the
values x fastest; see crates/pt-scene/src/volgrid.rs):

- scenes/meshes/knot.vol: a torus (major radius 0.3, minor 0.1 in the unit cube) twisted into
  a wave, unioned with a small sphere above it: curved, with thin parts a few voxels across;
- scenes/meshes/blob.vol: a rounded box carved by a sphere: flat faces, edges and a concave
  bowl, where per-voxel (analytic) normals show their facets.

Both 28^3 samples: Mitsuba 3.9.1 mishandles grids with unequal resolutions (no or far-side
hits, measured), so the references use cubic grids. Distances are in object units of the unit
cube (the shape's to_world scales them with the grid). Deterministic; plain Python (struct).
"""
import math
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
N = 28


def knot(x, y, z):
    cx, cy, cz = x - 0.5, y - 0.45, z - 0.5
    # The ring lies in the xz plane and waves up and down three times around.
    phi = math.atan2(cz, cx)
    ring = math.hypot(cx, cz) - 0.3
    torus = math.hypot(ring, cy - 0.06 * math.sin(3 * phi)) - 0.1
    sphere = math.dist((x, y, z), (0.5, 0.78, 0.5)) - 0.13
    return min(torus, sphere)


def blob(x, y, z):
    q = [abs(c - 0.5) - 0.32 for c in (x, y, z)]
    outside = math.sqrt(sum(max(c, 0.0) ** 2 for c in q))
    box = outside + min(max(q), 0.0) - 0.08
    bowl = math.dist((x, y, z), (0.5, 1.0, 0.5)) - 0.35
    return max(box, -bowl)


def write(name, f):
    values = [f(i / (N - 1), j / (N - 1), k / (N - 1))
              for k in range(N) for j in range(N) for i in range(N)]
    data = b"VOL" + bytes([3]) + struct.pack("<5i", 1, N, N, N, 1)
    data += struct.pack("<6f", 0, 0, 0, 1, 1, 1)
    data += struct.pack(f"<{len(values)}f", *values)
    path = os.path.join(HERE, name)
    tmp = path + ".tmp"
    with open(tmp, "wb") as out:
        out.write(data)
    os.replace(tmp, path)


if __name__ == "__main__":
    write("knot.vol", knot)
    write("blob.vol", blob)
