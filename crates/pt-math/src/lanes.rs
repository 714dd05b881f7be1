//! Several values at once, one per lane: arrays of `N` numbers on which every lane goes
//! through the same operations, written as loops over the lanes so that the compiler keeps
//! them in SIMD registers (eight lanes of AVX2 in the render loop's x86-64-v3 variant).
//!
//! The kernels of the shading step are written once over lanes (the shading frame here, the
//! ray offset, warps, Lambert's BSDF, parallelogram lights): the path tracer runs them for
//! all its paths in flight at once, and the single-value functions (`Frame::from_normal`,
//! `Lambert::sample`, ...) are the same kernels with one lane. Every lane performs the
//! single-value function's operations in the same order, so both give the same bits.

use glam::Vec3;

/// `[f(0), f(1), ..]` as a plain loop over the lanes (which the compiler vectorises reliably;
/// `std::array::from_fn` it sometimes leaves as a call).
#[inline(always)]
pub fn lanes<T: Copy + Default, const N: usize>(f: impl Fn(usize) -> T) -> [T; N] {
    let mut out = [T::default(); N];
    for (k, o) in out.iter_mut().enumerate() {
        *o = f(k);
    }
    out
}

/// A set of lanes as bits (bit `k`: lane `k`), for up to 32 lanes.
pub type Mask = u32;

/// The lanes in `mask`, in increasing order (skipping the others without testing each).
#[inline(always)]
pub fn set_lanes(mut mask: Mask) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (mask != 0).then(|| {
            let k = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            k
        })
    })
}

/// The lanes where `c` holds, as a mask.
#[inline(always)]
pub fn mask_of<const N: usize>(c: &[bool; N]) -> Mask {
    (0..N).fold(0, |m, k| m | (Mask::from(c[k]) << k))
}

/// The lanes `k` of `mask` for which `pred(k)` holds, as a mask (a plain loop, so that it is
/// inlined into the caller's compiled variant).
#[inline(always)]
pub fn lanes_where(mask: Mask, mut pred: impl FnMut(usize) -> bool) -> Mask {
    let mut out = 0;
    for k in set_lanes(mask) {
        out |= Mask::from(pred(k)) << k;
    }
    out
}

/// `N` 3-vectors, one per lane, stored by component (structure of arrays).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct V3<const N: usize> {
    /// x components.
    pub x: [f32; N],
    /// y components.
    pub y: [f32; N],
    /// z components.
    pub z: [f32; N],
}

impl<const N: usize> Default for V3<N> {
    fn default() -> Self {
        V3::splat(Vec3::ZERO)
    }
}

impl<const N: usize> V3<N> {
    /// The same vector in every lane.
    #[inline(always)]
    pub fn splat(v: Vec3) -> Self {
        V3 {
            x: [v.x; N],
            y: [v.y; N],
            z: [v.z; N],
        }
    }

    /// Lane `k`.
    #[inline(always)]
    pub fn get(&self, k: usize) -> Vec3 {
        Vec3::new(self.x[k], self.y[k], self.z[k])
    }

    /// Sets lane `k`.
    #[inline(always)]
    pub fn set(&mut self, k: usize, v: Vec3) {
        (self.x[k], self.y[k], self.z[k]) = (v.x, v.y, v.z);
    }

    /// `f(lane)` in every lane.
    #[inline(always)]
    pub fn from_fn(f: impl Fn(usize) -> Vec3) -> Self {
        let mut v = V3::default();
        for k in 0..N {
            v.set(k, f(k));
        }
        v
    }

    /// `-a`.
    #[inline(always)]
    pub fn neg(&self) -> Self {
        V3 {
            x: lanes(|k| -self.x[k]),
            y: lanes(|k| -self.y[k]),
            z: lanes(|k| -self.z[k]),
        }
    }

    /// `a` where `c[lane]`, else `b`.
    #[inline(always)]
    pub fn select(c: &[bool; N], a: &Self, b: &Self) -> Self {
        V3 {
            x: lanes(|k| if c[k] { a.x[k] } else { b.x[k] }),
            y: lanes(|k| if c[k] { a.y[k] } else { b.y[k] }),
            z: lanes(|k| if c[k] { a.z[k] } else { b.z[k] }),
        }
    }
}

/// Orthonormal frames `(s, t, n)`, one per lane (structure of arrays of [`crate::Frame`]).
///
/// Each operation is one loop over the lanes whose body is the whole single-frame function:
/// the compiler vectorises such a loop as one piece, and the single-frame function stays the
/// only implementation.
#[derive(Clone, Copy, Debug)]
pub struct Frames<const N: usize> {
    /// First tangents.
    pub s: V3<N>,
    /// Second tangents (`n x s`).
    pub t: V3<N>,
    /// Normals (local +z).
    pub n: V3<N>,
}

impl<const N: usize> Frames<N> {
    /// `f(lane)` in every lane.
    #[inline(always)]
    pub fn from_fn(f: impl Fn(usize) -> crate::Frame) -> Self {
        let mut out = Frames {
            s: V3::default(),
            t: V3::default(),
            n: V3::default(),
        };
        for k in 0..N {
            out.set(k, f(k));
        }
        out
    }

    /// World directions -> local frames.
    #[inline(always)]
    pub fn to_local(&self, v: &V3<N>) -> V3<N> {
        V3::from_fn(|k| self.get(k).to_local(v.get(k)))
    }

    /// Local directions -> world.
    #[inline(always)]
    pub fn to_world(&self, v: &V3<N>) -> V3<N> {
        V3::from_fn(|k| self.get(k).to_world(v.get(k)))
    }

    /// Lane `k`'s frame.
    #[inline(always)]
    pub fn get(&self, k: usize) -> crate::Frame {
        crate::Frame {
            s: self.s.get(k),
            t: self.t.get(k),
            n: self.n.get(k),
        }
    }

    /// Sets lane `k`'s frame.
    #[inline(always)]
    pub fn set(&mut self, k: usize, f: crate::Frame) {
        self.s.set(k, f.s);
        self.t.set(k, f.t);
        self.n.set(k, f.n);
    }
}

/// [`crate::offset_ray_origin`] in every lane: the points `p` moved off their surfaces along
/// the normals `n` (Wächter & Binder 2019).
#[inline(always)]
pub fn offset_ray_origins<const N: usize>(p: &V3<N>, n: &V3<N>) -> V3<N> {
    use crate::offset_coordinate as o;
    let mut out = V3::default();
    for k in 0..N {
        out.x[k] = o(p.x[k], n.x[k]);
        out.y[k] = o(p.y[k], n.y[k]);
        out.z[k] = o(p.z[k], n.z[k]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Frame;

    #[test]
    fn set_lanes_lists_the_set_bits_in_order() {
        assert_eq!(set_lanes(0).count(), 0);
        assert_eq!(set_lanes(0b1010_0101).collect::<Vec<_>>(), [0, 2, 5, 7]);
        assert_eq!(set_lanes(1 << 31).collect::<Vec<_>>(), [31]);
    }

    /// Frames in lanes hold and apply each lane's own frame, bit for bit (lane `k` is not
    /// mixed up with another, and the vectorised loops compute what the single frame does),
    /// for normals and tangents of every kind, including zero and parallel tangents (Duff's
    /// fallback).
    #[test]
    fn eight_lanes_match_one_lane_bit_for_bit() {
        let ns = [
            Vec3::Z,
            -Vec3::Z,
            Vec3::new(0.3, -0.5, 0.8).normalize(),
            Vec3::new(-0.3, 0.5, -0.8).normalize(),
            Vec3::X,
            Vec3::new(0.0, -1.0, 1e-8).normalize(),
            Vec3::new(0.6, 0.0, -0.8),
            Vec3::new(-0.48, 0.6, 0.64),
        ];
        let ts = [
            Vec3::ZERO,
            Vec3::new(0.3, 0.9, -0.2),
            Vec3::new(0.3, -0.5, 0.8),
            Vec3::X,
            Vec3::new(1e-30, 0.0, 0.0),
            Vec3::new(-2.0, 0.1, 0.3),
            Vec3::new(0.0, 4.0, 0.0),
            Vec3::new(f32::NAN, 0.0, 0.0),
        ];
        let f8 = Frames::<8>::from_fn(|k| Frame::from_normal_tangent(ns[k], ts[k]));
        let v = V3::<8>::from_fn(|k| Vec3::new(0.2 + k as f32, -0.7, 0.4));
        let (l8, w8) = (f8.to_local(&v), f8.to_world(&v));
        for k in 0..8 {
            let f1 = Frame::from_normal_tangent(ns[k], ts[k]);
            let bits = |v: Vec3| v.to_array().map(f32::to_bits);
            let g = f8.get(k);
            assert_eq!(
                [bits(g.s), bits(g.t), bits(g.n)],
                [bits(f1.s), bits(f1.t), bits(f1.n)],
                "lane {k}"
            );
            assert_eq!(bits(l8.get(k)), bits(f1.to_local(v.get(k))), "lane {k}");
            assert_eq!(bits(w8.get(k)), bits(f1.to_world(v.get(k))), "lane {k}");
        }
    }
}
