//! Area lights: emitting meshes, parallelograms, disks, spheres and cylinders.

use super::LightSample;
use crate::texture::{Texture, TexturePoint};
use pt_math::lanes::V3;
use pt_math::warp::{
    square_to_disk_concentric, square_to_uniform_sphere, square_to_uniform_triangle,
    uniform_cone_pdf,
};
use pt_math::{fastmath, Distribution1D, Frame, Mat3, Vec2, Vec3};
use pt_spectrum::{SampledSpectrum, SampledWavelengths};
use std::f32::consts::PI;

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
    /// A disk (an ellipse under non-uniform scale), sampled uniformly by area as Mitsuba
    /// samples it: Shirley and Chiu's concentric map, through the affine map of the disk (which
    /// keeps the density uniform), pdf 1 / area.
    Disk(pt_scene::Disk),
    /// A sphere (normal inwards when `flip`).
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius.
        radius: f32,
        /// Whether the front side faces inwards.
        flip: bool,
        /// Object-to-world rotation, for the texture coordinates of a textured emitter.
        frame: Mat3,
    },
    /// An open cylinder (see `pt_scene::Geometry::Cylinder`), sampled uniformly by area as
    /// Mitsuba samples it (its cylinder has no solid-angle sampling): z uniform along the
    /// axis, the azimuth uniform, pdf 1 / (2 pi r L) per unit area.
    Cylinder {
        /// Centre of the first end circle.
        p0: Vec3,
        /// Object-to-world rotation: column 2 the axis, columns 0 and 1 the azimuth's origin.
        frame: Mat3,
        /// Radius.
        radius: f32,
        /// Length along the axis.
        length: f32,
        /// Whether the front side faces the axis.
        flip: bool,
    },
}

impl LightShape {
    /// A point uniformly distributed by area over the whole shape (density `1 / area`): its
    /// position, its front-side unit normal and its texture coordinates (world space). `u_sel`
    /// picks a mesh's triangle (by area), `u` the point on it. The one area sampling of every
    /// shape, used by light sampling seen from a point, by light paths and by the
    /// irradiancemeter.
    #[inline(always)]
    pub fn sample_point(&self, u_sel: f32, u: Vec2) -> (Vec3, Vec3, Vec2) {
        match self {
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
                parallelogram_points(
                    &V3::<1>::splat(v0),
                    &V3::splat(e1),
                    &V3::splat(e2),
                    &[u.x],
                    &[u.y],
                )
                .get(0),
                n,
                uv[0] + uv[1] * u.x + uv[2] * u.y,
            ),
            LightShape::Sphere {
                center,
                radius,
                flip,
                frame,
            } => {
                let d = square_to_uniform_sphere(u);
                (
                    *center + d * *radius,
                    if *flip { -d } else { d },
                    sphere_uv(*frame, d),
                )
            }
            &LightShape::Cylinder {
                p0,
                frame,
                radius,
                length,
                flip,
            } => cylinder_point(p0, frame, radius, length, flip, u),
            LightShape::Disk(d) => {
                let local = square_to_disk_concentric(u);
                let (uv, _) = disk_uv(d.axes[0], d.axes[1], local);
                (d.point(local), d.normal, uv)
            }
        }
    }
}

/// An area light attached to one shape.
#[derive(Clone, Debug)]
pub struct AreaLight {
    /// Emitted radiance (W sr^-1 m^-2) over the shape's texture coordinates: a constant, or
    /// an image (a monitor), built for the emission role (spectral mode: times D65).
    pub radiance: Texture,
    /// The emitting geometry.
    pub shape: LightShape,
    /// Total surface area, scene units squared.
    pub area: f32,
}

impl AreaLight {
    /// Total emitted power estimate (for light selection): pi * area * luminance.
    pub fn power(&self) -> f32 {
        PI * self.area * crate::texture::luminance(self.radiance.mean_rgb()).max(0.0)
    }

    /// A point uniformly distributed by area over the whole light (density `1 / area`): its
    /// position, its front-side unit normal and its texture coordinates (world space), from
    /// [`LightShape::sample_point`].
    #[inline(always)]
    pub fn sample_point(&self, u_sel: f32, u: Vec2) -> (Vec3, Vec3, Vec2) {
        self.shape.sample_point(u_sel, u)
    }

    /// The emitted radiance at texture coordinates `uv` (front side), before the one-sided test,
    /// at the path's wavelengths `lambda` (used only by spectral textures).
    #[inline(always)]
    fn radiance_at(&self, uv: Vec2, lambda: &SampledWavelengths) -> SampledSpectrum {
        self.radiance.eval(&TexturePoint::uv(uv), lambda)
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
            frame,
        } = &self.shape
        {
            let c = sample_sphere_cone(*center, *radius, x, u);
            if c.outside[0] {
                if !c.ok[0] {
                    return None;
                }
                let (p, n_out, wi) = (c.p.get(0), c.n_out.get(0), c.wi.get(0));
                let n = if *flip { -n_out } else { n_out };
                // The texture coordinates (an atan2 and an acos) only for a textured light.
                let radiance = if n.dot(-wi) > 0.0 {
                    self.radiance.constant_at(lambda).unwrap_or_else(|| {
                        self.radiance_at(sphere_uv(*frame, (p - *center) / *radius), lambda)
                    })
                } else {
                    SampledSpectrum::ZERO
                };
                return Some(LightSample {
                    p,
                    n,
                    wi,
                    dist: c.dist[0],
                    radiance,
                    pdf: c.pdf[0],
                    delta: false,
                });
            }
        }
        let (p, n, uv) = self.sample_point(u_sel, u);
        let s = to_solid_angle(
            &V3::<1>::splat(x),
            &V3::splat(p),
            &V3::splat(n),
            &[self.area],
        );
        if !s.ok[0] {
            return None;
        }
        let radiance = if s.front[0] {
            self.radiance_at(uv, lambda)
        } else {
            SampledSpectrum::ZERO
        };
        Some(LightSample {
            p,
            n,
            wi: s.wi.get(0),
            dist: s.dist[0],
            radiance,
            pdf: s.pdf[0],
            delta: false,
        })
    }

    /// The emitted radiance at texture coordinates `uv`, at the path's wavelengths (for the
    /// path tracer's lanes, which sample parallelogram lights together).
    #[inline(always)]
    pub fn radiance_at_uv(&self, uv: Vec2, lambda: &SampledWavelengths) -> SampledSpectrum {
        self.radiance_at(uv, lambda)
    }

    /// The emitted radiance (front side) at the path's wavelengths `lambda` if it is the same
    /// all over the light (no texture).
    #[inline(always)]
    pub fn constant_radiance(&self, lambda: &SampledWavelengths) -> Option<SampledSpectrum> {
        self.radiance.constant_at(lambda)
    }

    /// Solid-angle pdf, from `x`, of having sampled the point `p` with normal `n` on this light
    /// (for MIS when a BSDF-sampled ray hits the light).
    #[inline]
    pub fn pdf(&self, x: Vec3, p: Vec3, n: Vec3) -> f32 {
        if let LightShape::Sphere { center, radius, .. } = &self.shape {
            let cone = sphere_cone(*center, *radius, x);
            if cone.outside {
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

/// The point of the open cylinder `p0 + frame * (r cos phi, r sin phi, z)` for the uniform
/// numbers `u`, uniform by area: z = `length` u.x, phi = 2 pi u.y. Returns the point, its
/// front normal (towards the axis when `flip`) and its texture coordinates (phi / 2 pi,
/// z / length: u.y and u.x, as at a hit).
#[inline]
pub fn cylinder_point(
    p0: Vec3,
    frame: Mat3,
    radius: f32,
    length: f32,
    flip: bool,
    u: Vec2,
) -> (Vec3, Vec3, Vec2) {
    let (sin, cos) = pt_math::fastmath::sin_cos_turns(u.y);
    let outward = frame * Vec3::new(cos, sin, 0.0);
    (
        p0 + outward * radius + frame.z_axis * (u.x * length),
        if flip { -outward } else { outward },
        Vec2::new(u.y, u.x),
    )
}

/// The cone a sphere (`center`, `radius`) subtends from the point `x`, for solid-angle sampling
/// (pbrt-v4 section 6.2.4, "Sampling Spheres"): directions uniform in the cone, pdf
/// 1 / (2 pi (1 - cos theta_max)), mapped to the visible point through the angle alpha at the
/// centre, `cos alpha = sin^2 theta / sin theta_max + cos theta sqrt(1 - sin^2 theta /
/// sin^2 theta_max)`, which needs no ray-sphere intersection and so never misses at the rim.
/// Much lower variance than area sampling for small or distant spheres, whose far half area
/// sampling wastes.
struct SphereCone {
    /// Whether `x` is outside the sphere; inside (or on it: NEE from a point of the emitter)
    /// area sampling is used instead, and the other fields are meaningless.
    outside: bool,
    /// Unit axis from the centre towards `x`.
    axis: Vec3,
    /// sin^2 theta_max.
    sin2_max: f32,
    /// 1 - cos theta_max.
    one_minus_cos_max: f32,
}

/// [`sphere_cone_lanes`]' one lane, out of line: [`AreaLight::sample`] is inlined wherever a
/// light is sampled, and the kernel need not be copied into each of those places.
fn sample_sphere_cone(center: Vec3, radius: f32, x: Vec3, u: Vec2) -> ConeSamples<1> {
    sphere_cone_lanes(&V3::splat(center), &[radius], &V3::splat(x), &[u.x], &[u.y])
}

/// The [`SphereCone`] of the sphere (`center`, `radius`) from `x`. Selects, not early returns:
/// inlined into [`sphere_cone_lanes`]' loop, which vectorises.
#[inline(always)]
fn sphere_cone(center: Vec3, radius: f32, x: Vec3) -> SphereCone {
    let d = x - center;
    let d2 = d.length_squared();
    let r2 = radius * radius;
    let sin2_max = r2 / d2;
    SphereCone {
        // A margin: on the surface itself keep area sampling.
        outside: d2 > r2 * 1.0001,
        axis: d / d2.sqrt(),
        sin2_max,
        // 1 - sqrt(1 - s) computed as s / (1 + sqrt(1 - s)): no cancellation for small s.
        one_minus_cos_max: sin2_max / (1.0 + (1.0 - sin2_max).sqrt()),
    }
}

/// Solid-angle samples of sphere lights, one per lane ([`sphere_cone_lanes`]).
pub struct ConeSamples<const N: usize> {
    /// Whether the reference point is outside the sphere (else the lane has no sample here:
    /// such points sample the sphere by area).
    pub outside: [bool; N],
    /// Whether the lane has a sample (outside, and the point is not the reference point).
    pub ok: [bool; N],
    /// Points on the spheres, world space.
    pub p: V3<N>,
    /// The spheres' outward normals there.
    pub n_out: V3<N>,
    /// Unit directions from the reference points towards `p`.
    pub wi: V3<N>,
    /// Distances to `p`.
    pub dist: [f32; N],
    /// Solid-angle pdfs.
    pub pdf: [f32; N],
}

/// Points on the visible caps of `N` spheres (`center`, `radius`) seen from the points `x`, for
/// the uniform numbers (`u0`, `u1`), uniform in the cones they subtend (see [`SphereCone`]),
/// for all lanes at once; [`AreaLight::sample`] of a sphere is its one lane.
#[inline(always)]
pub fn sphere_cone_lanes<const N: usize>(
    center: &V3<N>,
    radius: &[f32; N],
    x: &V3<N>,
    u0: &[f32; N],
    u1: &[f32; N],
) -> ConeSamples<N> {
    let (mut sin_phi, mut cos_phi) = ([0.0; N], [1.0; N]);
    for k in 0..N {
        (sin_phi[k], cos_phi[k]) = pt_math::fastmath::sin_cos_turns(u1[k]);
    }
    let mut out = ConeSamples {
        outside: [false; N],
        ok: [false; N],
        p: V3::default(),
        n_out: V3::default(),
        wi: V3::default(),
        dist: [0.0; N],
        pdf: [0.0; N],
    };
    for k in 0..N {
        let (c, r, x) = (center.get(k), radius[k], x.get(k));
        let cone = sphere_cone(c, r, x);
        let omc = u0[k] * cone.one_minus_cos_max; // 1 - cos(theta), uniform in cos(theta)
        let cos_t = 1.0 - omc;
        let sin2_t = omc * (2.0 - omc);
        let cos_alpha =
            sin2_t / cone.sin2_max.sqrt() + cos_t * (1.0 - sin2_t / cone.sin2_max).max(0.0).sqrt();
        let sin_alpha = (1.0 - cos_alpha * cos_alpha).max(0.0).sqrt();
        // The point's outward normal, measured from the axis towards x.
        let local = Vec3::new(sin_alpha * cos_phi[k], sin_alpha * sin_phi[k], cos_alpha);
        let n_out = Frame::from_normal(cone.axis).to_world(local).normalize();
        let p = c + n_out * r;
        let to = p - x;
        let dist = to.length();
        out.outside[k] = cone.outside;
        out.ok[k] = cone.outside & (dist > 0.0);
        out.p.set(k, p);
        out.n_out.set(k, n_out);
        out.wi.set(k, to / dist);
        out.dist[k] = dist;
        out.pdf[k] = uniform_cone_pdf(cone.one_minus_cos_max);
    }
    out
}

/// Mitsuba's sphere texture coordinates of a unit vector `d` from the centre (world space):
/// in the sphere's object frame, u = azimuth about z / 2 pi in [0, 1), v = polar angle from +z / pi.
#[cfg_attr(debug_assertions, inline)]
#[cfg_attr(not(debug_assertions), inline(always))]
pub fn sphere_uv(frame: Mat3, d: Vec3) -> Vec2 {
    let local = frame.transpose() * d;
    let mut u = fastmath::atan2(local.y, local.x) * (0.5 / PI);
    if u < 0.0 {
        u += 1.0;
    }
    Vec2::new(u, fastmath::acos(local.z) / PI)
}

/// Mitsuba's disk texture coordinates at the object-space point `local` = (x, y) of the disk
/// `c + x a + y b`: u = r = |local|, v = phi / 2 pi with phi = atan2(y, x) in [0, 2 pi); and
/// the derivatives of the position, dp/du = cos(phi) a + sin(phi) b (radial, the direction
/// that orients anisotropic BSDFs, as Mitsuba's) and dp/dv = 2 pi r (-sin(phi) a + cos(phi) b)
/// (Mitsuba leaves out the factor 2 pi r, the length of the true derivative, which bump maps
/// scale their slopes by). At the centre phi is taken as 0.
#[inline]
pub fn disk_uv(a: Vec3, b: Vec3, local: Vec2) -> (Vec2, [Vec3; 2]) {
    let r = local.length();
    let (cos_phi, sin_phi) = if r > 0.0 {
        (local.x / r, local.y / r)
    } else {
        (1.0, 0.0)
    };
    let mut v = fastmath::atan2(local.y, local.x) * (0.5 / PI);
    if v < 0.0 {
        v += 1.0;
    }
    let dpdu = a * cos_phi + b * sin_phi;
    let dpdv = (b * cos_phi - a * sin_phi) * (2.0 * PI * r);
    (Vec2::new(r, v), [dpdu, dpdv])
}

/// Points of parallelograms, `v0 + e1 u + e2 v` per lane (uniform by area for uniform `u`,
/// `v`; pdf 1 / area).
#[inline(always)]
pub fn parallelogram_points<const N: usize>(
    v0: &V3<N>,
    e1: &V3<N>,
    e2: &V3<N>,
    u: &[f32; N],
    v: &[f32; N],
) -> V3<N> {
    V3::from_fn(|k| v0.get(k) + e1.get(k) * u[k] + e2.get(k) * v[k])
}

/// Points sampled uniformly by area on lights, seen from the reference points `x`: the unit
/// directions towards them, their distances, and the solid-angle pdfs
/// `pdf_area |x - p|^2 / |cos theta_p|` (pbrt-v4 eq. 4.15; Veach 1997 eq. 8.10).
pub struct SolidAngle<const N: usize> {
    /// Unit directions from `x` towards the points.
    pub wi: V3<N>,
    /// Distances.
    pub dist: [f32; N],
    /// Solid-angle pdfs.
    pub pdf: [f32; N],
    /// Whether `x` sees the light's front side (`cos theta_p > 0`).
    pub front: [bool; N],
    /// Whether the sample exists: a positive distance and a finite pdf (not coinciding with
    /// `x`, not exactly edge-on).
    pub ok: [bool; N],
}

/// [`SolidAngle`] of points `p` with normals `n` on lights of areas `area`, from points `x`.
///
/// One loop over the lanes whose body is the whole computation of a lane: the compiler
/// vectorises it as one, where a sequence of small lane operations left it packing and
/// unpacking lanes between them.
#[inline(always)]
pub fn to_solid_angle<const N: usize>(
    x: &V3<N>,
    p: &V3<N>,
    n: &V3<N>,
    area: &[f32; N],
) -> SolidAngle<N> {
    let mut out = SolidAngle {
        wi: V3::default(),
        dist: [0.0; N],
        pdf: [0.0; N],
        front: [false; N],
        ok: [false; N],
    };
    for k in 0..N {
        let to = p.get(k) - x.get(k);
        let dist2 = to.dot(to);
        let dist = dist2.sqrt();
        let wi = Vec3::new(to.x / dist, to.y / dist, to.z / dist);
        let cos_l = n.get(k).dot(-wi);
        let pdf = dist2 / (cos_l.abs() * area[k]);
        out.wi.set(k, wi);
        (out.dist[k], out.pdf[k]) = (dist, pdf);
        out.front[k] = cos_l > 0.0;
        // `pdf` finite as a comparison (false for NaN), which runs in SIMD lanes.
        out.ok[k] = (dist > 0.0) & (pdf.abs() < f32::INFINITY);
    }
    out
}
