#!/usr/bin/env python3
"""Writes lcd-r.spd, lcd-g.spd, lcd-b.spd: the red, green and blue primaries of a model LCD
with a white-LED backlight, for the display-primaries extension of pt's area emitter
(<spectrum name="primary_r" filename="spectra/lcd-r.spd"/>, ...; see scenes/monitor-primaries.xml).

Written for this project in the style of measured LCD primaries, not a measurement: the
backlight is a blue InGaN LED (Gaussian at 450 nm, sigma 9 nm) plus a broad YAG:Ce phosphor
(Gaussian at 560 nm, sigma 50 nm, relative height 0.55); each subpixel's colour filter is a
smooth band (red: logistic edge at 595 nm, width 9 nm; green: Gaussian at 530 nm, sigma 32 nm;
blue: Gaussian at 455 nm, sigma 22 nm). Primary = backlight x filter, in relative radiance per nm
(pt rescales the three so that RGB (1, 1, 1) emits D65 of luminance 1). 380-780 nm in 5 nm
steps, "wavelength value" per line (the format Mitsuba 3 and pt read). Standard library only:
    python3 scenes/spectra/make_lcd_primaries.py
"""
import math
import os

def backlight(l):
    return math.exp(-0.5 * ((l - 450) / 9) ** 2) + 0.55 * math.exp(-0.5 * ((l - 560) / 50) ** 2)

FILTERS = {
    "r": lambda l: 1 / (1 + math.exp(-(l - 595) / 9)),
    "g": lambda l: math.exp(-0.5 * ((l - 530) / 32) ** 2),
    "b": lambda l: math.exp(-0.5 * ((l - 455) / 22) ** 2),
}

here = os.path.dirname(os.path.abspath(__file__))
for name, f in FILTERS.items():
    path = os.path.join(here, f"lcd-{name}.spd")
    with open(path + ".tmp", "w") as out:
        out.write(f"# Primary '{name}' of a model white-LED LCD (written by make_lcd_primaries.py; not a\n")
        out.write("# measurement): relative spectral radiance, one \"wavelength(nm) value\" pair per line.\n")
        for l in range(380, 781, 5):
            out.write(f"{l} {backlight(l) * f(l):.6f}\n")
    os.replace(path + ".tmp", path)
    print("wrote", path)
