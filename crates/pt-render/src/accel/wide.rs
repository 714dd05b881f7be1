//! An 8-wide BVH with uncompressed child boxes, converted from obvhs's CWBVH (same tree, same
//! primitive order), and its traversal: nearest child first, popped entries beyond the closest
//! hit skipped.
//!
//! Why a second layout of the same tree: the CWBVH's node (80 bytes; Ylitie et al. 2017) stores
//! its child boxes as bytes on a per-node grid and finds a child's node index by counting the
//! internal children before it. On a processor that traverses one ray at a time, each step of a
//! traversal waits for the previous one (the node test decides which node is loaded next), so
//! the length of that chain is the cost: decoding the planes (widen, convert, scale) and the
//! bit arithmetic that turns a hit mask into a node index are on it. Here a child's box is six
//! floats and its node index a stored word, as in Embree's BVH8 (Wald et al. 2014, "Embree: a
//! kernel framework for efficient CPU ray tracing"): a node test is one multiply-subtract per
//! plane, and the boxes are the exact bounds of what lies below (the CWBVH's are rounded outwards
//! to its grid), so fewer of them are entered.

use super::*;
use glam::Vec4;

/// A child reference with this bit set is a leaf: bits 28-30 hold its primitive count (1-3),
/// the low 28 bits its first primitive.
const LEAF: u32 = 1 << 31;
/// Bit position of a leaf's primitive count in its reference.
const COUNT_SHIFT: u32 = 28;
/// The first primitive's bits of a leaf reference.
const FIRST_MASK: u32 = (1 << COUNT_SHIFT) - 1;

/// One node: up to eight children, each with its box (structure of arrays, so that the eight
/// are tested in SIMD lanes) and its reference. 224 bytes. An empty slot has the inverted box
/// (lower bounds `f32::MAX`, upper `-f32::MAX`), which no ray enters: on every axis its entry
/// distance exceeds its exit distance by `2 f32::MAX |1 / d|` (the inverse direction is finite
/// and nonzero, `bvh_ray`), or the two are NaN, which fails the test as well.
#[derive(Clone, Copy, PartialEq)]
#[repr(C, align(32))]
pub(super) struct WideNode {
    /// The children's boxes, plane by plane (lower x, upper x, lower y, upper y, lower z,
    /// upper z), slot by slot; world units.
    planes: [[f32; 8]; 6],
    /// Per slot: an internal child's node index, or a leaf reference (`LEAF`, count, first
    /// primitive); 0 for an empty slot.
    child: [u32; 8],
}

impl WideNode {
    /// A node without children.
    const EMPTY: Self = WideNode {
        planes: [
            [f32::MAX; 8],
            [-f32::MAX; 8],
            [f32::MAX; 8],
            [-f32::MAX; 8],
            [f32::MAX; 8],
            [-f32::MAX; 8],
        ],
        child: [0; 8],
    };

    /// Sets slot `s`'s box.
    fn set_box(&mut self, s: usize, b: &Aabb) {
        for axis in 0..3 {
            self.planes[2 * axis][s] = b.min[axis];
            self.planes[2 * axis + 1][s] = b.max[axis];
        }
    }

    /// The union of the children's boxes.
    fn bounds(&self) -> Aabb {
        let p = &self.planes;
        let lo = |k: usize| p[k].iter().copied().fold(f32::MAX, f32::min);
        let hi = |k: usize| p[k].iter().copied().fold(-f32::MAX, f32::max);
        Aabb::new(
            Vec3A::new(lo(0), lo(2), lo(4)),
            Vec3A::new(hi(1), hi(3), hi(5)),
        )
    }
}

/// The tree: `nodes[0]` is the root; leaf references index the [`Accel`]'s primitives.
#[derive(PartialEq)]
pub(super) struct WideBvh {
    nodes: Vec<WideNode>,
    /// Most stack entries a traversal can hold: the root's, then at most seven more per level
    /// (a node's hit children but the one visited next).
    stack_need: usize,
}

impl WideBvh {
    /// The tree of `cw` with exact child boxes, computed from `prims` (in the tree's primitive
    /// order, as [`Accel::prims`]): a leaf's box bounds its primitives, an internal child's
    /// bounds its children's boxes. obvhs stores a node's internal children after the node
    /// (`bvh2_to_cwbvh`, and [`merge_groups`] likewise), so one pass from the last node to the
    /// first finds every child's box already made.
    pub(super) fn from_cwbvh(cw: &CwBvh, prims: &[Primitive]) -> Self {
        assert!(
            prims.len() <= FIRST_MASK as usize + 1,
            "more primitives than a leaf reference holds"
        );
        // Leaf boxes (the primitives' bounds, most of the work) in parallel.
        let mut nodes: Vec<WideNode> = cw
            .nodes
            .par_iter()
            .map(|n| {
                let mut out = WideNode::EMPTY;
                for s in (0..8).filter(|&s| !n.is_child_empty(s)) {
                    if n.is_leaf(s) {
                        let (first, count) = n.child_primitives(s);
                        out.child[s] = LEAF | count << COUNT_SHIFT | first;
                        let b = prims[first as usize..(first + count) as usize]
                            .iter()
                            .fold(Aabb::INVALID, |b, p| b.union(&p.aabb()));
                        out.set_box(s, &b);
                    } else {
                        out.child[s] = n.child_node_index(s);
                    }
                }
                out
            })
            .collect();
        // Internal children's boxes and the levels below each node, children first.
        let mut levels = vec![1u32; nodes.len()];
        for i in (0..nodes.len()).rev() {
            for s in 0..8 {
                let c = nodes[i].child[s];
                if c & LEAF == 0 && !cw.nodes[i].is_child_empty(s) {
                    debug_assert!(c as usize > i, "a child stored before its parent");
                    let b = nodes[c as usize].bounds();
                    nodes[i].set_box(s, &b);
                    levels[i] = levels[i].max(levels[c as usize] + 1);
                }
            }
        }
        let stack_need = 1 + 7 * levels.first().copied().unwrap_or(0) as usize;
        WideBvh { nodes, stack_need }
    }
}

/// A ray prepared for node tests: `t = plane * inv - origin_inv` per axis, and which of a
/// child's two planes the ray enters through.
struct WideRay {
    inv: Vec3A,
    origin_inv: Vec3A,
    /// Per axis: the plane the ray enters a box through ([`WideNode::planes`]'s index: the
    /// upper one for a negative direction); it leaves through the other (index ^ 1).
    near: [usize; 3],
    tmin: f32,
}

impl WideRay {
    #[inline(always)]
    fn new(r: &BvhRay) -> Self {
        WideRay {
            inv: r.inv_direction,
            origin_inv: r.origin * r.inv_direction,
            near: [
                usize::from(r.direction.x < 0.0),
                2 + usize::from(r.direction.y < 0.0),
                4 + usize::from(r.direction.z < 0.0),
            ],
            tmin: r.tmin,
        }
    }
}

/// The slots of `node` whose boxes the ray enters within `(tmin, tmax)`, as a bit mask, and the
/// entry distances.
#[inline(always)]
fn test_node(node: &WideNode, ray: &WideRay, tmax: f32) -> (u32, [f32; 8]) {
    let p = &node.planes;
    let [a, b, c] = ray.near;
    // Two halves of four slots in SSE vectors (glam's `Vec4`): written over arrays of eight,
    // the compiler's vectoriser split the far planes into scalar pieces.
    let half = |h: usize| {
        let plane = |k: usize| Vec4::from_slice(&p[k][4 * h..4 * h + 4]);
        let t = |k: usize, inv: f32, oi: f32| plane(k) * inv - Vec4::splat(oi);
        let (i, o) = (ray.inv, ray.origin_inv);
        let near = t(a, i.x, o.x)
            .max(t(b, i.y, o.y))
            .max(t(c, i.z, o.z).max(Vec4::splat(ray.tmin)));
        let far = t(a ^ 1, i.x, o.x)
            .min(t(b ^ 1, i.y, o.y))
            .min(t(c ^ 1, i.z, o.z).min(Vec4::splat(tmax)));
        (near.cmple(far).bitmask(), near)
    };
    let (m0, n0) = half(0);
    let (m1, n1) = half(1);
    let mut near = [0.0f32; 8];
    near[..4].copy_from_slice(&n0.to_array());
    near[4..].copy_from_slice(&n1.to_array());
    (m0 | m1 << 4, near)
}

/// A stack entry: a child reference and the distance at which the ray enters its box.
#[derive(Clone, Copy, Default)]
struct Entry {
    child: u32,
    near: f32,
}

/// Pushes the hit children of `node` so that the nearest is on top; `Err(Overflow)` (and
/// nothing pushed) when the stack has no room for them.
#[inline(always)]
fn push_sorted(
    node: &WideNode,
    mut mask: u32,
    near: &[f32; 8],
    stack: &mut [Entry],
    top: &mut usize,
) -> Result<(), Overflow> {
    if *top + mask.count_ones() as usize > stack.len() {
        return Err(Overflow);
    }
    let base = *top;
    while mask != 0 {
        let s = mask.trailing_zeros() as usize;
        mask &= mask - 1;
        let e = entry(node, s, near);
        // Insertion: entries above `base` are kept in decreasing distance.
        let mut j = *top;
        while j > base && stack[j - 1].near < e.near {
            stack[j] = stack[j - 1];
            j -= 1;
        }
        stack[j] = e;
        *top += 1;
    }
    Ok(())
}

/// A traversal's stack was too small for the tree (see [`stack!`]).
struct Overflow;

/// The entry for slot `s` of `node`.
#[inline(always)]
fn entry(node: &WideNode, s: usize, near: &[f32; 8]) -> Entry {
    Entry {
        child: node.child[s],
        near: near[s],
    }
}

/// The next entry to visit after the node `node` was tested (`mask`, `near`): its only hit child
/// directly, the nearest of several (the others pushed, nearest on top), or else the top of the
/// stack that the ray can still reach (entered before `tmax`); `None` when none is left.
#[inline(always)]
fn next_entry(
    node: &WideNode,
    mask: u32,
    near: &[f32; 8],
    stack: &mut [Entry],
    top: &mut usize,
    tmax: f32,
) -> Result<Option<Entry>, Overflow> {
    if mask != 0 && mask & (mask - 1) == 0 {
        return Ok(Some(entry(node, mask.trailing_zeros() as usize, near)));
    }
    if mask != 0 {
        push_sorted(node, mask, near, stack, top)?;
    }
    Ok(pop(stack, top, tmax))
}

/// The top of the stack that the ray can still reach (entered before `tmax`).
#[inline(always)]
fn pop(stack: &[Entry], top: &mut usize, tmax: f32) -> Option<Entry> {
    while *top > 0 {
        *top -= 1;
        let e = stack[*top];
        if e.near <= tmax {
            return Some(e);
        }
    }
    None
}

/// The entry a traversal of `ray` starts from: the root node, entered at `tmin`.
#[inline(always)]
fn root(ray: &BvhRay) -> Entry {
    Entry {
        child: 0,
        near: ray.tmin,
    }
}

/// A leaf entry's primitives: their range in the tree's primitive order.
#[inline(always)]
fn leaf_range(e: Entry) -> std::ops::Range<usize> {
    let first = (e.child & FIRST_MASK) as usize;
    first..first + (e.child >> COUNT_SHIFT & 7) as usize
}

/// What a traversal does at its leaves: [`Nearest`] keeps the closest hit and shortens the ray
/// to it, [`Blocked`] stops at the first blocker.
trait LeafQuery {
    /// The query for a ray that ends at `tmax`.
    fn new(tmax: f32) -> Self;
    /// Tests the leaf's primitives `prims[range]`; true when the traversal is done.
    fn leaf(&mut self, ray: &BvhRay, prims: &[Primitive], range: std::ops::Range<usize>) -> bool;
    /// Where the ray ends now: boxes entered beyond it are skipped.
    fn tmax(&self) -> f32;
}

/// The closest hit so far, and the ray shortened to it.
struct Nearest {
    tmax: f32,
    best: Option<AccelHit>,
}

impl LeafQuery for Nearest {
    #[inline(always)]
    fn new(tmax: f32) -> Self {
        Nearest { tmax, best: None }
    }

    #[inline(always)]
    fn leaf(&mut self, ray: &BvhRay, prims: &[Primitive], range: std::ops::Range<usize>) -> bool {
        let first = range.start;
        for (k, p) in prims[range].iter().enumerate() {
            let (t, b1, b2) = p.intersect_bary(ray.origin, ray.direction, ray.tmin, self.tmax);
            if t < self.tmax {
                self.tmax = t;
                self.best = Some(AccelHit {
                    index: first + k,
                    t,
                    b1,
                    b2,
                });
            }
        }
        false
    }

    #[inline(always)]
    fn tmax(&self) -> f32 {
        self.tmax
    }
}

/// Whether a blocker was found; the ray keeps its length.
struct Blocked {
    tmax: f32,
    blocked: bool,
}

impl LeafQuery for Blocked {
    #[inline(always)]
    fn new(tmax: f32) -> Self {
        Blocked {
            tmax,
            blocked: false,
        }
    }

    #[inline(always)]
    fn leaf(&mut self, ray: &BvhRay, prims: &[Primitive], range: std::ops::Range<usize>) -> bool {
        // A loop, not `Iterator::any`: the compiler left that call out of line, compiled for
        // the baseline instructions (see `stack!`).
        for p in &prims[range] {
            if p.intersect(ray.origin, ray.direction, ray.tmin, self.tmax) < self.tmax {
                self.blocked = true;
                return true;
            }
        }
        false
    }

    #[inline(always)]
    fn tmax(&self) -> f32 {
        self.tmax
    }
}

/// The query's answer for `ray` through `bvh`, nearest child first, or `Err(Overflow)` if
/// `stack` has no room for a node's hit children (see [`stack!`]).
#[inline(always)]
fn traverse<Q: LeafQuery>(
    bvh: &WideBvh,
    ray: &BvhRay,
    prims: &[Primitive],
    stack: &mut [Entry],
) -> Result<Q, Overflow> {
    let wide = WideRay::new(ray);
    let mut query = Q::new(ray.tmax);
    let mut top = 0;
    let mut current = (!bvh.nodes.is_empty()).then(|| root(ray));
    while let Some(e) = current {
        if e.child & LEAF != 0 {
            current = if query.leaf(ray, prims, leaf_range(e)) {
                None
            } else {
                pop(stack, &mut top, query.tmax())
            };
        } else {
            let node = &bvh.nodes[e.child as usize];
            let tmax = query.tmax();
            let (mask, near) = test_node(node, &wide, tmax);
            current = next_entry(node, mask, &near, stack, &mut top, tmax)?;
        }
    }
    Ok(query)
}

/// The query's answer for `ray` on `stack`, or on a stack as deep as the tree needs if this ray
/// overflows it ([`walk_deep`]): the same answer either way.
#[inline(always)]
fn walk<Q: LeafQuery>(bvh: &WideBvh, ray: BvhRay, prims: &[Primitive], stack: &mut [Entry]) -> Q {
    traverse(bvh, &ray, prims, stack).unwrap_or_else(|_| walk_deep(bvh, ray, prims))
}

/// [`walk`] on a stack from the heap deep enough for any ray in `bvh`: the retry of a ray that
/// overflowed the render loop's stack (rare: a deep tree and a ray that enters many of its
/// boxes). Out of line, so the render loop holds one copy of the traversal.
#[cold]
#[inline(never)]
fn walk_deep<Q: LeafQuery>(bvh: &WideBvh, ray: BvhRay, prims: &[Primitive]) -> Q {
    let mut stack = vec![Entry::default(); bvh.stack_need];
    traverse(bvh, &ray, prims, &mut stack).unwrap_or_else(|_| unreachable!("stack_need"))
}

/// Binds `$stack` to a zeroed traversal stack of [`STACK`] entries on the thread's stack: deep
/// enough for every ray in a tree of up to nine levels, and for all but rare rays in deeper
/// ones, which [`traverse`] reports (`Overflow`, checked before each push) and which are
/// traced again on a stack as deep as the tree needs ([`walk_deep`]).
/// The stack is zeroed once per batch of rays (safe Rust initialises it), so its size is a
/// cost: a stack for the deepest case (2 KB for a tree of 36 levels) cost 15-20% of the rays
/// per second of single-ray queries on a tree of ten levels (`traversal` bench, `mesh-100k`).
/// A macro, not a function taking a closure: the compiler left such closures, which hold the
/// whole traversal, out of line, so they ran compiled for baseline x86-64 instead of inside
/// the render loop's x86-64-v3 code.
macro_rules! stack {
    ($stack:ident) => {
        let mut array = [Entry::default(); STACK];
        let $stack: &mut [Entry] = &mut array;
    };
}

/// Entries of the traversal stack (see [`stack!`]): the bound for trees of up to nine levels
/// (the root's entry, then at most seven more per level).
pub(super) const STACK: usize = 1 + 7 * 9;

impl WideBvh {
    /// Most stack entries a traversal of this tree can hold.
    #[cfg(test)]
    pub(super) fn stack_need(&self) -> usize {
        self.stack_need
    }

    /// The closest hit and occlusion of `ray` as the render loop finds them, but on a stack of
    /// `entries` entries, and whether the closest-hit traversal overflowed it (and so took the
    /// retry on a deep stack).
    #[cfg(test)]
    pub(super) fn on_stack_of(
        &self,
        ray: &Ray,
        prims: &[Primitive],
        entries: usize,
    ) -> (Option<AccelHit>, bool, bool) {
        let mut stack = vec![Entry::default(); entries];
        let r = bvh_ray(ray);
        let overflowed = traverse::<Nearest>(self, &r, prims, &mut stack).is_err();
        let hit = walk::<Nearest>(self, r, prims, &mut stack).best;
        let blocked = walk::<Blocked>(self, r, prims, &mut stack).blocked;
        (hit, blocked, overflowed)
    }

    /// The root's internal children.
    #[cfg(test)]
    pub(super) fn root_internal_children(&self) -> usize {
        self.nodes.first().map_or(0, |n| {
            (0..8)
                .filter(|&s| n.child[s] & LEAF == 0 && n.planes[0][s] <= n.planes[1][s])
                .count()
        })
    }

    /// Closest hits of `rays[k]`, `k` in `active`, into `out[k]` (the other entries are left as
    /// they are), one ray after the other on one stack. (Two rays traversed in turns, a step of
    /// one then a step of the other on two stacks, so that the processor would overlap their
    /// independent chains of cache misses, made `mesh-100k` 11% slower: the turns' bookkeeping
    /// and mispredicted branches cost more than the overlap gained.)
    #[inline(always)]
    pub(super) fn closest_batch(
        &self,
        prims: &[Primitive],
        rays: &[Ray; BATCH],
        active: Mask,
        out: &mut [Option<AccelHit>; BATCH],
    ) {
        stack!(stack);
        for k in set_lanes(active) {
            out[k] = walk::<Nearest>(self, bvh_ray(&rays[k]), prims, stack).best;
        }
    }

    /// The mask of the rays `rays[k]`, `k` in `active`, that are blocked, as
    /// [`WideBvh::closest_batch`].
    #[inline(always)]
    pub(super) fn any_batch(&self, prims: &[Primitive], rays: &[Ray; BATCH], active: Mask) -> Mask {
        stack!(stack);
        // A loop, not `lanes_where`: its closure would hold the whole traversal (see `stack!`).
        let mut blocked: Mask = 0;
        for k in set_lanes(active) {
            if walk::<Blocked>(self, bvh_ray(&rays[k]), prims, stack).blocked {
                blocked |= 1 << k;
            }
        }
        blocked
    }

    /// Closest hit of one ray.
    #[inline(always)]
    pub(super) fn closest(&self, ray: &BvhRay, prims: &[Primitive]) -> Option<AccelHit> {
        stack!(stack);
        walk::<Nearest>(self, *ray, prims, stack).best
    }

    /// Whether anything blocks one ray.
    #[inline(always)]
    pub(super) fn any(&self, ray: &BvhRay, prims: &[Primitive]) -> bool {
        stack!(stack);
        walk::<Blocked>(self, *ray, prims, stack).blocked
    }
}
