"""Writes scenes/textures/bumps-height.png: a 64x48 8-bit grey height field (linear data: load
it with raw=true) for scenes/bumpmap.xml.

h(u, v) = 1/2 + 1/2 sin(2 pi 6 u) sin(2 pi 4 v): a grid of 6 x 4 bumps and dents, plus in the
right quarter (u > 3/4) a ramp h += u that tilts the whole strip, so that a sign error of the
u gradient shows as a brightness change. The image is not square, so a mix-up of width and
height in the gradient's texel-to-uv scale shows too. Row 0 is the top of the image (v = 0).
Run with .venv/bin/python.
"""
import math
import os
import numpy as np
import mitsuba as mi

mi.set_variant("scalar_rgb")
w, h = 64, 48
img = np.zeros((h, w, 1))
for y in range(h):
    for x in range(w):
        u, v = (x + 0.5) / w, (y + 0.5) / h
        z = 0.5 + 0.5 * math.sin(2 * math.pi * 6 * u) * math.sin(2 * math.pi * 4 * v)
        if u > 0.75:
            z = 0.5 * z + 2.0 * (u - 0.75)
        img[y, x, 0] = z
img = np.clip(np.round(img * 255.0), 0, 255).astype(np.uint8)
out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "bumps-height.png")
b = mi.Bitmap(img, pixel_format=mi.Bitmap.PixelFormat.Y)
b.set_srgb_gamma(False)  # linear data, not colour
b.write(out)
print("wrote", out)
