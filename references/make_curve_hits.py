"""Ray hits on Mitsuba 3.9.1's `linearcurve` and `bsplinecurve`, for pt's curve tests.

Writes crates/pt-render/src/testdata/mitsuba_curves.json: a few curves (hair-like bends,
tapered and constant radii, a joint between segments, open and capped ends) and, for each,
rays aimed at random points near the tube from outside it, with Mitsuba's hit distance,
normal, texture coordinates and segment index (t = null for a miss).

Usage: .venv/bin/python references/make_curve_hits.py   (scalar_rgb: Mitsuba's pip wheels
trace curves with Embree in the scalar variants.)
"""

import json
import os
import tempfile

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")

OUT = os.path.join(os.path.dirname(__file__), "..", "crates", "pt-render", "src", "testdata",
                   "mitsuba_curves.json")


def f32(x):
    """`x` as the nearest f32, in the shortest decimal that reads back as it."""
    return float(np.format_float_positional(np.float32(x), unique=True, trim="-"))


def curves():
    """(name, basis, list of curves as lists of [x, y, z, r])."""
    rng = np.random.default_rng(7)
    # A wavy strand: control points along y with sideways wiggle, radius tapering.
    wavy = [[0.3 * np.sin(1.3 * i), 0.8 * i, 0.25 * np.cos(0.9 * i), 0.12 - 0.01 * i]
            for i in range(8)]
    # A strongly bent one (a quarter circle of control points), constant radius.
    bent = [[np.cos(a), np.sin(a), 0.1 * a, 0.15] for a in np.linspace(0, 1.6, 6)]
    # Random hair-like strands.
    strands = []
    for _ in range(3):
        p = rng.uniform(-1, 1, 3)
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        pts = []
        for i in range(6):
            pts.append([*(p + 0.5 * i * d + rng.normal(scale=0.08, size=3)),
                        0.05 + 0.02 * rng.uniform()])
        strands.append(pts)
    return [
        ("linear", "linearcurve", [wavy, bent] + strands),
        ("bspline", "bsplinecurve", [wavy, bent] + strands),
    ]


def main():
    rng = np.random.default_rng(11)
    out = []
    tmp = tempfile.mkdtemp()
    for name, plugin, cs in curves():
        path = os.path.join(tmp, name + ".txt")
        with open(path, "w") as f:
            f.write("\n\n".join("\n".join(" ".join(repr(f32(x)) for x in p) for p in c)
                                for c in cs) + "\n")
        scene = mi.load_dict({"type": "scene", "c": {"type": plugin, "filename": path}})
        pts = np.array([p for c in cs for p in c])
        rays = []
        for _ in range(1000):
            # A target near a random control point's tube, a direction from anywhere.
            k = rng.integers(len(pts))
            target = pts[k, :3] + rng.normal(scale=1.5 * pts[k, 3], size=3)
            d = rng.normal(size=3)
            d /= np.linalg.norm(d)
            # As the f32 values Mitsuba traces, written so that they read back exactly.
            d = d.astype(np.float32)
            o = (target - 4.0 * d).astype(np.float32)
            si = scene.ray_intersect(mi.Ray3f(mi.Point3f(*o), mi.Vector3f(*d)))
            hit = bool(si.is_valid())
            rays.append({
                "o": [f32(x) for x in o],
                "d": [f32(x) for x in d],
                "t": f32(si.t) if hit else None,
                "n": [f32(x) for x in si.n] if hit else None,
                "uv": [f32(x) for x in si.uv] if hit else None,
                "prim": int(si.prim_index) if hit else None,
            })
        out.append({"name": name, "plugin": plugin,
                    "curves": [[[f32(x) for x in p] for p in c] for c in cs],
                    "rays": rays})
        print(name, sum(r["t"] is not None for r in rays), "hits of", len(rays))
    with open(OUT, "w") as f:
        json.dump({"source": "Mitsuba " + mi.__version__ + " scalar_rgb (Embree)",
                   "script": "references/make_curve_hits.py", "shapes": out}, f)


if __name__ == "__main__":
    main()
