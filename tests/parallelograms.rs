//! Triangle pairs tested as one parallelogram (rectangles, cube faces, quads) must give the
//! same hits as the two triangles: same shape, distance, point, normal, texture coordinates and
//! tangent, also on the shared diagonal's far side, where the parallelogram extrapolates the
//! first triangle's interpolation.
//!
//! The material is an anisotropic rough conductor, whose shading frame follows dp/du, so that
//! hits carry texture coordinates and dp/du (with a plain diffuse material nothing reads them
//! and hits get neither: checked at the end).
//!
//! The scene: the Cornell box's kinds of shapes (rectangles, rotated and scaled cubes, one
//! lifted 1 cm off the floor so that no faces overlap, where either could win) plus a flipped
//! rectangle (reversed winding) and an (analytic) disk. The same description with every triangle given its own vertices ("unwelded":
//! no shared indices, so nothing merges) is the reference. Rays from many points in every
//! direction; where both report a hit, the results must agree to float rounding (1e-5 relative
//! in distance and position, 1e-5 in normal and uv, 1e-4 relative in dp/du); a merged pair that
//! covered a different area (a wrong corner, a trapezoid taken for a parallelogram, the wrong
//! bound in the test) changes which shape is hit or leaves holes, and fails. Both must hit or
//! miss together except within 1e-4 of an edge, where the two tests may round differently.

use pt_math::{Ray, Vec3};
use pt_render::light::{Light, LightShape};
use pt_render::{BvhKind, LightSelection, Scene};
use pt_scene::{Geometry, SceneDesc};
use std::path::Path;

const XML: &str = r#"<scene version="3.0.0">
    <sensor type="perspective"><transform name="to_world"><lookat origin="0,0,4" target="0,0,0" up="0,1,0"/></transform>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
    BSDF
    <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/><translate value="0,-1,0"/></transform><ref id="w"/></shape>
    <shape type="rectangle"><transform name="to_world"><scale value="0.7,0.3,1"/><rotate y="1" angle="33"/><translate value="0.1,0.2,-1"/></transform>
        <boolean name="flip_normals" value="true"/><ref id="w"/></shape>
    <shape type="cube"><transform name="to_world"><scale value="0.3,0.6,0.3"/><rotate y="1" angle="20"/><translate value="-0.35,-0.39,-0.3"/></transform><ref id="w"/></shape>
    <shape type="cube"><transform name="to_world"><scale value="0.3,0.3,0.3"/><rotate x="1" angle="-17"/><translate value="0.33,-0.7,0.3"/></transform><ref id="w"/></shape>
    <shape type="disk"><transform name="to_world"><scale value="0.4"/><rotate x="1" angle="90"/><translate value="0,0.9,0"/></transform><ref id="w"/></shape>
    <shape type="rectangle"><transform name="to_world"><scale value="0.25,0.2,1"/><rotate x="1" angle="90"/><translate value="0,0.98,0"/></transform>
        <ref id="w"/><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>
</scene>"#;

/// The material (in place of `BSDF` in [`XML`]): anisotropic, so its shading frame follows dp/du
/// and hits carry texture coordinates and dp/du.
const ANISOTROPIC: &str = r#"<bsdf type="roughconductor" id="w"><float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.3"/></bsdf>"#;

/// `desc` with every triangle given its own three vertices, so that no two triangles share an
/// index and none are merged.
fn unwelded(desc: &SceneDesc) -> SceneDesc {
    let mut d = desc.clone();
    for s in &mut d.shapes {
        let Geometry::Mesh(m) = &mut s.geometry else {
            continue;
        };
        let order: Vec<u32> = m.indices.iter().flatten().copied().collect();
        fn pick<T: Copy>(v: &[T], order: &[u32]) -> Vec<T> {
            order.iter().map(|&i| v[i as usize]).collect()
        }
        m.positions = pick(&m.positions, &order);
        m.uvs = m.uvs.as_deref().map(|v| pick(v, &order));
        m.normals = m.normals.as_deref().map(|v| pick(v, &order));
        m.tangents = m.tangents.as_deref().map(|v| pick(v, &order));
        m.indices = (0..m.indices.len() as u32)
            .map(|k| [3 * k, 3 * k + 1, 3 * k + 2])
            .collect();
    }
    d
}

#[test]
fn parallelograms_hit_like_their_triangles() {
    let desc = pt_scene::load_str(
        &XML.replace("BSDF", ANISOTROPIC),
        Path::new("parallelograms.xml"),
        Path::new("."),
        &[],
    )
    .unwrap();
    let merged = Scene::build(&desc, BvhKind::default(), LightSelection::Power).unwrap();
    let split = Scene::build(&unwelded(&desc), BvhKind::default(), LightSelection::Power).unwrap();
    // 3 x 2 rectangle triangles, 2 x 12 cube triangles; the disk is analytic.
    assert_eq!(merged.stats.parallelograms, 3 + 12, "{:?}", merged.stats);
    // The rectangle light is sampled as one parallelogram (its sampling is tested in
    // pt-render's light tests), unwelded as two triangles.
    let shape = |s: &Scene| match &s.lights[0] {
        Light::Area(a) => matches!(a.shape, LightShape::Parallelogram { .. }),
        _ => panic!("not an area light"),
    };
    assert!(shape(&merged) && !shape(&split));
    assert_eq!(split.stats.parallelograms, 0);
    assert_eq!(merged.stats.triangles, split.stats.triangles);

    let mut s = 0x2545_f491_4f6c_dd1du64;
    let mut rnd = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 40) as f32 / (1u64 << 24) as f32
    };
    let (mut hits, mut edge) = (0, 0);
    for _ in 0..200_000 {
        let o = Vec3::new(rnd() * 2.4 - 1.2, rnd() * 2.4 - 1.2, rnd() * 2.4 - 1.2);
        let d = Vec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5).normalize();
        let ray = Ray::new(o, d);
        match (merged.intersect(&ray), split.intersect(&ray)) {
            (Some(a), Some(b)) => {
                hits += 1;
                let close =
                    |x: f32, y: f32, tol: f32| (x - y).abs() <= tol * (1.0 + x.abs().max(y.abs()));
                let near = |x: Vec3, y: Vec3, tol: f32| {
                    (x - y).abs().max_element()
                        <= tol * (1.0 + x.abs().max_element().max(y.abs().max_element()))
                };
                if a.shape != b.shape || !close(a.t, b.t, 1e-5) {
                    // Where two shapes meet (a cube's edge against the floor's) either may win.
                    assert!(
                        close(a.t, b.t, 1e-4),
                        "ray {o} {d}: shape {} t {} vs shape {} t {}",
                        a.shape,
                        a.t,
                        b.shape,
                        b.t
                    );
                    edge += 1;
                    continue;
                }
                assert!(near(a.p, b.p, 1e-5), "p {} vs {}", a.p, b.p);
                assert!(near(a.ng, b.ng, 1e-5), "ng {} vs {}", a.ng, b.ng);
                assert!(near(a.ns, b.ns, 1e-5), "ns {} vs {}", a.ns, b.ns);
                assert!(
                    (a.uv - b.uv).abs().max_element() <= 1e-5,
                    "uv {} vs {} at {}",
                    a.uv,
                    b.uv,
                    a.p
                );
                assert!(near(a.dpdu, b.dpdu, 1e-4), "dpdu {} vs {}", a.dpdu, b.dpdu);
            }
            (None, None) => {}
            (a, b) => {
                // Only a ray grazing an outer edge may be caught by one test and not the other.
                let h = a.or(b).unwrap();
                let other = if a.is_some() { &split } else { &merged };
                let nudged = |e: Vec3| other.intersect(&Ray::new(o + e, d)).is_some();
                let shift = 1e-4;
                assert!(
                    [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z]
                        .iter()
                        .any(|&e| nudged(e * shift)),
                    "ray {o} {d}: hit at {} only by {}",
                    h.p,
                    if a.is_some() {
                        "the parallelograms"
                    } else {
                        "the triangles"
                    }
                );
                edge += 1;
            }
        }
    }
    // About a quarter of the rays hit something (the scene is open on most sides: 56,247 with
    // this seed); edge cases are rare.
    assert!(hits > 40_000, "{hits} hits");
    assert!(edge < hits / 1000, "{edge} edge cases in {hits} hits");

    // With a diffuse material nothing reads texture coordinates: hits skip them and dp/du.
    let diffuse = XML.replace("BSDF", r#"<bsdf type="diffuse" id="w"/>"#);
    let desc = pt_scene::load_str(
        &diffuse,
        Path::new("parallelograms.xml"),
        Path::new("."),
        &[],
    )
    .unwrap();
    let plain = Scene::build(&desc, BvhKind::default(), LightSelection::Power).unwrap();
    let floor = plain
        .intersect(&Ray::new(
            Vec3::new(0.9, 0.0, 0.9),
            Vec3::new(0.0, -1.0, 0.0),
        ))
        .expect("the floor");
    assert!(
        (floor.p.y + 1.0).abs() < 1e-5 && floor.dpdu == Vec3::ZERO,
        "{:?}",
        (floor.p, floor.dpdu)
    );
    // The anisotropic material keeps them.
    let floor = merged
        .intersect(&Ray::new(
            Vec3::new(0.9, 0.0, 0.9),
            Vec3::new(0.0, -1.0, 0.0),
        ))
        .expect("the floor");
    assert_ne!(floor.dpdu, Vec3::ZERO);
}
