#!/usr/bin/env python3
"""Writes the glTF 2.0 test assets of this folder (standard library only; run from anywhere):

    python3 scenes/gltf/make_gltf.py

- lights.gltf       a 6 x 6 m grey plane (y = 0, facing +y) seen from straight above by a
                    perspective camera, lit by one KHR_lights_punctual light of each type: point,
                    spot (pointing down) and directional. tests/gltf.rs checks every pixel
                    against the closed form f(wo, wi) E(x) with E the irradiance of each light.
- iridescence.gltf  a UV sphere (radius 1) with KHR_materials_iridescence on a dark dielectric base,
                    no light (the default constant environment of radiance 1 lights it).
- textures.gltf     a plane whose base colour is a 2 x 1 PNG (sRGB (200, 100, 50) | (20, 60, 240),
                    nearest) times a factor, and whose metallic-roughness texture (1 x 1, linear)
                    scales roughness and metallic; KHR_texture_transform rotates the uvs by 90
                    degrees. textures-flat.gltf is the same scene with a 1 x 2 texture and no
                    transform, laid out so that both must render the same image (tests/gltf.rs).
- glass-block.glb   binary glTF: a 1 m thick slab (KHR_materials_transmission + _ior + _volume
                    with attenuationColor / attenuationDistance) between the camera and the
                    default white environment.

Geometry is written with explicit normals and, for the plane, texture coordinates; buffers are
embedded as base64 data URIs (.gltf) or the GLB binary chunk (.glb). The numbers in the tests
(tests/gltf.rs) are the ones set here: change both together.
"""
import base64
import json
import math
import os
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))


class Builder:
    """Accumulates one binary buffer with bufferViews and accessors."""

    def __init__(self):
        self.data = bytearray()
        self.views = []
        self.accessors = []

    def _view(self, raw, target):
        while len(self.data) % 4:
            self.data.append(0)
        self.views.append({"buffer": 0, "byteOffset": len(self.data), "byteLength": len(raw), "target": target})
        self.data += raw
        return len(self.views) - 1

    def vec(self, rows, kind):
        """Float VEC2/VEC3 accessor from a list of tuples."""
        n = len(rows[0])
        raw = b"".join(struct.pack("<%df" % n, *r) for r in rows)
        view = self._view(raw, 34962)
        acc = {"bufferView": view, "componentType": 5126, "count": len(rows), "type": kind}
        if kind == "VEC3":
            acc["min"] = [min(r[i] for r in rows) for i in range(3)]
            acc["max"] = [max(r[i] for r in rows) for i in range(3)]
        self.accessors.append(acc)
        return len(self.accessors) - 1

    def indices(self, idx):
        raw = struct.pack("<%dI" % len(idx), *idx)
        view = self._view(raw, 34963)
        self.accessors.append({"bufferView": view, "componentType": 5125, "count": len(idx), "type": "SCALAR"})
        return len(self.accessors) - 1


def quat_from_to(a, b):
    """Unit quaternion (x, y, z, w) rotating unit vector a onto unit vector b."""
    c = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    d = sum(x * y for x, y in zip(a, b))
    q = [c[0], c[1], c[2], 1.0 + d]
    n = math.sqrt(sum(x * x for x in q))
    return [x / n for x in q]


# Looking straight down (-y) with the image's top towards -z: rotate glTF's -z view axis onto -y.
DOWN = quat_from_to([0.0, 0.0, -1.0], [0.0, -1.0, 0.0])


def write_gltf(name, doc, b):
    doc["buffers"] = [{"byteLength": len(b.data), "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(b.data)).decode()}]
    doc["bufferViews"] = b.views
    doc["accessors"] = b.accessors
    with open(os.path.join(HERE, name), "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")


def write_glb(name, doc, b):
    doc["buffers"] = [{"byteLength": len(b.data)}]
    doc["bufferViews"] = b.views
    doc["accessors"] = b.accessors
    js = json.dumps(doc).encode()
    js += b" " * ((4 - len(js) % 4) % 4)
    bin_ = bytes(b.data) + b"\0" * ((4 - len(b.data) % 4) % 4)
    total = 12 + 8 + len(js) + 8 + len(bin_)
    out = struct.pack("<4sII", b"glTF", 2, total) + struct.pack("<I4s", len(js), b"JSON") + js + struct.pack("<I4s", len(bin_), b"BIN\0") + bin_
    with open(os.path.join(HERE, name), "wb") as f:
        f.write(out)


def png(width, height, rows):
    """An 8-bit RGB PNG (colour type 2) from rows of (r, g, b) tuples."""
    raw = b"".join(b"\0" + bytes(c for px in row for c in px) for row in rows)

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)) + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")


def data_uri(mime, raw):
    return "data:%s;base64,%s" % (mime, base64.b64encode(raw).decode())


def textures():
    """Two files that must render identically: textures.gltf rotates a 2 x 1 texture by 90
    degrees with KHR_texture_transform, textures-flat.gltf uses the rotated 1 x 2 texture."""
    a, b_ = (200, 100, 50), (20, 60, 240)
    for name, img, transform in [
        ("textures.gltf", png(2, 1, [[a, b_]]), {"rotation": math.pi / 2}),
        # rotation pi/2: u' = -v, v' = u. For v in (0, 1/2), u' in (-1/2, 0) -> repeat -> the right
        # texel (b_); for v in (1/2, 1) the left texel (a). So the 1 x 2 equivalent is b_ over a.
        ("textures-flat.gltf", png(1, 2, [[b_], [a]]), None),
    ]:
        b = Builder()
        s = 3.0
        pos = b.vec([(-s, 0, -s), (s, 0, -s), (s, 0, s), (-s, 0, s)], "VEC3")
        nrm = b.vec([(0, 1, 0)] * 4, "VEC3")
        uv = b.vec([(0, 0), (1, 0), (1, 1), (0, 1)], "VEC2")
        idx = b.indices([0, 2, 1, 0, 3, 2])
        base = {"index": 0}
        if transform:
            base["extensions"] = {"KHR_texture_transform": transform}
        doc = {
            "asset": {"version": "2.0", "generator": "pt scenes/gltf/make_gltf.py"},
            "extensionsUsed": ["KHR_texture_transform"] if transform else [],
            "scene": 0,
            "scenes": [{"nodes": [0, 1]}],
            "nodes": [{"mesh": 0, "name": "plane"}, {"camera": 0, "translation": [0, 4, 0], "rotation": DOWN, "name": "camera"}],
            "cameras": [{"type": "perspective", "perspective": {"yfov": math.radians(50.0), "aspectRatio": 1.0, "znear": 0.01}}],
            "meshes": [{"name": "plane", "primitives": [{"attributes": {"POSITION": pos, "NORMAL": nrm, "TEXCOORD_0": uv}, "indices": idx, "material": 0}]}],
            "materials": [
                {
                    "name": "textured",
                    "pbrMetallicRoughness": {
                        "baseColorFactor": [0.8, 1.0, 0.9, 1.0],
                        "baseColorTexture": base,
                        "metallicFactor": 0.5,
                        "roughnessFactor": 0.9,
                        "metallicRoughnessTexture": {"index": 1},
                    },
                }
            ],
            "samplers": [{"magFilter": 9728, "minFilter": 9728}],
            "images": [{"uri": data_uri("image/png", img)}, {"uri": data_uri("image/png", png(1, 1, [[(0, 128, 255)]]))}],
            "textures": [{"source": 0, "sampler": 0}, {"source": 1, "sampler": 0}],
        }
        if not doc["extensionsUsed"]:
            del doc["extensionsUsed"]
        write_gltf(name, doc, b)


def lights():
    b = Builder()
    s = 3.0
    pos = b.vec([(-s, 0, -s), (s, 0, -s), (s, 0, s), (-s, 0, s)], "VEC3")
    nrm = b.vec([(0, 1, 0)] * 4, "VEC3")
    uv = b.vec([(0, 0), (1, 0), (1, 1), (0, 1)], "VEC2")
    # Counter-clockwise seen from +y: (0, 2, 1), (0, 3, 2).
    idx = b.indices([0, 2, 1, 0, 3, 2])
    direction = [0.6, -0.8, 0.0]
    doc = {
        "asset": {"version": "2.0", "generator": "pt scenes/gltf/make_gltf.py"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2, 3, 4]}],
        "nodes": [
            {"mesh": 0, "name": "plane"},
            {"camera": 0, "translation": [0, 4, 0], "rotation": DOWN, "name": "camera"},
            {"translation": [0.7, 1.5, -0.4], "extensions": {"KHR_lights_punctual": {"light": 0}}, "name": "point"},
            {"translation": [0, 2, 0], "rotation": DOWN, "extensions": {"KHR_lights_punctual": {"light": 1}}, "name": "spot"},
            {"rotation": quat_from_to([0.0, 0.0, -1.0], direction), "extensions": {"KHR_lights_punctual": {"light": 2}}, "name": "sun"},
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": math.radians(50.0), "aspectRatio": 1.0, "znear": 0.01, "zfar": 100.0}}],
        "meshes": [{"name": "plane", "primitives": [{"attributes": {"POSITION": pos, "NORMAL": nrm, "TEXCOORD_0": uv}, "indices": idx, "material": 0}]}],
        "materials": [{"name": "grey", "pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.6, 0.6, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.5}}],
        "extensions": {
            "KHR_lights_punctual": {
                "lights": [
                    {"type": "point", "color": [1.0, 0.5, 0.25], "intensity": 5.0},
                    {"type": "spot", "color": [1.0, 1.0, 1.0], "intensity": 8.0, "spot": {"innerConeAngle": math.radians(15.0), "outerConeAngle": math.radians(30.0)}},
                    {"type": "directional", "color": [1.0, 1.0, 1.0], "intensity": 3.0},
                ]
            }
        },
    }
    write_gltf("lights.gltf", doc, b)


def sphere_mesh(b, n_theta=24, n_phi=48, radius=1.0):
    pos, nrm, idx = [], [], []
    for i in range(n_theta + 1):
        t = math.pi * i / n_theta
        for j in range(n_phi + 1):
            p = 2 * math.pi * j / n_phi
            n = (math.sin(t) * math.cos(p), math.cos(t), -math.sin(t) * math.sin(p))
            nrm.append(n)
            pos.append(tuple(radius * c for c in n))
    for i in range(n_theta):
        for j in range(n_phi):
            a = i * (n_phi + 1) + j
            c = a + n_phi + 1
            idx += [a, c, a + 1, a + 1, c, c + 1]
    return b.vec(pos, "VEC3"), b.vec(nrm, "VEC3"), b.indices(idx)


def iridescence():
    b = Builder()
    pos, nrm, idx = sphere_mesh(b)
    doc = {
        "asset": {"version": "2.0", "generator": "pt scenes/gltf/make_gltf.py"},
        "extensionsUsed": ["KHR_materials_iridescence"],
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0, "name": "sphere"}, {"camera": 0, "translation": [0, 0, 4], "name": "camera"}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": math.radians(32.0), "aspectRatio": 1.0, "znear": 0.01}}],
        "meshes": [{"name": "sphere", "primitives": [{"attributes": {"POSITION": pos, "NORMAL": nrm}, "indices": idx, "material": 0}]}],
        "materials": [
            {
                "name": "soap-film-on-glass",
                "pbrMetallicRoughness": {"baseColorFactor": [0.05, 0.05, 0.05, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.0},
                "extensions": {"KHR_materials_iridescence": {"iridescenceFactor": 1.0, "iridescenceIor": 1.33, "iridescenceThicknessMinimum": 100.0, "iridescenceThicknessMaximum": 450.0}},
            }
        ],
    }
    write_gltf("iridescence.gltf", doc, b)


def glass_block():
    b = Builder()
    # A 4 x 4 x 1 m slab, faces at z = +-0.5, outward normals, 24 vertices (flat faces).
    hx, hy, hz = 2.0, 2.0, 0.5
    faces = [
        ((0, 0, 1), [(-hx, -hy, hz), (hx, -hy, hz), (hx, hy, hz), (-hx, hy, hz)]),
        ((0, 0, -1), [(hx, -hy, -hz), (-hx, -hy, -hz), (-hx, hy, -hz), (hx, hy, -hz)]),
        ((1, 0, 0), [(hx, -hy, hz), (hx, -hy, -hz), (hx, hy, -hz), (hx, hy, hz)]),
        ((-1, 0, 0), [(-hx, -hy, -hz), (-hx, -hy, hz), (-hx, hy, hz), (-hx, hy, -hz)]),
        ((0, 1, 0), [(-hx, hy, hz), (hx, hy, hz), (hx, hy, -hz), (-hx, hy, -hz)]),
        ((0, -1, 0), [(-hx, -hy, -hz), (hx, -hy, -hz), (hx, -hy, hz), (-hx, -hy, hz)]),
    ]
    pos, nrm, idx = [], [], []
    for n, quad in faces:
        k = len(pos)
        pos += quad
        nrm += [n] * 4
        idx += [k, k + 1, k + 2, k, k + 2, k + 3]
    p, nn, ii = b.vec(pos, "VEC3"), b.vec(nrm, "VEC3"), b.indices(idx)
    doc = {
        "asset": {"version": "2.0", "generator": "pt scenes/gltf/make_gltf.py"},
        "extensionsUsed": ["KHR_materials_transmission", "KHR_materials_ior", "KHR_materials_volume"],
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0, "name": "slab"}, {"camera": 0, "translation": [0, 0, 3], "name": "camera"}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": math.radians(10.0), "aspectRatio": 1.0, "znear": 0.01}}],
        "meshes": [{"name": "slab", "primitives": [{"attributes": {"POSITION": p, "NORMAL": nn}, "indices": ii, "material": 0}]}],
        "materials": [
            {
                "name": "tinted-glass",
                "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0.0, "roughnessFactor": 0.0},
                "extensions": {
                    "KHR_materials_transmission": {"transmissionFactor": 1.0},
                    "KHR_materials_ior": {"ior": 1.5},
                    "KHR_materials_volume": {"thicknessFactor": 1.0, "attenuationDistance": 0.5, "attenuationColor": [0.8, 0.5, 0.2]},
                },
            }
        ],
    }
    write_glb("glass-block.glb", doc, b)


if __name__ == "__main__":
    lights()
    textures()
    iridescence()
    glass_block()
