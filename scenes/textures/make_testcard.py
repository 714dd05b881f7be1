"""Writes scenes/textures/testcard.png: a 64x40 8-bit sRGB test card for scenes/monitor.xml.

Colour bars in the top half (white, yellow, cyan, green, magenta, red, blue, black), a grey
ramp below, and a white frame, so that orientation (top row = v 0), sRGB decoding and the
bilinear lookup of bitmap emitters all show. Run with .venv/bin/python.
"""
import os
import numpy as np
import mitsuba as mi

mi.set_variant("scalar_rgb")
w, h = 64, 40
img = np.zeros((h, w, 3), np.uint8)
bars = [(255, 255, 255), (255, 255, 0), (0, 255, 255), (0, 255, 0), (255, 0, 255), (255, 0, 0), (0, 0, 255), (0, 0, 0)]
for i, c in enumerate(bars):
    img[:24, i * 8:(i + 1) * 8] = c
ramp = (np.arange(w) * 255 // (w - 1)).astype(np.uint8)
img[24:, :] = ramp[None, :, None]
img[0, :] = img[-1, :] = img[:, 0] = img[:, -1] = 255
out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "testcard.png")
b = mi.Bitmap(img, pixel_format=mi.Bitmap.PixelFormat.RGB)
b.set_srgb_gamma(True)  # 8-bit values are sRGB-encoded
b.write(out)
print("wrote", out)
