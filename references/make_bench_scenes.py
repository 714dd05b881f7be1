#!/usr/bin/env python3
"""Writes the generated scenes of the benchmark suite (references/bench.py): the ones too big
to keep in the repository, written the way public scenes are (mesh files beside the XML, a
light of the usual kinds, the default or a tent filter). Deterministic; numpy for the meshes.

    .venv/bin/python references/make_bench_scenes.py target/bench/scenes

Scenes (each `NAME.xml` with its data files):

- mesh-100k: a bumpy sphere of 100,352 triangles as an OBJ file (positions, normals), in rough
  plastic on a floor, under a rectangle light; the default gaussian filter.
- mesh-1m: the bumpy sphere at 1,001,112 triangles as a binary PLY (positions only: the
  readers compute vertex normals), a rough conductor under the environment map of
  scenes/textures/sky.exr; tent filter.
- mesh-5m: at 5,000,000 triangles as a Mitsuba serialized file (version 4, positions only),
  diffuse, lit by a sphere light; box filter.
- instances: 1,000 instances of a 100k-triangle shapegroup (the PLY of mesh-100k's sphere),
  each turned and coloured by its group, under a constant sky and a rectangle light.
- many-lights: 144 small sphere lights of four colours over a plane with rough plastic and
  conductor objects.
- street (not in the suite): 64 sphere lamps along a street, where choosing lights by distance
  matters.
"""

import math
import os
import struct
import sys
import zlib

import numpy as np

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def sphere(rings, segments):
    """A latitude-longitude sphere with bumps: vertices (n, 3) float32 and triangles (m, 3)
    uint32, counter-clockwise seen from outside; zero-area pole triangles left out."""
    theta = np.pi * np.arange(rings) / (rings - 1)
    phi = 2 * np.pi * np.arange(segments) / segments
    t, p = np.meshgrid(theta, phi, indexing="ij")
    x, y, z = np.sin(t) * np.cos(p), np.cos(t), np.sin(t) * np.sin(p)
    r = 1 + 0.08 * np.sin(7 * x) * np.sin(9 * y) * np.sin(5 * z)
    verts = np.stack([r * x, r * y, r * z], axis=-1).reshape(-1, 3).astype(np.float32)
    j, i = np.meshgrid(np.arange(rings - 1), np.arange(segments), indexing="ij")
    a = j * segments + i
    b = j * segments + (i + 1) % segments
    c, d = a + segments, b + segments
    tris = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3),
                           np.stack([b, d, c], -1).reshape(-1, 3)])
    # Rows 0 and rings-1 are the poles (all their vertices coincide).
    first_row = tris // segments
    keep = ~((first_row == 0).all(axis=1) | (first_row == rings - 1).all(axis=1))
    tris = tris[keep]
    area = np.linalg.norm(np.cross(verts[tris[:, 1]] - verts[tris[:, 0]],
                                   verts[tris[:, 2]] - verts[tris[:, 0]]), axis=1)
    return verts, tris[area > 0].astype(np.uint32)


def vertex_normals(verts, tris):
    n = np.zeros_like(verts, dtype=np.float64)
    fn = np.cross(verts[tris[:, 1]] - verts[tris[:, 0]], verts[tris[:, 2]] - verts[tris[:, 0]])
    for k in range(3):
        np.add.at(n, tris[:, k], fn)
    return (n / np.linalg.norm(n, axis=1, keepdims=True)).astype(np.float32)


def atomic_write(path, data):
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(data)
    os.replace(tmp, path)


def write_obj(path, verts, tris):
    n = vertex_normals(verts, tris)
    lines = ["# bumpy sphere, %d triangles" % len(tris), "o sphere"]
    lines += ["v %.6f %.6f %.6f" % tuple(v) for v in verts]
    lines += ["vn %.5f %.5f %.5f" % tuple(v) for v in n]
    lines += ["f %d//%d %d//%d %d//%d" % (a, a, b, b, c, c) for a, b, c in tris + 1]
    atomic_write(path, ("\n".join(lines) + "\n").encode())


def write_ply(path, verts, tris):
    head = ("ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\n"
            "property float y\nproperty float z\nelement face %d\n"
            "property list uchar int vertex_indices\nend_header\n" % (len(verts), len(tris)))
    faces = np.zeros(len(tris), dtype=[("n", "u1"), ("i", "<i4", 3)])
    faces["n"] = 3
    faces["i"] = tris
    atomic_write(path, head.encode() + verts.astype("<f4").tobytes() + faces.tobytes())


def write_serialized(path, verts, tris):
    body = struct.pack("<I", 0x1000)  # single precision, no normals/uvs/colours
    body += b"sphere\0" + struct.pack("<QQ", len(verts), len(tris))
    body += verts.astype("<f4").tobytes() + tris.astype("<u4").tobytes()
    data = struct.pack("<HH", 0x041C, 4) + zlib.compress(body, 6)
    data += struct.pack("<QI", 0, 1)  # offset table (one mesh at byte 0), mesh count
    atomic_write(path, data)


CAMERA = """    <sensor type="perspective">
        <float name="fov" value="{fov}"/>
        <transform name="to_world"><lookat origin="{origin}" target="{target}" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
        <film type="hdrfilm">
            <integer name="width" value="$width"/>
            <integer name="height" value="$height"/>{rfilter}
        </film>
    </sensor>"""


def scene(comment, body, fov=40, origin="0, 1.6, 4.5", target="0, 0.4, 0", rfilter="",
          width=256, height=192, max_depth=-1):
    cam = CAMERA.format(fov=fov, origin=origin, target=target,
                        rfilter=("\n            " + rfilter) if rfilter else "")
    return f"""<?xml version="1.0" encoding="utf-8"?>
<!-- {comment} -->
<scene version="3.0.0">
    <default name="spp" value="64"/>
    <default name="width" value="{width}"/>
    <default name="height" value="{height}"/>
    <default name="max_depth" value="{max_depth}"/>
    <integrator type="path"><integer name="max_depth" value="$max_depth"/></integrator>
{cam}
{body}
</scene>
"""


FLOOR = """    <shape type="rectangle">
        <transform name="to_world"><scale value="8"/><rotate x="1" angle="-90"/><translate value="0, -1.1, 0"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.45, 0.43, 0.4"/></bsdf>
    </shape>"""
PANEL = """    <shape type="rectangle">
        <transform name="to_world"><scale value="1.2, 0.8, 1"/><rotate x="1" angle="110"/><translate value="-1.5, 3.2, 1.5"/></transform>
        <emitter type="area"><rgb name="radiance" value="12, 11, 10"/></emitter>
    </shape>"""


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(REPO, "target", "bench", "scenes")
    os.makedirs(out, exist_ok=True)
    path = lambda name: os.path.join(out, name)

    v, t = sphere(225, 224)
    write_obj(path("sphere-100k.obj"), v, t)
    write_ply(path("sphere-100k.ply"), v, t)
    atomic_write(path("mesh-100k.xml"), scene(
        "A 100k-triangle OBJ mesh in rough plastic on a floor under a rectangle light; the "
        "default gaussian filter.",
        FLOOR + "\n" + PANEL + """
    <shape type="obj">
        <string name="filename" value="sphere-100k.obj"/>
        <bsdf type="roughplastic">
            <rgb name="diffuse_reflectance" value="0.6, 0.25, 0.1"/>
            <float name="alpha" value="0.12"/>
        </bsdf>
    </shape>""").encode())

    v, t = sphere(708, 708)
    write_ply(path("sphere-1m.ply"), v, t)
    sky = os.path.join(REPO, "scenes", "textures", "sky.exr")
    atomic_write(path("mesh-1m.xml"), scene(
        "A 1M-triangle binary PLY (positions only) as a rough conductor under an environment "
        "map; tent filter.",
        FLOOR + f"""
    <emitter type="envmap"><string name="filename" value="{sky}"/></emitter>
    <shape type="ply">
        <string name="filename" value="sphere-1m.ply"/>
        <bsdf type="roughconductor"><string name="material" value="Cu"/><float name="alpha" value="0.2"/></bsdf>
    </shape>""", rfilter='<rfilter type="tent"/>').encode())

    v, t = sphere(1582, 1582)
    write_serialized(path("sphere-5m.serialized"), v, t)
    atomic_write(path("mesh-5m.xml"), scene(
        "A 5M-triangle serialized mesh (positions only), diffuse, lit by a sphere light; box "
        "filter.",
        FLOOR + """
    <shape type="sphere">
        <point name="center" value="1.5, 2.5, 1.5"/><float name="radius" value="0.4"/>
        <emitter type="area"><rgb name="radiance" value="30, 28, 25"/></emitter>
    </shape>
    <shape type="serialized">
        <string name="filename" value="sphere-5m.serialized"/>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.7, 0.72"/></bsdf>
    </shape>""", rfilter='<rfilter type="box"/>').encode())

    instances = []
    for k in range(1000):
        i, j, l = k % 10, (k // 10) % 10, k // 100
        instances.append(
            f"""    <shape type="instance"><ref id="{('warm', 'cool')[k % 2]}"/>
        <transform name="to_world"><scale value="0.16"/><rotate y="1" angle="{(37 * k) % 360}"/><rotate x="1" angle="{(53 * k) % 360}"/><translate value="{(i - 4.5) * 0.5:.2f}, {l * 0.45 - 0.75:.2f}, {(j - 4.5) * 0.5 - 2:.2f}"/></transform>
    </shape>""")
    groups = "".join(
        f"""    <shape type="shapegroup" id="{name}">
        <shape type="ply"><string name="filename" value="sphere-100k.ply"/>
            <bsdf type="roughplastic"><rgb name="diffuse_reflectance" value="{rgb}"/><float name="alpha" value="0.2"/></bsdf>
        </shape>
    </shape>
""" for name, rgb in (("warm", "0.7, 0.35, 0.15"), ("cool", "0.15, 0.35, 0.7")))
    atomic_write(path("instances.xml"), scene(
        "1,000 instances of two 100k-triangle shapegroups (one PLY mesh, two materials) on a "
        "grid, turned each its own way, under a constant sky and a rectangle light.",
        FLOOR + "\n" + PANEL.replace("-1.5, 3.2, 1.5", "-1.5, 5, 4") + "\n    <emitter type=\"constant\"><rgb name=\"radiance\" value=\"0.3\"/></emitter>\n"
        + groups + "\n".join(instances), origin="0, 3.5, 5", target="0, 0.5, -2", fov=50).encode())

    lights = []
    colours = ["48, 40, 32", "32, 40, 48", "48, 24, 16", "24, 40, 24"]
    for k in range(144):
        i, j = k % 12, k // 12
        lights.append(
            f"""    <shape type="sphere"><point name="center" value="{(i - 5.5) * 0.6:.2f}, {1.8 + 0.15 * ((i * 7 + j * 3) % 5):.2f}, {(j - 5.5) * 0.6 - 1:.2f}"/><float name="radius" value="0.04"/>
        <emitter type="area"><rgb name="radiance" value="{colours[(i + j) % 4]}"/></emitter></shape>""")
    objects = """    <shape type="sphere"><point name="center" value="-1, -0.5, -0.5"/><float name="radius" value="0.6"/>
        <bsdf type="roughplastic"><rgb name="diffuse_reflectance" value="0.5"/><float name="alpha" value="0.1"/></bsdf></shape>
    <shape type="cube"><transform name="to_world"><scale value="0.5"/><rotate y="1" angle="30"/><translate value="1, -0.6, -1"/></transform>
        <bsdf type="roughconductor"><string name="material" value="Al"/><float name="alpha" value="0.15"/></bsdf></shape>"""
    # Not in the suite (bench.py does not list it): the case light trees are for, lamps spread
    # along a street, each point near a few of them. `pt render target/bench/scenes/street.xml
    # --light-selection tree|power` compares the two selections (references/performance.md).
    lamps = "\n".join(
        f"""    <shape type="sphere"><point name="center" value="{-2 + (k % 2) * 4}, 3, {-k * 3.0}"/><float name="radius" value="0.1"/>
        <emitter type="area"><rgb name="radiance" value="60, 50, 40"/></emitter></shape>""" for k in range(64))
    street = """    <shape type="rectangle">
        <transform name="to_world"><scale x="20" y="120"/><rotate x="1" angle="-90"/><translate z="-90"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf>
    </shape>
    <shape type="cube"><transform name="to_world"><scale value="0.5, 1, 0.5"/><translate value="0.5, 1, -8"/></transform></shape>"""
    atomic_write(path("street.xml"), scene(
        "64 sphere lamps 3 m apart along a 190 m street (not in the suite: light selection by "
        "distance).", street + "\n" + lamps, fov=50, origin="0, 2, 6", target="0, 0.5, -20",
        width=256, height=160, max_depth=6).encode())

    atomic_write(path("many-lights.xml"), scene(
        "144 small sphere lights of four colours over a floor with a rough plastic sphere and "
        "an aluminium cube; the default gaussian filter.",
        FLOOR + "\n" + objects + "\n" + "\n".join(lights), origin="0, 1.2, 4", target="0, 0, -1").encode())


if __name__ == "__main__":
    main()
