//! Maths shared by every crate: glam re-exports, the local shading [`Frame`], [`Ray`], the robust
//! ray-origin offset of Wächter & Binder (2019), square-to-domain warps with their pdfs, and a
//! 1D piecewise-constant distribution for discrete choices (light selection).
//!
//! Conventions (DESIGN.md): the local shading frame has z along the normal; directions point
//! away from the surface; pdfs of directions are per unit solid angle, of points per unit area.
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub use glam::{self, Mat3, Mat4, Vec2, Vec3, Vec3A, Vec4};

mod distribution;
pub mod fastmath;
mod frame;
pub mod lanes;
mod offset;
pub mod warp;

pub use distribution::{Distribution1D, Distribution2D};
pub use frame::Frame;
pub use offset::{offset_coordinate, offset_ray_origin};

/// A ray in world space: `origin + t * dir` for `t` in `[tmin, tmax]`. `dir` is unit length.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    /// Origin, world space.
    pub origin: Vec3,
    /// Unit direction, world space.
    pub dir: Vec3,
    /// Smallest accepted hit distance (scene units).
    pub tmin: f32,
    /// Largest accepted hit distance (scene units).
    pub tmax: f32,
}

impl Ray {
    /// A ray from `origin` along the unit direction `dir`, unbounded.
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Ray {
            origin,
            dir,
            tmin: 0.0,
            tmax: f32::INFINITY,
        }
    }

    /// The point at distance `t`.
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }
}

/// Veach's power heuristic with beta = 2 (Veach 1997, eq. 9.13) for two strategies with one
/// sample each: the weight of the strategy whose pdf is `a` when the other's is `b`.
/// Both pdfs must be in the same measure. Returns 0 when both are 0.
#[inline]
pub fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    // Branch-free: the quotient computed always and selected, with comparisons rather than
    // `is_finite` / `is_infinite` (the same for every input, NaN included), so that lanes of
    // this run in SIMD registers.
    let w = a2 / (a2 + b2);
    let fallback = if a.abs() == f32::INFINITY { 1.0 } else { 0.0 };
    if (a2 + b2 > 0.0) & (a2 < f32::INFINITY) {
        w
    } else {
        fallback
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn power_heuristic_limits() {
        assert_eq!(power_heuristic(1.0, 0.0), 1.0);
        assert_eq!(power_heuristic(0.0, 1.0), 0.0);
        assert_eq!(power_heuristic(0.0, 0.0), 0.0);
        assert!((power_heuristic(1.0, 1.0) - 0.5).abs() < 1e-7);
        assert!((power_heuristic(2.0, 1.0) + power_heuristic(1.0, 2.0) - 1.0).abs() < 1e-6);
        assert_eq!(power_heuristic(f32::INFINITY, 1.0), 1.0);
    }
}
