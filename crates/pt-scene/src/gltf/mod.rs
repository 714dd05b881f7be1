//! glTF 2.0 reader: a `.gltf` (JSON with external or `data:` buffers) or `.glb` file becomes the
//! renderer's scene description ([`SceneDesc`]), in world space, metres (glTF's unit). The
//! XML loader's `<shape type="gltf">` reads only the geometry, through [`load_mesh`].
//!
//! What is read, and how each part maps (also printed by `pt info model.glb`):
//!
//! | glTF                                  | renderer                                                        |
//! |---------------------------------------|-----------------------------------------------------------------|
//! | mesh primitive (triangles)            | one `TriangleMesh` shape, positions/normals by the node's world matrix (normals by its inverse transpose, winding reversed when the determinant is negative), `TEXCOORD_0` |
//! | `COLOR_0` (VEC3 or VEC4; float, or normalized unsigned byte or short) | the mesh attribute `vertex_color` (3 linear values per vertex, alpha dropped), which a `mesh_attribute` texture reads; glTF's multiplication of the base colour by it is not done (a warning says so) |
//! | node camera (perspective)             | the first one in node order, or `--camera N`; glTF looks down -z with +x right, the renderer's camera space looks down +z with +x left: `to_world = node * diag(-1, 1, -1)`; `yfov` is the vertical field of view |
//! | no camera                             | a default camera: vertical fov 45 deg, on the +z side of the bounds' centre, looking down -z, at the distance where the bounding sphere fits the vertical fov (x 1.1) |
//! | (film)                                | 320 x 240 pixels (height from the camera's `aspectRatio`), box filter, 64 spp, `volpath` (path tracing with Beer-Lambert media) with unlimited depth; `pt render --width/--height/--spp` override |
//! | no light and no emissive material     | a default environment: `constant` radiance 1 (white)             |
//! | `pbrMetallicRoughness`                | `BsdfKind::GltfPbr`, two-sided: base colour = `baseColorFactor` x `baseColorTexture`, metallic = `metallicFactor` x blue, roughness = `roughnessFactor` x green of `metallicRoughnessTexture` (`TextureDesc::Scaled`); alpha = roughness^2. Primitives without a material get glTF's default (white, metallic 1, roughness 1), two-sided too |
//! | `emissiveFactor` x `KHR_materials_emissive_strength` (x `emissiveTexture`) | an area emitter of that radiance (`AreaEmitterDesc::radiance`, the texture with its KHR_texture_transform) on every primitive with the material |
//! | `KHR_materials_transmission` (+ `KHR_materials_ior`) | with `KHR_materials_volume` thickness > 0: `dielectric` (roughness 0) or `roughdielectric` (GGX, alpha = roughness^2) of index `ior`; without volume (glTF's thin-walled case): `thindielectric`; a factor f < 1 (or metallic > 0): `blendbsdf` of the opaque material and that, weight f (1 - metallic) (see Partial factors) |
//! | `KHR_materials_volume`                | `ShapeDesc::interior`, Beer-Lambert: `sigma_t = -ln(attenuationColor) / attenuationDistance` per channel (the colour white light turns into after travelling `attenuationDistance`); `thicknessFactor` only selects volume vs thin-walled: the path tracer measures the real distance inside the mesh |
//! | `KHR_materials_iridescence`           | `thinfilm` (roughness 0) or `roughthinfilm` (GGX, alpha = roughness^2): thickness `iridescenceThicknessMaximum` nm, or per texel `mix(iridescenceThicknessMinimum, iridescenceThicknessMaximum, green)` of `iridescenceThicknessTexture`; film index `iridescenceIor`, base: an opaque (conductor) base of index `n = (1 + sqrt(F0))/(1 - sqrt(F0))`, `k = 0` from the base colour (metallic >= 0.5) or `n = ior` (metallic < 0.5); the diffuse base is dropped; `iridescenceFactor` f < 1 (or an `iridescenceTexture`): `blendbsdf` of the material without the film and the film, weight f (x red of the texture) |
//! | `baseColorTexture`, `metallicRoughnessTexture`, `KHR_texture_transform` | factors times texels at the hit's uv (see Textures below) |
//! | `normalTexture` (`scale`)              | `normalmap` around the material: tangent space from `TANGENT` (xyz by the node's matrix, w negated under a mirroring node) or generated from the uvs (see Normal maps below) |
//! | `alphaMode` BLEND / MASK              | `mask` around the material, opacity = alpha (BLEND) or alpha >= alphaCutoff (MASK), alpha = baseColorFactor alpha x the base colour texture's alpha per texel |
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
//! **Textures.** Each glTF texture becomes a `TextureDesc::Bitmap`: PNG or JPEG, embedded or a
//! file; colour textures (`baseColorTexture`, `emissiveTexture`) sRGB-decoded, data textures
//! (`metallicRoughnessTexture`, `normalTexture`, the iridescence textures) read raw; `magFilter`
//! NEAREST or bilinear (no mipmaps); `wrapS` CLAMP_TO_EDGE, MIRRORED_REPEAT or REPEAT (a
//! different `wrapT` is warned about and `wrapS` used for both); KHR_texture_transform (offset,
//! rotation, scale, texCoord) as the bitmap's `to_uv`, looked up at the hit's `TEXCOORD_0`.
//! Factors multiply texels through `TextureDesc::Scaled` (one channel selected where glTF reads
//! one). In spectral mode each base colour texel is upsampled once at load (Jakob & Hanika
//! 2019, as a bounded reflectance) and the interpolated texel spectra multiply the factor's
//! spectrum (pt-render's `spectral_texture`).
//!
//! **Alpha.** `alphaMode` BLEND becomes the renderer's `mask` with opacity = baseColorFactor's
//! alpha times the base colour texture's alpha (read raw: alpha is linear; 1 without an alpha
//! channel) at the hit; MASK an opacity of 0 or 1 per texel against `alphaCutoff` (0.5 by
//! default). Without a base colour texture the opacity is a constant (and no mask at all when
//! it is 1). Shadow rays are blocked by masked surfaces whatever their opacity, as in Mitsuba's
//! `path`: light through the holes is found by BSDF sampling (the mask's pass-through lobe),
//! the same for every texel.
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
//! the iridescence factor is treated as 1 (the renderer does not nest blends). The transmissive
//! and thin-film models take constant roughness: their textures (base colour,
//! metallic-roughness) are dropped, with a note.
//!
//! `emissiveTexture` (sRGB) multiplies emissiveFactor x strength per texel on the area light
//! (in spectral mode upsampled per texel, and the factor's spectrum times the texel's: exact
//! when either is grey). `occlusionTexture` is ignored with a warning: a path tracer computes
//! occlusion itself.
//!
//! **Not yet** (warned about, never silently): transmission textures,
//! texture coordinate sets other than 0, different `wrapS` and `wrapT`, the base colour's
//! `COLOR_0` factor, orthographic cameras, non-triangle primitives, sparse accessors, skins and
//! morph targets.
//!
//! Errors (malformed JSON or GLB, truncated or missing buffers, accessors out of range or of a
//! type glTF does not allow for their attribute, indices out of range, unsupported *required*
//! extensions) are [`GltfError`]s naming the file and the glTF element
//! (`meshes[2].primitives[0]`); unsupported *optional* extensions are warnings naming them. The
//! reader never panics on bad input.

mod light;
mod material;
mod mesh;
mod texture;

#[cfg(test)]
mod tests;

pub use mesh::generate_tangents;

use crate::ir::{
    AreaEmitterDesc, CameraDesc, FilmDesc, FilterDesc, FovAxis, Geometry, ImageSource,
    IntegratorDesc, IntegratorKind, Projection, RadiosityOptions, SamplerDesc, SceneDesc,
    ShapeDesc, SourceLoc, TriangleMesh,
};
use glam::Mat4;
use gltf::json::validation::Validate as _;
use light::CameraNode;
use material::MappedMaterial;
use std::collections::HashMap;
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
/// Samples per pixel (glTF has no render settings).
const DEFAULT_SPP: u32 = 64;

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

/// Every triangle primitive of a glTF file's scene as one mesh (node transforms applied;
/// normals, texture coordinates and mesh attributes such as `vertex_color` kept when every
/// primitive has them), for `<shape type="gltf">` in a Mitsuba XML scene. Errors name the file
/// and the element.
pub fn load_mesh(path: &Path) -> Result<TriangleMesh, String> {
    let g = load(path, &LoadOptions::default()).map_err(|e| e.to_string())?;
    let meshes: Vec<&TriangleMesh> = g
        .desc
        .shapes
        .iter()
        .filter_map(|s| match &s.geometry {
            Geometry::Mesh(m) => Some(m),
            Geometry::Sphere { .. }
            | Geometry::Disk(_)
            | Geometry::Cylinder { .. }
            | Geometry::SdfGrid(_)
            | Geometry::Curves(_) => None,
        })
        .collect();
    if meshes.is_empty() {
        return Err(format!("{}: no triangles", path.display()));
    }
    Ok(mesh::merge(&meshes))
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

/// The state of one read: the file (for messages), what is reported, and the images read so
/// far (each glTF image is decoded from its buffer or data URI once, then shared).
struct Ctx<'a> {
    file: &'a Path,
    warnings: Vec<String>,
    summary: Vec<String>,
    images: HashMap<usize, ImageSource>,
}

impl<'a> Ctx<'a> {
    fn new(file: &'a Path) -> Self {
        Ctx {
            file,
            warnings: Vec::new(),
            summary: Vec::new(),
            images: HashMap::new(),
        }
    }

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

    /// The folder relative URIs are resolved from.
    fn dir(&self) -> &Path {
        self.file.parent().unwrap_or(Path::new("."))
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
    let mut cx = Ctx::new(path);
    let gltf = parse(&mut cx, bytes)?;
    let doc = &gltf.document;
    let buffers = mesh::load_buffers(&cx, doc, gltf.blob.as_deref())?;
    let mut desc = default_desc(&cx);
    let materials = material::map_materials(&mut cx, doc, &buffers)?;
    desc.bsdfs = materials.iter().map(|m| m.bsdf.clone()).collect();
    let mut walk = Walk {
        buffers: &buffers,
        materials: &materials,
        default_material: None,
        cameras: Vec::new(),
        mesh_lines: Vec::new(),
        coloured: Vec::new(),
    };
    walk.nodes(&mut cx, doc, &mut desc)?;
    if let Some(first) = walk.coloured.first() {
        let others = match walk.coloured.len() - 1 {
            0 => String::new(),
            n => format!(" and {n} other primitive(s)"),
        };
        cx.warnings.push(format!("{first}{others}: COLOR_0 is read as the mesh attribute vertex_color but does not multiply the base colour (not yet implemented)"));
    }
    summarise_meshes(&mut cx, &desc, walk.mesh_lines);
    let cameras = walk.cameras;
    light::set_camera(&mut cx, &cameras, opts.camera, &mut desc)?;
    light::finish_lights(&mut cx, &mut desc);
    Ok(GltfScene {
        desc,
        warnings: cx.warnings,
        summary: cx.summary,
    })
}

/// Parses the JSON or GLB, refuses unsupported required extensions, warns about ignored
/// optional ones, and validates the document (indices in range, required members present), so
/// that the gltf crate's accessors cannot panic later.
fn parse(cx: &mut Ctx, bytes: &[u8]) -> Result<gltf::Gltf, GltfError> {
    let gltf = gltf::Gltf::from_slice_without_validation(bytes)
        .map_err(|e| cx.err(format!("malformed glTF: {e}")))?;
    let doc = &gltf.document;
    // Extensions first (the gltf crate's validation would call every extension it does not
    // model "unsupported", including ones this reader handles from the raw JSON).
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
    check_positions(cx, root)?;
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
    texture::check_images(cx, root)?;
    Ok(gltf)
}

/// Checks that every primitive's `POSITION` names an existing accessor, which the gltf crate's
/// validation assumes (it indexes the accessor list with it unchecked).
fn check_positions(cx: &Ctx, root: &gltf::json::Root) -> Result<(), GltfError> {
    let position = gltf::json::validation::Checked::Valid(gltf::Semantic::Positions);
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let index = prim.attributes.get(&position).map(|i| i.value());
            if let Some(i) = index.filter(|i| *i >= root.accessors.len()) {
                return Err(cx.err(format!(
                    "meshes[{m}].primitives[{p}]: POSITION is accessors[{i}], which does not exist ({} accessors)",
                    root.accessors.len()
                )));
            }
        }
    }
    Ok(())
}

/// The scene before the file's contents: default camera, film, sampler and integrator (see
/// the module doc), no shapes or lights.
fn default_desc(cx: &Ctx) -> SceneDesc {
    SceneDesc {
        source: cx.file.to_path_buf(),
        camera: CameraDesc {
            loc: cx.loc("camera".into()),
            projection: Projection::Perspective {
                fov_deg: DEFAULT_FOV_Y_DEG,
                fov_axis: FovAxis::Y,
            },
            to_world: Mat4::IDENTITY,
            near_clip: 0.01,
            far_clip: 1e4,
            principal_point_offset: [0.0; 2],
        },
        camera_medium: None,
        // Box filter: each pixel is the plain average over its own footprint (glTF has no film
        // settings; Mitsuba's default Gaussian would blur across neighbours).
        film: FilmDesc::new(
            DEFAULT_WIDTH,
            DEFAULT_HEIGHT,
            FilterDesc::Box { radius: 0.5 },
        ),
        sampler: SamplerDesc {
            sample_count: DEFAULT_SPP,
            seed: 0,
            kind: crate::SamplerKind::Independent,
        },
        integrator: IntegratorDesc {
            kind: IntegratorKind::VolPath,
            max_depth: -1,
            rr_depth: 5,
            hide_emitters: false,
            light_sampling: true,
            moment: None,
            aov: None,
            radiosity: RadiosityOptions::default(),
            loc: cx.loc("integrator".into()),
        },
        shapes: Vec::new(),
        bsdfs: Vec::new(),
        lights: Vec::new(),
        groups: Vec::new(),
        instances: Vec::new(),
        sensor_target: None,
        batch: Vec::new(),
    }
}

/// The nodes the scene graph is walked from: the default scene's (or the first scene's), or,
/// without scenes, every node that is nobody's child.
fn scene_roots(doc: &gltf::Document) -> Vec<gltf::Node<'_>> {
    if let Some(s) = doc.default_scene().or_else(|| doc.scenes().next()) {
        return s.nodes().collect();
    }
    let mut is_child = vec![false; doc.nodes().len()];
    for n in doc.nodes() {
        for c in n.children() {
            is_child[c.index()] = true;
        }
    }
    doc.nodes().filter(|n| !is_child[n.index()]).collect()
}

/// The walk over the scene graph: what it reads from and what it collects besides the scene.
struct Walk<'d, 'b> {
    buffers: &'b [Vec<u8>],
    /// The file's materials, by index.
    materials: &'b [MappedMaterial],
    /// glTF's default material, with its index in `SceneDesc::bsdfs`, once a primitive needs it.
    default_material: Option<(MappedMaterial, usize)>,
    /// The nodes with a camera, in walk order.
    cameras: Vec<CameraNode<'d>>,
    /// One `pt info` line per primitive.
    mesh_lines: Vec<String>,
    /// The primitives with `COLOR_0`.
    coloured: Vec<String>,
}

impl<'d> Walk<'d, '_> {
    /// Walks the scene graph depth first in node order, accumulating world transforms, and adds
    /// every triangle primitive as a shape and every punctual light as a light; cameras are
    /// collected.
    fn nodes(
        &mut self,
        cx: &mut Ctx,
        doc: &'d gltf::Document,
        desc: &mut SceneDesc,
    ) -> Result<(), GltfError> {
        let mut stack: Vec<(gltf::Node, Mat4, usize)> = scene_roots(doc)
            .into_iter()
            .rev()
            .map(|n| (n, Mat4::IDENTITY, 0))
            .collect();
        let mut visited = 0usize;
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
            if let Some(camera) = node.camera() {
                self.cameras.push(CameraNode {
                    camera,
                    world,
                    node: node.index(),
                });
            }
            if let Some(l) = node.light() {
                desc.lights
                    .push(light::map_light(cx, &l, world, node.index())?);
            }
            if let Some(mesh) = node.mesh() {
                self.mesh(cx, &node, &mesh, world, desc)?;
            }
            for c in node.children().collect::<Vec<_>>().into_iter().rev() {
                stack.push((c, world, depth + 1));
            }
        }
        Ok(())
    }

    /// Adds the triangle primitives of a node's mesh (others are skipped with a warning).
    fn mesh(
        &mut self,
        cx: &mut Ctx,
        node: &gltf::Node,
        mesh: &gltf::Mesh,
        world: Mat4,
        desc: &mut SceneDesc,
    ) -> Result<(), GltfError> {
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
            self.primitive(cx, node, mesh, &prim, world, desc)?;
        }
        Ok(())
    }

    /// Adds one triangle primitive as a shape with its material's BSDF, emitter and medium.
    fn primitive(
        &mut self,
        cx: &mut Ctx,
        node: &gltf::Node,
        mesh: &gltf::Mesh,
        prim: &gltf::Primitive,
        world: Mat4,
        desc: &mut SceneDesc,
    ) -> Result<(), GltfError> {
        let elem = &format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
        let (mm, bsdf) = match prim.material().index() {
            Some(i) => (&self.materials[i], i),
            None => {
                let (mm, i) = self.default_material.get_or_insert_with(|| {
                    let mm = material::default_material(cx);
                    desc.bsdfs.push(mm.bsdf.clone());
                    (mm, desc.bsdfs.len() - 1)
                });
                (&*mm, *i)
            }
        };
        let tri = mesh::read_primitive(cx, prim, self.buffers, world, elem, mm.normal_mapped())?;
        if prim.get(&gltf::Semantic::Colors(0)).is_some() {
            self.coloured.push(elem.clone());
        }
        self.mesh_lines.push(format!(
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
                loc,
                radiance,
                primaries: None,
            }),
            interior: mm.interior.clone(),
            exterior: None,
        });
        Ok(())
    }
}

/// The `pt info` lines on the meshes: a total, then one line per primitive.
fn summarise_meshes(cx: &mut Ctx, desc: &SceneDesc, lines: Vec<String>) {
    let triangles: usize = desc
        .shapes
        .iter()
        .map(|s| match &s.geometry {
            Geometry::Mesh(m) => m.indices.len(),
            Geometry::Sphere { .. }
            | Geometry::Disk(_)
            | Geometry::Cylinder { .. }
            | Geometry::SdfGrid(_)
            | Geometry::Curves(_) => 0,
        })
        .sum();
    cx.summary.push(format!(
        "meshes      {} primitive(s), {triangles} triangles",
        desc.shapes.len()
    ));
    cx.summary.extend(lines);
}
