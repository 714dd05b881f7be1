//! glTF reader tests: small documents built in memory (one triangle plus what a test adds),
//! the assets in `scenes/gltf/`, and `<shape type="gltf">` in an XML scene.

use super::*;
use crate::ir::*;
use base64::Engine as _;
use glam::{Vec2, Vec3, Vec4};
use serde_json::{json, Value};
use std::sync::Arc;

/// glTF's component types.
const U8: u32 = 5121;
const U16: u32 = 5123;
const F32: u32 = 5126;

/// A glTF document under construction: its JSON and the bytes of its one buffer.
struct Doc {
    json: Value,
    bin: Vec<u8>,
}

impl Doc {
    /// One triangle (0,0,0), (1,0,0), (0,1,0) with normals +z: mesh 0 at node 0 of scene 0.
    fn triangle() -> Doc {
        let mut d = Doc {
            json: json!({
                "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
                "nodes": [{"mesh": 0}], "meshes": [{"primitives": [{"attributes": {}}]}],
                "bufferViews": [], "accessors": []
            }),
            bin: Vec::new(),
        };
        let p = d.floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0], "VEC3");
        d.json["accessors"][p]["min"] = json!([0, 0, 0]);
        d.json["accessors"][p]["max"] = json!([1, 1, 0]);
        let n = d.floats(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0], "VEC3");
        d.prim()["attributes"] = json!({"POSITION": p, "NORMAL": n});
        d
    }

    /// Appends `bytes` as a buffer view with an accessor over it; returns the accessor.
    fn accessor(&mut self, bytes: &[u8], component: u32, ty: &str, count: usize) -> usize {
        while self.bin.len() % 4 != 0 {
            self.bin.push(0);
        }
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        let views = self.json["bufferViews"].as_array_mut().unwrap();
        views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": bytes.len()}));
        let view = views.len() - 1;
        let accessors = self.json["accessors"].as_array_mut().unwrap();
        let normalized = component != F32;
        accessors.push(
            json!({"bufferView": view, "componentType": component, "count": count,
                              "type": ty, "normalized": normalized}),
        );
        accessors.len() - 1
    }

    /// Appends float data of type `ty` (`VEC2`, ...); returns the accessor.
    fn floats(&mut self, v: &[f32], ty: &str) -> usize {
        let per = match ty {
            "SCALAR" => 1,
            "VEC2" => 2,
            "VEC3" => 3,
            _ => 4,
        };
        let bytes: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
        self.accessor(&bytes, F32, ty, v.len() / per)
    }

    /// The triangle's primitive.
    fn prim(&mut self) -> &mut Value {
        &mut self.json["meshes"][0]["primitives"][0]
    }

    /// Gives the triangle the uvs (0,0), (1,0), (0,1).
    fn with_uvs(&mut self) {
        let uv = self.floats(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0], "VEC2");
        self.prim()["attributes"]["TEXCOORD_0"] = json!(uv);
    }

    /// Makes `material` the triangle's material, with textures `i` = image `images[i]`
    /// (`tex{i}.png` beside the file, never read) and sampler `samplers[i]` where given.
    fn with_material(&mut self, material: Value, textures: usize, samplers: Value) {
        self.json["materials"] = json!([material]);
        self.prim()["material"] = json!(0);
        let has_samplers = samplers.as_array().is_some_and(|s| !s.is_empty());
        self.json["textures"] = (0..textures)
            .map(|i| match has_samplers {
                true => json!({"source": i, "sampler": i}),
                false => json!({"source": i}),
            })
            .collect();
        self.json["images"] = (0..textures)
            .map(|i| json!({"uri": format!("tex{i}.png")}))
            .collect();
        if has_samplers {
            self.json["samplers"] = samplers;
        }
    }

    /// The file: the JSON with the buffer as a `data:` URI.
    fn bytes(&self) -> Vec<u8> {
        let mut j = self.json.clone();
        let b64 = base64::engine::general_purpose::STANDARD.encode(&self.bin);
        j["buffers"] = json!([{"byteLength": self.bin.len(),
                               "uri": format!("data:application/octet-stream;base64,{b64}")}]);
        serde_json::to_vec(&j).unwrap()
    }

    fn try_load(&self, opts: &LoadOptions) -> Result<GltfScene, GltfError> {
        load_slice(&self.bytes(), Path::new("dir/t.gltf"), opts)
    }

    fn load(&self) -> GltfScene {
        self.try_load(&LoadOptions::default())
            .unwrap_or_else(|e| panic!("{e}"))
    }

    fn error(&self) -> String {
        match self.try_load(&LoadOptions::default()) {
            Ok(_) => panic!("loaded but should not have"),
            Err(e) => e.to_string(),
        }
    }
}

fn mesh(g: &GltfScene) -> &TriangleMesh {
    match &g.desc.shapes[0].geometry {
        Geometry::Mesh(m) => m,
        _ => unreachable!("a glTF shape is a mesh"),
    }
}

/// The BSDF of the first shape.
fn bsdf(g: &GltfScene) -> &BsdfKind {
    &g.desc.bsdfs[g.desc.shapes[0].bsdf].kind
}

/// The model inside the wrappers (two-sided, mask, normal map).
fn core(kind: &BsdfKind) -> &BsdfKind {
    match kind {
        BsdfKind::TwoSided { inner }
        | BsdfKind::Mask { inner, .. }
        | BsdfKind::NormalMap { inner, .. } => core(&inner.kind),
        k => k,
    }
}

/// The parts of a `TextureDesc::Scaled` over a bitmap.
fn scaled_bitmap(t: &TextureDesc) -> (&BitmapDesc, Option<TextureChannel>, [f32; 3], f32) {
    match t {
        TextureDesc::Scaled(s) => match &s.inner {
            TextureDesc::Bitmap(b) => (b, s.channel, s.scale, s.offset),
            other => panic!("scaled {other:?}"),
        },
        other => panic!("not scaled: {other:?}"),
    }
}

fn close(a: &[f32], b: &[f32]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-5)
}

#[test]
fn mirrored_node_keeps_front_side_with_the_normals() {
    // A scale of -1 in x mirrors the triangle: the winding must be reversed so that the
    // geometric normal (p1 - p0) x (p2 - p0) still points along the (transformed) vertex
    // normal, +z.
    for flipped in [false, true] {
        let mut d = Doc::triangle();
        if flipped {
            d.json["nodes"][0]["scale"] = json!([-1, 1, 1]);
        }
        let g = d.load();
        let m = mesh(&g);
        let [a, b, c] = m.indices[0].map(|i| m.positions[i as usize]);
        let ng = (b - a).cross(c - a);
        assert!(ng.z > 0.0, "flipped {flipped}: geometric normal {ng}");
        assert!(m
            .normals
            .as_ref()
            .unwrap()
            .iter()
            .all(|n| (n.z - 1.0).abs() < 1e-6));
        assert_eq!(m.positions[1].x, if flipped { -1.0 } else { 1.0 });
    }
}

#[test]
fn default_camera_frames_the_bounds_and_default_light_is_announced() {
    let g = Doc::triangle().load();
    // Bounds: box (0,0,0)-(1,1,0), centre (0.5, 0.5, 0), radius sqrt(2)/2.
    let eye = g.desc.camera.to_world.transform_point3(Vec3::ZERO);
    let look = g
        .desc
        .camera
        .to_world
        .transform_vector3(Vec3::Z)
        .normalize();
    let r = 0.5f32 * 2f32.sqrt();
    let dist = 1.1 * r / (0.5 * DEFAULT_FOV_Y_DEG.to_radians()).sin();
    assert!(
        (eye - Vec3::new(0.5, 0.5, dist)).length() < 1e-5,
        "eye {eye}"
    );
    assert!((look - Vec3::NEG_Z).length() < 1e-6, "looks along {look}");
    // Mitsuba camera space: +x is image left, so world +x (glTF right) must map to camera -x.
    assert!(g.desc.camera.to_world.transform_vector3(Vec3::X).x < 0.0);
    assert!(g.warnings.iter().any(|w| w.contains("default camera")));
    assert!(g.warnings.iter().any(|w| w.contains("default environment")));
    assert!(matches!(g.desc.lights[0].kind, LightKind::Constant { .. }));
}

#[test]
fn camera_node_axes_and_choice() {
    // Camera node at (0, 0, 5) with no rotation: looks down -z, image right is +x.
    let mut d = Doc::triangle();
    d.json["cameras"] = json!([
        {"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}},
        {"type": "orthographic", "orthographic": {"xmag": 1, "ymag": 1, "znear": 0.1, "zfar": 10}}
    ]);
    d.json["nodes"] = json!([
        {"mesh": 0, "children": [1, 2]},
        {"camera": 0, "translation": [0, 0, 5]},
        {"camera": 1}
    ]);
    let g = d.load();
    let c = &g.desc.camera;
    assert!((c.to_world.transform_point3(Vec3::ZERO) - Vec3::new(0.0, 0.0, 5.0)).length() < 1e-6);
    assert!((c.to_world.transform_vector3(Vec3::Z) - Vec3::NEG_Z).length() < 1e-6);
    assert!(
        matches!(c.projection, Projection::Perspective { fov_deg, fov_axis: FovAxis::Y } if (fov_deg - 0.5f32.to_degrees()).abs() < 1e-4)
    );
    let e = d.try_load(&LoadOptions { camera: Some(1) }).unwrap_err();
    assert!(e.message.contains("orthographic"), "{e}");
    let e = d.try_load(&LoadOptions { camera: Some(2) }).unwrap_err();
    assert!(e.message.contains("2 camera(s)"), "{e}");
}

/// Base colour = factor x sRGB texels, metallic = factor x blue and roughness = factor x green
/// of the raw metallic-roughness texels; the sampler's filter and KHR_texture_transform go
/// with each bitmap.
#[test]
fn metallic_roughness_textures_scale_their_factors() {
    let mut d = Doc::triangle();
    d.json["extensionsUsed"] = json!(["KHR_texture_transform"]);
    d.with_material(
        json!({"name": "m", "pbrMetallicRoughness": {
            "baseColorFactor": [0.5, 0.25, 1.0, 1.0], "metallicFactor": 0.8, "roughnessFactor": 0.6,
            "baseColorTexture": {"index": 0, "extensions": {"KHR_texture_transform":
                {"offset": [0.5, 0.0], "scale": [2.0, 3.0]}}},
            "metallicRoughnessTexture": {"index": 1}}}),
        2,
        json!([{"magFilter": 9728}, {}]),
    );
    let g = d.load();
    let BsdfKind::TwoSided { inner } = bsdf(&g) else {
        panic!("{:?}", bsdf(&g))
    };
    let BsdfKind::GltfPbr {
        base_color,
        metallic,
        roughness,
        ior,
    } = &inner.kind
    else {
        panic!("{inner:?}")
    };
    assert_eq!(*ior, 1.5);
    let (b, ch, scale, offset) = scaled_bitmap(base_color);
    assert_eq!((ch, scale, offset), (None, [0.5, 0.25, 1.0], 0.0));
    assert!(!b.raw);
    assert_eq!(b.filter, BitmapFilter::Nearest);
    assert_eq!(b.wrap, WrapMode::Repeat);
    assert_eq!(b.to_uv, [2.0, 0.0, 0.5, 0.0, 3.0, 0.0]);
    assert_eq!(
        b.source,
        ImageSource::File(Path::new("dir/tex0.png").into())
    );
    assert!(
        b.loc
            .element
            .contains("materials[0] 'm' baseColorTexture (textures[0])"),
        "{}",
        b.loc
    );
    for (t, want_ch, factor) in [
        (metallic, TextureChannel::Blue, 0.8),
        (roughness, TextureChannel::Green, 0.6),
    ] {
        let (b, ch, scale, offset) = scaled_bitmap(t);
        assert_eq!((ch, scale, offset), (Some(want_ch), [factor; 3], 0.0));
        assert!(b.raw);
        assert_eq!(b.filter, BitmapFilter::Bilinear);
        assert_eq!(b.to_uv, UV_IDENTITY);
        assert_eq!(
            b.source,
            ImageSource::File(Path::new("dir/tex1.png").into())
        );
    }
    // Without textures, constants.
    let mut d = Doc::triangle();
    d.with_material(
        json!({"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.25, 1.0, 1.0], "metallicFactor": 0.0}}),
        0,
        json!([]),
    );
    let g = d.load();
    assert!(
        matches!(core(bsdf(&g)), BsdfKind::GltfPbr { base_color, metallic, roughness, .. }
        if *base_color == TextureDesc::Constant(SpectrumDesc::Rgb([0.5, 0.25, 1.0]))
            && *metallic == TextureDesc::constant(0.0) && *roughness == TextureDesc::constant(1.0))
    );
}

/// `wrapS` gives the bitmap's wrap mode; a different `wrapT` is warned about.
#[test]
fn wrap_modes_follow_wrap_s() {
    for (s, t, want, warns) in [
        (33071, 33071, WrapMode::Clamp, false),
        (33648, 33648, WrapMode::Mirror, false),
        (10497, 10497, WrapMode::Repeat, false),
        (33071, 10497, WrapMode::Clamp, true),
        (10497, 33648, WrapMode::Repeat, true),
    ] {
        let mut d = Doc::triangle();
        d.with_material(
            json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}),
            1,
            json!([{"wrapS": s, "wrapT": t}]),
        );
        let g = d.load();
        let BsdfKind::GltfPbr { base_color, .. } = core(bsdf(&g)) else {
            unreachable!()
        };
        assert_eq!(
            scaled_bitmap(base_color).0.wrap,
            want,
            "wrapS {s}, wrapT {t}"
        );
        let warning = g.warnings.iter().find(|w| w.contains("wrapT"));
        assert_eq!(warning.is_some(), warns, "{:?}", g.warnings);
        if let Some(w) = warning {
            assert!(w.contains("baseColorTexture (textures[0])"), "{w}");
        }
    }
    // No sampler: glTF's default, repeat.
    let mut d = Doc::triangle();
    d.with_material(
        json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}),
        1,
        json!([]),
    );
    let g = d.load();
    let BsdfKind::GltfPbr { base_color, .. } = core(bsdf(&g)) else {
        unreachable!()
    };
    assert_eq!(scaled_bitmap(base_color).0.wrap, WrapMode::Repeat);
}

/// `COLOR_0` becomes the mesh attribute `vertex_color`: 3 linear values per vertex from float
/// or normalized integer data, alpha dropped.
#[test]
fn color_0_becomes_the_vertex_color_attribute() {
    let want = [1.0, 0.2, 0.0, 0.0, 1.0, 0.6, 0.4, 0.0, 1.0];
    let u8s: Vec<u8> = [[255u8, 51, 0, 7], [0, 255, 153, 7], [102, 0, 255, 7]].concat();
    let u16s: Vec<u8> = [65535u16, 13107, 0, 0, 65535, 39321, 26214, 0, 65535]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    for case in ["f32 VEC3", "f32 VEC4", "u8 VEC4", "u16 VEC3"] {
        let mut d = Doc::triangle();
        let acc = match case {
            "f32 VEC3" => d.floats(&want, "VEC3"),
            "f32 VEC4" => d.floats(
                &[1.0, 0.2, 0.0, 0.5, 0.0, 1.0, 0.6, 0.5, 0.4, 0.0, 1.0, 0.5],
                "VEC4",
            ),
            "u8 VEC4" => d.accessor(&u8s, U8, "VEC4", 3),
            _ => d.accessor(&u16s, U16, "VEC3", 3),
        };
        d.prim()["attributes"]["COLOR_0"] = json!(acc);
        let g = d.load();
        let m = mesh(&g);
        assert_eq!(m.attributes.len(), 1, "{case}");
        let a = &m.attributes[0];
        assert_eq!(
            (a.name.as_str(), a.kind, a.dims),
            ("vertex_color", AttributeKind::Vertex, 3),
            "{case}"
        );
        assert!(close(&a.values, &want), "{case}: {:?}", a.values);
        assert!(
            g.warnings
                .iter()
                .any(|w| w.contains("COLOR_0") && w.contains("base colour")),
            "{:?}",
            g.warnings
        );
    }
    // Without COLOR_0, no attribute and no warning.
    let g = Doc::triangle().load();
    assert!(mesh(&g).attributes.is_empty());
    assert!(!g.warnings.iter().any(|w| w.contains("COLOR_0")));
}

/// Accessors of a type glTF does not allow for their attribute, or with no elements, are
/// errors naming the primitive and the attribute (the gltf crate would panic on them).
#[test]
fn accessors_of_the_wrong_type_are_errors() {
    let mut d = Doc::triangle();
    let acc = d.floats(&[1.0, 0.5, 0.2], "SCALAR");
    d.prim()["attributes"]["COLOR_0"] = json!(acc);
    let e = d.error();
    assert!(
        e.contains("meshes[0].primitives[0] COLOR_0") && e.contains("not allowed"),
        "{e}"
    );

    let mut d = Doc::triangle();
    let acc = d.accessor(&[0; 6], 5120, "VEC2", 3); // signed bytes
    d.prim()["attributes"]["TEXCOORD_0"] = json!(acc);
    let e = d.error();
    assert!(e.contains("TEXCOORD_0") && e.contains("not allowed"), "{e}");

    let mut d = Doc::triangle();
    let acc = d.floats(&[0.0, 1.0, 2.0], "SCALAR");
    d.prim()["indices"] = json!(acc);
    let e = d.error();
    assert!(e.contains("indices") && e.contains("not allowed"), "{e}");

    let mut d = Doc::triangle();
    let acc = d.floats(&[0.0, 0.0], "VEC2");
    d.json["accessors"][acc]["count"] = json!(0);
    d.prim()["attributes"]["TEXCOORD_0"] = json!(acc);
    let e = d.error();
    assert!(e.contains("count is 0"), "{e}");
}

/// MASK with a base colour texture: opacity = factor alpha x texel alpha (the texture read
/// raw) against the cutoff; BLEND without one: a constant opacity; an opaque result: no mask.
#[test]
fn alpha_modes_become_masks() {
    let mut d = Doc::triangle();
    d.with_material(
        json!({"alphaMode": "MASK", "alphaCutoff": 0.3,
               "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 0.8], "baseColorTexture": {"index": 0}}}),
        1,
        json!([]),
    );
    let g = d.load();
    let BsdfKind::Mask {
        opacity,
        cutoff,
        inner,
    } = bsdf(&g)
    else {
        panic!("{:?}", bsdf(&g))
    };
    assert_eq!(*cutoff, Some(0.3));
    let (alpha, ch, scale, offset) = scaled_bitmap(opacity);
    assert_eq!(
        (ch, scale, offset),
        (Some(TextureChannel::Alpha), [0.8; 3], 0.0)
    );
    assert!(alpha.raw);
    let BsdfKind::TwoSided { inner } = &inner.kind else {
        panic!("{inner:?}")
    };
    let BsdfKind::GltfPbr { base_color, .. } = &inner.kind else {
        panic!("{inner:?}")
    };
    let colour = scaled_bitmap(base_color).0;
    assert!(!colour.raw);
    assert_eq!(colour.source, alpha.source);

    let blend = |a: f32, mode: &str| {
        let mut d = Doc::triangle();
        d.with_material(
            json!({"alphaMode": mode, "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, a]}}),
            0,
            json!([]),
        );
        d.load()
    };
    let g = blend(0.25, "BLEND");
    assert!(
        matches!(bsdf(&g), BsdfKind::Mask { opacity, cutoff: None, .. } if *opacity == TextureDesc::constant(0.25))
    );
    let g = blend(0.25, "MASK");
    assert!(
        matches!(bsdf(&g), BsdfKind::Mask { opacity, cutoff: None, .. } if *opacity == TextureDesc::constant(0.0))
    );
    for (a, mode) in [(0.75, "MASK"), (1.0, "BLEND"), (0.25, "OPAQUE")] {
        let g = blend(a, mode);
        assert!(matches!(bsdf(&g), BsdfKind::TwoSided { .. }), "{mode} {a}");
    }
}

/// emissiveFactor x strength x emissiveTexture is the area emitter's radiance; the texture
/// keeps its KHR_texture_transform.
#[test]
fn emissive_texture_with_transform_is_the_radiance() {
    let mut d = Doc::triangle();
    d.json["extensionsUsed"] = json!(["KHR_texture_transform", "KHR_materials_emissive_strength"]);
    d.with_material(
        json!({"emissiveFactor": [1.0, 0.5, 0.25],
               "emissiveTexture": {"index": 0, "extensions": {"KHR_texture_transform": {"offset": [0.25, 0]}}},
               "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}}}),
        1,
        json!([]),
    );
    let g = d.load();
    let e = g.desc.shapes[0].emitter.as_ref().expect("emits");
    let (b, ch, scale, offset) = scaled_bitmap(&e.radiance);
    assert_eq!((ch, scale, offset), (None, [4.0, 2.0, 1.0], 0.0));
    assert!(!b.raw);
    assert_eq!(b.to_uv, [1.0, 0.0, 0.25, 0.0, 1.0, 0.0]);
    assert!(!g.warnings.iter().any(|w| w.contains("default environment")));
    // A black factor: no emitter, whatever the texture.
    let mut d = Doc::triangle();
    d.with_material(json!({"emissiveTexture": {"index": 0}}), 1, json!([]));
    assert!(d.load().desc.shapes[0].emitter.is_none());
    // No texture: a constant.
    let mut d = Doc::triangle();
    d.with_material(json!({"emissiveFactor": [1.0, 0.5, 0.25]}), 0, json!([]));
    let g = d.load();
    let e = g.desc.shapes[0].emitter.as_ref().expect("emits");
    assert_eq!(
        e.radiance,
        TextureDesc::Constant(SpectrumDesc::Rgb([1.0, 0.5, 0.25]))
    );
}

/// Partial iridescence with both textures: a blend of the material and the film, weight =
/// factor x red; thickness = min + (max - min) x green, on a conductor base from the base
/// colour (metallic).
#[test]
fn iridescence_textures_give_weight_and_thickness() {
    let mut d = Doc::triangle();
    d.json["extensionsUsed"] = json!(["KHR_materials_iridescence"]);
    d.with_material(
        json!({"pbrMetallicRoughness": {"baseColorFactor": [0.25, 0.25, 0.25, 1], "metallicFactor": 1.0, "roughnessFactor": 0.0},
               "extensions": {"KHR_materials_iridescence": {
                   "iridescenceFactor": 0.5, "iridescenceIor": 1.4,
                   "iridescenceThicknessMinimum": 200, "iridescenceThicknessMaximum": 600,
                   "iridescenceTexture": {"index": 0}, "iridescenceThicknessTexture": {"index": 1}}}}),
        2,
        json!([]),
    );
    let g = d.load();
    let BsdfKind::Blend {
        weight,
        first,
        second,
    } = core(bsdf(&g))
    else {
        panic!("{:?}", bsdf(&g))
    };
    let (w, ch, scale, offset) = scaled_bitmap(weight);
    assert_eq!(
        (ch, scale, offset),
        (Some(TextureChannel::Red), [0.5; 3], 0.0)
    );
    assert!(w.raw && w.source == ImageSource::File("dir/tex0.png".into()));
    assert!(matches!(first.kind, BsdfKind::GltfPbr { .. }));
    let BsdfKind::ThinFilm {
        thickness,
        film_ior,
        ext_ior,
        base,
    } = &second.kind
    else {
        panic!("{second:?}")
    };
    assert_eq!((*film_ior, *ext_ior), (1.4, 1.0));
    let (t, ch, scale, offset) = scaled_bitmap(thickness);
    assert_eq!(
        (ch, scale, offset),
        (Some(TextureChannel::Green), [400.0; 3], 200.0)
    );
    assert!(t.raw && t.source == ImageSource::File("dir/tex1.png".into()));
    // F0 = 0.25: n = (1 + 0.5) / (1 - 0.5) = 3.
    assert_eq!(
        *base,
        FilmBaseDesc::Conductor {
            eta: TextureDesc::Constant(SpectrumDesc::Rgb([3.0; 3])),
            k: TextureDesc::constant(0.0)
        }
    );
    assert!(g
        .summary
        .iter()
        .any(|l| l.contains("thinfilm: 600 nm film of ior 1.4")));
}

/// Transmission: a dielectric with a volume (rough: GGX), a thin dielectric without, a blend
/// with the opaque material for a partial factor.
#[test]
fn transmission_becomes_dielectrics() {
    let material = |factor: f32, roughness: f32, volume: bool| {
        let mut d = Doc::triangle();
        d.json["extensionsUsed"] = json!(["KHR_materials_transmission", "KHR_materials_volume"]);
        let mut m = json!({"pbrMetallicRoughness": {"metallicFactor": 0.0, "roughnessFactor": roughness},
                           "extensions": {"KHR_materials_transmission": {"transmissionFactor": factor}}});
        if volume {
            m["extensions"]["KHR_materials_volume"] = json!({"thicknessFactor": 1.0});
        }
        d.with_material(m, 0, json!([]));
        d.load()
    };
    let one = TextureDesc::constant(1.0);
    let g = material(1.0, 0.0, true);
    assert!(
        matches!(bsdf(&g), BsdfKind::Dielectric { int_ior, ext_ior, specular_reflectance, specular_transmittance }
            if (*int_ior, *ext_ior) == (1.5, 1.0) && *specular_reflectance == one && *specular_transmittance == one),
        "{:?}",
        bsdf(&g)
    );
    assert!(
        g.desc.shapes[0].interior.is_none(),
        "no attenuation distance: no medium"
    );
    let g = material(1.0, 0.5, true);
    let BsdfKind::RoughDielectric { microfacet, .. } = bsdf(&g) else {
        panic!("{:?}", bsdf(&g))
    };
    assert_eq!(
        *microfacet,
        MicrofacetDesc {
            distribution: MicrofacetDistribution::Ggx,
            alpha_u: TextureDesc::constant(0.25),
            alpha_v: TextureDesc::constant(0.25)
        }
    );
    let g = material(1.0, 0.0, false);
    assert!(
        matches!(bsdf(&g), BsdfKind::ThinDielectric { .. }),
        "{:?}",
        bsdf(&g)
    );
    let g = material(0.25, 0.0, true);
    assert!(
        matches!(core(bsdf(&g)), BsdfKind::Blend { weight, first, second }
            if *weight == TextureDesc::constant(0.25)
                && matches!(first.kind, BsdfKind::GltfPbr { .. })
                && matches!(second.kind, BsdfKind::Dielectric { .. })),
        "{:?}",
        bsdf(&g)
    );
}

/// A normal texture: `normalmap` (raw bitmap with its transform, glTF tangent space) around
/// the material, and the mesh gets tangents generated from its uvs.
#[test]
fn normal_texture_wraps_the_material_and_gives_tangents() {
    let mut d = Doc::triangle();
    d.with_uvs();
    d.json["extensionsUsed"] = json!(["KHR_texture_transform"]);
    d.with_material(
        json!({"normalTexture": {"index": 0, "scale": 0.5, "extensions": {"KHR_texture_transform":
            {"rotation": std::f32::consts::FRAC_PI_2, "scale": [2.0, 2.0], "offset": [0.5, 0.0]}}}}),
        1,
        json!([]),
    );
    let g = d.load();
    let BsdfKind::NormalMap {
        texture: TextureDesc::Bitmap(b),
        scale,
        gltf,
        inner,
    } = bsdf(&g)
    else {
        panic!("{:?}", bsdf(&g))
    };
    assert_eq!((*scale, *gltf, b.raw), (0.5, true, true));
    assert!(
        close(&b.to_uv, &[0.0, -2.0, 0.5, 2.0, 0.0, 0.0]),
        "{:?}",
        b.to_uv
    );
    assert!(matches!(inner.kind, BsdfKind::TwoSided { .. }));
    // dp/du = +x; the bitangent -dp/dv = -y is -(n x t): w = -1.
    let t = mesh(&g).tangents.as_ref().expect("tangents");
    assert!(
        t.iter()
            .all(|t| (*t - Vec4::new(1.0, 0.0, 0.0, -1.0)).length() < 1e-6),
        "{t:?}"
    );
    // Without uvs (or TANGENT) there is no tangent space: a warning.
    let mut d = Doc::triangle();
    d.with_material(json!({"normalTexture": {"index": 0}}), 1, json!([]));
    let g = d.load();
    assert!(mesh(&g).tangents.is_none());
    assert!(g.warnings.iter().any(|w| w.contains("normal map ignored")));
}

#[test]
fn generated_tangents_follow_u_with_the_bitangent_towards_decreasing_v() {
    // A quad in the xz plane, normal +y, u along +x and v along +z.
    let positions = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 0.0, 1.0), Vec3::Z];
    let uvs = [Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y];
    let indices = [[0, 3, 2], [0, 2, 1]];
    let t = generate_tangents(&positions, None, &uvs, &indices);
    // n = +y, t = +x: n x t = -z, and -dp/dv = -z: w = +1.
    for t in t {
        assert!((t - Vec4::new(1.0, 0.0, 0.0, 1.0)).length() < 1e-6, "{t}");
    }
}

/// glTF's default material is two-sided like every opaque one, and is not confused with a
/// material the file names "gltf-default".
#[test]
fn default_material_is_two_sided_and_its_own() {
    let g = Doc::triangle().load();
    assert_eq!(g.desc.bsdfs.len(), 1);
    assert!(
        matches!(bsdf(&g), BsdfKind::TwoSided { inner } if matches!(inner.kind, BsdfKind::GltfPbr { .. }))
    );
    let mut d = Doc::triangle();
    d.with_material(json!({"name": "gltf-default"}), 0, json!([]));
    d.prim().as_object_mut().unwrap().remove("material");
    let g = d.load();
    assert_eq!(g.desc.bsdfs.len(), 2);
    assert_eq!(g.desc.shapes[0].bsdf, 1);
}

fn asset(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes/gltf")
        .join(name)
}

/// Every glTF asset of the repository loads; spot checks of what each maps to.
#[test]
fn scene_assets_load() {
    let dir = asset("");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if !is_gltf_path(&path) {
            continue;
        }
        let g = load(&path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        assert!(!g.desc.shapes.is_empty(), "{}", path.display());
        n += 1;
    }
    assert!(n >= 5, "{n} assets in {}", dir.display());

    // glass-block.glb: KHR_materials_volume, attenuationColor (0.8, 0.5, 0.2) at distance 0.5.
    let g = load(&asset("glass-block.glb"), &LoadOptions::default()).unwrap();
    let m = g.desc.shapes[0].interior.as_ref().expect("a medium");
    let SpectrumDesc::Rgb(sigma) = m.sigma_t else {
        panic!("{:?}", m.sigma_t)
    };
    let want = [0.8f32, 0.5, 0.2].map(|c| -c.ln() / 0.5);
    assert!(close(&sigma, &want), "{sigma:?}");
    assert!(matches!(bsdf(&g), BsdfKind::Dielectric { int_ior, .. } if *int_ior == 1.5));

    let g = load(&asset("iridescence.gltf"), &LoadOptions::default()).unwrap();
    assert!(g
        .summary
        .iter()
        .any(|l| l.contains("thinfilm: 450 nm film of ior 1.33")));
    assert!(g.desc.spectral_reason().is_some());

    // textures.gltf: a rotated, nearest-filtered embedded base colour texture.
    let g = load(&asset("textures.gltf"), &LoadOptions::default()).unwrap();
    let BsdfKind::GltfPbr { base_color, .. } = core(bsdf(&g)) else {
        panic!("{:?}", bsdf(&g))
    };
    let (b, _, scale, _) = scaled_bitmap(base_color);
    assert_eq!(scale, [0.8, 1.0, 0.9]);
    assert_eq!(b.filter, BitmapFilter::Nearest);
    assert!(
        close(&b.to_uv, &[0.0, -1.0, 0.0, 1.0, 0.0, 0.0]),
        "{:?}",
        b.to_uv
    );
    assert!(matches!(&b.source, ImageSource::Embedded { name, .. } if name == "images[0]"));
}

/// A fresh folder under the system temp dir, unique to this process and test.
fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("pt-scene-gltf-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

/// `<shape type="gltf">` reads the file's triangles (node transforms, then `to_world`), with
/// the vertex colours as the mesh attribute `vertex_color`; errors name the file.
#[test]
fn xml_gltf_shape_reads_the_mesh_and_vertex_colours() {
    let dir = temp_dir("xml-shape");
    let mut d = Doc::triangle();
    d.json["nodes"][0]["translation"] = json!([0, 0, 2]);
    let colours = d.floats(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], "VEC3");
    d.prim()["attributes"]["COLOR_0"] = json!(colours);
    // A second primitive of the same triangle: the two are merged, colours included.
    let p = d.json["meshes"][0]["primitives"][0].clone();
    d.json["meshes"][0]["primitives"] = json!([p.clone(), p]);
    std::fs::write(dir.join("tri.gltf"), d.bytes()).unwrap();
    let xml = r#"<scene version="3.0.0">
        <shape type="gltf">
            <string name="filename" value="tri.gltf"/>
            <transform name="to_world"><translate x="10"/></transform>
            <bsdf type="diffuse"><texture type="mesh_attribute" name="reflectance"><string name="name" value="vertex_color"/></texture></bsdf>
        </shape>
    </scene>"#;
    let scene =
        crate::load_str(xml, &dir.join("s.xml"), &dir, &[]).unwrap_or_else(|e| panic!("{e}"));
    let Geometry::Mesh(m) = &scene.shapes[0].geometry else {
        panic!("not a mesh")
    };
    assert_eq!((m.positions.len(), m.indices.len()), (6, 2));
    assert!(
        (m.positions[1] - Vec3::new(11.0, 0.0, 2.0)).length() < 1e-6,
        "{:?}",
        m.positions
    );
    assert_eq!(m.indices[1], [3, 4, 5]);
    let a = m
        .attributes
        .iter()
        .find(|a| a.name == "vertex_color")
        .expect("vertex_color");
    assert_eq!(a.values.len(), 18);
    assert_eq!(a.values[9..12], [1.0, 0.0, 0.0]);

    std::fs::write(dir.join("bad.gltf"), b"{ not json").unwrap();
    let bad = xml.replace("tri.gltf", "bad.gltf");
    let e = crate::load_str(&bad, &dir.join("s.xml"), &dir, &[]).unwrap_err();
    assert!(
        e.to_string().contains("bad.gltf") && e.to_string().contains("malformed glTF"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Images are shared: two textures of one embedded image hold the same bytes.
#[test]
fn textures_of_one_image_share_its_bytes() {
    let mut d = Doc::triangle();
    d.with_material(
        json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicRoughnessTexture": {"index": 1}}}),
        2,
        json!([]),
    );
    d.json["images"] = json!([{"uri": "data:image/png;base64,AAAA"}]);
    d.json["textures"] = json!([{"source": 0}, {"source": 0}]);
    let g = d.load();
    let BsdfKind::GltfPbr {
        base_color,
        metallic,
        ..
    } = core(bsdf(&g))
    else {
        unreachable!()
    };
    let bytes = |t: &TextureDesc| match &scaled_bitmap(t).0.source {
        ImageSource::Embedded { bytes, .. } => bytes.clone(),
        other => panic!("{other:?}"),
    };
    assert!(Arc::ptr_eq(&bytes(base_color), &bytes(metallic)));
}
