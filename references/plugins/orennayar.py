"""Mitsuba 3 Python BSDF plugin `orennayar`: the project's Oren-Nayar model (four variants).

A line-by-line port of crates/pt-bsdf/src/oren_nayar.rs (`OrenNayar::eval`, `eval_full`,
`fon_albedo`, `qualitative_ab`, `fujii_roughness`); that file's module documentation gives the
formulas and their sources.  Same plugin name and parameters as the Rust scene loader
(crates/pt-scene/src/materials.rs):

    <bsdf type="orennayar">
        <rgb name="reflectance" value="0.8, 0.6, 0.4"/>   <!-- texture/spectrum, default 0.5 -->
        <float name="sigma" value="0.35"/>                <!-- radians, >= 0, default 0 -->
        <string name="variant" value="eon"/>              <!-- qualitative|full|fujii|eon -->
    </bsdf>

Conventions.  Mitsuba's `si.wi` points to the viewer (the Rust `wo`, cosine `cos_o`) and the `wo`
passed to eval/pdf points to the light (the Rust `wi`, cosine `cos_i`).  `eval` returns
f * cos_i (Mitsuba's convention), the Rust `eval` returns f.  One-sided: zero unless both
cosines are > 0.

Sampling is cosine-weighted for every variant (pdf cos_i / pi).  The Rust code samples EON with
the paper's CLTC/uniform mixture instead: that changes only the variance, not the expectation.

The code is written with Dr.Jit operations only (no Python branches on data), so it runs in the
scalar_* and llvm_ad_* variants.  make_references.py imports this module and calls register()
after every mi.set_variant.  Validated by check_plugins.py (see references/README.md).
"""

import math

PI = math.pi
INV_PI = 1.0 / math.pi
# float32 constants as in the Rust code (f32 arithmetic on the consts).
C1_FON = 0.5 - 2.0 / (3.0 * PI)               # FON's A_F = 1 / (1 + C1_FON r)
C2_FON = 2.0 / 3.0 - 28.0 / (15.0 * PI)       # FON's average albedo A_F (1 + C2_FON r)
EPS = 1e-7
VARIANT_NAMES = ("qualitative", "full", "fujii", "eon")


def qualitative_ab(sigma):
    """(A, B) of the qualitative model for slope deviation sigma (radians)."""
    s2 = sigma * sigma
    return 1.0 - 0.5 * s2 / (s2 + 0.33), 0.45 * s2 / (s2 + 0.09)


def fujii_roughness(sigma):
    """Fujii's roughness r = B/A of the qualitative model (maps [0, inf) to [0, 0.9))."""
    a, b = qualitative_ab(max(sigma, 0.0))
    return b / a


def parameters(sigma, variant):
    """(a, b) precomputed as OrenNayar::new does: (A, B) for qualitative/full, (A_F, r) for
    fujii/eon.  Plain Python floats."""
    sigma = sigma if math.isfinite(sigma) else 0.0
    sigma = max(sigma, 0.0)
    if variant in ("qualitative", "full"):
        return qualitative_ab(sigma)
    r = fujii_roughness(sigma)
    r = min(max(r, 0.0), 1.0)
    return 1.0 / (1.0 + C1_FON * r), r


def register():
    import drjit as dr
    import mitsuba as mi

    def fon_albedo(mu, r):
        """Exact FON directional albedo at rho = 1 (EON Listing 1, rewritten to be finite at
        mu = 0 exactly as the Rust fon_albedo)."""
        mu = dr.clip(mu, 0.0, 1.0)
        a_f = 1.0 / (1.0 + C1_FON * r)
        b_f = r * a_f
        si = dr.sqrt(dr.maximum(1.0 - mu * mu, 0.0))
        g = si * (dr.acos(mu) - si * mu) + (2.0 / 3.0) * (
            si * mu * (1.0 + si + si * si) / (1.0 + si) - si)
        return a_f + b_f * INV_PI * g

    class OrenNayar(mi.BSDF):
        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            self.m_reflectance = props.get_texture("reflectance", 0.5)
            sigma = float(props.get("sigma")) if props.has_property("sigma") else 0.0
            if not sigma >= 0.0:
                raise ValueError(f"orennayar: sigma (radians) must be >= 0, got {sigma}")
            variant = (str(props.get("variant")) if props.has_property("variant")
                       else "qualitative").lower()
            if variant not in VARIANT_NAMES:
                raise ValueError(f"orennayar: unknown Oren-Nayar variant '{variant}' "
                                 "(qualitative, full, fujii, eon)")
            self.m_sigma = sigma
            self.m_variant = variant
            self.m_a, self.m_b = parameters(sigma, variant)
            flags = mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide
            self.m_components = [flags]
            self.m_flags = flags

        # ---- f(wo, wi) without the cosine, Rust notation: cos_o viewer, cos_i light ----
        def _f(self, si, wl, active):
            """f (no cosine) for Mitsuba's si.wi (viewer) and wl (light); zero unless both
            cosines are > 0."""
            wv = si.wi
            cos_i_raw, cos_o_raw = wl.z, wv.z
            valid = active & (cos_i_raw > 0.0) & (cos_o_raw > 0.0)
            cos_i = dr.minimum(cos_i_raw, 1.0)
            cos_o = dr.minimum(cos_o_raw, 1.0)
            s = dr.dot(wl, wv) - cos_i * cos_o
            rho = self.m_reflectance.eval(si, valid)
            a, b = self.m_a, self.m_b
            v = self.m_variant
            if v == "qualitative":
                t = dr.maximum(cos_i, cos_o)
                f = rho * (INV_PI * (a + b * dr.maximum(s, 0.0) / t))
            elif v == "fujii" or v == "eon":
                r = b
                s_over_t = dr.select(s > 0.0, s / dr.maximum(cos_i, cos_o), s)
                f = rho * (INV_PI * a * dr.maximum(1.0 + r * s_over_t, 0.0))
                if v == "eon":
                    e_o = fon_albedo(cos_o, r)
                    e_i = fon_albedo(cos_i, r)
                    avg = a * (1.0 + C2_FON * r)
                    lobe = (INV_PI * dr.maximum(1.0 - e_o, EPS) * dr.maximum(1.0 - e_i, EPS)
                            / max(1.0 - avg, EPS))
                    rho_ms = rho * rho * avg / dr.maximum(1.0 - rho * (1.0 - avg), EPS)
                    f = f + rho_ms * lobe
            else:  # full
                sigma2 = self.m_sigma * self.m_sigma
                theta_i = dr.acos(cos_i)
                theta_o = dr.acos(cos_o)
                alpha = dr.maximum(theta_i, theta_o)
                beta = dr.minimum(theta_i, theta_o)
                sin_i = dr.sqrt(dr.maximum(1.0 - cos_i_raw * cos_i_raw, 0.0))
                sin_o = dr.sqrt(dr.maximum(1.0 - cos_o_raw * cos_o_raw, 0.0))
                denom = sin_i * sin_o
                cos_phi = dr.select(denom > 1e-6,
                                    dr.clip(s / dr.select(denom > 1e-6, denom, 1.0), -1.0, 1.0),
                                    0.0)
                k = 0.45 * sigma2 / (sigma2 + 0.09)
                two_beta_pi = 2.0 * beta / PI
                sin_alpha = dr.sin(alpha)
                c2 = dr.select(cos_phi >= 0.0, k * sin_alpha,
                               k * (sin_alpha - two_beta_pi * two_beta_pi * two_beta_pi))
                x = 4.0 * alpha * beta / (PI * PI)
                c3 = 0.125 * sigma2 / (sigma2 + 0.09) * (x * x)
                tan_beta = dr.sin(beta) / dr.maximum(dr.cos(beta), 1e-7)
                half = 0.5 * (alpha + beta)
                tan_half = dr.sin(half) / dr.maximum(dr.cos(half), 1e-7)
                l1 = INV_PI * (a + cos_phi * c2 * tan_beta
                               + (1.0 - dr.abs(cos_phi)) * c3 * tan_half)
                l2 = (INV_PI * 0.17 * sigma2 / (sigma2 + 0.13)
                      * (1.0 - cos_phi * two_beta_pi * two_beta_pi))
                f = dr.maximum(rho * l1 + rho * rho * l2, 0.0)
            return dr.select(valid, f, 0.0), valid

        def _pdf(self, si, wl, active):
            valid = active & (si.wi.z > 0.0) & (wl.z > 0.0)
            return dr.select(valid, mi.warp.square_to_cosine_hemisphere_pdf(wl), 0.0)

        # ---- Mitsuba interface ----
        def eval(self, ctx, si, wo, active=True):
            if not ctx.is_enabled(mi.BSDFFlags.DiffuseReflection):
                return mi.Spectrum(0.0)
            f, valid = self._f(si, wo, active)
            return dr.select(valid, f * wo.z, 0.0)

        def pdf(self, ctx, si, wo, active=True):
            if not ctx.is_enabled(mi.BSDFFlags.DiffuseReflection):
                return mi.Float(0.0)
            return self._pdf(si, wo, active)

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

        def sample(self, ctx, si, sample1, sample2, active=True):
            bs = mi.BSDFSample3f()
            active = active & (si.wi.z > 0.0)
            if not ctx.is_enabled(mi.BSDFFlags.DiffuseReflection):
                return bs, mi.Spectrum(0.0)
            wl = mi.warp.square_to_cosine_hemisphere(sample2)
            bs.wo = wl
            bs.pdf = self._pdf(si, wl, active)
            bs.eta = 1.0
            bs.sampled_type = mi.UInt32(+mi.BSDFFlags.DiffuseReflection)
            bs.sampled_component = mi.UInt32(0)
            f, valid = self._f(si, wl, active)
            ok = valid & (bs.pdf > 0.0)
            weight = dr.select(ok, f * wl.z / dr.select(ok, bs.pdf, 1.0), 0.0)
            return bs, weight

        def eval_diffuse_reflectance(self, si, active=True):
            return self.m_reflectance.eval(si, active)

        def to_string(self):
            return (f"OrenNayar[python plugin, variant={self.m_variant}, sigma={self.m_sigma}, "
                    f"a={self.m_a}, b={self.m_b}, reflectance={self.m_reflectance}]")

    mi.register_bsdf("orennayar", lambda props: OrenNayar(props))
