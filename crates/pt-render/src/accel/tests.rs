//! Tests of the acceleration structures against brute force and each other.

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
    let w: Vec<u32> = (10..18).collect();
    assert_eq!(gathered(w, &order), v);
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
            (Tree::Wide(x), Tree::Wide(y)) => assert!(x == y),
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
            let hit = accel
                .intersect(&ray)
                .unwrap_or_else(|| panic!("{kind:?} {chunk}: missed the plane from height {h}"));
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

/// 3,000 triangles along the x axis, each 1% farther out and 1% larger than the one before:
/// the builder's tree over them is deep (25 levels) where a uniform grid of the same count
/// has 5.
fn geometric_line() -> Vec<Primitive> {
    (0..3000)
        .map(|k| {
            let x = 1.01f32.powi(k);
            Primitive::Triangle {
                v0: Vec3A::new(x, 0.0, 0.0),
                e1: Vec3A::new(0.01 * x, 0.0, 0.0),
                e2: Vec3A::new(0.0, 0.01 * x, 0.0),
            }
        })
        .collect()
}

#[test]
fn stack_size_follows_the_tree_depth() {
    // The traversal stack holds at most seven entries per level (a node's hit children but
    // the one visited next); obvhs's validation counts depth from 0 at the root.
    for (prims, small) in [(grid(2), true), (grid(8), true), (geometric_line(), false)] {
        let n = prims.len();
        let accel = Accel::build(prims.clone(), BvhKind::CwBvh);
        let Tree::Wide(w) = &accel.tree else {
            panic!("not a CWBVH's tree")
        };
        // The CWBVH it was made from, built again (the build is deterministic).
        let cw = build_cwbvh(
            &prims,
            BvhBuildParams::medium_build(),
            &mut Duration::default(),
        );
        let levels = cw.validate(&accel.prims, true).max_depth as usize + 1;
        assert_eq!(w.stack_need(), 1 + 7 * levels, "{n} primitives");
        assert_eq!(w.stack_need() <= wide::STACK, small, "{n}: {levels} levels");
        // Closest hits through the deep tree agree with a brute-force search: rays from above
        // each 15th triangle's centre, slanted so that they pass over its neighbours.
        if !small {
            for (k, p) in prims.iter().enumerate().step_by(15) {
                let Primitive::Triangle { v0, e1, e2 } = *p else {
                    unreachable!()
                };
                let c = Vec3::from(v0 + (e1 + e2) / 3.0);
                let d = Vec3::new(-0.3, -0.2, -1.0).normalize();
                let o = c - d * (10.0 * e1.length());
                let ray = Ray::new(o, d);
                let brute = prims
                    .iter()
                    .map(|p| p.intersect(o.into(), d.into(), 0.0, f32::INFINITY))
                    .fold(f32::INFINITY, f32::min);
                assert!(brute.is_finite(), "ray {k} misses");
                assert_eq!(
                    accel.intersect(&ray).map_or(f32::INFINITY, |h| h.t),
                    brute,
                    "ray {k}"
                );
                assert!(accel.occluded(&ray), "ray {k}");
            }
        }
    }
}

/// Uniform numbers in [0, 1) from a 64-bit LCG seeded with `seed` (its top 24 bits): the
/// tests' fixed random geometry.
fn uniform_numbers(mut s: u64) -> impl FnMut() -> f32 {
    move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 40) as f32) / (1u64 << 24) as f32
    }
}

#[test]
fn rays_that_overflow_the_stack_are_traced_again() {
    // 2,000 random triangles in a cube and rays across it: a ray enters several children of
    // many nodes, so on a stack of three entries most overflow, and the retry on a stack as
    // deep as the tree needs must give the brute-force search's closest hit and occlusion.
    let mut rnd = uniform_numbers(7);
    let prims: Vec<Primitive> = (0..2000)
        .map(|_| Primitive::Triangle {
            v0: Vec3A::new(rnd(), rnd(), rnd()) * 10.0,
            e1: Vec3A::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5),
            e2: Vec3A::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5),
        })
        .collect();
    let accel = Accel::build(prims.clone(), BvhKind::CwBvh);
    let Tree::Wide(w) = &accel.tree else {
        panic!("not a CWBVH's tree")
    };
    let mut overflows = 0;
    for k in 0..200 {
        let o = Vec3::new(rnd(), rnd(), rnd()) * 10.0;
        let d = Vec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5).normalize();
        let brute = prims
            .iter()
            .map(|p| p.intersect(o.into(), d.into(), 0.0, f32::INFINITY))
            .fold(f32::INFINITY, f32::min);
        let (hit, blocked, overflowed) = w.on_stack_of(&Ray::new(o, d), &accel.prims, 3);
        assert_eq!(hit.map_or(f32::INFINITY, |h| h.t), brute, "ray {k}");
        assert_eq!(blocked, brute.is_finite(), "ray {k}");
        overflows += usize::from(overflowed);
    }
    assert!(
        overflows > 50,
        "{overflows} of 200 rays overflowed: the retry is untested"
    );
}

#[test]
fn flat_blocks_match_the_scalar_tests() {
    // 45 random triangles and parallelograms (six blocks, the last partly empty), two
    // spheres and two cylinders, tested without a tree: each ray's hit must be the scalar tests' nearest (to
    // rounding), and a shadow ray must be blocked exactly when something lies within its
    // interval. A wrong sign or bound in the lanes misses or invents hits here.
    let mut rnd = uniform_numbers(99);
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
        if k % 20 == 3 {
            // Its hit coordinates are the disk's object-space point: checked below.
            prims.push(Primitive::Disk {
                center: v0,
                a: e1,
                b: e2,
            });
        }
        if k % 20 == 13 {
            prims.push(Primitive::Cylinder {
                p0: v0,
                axis: e1.normalize(),
                radius: 0.5,
                length: 2.0,
                flip: false,
            });
        }
    }
    let accel = Accel::build(prims.clone(), BvhKind::Flat);
    let Tree::Flat {
        blocks,
        analytic_from,
    } = &accel.tree
    else {
        panic!("not flat")
    };
    assert_eq!((blocks.len(), *analytic_from), (6, 45));
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
                    Primitive::Disk { center, a, b } => {
                        (center, a.cross(b).normalize().dot(d.into()).abs())
                    }
                    Primitive::Sphere { center: c, .. } | Primitive::Cylinder { p0: c, .. } => {
                        (c, 1.0)
                    }
                    Primitive::SdfVoxel { lo, .. } => (lo.into(), 1.0),
                    Primitive::RoundCone { p0: c, .. } => (c, 1.0),
                    Primitive::BSpline { p, .. } => (p[0].into(), 1.0),
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
                        (accel.prims[h.index].intersect(o.into(), d.into(), ray.tmin, ray.tmax)
                            - t)
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
        Tree::Wide(_)
    ));
    assert!(matches!(
        Accel::build_compact(prims[..FLAT_MAX].to_vec(), BvhKind::Auto, |i| prims[i]).tree,
        Tree::Flat { .. }
    ));
}

#[test]
fn matches_brute_force() {
    let prims = grid(8);
    // The last three: CWBVH in 2, 4 and 8 groups (129 primitives, at most 80, 40 and 16 per
    // group) joined under one root, as large scenes are built.
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
            // One tree whose root joins the groups.
            let Tree::Wide(w) = &accel.tree else {
                panic!("{chunk}: not a CWBVH's tree")
            };
            assert_eq!(
                w.root_internal_children(),
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

#[test]
fn batches_match_single_rays() {
    // A batch of eight rays must give each ray the bits of its own traversal (closest hit:
    // primitive, distance, edge coordinates; any hit), whichever lanes are active, on every
    // tree kind, including grouped CWBVHs (whose rays share one stack, so each must start
    // from an empty one), and scenes too small for a tree (`Flat`) or empty.
    let prims = grid(8);
    let mut accels = vec![
        Accel::build(prims.clone(), BvhKind::CwBvh),
        Accel::build(prims.clone(), BvhKind::Bvh2),
        Accel::build(prims[..20].to_vec(), BvhKind::Auto),
        // Flat with a sphere (tested one by one after the blocks), and with one triangle.
        Accel::build(prims[prims.len() - 21..].to_vec(), BvhKind::Auto),
        Accel::build(prims[5..6].to_vec(), BvhKind::Auto),
        Accel::build(Vec::new(), BvhKind::Auto),
    ];
    for chunk in [80, 16] {
        accels.push(Accel::build_compact_chunked(
            prims.clone(),
            BvhKind::CwBvh,
            |i| prims[i],
            chunk,
        ));
    }
    let mut s = 777u64;
    let mut rnd = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 40) as f32) / (1u64 << 24) as f32
    };
    for accel in &accels {
        for _ in 0..300 {
            let rays: [Ray; BATCH] = std::array::from_fn(|_| {
                let o = Vec3::new(rnd() * 10.0 - 1.0, rnd() * 10.0 - 1.0, rnd() * 8.0 - 2.0);
                let d = Vec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.7).normalize();
                let mut r = Ray::new(o, d);
                // Some segments end early, as shadow rays do.
                if rnd() < 0.3 {
                    r.tmax = rnd() * 6.0;
                }
                r
            });
            let active = (rnd() * 256.0) as Mask;
            let out = [Some(AccelHit {
                index: 7,
                t: -1.0,
                b1: 0.0,
                b2: 0.0,
            }); BATCH];
            let before = out;
            let mut o = out;
            accel.intersect_batch(&rays, active, &mut o);
            let results = [(o, accel.occluded_batch(&rays, active))];
            for (out, blocked) in results {
                for k in 0..BATCH {
                    if active >> k & 1 == 0 {
                        assert_eq!(out[k], before[k], "inactive lanes are left alone");
                        assert_eq!(blocked >> k & 1, 0);
                        continue;
                    }
                    assert_eq!(out[k], accel.intersect(&rays[k]));
                    assert_eq!(blocked >> k & 1 == 1, accel.occluded(&rays[k]));
                }
            }
        }
    }
}
