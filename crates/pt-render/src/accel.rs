//! The acceleration structure: one obvhs BVH over all primitives, kept unaware of materials.
//!
//! Both obvhs layouts are available: the compressed 8-wide CWBVH (Ylitie et al. 2017) and the
//! binary BVH2 built by PLOC. CWBVH is the default; `benches/traversal.rs` compares them. Scenes
//! of at most [`FLAT_MAX`] primitives (a Cornell box has 18) get no tree by default: every
//! triangle and parallelogram is tested, eight at a time in SIMD lanes ([`BvhKind::Flat`]),
//! which is faster than any traversal at that size.

use crate::geometry::Primitive;
use obvhs::aabb::Aabb;
use obvhs::bvh2::builder::build_bvh2;
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::bvh2::Bvh2;
use obvhs::cwbvh::builder::build_cwbvh;
use obvhs::cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh;
use obvhs::cwbvh::node::CwBvhNode;
use obvhs::cwbvh::CwBvh;
use obvhs::faststack::StackStack;
use obvhs::ploc::PlocBuilder;
use obvhs::ray::{Ray as BvhRay, RayHit};
use obvhs::{Boundable, BvhBuildParams};
// The `traverse!` macro of obvhs names `UVec2` unqualified.
use glam::UVec2;
use pt_math::{Ray, Vec3A};
use std::time::Duration;

/// Which BVH layout to build.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum BvhKind {
    /// [`BvhKind::Flat`] for scenes of at most [`FLAT_MAX`] primitives, [`BvhKind::CwBvh`] for
    /// larger ones (default).
    #[default]
    Auto,
    /// Compressed wide BVH8.
    CwBvh,
    /// Binary BVH.
    Bvh2,
    /// No tree: every primitive is tested for every ray, triangles and parallelograms eight at
    /// a time in SIMD lanes. Only sensible for small scenes (cost grows with the primitive
    /// count).
    Flat,
}

/// Largest scene that [`BvhKind::Auto`] tests without a tree. Measured (`benches/traversal.rs`,
/// incoherent closest-hit rays, one thread): see the README's Performance section.
pub const FLAT_MAX: usize = 32;

enum Tree {
    Cw(CwBvh),
    /// Large scenes: several CWBVHs over spatially separate groups of primitives (see
    /// [`Accel::build_compact`]).
    CwChunks(Vec<Chunk>),
    Two(Bvh2),
    /// No tree: `prims[..blocks.len() * LANES]` (at most) are the triangles and parallelograms,
    /// also held in `blocks`; spheres follow them and are tested one by one.
    Flat {
        blocks: Vec<Block>,
        spheres_from: usize,
    },
    Empty,
}

/// One CWBVH of a chunked tree: its primitives are `prims[base..]`, in its traversal order.
struct Chunk {
    bvh: CwBvh,
    base: usize,
    bounds: Aabb,
}

/// Largest number of primitives built as one CWBVH by [`Accel::build_compact`]: above it, the
/// primitives are split into 2, 4 or 8 spatial groups built one after the other, because
/// obvhs's CWBVH conversion holds 208 bytes per primitive of temporaries (binary nodes and cost
/// table). 2^18 keeps those under 60 MB per group; traversal then tests each group's box first.
const CHUNK_PRIMS: usize = 1 << 18;

/// Most groups a chunked tree has (a fixed array orders them per ray); larger scenes make larger
/// groups.
const MAX_CHUNKS: usize = 8;

/// A BVH over primitives stored in traversal order.
pub struct Accel {
    tree: Tree,
    /// Whether every CWBVH here is shallow enough for [`SMALL_STACK`] (chosen at build time).
    small_stack: bool,
    /// Primitives reordered so that the BVH's primitive id indexes this directly.
    pub prims: Vec<Primitive>,
    /// For each entry of `prims`, its index in the order given to [`Accel::build`].
    pub original_index: Vec<u32>,
    /// Without a tree (at most [`FLAT_MAX`] primitives, or forced): each triangle's and
    /// parallelogram's unit normal `normalize(e1 x e2)`, computed once instead of at every hit
    /// (the same expression, so the same bits). Empty otherwise.
    pub unit_normals: Vec<pt_math::Vec3>,
}

impl Accel {
    /// Builds the BVH. Primitives are reordered; `original_index` maps back.
    ///
    /// Memory: the builder reads the primitives' boxes directly (no array of boxes), and the
    /// primitives are permuted in place afterwards (no second copy).
    pub fn build(mut prims: Vec<Primitive>, kind: BvhKind) -> Self {
        if prims.is_empty() {
            return Accel {
                tree: Tree::Empty,
                small_stack: true,
                prims,
                original_index: Vec::new(),
                unit_normals: Vec::new(),
            };
        }
        if use_flat(kind, prims.len()) {
            return Accel::build_flat(prims);
        }
        let params = BvhBuildParams::medium_build();
        let mut t = Duration::default();
        let (tree, order) = match kind {
            BvhKind::CwBvh | BvhKind::Auto | BvhKind::Flat => {
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
        Accel {
            small_stack: fits_small_stack(&tree),
            tree,
            prims,
            original_index: order,
            unit_normals: Vec::new(),
        }
    }

    /// [`Accel::build`] with a lower memory peak, for large meshes: the primitives are dropped
    /// while the tree is built and made again afterwards, in traversal order, by `remake(i)`,
    /// which must return the primitive that was `prims[i]`. The tree and the resulting `prims`
    /// and `original_index` are the same as [`Accel::build`]'s.
    ///
    /// Memory (1M triangles): the builder reads 24-byte boxes instead of the 64-byte primitives,
    /// and frees them once the binary tree is built, before the CWBVH conversion, whose
    /// temporaries (112 MB of cost table next to the 96 MB binary tree) are the peak. This is
    /// obvhs's `build_cwbvh` (PLOC, reinsertion, conversion with the same parameters) written
    /// out so that the boxes can be freed in between.
    pub fn build_compact(
        prims: Vec<Primitive>,
        kind: BvhKind,
        remake: impl Fn(usize) -> Primitive,
    ) -> Self {
        Self::build_compact_chunked(prims, kind, remake, CHUNK_PRIMS)
    }

    /// [`Accel::build_compact`] with CWBVH groups of at most `chunk_prims` primitives (as long
    /// as that makes at most [`MAX_CHUNKS`] groups).
    fn build_compact_chunked(
        prims: Vec<Primitive>,
        kind: BvhKind,
        remake: impl Fn(usize) -> Primitive,
        chunk_prims: usize,
    ) -> Self {
        if prims.is_empty() {
            return Accel {
                tree: Tree::Empty,
                small_stack: true,
                prims,
                original_index: Vec::new(),
                unit_normals: Vec::new(),
            };
        }
        if use_flat(kind, prims.len()) {
            return Accel::build_flat(prims);
        }
        let mut boxes: Vec<BuildBox> = Vec::with_capacity(prims.len());
        boxes.extend(prims.iter().map(|p| BuildBox::from(p.aabb())));
        drop(prims);
        let params = BvhBuildParams::medium_build();
        let (tree, order) = match kind {
            BvhKind::CwBvh | BvhKind::Auto | BvhKind::Flat if boxes.len() <= chunk_prims => {
                let bvh = build_cw_low_memory(boxes, &params);
                let order = bvh.primitive_indices.clone();
                (Tree::Cw(bvh), order)
            }
            BvhKind::CwBvh | BvhKind::Auto | BvhKind::Flat => {
                let parts = boxes
                    .len()
                    .div_ceil(chunk_prims)
                    .next_power_of_two()
                    .min(MAX_CHUNKS);
                let mut ids: Vec<u32> = (0..boxes.len() as u32).collect();
                split_median(&mut ids, &boxes, parts);
                let mut order = Vec::with_capacity(ids.len());
                let mut chunks = Vec::with_capacity(parts);
                let size = ids.len().div_ceil(parts);
                for group in ids.chunks(size) {
                    let group_boxes: Vec<BuildBox> =
                        group.iter().map(|&i| boxes[i as usize]).collect();
                    let bvh = build_cw_low_memory(group_boxes, &params);
                    let base = order.len();
                    order.extend(bvh.primitive_indices.iter().map(|&k| group[k as usize]));
                    chunks.push(Chunk {
                        bounds: bvh.total_aabb,
                        bvh,
                        base,
                    });
                }
                drop(boxes);
                (Tree::CwChunks(chunks), order)
            }
            BvhKind::Bvh2 => {
                let bvh = build_bvh2(&boxes, params, &mut Duration::default());
                drop(boxes);
                let order = bvh.primitive_indices.clone();
                (Tree::Two(bvh), order)
            }
        };
        let mut prims = Vec::with_capacity(order.len());
        prims.extend(order.iter().map(|&i| remake(i as usize)));
        Accel {
            small_stack: fits_small_stack(&tree),
            tree,
            prims,
            original_index: order,
            unit_normals: Vec::new(),
        }
    }

    /// The flat "tree" ([`BvhKind::Flat`]): triangles and parallelograms first, in their given
    /// order, copied into SIMD blocks; spheres after them.
    fn build_flat(mut prims: Vec<Primitive>) -> Self {
        let mut order: Vec<u32> = (0..prims.len() as u32).collect();
        // Stable: the order within each kind is kept.
        order.sort_by_key(|&i| matches!(prims[i as usize], Primitive::Sphere { .. }));
        permute_in_place(&mut prims, &order);
        let spheres_from = prims
            .iter()
            .position(|p| matches!(p, Primitive::Sphere { .. }))
            .unwrap_or(prims.len());
        let blocks = prims[..spheres_from]
            .chunks(LANES)
            .map(Block::new)
            .collect();
        let unit_normals = prims[..spheres_from]
            .iter()
            .map(|p| match *p {
                Primitive::Triangle { e1, e2, .. } | Primitive::Parallelogram { e1, e2, .. } => {
                    pt_math::Vec3::from(e1.cross(e2)).normalize()
                }
                Primitive::Sphere { .. } => pt_math::Vec3::ZERO,
            })
            .collect();
        Accel {
            tree: Tree::Flat {
                blocks,
                spheres_from,
            },
            small_stack: false,
            prims,
            original_index: order,
            unit_normals,
        }
    }

    /// Closest hit along the ray: which primitive, at what distance, with the edge coordinates
    /// its test found (so the caller need not test it again).
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray) -> Option<AccelHit> {
        if let Tree::Flat {
            blocks,
            spheres_from,
        } = &self.tree
        {
            return flat_closest(blocks, &self.prims[*spheres_from..], *spheres_from, ray);
        }
        let r = bvh_ray(ray);
        let mut hit = RayHit::none();
        let prims = &self.prims;
        // obvhs and `cw_closest` accept a candidate exactly when its distance is below the
        // current `tmax`, so the barycentrics of the last candidate below it are the hit's.
        let mut bary = (0.0, 0.0);
        let mut f = |r: &BvhRay, id: usize| {
            let (t, b1, b2) = prims[id].intersect_bary(r.origin, r.direction, r.tmin, r.tmax);
            if t < r.tmax {
                bary = (b1, b2);
            }
            t
        };
        let found = match &self.tree {
            Tree::Cw(b) if self.small_stack => cw_closest::<SMALL_STACK>(b, r, &mut hit, &mut f),
            Tree::Cw(b) => cw_closest::<LARGE_STACK>(b, r, &mut hit, &mut f),
            Tree::CwChunks(chunks) => chunks_closest(chunks, r, &mut hit, &mut f),
            Tree::Two(b) => b.ray_traverse(r, &mut hit, &mut f),
            Tree::Flat { .. } => unreachable!("handled above"),
            Tree::Empty => false,
        };
        found.then_some(AccelHit {
            index: hit.primitive_id as usize,
            t: hit.t,
            b1: bary.0,
            b2: bary.1,
        })
    }

    /// Whether anything blocks the ray within `(tmin, tmax)` (any-hit traversal, stops at the
    /// first blocker).
    #[inline(always)]
    pub fn occluded(&self, ray: &Ray) -> bool {
        if let Tree::Flat {
            blocks,
            spheres_from,
        } = &self.tree
        {
            return flat_any(blocks, &self.prims[*spheres_from..], ray);
        }
        let r = bvh_ray(ray);
        let prims = &self.prims;
        let f = |r: &BvhRay, id: usize| prims[id].intersect(r.origin, r.direction, r.tmin, r.tmax);
        match &self.tree {
            Tree::Cw(b) if self.small_stack => cw_any::<SMALL_STACK>(b, r, prims),
            Tree::Cw(b) => cw_any::<LARGE_STACK>(b, r, prims),
            Tree::CwChunks(chunks) => chunks.iter().any(|c| {
                c.bounds.intersect_ray(&r) < r.tmax
                    && cw_any::<LARGE_STACK>(&c.bvh, r, &prims[c.base..])
            }),
            Tree::Two(b) => !b.ray_traverse_miss(r, f),
            Tree::Flat { .. } => unreachable!("handled above"),
            Tree::Empty => false,
        }
    }
}

/// Whether `kind` asks for the flat "tree" for `n` primitives.
fn use_flat(kind: BvhKind, n: usize) -> bool {
    kind == BvhKind::Flat || (kind == BvhKind::Auto && n <= FLAT_MAX)
}

/// Primitives per [`Block`]: eight `f32` fill one AVX2 register.
const LANES: usize = 8;

/// Up to [`LANES`] triangles and parallelograms in structure-of-arrays form (world space), for
/// a Möller-Trumbore test of all of them at once, written as loops over lanes that the
/// compiler vectorises. The lanes compute what [`crate::geometry::intersect_triangle`] and
/// [`crate::geometry::intersect_parallelogram`] compute, with the triple products regrouped
/// around a stored normal (one cross product per lane instead of two: 4% fewer instructions
/// for the Cornell box), so they agree to rounding. Unused lanes have zero edges: their
/// determinant is 0 and they never hit.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(32))]
struct Block {
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
struct LaneBest {
    /// Distance (the ray's `tmax` while nothing was hit in the lane).
    t: [f32; LANES],
    /// Edge coordinates of the hit (see [`AccelHit`]).
    b1: [f32; LANES],
    b2: [f32; LANES],
    /// Primitive index of the hit (`u32::MAX` while nothing was hit).
    id: [u32; LANES],
}

impl Block {
    /// The block of `prims` (at most [`LANES`], no spheres).
    fn new(prims: &[Primitive]) -> Block {
        let mut b = Block::default();
        for (i, p) in prims.iter().enumerate() {
            let (v0, e1, e2, k1) = match *p {
                Primitive::Triangle { v0, e1, e2 } => (v0, e1, e2, 1.0),
                Primitive::Parallelogram { v0, e1, e2 } => (v0, e1, e2, 0.0),
                Primitive::Sphere { .. } => unreachable!("spheres are kept out of blocks"),
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
/// and `spheres` (primitives `spheres_from..`). Ties go to the lowest lane, then the earliest
/// block.
#[inline(always)]
fn flat_closest(
    blocks: &[Block],
    spheres: &[Primitive],
    spheres_from: usize,
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
    for (j, s) in spheres.iter().enumerate() {
        let t = s.intersect(o, d, ray.tmin, hit.t);
        if t < hit.t {
            hit = AccelHit {
                index: spheres_from + j,
                t,
                b1: 0.0,
                b2: 0.0,
            };
        }
    }
    (hit.t < ray.tmax).then_some(hit)
}

/// Whether any of `blocks` or `spheres` is hit in `(ray.tmin, ray.tmax)`. Plain loops: the
/// iterator adaptor `any` was not inlined, so the lane tests ran outside the x86-64-v3 loop.
#[inline(always)]
fn flat_any(blocks: &[Block], spheres: &[Primitive], ray: &Ray) -> bool {
    for b in blocks {
        if b.any_hit(ray) {
            return true;
        }
    }
    let (o, d) = (Vec3A::from(ray.origin), Vec3A::from(ray.dir));
    for s in spheres {
        if s.intersect(o, d, ray.tmin, ray.tmax) < ray.tmax {
            return true;
        }
    }
    false
}

/// The closest hit [`Accel::intersect`] found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AccelHit {
    /// Index into [`Accel::prims`].
    pub index: usize,
    /// Distance along the ray (in units of the ray's direction vector).
    pub t: f32,
    /// Coordinate along the primitive's first edge: a triangle's barycentric weight of
    /// `v0 + e1`, a parallelogram's fraction of `e1`; 0 for spheres.
    pub b1: f32,
    /// The same along the second edge (`v0 + e2`, `e2`).
    pub b2: f32,
}

/// obvhs's ray for `ray`: the same values as its `Ray::new` (its `safe_inverse`: components of
/// magnitude at most `f32::EPSILON` invert to `±1 / EPSILON`), computed on all three lanes at
/// once instead of with a branch per component.
#[inline(always)]
fn bvh_ray(ray: &Ray) -> BvhRay {
    let d = Vec3A::from(ray.dir);
    let tiny = d.abs().cmple(Vec3A::splat(f32::EPSILON));
    let inv_direction = Vec3A::select(tiny, d.signum() / f32::EPSILON, Vec3A::ONE / d);
    BvhRay {
        origin: Vec3A::from(ray.origin),
        direction: d,
        inv_direction,
        tmin: ray.tmin,
        tmax: ray.tmax,
    }
}

/// Stack entries for CWBVHs of depth below [`SMALL_STACK`]: a traversal pushes at most one
/// node group per level it descends, and a shorter stack is cheaper to set up per ray (obvhs
/// clears its 32 entries for every ray). Small scenes such as the Cornell box have depth 2.
const SMALL_STACK: usize = 8;
/// obvhs's own traversal stack size, which its `validate` requires to exceed the depth.
const LARGE_STACK: usize = 32;

/// Whether every CWBVH in `tree` is shallow enough for [`SMALL_STACK`]. obvhs's stack keeps
/// writing into its last entry when full, so the depth must stay below the size minus one.
fn fits_small_stack(tree: &Tree) -> bool {
    match tree {
        Tree::Cw(b) => cw_depth(b, 0) + 1 < SMALL_STACK as u32,
        _ => false,
    }
}

/// Number of internal-node levels from `node` down (1 for a node whose children are all
/// leaves; 0 for an empty tree). A node's `imask` marks its internal children.
fn cw_depth(bvh: &CwBvh, node: usize) -> u32 {
    let Some(n) = bvh.nodes.get(node) else {
        return 0;
    };
    let deepest = (0..8)
        .filter(|&ch| n.imask >> ch & 1 != 0)
        .map(|ch| cw_depth(bvh, n.child_node_index(ch) as usize))
        .max();
    1 + deepest.unwrap_or(0)
}

/// State of one CWBVH traversal, as obvhs's `traverse!` macro reads and writes it (the fields of
/// its `Traversal`), with a stack of `N` entries held outside: an array inside the state would
/// make the whole state live in memory, its fields stored and reloaded on every step.
struct CwTraversal<'s, const N: usize> {
    stack: &'s mut StackStack<UVec2, N>,
    current_group: UVec2,
    primitive_group: UVec2,
    oct_inv4: u32,
    primitive_id: u32,
    hitmask: u32,
}

/// obvhs's inverted ray octant per child slot byte, indexed by the sign mask of the direction
/// (bit 0: x < 0, bit 1: y < 0, bit 2: z < 0): bytes of 4 for x >= 0, 2 for y >= 0, 1 for
/// z >= 0 (Ylitie et al. 2017, the order children are stored in for each octant).
const OCT_INV4: [u32; 8] = {
    let mut t = [0u32; 8];
    let mut m = 0;
    while m < 8 {
        let x = if m & 1 != 0 { 0 } else { 0x0404_0404 };
        let y = if m & 2 != 0 { 0 } else { 0x0202_0202 };
        let z = if m & 4 != 0 { 0 } else { 0x0101_0101 };
        t[m] = x | y | z;
        m += 1;
    }
    t
};

impl<'s, const N: usize> CwTraversal<'s, N> {
    /// obvhs's `CwBvh::new_traversal` over `stack` (empty): the root's group, or nothing for an
    /// empty tree.
    #[inline(always)]
    fn new(bvh: &CwBvh, dir: Vec3A, stack: &'s mut StackStack<UVec2, N>) -> Self {
        let current_group = if bvh.nodes.is_empty() {
            UVec2::ZERO
        } else {
            UVec2::new(0, 0x8000_0000)
        };
        // Same comparisons as obvhs (`< 0.0`, so -0.0 counts as positive), one vector compare.
        let oct_inv4 = OCT_INV4[dir.cmplt(Vec3A::ZERO).bitmask() as usize];
        CwTraversal {
            stack,
            current_group,
            primitive_group: UVec2::ZERO,
            oct_inv4,
            primitive_id: 0,
            hitmask: 0,
        }
    }
}

/// CWBVH closest-hit traversal: obvhs's `CwBvh::ray_traverse` written out with its `traverse!`
/// macro (same visiting order, same result) with this module's node test, [`intersect_node`],
/// and an `N`-entry stack. `hit` receives the closest primitive in `(ray.tmin, ray.tmax)`;
/// returns whether there is one.
#[inline(always)]
fn cw_closest<const N: usize>(
    bvh: &CwBvh,
    ray: BvhRay,
    hit: &mut RayHit,
    mut f: impl FnMut(&BvhRay, usize) -> f32,
) -> bool {
    let mut traverse_ray = ray;
    let mut stack = StackStack::default();
    let mut state = CwTraversal::<N>::new(bvh, ray.direction, &mut stack);
    let mut node;
    obvhs::traverse!(
        bvh,
        node,
        state,
        intersect_node(node, &traverse_ray, state.oct_inv4),
        {
            let t = f(&traverse_ray, state.primitive_id as usize);
            if t < traverse_ray.tmax {
                hit.primitive_id = state.primitive_id;
                hit.t = t;
                traverse_ray.tmax = t;
            }
        }
    );
    hit.t < ray.tmax
}

/// CWBVH any-hit traversal: whether some primitive is hit in `(ray.tmin, ray.tmax)`; stops at
/// the first one found (obvhs's `CwBvh::ray_traverse_miss`, negated, with [`intersect_node`]
/// and an `N`-entry stack). The tree's primitive ids index `prims`; they are tested directly
/// rather than through a closure, which the compiler stopped inlining once primitives had three
/// kinds (the test then ran outside the x86-64-v3 render loop).
#[inline(always)]
fn cw_any<const N: usize>(bvh: &CwBvh, ray: BvhRay, prims: &[Primitive]) -> bool {
    let mut stack = StackStack::default();
    let mut state = CwTraversal::<N>::new(bvh, ray.direction, &mut stack);
    let mut node;
    let mut hit = false;
    'outer: {
        obvhs::traverse!(
            bvh,
            node,
            state,
            intersect_node(node, &ray, state.oct_inv4),
            {
                if prims[state.primitive_id as usize].intersect(
                    ray.origin,
                    ray.direction,
                    ray.tmin,
                    ray.tmax,
                ) < ray.tmax
                {
                    hit = true;
                    break 'outer;
                }
            }
        );
    }
    hit
}

/// obvhs's `build_cwbvh` (PLOC, reinsertion, conversion, with `params`) written out so that the
/// boxes are freed once the binary tree is built, before the conversion allocates its cost table.
fn build_cw_low_memory(boxes: Vec<BuildBox>, params: &BvhBuildParams) -> CwBvh {
    let n = boxes.len() as u32;
    let mut bvh2 = PlocBuilder::with_capacity(boxes.len()).build(
        params.ploc_search_distance,
        &boxes,
        (0..n).collect(),
        params.sort_precision,
        params.search_depth_threshold,
    );
    drop(boxes);
    ReinsertionOptimizer::default().run(&mut bvh2, params.reinsertion_batch_ratio, None);
    let mut bvh = bvh2_to_cwbvh(&bvh2, params.max_prims_per_leaf.clamp(1, 3), true, false);
    // The converter reserves one node per primitive (80 bytes each); about a tenth are used.
    bvh.nodes.shrink_to_fit();
    bvh
}

/// Reorders `ids` into `parts` (a power of two) consecutive groups of equal size (the last may
/// be smaller) that are spatially separate: recursive median splits of the box centres along
/// the axis of their largest extent.
fn split_median(ids: &mut [u32], boxes: &[BuildBox], parts: usize) {
    if parts <= 1 || ids.len() < 2 {
        return;
    }
    let centre = |i: u32| {
        let b = &boxes[i as usize];
        (b.min + b.max) * 0.5
    };
    let (lo, hi) = ids.iter().fold(
        (pt_math::Vec3::INFINITY, pt_math::Vec3::NEG_INFINITY),
        |(lo, hi), &i| (lo.min(centre(i)), hi.max(centre(i))),
    );
    let ext = hi - lo;
    let axis = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    // Equal groups at every level: the left half gets ceil(len / parts) * parts / 2 items.
    let size = ids.len().div_ceil(parts);
    let mid = (size * parts / 2).min(ids.len());
    if mid == 0 || mid >= ids.len() {
        return;
    }
    // Ties broken by index, so the split does not depend on the input order.
    ids.select_nth_unstable_by(mid, |&a, &b| {
        centre(a)[axis].total_cmp(&centre(b)[axis]).then(a.cmp(&b))
    });
    let (left, right) = ids.split_at_mut(mid);
    split_median(left, boxes, parts / 2);
    split_median(right, boxes, parts / 2);
}

/// Closest hit over the groups of a chunked tree: the groups whose box the ray enters, nearest
/// entry first, each traversed with the closest hit so far as its `tmax`. `hit` receives the
/// index into `prims` and the distance.
#[inline]
fn chunks_closest(
    chunks: &[Chunk],
    ray: BvhRay,
    hit: &mut RayHit,
    f: &mut impl FnMut(&BvhRay, usize) -> f32,
) -> bool {
    let mut entries = [(f32::INFINITY, 0usize); MAX_CHUNKS];
    let mut n = 0;
    for (k, c) in chunks.iter().enumerate() {
        let t = c.bounds.intersect_ray(&ray);
        if t < ray.tmax {
            // Insertion sort by entry distance (at most MAX_CHUNKS entries).
            let mut j = n;
            while j > 0 && entries[j - 1].0 > t {
                entries[j] = entries[j - 1];
                j -= 1;
            }
            entries[j] = (t, k);
            n += 1;
        }
    }
    let mut best = ray.tmax;
    for &(t, k) in &entries[..n] {
        if t >= best {
            break;
        }
        let c = &chunks[k];
        let mut r = ray;
        r.tmax = best;
        let mut h = RayHit::none();
        if cw_closest::<LARGE_STACK>(&c.bvh, r, &mut h, |r: &BvhRay, id: usize| f(r, c.base + id)) {
            best = h.t;
            hit.t = h.t;
            hit.primitive_id = (c.base + h.primitive_id as usize) as u32;
        }
    }
    best < ray.tmax
}

/// A primitive's bounds as the BVH builder reads them: 24 bytes (obvhs's `Aabb` has 32, a
/// `Primitive` 64).
#[derive(Clone, Copy)]
struct BuildBox {
    min: pt_math::Vec3,
    max: pt_math::Vec3,
}

impl From<Aabb> for BuildBox {
    fn from(b: Aabb) -> Self {
        BuildBox {
            min: b.min.into(),
            max: b.max.into(),
        }
    }
}

impl Boundable for BuildBox {
    #[inline]
    fn aabb(&self) -> Aabb {
        Aabb::new(self.min.into(), self.max.into())
    }
}

/// Which of a CWBVH node's eight children the ray enters within `(ray.tmin, ray.tmax)`, as the
/// hit mask the `traverse!` macro expects: child node bits (in traversal order for the ray's
/// octant) in the top byte, leaf primitive bits in the low 24.
///
/// The same slab test as obvhs's `CwBvhNode::intersect_ray_simd` (Ylitie et al. 2017: child
/// planes are bytes on the node's grid, `t = q * (extent / d) + (p - o) / d`, a separate
/// multiply and add as there), with the same results except for the lower bound (below), but
/// written over arrays of eight so that the compiler vectorises it: obvhs converts the 48 plane bytes to floats one at a time
/// (`_mm_set_ps` of scalars); here they are widened four at a time (SSE2).
#[inline(always)]
fn intersect_node(node: &CwBvhNode, ray: &BvhRay, oct_inv4: u32) -> u32 {
    let scale = node.compute_extent() * ray.inv_direction;
    let offset = (Vec3A::from(node.p) - ray.origin) * ray.inv_direction;
    // For a negative direction component the ray enters through the child's max plane.
    let pick =
        |neg: bool, min: &[u8; 8], max: &[u8; 8]| if neg { (*max, *min) } else { (*min, *max) };
    let (near_x, far_x) = pick(ray.direction.x < 0.0, &node.child_min_x, &node.child_max_x);
    let (near_y, far_y) = pick(ray.direction.y < 0.0, &node.child_min_y, &node.child_max_y);
    let (near_z, far_z) = pick(ray.direction.z < 0.0, &node.child_min_z, &node.child_max_z);
    // `if a > b` forms compile to maxps/minps; no NaN can occur (finite planes and scales).
    let max = |a: f32, b: f32| if a > b { a } else { b };
    let min = |a: f32, b: f32| if a < b { a } else { b };
    // Each child that the ray enters contributes its bits (`child_bits8`, byte i) at its
    // position (`bit_index8`, byte i); summed over all eight without a branch per child, so
    // that the x86-64-v3 loop computes it with per-lane shifts.
    let (child_bits8, bit_index8) = node.get_child_and_index_bits(oct_inv4);
    let child_bits = child_bits8.to_le_bytes();
    let bit_index = bit_index8.to_le_bytes();
    let mut mask = 0u32;
    for i in 0..8 {
        let t0x = near_x[i] as f32 * scale.x + offset.x;
        let t1x = far_x[i] as f32 * scale.x + offset.x;
        let t0y = near_y[i] as f32 * scale.y + offset.y;
        let t1y = far_y[i] as f32 * scale.y + offset.y;
        let t0z = near_z[i] as f32 * scale.z + offset.z;
        let t1z = far_z[i] as f32 * scale.z + offset.z;
        // obvhs clamps with a fixed 1e-4 (its `EPSILON`) here instead of `ray.tmin`: boxes the
        // ray leaves within 1e-4 scene units are skipped, so surfaces that close to the origin
        // were missed or not depending on the tree (a Cornell box scaled by 1e-4 lost 12% of
        // its light). Rays here leave surfaces through robust origin offsets instead.
        let t0 = max(max(t0x, max(t0y, t0z)), ray.tmin);
        let t1 = min(min(t1x, min(t1y, t1z)), ray.tmax);
        // Bit positions are below 32 (child bits in the top byte, primitives in the low 24).
        mask |= (u32::from(t0 <= t1) * child_bits[i] as u32) << (bit_index[i] & 31);
    }
    mask
}

/// Reorders `v` so that `v[k]` becomes the old `v[order[k]]` (`order` a permutation), in place
/// by following cycles; one bit per element marks what is done.
pub(crate) fn permute_in_place<T: Copy>(v: &mut [T], order: &[u32]) {
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
                v.push(Primitive::Triangle {
                    v0: p,
                    e1: Vec3A::X,
                    e2: Vec3A::Y,
                });
                v.push(Primitive::Triangle {
                    v0: p + Vec3A::X + Vec3A::Y,
                    e1: -Vec3A::X,
                    e2: -Vec3A::Y,
                });
            }
        }
        v.push(Primitive::Sphere {
            center: Vec3A::new(2.5, 2.5, 3.0),
            radius: 1.0,
            flip: false,
        });
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
    fn compact_build_gives_the_same_accel() {
        // The low-memory build must make exactly the tree and order of `build` (same builder
        // steps and parameters), so images do not change.
        let prims = grid(12);
        for kind in [BvhKind::CwBvh, BvhKind::Bvh2] {
            let a = Accel::build(prims.clone(), kind);
            let b = Accel::build_compact(prims.clone(), kind, |i| prims[i]);
            assert_eq!(a.original_index, b.original_index, "{kind:?}");
            match (&a.tree, &b.tree) {
                (Tree::Cw(x), Tree::Cw(y)) => assert!(x == y),
                (Tree::Two(x), Tree::Two(y)) => {
                    assert_eq!(format!("{:?}", x.nodes), format!("{:?}", y.nodes))
                }
                _ => panic!("{kind:?}: different tree kinds"),
            }
            for (p, q) in a.prims.iter().zip(&b.prims) {
                assert_eq!(format!("{p:?}"), format!("{q:?}"));
            }
        }
    }

    #[test]
    fn median_split_makes_equal_separate_groups() {
        // 1000 boxes along x in shuffled order, 4 groups: each group must hold 250 consecutive
        // positions (so the groups do not overlap).
        let mut xs: Vec<u32> = (0..1000).collect();
        xs.sort_by_key(|&i| (i * 7919) % 1000);
        let boxes: Vec<BuildBox> = xs
            .iter()
            .map(|&x| BuildBox {
                min: Vec3::new(x as f32, 0.0, 0.0),
                max: Vec3::new(x as f32 + 0.5, 1.0, 1.0),
            })
            .collect();
        let mut ids: Vec<u32> = (0..1000).collect();
        split_median(&mut ids, &boxes, 4);
        for (g, group) in ids.chunks(250).enumerate() {
            let mut pos: Vec<u32> = group.iter().map(|&i| xs[i as usize]).collect();
            pos.sort();
            assert_eq!(
                pos,
                ((250 * g as u32)..(250 * (g as u32 + 1))).collect::<Vec<_>>(),
                "group {g}"
            );
        }
    }

    #[test]
    fn finds_hits_closer_than_obvhs_epsilon() {
        // Rays starting 1e-6 to 1e-4 above the z = 0 grid, pointing down at it: the hit is closer
        // than obvhs's node-test bound (1e-4), which skipped boxes left that early, so whether
        // these were found depended on the tree. Every one must be found, by every tree kind.
        let prims = grid(8);
        for (kind, chunk) in [
            (BvhKind::CwBvh, usize::MAX),
            (BvhKind::Bvh2, usize::MAX),
            (BvhKind::CwBvh, 40),
            (BvhKind::Flat, usize::MAX),
        ] {
            let accel = if chunk == usize::MAX {
                Accel::build(prims.clone(), kind)
            } else {
                Accel::build_compact_chunked(prims.clone(), kind, |i| prims[i], chunk)
            };
            for k in 0..1000 {
                let h = 1e-6 + 1e-4 * (k as f32 / 1000.0);
                let o = Vec3::new(
                    0.1 + 7.8 * ((k * 37) % 1000) as f32 / 1000.0,
                    0.1 + 7.8 * ((k * 91) % 1000) as f32 / 1000.0,
                    h,
                );
                let ray = Ray::new(o, Vec3::new(0.01, -0.02, -1.0).normalize());
                let hit = accel.intersect(&ray).unwrap_or_else(|| {
                    panic!("{kind:?} {chunk}: missed the plane from height {h}")
                });
                assert!(
                    (hit.t - h).abs() < 1e-2 * h,
                    "{kind:?}: t {} for height {h}",
                    hit.t
                );
                assert!(
                    accel.occluded(&ray),
                    "{kind:?} {chunk}: shadow ray from height {h}"
                );
            }
        }
    }

    #[test]
    fn stack_size_follows_the_tree_depth() {
        // obvhs's validation counts depth from 0 at the root; `cw_depth` counts levels.
        for (n, small) in [(2, true), (8, true), (300, false)] {
            let prims = grid(n);
            let accel = Accel::build(prims.clone(), BvhKind::CwBvh);
            let Tree::Cw(b) = &accel.tree else {
                panic!("not a single CWBVH")
            };
            let levels = cw_depth(b, 0);
            assert_eq!(
                levels,
                b.validate(&accel.prims, true).max_depth + 1,
                "grid {n}"
            );
            // 180,001 primitives need more levels than the small stack holds.
            assert_eq!(accel.small_stack, small, "grid {n}: {levels} levels");
            // Closest hits through the large stack agree with a brute-force search.
            if !small {
                for k in 0..200 {
                    let o = Vec3::new(k as f32 * 1.37 % 300.0, k as f32 * 2.71 % 300.0, 6.0);
                    let ray = Ray::new(o, Vec3::new(0.3, -0.2, -1.0).normalize());
                    let brute = prims
                        .iter()
                        .map(|p| p.intersect(o.into(), ray.dir.into(), 0.0, f32::INFINITY))
                        .fold(f32::INFINITY, f32::min);
                    assert_eq!(
                        accel.intersect(&ray).map_or(f32::INFINITY, |h| h.t),
                        brute,
                        "ray {k}"
                    );
                }
            }
        }
    }

    #[test]
    fn flat_blocks_match_the_scalar_tests() {
        // 45 random triangles and parallelograms (six blocks, the last partly empty) and two
        // spheres, tested without a tree: each ray's hit must be the scalar tests' nearest (to
        // rounding), and a shadow ray must be blocked exactly when something lies within its
        // interval. A wrong sign or bound in the lanes misses or invents hits here.
        let mut s = 99u64;
        let mut rnd = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 40) as f32) / (1u64 << 24) as f32
        };
        let mut prims = Vec::new();
        for k in 0..45 {
            let v0 = Vec3A::new(rnd() * 8.0 - 4.0, rnd() * 8.0 - 4.0, rnd() * 8.0 - 4.0);
            let e1 = Vec3A::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5) * 3.0;
            let e2 = Vec3A::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5) * 3.0;
            prims.push(if k % 3 == 0 {
                Primitive::Parallelogram { v0, e1, e2 }
            } else {
                Primitive::Triangle { v0, e1, e2 }
            });
            if k % 20 == 7 {
                prims.push(Primitive::Sphere {
                    center: v0,
                    radius: 0.7,
                    flip: false,
                });
            }
        }
        let accel = Accel::build(prims.clone(), BvhKind::Flat);
        let Tree::Flat {
            blocks,
            spheres_from,
        } = &accel.tree
        else {
            panic!("not flat")
        };
        assert_eq!((blocks.len(), *spheres_from), (6, 45));
        let mut hits = 0;
        for _ in 0..20_000 {
            let o = Vec3::new(rnd() * 10.0 - 5.0, rnd() * 10.0 - 5.0, rnd() * 10.0 - 5.0);
            let d = Vec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5).normalize();
            let mut ray = Ray::new(o, d);
            ray.tmax = 1.0 + 6.0 * rnd();
            let brute = accel
                .prims
                .iter()
                .enumerate()
                .map(|(i, p)| (i, p.intersect_bary(o.into(), d.into(), ray.tmin, ray.tmax)))
                .filter(|h| h.1 .0 < ray.tmax)
                .min_by(|a, b| a.1 .0.total_cmp(&b.1 .0));
            let got = accel.intersect(&ray);
            match (brute, got) {
                (None, None) => {}
                (Some((i, (t, b1, b2))), Some(h)) => {
                    hits += 1;
                    // The lanes regroup Möller-Trumbore's products around the stored normal, so
                    // results agree to rounding (a few ulp), not to the bit.
                    // Both forms round differently. Their error grows as 1/cos of the angle to
                    // the normal (both divide by the determinant) and with the distance from the
                    // origin to the primitive's corner (t is a difference of products of that
                    // size): allow 1e-6 (8 ulp) of that distance per unit of 1/cos. At a grazing
                    // 0.18 degrees the two differ by 2e-5 of t; a wrong term would be far off.
                    let (v0, cos) = match accel.prims[i] {
                        Primitive::Triangle { v0, e1, e2 }
                        | Primitive::Parallelogram { v0, e1, e2 } => {
                            (v0, e1.cross(e2).normalize().dot(d.into()).abs())
                        }
                        Primitive::Sphere { center, .. } => (center, 1.0),
                    };
                    let tol = 1e-6 / cos;
                    let scale = t + (Vec3A::from(o) - v0).length();
                    assert!(
                        (h.t - t).abs() <= tol * scale,
                        "t {} vs {t} (cos {cos}, scale {scale})",
                        h.t
                    );
                    // Equal distances (two primitives through one point) may pick either.
                    if h.index == i {
                        assert!(
                            (h.b1 - b1).abs() <= tol && (h.b2 - b2).abs() <= tol,
                            "{:?} vs {:?}",
                            (h.b1, h.b2),
                            (b1, b2)
                        );
                    } else {
                        assert!(
                            (accel.prims[h.index].intersect(
                                o.into(),
                                d.into(),
                                ray.tmin,
                                ray.tmax
                            ) - t)
                                .abs()
                                <= tol * scale
                        );
                    }
                    let orig = accel.original_index[h.index] as usize;
                    assert_eq!(
                        format!("{:?}", accel.prims[h.index]),
                        format!("{:?}", prims[orig])
                    );
                }
                other => panic!("{other:?}"),
            }
            assert_eq!(accel.occluded(&ray), brute.is_some());
        }
        // The rays must exercise both outcomes.
        assert!((1_000..19_000).contains(&hits), "{hits} hits");
        // Auto: flat up to FLAT_MAX primitives, a tree above.
        assert!(matches!(
            Accel::build(prims[..FLAT_MAX].to_vec(), BvhKind::Auto).tree,
            Tree::Flat { .. }
        ));
        assert!(matches!(
            Accel::build(prims[..FLAT_MAX + 1].to_vec(), BvhKind::Auto).tree,
            Tree::Cw(_)
        ));
        assert!(matches!(
            Accel::build_compact(prims[..FLAT_MAX].to_vec(), BvhKind::Auto, |i| prims[i]).tree,
            Tree::Flat { .. }
        ));
    }

    #[test]
    fn matches_brute_force() {
        let prims = grid(8);
        // The last three: CWBVH in 2 and 4 groups (129 primitives, at most 80 and 40 per group),
        // as large scenes are built.
        let builds = [
            (BvhKind::CwBvh, usize::MAX),
            (BvhKind::Bvh2, usize::MAX),
            (BvhKind::CwBvh, 80),
            (BvhKind::CwBvh, 40),
            (BvhKind::CwBvh, 16),
        ];
        for (kind, chunk) in builds {
            let accel = if chunk == usize::MAX {
                Accel::build(prims.clone(), kind)
            } else {
                let accel = Accel::build_compact_chunked(prims.clone(), kind, |i| prims[i], chunk);
                let Tree::CwChunks(c) = &accel.tree else {
                    panic!("{chunk}: not chunked")
                };
                assert_eq!(
                    c.len(),
                    prims
                        .len()
                        .div_ceil(chunk)
                        .next_power_of_two()
                        .min(MAX_CHUNKS)
                );
                accel
            };
            assert_eq!(accel.prims.len(), prims.len());
            let mut s = 12345u64;
            let mut rnd = || {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
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
                    (
                        Some((_, tb)),
                        Some(AccelHit {
                            index: i,
                            t,
                            b1,
                            b2,
                        }),
                    ) => {
                        assert_eq!(t, tb);
                        // The barycentrics are those of the accepted primitive's own test.
                        let (_, eb1, eb2) =
                            accel.prims[i].intersect_bary(o.into(), d.into(), 0.0, f32::INFINITY);
                        assert_eq!((b1, b2), (eb1, eb2));
                        // The returned index is where the hit primitive is stored.
                        let orig = accel.original_index[i] as usize;
                        assert_eq!(
                            format!("{:?}", accel.prims[i]),
                            format!("{:?}", prims[orig])
                        );
                        assert_eq!(
                            prims[orig].intersect(o.into(), d.into(), 0.0, f32::INFINITY),
                            t
                        );
                    }
                    other => panic!("{kind:?} {chunk}: {other:?}"),
                }
                assert_eq!(accel.occluded(&ray), brute.is_some());
            }
        }
    }
}
