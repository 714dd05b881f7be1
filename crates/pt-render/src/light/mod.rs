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

mod area;
mod build;
mod emit;
mod envmap;
mod profile;
mod projected;
mod sunsky;
#[cfg(test)]
mod tests;
mod tree;

pub use area::{
    cylinder_point, disk_uv, parallelogram_points, sphere_cone_lanes, sphere_uv, to_solid_angle,
    AreaLight, ConeSamples, LightShape, LightTriangle, SolidAngle,
};
pub use build::build_light;
pub use emit::{EmittedRay, LightPoint};
pub use envmap::EnvMap;
pub use profile::{envmap_table, IntensityProfile, ProfileError};
pub use projected::{Projector, SpotTexture};
pub use sunsky::SunSky;
pub use tree::LightTree;

use crate::texture::ConstantSpectrum;
use pt_math::warp::{square_to_uniform_cone, square_to_uniform_sphere, uniform_cone_pdf};
use pt_math::{Frame, Vec2, Vec3};
use pt_spectrum::{SampledSpectrum, SampledWavelengths};
use std::f32::consts::PI;

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

/// A light sample from infinitely far away (an environment): `(direction towards it, radiance,
/// solid-angle pdf)` as seen from `x`.
#[inline]
fn from_infinity(x: Vec3, (wi, radiance, pdf): (Vec3, SampledSpectrum, f32)) -> LightSample {
    LightSample {
        p: x,
        n: Vec3::ZERO,
        wi,
        dist: f32::INFINITY,
        radiance,
        pdf,
        delta: false,
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

/// Any light of the scene.
#[derive(Clone, Debug)]
pub enum Light {
    /// An emitting shape.
    Area(AreaLight),
    /// Point light with intensity `intensity` (W/sr), times its profile's value if it has one.
    Point {
        /// Position, world.
        position: Vec3,
        /// Radiant intensity, W/sr.
        intensity: ConstantSpectrum,
        /// How the intensity varies over directions (IES, goniometric); isotropic without.
        profile: Option<Box<IntensityProfile>>,
    },
    /// Spot light at `position` pointing along `frame.n`.
    Spot {
        /// Position, world.
        position: Vec3,
        /// Frame whose normal is the spot axis.
        frame: Frame,
        /// Intensity on the axis, W/sr.
        intensity: ConstantSpectrum,
        /// Angular falloff.
        cone: SpotCone,
        /// An image cast through the cone (Mitsuba's `texture`), multiplying the intensity.
        texture: Option<Box<SpotTexture>>,
        /// An IES profile about the axis, multiplying the intensity.
        profile: Option<Box<IntensityProfile>>,
    },
    /// An image cast through a perspective frustum (Mitsuba `projector`).
    Projector(Box<Projector>),
    /// Directional light: irradiance `irradiance` arriving from direction `to_light`.
    Directional {
        /// Unit direction from the scene towards the light, world.
        to_light: Vec3,
        /// Irradiance on a surface facing the light, W/m^2.
        irradiance: ConstantSpectrum,
    },
    /// A disk of uniform radiance at infinity (the sun), sampled uniformly over its cone.
    Sun {
        /// Frame whose normal points from the scene towards the sun's centre.
        frame: Frame,
        /// Irradiance on a surface facing the sun, W/m^2.
        irradiance: ConstantSpectrum,
        /// 1 / (pi sin^2(alpha)), alpha the angular radius: the disk's radiance over the
        /// irradiance.
        to_radiance: f32,
        /// 1 - cos(alpha), computed without cancellation.
        one_minus_cos: f32,
    },
    /// Uniform radiance from every direction.
    Constant {
        /// Radiance, W sr^-1 m^-2.
        radiance: ConstantSpectrum,
    },
    /// Environment map.
    EnvMap(EnvMap),
    /// The Hosek-Wilkie sun and sky (Mitsuba `sunsky`).
    SunSky(Box<SunSky>),
}

impl Light {
    /// Whether rays escaping the scene can see this light (environment and sun).
    pub fn is_infinite(&self) -> bool {
        matches!(
            self,
            Light::Sun { .. } | Light::Constant { .. } | Light::EnvMap(_) | Light::SunSky(_)
        )
    }

    /// Power estimate for light selection, W (luminance). Distant lights use the scene's
    /// bounding sphere radius `r`: the power they deliver into it (pbrt-v4 `Phi`).
    pub fn power(&self, scene_radius: f32) -> f32 {
        let disk = PI * scene_radius * scene_radius;
        let p = match self {
            Light::Area(a) => a.power(),
            Light::Point {
                intensity, profile, ..
            } => intensity.luminance() * profile.as_ref().map_or(4.0 * PI, |p| p.integral()),
            Light::Spot {
                intensity,
                profile: Some(p),
                ..
            } => intensity.luminance() * p.integral(),
            Light::Spot {
                intensity,
                cone,
                texture,
                ..
            } => {
                // Full cone up to the mid-falloff angle: exact for a hard cutoff. A texture
                // counts with its mean (an estimate: selection needs only the proportions).
                let mid = 0.5 * (cone.cutoff + cone.beam_width);
                let image = texture
                    .as_ref()
                    .map_or(1.0, |t| crate::texture::luminance(t.texture.mean_rgb()));
                2.0 * PI * (1.0 - mid.cos()) * intensity.luminance() * image
            }
            Light::Projector(p) => p.power(),
            Light::Directional { irradiance, .. } => disk * irradiance.luminance(),
            Light::Sun { irradiance, .. } => disk * irradiance.luminance(),
            Light::Constant { radiance } => 4.0 * PI * disk * radiance.luminance(),
            Light::EnvMap(e) => 4.0 * PI * disk * e.mean_luminance(),
            Light::SunSky(s) => disk * s.luminance_integral(),
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
                profile,
            } => {
                let to = *position - x;
                let d2 = to.length_squared();
                let dist = d2.sqrt();
                if !(dist > 0.0) {
                    return None;
                }
                let shape = profile.as_deref().map_or(1.0, |p| p.eval(-to / dist));
                let radiance = intensity.at(lambda) * (shape / d2);
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
                texture,
                profile,
            } => {
                let to = *position - x;
                let d2 = to.length_squared();
                let dist = d2.sqrt();
                if !(dist > 0.0) {
                    return None;
                }
                let wi = to / dist;
                let shape = profile.as_deref().map_or(1.0, |p| p.eval(-wi));
                let fall = cone.falloff(frame.n.dot(-wi)) * shape;
                let mut radiance = intensity.at(lambda) * (fall / d2);
                if let Some(t) = texture.as_deref().filter(|_| fall > 0.0) {
                    radiance *= t.eval(-to, lambda);
                }
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
            Light::Projector(p) => {
                let (dir, dist, radiance) = p.arriving(x, lambda)?;
                radiance.is_finite().then_some(LightSample {
                    p: p.position,
                    n: Vec3::ZERO,
                    wi: -dir,
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
                radiance: irradiance.at(lambda),
                pdf: 1.0,
                delta: true,
            }),
            Light::Sun {
                frame,
                irradiance,
                to_radiance,
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
                    radiance: irradiance.at(lambda) * *to_radiance,
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
                    radiance: radiance.at(lambda),
                    pdf: pt_math::warp::UNIFORM_SPHERE_PDF,
                    delta: false,
                })
            }
            Light::SunSky(s) => s.sample(u, lambda).map(|d| from_infinity(x, d)),
            Light::EnvMap(e) => e.sample(u, lambda).map(|d| from_infinity(x, d)),
        }
    }

    /// Radiance seen along a ray that left the scene in direction `dir` (infinite lights only),
    /// at the path's wavelengths `lambda` (spectral environment maps).
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn escaped_radiance(&self, dir: Vec3, lambda: &SampledWavelengths) -> SampledSpectrum {
        match self {
            Light::Sun {
                frame,
                irradiance,
                to_radiance,
                one_minus_cos,
            } => {
                // Inside the cone: 1 - cos(theta) < 1 - cos(alpha), compared without cancellation
                // as |dir - n|^2 / 2 = 1 - cos(theta).
                if 0.5 * (dir - frame.n).length_squared() < *one_minus_cos {
                    irradiance.at(lambda) * *to_radiance
                } else {
                    SampledSpectrum::ZERO
                }
            }
            Light::Constant { radiance } => radiance.at(lambda),
            Light::EnvMap(e) => e.radiance(dir, lambda),
            Light::SunSky(s) => s.radiance(dir, lambda),
            _ => SampledSpectrum::ZERO,
        }
    }

    /// Solid-angle pdf that `sample` produces direction `dir` (infinite lights only).
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn escaped_pdf(&self, dir: Vec3) -> f32 {
        match self {
            // Inside the sun's cone: |dir - n|^2 / 2 = 1 - cos.
            Light::Sun {
                frame,
                one_minus_cos,
                ..
            } if 0.5 * (dir - frame.n).length_squared() < *one_minus_cos => {
                uniform_cone_pdf(*one_minus_cos)
            }
            Light::Constant { .. } => pt_math::warp::UNIFORM_SPHERE_PDF,
            Light::EnvMap(e) => e.pdf(dir),
            Light::SunSky(s) => s.pdf(dir),
            _ => 0.0,
        }
    }
}
