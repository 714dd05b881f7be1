//! The renderable scene: the BVH (obvhs), geometry, the camera and film, textures, the
//! material layer, lights and light selection, built once from the scene description and
//! shared by every integrator (crate `pt-integrators`).
//!
//! ```no_run
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let desc = pt_scene::load_file("scenes/cornell-box.xml".as_ref(), &[])?;
//! let scene = pt_render::Scene::build(&desc, Default::default(), Default::default())?;
//! let ray = scene.camera.generate_ray(pt_math::Vec2::new(128.0, 128.0), pt_math::Vec2::splat(0.5));
//! if let Some(hit) = scene.intersect(&ray) {
//!     let lambda = pt_spectrum::SampledWavelengths::sample_visible(0.5);
//!     let bsdf = scene.bsdf(&hit, &lambda);
//!     println!("{:?}", bsdf.bsdf);
//! }
//! # Ok(()) }
//! ```
#![warn(missing_docs)]
// `unsafe` only to call code compiled for the processor's wider instructions once they are
// detected (`isa`).
#![deny(unsafe_code)]

pub mod accel;
pub mod camera;
pub mod curve;
pub mod film;
pub mod fluorescence;
pub mod geometry;
pub mod isa;
pub mod light;
pub mod material;
pub mod medium;
pub mod sampler;
pub mod scene;
pub mod sdf;
pub mod texture;

pub use accel::BvhKind;
pub use film::RenderOutput;
#[cfg(target_arch = "x86_64")]
pub use isa::has_x86_64_v3;
pub use scene::{BuildError, LightSelection, Scene};
