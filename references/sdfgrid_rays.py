#!/usr/bin/env python3
"""Mitsuba 3.9.1's own sdfgrid intersections, for the differential test in
crates/pt-render/src/sdf.rs (`matches_mitsuba_3_9_1`).

Builds the grid the test builds (the same formula, rounded to f32), shoots fixed rays at it
with Mitsuba's scalar_rgb variant (`normals` smooth, then analytic) and prints the Rust table
of (origin, direction, t, geometric normal, smooth shading normal) for the rays that hit.

    .venv/bin/python references/sdfgrid_rays.py
"""
import numpy as np
import mitsuba as mi

mi.set_variant("scalar_rgb")

RES = (9, 9, 9)  # samples along x, y, z (equal: Mitsuba 3.9.1 mishandles unequal ones, see the module docs of sdf.rs)
ORIGIN = np.array([-0.7, -0.5, -1.0])
EXTENT = np.array([1.5, 1.0, 2.0])


def grid():
    """f(q) for q the object-space position of each sample: a wobbly sphere."""
    nx, ny, nz = RES
    g = np.zeros((nz, ny, nx, 1), dtype=np.float32)
    for z in range(nz):
        for y in range(ny):
            for x in range(nx):
                q = np.array([x / (nx - 1), y / (ny - 1), z / (nz - 1)])
                f = np.linalg.norm(q - 0.5) - 0.3 + 0.05 * np.sin(7 * q[0]) * np.cos(5 * q[1])
                g[z, y, x, 0] = np.float32(f)
    return g


def main():
    g = grid()
    to_world = mi.ScalarTransform4f().translate(ORIGIN.tolist()).scale(EXTENT.tolist())
    scenes = {
        n: mi.load_dict({"type": "scene", "s": {"type": "sdfgrid", "grid": mi.TensorXf(g),
                                                  "normals": n, "to_world": to_world}})
        for n in ("smooth", "analytic")
    }
    rng = np.random.default_rng(7)
    rows = []
    while len(rows) < 24:
        target = ORIGIN + EXTENT * rng.uniform(0.2, 0.8, 3)
        o = target + rng.normal(size=3) * 3
        d = target - o
        d = (d / np.linalg.norm(d)).astype(np.float32)
        o = o.astype(np.float32)
        ray = mi.Ray3f(o.tolist(), d.tolist())
        s = scenes["smooth"].ray_intersect(ray)
        a = scenes["analytic"].ray_intersect(ray)
        if not s.is_valid():
            continue
        assert abs(s.t - a.t) == 0
        rows.append((o, d, s.t, list(a.sh_frame.n), list(s.sh_frame.n)))
    f = lambda v: ", ".join(f"{float(x):.9e}" for x in v)
    for o, d, t, n, sh in rows:
        print(f"    ([{f(o)}], [{f(d)}], {float(t):.9e}, [{f(n)}], [{f(sh)}]),")


if __name__ == "__main__":
    main()
