//! Geometry: buffers, accessors (checked before the gltf crate reads them), triangle
//! primitives in world space with their vertex colours, and tangents.

use super::{Ctx, GltfError};
use crate::ir::{AttributeKind, MeshAttribute, TriangleMesh};
use base64::Engine as _;
use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};
use gltf::accessor::{DataType, Dimensions};

/// The mesh attribute `COLOR_0` becomes.
pub(super) const VERTEX_COLOR: &str = "vertex_color";

/// The bytes of a `data:` URI (base64), or `None` when `uri` is not one. `elem` names the
/// glTF element in errors.
pub(super) fn data_uri(cx: &Ctx, uri: &str, elem: &str) -> Option<Result<Vec<u8>, GltfError>> {
    let rest = uri.strip_prefix("data:")?;
    Some(match rest.split_once(";base64,") {
        None => Err(cx.err(format!("{elem}: data URI is not base64"))),
        Some((_, b64)) => base64::engine::general_purpose::STANDARD
            .decode(b64)
            .map_err(|e| cx.err(format!("{elem}: bad base64 data: {e}"))),
    })
}

/// Data of every buffer: the GLB binary chunk, a `data:` URI (base64) or a file beside the
/// glTF. Each must hold at least `byteLength` bytes (a shorter one is a truncated file).
pub(super) fn load_buffers(
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
            gltf::buffer::Source::Uri(uri) => match data_uri(cx, uri, &elem) {
                Some(bytes) => bytes?,
                None => {
                    let p = cx.dir().join(uri);
                    std::fs::read(&p).map_err(|e| {
                        cx.err(format!("{elem}: cannot read '{}': {e}", p.display()))
                    })?
                }
            },
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

/// The element types glTF allows for an attribute: component types and dimensions.
struct Allowed {
    types: &'static [DataType],
    dims: &'static [Dimensions],
}

const POSITION: Allowed = Allowed {
    types: &[DataType::F32],
    dims: &[Dimensions::Vec3],
};
const NORMAL: Allowed = POSITION;
const TEXCOORD: Allowed = Allowed {
    types: &[DataType::F32, DataType::U8, DataType::U16],
    dims: &[Dimensions::Vec2],
};
const INDICES: Allowed = Allowed {
    types: &[DataType::U8, DataType::U16, DataType::U32],
    dims: &[Dimensions::Scalar],
};
const TANGENT: Allowed = Allowed {
    types: &[DataType::F32],
    dims: &[Dimensions::Vec4],
};
const COLOR: Allowed = Allowed {
    types: &[DataType::F32, DataType::U8, DataType::U16],
    dims: &[Dimensions::Vec3, Dimensions::Vec4],
};

/// Checks that an accessor has a type glTF allows for `what` and that every element lies
/// inside its buffer view and buffer, so the gltf crate's reader can never panic, read out of
/// bounds or return short data.
fn check_accessor(
    cx: &Ctx,
    acc: &gltf::Accessor,
    buffers: &[Vec<u8>],
    (what, allowed): (&str, &Allowed),
    elem: &str,
) -> Result<(), GltfError> {
    let name = format!("{elem} {what} (accessors[{}])", acc.index());
    if !allowed.types.contains(&acc.data_type()) || !allowed.dims.contains(&acc.dimensions()) {
        return Err(cx.err(format!(
            "{name}: {:?} {:?} is not allowed (glTF allows {:?} of {:?})",
            acc.dimensions(),
            acc.data_type(),
            allowed.dims,
            allowed.types
        )));
    }
    if acc.sparse().is_some() {
        return Err(cx.err(format!(
            "{name}: sparse accessors are not supported (not yet implemented)"
        )));
    }
    if acc.count() == 0 {
        return Err(cx.err(format!("{name}: count is 0 (glTF requires at least 1)")));
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

/// Checks the accessors of every attribute [`read_primitive`] reads (`TANGENT` only with
/// `want_tangents`).
fn check_attributes(
    cx: &Ctx,
    prim: &gltf::Primitive,
    buffers: &[Vec<u8>],
    elem: &str,
    want_tangents: bool,
) -> Result<(), GltfError> {
    let pos = prim
        .get(&gltf::Semantic::Positions)
        .ok_or_else(|| cx.err(format!("{elem}: no POSITION attribute")))?;
    check_accessor(cx, &pos, buffers, ("POSITION", &POSITION), elem)?;
    let optional = [
        (gltf::Semantic::Normals, "NORMAL", &NORMAL),
        (gltf::Semantic::TexCoords(0), "TEXCOORD_0", &TEXCOORD),
        (gltf::Semantic::Colors(0), "COLOR_0", &COLOR),
    ];
    for (semantic, what, allowed) in optional {
        if let Some(a) = prim.get(&semantic) {
            check_accessor(cx, &a, buffers, (what, allowed), elem)?;
        }
    }
    if let Some(a) = prim.indices() {
        check_accessor(cx, &a, buffers, ("indices", &INDICES), elem)?;
    }
    if let Some(a) = prim
        .get(&gltf::Semantic::Tangents)
        .filter(|_| want_tangents)
    {
        check_accessor(cx, &a, buffers, ("TANGENT", &TANGENT), elem)?;
    }
    Ok(())
}

/// The data of a buffer, by the buffer.
type GetBuffer<'s> = dyn Fn(gltf::Buffer<'_>) -> Option<&'s [u8]> + 's;

/// The reader of a primitive's (checked) attributes.
type Reader<'a, 's, 'f> = gltf::mesh::Reader<'a, 's, &'f GetBuffer<'s>>;

/// Positions, normals, uvs, indices and `COLOR_0` (as the mesh attribute `vertex_color`) of a
/// triangle primitive, in world space. With `want_tangents` (a normal-mapped material) also
/// the tangents: `TANGENT` (xyz by the node's matrix, w negated when it mirrors), or generated
/// from the uvs ([`generate_tangents`]).
pub(super) fn read_primitive(
    cx: &mut Ctx,
    prim: &gltf::Primitive,
    buffers: &[Vec<u8>],
    world: Mat4,
    elem: &str,
    want_tangents: bool,
) -> Result<TriangleMesh, GltfError> {
    check_attributes(cx, prim, buffers, elem, want_tangents)?;
    let get: &GetBuffer = &|b| buffers.get(b.index()).map(|v| v.as_slice());
    let reader: Reader = prim.reader(get);
    let flip = Mat3::from_mat4(world).determinant() < 0.0;
    let positions = read_positions(cx, &reader, world, elem)?;
    let n = positions.len();
    let normals = read_normals(cx, &reader, world, n, elem)?;
    let uvs = read_uvs(cx, &reader, n, elem)?;
    let indices = read_indices(cx, &reader, n, flip, elem)?;
    let attributes = read_colors(cx, &reader, n, elem)?.into_iter().collect();
    let mut mesh = TriangleMesh {
        positions,
        normals,
        uvs,
        tangents: None,
        indices,
        attributes,
    };
    if want_tangents {
        let given = prim.get(&gltf::Semantic::Tangents).is_some();
        mesh.tangents = read_tangents(cx, &reader, given, world, &mesh, elem)?;
    }
    Ok(mesh)
}

/// `POSITION` in world space (finite).
fn read_positions(
    cx: &Ctx,
    reader: &Reader,
    world: Mat4,
    elem: &str,
) -> Result<Vec<Vec3>, GltfError> {
    let positions: Vec<Vec3> = reader
        .read_positions()
        .ok_or_else(|| cx.err(format!("{elem}: POSITION cannot be read")))?
        .map(|p| world.transform_point3(Vec3::from(p)))
        .collect();
    if positions.iter().any(|p| !p.is_finite()) {
        return Err(cx.err(format!("{elem}: non-finite vertex position")));
    }
    Ok(positions)
}

/// `NORMAL` in world space (by the inverse transpose), unit length; `None` without it, or when
/// a normal is zero or non-finite (which would poison shading: face normals are used instead).
fn read_normals(
    cx: &Ctx,
    reader: &Reader,
    world: Mat4,
    n: usize,
    elem: &str,
) -> Result<Option<Vec<Vec3>>, GltfError> {
    let Some(it) = reader.read_normals() else {
        return Ok(None);
    };
    let normal_m = Mat3::from_mat4(world).inverse().transpose();
    let v: Vec<Vec3> = it
        .map(|nn| (normal_m * Vec3::from(nn)).normalize_or_zero())
        .collect();
    if v.len() != n {
        return Err(cx.err(format!("{elem}: {} normals for {n} positions", v.len())));
    }
    Ok(v.iter()
        .all(|x| x.is_finite() && *x != Vec3::ZERO)
        .then_some(v))
}

/// `TEXCOORD_0` as floats (normalized integers divided out).
fn read_uvs(
    cx: &Ctx,
    reader: &Reader,
    n: usize,
    elem: &str,
) -> Result<Option<Vec<Vec2>>, GltfError> {
    let Some(it) = reader.read_tex_coords(0) else {
        return Ok(None);
    };
    let v: Vec<Vec2> = it.into_f32().map(Vec2::from).collect();
    if v.len() != n {
        return Err(cx.err(format!(
            "{elem}: {} texture coordinates for {n} positions",
            v.len()
        )));
    }
    Ok(Some(v))
}

/// The triangles (`0, 1, 2, ...` without indices), in range, with the winding reversed when
/// `flip` (a mirroring node) so that the front side stays with the normals.
fn read_indices(
    cx: &Ctx,
    reader: &Reader,
    n: usize,
    flip: bool,
    elem: &str,
) -> Result<Vec<[u32; 3]>, GltfError> {
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
    Ok(flat
        .chunks_exact(3)
        .map(|t| {
            if flip {
                [t[0], t[2], t[1]]
            } else {
                [t[0], t[1], t[2]]
            }
        })
        .collect())
}

/// `COLOR_0` as the mesh attribute `vertex_color`: linear RGB (glTF stores vertex colours
/// linearly; normalized integers divided out), alpha dropped.
fn read_colors(
    cx: &Ctx,
    reader: &Reader,
    n: usize,
    elem: &str,
) -> Result<Option<MeshAttribute>, GltfError> {
    let Some(it) = reader.read_colors(0) else {
        return Ok(None);
    };
    let values: Vec<f32> = it.into_rgb_f32().flatten().collect();
    if values.len() != 3 * n {
        return Err(cx.err(format!(
            "{elem}: {} colours (COLOR_0) for {n} positions",
            values.len() / 3
        )));
    }
    if values.iter().any(|c| !c.is_finite()) {
        return Err(cx.err(format!("{elem}: non-finite vertex colour (COLOR_0)")));
    }
    Ok(Some(MeshAttribute {
        name: VERTEX_COLOR.into(),
        kind: AttributeKind::Vertex,
        dims: 3,
        values,
    }))
}

/// Tangents of a normal-mapped mesh: `TANGENT` when `given` (xyz by the node's matrix, w
/// negated when the node mirrors), else generated from the uvs; `None` with a warning when
/// there are neither.
fn read_tangents(
    cx: &mut Ctx,
    reader: &Reader,
    given: bool,
    world: Mat4,
    mesh: &TriangleMesh,
    elem: &str,
) -> Result<Option<Vec<Vec4>>, GltfError> {
    let n = mesh.positions.len();
    let m3 = Mat3::from_mat4(world);
    let flip = m3.determinant() < 0.0;
    if let Some(it) = reader.read_tangents().filter(|_| given) {
        let v: Vec<Vec4> = it
            .map(|t| {
                let w = if (t[3] < 0.0) != flip { -1.0 } else { 1.0 };
                (m3 * Vec3::new(t[0], t[1], t[2])).extend(w)
            })
            .collect();
        if v.len() != n {
            return Err(cx.err(format!("{elem}: {} tangents for {n} positions", v.len())));
        }
        if v.iter().all(|t| t.is_finite()) {
            return Ok(Some(v));
        }
    }
    match &mesh.uvs {
        Some(uv) => Ok(Some(generate_tangents(
            &mesh.positions,
            mesh.normals.as_deref(),
            uv,
            &mesh.indices,
        ))),
        None => {
            cx.warnings.push(format!("{elem}: normal map without TEXCOORD_0 or TANGENT: no tangent space, normal map ignored"));
            Ok(None)
        }
    }
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
        // (`area > 0` is false for NaN too.)
        if det == 0.0 || area.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
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

/// The meshes as one (for [`super::load_mesh`]): normals, uvs and each mesh attribute kept when
/// every mesh has them (an attribute: the same name, kind and size); tangents dropped.
pub(super) fn merge(meshes: &[&TriangleMesh]) -> TriangleMesh {
    let mut out = TriangleMesh::default();
    let all_normals = meshes.iter().all(|m| m.normals.is_some());
    let all_uvs = meshes.iter().all(|m| m.uvs.is_some());
    let (mut normals, mut uvs) = (Vec::new(), Vec::new());
    if let Some(first) = meshes.first() {
        out.attributes = first
            .attributes
            .iter()
            .filter(|a| {
                meshes.iter().all(|m| {
                    m.attributes
                        .iter()
                        .any(|b| b.name == a.name && b.kind == a.kind && b.dims == a.dims)
                })
            })
            .map(|a| MeshAttribute {
                values: Vec::new(),
                ..a.clone()
            })
            .collect();
    }
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
        for a in &mut out.attributes {
            if let Some(b) = m.attributes.iter().find(|b| b.name == a.name) {
                a.values.extend_from_slice(&b.values);
            }
        }
    }
    out.normals = all_normals.then_some(normals);
    out.uvs = all_uvs.then_some(uvs);
    out
}
