"""Writes scenes/textures/bumps-normal.png: a 64x64 8-bit tangent-space normal map (RGB =
(n + 1) / 2, linear data: load it with raw=true) for scenes/normal-map.xml.

Left third: vertical stripes whose normals tilt +-35 degrees about the v axis (x only); middle
third: a dome (spherical cap, tilt up to 50 degrees at its rim) that tilts in x and y; right
third: horizontal stripes tilting +-35 degrees in y only, so that a swapped or flipped green
channel shows. Row 0 is the top of the image (v = 0). Run with .venv/bin/python.
"""
import math
import os
import numpy as np
import mitsuba as mi

mi.set_variant("scalar_rgb")
w = h = 64
n = np.zeros((h, w, 3))
n[..., 2] = 1.0
a = math.radians(35.0)
for y in range(h):
    for x in range(w):
        if x < 21:
            s = 1.0 if (x // 4) % 2 == 0 else -1.0
            n[y, x] = (s * math.sin(a), 0.0, math.cos(a))
        elif x < 43:
            dx, dy = (x + 0.5 - 32.0) / 10.0, (y + 0.5 - 32.0) / 10.0
            r = math.hypot(dx, dy)
            if r < 1.0:
                t = math.radians(50.0) * r  # tilt grows linearly to the rim
                n[y, x] = (math.sin(t) * dx / max(r, 1e-9), math.sin(t) * dy / max(r, 1e-9), math.cos(t))
        else:
            s = 1.0 if (y // 4) % 2 == 0 else -1.0
            n[y, x] = (0.0, s * math.sin(a), math.cos(a))
img = np.clip(np.round((n + 1.0) * 0.5 * 255.0), 0, 255).astype(np.uint8)
out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "bumps-normal.png")
b = mi.Bitmap(img, pixel_format=mi.Bitmap.PixelFormat.RGB)
b.set_srgb_gamma(False)  # linear data, not colour
b.write(out)
print("wrote", out)
