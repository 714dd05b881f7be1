//! Phosphorescence: surfaces that store absorbed light and glow after the lights go out.
//!
//! # Model
//! A phosphor absorbs a fraction `a(l)` of the incident photons, stores them in a long-lived
//! state and returns to the ground state at rate `1 / tau`, emitting a photon with probability
//! `Q` (quantum yield) with the emission spectrum `e(l)` (normalised to unit area per nm over
//! 360-830 nm), Lambertian. This is first-order kinetics, the exponential decay law of
//! luminescence `I(t) = I(0) e^{-t / tau}` (Lakowicz, "Principles of Fluorescence
//! Spectroscopy", 3rd ed., 2006, sec. 1.4); real long-afterglow phosphors decay slower than one
//! exponential (several trap depths), which this model does not attempt.
//!
//! Assumptions:
//! 1. The lights were on long enough for the stored population to reach steady state: absorption
//!    rate = decay rate, so the stored photons per area are `N = tau * A`, with `A` the absorbed
//!    photon flux per area, `A = int a(l) E(l) l / (h c) dl` (E: spectral irradiance).
//! 2. At `t = 0` all lights go out; the stored population decays as `N(t) = N e^{-t / tau}`, so
//!    the photon exitance is `Q N(t) / tau = Q A e^{-t / tau}` and the emitted radiance is
//!    `L(lo, t) = Q e^{-t / tau} e(lo) / (pi lo) * Phi`, `Phi = int a(l) E(l) l dl`
//!    (energy per photon `hc / lo`; `h c` cancels).
//! 3. `Phi` is computed in a first pass with the lights on, per triangle (one value for an
//!    analytic sphere): the glow is uniform over each triangle. In that pass the phosphor is its
//!    elastic reflectance only (its own steady glow, which adds to the light reaching other
//!    phosphor, is left out: a second-order effect for yields and albedos below 1).
//! 4. With the lights on (no `--time`), the material renders as its elastic diffuse reflectance;
//!    its steady glow (`Q A`, like fluorescence) is not shown.
//!
//! `Phi` per triangle is estimated with [`AFTERGLOW_SAMPLES`] samples: a point uniform on the
//! triangle, wavelengths stratified over the samples (uniform density), the irradiance from one
//! light sample (next-event estimation, which also covers delta lights) plus pi times the
//! radiance along one cosine-sampled direction with directly seen emitters hidden (indirect
//! light; the direct part is the light sample's).
//!
//! # Parameters (Mitsuba-style XML, project extension)
//! | name | type | default | unit |
//! |---|---|---|---|
//! | `reflectance` | spectrum / rgb / float | 0.5 | elastic albedo in [0, 1] |
//! | `absorption` | spectrum / float | 0.5 | absorbed fraction in [0, 1] |
//! | `emission` | spectrum (required) | - | shape only, normalised per nm |
//! | `yield` | float | 1 | photons out / photons absorbed |
//! | `lifetime` | float (required) | - | tau, seconds |
//!
//! ```xml
//! <bsdf type="phosphorescent">
//!     <spectrum name="reflectance" value="360:0.3, 830:0.3"/>
//!     <spectrum name="absorption" value="360:0.6, 450:0.6, 480:0, 830:0"/>
//!     <spectrum name="emission" value="480:0, 520:1, 580:0"/>
//!     <float name="yield" value="0.5"/>
//!     <float name="lifetime" value="5"/>
//! </bsdf>
//! ```
//! `pt render scene.xml --time 10` renders the scene 10 s after the lights went out: every
//! light and emitter is off and each phosphorescent triangle emits its afterglow.

use crate::path::{li, PathSettings};
use pt_math::warp::{square_to_cosine_hemisphere, square_to_disk_concentric};
use pt_math::{offset_ray_origin, Frame, Ray, Vec2, Vec3};
use pt_render::sampler::Sampler;
use pt_render::texture::{spectrum_for_role, Role};
use pt_render::{BuildError, BvhKind, LightSelection, Scene};
use pt_scene::{
    AreaEmitterDesc, BsdfKind, Geometry, SceneDesc, ShapeDesc, SpectrumDesc, TextureDesc,
    TriangleMesh,
};
use pt_spectrum::cie::{integrate_visible, LAMBDA_MAX, LAMBDA_MIN};
use pt_spectrum::{ColorMode, SampledWavelengths, Spectrum};
use std::sync::Arc;

/// Samples per triangle (or sphere) of the first pass that estimates the absorbed irradiance.
pub const AFTERGLOW_SAMPLES: u32 = 1024;

/// Spacing (nm) of the tabulated afterglow emission spectrum `e(l) / l`; linear interpolation
/// between nodes 2 nm apart is within 1e-3 of the exact curve for emission spectra smooth on
/// a 10 nm scale.
const TABLE_STEP: f32 = 2.0;

/// The phosphor parameters of a material (also inside `twosided`), if it is phosphorescent:
/// `(absorption, emission, yield, lifetime)`.
fn phosphor(kind: &BsdfKind) -> Option<(&SpectrumDesc, &SpectrumDesc, f32, f32)> {
    match kind {
        BsdfKind::Phosphorescent {
            absorption,
            emission,
            quantum_yield,
            lifetime,
            ..
        } => Some((absorption, emission, *quantum_yield, *lifetime)),
        BsdfKind::TwoSided { inner } => phosphor(&inner.kind),
        _ => None,
    }
}

/// The scene `time_s` seconds after its lights went out: no lights, no emitters, and each
/// triangle (or sphere) of a phosphorescent shape an area emitter of its afterglow (module doc).
/// The first pass renders `desc` in spectral mode with `seed`. Errors if the scene has no
/// phosphorescent shape or `time_s` is negative.
pub fn afterglow(desc: &SceneDesc, time_s: f32, seed: u64) -> Result<SceneDesc, BuildError> {
    check_request(desc, time_s)?;
    let lit = Scene::build_with_mode(
        desc,
        BvhKind::CwBvh,
        LightSelection::Power,
        Some(ColorMode::Spectral),
    )?;
    let settings = PathSettings {
        max_depth: desc.integrator.max_depth,
        rr_depth: desc.integrator.rr_depth,
        hide_emitters: true,
        ..PathSettings::default()
    };
    let first = FirstPass {
        scene: &lit,
        settings: &settings,
        seed,
    };
    let mut out = desc.clone();
    out.lights.clear();
    out.shapes.clear();
    for (si, shape) in desc.shapes.iter().enumerate() {
        let mut dark = shape.clone();
        dark.emitter = None;
        let Some(params) = phosphor(&desc.bsdfs[shape.bsdf].kind) else {
            out.shapes.push(dark);
            continue;
        };
        let glow = Glow::new(shape, params, time_s)?;
        refuse_non_emitters(shape)?;
        glowing_shape(&first, &glow, si, dark, &mut out.shapes);
    }
    Ok(out)
}

/// Refuses a negative or non-finite `time_s` and a scene without phosphorescent shapes (the
/// error names the scene file).
fn check_request(desc: &SceneDesc, time_s: f32) -> Result<(), BuildError> {
    let err = |m: String| BuildError {
        loc: pt_scene::SourceLoc {
            file: desc.source.clone(),
            line: 0,
            col: 0,
            element: "scene".into(),
        },
        message: m,
    };
    if !(time_s >= 0.0 && time_s.is_finite()) {
        return Err(err(format!(
            "--time must be a non-negative number of seconds, got {time_s}"
        )));
    }
    if !desc
        .shapes
        .iter()
        .any(|s| phosphor(&desc.bsdfs[s.bsdf].kind).is_some())
    {
        return Err(err(
            "--time shows the afterglow of phosphorescent materials, and this scene has none"
                .into(),
        ));
    }
    Ok(())
}

/// The first pass: the scene with its lights on (spectral mode), the path settings of its
/// indirect light, and the seed of its random streams.
struct FirstPass<'a> {
    scene: &'a Scene,
    settings: &'a PathSettings,
    seed: u64,
}

/// A phosphorescent shape's afterglow: its absorption `a(l)`, its emission `e(l)`, and the
/// factor `k = Q e^{-t/tau} / (pi area)` of `L(lo) = k Phi e(lo) / lo` (module doc).
struct Glow {
    a: Spectrum,
    e: Spectrum,
    k: f64,
    /// The shape's location, for its emitters.
    loc: pt_scene::SourceLoc,
}

impl Glow {
    /// The afterglow of `shape` `time_s` seconds after the lights went out, from its phosphor
    /// `(absorption, emission, yield, lifetime)`; an error if the emission spectrum has no
    /// area over the visible range.
    fn new(
        shape: &ShapeDesc,
        (absorption, emission, q, tau): (&SpectrumDesc, &SpectrumDesc, f32, f32),
        time_s: f32,
    ) -> Result<Glow, BuildError> {
        let a = spectrum_for_role(absorption, Role::Albedo);
        let e = spectrum_for_role(emission, Role::Albedo);
        let area = integrate_visible(|l| e.eval(l as f32) as f64);
        if !(area > 0.0) {
            return Err(BuildError {
                loc: shape.loc.clone(),
                message: "phosphor emission spectrum has no area over 360-830 nm".into(),
            });
        }
        // L(lo) = k Phi e(lo) / lo with k = Q e^{-t/tau} / (pi area).
        let k = q as f64 * (-(time_s as f64) / tau as f64).exp() / (std::f64::consts::PI * area);
        Ok(Glow {
            a,
            e,
            k,
            loc: shape.loc.clone(),
        })
    }

    /// The area emitter of a surface that absorbed `phi` (`e(l) / l` tabulated every
    /// [`TABLE_STEP`] nm), or `None` when it does not glow.
    fn emitter(&self, phi: f64) -> Option<AreaEmitterDesc> {
        let scale = self.k * phi;
        if !(scale > 0.0) {
            return None;
        }
        let n = ((LAMBDA_MAX - LAMBDA_MIN) / TABLE_STEP) as usize;
        let pairs: Vec<(f32, f32)> = (0..=n)
            .map(|j| {
                let l = LAMBDA_MIN + j as f32 * TABLE_STEP;
                (l, (scale * self.e.eval(l) as f64 / l as f64) as f32)
            })
            .collect();
        Some(AreaEmitterDesc {
            loc: self.loc.clone(),
            radiance: TextureDesc::Constant(SpectrumDesc::Tabulated(Arc::new(pairs))),
            primaries: None,
        })
    }
}

/// Refuses a phosphorescent shape that cannot be an emitter (curves, sdfgrids).
fn refuse_non_emitters(shape: &ShapeDesc) -> Result<(), BuildError> {
    if matches!(shape.geometry, Geometry::Curves(_)) {
        return Err(BuildError {
            loc: shape.loc.clone(),
            message: "a phosphorescent curve cannot glow: curves cannot be emitters".into(),
        });
    }
    if matches!(shape.geometry, Geometry::SdfGrid(_)) {
        // Its afterglow would make it an emitter, and an sdfgrid cannot emit (no point
        // on it can be sampled, as in Mitsuba).
        return Err(BuildError {
            loc: shape.loc.clone(),
            message: "a phosphorescent sdfgrid cannot glow: an sdfgrid cannot be an emitter".into(),
        });
    }
    Ok(())
}

/// Appends to `shapes` the phosphorescent shape `si`, made `dark` (no emitter of its own), as
/// the emitters of its afterglow: one per triangle of a mesh, one for an analytic shape. Each
/// surface's absorbed `Phi` has its own random stream (`si`, then 1, 2, .. per surface).
fn glowing_shape(
    first: &FirstPass,
    glow: &Glow,
    si: usize,
    mut dark: ShapeDesc,
    shapes: &mut Vec<ShapeDesc>,
) {
    let mut sampler_index = 0u64;
    let mut next = || {
        sampler_index += 1;
        Sampler::new(first.seed, si as u64, sampler_index)
    };
    let (lit, a, settings) = (first.scene, &glow.a, first.settings);
    let phi = match &dark.geometry {
        Geometry::Mesh(m) => {
            // One emitter per triangle, each with the glow of its own Phi.
            for (t, idx) in m.indices.iter().enumerate() {
                let p = idx.map(|i| m.positions[i as usize]);
                let n = (p[1] - p[0]).cross(p[2] - p[0]);
                let Some(n) = n.try_normalize() else { continue };
                let mut s = next();
                let phi = absorbed(lit, a, &mut s, settings, &|u| {
                    // Uniform point on the triangle (pbrt-v4 SampleUniformTriangle, square root form).
                    let su = u.x.sqrt();
                    (
                        p[0] * (1.0 - su) + p[1] * (su * (1.0 - u.y)) + p[2] * (su * u.y),
                        n,
                    )
                });
                let mut tri = one_triangle_shape(&dark, m, idx, t);
                tri.emitter = glow.emitter(phi);
                shapes.push(tri);
            }
            return;
        }
        &Geometry::Sphere {
            center,
            radius,
            flip_normals,
            ..
        } => {
            let mut s = next();
            absorbed(lit, a, &mut s, settings, &|u| {
                let d = pt_math::warp::square_to_uniform_sphere(u);
                (center + d * radius, if flip_normals { -d } else { d })
            })
        }
        &Geometry::Cylinder {
            p0,
            frame,
            radius,
            length,
            flip_normals,
        } => {
            let mut s = next();
            absorbed(lit, a, &mut s, settings, &|u| {
                let (p, n, _) =
                    pt_render::light::cylinder_point(p0, frame, radius, length, flip_normals, u);
                (p, n)
            })
        }
        Geometry::Disk(d) => {
            // One glow over the whole disk, as for spheres and cylinders.
            let mut s = next();
            absorbed(lit, a, &mut s, settings, &|u| {
                (d.point(square_to_disk_concentric(u)), d.normal)
            })
        }
        Geometry::SdfGrid(_) | Geometry::Curves(_) => unreachable!("refused above"),
    };
    dark.emitter = glow.emitter(phi);
    shapes.push(dark);
}

/// Triangle `t` (vertices `idx`) of the mesh `m` of the dark shape `dark`, as a shape of its
/// own: its vertex data, face attributes and an id of `id#t`.
fn one_triangle_shape(dark: &ShapeDesc, m: &TriangleMesh, idx: &[u32; 3], t: usize) -> ShapeDesc {
    let mut tri = dark.clone();
    tri.geometry = Geometry::Mesh(TriangleMesh {
        positions: idx.map(|i| m.positions[i as usize]).to_vec(),
        normals: m
            .normals
            .as_ref()
            .map(|ns| idx.map(|i| ns[i as usize]).to_vec()),
        uvs: m
            .uvs
            .as_ref()
            .map(|uv| idx.map(|i| uv[i as usize]).to_vec()),
        tangents: m
            .tangents
            .as_ref()
            .map(|ts| idx.map(|i| ts[i as usize]).to_vec()),
        indices: vec![[0, 1, 2]],
        // A face attribute of triangle t is the one attribute value of `tri`.
        attributes: m
            .attributes
            .iter()
            .map(|a| one_triangle(a, idx, t))
            .collect(),
    });
    tri.id = dark.id.as_ref().map(|id| format!("{id}#{t}"));
    tri
}

/// Estimate of `Phi = int a(l) E(l) l dl` (W m^-2 nm, before dividing by hc) averaged over a
/// surface, whose points and front normals `point(u)` draws uniformly by area (a `dyn`
/// closure: one copy of the path tracer inlined here serves every kind of surface).
fn absorbed(
    scene: &Scene,
    a: &Spectrum,
    sampler: &mut Sampler,
    settings: &PathSettings,
    point: &dyn Fn(Vec2) -> (Vec3, Vec3),
) -> f64 {
    let n_samples = AFTERGLOW_SAMPLES;
    let mut sum = 0.0f64;
    for k in 0..n_samples {
        let (p, n) = point(sampler.next_2d());
        // Wavelengths stratified over the samples: the hero lane in the k-th of N strata.
        let lambda =
            SampledWavelengths::sample_uniform((k as f32 + sampler.next_1d()) / n_samples as f32);
        let origin = offset_ray_origin(p, n);
        // Direct: one light sample.
        let mut e = pt_spectrum::SampledSpectrum::ZERO;
        if let Some((i, pmf, u_sel)) = scene.sample_light_at(p, sampler.next_1d()) {
            let u = sampler.next_2d();
            if let Some(ls) = scene.lights[i].sample(p, u_sel, u, &lambda) {
                let cos = ls.wi.dot(n);
                if cos > 0.0 && !ls.radiance.is_black() && scene.light_unoccluded(origin, &ls) {
                    e += ls.radiance * (cos / (pmf * ls.pdf));
                }
            }
        } else {
            let _ = sampler.next_2d();
        }
        // Indirect: pi times the radiance along a cosine-sampled direction (pdf cos / pi).
        let wi = Frame::from_normal(n).to_world(square_to_cosine_hemisphere(sampler.next_2d()));
        e += li(scene, Ray::new(origin, wi), settings, sampler, &lambda) * std::f32::consts::PI;
        let (l, pdf) = (lambda.lambda().to_array(), lambda.pdf().to_array());
        for j in 0..4 {
            sum += (a.eval(l[j]) * l[j] * e.0[j] / pdf[j]) as f64 / 4.0;
        }
    }
    sum / n_samples as f64
}

/// The values of a mesh attribute for one triangle `t` of the mesh, as the attribute of a
/// mesh of that triangle alone (vertices in the order `idx`).
fn one_triangle(a: &pt_scene::MeshAttribute, idx: &[u32; 3], t: usize) -> pt_scene::MeshAttribute {
    let d = a.dims as usize;
    let values = match a.kind {
        pt_scene::AttributeKind::Vertex => idx
            .iter()
            .flat_map(|&i| a.values[i as usize * d..][..d].iter().copied())
            .collect(),
        pt_scene::AttributeKind::Face => a.values[t * d..][..d].to_vec(),
    };
    pt_scene::MeshAttribute {
        values,
        ..a.clone()
    }
}
