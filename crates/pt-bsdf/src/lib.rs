//! BSDF models.
//!
//! Conventions, shared by every model (DESIGN.md):
//! - All directions are unit vectors in the **local shading frame**, z = shading normal.
//! - `wo` points towards the viewer (previous path vertex), `wi` towards the light (next vertex);
//!   both point away from the surface. (Mitsuba calls the viewer direction `si.wi`.)
//! - [`Bsdf::eval`] returns f(wo, wi) **without** the cosine factor.
//! - [`Bsdf::pdf`] is per unit **solid angle** of `wi`.
//! - [`Bsdf::sample`] returns `weight = f * |cos theta_i| / pdf`, and `eta`, the relative index
//!   along the sampled segment (1 for reflection).
//! - Delta lobes ([`Conductor`], [`Dielectric`], [`ThinDielectric`], [`ThinFilm`]) return eval = pdf = 0 and
//!   are reached only through `sample`, which sets `delta = true` and `pdf` = the discrete
//!   probability of the chosen lobe (not a density: never use it in MIS).
//! - Refraction carries radiance: transmitted values include the factor `1/eta^2` (pbrt-v4
//!   `TransportMode::Radiance`). Energy is conserved in the sense `R + T eta^2 (weight) = 1`.
//! - Transmissive models ([`Dielectric`], [`RoughDielectric`], [`ThinDielectric`], [`ThinFilm`]
//!   on a dielectric base) handle both
//!   sides themselves (`wo.z < 0` is inside); [`SurfaceBsdf`] never mirrors them, even if
//!   `two_sided` is set.
//!
//! Models are a closed set behind one enum, held by value at a hit (no allocation per hit).
//! Each model is in its own file, whose header gives the formula, the citation, the parameter
//! table and the Mitsuba XML it is read from.
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod blend;
pub mod conductor;
pub mod dielectric;
pub mod fresnel;
pub mod gltf_pbr;
pub mod hair;
pub mod lambert;
pub mod mask;
pub mod microfacet;
pub mod minnaert;
pub mod normal_map;
pub mod oren_nayar;
pub mod plastic;
pub mod polarizer;
pub mod pplastic;
pub mod principled;
pub mod principled_thin;
pub mod rough_dielectric;
pub mod rough_plastic;
pub mod rough_thin_film;
pub mod thin_dielectric;
pub mod thin_film;

pub use conductor::{Conductor, RoughConductor};
pub use dielectric::Dielectric;
pub use gltf_pbr::GltfPbr;
pub use hair::Hair;
pub use lambert::Lambert;
pub use microfacet::{Distribution, Microfacet};
pub use minnaert::Minnaert;
pub use oren_nayar::{OrenNayar, OrenNayarVariant};
pub use plastic::{fresnel_diffuse_reflectance, Plastic};
pub use polarizer::Polarizer;
pub use pplastic::PPlastic;
pub use principled::Principled;
pub use principled_thin::PrincipledThin;
use pt_math::lanes::V3;
use pt_math::{Vec2, Vec3, Vec4};
use pt_spectrum::SampledSpectrum;
pub use rough_dielectric::RoughDielectric;
pub use rough_plastic::{CoatingTable, RoughPlastic};
pub use rough_thin_film::RoughThinFilm;
pub use thin_dielectric::ThinDielectric;
pub use thin_film::{FilmBase, FilmColor, ThinFilm};

/// Applies `f` to each of the four lanes.
#[inline]
pub(crate) fn map_lanes(s: SampledSpectrum, f: impl Fn(f32) -> f32) -> SampledSpectrum {
    SampledSpectrum(Vec4::new(f(s.0.x), f(s.0.y), f(s.0.z), f(s.0.w)))
}

/// The result of sampling a BSDF.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    /// Sampled incident direction, local shading frame.
    pub wi: Vec3,
    /// `f(wo, wi) * |cos theta_i| / pdf`: the throughput multiplier.
    pub weight: SampledSpectrum,
    /// Solid-angle pdf of `wi` (for a delta lobe: the discrete probability of choosing it).
    pub pdf: f32,
    /// Whether `wi` came from a delta (specular) lobe: MIS must not weight it.
    pub delta: bool,
    /// Relative index of refraction along the sampled segment, eta_t / eta_i: the index of the
    /// side `wi` points into over the index of the side `wo` points into. 1 for reflection.
    /// Refraction already scales `weight` by 1 / eta^2 (radiance transport); an integrator
    /// that applies Russian roulette on throughput may multiply by `eta^2` for the decision only
    /// (pbrt-v4 `etaScale`).
    pub eta: f32,
}

/// BSDF samples of `N` lanes (structure of arrays of [`BsdfSample`]) from the models whose
/// lane kernels the path tracer runs: non-delta reflections (`delta` false, `eta` 1).
#[derive(Clone, Copy, Debug)]
pub struct SampleLanes<const N: usize> {
    /// Sampled directions, local shading frames.
    pub wi: V3<N>,
    /// Throughput multipliers f |cos theta_i| / pdf.
    pub weight: [SampledSpectrum; N],
    /// Solid-angle pdfs.
    pub pdf: [f32; N],
    /// Whether the lane has a sample (the others' values are meaningless).
    pub ok: [bool; N],
}

impl<const N: usize> SampleLanes<N> {
    /// Lane `k`'s sample (meaningful where `ok[k]`).
    #[inline(always)]
    pub fn get(&self, k: usize) -> BsdfSample {
        BsdfSample {
            wi: self.wi.get(k),
            weight: self.weight[k],
            pdf: self.pdf[k],
            delta: false,
            eta: 1.0,
        }
    }
}

impl BsdfSample {
    /// Whether the sample passes straight through the surface: a delta event with
    /// `wi = -wo` and no change of index (Mitsuba's *null* lobes: a `mask`'s holes, a thin
    /// dielectric's transmission; here also a thin film's). `wo` in the frame of `wi`; the
    /// tolerance absorbs the rounding of frame changes (normal maps, two-sided flips).
    #[inline]
    pub fn is_pass_through(&self, wo: Vec3) -> bool {
        self.delta && self.eta == 1.0 && (self.wi + wo).length_squared() < 1e-8
    }
}

/// A BSDF model (one-sided unless wrapped by [`SurfaceBsdf`] with `two_sided`).
#[derive(Clone, Copy, Debug)]
pub enum Bsdf {
    /// Lambertian diffuse reflection.
    Lambert(Lambert),
    /// Oren-Nayar rough diffuse reflection (four variants).
    OrenNayar(OrenNayar),
    /// Minnaert lunar-type reflection.
    Minnaert(Minnaert),
    /// Smooth conductor (delta).
    Conductor(Conductor),
    /// Rough microfacet conductor.
    RoughConductor(RoughConductor),
    /// Smooth dielectric interface (two delta lobes; handles both sides itself).
    Dielectric(Dielectric),
    /// Thin dielectric sheet (two delta lobes, symmetric).
    ThinDielectric(ThinDielectric),
    /// Rough dielectric interface (handles both sides itself).
    RoughDielectric(RoughDielectric),
    /// Smooth thin film on a conductor (one delta lobe) or dielectric base (two delta lobes,
    /// handles both sides itself).
    ThinFilm(ThinFilm),
    /// glTF 2.0 metallic-roughness (GGX specular over a coupled diffuse base, and metal).
    GltfPbr(GltfPbr),
    /// Smooth dielectric coating over a diffuse base (Mitsuba `plastic`; a delta lobe and a
    /// diffuse one).
    Plastic(Plastic),
    /// Rough dielectric coating over a diffuse base (Mitsuba `roughplastic`).
    RoughPlastic(RoughPlastic),
    /// Thin film on a rough conductor or dielectric base (handles both sides for a dielectric).
    RoughThinFilm(RoughThinFilm),
    /// Mitsuba's `principled` (Disney): diffuse, sheen, clearcoat, GGX specular and rough
    /// transmission (handles both sides when it transmits).
    Principled(Principled),
    /// Mitsuba's `pplastic` without polarization: rough reflection plus a refracted
    /// Lambertian base.
    PPlastic(PPlastic),
    /// Mitsuba's `polarizer` without polarization: half the light straight through.
    Polarizer(Polarizer),
    /// Mitsuba's `principledthin`: the thin-sheet principled BSDF (two-sided, light passes
    /// without bending).
    PrincipledThin(PrincipledThin),
    /// Mitsuba's `hair`: Chiang et al. 2016's fibre model (fibre along local y).
    Hair(Hair),
}

impl Bsdf {
    /// f(wo, wi) without the cosine, local frame.
    #[inline(always)]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        match self {
            Bsdf::Lambert(m) => m.eval(wo, wi),
            Bsdf::OrenNayar(m) => m.eval(wo, wi),
            Bsdf::Minnaert(m) => m.eval(wo, wi),
            Bsdf::Conductor(m) => m.eval(wo, wi),
            Bsdf::RoughConductor(m) => m.eval(wo, wi),
            Bsdf::Dielectric(m) => m.eval(wo, wi),
            Bsdf::ThinDielectric(m) => m.eval(wo, wi),
            Bsdf::RoughDielectric(m) => m.eval(wo, wi),
            Bsdf::ThinFilm(m) => m.eval(wo, wi),
            Bsdf::GltfPbr(m) => m.eval(wo, wi),
            Bsdf::Plastic(m) => m.eval(wo, wi),
            Bsdf::RoughPlastic(m) => m.eval(wo, wi),
            Bsdf::RoughThinFilm(m) => m.eval(wo, wi),
            Bsdf::Principled(m) => m.eval(wo, wi),
            Bsdf::PrincipledThin(m) => m.eval(wo, wi),
            Bsdf::Hair(m) => m.eval(wo, wi),
            Bsdf::PPlastic(m) => m.eval(wo, wi),
            Bsdf::Polarizer(m) => m.eval(wo, wi),
        }
    }

    /// [`Bsdf::eval`] and [`Bsdf::pdf`] of one pair of directions, sharing what the model can
    /// share (the rough conductor's and rough plastic's D and G1(wo), the hair model's setup
    /// and lobes); the same values as the two calls.
    #[inline(always)]
    pub fn eval_pdf(&self, wo: Vec3, wi: Vec3) -> (SampledSpectrum, f32) {
        match self {
            Bsdf::RoughConductor(m) => m.eval_pdf(wo, wi),
            Bsdf::RoughPlastic(m) => m.eval_pdf(wo, wi),
            Bsdf::Hair(m) => m.eval_pdf(wo, wi),
            _ => (self.eval(wo, wi), self.pdf(wo, wi)),
        }
    }

    /// [`Bsdf::eval_pdf`] of `wi` and [`Bsdf::sample`], both for `wo`, sharing what depends on
    /// `wo` alone where the model computes much of that (the hair model's setup); the same
    /// values as the two calls.
    #[inline(always)]
    pub fn eval_pdf_and_sample(
        &self,
        wo: Vec3,
        wi: Vec3,
        u_lobe: f32,
        u: Vec2,
    ) -> ((SampledSpectrum, f32), Option<BsdfSample>) {
        match self {
            Bsdf::Hair(m) => m.eval_pdf_and_sample(wo, wi, u_lobe, u),
            _ => (self.eval_pdf(wo, wi), self.sample(wo, u_lobe, u)),
        }
    }

    /// Solid-angle pdf of sampling `wi` given `wo`, local frame.
    #[inline(always)]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            Bsdf::Lambert(m) => m.pdf(wo, wi),
            Bsdf::OrenNayar(m) => m.pdf(wo, wi),
            Bsdf::Minnaert(m) => m.pdf(wo, wi),
            Bsdf::Conductor(m) => m.pdf(wo, wi),
            Bsdf::RoughConductor(m) => m.pdf(wo, wi),
            Bsdf::Dielectric(m) => m.pdf(wo, wi),
            Bsdf::ThinDielectric(m) => m.pdf(wo, wi),
            Bsdf::RoughDielectric(m) => m.pdf(wo, wi),
            Bsdf::ThinFilm(m) => m.pdf(wo, wi),
            Bsdf::GltfPbr(m) => m.pdf(wo, wi),
            Bsdf::Plastic(m) => m.pdf(wo, wi),
            Bsdf::RoughPlastic(m) => m.pdf(wo, wi),
            Bsdf::RoughThinFilm(m) => m.pdf(wo, wi),
            Bsdf::Principled(m) => m.pdf(wo, wi),
            Bsdf::PrincipledThin(m) => m.pdf(wo, wi),
            Bsdf::Hair(m) => m.pdf(wo, wi),
            Bsdf::PPlastic(m) => m.pdf(wo, wi),
            Bsdf::Polarizer(m) => m.pdf(wo, wi),
        }
    }

    /// Samples `wi` given `wo` from `u` in [0,1)^2 (and `u_lobe` in [0,1) for lobe choice).
    #[inline(always)]
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        match self {
            Bsdf::Lambert(m) => m.sample(wo, u),
            Bsdf::OrenNayar(m) => m.sample(wo, u),
            Bsdf::Minnaert(m) => m.sample(wo, u),
            Bsdf::Conductor(m) => m.sample(wo, u),
            Bsdf::RoughConductor(m) => m.sample(wo, u),
            Bsdf::Dielectric(m) => m.sample(wo, u_lobe, u),
            Bsdf::ThinDielectric(m) => m.sample(wo, u_lobe, u),
            Bsdf::RoughDielectric(m) => m.sample(wo, u_lobe, u),
            Bsdf::ThinFilm(m) => m.sample(wo, u_lobe, u),
            Bsdf::GltfPbr(m) => m.sample(wo, u_lobe, u),
            Bsdf::Plastic(m) => m.sample(wo, u_lobe, u),
            Bsdf::RoughPlastic(m) => m.sample(wo, u_lobe, u),
            Bsdf::RoughThinFilm(m) => m.sample(wo, u_lobe, u),
            Bsdf::Principled(m) => m.sample(wo, u_lobe, u),
            Bsdf::PrincipledThin(m) => m.sample(wo, u_lobe, u),
            Bsdf::Hair(m) => m.sample(wo, u_lobe, u),
            Bsdf::PPlastic(m) => m.sample(wo, u_lobe, u),
            Bsdf::Polarizer(m) => m.sample(wo, u),
        }
    }

    /// Whether the model transmits light (handles `wo` below the surface itself).
    #[inline(always)]
    pub fn is_transmissive(&self) -> bool {
        match self {
            Bsdf::Dielectric(_) | Bsdf::RoughDielectric(_) | Bsdf::ThinDielectric(_) => true,
            Bsdf::ThinFilm(m) => m.is_transmissive(),
            Bsdf::RoughThinFilm(m) => m.film.is_transmissive(),
            Bsdf::Principled(m) => m.transmissive,
            Bsdf::PrincipledThin(_) | Bsdf::Polarizer(_) | Bsdf::Hair(_) => true,
            _ => false,
        }
    }

    /// Whether the model has a non-delta component, so that light sampling can help.
    #[inline(always)]
    pub fn has_smooth_lobe(&self) -> bool {
        match self {
            Bsdf::Lambert(_)
            | Bsdf::OrenNayar(_)
            | Bsdf::Minnaert(_)
            | Bsdf::RoughConductor(_)
            | Bsdf::RoughDielectric(_)
            | Bsdf::GltfPbr(_)
            | Bsdf::Plastic(_)
            | Bsdf::RoughPlastic(_)
            | Bsdf::RoughThinFilm(_)
            | Bsdf::Principled(_)
            | Bsdf::PrincipledThin(_)
            | Bsdf::PPlastic(_)
            | Bsdf::Hair(_) => true,
            Bsdf::Conductor(_)
            | Bsdf::Dielectric(_)
            | Bsdf::ThinDielectric(_)
            | Bsdf::ThinFilm(_)
            | Bsdf::Polarizer(_) => false,
        }
    }
}

/// A BSDF as attached to a surface: the model, and whether it acts the same from both sides
/// (Mitsuba's `twosided`). A one-sided BSDF is black when `wo` is below the surface.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceBsdf {
    /// The reflectance model.
    pub bsdf: Bsdf,
    /// Mirror the model to the back side (ignored for transmissive models).
    pub two_sided: bool,
    /// Opacity in [0, 1] (Mitsuba `mask`, see [`mask`]): the fraction of light that meets the
    /// model; the rest passes straight through. 1 for ordinary surfaces.
    pub opacity: f32,
    /// Normal mapping (Mitsuba `normalmap`, see [`normal_map`]): the mapped normal expressed
    /// **in the local shading frame** (not necessarily unit length). `None`: the model sees the
    /// local frame unchanged.
    pub normal: Option<Vec3>,
    /// A second model mixed in (Mitsuba `blendbsdf`, see [`blend`]): `(w, model)` makes the
    /// surface `(1 - w) bsdf + w model`, both sharing `two_sided`, `opacity` and `normal`.
    pub blend: Option<(f32, Bsdf)>,
}

impl SurfaceBsdf {
    /// The surface's diffuse reflectance seen from `wo` (local frame), as Mitsuba's
    /// `eval_diffuse_reflectance` (what its `aov` integrator's `albedo` writes): the models
    /// with a diffuse base give its reflectance whatever the side (`diffuse`, `plastic`,
    /// `roughplastic`; `principled` and `principledthin` their base colour); the others
    /// pi f(wo, n) (Mitsuba's default: 0 for smooth models, the lobe's value towards the normal
    /// for rough ones). A mask gives its nested model's, a blend the blend of its two, a
    /// two-sided surface its model's seen from the front.
    pub fn diffuse_reflectance(&self, wo: Vec3) -> SampledSpectrum {
        let wo = if self.two_sided && wo.z < 0.0 {
            Vec3::new(wo.x, wo.y, -wo.z)
        } else {
            wo
        };
        let of = |b: &Bsdf| match b {
            Bsdf::Lambert(l) => l.reflectance,
            Bsdf::Plastic(p) => p.diffuse_reflectance,
            Bsdf::RoughPlastic(p) => p.diffuse_reflectance,
            Bsdf::Principled(p) => p.base_color,
            Bsdf::PrincipledThin(p) => p.base_color,
            _ => b.eval(wo, Vec3::Z) * std::f32::consts::PI,
        };
        match &self.blend {
            None => of(&self.bsdf),
            Some((w, second)) => of(&self.bsdf) * (1.0 - w) + of(second) * *w,
        }
    }

    /// An opaque surface with the given model.
    pub fn new(bsdf: Bsdf, two_sided: bool) -> Self {
        SurfaceBsdf {
            bsdf,
            two_sided,
            opacity: 1.0,
            normal: None,
            blend: None,
        }
    }

    /// Flips directions to the front side when two-sided and seen from the back (never for
    /// transmissive models, whose back side is their inside).
    #[inline(always)]
    fn side(&self, bsdf: &Bsdf, wo: Vec3) -> f32 {
        mirror_side(self.two_sided, bsdf.is_transmissive(), wo.z)
    }

    /// The model of a plain surface (no normal map, no blend, fully opaque) and whether it is
    /// two-sided: what the path tracer may shade with a model's lane kernels (the same
    /// arithmetic as [`SurfaceBsdf::eval`], `pdf` and `sample` of such a surface, whose
    /// opacity factors are 1); `None` for every other surface.
    #[inline(always)]
    pub fn plain_model(&self) -> Option<(&Bsdf, bool)> {
        (self.normal.is_none() && self.blend.is_none() && self.opacity == 1.0)
            .then_some((&self.bsdf, self.two_sided))
    }

    /// The albedo of a plain Lambertian surface ([`SurfaceBsdf::plain_model`]) and whether it
    /// is two-sided, which the path tracer shades for all its paths at once with
    /// [`Lambert`]'s lane kernels; `None` for every other surface.
    #[inline(always)]
    pub fn plain_lambert(&self) -> Option<(SampledSpectrum, bool)> {
        match self.plain_model() {
            Some((Bsdf::Lambert(l), two_sided)) => Some((l.reflectance, two_sided)),
            _ => None,
        }
    }

    /// One model's f(wo, wi) with sides and normal map applied, without the opacity.
    #[inline(always)]
    fn eval_of(&self, bsdf: &Bsdf, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        let s = self.side(bsdf, wo);
        let (wo, wi) = (flip_z(wo, s), flip_z(wi, s));
        match self.normal {
            None => bsdf.eval(wo, wi),
            Some(n) => match normal_map::perturb(n, wo, wi) {
                Some((f, pwo, pwi)) => {
                    bsdf.eval(pwo, pwi)
                        * (pwi.z.abs() * normal_map::shadowing(f.n, wi) / wi.z.abs())
                }
                None => SampledSpectrum::ZERO,
            },
        }
    }

    /// [`SurfaceBsdf::eval_of`] and [`SurfaceBsdf::pdf_of`] together (the normal map's
    /// frame built once).
    #[inline(always)]
    fn eval_pdf_of(&self, bsdf: &Bsdf, wo: Vec3, wi: Vec3) -> (SampledSpectrum, f32) {
        let s = self.side(bsdf, wo);
        let (wo, wi) = (flip_z(wo, s), flip_z(wi, s));
        match self.normal {
            None => bsdf.eval_pdf(wo, wi),
            Some(n) => match normal_map::perturb(n, wo, wi) {
                Some((f, pwo, pwi)) => {
                    let (value, pdf) = bsdf.eval_pdf(pwo, pwi);
                    (
                        value * (pwi.z.abs() * normal_map::shadowing(f.n, wi) / wi.z.abs()),
                        pdf,
                    )
                }
                None => (SampledSpectrum::ZERO, 0.0),
            },
        }
    }

    /// One model's pdf with sides and normal map applied, without the opacity.
    #[inline(always)]
    fn pdf_of(&self, bsdf: &Bsdf, wo: Vec3, wi: Vec3) -> f32 {
        let s = self.side(bsdf, wo);
        let (wo, wi) = (flip_z(wo, s), flip_z(wi, s));
        match self.normal {
            None => bsdf.pdf(wo, wi),
            Some(n) => {
                normal_map::perturb(n, wo, wi).map_or(0.0, |(_, pwo, pwi)| bsdf.pdf(pwo, pwi))
            }
        }
    }

    /// One model's sample with sides and normal map applied.
    #[inline(always)]
    fn sample_of(&self, bsdf: &Bsdf, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        let s = self.side(bsdf, wo);
        let mut bs = match self.normal {
            None => bsdf.sample(flip_z(wo, s), u_lobe, u)?,
            Some(n) => normal_map::sample(n, bsdf, flip_z(wo, s), u_lobe, u)?,
        };
        bs.wi = flip_z(bs.wi, s);
        Some(bs)
    }

    /// f(wo, wi) without the cosine, local frame. With a normal map: the model's value in the
    /// perturbed frame times |cos_perturbed(wi)| G(wi) / |cos(wi)| (see [`normal_map`]).
    #[inline(always)]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        match &self.blend {
            None => self.eval_of(&self.bsdf, wo, wi) * self.opacity,
            Some((w, b)) => {
                (self.eval_of(&self.bsdf, wo, wi) * (1.0 - w) + self.eval_of(b, wo, wi) * *w)
                    * self.opacity
            }
        }
    }

    /// The fraction of light that passes straight through the surface arriving along `-wo`
    /// (`wo` local frame, pointing away from the side the light arrives from): a mask's holes
    /// (1 - opacity) plus what the model lets through unbent, a thin dielectric's transmission
    /// (1 - R', its `specular_transmittance` included); 0 for every other model (Mitsuba's
    /// `eval_null_transmission`). Light sampling through media multiplies shadow rays by it.
    pub fn null_transmission(&self, wo: Vec3) -> SampledSpectrum {
        let model = |b: &Bsdf| match b {
            Bsdf::ThinDielectric(t) => t.specular_transmittance * (1.0 - t.reflectance(wo.z)),
            _ => SampledSpectrum::ZERO,
        };
        let through = match &self.blend {
            None => model(&self.bsdf),
            Some((w, b)) => model(&self.bsdf) * (1.0 - w) + model(b) * *w,
        };
        through * self.opacity + SampledSpectrum::splat(1.0 - self.opacity)
    }

    /// [`SurfaceBsdf::eval`] and [`SurfaceBsdf::pdf`] together: the same values, with what
    /// the model shares computed once (light sampling under MIS needs both).
    #[inline(always)]
    pub fn eval_pdf(&self, wo: Vec3, wi: Vec3) -> (SampledSpectrum, f32) {
        match &self.blend {
            None => {
                let (f, pdf) = self.eval_pdf_of(&self.bsdf, wo, wi);
                (f * self.opacity, pdf * self.opacity)
            }
            Some((w, b)) => {
                let (f1, p1) = self.eval_pdf_of(&self.bsdf, wo, wi);
                let (f2, p2) = self.eval_pdf_of(b, wo, wi);
                (
                    (f1 * (1.0 - w) + f2 * *w) * self.opacity,
                    ((1.0 - w) * p1 + w * p2) * self.opacity,
                )
            }
        }
    }

    /// [`SurfaceBsdf::eval_pdf`] of `wi` and [`SurfaceBsdf::sample`], both for `wo`: the same
    /// values as the two calls. A plain surface (no blend, no normal map, opaque) asks its
    /// model for both at once ([`Bsdf::eval_pdf_and_sample`]).
    #[inline(always)]
    pub fn eval_pdf_and_sample(
        &self,
        wo: Vec3,
        wi: Vec3,
        u_lobe: f32,
        u: Vec2,
    ) -> ((SampledSpectrum, f32), Option<BsdfSample>) {
        if self.blend.is_some() || self.normal.is_some() || self.opacity != 1.0 {
            return (self.eval_pdf(wo, wi), self.sample(wo, u_lobe, u));
        }
        // What `eval_pdf` and `sample` do for such a surface: sides mirrored, the opacity's
        // factors of 1 left out; its lobe choice picks the model (an opaque surface passes
        // nothing straight through, but the separate calls would handle it).
        let Ok(model_u) = mask::choose(self.opacity, wo, u_lobe) else {
            return (self.eval_pdf(wo, wi), self.sample(wo, u_lobe, u));
        };
        let s = self.side(&self.bsdf, wo);
        let (value_pdf, sample) =
            self.bsdf
                .eval_pdf_and_sample(flip_z(wo, s), flip_z(wi, s), model_u, u);
        let sample = sample.map(|mut bs| {
            bs.wi = flip_z(bs.wi, s);
            bs
        });
        (value_pdf, sample)
    }

    /// Solid-angle pdf of `wi`, local frame.
    #[inline(always)]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match &self.blend {
            None => self.pdf_of(&self.bsdf, wo, wi) * self.opacity,
            Some((w, b)) => {
                ((1.0 - w) * self.pdf_of(&self.bsdf, wo, wi) + w * self.pdf_of(b, wo, wi))
                    * self.opacity
            }
        }
    }

    /// Samples `wi`, local frame.
    #[inline(always)]
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        let u_lobe = match mask::choose(self.opacity, wo, u_lobe) {
            Ok(u_lobe) => u_lobe,
            Err(pass_through) => return Some(pass_through),
        };
        let mut bs = match &self.blend {
            None => self.sample_of(&self.bsdf, wo, u_lobe, u)?,
            Some((w, b)) => blend::sample(
                *w,
                u_lobe,
                |ul| self.sample_of(&self.bsdf, wo, ul, u),
                |ul| self.sample_of(b, wo, ul, u),
                |wi| {
                    let f =
                        self.eval_of(&self.bsdf, wo, wi) * (1.0 - w) + self.eval_of(b, wo, wi) * *w;
                    (
                        f,
                        (1.0 - w) * self.pdf_of(&self.bsdf, wo, wi) + w * self.pdf_of(b, wo, wi),
                    )
                },
            )?,
        };
        // The nested lobe was chosen with probability `opacity`; its weight is unchanged (the
        // opacity in f and in the pdf cancel).
        bs.pdf *= self.opacity;
        Some(bs)
    }

    /// Whether light sampling can help (a non-delta lobe exists).
    #[inline(always)]
    pub fn has_smooth_lobe(&self) -> bool {
        self.bsdf.has_smooth_lobe() || self.blend.is_some_and(|(_, b)| b.has_smooth_lobe())
    }
}

/// The side a two-sided surface is seen from: -1 (mirror the local frame's z) when it is
/// two-sided, seen from behind (`wo_z < 0`) and not transmissive (transmissive models handle
/// both sides themselves), else 1.
#[inline(always)]
pub fn mirror_side(two_sided: bool, transmissive: bool, wo_z: f32) -> f32 {
    if two_sided & (wo_z < 0.0) & !transmissive {
        -1.0
    } else {
        1.0
    }
}

#[inline(always)]
fn flip_z(v: Vec3, s: f32) -> Vec3 {
    Vec3::new(v.x, v.y, v.z * s)
}

// A BSDF value is copied at every hit (twice in a `SurfaceBsdf` with a blend): a new model
// must not make the enum larger unnoticed (112 bytes: `RoughThinFilm` and `Principled`).
const _: () = assert!(std::mem::size_of::<Bsdf>() <= 112);

/// Test support: that a model's `eval_pdf` gives exactly its `eval` and `pdf` (to the bit:
/// MIS weights computed from either must agree) over `n` random pairs of directions, in every
/// quadrant, grazing and below the surface.
#[cfg(test)]
pub(crate) fn check_eval_pdf(
    seed: u64,
    n: usize,
    eval_pdf: impl Fn(Vec3, Vec3) -> (SampledSpectrum, f32),
    eval: impl Fn(Vec3, Vec3) -> SampledSpectrum,
    pdf: impl Fn(Vec3, Vec3) -> f32,
) {
    // xorshift64: reproducible and dependency-free.
    let mut s = seed | 1;
    let mut rnd = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 40) as f32 / (1u64 << 24) as f32
    };
    for _ in 0..n {
        let mut dir = || Vec3::new(rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0, rnd() * 1.2 - 0.2);
        let (wo, wi) = (dir().normalize(), dir().normalize());
        let (f, p) = eval_pdf(wo, wi);
        assert_eq!(f.0, eval(wo, wi).0, "{wo} {wi}");
        assert_eq!(p.to_bits(), pdf(wo, wi).to_bits(), "{wo} {wi}");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `eval_pdf_and_sample` gives exactly what `eval_pdf` and `sample` give, for the hair
    /// model (which shares its setup between them) and for others, on plain surfaces (one or
    /// two sides) and on those that take the separate calls (half opaque, blended), over
    /// random directions on both sides and lobe numbers up to 1.
    #[test]
    fn eval_pdf_and_sample_is_both_calls() {
        let rgb = pt_math::Vec4::new(0.212_671, 0.715_160, 0.072_169, 0.0);
        let sigma_a = SampledSpectrum::from_rgb(Hair::pigment_sigma_a_rgb(1.3, 0.2));
        let hair = Bsdf::Hair(Hair::new(sigma_a, rgb, 1.55, 0.3, 0.3, 2.0));
        let gold = Bsdf::RoughConductor(RoughConductor::new(
            SampledSpectrum::from_rgb([0.2, 0.4, 1.4]),
            SampledSpectrum::from_rgb([3.6, 2.4, 1.8]),
            SampledSpectrum::splat(1.0),
            Microfacet::new(Distribution::Ggx, 0.2, 0.2),
        ));
        let mut surfaces = vec![
            SurfaceBsdf::new(hair, false),
            SurfaceBsdf::new(hair, true),
            SurfaceBsdf::new(gold, true),
        ];
        let mut masked = SurfaceBsdf::new(hair, false);
        masked.opacity = 0.5;
        surfaces.push(masked);
        let mut blended = SurfaceBsdf::new(gold, true);
        blended.blend = Some((0.3, hair));
        surfaces.push(blended);
        let mut s = 99u64;
        let mut rnd = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 40) as f32 / (1u64 << 24) as f32
        };
        for b in &surfaces {
            for _ in 0..3_000 {
                let mut dir = || Vec3::new(rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0);
                let (wo, wi) = (dir().normalize(), dir().normalize());
                let u_lobe = if rnd() < 0.1 { 1.0 } else { rnd() };
                let u = Vec2::new(rnd(), rnd());
                let (value_pdf, sample) = b.eval_pdf_and_sample(wo, wi, u_lobe, u);
                assert_eq!(
                    format!("{value_pdf:?}"),
                    format!("{:?}", b.eval_pdf(wo, wi))
                );
                assert_eq!(
                    format!("{sample:?}"),
                    format!("{:?}", b.sample(wo, u_lobe, u))
                );
            }
        }
    }

    #[test]
    fn one_sided_is_black_from_behind_two_sided_is_not() {
        let lam = Bsdf::Lambert(Lambert::new(SampledSpectrum::from_rgb([0.5; 3])));
        let wo = Vec3::new(0.0, 0.6, -0.8);
        let wi = Vec3::new(0.6, 0.0, -0.8);
        let one = SurfaceBsdf::new(lam, false);
        let two = SurfaceBsdf::new(lam, true);
        assert!(one.eval(wo, wi).is_black());
        assert!(one.sample(wo, 0.5, Vec2::splat(0.3)).is_none());
        assert!((two.eval(wo, wi).rgb()[0] - 0.5 / std::f32::consts::PI).abs() < 1e-6);
        let bs = two.sample(wo, 0.5, Vec2::new(0.3, 0.7)).unwrap();
        assert!(bs.wi.z < 0.0, "sampled on the viewer's side");
        assert!((two.pdf(wo, bs.wi) - bs.pdf).abs() < 1e-6);
    }

    #[test]
    fn two_sided_never_mirrors_a_dielectric() {
        // From inside glass, straight up through the interface: refraction must go out (+z)
        // with eta' = 1/1.5, whatever two_sided says.
        let glass = SurfaceBsdf::new(Bsdf::Dielectric(Dielectric::new(1.5)), true);
        let bs = glass.sample(-Vec3::Z, 0.99, Vec2::ZERO).unwrap();
        assert!(
            bs.wi.z > 0.99 && (bs.eta - 1.0 / 1.5).abs() < 1e-6,
            "{bs:?}"
        );
        assert!(
            (bs.weight.0.x - 2.25).abs() < 1e-5,
            "radiance gains eta^2 leaving glass"
        );
    }
}
