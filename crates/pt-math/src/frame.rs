//! Orthonormal frames: world <-> local shading frame (z = normal).

use glam::Vec3;

/// An orthonormal basis `(s, t, n)`. `to_local` maps world directions into the frame, in which
/// the normal `n` is +z; `to_world` maps back.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    /// First tangent.
    pub s: Vec3,
    /// Second tangent (`n x s`).
    pub t: Vec3,
    /// Normal (local +z).
    pub n: Vec3,
}

impl Frame {
    /// A frame around the unit normal `n`, with tangents from Duff et al. 2017, "Building an
    /// Orthonormal Basis, Revisited" (JCGT 6(1), listing 3): branch-free and continuous except
    /// at n.z = 0 sign flips, exact to rounding.
    #[inline(always)]
    pub fn from_normal(n: Vec3) -> Self {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        Frame {
            s: Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
            t: Vec3::new(b, sign + n.y * n.y * a, -n.y),
            n,
        }
    }

    /// A frame around the unit normal `n` whose first tangent follows `tangent` projected onto
    /// the tangent plane (Gram-Schmidt), as Mitsuba builds its shading frame from `dp_du`. Falls
    /// back to [`Frame::from_normal`] when `tangent` is zero or parallel to `n`.
    #[inline(always)]
    pub fn from_normal_tangent(n: Vec3, tangent: Vec3) -> Self {
        let along = tangent - n * n.dot(tangent);
        // glam's try_normalize: 1 / length, accepted when finite and positive (written as two
        // comparisons, false for NaN, so that lanes of this run in SIMD registers).
        let rcp = 1.0 / along.dot(along).sqrt();
        let s = along * rcp;
        let duff = Frame::from_normal(n);
        if (rcp > 0.0) & (rcp < f32::INFINITY) {
            Frame {
                s,
                t: n.cross(s),
                n,
            }
        } else {
            duff
        }
    }

    /// World direction -> local frame.
    #[inline(always)]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    /// Local direction -> world.
    #[inline(always)]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orthonormal_for_many_normals() {
        let normals = [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(0.0, -1.0, 1e-8).normalize(),
            Vec3::new(0.3, -0.5, 0.8).normalize(),
            Vec3::new(-0.3, 0.5, -0.8).normalize(),
        ];
        for n in normals {
            let f = Frame::from_normal(n);
            assert!((f.s.length() - 1.0).abs() < 1e-5);
            assert!((f.t.length() - 1.0).abs() < 1e-5);
            assert!(
                f.s.dot(f.t).abs() < 1e-5 && f.s.dot(n).abs() < 1e-5 && f.t.dot(n).abs() < 1e-5
            );
            // Right-handed: s x t = n.
            assert!((f.s.cross(f.t) - n).length() < 1e-5);
            let g = Frame::from_normal_tangent(n, Vec3::new(0.3, 0.9, -0.2));
            assert!((g.s.cross(g.t) - n).length() < 1e-5 && g.s.dot(n).abs() < 1e-5);
            let v = Vec3::new(0.2, -0.7, 0.4);
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-5);
            assert!((f.to_local(n) - Vec3::Z).length() < 1e-5);
        }
    }
}
