//! Light leaving the lights: rays sampled from a light into the scene, for the methods that
//! trace paths from the lights (Mitsuba's `ptracer`; photon mapping and the bidirectional
//! methods build on the same rays).
//!
//! Each ray comes with its weight `Le cos / (p_pos p_dir)`: the emitted radiance times the
//! cosine at the light over the densities of its origin (per unit area) and direction (per
//! unit solid angle), so that the mean weight over many rays is the light's power (pbrt-v4
//! `SampleLe`; Veach 1997, ch. 10). Light selection is not included. The strategies follow
//! Mitsuba 3.9.1's `sample_ray` of each emitter:
//!
//! | light | origin | direction | weight |
//! |---|---|---|---|
//! | area | uniform by area | cosine-weighted about the front normal | `pi A Le(uv)` |
//! | point | the point | uniform over the sphere | `4 pi I` |
//! | point, spot with a profile (IES, goniometric) | the point | the profile's cells (`profile.rs`) | `I P(d) falloff / p(d)` |
//! | spot | the point | uniform in the cutoff cone | `2 pi (1 - cos c) I falloff T` |
//! | projector | the point | uniform over the image on its plane z = 1 | `I(d) / p(d)` |
//! | directional | uniform on a disk of the scene's bounding radius R, facing the light, behind the scene | the light's | `pi R^2 E` |
//! | sun, constant, envmap | as directional | the light's own sampling (uniform in the sun's cone, uniform sphere, the map's distribution) | `pi R^2 L(d) / p(d)` |
//!
//! Distant lights emit from a disk of radius R perpendicular to the direction, placed at
//! distance R from the bounding sphere's centre on the light's side, so that every ray of the
//! sampled direction that meets the scene starts on the disk (Mitsuba's choice).

use super::{AreaLight, Light};
use pt_math::warp::{
    square_to_cosine_hemisphere, square_to_disk_concentric, square_to_uniform_cone,
    square_to_uniform_sphere, uniform_cone_pdf, UNIFORM_SPHERE_PDF,
};
use pt_math::{offset_ray_origin, Frame, Ray, Vec2, Vec3};
use pt_spectrum::{SampledSpectrum, SampledWavelengths};
use std::f32::consts::{FRAC_1_PI, PI};

/// A ray leaving a light, world space.
#[derive(Clone, Copy, Debug)]
pub struct EmittedRay {
    /// The ray (its origin moved off the light's surface for area lights).
    pub ray: Ray,
    /// `Le cos / (p_pos p_dir)` (see the module documentation), light selection not included.
    pub weight: SampledSpectrum,
    /// The point the ray leaves from, world space: on an area light (before the offset), the
    /// position of a point-like light, the point on a distant light's disk.
    pub origin: Vec3,
    /// The area light's front normal at `origin` (zero for the other lights).
    pub normal: Vec3,
    /// The densities the ray was drawn with ([`Light::emission_pdf`]): the origin's per unit
    /// area (1 for point-like lights), the direction's per unit solid angle (1 for a
    /// directional light).
    pub pdf_pos: f32,
    /// See `pdf_pos`.
    pub pdf_dir: f32,
}

/// A point on an area light, uniform by area: what connecting a light directly to the camera
/// needs.
#[derive(Clone, Copy, Debug)]
pub struct LightPoint {
    /// Position, world.
    pub p: Vec3,
    /// Front-side unit normal, world.
    pub n: Vec3,
    /// Texture coordinates (for textured emission).
    pub uv: Vec2,
    /// Density of the point per unit area: 1 / the light's area.
    pub pdf_area: f32,
}

impl AreaLight {
    /// A point of the light uniform by area ([`AreaLight::sample_point`]) with its density.
    #[inline]
    pub fn sample_position(&self, u_sel: f32, u: Vec2) -> LightPoint {
        let (p, n, uv) = self.sample_point(u_sel, u);
        LightPoint {
            p,
            n,
            uv,
            pdf_area: 1.0 / self.area,
        }
    }
}

/// A ray entering the scene's bounding sphere (`centre`, `radius`) from the distant
/// direction `to_light` (unit, from the scene towards the light): its origin uniform on the
/// disk of radius `radius` facing the light at distance `radius` from the centre (density
/// 1 / (pi R^2)).
#[inline]
fn ray_from_disk(to_light: Vec3, u: Vec2, (centre, radius): (Vec3, f32)) -> Ray {
    let frame = Frame::from_normal(to_light);
    let d = square_to_disk_concentric(u) * radius;
    let origin = centre + frame.to_world(Vec3::new(d.x, d.y, radius));
    Ray::new(origin, -to_light)
}

impl Light {
    /// Samples a ray leaving the light ([`EmittedRay`]): `u_sel` picks a mesh light's
    /// triangle, `u_pos` the origin, `u_dir` the direction (the table in the module
    /// documentation); `bounds` is the scene's bounding sphere (centre, radius), from which
    /// distant lights emit. `None` when the sample carries nothing (outside a projector's
    /// image, a degenerate light).
    pub fn sample_emission(
        &self,
        u_sel: f32,
        u_pos: Vec2,
        u_dir: Vec2,
        lambda: &SampledWavelengths,
        bounds: (Vec3, f32),
    ) -> Option<EmittedRay> {
        let disk_area = PI * bounds.1 * bounds.1;
        let point_like = |position: Vec3, dir: Vec3, weight: SampledSpectrum, pdf_dir: f32| {
            (
                Ray::new(position, dir),
                weight,
                position,
                Vec3::ZERO,
                1.0,
                pdf_dir,
            )
        };
        let (ray, weight, origin, normal, pdf_pos, pdf_dir) = match self {
            Light::Area(a) => {
                let pt = a.sample_position(u_sel, u_pos);
                if pt.n == Vec3::ZERO {
                    return None;
                }
                let local = square_to_cosine_hemisphere(u_dir);
                let dir = Frame::from_normal(pt.n).to_world(local);
                // Le cos / (pdf_area cos / pi) = pi A Le.
                let le = a.radiance_at_uv(pt.uv, lambda);
                (
                    Ray::new(offset_ray_origin(pt.p, pt.n), dir),
                    le * (PI * a.area),
                    pt.p,
                    pt.n,
                    pt.pdf_area,
                    local.z * FRAC_1_PI,
                )
            }
            Light::Point {
                position,
                intensity,
                profile: None,
            } => point_like(
                *position,
                square_to_uniform_sphere(u_dir),
                intensity.at(lambda) * (4.0 * PI),
                UNIFORM_SPHERE_PDF,
            ),
            Light::Point {
                position,
                intensity,
                profile: Some(p),
            } => {
                let (dir, pdf) = p.sample(u_dir);
                point_like(
                    *position,
                    dir,
                    intensity.at(lambda) * (p.eval(dir) / pdf),
                    pdf,
                )
            }
            Light::Spot {
                position,
                frame,
                intensity,
                cone,
                texture,
                profile,
            } => {
                // Uniform in the cone, or by the profile (whose density knows the cone).
                let (dir, pdf, shape) = match profile.as_deref() {
                    Some(p) => {
                        let (dir, pdf) = p.sample(u_dir);
                        (dir, pdf, p.eval(dir))
                    }
                    None => {
                        let one_minus_cos = 1.0 - cone.cos_cutoff;
                        let local = square_to_uniform_cone(u_dir, one_minus_cos);
                        let dir = frame.to_world(local).normalize();
                        (dir, uniform_cone_pdf(one_minus_cos), 1.0)
                    }
                };
                let fall = cone.falloff(frame.n.dot(dir)) * shape;
                let mut w = intensity.at(lambda) * (fall / pdf);
                if let Some(t) = texture.as_deref().filter(|_| fall > 0.0) {
                    w *= t.eval(dir, lambda);
                }
                point_like(*position, dir, w, pdf)
            }
            Light::Projector(p) => {
                let (dir, pdf) = p.sample_direction(u_dir);
                // The intensity towards `dir`: what arrives at unit distance.
                let (_, _, intensity) = p.arriving(p.position + dir, lambda)?;
                point_like(p.position, dir, intensity * (1.0 / pdf), pdf)
            }
            // Distant lights: the direction their own light sampling draws (from any point:
            // it does not depend on it), the origin on the disk facing it. The weight is
            // L / p(d) times the disk's area (a directional light: E, with p = 1).
            Light::Directional { .. }
            | Light::Sun { .. }
            | Light::Constant { .. }
            | Light::EnvMap(_)
            | Light::SunSky(_) => {
                let ls = self.sample(bounds.0, u_sel, u_dir, lambda)?;
                if !(ls.pdf > 0.0) {
                    return None;
                }
                let ray = ray_from_disk(ls.wi, u_pos, bounds);
                (
                    ray,
                    ls.radiance * (disk_area / ls.pdf),
                    ray.origin,
                    Vec3::ZERO,
                    1.0 / disk_area,
                    ls.pdf,
                )
            }
        };
        (weight.is_finite() && !weight.is_black()).then_some(EmittedRay {
            ray,
            weight,
            origin,
            normal,
            pdf_pos,
            pdf_dir,
        })
    }

    /// The densities with which [`Light::sample_emission`] draws a ray leaving the point `p`
    /// (normal `n`, for area lights) in the unit direction `dir` (world, away from the
    /// light): the origin's per unit area (1 for point-like lights: a delta), the
    /// direction's per unit solid angle (1 for a directional light: a delta). Light
    /// selection is not included. What the bidirectional methods weigh strategies with.
    pub fn emission_pdf(&self, n: Vec3, dir: Vec3, bounds: (Vec3, f32)) -> (f32, f32) {
        let disk = 1.0 / (PI * bounds.1 * bounds.1);
        match self {
            Light::Area(a) => (1.0 / a.area, n.dot(dir).max(0.0) * FRAC_1_PI),
            Light::Point { profile: None, .. } => (1.0, UNIFORM_SPHERE_PDF),
            Light::Point {
                profile: Some(p), ..
            }
            | Light::Spot {
                profile: Some(p), ..
            } => (1.0, p.pdf(dir)),
            Light::Spot { frame, cone, .. } => {
                let inside = frame.n.dot(dir) >= cone.cos_cutoff;
                (
                    1.0,
                    if inside {
                        uniform_cone_pdf(1.0 - cone.cos_cutoff)
                    } else {
                        0.0
                    },
                )
            }
            Light::Projector(p) => (1.0, p.direction_pdf(dir)),
            Light::Directional { .. } => (disk, 1.0),
            Light::Sun { .. } | Light::Constant { .. } | Light::EnvMap(_) | Light::SunSky(_) => {
                (disk, self.escaped_pdf(-dir))
            }
        }
    }

    /// Whether the light is a delta light (point, spot, projector, directional): it can be
    /// neither hit by a ray nor seen by the camera.
    pub fn is_delta(&self) -> bool {
        matches!(
            self,
            Light::Point { .. }
                | Light::Spot { .. }
                | Light::Projector(_)
                | Light::Directional { .. }
        )
    }
}
