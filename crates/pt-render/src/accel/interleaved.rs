//! CWBVH traversal of several rays at once, interleaved: each ray advances one node at a
//! time, in turn, so that the memory loads of different rays' nodes and primitives are
//! independent and the processor overlaps their cache misses. One ray's traversal is a chain
//! of dependent loads (the node decides which node comes next), and a large mesh's nodes and
//! primitives miss the caches: alone, each miss is waited for in turn. This is the software
//! interleaving of independent lookups that Kocberber et al. 2015 ("Asynchronous memory access
//! chaining", VLDB) apply to hash joins, here over BVH traversals.
//!
//! Every ray visits the same nodes and tests the same primitives in the same order as
//! `cw_closest` and `cw_any` (obvhs's `traverse!` loop), so the results are the same bits.

use super::*;
use pt_math::lanes::{set_lanes, Mask};

/// Most rays traversed together (the path tracer's paths in flight).
pub const BATCH: usize = 8;

/// No node chosen.
const NONE: u32 = u32::MAX;

/// One ray's traversal state in a batch: obvhs's `traverse!` state ([`CwTraversal`]) with the
/// node to test next held over to the ray's next turn.
#[derive(Clone, Copy)]
struct Lane {
    ray: BvhRay,
    /// Entries on the ray's stack of node groups still to visit (held apart, [`Stacks`]).
    depth: usize,
    current_group: UVec2,
    primitive_group: UVec2,
    oct_inv4: u32,
    /// The node chosen at the end of the ray's last turn, tested at the start of its next.
    next: u32,
    /// Closest hit so far: its primitive (`NONE` before one) and edge coordinates.
    primitive: u32,
    bary: (f32, f32),
}

/// The rays' stacks of node groups still to visit, one of `N` entries per ray, as obvhs's
/// `StackStack`: a push onto a full stack overwrites its last entry (the tree's depth is
/// checked at build time to stay below `N - 1`, [`fits_small_stack`]). Apart from the lanes'
/// other state, which a batch's set-up copies in: the stacks are only cleared.
type Stacks<const N: usize> = [[UVec2; N]; BATCH];

impl Lane {
    const IDLE: Self = Lane {
        ray: BvhRay {
            origin: Vec3A::ZERO,
            direction: Vec3A::Z,
            inv_direction: Vec3A::ONE,
            tmin: 0.0,
            tmax: 0.0,
        },
        depth: 0,
        current_group: UVec2::ZERO,
        primitive_group: UVec2::ZERO,
        oct_inv4: 0,
        next: NONE,
        primitive: NONE,
        bary: (0.0, 0.0),
    };

    /// The state at the start of `ray`'s traversal of `bvh`, its first node (the root) chosen;
    /// `None` for an empty tree.
    #[inline(always)]
    fn start(bvh: &CwBvh, ray: &Ray) -> Option<Self> {
        if bvh.nodes.is_empty() {
            return None;
        }
        let ray = bvh_ray(ray);
        // As `CwTraversal::new`.
        let oct_inv4 = OCT_INV4[ray.direction.cmplt(Vec3A::ZERO).bitmask() as usize];
        Some(Lane {
            ray,
            current_group: UVec2::new(0, 0x8000_0000),
            oct_inv4,
            ..Self::IDLE
        })
    }

    #[inline(always)]
    fn push<const N: usize>(&mut self, stack: &mut [UVec2; N], group: UVec2) {
        stack[self.depth] = group;
        self.depth = (self.depth + 1).min(N - 1);
    }

    /// Tests the node chosen last turn, if any: its internal children become the current
    /// group, its leaf primitives the primitive group (as `traverse!` after a node test).
    #[inline(always)]
    fn test_node(&mut self, bvh: &CwBvh) {
        if self.next == NONE {
            return;
        }
        let node = &bvh.nodes[self.next as usize];
        let hitmask = intersect_node(node, &self.ray, self.oct_inv4);
        self.current_group = UVec2::new(
            node.child_base_idx,
            (hitmask & 0xff00_0000) | node.imask as u32,
        );
        self.primitive_group = UVec2::new(node.primitive_base_idx, hitmask & 0x00ff_ffff);
        self.next = NONE;
    }

    /// Chooses the node to test next: the nearest child left in the current group, or in the
    /// groups on the stack (as `traverse!`). Returns whether the ray has work left (a node
    /// chosen, or primitives still to test).
    #[inline(always)]
    fn choose_next<const N: usize>(&mut self, stack: &mut [UVec2; N]) -> bool {
        loop {
            let hits_imask = self.current_group.y;
            if hits_imask & 0xff00_0000 != 0 {
                let child_index_offset = 31 - hits_imask.leading_zeros();
                self.current_group.y &= !(1u32 << child_index_offset);
                if self.current_group.y & 0xff00_0000 != 0 {
                    self.push(stack, self.current_group);
                }
                let slot_index = (child_index_offset - 24) ^ (self.oct_inv4 & 0xff);
                let relative_index = (hits_imask & !(0xffff_ffffu32 << slot_index)).count_ones();
                self.next = self.current_group.x + relative_index;
                return true;
            }
            if self.depth == 0 {
                self.current_group = UVec2::ZERO;
                return self.primitive_group.y != 0;
            }
            self.depth -= 1;
            self.current_group = stack[self.depth];
        }
    }

    /// The next primitive of the primitive group (highest bit first, as `traverse!`).
    #[inline(always)]
    fn next_primitive(&mut self) -> Option<u32> {
        let bits = self.primitive_group.y;
        if bits == 0 {
            return None;
        }
        let local = 31 - bits.leading_zeros();
        self.primitive_group.y &= !(1u32 << local);
        Some(self.primitive_group.x + local)
    }
}

/// Sets `lanes` to the start of the traversals of the rays `rays[k]`, `k` in `active`, each
/// with its first node chosen; returns the mask of those with work to do.
#[inline(always)]
fn start_batch<const N: usize>(
    bvh: &CwBvh,
    rays: &[Ray; BATCH],
    active: Mask,
    lanes: &mut [Lane; BATCH],
    stacks: &mut Stacks<N>,
) -> Mask {
    let mut live: Mask = 0;
    for k in set_lanes(active) {
        if let Some(lane) = Lane::start(bvh, &rays[k]) {
            lanes[k] = lane;
            if lanes[k].choose_next(&mut stacks[k]) {
                live |= 1 << k;
            }
        }
    }
    live
}

/// Closest hits of the rays `rays[k]` for `k` in `active`, as [`cw_closest`] gives them, into
/// `out[k]` (the other entries are left as they are). Each turn a ray tests the primitives its
/// last node test found, then the node it chose, then chooses the next.
#[inline(always)]
pub(super) fn cw_closest_batch<const N: usize>(
    bvh: &CwBvh,
    prims: &[Primitive],
    rays: &[Ray; BATCH],
    active: Mask,
    out: &mut [Option<AccelHit>; BATCH],
) {
    let mut lanes = [Lane::IDLE; BATCH];
    let mut stacks: Stacks<N> = [[UVec2::ZERO; N]; BATCH];
    let mut live = start_batch(bvh, rays, active, &mut lanes, &mut stacks);
    while live != 0 {
        for k in set_lanes(live) {
            let l = &mut lanes[k];
            while let Some(id) = l.next_primitive() {
                let r = &l.ray;
                let (t, b1, b2) =
                    prims[id as usize].intersect_bary(r.origin, r.direction, r.tmin, r.tmax);
                if t < l.ray.tmax {
                    l.ray.tmax = t;
                    l.primitive = id;
                    l.bary = (b1, b2);
                }
            }
            l.test_node(bvh);
            if !l.choose_next(&mut stacks[k]) {
                live &= !(1 << k);
            }
        }
    }
    for k in set_lanes(active) {
        let l = &lanes[k];
        out[k] = (l.primitive != NONE).then_some(AccelHit {
            index: l.primitive as usize,
            t: l.ray.tmax,
            b1: l.bary.0,
            b2: l.bary.1,
        });
    }
}

/// Which of the rays `rays[k]`, `k` in `active`, are blocked (as [`cw_any`] finds it): the
/// mask of those. A ray stops at its first blocker.
#[inline(always)]
pub(super) fn cw_any_batch<const N: usize>(
    bvh: &CwBvh,
    prims: &[Primitive],
    rays: &[Ray; BATCH],
    active: Mask,
) -> Mask {
    let mut lanes = [Lane::IDLE; BATCH];
    let mut stacks: Stacks<N> = [[UVec2::ZERO; N]; BATCH];
    let mut live = start_batch(bvh, rays, active, &mut lanes, &mut stacks);
    let mut blocked: Mask = 0;
    while live != 0 {
        'lanes: for k in set_lanes(live) {
            let l = &mut lanes[k];
            while let Some(id) = l.next_primitive() {
                let r = &l.ray;
                if prims[id as usize].intersect(r.origin, r.direction, r.tmin, r.tmax) < r.tmax {
                    blocked |= 1 << k;
                    live &= !(1 << k);
                    continue 'lanes;
                }
            }
            l.test_node(bvh);
            if !l.choose_next(&mut stacks[k]) {
                live &= !(1 << k);
            }
        }
    }
    blocked
}
