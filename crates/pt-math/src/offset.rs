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
///
/// One deviation from the listing: the number of ULPs, 256 x the normal's component, is rounded
/// to the nearest integer instead of truncated (one ULP more or less in a step of up to 256).
/// That lets the float adder do the conversion (adding 1.5 x 2^23 leaves the integer in the low
/// bits of the sum), so all three coordinates are computed together in one SIMD register,
/// where Rust's saturating float-to-integer cast was three scalar conversions with range checks
/// (3% of a Cornell box render's time).
#[inline(always)]
pub fn offset_ray_origin(p: Vec3, ng: Vec3) -> Vec3 {
    // Four lanes (the last one unused) so that the loop maps onto one SSE register.
    let (p, n) = ([p.x, p.y, p.z, 0.0], [ng.x, ng.y, ng.z, 0.0]);
    let mut out = [0.0f32; 4];
    for i in 0..4 {
        out[i] = offset_coordinate(p[i], n[i]);
    }
    Vec3::new(out[0], out[1], out[2])
}

/// One coordinate of [`offset_ray_origin`]: `p` moved along the normal's component `n`. Also
/// called lane by lane by code that offsets several points at once in SIMD lanes.
#[inline(always)]
pub fn offset_coordinate(p: f32, n: f32) -> f32 {
    // Both candidates, then a select: no branch per coordinate.
    let of_i =
        ((INT_SCALE * n + ROUND_MAGIC).to_bits() as i32).wrapping_sub(ROUND_MAGIC.to_bits() as i32);
    let bits = p.to_bits() as i32;
    // Outside the origin's box p is not zero, so its sign bit says p < 0: then step the
    // integer down (two's complement: (x ^ -1) - (-1) = -x), else up.
    let neg = bits >> 31;
    let stepped = f32::from_bits(bits.wrapping_add((of_i ^ neg).wrapping_sub(neg)) as u32);
    if p.abs() < ORIGIN {
        p + FLOAT_SCALE * n
    } else {
        stepped
    }
}

/// 1.5 x 2^23: a float of magnitude below 2^22 plus this is rounded to an integer, which sits in
/// the low mantissa bits of the sum (the sum's bits minus this constant's bits are the integer).
const ROUND_MAGIC: f32 = 12_582_912.0;

/// Origin within which the offset is a small absolute step instead of a number of ULPs.
const ORIGIN: f32 = 1.0 / 32.0;
/// Absolute step per unit of normal near the origin.
const FLOAT_SCALE: f32 = 1.0 / 65536.0;
/// ULPs per unit of normal elsewhere.
const INT_SCALE: f32 = 256.0;

/// [`offset_ray_origin`] written with a branch per coordinate, as in the paper's listing (but
/// rounding the ULP count, as the fast form does): the reference the branch-free form is tested
/// against.
#[cfg(test)]
fn offset_scalar(p: Vec3, ng: Vec3) -> Vec3 {
    let comp = |p: f32, n: f32| -> f32 {
        if p.abs() < ORIGIN {
            p + FLOAT_SCALE * n
        } else {
            let of_i = (INT_SCALE * n).round_ties_even() as i32;
            // Stepping the integer representation moves p by |of_i| ULPs, away from 0 when n has
            // the sign of p and towards 0 otherwise.
            let bits = p.to_bits() as i32;
            let moved = if p < 0.0 {
                bits.wrapping_sub(of_i)
            } else {
                bits.wrapping_add(of_i)
            };
            f32::from_bits(moved as u32)
        }
    };
    Vec3::new(comp(p.x, ng.x), comp(p.y, ng.y), comp(p.z, ng.z))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn branch_free_form_matches_the_listing() {
        // Points across scales and signs, including inside and at the edge of the origin's box
        // and zeros; normals in every direction.
        let mut s = 7u64;
        let mut rnd = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 40) as f32) / (1u64 << 24) as f32 * 2.0 - 1.0
        };
        for k in 0..100_000 {
            let scale = [0.0, 1e-3, 1.0 / 32.0, 0.5, 1.0, 1e3, 1e6][k % 7];
            let p = Vec3::new(rnd(), rnd(), rnd()) * scale;
            let n = Vec3::new(rnd(), rnd(), rnd()).normalize_or(Vec3::Z);
            let (a, b) = (offset_ray_origin(p, n), offset_scalar(p, n));
            assert_eq!(
                a.to_array().map(f32::to_bits),
                b.to_array().map(f32::to_bits),
                "p {p} n {n}"
            );
        }
        for p in [
            Vec3::splat(1.0 / 32.0),
            Vec3::splat(-1.0 / 32.0),
            Vec3::new(0.0, -0.0, 1.0),
        ] {
            for n in [Vec3::X, -Vec3::Y, Vec3::new(0.6, 0.0, -0.8)] {
                assert_eq!(offset_ray_origin(p, n), offset_scalar(p, n));
            }
        }
    }

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
