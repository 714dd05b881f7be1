//! Robust spawning of secondary rays.

use glam::Vec3;

/// Moves a surface point off its surface along the geometric normal `ng` so that a ray spawned
/// from the result does not hit the same surface again. The step scales with the point's
/// magnitude (a fixed number of float ULPs, applied to the integer representation) instead of a
/// fixed epsilon, so it works at any scene scale. Near the origin, where ULPs become tiny, a small
/// absolute step is used instead.
///
/// Method and constants: Wächter & Binder 2019, "A Fast and Robust Method for Avoiding
/// Self-Intersection", Ray Tracing Gems ch. 6, listing 6-1 (origin 1/32, float scale 1/65536,
/// int scale 256). Pass `ng` facing the side the new ray leaves towards.
#[inline]
pub fn offset_ray_origin(p: Vec3, ng: Vec3) -> Vec3 {
    const ORIGIN: f32 = 1.0 / 32.0;
    const FLOAT_SCALE: f32 = 1.0 / 65536.0;
    const INT_SCALE: f32 = 256.0;
    let comp = |p: f32, n: f32| -> f32 {
        if p.abs() < ORIGIN {
            p + FLOAT_SCALE * n
        } else {
            let of_i = (INT_SCALE * n) as i32;
            // Stepping the integer representation moves p by |of_i| ULPs, away from 0 when n has
            // the sign of p and towards 0 otherwise.
            let bits = p.to_bits() as i32;
            let moved = if p < 0.0 { bits.wrapping_sub(of_i) } else { bits.wrapping_add(of_i) };
            f32::from_bits(moved as u32)
        }
    };
    Vec3::new(comp(p.x, ng.x), comp(p.y, ng.y), comp(p.z, ng.z))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moves_to_the_normal_side_at_every_scale() {
        for scale in [1e-4f32, 1e-2, 1.0, 1e2, 1e5] {
            let p = Vec3::new(0.3, -0.7, 0.5) * scale;
            for n in [Vec3::X, -Vec3::Y, Vec3::new(0.6, 0.0, -0.8)] {
                let q = offset_ray_origin(p, n);
                assert!((q - p).dot(n) > 0.0, "scale {scale} n {n:?}");
                // Small relative to the scene scale.
                assert!((q - p).length() < 1e-3 * scale.max(1.0));
            }
        }
    }
}
