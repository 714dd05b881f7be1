//! Light selection from a shading point with a light tree (Conty Estevez and Kulla 2018,
//! "Importance Sampling of Many Lights with Adaptive Tree Splitting"): the lights at a finite
//! distance sit in a tree whose nodes bound their lights' positions (a box), emission
//! directions (a cone) and power; from a point, each step down the tree picks a child with
//! probability proportional to its importance, power over squared distance times a bound on
//! the cosine at the emitter. A light's pmf is the product of the choices on its path, which
//! [`LightTree::pmf`] retraces from the bits stored per light.
//!
//! The tree is built binary (median splits) and collapsed into nodes of eight children, whose
//! importances are computed together in SIMD lanes: a step chooses among eight, so 144 lights
//! take three steps, where the binary tree took eight steps of two scalar evaluations each.
//!
//! The importance here leaves out the paper's receiver term (the cosine at the shading point's
//! normal), so that a light's pmf is a function of the point alone: every MIS weight is then
//! computed from the previous path vertex's position, which surfaces and media both have.
//!
//! Distant lights (environment, sun, sky, directional) are not in the tree: they keep the
//! share [`LightSelection::Power`](crate::LightSelection) gives them, and the tree takes the
//! rest. All positions and directions are world space.

use super::{Light, LightShape};
use pt_math::{Distribution1D, Vec3};
use std::f32::consts::PI;

/// What a node (or one light) bounds: where its emitters are, which way they emit, how much.
#[derive(Clone, Copy, Debug)]
struct Bounds {
    /// Box of the emitting points, world space.
    lo: Vec3,
    /// See `lo`.
    hi: Vec3,
    /// Axis of the cone that holds every emitter's normal (unit; arbitrary when `cos_o` is -1).
    axis: Vec3,
    /// cos theta_o: the normals lie within theta_o of `axis` (spheres and point lights emit
    /// everywhere: theta_o = pi). Every emitter here sends light within theta_e = pi / 2 of
    /// its normal (one-sided surfaces; a spot's cone is its normal cone), so theta_e is not
    /// stored.
    cos_o: f32,
    /// Power (W, luminance; [`Light::power`]).
    phi: f32,
}

impl Bounds {
    /// The union of two bounds (the paper's Algorithm 1 for the cones).
    fn union(&self, o: &Bounds) -> Bounds {
        let (axis, cos_o) = cone_union((self.axis, self.cos_o), (o.axis, o.cos_o));
        Bounds {
            lo: self.lo.min(o.lo),
            hi: self.hi.max(o.hi),
            axis,
            cos_o,
            phi: self.phi + o.phi,
        }
    }

    fn centroid(&self) -> Vec3 {
        0.5 * (self.lo + self.hi)
    }

    /// What traversal reads: the same bounds with the centre, radius and cone sine
    /// precomputed.
    fn packed(&self) -> Packed {
        Packed {
            center: self.centroid(),
            r2: 0.25 * (self.hi - self.lo).length_squared(),
            axis: self.axis,
            cos_o: self.cos_o,
            sin_o: (1.0 - self.cos_o * self.cos_o).max(0.0).sqrt(),
            phi: self.phi,
        }
    }
}

/// A node's bounds as a [`WideNode`]'s slot holds them (see [`Bounds`]).
#[derive(Clone, Copy, Debug)]
struct Packed {
    /// Centre of the box.
    center: Vec3,
    /// Squared radius of the box's bounding sphere.
    r2: f32,
    /// Cone axis.
    axis: Vec3,
    /// cos theta_o.
    cos_o: f32,
    /// sin theta_o.
    sin_o: f32,
    /// Power.
    phi: f32,
}

/// The smallest cone (of this construction) holding the cones `a` and `b`, each (unit axis,
/// cos of the half angle): Conty Estevez and Kulla 2018, Algorithm 1.
fn cone_union(a: (Vec3, f32), b: (Vec3, f32)) -> (Vec3, f32) {
    let (wide, narrow) = if a.1 <= b.1 { (a, b) } else { (b, a) };
    let theta_a = wide.1.clamp(-1.0, 1.0).acos();
    let theta_b = narrow.1.clamp(-1.0, 1.0).acos();
    let theta_d = wide.0.dot(narrow.0).clamp(-1.0, 1.0).acos();
    if (theta_d + theta_b + 1e-3).min(PI) <= theta_a {
        return wide;
    }
    // Widened by 1e-3 rad: acos loses precision near +-1 (a dot product rounded by 6e-8
    // there moves the angle by 3.5e-4), and the cone must hold its emitters, or a delta light
    // at its rim would never be chosen where it shines.
    let theta_o = 0.5 * (theta_a + theta_d + theta_b) + 1e-3;
    if theta_o >= PI {
        return (wide.0, -1.0);
    }
    // Turn the wide axis towards the narrow one by theta_o - theta_a.
    let turn = theta_o - theta_a;
    // Nearly opposite axes leave no plane to turn in (what remains of the difference is
    // rounding): every plane through the wide axis then holds the narrow one, so any
    // perpendicular will do.
    let ortho = narrow.0 - wide.0 * wide.0.dot(narrow.0);
    let ortho = if ortho.length_squared() > 1e-6 {
        ortho.normalize()
    } else {
        pt_math::Frame::from_normal(wide.0).s
    };
    let axis = (wide.0 * turn.cos() + ortho * turn.sin()).normalize();
    (axis, theta_o.cos())
}

/// The bounds of a light at a finite distance; `None` for distant lights (and lights with no
/// power).
fn light_bounds(light: &Light, scene_radius: f32) -> Option<Bounds> {
    let phi = light.power(scene_radius);
    if !(phi > 0.0 && phi.is_finite()) {
        return None;
    }
    // Emitters in the box `lo`-`hi` whose normals lie within the cone (`axis`, `cos_o`).
    let one_sided = |lo: Vec3, hi: Vec3, axis: Vec3, cos_o: f32| Bounds {
        lo,
        hi,
        axis,
        cos_o,
        phi,
    };
    // Emitting in every direction: the cone is the whole sphere.
    let everywhere = |lo: Vec3, hi: Vec3| one_sided(lo, hi, Vec3::Z, -1.0);
    Some(match light {
        Light::Area(a) => match &a.shape {
            LightShape::Mesh { tris, .. } => {
                let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
                let mut sum = Vec3::ZERO;
                for t in tris {
                    for (p, n) in t.p.iter().zip(&t.n) {
                        lo = lo.min(*p);
                        hi = hi.max(*p);
                        sum += *n;
                    }
                }
                // The normals' cone about their mean direction (the shading normals, which
                // set the emitting side).
                match sum.try_normalize() {
                    Some(axis) => {
                        let cos_o = tris
                            .iter()
                            .flat_map(|t| t.n)
                            .map(|n| axis.dot(n.normalize_or_zero()))
                            .fold(1.0f32, f32::min);
                        one_sided(lo, hi, axis, cos_o)
                    }
                    None => everywhere(lo, hi),
                }
            }
            &LightShape::Parallelogram { v0, e1, e2, n, .. } => {
                let corners = [v0, v0 + e1, v0 + e2, v0 + e1 + e2];
                let lo = corners.iter().fold(Vec3::INFINITY, |m, p| m.min(*p));
                let hi = corners.iter().fold(Vec3::NEG_INFINITY, |m, p| m.max(*p));
                one_sided(lo, hi, n, 1.0)
            }
            LightShape::Disk(d) => {
                let (lo, hi) = d.bounds();
                one_sided(lo, hi, d.normal, 1.0)
            }
            &LightShape::Sphere { center, radius, .. } => {
                everywhere(center - Vec3::splat(radius), center + Vec3::splat(radius))
            }
            &LightShape::Cylinder {
                p0,
                frame,
                radius,
                length,
                ..
            } => {
                let (lo, hi) = pt_scene::cylinder_bounds(p0, frame.z_axis, radius, length);
                everywhere(lo, hi)
            }
        },
        &Light::Point { position, .. } => everywhere(position, position),
        Light::Spot {
            position,
            frame,
            cone,
            ..
        } => one_sided(*position, *position, frame.n, cone.cos_cutoff),
        Light::Projector(p) => everywhere(p.position, p.position),
        Light::Directional { .. }
        | Light::Sun { .. }
        | Light::Constant { .. }
        | Light::EnvMap(_)
        | Light::SunSky(_) => return None,
    })
}

/// A node of the binary tree that [`LightTree::build`] splits first: its bounds and either
/// two children or one light. Build-time only; traversal reads the [`WideNode`]s made from it.
#[derive(Clone, Debug)]
struct BinaryNode {
    bounds: Packed,
    /// Children (node indices) of an inner node; `[light, u32::MAX]` for a leaf.
    children: [u32; 2],
}

impl BinaryNode {
    fn leaf_light(&self) -> Option<u32> {
        (self.children[1] == u32::MAX).then_some(self.children[0])
    }
}

/// Children per [`WideNode`]: eight `f32` fill one AVX2 register, so one node's importances
/// are evaluated in one pass of vector instructions.
const WIDTH: usize = 8;

/// Bits of a light's trail per level: the child's slot in `0..WIDTH`.
const SLOT_BITS: u32 = 3;

/// Tag of a [`WideNode`] child that is a light (its index in the low bits), not a node.
const LIGHT: u32 = 1 << 31;

/// A node of the tree that traversal reads: up to [`WIDTH`] children's bounds ([`Packed`]) in
/// structure-of-arrays form, so that their importances are computed in SIMD lanes. The binary
/// tree collapsed three levels at a time (as wide BVHs are made from binary ones), so a choice
/// among 144 lights takes three steps instead of eight. Unused slots have no power and are
/// never chosen.
#[derive(Clone, Debug, Default)]
#[repr(C, align(32))]
struct WideNode {
    /// Centre of each child's box, x, y, z per slot.
    center: [[f32; WIDTH]; 3],
    /// Squared radius of the box's bounding sphere.
    r2: [f32; WIDTH],
    /// Cone axis, x, y, z per slot.
    axis: [[f32; WIDTH]; 3],
    /// cos theta_o (-1: emitting everywhere).
    cos_o: [f32; WIDTH],
    /// sin theta_o.
    sin_o: [f32; WIDTH],
    /// Power (0 for an unused slot).
    phi: [f32; WIDTH],
    /// Child node index, or [`LIGHT`] | light index.
    child: [u32; WIDTH],
}

impl WideNode {
    /// The importance of each child's emitters for the point `p`: phi cos(theta') / d^2, where
    /// d is the distance to the box's centre (at least the radius r of the box's bounding
    /// sphere, since the emitters may lie anywhere within it) and theta' = max(0, theta -
    /// theta_o - theta_u), theta the angle between the axis and the direction to `p`, theta_u
    /// the half angle the bounding sphere subtends at `p` (pi inside it); 0 when theta' >=
    /// theta_e = pi / 2: no emitter of the child sends light towards `p` (Conty Estevez and
    /// Kulla 2018, eq. 3 without the receiver's cosine). Angle differences by the sine and
    /// cosine subtraction formulas, without inverse trigonometry. One loop over the slots with
    /// selects instead of branches, so that it compiles to vector instructions.
    #[inline(always)]
    fn importances(&self, p: Vec3) -> [f32; WIDTH] {
        // `if a < b` forms compile to minps/maxps; the NaNs of a point at a box's centre
        // (d = 0) only reach values that the selects below discard.
        let min = |a: f32, b: f32| if a < b { a } else { b };
        let max = |a: f32, b: f32| if a > b { a } else { b };
        let mut out = [0.0; WIDTH];
        for (i, o) in out.iter_mut().enumerate() {
            let to_p = [
                p.x - self.center[0][i],
                p.y - self.center[1][i],
                p.z - self.center[2][i],
            ];
            let d2 = (to_p[0] * to_p[0] + to_p[1] * to_p[1]) + to_p[2] * to_p[2];
            let (r2, cos_o, sin_o) = (self.r2[i], self.cos_o[i], self.sin_o[i]);
            let inv_d = 1.0 / d2.sqrt();
            let axis_dot =
                (self.axis[0][i] * to_p[0] + self.axis[1][i] * to_p[1]) + self.axis[2][i] * to_p[2];
            let cos_w = min(max(axis_dot * inv_d, -1.0), 1.0);
            let sin_w = max(1.0 - cos_w * cos_w, 0.0).sqrt();
            // theta_x = max(0, theta - theta_o).
            let inside = cos_w >= cos_o;
            let cos_x = if inside {
                1.0
            } else {
                cos_w * cos_o + sin_w * sin_o
            };
            let sin_x = if inside {
                0.0
            } else {
                sin_w * cos_o - cos_w * sin_o
            };
            // theta' = max(0, theta_x - theta_u), sin(theta_u) = r / d.
            let sin_u2 = r2 / d2;
            let cos_u = max(1.0 - sin_u2, 0.0).sqrt();
            let cos_t = if cos_x < cos_u {
                cos_x * cos_u + sin_x * sin_u2.sqrt()
            } else {
                1.0
            };
            // Children emitting everywhere, and points inside a child's bounding sphere, see
            // the whole cone.
            let cos_t = if cos_o > -1.0 && d2 > r2 { cos_t } else { 1.0 };
            let imp = self.phi[i] * cos_t / max(max(d2, r2), f32::MIN_POSITIVE);
            *o = if cos_t > 0.0 { imp } else { 0.0 };
        }
        out
    }

    /// The running sums of `imp` (the last is the total), in the one order that both
    /// [`WideNode::choose`] and [`LightTree::pmf`] use, so that they divide by the same bits.
    #[inline(always)]
    fn running_sums(imp: &[f32; WIDTH]) -> [f32; WIDTH] {
        let mut running = [0.0f32; WIDTH];
        let mut sum = 0.0f32;
        for (r, &x) in running.iter_mut().zip(imp) {
            sum += x;
            *r = sum;
        }
        running
    }

    /// The slot that the uniform number `u` (in [0, 1)) chooses among `imp` in proportion to
    /// them, with its probability and `u` rescaled to [0, 1) within the slot's share; `None`
    /// when every importance is 0 (or their sum overflows). The chosen slot's importance is
    /// positive: it is the first whose running sum exceeds `u` times the total.
    #[inline(always)]
    fn choose(imp: &[f32; WIDTH], u: f32) -> Option<(usize, f32, f32)> {
        let running = Self::running_sums(imp);
        let sum = running[WIDTH - 1];
        if !(sum > 0.0 && sum.is_finite()) {
            return None;
        }
        let target = u * sum;
        let mut slot = 0;
        for &r in &running {
            slot += usize::from(r <= target);
        }
        // Rounding can leave `target` at the total: then the last slot with importance.
        if slot == WIDTH {
            slot = imp.iter().rposition(|&x| x > 0.0)?;
        }
        let below = running[slot] - imp[slot];
        let u = ((target - below) / imp[slot]).clamp(0.0, ONE_MINUS_EPSILON);
        Some((slot, imp[slot] / sum, u))
    }
}

/// Light selection from a point: the tree over the lights at a finite distance, and the
/// distant lights' fixed shares.
#[derive(Clone, Debug)]
pub struct LightTree {
    /// Wide nodes, root first (empty when the tree holds one light).
    nodes: Vec<WideNode>,
    /// The tree's light when it holds only one: chosen without a test, as power selection
    /// chooses it.
    only: Option<usize>,
    /// Per light: its path from the root (the slot taken at depth k in bits
    /// `SLOT_BITS * k..`) and its depth, or `None` for lights outside the tree.
    trails: Vec<Option<(u128, u32)>>,
    /// Probability of choosing within the tree (the other lights' shares are fixed).
    tree_share: f32,
    /// Choice among all lights with the tree's lights at weight 0 (`None` when every light
    /// with a share is in the tree).
    others: Option<Distribution1D>,
}

impl LightTree {
    /// The tree over `lights`, with the selection weights `weights` (those of
    /// [`LightSelection::Power`](crate::LightSelection)) giving the lights outside it their
    /// shares and the tree the rest; `None` when no light with power lies at a finite
    /// distance. `scene_radius` as for [`Light::power`].
    pub fn build(lights: &[Light], weights: &[f32], scene_radius: f32) -> Option<LightTree> {
        let bounds: Vec<Option<Bounds>> = lights
            .iter()
            .map(|l| light_bounds(l, scene_radius))
            .collect();
        let total: f32 = weights.iter().sum();
        let tree_weight: f32 = weights
            .iter()
            .zip(&bounds)
            .filter(|(_, b)| b.is_some())
            .map(|(w, _)| w)
            .sum();
        if !(total > 0.0 && tree_weight > 0.0) {
            return None;
        }
        let other_weights: Vec<f32> = weights
            .iter()
            .zip(&bounds)
            .map(|(w, b)| if b.is_some() { 0.0 } else { *w })
            .collect();
        let mut items: Vec<(usize, Bounds)> = bounds
            .iter()
            .enumerate()
            .filter_map(|(i, b)| b.map(|b| (i, b)))
            .collect();
        let mut binary = Vec::with_capacity(2 * items.len());
        split(&mut binary, &mut items);
        let mut tree = LightTree {
            nodes: Vec::with_capacity(binary.len() / (WIDTH - 1) + 1),
            only: binary[0].leaf_light().map(|l| l as usize),
            trails: vec![None; lights.len()],
            tree_share: (tree_weight / total).min(1.0),
            others: Distribution1D::new(&other_weights),
        };
        if tree.only.is_none() {
            tree.widen(&binary, 0, 0, 0);
        }
        Some(tree)
    }

    /// Adds the wide node made from the binary inner node `node` and, below it, those of its
    /// descendants; returns its index. `trail` and `depth` are the wide node's path from the
    /// root. The node's children are found by opening, while there are fewer than
    /// [`WIDTH`], the inner node among them whose bounding sphere is largest (as wide BVHs are
    /// collapsed from binary ones): for the median-split tree, three binary levels.
    fn widen(&mut self, binary: &[BinaryNode], node: u32, depth: u32, trail: u128) -> u32 {
        let mut kids: Vec<u32> = binary[node as usize].children.to_vec();
        while kids.len() < WIDTH {
            let open = kids
                .iter()
                .enumerate()
                .filter(|(_, &k)| binary[k as usize].leaf_light().is_none())
                .max_by(|a, b| {
                    let r2 = |k: &u32| binary[*k as usize].bounds.r2;
                    r2(a.1).total_cmp(&r2(b.1))
                })
                .map(|(j, _)| j);
            let Some(j) = open else { break };
            let [l, r] = binary[kids[j] as usize].children;
            kids[j] = l;
            kids.insert(j + 1, r);
        }
        let at = self.nodes.len() as u32;
        self.nodes.push(WideNode::default());
        assert!(
            (depth + 1) * SLOT_BITS <= u128::BITS,
            "light tree deeper than its trails"
        );
        for (slot, &k) in kids.iter().enumerate() {
            let kid = &binary[k as usize];
            let b = &kid.bounds;
            let trail = trail | (slot as u128) << (SLOT_BITS * depth);
            let child = match kid.leaf_light() {
                Some(light) => {
                    self.trails[light as usize] = Some((trail, depth + 1));
                    LIGHT | light
                }
                None => self.widen(binary, k, depth + 1, trail),
            };
            let w = &mut self.nodes[at as usize];
            for a in 0..3 {
                w.center[a][slot] = b.center[a];
                w.axis[a][slot] = b.axis[a];
            }
            w.r2[slot] = b.r2;
            w.cos_o[slot] = b.cos_o;
            w.sin_o[slot] = b.sin_o;
            w.phi[slot] = b.phi;
            w.child[slot] = child;
        }
        at
    }

    /// Picks a light for the point `p` with the uniform number `u`: (light index, its
    /// probability, `u` rescaled to [0, 1) for the light's own use), or `None` when no light
    /// can be chosen from `p`. Inlined into the render loops (compiled there for their
    /// instruction sets).
    #[inline(always)]
    pub fn sample(&self, p: Vec3, u: f32) -> Option<(usize, f32, f32)> {
        if u >= self.tree_share {
            let u = ((u - self.tree_share) / (1.0 - self.tree_share)).min(ONE_MINUS_EPSILON);
            return self.others.as_ref().map(|d| {
                let (i, pmf, u) = d.sample(u);
                (i, pmf * (1.0 - self.tree_share), u)
            });
        }
        let mut u = (u / self.tree_share).min(ONE_MINUS_EPSILON);
        let mut pmf = self.tree_share;
        if let Some(light) = self.only {
            return Some((light, pmf, u));
        }
        let mut node = &self.nodes[0];
        loop {
            let (slot, prob, rescaled) = WideNode::choose(&node.importances(p), u)?;
            u = rescaled;
            pmf *= prob;
            let child = node.child[slot];
            if child & LIGHT != 0 {
                return Some(((child & !LIGHT) as usize, pmf, u));
            }
            node = &self.nodes[child as usize];
        }
    }

    /// The probability that [`LightTree::sample`] picks light `i` for the point `p`.
    #[inline]
    pub fn pmf(&self, p: Vec3, i: usize) -> f32 {
        let Some(Some((trail, depth))) = self.trails.get(i) else {
            if self.only == Some(i) {
                return self.tree_share;
            }
            return self
                .others
                .as_ref()
                .map_or(0.0, |d| d.pmf(i) * (1.0 - self.tree_share));
        };
        let mut pmf = self.tree_share;
        let mut node = &self.nodes[0];
        for k in 0..*depth {
            let imp = node.importances(p);
            let sum = WideNode::running_sums(&imp)[WIDTH - 1];
            let slot = (trail >> (SLOT_BITS * k)) as usize & (WIDTH - 1);
            if !(sum > 0.0 && sum.is_finite()) || imp[slot] == 0.0 {
                return 0.0;
            }
            pmf *= imp[slot] / sum;
            let child = node.child[slot];
            if child & LIGHT == 0 {
                node = &self.nodes[child as usize];
            }
        }
        pmf
    }
}

/// Builds the binary subtree of `items` into `nodes`; returns its node index. Splits at the
/// median along the widest axis of the centroids.
fn split(nodes: &mut Vec<BinaryNode>, items: &mut [(usize, Bounds)]) -> u32 {
    let at = nodes.len() as u32;
    if let [(light, b)] = items {
        nodes.push(BinaryNode {
            bounds: b.packed(),
            children: [*light as u32, u32::MAX],
        });
        return at;
    }
    let all = items[1..]
        .iter()
        .fold(items[0].1, |acc, (_, b)| acc.union(b));
    nodes.push(BinaryNode {
        bounds: all.packed(),
        children: [0, 0],
    });
    let (lo, hi) = items
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), (_, b)| {
            (lo.min(b.centroid()), hi.max(b.centroid()))
        });
    let axis = (hi - lo).max_position();
    items.sort_by(|a, b| a.1.centroid()[axis].total_cmp(&b.1.centroid()[axis]));
    let mid = items.len() / 2;
    let (left, right) = items.split_at_mut(mid);
    let l = split(nodes, left);
    let r = split(nodes, right);
    nodes[at as usize].children = [l, r];
    at
}

/// The largest float below 1 (rescaled uniform numbers stay in [0, 1)).
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::tests::lcg;
    use crate::light::AreaLight;
    use crate::texture::Texture;

    fn sphere(center: Vec3, radius: f32, radiance: f32) -> Light {
        Light::Area(AreaLight {
            radiance: Texture::rgb([radiance; 3]),
            shape: LightShape::Sphere {
                center,
                radius,
                flip: false,
                frame: pt_math::Mat3::IDENTITY,
            },
            area: 4.0 * PI * radius * radius,
        })
    }

    /// A square light of side 1 at height `y` facing down (its front side towards -y).
    fn ceiling(x: f32, y: f32) -> Light {
        let (e1, e2) = (Vec3::X, Vec3::Z);
        Light::Area(AreaLight {
            radiance: Texture::rgb([5.0; 3]),
            shape: LightShape::Parallelogram {
                v0: Vec3::new(x - 0.5, y, -0.5),
                e1,
                e2,
                n: e1.cross(e2),
                uv: [pt_math::Vec2::ZERO; 3],
            },
            area: 1.0,
        })
    }

    /// Lights of several kinds and powers scattered over a street, and a distant light.
    fn lights() -> Vec<Light> {
        let mut rnd = lcg(3);
        let mut v: Vec<Light> = (0..37)
            .map(|k| {
                let c = Vec3::new(rnd() * 4.0 - 2.0, 2.0 + rnd(), -(k as f32) * 1.5);
                if k % 3 == 0 {
                    ceiling(c.x, c.y)
                } else {
                    sphere(c, 0.05 + 0.1 * rnd(), 1.0 + 20.0 * rnd())
                }
            })
            .collect();
        v.push(Light::Directional {
            to_light: Vec3::Y,
            irradiance: crate::texture::ConstantSpectrum::Rgb(
                pt_spectrum::SampledSpectrum::from_rgb([1.0; 3]),
            ),
        });
        v
    }

    /// The light `t` chooses from `p` with `u`, after checking that the probability it reports
    /// is `pmfs[i]` (what [`LightTree::pmf`] gives) and that its rescaled number is in [0, 1).
    fn checked_sample(t: &LightTree, p: Vec3, u: f32, pmfs: &[f32]) -> usize {
        let (i, pmf, u) = t.sample(p, u).expect("a light");
        assert!(
            (pmf - pmfs[i]).abs() <= 1e-5 * pmfs[i],
            "{pmf} vs {}",
            pmfs[i]
        );
        assert!((0.0..1.0).contains(&u));
        i
    }

    fn tree(lights: &[Light]) -> LightTree {
        let w = vec![1.0; lights.len()];
        LightTree::build(lights, &w, 50.0).expect("a tree")
    }

    /// From points along the street: the pmfs of all lights sum to 1, every sample's
    /// probability is `pmf` of the light it chose, and the frequencies of 200,000 choices
    /// match the pmfs (each within 5 standard deviations of a binomial count, plus one count
    /// for rounding: a pmf that disagreed with the sampler by 1% of a light's share would
    /// fail on the larger shares). The distant light keeps its share 1 / 38 everywhere.
    #[test]
    fn sampling_matches_pmf() {
        let lights = lights();
        let t = tree(&lights);
        let n = 200_000;
        let mut rnd = lcg(17);
        for p in [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.5, -1.0, -20.0),
            Vec3::new(-1.0, 2.5, -40.0),
        ] {
            let pmfs: Vec<f32> = (0..lights.len()).map(|i| t.pmf(p, i)).collect();
            let total: f32 = pmfs.iter().sum();
            assert!((total - 1.0).abs() < 1e-4, "{total}");
            assert!((pmfs[lights.len() - 1] - 1.0 / 38.0).abs() < 1e-6);
            let mut counts = vec![0u32; lights.len()];
            for _ in 0..n {
                counts[checked_sample(&t, p, rnd(), &pmfs)] += 1;
            }
            for (i, (&c, &q)) in counts.iter().zip(&pmfs).enumerate() {
                let mean = q as f64 * n as f64;
                let sd = (mean * (1.0 - q as f64)).sqrt();
                assert!(
                    (c as f64 - mean).abs() <= 5.0 * sd + 1.0,
                    "light {i} at {p}: {c} vs {mean}"
                );
            }
        }
    }

    /// A tree four wide levels deep (3,000 lights of random sizes and powers in a slab): from
    /// points inside and outside it, the pmfs of all lights sum to 1 (to the rounding of 3,000
    /// f32 terms) and every sampled choice reports the probability `pmf` gives its light, so
    /// that the trails address the slots `sample` takes at every level.
    #[test]
    fn deep_trees_are_consistent() {
        let mut rnd = lcg(23);
        let lights: Vec<Light> = (0..3000)
            .map(|_| {
                let c = Vec3::new(rnd() * 40.0, rnd() * 4.0, rnd() * 40.0);
                sphere(c, 0.02 + 0.2 * rnd(), 1.0 + 50.0 * rnd())
            })
            .collect();
        let t = tree(&lights);
        let deepest = t.trails.iter().flatten().map(|&(_, d)| d).max();
        assert!(deepest >= Some(4), "{deepest:?}");
        for p in [
            Vec3::new(20.0, 2.0, 20.0),
            Vec3::new(3.0, 0.5, 37.0),
            Vec3::new(-30.0, 10.0, 60.0),
        ] {
            let pmfs: Vec<f32> = (0..lights.len()).map(|i| t.pmf(p, i)).collect();
            let total: f64 = pmfs.iter().map(|&x| x as f64).sum();
            assert!((total - 1.0).abs() < 1e-3, "{total}");
            for _ in 0..2000 {
                checked_sample(&t, p, rnd(), &pmfs);
            }
        }
    }

    /// The tree prefers near lights: along a street of equal lamps, the lamp overhead gets
    /// more than ten times the share of one 30 m away. And a point above a ceiling light
    /// (behind its emitting side) never chooses it, while a point below may.
    #[test]
    fn near_lights_win_and_back_sides_lose() {
        let street: Vec<Light> = (0..32)
            .map(|k| sphere(Vec3::new(0.0, 3.0, -2.0 * k as f32), 0.1, 10.0))
            .collect();
        let t = tree(&street);
        let p = Vec3::new(0.5, 0.0, 0.0);
        assert!(
            t.pmf(p, 0) > 10.0 * t.pmf(p, 15),
            "{} {}",
            t.pmf(p, 0),
            t.pmf(p, 15)
        );
        let two = [ceiling(0.0, 2.0), ceiling(5.0, 2.0)];
        let t = tree(&two);
        let above = Vec3::new(0.2, 3.0, 0.1);
        assert_eq!(t.pmf(above, 0), 0.0);
        assert!(t.pmf(above, 1) == 0.0 && t.sample(above, 0.3).is_none());
        let below = Vec3::new(0.2, 0.0, 0.1);
        assert!(t.pmf(below, 0) > t.pmf(below, 1) && t.pmf(below, 1) > 0.0);
    }

    /// The union of two cones holds both: directions inside either cone (sampled at random
    /// within each) lie inside the union, for random pairs of axes and angles, including
    /// opposite axes.
    #[test]
    fn cone_union_holds_both_cones() {
        let mut rnd = lcg(5);
        let mut dir = || pt_math::warp::square_to_uniform_sphere(pt_math::Vec2::new(rnd(), rnd()));
        let mut rnd2 = lcg(9);
        for k in 0..2000 {
            let a = (dir(), (rnd2() * 2.0 - 1.0).max(-0.99));
            let b = if k % 100 == 0 {
                (-a.0, 0.9)
            } else {
                (dir(), rnd2() * 2.0 - 1.0)
            };
            let (axis, cos_o) = cone_union(a, b);
            for (c_axis, c_cos) in [a, b] {
                // The cone's rim in eight directions is the extreme of what it holds.
                let f = pt_math::Frame::from_normal(c_axis);
                let sin = (1.0 - c_cos * c_cos).max(0.0).sqrt();
                for j in 0..8 {
                    let phi = j as f32 * PI / 4.0;
                    let d = f.to_world(Vec3::new(sin * phi.cos(), sin * phi.sin(), c_cos));
                    assert!(
                        axis.dot(d) >= cos_o - 1e-4,
                        "{a:?} {b:?} -> {axis} {cos_o}: {}",
                        axis.dot(d)
                    );
                }
            }
        }
    }
}
