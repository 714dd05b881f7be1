//! Environment maps (Mitsuba `envmap`).

use crate::texture::spectral::{upsample_texels, TexelSpectrum, Upsampling};
use pt_math::{fastmath, Distribution2D, Mat3, Vec2, Vec3};
use pt_spectrum::{NamedIlluminant, SampledSpectrum, SampledWavelengths, Spectrum};
use std::f32::consts::PI;

/// A latitude-longitude environment map (Mitsuba 3 `envmap` conventions): the direction `d` in
/// map space (y up) has `u = atan2(d.x, -d.z) / (2 pi)` (wrapped to [0,1)) and
/// `v = acos(d.y) / pi`; radiance is bilinearly interpolated, with pixel centres at
/// `u = (x + 0.5) / W` (wrapping) and rows at `v = y / (H - 1)` (row 0 on the +y pole), as
/// Mitsuba 3 does (checked against its reference render of scenes/envmap.xml). Sampled by a piecewise-constant distribution over pixels proportional
/// to the largest luminance in each pixel's bilinear footprint times sin(theta), so that every
/// direction with non-zero radiance has a non-zero pdf.
///
/// Spectral mode ([`EnvMap::upsample`]): each texel becomes `scale * S(lambda)` (the sigmoid fit
/// of `rgb / (2 max rgb)`, scale `2 max rgb`; `spectral_texture.rs`), and a lookup multiplies
/// the bilinear interpolant of the four texels' sigmoid values by the interpolant of their
/// scales, as Mitsuba 3's `envmap` does (module docs of `texture::spectral`), times D65 of
/// luminance 1. The sampling distribution stays the RGB one above (the
/// radiance's support is the same: a texel has scale 0 exactly when it is black), so `sample`
/// and `pdf` are unchanged and consistent.
#[derive(Clone, Debug)]
pub struct EnvMap {
    width: usize,
    height: usize,
    /// Linear RGB radiance times scale, row-major from v = 0 (the +y pole).
    texels: Vec<[f32; 3]>,
    /// Spectral mode: the texels' spectra (same layout) and the D65 they multiply; `None` in
    /// RGB mode.
    spectral: Option<(Vec<TexelSpectrum>, Spectrum)>,
    distr: Distribution2D,
    to_world: Mat3,
    to_local: Mat3,
}

impl EnvMap {
    /// Builds from an image (row-major, top row = +y pole) and a map-to-world rotation.
    pub fn new(width: usize, height: usize, texels: Vec<[f32; 3]>, to_world: Mat3) -> Option<Self> {
        if width == 0 || height == 0 || texels.len() != width * height {
            return None;
        }
        let lum = |t: [f32; 3]| (0.212_671 * t[0] + 0.715_160 * t[1] + 0.072_169 * t[2]).max(0.0);
        let mut w = vec![0.0f32; width * height];
        for y in 0..height {
            let sin_t = (PI * (y as f32 + 0.5) / height as f32).sin();
            for x in 0..width {
                // Max over the 3x3 neighbourhood covers the bilinear footprint of this cell.
                let mut m = 0.0f32;
                for dy in [-1i64, 0, 1] {
                    let yy = (y as i64 + dy).clamp(0, height as i64 - 1) as usize;
                    for dx in [-1i64, 0, 1] {
                        let xx = (x as i64 + dx).rem_euclid(width as i64) as usize;
                        m = m.max(lum(texels[yy * width + xx]));
                    }
                }
                w[y * width + x] = m * sin_t;
            }
        }
        let distr = Distribution2D::new(&w, width, height)?;
        Some(EnvMap {
            width,
            height,
            texels,
            spectral: None,
            distr,
            to_world,
            to_local: to_world.transpose(),
        })
    }

    #[inline(always)]
    pub(super) fn dir_to_uv(&self, world: Vec3) -> Vec2 {
        let d = self.to_local * world;
        let mut u = fastmath::atan2(d.x, -d.z) * (0.5 / PI);
        if u < 0.0 {
            u += 1.0;
        }
        Vec2::new(u, fastmath::acos(d.y) / PI)
    }

    #[inline(always)]
    pub(super) fn uv_to_dir(&self, uv: Vec2) -> (Vec3, f32) {
        let (phi, theta) = (2.0 * PI * uv.x, PI * uv.y);
        let (st, ct) = theta.sin_cos();
        let local = Vec3::new(st * phi.sin(), ct, -st * phi.cos());
        (self.to_world * local, st)
    }

    /// Spectral mode: upsamples every texel (load time; see the type's docs).
    pub fn upsample(&mut self) {
        self.spectral = Some((
            upsample_texels(&self.texels, self.width, Upsampling::Emission),
            Spectrum::illuminant(NamedIlluminant::D65, 1.0),
        ));
    }

    /// The four texels (indices a, b, c, d: (x0, y0), (x0 + 1, y0), (x0, y0 + 1),
    /// (x0 + 1, y0 + 1)) and the bilinear weights (fx, fy) of a lookup at `uv`.
    #[inline(always)]
    fn footprint(&self, uv: Vec2) -> ([usize; 4], f32, f32) {
        // Mitsuba 3's envmap: columns are pixel centres (u = (x + 0.5) / W, wrapping), rows span
        // the poles exactly (row 0 at v = 0, row H-1 at v = 1).
        let x = uv.x * self.width as f32 - 0.5;
        let y = (uv.y * (self.height - 1) as f32).clamp(0.0, (self.height - 1) as f32);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let xi = |k: f32| (k as i64).rem_euclid(self.width as i64) as usize;
        let yi = |k: f32| (k as usize).min(self.height - 1);
        let t = |xx: f32, yy: f32| yi(yy) * self.width + xi(xx);
        (
            [
                t(x0, y0),
                t(x0 + 1.0, y0),
                t(x0, y0 + 1.0),
                t(x0 + 1.0, y0 + 1.0),
            ],
            fx,
            fy,
        )
    }

    /// Bilinearly interpolated radiance at `uv`.
    #[inline(always)]
    fn lookup(&self, uv: Vec2) -> [f32; 3] {
        let ([ia, ib, ic, id], fx, fy) = self.footprint(uv);
        let (a, b, c, d) = (
            self.texels[ia],
            self.texels[ib],
            self.texels[ic],
            self.texels[id],
        );
        std::array::from_fn(|k| {
            (a[k] * (1.0 - fx) + b[k] * fx) * (1.0 - fy) + (c[k] * (1.0 - fx) + d[k] * fx) * fy
        })
    }

    /// Radiance at `uv`: RGB lanes, or in spectral mode the interpolated sigmoid values times
    /// the interpolated scales (Mitsuba 3), at the path's wavelengths.
    #[inline(always)]
    fn radiance_uv(&self, uv: Vec2, lambda: &SampledWavelengths) -> SampledSpectrum {
        let Some((spec, d65)) = &self.spectral else {
            return SampledSpectrum::from_rgb(self.lookup(uv));
        };
        let (idx, fx, fy) = self.footprint(uv);
        let [a, b, c, d] = idx.map(|i| spec[i]);
        let l = lambda.lambda();
        let s = |t: TexelSpectrum| t.sigmoid.eval4(l);
        let sig =
            (s(a) * (1.0 - fx) + s(b) * fx) * (1.0 - fy) + (s(c) * (1.0 - fx) + s(d) * fx) * fy;
        let scale = (a.scale * (1.0 - fx) + b.scale * fx) * (1.0 - fy)
            + (c.scale * (1.0 - fx) + d.scale * fx) * fy;
        SampledSpectrum(sig * scale) * d65.sample(lambda)
    }

    /// Radiance arriving from world direction `dir` (unit, pointing away from the scene), at the
    /// path's wavelengths `lambda` (spectral mode).
    #[inline(always)]
    pub fn radiance(&self, dir: Vec3, lambda: &SampledWavelengths) -> SampledSpectrum {
        self.radiance_uv(self.dir_to_uv(dir), lambda)
    }

    /// Solid-angle pdf of sampling `dir`.
    #[inline(always)]
    pub fn pdf(&self, dir: Vec3) -> f32 {
        let uv = self.dir_to_uv(dir);
        let sin_t = (PI * uv.y).sin();
        if sin_t <= 0.0 {
            return 0.0;
        }
        self.distr.pdf(uv) / (2.0 * PI * PI * sin_t)
    }

    /// Samples a direction: (dir, radiance at the path's wavelengths, solid-angle pdf).
    #[inline(always)]
    pub fn sample(
        &self,
        u: Vec2,
        lambda: &SampledWavelengths,
    ) -> Option<(Vec3, SampledSpectrum, f32)> {
        let (uv, pdf_uv) = self.distr.sample(u);
        let (dir, sin_t) = self.uv_to_dir(uv);
        if sin_t <= 0.0 || pdf_uv <= 0.0 {
            return None;
        }
        Some((
            dir,
            self.radiance_uv(uv, lambda),
            pdf_uv / (2.0 * PI * PI * sin_t),
        ))
    }

    /// Mean radiance luminance over the sphere (for light selection).
    pub fn mean_luminance(&self) -> f32 {
        let mut acc = 0.0f64;
        let mut wsum = 0.0f64;
        for y in 0..self.height {
            let s = (PI * (y as f32 + 0.5) / self.height as f32).sin() as f64;
            for x in 0..self.width {
                let t = self.texels[y * self.width + x];
                acc += s * (0.212_671 * t[0] + 0.715_160 * t[1] + 0.072_169 * t[2]) as f64;
                wsum += s;
            }
        }
        (acc / wsum.max(1e-30)) as f32
    }
}
