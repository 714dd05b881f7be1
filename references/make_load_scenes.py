#!/usr/bin/env python3
"""Writes the scenes of the mesh-loading benchmark (references/performance.md, "Loading meshes"):
the bumpy sphere of make_memory_scene.py (1,001,112 triangles, 501,264 vertices) as a binary
little-endian PLY (positions only) and as a Mitsuba serialized file (version 4, single
precision, positions only), each with a scene that loads it and renders 1 sample of an 8x8
film, so that the time is the file's reading, the normals and the BVH build. Plain Python.

    python3 references/make_load_scenes.py /tmp/load      # sphere.ply, sphere.serialized, *.xml
    farm-bench -n 5 -- target/release/pt info /tmp/load/ply.xml
    /usr/bin/time -f "%e s %M KB" target/release/pt render /tmp/load/ply.xml -o /tmp/l.exr -q
    /usr/bin/time -f "%e s %M KB" .venv/bin/python references/load_mitsuba.py /tmp/load/ply.xml
"""

import os
import struct
import sys
import zlib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from make_memory_scene import mesh  # noqa: E402

SCENE = """<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="2"/></integrator>
    <sensor type="perspective"><float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 1, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="1"/></sampler>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film>
    </sensor>
    <shape type="{kind}"><string name="filename" value="sphere.{kind}"/><bsdf type="diffuse"/></shape>
    <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
</scene>
"""


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "."
    os.makedirs(out, exist_ok=True)
    verts, faces = mesh()
    pos = struct.pack("<%df" % (3 * len(verts)), *[c for v in verts for c in v])
    idx = struct.pack("<%dI" % (3 * len(faces)), *[i for f in faces for i in f])
    head = ("ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\n"
            "property float y\nproperty float z\nelement face %d\n"
            "property list uchar int vertex_indices\nend_header\n" % (len(verts), len(faces)))
    face_records = b"".join(b"\x03" + idx[12 * k:12 * k + 12] for k in range(len(faces)))
    with open(os.path.join(out, "sphere.ply"), "wb") as f:
        f.write(head.encode() + pos + face_records)
    payload = struct.pack("<I", 0x1000) + b"sphere\0" + struct.pack("<QQ", len(verts), len(faces)) + pos + idx
    with open(os.path.join(out, "sphere.serialized"), "wb") as f:
        f.write(struct.pack("<HH", 0x041C, 4) + zlib.compress(payload, 6) + struct.pack("<QI", 0, 1))
    for kind in ("ply", "serialized"):
        with open(os.path.join(out, kind + ".xml"), "w") as f:
            f.write(SCENE.format(kind=kind))
    print(f"wrote {out}: sphere.ply, sphere.serialized ({len(verts)} vertices, {len(faces)} triangles), ply.xml, serialized.xml")


if __name__ == "__main__":
    main()
