#!/usr/bin/env python3
"""Writes references/figures/monitor-rgb-spectral-primaries.png: the test-card monitor rendered by
pt in RGB mode (scenes/monitor.xml), in spectral mode with each texel upsampled
(scenes/monitor-spectral.xml) and with the model LCD's own spectral primaries
(scenes/monitor-primaries.xml), side by side, +1 stop, clamped, sRGB-encoded.

Usage (from the repository root, after building pt; the venv of references/README.md):

    for s in monitor monitor-spectral monitor-primaries; do
        target/release/pt render scenes/$s.xml -o /tmp/fig_$s.exr --spp 1024 --quiet; done
    .venv/bin/python references/make_monitor_figure.py /tmp
"""
import os
import sys

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")
src = sys.argv[1] if len(sys.argv) > 1 else "/tmp"
panels = [np.array(mi.Bitmap(os.path.join(src, f"fig_{s}.exr")))[..., :3]
          for s in ("monitor", "monitor-spectral", "monitor-primaries")]
gap = np.ones((panels[0].shape[0], 4, 3), np.float32)
row = np.clip(np.concatenate([panels[0], gap, panels[1], gap, panels[2]], 1) * 2.0, 0.0, 1.0)
enc = np.where(row <= 0.0031308, 12.92 * row, 1.055 * np.power(row, 1 / 2.4) - 0.055)
out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "figures", "monitor-rgb-spectral-primaries.png")
mi.Bitmap((enc * 255 + 0.5).astype(np.uint8), pixel_format=mi.Bitmap.PixelFormat.RGB).write(out)
print("wrote", out)
