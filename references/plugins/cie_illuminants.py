"""Mitsuba 3 Python spectrum plugins `a` and `f1` .. `f12`: the CIE standard illuminant A and the
CIE fluorescent lamps F1-F12, which pt reads as `<spectrum type="f11">` (scenes/README.md,
"Spectra and colours") and Mitsuba 3.9.1 does not have.

    <spectrum name="radiance" type="f11">
        <float name="scale" value="16"/>      <!-- luminance Y of the emission, default 1 -->
    </spectrum>

Same meaning as pt (crates/pt-spectrum/src/spectrum.rs, `Spectrum::illuminant`): the relative
spectral power distribution scaled so that its luminance Y (the CIE 1931 y-bar integral over
360-830 nm divided by y-bar's own integral, the film's convention) equals `scale`, as Mitsuba's
`d65` plugin scales D65.

Data, not code, carries over: F1-F12 are read from the table pt compiles in
(crates/pt-spectrum/src/data/cie_tables.rs, CIE 15:2004 via colour-science 0.4.7: 380-780 nm at
5 nm, zero outside); illuminant A is CIE 15:2004's closed form (Planck at 2848 K with
c2 = 1.435e-2 m K, normalised to 100 at 560 nm). The normalisation integrates the SPD against
Mitsuba's own y-bar with Simpson's rule on every 1 nm interval (pt: `cie::integrate_visible`).

Evaluation and wavelength sampling are Mitsuba's `regular` spectrum plugin holding the table
(A tabulated at 1 nm), times the factor. Spectral variants only: pt renders these scenes
spectrally and make_references.py picks a spectral variant for any `<spectrum type=...>`.
"""

import math
import re
from pathlib import Path

TABLES = Path(__file__).resolve().parents[2] / "crates" / "pt-spectrum" / "src" / "data" / "cie_tables.rs"


def f_series():
    """The twelve F tables (81 values each, 380-780 nm at 5 nm) from pt's source."""
    text = TABLES.read_text()
    start = text.index("pub static F_SERIES")
    eq = text.index("=", start)
    body = text[eq : text.index("];", eq)]
    rows = re.findall(r"\[([^\[\]]*)\]", body)
    tables = [[float(x) for x in row.replace("\n", " ").split(",") if x.strip()] for row in rows]
    if len(tables) != 12 or any(len(t) != 81 for t in tables):
        raise RuntimeError(f"{TABLES}: F_SERIES is not 12 rows of 81 values")
    return tables


def illuminant_a(lam):
    """CIE illuminant A at `lam` nm (CIE 15:2004, eq. 1 with c2 = 1.435e-2 m K)."""
    c2 = 1.435e7  # nm K
    return 100.0 * (560.0 / lam) ** 5 * (math.exp(c2 / (2848.0 * 560.0)) - 1.0) / (math.exp(c2 / (2848.0 * lam)) - 1.0)


def luminance_factor(spd, ybar, y_integral):
    """`y_integral / integral(spd ybar)` over 360-830 nm, Simpson on each 1 nm interval; `ybar`
    holds y-bar at 360, 360.5, ..., 830 nm."""
    total = 0.0
    for k in range(470):
        lam = 360.0 + k
        total += (spd(lam) * ybar[2 * k] + 4.0 * spd(lam + 0.5) * ybar[2 * k + 1] + spd(lam + 1.0) * ybar[2 * k + 2]) / 6.0
    return y_integral / total


def half_nm_ybar(mi):
    """Mitsuba's CIE 1931 y-bar at 360, 360.5, ..., 830 nm (one vectorised call in the JIT
    variants; scalar variants take one wavelength at a time)."""
    xs = [360.0 + 0.5 * k for k in range(941)]
    if mi.variant().startswith("scalar"):
        return [float(mi.cie1931_y(x)) for x in xs]
    return [float(v) for v in mi.cie1931_y(mi.Float(xs))]


def linear(lo, step, values):
    """The piecewise-linear function through `values` from `lo` nm in steps of `step`, zero
    outside (as pt's `lerp_table` and Mitsuba's `regular` spectrum)."""
    hi = lo + step * (len(values) - 1)

    def f(lam):
        if lam < lo or lam > hi:
            return 0.0
        x = (lam - lo) / step
        i = min(int(x), len(values) - 2)
        t = x - i
        return values[i] * (1.0 - t) + values[i + 1] * t

    return f


def register():
    import mitsuba as mi

    if not mi.is_spectral:
        return
    ybar = half_nm_ybar(mi)
    y_integral = 1.0 / mi.MI_CIE_Y_NORMALIZATION

    tables = {f"f{n + 1}": (380.0, 5.0, t) for n, t in enumerate(f_series())}
    tables["a"] = (360.0, 1.0, [illuminant_a(float(l)) for l in range(360, 831)])

    def make(name):
        lo, step, values = tables[name]
        factor_unit = luminance_factor(linear(lo, step, values), ybar, y_integral)

        class Illuminant(mi.Texture):
            def __init__(self, props):
                mi.Texture.__init__(self, props)
                scale = float(props.get("scale")) if props.has_property("scale") else 1.0
                self.m_factor = scale * factor_unit
                self.m_inner = mi.load_dict(
                    {
                        "type": "regular",
                        "wavelength_min": lo,
                        "wavelength_max": lo + step * (len(values) - 1),
                        "values": ", ".join(repr(v) for v in values),
                    }
                )

            def eval(self, si, active=True):
                return self.m_inner.eval(si, active) * self.m_factor

            def sample_spectrum(self, si, sample, active=True):
                wavelengths, weight = self.m_inner.sample_spectrum(si, sample, active)
                return wavelengths, weight * self.m_factor

            def pdf_spectrum(self, si, active=True):
                return self.m_inner.pdf_spectrum(si, active)

            def mean(self):
                return self.m_inner.mean() * self.m_factor

            def is_spatially_varying(self):
                return False

            def to_string(self):
                return f"CIE illuminant {name.upper()} (pt extension), factor {self.m_factor}"

        return Illuminant

    for name in tables:
        mi.register_texture(name, make(name))
