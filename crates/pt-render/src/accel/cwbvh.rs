//! The CWBVH build (8-wide nodes, Ylitie et al. 2017): obvhs's builder with a lower memory
//! peak, in spatial groups for large meshes. Traversal runs on its tree converted to
//! uncompressed boxes ([`super::wide`]).

use super::*;

/// obvhs's `build_cwbvh` (PLOC, reinsertion, conversion, with `params`) written out so that the
/// boxes are freed once the binary tree is built, before the conversion allocates its cost table.
pub(super) fn build_cw_low_memory(boxes: Vec<BuildBox>, params: &BvhBuildParams) -> CwBvh {
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
pub(super) fn split_median(ids: &mut [u32], boxes: &[BuildBox], parts: usize) {
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
    // Ties broken by index, so the split does not depend on the input order. The keys are
    // gathered first: comparing through `boxes` made every comparison two scattered loads.
    let mut keyed: Vec<(f32, u32)> = ids.iter().map(|&i| (centre(i)[axis], i)).collect();
    keyed.select_nth_unstable_by(mid, |a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    for (id, (_, i)) in ids.iter_mut().zip(keyed) {
        *id = i;
    }
    // The halves are independent: split them in parallel (the result does not depend on it).
    let (left, right) = ids.split_at_mut(mid);
    rayon::join(
        || split_median(left, boxes, parts / 2),
        || split_median(right, boxes, parts / 2),
    );
}

/// One CWBVH over separately built group trees: a new root whose children are the groups'
/// roots (at most eight), with every group's nodes and primitive ranges moved behind it.
/// `groups` holds each tree with the offset of its primitives in the merged primitive order
/// (`order`, which becomes the tree's `primitive_indices`). Traversal then sorts the groups
/// per ray like any node's children, where a loop over the groups' boxes came first: a
/// 5M-triangle mesh in eight groups renders 14% faster so.
///
/// The root is written as obvhs's converter writes a node (Ylitie et al. 2017, sec. 3.1): its
/// box origin `p`, power-of-two scales `e` with `255 e` covering the box, each child's box in
/// units of `e` rounded outwards, and children placed in the slots of the eight ray octants by
/// the greedy assignment of obvhs's `order_children` (each slot's direction against the
/// child's centre), so traversal visits them nearest first.
pub(super) fn merge_groups(groups: Vec<(CwBvh, u32)>, order: Vec<u32>) -> CwBvh {
    assert!(!groups.is_empty() && groups.len() <= 8, "1 to 8 groups");
    let mut bounds = Aabb::empty();
    for (g, _) in &groups {
        bounds = bounds.union(&g.total_aabb);
    }
    let p = bounds.min;
    // The smallest power of two per axis with 255 e >= the extent (obvhs's `DENOM` is 1/255).
    let e = ((bounds.max - bounds.min).max(Vec3A::splat(1e-20)) * (1.0 / 255.0))
        .log2()
        .ceil()
        .exp2();
    let rcp_e = 1.0 / e;
    let mut root = CwBvhNode {
        p: p.into(),
        e: e.to_array().map(|c| (c.to_bits() >> 23) as u8),
        child_base_idx: 1,
        ..Default::default()
    };
    // Slot s looks along (-1)^bit2 x, (-1)^bit1 y, (-1)^bit0 z; the cheapest (child, slot)
    // pair of dot(direction, centre offset) is taken first.
    let centre = bounds.center();
    let direction = |s: usize| {
        Vec3A::new(
            if s & 4 != 0 { -1.0 } else { 1.0 },
            if s & 2 != 0 { -1.0 } else { 1.0 },
            if s & 1 != 0 { -1.0 } else { 1.0 },
        )
    };
    let mut slot_of = [usize::MAX; 8];
    let mut filled = [false; 8];
    for _ in 0..groups.len() {
        let mut best = (f32::INFINITY, usize::MAX, usize::MAX);
        for (c, (g, _)) in groups.iter().enumerate() {
            if slot_of[c] != usize::MAX {
                continue;
            }
            for s in (0..8).filter(|&s| !filled[s]) {
                let cost = direction(s).dot(g.total_aabb.center() - centre);
                if cost < best.0 || best.1 == usize::MAX {
                    best = (cost, c, s);
                }
            }
        }
        slot_of[best.1] = best.2;
        filled[best.2] = true;
    }
    let mut in_slot = [usize::MAX; 8];
    for (c, &s) in slot_of[..groups.len()].iter().enumerate() {
        in_slot[s] = c;
        let b = &groups[c].0.total_aabb;
        let lo = ((b.min - p) * rcp_e)
            .floor()
            .clamp(Vec3A::ZERO, Vec3A::splat(255.0));
        let hi = ((b.max - p) * rcp_e)
            .ceil()
            .clamp(Vec3A::ZERO, Vec3A::splat(255.0));
        root.child_min_x[s] = lo.x as u8;
        root.child_min_y[s] = lo.y as u8;
        root.child_min_z[s] = lo.z as u8;
        root.child_max_x[s] = hi.x as u8;
        root.child_max_y[s] = hi.y as u8;
        root.child_max_z[s] = hi.z as u8;
        root.imask |= 1 << s;
        // An internal child: 001 in the high bits, 24 + slot in the low five.
        root.child_meta[s] = (24 + s as u8) | 0b0010_0000;
    }
    // Node layout: the root, the groups' roots in slot order (a node's internal children are
    // consecutive), then each group's other nodes. A group's node j >= 1 moves to
    // `rest + j - 1`; its primitive ranges move by the group's offset.
    let by_slot: Vec<usize> = in_slot
        .iter()
        .copied()
        .filter(|&c| c != usize::MAX)
        .collect();
    let total: usize = 1 + groups.iter().map(|(g, _)| g.nodes.len()).sum::<usize>();
    let mut nodes = Vec::with_capacity(total);
    nodes.push(root);
    let mut rest = 1 + groups.len() as u32;
    let mut rests = vec![0; groups.len()];
    for &c in &by_slot {
        rests[c] = rest;
        rest += groups[c].0.nodes.len() as u32 - 1;
    }
    let moved = |n: &CwBvhNode, rest: u32, base: u32| CwBvhNode {
        child_base_idx: rest + n.child_base_idx - 1,
        primitive_base_idx: base + n.primitive_base_idx,
        ..*n
    };
    for &c in &by_slot {
        let (g, base) = &groups[c];
        nodes.push(moved(&g.nodes[0], rests[c], *base));
    }
    for &c in &by_slot {
        let (g, base) = &groups[c];
        nodes.extend(g.nodes[1..].iter().map(|n| moved(n, rests[c], *base)));
    }
    debug_assert_eq!(nodes.len(), total);
    CwBvh {
        nodes,
        primitive_indices: order,
        total_aabb: bounds,
        exact_node_aabbs: None,
        uses_spatial_splits: false,
    }
}

/// A primitive's bounds as the BVH builder reads them: 24 bytes (obvhs's `Aabb` has 32, a
/// `Primitive` 64).
#[derive(Clone, Copy)]
pub(super) struct BuildBox {
    pub(super) min: pt_math::Vec3,
    pub(super) max: pt_math::Vec3,
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

/// `v` reordered so that element k is the old `v[order[k]]` (`order` a permutation), into a
/// new array: the loads are independent, so the processor overlaps their cache misses, where
/// following the permutation's cycles in place ([`permute_in_place`]) waits for each miss in
/// turn. For the 12-byte primitive references of a 1M-triangle mesh, after the BVH build
/// (whose temporaries are the memory peak, so the second array does not raise it): the whole
/// load 11% faster (wall 0.893 of the in-place order, 8 runs A/B; peak 137.1 vs 137.8 MiB).
pub(crate) fn gathered<T: Copy>(v: Vec<T>, order: &[u32]) -> Vec<T> {
    assert_eq!(v.len(), order.len());
    order.iter().map(|&i| v[i as usize]).collect()
}

/// Reorders `v` so that `v[k]` becomes the old `v[order[k]]` (`order` a permutation), in place
/// by following cycles; one bit per element marks what is done. For arrays whose copy would
/// raise the memory peak (the primitives themselves); see [`gathered`].
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
