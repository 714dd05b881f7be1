#!/usr/bin/env python3
"""Write scenes/spectra/fluorescent-twin.spd: the reflectance of a plain diffuse surface that
looks like the fluorescent paint of scenes/fluorescence.xml under D65 daylight.

Under an illuminant S(l), the fluorescent Lambertian (crates/pt-render/src/fluorescence.rs)
sends back, per unit of incident S(lo), the effective reflectance

    R(lo) = r(lo) + Q e(lo) / (lo S(lo)) int_{360}^{lo} a(li) S(li) li dli

(e normalised to unit area over 360-830 nm). With S = D65 the twin with reflectance R has the
same directly lit spectrum, hence the same colour in daylight; under a blue lamp it does not.
Only the D65 shape matters (its normalisation cancels). Run with the Mitsuba virtual
environment (D65 from Mitsuba's `d65` plugin, the CIE table at 5 nm):

    /work/main/.venv/bin/python scenes/spectra/make_fluorescent_twin.py
"""
import os
import numpy as np
import mitsuba as mi

# Keep in sync with the fluorescent paint in scenes/fluorescence.xml.
REFLECTANCE = [(360, 0.06), (480, 0.06), (510, 0.08), (540, 0.12), (580, 0.35), (620, 0.55), (830, 0.6)]
ABSORPTION = [(360, 0.3), (420, 0.45), (470, 0.7), (495, 0.75), (515, 0.2), (530, 0.0), (830, 0.0)]
EMISSION = [(490, 0.0), (515, 1.0), (535, 0.8), (570, 0.3), (620, 0.0)]
YIELD = 0.6


def pw(pairs, l):
    """Piecewise linear, zero outside the nodes (Mitsuba / pt convention)."""
    xs, ys = zip(*pairs)
    return np.where((l >= xs[0]) & (l <= xs[-1]), np.interp(l, xs, ys), 0.0)


def main():
    mi.set_variant("scalar_spectral")
    d65 = mi.load_dict({"type": "d65"})
    si = mi.SurfaceInteraction3f()
    h = 0.05
    l = np.arange(360.0, 830.0 + h / 2, h)
    s = np.empty_like(l)
    for i, x in enumerate(l):
        si.wavelengths = mi.Spectrum([float(x)] * 4)
        s[i] = d65.eval(si)[0]
    e = pw(EMISSION, l)
    e /= np.trapezoid(e, l)
    g = pw(ABSORPTION, l) * s * l
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (g[1:] + g[:-1]) * h)])
    R = pw(REFLECTANCE, l) + YIELD * e / (l * s) * cum
    assert R.max() <= 1.0, R.max()
    out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "fluorescent-twin.spd")
    with open(out, "w") as f:
        f.write("# Reflectance of the non-fluorescent twin in scenes/fluorescence.xml: equal under D65\n")
        f.write("# to the fluorescent paint's elastic + re-emitted light. Made by make_fluorescent_twin.py.\n")
        for x in range(360, 831, 5):
            i = int(round((x - 360) / h))
            f.write(f"{x} {R[i]:.5f}\n")
    print(f"wrote {out}, max reflectance {R.max():.3f} at {l[R.argmax()]:.0f} nm")


if __name__ == "__main__":
    main()
