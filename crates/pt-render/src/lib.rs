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
#![forbid(unsafe_code)]

pub mod accel;
pub mod camera;
pub mod curve;
pub mod film;
pub mod fluorescence;
pub mod geometry;
pub mod light;
pub mod material;
pub mod medium;
pub mod sampler;
pub mod scene;
pub mod sdf;
pub mod texture;

pub use accel::BvhKind;
pub use film::RenderOutput;
pub use scene::{BuildError, LightSelection, Scene};

/// Whether this processor has the x86-64-v3 features `render_tile_v3` is compiled for
/// (detected once by std and cached): the render loop and the traversal benchmarks run code
/// compiled for them when it has.
#[cfg(target_arch = "x86_64")]
#[inline]
pub fn has_x86_64_v3() -> bool {
    std::is_x86_feature_detected!("avx2")
        && std::is_x86_feature_detected!("fma")
        && std::is_x86_feature_detected!("bmi1")
        && std::is_x86_feature_detected!("bmi2")
        && std::is_x86_feature_detected!("lzcnt")
        && std::is_x86_feature_detected!("popcnt")
        && std::is_x86_feature_detected!("movbe")
}
