#!/usr/bin/env python3
"""Writes the scene of the README's peak-memory comparison: a bumpy latitude-longitude sphere
of 1,001,112 triangles (708 rings of 708 vertices; the 1,416 triangles at the poles have zero
area and are skipped by pt) as an OBJ, and a Mitsuba XML scene that renders it under a constant
environment at 256x256 and 16 spp, max_depth 8. Plain Python, no packages.

    python3 references/make_memory_scene.py /tmp/memory        # writes sphere.obj, scene.xml
    /usr/bin/time -f "%M KB" target/release/pt render /tmp/memory/scene.xml -o /tmp/m.exr
    /usr/bin/time -f "%M KB" .venv/bin/mitsuba -m llvm_ad_rgb -o /tmp/m.exr /tmp/memory/scene.xml
"""

import math
import os
import sys

RINGS = 708  # latitude rings, poles included
SEGMENTS = 708  # vertices per ring (the seam wraps around; no duplicated column)

SCENE = """<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="8"/></integrator>
    <sensor type="perspective"><float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 1, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="16"/></sampler>
        <film type="hdrfilm"><integer name="width" value="256"/><integer name="height" value="256"/><rfilter type="box"/></film>
    </sensor>
    <shape type="obj"><string name="filename" value="sphere.obj"/><bsdf type="diffuse"/></shape>
    <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
</scene>
"""


def bump(x, y, z):
    """Radial displacement of the unit direction (x, y, z): three octaves of products of sines
    (the same as the traversal bench's displaced sphere)."""
    return (0.06 * math.sin(7 * x) * math.sin(9 * y) * math.sin(5 * z)
            + 0.02 * math.sin(31 * x + 3) * math.sin(27 * z)
            + 0.005 * math.sin(97 * y) * math.sin(89 * x + 1))


def mesh():
    """The sphere's vertices (x, y, z) and triangles (0-based, counter-clockwise seen from
    outside)."""
    verts = []
    for j in range(RINGS):
        theta = math.pi * j / (RINGS - 1)
        for i in range(SEGMENTS):
            phi = 2 * math.pi * i / SEGMENTS
            x, y, z = math.sin(theta) * math.cos(phi), math.cos(theta), math.sin(theta) * math.sin(phi)
            r = 1 + bump(x, y, z)
            verts.append((r * x, r * y, r * z))
    faces = []
    for j in range(RINGS - 1):
        for i in range(SEGMENTS):
            # a, b along the ring, c, d one ring further south: (a, b, c) and (b, d, c).
            a = j * SEGMENTS + i
            b = j * SEGMENTS + (i + 1) % SEGMENTS
            c, d = a + SEGMENTS, b + SEGMENTS
            faces += [(a, b, c), (b, d, c)]
    return verts, faces


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "."
    os.makedirs(out, exist_ok=True)
    verts, faces = mesh()
    lines = [f"v {x:.6f} {y:.6f} {z:.6f}\n" for x, y, z in verts]
    # OBJ indices count from 1.
    lines += [f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces]
    with open(os.path.join(out, "sphere.obj"), "w") as f:
        f.writelines(lines)
    with open(os.path.join(out, "scene.xml"), "w") as f:
        f.write(SCENE)
    print(f"wrote {out}/sphere.obj ({RINGS * SEGMENTS} vertices, {2 * (RINGS - 1) * SEGMENTS} triangles) and {out}/scene.xml")


if __name__ == "__main__":
    main()
