#!/usr/bin/env python3
"""Writes the scenes of the instancing memory measurement (issue 20: 1,000 instances of a
100k-triangle mesh against one copy): a bumpy latitude-longitude sphere of 100,352 triangles
(225 rings of 224 vertices; 448 zero-area pole triangles) as a binary PLY, and three Mitsuba XML
scenes that render it under a constant environment at 128x128, 4 spp:

    one.xml       the mesh as a plain shape
    group1.xml    a shapegroup holding the mesh, placed by one instance
    group1000.xml the same shapegroup placed by 1,000 instances (a 10 x 10 x 10 grid, each
                  turned differently)

Plain Python, no packages.

    python3 references/make_instances_scene.py /tmp/instances
    for s in one group1 group1000; do /usr/bin/time -f "$s %M KB %e s" \\
        target/release/pt render /tmp/instances/$s.xml -o /tmp/i.exr --quiet; done
    for s in one group1 group1000; do /usr/bin/time -f "$s %M KB %e s" \\
        .venv/bin/mitsuba -m scalar_rgb -o /tmp/i.exr /tmp/instances/$s.xml; done
"""

import math
import os
import struct
import sys

RINGS = 225
SEGMENTS = 224

HEAD = """<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="4"/></integrator>
    <sensor type="perspective"><float name="fov" value="50"/>
        <transform name="to_world"><lookat origin="%s" target="%s" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="4"/></sampler>
        <film type="hdrfilm"><integer name="width" value="128"/><integer name="height" value="128"/><rfilter type="box"/></film>
    </sensor>
    <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
"""
MESH = """<shape type="ply"><string name="filename" value="bumpy.ply"/><bsdf type="diffuse"/></shape>"""


def bump(x, y, z):
    return 0.08 * math.sin(7 * x) * math.sin(9 * y) * math.sin(5 * z)


def write_ply(path):
    verts = []
    for i in range(RINGS):
        theta = math.pi * i / (RINGS - 1)
        for j in range(SEGMENTS):
            phi = 2 * math.pi * j / SEGMENTS
            x, y, z = math.sin(theta) * math.cos(phi), math.cos(theta), math.sin(theta) * math.sin(phi)
            r = 1 + bump(x, y, z)
            verts.append((r * x, r * y, r * z))
    faces = []
    for i in range(RINGS - 1):
        for j in range(SEGMENTS):
            a, b = i * SEGMENTS + j, i * SEGMENTS + (j + 1) % SEGMENTS
            c, d = a + SEGMENTS, b + SEGMENTS
            faces.append((a, c, b))
            faces.append((b, c, d))
    with open(path, "wb") as f:
        f.write(("ply\nformat binary_little_endian 1.0\nelement vertex %d\n"
                 "property float x\nproperty float y\nproperty float z\n"
                 "element face %d\nproperty list uchar int vertex_indices\nend_header\n"
                 % (len(verts), len(faces))).encode())
        f.write(b"".join(struct.pack("<3f", *v) for v in verts))
        f.write(b"".join(struct.pack("<B3i", 3, *t) for t in faces))
    return len(faces)


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "/tmp/instances"
    os.makedirs(out, exist_ok=True)
    n = write_ply(os.path.join(out, "bumpy.ply"))
    near = HEAD % ("0, 1, 4", "0, 0, 0")
    with open(os.path.join(out, "one.xml"), "w") as f:
        f.write(near + "    " + MESH + "\n</scene>\n")
    group = '    <shape type="shapegroup" id="g">' + MESH + "</shape>\n"
    with open(os.path.join(out, "group1.xml"), "w") as f:
        f.write(near + group + '    <shape type="instance"><ref id="g"/></shape>\n</scene>\n')
    far = HEAD % ("30, 24, 40", "13.5, 13.5, 13.5")
    with open(os.path.join(out, "group1000.xml"), "w") as f:
        f.write(far + group)
        for k in range(1000):
            x, y, z = k % 10, (k // 10) % 10, k // 100
            f.write('    <shape type="instance"><ref id="g"/><transform name="to_world">'
                    '<rotate y="1" angle="%d"/><translate value="%g, %g, %g"/></transform></shape>\n'
                    % ((37 * k) % 360, 3 * x, 3 * y, 3 * z))
        f.write("</scene>\n")
    print(f"{out}: bumpy.ply ({n} triangles), one.xml, group1.xml, group1000.xml")


if __name__ == "__main__":
    main()
