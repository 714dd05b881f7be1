//! Scenes without a tree: every primitive tested, eight at a time in SIMD lanes.

use super::*;

/// Whether `kind` asks for the flat "tree" for `prims`: forced, or automatic for at most
/// [`FLAT_MAX`] primitives of which at most [`FLAT_MAX_ANALYTIC`] are analytic.
pub(super) fn use_flat(kind: BvhKind, prims: &[Primitive]) -> bool {
    kind == BvhKind::Flat
        || (kind == BvhKind::Auto
            && prims.len() <= FLAT_MAX
            && prims.iter().filter(|p| p.is_analytic()).count() <= FLAT_MAX_ANALYTIC)
}

/// Most analytic primitives (spheres, cylinders, disks, curve segments) that
/// [`BvhKind::Auto`] tests without a tree. They are tested one by one, not eight at a time:
/// measured (whole renders, A/B), 4 spheres beside 4 parallelograms (`scenes/atlas/veach-mis.xml`)
/// render 4.5% faster without a tree, 24 cylinders (`scenes/hair-fibres.xml`) 11% faster with
/// one.
pub(super) const FLAT_MAX_ANALYTIC: usize = 8;

/// Primitives per [`Block`]: eight `f32` fill one AVX2 register.
pub(super) const LANES: usize = 8;

/// Up to [`LANES`] triangles and parallelograms in structure-of-arrays form (world space), for
/// a Möller-Trumbore test of all of them at once, written as loops over lanes that the
/// compiler vectorises. The lanes compute what [`crate::geometry::intersect_triangle`] and
/// [`crate::geometry::intersect_parallelogram`] compute, with the triple products regrouped
/// around a stored normal (one cross product per lane instead of two: 4% fewer instructions
/// for the Cornell box), so they agree to rounding. Unused lanes have zero edges: their
/// determinant is 0 and they never hit.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(32))]
pub(super) struct Block {
    /// First vertex (corner), x, y, z per lane.
    v0: [[f32; LANES]; 3],
    /// First edge.
    e1: [[f32; LANES]; 3],
    /// Second edge.
    e2: [[f32; LANES]; 3],
    /// `e1 x e2` (unnormalised geometric normal).
    n: [[f32; LANES]; 3],
    /// Weight of `b1` in the outer bound `k1 b1 + b2 <= 1`: 1 for a triangle (`b1 + b2 <= 1`),
    /// 0 for a parallelogram (`b2 <= 1`).
    k1: [f32; LANES],
}

/// The nearest hit per lane so far, over the blocks a closest-hit search has tested.
pub(super) struct LaneBest {
    /// Distance (the ray's `tmax` while nothing was hit in the lane).
    t: [f32; LANES],
    /// Edge coordinates of the hit (see [`AccelHit`]).
    b1: [f32; LANES],
    b2: [f32; LANES],
    /// Primitive index of the hit (`u32::MAX` while nothing was hit).
    id: [u32; LANES],
}

impl Block {
    /// The block of `prims` (at most [`LANES`], no analytic primitives).
    pub(super) fn new(prims: &[Primitive]) -> Block {
        let mut b = Block::default();
        for (i, p) in prims.iter().enumerate() {
            let (v0, e1, e2, k1) = match *p {
                Primitive::Triangle { v0, e1, e2 } => (v0, e1, e2, 1.0),
                Primitive::Parallelogram { v0, e1, e2 } => (v0, e1, e2, 0.0),
                _ => {
                    unreachable!("analytic primitives are kept out of blocks")
                }
            };
            let n = e1.cross(e2);
            for a in 0..3 {
                b.v0[a][i] = v0[a];
                b.e1[a][i] = e1[a];
                b.e2[a][i] = e2[a];
                b.n[a][i] = n[a];
            }
            b.k1[i] = k1;
        }
        b
    }

    /// Lane `i`'s Möller-Trumbore test (Möller & Trumbore 1997, one combined bounds test as in
    /// `geometry::moller_trumbore`): `(hit, t, b1, b2)` for a hit in `(ray.tmin, tmax)`.
    #[inline(always)]
    fn lane(&self, i: usize, ray: &Ray, tmax: f32) -> (bool, f32, f32, f32) {
        let (o, d) = (ray.origin, ray.dir);
        let e1 = [self.e1[0][i], self.e1[1][i], self.e1[2][i]];
        let e2 = [self.e2[0][i], self.e2[1][i], self.e2[2][i]];
        let cross = |a: [f32; 3], b: [f32; 3]| {
            [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ]
        };
        let dot = |a: [f32; 3], b: [f32; 3]| (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2];
        // Möller-Trumbore's scalar triple products regrouped around the stored normal
        // n = e1 x e2 and r = tvec x d (one cross product per lane instead of two):
        // det = e1 . (d x e2) = -d . n, b1 det = tvec . (d x e2) = e2 . r,
        // b2 det = d . (tvec x e1) = -e1 . r, t det = e2 . (tvec x e1) = tvec . n.
        let n = [self.n[0][i], self.n[1][i], self.n[2][i]];
        let tvec = [
            o.x - self.v0[0][i],
            o.y - self.v0[1][i],
            o.z - self.v0[2][i],
        ];
        let r = cross(tvec, [d.x, d.y, d.z]);
        let det = -dot([d.x, d.y, d.z], n);
        let inv_det = 1.0 / det;
        let b1 = dot(e2, r) * inv_det;
        let b2 = -dot(e1, r) * inv_det;
        let t = dot(tvec, n) * inv_det;
        // The bounds in four comparisons: b1, b2 >= 0 as min(b1, b2) >= 0; the outer bound
        // k1 b1 + b2 <= 1 (b1 + b2 for triangles, b2 for parallelograms) together with
        // b1 <= 1 as one max (for triangles b1 <= b1 + b2 already). A zero determinant needs no
        // test of its own: t is then infinite or NaN and fails `t > tmin & t < tmax` (a NaN in
        // b1 or b2, which min and max might pass on, only arises there).
        let min = |a: f32, b: f32| if a < b { a } else { b };
        let max = |a: f32, b: f32| if a > b { a } else { b };
        let hit = (min(b1, b2) >= 0.0)
            & (max(b1, self.k1[i] * b1 + b2) <= 1.0)
            & (t > ray.tmin)
            & (t < tmax);
        (hit, t, b1, b2)
    }

    /// Keeps in `best` each lane's hit that is nearer than the lane's best so far; `first_id`
    /// is the primitive index of lane 0. One loop over lanes, so that test and update are
    /// vectorised together (selects, no branch per lane).
    #[inline(always)]
    fn closest(&self, ray: &Ray, first_id: u32, best: &mut LaneBest) {
        for i in 0..LANES {
            let (hit, t, b1, b2) = self.lane(i, ray, best.t[i]);
            best.t[i] = if hit { t } else { best.t[i] };
            best.b1[i] = if hit { b1 } else { best.b1[i] };
            best.b2[i] = if hit { b2 } else { best.b2[i] };
            best.id[i] = if hit { first_id + i as u32 } else { best.id[i] };
        }
    }

    /// Whether some lane is hit in `(ray.tmin, ray.tmax)`.
    #[inline(always)]
    fn any_hit(&self, ray: &Ray) -> bool {
        // Lane results into an array first, then one reduction: written as `any |= hit` per
        // lane, the compiler tested the lanes one at a time in scalar code.
        let mut hits = [0u32; LANES];
        for (i, h) in hits.iter_mut().enumerate() {
            *h = u32::from(self.lane(i, ray, ray.tmax).0);
        }
        hits.iter().fold(0, |a, &h| a | h) != 0
    }
}

/// Closest hit among `blocks` (primitives `0..`, lane `i` of block `k` being `k * LANES + i`)
/// and `analytic` (primitives `analytic_from..`). Ties go to the lowest lane, then the earliest
/// block.
#[inline(always)]
pub(super) fn flat_closest(
    blocks: &[Block],
    analytic: &[Primitive],
    analytic_from: usize,
    ray: &Ray,
) -> Option<AccelHit> {
    let mut best = LaneBest {
        t: [ray.tmax; LANES],
        b1: [0.0; LANES],
        b2: [0.0; LANES],
        id: [u32::MAX; LANES],
    };
    for (k, b) in blocks.iter().enumerate() {
        b.closest(ray, (k * LANES) as u32, &mut best);
    }
    // The nearest lane without a branch per lane (which lane wins is unpredictable): a tree of
    // minima, then the lowest lane holding it. No NaN occurs (hits and tmax only).
    let min = |a: f32, b: f32| if a < b { a } else { b };
    let t = &best.t;
    let m4 = [
        min(t[0], t[4]),
        min(t[1], t[5]),
        min(t[2], t[6]),
        min(t[3], t[7]),
    ];
    let nearest = min(min(m4[0], m4[2]), min(m4[1], m4[3]));
    let mut at_nearest = 0u32;
    for (i, &ti) in t.iter().enumerate() {
        at_nearest |= u32::from(ti == nearest) << i;
    }
    let lane = at_nearest.trailing_zeros() as usize & (LANES - 1);
    let mut hit = AccelHit {
        index: best.id[lane] as usize,
        t: best.t[lane],
        b1: best.b1[lane],
        b2: best.b2[lane],
    };
    let (o, d) = (Vec3A::from(ray.origin), Vec3A::from(ray.dir));
    for (j, s) in analytic.iter().enumerate() {
        // With the coordinates the hit's surface interaction needs (a disk's object-space
        // point, a curve's parameter).
        let (t, b1, b2) = s.intersect_bary(o, d, ray.tmin, hit.t);
        if t < hit.t {
            hit = AccelHit {
                index: analytic_from + j,
                t,
                b1,
                b2,
            };
        }
    }
    (hit.t < ray.tmax).then_some(hit)
}

/// Whether any of `blocks` or `analytic` is hit in `(ray.tmin, ray.tmax)`. Plain loops: the
/// iterator adaptor `any` was not inlined, so the lane tests ran outside the x86-64-v3 loop.
#[inline(always)]
pub(super) fn flat_any(blocks: &[Block], analytic: &[Primitive], ray: &Ray) -> bool {
    for b in blocks {
        if b.any_hit(ray) {
            return true;
        }
    }
    let (o, d) = (Vec3A::from(ray.origin), Vec3A::from(ray.dir));
    for s in analytic {
        if s.intersect(o, d, ray.tmin, ray.tmax) < ray.tmax {
            return true;
        }
    }
    false
}
