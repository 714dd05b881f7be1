//! The top level of two-level ray tracing (instancing): a binary BVH over the world boxes of
//! instances, whose leaves the caller intersects itself (transforming the ray into the
//! instance's own space and traversing the instanced group's [`super::Accel`]). A thousand
//! instances of one group then cost one copy of its primitives and tree, plus a box and two
//! transforms each.

use super::bvh_ray;
use obvhs::aabb::Aabb;
use obvhs::bvh2::builder::build_bvh2;
use obvhs::bvh2::Bvh2;
use obvhs::ray::RayHit;
use obvhs::BvhBuildParams;
use pt_math::Ray;
use std::time::Duration;

/// A BVH over boxes (the instances' world bounds). Slots are the boxes in traversal order:
/// `order[slot]` is the box's index in the order given to [`TopLevel::build`].
pub struct TopLevel {
    bvh: Bvh2,
    /// For each slot, the index of its box in the order given to [`TopLevel::build`].
    pub order: Vec<u32>,
}

impl TopLevel {
    /// Builds the tree over `boxes` (world space).
    pub fn build(boxes: &[Aabb]) -> TopLevel {
        let mut t = Duration::default();
        let bvh = build_bvh2(boxes, BvhBuildParams::medium_build(), &mut t);
        let order = bvh.primitive_indices.clone();
        TopLevel { bvh, order }
    }

    /// The closest hit along `ray` below `tmax`: `hit(slot, tmax)` intersects the contents of
    /// the box in `slot` and returns the distance of its closest hit below `tmax` (in the
    /// ray's units), or infinity. Returns the slot and distance of the closest.
    #[inline]
    pub fn closest(
        &self,
        ray: &Ray,
        tmax: f32,
        mut hit: impl FnMut(usize, f32) -> f32,
    ) -> Option<(usize, f32)> {
        if self.order.is_empty() {
            return None;
        }
        let mut r = bvh_ray(ray);
        r.tmax = tmax;
        let mut best = RayHit::none();
        self.bvh
            .ray_traverse(r, &mut best, |r, slot| hit(slot, r.tmax))
            .then_some((best.primitive_id as usize, best.t))
    }

    /// Whether the contents of any box block `ray` within (tmin, tmax): `blocks(slot, tmax)`
    /// tests the box in `slot`. Stops at the first blocker.
    #[inline]
    pub fn any(&self, ray: &Ray, mut blocks: impl FnMut(usize, f32) -> bool) -> bool {
        if self.order.is_empty() {
            return false;
        }
        !self.bvh.ray_traverse_miss(bvh_ray(ray), |r, slot| {
            if blocks(slot, r.tmax) {
                0.0
            } else {
                f32::INFINITY
            }
        })
    }
}
