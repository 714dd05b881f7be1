//! The acceleration structure: one obvhs BVH over all primitives, kept unaware of materials.
//!
//! Both obvhs layouts are available: the compressed 8-wide CWBVH (Ylitie et al. 2017) and the
//! binary BVH2 built by PLOC. CWBVH is the default; `benches/traversal.rs` compares them.

use crate::geometry::Primitive;
use obvhs::bvh2::builder::build_bvh2;
use obvhs::bvh2::Bvh2;
use obvhs::cwbvh::builder::build_cwbvh;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::{Ray as BvhRay, RayHit};
use obvhs::BvhBuildParams;
use pt_math::{Ray, Vec3A};
use std::time::Duration;

/// Which BVH layout to build.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum BvhKind {
    /// Compressed wide BVH8 (default).
    #[default]
    CwBvh,
    /// Binary BVH.
    Bvh2,
}

enum Tree {
    Cw(CwBvh),
    Two(Bvh2),
    Empty,
}

/// A BVH over primitives stored in traversal order.
pub struct Accel {
    tree: Tree,
    /// Primitives reordered so that the BVH's primitive id indexes this directly.
    pub prims: Vec<Primitive>,
    /// For each entry of `prims`, its index in the order given to [`Accel::build`].
    pub original_index: Vec<u32>,
}

impl Accel {
    /// Builds the BVH. Primitives are reordered; `original_index` maps back.
    ///
    /// Memory: the builder reads the primitives' boxes directly (no array of boxes), and the
    /// primitives are permuted in place afterwards (no second copy).
    pub fn build(mut prims: Vec<Primitive>, kind: BvhKind) -> Self {
        if prims.is_empty() {
            return Accel { tree: Tree::Empty, prims, original_index: Vec::new() };
        }
        let params = BvhBuildParams::medium_build();
        let mut t = Duration::default();
        let (tree, order) = match kind {
            BvhKind::CwBvh => {
                let bvh = build_cwbvh(&prims, params, &mut t);
                let order = bvh.primitive_indices.clone();
                (Tree::Cw(bvh), order)
            }
            BvhKind::Bvh2 => {
                let bvh = build_bvh2(&prims, params, &mut t);
                let order = bvh.primitive_indices.clone();
                (Tree::Two(bvh), order)
            }
        };
        permute_in_place(&mut prims, &order);
        Accel { tree, prims, original_index: order }
    }

    /// Closest hit along the ray: `(index into prims, t)`.
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<(usize, f32)> {
        let r = BvhRay::new(Vec3A::from(ray.origin), Vec3A::from(ray.dir), ray.tmin, ray.tmax);
        let mut hit = RayHit::none();
        let prims = &self.prims;
        let f = |r: &BvhRay, id: usize| prims[id].intersect(r.origin, r.direction, r.tmin, r.tmax);
        let found = match &self.tree {
            Tree::Cw(b) => b.ray_traverse(r, &mut hit, f),
            Tree::Two(b) => b.ray_traverse(r, &mut hit, f),
            Tree::Empty => false,
        };
        found.then_some((hit.primitive_id as usize, hit.t))
    }

    /// Whether anything blocks the ray within `(tmin, tmax)` (any-hit traversal, stops at the
    /// first blocker).
    #[inline]
    pub fn occluded(&self, ray: &Ray) -> bool {
        let r = BvhRay::new(Vec3A::from(ray.origin), Vec3A::from(ray.dir), ray.tmin, ray.tmax);
        let prims = &self.prims;
        let f = |r: &BvhRay, id: usize| prims[id].intersect(r.origin, r.direction, r.tmin, r.tmax);
        match &self.tree {
            Tree::Cw(b) => !b.ray_traverse_miss(r, f),
            Tree::Two(b) => !b.ray_traverse_miss(r, f),
            Tree::Empty => false,
        }
    }
}

/// Reorders `v` so that `v[k]` becomes the old `v[order[k]]` (`order` a permutation), in place
/// by following cycles; one bit per element marks what is done.
fn permute_in_place<T: Copy>(v: &mut [T], order: &[u32]) {
    assert_eq!(v.len(), order.len());
    let mut done = vec![0u64; v.len().div_ceil(64)];
    for start in 0..v.len() {
        if done[start / 64] >> (start % 64) & 1 != 0 {
            continue;
        }
        // Walk the cycle start -> order[start] -> ..., pulling each element into place.
        let first = v[start];
        let mut k = start;
        loop {
            done[k / 64] |= 1 << (k % 64);
            let src = order[k] as usize;
            if src == start {
                v[k] = first;
                break;
            }
            v[k] = v[src];
            k = src;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pt_math::Vec3;

    fn grid(n: usize) -> Vec<Primitive> {
        // n x n unit quads (two triangles each) in the plane z = 0, plus a sphere above.
        let mut v = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let p = Vec3A::new(i as f32, j as f32, 0.0);
                v.push(Primitive::Triangle { v0: p, e1: Vec3A::X, e2: Vec3A::Y });
                v.push(Primitive::Triangle { v0: p + Vec3A::X + Vec3A::Y, e1: -Vec3A::X, e2: -Vec3A::Y });
            }
        }
        v.push(Primitive::Sphere { center: Vec3A::new(2.5, 2.5, 3.0), radius: 1.0, flip: false });
        v
    }

    #[test]
    fn permutes_in_place() {
        let order = [3u32, 0, 4, 1, 2, 6, 5, 7];
        let mut v: Vec<u32> = (10..18).collect();
        permute_in_place(&mut v, &order);
        assert_eq!(v, order.map(|i| 10 + i));
    }

    #[test]
    fn matches_brute_force() {
        let prims = grid(8);
        for kind in [BvhKind::CwBvh, BvhKind::Bvh2] {
            let accel = Accel::build(prims.clone(), kind);
            assert_eq!(accel.prims.len(), prims.len());
            let mut s = 12345u64;
            let mut rnd = || {
                s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                ((s >> 40) as f32) / (1u64 << 24) as f32
            };
            for _ in 0..2000 {
                let o = Vec3::new(rnd() * 10.0 - 1.0, rnd() * 10.0 - 1.0, 6.0);
                let d = Vec3::new(rnd() - 0.5, rnd() - 0.5, -1.0).normalize();
                let ray = Ray::new(o, d);
                let brute = prims
                    .iter()
                    .enumerate()
                    .map(|(i, p)| (i, p.intersect(o.into(), d.into(), 0.0, f32::INFINITY)))
                    .filter(|h| h.1.is_finite())
                    .min_by(|a, b| a.1.total_cmp(&b.1));
                let got = accel.intersect(&ray);
                match (brute, got) {
                    (None, None) => {}
                    (Some((_, tb)), Some((i, t))) => {
                        assert_eq!(t, tb);
                        let _ = accel.original_index[i];
                    }
                    other => panic!("{kind:?}: {other:?}"),
                }
                assert_eq!(accel.occluded(&ray), brute.is_some());
            }
        }
    }
}
