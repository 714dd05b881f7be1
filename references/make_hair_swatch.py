"""Writes scenes/hair/swatch.txt: the strands of scenes/hair-swatch.xml, in Mitsuba's curve file
format (x y z radius per control point, a blank line between strands; B-spline control points).

A swatch of 300 wavy strands hanging from a bar at y = 0.9 down to about y = -0.55, three
layers deep, 9 control points each (6 B-spline segments), radius 0.004 tapering to 0.0015 at
the tip. Deterministic (numpy seed 2026), so rerunning gives the committed file.

Usage: .venv/bin/python references/make_hair_swatch.py   (numpy only)
"""

import os

import numpy as np

OUT = os.path.join(os.path.dirname(__file__), "..", "scenes", "hair", "swatch.txt")


def main():
    rng = np.random.default_rng(2026)
    strands = []
    for i in range(300):
        x0 = -0.55 + 1.1 * (i + rng.uniform()) / 300
        z0 = rng.choice([-0.03, 0.0, 0.03]) + rng.normal(scale=0.008)
        length = 1.45 + rng.normal(scale=0.05)
        phase, freq = rng.uniform(0, 2 * np.pi), rng.uniform(1.2, 2.0)
        amp = rng.uniform(0.02, 0.05)
        pts = []
        for k in range(9):
            s = k / 8
            x = x0 + amp * np.sin(2 * np.pi * freq * s + phase) + 0.04 * s * s * np.sign(x0)
            y = 0.9 - length * s
            z = z0 + 0.6 * amp * np.cos(2 * np.pi * freq * s + phase) + 0.05 * s * s
            r = 0.004 - 0.0025 * s ** 3
            pts.append(f"{x:.5f} {y:.5f} {z:.5f} {r:.5f}")
        strands.append("\n".join(pts))
    with open(OUT, "w") as f:
        f.write("\n\n".join(strands) + "\n")


if __name__ == "__main__":
    main()
