//! Spectral radiosity: the energy balance solved per wavelength bin, for scenes that need
//! spectral transport (tabulated spectra; see `SceneDesc::spectral_reason`).
//!
//! The form factors are geometric and shared by every wavelength. The visible range 360-830 nm
//! is cut into [`BINS`] equal bins; each patch's reflectance and emission are averaged over each
//! bin (inputs turned into spectra exactly as the path tracer's spectral mode does:
//! `pt_render::texture::spectrum_for_role`), the existing 3-channel solver and display run once per
//! group of three bins, and each pixel's bin radiances `L_b` are turned into colour as the
//! spectral film does: `XYZ = sum_b L_b int_bin cmf / int y-bar`, then linear sRGB. Piecewise-
//! constant spectra per bin are the method's spectral discretisation error (bins of 19.6 nm;
//! measured on scenes/cornell-spectral.xml: with 12 bins the walls were 1.8% off in red and
//! 1.2% in blue, with 24 bins 0.1-0.9%).

use crate::display::{self, DisplayInput, ImageSettings};
use crate::patches::PatchMesh;
use crate::{solve, RadiosityError, RadiosityParams, Simulation};
use pt_render::camera::Camera;
use pt_render::texture::Role;
use pt_render::RenderOutput;
use pt_scene::{BsdfKind, SceneDesc};
use pt_spectrum::{cie, xyz_to_srgb, Spectrum};

/// Number of wavelength bins over 360-830 nm (a multiple of 3: the solver has three channels).
pub const BINS: usize = 24;
const LO: f32 = 360.0;
const HI: f32 = 830.0;

fn bin_range(b: usize) -> (f32, f32) {
    let w = (HI - LO) / BINS as f32;
    (LO + w * b as f32, LO + w * (b + 1) as f32)
}

/// Mean of `s` over each bin (midpoint rule, 1 nm steps).
fn bin_means(s: &Spectrum) -> [f32; BINS] {
    std::array::from_fn(|b| {
        let (a, z) = bin_range(b);
        let n = (z - a).round().max(1.0) as usize;
        (0..n)
            .map(|i| s.eval(a + (i as f32 + 0.5) * (z - a) / n as f32))
            .sum::<f32>()
            / n as f32
    })
}

/// `int_bin cmf_k / int y-bar` for each bin and k = x, y, z: the film weights of a bin.
fn film_weights() -> [[f64; 3]; BINS] {
    std::array::from_fn(|b| {
        let (a, z) = bin_range(b);
        let n = ((z - a) * 4.0) as usize;
        let h = ((z - a) / n as f32) as f64;
        let mut acc = [0.0f64; 3];
        for i in 0..n {
            let c = cie::cmf(a + (i as f32 + 0.5) * h as f32);
            for k in 0..3 {
                acc[k] += c[k] as f64 * h;
            }
        }
        acc.map(|v| v / cie::CIE_Y_INTEGRAL as f64)
    })
}

/// The diffuse reflectance spectrum of a material as radiosity sees it (non-diffuse models are
/// grey 0.5, as in the RGB solve, which has already warned about them).
fn reflectance(kind: &BsdfKind) -> Spectrum {
    match kind {
        BsdfKind::Diffuse { reflectance } => match reflectance.as_constant() {
            Some(r) => pt_render::texture::spectrum_for_role(r, Role::Albedo),
            None => Spectrum::constant(0.5),
        },
        BsdfKind::TwoSided { inner } => reflectance(&inner.kind),
        _ => Spectrum::constant(0.5),
    }
}

/// Solves and displays `sim` (solved in RGB, which built the mesh and form factors) per
/// wavelength bin and returns the sRGB image. The variance is the conservative bound
/// `(sum_b |w_b| sd_b)^2` of the sum of correlated bin images (they share camera samples).
pub fn render(
    desc: &SceneDesc,
    params: &RadiosityParams,
    sim: &Simulation,
    progress: &(dyn Fn(&str, f32) + Sync),
) -> Result<RenderOutput, RadiosityError> {
    // Per shape: bin means of reflectance and of emitted radiosity (pi Le).
    let mut shape_bins: Vec<([f32; BINS], [f32; BINS])> = Vec::with_capacity(desc.shapes.len());
    for shape in &desc.shapes {
        let refl = desc
            .bsdfs
            .get(shape.bsdf)
            .map_or([0.0; BINS], |b| bin_means(&reflectance(&b.kind)));
        let emit = shape.emitter.as_ref().map_or([0.0; BINS], |e| {
            let s = e
                .radiance
                .as_constant()
                .map_or(Spectrum::constant(0.0), |r| {
                    pt_render::texture::spectrum_for_role(r, Role::Emission)
                });
            bin_means(&s).map(|v| v * std::f32::consts::PI)
        });
        shape_bins.push((refl, emit));
    }
    let weights = film_weights();
    let (w, h) = (desc.film.width, desc.film.height);
    let camera = Camera::for_film(&desc.camera, &desc.film);
    let settings = ImageSettings {
        width: w,
        height: h,
        filter: desc.film.filter,
        sample_border: desc.film.sample_border,
        spp: params.spp.max(1),
        seed: params.seed,
    };
    let npx = (w * h) as usize;
    let mut xyz = vec![[0.0f64; 3]; npx];
    let mut sd = vec![[0.0f64; 3]; npx];
    let mut time = std::time::Duration::ZERO;
    for group in 0..BINS / 3 {
        let mut mesh: PatchMesh = sim.mesh.clone();
        for p in &mut mesh.patches {
            let (refl, emit) = shape_bins
                .get(p.shape as usize)
                .copied()
                .unwrap_or(([0.0; BINS], [0.0; BINS]));
            // Patches the RGB solve made black (the back of one-sided surfaces) or not
            // emitting stay so.
            let reflects = p.reflectance.iter().any(|&r| r > 0.0);
            let emits = p.emission.iter().any(|&e| e > 0.0);
            p.reflectance =
                std::array::from_fn(|c| if reflects { refl[3 * group + c] } else { 0.0 });
            p.emission = std::array::from_fn(|c| if emits { emit[3 * group + c] } else { 0.0 });
        }
        let solution = solve::solve(
            &mesh.patches,
            &sim.form_factors,
            params.solver,
            params.tolerance,
            params.max_iterations,
            &|_, _| {},
        );
        let input = DisplayInput {
            mesh: &mesh,
            accel: &sim.accel,
            radiosity: &solution.radiosity,
        };
        let img = display::render_image(&input, &camera, &settings, params.display, &|f| {
            progress("display", (group as f32 + f) / (BINS / 3) as f32)
        });
        time += img.time;
        for i in 0..npx {
            for c in 0..3 {
                let wb = weights[3 * group + c];
                let (l, v) = (
                    img.mean[i][c] as f64,
                    (img.variance[i][c] as f64).max(0.0).sqrt(),
                );
                for k in 0..3 {
                    xyz[i][k] += l * wb[k];
                    sd[i][k] += v * wb[k].abs();
                }
            }
        }
    }
    let mean = xyz
        .iter()
        .map(|x| xyz_to_srgb([x[0] as f32, x[1] as f32, x[2] as f32]))
        .collect();
    // sRGB is a linear map of XYZ: bound each channel's sd by the absolute row sums.
    let variance = sd
        .iter()
        .map(|s| {
            let b = xyz_to_srgb([s[0] as f32, 0.0, 0.0]).map(f32::abs);
            let g = xyz_to_srgb([0.0, s[1] as f32, 0.0]).map(f32::abs);
            let z = xyz_to_srgb([0.0, 0.0, s[2] as f32]).map(f32::abs);
            std::array::from_fn(|c| (b[c] + g[c] + z[c]).powi(2))
        })
        .collect();
    Ok(RenderOutput {
        width: w,
        height: h,
        mean,
        variance,
        spp: settings.spp,
        time,
        nonfinite_samples: 0,
        alpha: None,
        second_moment: None,
    })
}
