//! Rendering: the BVH (obvhs), the renderable scene, area lights, the camera, the film and the
//! path-tracing integrator, scheduled over tiles with rayon.
//!
//! ```no_run
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let desc = pt_scene::load_file("scenes/cornell-box.xml".as_ref(), &[])?;
//! let scene = pt_render::Scene::build(&desc, Default::default(), Default::default())?;
//! let settings = pt_render::RenderSettings::from_desc(&desc);
//! let image = pt_render::render(&scene, &settings, &|_| {});
//! assert_eq!(image.mean.len(), (desc.film.width * desc.film.height) as usize);
//! # Ok(()) }
//! ```
#![warn(missing_docs)]
// One exception, allowed where it is: calling the render loop's x86-64-v3 variant after the
// processor was checked for those features (render.rs, `render_tile`).
#![deny(unsafe_code)]

pub mod accel;
pub mod camera;
pub mod film;
pub mod fluorescence;
pub mod geometry;
pub mod integrator;
pub mod light;
pub mod phosphorescence;
pub mod render;
pub mod sampler;
pub mod scene;
pub mod spectral_texture;
pub mod texture;

pub use accel::BvhKind;
pub use integrator::{PathSettings, Strategy};
pub use render::{render, render_passes, RenderOutput, RenderSettings, RenderState};
pub use scene::{BuildError, LightSelection, Scene};

impl RenderSettings {
    /// The settings a scene file asks for (film size, filter, spp, seed, integrator).
    pub fn from_desc(desc: &pt_scene::SceneDesc) -> Self {
        let i = &desc.integrator;
        let max_depth = match i.kind {
            // Radiosity scenes rendered by the path tracer (`--integrator path`) keep their depth.
            pt_scene::IntegratorKind::Path
            | pt_scene::IntegratorKind::VolPath
            | pt_scene::IntegratorKind::Radiosity => i.max_depth,
            pt_scene::IntegratorKind::Direct => 2,
        };
        RenderSettings {
            width: desc.film.width,
            height: desc.film.height,
            spp: desc.sampler.sample_count,
            seed: desc.sampler.seed,
            filter: desc.film.filter,
            path: PathSettings {
                max_depth,
                rr_depth: i.rr_depth,
                hide_emitters: i.hide_emitters,
                strategy: Strategy::Mis,
                media: i.kind == pt_scene::IntegratorKind::VolPath,
            },
            clamp: None,
        }
    }
}
