use super::*;
use crate::geometry::Primitive;
use pt_scene::CurveBasis;

/// The primitives of a shape's curves (lists of `[x, y, z, r]`), as the scene builds them, with
/// each one's segment index within the shape.
fn primitives(basis: CurveBasis, curves: &[Vec<[f32; 4]>]) -> Vec<(Primitive, u32)> {
    let mut prims = Vec::new();
    let mut segment = 0;
    for c in curves {
        let p = |i: usize| Vec3::new(c[i][0], c[i][1], c[i][2]);
        match basis {
            CurveBasis::Linear => {
                for i in 0..c.len() - 1 {
                    let prim = Primitive::RoundCone {
                        p0: p(i).into(),
                        p1: p(i + 1).into(),
                        r0: c[i][3],
                        r1: c[i + 1][3],
                    };
                    prims.push((prim, segment));
                    segment += 1;
                }
            }
            CurveBasis::BSpline => {
                for i in 0..c.len() - 3 {
                    let cp = [p(i), p(i + 1), p(i + 2), p(i + 3)];
                    let r = [c[i][3], c[i + 1][3], c[i + 2][3], c[i + 3][3]];
                    let whole = std::array::from_fn(|k| cp[k].extend(r[k]));
                    for piece in Piece::split(whole) {
                        let (cp, r) = piece.of(cp, r);
                        prims.push((Primitive::new_bspline(cp, r, piece), segment));
                    }
                    segment += 1;
                }
            }
        }
    }
    prims
}

/// The nearest hit of the ray on any of `prims`: (t, index, curve parameter).
fn nearest(prims: &[(Primitive, u32)], o: Vec3A, d: Vec3A) -> Option<(f32, usize, f32)> {
    let mut best: Option<(f32, usize, f32)> = None;
    for (i, (p, _)) in prims.iter().enumerate() {
        let (t, u, _) = p.intersect_bary(o, d, 0.0, best.map_or(f32::INFINITY, |b| b.0));
        if t.is_finite() {
            best = Some((t, i, u));
        }
    }
    best
}

/// The surface pt reports at a hit (as the scene's interaction computes it).
fn surface(prim: &Primitive, u: f32, p: Vec3, segment: u32, segments: u32) -> CurveHit {
    match *prim {
        Primitive::RoundCone { p0, p1, r0, r1 } => {
            round_cone_hit([p0, p1], [r0, r1], u, p, segment, segments)
        }
        Primitive::BSpline { piece, .. } => {
            let (cp, r) = prim.bspline_segment().unwrap();
            bspline_hit(
                &cp,
                &r,
                u,
                p,
                Piece::from_code(piece).range(),
                segment,
                segments,
            )
        }
        _ => unreachable!(),
    }
}

/// Mitsuba 3.9.1's own hits on its `linearcurve` and `bsplinecurve` (traced by Embree; 1000
/// rays each from around five curves: wavy and tapered, strongly bent, hair-like; written by
/// references/make_curve_hits.py). pt must find the same hits and misses, at the same
/// distance, with the same normal and texture coordinates. What may differ: rays that graze
/// the tube (|cos| < 0.02 at either renderer's hit), where each intersector's rounding decides;
/// and Embree misses rays running within a few degrees of a linear curve's axis into its end
/// sphere (a limitation of its round-cone test), which pt hits: those are told apart by the
/// hit lying on an end sphere of the curve with the ray nearly along the axis.
#[test]
fn matches_mitsuba_hits() {
    let data: serde_json::Value =
        serde_json::from_str(include_str!("../testdata/mitsuba_curves.json")).unwrap();
    for shape in data["shapes"].as_array().unwrap() {
        let basis = match shape["plugin"].as_str().unwrap() {
            "linearcurve" => CurveBasis::Linear,
            _ => CurveBasis::BSpline,
        };
        let curves: Vec<Vec<[f32; 4]>> = serde_json::from_value(shape["curves"].clone()).unwrap();
        let prims = primitives(basis, &curves);
        let segments = prims.last().unwrap().1 + 1;
        let v3 = |v: &serde_json::Value| {
            let a: [f32; 3] = serde_json::from_value(v.clone()).unwrap();
            Vec3::from(a)
        };
        let (mut hits, mut compared, mut excused) = (0, 0, 0);
        let mut bad = Vec::new();
        for ray in shape["rays"].as_array().unwrap() {
            let (o, d) = (v3(&ray["o"]), v3(&ray["d"]));
            let ours = nearest(&prims, o.into(), d.into());
            let theirs = ray["t"].as_f64().map(|t| (t as f32, v3(&ray["n"])));
            match (ours, theirs) {
                (None, None) => {}
                (Some((t, i, u)), Some((t_m, n_m))) => {
                    hits += 1;
                    let h = surface(&prims[i].0, u, o + d * t, prims[i].1, segments);
                    let cos = h.n.dot(d).abs().min(n_m.dot(d).abs());
                    if cos < 0.02 {
                        continue;
                    }
                    compared += 1;
                    let uv_m: [f32; 2] = serde_json::from_value(ray["uv"].clone()).unwrap();
                    let du = (h.uv.x - uv_m[0]).abs();
                    let du = du.min(1.0 - du);
                    let dv = (h.uv.y - uv_m[1]).abs();
                    // Distances to 1e-4 of the ray length plus what a 1e-4 error across the
                    // tube makes along a slanted ray; normals and uv to 2e-3.
                    let t_ok = (t - t_m).abs() <= 1e-4 * t_m + 1e-4 / cos;
                    let n_ok = (h.n - n_m).length() <= 2e-3 / cos.min(0.5) * 0.5;
                    if !(t_ok && n_ok && du <= 2e-3 && dv <= 2e-3) {
                        bad.push(format!(
                            "o {o} d {d}: t {t} vs {t_m}, n {} vs {n_m}, uv {} vs {uv_m:?} (cos {cos})",
                            h.n, h.uv
                        ));
                    }
                }
                (Some((t, i, u)), None) => {
                    let h = surface(&prims[i].0, u, o + d * t, prims[i].1, segments);
                    let along = match prims[i].0 {
                        Primitive::RoundCone { p0, p1, .. } => {
                            Vec3::from(p1 - p0).normalize().dot(d).abs()
                        }
                        _ => 0.0,
                    };
                    let end_sphere = basis == CurveBasis::Linear && (u == 0.0 || u == 1.0);
                    excused += 1;
                    if !(h.n.dot(d).abs() < 0.02 || (end_sphere && along > 0.99)) {
                        bad.push(format!(
                            "o {o} d {d}: pt hits at {t} (n {}), Mitsuba misses",
                            h.n
                        ));
                    }
                }
                (None, Some((t_m, n_m))) => {
                    excused += 1;
                    if n_m.dot(d).abs() >= 0.02 {
                        bad.push(format!(
                            "o {o} d {d}: Mitsuba hits at {t_m} (n {n_m}), pt misses"
                        ));
                    }
                }
            }
        }
        println!(
            "{}: {hits} hits, {compared} compared, {excused} excused",
            shape["name"]
        );
        // The excuses are for rare rays; many would mean they hide a real difference.
        assert!(excused * 50 <= hits && compared * 10 >= hits * 9);
        assert!(
            bad.is_empty(),
            "{}: {} of {hits} hits ({compared} compared) disagree:\n{}",
            shape["name"],
            bad.len(),
            bad[..bad.len().min(20)].join("\n")
        );
    }
}

/// The round cone against closed forms: a capsule of radius 0.5 from (0,0,0) to (2,0,0), and
/// a cone from radius 1 at the origin to 0.5 at (4,0,0), whose profile line
/// `z sin a + q cos a = 1` (sin a = 1/8) puts the surface above z = 2 at
/// q = (1 - 2/8) / cos a, touching the sphere of parameter v = (2 - q tan a) / 4.
#[test]
fn round_cone_closed_forms() {
    let inf = f32::INFINITY;
    let capsule = |o: [f32; 3], d: [f32; 3]| {
        intersect_round_cone(
            Vec3A::from(o),
            Vec3A::from(d).normalize(),
            Vec3A::ZERO,
            Vec3A::new(2.0, 0.0, 0.0),
            0.5,
            0.5,
            0.0,
            inf,
        )
    };
    assert_eq!(capsule([1.0, 0.0, 5.0], [0.0, 0.0, -1.0]), (4.5, 0.5));
    // Into the end spheres along the axis, from either side.
    assert_eq!(capsule([-5.0, 0.0, 0.0], [1.0, 0.0, 0.0]), (4.5, 0.0));
    assert_eq!(capsule([7.0, 0.0, 0.0], [-1.0, 0.0, 0.0]), (4.5, 1.0));
    // From inside: the exit is a back face, culled.
    assert_eq!(capsule([1.0, 0.0, 0.0], [0.0, 0.0, 1.0]).0, inf);
    // Beside it: a miss.
    assert_eq!(capsule([1.0, 0.6, 5.0], [0.0, 0.0, -1.0]).0, inf);
    let (sin_a, cos_a) = (0.125f32, (1.0f32 - 0.125 * 0.125).sqrt());
    let q = 0.75 / cos_a;
    let (t, v) = intersect_round_cone(
        Vec3A::new(2.0, 0.0, 5.0),
        Vec3A::NEG_Z,
        Vec3A::ZERO,
        Vec3A::new(4.0, 0.0, 0.0),
        1.0,
        0.5,
        0.0,
        inf,
    );
    assert!((t - (5.0 - q)).abs() < 1e-6, "{t}");
    assert!((v - (2.0 - q * sin_a / cos_a) / 4.0).abs() < 1e-6, "{v}");
    let h = round_cone_hit(
        [Vec3A::ZERO, Vec3A::new(4.0, 0.0, 0.0)],
        [1.0, 0.5],
        v,
        Vec3::new(2.0, 0.0, 5.0 - t),
        0,
        1,
    );
    assert!(
        (h.n - Vec3::new(sin_a, 0.0, cos_a)).length() < 1e-6,
        "{}",
        h.n
    );
}

/// A small deterministic generator for the tests below.
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32) / (1u64 << 24) as f32
    }
    fn range(&mut self, a: f32, b: f32) -> f32 {
        a + (b - a) * self.next()
    }
    fn vec(&mut self, s: f32) -> Vec3 {
        Vec3::new(self.range(-s, s), self.range(-s, s), self.range(-s, s))
    }
}

/// The largest ratio of the tube's radius to its radius of curvature along the segment
/// (at 101 parameters): beyond 1/2 the circle sweep folds into itself inside a bend.
fn max_fold(cp: &[Vec3A; 4], r: &[f32; 4]) -> f32 {
    (0..=100)
        .map(|i| {
            let e = bspline_eval(cp, r, i as f32 / 100.0);
            e.r * e.dc.cross(e.ddc).length() / e.dc.length().powi(3)
        })
        .fold(0.0f32, f32::max)
}

/// The tessellation of a B-spline tube: `n_u + 1` rings of the circle sweep of `n_around`
/// points each, joined by triangles oriented outwards (ring `i` starts triangle
/// `2 n_around i`).
fn tessellate(cp: &[Vec3A; 4], r: &[f32; 4], n_u: usize, n_around: usize) -> Vec<[Vec3; 3]> {
    let ring = |i: usize| {
        let e = bspline_eval(cp, r, i as f32 / n_u as f32);
        let axis = Vec3::from(e.dc).normalize();
        let (rot, rad) = curve_frame(axis);
        (0..n_around)
            .map(|j| {
                let phi = std::f32::consts::TAU * j as f32 / n_around as f32;
                Vec3::from(e.c) + (rad * phi.cos() + rot * phi.sin()) * e.r
            })
            .collect::<Vec<_>>()
    };
    let rings: Vec<Vec<Vec3>> = (0..=n_u).map(ring).collect();
    let mut tris = Vec::new();
    for i in 0..n_u {
        let mid = Vec3::from(bspline_eval(cp, r, (i as f32 + 0.5) / n_u as f32).c);
        for j in 0..n_around {
            let k = (j + 1) % n_around;
            for t in [
                [rings[i][j], rings[i + 1][j], rings[i + 1][k]],
                [rings[i][j], rings[i + 1][k], rings[i][k]],
            ] {
                let n = (t[1] - t[0]).cross(t[2] - t[0]);
                let out = n.dot((t[0] + t[1] + t[2]) / 3.0 - mid) > 0.0;
                tris.push(if out { t } else { [t[0], t[2], t[1]] });
            }
        }
    }
    tris
}

/// The nearest front face of the tessellation `tris` (of `n_u` rings of `n_around` points)
/// along the ray `o + t d`: its distance, normal and the parameter of its ring.
fn tessellation_hit(
    tris: &[[Vec3; 3]],
    o: Vec3,
    d: Vec3,
    n_u: usize,
    n_around: usize,
) -> Option<(f32, Vec3, f32)> {
    let mut tess: Option<(f32, Vec3, f32)> = None;
    for (k, tri) in tris.iter().enumerate() {
        let (e1, e2) = (tri[1] - tri[0], tri[2] - tri[0]);
        let n = e1.cross(e2).normalize();
        if n.dot(d) >= 0.0 {
            continue;
        }
        let hit = crate::geometry::intersect_triangle(
            o.into(),
            d.into(),
            tri[0].into(),
            e1.into(),
            e2.into(),
            0.0,
            tess.map_or(f32::INFINITY, |h| h.0),
        );
        if let Some((th, _, _)) = hit {
            let ring_u = (k / (2 * n_around)) as f32 / n_u as f32;
            tess = Some((th, n, ring_u));
        }
    }
    tess
}

/// How far the point `x` lies off the tube: its distance from the curve point whose circle
/// plane holds it (the foot, by Newton from the parameter `u`) minus the radius there; with
/// that curve point.
fn off_tube(cp: &[Vec3A; 4], r: &[f32; 4], x: Vec3A, mut u: f32) -> (f32, CurvePoint) {
    for _ in 0..8 {
        let e = bspline_eval(cp, r, u);
        let g = (x - e.c).dot(e.dc);
        let dg = (x - e.c).dot(e.ddc) - e.dc.length_squared();
        u -= g / dg;
    }
    let e = bspline_eval(cp, r, u);
    ((x - e.c).length() - e.r, e)
}

/// The B-spline intersector against a dense tessellation of the same tube (the circle of
/// radius r(u) across c'(u) at 200 values of u, 96 points around; front faces only), over
/// 30 segments from gently to strongly bent with radii varying up to threefold, and 400 rays
/// each aimed at points within 1.5 radii of the curve. Hits and misses must agree, the
/// distances match to what the polygon's error allows (r (1 - cos(pi/96)) = 5e-4 r across the
/// tube, up to 1.4e-3 r on the inner side of the strongest bends, over the cosine along a
/// slanted ray; 3e-3 r / cos is asked: a wrong root would be a radius off), and pt's hit
/// must lie on the exact tube to 1e-4 r (its distance from the centre of the circle through
/// it). Excepted are
/// grazing rays (|cos| < 0.05 at either hit) and rays through the rims of the open ends (within
/// 1% of u = 0 or 1), where the polygon and the circle differ by their rounding.
#[test]
fn bspline_matches_dense_tessellation() {
    let mut rng = Lcg(0x5eed_cafe);
    let (n_u, n_around) = (200usize, 96usize);
    let mut checked = 0;
    let mut missed = Vec::new();
    let mut skipped = 0;
    let mut piece_disagree = Vec::new();
    for case in 0..30 {
        let bend = 0.05 + 0.6 * (case as f32 / 29.0);
        let dir = rng.vec(1.0).normalize();
        let p: [Vec3; 4] = std::array::from_fn(|i| dir * i as f32 + rng.vec(bend));
        let r_base = rng.range(0.05, 0.2);
        let radii: [f32; 4] = std::array::from_fn(|_| r_base * rng.range(0.5, 1.5));
        let prim = Primitive::new_bspline(p, radii, Piece::WHOLE);
        let (cp, r) = prim.bspline_segment().unwrap();
        // Tubes thinner than half their radius of curvature: beyond, the circle sweep folds
        // into itself on the inside of a bend, where no two tube models agree (hair is far
        // thinner than its bends).
        if max_fold(&cp, &r) > 0.5 {
            skipped += 1;
            continue;
        }
        let whole: [pt_math::Vec4; 4] = std::array::from_fn(|k| Vec3::from(cp[k]).extend(r[k]));
        let pieces: Vec<([Vec3A; 4], [f32; 4])> = Piece::split(whole)
            .map(|piece| {
                let (pp, pr) = piece.of(whole.map(|w| w.truncate()), r);
                (pp.map(Vec3A::from), pr)
            })
            .collect();
        let tris = tessellate(&cp, &r, n_u, n_around);
        for _ in 0..400 {
            let u = rng.next();
            let e = bspline_eval(&cp, &r, u);
            let target = Vec3::from(e.c) + rng.vec(1.5 * e.r);
            let d = rng.vec(1.0).normalize();
            let o = target - d * 4.0;
            let (t, u_hit) = intersect_bspline(o.into(), d.into(), &cp, &r, 0.0, f32::INFINITY);
            // The same segment in the pieces the scene builds (short ones, whose first hit
            // and first settled miss end the search) must find the same hit.
            let t_pieces = pieces
                .iter()
                .map(|(pp, pr)| intersect_bspline(o.into(), d.into(), pp, pr, 0.0, f32::INFINITY).0)
                .fold(f32::INFINITY, f32::min);
            let same =
                (t.is_infinite() && t_pieces.is_infinite()) || (t - t_pieces).abs() <= 1e-4 * e.r;
            if !same {
                piece_disagree.push(format!(
                    "case {case}: o {o} d {d}: whole {t}, pieces {t_pieces}"
                ));
            }
            let tess = tessellation_hit(&tris, o, d, n_u, n_around);
            let ours = t.is_finite().then(|| {
                let h = bspline_hit(&cp, &r, u_hit, o + d * t, (0.0, 1.0), 0, 1);
                (t, h.n, u_hit)
            });
            let grazing = |h: Option<(f32, Vec3, f32)>| h.is_some_and(|h| h.1.dot(d).abs() < 0.05);
            let at_rim =
                |h: Option<(f32, Vec3, f32)>| h.is_some_and(|h| !(0.01..=0.99).contains(&h.2));
            if grazing(ours) || grazing(tess) || at_rim(ours) || at_rim(tess) {
                continue;
            }
            checked += 1;
            match (ours, tess) {
                (None, None) => {}
                (Some(a), Some(b)) => {
                    let cos = a.1.dot(d).abs();
                    let (off, e) = off_tube(&cp, &r, Vec3A::from(o + d * a.0), a.2);
                    assert!(
                        off.abs() <= 1e-4 * e.r,
                        "case {case}: {off} off the tube (r {})",
                        e.r
                    );
                    assert!(
                        (a.0 - b.0).abs() <= 3e-3 * e.r / cos + 1e-5,
                        "case {case}: t {} vs tessellation {} (cos {cos}, r {})",
                        a.0,
                        b.0,
                        e.r
                    );
                }
                (a, b) => {
                    let cos = a.or(b).map_or(0.0, |h| h.1.dot(d).abs());
                    missed.push(format!(
                        "case {case}: o {o} d {d}: pt {a:?}, tessellation {b:?} cos {cos}"
                    ));
                }
            }
        }
    }
    assert!(
        missed.is_empty(),
        "{} of {checked}:\n{}",
        missed.len(),
        missed.join("\n")
    );
    assert!(checked > (30 - skipped) * 400 * 8 / 10, "{checked}");
    // Grazing rays may differ between the whole and its pieces (which split it at other
    // places, 2 of 11476 rays here) as between the whole and the tessellation: allow as many as
    // 1 in 1000.
    assert!(
        piece_disagree.len() * 1000 <= checked,
        "{}:\n{}",
        piece_disagree.len(),
        piece_disagree.join("\n")
    );
}

/// Garbage in, no NaN out: curve segments with coincident control points (c' = 0), zero and
/// huge radii, huge coordinates, non-finite values, and rays in every direction (also NaN)
/// give either no hit or a finite distance inside (tmin, tmax) with a parameter in [0, 1].
#[test]
fn curves_fuzzed_give_no_nan() {
    let mut rng = Lcg(42);
    let specials = [0.0, 1e-30, 1e30, f32::NAN, f32::INFINITY, -1.0];
    let pick = |rng: &mut Lcg| {
        if rng.next() < 0.1 {
            specials[(rng.next() * specials.len() as f32) as usize % specials.len()]
        } else {
            rng.range(-2.0, 2.0)
        }
    };
    for _ in 0..200_000 {
        let mut v = || Vec3::new(pick(&mut rng), pick(&mut rng), pick(&mut rng));
        let mut p: [Vec3; 4] = std::array::from_fn(|_| v());
        if rng.next() < 0.2 {
            p[1] = p[0];
            p[2] = p[0];
        }
        let radii: [f32; 4] = std::array::from_fn(|_| pick(&mut rng).abs());
        let o = Vec3::new(pick(&mut rng), pick(&mut rng), pick(&mut rng)) * 3.0;
        let d = Vec3::new(pick(&mut rng), pick(&mut rng), pick(&mut rng)).normalize_or_zero();
        let (tmin, tmax) = (0.0, if rng.next() < 0.5 { f32::INFINITY } else { 3.0 });
        for prim in [
            Primitive::new_bspline(p, radii, Piece::WHOLE),
            Primitive::RoundCone {
                p0: p[0].into(),
                p1: p[1].into(),
                r0: radii[0],
                r1: radii[1],
            },
        ] {
            let (t, u, _) = prim.intersect_bary(o.into(), d.into(), tmin, tmax);
            assert!(
                t == f32::INFINITY || (t > tmin && t < tmax && (0.0..=1.0).contains(&u)),
                "{prim:?} o {o} d {d}: t {t} u {u}"
            );
            let b = prim.aabb();
            assert!(
                !(b.min.is_nan() || b.max.is_nan())
                    || p.iter().any(|x| !x.is_finite())
                    || radii.iter().any(|x| !x.is_finite())
            );
        }
    }
}

/// A piece is the same cubic over its range: its point and radius at t are the segment's at
/// u0 + (u1 - u0) t, its derivative the segment's times (u1 - u0); and the codes round-trip.
#[test]
fn pieces_trace_their_segment() {
    let p = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.3, -0.2),
        Vec3::new(2.0, -0.4, 0.5),
        Vec3::new(3.5, 0.2, 0.1),
    ];
    let r = [0.01, 0.02, 0.015, 0.005];
    let whole: [pt_math::Vec4; 4] = std::array::from_fn(|i| p[i].extend(r[i]));
    let pieces: Vec<Piece> = Piece::split(whole).collect();
    // About 3.6 units of control polygon over 8 radii of 0.02: 16 pieces (the most).
    assert_eq!(pieces.len(), 16);
    let (cp, cr) = (p.map(Vec3A::from), r);
    for piece in pieces {
        assert_eq!(Piece::from_code(piece.code()), piece);
        let (u0, u1) = piece.range();
        let (pp, pr) = piece.of(p, r);
        let pp = pp.map(Vec3A::from);
        for t in [0.0, 0.3, 1.0] {
            let a = bspline_eval(&pp, &pr, t);
            let b = bspline_eval(&cp, &cr, u0 + (u1 - u0) * t);
            assert!((a.c - b.c).length() < 1e-5, "{piece:?} {t}");
            assert!((a.r - b.r).abs() < 1e-6, "{piece:?} {t}");
            assert!((a.dc - b.dc * (u1 - u0)).length() < 1e-4, "{piece:?} {t}");
        }
    }
}
