//! Scenes without a tree: every primitive tested, eight at a time in SIMD lanes.

use super::*;
use crate::geometry::sphere_hit;

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

/// One triangle or parallelogram of a [`Block`] (world space), as its test reads it.
#[derive(Clone, Copy)]
struct Facet {
    v0: [f32; 3],
    e1: [f32; 3],
    e2: [f32; 3],
    /// `e1 x e2`.
    n: [f32; 3],
    /// See [`Block::k1`].
    k1: f32,
}

impl Facet {
    /// Möller-Trumbore test (Möller & Trumbore 1997, one combined bounds test as in
    /// `geometry::moller_trumbore`) of the ray from `o` along `d`: `(hit, t, b1, b2)` for a hit
    /// in `(tmin, tmax)`. The one implementation of both ways of filling SIMD lanes: eight
    /// primitives against one ray ([`Block::lane`]) and one primitive against eight rays
    /// ([`flat_closest_batch`]).
    #[inline(always)]
    fn test(&self, o: [f32; 3], d: [f32; 3], tmin: f32, tmax: f32) -> (bool, f32, f32, f32) {
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
        let tvec = [o[0] - self.v0[0], o[1] - self.v0[1], o[2] - self.v0[2]];
        let r = cross(tvec, d);
        let det = -dot(d, self.n);
        let inv_det = 1.0 / det;
        let b1 = dot(self.e2, r) * inv_det;
        let b2 = -dot(self.e1, r) * inv_det;
        let t = dot(tvec, self.n) * inv_det;
        // The bounds in four comparisons: b1, b2 >= 0 as min(b1, b2) >= 0; the outer bound
        // k1 b1 + b2 <= 1 (b1 + b2 for triangles, b2 for parallelograms) together with
        // b1 <= 1 as one max (for triangles b1 <= b1 + b2 already). A zero determinant needs no
        // test of its own: t is then infinite or NaN and fails `t > tmin & t < tmax` (a NaN in
        // b1 or b2, which min and max might pass on, only arises there).
        let min = |a: f32, b: f32| if a < b { a } else { b };
        let max = |a: f32, b: f32| if a > b { a } else { b };
        let hit =
            (min(b1, b2) >= 0.0) & (max(b1, self.k1 * b1 + b2) <= 1.0) & (t > tmin) & (t < tmax);
        (hit, t, b1, b2)
    }
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

impl LaneBest {
    /// Keeps in lane `i` the hit `(t, b1, b2)` of primitive `id` when `hit` (a select per
    /// field, no branch, so that loops over lanes vectorise).
    #[inline(always)]
    fn keep(&mut self, i: usize, hit: bool, (t, b1, b2): (f32, f32, f32), id: u32) {
        self.t[i] = if hit { t } else { self.t[i] };
        self.b1[i] = if hit { b1 } else { self.b1[i] };
        self.b2[i] = if hit { b2 } else { self.b2[i] };
        self.id[i] = if hit { id } else { self.id[i] };
    }
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

    /// Lane `i`'s Möller-Trumbore test: `(hit, t, b1, b2)` for a hit in `(ray.tmin, tmax)`
    /// ([`Facet::test`]).
    #[inline(always)]
    fn lane(&self, i: usize, ray: &Ray, tmax: f32) -> (bool, f32, f32, f32) {
        let (o, d) = (ray.origin, ray.dir);
        self.facet(i)
            .test([o.x, o.y, o.z], [d.x, d.y, d.z], ray.tmin, tmax)
    }

    /// Lane `i`'s primitive.
    #[inline(always)]
    fn facet(&self, i: usize) -> Facet {
        Facet {
            v0: [self.v0[0][i], self.v0[1][i], self.v0[2][i]],
            e1: [self.e1[0][i], self.e1[1][i], self.e1[2][i]],
            e2: [self.e2[0][i], self.e2[1][i], self.e2[2][i]],
            n: [self.n[0][i], self.n[1][i], self.n[2][i]],
            k1: self.k1[i],
        }
    }

    /// Keeps in `best` each lane's hit that is nearer than the lane's best so far; `first_id`
    /// is the primitive index of lane 0. One loop over lanes, so that test and update are
    /// vectorised together (selects, no branch per lane).
    #[inline(always)]
    fn closest(&self, ray: &Ray, first_id: u32, best: &mut LaneBest) {
        for i in 0..LANES {
            let (hit, t, b1, b2) = self.lane(i, ray, best.t[i]);
            best.keep(i, hit, (t, b1, b2), first_id + i as u32);
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

/// The rays of a batch by component (structure of arrays): lane `j` is `rays[j]`.
struct RayLanes {
    o: [[f32; BATCH]; 3],
    d: [[f32; BATCH]; 3],
    tmin: [f32; BATCH],
    tmax: [f32; BATCH],
}

impl RayLanes {
    #[inline(always)]
    fn of(rays: &[Ray; BATCH]) -> Self {
        let mut l = RayLanes {
            o: [[0.0; BATCH]; 3],
            d: [[0.0; BATCH]; 3],
            tmin: [0.0; BATCH],
            tmax: [0.0; BATCH],
        };
        for (j, r) in rays.iter().enumerate() {
            for a in 0..3 {
                l.o[a][j] = r.origin[a];
                l.d[a][j] = r.dir[a];
            }
            l.tmin[j] = r.tmin;
            l.tmax[j] = r.tmax;
        }
        l
    }

    /// Lane `j`'s origin and direction.
    #[inline(always)]
    fn ray(&self, j: usize) -> ([f32; 3], [f32; 3]) {
        let (o, d) = (&self.o, &self.d);
        ([o[0][j], o[1][j], o[2][j]], [d[0][j], d[1][j], d[2][j]])
    }
}

/// [`flat_closest`] of the rays `rays[j]`, `j` in `active`, into `out[j]` (the other entries are
/// left as they are), the same bits: each triangle and parallelogram is tested against the
/// eight rays at once, in SIMD lanes, rather than each ray against eight primitives. A batch
/// then tests each primitive once, where one ray at a time tests every block (the last one
/// partly empty) and then reduces its lanes: a scene of one rectangle tests it once instead
/// of eight times. The primitives are visited in the order of the single-ray search's
/// tie-break (lane, then block) and a hit is kept only when strictly nearer, so ties go the
/// same way.
#[inline(always)]
pub(super) fn flat_closest_batch(
    blocks: &[Block],
    analytic: &[Primitive],
    analytic_from: usize,
    rays: &[Ray; BATCH],
    active: Mask,
    out: &mut [Option<AccelHit>; BATCH],
) {
    let lanes = RayLanes::of(rays);
    let mut best = LaneBest {
        t: lanes.tmax,
        b1: [0.0; BATCH],
        b2: [0.0; BATCH],
        id: [u32::MAX; BATCH],
    };
    for i in 0..LANES {
        for (k, b) in blocks.iter().enumerate() {
            let id = k * LANES + i;
            if id >= analytic_from {
                break;
            }
            let f = b.facet(i);
            for j in 0..BATCH {
                let (o, d) = lanes.ray(j);
                let (hit, t, b1, b2) = f.test(o, d, lanes.tmin[j], best.t[j]);
                best.keep(j, hit, (t, b1, b2), id as u32);
            }
        }
    }
    // The analytic primitives in their order, each against every ray: spheres in SIMD lanes,
    // the others one ray at a time (their hit coordinates with them).
    for (m, s) in analytic.iter().enumerate() {
        let id = (analytic_from + m) as u32;
        if let Primitive::Sphere { center, radius, .. } = *s {
            let c = center.to_array();
            for j in 0..BATCH {
                let (o, d) = lanes.ray(j);
                let t = sphere_hit(o, d, c, radius, lanes.tmin[j], best.t[j]);
                best.keep(j, t < best.t[j], (t, 0.0, 0.0), id);
            }
            continue;
        }
        for j in set_lanes(active) {
            let ray = &rays[j];
            let (o, d) = (Vec3A::from(ray.origin), Vec3A::from(ray.dir));
            let (t, b1, b2) = s.intersect_bary(o, d, ray.tmin, best.t[j]);
            best.keep(j, t < best.t[j], (t, b1, b2), id);
        }
    }
    for j in set_lanes(active) {
        let hit = AccelHit {
            index: best.id[j] as usize,
            t: best.t[j],
            b1: best.b1[j],
            b2: best.b2[j],
        };
        out[j] = (hit.t < rays[j].tmax).then_some(hit);
    }
}

/// [`flat_any`] of the rays `rays[j]`, `j` in `active`: the mask of those blocked. Each
/// triangle and parallelogram is tested against the eight rays at once (as in
/// [`flat_closest_batch`]) until every active ray is blocked.
#[inline(always)]
pub(super) fn flat_any_batch(
    blocks: &[Block],
    analytic: &[Primitive],
    analytic_from: usize,
    rays: &[Ray; BATCH],
    active: Mask,
) -> Mask {
    let lanes = RayLanes::of(rays);
    let mut blocked: Mask = 0;
    for id in 0..analytic_from {
        let f = blocks[id / LANES].facet(id % LANES);
        // Lane results into an array first, then one reduction (as `Block::any_hit`).
        let mut hits = [0u32; BATCH];
        for (j, h) in hits.iter_mut().enumerate() {
            let (o, d) = lanes.ray(j);
            *h = u32::from(f.test(o, d, lanes.tmin[j], lanes.tmax[j]).0) << j;
        }
        blocked |= hits.iter().fold(0, |a, &h| a | h) & active;
        if blocked == active {
            return blocked;
        }
    }
    // The analytic primitives: spheres against all rays in SIMD lanes, the others one ray at
    // a time (plain loops, as in `flat_any`: the adaptor `any` was left outlined, compiled for
    // the baseline, 5.6% of `veach-mis`'s profile samples).
    for s in analytic {
        if let Primitive::Sphere { center, radius, .. } = *s {
            let c = center.to_array();
            let mut hits = [0u32; BATCH];
            for (j, h) in hits.iter_mut().enumerate() {
                let (o, d) = lanes.ray(j);
                let t = sphere_hit(o, d, c, radius, lanes.tmin[j], lanes.tmax[j]);
                *h = u32::from(t < lanes.tmax[j]) << j;
            }
            blocked |= hits.iter().fold(0, |a, &h| a | h) & active;
        } else {
            for j in set_lanes(active & !blocked) {
                let ray = &rays[j];
                let (o, d) = (Vec3A::from(ray.origin), Vec3A::from(ray.dir));
                blocked |= Mask::from(s.intersect(o, d, ray.tmin, ray.tmax) < ray.tmax) << j;
            }
        }
        if blocked == active {
            break;
        }
    }
    blocked
}
