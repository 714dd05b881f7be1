//! glTF 2.0 reader: a `.gltf` (JSON with external or `data:` buffers) or `.glb` file becomes the
//! renderer's scene description ([`pt_scene::SceneDesc`]), in world space, metres (glTF's unit).
//!
//! What is read, and how each part maps (also printed by `pt info model.glb`):
//!
//! | glTF                                  | renderer                                                        |
//! |---------------------------------------|-----------------------------------------------------------------|
//! | mesh primitive (triangles)            | one `TriangleMesh` shape, positions/normals by the node's world matrix (normals by its inverse transpose, winding reversed when the determinant is negative), `TEXCOORD_0` |
//! | node camera (perspective)             | the first one in node order, or `--camera N`; glTF looks down -z with +x right, the renderer's camera space looks down +z with +x left: `to_world = node * diag(-1, 1, -1)`; `yfov` is the vertical field of view |
//! | no camera                             | a default camera: vertical fov 45 deg, on the +z side of the bounds' centre, looking down -z, at the distance where the bounding sphere fits the vertical fov (x 1.1) |
//! | (film)                                | 320 x 240 pixels (height from the camera's `aspectRatio`), box filter, 64 spp, `volpath` (path tracing with Beer-Lambert media) with unlimited depth; `pt render --width/--height/--spp` override |
//! | no light and no emissive material     | a default environment: `constant` radiance 1 (white)             |
//! | `pbrMetallicRoughness`                | `BsdfKind::GltfPbr` (base colour factor, metallic, roughness; alpha = roughness^2), two-sided |
//! | `emissiveFactor` x `KHR_materials_emissive_strength` | an area emitter of that radiance on every primitive with the material |
//! | `KHR_materials_transmission` (+ `KHR_materials_ior`) | with `KHR_materials_volume` thickness > 0: `dielectric` (roughness 0) or `roughdielectric` (GGX, alpha = roughness^2) of index `ior`; without volume (glTF's thin-walled case): `thindielectric`; a factor f < 1 (or metallic > 0): `blendbsdf` of the opaque material and that, weight f (1 - metallic) (see Partial factors) |
//! | `KHR_materials_volume`                | `ShapeDesc::interior`, Beer-Lambert: `sigma_t = -ln(attenuationColor) / attenuationDistance` per channel (the colour white light turns into after travelling `attenuationDistance`); `thicknessFactor` only selects volume vs thin-walled: the path tracer measures the real distance inside the mesh |
//! | `KHR_materials_iridescence`           | `thinfilm` (roughness 0) or `roughthinfilm` (GGX, alpha = roughness^2): thickness `iridescenceThicknessMaximum` nm, or per texel `mix(iridescenceThicknessMinimum, iridescenceThicknessMaximum, green)` of `iridescenceThicknessTexture`; film index `iridescenceIor`, base: an opaque base of index `n = (1 + sqrt(F0))/(1 - sqrt(F0))`, `k = 0` from the base colour (metallic >= 0.5) or `n = ior` (metallic < 0.5); the diffuse base is dropped; `iridescenceFactor` f < 1: `blendbsdf` of the material without the film and the film, weight f |
//! | `baseColorTexture`, `metallicRoughnessTexture`, `KHR_texture_transform` | factors times texels at the hit's uv (see Textures below) |
//! | `normalTexture` (`scale`)              | `normalmap` around the material: tangent space from `TANGENT` (xyz by the node's matrix, w negated under a mirroring node) or generated from the uvs (see Normal maps below) |
//! | `alphaMode` BLEND / MASK              | `mask` around the material, opacity = alpha / (alpha >= alphaCutoff), alpha = baseColorFactor alpha x the base colour texture's alpha per texel |
//! | `KHR_lights_punctual` point           | `point`, intensity (cd) x colour                                |
//! | `KHR_lights_punctual` spot            | `spot` on the node's -z axis, full intensity within `innerConeAngle`, zero beyond `outerConeAngle` (the renderer's falloff between them is linear in angle, Mitsuba's; glTF suggests a squared linear-in-cosine ramp) |
//! | `KHR_lights_punctual` directional     | `directional` along the node's -z axis, irradiance (lux) x colour |
//!
//! **Photometric units.** KHR_lights_punctual gives point and spot intensities in candela
//! (lm/sr) and directional illuminance in lux (lm/m^2). The renderer is linear, and a glTF scene
//! has no radiometric input to be consistent with (emissive values are unitless, used as
//! luminance by glTF viewers), so the numbers are used as they are: 1 cd becomes an intensity
//! of 1 (per sr) and 1 lx an irradiance of 1 (per m^2). The whole scene is then in photometric
//! units and a pixel holds luminance in cd/m^2 (nits) for a white light (the renderer's RGB has
//! Y(1, 1, 1) = 1). Dividing by 683 lm/W, the luminous efficacy that defines the candela at
//! 555 nm, would give watts only for 555 nm light and would put lights and emissive surfaces
//! on different scales; it is not done. `range` is ignored (physical inverse-square falloff).
//!
//! **Textures.** `baseColorTexture` (sRGB-decoded) and `metallicRoughnessTexture` (linear:
//! green scales roughness, blue metallic) multiply their factors at the hit's `TEXCOORD_0`, after
//! KHR_texture_transform (offset, rotation, scale, texCoord); PNG or JPEG, embedded or files;
//! repeat wrapping; `magFilter` NEAREST or bilinear (no mipmaps). In spectral mode each base colour
//! texel is upsampled once at load (Jakob & Hanika 2019, as a bounded reflectance) and the
//! interpolated texel spectra multiply the factor's spectrum (pt-render's `spectral_texture`).
//!
//! **Alpha.** `alphaMode` BLEND becomes the renderer's `mask` with opacity = baseColorFactor's
//! alpha times the base colour texture's alpha (stored linearly; 1 without an alpha channel) at
//! the hit; MASK an opacity of 0 or 1 per texel against `alphaCutoff`. Shadow rays are blocked
//! by masked surfaces whatever their opacity, as in Mitsuba's `path`: light through the holes
//! is found by BSDF sampling (the mask's pass-through lobe), the same for every texel.
//!
//! **Normal maps.** `normalTexture` is linear data, decoded as `n = (2 c - 1) (scale, scale, 1)`
//! in the tangent frame `(t, w (n x t), n)` (glTF: +x along increasing u, +y towards image-up,
//! i.e. decreasing v), then treated as Mitsuba 3.9's `normalmap` (pt-bsdf `normal_map`: the
//! viewer-side flip and the Conty Estevez 2019 shadowing term). Without `TANGENT` the tangents
//! are generated per vertex from the uvs (Lengyel 2001, area-weighted dp/du and -dp/dv,
//! [`generate_tangents`]) instead of MikkTSpace: the same where the uv mapping is affine around
//! each vertex, different at mirrored-uv seams, which MikkTSpace splits.
//!
//! **Partial factors.** A `KHR_materials_transmission` factor f < 1 (or a partly metallic
//! transmissive material) becomes a `blendbsdf` (pt-bsdf `blend`) of the opaque
//! metallic-roughness material and the transmissive model with weight `f (1 - metallic)`.
//! glTF instead mixes only the dielectric's diffuse base with the transmission lobe under one
//! specular layer; the blend keeps each model's own specular reflection (the same ior and
//! roughness, so nearly the same lobe), which is exact at f = 0 and f = 1. An
//! `iridescenceFactor` f < 1 becomes a blend of the material without the film (weight 1 - f)
//! and the thin film (weight f, times the red channel of `iridescenceTexture` per texel when
//! there is one); glTF mixes the Fresnel terms, `F = mix(F_dielectric,
//! F_iridescence, f)`, keeping the diffuse base under both, while the film model here drops the
//! diffuse base, so the blend has (1 - f) of it: exact at f = 0 and f = 1. With both partial,
//! the iridescence factor is treated as 1 (nested blends are not supported).
//!
//! `emissiveTexture` (sRGB) multiplies emissiveFactor x strength per texel on the area light
//! (in spectral mode upsampled per texel, and the factor's spectrum times the texel's: exact
//! when either is grey); with KHR_texture_transform it is an error (not yet implemented).
//! `occlusionTexture` is ignored with a warning: a path tracer computes occlusion itself.
//!
//! **Not yet** (warned about, never silently): transmission textures,
//! texture coordinate sets other than 0,
//! clamped/mirrored wrapping, orthographic cameras, non-triangle primitives, sparse accessors,
//! skins and morph targets.
//!
//! Errors (malformed JSON or GLB, truncated or missing buffers, accessors or indices out of
//! range, unsupported *required* extensions) are [`GltfError`]s naming the file and the glTF
//! element (`meshes[2].primitives[0]`); unsupported *optional* extensions are warnings naming
//! them.
#![warn(missing_docs)]
#![forbid(unsafe_code)]

use base64::Engine as _;
use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};
use gltf::json::validation::Validate as _;
use pt_scene::{
    AreaEmitterDesc, BsdfDesc, BsdfKind, CameraDesc, FilmDesc, FilterDesc, FovAxis, Geometry,
    ImageSource, IntegratorDesc, IntegratorKind, LightDesc, LightKind, MediumDesc, Projection,
    RadiosityOptions, SamplerDesc, SceneDesc, ShapeDesc, SourceLoc, SpectrumDesc, TriangleMesh,
    UvTexture,
};
use std::path::{Path, PathBuf};

/// Extensions this reader maps onto the renderer (see the module doc).
pub const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_transmission",
    "KHR_materials_volume",
    "KHR_materials_iridescence",
    "KHR_texture_transform",
];

/// Vertical field of view of the default camera, degrees.
pub const DEFAULT_FOV_Y_DEG: f32 = 45.0;
/// Image width when the file does not say (glTF cameras give an aspect ratio only), pixels.
pub const DEFAULT_WIDTH: u32 = 320;
/// Image height of the default 4:3 image, pixels.
pub const DEFAULT_HEIGHT: u32 = 240;

/// A glTF file that cannot be read, with the file and the glTF element at fault.
#[derive(Debug, thiserror::Error)]
#[error("{}: {message}", file.display())]
pub struct GltfError {
    /// The glTF file.
    pub file: PathBuf,
    /// What is wrong, naming the element (`meshes[0].primitives[1]`).
    pub message: String,
}

/// Options of [`load`].
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// Which camera to use (index in node order, as `pt info` lists them); `None`: the first.
    pub camera: Option<usize>,
}

/// A loaded glTF file.
#[derive(Clone, Debug)]
pub struct GltfScene {
    /// The scene description for the renderer.
    pub desc: SceneDesc,
    /// Things the user must know (defaults used, features ignored): print them on stderr.
    pub warnings: Vec<String>,
    /// A human-readable listing for `pt info`: meshes, materials with extensions and how each
    /// maps, lights, cameras.
    pub summary: Vec<String>,
}

/// Every triangle primitive of a glTF file's scene as one mesh (node transforms applied; normals
/// and texture coordinates kept when every primitive has them), for `<shape type="gltf">` in a
/// Mitsuba XML scene ([`pt_scene::GltfMeshReader`]). Errors name the file and the element.
pub fn load_mesh(path: &Path) -> Result<TriangleMesh, String> {
    let g = load(path, &LoadOptions::default()).map_err(|e| e.to_string())?;
    let meshes: Vec<&TriangleMesh> = g
        .desc
        .shapes
        .iter()
        .filter_map(|s| {
            if let Geometry::Mesh(m) = &s.geometry {
                Some(m)
            } else {
                None
            }
        })
        .collect();
    if meshes.is_empty() {
        return Err(format!("{}: no triangles", path.display()));
    }
    let mut out = TriangleMesh::default();
    let all_normals = meshes.iter().all(|m| m.normals.is_some());
    let all_uvs = meshes.iter().all(|m| m.uvs.is_some());
    let (mut normals, mut uvs) = (Vec::new(), Vec::new());
    for m in meshes {
        let base = out.positions.len() as u32;
        out.positions.extend_from_slice(&m.positions);
        out.indices
            .extend(m.indices.iter().map(|t| t.map(|i| i + base)));
        if let (true, Some(n)) = (all_normals, &m.normals) {
            normals.extend_from_slice(n);
        }
        if let (true, Some(u)) = (all_uvs, &m.uvs) {
            uvs.extend_from_slice(u);
        }
    }
    out.normals = all_normals.then_some(normals);
    out.uvs = all_uvs.then_some(uvs);
    Ok(out)
}

/// Whether a path names a glTF file (`.gltf` or `.glb`, any case).
pub fn is_gltf_path(path: &Path) -> bool {
    matches!(
        path.extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref(),
        Some("gltf" | "glb")
    )
}

struct Ctx<'a> {
    file: &'a Path,
    warnings: Vec<String>,
    summary: Vec<String>,
}

impl Ctx<'_> {
    fn err(&self, message: impl Into<String>) -> GltfError {
        GltfError {
            file: self.file.to_path_buf(),
            message: message.into(),
        }
    }
    fn loc(&self, element: String) -> SourceLoc {
        SourceLoc {
            file: self.file.to_path_buf(),
            line: 0,
            col: 0,
            element,
        }
    }
}

/// Reads a `.gltf` or `.glb` file (see the module doc for the mapping).
pub fn load(path: &Path, opts: &LoadOptions) -> Result<GltfScene, GltfError> {
    let bytes = std::fs::read(path).map_err(|e| GltfError {
        file: path.to_path_buf(),
        message: format!("cannot read: {e}"),
    })?;
    load_slice(&bytes, path, opts)
}

/// Reads glTF from memory; `path` names it in messages and is where relative buffer URIs are
/// resolved from.
pub fn load_slice(bytes: &[u8], path: &Path, opts: &LoadOptions) -> Result<GltfScene, GltfError> {
    let mut cx = Ctx {
        file: path,
        warnings: Vec::new(),
        summary: Vec::new(),
    };
    let gltf = gltf::Gltf::from_slice_without_validation(bytes)
        .map_err(|e| cx.err(format!("malformed glTF: {e}")))?;
    let doc = &gltf.document;

    // Required extensions first (the gltf crate would call every extension it does not model
    // "unsupported", including ones this reader handles from the raw JSON).
    let unsupported: Vec<&str> = doc
        .extensions_required()
        .filter(|e| !SUPPORTED_EXTENSIONS.contains(e))
        .collect();
    if !unsupported.is_empty() {
        return Err(cx.err(format!(
            "requires extension(s) this renderer does not support: {} (supported: {})",
            unsupported.join(", "),
            SUPPORTED_EXTENSIONS.join(", ")
        )));
    }
    let ignored: Vec<&str> = doc
        .extensions_used()
        .filter(|e| !SUPPORTED_EXTENSIONS.contains(e))
        .collect();
    if !ignored.is_empty() {
        cx.warnings.push(format!(
            "ignoring optional extension(s): {}",
            ignored.join(", ")
        ));
    }
    let root = doc.as_json();
    let mut errors = Vec::new();
    root.validate(
        root,
        gltf::json::Path::new,
        &mut |p: &dyn Fn() -> gltf::json::Path, e| {
            if !matches!(e, gltf::json::validation::Error::Unsupported) {
                errors.push(format!("{}: {e}", p()));
            }
        },
    );
    if !errors.is_empty() {
        return Err(cx.err(format!("invalid glTF: {}", errors.join("; "))));
    }

    let buffers = load_buffers(&cx, doc, gltf.blob.as_deref())?;
    let mut desc = SceneDesc {
        source: path.to_path_buf(),
        camera: CameraDesc {
            loc: cx.loc("camera".into()),
            projection: Projection::Perspective {
                fov_deg: DEFAULT_FOV_Y_DEG,
                fov_axis: FovAxis::Y,
            },
            to_world: Mat4::IDENTITY,
            near_clip: 0.01,
            far_clip: 1e4,
        },
        // Box filter: each pixel is the plain average over its own footprint (glTF has no film
        // settings; Mitsuba's default Gaussian would blur across neighbours).
        film: FilmDesc {
            width: DEFAULT_WIDTH,
            height: DEFAULT_HEIGHT,
            filter: FilterDesc::Box { radius: 0.5 },
        },
        sampler: SamplerDesc {
            sample_count: 64,
            seed: 0,
        },
        integrator: IntegratorDesc {
            kind: IntegratorKind::VolPath,
            max_depth: -1,
            rr_depth: 5,
            hide_emitters: false,
            moment: false,
            radiosity: RadiosityOptions::default(),
            loc: cx.loc("integrator".into()),
        },
        shapes: Vec::new(),
        bsdfs: Vec::new(),
        lights: Vec::new(),
    };

    // Materials: one BSDF each, plus glTF's default material (index = count) for primitives
    // without one.
    let mut mats = Vec::new();
    cx.summary
        .push(format!("materials   {} (glTF)", doc.materials().len()));
    for m in doc.materials() {
        let mm = map_material(&mut cx, doc, &m, &buffers)?;
        desc.bsdfs.push(mm.bsdf.clone());
        mats.push(mm);
    }
    let default_mat = MappedMaterial {
        bsdf: BsdfDesc {
            loc: cx.loc("default material".into()),
            id: Some("gltf-default".into()),
            kind: BsdfKind::GltfPbr {
                base_color: SpectrumDesc::Constant(1.0),
                metallic: 1.0,
                roughness: 1.0,
                ior: 1.5,
                base_color_texture: None,
                metallic_roughness_texture: None,
            },
        },
        emission: None,
        emissive_texture: None,
        interior: None,
    };

    // Walk the scene graph.
    let scene = doc.default_scene().or_else(|| doc.scenes().next());
    let roots: Vec<gltf::Node> = match &scene {
        Some(s) => s.nodes().collect(),
        None => {
            // No scene: every node that is nobody's child is a root.
            let mut is_child = vec![false; doc.nodes().len()];
            for n in doc.nodes() {
                for c in n.children() {
                    is_child[c.index()] = true;
                }
            }
            doc.nodes().filter(|n| !is_child[n.index()]).collect()
        }
    };
    let mut cameras: Vec<(gltf::Camera, Mat4, usize)> = Vec::new();
    let mut stack: Vec<(gltf::Node, Mat4, usize)> = roots
        .into_iter()
        .rev()
        .map(|n| (n, Mat4::IDENTITY, 0))
        .collect();
    let mut visited = 0usize;
    let mut mesh_lines = Vec::new();
    while let Some((node, parent, depth)) = stack.pop() {
        visited += 1;
        if depth > 1000 || visited > 1_000_000 {
            return Err(cx.err(format!(
                "nodes[{}]: node hierarchy too deep or cyclic",
                node.index()
            )));
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if !world.is_finite() {
            return Err(cx.err(format!("nodes[{}]: non-finite transform", node.index())));
        }
        if let Some(cam) = node.camera() {
            cameras.push((cam, world, node.index()));
        }
        if let Some(light) = node.light() {
            desc.lights
                .push(map_light(&mut cx, &light, world, node.index())?);
        }
        if let Some(mesh) = node.mesh() {
            if node.skin().is_some() || mesh.weights().is_some() {
                cx.warnings.push(format!("nodes[{}]: skins and morph targets are not supported (not yet implemented); the mesh is used in its rest pose", node.index()));
            }
            for prim in mesh.primitives() {
                let elem = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
                if prim.mode() != gltf::mesh::Mode::Triangles {
                    cx.warnings.push(format!(
                        "{elem}: mode {:?} skipped (only triangles are rendered)",
                        prim.mode()
                    ));
                    continue;
                }
                let normal_mapped = prim
                    .material()
                    .index()
                    .is_some_and(|i| matches!(mats[i].bsdf.kind, BsdfKind::NormalMap { .. }));
                let tri = read_primitive(&mut cx, &prim, &buffers, world, &elem, normal_mapped)?;
                let (mm, bsdf) = match prim.material().index() {
                    Some(i) => (&mats[i], i),
                    None => {
                        if !desc
                            .bsdfs
                            .iter()
                            .any(|b| b.id.as_deref() == Some("gltf-default"))
                        {
                            desc.bsdfs.push(default_mat.bsdf.clone());
                        }
                        (&default_mat, desc.bsdfs.len() - 1)
                    }
                };
                mesh_lines.push(format!(
                    "  {elem:<28} node {:<3} {:>7} triangles  material {}{}",
                    node.index(),
                    tri.indices.len(),
                    prim.material()
                        .index()
                        .map_or("default".to_string(), |i| i.to_string()),
                    mesh.name().map(|n| format!("  '{n}'")).unwrap_or_default()
                ));
                let loc = cx.loc(format!("{elem} (node {})", node.index()));
                desc.shapes.push(ShapeDesc {
                    loc: loc.clone(),
                    plugin: "gltf".into(),
                    id: mesh.name().map(str::to_string),
                    geometry: Geometry::Mesh(tri),
                    bsdf,
                    emitter: mm.emission.clone().map(|radiance| AreaEmitterDesc {
                        loc: loc.clone(),
                        radiance,
                        texture: None,
                        primaries: None,
                        uv_texture: mm.emissive_texture.clone(),
                    }),
                    interior: mm.interior.clone(),
                });
            }
        }
        for c in node.children().collect::<Vec<_>>().into_iter().rev() {
            stack.push((c, world, depth + 1));
        }
    }
    let n_tris: usize = desc
        .shapes
        .iter()
        .map(|s| {
            if let Geometry::Mesh(m) = &s.geometry {
                m.indices.len()
            } else {
                0
            }
        })
        .sum();
    cx.summary.push(format!(
        "meshes      {} primitive(s), {} triangles",
        desc.shapes.len(),
        n_tris
    ));
    cx.summary.extend(mesh_lines);

    // Camera.
    cx.summary.push(format!(
        "cameras     {} (in node order; choose with --camera N)",
        cameras.len()
    ));
    for (i, (c, _, node)) in cameras.iter().enumerate() {
        let kind = match c.projection() {
            gltf::camera::Projection::Perspective(p) => format!(
                "perspective, yfov {:.2} deg, aspect {:?}",
                p.yfov().to_degrees(),
                p.aspect_ratio()
            ),
            gltf::camera::Projection::Orthographic(_) => "orthographic (not supported)".into(),
        };
        cx.summary
            .push(format!("  camera {i}: node {node}, {kind}"));
    }
    let perspective: Vec<usize> = (0..cameras.len())
        .filter(|&i| {
            matches!(
                cameras[i].0.projection(),
                gltf::camera::Projection::Perspective(_)
            )
        })
        .collect();
    let chosen = match opts.camera {
        Some(n) if n < cameras.len() => {
            if !perspective.contains(&n) {
                return Err(cx.err(format!(
                    "camera {n} is orthographic: only perspective cameras are supported"
                )));
            }
            Some(n)
        }
        Some(n) => {
            return Err(cx.err(format!(
                "--camera {n}: the file has {} camera(s) (0-based)",
                cameras.len()
            )))
        }
        None => perspective.first().copied(),
    };
    let bounds = scene_bounds(&desc.shapes);
    match chosen {
        Some(i) => {
            let (cam, world, node) = &cameras[i];
            if let gltf::camera::Projection::Perspective(p) = cam.projection() {
                let yfov = p.yfov().to_degrees();
                if !(yfov > 0.0 && yfov < 180.0) {
                    return Err(cx.err(format!(
                        "cameras[{}]: yfov {} rad is not in (0, pi)",
                        cam.index(),
                        p.yfov()
                    )));
                }
                desc.camera = CameraDesc {
                    loc: cx.loc(format!("cameras[{}] (node {node})", cam.index())),
                    projection: Projection::Perspective {
                        fov_deg: yfov,
                        fov_axis: FovAxis::Y,
                    },
                    to_world: *world * Mat4::from_scale(Vec3::new(-1.0, 1.0, -1.0)),
                    near_clip: p.znear().max(1e-6),
                    far_clip: p.zfar().unwrap_or(1e6),
                };
                if let Some(a) = p.aspect_ratio().filter(|a| *a > 0.0 && a.is_finite()) {
                    desc.film.height = ((DEFAULT_WIDTH as f32 / a).round() as u32).max(1);
                }
            }
            if cameras.len() > 1 {
                cx.warnings.push(format!(
                    "using camera {i} of {} (choose another with --camera N)",
                    cameras.len()
                ));
            }
        }
        None => {
            let (c, r) = bounds;
            let dist = 1.1 * r / (0.5 * DEFAULT_FOV_Y_DEG.to_radians()).sin();
            let eye = c + Vec3::Z * dist;
            // A glTF camera at `eye` with no rotation looks down -z with +y up.
            desc.camera.to_world =
                Mat4::from_translation(eye) * Mat4::from_scale(Vec3::new(-1.0, 1.0, -1.0));
            desc.camera.near_clip = (dist - r).max(dist * 1e-3) * 0.5;
            desc.camera.far_clip = (dist + r) * 2.0;
            cx.warnings.push(format!(
                "no perspective camera: using the default camera (vertical fov {DEFAULT_FOV_Y_DEG} deg at ({:.3}, {:.3}, {:.3}) looking down -z at the bounds' centre ({:.3}, {:.3}, {:.3}), radius {:.3})",
                eye.x, eye.y, eye.z, c.x, c.y, c.z, r
            ));
        }
    }

    // Lights.
    let emissive = desc.shapes.iter().any(|s| s.emitter.is_some());
    cx.summary.push(format!(
        "lights      {} punctual, {} emissive primitive(s)",
        desc.lights.len(),
        desc.shapes.iter().filter(|s| s.emitter.is_some()).count()
    ));
    for l in &desc.lights {
        cx.summary
            .push(format!("  {}: {}", l.loc.element, describe_light(&l.kind)));
    }
    if desc.lights.is_empty() && !emissive {
        desc.lights.push(LightDesc {
            loc: cx.loc("default environment".into()),
            kind: LightKind::Constant {
                radiance: SpectrumDesc::Constant(1.0),
            },
        });
        cx.warnings.push("no light and no emissive material: using the default environment (constant radiance 1, white)".into());
    }
    Ok(GltfScene {
        desc,
        warnings: cx.warnings,
        summary: cx.summary,
    })
}

fn describe_light(k: &LightKind) -> String {
    match k {
        LightKind::Point {
            position,
            intensity,
        } => format!("point at {position:.3}, intensity {intensity:?} (cd -> per sr, 1:1)"),
        LightKind::Spot {
            intensity,
            cutoff_deg,
            beam_width_deg,
            to_world,
        } => {
            format!("spot at {:.3}, intensity {intensity:?} (cd, 1:1), full to {beam_width_deg:.2} deg, off beyond {cutoff_deg:.2} deg", to_world.transform_point3(Vec3::ZERO))
        }
        LightKind::Directional {
            direction,
            irradiance,
        } => format!(
            "directional towards {direction:.3}, irradiance {irradiance:?} (lux -> per m^2, 1:1)"
        ),
        other => format!("{other:?}"),
    }
}

/// Data of every buffer: the GLB binary chunk, a `data:` URI (base64) or a file beside the
/// glTF. Each must hold at least `byteLength` bytes (a shorter one is a truncated file).
fn load_buffers(
    cx: &Ctx,
    doc: &gltf::Document,
    blob: Option<&[u8]>,
) -> Result<Vec<Vec<u8>>, GltfError> {
    let mut out = Vec::new();
    for b in doc.buffers() {
        let elem = format!("buffers[{}]", b.index());
        let data = match b.source() {
            gltf::buffer::Source::Bin => blob
                .ok_or_else(|| {
                    cx.err(format!(
                        "{elem}: refers to the GLB binary chunk, which the file does not have"
                    ))
                })?
                .to_vec(),
            gltf::buffer::Source::Uri(uri) => {
                if let Some(rest) = uri.strip_prefix("data:") {
                    let (_, b64) = rest
                        .split_once(";base64,")
                        .ok_or_else(|| cx.err(format!("{elem}: data URI is not base64")))?;
                    base64::engine::general_purpose::STANDARD
                        .decode(b64)
                        .map_err(|e| cx.err(format!("{elem}: bad base64 data: {e}")))?
                } else {
                    let dir = cx.file.parent().unwrap_or(Path::new("."));
                    let p = dir.join(uri);
                    std::fs::read(&p).map_err(|e| {
                        cx.err(format!("{elem}: cannot read '{}': {e}", p.display()))
                    })?
                }
            }
        };
        if data.len() < b.length() {
            return Err(cx.err(format!(
                "{elem}: truncated: byteLength {} but only {} bytes",
                b.length(),
                data.len()
            )));
        }
        out.push(data);
    }
    Ok(out)
}

/// Checks that every element of an accessor lies inside its buffer view and buffer, so the
/// gltf crate's reader can never read out of bounds or return short data.
fn check_accessor(
    cx: &Ctx,
    acc: &gltf::Accessor,
    buffers: &[Vec<u8>],
    what: &str,
    elem: &str,
) -> Result<(), GltfError> {
    let name = format!("{elem} {what} (accessors[{}])", acc.index());
    if acc.sparse().is_some() {
        return Err(cx.err(format!(
            "{name}: sparse accessors are not supported (not yet implemented)"
        )));
    }
    let view = acc
        .view()
        .ok_or_else(|| cx.err(format!("{name}: has no bufferView")))?;
    let size = acc.size();
    let stride = view.stride().unwrap_or(size);
    if stride < size {
        return Err(cx.err(format!(
            "{name}: byteStride {stride} is smaller than the element size {size}"
        )));
    }
    let buf = &buffers[view.buffer().index()];
    let view_end = view.offset().checked_add(view.length());
    if view_end.is_none_or(|e| e > buf.len()) {
        return Err(cx.err(format!("{name}: bufferViews[{}] (offset {}, length {}) runs past the end of its buffer ({} bytes)", view.index(), view.offset(), view.length(), buf.len())));
    }
    if acc.count() == 0 {
        return Ok(());
    }
    let need = (acc.count() - 1)
        .checked_mul(stride)
        .and_then(|x| x.checked_add(acc.offset()))
        .and_then(|x| x.checked_add(size));
    if need.is_none_or(|n| n > view.length()) {
        return Err(cx.err(format!(
            "{name}: {} elements from offset {} need more than the {} bytes of bufferViews[{}]",
            acc.count(),
            acc.offset(),
            view.length(),
            view.index()
        )));
    }
    Ok(())
}

/// Positions, normals, uvs and indices of a triangle primitive, in world space.
/// With `want_tangents` (a normal-mapped material) also the tangents: `TANGENT` (xyz by the
/// node's matrix, w negated when it mirrors), or generated from the uvs ([`generate_tangents`]).
fn read_primitive(
    cx: &mut Ctx,
    prim: &gltf::Primitive,
    buffers: &[Vec<u8>],
    world: Mat4,
    elem: &str,
    want_tangents: bool,
) -> Result<TriangleMesh, GltfError> {
    let pos_acc = prim
        .get(&gltf::Semantic::Positions)
        .ok_or_else(|| cx.err(format!("{elem}: no POSITION attribute")))?;
    check_accessor(cx, &pos_acc, buffers, "POSITION", elem)?;
    let nrm_acc = prim.get(&gltf::Semantic::Normals);
    if let Some(a) = &nrm_acc {
        check_accessor(cx, a, buffers, "NORMAL", elem)?;
    }
    let uv_acc = prim.get(&gltf::Semantic::TexCoords(0));
    if let Some(a) = &uv_acc {
        check_accessor(cx, a, buffers, "TEXCOORD_0", elem)?;
    }
    if let Some(a) = prim.indices() {
        check_accessor(cx, &a, buffers, "indices", elem)?;
    }
    let tan_acc = prim
        .get(&gltf::Semantic::Tangents)
        .filter(|_| want_tangents);
    if let Some(a) = &tan_acc {
        check_accessor(cx, a, buffers, "TANGENT", elem)?;
    }
    let reader = prim.reader(|b| buffers.get(b.index()).map(|v| v.as_slice()));
    let positions: Vec<Vec3> = reader
        .read_positions()
        .ok_or_else(|| cx.err(format!("{elem}: POSITION cannot be read")))?
        .map(Vec3::from)
        .collect();
    let n = positions.len();
    let normal_m = Mat3::from_mat4(world).inverse().transpose();
    let flip = Mat3::from_mat4(world).determinant() < 0.0;
    let positions: Vec<Vec3> = positions
        .into_iter()
        .map(|p| world.transform_point3(p))
        .collect();
    if positions.iter().any(|p| !p.is_finite()) {
        return Err(cx.err(format!("{elem}: non-finite vertex position")));
    }
    let normals = match reader.read_normals() {
        Some(it) => {
            let v: Vec<Vec3> = it
                .map(|nn| (normal_m * Vec3::from(nn)).normalize_or_zero())
                .collect();
            if v.len() != n {
                return Err(cx.err(format!("{elem}: {} normals for {n} positions", v.len())));
            }
            // Zero or non-finite normals would poison shading: fall back to face normals.
            if v.iter().all(|x| x.is_finite() && *x != Vec3::ZERO) {
                Some(v)
            } else {
                None
            }
        }
        None => None,
    };
    let uvs = match reader.read_tex_coords(0) {
        Some(it) => {
            let v: Vec<Vec2> = it.into_f32().map(Vec2::from).collect();
            if v.len() != n {
                return Err(cx.err(format!(
                    "{elem}: {} texture coordinates for {n} positions",
                    v.len()
                )));
            }
            Some(v)
        }
        None => None,
    };
    let flat: Vec<u32> = match reader.read_indices() {
        Some(it) => it.into_u32().collect(),
        None => (0..n as u32).collect(),
    };
    if flat.len() % 3 != 0 {
        return Err(cx.err(format!(
            "{elem}: {} indices is not a multiple of 3",
            flat.len()
        )));
    }
    if let Some((k, &i)) = flat.iter().enumerate().find(|(_, &i)| i as usize >= n) {
        return Err(cx.err(format!(
            "{elem}: index {k} is {i}, out of range for {n} vertices"
        )));
    }
    let indices: Vec<[u32; 3]> = flat
        .chunks_exact(3)
        .map(|t| {
            if flip {
                [t[0], t[2], t[1]]
            } else {
                [t[0], t[1], t[2]]
            }
        })
        .collect();
    let mut tangents = None;
    if want_tangents {
        let given = match (&tan_acc, reader.read_tangents()) {
            (Some(_), Some(it)) => {
                let m3 = Mat3::from_mat4(world);
                let v: Vec<Vec4> = it
                    .map(|t| {
                        (m3 * Vec3::new(t[0], t[1], t[2])).extend(if (t[3] < 0.0) != flip {
                            -1.0
                        } else {
                            1.0
                        })
                    })
                    .collect();
                if v.len() != n {
                    return Err(cx.err(format!("{elem}: {} tangents for {n} positions", v.len())));
                }
                v.iter().all(|t| t.is_finite()).then_some(v)
            }
            _ => None,
        };
        tangents = match (given, &uvs) {
            (Some(t), _) => Some(t),
            (None, Some(uv)) => Some(generate_tangents(
                &positions,
                normals.as_deref(),
                uv,
                &indices,
            )),
            (None, None) => {
                cx.warnings.push(format!("{elem}: normal map without TEXCOORD_0 or TANGENT: no tangent space, normal map ignored"));
                None
            }
        };
    }
    Ok(TriangleMesh {
        positions,
        normals,
        uvs,
        tangents,
        indices,
    })
}

/// Per-vertex tangents from the uvs when a mesh has no `TANGENT` (Lengyel 2001, "Computing
/// tangent space basis vectors for an arbitrary mesh"): each triangle's dp/du and -dp/dv
/// (glTF's bitangent points to image-up, decreasing v) are normalised, weighted by the
/// triangle's area and summed at its vertices; the tangent is the sum made orthogonal to the
/// vertex normal, and w = sign((n x t) . bitangent sum).
///
/// The glTF spec asks for MikkTSpace. The two agree wherever the uv mapping is affine over the
/// triangles around a vertex (planes, boxes, cylinders unrolled evenly: every test asset here);
/// elsewhere MikkTSpace weights by corner angle rather than area and splits vertices at mirrored
/// uv seams, which this does not (a vertex on such a seam gets one averaged tangent).
pub fn generate_tangents(
    positions: &[Vec3],
    normals: Option<&[Vec3]>,
    uvs: &[Vec2],
    indices: &[[u32; 3]],
) -> Vec<Vec4> {
    let n = positions.len();
    let (mut tacc, mut bacc, mut nacc) = (
        vec![Vec3::ZERO; n],
        vec![Vec3::ZERO; n],
        vec![Vec3::ZERO; n],
    );
    for tri in indices {
        let [i0, i1, i2] = tri.map(|i| i as usize);
        let (e1, e2) = (positions[i1] - positions[i0], positions[i2] - positions[i0]);
        let (d1, d2) = (uvs[i1] - uvs[i0], uvs[i2] - uvs[i0]);
        let cross = e1.cross(e2);
        let area = 0.5 * cross.length();
        let det = d1.x * d2.y - d1.y * d2.x;
        for i in [i0, i1, i2] {
            nacc[i] += cross; // area-weighted face normal, for meshes without normals
        }
        if det == 0.0 || !(area > 0.0) {
            continue;
        }
        // [e1 e2] = [dpdu dpdv] [d1 d2] (pbrt-v4 eq. 6.7).
        let dpdu = (e1 * d2.y - e2 * d1.y) / det;
        let dpdv = (e2 * d1.x - e1 * d2.x) / det;
        let (Some(t), Some(b)) = (dpdu.try_normalize(), (-dpdv).try_normalize()) else {
            continue;
        };
        for i in [i0, i1, i2] {
            tacc[i] += t * area;
            bacc[i] += b * area;
        }
    }
    (0..n)
        .map(|i| {
            let nn = normals
                .map(|ns| ns[i])
                .unwrap_or(nacc[i])
                .normalize_or_zero();
            match (tacc[i] - nn * nn.dot(tacc[i])).try_normalize() {
                Some(t) => t.extend(if nn.cross(t).dot(bacc[i]) < 0.0 {
                    -1.0
                } else {
                    1.0
                }),
                None => Vec4::ZERO, // the renderer falls back to dp/du
            }
        })
        .collect()
}

/// Centre and radius of the bounding sphere of the boxes of all meshes (a unit sphere at the
/// origin when empty).
fn scene_bounds(shapes: &[ShapeDesc]) -> (Vec3, f32) {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for s in shapes {
        if let Geometry::Mesh(m) = &s.geometry {
            for p in &m.positions {
                lo = lo.min(*p);
                hi = hi.max(*p);
            }
        }
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return (Vec3::ZERO, 1.0);
    }
    (0.5 * (lo + hi), (0.5 * (hi - lo).length()).max(1e-3))
}

fn map_light(
    cx: &mut Ctx,
    light: &gltf::khr_lights_punctual::Light,
    world: Mat4,
    node: usize,
) -> Result<LightDesc, GltfError> {
    use gltf::khr_lights_punctual::Kind;
    let elem = format!(
        "KHR_lights_punctual.lights[{}] (node {node})",
        light.index()
    );
    let c = light.color();
    let i = light.intensity();
    if !(i >= 0.0 && i.is_finite()) || c.iter().any(|x| !(*x >= 0.0 && x.is_finite())) {
        return Err(cx.err(format!(
            "{elem}: intensity and colour must be finite and >= 0"
        )));
    }
    if light.range().is_some() {
        cx.warnings.push(format!(
            "{elem}: range ignored (physical inverse-square falloff)"
        ));
    }
    // Photometric units used 1:1 (module doc): cd -> intensity per sr, lx -> irradiance.
    let value = SpectrumDesc::Rgb([c[0] * i, c[1] * i, c[2] * i]);
    let position = world.transform_point3(Vec3::ZERO);
    let dir = world
        .transform_vector3(-Vec3::Z)
        .try_normalize()
        .ok_or_else(|| cx.err(format!("{elem}: the node's transform has no direction")))?;
    let kind = match light.kind() {
        Kind::Point => LightKind::Point {
            position,
            intensity: value,
        },
        Kind::Directional => LightKind::Directional {
            direction: dir,
            irradiance: value,
        },
        Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => {
            if !(outer_cone_angle > 0.0
                && outer_cone_angle <= std::f32::consts::FRAC_PI_2
                && inner_cone_angle >= 0.0
                && inner_cone_angle < outer_cone_angle)
            {
                return Err(cx.err(format!("{elem}: need 0 <= innerConeAngle < outerConeAngle <= pi/2, got {inner_cone_angle}, {outer_cone_angle}")));
            }
            // The renderer's spot points along its +z: a rotation taking +z to the glTF axis.
            let rot = glam::Quat::from_rotation_arc(Vec3::Z, dir);
            LightKind::Spot {
                to_world: Mat4::from_rotation_translation(rot, position),
                intensity: value,
                cutoff_deg: outer_cone_angle.to_degrees(),
                beam_width_deg: inner_cone_angle.to_degrees(),
            }
        }
    };
    Ok(LightDesc {
        loc: cx.loc(elem),
        kind,
    })
}

struct MappedMaterial {
    bsdf: BsdfDesc,
    emission: Option<SpectrumDesc>,
    /// `emissiveTexture` (sRGB), multiplying `emission`.
    emissive_texture: Option<Box<UvTexture>>,
    interior: Option<MediumDesc>,
}

/// A number from an extension's JSON object, or its default.
fn ext_f32(v: Option<&serde_json::Value>, key: &str, default: f32) -> f32 {
    v.and_then(|o| o.get(key))
        .and_then(|x| x.as_f64())
        .map_or(default, |x| x as f32)
}

/// A material's texture: its image (embedded or a file), sampler filter and
/// KHR_texture_transform as an affine uv map. `None` (with a warning) for what is not supported:
/// texture coordinate sets other than 0, clamped or mirrored wrapping.
fn texture_of(
    cx: &mut Ctx,
    info: &gltf::texture::Info,
    srgb: bool,
    buffers: &[Vec<u8>],
    what: &str,
) -> Result<Option<Box<UvTexture>>, GltfError> {
    let mut tex_coord = info.tex_coord();
    // KHR_texture_transform: uv' = T R S uv (the extension's GLSL, column-major mat3s):
    // u' = sx u cos(r) - sy v sin(r) + ox, v' = sx u sin(r) + sy v cos(r) + oy.
    let mut transform = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    if let Some(t) = info.texture_transform() {
        let ([ox, oy], r, [sx, sy]) = (t.offset(), t.rotation(), t.scale());
        let (sin, cos) = r.sin_cos();
        transform = [sx * cos, -sy * sin, ox, sx * sin, sy * cos, oy];
        if let Some(tc) = t.tex_coord() {
            tex_coord = tc;
        }
    }
    texture_source(
        cx,
        info.texture(),
        tex_coord,
        transform,
        srgb,
        buffers,
        what,
    )
}

/// KHR_texture_transform read from a textureInfo's raw `extensions` JSON (for texture slots the
/// gltf crate does not model: `normalTexture`, extension textures), as in [`texture_of`];
/// its `texCoord` overrides `tex_coord`.
fn transform_from_json(ext: Option<&serde_json::Value>, tex_coord: &mut u32) -> [f32; 6] {
    let Some(t) = ext else {
        return [1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    };
    let pair = |k: &str, d: f32| {
        t.get(k).and_then(|v| v.as_array()).map_or([d, d], |a| {
            [0, 1].map(|i| a.get(i).and_then(|x| x.as_f64()).map_or(d, |x| x as f32))
        })
    };
    let ([ox, oy], r, [sx, sy]) = (
        pair("offset", 0.0),
        ext_f32(Some(t), "rotation", 0.0),
        pair("scale", 1.0),
    );
    if let Some(tc) = t.get("texCoord").and_then(|v| v.as_u64()) {
        *tex_coord = tc as u32;
    }
    let (sin, cos) = r.sin_cos();
    [sx * cos, -sy * sin, ox, sx * sin, sy * cos, oy]
}

/// A texture given by a raw textureInfo JSON object (`index`, `texCoord`, KHR_texture_transform)
/// of an extension the gltf crate does not model, as [`texture_of`].
fn json_texture(
    cx: &mut Ctx,
    doc: &gltf::Document,
    info: &serde_json::Value,
    srgb: bool,
    buffers: &[Vec<u8>],
    what: &str,
) -> Result<Option<Box<UvTexture>>, GltfError> {
    let index = info
        .get("index")
        .and_then(|v| v.as_u64())
        .ok_or_else(|| cx.err(format!("{what}: textureInfo without an index")))?
        as usize;
    let tex = doc.textures().nth(index).ok_or_else(|| {
        cx.err(format!(
            "{what}: textures[{index}] does not exist ({} textures)",
            doc.textures().len()
        ))
    })?;
    let mut tex_coord = info.get("texCoord").and_then(|v| v.as_u64()).unwrap_or(0) as u32;
    let transform = transform_from_json(
        info.get("extensions")
            .and_then(|e| e.get("KHR_texture_transform")),
        &mut tex_coord,
    );
    texture_source(cx, tex, tex_coord, transform, srgb, buffers, what)
}

/// The image, sampler and uv map of a texture (see [`texture_of`]).
fn texture_source(
    cx: &mut Ctx,
    tex: gltf::Texture,
    tex_coord: u32,
    transform: [f32; 6],
    srgb: bool,
    buffers: &[Vec<u8>],
    what: &str,
) -> Result<Option<Box<UvTexture>>, GltfError> {
    let elem = format!("{what} (textures[{}])", tex.index());
    if tex_coord != 0 {
        cx.warnings.push(format!("{elem}: texture coordinate set {tex_coord} is not read (only TEXCOORD_0): texture ignored"));
        return Ok(None);
    }
    let sampler = tex.sampler();
    if sampler.wrap_s() != gltf::texture::WrappingMode::Repeat
        || sampler.wrap_t() != gltf::texture::WrappingMode::Repeat
    {
        cx.warnings.push(format!("{elem}: clamped or mirrored wrapping is not supported (not yet implemented): the texture repeats"));
    }
    let nearest = sampler.mag_filter() == Some(gltf::texture::MagFilter::Nearest);
    let img = tex.source();
    let name = format!("images[{}]", img.index());
    let source = match img.source() {
        gltf::image::Source::View { view, .. } => {
            let buf = &buffers[view.buffer().index()];
            let end = view
                .offset()
                .checked_add(view.length())
                .filter(|e| *e <= buf.len())
                .ok_or_else(|| {
                    cx.err(format!(
                        "{name}: bufferViews[{}] runs past the end of its buffer",
                        view.index()
                    ))
                })?;
            ImageSource::Embedded {
                name,
                bytes: std::sync::Arc::new(buf[view.offset()..end].to_vec()),
            }
        }
        gltf::image::Source::Uri { uri, .. } => {
            if let Some(rest) = uri.strip_prefix("data:") {
                let (_, b64) = rest
                    .split_once(";base64,")
                    .ok_or_else(|| cx.err(format!("{name}: data URI is not base64")))?;
                let bytes = base64::engine::general_purpose::STANDARD
                    .decode(b64)
                    .map_err(|e| cx.err(format!("{name}: bad base64 data: {e}")))?;
                ImageSource::Embedded {
                    name,
                    bytes: std::sync::Arc::new(bytes),
                }
            } else {
                ImageSource::File(cx.file.parent().unwrap_or(Path::new(".")).join(uri))
            }
        }
    };
    Ok(Some(Box::new(UvTexture {
        source,
        srgb,
        nearest,
        transform,
    })))
}

fn map_material(
    cx: &mut Ctx,
    doc: &gltf::Document,
    m: &gltf::Material,
    buffers: &[Vec<u8>],
) -> Result<MappedMaterial, GltfError> {
    let idx = m.index().unwrap_or(0);
    let elem = format!("materials[{idx}]");
    let name = m.name().map(|n| format!(" '{n}'")).unwrap_or_default();
    let loc = cx.loc(format!("{elem}{name}"));
    let pbr = m.pbr_metallic_roughness();
    let bc = pbr.base_color_factor();
    let (metallic, roughness) = (pbr.metallic_factor(), pbr.roughness_factor());
    let ior = m.ior().unwrap_or(1.5);
    let mut used = Vec::new();
    let mut notes = Vec::new();
    let base_color_texture = match pbr.base_color_texture() {
        Some(i) => texture_of(
            cx,
            &i,
            true,
            buffers,
            &format!("{elem}{name} baseColorTexture"),
        )?,
        None => None,
    };
    let metallic_roughness_texture = match pbr.metallic_roughness_texture() {
        Some(i) => texture_of(
            cx,
            &i,
            false,
            buffers,
            &format!("{elem}{name} metallicRoughnessTexture"),
        )?,
        None => None,
    };
    for (slot, texture) in [
        ("baseColorTexture", &base_color_texture),
        ("metallicRoughnessTexture", &metallic_roughness_texture),
    ] {
        if let Some(t) = texture {
            let ext = if t.transform != [1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
                format!(", KHR_texture_transform {:?}", t.transform)
            } else {
                String::new()
            };
            notes.push(format!(
                "{slot}: {} {}{ext}",
                if t.srgb { "sRGB-decoded" } else { "linear" },
                if t.nearest { "nearest" } else { "bilinear" }
            ));
        }
    }
    let normal_texture = match m.normal_texture() {
        Some(nt) => {
            let mut tc = nt.tex_coord();
            let transform =
                transform_from_json(nt.extension_value("KHR_texture_transform"), &mut tc);
            let scale = nt.scale();
            if !scale.is_finite() {
                return Err(cx.err(format!(
                    "{elem}: normalTexture.scale must be finite, got {scale}"
                )));
            }
            texture_source(
                cx,
                nt.texture(),
                tc,
                transform,
                false,
                buffers,
                &format!("{elem}{name} normalTexture"),
            )?
            .map(|t| (t, scale))
        }
        None => None,
    };
    if let Some((t, scale)) = &normal_texture {
        let ext = if t.transform != [1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
            format!(", KHR_texture_transform {:?}", t.transform)
        } else {
            String::new()
        };
        notes.push(format!("normalTexture: linear {}, scale {scale}, tangent space from TANGENT (or generated from the uvs){ext}", if t.nearest { "nearest" } else { "bilinear" }));
    }
    // Emissive texture: sRGB colour data multiplying emissiveFactor x strength. The area light
    // looks its image up at the hit's uv without KHR_texture_transform, so a transformed one is
    // refused rather than shown in the wrong place.
    let emissive_texture = match m.emissive_texture() {
        Some(i) => texture_of(
            cx,
            &i,
            true,
            buffers,
            &format!("{elem}{name} emissiveTexture"),
        )?,
        None => None,
    };
    if let Some(t) = &emissive_texture {
        if t.transform != [1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
            return Err(cx.err(format!("{elem}{name}: KHR_texture_transform on emissiveTexture is not yet supported (not yet implemented)")));
        }
        notes.push(format!(
            "emissiveTexture: sRGB-decoded {}, times the emissive factor",
            if t.nearest { "nearest" } else { "bilinear" }
        ));
    }
    if m.occlusion_texture().is_some() {
        // Ambient occlusion is a rasteriser's stand-in for what the path tracer computes.
        cx.warnings.push(format!(
            "{elem}{name}: occlusionTexture ignored (a path tracer computes occlusion)"
        ));
    }
    // Alpha as opacity (the renderer's `mask`: light meets the surface with probability
    // `opacity`, else passes straight through): BLEND uses the factor's alpha, MASK makes it 0
    // or 1 against alphaCutoff (default 0.5). The base colour texture's alpha is not read.
    let opacity = match m.alpha_mode() {
        gltf::material::AlphaMode::Opaque => 1.0,
        gltf::material::AlphaMode::Blend => bc[3].clamp(0.0, 1.0),
        gltf::material::AlphaMode::Mask => {
            if bc[3] >= m.alpha_cutoff().unwrap_or(0.5) {
                1.0
            } else {
                0.0
            }
        }
    };
    // With a base colour texture, the texel's alpha (linear) times the factor's alpha, per hit
    // (BLEND), or 0/1 against alphaCutoff per texel (MASK).
    let alpha_texture = match (&base_color_texture, m.alpha_mode()) {
        (_, gltf::material::AlphaMode::Opaque) | (None, _) => None,
        (Some(t), mode) => {
            let cutoff =
                (mode == gltf::material::AlphaMode::Mask).then(|| m.alpha_cutoff().unwrap_or(0.5));
            Some((
                Box::new(UvTexture {
                    srgb: false,
                    ..(**t).clone()
                }),
                cutoff,
            ))
        }
    };
    if m.alpha_mode() != gltf::material::AlphaMode::Opaque {
        match &alpha_texture {
            None => used.push(format!("alphaMode {:?}: opacity {opacity} (mask)", m.alpha_mode())),
            Some((_, Some(c))) => used.push(format!("alphaMode MASK: opacity 1 where {} x texture alpha >= {c}, else 0, per texel (mask)", bc[3])),
            Some((_, None)) => used.push(format!("alphaMode BLEND: opacity {} x texture alpha, per texel (mask)", bc[3])),
        }
    }
    let base_color = SpectrumDesc::Rgb([bc[0], bc[1], bc[2]]);
    if m.ior().is_some() {
        used.push(format!("KHR_materials_ior (ior {ior})"));
    }
    let iridescence = m.extension_value("KHR_materials_iridescence");
    let textured = base_color_texture.is_some() || metallic_roughness_texture.is_some();
    let mut kind = BsdfKind::GltfPbr {
        base_color: base_color.clone(),
        metallic,
        roughness,
        ior,
        base_color_texture,
        metallic_roughness_texture,
    };
    let mut interior = None;
    let mut mapping = format!("gltf metallic-roughness: base colour {:?}, metallic {metallic}, roughness {roughness} (alpha {:.4}), dielectric ior {ior}", [bc[0], bc[1], bc[2]], roughness * roughness);
    if let Some(t) = m.transmission().filter(|t| t.transmission_factor() > 0.0) {
        let f = t.transmission_factor();
        let opaque = kind.clone();
        if textured {
            notes.push("base colour / metallic-roughness textures ignored (transmissive)".into());
        }
        if t.transmission_texture().is_some() {
            cx.warnings.push(format!(
                "{elem}{name}: transmissionTexture ignored (textures are not yet implemented)"
            ));
        }
        let vol = m.volume().filter(|v| v.thickness_factor() > 0.0);
        let alpha = roughness * roughness;
        if let Some(v) = &vol {
            kind = if alpha < 1e-3 {
                mapping = format!("dielectric, ior {ior}");
                BsdfKind::Dielectric {
                    int_ior: ior,
                    ext_ior: 1.0,
                }
            } else {
                mapping = format!("roughdielectric GGX alpha {alpha:.4}, ior {ior}");
                BsdfKind::RoughDielectric {
                    int_ior: ior,
                    ext_ior: 1.0,
                    distribution: "ggx".into(),
                    alpha_u: alpha,
                    alpha_v: alpha,
                }
            };
            let (d, c) = (v.attenuation_distance(), v.attenuation_color());
            let mut vol_note = format!(
                "KHR_materials_volume (thicknessFactor {} only marks a volume)",
                v.thickness_factor()
            );
            if d.is_finite() && d > 0.0 {
                // Beer-Lambert: white light is c after distance d, so exp(-sigma_t d) = c.
                let sigma = c.map(|ci| {
                    if ci > 0.0 {
                        -ci.min(1.0).ln() / d
                    } else {
                        f32::MAX.sqrt()
                    }
                });
                interior = Some(MediumDesc {
                    loc: loc.clone(),
                    sigma_t: SpectrumDesc::Rgb(sigma),
                });
                vol_note = format!(
                    "{vol_note}: interior medium sigma_t = -ln({c:?})/{d} = {sigma:?} per m"
                );
            } else {
                vol_note = format!("{vol_note}: no attenuation (attenuationDistance infinite)");
            }
            used.push(vol_note);
        } else {
            mapping = format!("thindielectric (thin-walled: no volume), ior {ior}");
            if alpha >= 1e-3 {
                notes.push(format!(
                    "roughness {roughness} ignored (thin-walled transmission is smooth)"
                ));
            }
            kind = BsdfKind::ThinDielectric {
                int_ior: ior,
                ext_ior: 1.0,
            };
        }
        if bc[..3].iter().any(|c| (c - 1.0).abs() > 1e-6) {
            notes.push("baseColor tint of transmitted light ignored".into());
        }
        // A partial transmission: a blend of the opaque material and the transmissive one.
        // glTF mixes only the dielectric's diffuse base with the transmission lobe, under the
        // same specular layer, and leaves the metal part alone: the blend weight is
        // f (1 - metallic), and the specular layer is the opaque material's GGX reflection in
        // one share and the dielectric's Fresnel reflection in the other (the same ior and
        // roughness, so nearly the same lobe).
        let w = f.min(1.0) * (1.0 - metallic.clamp(0.0, 1.0));
        if w < 1.0 {
            mapping = format!(
                "blend of {:.4} x ({mapping}) and {:.4} x (the opaque metallic-roughness material)",
                w,
                1.0 - w
            );
            notes.push(format!("transmissionFactor {f} with metallic {metallic}: blend weight f (1 - metallic) = {w} (approximates glTF's layering: see the module doc)"));
            kind = BsdfKind::Blend {
                weight: w,
                weight_texture: None,
                first: Box::new(BsdfDesc {
                    loc: loc.clone(),
                    id: None,
                    kind: opaque,
                }),
                second: Box::new(BsdfDesc {
                    loc: loc.clone(),
                    id: None,
                    kind,
                }),
            };
        }
        used.push(format!("KHR_materials_transmission (factor {f})"));
    } else if m.volume().is_some() {
        notes.push("KHR_materials_volume without transmission has no effect".into());
    }
    if let Some(ir) = iridescence {
        let factor = ext_f32(Some(ir), "iridescenceFactor", 0.0);
        if factor > 0.0 {
            let film_ior = ext_f32(Some(ir), "iridescenceIor", 1.3);
            let thickness = ext_f32(Some(ir), "iridescenceThicknessMaximum", 400.0);
            if !(thickness >= 0.0
                && thickness.is_finite()
                && film_ior >= 1.0
                && film_ior.is_finite())
            {
                return Err(cx.err(format!("{elem}: KHR_materials_iridescence needs thickness >= 0 and ior >= 1, got {thickness}, {film_ior}")));
            }
            // iridescenceThicknessTexture: thickness = mix(min, max, green) per texel.
            let thickness_texture = match ir.get("iridescenceThicknessTexture") {
                Some(info) => {
                    let min_nm = ext_f32(Some(ir), "iridescenceThicknessMinimum", 100.0);
                    if !(min_nm >= 0.0 && min_nm.is_finite()) {
                        return Err(cx.err(format!("{elem}: iridescenceThicknessMinimum must be finite and >= 0, got {min_nm}")));
                    }
                    json_texture(
                        cx,
                        doc,
                        info,
                        false,
                        buffers,
                        &format!("{elem}{name} iridescenceThicknessTexture"),
                    )?
                    .map(|t| (t, min_nm))
                }
                None => None,
            };
            // iridescenceTexture: its red channel multiplies the factor per texel.
            let factor_texture = match ir.get("iridescenceTexture") {
                Some(info) => json_texture(
                    cx,
                    doc,
                    info,
                    false,
                    buffers,
                    &format!("{elem}{name} iridescenceTexture"),
                )?,
                None => None,
            };
            // A partial iridescence blends the material without the film and the film; with a
            // partial transmission already blended, nested blends are not supported: factor 1.
            let partial = (factor < 1.0 || factor_texture.is_some())
                && !matches!(kind, BsdfKind::Blend { .. });
            if (factor < 1.0 || factor_texture.is_some()) && !partial {
                cx.warnings.push(format!("{elem}{name}: iridescenceFactor {factor} and iridescenceTexture treated as 1: the material already blends a partial transmission (nested blends are not yet implemented)"));
            }
            let without_film = kind.clone();
            if textured {
                notes.push("base colour / metallic-roughness textures ignored (thin film)".into());
            }
            // An opaque base of the reflectance F0 at normal incidence: n from F0 with k = 0.
            let n_of = |f0: f32| {
                let s = f0.clamp(0.0, 0.999).sqrt();
                (1.0 + s) / (1.0 - s)
            };
            let eta = if metallic >= 0.5 {
                SpectrumDesc::Rgb([n_of(bc[0]), n_of(bc[1]), n_of(bc[2])])
            } else {
                SpectrumDesc::Constant(ior)
            };
            let alpha = roughness * roughness;
            if alpha < 1e-3 {
                mapping = format!("thinfilm: {thickness} nm film of ior {film_ior} over an opaque base of index {eta:?} (k = 0); smooth, diffuse dropped");
                kind = BsdfKind::ThinFilm {
                    thickness,
                    film_ior,
                    ext_ior: 1.0,
                    int_ior: None,
                    eta,
                    k: SpectrumDesc::Constant(0.0),
                };
            } else {
                mapping = format!("roughthinfilm: {thickness} nm film of ior {film_ior} over an opaque base of index {eta:?} (k = 0), GGX alpha {alpha:.4}; diffuse dropped");
                kind = BsdfKind::RoughThinFilm {
                    thickness,
                    film_ior,
                    ext_ior: 1.0,
                    int_ior: None,
                    eta,
                    k: SpectrumDesc::Constant(0.0),
                    distribution: "ggx".into(),
                    alpha_u: alpha,
                    alpha_v: alpha,
                };
            }
            if partial {
                notes.push(format!("iridescenceFactor {factor}: blend of {factor} x film and {} x the material without it (approximates glTF's Fresnel mix: see the module doc)", 1.0 - factor));
                mapping = format!(
                    "blend of {factor} x ({mapping}) and {} x (the material without the film)",
                    1.0 - factor
                );
                let film = BsdfDesc {
                    loc: loc.clone(),
                    id: None,
                    kind,
                };
                if factor_texture.is_some() {
                    notes.push(
                        "iridescenceTexture: its red channel multiplies the blend weight per texel"
                            .into(),
                    );
                }
                let weight_texture = factor_texture.map(|t| (t, pt_scene::TextureChannel::Red));
                kind = BsdfKind::Blend {
                    weight: factor,
                    weight_texture,
                    first: Box::new(BsdfDesc {
                        loc: loc.clone(),
                        id: None,
                        kind: without_film,
                    }),
                    second: Box::new(film),
                };
            }
            if let Some((texture, min_nm)) = thickness_texture {
                notes.push(format!("iridescenceThicknessTexture: thickness = {min_nm} + ({thickness} - {min_nm}) x green, nm, per texel"));
                kind = BsdfKind::FilmThicknessTexture {
                    texture,
                    min_nm,
                    max_nm: thickness,
                    inner: Box::new(BsdfDesc {
                        loc: loc.clone(),
                        id: None,
                        kind,
                    }),
                };
            }
            used.push(format!("KHR_materials_iridescence (factor {factor}, ior {film_ior}, thickness max {thickness} nm)"));
        }
    }
    let ef = m.emissive_factor();
    let strength = m.emissive_strength().unwrap_or(1.0);
    if m.emissive_strength().is_some() {
        used.push(format!("KHR_materials_emissive_strength ({strength})"));
    }
    let emission = if ef.iter().any(|c| *c > 0.0) && strength > 0.0 {
        let e = ef.map(|c| c * strength);
        if e.iter().any(|c| !c.is_finite() || *c < 0.0) {
            return Err(cx.err(format!("{elem}: emissive must be finite and >= 0")));
        }
        notes.push(format!("emits radiance {e:?} (front side)"));
        Some(SpectrumDesc::Rgb(e))
    } else {
        None
    };
    if !matches!(
        kind,
        BsdfKind::Dielectric { .. }
            | BsdfKind::RoughDielectric { .. }
            | BsdfKind::ThinDielectric { .. }
    ) {
        // glTF's doubleSided only controls back-face culling in rasterisers; a path tracer sees
        // back faces anyway, so opaque materials shade both sides.
        kind = BsdfKind::TwoSided {
            inner: Box::new(BsdfDesc {
                loc: loc.clone(),
                id: None,
                kind,
            }),
        };
    }
    if let Some((texture, cutoff)) = alpha_texture {
        let factor = bc[3].clamp(0.0, 1.0);
        kind = BsdfKind::OpacityTexture {
            texture,
            channel: pt_scene::TextureChannel::Alpha,
            factor,
            cutoff,
            inner: Box::new(BsdfDesc {
                loc: loc.clone(),
                id: None,
                kind,
            }),
        };
    } else if opacity < 1.0 {
        kind = BsdfKind::Mask {
            opacity,
            inner: Box::new(BsdfDesc {
                loc: loc.clone(),
                id: None,
                kind,
            }),
        };
    }
    if let Some((texture, scale)) = normal_texture {
        kind = BsdfKind::NormalMap {
            texture,
            scale,
            gltf: true,
            inner: Box::new(BsdfDesc {
                loc: loc.clone(),
                id: None,
                kind,
            }),
        };
    }
    cx.summary.push(format!("  {elem}{name}: {mapping}"));
    for u in &used {
        cx.summary.push(format!("      extension {u}"));
    }
    for nt in &notes {
        cx.summary.push(format!("      note: {nt}"));
    }
    let emissive_texture = emission.as_ref().and(emissive_texture);
    Ok(MappedMaterial {
        bsdf: BsdfDesc {
            loc,
            id: Some(m.name().map_or(format!("material{idx}"), str::to_string)),
            kind,
        },
        emission,
        emissive_texture,
        interior,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A one-triangle glTF (vertices (0,0,0), (1,0,0), (0,1,0), normals +z) under one node with
    /// the given extra node properties, plus `extra` top-level members.
    fn triangle(node: &str, extra: &str) -> Vec<u8> {
        let mut bytes = Vec::new();
        for v in [
            [0.0f32, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, 1.0],
        ] {
            for c in v {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
        let b64 = base64::engine::general_purpose::STANDARD.encode(&bytes);
        format!(
            r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}],
            "nodes": [{{"mesh": 0 {node}}}],
            "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "NORMAL": 1}}}}]}}],
            "buffers": [{{"byteLength": 72, "uri": "data:application/octet-stream;base64,{b64}"}}],
            "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 36}}, {{"buffer": 0, "byteOffset": 36, "byteLength": 36}}],
            "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]}},
                          {{"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3"}}]
            {extra}}}"#
        )
        .into_bytes()
    }

    fn mesh(g: &GltfScene) -> &TriangleMesh {
        match &g.desc.shapes[0].geometry {
            Geometry::Mesh(m) => m,
            _ => unreachable!(),
        }
    }

    #[test]
    fn mirrored_node_keeps_front_side_with_the_normals() {
        // A scale of -1 in x mirrors the triangle: the winding must be reversed so that the
        // geometric normal (p1 - p0) x (p2 - p0) still points along the (transformed) vertex
        // normal, +z.
        for (node, flipped) in [("", false), (r#", "scale": [-1, 1, 1]"#, true)] {
            let g = load_slice(
                &triangle(node, ""),
                Path::new("t.gltf"),
                &LoadOptions::default(),
            )
            .unwrap();
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
        let g = load_slice(
            &triangle("", ""),
            Path::new("t.gltf"),
            &LoadOptions::default(),
        )
        .unwrap();
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
        let extra = r#", "cameras": [{"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}},
                                      {"type": "orthographic", "orthographic": {"xmag": 1, "ymag": 1, "znear": 0.1, "zfar": 10}}]"#;
        let node =
            r#", "children": [1, 2]}, {"camera": 0, "translation": [0, 0, 5]}, {"camera": 1"#;
        let bytes = triangle(node, extra);
        let g = load_slice(&bytes, Path::new("t.gltf"), &LoadOptions::default()).unwrap();
        let c = &g.desc.camera;
        assert!(
            (c.to_world.transform_point3(Vec3::ZERO) - Vec3::new(0.0, 0.0, 5.0)).length() < 1e-6
        );
        assert!((c.to_world.transform_vector3(Vec3::Z) - Vec3::NEG_Z).length() < 1e-6);
        assert!(
            matches!(c.projection, Projection::Perspective { fov_deg, fov_axis: FovAxis::Y } if (fov_deg - 0.5f32.to_degrees()).abs() < 1e-4)
        );
        let e = load_slice(
            &bytes,
            Path::new("t.gltf"),
            &LoadOptions { camera: Some(1) },
        )
        .unwrap_err();
        assert!(e.message.contains("orthographic"), "{e}");
        let e = load_slice(
            &bytes,
            Path::new("t.gltf"),
            &LoadOptions { camera: Some(2) },
        )
        .unwrap_err();
        assert!(e.message.contains("2 camera(s)"), "{e}");
    }
}
