"""Writes scenes/textures/sky.exr: a synthetic 128x64 latitude-longitude sky for scenes/envmap.xml.

A blue-to-white gradient from zenith to horizon, a dim brown ground, and a bright warm disk
(a small "sun") at u = 0.3, v = 0.25, so that importance sampling matters. Linear RGB, float32.
Run with the references venv: .venv/bin/python scenes/textures/make_sky.py
"""
import os
import numpy as np
import mitsuba as mi

mi.set_variant("scalar_rgb")
w, h = 128, 64
u = (np.arange(w) + 0.5) / w
v = (np.arange(h) + 0.5) / h
U, V = np.meshgrid(u, v)
sky = np.where(V[..., None] < 0.5,
               np.stack([0.4 + 0.6 * V * 2, 0.6 + 0.4 * V * 2, 1.0 + 0 * V], -1) * 0.8,
               np.stack([0.25 + 0 * V, 0.2 + 0 * V, 0.15 + 0 * V], -1))
d2 = ((U - 0.3) * 2) ** 2 + (V - 0.25) ** 2
sky = sky + np.exp(-d2 / 0.0015)[..., None] * np.array([60.0, 50.0, 35.0])
out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "sky.exr")
mi.Bitmap(sky.astype(np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB).write(out)
print("wrote", out)
