//! Light selection from a shading point with a light tree (Conty Estevez and Kulla 2018,
//! "Importance Sampling of Many Lights with Adaptive Tree Splitting"): the lights at a finite
//! distance sit in a binary tree whose nodes bound their lights' positions (a box), emission
//! directions (a cone) and power; from a point, each step down the tree picks a child with
//! probability proportional to its importance, power over squared distance times a bound on
//! the cosine at the emitter. A light's pmf is the product of the choices on its path, which
//! [`LightTree::pmf`] retraces from the bits stored per light.
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

/// A node's bounds as traversal reads them (see [`Bounds`]).
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

impl Packed {
    /// The importance of these emitters for the point `p` as a fraction (numerator,
    /// denominator), so that comparing two costs no division: phi cos(theta') / d^2, where d is
    /// the distance to the box's centre (at least the radius r of the box's bounding sphere,
    /// since the emitters may lie anywhere within it) and theta' = max(0, theta - theta_o -
    /// theta_u), theta the angle between the axis and the direction to `p`, theta_u the half
    /// angle the bounding sphere subtends at `p` (pi inside it). 0 when theta' >= theta_e = pi / 2:
    /// no emitter in the node sends light towards `p`. Angle differences by the sine and
    /// cosine subtraction formulas, without inverse trigonometry.
    #[inline(always)]
    fn importance(&self, p: Vec3) -> (f32, f32) {
        let r2 = self.r2;
        let to_p = p - self.center;
        let d2 = to_p.length_squared();
        let mut cos_t = 1.0f32;
        if self.cos_o > -1.0 && d2 > r2 {
            let w = to_p / d2.sqrt();
            let (cos_w, sin_w) = cos_sin(self.axis.dot(w));
            // theta_x = max(0, theta - theta_o).
            let (cos_x, sin_x) = if cos_w >= self.cos_o {
                (1.0, 0.0)
            } else {
                (
                    cos_w * self.cos_o + sin_w * self.sin_o,
                    sin_w * self.cos_o - cos_w * self.sin_o,
                )
            };
            // theta' = max(0, theta_x - theta_u), sin(theta_u) = r / d.
            let sin_u2 = r2 / d2;
            let cos_u = (1.0 - sin_u2).max(0.0).sqrt();
            if cos_x < cos_u {
                cos_t = cos_x * cos_u + sin_x * sin_u2.sqrt();
            }
            if cos_t <= 0.0 {
                return (0.0, 1.0);
            }
        }
        (self.phi * cos_t, d2.max(r2).max(f32::MIN_POSITIVE))
    }
}

/// cos and sin of the angle whose cosine is `c` (clamped to [-1, 1]).
#[inline]
fn cos_sin(c: f32) -> (f32, f32) {
    let c = c.clamp(-1.0, 1.0);
    (c, (1.0 - c * c).max(0.0).sqrt())
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

/// A node: its bounds and either two children or one light.
#[derive(Clone, Debug)]
struct Node {
    bounds: Packed,
    /// Children (node indices) of an inner node; `[light, u32::MAX]` for a leaf.
    children: [u32; 2],
}

impl Node {
    fn leaf_light(&self) -> Option<usize> {
        (self.children[1] == u32::MAX).then_some(self.children[0] as usize)
    }
}

/// Light selection from a point: the tree over the lights at a finite distance, and the
/// distant lights' fixed shares.
#[derive(Clone, Debug)]
pub struct LightTree {
    /// Nodes, root first.
    nodes: Vec<Node>,
    /// Per light: its path from the root (bit k: the second child at depth k) and its depth,
    /// or `None` for lights outside the tree.
    trails: Vec<Option<(u64, u32)>>,
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
        let mut tree = LightTree {
            nodes: Vec::with_capacity(2 * items.len()),
            trails: vec![None; lights.len()],
            tree_share: (tree_weight / total).min(1.0),
            others: Distribution1D::new(&other_weights),
        };
        tree.split(&mut items, 0, 0);
        Some(tree)
    }

    /// Builds the subtree of `items` at depth `depth` reached by the path `trail`; returns its
    /// node index. Splits at the median along the widest axis of the centroids (depth stays
    /// below log2(n) + 1, far under the 64 bits of a trail).
    fn split(&mut self, items: &mut [(usize, Bounds)], depth: u32, trail: u64) -> u32 {
        let at = self.nodes.len() as u32;
        if let [(light, b)] = items {
            self.nodes.push(Node {
                bounds: b.packed(),
                children: [*light as u32, u32::MAX],
            });
            self.trails[*light] = Some((trail, depth));
            return at;
        }
        let all = items[1..]
            .iter()
            .fold(items[0].1, |acc, (_, b)| acc.union(b));
        self.nodes.push(Node {
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
        let l = self.split(left, depth + 1, trail);
        let r = self.split(right, depth + 1, trail | (1 << depth));
        self.nodes[at as usize].children = [l, r];
        at
    }

    /// The probabilities of the two children of inner node `node` seen from `p` (0 and 0 when
    /// neither can light it).
    #[inline(always)]
    fn child_probs(&self, node: &Node, p: Vec3) -> (f32, f32) {
        // Two plain calls: `array::map` here was not inlined. a = na / da and b = nb / db,
        // so a / (a + b) = na db / (na db + nb da): one division for both.
        let (na, da) = self.nodes[node.children[0] as usize].bounds.importance(p);
        let (nb, db) = self.nodes[node.children[1] as usize].bounds.importance(p);
        let (a, b) = (na * db, nb * da);
        let sum = a + b;
        if sum > 0.0 && sum.is_finite() {
            let inv = 1.0 / sum;
            (a * inv, b * inv)
        } else {
            (0.0, 0.0)
        }
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
        let mut node = &self.nodes[0];
        loop {
            if let Some(light) = node.leaf_light() {
                // Its importance was weighed at its parent (a tree of one light has no parent
                // and chooses it without a test, as power selection does).
                return Some((light, pmf, u));
            }
            let (pa, pb) = self.child_probs(node, p);
            if pa + pb == 0.0 {
                return None;
            }
            // Selects rather than branches: which child is taken is a coin flip per level.
            let second = u >= pa;
            let (prob, below) = if second { (pb, pa) } else { (pa, 0.0) };
            u = ((u - below) / prob).min(ONE_MINUS_EPSILON);
            pmf *= prob;
            node = &self.nodes[node.children[usize::from(second)] as usize];
        }
    }

    /// The probability that [`LightTree::sample`] picks light `i` for the point `p`.
    #[inline]
    pub fn pmf(&self, p: Vec3, i: usize) -> f32 {
        let Some(Some((trail, depth))) = self.trails.get(i) else {
            return self
                .others
                .as_ref()
                .map_or(0.0, |d| d.pmf(i) * (1.0 - self.tree_share));
        };
        let mut pmf = self.tree_share;
        let mut node = &self.nodes[0];
        for k in 0..*depth {
            let (pa, pb) = self.child_probs(node, p);
            let second = trail >> k & 1 == 1;
            pmf *= if second { pb } else { pa };
            if pmf == 0.0 {
                return 0.0;
            }
            node = &self.nodes[node.children[usize::from(second)] as usize];
        }
        pmf
    }
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
                let (i, pmf, u) = t.sample(p, rnd()).expect("a light");
                assert!(
                    (pmf - pmfs[i]).abs() <= 1e-5 * pmfs[i],
                    "{pmf} vs {}",
                    pmfs[i]
                );
                assert!((0.0..1.0).contains(&u));
                counts[i] += 1;
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
