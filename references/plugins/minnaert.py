"""Mitsuba 3 Python BSDF plugin `minnaert`: the project's Minnaert lunar-type reflection.

A port of crates/pt-bsdf/src/minnaert.rs (eval, pdf, sample and the documented rule for k < 1);
that file's module documentation gives the formulas.  Same plugin name and parameters as the Rust
scene loader (crates/pt-scene/src/materials.rs):

    <bsdf type="minnaert">
        <rgb name="reflectance" value="0.5, 0.5, 0.5"/>   <!-- texture/spectrum, default 0.5 -->
        <float name="k" value="1.5"/>                     <!-- > 0, default 1 (Lambert) -->
    </bsdf>

    f = rho (k+1)/(2 pi) cos_i^(k-1) V(cos_o),  V = cos_o^(k-1) for k >= 1, V = 1 for k < 1

(cos_i towards the light, cos_o towards the viewer; one-sided; cos_i is clamped to
[1e-12, 1] inside cos_i^(k-1)).  Mitsuba's `si.wi` is the viewer direction (Rust `wo`), the `wo`
passed to eval is the light direction (Rust `wi`); `eval` returns f * cos_i.

Sampling is the Rust sampler, exact for the cos_i part: cos theta = u^(1/(k+1)), phi = 2 pi v,
pdf (k+1)/(2 pi) cos^k, weight rho V(cos_o) (constant over samples).

Dr.Jit operations only, so it runs in scalar_* and llvm_ad_* variants.  make_references.py
imports this module and calls register() after every mi.set_variant.
"""

import math

PI = math.pi
MIN_COS = 1e-12


def register():
    import drjit as dr
    import mitsuba as mi

    class Minnaert(mi.BSDF):
        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            self.m_reflectance = props.get_texture("reflectance", 0.5)
            k = float(props.get("k")) if props.has_property("k") else 1.0
            if not k > 0.0:
                raise ValueError(f"minnaert: k must be positive, got {k}")
            self.m_k = k
            flags = mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide
            self.m_components = [flags]
            self.m_flags = flags

        def _view_factor(self, cos_o):
            if self.m_k >= 1.0:
                return dr.power(dr.minimum(cos_o, 1.0), self.m_k - 1.0)
            return 1.0

        def _pdf(self, si, wl, active):
            valid = active & (si.wi.z > 0.0) & (wl.z > 0.0)
            p = (self.m_k + 1.0) / (2.0 * PI) * dr.power(dr.minimum(wl.z, 1.0), self.m_k)
            return dr.select(valid, p, 0.0)

        def eval(self, ctx, si, wo, active=True):
            if not ctx.is_enabled(mi.BSDFFlags.DiffuseReflection):
                return mi.Spectrum(0.0)
            valid = active & (si.wi.z > 0.0) & (wo.z > 0.0)
            k = self.m_k
            ci = dr.power(dr.clip(wo.z, MIN_COS, 1.0), k - 1.0)
            rho = self.m_reflectance.eval(si, valid)
            f = rho * ((k + 1.0) / (2.0 * PI) * ci * self._view_factor(si.wi.z))
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
            k = self.m_k
            cos = dr.power(sample2.x, 1.0 / (k + 1.0))
            sin = dr.sqrt(dr.maximum(1.0 - cos * cos, 0.0))
            sp, cp = dr.sincos(2.0 * PI * sample2.y)
            wl = mi.Vector3f(sin * cp, sin * sp, cos)
            bs.wo = wl
            bs.pdf = self._pdf(si, wl, active)
            bs.eta = 1.0
            bs.sampled_type = mi.UInt32(+mi.BSDFFlags.DiffuseReflection)
            bs.sampled_component = mi.UInt32(0)
            ok = active & (bs.pdf > 0.0) & dr.isfinite(bs.pdf)
            rho = self.m_reflectance.eval(si, ok)
            weight = rho * self._view_factor(si.wi.z)
            return bs, dr.select(ok, weight, 0.0)

        def eval_diffuse_reflectance(self, si, active=True):
            return self.m_reflectance.eval(si, active)

        def to_string(self):
            return f"Minnaert[python plugin, k={self.m_k}, reflectance={self.m_reflectance}]"

    mi.register_bsdf("minnaert", lambda props: Minnaert(props))
