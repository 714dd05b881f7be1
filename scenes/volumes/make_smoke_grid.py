#!/usr/bin/env python3
"""Write a smoke-like density grid in Mitsuba's binary gridvolume format (.vol).

Usage: python3 make_smoke_grid.py [OUT.vol] [--res N] [--seed S]
(default OUT: smoke.vol next to this script, N = 40, S = 7; numpy only, deterministic.)

Format (little endian; Mitsuba 3 src/volumes/grid.cpp, compatible with Mitsuba 0.6):
  bytes 0-2   'VOL'
  byte  3     version 3
  int32       encoding 1 (float32)
  int32 x3    xres, yres, zres
  int32       channels (1 here)
  float32 x6  bounding box xmin, ymin, zmin, xmax, ymax, zmax (written as the unit cube; Mitsuba
              ignores it unless the gridvolume has use_grid_bbox = true: the grid fills [0, 1]^3
              in the volume's local space, placed by its to_world)
  float32     data[((z * yres + y) * xres + x) * channels + c], x fastest

Density: a rising, drifting plume of gaussian puffs (wider and thinner with height) times a
smooth multi-octave value noise, a soft fade towards the faces so that the density is ~0 at the
grid's boundary (the trilinear lookup clamps at the faces), normalised so that the maximum is
exactly 1 (the medium's `scale` is then its peak extinction per unit length). Sample (x, y, z)
is the value at the cell centre ((x + 0.5) / xres, ...), as Dr.Jit's texture lookup reads it.
"""

import argparse
from pathlib import Path

import numpy as np

from volfile import value_noise, write_vol


def smoke_density(res, seed):
    rng = np.random.default_rng(seed)
    c = (np.arange(res) + 0.5) / res
    z, y, x = np.meshgrid(c, c, c, indexing="ij")  # arrays indexed [z, y, x]

    d = np.zeros((res, res, res))
    # a plume rising from near the bottom, drifting in +x and curling in z
    for k in range(9):
        h = 0.14 + 0.085 * k
        cx = 0.42 + 0.16 * h * h + 0.05 * np.sin(5.0 * h)
        cz = 0.5 + 0.08 * np.sin(7.0 * h + 1.0)
        r = 0.07 + 0.11 * h
        w = 1.0 - 0.55 * h
        d += w * np.exp(-((x - cx) ** 2 + (y - h) ** 2 + (z - cz) ** 2) / (2 * r * r))
    # a few random side puffs
    for _ in range(5):
        p = rng.uniform([0.3, 0.3, 0.35], [0.7, 0.8, 0.65])
        r = rng.uniform(0.05, 0.09)
        d += 0.5 * np.exp(-((x - p[0]) ** 2 + (y - p[1]) ** 2 + (z - p[2]) ** 2) / (2 * r * r))

    noise = (0.55 * value_noise(rng, res, 4) + 0.3 * value_noise(rng, res, 8)
             + 0.15 * value_noise(rng, res, 16))
    d *= np.clip(1.6 * noise - 0.25, 0.0, None)
    # soft fade to zero over the outer 12% of each axis
    def fade(u):
        return np.clip(np.minimum(u, 1 - u) / 0.12, 0.0, 1.0) ** 2
    d *= fade(x) * fade(y) * fade(z)
    d /= d.max()
    return d.astype(np.float32)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out", nargs="?", default=str(Path(__file__).resolve().parent / "smoke.vol"))
    ap.add_argument("--res", type=int, default=40)
    ap.add_argument("--seed", type=int, default=7)
    a = ap.parse_args()
    d = smoke_density(a.res, a.seed)
    write_vol(Path(a.out), d[..., None])
    print(f"{a.out}: {a.res}^3 float32, mean {d.mean():.4f}, max {d.max():.1f}, "
          f"boundary max {max(d[0].max(), d[-1].max(), d[:, 0].max(), d[:, -1].max(), d[:, :, 0].max(), d[:, :, -1].max()):.2e}")


if __name__ == "__main__":
    main()
