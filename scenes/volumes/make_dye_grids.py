#!/usr/bin/env python3
"""Write the two RGB (3-channel) grids of scenes/dye-plume.xml in Mitsuba's binary gridvolume format.

Usage: python3 make_dye_grids.py [OUTDIR] [--sigma-res N] [--albedo-res M] [--seed S]
(default OUTDIR: this script's folder, N = 32, M = 12, S = 11; numpy only, deterministic.)

Writes
  dye_sigma.vol   N^3 x 3 channels: the extinction of a plume of dye in water (a rising, curling
                  column of gaussian blobs times smooth noise, ~0 at the faces) whose colour
                  changes across space: every blob has its own per-channel weights (the lower
                  ones denser in red, the upper ones denser in blue, one in green), so that the
                  ratios between the channels, and hence the medium's chromatic extinction, vary
                  from cell to cell and no channel is a multiple of another. The few highest
                  peaks are soft-saturated (tanh) so that the maximum, which sets the majorant,
                  is not far above the bulk of the dense cells (a cheaper render). Normalised so
                  that the maximum over all cells AND channels is exactly 1 (the medium's `scale` is
                  then its peak extinction per unit length; Mitsuba's majorant is scale times
                  that maximum).
  dye_albedo.vol  M^3 x 3 channels: the single-scattering albedo, a smooth gradient from
                  orange-ish (low x, low y) to blue-ish (high x, high y) plus a little smooth
                  per-channel noise, clipped to [0.2, 0.98]. The scene reads it with the
                  `nearest` filter through a to_world different from the extinction grid's, so
                  it is coarse on purpose: each cell is a visible block of constant albedo.

Why: a test of heterogeneous media whose grids have three channels: spectrally varying
majorant-vs-extinction ratios (null collisions differ per channel), per-channel ratio-tracked
transmittance, a coloured albedo, trilinear and nearest lookups of cell-centred values, and the
clamp wrap mode where the albedo grid's cube does not cover the medium.

Format (little endian; Mitsuba 3 src/volumes/grid.cpp, compatible with Mitsuba 0.6):
  bytes 0-2   'VOL'
  byte  3     version 3
  int32       encoding 1 (float32)
  int32 x3    xres, yres, zres
  int32       channels (3 here)
  float32 x6  bounding box xmin, ymin, zmin, xmax, ymax, zmax (written as the unit cube; Mitsuba
              ignores it unless the gridvolume has use_grid_bbox = true: the grid fills [0, 1]^3
              in the volume's local space, placed by its to_world)
  float32     data[((z * yres + y) * xres + x) * channels + c], x fastest, channel innermost
Sample (x, y, z) is the value at the cell centre ((x + 0.5) / xres, ...), as Dr.Jit's texture
lookup reads it. Files are written atomically (temporary file, then os.replace).
"""

import argparse
import os
from pathlib import Path

import numpy as np

from volfile import value_noise, write_vol


def cell_centres(res):
    c = (np.arange(res) + 0.5) / res
    return np.meshgrid(c, c, c, indexing="ij")  # z, y, x arrays indexed [z, y, x]


def dye_sigma(res, seed):
    """[z, y, x, c] extinction, max over everything = 1, ~0 at the faces."""
    rng = np.random.default_rng(seed)
    z, y, x = cell_centres(res)
    d = np.zeros((res, res, res, 3))

    def blob(px, py, pz, r):
        return np.exp(-((x - px) ** 2 + (y - py) ** 2 + (z - pz) ** 2) / (2 * r * r))

    # the column: rising from near the bottom, leaning in -x, curling in z; its colour goes from
    # red-dense (bottom) over neutral to blue-dense (top)
    n = 11
    for k in range(n):
        s = k / (n - 1)
        h = 0.15 + 0.66 * s
        cx = 0.56 - 0.2 * s * s + 0.05 * np.sin(7.0 * s)
        cz = 0.5 + 0.1 * np.sin(5.0 * s + 0.5)
        r = 0.06 + 0.065 * s
        w = 1.0 - 0.4 * s
        colour = (1.0 - s) * np.array([1.0, 0.55, 0.3]) + s * np.array([0.25, 0.5, 1.0])
        d += (w * blob(cx, h, cz, r))[..., None] * colour
    # a side puff drifting off to +x, denser in green (magenta in transmission)
    d += (0.7 * blob(0.68, 0.6, 0.45, 0.09))[..., None] * np.array([0.35, 1.0, 0.4])
    # a few small random puffs of random colour
    for _ in range(4):
        p = rng.uniform([0.3, 0.25, 0.35], [0.7, 0.75, 0.65])
        r = rng.uniform(0.04, 0.07)
        colour = rng.uniform(0.2, 1.0, 3)
        d += (0.45 * blob(*p, r))[..., None] * colour

    # smooth noise, its own per channel at the finest octave (so the colour varies in small
    # structures too), shared at the coarse ones
    coarse = 0.5 * value_noise(rng, res, 4) + 0.3 * value_noise(rng, res, 8)
    for c in range(3):
        noise = coarse + 0.2 * value_noise(rng, res, 14)
        d[..., c] *= np.clip(0.15 + 1.8 * (noise - 0.3), 0.02, None) ** 1.5

    # soft fade to zero over the outer 12% of each axis
    def fade(u):
        return np.clip(np.minimum(u, 1 - u) / 0.12, 0.0, 1.0) ** 2
    d *= (fade(x) * fade(y) * fade(z))[..., None]
    # soft-saturate the few highest peaks (where blobs overlap) so that the maximum, which sets
    # the majorant, is not far above the bulk of the dense cells
    d /= np.percentile(d, 99.8)
    d = np.tanh(d)
    d /= d.max()
    return d.astype(np.float32)


def dye_albedo(res, seed):
    """[z, y, x, c] albedo in [0.2, 0.98]: orange-ish to blue-ish plus smooth variation."""
    rng = np.random.default_rng(seed + 1000)
    z, y, x = cell_centres(res)
    t = np.clip(0.55 * x + 0.45 * y + 0.15 * (z - 0.5), 0.0, 1.0)[..., None]
    orange = np.array([0.96, 0.62, 0.28])
    blue = np.array([0.30, 0.62, 0.95])
    a = (1 - t) * orange + t * blue
    for c in range(3):
        a[..., c] += 0.22 * (value_noise(rng, res, 3) - 0.5)
    return np.clip(a, 0.2, 0.98).astype(np.float32)


def describe(path, d):
    faces = max(d[0].max(), d[-1].max(), d[:, 0].max(), d[:, -1].max(),
                d[:, :, 0].max(), d[:, :, -1].max())
    zr, yr, xr, ch = d.shape
    per = ", ".join(f"{'RGB'[c]} mean {d[..., c].mean():.4f} min {d[..., c].min():.3f} "
                    f"max {d[..., c].max():.3f}" for c in range(ch))
    return f"{path}: {xr}x{yr}x{zr}x{ch} float32; {per}; faces max {faces:.2e}"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("outdir", nargs="?", default=str(Path(__file__).resolve().parent))
    ap.add_argument("--sigma-res", type=int, default=32)
    ap.add_argument("--albedo-res", type=int, default=12)
    ap.add_argument("--seed", type=int, default=11)
    a = ap.parse_args()
    out = Path(a.outdir)
    s = dye_sigma(a.sigma_res, a.seed)
    write_vol(out / "dye_sigma.vol", s)
    print(describe(out / "dye_sigma.vol", s))
    alb = dye_albedo(a.albedo_res, a.seed)
    write_vol(out / "dye_albedo.vol", alb)
    print(describe(out / "dye_albedo.vol", alb))


if __name__ == "__main__":
    main()
