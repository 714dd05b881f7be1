"""Mitsuba 3 Python BSDF plugins `thinfilm` and `roughthinfilm`: the project's thin-film models.

A port of the spectral path of crates/pt-bsdf/src/thin_film.rs (`ThinFilm::spectral` and
`ThinFilm::sample`); that file's module documentation gives the physics (Born & Wolf 1999,
Sec. 1.6.4 and 7.6.1: Airy summation of the film's two interfaces, s and p intensities averaged).
Same plugin name and parameters as the Rust scene loader (crates/pt-scene/src/materials.rs):

    <bsdf type="thinfilm">
        <float name="thickness" value="500"/>    <!-- nm, >= 0, default 500 -->
        <float name="film_ior" value="1.33"/>    <!-- film index, default 1.33 -->
        <float name="ext_ior" value="1"/>        <!-- outside index, default 1 -->
        <float name="int_ior" value="1.5"/>      <!-- dielectric base, or: -->
        <float name="eta" value="0.2"/> <float name="k" value="3.4"/>   <!-- conductor base -->
    </bsdf>

Limits of the port: spectral variants only (the RGB mode of pt uses Belcour & Barla's
integration, which this plugin does not reproduce); a conductor base only by constant `eta` and
`k` floats (pt upsamples RGB or named conductors with Jakob-Hanika, Mitsuba uses measured
spectra: those would differ in the base, not in the film). Both refuse with a clear message.

Lobes (as in Rust): reflection with the film's R per wavelength; for a dielectric base also
refraction (the parallel film does not bend the ray) with T = 1 - R, the lobe chosen with
probability P = mean of R over the four wavelengths, weights R / P and T / ((1 - P) eta'^2)
(radiance transport); total internal reflection in the last medium reflects everything.

Dr.Jit operations only, so it runs in the llvm_ad_spectral (and scalar_spectral) variants.
make_references.py imports this module and calls register() after every mi.set_variant.
"""

import math

PI = math.pi


def register():
    import drjit as dr
    import mitsuba as mi

    if not mi.variant().endswith("spectral"):
        # Registered anyway so that RGB scenes load; using it there raises below.
        spectral = False
    else:
        spectral = True

    # Complex numbers as (re, im) pairs of mi.Spectrum (one lane per wavelength).
    def c_add(a, b):
        return (a[0] + b[0], a[1] + b[1])

    def c_sub(a, b):
        return (a[0] - b[0], a[1] - b[1])

    def c_mul(a, b):
        return (a[0] * b[0] - a[1] * b[1], a[0] * b[1] + a[1] * b[0])

    def c_div(a, b):
        d = b[0] * b[0] + b[1] * b[1]
        return ((a[0] * b[0] + a[1] * b[1]) / d, (a[1] * b[0] - a[0] * b[1]) / d)

    def c_sqrt(z):
        # Principal root; an imaginary part of +0 (or -0) takes the +i branch, as the Rust
        # `q_of` does, so an evanescent wave decays into the film.
        m = dr.sqrt(z[0] * z[0] + z[1] * z[1])
        re = dr.sqrt(dr.maximum((m + z[0]) * 0.5, 0.0))
        im = dr.sqrt(dr.maximum((m - z[0]) * 0.5, 0.0))
        return (re, dr.select(z[1] < 0.0, -im, im))

    def c_exp_i(z):
        # e^{i z} = e^{-im} (cos re + i sin re)
        s, c = dr.sincos(z[0])
        a = dr.exp(-z[1])
        return (a * c, a * s)

    def airy(c, n0, nf, nb, d_nm, lam):
        """Film reflectance for cos(theta) = c in the outside medium n0 (real), film nf (real),
        base nb = (re, im) (Spectrum pair), thickness d_nm, wavelengths lam (nm, Spectrum)."""
        zero = mi.Spectrum(0.0)
        s2 = mi.Spectrum(n0 * n0 * (1.0 - c * c))
        q0 = (mi.Spectrum(n0 * c), zero)
        qf = c_sqrt((mi.Spectrum(nf * nf) - s2, zero))
        nb2 = c_mul(nb, nb)
        qb = c_sqrt((nb2[0] - s2, nb2[1]))
        n0c, nfc = (mi.Spectrum(n0), zero), (mi.Spectrum(nf), zero)
        n02, nf2 = c_mul(n0c, n0c), c_mul(nfc, nfc)

        def amplitudes(ni2, qi, nj2, qj):
            rs = c_div(c_sub(qi, qj), c_add(qi, qj))
            a, b = c_mul(nj2, qi), c_mul(ni2, qj)
            rp = c_div(c_sub(a, b), c_add(a, b))
            return rs, rp

        r01s, r01p = amplitudes(n02, q0, nf2, qf)
        r12s, r12p = amplitudes(nf2, qf, nb2, qb)
        k = 4.0 * PI * d_nm / lam
        e = c_exp_i((qf[0] * k, qf[1] * k))
        one = (mi.Spectrum(1.0), zero)

        def intensity(r01, r12):
            x = c_mul(r12, e)
            r = c_div(c_add(r01, x), c_add(one, c_mul(r01, x)))
            return r[0] * r[0] + r[1] * r[1]

        big_r = 0.5 * (intensity(r01s, r12s) + intensity(r01p, r12p))
        big_r = dr.select(dr.isfinite(big_r), big_r, 1.0)
        return dr.clip(big_r, 0.0, 1.0)

    class ThinFilm(mi.BSDF):
        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            get = lambda name, default: float(props.get(name)) if props.has_property(name) else default
            self.m_thickness = get("thickness", 500.0)
            self.m_film_ior = get("film_ior", 1.33)
            self.m_ext_ior = get("ext_ior", 1.0)
            if props.has_property("material"):
                raise ValueError("thinfilm plugin: give a conductor base as constant eta and k floats "
                                 "(named conductors are upsampled differently in pt and Mitsuba)")
            self.m_dielectric = props.has_property("int_ior")
            if self.m_dielectric:
                self.m_int_ior = get("int_ior", 1.5)
            else:
                self.m_eta = get("eta", 0.0)
                self.m_k = get("k", 1.0)
            if not (self.m_thickness >= 0.0):
                raise ValueError(f"thinfilm: thickness must be >= 0, got {self.m_thickness}")
            flags = mi.BSDFFlags.DeltaReflection | mi.BSDFFlags.FrontSide
            if self.m_dielectric:
                flags = flags | mi.BSDFFlags.DeltaTransmission | mi.BSDFFlags.BackSide
            self.m_components = [flags]
            self.m_flags = flags

        def _reflectance(self, si, cos_o):
            if not spectral:
                raise RuntimeError("thinfilm plugin: spectral variants only (scalar_spectral, llvm_ad_spectral)")
            lam = si.wavelengths
            c = dr.minimum(dr.abs(cos_o), 1.0)
            if self.m_dielectric:
                front = cos_o >= 0.0
                n0 = dr.select(front, self.m_ext_ior, self.m_int_ior)
                nb_re = dr.select(front, self.m_int_ior, self.m_ext_ior)
                nb = (mi.Spectrum(nb_re), mi.Spectrum(0.0))
            else:
                n0 = self.m_ext_ior
                nb = (mi.Spectrum(self.m_eta), mi.Spectrum(self.m_k))
            return airy(c, n0, self.m_film_ior, nb, self.m_thickness, lam)

        def eval(self, ctx, si, wo, active=True):
            return mi.Spectrum(0.0)

        def pdf(self, ctx, si, wo, active=True):
            return mi.Float(0.0)

        def eval_pdf(self, ctx, si, wo, active=True):
            return mi.Spectrum(0.0), mi.Float(0.0)

        def sample(self, ctx, si, sample1, sample2, active=True):
            bs = mi.BSDFSample3f()
            cos_o = si.wi.z
            active = active & (cos_o != 0.0)
            refl = mi.Vector3f(-si.wi.x, -si.wi.y, si.wi.z)
            r = self._reflectance(si, cos_o)
            bs.sampled_component = mi.UInt32(0)
            if not self.m_dielectric:
                active = active & (cos_o > 0.0)
                bs.wo = refl
                bs.pdf = mi.Float(1.0)
                bs.eta = mi.Float(1.0)
                bs.sampled_type = mi.UInt32(+mi.BSDFFlags.DeltaReflection)
                return bs, dr.select(active, r, 0.0)
            # Refraction through the stack: from n_in (viewer side) into n_out.
            front = cos_o > 0.0
            n_in = dr.select(front, self.m_ext_ior, self.m_int_ior)
            n_out = dr.select(front, self.m_int_ior, self.m_ext_ior)
            ratio = n_in / n_out
            c = dr.abs(cos_o)
            sin2_t = (1.0 - c * c) * ratio * ratio
            tir = sin2_t >= 1.0
            cos_t = dr.sqrt(dr.maximum(1.0 - sin2_t, 0.0))
            wt = mi.Vector3f(-si.wi.x * ratio, -si.wi.y * ratio, dr.select(front, -cos_t, cos_t))
            p = dr.clip((r[0] + r[1] + r[2] + r[3]) * 0.25, 0.0, 1.0)
            choose_r = tir | ((p > 0.0) & ((sample1 < p) | (p >= 1.0)))
            etap = n_out / n_in
            w_r = dr.select(tir, mi.Spectrum(1.0), r / dr.select(p > 0.0, p, 1.0))
            w_t = (1.0 - r) / dr.maximum((1.0 - p) * etap * etap, 1e-30)
            bs.wo = dr.select(choose_r, refl, wt)
            bs.pdf = dr.select(tir, 1.0, dr.select(choose_r, p, 1.0 - p))
            bs.eta = dr.select(choose_r, 1.0, etap)
            bs.sampled_type = dr.select(choose_r, mi.UInt32(+mi.BSDFFlags.DeltaReflection),
                                        mi.UInt32(+mi.BSDFFlags.DeltaTransmission))
            weight = dr.select(choose_r, w_r, w_t)
            return bs, dr.select(active, weight, 0.0)

        def to_string(self):
            base = f"int_ior={self.m_int_ior}" if self.m_dielectric else f"eta={self.m_eta}, k={self.m_k}"
            return (f"ThinFilm[python plugin, thickness={self.m_thickness} nm, film_ior={self.m_film_ior}, "
                    f"ext_ior={self.m_ext_ior}, {base}]")

    mi.register_bsdf("thinfilm", lambda props: ThinFilm(props))

    class RoughThinFilm(mi.BSDF):
        """`roughthinfilm` on a conductor base: a rough conductor (Walter et al. 2007) whose
        Fresnel term is the film's Airy reflectance at the facet angle (Belcour & Barla 2017,
        Sec. 3), as crates/pt-bsdf/src/rough_thin_film.rs. GGX or Beckmann, isotropic or not,
        Mitsuba's visible-normal sampling and separable Smith G (as pt)."""

        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            get = lambda name, default: float(props.get(name)) if props.has_property(name) else default
            self.m_thickness = get("thickness", 500.0)
            self.m_film_ior = get("film_ior", 1.33)
            self.m_ext_ior = get("ext_ior", 1.0)
            if props.has_property("int_ior") or props.has_property("material"):
                raise ValueError("roughthinfilm plugin: only a conductor base given by constant eta and k floats "
                                 "is ported (the dielectric base is tested in pt's unit tests)")
            self.m_eta = get("eta", 0.0)
            self.m_k = get("k", 1.0)
            dist = str(props.get("distribution")) if props.has_property("distribution") else "beckmann"
            kind = {"ggx": mi.MicrofacetType.GGX, "beckmann": mi.MicrofacetType.Beckmann}[dist]
            if props.has_property("alpha"):
                au = av = get("alpha", 0.1)
            else:
                au, av = get("alpha_u", 0.1), get("alpha_v", 0.1)
            self.m_distr = mi.MicrofacetDistribution(kind, au, av, True)
            flags = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide
            self.m_components = [flags]
            self.m_flags = flags

        def _r(self, si, cos_h):
            if not spectral:
                raise RuntimeError("roughthinfilm plugin: spectral variants only")
            nb = (mi.Spectrum(self.m_eta), mi.Spectrum(self.m_k))
            return airy(dr.clip(cos_h, 0.0, 1.0), self.m_ext_ior, self.m_film_ior, nb, self.m_thickness, si.wavelengths)

        def eval(self, ctx, si, wo, active=True):
            valid = active & (si.wi.z > 0.0) & (wo.z > 0.0)
            h = dr.normalize(si.wi + wo)
            d = self.m_distr.eval(h)
            g = self.m_distr.G(si.wi, wo, h)
            f = self._r(si, dr.dot(si.wi, h)) * (d * g / (4.0 * si.wi.z))
            return dr.select(valid & (d > 0.0), f, 0.0)

        def pdf(self, ctx, si, wo, active=True):
            valid = active & (si.wi.z > 0.0) & (wo.z > 0.0)
            h = dr.normalize(si.wi + wo)
            p = self.m_distr.pdf(si.wi, h) / (4.0 * dr.dot(wo, h))
            return dr.select(valid & (dr.dot(wo, h) > 0.0), p, 0.0)

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

        def sample(self, ctx, si, sample1, sample2, active=True):
            bs = mi.BSDFSample3f()
            active = active & (si.wi.z > 0.0)
            m, _ = self.m_distr.sample(si.wi, sample2)
            wo = mi.reflect(si.wi, m)
            bs.wo = wo
            bs.eta = mi.Float(1.0)
            bs.sampled_component = mi.UInt32(0)
            bs.sampled_type = mi.UInt32(+mi.BSDFFlags.GlossyReflection)
            bs.pdf = self.pdf(ctx, si, wo, active)
            ok = active & (wo.z > 0.0) & (bs.pdf > 0.0)
            weight = self.eval(ctx, si, wo, ok) / dr.select(ok, bs.pdf, 1.0)
            return bs, dr.select(ok, weight, 0.0)

        def to_string(self):
            return f"RoughThinFilm[python plugin, thickness={self.m_thickness} nm, eta={self.m_eta}, k={self.m_k}]"

    mi.register_bsdf("roughthinfilm", lambda props: RoughThinFilm(props))
