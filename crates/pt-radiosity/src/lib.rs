//! Radiosity: diffuse global illumination by the finite-element method, the second
//! global-illumination method of `pt` beside path tracing.
//!
//! # Method
//! The scene's surfaces are cut into small flat patches ([`patches`]) on which radiosity
//! (W m^-2, power leaving per unit area) is assumed constant. For Lambertian surfaces the
//! rendering equation then becomes the linear system (Goral, Torrance, Greenberg & Battaile 1984,
//! "Modeling the interaction of light between diffuse surfaces"; Cohen & Wallace 1993,
//! *Radiosity and Realistic Image Synthesis*, ch. 2-3)
//!
//! `B_i = E_i + R_i sum_j F_ij B_j`
//!
//! with `E_i = pi Le` the emitted radiosity, `R_i` the diffuse albedo and `F_ij` the form factor:
//! the fraction of power leaving patch `i` that arrives at patch `j`. Form factors are estimated
//! by cosine-weighted hemisphere ray casting through the BVH ([`form_factor`]: unbiased, standard
//! error `sqrt(F (1 - F) / N)` with `N` rays per patch, Cohen & Wallace ch. 4), made reciprocal,
//! and the system is solved per RGB channel by Jacobi, Gauss-Seidel or progressive refinement
//! (Cohen, Chen, Wallace & Greenberg 1988, "A progressive refinement approach to fast radiosity
//! image generation"; Cohen & Wallace ch. 5) with a residual-based stopping rule ([`solve`]).
//! The solution is displayed from the scene camera ([`display`]) flat, vertex-smoothed
//! (Cohen & Wallace ch. 9) or by a final gather, into a [`pt_render::RenderOutput`] that the CLI
//! writes exactly like a path-traced image.
//!
//! # Assumptions and failure modes
//! - **Diffuse only.** Glossy, specular and transmissive materials cannot be represented: they are
//!   treated as diffuse (reflectance 0.5 when the model has no diffuse albedo) and a warning names
//!   the element ([`RadiosityStats::warnings`]). Radiance is view-independent.
//! - **Discretisation bias.** Radiosity is constant per patch: shadows and gradients are blurred
//!   to the patch size, and the error shrinks only as patches shrink (about linearly in the
//!   patch size for the image, see the Cornell test in `tests/`). Smoothing hides patch edges but
//!   not this bias; the final gather removes it on the visible surface (not at the gathered
//!   patches).
//! - **Light leaks.** A patch that crosses a contact (a box standing on the floor, a wall meeting
//!   another) averages light from both sides of the contact: bright seams under objects and
//!   dark seams at lit edges. Meshing does not split patches at contacts.
//! - **Form-factor noise.** With `N` rays a patch seeing a small light with form factor `F` has a
//!   relative error of about `1 / sqrt(N F)` in its direct light: blotches at large patch counts
//!   and few rays. Reciprocity averaging halves the variance where both sides are estimated.
//! - **One-sided surfaces.** As in the path tracer, the back of a one-sided material is black and
//!   emitters emit only from their front. Only area emitters are supported: point, spot,
//!   directional, sun, constant and environment lights are ignored with a warning.
//! - **Costs.** Form factors cost `N n` rays and `8 nnz` bytes, `nnz <= 2 N n` after
//!   symmetrisation; solving costs `O(nnz)` per iteration. Measured on the Cornell box with 1024
//!   rays (two shared cores): 11,372 patches, nnz 11.3 M, 91 MB, form factors 11.5 s, solve
//!   0.5 s. `rays_per_patch` trades time and memory (linear) against form-factor noise.
//!
//! # Parameters
//! | parameter | type | default | unit / meaning |
//! |---|---|---|---|
//! | `patch_size` | `Option<f32>` | `None`: 1/32 of the scene's bounding-box diagonal | longest patch edge, scene units |
//! | `rays_per_patch` | `u32` | 1024 | hemisphere rays per patch for the form factors |
//! | `reciprocity` | [`Reciprocity`] | `Balanced` | how `A_i F_ij = A_j F_ji` is enforced |
//! | `solver` | [`Solver`] | `GaussSeidel` | `Jacobi`, `GaussSeidel`, `Progressive` |
//! | `tolerance` | `f32` | 1e-4 | relative residual (fraction of emitted power) per channel |
//! | `max_iterations` | `u32` | 1000 | sweeps (progressive: sweeps of n shots) |
//! | `display` | [`Display`] | `Smoothed` | `Constant`, `Smoothed`, `FinalGather` |
//! | `spp` | `u32` | 16 | camera samples per pixel (film filter) |
//! | `seed` | `u64` | 0 | seed of every random stream |
//! | `max_patches` | `usize` | 2,000,000 | refuse patch sizes that would make more |
//!
//! ```
//! use pt_radiosity::{render, RadiosityParams};
//! let xml = r#"<scene version="3.0.0">
//!     <sensor type="perspective"><film type="hdrfilm">
//!         <integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
//!     <shape type="sphere"><boolean name="flip_normals" value="true"/>
//!         <float name="radius" value="10"/>
//!         <bsdf type="diffuse"><float name="reflectance" value="0.5"/></bsdf>
//!         <emitter type="area"><float name="radiance" value="1"/></emitter></shape>
//! </scene>"#;
//! let desc = pt_scene::load_str(xml, "<doc>".as_ref(), ".".as_ref(), &[])?;
//! let params = RadiosityParams { patch_size: Some(5.0), rays_per_patch: 256, ..Default::default() };
//! let (image, stats) = render(&desc, &params, &|_, _| {})?;
//! // Inside a closed emitting sphere every patch has B = E / (1 - R): radiance Le / (1 - R) = 2.
//! assert!(image.mean.iter().all(|p| (p[0] - 2.0).abs() < 2e-3));
//! assert!(stats.converged);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod display;
pub mod form_factor;
pub mod patches;
pub mod solve;
pub mod spectral;

pub use display::{Display, ImageSettings};
pub use form_factor::{FormFactors, Reciprocity};
pub use patches::{Patch, PatchMesh};
pub use solve::{Solution, Solver};

use pt_render::accel::{Accel, BvhKind};
use pt_render::camera::Camera;
use pt_render::geometry::Primitive;
use pt_render::RenderOutput;
use pt_scene::{SceneDesc, SourceLoc};
use std::time::{Duration, Instant};

/// Errors of the radiosity method: bad scene input (with the element's location) or bad
/// parameters.
#[derive(Debug, thiserror::Error)]
pub enum RadiosityError {
    /// A scene element the method cannot use.
    #[error("{loc}: {message}")]
    Scene {
        /// The offending element.
        loc: SourceLoc,
        /// What is wrong.
        message: String,
    },
    /// A parameter out of range.
    #[error("radiosity: {0}")]
    Params(String),
}

impl RadiosityError {
    pub(crate) fn scene(loc: &SourceLoc, message: impl Into<String>) -> Self {
        RadiosityError::Scene {
            loc: loc.clone(),
            message: message.into(),
        }
    }
}

/// Settings of the radiosity method (see the parameter table in the crate doc).
#[derive(Clone, Debug, PartialEq)]
pub struct RadiosityParams {
    /// Longest patch edge, scene units; `None`: 1/32 of the scene's bounding-box diagonal.
    pub patch_size: Option<f32>,
    /// Hemisphere rays per patch for the form factors (>= 1).
    pub rays_per_patch: u32,
    /// How reciprocity of the estimated form factors is enforced.
    pub reciprocity: Reciprocity,
    /// Which solver.
    pub solver: Solver,
    /// Relative residual per channel at which the solver stops (> 0).
    pub tolerance: f32,
    /// Iteration limit (progressive: sweeps of n shots).
    pub max_iterations: u32,
    /// How the solution is shown.
    pub display: Display,
    /// Camera samples per pixel (>= 1).
    pub spp: u32,
    /// Seed of every random stream (form-factor rays, camera and gather samples).
    pub seed: u64,
    /// Largest number of triangles the meshing may make.
    pub max_patches: usize,
}

impl Default for RadiosityParams {
    fn default() -> Self {
        RadiosityParams {
            patch_size: None,
            rays_per_patch: 1024,
            reciprocity: Reciprocity::Balanced,
            solver: Solver::GaussSeidel,
            tolerance: 1e-4,
            max_iterations: 1000,
            display: Display::Smoothed,
            spp: 16,
            seed: 0,
            max_patches: 2_000_000,
        }
    }
}

impl RadiosityParams {
    /// Checks the ranges of the parameters.
    pub fn validate(&self) -> Result<(), RadiosityError> {
        let bad = |m: String| Err(RadiosityError::Params(m));
        if let Some(h) = self.patch_size {
            if !(h.is_finite() && h > 0.0) {
                return bad(format!("patch_size must be positive and finite, got {h}"));
            }
        }
        if self.rays_per_patch == 0 {
            return bad("rays_per_patch must be at least 1".into());
        }
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return bad(format!(
                "tolerance must be positive, got {}",
                self.tolerance
            ));
        }
        if self.spp == 0 {
            return bad("spp must be at least 1".into());
        }
        Ok(())
    }
}

/// What a radiosity run did and cost.
#[derive(Clone, Debug, Default)]
pub struct RadiosityStats {
    /// Number of patches (front patches plus back patches of two-sided materials).
    pub patches: usize,
    /// Number of geometric triangles (BVH primitives).
    pub triangles: usize,
    /// The patch size used, scene units.
    pub patch_size: f32,
    /// Rays cast for form factors.
    pub form_factor_rays: u64,
    /// Stored form factors.
    pub nnz: usize,
    /// Area-weighted mean row sum of the form factors (1 for a closed scene).
    pub mean_row_sum: f32,
    /// Iterations of the reciprocity balancing (0 unless `Balanced`).
    pub balance_iterations: u32,
    /// Bytes of the form-factor matrix.
    pub form_factor_bytes: usize,
    /// Bytes of the form factors, patches and BVH primitives (BVH nodes not counted).
    pub memory_bytes: usize,
    /// Meshing and BVH build time.
    pub mesh_time: Duration,
    /// Form-factor time: ray casting plus reciprocity enforcement.
    pub form_factor_time: Duration,
    /// The part of `form_factor_time` spent enforcing reciprocity.
    pub reciprocity_time: Duration,
    /// Solver time.
    pub solve_time: Duration,
    /// Solver iterations.
    pub iterations: u32,
    /// Shots of progressive refinement.
    pub shots: u64,
    /// Final relative residual per channel.
    pub residual: [f32; 3],
    /// Stopping quantity after each iteration.
    pub residual_history: Vec<[f32; 3]>,
    /// Whether the solver reached the tolerance.
    pub converged: bool,
    /// Method failures to show the user (non-diffuse materials, dropped triangles).
    pub warnings: Vec<String>,
}

/// A solved radiosity system, ready to be displayed (possibly several times).
pub struct Simulation {
    /// The patches.
    pub mesh: PatchMesh,
    /// BVH over the patch triangles.
    pub accel: Accel,
    /// The form factors.
    pub form_factors: FormFactors,
    /// The solution.
    pub solution: Solution,
    /// Counts and timings.
    pub stats: RadiosityStats,
}

/// The BVH over a patch mesh's triangles (primitive `k` of the input is `mesh.triangles[k]`).
pub fn build_accel(mesh: &PatchMesh) -> Accel {
    let prims = mesh
        .triangles
        .iter()
        .map(|t| {
            let p = t.v.map(|v| mesh.vertices[v as usize]);
            Primitive::Triangle {
                v0: p[0].into(),
                e1: (p[1] - p[0]).into(),
                e2: (p[2] - p[0]).into(),
            }
        })
        .collect();
    Accel::build(prims, BvhKind::CwBvh)
}

/// Meshes the scene, estimates the form factors and solves the system. `progress(stage,
/// fraction)` is called from worker threads with the stage name (`"mesh"`, `"form factors"`,
/// `"solve"`) and its fraction done in [0, 1].
pub fn simulate(
    desc: &SceneDesc,
    params: &RadiosityParams,
    progress: &(dyn Fn(&str, f32) + Sync),
) -> Result<Simulation, RadiosityError> {
    params.validate()?;
    let t0 = Instant::now();
    let mesh = PatchMesh::build(desc, params.patch_size, params.max_patches)?;
    let accel = build_accel(&mesh);
    progress("mesh", 1.0);
    let mesh_time = t0.elapsed();

    let t1 = Instant::now();
    let area: Vec<f32> = mesh.patches.iter().map(|p| p.area).collect();
    let mut ff = FormFactors::estimate(&mesh, &accel, params.rays_per_patch, params.seed, &|f| {
        progress("form factors", f)
    });
    let raw_rows: f64 = (0..ff.len())
        .map(|i| area[i] as f64 * ff.hit_fraction[i] as f64)
        .sum();
    let t_rec = Instant::now();
    ff.enforce_reciprocity(&area, params.reciprocity);
    let reciprocity_time = t_rec.elapsed();
    let form_factor_time = t1.elapsed();

    let mut warnings = mesh.warnings.clone();
    if params.solver == Solver::Progressive && params.reciprocity == Reciprocity::None {
        warnings.push(
            "progressive refinement shoots with F_ji = A_i F_ij / A_j, which assumes reciprocal form factors: \
             with reciprocity = none it solves the system of the transposed estimates (use average or balanced)"
                .into(),
        );
    }
    let t2 = Instant::now();
    let max_iter = params.max_iterations;
    let solution = solve::solve(
        &mesh.patches,
        &ff,
        params.solver,
        params.tolerance,
        max_iter,
        &|it, _r| progress("solve", it as f32 / max_iter.max(1) as f32),
    );
    let solve_time = t2.elapsed();

    let total_area = mesh.total_area();
    let stats = RadiosityStats {
        patches: mesh.patches.len(),
        triangles: mesh.triangles.len(),
        patch_size: mesh.patch_size,
        form_factor_rays: mesh.patches.len() as u64 * params.rays_per_patch as u64,
        nnz: ff.nnz(),
        mean_row_sum: if total_area > 0.0 {
            (raw_rows / total_area) as f32
        } else {
            0.0
        },
        balance_iterations: ff.balance_iterations,
        form_factor_bytes: ff.memory_bytes(),
        memory_bytes: ff.memory_bytes()
            + mesh.memory_bytes()
            + accel.prims.capacity() * std::mem::size_of::<Primitive>()
            + accel.original_index.capacity() * 4,
        mesh_time,
        form_factor_time,
        reciprocity_time,
        solve_time,
        iterations: solution.iterations,
        shots: solution.shots,
        residual: solution.residual,
        residual_history: solution.history.clone(),
        converged: solution.converged,
        warnings,
    };
    Ok(Simulation {
        mesh,
        accel,
        form_factors: ff,
        solution,
        stats,
    })
}

impl Simulation {
    /// Renders the solution from the scene camera at the scene film's size and filter with
    /// `display`, `spp` samples per pixel and `seed`.
    pub fn render_image(
        &self,
        desc: &SceneDesc,
        display: Display,
        spp: u32,
        seed: u64,
        progress: &(dyn Fn(f32) + Sync),
    ) -> RenderOutput {
        let (w, h) = (desc.film.width, desc.film.height);
        let camera = Camera::for_film(&desc.camera, &desc.film);
        let settings = ImageSettings {
            width: w,
            height: h,
            filter: desc.film.filter,
            sample_border: desc.film.sample_border,
            spp: spp.max(1),
            seed,
        };
        let input = display::DisplayInput {
            mesh: &self.mesh,
            accel: &self.accel,
            radiosity: &self.solution.radiosity,
        };
        display::render_image(&input, &camera, &settings, display, progress)
    }
}

/// Renders a scene by radiosity: meshing, form factors, solve, display (the `pt render
/// --integrator radiosity` entry point). The image is linear RGB radiance at the scene film's
/// size, with the per-pixel variance of the camera sampling, so it can be written like a
/// path-traced image. `RenderOutput::time` is the whole run (meshing to display).
pub fn render(
    desc: &SceneDesc,
    params: &RadiosityParams,
    progress: &(dyn Fn(&str, f32) + Sync),
) -> Result<(RenderOutput, RadiosityStats), RadiosityError> {
    let start = Instant::now();
    if desc.film.width == 0 || desc.film.height == 0 {
        return Err(RadiosityError::Params(format!(
            "image size must be at least 1x1, got {}x{}",
            desc.film.width, desc.film.height
        )));
    }
    let sim = simulate(desc, params, progress)?;
    let mut out = if desc.spectral_reason().is_some() {
        // Wavelength-dependent inputs: solve per wavelength bin (see `spectral`).
        spectral::render(desc, params, &sim, progress)?
    } else {
        sim.render_image(desc, params.display, params.spp, params.seed, &|f| {
            progress("display", f)
        })
    };
    out.time = start.elapsed();
    Ok((out, sim.stats))
}
