//! The acceleration structure: one obvhs BVH over all primitives, kept unaware of materials.
//!
//! Both obvhs layouts are available: the compressed 8-wide CWBVH (Ylitie et al. 2017), whose
//! tree is traversed with its child boxes uncompressed ([`wide`]), and the binary BVH2 built by
//! PLOC. CWBVH is the default; `benches/traversal.rs` compares them. Scenes
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
use obvhs::ploc::PlocBuilder;
use obvhs::ray::{Ray as BvhRay, RayHit};
use obvhs::{Boundable, BvhBuildParams};
use pt_math::{Ray, Vec3A};
use rayon::prelude::*;
use std::time::Duration;

/// Which BVH layout to build.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum BvhKind {
    /// [`BvhKind::Flat`] for scenes of at most [`FLAT_MAX`] primitives (of them at most 8
    /// analytic ones, which are tested one by one), [`BvhKind::CwBvh`] for larger ones
    /// (default).
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
    /// A CWBVH's tree with uncompressed child boxes ([`wide`]).
    Wide(WideBvh),
    Two(Bvh2),
    /// No tree: `prims[..blocks.len() * LANES]` (at most) are the triangles and parallelograms,
    /// also held in `blocks`; the analytic primitives follow them and are tested one by one.
    Flat {
        blocks: Vec<Block>,
        analytic_from: usize,
    },
    Empty,
}

/// Largest number of primitives built as one CWBVH by [`Accel::build_compact`]: above it, the
/// primitives are split into 2, 4 or 8 spatial groups, because obvhs's CWBVH conversion holds
/// 208 bytes per primitive of temporaries (binary nodes and cost table). 2^18 keeps those under
/// 60 MB per group. The groups are built two at a time (rayon) and joined under one root node
/// ([`merge_groups`]).
const CHUNK_PRIMS: usize = 1 << 18;

/// Most groups (the children of the joining root node); larger scenes make larger groups.
const MAX_CHUNKS: usize = 8;

/// A BVH over primitives stored in traversal order.
pub struct Accel {
    tree: Tree,
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
    /// The structures that need no tree: nothing for no primitives, the flat SIMD blocks for
    /// few (see `use_flat`). Gives the primitives back when they need a tree.
    fn without_tree(prims: Vec<Primitive>, kind: BvhKind) -> Result<Self, Vec<Primitive>> {
        if prims.is_empty() {
            Ok(Accel {
                tree: Tree::Empty,
                prims,
                original_index: Vec::new(),
                unit_normals: Vec::new(),
            })
        } else if use_flat(kind, &prims) {
            Ok(Accel::build_flat(prims))
        } else {
            Err(prims)
        }
    }

    /// Builds the BVH. Primitives are reordered; `original_index` maps back.
    ///
    /// Memory: the builder reads the primitives' boxes directly (no array of boxes), and the
    /// primitives are permuted in place afterwards (no second copy).
    pub fn build(prims: Vec<Primitive>, kind: BvhKind) -> Self {
        let mut prims = match Accel::without_tree(prims, kind) {
            Ok(accel) => return accel,
            Err(prims) => prims,
        };
        let params = BvhBuildParams::medium_build();
        let mut t = Duration::default();
        let (tree, order) = match kind {
            BvhKind::CwBvh | BvhKind::Auto | BvhKind::Flat => {
                let bvh = build_cwbvh(&prims, params, &mut t);
                let order = bvh.primitive_indices.clone();
                (Built::Cw(bvh), order)
            }
            BvhKind::Bvh2 => {
                let bvh = build_bvh2(&prims, params, &mut t);
                let order = bvh.primitive_indices.clone();
                (Built::Two(bvh), order)
            }
        };
        permute_in_place(&mut prims, &order);
        Accel {
            tree: tree.finish(&prims),
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
        remake: impl Fn(usize) -> Primitive + Sync,
    ) -> Self {
        Self::build_compact_chunked(prims, kind, remake, CHUNK_PRIMS)
    }

    /// [`Accel::build_compact`] with CWBVH groups of at most `chunk_prims` primitives (as long
    /// as that makes at most [`MAX_CHUNKS`] groups).
    fn build_compact_chunked(
        prims: Vec<Primitive>,
        kind: BvhKind,
        remake: impl Fn(usize) -> Primitive + Sync,
        chunk_prims: usize,
    ) -> Self {
        let prims = match Accel::without_tree(prims, kind) {
            Ok(accel) => return accel,
            Err(prims) => prims,
        };
        let mut boxes: Vec<BuildBox> = Vec::with_capacity(prims.len());
        boxes.extend(prims.iter().map(|p| BuildBox::from(p.aabb())));
        drop(prims);
        let params = BvhBuildParams::medium_build();
        let (tree, order) = match kind {
            BvhKind::CwBvh | BvhKind::Auto | BvhKind::Flat if boxes.len() <= chunk_prims => {
                let bvh = build_cw_low_memory(boxes, &params);
                let order = bvh.primitive_indices.clone();
                (Built::Cw(bvh), order)
            }
            BvhKind::CwBvh | BvhKind::Auto | BvhKind::Flat => {
                let parts = boxes
                    .len()
                    .div_ceil(chunk_prims)
                    .next_power_of_two()
                    .min(MAX_CHUNKS);
                let mut ids: Vec<u32> = (0..boxes.len() as u32).collect();
                split_median(&mut ids, &boxes, parts);
                let size = ids.len().div_ceil(parts);
                let built: Vec<CwBvh> = ids
                    .par_chunks(size)
                    .map(|group| {
                        let group_boxes: Vec<BuildBox> =
                            group.iter().map(|&i| boxes[i as usize]).collect();
                        build_cw_low_memory(group_boxes, &params)
                    })
                    .collect();
                let mut order = Vec::with_capacity(ids.len());
                let mut groups = Vec::with_capacity(parts);
                for (group, bvh) in ids.chunks(size).zip(built) {
                    let base = order.len() as u32;
                    order.extend(bvh.primitive_indices.iter().map(|&k| group[k as usize]));
                    groups.push((bvh, base));
                }
                drop(boxes);
                let bvh = merge_groups(groups, order.clone());
                (Built::Cw(bvh), order)
            }
            BvhKind::Bvh2 => {
                let bvh = build_bvh2(&boxes, params, &mut Duration::default());
                drop(boxes);
                let order = bvh.primitive_indices.clone();
                (Built::Two(bvh), order)
            }
        };
        let mut prims = Vec::with_capacity(order.len());
        order
            .par_iter()
            .map(|&i| remake(i as usize))
            .collect_into_vec(&mut prims);
        Accel {
            tree: tree.finish(&prims),
            prims,
            original_index: order,
            unit_normals: Vec::new(),
        }
    }

    /// The flat "tree" ([`BvhKind::Flat`]): triangles and parallelograms first, in their given
    /// order, copied into SIMD blocks; the analytic primitives (spheres, cylinders) after them.
    fn build_flat(mut prims: Vec<Primitive>) -> Self {
        let mut order: Vec<u32> = (0..prims.len() as u32).collect();
        // Stable: the order within each kind is kept.
        order.sort_by_key(|&i| prims[i as usize].is_analytic());
        permute_in_place(&mut prims, &order);
        let analytic_from = prims
            .iter()
            .position(Primitive::is_analytic)
            .unwrap_or(prims.len());
        let blocks = prims[..analytic_from]
            .chunks(LANES)
            .map(Block::new)
            .collect();
        let unit_normals = prims[..analytic_from]
            .iter()
            .map(|p| match *p {
                Primitive::Triangle { e1, e2, .. } | Primitive::Parallelogram { e1, e2, .. } => {
                    pt_math::Vec3::from(e1.cross(e2)).normalize()
                }
                _ => pt_math::Vec3::ZERO,
            })
            .collect();
        Accel {
            tree: Tree::Flat {
                blocks,
                analytic_from,
            },
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
            analytic_from,
        } = &self.tree
        {
            return flat_closest(blocks, &self.prims[*analytic_from..], *analytic_from, ray);
        }
        let r = bvh_ray(ray);
        let prims = &self.prims;
        match &self.tree {
            Tree::Wide(w) => w.closest(&r, prims),
            Tree::Two(b) => {
                let mut hit = RayHit::none();
                // obvhs accepts a candidate exactly when its distance is below the current
                // `tmax`, so the barycentrics of the last candidate below it are the hit's.
                let mut bary = (0.0, 0.0);
                let found = b.ray_traverse(r, &mut hit, |r: &BvhRay, id: usize| {
                    let (t, b1, b2) =
                        prims[id].intersect_bary(r.origin, r.direction, r.tmin, r.tmax);
                    if t < r.tmax {
                        bary = (b1, b2);
                    }
                    t
                });
                found.then_some(AccelHit {
                    index: hit.primitive_id as usize,
                    t: hit.t,
                    b1: bary.0,
                    b2: bary.1,
                })
            }
            Tree::Flat { .. } => unreachable!("handled above"),
            Tree::Empty => None,
        }
    }

    /// Whether anything blocks the ray within `(tmin, tmax)` (any-hit traversal, stops at the
    /// first blocker).
    #[inline(always)]
    pub fn occluded(&self, ray: &Ray) -> bool {
        if let Tree::Flat {
            blocks,
            analytic_from,
        } = &self.tree
        {
            return flat_any(blocks, &self.prims[*analytic_from..], ray);
        }
        let r = bvh_ray(ray);
        let prims = &self.prims;
        let f = |r: &BvhRay, id: usize| prims[id].intersect(r.origin, r.direction, r.tmin, r.tmax);
        match &self.tree {
            Tree::Wide(w) => w.any(&r, prims),
            Tree::Two(b) => !b.ray_traverse_miss(r, f),
            Tree::Flat { .. } => unreachable!("handled above"),
            Tree::Empty => false,
        }
    }
}

impl Accel {
    /// [`Accel::intersect`] of the rays `rays[k]` for each lane `k` in `active`, into `out[k]`
    /// (other entries are left as they are), the same bits as one by one: the flat structure
    /// tests each primitive against all of them at once (`flat::flat_closest_batch`), a tree
    /// takes them one after the other (a CWBVH's on one traversal stack).
    #[inline(always)]
    pub fn intersect_batch(
        &self,
        rays: &[Ray; BATCH],
        active: Mask,
        out: &mut [Option<AccelHit>; BATCH],
    ) {
        match &self.tree {
            Tree::Wide(w) => w.closest_batch(&self.prims, rays, active, out),
            Tree::Flat {
                blocks,
                analytic_from,
            } => flat_closest_batch(
                blocks,
                &self.prims[*analytic_from..],
                *analytic_from,
                rays,
                active,
                out,
            ),
            _ => {
                for k in set_lanes(active) {
                    out[k] = self.intersect(&rays[k]);
                }
            }
        }
    }

    /// [`Accel::occluded`] of the rays `rays[k]` for each lane `k` in `active`: the mask of
    /// those blocked, found as [`Accel::intersect_batch`] finds closest hits.
    #[inline(always)]
    pub fn occluded_batch(&self, rays: &[Ray; BATCH], active: Mask) -> Mask {
        match &self.tree {
            Tree::Wide(w) => w.any_batch(&self.prims, rays, active),
            Tree::Flat {
                blocks,
                analytic_from,
            } => flat_any_batch(
                blocks,
                &self.prims[*analytic_from..],
                *analytic_from,
                rays,
                active,
            ),
            _ => lanes_where(active, |k| self.occluded(&rays[k])),
        }
    }
}

/// Most rays a batch query ([`Accel::intersect_batch`], [`Accel::occluded_batch`]) takes: the
/// path tracer's paths in flight.
pub const BATCH: usize = 8;

/// The closest hit [`Accel::intersect`] found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AccelHit {
    /// Index into [`Accel::prims`].
    pub index: usize,
    /// Distance along the ray (in units of the ray's direction vector).
    pub t: f32,
    /// Coordinate along the primitive's first edge: a triangle's barycentric weight of
    /// `v0 + e1`, a parallelogram's fraction of `e1`; 0 for spheres and cylinders.
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

/// A tree as built, before traversal's layout is made from it (which needs the primitives in
/// the tree's order).
enum Built {
    Cw(CwBvh),
    Two(Bvh2),
}

impl Built {
    /// The tree traversal uses; `prims` in the tree's primitive order.
    fn finish(self, prims: &[Primitive]) -> Tree {
        match self {
            Built::Cw(b) => Tree::Wide(WideBvh::from_cwbvh(&b, prims)),
            Built::Two(b) => Tree::Two(b),
        }
    }
}

mod cwbvh;
mod flat;
#[cfg(test)]
mod tests;
pub mod top;
mod wide;

use cwbvh::*;
pub(crate) use cwbvh::{gathered, permute_in_place};
use flat::*;
use pt_math::lanes::{lanes_where, set_lanes, Mask};
use wide::*;
