//! Lights: area lights on shapes, point and spot lights, distant lights (directional, sun),
//! and environment lights (constant, environment map).
//!
//! Every light offers `sample` (a direction towards it from a reference point, with the
//! radiance arriving along it and the solid-angle pdf, or a `delta` flag for lights that cannot be
//! hit by a ray) and, for lights a BSDF-sampled ray can find, `pdf` for MIS.
//!
//! Area lights:
//! An area emitter radiates `radiance` from its front side only (the side its shading normal
//! faces), as Mitsuba's `area` emitter. Points are sampled uniformly by area over the whole
//! shape (triangles chosen by area, then uniform barycentrics; spheres uniformly over their
//! surface), so `pdf_area = 1 / total area`, and the solid-angle pdf seen from a point `x` is
//! `pdf_area * |x - y|^2 / |cos theta_y|` (pbrt-v4 eq. 4.15; Veach 1997 eq. 8.10).

use crate::spectral_texture::{SpectralEmission, TexelSpectrum};
use pt_math::warp::{
    square_to_uniform_cone, square_to_uniform_sphere, square_to_uniform_triangle, uniform_cone_pdf,
};
use pt_math::{Distribution1D, Distribution2D, Frame, Mat3, Vec2, Vec3};
use pt_spectrum::{SampledSpectrum, SampledWavelengths};
use std::f32::consts::PI;
use std::sync::Arc;

/// Shape data a mesh light samples from (world space).
#[derive(Clone, Debug)]
pub struct LightTriangle {
    /// Vertices.
    pub p: [Vec3; 3],
    /// Per-vertex shading normals, or the geometric normal three times.
    pub n: [Vec3; 3],
    /// Per-vertex texture coordinates (for textured emission).
    pub uv: [Vec2; 3],
}

/// The geometry of an area light.
#[derive(Clone, Debug)]
pub enum LightShape {
    /// Triangles with an area distribution.
    Mesh {
        /// The emitting triangles (zero-area ones removed).
        tris: Vec<LightTriangle>,
        /// Triangle choice proportional to area.
        distr: Distribution1D,
    },
    /// A parallelogram `v0 + a e1 + b e2`, `a, b` in [0, 1] (a `rectangle` emitter, or any
    /// emissive mesh of one triangle pair tested as a parallelogram): sampled by area directly,
    /// with no triangle choice and no square root.
    Parallelogram {
        /// Corner.
        v0: Vec3,
        /// First edge.
        e1: Vec3,
        /// Second edge.
        e2: Vec3,
        /// Unit normal of the emitting (front) side.
        n: Vec3,
        /// Texture coordinates at `v0`, and their change along `e1` and along `e2`.
        uv: [Vec2; 3],
    },
    /// A sphere (normal inwards when `flip`).
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius.
        radius: f32,
        /// Whether the front side faces inwards.
        flip: bool,
    },
}

/// An area light attached to one shape.
#[derive(Clone, Debug)]
pub struct AreaLight {
    /// Emitted radiance (W sr^-1 m^-2), constant over the surface (times `texture` if any).
    pub radiance: SampledSpectrum,
    /// Radiance image over the shape's texture coordinates (a monitor): the RGB-mode lookup,
    /// and in spectral mode the basis of the power estimate.
    pub texture: Option<std::sync::Arc<crate::texture::Bitmap>>,
    /// Spectral mode: the image's spectral form (upsampled texels or display primaries),
    /// which replaces `texture` for radiance lookups.
    pub spectral: Option<Arc<SpectralEmission>>,
    /// The emitting geometry.
    pub shape: LightShape,
    /// Total surface area, scene units squared.
    pub area: f32,
}

/// A point sampled on a light, as seen from a reference point.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// The point on the light, world space (for distant lights: unused).
    pub p: Vec3,
    /// The light's surface normal there (zero for point-like and distant lights: the shadow ray
    /// then needs no offset at the light's end).
    pub n: Vec3,
    /// Unit direction from the reference point towards the light.
    pub wi: Vec3,
    /// Distance to `p` (infinite for distant lights).
    pub dist: f32,
    /// Radiance arriving along `-wi` (for delta lights: the irradiance-like quantity
    /// `I / d^2` or `E`, to be divided by `pdf` = 1).
    pub radiance: SampledSpectrum,
    /// Solid-angle pdf of `wi` for this light alone (not including light selection); 1 for
    /// delta lights.
    pub pdf: f32,
    /// Whether the light is a delta light (point, spot, directional): no MIS, never hit.
    pub delta: bool,
}

impl AreaLight {
    /// Total emitted power estimate (for light selection): pi * area * luminance.
    pub fn power(&self) -> f32 {
        let scale = self.texture.as_ref().map_or(1.0, |t| t.mean_luminance());
        std::f32::consts::PI * self.area * self.radiance.luminance_rgb().max(0.0) * scale
    }

    /// The emitted radiance at texture coordinates `uv` (front side), before the one-sided test,
    /// at the path's wavelengths `lambda` (used only by spectral textures).
    #[inline(always)]
    fn radiance_at(&self, uv: Vec2, lambda: &SampledWavelengths) -> SampledSpectrum {
        if let Some(s) = &self.spectral {
            return self.radiance * s.eval(uv, lambda);
        }
        match &self.texture {
            Some(t) => self.radiance * SampledSpectrum::from_rgb(t.eval(uv)),
            None => self.radiance,
        }
    }

    /// Samples a point uniformly by area and converts to solid angle as seen from `x`.
    /// Returns `None` when the pdf is not finite (the point coincides with `x` or is seen
    /// exactly edge-on). `lambda`: the path's wavelengths (spectral textures).
    #[inline(always)]
    pub fn sample(
        &self,
        x: Vec3,
        u_sel: f32,
        u: Vec2,
        lambda: &SampledWavelengths,
    ) -> Option<LightSample> {
        if let LightShape::Sphere {
            center,
            radius,
            flip,
        } = &self.shape
        {
            if let Some(cone) = SphereCone::new(*center, *radius, x) {
                return cone.sample(u, *flip, self.radiance, x);
            }
        }
        let (p, n, uv) = match &self.shape {
            LightShape::Mesh { tris, distr } => {
                let (i, _, _) = distr.sample(u_sel);
                let t = &tris[i];
                let b = square_to_uniform_triangle(u);
                let b0 = 1.0 - b.x - b.y;
                let p = t.p[0] * b0 + t.p[1] * b.x + t.p[2] * b.y;
                let n = (t.n[0] * b0 + t.n[1] * b.x + t.n[2] * b.y).normalize_or_zero();
                (p, n, t.uv[0] * b0 + t.uv[1] * b.x + t.uv[2] * b.y)
            }
            &LightShape::Parallelogram { v0, e1, e2, n, uv } => (
                v0 + e1 * u.x + e2 * u.y,
                n,
                uv[0] + uv[1] * u.x + uv[2] * u.y,
            ),
            LightShape::Sphere {
                center,
                radius,
                flip,
            } => {
                let d = square_to_uniform_sphere(u);
                (
                    *center + d * *radius,
                    if *flip { -d } else { d },
                    Vec2::ZERO,
                )
            }
        };
        let to = p - x;
        let dist2 = to.length_squared();
        let dist = dist2.sqrt();
        if !(dist > 0.0) {
            return None;
        }
        let wi = to / dist;
        let cos_l = n.dot(-wi);
        let pdf = dist2 / (cos_l.abs() * self.area);
        if !pdf.is_finite() {
            return None;
        }
        let radiance = if cos_l > 0.0 {
            self.radiance_at(uv, lambda)
        } else {
            SampledSpectrum::ZERO
        };
        Some(LightSample {
            p,
            n,
            wi,
            dist,
            radiance,
            pdf,
            delta: false,
        })
    }

    /// Solid-angle pdf, from `x`, of having sampled the point `p` with normal `n` on this light
    /// (for MIS when a BSDF-sampled ray hits the light).
    #[inline]
    pub fn pdf(&self, x: Vec3, p: Vec3, n: Vec3) -> f32 {
        if let LightShape::Sphere { center, radius, .. } = &self.shape {
            if let Some(cone) = SphereCone::new(*center, *radius, x) {
                return uniform_cone_pdf(cone.one_minus_cos_max);
            }
        }
        let to = p - x;
        let dist2 = to.length_squared();
        let cos_l = n.dot(to).abs() / dist2.sqrt();
        let pdf = dist2 / (cos_l * self.area);
        if pdf.is_finite() {
            pdf
        } else {
            0.0
        }
    }

    /// Radiance leaving the light at a point with normal `n` towards direction `w` (unit,
    /// pointing away from the light), at the path's wavelengths `lambda` (spectral textures).
    #[inline]
    pub fn emitted(
        &self,
        n: Vec3,
        w: Vec3,
        uv: Vec2,
        lambda: &SampledWavelengths,
    ) -> SampledSpectrum {
        if n.dot(w) > 0.0 {
            self.radiance_at(uv, lambda)
        } else {
            SampledSpectrum::ZERO
        }
    }
}

/// Solid-angle sampling of a sphere seen from an outside point `x` (pbrt-v4 section 6.2.4,
/// "Sampling Spheres"): directions uniform in the cone the sphere subtends, pdf
/// 1 / (2 pi (1 - cos theta_max)), mapped to the visible point through the angle alpha at the
/// centre, `cos alpha = sin^2 theta / sin theta_max + cos theta sqrt(1 - sin^2 theta /
/// sin^2 theta_max)`, which needs no ray-sphere intersection and so never misses at the rim.
/// Much lower variance than area sampling for small or distant spheres, whose far half area
/// sampling wastes.
struct SphereCone {
    center: Vec3,
    radius: f32,
    /// Frame whose normal points from the centre towards `x`.
    frame: Frame,
    sin2_max: f32,
    one_minus_cos_max: f32,
}

impl SphereCone {
    /// `None` when `x` is inside (or on) the sphere: then area sampling is used.
    fn new(center: Vec3, radius: f32, x: Vec3) -> Option<Self> {
        let d = x - center;
        let d2 = d.length_squared();
        let r2 = radius * radius;
        // Margin: on the surface itself (NEE from a point of the emitter) keep area sampling.
        if !(d2 > r2 * 1.0001) {
            return None;
        }
        let sin2_max = r2 / d2;
        // 1 - sqrt(1 - s) computed as s / (1 + sqrt(1 - s)): no cancellation for small s.
        let one_minus_cos_max = sin2_max / (1.0 + (1.0 - sin2_max).sqrt());
        Some(SphereCone {
            center,
            radius,
            frame: Frame::from_normal(d / d2.sqrt()),
            sin2_max,
            one_minus_cos_max,
        })
    }

    fn sample(
        &self,
        u: Vec2,
        flip: bool,
        radiance: SampledSpectrum,
        x: Vec3,
    ) -> Option<LightSample> {
        let omc = u.x * self.one_minus_cos_max; // 1 - cos(theta), uniform in cos(theta)
        let cos_t = 1.0 - omc;
        let sin2_t = omc * (2.0 - omc);
        let cos_alpha =
            sin2_t / self.sin2_max.sqrt() + cos_t * (1.0 - sin2_t / self.sin2_max).max(0.0).sqrt();
        let sin_alpha = (1.0 - cos_alpha * cos_alpha).max(0.0).sqrt();
        let phi = 2.0 * PI * u.y;
        // The point's outward normal, measured from the axis towards x.
        let n_out = self
            .frame
            .to_world(Vec3::new(
                sin_alpha * phi.cos(),
                sin_alpha * phi.sin(),
                cos_alpha,
            ))
            .normalize();
        let p = self.center + n_out * self.radius;
        let to = p - x;
        let dist = to.length();
        if !(dist > 0.0) {
            return None;
        }
        let wi = to / dist;
        let n = if flip { -n_out } else { n_out };
        let radiance = if n.dot(-wi) > 0.0 {
            radiance
        } else {
            SampledSpectrum::ZERO
        };
        Some(LightSample {
            p,
            n,
            wi,
            dist,
            radiance,
            pdf: uniform_cone_pdf(self.one_minus_cos_max),
            delta: false,
        })
    }
}

/// Spot light falloff: 1 inside `beam_width`, 0 beyond `cutoff`, linear in angle between
/// (Mitsuba 3 `spot`).
#[derive(Clone, Copy, Debug)]
pub struct SpotCone {
    /// cos of the cutoff angle.
    pub cos_cutoff: f32,
    /// Cutoff angle, radians.
    pub cutoff: f32,
    /// Full-intensity half-angle, radians.
    pub beam_width: f32,
}

impl SpotCone {
    /// Falloff factor for a direction making cos(theta) = `cos_t` with the axis.
    #[inline]
    pub fn falloff(&self, cos_t: f32) -> f32 {
        if cos_t <= self.cos_cutoff {
            return 0.0;
        }
        let angle = cos_t.clamp(-1.0, 1.0).acos();
        if angle <= self.beam_width {
            1.0
        } else {
            ((self.cutoff - angle) / (self.cutoff - self.beam_width)).clamp(0.0, 1.0)
        }
    }
}

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
/// scales, as Mitsuba 3's `envmap` does (module docs of `spectral_texture`); the scene then
/// multiplies by D65 of luminance 1. The sampling distribution stays the RGB one above (the
/// radiance's support is the same: a texel has scale 0 exactly when it is black), so `sample`
/// and `pdf` are unchanged and consistent.
#[derive(Clone, Debug)]
pub struct EnvMap {
    width: usize,
    height: usize,
    /// Linear RGB radiance times scale, row-major from v = 0 (the +y pole).
    texels: Vec<[f32; 3]>,
    /// Spectral mode: the texels' spectra (same layout), `None` in RGB mode.
    spectral: Option<Vec<TexelSpectrum>>,
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

    fn dir_to_uv(&self, world: Vec3) -> Vec2 {
        let d = self.to_local * world;
        let mut u = d.x.atan2(-d.z) * (0.5 / PI);
        if u < 0.0 {
            u += 1.0;
        }
        Vec2::new(u, d.y.clamp(-1.0, 1.0).acos() / PI)
    }

    fn uv_to_dir(&self, uv: Vec2) -> (Vec3, f32) {
        let (phi, theta) = (2.0 * PI * uv.x, PI * uv.y);
        let (st, ct) = theta.sin_cos();
        let local = Vec3::new(st * phi.sin(), ct, -st * phi.cos());
        (self.to_world * local, st)
    }

    /// Spectral mode: upsamples every texel (load time; see the type's docs).
    pub fn upsample(&mut self) {
        self.spectral = Some(crate::spectral_texture::upsample_texels(
            &self.texels,
            self.width,
            crate::spectral_texture::Upsampling::Emission,
        ));
    }

    /// The four texels (indices a, b, c, d: (x0, y0), (x0 + 1, y0), (x0, y0 + 1),
    /// (x0 + 1, y0 + 1)) and the bilinear weights (fx, fy) of a lookup at `uv`.
    #[inline]
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
    #[inline]
    fn radiance_uv(&self, uv: Vec2, lambda: &SampledWavelengths) -> SampledSpectrum {
        let Some(spec) = &self.spectral else {
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
        SampledSpectrum(sig * scale)
    }

    /// Radiance arriving from world direction `dir` (unit, pointing away from the scene), at the
    /// path's wavelengths `lambda` (spectral mode).
    pub fn radiance(&self, dir: Vec3, lambda: &SampledWavelengths) -> SampledSpectrum {
        self.radiance_uv(self.dir_to_uv(dir), lambda)
    }

    /// Solid-angle pdf of sampling `dir`.
    pub fn pdf(&self, dir: Vec3) -> f32 {
        let uv = self.dir_to_uv(dir);
        let sin_t = (PI * uv.y).sin();
        if sin_t <= 0.0 {
            return 0.0;
        }
        self.distr.pdf(uv) / (2.0 * PI * PI * sin_t)
    }

    /// Samples a direction: (dir, radiance at the path's wavelengths, solid-angle pdf).
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

/// Any light of the scene.
#[derive(Clone, Debug)]
pub enum Light {
    /// An emitting shape.
    Area(AreaLight),
    /// Isotropic point light with intensity `intensity` (W/sr).
    Point {
        /// Position, world.
        position: Vec3,
        /// Radiant intensity, W/sr.
        intensity: SampledSpectrum,
    },
    /// Spot light at `position` pointing along `frame.n`.
    Spot {
        /// Position, world.
        position: Vec3,
        /// Frame whose normal is the spot axis.
        frame: Frame,
        /// Intensity on the axis, W/sr.
        intensity: SampledSpectrum,
        /// Angular falloff.
        cone: SpotCone,
    },
    /// Directional light: irradiance `irradiance` arriving from direction `to_light`.
    Directional {
        /// Unit direction from the scene towards the light, world.
        to_light: Vec3,
        /// Irradiance on a surface facing the light, W/m^2.
        irradiance: SampledSpectrum,
    },
    /// A disk of uniform radiance at infinity (the sun), sampled uniformly over its cone.
    Sun {
        /// Frame whose normal points from the scene towards the sun's centre.
        frame: Frame,
        /// Radiance of the disk: irradiance / (pi sin^2(alpha)), alpha the angular radius.
        radiance: SampledSpectrum,
        /// 1 - cos(alpha), computed without cancellation.
        one_minus_cos: f32,
    },
    /// Uniform radiance from every direction.
    Constant {
        /// Radiance, W sr^-1 m^-2.
        radiance: SampledSpectrum,
    },
    /// Environment map.
    EnvMap(EnvMap),
}

impl Light {
    /// Whether rays escaping the scene can see this light (environment and sun).
    pub fn is_infinite(&self) -> bool {
        matches!(
            self,
            Light::Sun { .. } | Light::Constant { .. } | Light::EnvMap(_)
        )
    }

    /// Power estimate for light selection, W (luminance). Distant lights use the scene's
    /// bounding sphere radius `r`: the power they deliver into it (pbrt-v4 `Phi`).
    pub fn power(&self, scene_radius: f32) -> f32 {
        let disk = PI * scene_radius * scene_radius;
        let p = match self {
            Light::Area(a) => a.power(),
            Light::Point { intensity, .. } => 4.0 * PI * intensity.luminance_rgb(),
            Light::Spot {
                intensity, cone, ..
            } => {
                // Full cone up to the mid-falloff angle: exact for a hard cutoff.
                let mid = 0.5 * (cone.cutoff + cone.beam_width);
                2.0 * PI * (1.0 - mid.cos()) * intensity.luminance_rgb()
            }
            Light::Directional { irradiance, .. } => disk * irradiance.luminance_rgb(),
            Light::Sun {
                radiance,
                one_minus_cos,
                ..
            } => {
                // E = L pi sin^2(alpha) = L pi (1 - cos)(1 + cos).
                disk * radiance.luminance_rgb() * PI * one_minus_cos * (2.0 - one_minus_cos)
            }
            Light::Constant { radiance } => 4.0 * PI * disk * radiance.luminance_rgb(),
            Light::EnvMap(e) => 4.0 * PI * disk * e.mean_luminance(),
        };
        p.max(0.0)
    }

    /// Samples a direction towards the light from `x`; `lambda` are the path's wavelengths
    /// (spectral textures and environment maps).
    #[inline(always)]
    pub fn sample(
        &self,
        x: Vec3,
        u_sel: f32,
        u: Vec2,
        lambda: &SampledWavelengths,
    ) -> Option<LightSample> {
        match self {
            Light::Area(a) => a.sample(x, u_sel, u, lambda),
            Light::Point {
                position,
                intensity,
            } => {
                let to = *position - x;
                let d2 = to.length_squared();
                let dist = d2.sqrt();
                if !(dist > 0.0) {
                    return None;
                }
                let radiance = *intensity / d2;
                radiance.is_finite().then_some(LightSample {
                    p: *position,
                    n: Vec3::ZERO,
                    wi: to / dist,
                    dist,
                    radiance,
                    pdf: 1.0,
                    delta: true,
                })
            }
            Light::Spot {
                position,
                frame,
                intensity,
                cone,
            } => {
                let to = *position - x;
                let d2 = to.length_squared();
                let dist = d2.sqrt();
                if !(dist > 0.0) {
                    return None;
                }
                let wi = to / dist;
                let fall = cone.falloff(frame.n.dot(-wi));
                let radiance = *intensity * (fall / d2);
                radiance.is_finite().then_some(LightSample {
                    p: *position,
                    n: Vec3::ZERO,
                    wi,
                    dist,
                    radiance,
                    pdf: 1.0,
                    delta: true,
                })
            }
            Light::Directional {
                to_light,
                irradiance,
            } => Some(LightSample {
                p: x,
                n: Vec3::ZERO,
                wi: *to_light,
                dist: f32::INFINITY,
                radiance: *irradiance,
                pdf: 1.0,
                delta: true,
            }),
            Light::Sun {
                frame,
                radiance,
                one_minus_cos,
            } => {
                let wi = frame
                    .to_world(square_to_uniform_cone(u, *one_minus_cos))
                    .normalize();
                Some(LightSample {
                    p: x,
                    n: Vec3::ZERO,
                    wi,
                    dist: f32::INFINITY,
                    radiance: *radiance,
                    pdf: uniform_cone_pdf(*one_minus_cos),
                    delta: false,
                })
            }
            Light::Constant { radiance } => {
                let wi = square_to_uniform_sphere(u);
                Some(LightSample {
                    p: x,
                    n: Vec3::ZERO,
                    wi,
                    dist: f32::INFINITY,
                    radiance: *radiance,
                    pdf: pt_math::warp::UNIFORM_SPHERE_PDF,
                    delta: false,
                })
            }
            Light::EnvMap(e) => {
                let (wi, radiance, pdf) = e.sample(u, lambda)?;
                Some(LightSample {
                    p: x,
                    n: Vec3::ZERO,
                    wi,
                    dist: f32::INFINITY,
                    radiance,
                    pdf,
                    delta: false,
                })
            }
        }
    }

    /// Radiance seen along a ray that left the scene in direction `dir` (infinite lights only),
    /// at the path's wavelengths `lambda` (spectral environment maps).
    pub fn escaped_radiance(&self, dir: Vec3, lambda: &SampledWavelengths) -> SampledSpectrum {
        match self {
            Light::Sun {
                frame,
                radiance,
                one_minus_cos,
            } => {
                // Inside the cone: 1 - cos(theta) < 1 - cos(alpha), compared without cancellation
                // as |dir - n|^2 / 2 = 1 - cos(theta).
                if 0.5 * (dir - frame.n).length_squared() < *one_minus_cos {
                    *radiance
                } else {
                    SampledSpectrum::ZERO
                }
            }
            Light::Constant { radiance } => *radiance,
            Light::EnvMap(e) => e.radiance(dir, lambda),
            _ => SampledSpectrum::ZERO,
        }
    }

    /// Solid-angle pdf that `sample` produces direction `dir` (infinite lights only).
    pub fn escaped_pdf(&self, dir: Vec3) -> f32 {
        match self {
            Light::Sun {
                frame,
                one_minus_cos,
                ..
            } => {
                if 0.5 * (dir - frame.n).length_squared() < *one_minus_cos {
                    uniform_cone_pdf(*one_minus_cos)
                } else {
                    0.0
                }
            }
            Light::Constant { .. } => pt_math::warp::UNIFORM_SPHERE_PDF,
            Light::EnvMap(e) => e.pdf(dir),
            _ => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The path's four wavelengths all at `l` nm.
    fn at(l: f32) -> SampledWavelengths {
        SampledWavelengths::sample_visible(0.5).with_lambda(pt_math::Vec4::splat(l))
    }

    #[test]
    fn spectral_envmap_matches_mitsuba_probe() {
        // A 4x3 map with columns of rgb (1, 0.5, 0.2), (10, 10, 10), (0.1, 0.2, 0.8), (2, 1, 1),
        // evaluated halfway between the first two column centres (u = 0.25, v = 0.5). Mitsuba
        // 3.9.1 scalar_spectral's envmap (times its D65) gave 3.99998, 4.43127, 4.58698 at 450,
        // 550, 650 nm: the product of the interpolated sigmoid values and the interpolated
        // scales. Interpolating the products instead gives 6.046, 5.535, 4.472 (+51%, +25%,
        // -2.5%). 1% allows for Mitsuba's tabulated coefficients against pt's exact fit.
        let cols = [
            [1.0f32, 0.5, 0.2],
            [10.0, 10.0, 10.0],
            [0.1, 0.2, 0.8],
            [2.0, 1.0, 1.0],
        ];
        let texels: Vec<[f32; 3]> = (0..12).map(|i| cols[i % 4]).collect();
        let mut e = EnvMap::new(4, 3, texels, Mat3::IDENTITY).unwrap();
        e.upsample();
        let (dir, _) = e.uv_to_dir(Vec2::new(0.25, 0.5));
        let d65 = pt_spectrum::Spectrum::illuminant(pt_spectrum::NamedIlluminant::D65, 1.0);
        for (l, mitsuba) in [(450.0f32, 3.99998f32), (550.0, 4.43127), (650.0, 4.58698)] {
            let v = e.radiance(dir, &at(l)).0.x * d65.eval(l);
            assert!(
                (v / mitsuba - 1.0).abs() < 0.01,
                "{l} nm: {v} vs Mitsuba {mitsuba}"
            );
        }
    }

    #[test]
    fn spectral_envmap_sampling_is_consistent_with_its_pdf() {
        // Spectral radiance with the RGB-luminance sampling distribution: every sample's pdf must
        // equal pdf(dir), and E[L / pdf] must equal the integral of L over the sphere (computed
        // by midpoint quadrature in (u, v) with the Jacobian 2 pi^2 sin(pi v)). Radiance where
        // the pdf is 0, or a pdf that does not match the sampling, biases the estimate. The map
        // has black texels, a bright spot and colours; threshold 5 standard errors of the
        // estimate (from the samples), plus 1e-3 relative for the quadrature.
        let (w, h) = (8usize, 6usize);
        let texels: Vec<[f32; 3]> = (0..w * h)
            .map(|i| match (i % w, i / w) {
                (x, _) if x < 2 => [0.0; 3],
                (5, 2) => [40.0, 30.0, 5.0],
                (x, y) => [0.1 + 0.1 * x as f32, 0.2 + 0.1 * y as f32, 0.6],
            })
            .collect();
        let mut e = EnvMap::new(w, h, texels, Mat3::from_rotation_y(0.7)).unwrap();
        e.upsample();
        let lambda = at(520.0);
        let n = 200_000;
        let mut s = 7u64;
        let mut rnd = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 40) as f32) / (1u64 << 24) as f32
        };
        let (mut sum, mut sum2) = (0.0f64, 0.0f64);
        let mut boundary = 0;
        for _ in 0..n {
            let Some((dir, l, pdf)) = e.sample(Vec2::new(rnd(), rnd()), &lambda) else {
                continue;
            };
            // A sample on a cell boundary can come back (dir -> uv in f32) in the neighbouring
            // cell, whose pdf differs: allowed for a few; a wrong pdf would mismatch everywhere.
            if (e.pdf(dir) - pdf).abs() > 1e-3 * pdf {
                boundary += 1;
            }
            // Same lookup up to the uv -> direction -> uv round trip in f32.
            let back = e.radiance(dir, &lambda);
            assert!(
                (l.0 - back.0).abs().max_element() <= 1e-4 * back.0.abs().max_element().max(1e-3),
                "{l:?} vs {back:?}"
            );
            let f = (l.0.x / pdf) as f64;
            sum += f;
            sum2 += f * f;
        }
        assert!(
            boundary < n / 1000,
            "{boundary} of {n} samples have a pdf that pdf(dir) does not reproduce"
        );
        let mean = sum / n as f64;
        let se = ((sum2 / n as f64 - mean * mean) / n as f64).sqrt();
        let m = 1000;
        let mut quad = 0.0f64;
        for j in 0..m {
            let v = (j as f32 + 0.5) / m as f32;
            for i in 0..2 * m {
                let u = (i as f32 + 0.5) / (2 * m) as f32;
                let (dir, sin_t) = e.uv_to_dir(Vec2::new(u, v));
                quad += (e.radiance(dir, &lambda).0.x * 2.0 * PI * PI * sin_t) as f64
                    / (2 * m * m) as f64;
            }
        }
        assert!(
            (mean - quad).abs() < 5.0 * se + 1e-3 * quad,
            "E[L/pdf] {mean} +- {se} vs integral {quad}"
        );
    }

    #[test]
    fn sampled_pdf_matches_pdf_query() {
        let tri = |a: Vec3, b: Vec3, c: Vec3| {
            let n = (b - a).cross(c - a).normalize();
            LightTriangle {
                p: [a, b, c],
                n: [n; 3],
                uv: [Vec2::ZERO; 3],
            }
        };
        // A 2 x 1 rectangle at y = 1 facing down, split into two triangles of equal area.
        let tris = vec![
            tri(
                Vec3::new(-1.0, 1.0, -0.5),
                Vec3::new(1.0, 1.0, -0.5),
                Vec3::new(1.0, 1.0, 0.5),
            ),
            tri(
                Vec3::new(-1.0, 1.0, -0.5),
                Vec3::new(1.0, 1.0, 0.5),
                Vec3::new(-1.0, 1.0, 0.5),
            ),
        ];
        assert!(
            tris[0].n.iter().all(|n| (n.y + 1.0).abs() < 1e-6),
            "faces down"
        );
        // The same rectangle as a parallelogram.
        let (v0, e1, e2) = (
            Vec3::new(-1.0, 1.0, -0.5),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, 1.0),
        );
        let parallelogram = LightShape::Parallelogram {
            v0,
            e1,
            e2,
            n: e1.cross(e2).normalize(),
            uv: [Vec2::ZERO, Vec2::X, Vec2::Y],
        };
        assert_eq!(e1.cross(e2).normalize(), -Vec3::Y, "faces down");
        for shape in [
            LightShape::Mesh {
                tris,
                distr: Distribution1D::new(&[1.0, 1.0]).unwrap(),
            },
            parallelogram,
        ] {
            solid_angle_matches_quadrature(AreaLight {
                radiance: SampledSpectrum::from_rgb([1.0; 3]),
                texture: None,
                spectral: None,
                shape,
                area: 2.0,
            });
        }
    }

    /// For the 2 x 1 rectangle at y = 1 facing down that `light` is: the solid angle from a
    /// point below estimated with light samples, E[1/pdf], against quadrature; and every
    /// sample's pdf against [`AreaLight::pdf`].
    fn solid_angle_matches_quadrature(light: AreaLight) {
        let x = Vec3::new(0.2, 0.0, 0.1);
        // Estimate the solid angle subtended: E[1/pdf] = solid angle. Compare with the value from
        // dense midpoint quadrature of cos/d^2 over the rectangle.
        let n = 200_000;
        let mut s = 99u64;
        let mut rnd = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 40) as f32) / (1u64 << 24) as f32
        };
        let mut est = 0.0f64;
        let lambda = SampledWavelengths::sample_visible(0.5);
        for _ in 0..n {
            let ls = light
                .sample(x, rnd(), Vec2::new(rnd(), rnd()), &lambda)
                .unwrap();
            assert!((light.pdf(x, ls.p, ls.n) - ls.pdf).abs() <= 1e-4 * ls.pdf);
            assert!(!ls.radiance.is_black(), "front side faces x");
            est += 1.0 / ls.pdf as f64;
        }
        est /= n as f64;
        let m = 400;
        let mut quad = 0.0f64;
        for i in 0..m {
            for j in 0..m {
                let p = Vec3::new(
                    -1.0 + 2.0 * (i as f32 + 0.5) / m as f32,
                    1.0,
                    -0.5 + (j as f32 + 0.5) / m as f32,
                );
                let d = p - x;
                let cos = d.y / d.length();
                quad += (cos / d.length_squared()) as f64 * (2.0 / (m * m) as f64);
            }
        }
        // Monte Carlo relative error of 1/pdf here is ~0.3 / sqrt(2e5) < 1e-3; 5e-3 is 5 sigma.
        assert!((est - quad).abs() / quad < 5e-3, "{est} vs {quad}");
    }
}
