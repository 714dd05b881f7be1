//! A renderable scene built from the loader's description: BVH, materials, lights, camera.

use crate::accel::{Accel, AccelHit, BvhKind};
use crate::camera::Camera;
use crate::geometry::{Interaction, Primitive};
use crate::light::{AreaLight, EnvMap, Light, LightShape, LightTriangle, SpotCone};
use pt_bsdf::{
    Bsdf, CoatingTable, Conductor, Dielectric, Distribution, FilmBase, GltfPbr, Lambert,
    Microfacet, Minnaert, OrenNayar, OrenNayarVariant, RoughConductor, RoughDielectric,
    RoughPlastic, RoughThinFilm, SurfaceBsdf, ThinDielectric, ThinFilm,
};
use pt_math::{Distribution1D, Frame, Mat3, Ray, Vec2, Vec3, Vec3A};
use pt_scene::{
    BsdfDesc, BsdfKind, Geometry, LightDesc, LightKind, SceneDesc, SourceLoc, SpectrumDesc,
    TriangleMesh,
};
use pt_spectrum::{
    xyz_to_srgb, ColorMode, NamedIlluminant, SampledSpectrum, SampledWavelengths, Spectrum,
};

/// Errors found while building a scene (after parsing): each names the element at fault.
#[derive(Debug, thiserror::Error)]
#[error("{loc}: {message}")]
pub struct BuildError {
    /// The offending element.
    pub loc: SourceLoc,
    /// What is wrong.
    pub message: String,
}

/// How lights are chosen for next-event estimation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum LightSelection {
    /// Proportional to emitted power (default).
    #[default]
    Power,
    /// Uniform over lights (Mitsuba 3's choice), for comparison.
    Uniform,
}

/// Per-shape data needed after a hit.
struct ShapeData {
    material: u32,
    light: Option<u32>,
    /// Index into `Scene::media` of the shape's interior medium.
    interior: Option<u32>,
    /// Vertex normals and uvs of meshes, indexed through `indices`.
    normals: Option<Vec<Vec3>>,
    uvs: Option<Vec<Vec2>>,
    /// Vertex tangents (xyz, handedness w) of meshes that have them (normal maps).
    tangents: Option<Vec<pt_math::Vec4>>,
    indices: Vec<[u32; 3]>,
}

/// Where each BVH primitive came from.
#[derive(Clone, Copy)]
struct PrimRef {
    shape: u32,
    /// Triangle index within the shape's mesh (0 for spheres); for a parallelogram, the first
    /// of its two triangles (`local + 1` is the other).
    local: u32,
    /// For a parallelogram: which vertex of triangle `local` is its corner `v0` (its edges run
    /// to the next two vertices in winding order). `None` for a triangle or sphere.
    corner: Option<u8>,
}

impl PrimRef {
    /// A triangle's or sphere's reference.
    fn single(shape: u32, local: u32) -> Self {
        PrimRef {
            shape,
            local,
            corner: None,
        }
    }

    /// The vertex indices of triangle `local` of `indices`, rotated so that a parallelogram's
    /// corner comes first: vertex 0 has barycentric weight `1 - b1 - b2`, 1 and 2 have `b1`
    /// and `b2` (over a parallelogram the same affine interpolation, with `1 - b1 - b2` down
    /// to -1 in the second triangle's half).
    #[inline(always)]
    fn vertices(&self, indices: &[[u32; 3]]) -> [u32; 3] {
        let t = indices
            .get(self.local as usize)
            .copied()
            .unwrap_or([0, 0, 0]);
        match self.corner {
            Some(c) => rotate(t, c),
            None => t,
        }
    }
}

/// Whether hits on a shape need its texture coordinates and the tangent dp/du derived from
/// them: for a textured material, a textured emitter, or a BSDF that may depend on the azimuth
/// (anisotropic roughness follows dp/du, as in Mitsuba). Without them the hit gets dp/du = 0
/// and the shading frame an arbitrary tangent, which leaves an isotropic BSDF's values and
/// sampling distribution unchanged. Skipping the interpolation and the dp/du solve saves about
/// 4% of the Cornell box's render time.
fn uses_uv(material: &SurfaceBsdf, textured: bool, light: Option<&Light>) -> bool {
    let isotropic = |b: &Bsdf| {
        matches!(
            b,
            Bsdf::Lambert(_)
                | Bsdf::OrenNayar(_)
                | Bsdf::Minnaert(_)
                | Bsdf::Conductor(_)
                | Bsdf::Dielectric(_)
                | Bsdf::ThinDielectric(_)
                | Bsdf::ThinFilm(_)
        )
    };
    let textured_light =
        matches!(light, Some(Light::Area(a)) if a.texture.is_some() || a.spectral.is_some());
    textured
        || textured_light
        || material.normal.is_some()
        || !isotropic(&material.bsdf)
        || material.blend.as_ref().is_some_and(|(_, b)| !isotropic(b))
}

/// The data of the integrator's vectorised shading (eight paths' scattering in SIMD lanes, see
/// `integrator::scatter_lanes`), for scenes where it gives exactly what the general code
/// gives: RGB mode, every light a parallelogram area light of constant radiance (so light
/// samples need no texture or spectrum), and a light to sample. Hits on Lambert materials that
/// are opaque, unblended and without normal map or texture go through it; all other hits
/// through the general code.
pub struct LaneShading {
    /// Per material: the Lambert albedo (RGB, fourth lane 0) and two-sidedness, or `None`.
    lambert: Vec<Option<([f32; 4], bool)>>,
    /// Per light (same order as `Scene::lights`).
    pub lights: Vec<LaneLight>,
}

/// A parallelogram area light as the vectorised shading samples it (world space).
#[derive(Clone, Copy)]
pub struct LaneLight {
    /// Corner.
    pub v0: Vec3,
    /// First edge.
    pub e1: Vec3,
    /// Second edge.
    pub e2: Vec3,
    /// Unit normal of the emitting side.
    pub n: Vec3,
    /// Area (scene units squared).
    pub area: f32,
    /// Emitted radiance (RGB lanes, fourth as stored).
    pub radiance: [f32; 4],
}

impl LaneShading {
    fn new(
        mode: ColorMode,
        materials: &[SurfaceBsdf],
        textures: &[Option<Box<MaterialTextures>>],
        lights: &[Light],
        has_light_choice: bool,
    ) -> Option<Self> {
        if mode != ColorMode::Rgb || !has_light_choice {
            return None;
        }
        let lights = lights
            .iter()
            .map(|l| match l {
                Light::Area(a) if a.texture.is_none() && a.spectral.is_none() => match a.shape {
                    LightShape::Parallelogram { v0, e1, e2, n, .. } => Some(LaneLight {
                        v0,
                        e1,
                        e2,
                        n,
                        area: a.area,
                        radiance: a.radiance.0.to_array(),
                    }),
                    _ => None,
                },
                _ => None,
            })
            .collect::<Option<Vec<_>>>()?;
        let lambert = materials
            .iter()
            .enumerate()
            .map(
                |(m, b)| match (b.bsdf, b.opacity, b.normal, b.blend, textures.get(m)) {
                    (Bsdf::Lambert(l), o, None, None, None | Some(None)) if o == 1.0 => {
                        Some((l.reflectance.0.to_array(), b.two_sided))
                    }
                    _ => None,
                },
            )
            .collect();
        Some(LaneShading { lambert, lights })
    }
}

/// `t` rotated so that `t[c]` comes first (winding kept); `c` < 3.
#[inline(always)]
fn rotate(t: [u32; 3], c: u8) -> [u32; 3] {
    const ORDER: [[usize; 3]; 3] = [[0, 1, 2], [1, 2, 0], [2, 0, 1]];
    ORDER[c as usize].map(|k| t[k])
}

/// Counts for `pt info` and logs.
#[derive(Clone, Debug, Default)]
pub struct SceneStats {
    /// Triangles in the BVH, counting those merged into parallelograms.
    pub triangles: usize,
    /// Pairs of mesh triangles tested as one parallelogram (rectangles, cube faces, quads).
    pub parallelograms: usize,
    /// Analytic spheres in the BVH.
    pub spheres: usize,
    /// Zero-area triangles left out of the BVH (they can neither be hit nor emit).
    pub degenerate_triangles: usize,
}

/// A scene ready for rendering. Immutable and shared by all render threads.
pub struct Scene {
    accel: Accel,
    prim_refs: Vec<PrimRef>,
    shapes: Vec<ShapeData>,
    /// One BSDF per material of the description (RGB mode: evaluated once; spectral mode: at
    /// a reference white, used only as a fallback).
    pub materials: Vec<SurfaceBsdf>,
    /// Spectral mode: each material's spectra, evaluated per path at its wavelengths.
    spectral_materials: Vec<SpectralMaterial>,
    /// Spectral mode: per material, its fluorescence model if it is `fluorescent`.
    fluorescent: Vec<Option<crate::fluorescence::Fluorescent>>,
    /// Per material: its textures, `None` when nothing of it varies over the surface (then, in
    /// RGB mode, `materials[m]` is its BSDF at every hit).
    textures: Vec<Option<Box<MaterialTextures>>>,
    /// Spectral mode: each light's emission spectrum (its `radiance` fields hold the geometric
    /// factors only); empty in RGB mode. Textured area lights and environment maps multiply it
    /// by their texels' upsampled spectra themselves (D65 here); lights with display primaries
    /// have `None` (their texture gives the whole spectrum).
    light_spectra: Vec<Option<Spectrum>>,
    /// Interior media (absorbing only): extinction per scene unit, RGB lanes in RGB mode, and the
    /// spectrum evaluated per path in spectral mode.
    media: Vec<(SampledSpectrum, Option<Spectrum>)>,
    /// All lights: area lights first (in shape order), then the others in file order.
    pub lights: Vec<Light>,
    /// Indices into `lights` of lights that rays leaving the scene can see.
    pub infinite_lights: Vec<usize>,
    light_distr: Option<Distribution1D>,
    /// What the integrator's vectorised shading needs, for scenes that allow it (see
    /// [`LaneShading`]).
    lane_shading: Option<LaneShading>,
    /// Centre and radius of the scene's bounding sphere.
    pub bounds: (Vec3, f32),
    /// The camera.
    pub camera: Camera,
    /// Colour mode the scene is rendered in.
    pub mode: ColorMode,
    /// Counts.
    pub stats: SceneStats,
}

/// How an RGB or constant input becomes a spectrum in spectral mode (Jakob & Hanika 2019
/// upsampling; DESIGN.md "Colour").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Role {
    /// Bounded reflectance in [0, 1].
    Albedo,
    /// Unbounded positive quantity (conductor eta, k).
    Unbounded,
    /// Emission: upsampled colour times D65; a constant c becomes D65 scaled to luminance c
    /// (Mitsuba's convention for emitters).
    Emission,
}

/// RGB value of a spectral input (see `spectrum`), for RGB-only methods such as radiosity.
pub fn rgb_of(s: &SpectrumDesc) -> [f32; 3] {
    spectrum(s).rgb()
}

/// RGB-mode value of a spectral input. A tabulated spectrum (only with `--mode rgb` on a
/// spectral scene) is projected to linear sRGB through the CIE 1931 observer, as Mitsuba's RGB
/// variants do.
fn spectrum(s: &SpectrumDesc) -> SampledSpectrum {
    match s {
        SpectrumDesc::Constant(v) => SampledSpectrum::from_rgb([*v; 3]),
        SpectrumDesc::Rgb(c) => SampledSpectrum::from_rgb(*c),
        SpectrumDesc::Tabulated(p) => match Spectrum::tabulated(p) {
            Ok(sp) => SampledSpectrum::from_rgb(xyz_to_srgb(sp.emission_xyz())),
            Err(_) => SampledSpectrum::ZERO,
        },
        SpectrumDesc::Blackbody { .. } | SpectrumDesc::Illuminant { .. } => {
            SampledSpectrum::from_rgb(xyz_to_srgb(to_spectrum(s, Role::Emission).emission_xyz()))
        }
    }
}

/// The spectrum spectral mode uses for an input: a reflectance (`emission` false, RGB upsampled
/// as a bounded albedo) or an emission (RGB times D65). For other methods (spectral radiosity)
/// that must treat inputs exactly as the path tracer does.
pub fn spectrum_for(s: &SpectrumDesc, emission: bool) -> Spectrum {
    to_spectrum(
        s,
        if emission {
            Role::Emission
        } else {
            Role::Albedo
        },
    )
}

/// Spectral-mode form of an input (fitted once at scene build).
fn to_spectrum(s: &SpectrumDesc, role: Role) -> Spectrum {
    match (s, role) {
        (SpectrumDesc::Constant(v), Role::Emission) => {
            Spectrum::illuminant(NamedIlluminant::D65, *v)
        }
        (SpectrumDesc::Constant(v), _) => Spectrum::constant(*v),
        (SpectrumDesc::Rgb(c), Role::Albedo) => Spectrum::rgb_albedo(*c),
        (SpectrumDesc::Rgb(c), Role::Unbounded) => Spectrum::rgb_unbounded(*c),
        (SpectrumDesc::Rgb(c), Role::Emission) => Spectrum::rgb_illuminant(*c),
        (SpectrumDesc::Tabulated(p), _) => {
            Spectrum::tabulated(p).unwrap_or(Spectrum::constant(0.0))
        }
        (SpectrumDesc::Blackbody { temperature }, _) => {
            Spectrum::blackbody(*temperature).unwrap_or(Spectrum::constant(0.0))
        }
        (SpectrumDesc::Illuminant { name, scale }, _) => match NamedIlluminant::from_name(name) {
            Some(which) => Spectrum::illuminant(which, *scale),
            None => Spectrum::constant(0.0), // the loader accepts only known names
        },
    }
}

/// The BSDF of a material description. `val` turns each spectral parameter into lane values;
/// it is called in a fixed order, so spectral mode can fit the spectra once (at build) and
/// evaluate them per path in the same order.
fn material_with(
    desc: &BsdfDesc,
    lambda: Option<&SampledWavelengths>,
    val: &mut dyn FnMut(&SpectrumDesc, Role) -> SampledSpectrum,
    tables: &mut dyn FnMut(Distribution, f32, f32) -> &'static CoatingTable,
) -> Result<SurfaceBsdf, BuildError> {
    let one_sided = |bsdf| SurfaceBsdf::new(bsdf, false);
    let mf = |dist: &str, au: f32, av: f32| -> Result<Microfacet, BuildError> {
        let d = Distribution::from_name(dist).ok_or_else(|| BuildError {
            loc: desc.loc.clone(),
            message: format!("unknown microfacet distribution '{dist}'"),
        })?;
        Ok(Microfacet::new(d, au, av))
    };
    Ok(match &desc.kind {
        BsdfKind::Diffuse { reflectance } => {
            one_sided(Bsdf::Lambert(Lambert::new(val(reflectance, Role::Albedo))))
        }
        BsdfKind::TwoSided { inner } => SurfaceBsdf {
            two_sided: true,
            ..material_with(inner, lambda, val, tables)?
        },
        BsdfKind::Mask { opacity, inner } => SurfaceBsdf {
            opacity: *opacity,
            ..material_with(inner, lambda, val, tables)?
        },
        // The perturbed frame depends on the hit: set by `Scene::material_at_hit`.
        BsdfKind::NormalMap { inner, .. } => material_with(inner, lambda, val, tables)?,
        // The thickness depends on the hit: set by `Scene::material_at_hit`.
        BsdfKind::FilmThicknessTexture { inner, .. } => material_with(inner, lambda, val, tables)?,
        // The opacity depends on the hit: set by `Scene::material_at_hit`.
        BsdfKind::OpacityTexture { inner, .. } => material_with(inner, lambda, val, tables)?,
        BsdfKind::Blend {
            weight,
            first,
            second,
            ..
        } => {
            let (a, b) = (
                material_with(first, lambda, val, tables)?,
                material_with(second, lambda, val, tables)?,
            );
            let plain =
                |s: &SurfaceBsdf| s.opacity == 1.0 && s.normal.is_none() && s.blend.is_none();
            if !plain(&a) || !plain(&b) {
                return Err(BuildError { loc: desc.loc.clone(), message: "blendbsdf of masks, normal maps or blends is not yet supported (not yet implemented): put the mask or normal map around the blendbsdf".into() });
            }
            // `two_sided` never mirrors a transmissive model, so it may differ there.
            if a.two_sided != b.two_sided && !a.bsdf.is_transmissive() && !b.bsdf.is_transmissive()
            {
                return Err(BuildError { loc: desc.loc.clone(), message: "blendbsdf of a one-sided and a two-sided BSDF is not yet supported (not yet implemented): put twosided around the blendbsdf".into() });
            }
            SurfaceBsdf {
                blend: Some((*weight, b.bsdf)),
                two_sided: a.two_sided || b.two_sided,
                ..a
            }
        }
        BsdfKind::ThinFilm {
            thickness,
            film_ior,
            ext_ior,
            int_ior,
            eta,
            k,
        } => {
            let base = match int_ior {
                Some(ior) => FilmBase::Dielectric { ior: *ior },
                None => FilmBase::Conductor {
                    eta: val(eta, Role::Unbounded),
                    k: val(k, Role::Unbounded),
                },
            };
            // Spectral mode: exact Airy reflectance per lane; RGB mode: Belcour & Barla 2017.
            let film = match lambda {
                Some(l) => ThinFilm::spectral(*thickness, *film_ior, *ext_ior, base, l.lambda()),
                None => ThinFilm::rgb(*thickness, *film_ior, *ext_ior, base),
            };
            one_sided(Bsdf::ThinFilm(film))
        }
        BsdfKind::RoughThinFilm {
            thickness,
            film_ior,
            ext_ior,
            int_ior,
            eta,
            k,
            distribution,
            alpha_u,
            alpha_v,
        } => {
            let base = match int_ior {
                Some(ior) => FilmBase::Dielectric { ior: *ior },
                None => FilmBase::Conductor {
                    eta: val(eta, Role::Unbounded),
                    k: val(k, Role::Unbounded),
                },
            };
            let film = match lambda {
                Some(l) => ThinFilm::spectral(*thickness, *film_ior, *ext_ior, base, l.lambda()),
                None => ThinFilm::rgb(*thickness, *film_ior, *ext_ior, base),
            };
            one_sided(Bsdf::RoughThinFilm(RoughThinFilm::new(
                film,
                mf(distribution, *alpha_u, *alpha_v)?,
            )))
        }
        BsdfKind::OrenNayar {
            reflectance,
            sigma,
            variant,
        } => {
            let v = OrenNayarVariant::from_name(variant).ok_or_else(|| BuildError {
                loc: desc.loc.clone(),
                message: format!("unknown Oren-Nayar variant '{variant}'"),
            })?;
            one_sided(Bsdf::OrenNayar(OrenNayar::new(
                val(reflectance, Role::Albedo),
                *sigma,
                v,
            )))
        }
        BsdfKind::Minnaert { reflectance, k } => one_sided(Bsdf::Minnaert(Minnaert::new(
            val(reflectance, Role::Albedo),
            *k,
        ))),
        // Spectral mode replaces it by a Lambertian of the total albedo (`Scene::material_at`);
        // RGB mode cannot move light between wavelengths and keeps the elastic part only.
        BsdfKind::Fluorescent { reflectance, .. } => {
            one_sided(Bsdf::Lambert(Lambert::new(val(reflectance, Role::Albedo))))
        }
        // Lights on: the elastic part (the afterglow is rendered by `phosphorescence::afterglow`).
        BsdfKind::Phosphorescent { reflectance, .. } => {
            one_sided(Bsdf::Lambert(Lambert::new(val(reflectance, Role::Albedo))))
        }
        BsdfKind::Dielectric { int_ior, ext_ior } => {
            one_sided(Bsdf::Dielectric(Dielectric::new(int_ior / ext_ior)))
        }
        BsdfKind::ThinDielectric { int_ior, ext_ior } => {
            one_sided(Bsdf::ThinDielectric(ThinDielectric::new(int_ior / ext_ior)))
        }
        BsdfKind::RoughDielectric {
            int_ior,
            ext_ior,
            distribution,
            alpha_u,
            alpha_v,
        } => one_sided(Bsdf::RoughDielectric(RoughDielectric::new(
            int_ior / ext_ior,
            mf(distribution, *alpha_u, *alpha_v)?,
        ))),
        BsdfKind::Conductor {
            eta,
            k,
            specular_reflectance,
        } => {
            let (e, kk, sr) = (
                val(eta, Role::Unbounded),
                val(k, Role::Unbounded),
                val(specular_reflectance, Role::Albedo),
            );
            one_sided(Bsdf::Conductor(Conductor::new(e, kk, sr)))
        }
        BsdfKind::RoughPlastic {
            diffuse_reflectance,
            specular_reflectance,
            int_ior,
            ext_ior,
            distribution,
            alpha,
            nonlinear,
        } => {
            let (rho, ks) = (
                val(diffuse_reflectance, Role::Albedo),
                val(specular_reflectance, Role::Unbounded),
            );
            let m = mf(distribution, *alpha, *alpha)?;
            let eta = int_ior / ext_ior;
            // Mitsuba: the share of specular samples from the spectra's means (RGB means here, so
            // it is the same for every path; it changes the variance, not the expectation).
            let mean = |s: &SpectrumDesc| rgb_of(s).iter().sum::<f32>() / 3.0;
            let (d_mean, s_mean) = (mean(diffuse_reflectance), mean(specular_reflectance));
            let weight = if d_mean + s_mean > 0.0 {
                s_mean / (d_mean + s_mean)
            } else {
                0.5
            };
            let table = tables(m.dist, m.alpha_u, eta);
            one_sided(Bsdf::RoughPlastic(RoughPlastic::new(
                rho, ks, eta, m, *nonlinear, weight, table,
            )))
        }
        BsdfKind::RoughConductor {
            eta,
            k,
            specular_reflectance,
            distribution,
            alpha_u,
            alpha_v,
        } => {
            let (e, kk, sr) = (
                val(eta, Role::Unbounded),
                val(k, Role::Unbounded),
                val(specular_reflectance, Role::Albedo),
            );
            one_sided(Bsdf::RoughConductor(RoughConductor::new(
                e,
                kk,
                sr,
                mf(distribution, *alpha_u, *alpha_v)?,
            )))
        }
        BsdfKind::GltfPbr {
            base_color,
            metallic,
            roughness,
            ior,
            ..
        } => one_sided(Bsdf::GltfPbr(GltfPbr::new(
            val(base_color, Role::Albedo),
            *metallic,
            *roughness,
            *ior,
        ))),
    })
}

/// The fluorescence model of a `fluorescent` material (also inside `twosided`), else `None`.
fn fluorescent_model(b: &BsdfDesc) -> Result<Option<crate::fluorescence::Fluorescent>, BuildError> {
    match &b.kind {
        BsdfKind::TwoSided { inner }
        | BsdfKind::NormalMap { inner, .. }
        | BsdfKind::FilmThicknessTexture { inner, .. } => fluorescent_model(inner),
        // The integrator switches wavelengths before the BSDF chooses between pass-through and
        // scattering, which would be wrong for the pass-through part.
        BsdfKind::Blend { first, second, .. }
            if fluorescent_model(first)?.is_some() || fluorescent_model(second)?.is_some() =>
        {
            Err(BuildError {
                loc: b.loc.clone(),
                message:
                    "a blendbsdf with a fluorescent BSDF is not yet supported (not yet implemented)"
                        .into(),
            })
        }
        BsdfKind::Mask { inner, .. } | BsdfKind::OpacityTexture { inner, .. }
            if fluorescent_model(inner)?.is_some() =>
        {
            Err(BuildError {
                loc: b.loc.clone(),
                message:
                    "a mask around a fluorescent BSDF is not yet supported (not yet implemented)"
                        .into(),
            })
        }
        BsdfKind::Fluorescent {
            reflectance,
            absorption,
            emission,
            quantum_yield,
        } => crate::fluorescence::Fluorescent::new(
            to_spectrum(reflectance, Role::Albedo),
            &to_spectrum(absorption, Role::Albedo),
            &to_spectrum(emission, Role::Unbounded),
            *quantum_yield,
        )
        .map(Some)
        .map_err(|message| BuildError {
            loc: b.loc.clone(),
            message,
        }),
        _ => Ok(None),
    }
}

/// Spectral-mode data of one material: its description and its spectra, fitted at build in the
/// order [`material_with`] asks for them.
struct SpectralMaterial {
    desc: BsdfDesc,
    spectra: Vec<Spectrum>,
    /// Coating tables (rough plastic), in the order [`material_with`] asks for them: looked up
    /// once at build so that per-path rebuilding takes no lock.
    tables: Vec<&'static CoatingTable>,
}

impl Scene {
    /// Builds the BVH and lights in the colour mode the scene needs (spectral when it has
    /// wavelength-dependent inputs, see [`SceneDesc::spectral_reason`]). `selection` chooses how
    /// NEE picks lights.
    pub fn build(
        desc: &SceneDesc,
        bvh: BvhKind,
        selection: LightSelection,
    ) -> Result<Scene, BuildError> {
        Scene::build_with_mode(desc, bvh, selection, None)
    }

    /// [`Scene::build`] with the colour mode forced (`--mode`); `None` chooses automatically.
    pub fn build_with_mode(
        desc: &SceneDesc,
        bvh: BvhKind,
        selection: LightSelection,
        mode: Option<ColorMode>,
    ) -> Result<Scene, BuildError> {
        let mode = mode.unwrap_or(if desc.spectral_reason().is_some() {
            ColorMode::Spectral
        } else {
            ColorMode::Rgb
        });
        let spectral = mode == ColorMode::Spectral;
        let materials: Vec<SurfaceBsdf> = desc
            .bsdfs
            .iter()
            .map(|b| material_with(b, None, &mut |s, _| spectrum(s), &mut CoatingTable::get))
            .collect::<Result<_, _>>()?;
        let textures = desc
            .bsdfs
            .iter()
            .map(|b| MaterialTextures::of(b, spectral))
            .collect::<Result<Vec<_>, _>>()?;
        let mut spectral_materials = Vec::new();
        if spectral {
            for b in &desc.bsdfs {
                let mut spectra = Vec::new();
                let mut tables = Vec::new();
                material_with(
                    b,
                    None,
                    &mut |s, role| {
                        spectra.push(to_spectrum(s, role));
                        SampledSpectrum::ZERO
                    },
                    &mut |d, a, e| {
                        let t = CoatingTable::get(d, a, e);
                        tables.push(t);
                        t
                    },
                )?;
                spectral_materials.push(SpectralMaterial {
                    desc: b.clone(),
                    spectra,
                    tables,
                });
            }
        }
        let fluorescent = if spectral {
            desc.bsdfs
                .iter()
                .map(fluorescent_model)
                .collect::<Result<Vec<_>, _>>()?
        } else {
            Vec::new()
        };
        // Emission: RGB mode keeps the colour in the light; spectral mode keeps a unit factor in
        // the light and the spectrum beside it.
        let mut light_spectra: Vec<Option<Spectrum>> = Vec::new();
        let mut emission = |s: &SpectrumDesc| -> SampledSpectrum {
            if spectral {
                light_spectra.push(Some(to_spectrum(s, Role::Emission)));
                SampledSpectrum::splat(1.0)
            } else {
                spectrum(s)
            }
        };
        let mut prims = Vec::new();
        let mut refs = Vec::new();
        let mut shapes = Vec::new();
        let mut lights = Vec::new();
        let mut stats = SceneStats::default();
        let mut media = Vec::new();
        // Lights with display primaries: their spectrum is in the texture (light spectrum 1).
        let mut primaries_lights: Vec<usize> = Vec::new();

        for (si, shape) in desc.shapes.iter().enumerate() {
            if shape.bsdf >= materials.len() {
                return Err(BuildError {
                    loc: shape.loc.clone(),
                    message: format!("BSDF index {} out of range", shape.bsdf),
                });
            }
            let mut data = ShapeData {
                material: shape.bsdf as u32,
                light: None,
                interior: None,
                normals: None,
                uvs: None,
                tangents: None,
                indices: Vec::new(),
            };
            let light_shape = match &shape.geometry {
                Geometry::Mesh(mesh) => {
                    let tris = add_mesh(
                        mesh,
                        si as u32,
                        shape.emitter.is_some(),
                        &mut prims,
                        &mut refs,
                        &mut stats,
                        &shape.loc,
                    )?;
                    if let Some(ts) = &mesh.tangents {
                        if ts.len() != mesh.positions.len() {
                            return Err(BuildError {
                                loc: shape.loc.clone(),
                                message: format!(
                                    "mesh has {} tangents for {} vertices",
                                    ts.len(),
                                    mesh.positions.len()
                                ),
                            });
                        }
                    }
                    // An emitter that is one parallelogram (a rectangle light) samples it as one.
                    let single = match (prims.last(), refs.last(), &tris) {
                        (Some(&prim), Some(r), Some((t, _)))
                            if r.shape == si as u32 && t.len() == 2 =>
                        {
                            parallelogram_light(mesh, prim, *r)
                        }
                        _ => None,
                    };
                    single.or_else(|| {
                        tris.map(|(tris, areas)| {
                            (
                                LightShape::Mesh {
                                    distr: Distribution1D::new(&areas).expect("non-empty"),
                                    tris,
                                },
                                areas.iter().sum::<f32>(),
                            )
                        })
                    })
                }
                &Geometry::Sphere {
                    center,
                    radius,
                    flip_normals,
                } => {
                    if !(radius > 0.0 && radius.is_finite() && center.is_finite()) {
                        return Err(BuildError {
                            loc: shape.loc.clone(),
                            message: format!(
                                "sphere radius must be positive and finite, got {radius}"
                            ),
                        });
                    }
                    prims.push(Primitive::Sphere {
                        center: center.into(),
                        radius,
                        flip: flip_normals,
                    });
                    refs.push(PrimRef::single(si as u32, 0));
                    stats.spheres += 1;
                    Some((
                        LightShape::Sphere {
                            center,
                            radius,
                            flip: flip_normals,
                        },
                        4.0 * std::f32::consts::PI * radius * radius,
                    ))
                }
            };
            if let Some(m) = &shape.interior {
                let rgb = spectrum(&m.sigma_t);
                if !rgb.is_finite() || rgb.0.min_element() < 0.0 {
                    return Err(BuildError {
                        loc: m.loc.clone(),
                        message: "sigma_t must be finite and non-negative".into(),
                    });
                }
                data.interior = Some(media.len() as u32);
                media.push((
                    rgb,
                    spectral.then(|| to_spectrum(&m.sigma_t, Role::Unbounded)),
                ));
            }
            if let Some(em) = &shape.emitter {
                // glTF emissiveTexture: glTF defines emission as factor x texel in RGB, so the
                // factor is multiplied into the texels and the light keeps a white factor; in
                // spectral mode each product texel is then upsampled (a product of the factor's
                // and the texel's spectra would leave the gamut for saturated colours).
                let white = SpectrumDesc::Rgb([1.0; 3]);
                let radiance = emission(if em.uv_texture.is_some() {
                    &white
                } else {
                    &em.radiance
                });
                if !radiance.is_finite() || radiance.0.min_element() < 0.0 {
                    return Err(BuildError {
                        loc: em.loc.clone(),
                        message: "radiance must be finite and non-negative".into(),
                    });
                }
                if (em.texture.is_some() || em.uv_texture.is_some())
                    && matches!(shape.geometry, Geometry::Sphere { .. })
                {
                    return Err(BuildError { loc: em.loc.clone(), message: "textured emitters on spheres are not yet supported (not yet implemented); use a mesh".into() });
                }
                let texture = match (&em.texture, &em.uv_texture) {
                    (Some(t), _) => Some(std::sync::Arc::new(
                        crate::texture::Bitmap::load(t).map_err(|m| BuildError {
                            loc: t.loc.clone(),
                            message: m,
                        })?,
                    )),
                    // glTF emissiveTexture: the image times `radiance` (the emissive factor).
                    (None, Some(t)) => {
                        let f = rgb_of(&em.radiance);
                        let image =
                            crate::texture::Bitmap::from_source(&t.source, t.srgb, t.nearest)
                                .map_err(|m| BuildError {
                                    loc: em.loc.clone(),
                                    message: m,
                                })?;
                        Some(std::sync::Arc::new(
                            image.map_texels(|c| [c[0] * f[0], c[1] * f[1], c[2] * f[2]]),
                        ))
                    }
                    (None, None) => None,
                };
                // Spectral mode: the image's spectral form (per-texel upsampling, times the D65 of
                // the light's emission spectrum; or display primaries, whose light spectrum is 1).
                let (texture, spectral_tex) =
                    emission_texture(texture, em, spectral, lights.len(), &mut primaries_lights)?;
                match light_shape {
                    Some((shape, area)) if area > 0.0 => {
                        data.light = Some(lights.len() as u32);
                        lights.push(Light::Area(AreaLight {
                            radiance,
                            texture,
                            spectral: spectral_tex,
                            shape,
                            area,
                        }));
                    }
                    _ => {
                        return Err(BuildError {
                            loc: em.loc.clone(),
                            message: "area emitter on a shape with zero area".into(),
                        });
                    }
                }
            }
            shapes.push(data);
        }

        let bounds = bounding_sphere(&prims);
        // The primitives are made again from the description after the BVH build (less memory).
        let accel = Accel::build_compact(prims, bvh, |i| primitive_of(desc, refs[i]));
        // Into the BVH's order in place (a second array of these was 12 MB per million
        // primitives at the memory peak).
        let mut prim_refs = refs;
        crate::accel::permute_in_place(&mut prim_refs, &accel.original_index);
        // Vertex data for shading, copied after the BVH build (whose temporaries are the memory
        // peak) rather than before.
        for (data, shape) in shapes.iter_mut().zip(&desc.shapes) {
            if let Geometry::Mesh(mesh) = &shape.geometry {
                data.normals = mesh.normals.clone();
                // Texture coordinates (and dp/du, from them) only where something reads them.
                if uses_uv(
                    &materials[data.material as usize],
                    textures[data.material as usize].is_some(),
                    data.light.map(|i| &lights[i as usize]),
                ) {
                    data.uvs = mesh.uvs.clone();
                }
                data.tangents = mesh.tangents.clone();
                // Indices serve only to interpolate normals, uvs and tangents: without them, no copy.
                if data.normals.is_some() || data.uvs.is_some() || data.tangents.is_some() {
                    data.indices = mesh.indices.clone();
                }
            }
        }
        for l in &desc.lights {
            let mut light = build_light(l, &mut emission)?;
            if let (true, Light::EnvMap(e)) = (spectral, &mut light) {
                e.upsample();
            }
            lights.push(light);
        }
        for &i in &primaries_lights {
            light_spectra[i] = None;
        }
        let infinite_lights = (0..lights.len())
            .filter(|&i| lights[i].is_infinite())
            .collect();
        // Spectral mode: scale each light's geometric power by its spectrum's luminance.
        let luminance = |i: usize| {
            light_spectra
                .get(i)
                .and_then(|s| s.as_ref())
                .map_or(1.0, |s| s.emission_xyz()[1])
        };
        let weights: Vec<f32> = match selection {
            LightSelection::Power => lights
                .iter()
                .enumerate()
                .map(|(i, l)| l.power(bounds.1) * luminance(i))
                .collect(),
            LightSelection::Uniform => vec![1.0; lights.len()],
        };
        let light_distr = Distribution1D::new(&weights);
        let camera = Camera::new(&desc.camera, desc.film.width, desc.film.height);
        if !spectral {
            light_spectra.clear();
        }
        let lane_shading =
            LaneShading::new(mode, &materials, &textures, &lights, light_distr.is_some());
        Ok(Scene {
            accel,
            prim_refs,
            shapes,
            materials,
            spectral_materials,
            fluorescent,
            textures,
            light_spectra,
            media,
            lights,
            infinite_lights,
            light_distr,
            lane_shading,
            bounds,
            camera,
            mode,
            stats,
        })
    }

    /// Closest hit along `ray`, with its surface data.
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray) -> Option<Interaction> {
        let AccelHit {
            index: id,
            t,
            b1,
            b2,
        } = self.accel.intersect(ray)?;
        let r = self.prim_refs[id];
        let shape = &self.shapes[r.shape as usize];
        match self.accel.prims[id] {
            Primitive::Triangle { v0, e1, e2 } | Primitive::Parallelogram { v0, e1, e2 } => {
                let b0 = 1.0 - b1 - b2;
                let p = Vec3::from(v0 + e1 * b1 + e2 * b2);
                let ng = match self.accel.unit_normals.get(id) {
                    Some(&n) => n,
                    None => Vec3::from(e1.cross(e2)).normalize(),
                };
                let idx = r.vertices(&shape.indices);
                let ns = match &shape.normals {
                    Some(n) => {
                        let v = n[idx[0] as usize] * b0
                            + n[idx[1] as usize] * b1
                            + n[idx[2] as usize] * b2;
                        v.try_normalize().unwrap_or(ng)
                    }
                    None => ng,
                };
                let (uv, dpdu) = match &shape.uvs {
                    Some(uv) => {
                        let (t0, t1, t2) = (
                            uv[idx[0] as usize],
                            uv[idx[1] as usize],
                            uv[idx[2] as usize],
                        );
                        // dp/du from the uv differentials (pbrt-v4 eq. 6.7): solve
                        // [e1 e2] = [dpdu dpdv] [du1 du2; dv1 dv2].
                        let (d1, d2) = (t1 - t0, t2 - t0);
                        let det = d1.x * d2.y - d1.y * d2.x;
                        let dpdu = if det != 0.0 {
                            (Vec3::from(e1) * d2.y - Vec3::from(e2) * d1.y) / det
                        } else {
                            Vec3::ZERO
                        };
                        (
                            t0 * b0 + t1 * b1 + t2 * b2,
                            if dpdu.is_finite() { dpdu } else { Vec3::ZERO },
                        )
                    }
                    None => (Vec2::new(b1, b2), Vec3::ZERO),
                };
                let tangent = match &shape.tangents {
                    Some(ts) => {
                        let (a, b, c) = (
                            ts[idx[0] as usize],
                            ts[idx[1] as usize],
                            ts[idx[2] as usize],
                        );
                        // Handedness is constant over a triangle in well-formed data; take vertex 0's.
                        (a * b0 + b * b1 + c * b2).truncate().extend(if a.w < 0.0 {
                            -1.0
                        } else {
                            1.0
                        })
                    }
                    None => pt_math::Vec4::ZERO,
                };
                Some(Interaction {
                    p,
                    ng,
                    ns,
                    uv,
                    dpdu,
                    tangent,
                    t,
                    shape: r.shape,
                })
            }
            Primitive::Sphere {
                center,
                radius,
                flip,
            } => {
                let c = Vec3::from(center);
                let local = (ray.at(t) - c).normalize();
                // Re-project onto the surface: removes the error of o + t d (pbrt-v4 6.8.5).
                let p = c + local * radius;
                let n = if flip { -local } else { local };
                let uv = Vec2::new(local.y.atan2(local.x), local.z.clamp(-1.0, 1.0).acos());
                // Mitsuba's sphere: u runs along the longitude about its local z axis (spheres
                // here carry no rotation).
                let dpdu = Vec3::new(-local.y, local.x, 0.0);
                Some(Interaction {
                    p,
                    ng: n,
                    ns: n,
                    uv,
                    dpdu,
                    tangent: pt_math::Vec4::ZERO,
                    t,
                    shape: r.shape,
                })
            }
        }
    }

    /// Whether the segment `ray` (tmin..tmax) is blocked.
    #[inline(always)]
    pub fn occluded(&self, ray: &Ray) -> bool {
        self.accel.occluded(ray)
    }

    /// The primitives the BVH holds (world space, in BVH order): triangles, parallelograms
    /// merged from triangle pairs, spheres. For benchmarks and tools.
    pub fn primitives(&self) -> &[Primitive] {
        &self.accel.prims
    }

    /// The BSDF of a hit shape at the path's wavelengths (RGB mode: the precomputed one).
    #[inline]
    pub fn material_at(&self, shape: u32, lambda: &SampledWavelengths) -> SurfaceBsdf {
        let m = self.shapes[shape as usize].material as usize;
        if let Some(Some(f)) = self.fluorescent.get(m) {
            return SurfaceBsdf {
                bsdf: Bsdf::Lambert(Lambert::new(f.albedo(lambda))),
                ..self.materials[m]
            };
        }
        match self.spectral_materials.get(m) {
            None => self.materials[m],
            Some(sm) => {
                let (mut i, mut j) = (0, 0);
                material_with(
                    &sm.desc,
                    Some(lambda),
                    &mut |_, _| {
                        let v = sm
                            .spectra
                            .get(i)
                            .map_or(SampledSpectrum::ZERO, |s| s.sample(lambda));
                        i += 1;
                        v
                    },
                    &mut |d, a, e| {
                        // Replays the build's lookups in order; a mismatch would be a bug, and
                        // falls back to the (locking) cache rather than failing.
                        let t = sm
                            .tables
                            .get(j)
                            .copied()
                            .unwrap_or_else(|| CoatingTable::get(d, a, e));
                        j += 1;
                        t
                    },
                )
                .unwrap_or(self.materials[m])
            }
        }
    }

    /// Whether the hit shape's material is fluorescent (spectral mode only).
    #[inline]
    pub fn is_fluorescent(&self, shape: u32) -> bool {
        matches!(
            self.fluorescent
                .get(self.shapes[shape as usize].material as usize),
            Some(Some(_))
        )
    }

    /// At a fluorescent hit, the wavelengths at which each lane continues (some lanes move to
    /// an excitation wavelength, see `fluorescence.rs`); unchanged elsewhere. `u` is uniform.
    #[inline]
    pub fn fluoresce(&self, shape: u32, lambda: &SampledWavelengths, u: f32) -> SampledWavelengths {
        match self
            .fluorescent
            .get(self.shapes[shape as usize].material as usize)
        {
            Some(Some(f)) => f.scatter(lambda, u),
            _ => *lambda,
        }
    }

    /// The BSDF at a hit: the material at the path's wavelengths ([`Scene::material_at`]) or,
    /// for textured glTF materials, at the hit's texture coordinates, with the textured normal
    /// map (turned into the perturbed frame, pt-bsdf `normal_map`, relative to the integrator's
    /// shading frame `Frame::from_normal_tangent(hit.ns, hit.dpdu)`), film thickness, opacity and
    /// blend weight.
    #[inline(always)]
    pub fn material_at_hit(&self, hit: &Interaction, lambda: &SampledWavelengths) -> SurfaceBsdf {
        let m = self.shapes[hit.shape as usize].material as usize;
        let Some(Some(tex)) = self.textures.get(m) else {
            // Nothing varies over the surface: RGB mode's precomputed BSDF (one lookup).
            return if self.mode == ColorMode::Rgb {
                self.materials[m]
            } else {
                self.material_at(hit.shape, lambda)
            };
        };
        let mut b = match &tex.pbr {
            Some(t) => t.eval(hit.uv, self.mode, lambda),
            None => self.material_at(hit.shape, lambda),
        };
        if let Some(nm) = &tex.normal {
            b.normal = nm.normal(hit);
        }
        if let Some(ft) = &tex.film {
            let d = ft.thickness(hit.uv);
            let second = b.blend.as_mut().map(|(_, s)| s);
            for model in std::iter::once(&mut b.bsdf).chain(second) {
                match model {
                    Bsdf::ThinFilm(f) => f.thickness_nm = d,
                    Bsdf::RoughThinFilm(r) => r.film.thickness_nm = d,
                    _ => {}
                }
            }
        }
        if let Some(ot) = &tex.opacity {
            b.opacity = ot.opacity(hit.uv);
        }
        if let (Some(bt), Some((w, _))) = (&tex.blend, b.blend.as_mut()) {
            *w = bt.weight(hit.uv);
        }
        b
    }

    /// Transmittance exp(-sigma_t d) of the interior medium of `shape` over `distance` scene units,
    /// at the path's wavelengths (spectral mode) or per RGB channel; `None` if it has no medium.
    #[inline]
    pub fn interior_transmittance(
        &self,
        shape: u32,
        distance: f32,
        lambda: &SampledWavelengths,
    ) -> Option<SampledSpectrum> {
        let (rgb, spectrum) = &self.media[self.shapes[shape as usize].interior? as usize];
        let sigma = match spectrum {
            Some(s) => s.sample(lambda),
            None => *rgb,
        };
        let e = sigma.0 * -distance;
        Some(SampledSpectrum(pt_math::Vec4::new(
            e.x.exp(),
            e.y.exp(),
            e.z.exp(),
            e.w.exp(),
        )))
    }

    /// The emission spectrum of light `i` at the path's wavelengths, which multiplies the
    /// radiance the light reports (spectral mode); 1 in RGB mode.
    #[inline]
    pub fn emission(&self, i: usize, lambda: &SampledWavelengths) -> SampledSpectrum {
        match self.light_spectra.get(i) {
            Some(Some(s)) => s.sample(lambda),
            _ => SampledSpectrum::splat(1.0),
        }
    }

    /// The light attached to a shape, if it emits: `(light index, light)`.
    #[inline]
    pub fn shape_light(&self, shape: u32) -> Option<(usize, &AreaLight)> {
        let i = self.shapes[shape as usize].light? as usize;
        match &self.lights[i] {
            Light::Area(a) => Some((i, a)),
            _ => None,
        }
    }

    /// Chooses a light for NEE: `(index, probability, u rescaled)`.
    #[inline(always)]
    pub fn sample_light(&self, u: f32) -> Option<(usize, f32, f32)> {
        self.light_distr.as_ref().map(|d| d.sample(u))
    }

    /// The vectorised shading's data, if the scene allows it.
    #[inline(always)]
    pub fn lane_shading(&self) -> Option<&LaneShading> {
        self.lane_shading.as_ref()
    }

    /// Switches the vectorised shading off (every hit then goes through the general code),
    /// for tests that compare the two.
    #[cfg(test)]
    pub(crate) fn disable_lane_shading(&mut self) {
        self.lane_shading = None;
    }

    /// Lambert albedo (RGB lanes, fourth 0) and two-sidedness of the shape's material, if the
    /// vectorised shading may shade its hits.
    #[inline(always)]
    pub fn lane_lambert(&self, lanes: &LaneShading, shape: u32) -> Option<([f32; 4], bool)> {
        lanes.lambert[self.shapes[shape as usize].material as usize]
    }

    /// Probability that NEE chooses light `i`.
    #[inline]
    pub fn light_pmf(&self, i: usize) -> f32 {
        self.light_distr.as_ref().map_or(0.0, |d| d.pmf(i))
    }
}

/// What varies over a material's surface: at least one of these is present.
struct MaterialTextures {
    /// glTF metallic-roughness factors times texels.
    pbr: Option<TexturedPbr>,
    normal: Option<NormalMapTex>,
    film: Option<FilmThicknessTex>,
    opacity: Option<OpacityTex>,
    blend: Option<BlendWeightTex>,
}

impl MaterialTextures {
    /// The textures of a material description, `None` if it has none.
    fn of(desc: &BsdfDesc, spectral: bool) -> Result<Option<Box<MaterialTextures>>, BuildError> {
        let t = MaterialTextures {
            pbr: TexturedPbr::of(desc, spectral)?,
            normal: NormalMapTex::of(desc)?,
            film: FilmThicknessTex::of(desc)?,
            opacity: OpacityTex::of(desc)?,
            blend: BlendWeightTex::of(desc)?,
        };
        let any = t.pbr.is_some()
            || t.normal.is_some()
            || t.film.is_some()
            || t.opacity.is_some()
            || t.blend.is_some();
        Ok(any.then(|| Box::new(t)))
    }
}

/// A bitmap looked up at a hit's texture coordinates through a KHR_texture_transform (the
/// identity for Mitsuba's bitmaps): every textured material parameter holds one.
struct UvBitmap {
    bitmap: std::sync::Arc<crate::texture::Bitmap>,
    /// `[a, b, c, d, e, f]`: `u' = a u + b v + c`, `v' = d u + e v + f`.
    transform: [f32; 6],
}

impl UvBitmap {
    fn new(bitmap: crate::texture::Bitmap, transform: [f32; 6]) -> Self {
        UvBitmap {
            bitmap: std::sync::Arc::new(bitmap),
            transform,
        }
    }

    /// The texture coordinates the bitmap is read at for the surface's `uv`.
    #[inline]
    fn map_uv(&self, uv: Vec2) -> Vec2 {
        let m = self.transform;
        Vec2::new(
            m[0] * uv.x + m[1] * uv.y + m[2],
            m[3] * uv.x + m[4] * uv.y + m[5],
        )
    }

    /// The (filtered) texel at the surface's `uv`, linear RGB.
    #[inline]
    fn eval(&self, uv: Vec2) -> [f32; 3] {
        self.bitmap.eval(self.map_uv(uv))
    }
}

/// A glTF metallic-roughness material with textures: factors times texels at the hit's uv.
struct TexturedPbr {
    base_color: [f32; 3],
    /// Spectral mode: the base colour factor's spectrum (no base colour texture then).
    base_spectrum: Spectrum,
    metallic: f32,
    roughness: f32,
    ior: f32,
    base_tex: Option<UvBitmap>,
    /// Spectral mode: the base colour texture's upsampled texels (reflectances), looked up
    /// with `base_tex`'s transform; they multiply `base_spectrum`.
    base_spec: Option<std::sync::Arc<crate::spectral_texture::SpectralBitmap>>,
    mr_tex: Option<UvBitmap>,
    two_sided: bool,
    /// Opacity of an enclosing `Mask` (glTF alpha), 1 without.
    opacity: f32,
}

impl TexturedPbr {
    /// The textured form of a material description, if it is a glTF material with textures.
    fn of(desc: &BsdfDesc, spectral: bool) -> Result<Option<TexturedPbr>, BuildError> {
        // glTF materials come as [NormalMap] around [Mask or OpacityTexture (alpha)] around
        // [TwoSided] around GltfPbr.
        let desc = match &desc.kind {
            BsdfKind::NormalMap { inner, .. } => inner.as_ref(),
            _ => desc,
        };
        let (desc_in, opacity) = match &desc.kind {
            BsdfKind::Mask { opacity, inner } => (inner.as_ref(), *opacity),
            // The opacity is set per hit (`Scene::material_at_hit`).
            BsdfKind::OpacityTexture { inner, .. } => (inner.as_ref(), 1.0),
            _ => (desc, 1.0),
        };
        let (inner, two_sided) = match &desc_in.kind {
            BsdfKind::TwoSided { inner } => (inner.as_ref(), true),
            _ => (desc_in, false),
        };
        let BsdfKind::GltfPbr {
            base_color,
            metallic,
            roughness,
            ior,
            base_color_texture,
            metallic_roughness_texture,
        } = &inner.kind
        else {
            return Ok(None);
        };
        if base_color_texture.is_none() && metallic_roughness_texture.is_none() {
            return Ok(None);
        }
        let load = |t: &Option<Box<pt_scene::UvTexture>>| -> Result<_, BuildError> {
            t.as_ref()
                .map(|t| {
                    crate::texture::Bitmap::from_source(&t.source, t.srgb, t.nearest)
                        .map(|b| UvBitmap::new(b, t.transform))
                })
                .transpose()
                .map_err(|m| BuildError {
                    loc: desc.loc.clone(),
                    message: m,
                })
        };
        let base_tex = load(base_color_texture)?;
        // Spectral mode: each texel upsampled as a bounded reflectance (Mitsuba's bitmap); the
        // factor's spectrum times the interpolated texel spectrum stands for factor x texel
        // (exact when either is grey, in particular for the default factor 1).
        let base_spec = match (&base_tex, spectral) {
            (Some(t), true) => Some(std::sync::Arc::new(
                crate::spectral_texture::SpectralBitmap::new(&t.bitmap),
            )),
            _ => None,
        };
        Ok(Some(TexturedPbr {
            base_color: rgb_of(base_color),
            base_spectrum: to_spectrum(base_color, Role::Albedo),
            metallic: *metallic,
            roughness: *roughness,
            ior: *ior,
            base_tex,
            base_spec,
            mr_tex: load(metallic_roughness_texture)?,
            two_sided,
            opacity,
        }))
    }

    /// The BSDF at texture coordinates `uv`, at the path's wavelengths in spectral mode (the
    /// factor's spectrum fitted once at build, the texels' at load).
    #[inline]
    fn eval(&self, uv: Vec2, mode: ColorMode, lambda: &SampledWavelengths) -> SurfaceBsdf {
        let mut c = self.base_color;
        if let (Some(t), ColorMode::Rgb) = (&self.base_tex, mode) {
            let v = t.eval(uv);
            c = [c[0] * v[0], c[1] * v[1], c[2] * v[2]];
        }
        let (mut metallic, mut roughness) = (self.metallic, self.roughness);
        if let Some(t) = &self.mr_tex {
            let v = t.eval(uv);
            roughness *= v[1];
            metallic *= v[2];
        }
        let base = match mode {
            ColorMode::Rgb => SampledSpectrum::from_rgb(c),
            ColorMode::Spectral => match (&self.base_spec, &self.base_tex) {
                (Some(sb), Some(t)) => {
                    self.base_spectrum.sample(lambda) * sb.eval(t.map_uv(uv), lambda)
                }
                _ => self.base_spectrum.sample(lambda),
            },
        };
        SurfaceBsdf {
            bsdf: Bsdf::GltfPbr(GltfPbr::new(base, metallic, roughness, self.ior)),
            two_sided: self.two_sided,
            opacity: self.opacity,
            normal: None,
            blend: None,
        }
    }
}

/// A material's normal map (pt-bsdf `normal_map`): the texture and whose tangent space it uses.
struct NormalMapTex {
    tex: UvBitmap,
    /// glTF `scale` on the decoded x and y.
    scale: f32,
    /// glTF tangent space (mesh tangents and handedness) rather than Mitsuba's (dp/du).
    gltf: bool,
}

impl NormalMapTex {
    /// The normal map of a material (found through `Mask`, `TwoSided` and `NormalMap` wrappers).
    fn of(desc: &BsdfDesc) -> Result<Option<NormalMapTex>, BuildError> {
        match &desc.kind {
            BsdfKind::Mask { inner, .. } | BsdfKind::TwoSided { inner } => NormalMapTex::of(inner),
            BsdfKind::NormalMap {
                texture,
                scale,
                gltf,
                inner,
            } => {
                if NormalMapTex::of(inner)?.is_some() {
                    return Err(BuildError {
                        loc: desc.loc.clone(),
                        message: "nested normal maps are not supported (not yet implemented)"
                            .into(),
                    });
                }
                let bitmap = crate::texture::Bitmap::from_source(
                    &texture.source,
                    texture.srgb,
                    texture.nearest,
                )
                .map_err(|m| BuildError {
                    loc: desc.loc.clone(),
                    message: m,
                })?;
                Ok(Some(NormalMapTex {
                    tex: UvBitmap::new(bitmap, texture.transform),
                    scale: *scale,
                    gltf: *gltf,
                }))
            }
            _ => Ok(None),
        }
    }

    /// The mapped normal at a hit, in the integrator's local shading frame (pt-bsdf
    /// `normal_map` builds the frame from it). The texel c decodes to n = 2 c - 1 (glTF: x and y
    /// times `scale`), in the tangent space (s, t, n): Mitsuba: s along dp/du, t = n x s; glTF:
    /// s along the mesh tangent, t = w (n x s).
    #[inline]
    fn normal(&self, hit: &Interaction) -> Option<Vec3> {
        let c = self.tex.eval(hit.uv);
        let n = Vec3::new(2.0 * c[0] - 1.0, 2.0 * c[1] - 1.0, 2.0 * c[2] - 1.0);
        if !self.gltf {
            return Some(n);
        }
        let n = Vec3::new(n.x * self.scale, n.y * self.scale, n.z);
        let local = Frame::from_normal_tangent(hit.ns, hit.dpdu);
        // Tangent frame of the mesh; without tangents, dp/du with w = +1.
        let (t, w) = if hit.tangent.truncate() != Vec3::ZERO {
            (hit.tangent.truncate(), hit.tangent.w)
        } else {
            (hit.dpdu, 1.0)
        };
        let tf = Frame::from_normal_tangent(hit.ns, t);
        let world = tf.s * n.x + tf.t * (w * n.y) + tf.n * n.z;
        Some(local.to_local(world))
    }
}

/// A texture read as one number per texel (`channel`), stored in all three channels.
fn scalar_bitmap(
    texture: &pt_scene::UvTexture,
    channel: pt_scene::TextureChannel,
) -> Result<crate::texture::Bitmap, String> {
    use pt_scene::TextureChannel as C;
    Ok(match channel {
        C::Alpha => crate::texture::Bitmap::alpha_from_source(&texture.source, texture.nearest)?,
        // Rec. 709 luminance of each texel, once (Mitsuba's eval_1 of an RGB bitmap).
        C::Luminance => {
            crate::texture::Bitmap::from_source(&texture.source, texture.srgb, texture.nearest)?
                .map_texels(|t| [0.212_671 * t[0] + 0.715_160 * t[1] + 0.072_169 * t[2]; 3])
        }
        C::Red => {
            crate::texture::Bitmap::from_source(&texture.source, texture.srgb, texture.nearest)?
                .map_texels(|t| [t[0]; 3])
        }
    })
}

/// A blend whose weight is textured (glTF `iridescenceTexture`): weight = factor x texel.
struct BlendWeightTex {
    tex: UvBitmap,
    /// The blend's own weight, which the texel multiplies.
    factor: f32,
}

impl BlendWeightTex {
    /// The textured blend weight of a material (through the other wrappers).
    fn of(desc: &BsdfDesc) -> Result<Option<BlendWeightTex>, BuildError> {
        match &desc.kind {
            BsdfKind::Mask { inner, .. }
            | BsdfKind::TwoSided { inner }
            | BsdfKind::NormalMap { inner, .. }
            | BsdfKind::OpacityTexture { inner, .. }
            | BsdfKind::FilmThicknessTexture { inner, .. } => BlendWeightTex::of(inner),
            BsdfKind::Blend {
                weight,
                weight_texture: Some((texture, channel)),
                ..
            } => {
                let bitmap = scalar_bitmap(texture, *channel).map_err(|m| BuildError {
                    loc: desc.loc.clone(),
                    message: m,
                })?;
                Ok(Some(BlendWeightTex {
                    tex: UvBitmap::new(bitmap, texture.transform),
                    factor: *weight,
                }))
            }
            _ => Ok(None),
        }
    }

    /// The blend weight at texture coordinates `uv`, in [0, 1].
    #[inline]
    fn weight(&self, uv: Vec2) -> f32 {
        (self.factor * self.tex.eval(uv)[0]).clamp(0.0, 1.0)
    }
}

/// An opacity texture (Mitsuba `mask` with a bitmap, glTF base colour alpha).
struct OpacityTex {
    tex: UvBitmap,
    /// Multiplies the texel's value.
    factor: f32,
    /// glTF MASK cutoff.
    cutoff: Option<f32>,
}

impl OpacityTex {
    /// The opacity texture of a material (through `TwoSided` and `NormalMap`; the glTF loader
    /// puts it outside `TwoSided`).
    fn of(desc: &BsdfDesc) -> Result<Option<OpacityTex>, BuildError> {
        match &desc.kind {
            BsdfKind::TwoSided { inner } | BsdfKind::NormalMap { inner, .. } => {
                OpacityTex::of(inner)
            }
            BsdfKind::OpacityTexture {
                texture,
                channel,
                factor,
                cutoff,
                inner,
            } => {
                if OpacityTex::of(inner)?.is_some() {
                    return Err(BuildError {
                        loc: desc.loc.clone(),
                        message: "nested opacity textures are not supported (not yet implemented)"
                            .into(),
                    });
                }
                let bitmap = scalar_bitmap(texture, *channel).map_err(|m| BuildError {
                    loc: desc.loc.clone(),
                    message: m,
                })?;
                Ok(Some(OpacityTex {
                    tex: UvBitmap::new(bitmap, texture.transform),
                    factor: *factor,
                    cutoff: *cutoff,
                }))
            }
            _ => Ok(None),
        }
    }

    /// Opacity in [0, 1] at texture coordinates `uv`.
    #[inline]
    fn opacity(&self, uv: Vec2) -> f32 {
        let a = self.factor * self.tex.eval(uv)[0];
        match self.cutoff {
            Some(c) => {
                if a >= c {
                    1.0
                } else {
                    0.0
                }
            }
            None => a.clamp(0.0, 1.0),
        }
    }
}

/// A film thickness texture (glTF `iridescenceThicknessTexture`).
struct FilmThicknessTex {
    tex: UvBitmap,
    /// Thickness at green 0 and 1, nm.
    min_nm: f32,
    max_nm: f32,
}

impl FilmThicknessTex {
    /// The film thickness texture of a material (through `Mask`, `TwoSided`, `NormalMap`).
    fn of(desc: &BsdfDesc) -> Result<Option<FilmThicknessTex>, BuildError> {
        match &desc.kind {
            BsdfKind::Mask { inner, .. }
            | BsdfKind::TwoSided { inner }
            | BsdfKind::NormalMap { inner, .. }
            | BsdfKind::OpacityTexture { inner, .. } => FilmThicknessTex::of(inner),
            BsdfKind::Blend { first, second, .. } => {
                Ok(FilmThicknessTex::of(first)?.or(FilmThicknessTex::of(second)?))
            }
            BsdfKind::FilmThicknessTexture {
                texture,
                min_nm,
                max_nm,
                ..
            } => {
                if !(min_nm.is_finite() && max_nm.is_finite() && *min_nm >= 0.0 && *max_nm >= 0.0) {
                    return Err(BuildError { loc: desc.loc.clone(), message: format!("film thickness range must be finite and >= 0 nm, got {min_nm}..{max_nm}") });
                }
                let bitmap = crate::texture::Bitmap::from_source(
                    &texture.source,
                    texture.srgb,
                    texture.nearest,
                )
                .map_err(|m| BuildError {
                    loc: desc.loc.clone(),
                    message: m,
                })?;
                Ok(Some(FilmThicknessTex {
                    tex: UvBitmap::new(bitmap, texture.transform),
                    min_nm: *min_nm,
                    max_nm: *max_nm,
                }))
            }
            _ => Ok(None),
        }
    }

    /// Thickness at texture coordinates `uv`, nm: `min + (max - min) g` (glTF: mix(min, max, g)).
    #[inline]
    fn thickness(&self, uv: Vec2) -> f32 {
        let g = self.tex.eval(uv)[1];
        (self.min_nm + (self.max_nm - self.min_nm) * g).max(0.0)
    }
}

/// Adds a mesh's non-degenerate triangles to the BVH list; for an emissive mesh also returns its
/// light triangles and their areas.
#[allow(clippy::type_complexity)]
fn add_mesh(
    mesh: &TriangleMesh,
    shape: u32,
    emissive: bool,
    prims: &mut Vec<Primitive>,
    refs: &mut Vec<PrimRef>,
    stats: &mut SceneStats,
    loc: &SourceLoc,
) -> Result<Option<(Vec<LightTriangle>, Vec<f32>)>, BuildError> {
    let n = mesh.positions.len();
    let bad_len = |what: &str, len: usize| BuildError {
        loc: loc.clone(),
        message: format!("mesh has {len} {what} for {n} vertices"),
    };
    if let Some(ns) = &mesh.normals {
        if ns.len() != n {
            return Err(bad_len("normals", ns.len()));
        }
    }
    if let Some(uvs) = &mesh.uvs {
        if uvs.len() != n {
            return Err(bad_len("texture coordinates", uvs.len()));
        }
    }
    let mut tris = Vec::new();
    let mut areas = Vec::new();
    // The triangle that the previous one took in as the second half of its parallelogram.
    let mut merged_with_previous = None;
    for (k, idx) in mesh.indices.iter().enumerate() {
        if idx.iter().any(|&i| i as usize >= n) {
            return Err(BuildError {
                loc: loc.clone(),
                message: format!("triangle {k} has a vertex index out of range ({n} vertices)"),
            });
        }
        let p = idx.map(|i| mesh.positions[i as usize]);
        if !p.iter().all(|v| v.is_finite()) {
            return Err(BuildError {
                loc: loc.clone(),
                message: format!("triangle {k} has a non-finite vertex"),
            });
        }
        let cross = (p[1] - p[0]).cross(p[2] - p[0]);
        let area = 0.5 * cross.length();
        if !(area > 0.0) {
            stats.degenerate_triangles += 1;
            continue;
        }
        stats.triangles += 1;
        if merged_with_previous == Some(k) {
            // Already in the BVH as the second half of a parallelogram.
        } else if let Some(corner) = parallelogram_corner(mesh, k) {
            let r = PrimRef {
                shape,
                local: k as u32,
                corner: Some(corner),
            };
            prims.push(parallelogram_primitive(mesh, r));
            refs.push(r);
            stats.parallelograms += 1;
            merged_with_previous = Some(k + 1);
        } else {
            prims.push(triangle_primitive(p));
            refs.push(PrimRef::single(shape, k as u32));
        }
        if !emissive {
            continue;
        }
        let ng = cross.normalize();
        let nrm = match &mesh.normals {
            Some(ns) => idx.map(|i| {
                ns.get(i as usize)
                    .copied()
                    .and_then(Vec3::try_normalize)
                    .unwrap_or(ng)
            }),
            None => [ng; 3],
        };
        let uv = match &mesh.uvs {
            Some(uvs) => idx.map(|i| uvs.get(i as usize).copied().unwrap_or(Vec2::ZERO)),
            None => [Vec2::ZERO, Vec2::X, Vec2::Y],
        };
        tris.push(LightTriangle { p, n: nrm, uv });
        areas.push(area);
    }
    Ok((!tris.is_empty()).then_some((tris, areas)))
}

/// The BVH primitive of a triangle with vertices `p`.
fn triangle_primitive(p: [Vec3; 3]) -> Primitive {
    Primitive::Triangle {
        v0: Vec3A::from(p[0]),
        e1: Vec3A::from(p[1] - p[0]),
        e2: Vec3A::from(p[2] - p[0]),
    }
}

/// The light shape and area of an emissive mesh of two triangles that went into the BVH as the
/// parallelogram `prim` (source `r`): sampled as one parallelogram. `None` when `prim` is not a
/// parallelogram, or the mesh has no texture coordinates (its triangles then keep the default
/// per-triangle uvs a textured emitter would see).
fn parallelogram_light(
    mesh: &TriangleMesh,
    prim: Primitive,
    r: PrimRef,
) -> Option<(LightShape, f32)> {
    let Primitive::Parallelogram { v0, e1, e2 } = prim else {
        return None;
    };
    let uvs = mesh.uvs.as_ref()?;
    let corners = r.vertices(&mesh.indices);
    let [a, b, c] = corners.map(|i| uvs[i as usize]);
    let cross = Vec3::from(e1.cross(e2));
    let n = match &mesh.normals {
        // Equal at all four corners (a condition of the merge).
        Some(ns) => ns[corners[0] as usize].normalize(),
        None => cross.normalize(),
    };
    Some((
        LightShape::Parallelogram {
            v0: v0.into(),
            e1: e1.into(),
            e2: e2.into(),
            n,
            uv: [a, b - a, c - a],
        },
        cross.length(),
    ))
}

/// The parallelogram whose corner and edges are the vertices of triangle `r.local` of `mesh`,
/// rotated by `r.corner` (see [`parallelogram_corner`]).
fn parallelogram_primitive(mesh: &TriangleMesh, r: PrimRef) -> Primitive {
    let [v0, v1, v2] = r
        .vertices(&mesh.indices)
        .map(|i| mesh.positions[i as usize]);
    Primitive::Parallelogram {
        v0: Vec3A::from(v0),
        e1: Vec3A::from(v1 - v0),
        e2: Vec3A::from(v2 - v0),
    }
}

/// Whether mesh triangles `k` and `k + 1` together form a parallelogram that can be tested as
/// one primitive, and if so which vertex of triangle `k` is its corner (the vertex that
/// triangle `k + 1` lacks). They must share exactly two vertex indices (the diagonal), be
/// wound the same way, and their four corners `x` (triangle k's own), `y` (triangle k+1's
/// own) and the diagonal's `s1`, `s2` must satisfy `x + y = s1 + s2` (the diagonals bisect
/// each other) to within float rounding of the vertex positions (16 ULPs of the largest
/// coordinate: transformed rectangles and cube faces miss it by a few), and so must their
/// texture coordinates, which are then one affine map over the whole parallelogram. Vertex
/// normals and tangents, where present, must be the same at all four corners (flat faces).
/// Both triangles are known to be valid (indices in range, finite); `k + 1`'s area is checked
/// here.
fn parallelogram_corner(mesh: &TriangleMesh, k: usize) -> Option<u8> {
    let (a, b) = (mesh.indices[k], *mesh.indices.get(k + 1)?);
    let n = mesh.positions.len();
    if b.iter().any(|&i| i as usize >= n) {
        return None;
    }
    let shared = |i: u32| b.contains(&i);
    if a.iter().filter(|&&i| shared(i)).count() != 2 || a[0] == a[1] || a[1] == a[2] || a[0] == a[2]
    {
        return None;
    }
    let c = a.iter().position(|&i| !shared(i))?;
    let [x, s1, s2] = rotate(a, c as u8);
    let y = *b.iter().find(|&&i| !a.contains(&i))?;
    // Consistent winding: triangle k+1 runs along the diagonal from s2 to s1.
    let at = |i: u32| b.iter().position(|&j| j == i).unwrap_or(0);
    if (at(s2) + 1) % 3 != at(s1) {
        return None;
    }
    let p = |i: u32| mesh.positions[i as usize];
    let corners = [p(x), p(y), p(s1), p(s2)];
    if !corners.iter().all(|v| v.is_finite())
        || (p(s1) - p(y)).cross(p(s2) - p(y)).length_squared() <= 0.0
    {
        return None;
    }
    let scale = corners
        .iter()
        .map(|v| v.abs().max_element())
        .fold(0.0f32, f32::max);
    if (p(x) + p(y) - p(s1) - p(s2)).abs().max_element() > 16.0 * f32::EPSILON * scale {
        return None;
    }
    if let Some(uv) = &mesh.uvs {
        let t = |i: u32| uv[i as usize];
        let uv_scale = [t(x), t(y), t(s1), t(s2)]
            .iter()
            .map(|v| v.abs().max_element())
            .fold(1.0f32, f32::max);
        if !((t(x) + t(y) - t(s1) - t(s2)).abs().max_element() <= 16.0 * f32::EPSILON * uv_scale) {
            return None;
        }
    }
    let same = |v: [pt_math::Vec4; 4]| v.iter().all(|&u| u == v[0]);
    if let Some(ns) = &mesh.normals {
        if !same([x, y, s1, s2].map(|i| ns[i as usize].extend(0.0))) {
            return None;
        }
    }
    if let Some(ts) = &mesh.tangents {
        if ts.len() != n || !same([x, y, s1, s2].map(|i| ts[i as usize])) {
            return None;
        }
    }
    Some(c as u8)
}

/// The BVH primitive `r` refers to, made from the description as the shape loop made it.
fn primitive_of(desc: &SceneDesc, r: PrimRef) -> Primitive {
    match &desc.shapes[r.shape as usize].geometry {
        Geometry::Mesh(m) if r.corner.is_some() => parallelogram_primitive(m, r),
        Geometry::Mesh(m) => {
            triangle_primitive(m.indices[r.local as usize].map(|i| m.positions[i as usize]))
        }
        &Geometry::Sphere {
            center,
            radius,
            flip_normals,
        } => Primitive::Sphere {
            center: center.into(),
            radius,
            flip: flip_normals,
        },
    }
}

/// Bounding sphere (centre, radius) of all primitives; a unit sphere at the origin if empty.
fn bounding_sphere(prims: &[Primitive]) -> (Vec3, f32) {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for p in prims {
        let b = p.aabb();
        lo = lo.min(b.min.into());
        hi = hi.max(b.max.into());
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return (Vec3::ZERO, 1.0);
    }
    let c = 0.5 * (lo + hi);
    (c, (0.5 * (hi - lo).length()).max(1e-6))
}

/// The RGB image and the spectral-mode form of an area emitter's radiance texture. RGB mode: the
/// image as loaded, or with display primaries its colours through the display's matrix
/// ([`DisplayPrimaries::to_srgb_matrix`](crate::spectral_texture::DisplayPrimaries::to_srgb_matrix)).
/// Spectral mode: the image (kept for the power estimate) and its upsampled texels, or the
/// primaries driven by it; light `index` is then recorded in `primaries_lights`.
#[allow(clippy::type_complexity)]
fn emission_texture(
    texture: Option<std::sync::Arc<crate::texture::Bitmap>>,
    em: &pt_scene::AreaEmitterDesc,
    spectral: bool,
    index: usize,
    primaries_lights: &mut Vec<usize>,
) -> Result<
    (
        Option<std::sync::Arc<crate::texture::Bitmap>>,
        Option<std::sync::Arc<crate::spectral_texture::SpectralEmission>>,
    ),
    BuildError,
> {
    use crate::spectral_texture::{DisplayPrimaries, SpectralBitmap, SpectralEmission};
    use std::sync::Arc;
    let Some(image) = texture else {
        return Ok((None, None));
    };
    let display = match &em.primaries {
        Some(p) => {
            let spectra = [0, 1, 2].map(|i| to_spectrum(&p[i], Role::Unbounded));
            Some(DisplayPrimaries::new(spectra).map_err(|m| BuildError {
                loc: em.loc.clone(),
                message: format!("display primaries: {m}"),
            })?)
        }
        None => None,
    };
    Ok(match (display, spectral) {
        (None, false) => (Some(image), None),
        (None, true) => {
            let up = SpectralBitmap::new(&image);
            (Some(image), Some(Arc::new(SpectralEmission::Upsampled(up))))
        }
        (Some(d), spectral) => {
            // The colours the display shows, in linear sRGB: exact for the film by linearity;
            // saturated primaries give components below 0 (outside the sRGB gamut), kept so.
            // Their luminance (Y >= 0) is also the power estimate in spectral mode.
            let m = d.to_srgb_matrix();
            let shown = Arc::new(image.map_texels(|t| {
                std::array::from_fn(|r| m[r][0] * t[0] + m[r][1] * t[1] + m[r][2] * t[2])
            }));
            if !spectral {
                return Ok((Some(shown), None));
            }
            primaries_lights.push(index);
            (
                Some(shown),
                Some(Arc::new(SpectralEmission::Primaries { image, display: d })),
            )
        }
    })
}

/// A light that is not attached to a shape.
fn build_light(
    l: &LightDesc,
    spectrum: &mut dyn FnMut(&SpectrumDesc) -> SampledSpectrum,
) -> Result<Light, BuildError> {
    let err = |m: String| BuildError {
        loc: l.loc.clone(),
        message: m,
    };
    Ok(match &l.kind {
        LightKind::Point {
            position,
            intensity,
        } => Light::Point {
            position: *position,
            intensity: spectrum(intensity),
        },
        LightKind::Spot {
            to_world,
            intensity,
            cutoff_deg,
            beam_width_deg,
        } => {
            let axis = to_world
                .transform_vector3(Vec3::Z)
                .try_normalize()
                .ok_or_else(|| err("spot to_world has no direction".into()))?;
            let cutoff = cutoff_deg.to_radians();
            Light::Spot {
                position: to_world.transform_point3(Vec3::ZERO),
                frame: Frame::from_normal(axis),
                intensity: spectrum(intensity),
                cone: SpotCone {
                    cos_cutoff: cutoff.cos(),
                    cutoff,
                    beam_width: beam_width_deg.to_radians(),
                },
            }
        }
        LightKind::Directional {
            direction,
            irradiance,
        } => Light::Directional {
            to_light: -*direction,
            irradiance: spectrum(irradiance),
        },
        LightKind::Sun {
            direction,
            irradiance,
            angular_diameter_deg,
        } => {
            let alpha = 0.5 * angular_diameter_deg.to_radians();
            let half = (0.5 * alpha).sin();
            let one_minus_cos = 2.0 * half * half; // 1 - cos(alpha) without cancellation
            let sin2 = one_minus_cos * (2.0 - one_minus_cos);
            Light::Sun {
                frame: Frame::from_normal(-*direction),
                radiance: spectrum(irradiance) * (1.0 / (std::f32::consts::PI * sin2)),
                one_minus_cos,
            }
        }
        LightKind::Constant { radiance } => Light::Constant {
            radiance: spectrum(radiance),
        },
        LightKind::EnvMap {
            filename,
            to_world,
            scale,
        } => {
            let (img, _) =
                pt_image::read_exr(filename).map_err(|e| err(format!("environment map: {e}")))?;
            if img
                .data
                .iter()
                .any(|p| p.iter().any(|c| !c.is_finite() || *c < 0.0))
            {
                return Err(err(format!(
                    "environment map '{}' has negative or non-finite pixels",
                    filename.display()
                )));
            }
            let texels = img.data.iter().map(|p| p.map(|c| c * scale)).collect();
            // Spectral mode: registers the light's emission spectrum, D65 of luminance 1, which
            // multiplies the upsampled texels (Mitsuba 3's envmap); RGB mode: white, unused.
            let _ = spectrum(&SpectrumDesc::Constant(1.0));
            let rot = Mat3::from_mat4(*to_world);
            EnvMap::new(img.width as usize, img.height as usize, texels, rot)
                .map(Light::EnvMap)
                .ok_or_else(|| err("empty environment map".into()))?
        }
    })
}
