//! Textures: a glTF `textureInfo` (its texture, sampler, image and KHR_texture_transform)
//! becomes a [`TextureDesc::Bitmap`]; factors times texels become [`TextureDesc::Scaled`].

use super::{mesh, Ctx, GltfError};
use crate::ir::{
    BitmapDesc, BitmapFilter, ImageSource, ScaledTexture, TextureChannel, TextureDesc, UvTransform,
    WrapMode, UV_IDENTITY,
};
use gltf::texture::WrappingMode;
use std::sync::Arc;

/// How a texture's stored values are read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Encoding {
    /// Colour (`baseColorTexture`, `emissiveTexture`): sRGB-decoded.
    Srgb,
    /// Data (metallic-roughness, normals, iridescence, alpha): as stored.
    Raw,
}

/// A texture slot the gltf crate models (`baseColorTexture`, `emissiveTexture`, ...), with
/// its KHR_texture_transform. `None` (with a warning) for texture coordinate sets other
/// than 0. `what` names the slot in messages and in the bitmap's location.
pub(super) fn texture_of(
    cx: &mut Ctx,
    info: &gltf::texture::Info,
    encoding: Encoding,
    buffers: &[Vec<u8>],
    what: &str,
) -> Result<Option<Arc<BitmapDesc>>, GltfError> {
    let mut tex_coord = info.tex_coord();
    let mut to_uv = UV_IDENTITY;
    if let Some(t) = info.texture_transform() {
        to_uv = affine(t.offset(), t.rotation(), t.scale());
        if let Some(tc) = t.tex_coord() {
            tex_coord = tc;
        }
    }
    bitmap(
        cx,
        info.texture(),
        tex_coord,
        to_uv,
        encoding,
        buffers,
        what,
    )
}

/// A material's `normalTexture` (raw data), as [`texture_of`]; the gltf crate leaves its
/// KHR_texture_transform in the raw JSON.
pub(super) fn normal_texture_of(
    cx: &mut Ctx,
    nt: &gltf::material::NormalTexture,
    buffers: &[Vec<u8>],
    what: &str,
) -> Result<Option<Arc<BitmapDesc>>, GltfError> {
    let mut tex_coord = nt.tex_coord();
    let to_uv = transform_from_json(nt.extension_value("KHR_texture_transform"), &mut tex_coord);
    let tex = nt.texture();
    bitmap(cx, tex, tex_coord, to_uv, Encoding::Raw, buffers, what)
}

/// A texture given by a raw textureInfo JSON object (`index`, `texCoord`,
/// KHR_texture_transform) of an extension the gltf crate does not model, as [`texture_of`].
pub(super) fn json_texture(
    cx: &mut Ctx,
    doc: &gltf::Document,
    info: &serde_json::Value,
    encoding: Encoding,
    buffers: &[Vec<u8>],
    what: &str,
) -> Result<Option<Arc<BitmapDesc>>, GltfError> {
    let index = info
        .get("index")
        .and_then(|v| v.as_u64())
        .ok_or_else(|| cx.err(format!("{what}: textureInfo without an index")))?;
    let tex = usize::try_from(index)
        .ok()
        .and_then(|i| doc.textures().nth(i))
        .ok_or_else(|| {
            cx.err(format!(
                "{what}: textures[{index}] does not exist ({} textures)",
                doc.textures().len()
            ))
        })?;
    let tex_coord = info.get("texCoord").and_then(|v| v.as_u64()).unwrap_or(0);
    let mut tex_coord = u32::try_from(tex_coord).unwrap_or(u32::MAX);
    let to_uv = transform_from_json(
        info.get("extensions")
            .and_then(|e| e.get("KHR_texture_transform")),
        &mut tex_coord,
    );
    bitmap(cx, tex, tex_coord, to_uv, encoding, buffers, what)
}

/// KHR_texture_transform as a uv map: `uv' = T R S uv` (the extension's GLSL, column-major
/// mat3s), i.e. `u' = sx u cos(r) - sy v sin(r) + ox`, `v' = sx u sin(r) + sy v cos(r) + oy`.
fn affine([ox, oy]: [f32; 2], rotation: f32, [sx, sy]: [f32; 2]) -> UvTransform {
    let (sin, cos) = rotation.sin_cos();
    [sx * cos, -sy * sin, ox, sx * sin, sy * cos, oy]
}

/// KHR_texture_transform read from its raw JSON object (for texture slots the gltf crate does
/// not model), as [`affine`]; its `texCoord` overrides `tex_coord`.
fn transform_from_json(ext: Option<&serde_json::Value>, tex_coord: &mut u32) -> UvTransform {
    let Some(t) = ext else {
        return UV_IDENTITY;
    };
    let pair = |k: &str, d: f32| {
        t.get(k).and_then(|v| v.as_array()).map_or([d, d], |a| {
            [0, 1].map(|i| a.get(i).and_then(|x| x.as_f64()).map_or(d, |x| x as f32))
        })
    };
    if let Some(tc) = t.get("texCoord").and_then(|v| v.as_u64()) {
        *tex_coord = u32::try_from(tc).unwrap_or(u32::MAX);
    }
    affine(
        pair("offset", 0.0),
        ext_f32(Some(t), "rotation", 0.0),
        pair("scale", 1.0),
    )
}

/// A number from an extension's JSON object, or its default.
pub(super) fn ext_f32(v: Option<&serde_json::Value>, key: &str, default: f32) -> f32 {
    v.and_then(|o| o.get(key))
        .and_then(|x| x.as_f64())
        .map_or(default, |x| x as f32)
}

/// The bitmap of a texture: its image, the sampler's filter and wrapping, the uv map.
fn bitmap(
    cx: &mut Ctx,
    tex: gltf::Texture,
    tex_coord: u32,
    to_uv: UvTransform,
    encoding: Encoding,
    buffers: &[Vec<u8>],
    what: &str,
) -> Result<Option<Arc<BitmapDesc>>, GltfError> {
    let elem = format!("{what} (textures[{}])", tex.index());
    if tex_coord != 0 {
        cx.warnings.push(format!("{elem}: texture coordinate set {tex_coord} is not read (only TEXCOORD_0): texture ignored"));
        return Ok(None);
    }
    let sampler = tex.sampler();
    let wrap = wrap_mode(cx, &sampler, &elem);
    let filter = match sampler.mag_filter() {
        Some(gltf::texture::MagFilter::Nearest) => BitmapFilter::Nearest,
        _ => BitmapFilter::Bilinear,
    };
    let source = image_source(cx, tex.source(), buffers)?;
    Ok(Some(Arc::new(BitmapDesc {
        loc: cx.loc(elem),
        source,
        raw: encoding == Encoding::Raw,
        filter,
        wrap,
        to_uv,
    })))
}

/// glTF's name of a wrapping mode.
fn gl_name(m: WrappingMode) -> &'static str {
    match m {
        WrappingMode::ClampToEdge => "CLAMP_TO_EDGE",
        WrappingMode::MirroredRepeat => "MIRRORED_REPEAT",
        WrappingMode::Repeat => "REPEAT",
    }
}

/// The sampler's wrapping: `wrapS`, with a warning when `wrapT` differs (a bitmap wraps both
/// axes alike).
fn wrap_mode(cx: &mut Ctx, sampler: &gltf::texture::Sampler, elem: &str) -> WrapMode {
    let (s, t) = (sampler.wrap_s(), sampler.wrap_t());
    if s != t {
        cx.warnings.push(format!(
            "{elem}: wrapS {} and wrapT {} differ (not yet implemented): both axes use {}",
            gl_name(s),
            gl_name(t),
            gl_name(s)
        ));
    }
    match s {
        WrappingMode::ClampToEdge => WrapMode::Clamp,
        WrappingMode::MirroredRepeat => WrapMode::Mirror,
        WrappingMode::Repeat => WrapMode::Repeat,
    }
}

/// Checks what the gltf crate's `Image::source` unwraps: every image has a `uri` or a
/// `bufferView`, and one in a buffer view its `mimeType`.
pub(super) fn check_images(cx: &Ctx, root: &gltf::json::Root) -> Result<(), GltfError> {
    for (i, img) in root.images.iter().enumerate() {
        if img.buffer_view.is_none() && img.uri.is_none() {
            return Err(cx.err(format!("images[{i}]: needs a uri or a bufferView")));
        }
        if img.buffer_view.is_some() && img.mime_type.is_none() {
            return Err(cx.err(format!(
                "images[{i}]: an image in a bufferView needs a mimeType"
            )));
        }
    }
    Ok(())
}

/// The encoded image: bytes of a buffer view or a `data:` URI (embedded), or a file beside the
/// glTF. Each image is read once per file and shared by the textures that use it.
fn image_source(
    cx: &mut Ctx,
    img: gltf::Image,
    buffers: &[Vec<u8>],
) -> Result<ImageSource, GltfError> {
    if let Some(s) = cx.images.get(&img.index()) {
        return Ok(s.clone());
    }
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
            let bytes = Arc::new(buf[view.offset()..end].to_vec());
            ImageSource::Embedded { name, bytes }
        }
        gltf::image::Source::Uri { uri, .. } => match mesh::data_uri(cx, uri, &name) {
            Some(bytes) => ImageSource::Embedded {
                name,
                bytes: Arc::new(bytes?),
            },
            None => ImageSource::File(cx.dir().join(uri)),
        },
    };
    cx.images.insert(img.index(), source.clone());
    Ok(source)
}

/// `scale * channel(inner) + offset` (see [`TextureDesc::Scaled`]).
pub(super) fn scaled(
    inner: TextureDesc,
    channel: Option<TextureChannel>,
    scale: [f32; 3],
    offset: f32,
) -> TextureDesc {
    TextureDesc::Scaled(Box::new(ScaledTexture {
        inner,
        channel,
        scale,
        offset,
    }))
}

/// The same bitmap read as data (raw): for the alpha channel of an sRGB colour texture.
pub(super) fn as_raw(b: &Arc<BitmapDesc>) -> Arc<BitmapDesc> {
    Arc::new(BitmapDesc {
        raw: true,
        ..(**b).clone()
    })
}

/// How a bitmap is read, for `pt info`: `sRGB-decoded bilinear, wrap Repeat` and the uv map
/// if it is not the identity.
pub(super) fn describe(b: &BitmapDesc) -> String {
    let transform = if b.to_uv != UV_IDENTITY {
        format!(", KHR_texture_transform {:?}", b.to_uv)
    } else {
        String::new()
    };
    format!(
        "{} {}, wrap {:?}{transform}",
        if b.raw { "linear" } else { "sRGB-decoded" },
        match b.filter {
            BitmapFilter::Nearest => "nearest",
            BitmapFilter::Bilinear => "bilinear",
        },
        b.wrap
    )
}
