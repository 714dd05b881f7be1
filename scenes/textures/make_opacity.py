"""Writes scenes/textures/opacity.png: a 32x32 8-bit sRGB opacity texture for
scenes/mask-texture.xml (Mitsuba `mask` reads the Rec. 709 luminance of the decoded linear RGB).

A white card (opacity 1) with a 3 x 3 grid of round holes (opacity 0), a grey ramp along the
bottom rows (partial opacity) and a pure red square top left (opacity = luminance of red,
0.2127), so that hole shapes, partial values and the luminance rule all show. Row 0 is the top
of the image (v = 0). Run with .venv/bin/python.
"""
import os
import numpy as np
import mitsuba as mi

mi.set_variant("scalar_rgb")
w = h = 32
img = np.full((h, w, 3), 255, np.uint8)
for cy in (6, 14, 22):
    for cx in (8, 16, 24):
        for y in range(h):
            for x in range(w):
                if (x + 0.5 - cx) ** 2 + (y + 0.5 - cy) ** 2 < 3.2 ** 2:
                    img[y, x] = 0
img[27:, :, :] = (np.arange(w) * 255 // (w - 1)).astype(np.uint8)[None, :, None]
img[0:4, 0:4] = (255, 0, 0)
out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "opacity.png")
b = mi.Bitmap(img, pixel_format=mi.Bitmap.PixelFormat.RGB)
b.set_srgb_gamma(True)
b.write(out)
print("wrote", out)
