//! Texturable parameters: a constant or a texture, as Mitsuba 3 declares them
//! (`|spectrum| or |texture|`, `|float| or |texture|`).
//!
//! A [`TextureDesc`] says *what* a parameter is; the renderer decides *how* it is read from
//! the role of the parameter (a bounded reflectance, an unbounded quantity such as a
//! conductor's `eta`, an emission, or a scalar such as a roughness).

use super::{SourceLoc, SpectrumDesc};
use std::path::PathBuf;
use std::sync::Arc;

/// A texturable parameter.
#[derive(Clone, PartialEq)]
pub enum TextureDesc {
    /// The same value at every point: `<rgb>`, `<float>` or `<spectrum>` (Mitsuba's `srgb`,
    /// `uniform` and spectrum plugins).
    Constant(SpectrumDesc),
    /// An image looked up at the hit's texture coordinates (Mitsuba `bitmap`).
    Bitmap(Arc<BitmapDesc>),
    /// Two alternating values (Mitsuba `checkerboard`).
    Checkerboard(Box<CheckerboardDesc>),
    /// A value stored with the mesh (Mitsuba `mesh_attribute`).
    MeshAttribute(MeshAttributeDesc),
    /// A value used exactly as given in every colour mode, without RGB-to-spectrum conversion
    /// (Mitsuba `rawconstant`): one number, or three (RGB mode only).
    RawConstant(RawConstant),
    /// `scale * inner + offset`, with one channel of `inner` selected first if `channel` is
    /// given (the channel's value then stands in all three). Not a Mitsuba plugin: glTF
    /// defines its parameters as factors times texels (`baseColorFactor` times
    /// `baseColorTexture`, roughness from the green channel, ...), which the glTF reader writes
    /// this way.
    Scaled(Box<ScaledTexture>),
}

impl TextureDesc {
    /// A constant number.
    pub fn constant(v: f32) -> Self {
        TextureDesc::Constant(SpectrumDesc::Constant(v))
    }

    /// The constant it is, if it does not vary over the surface.
    pub fn as_constant(&self) -> Option<&SpectrumDesc> {
        match self {
            TextureDesc::Constant(s) => Some(s),
            _ => None,
        }
    }

    /// Every spectrum it holds (constants, checkerboard colours), for range checks and for
    /// deciding whether a scene needs spectral transport.
    pub fn spectra(&self) -> Vec<&SpectrumDesc> {
        match self {
            TextureDesc::Constant(s) => vec![s],
            TextureDesc::Checkerboard(c) => {
                let mut v = c.color0.spectra();
                v.extend(c.color1.spectra());
                v
            }
            TextureDesc::Scaled(s) => s.inner.spectra(),
            TextureDesc::Bitmap(_)
            | TextureDesc::MeshAttribute(_)
            | TextureDesc::RawConstant(_) => Vec::new(),
        }
    }

    /// Whether it varies over the surface (anything but a constant).
    pub fn is_textured(&self) -> bool {
        !matches!(self, TextureDesc::Constant(_) | TextureDesc::RawConstant(_))
    }

    /// A short description for `pt info`: the constant, or the texture's plugin and file.
    pub fn describe(&self) -> String {
        match self {
            TextureDesc::Constant(s) => format!("{s:?}"),
            TextureDesc::Bitmap(b) => {
                let mut opts = Vec::new();
                if b.raw {
                    opts.push("raw".to_string());
                }
                if b.filter != BitmapFilter::Bilinear {
                    opts.push(format!("{:?}", b.filter).to_lowercase());
                }
                if b.wrap != WrapMode::Repeat {
                    opts.push(format!("{:?}", b.wrap).to_lowercase());
                }
                if b.to_uv != UV_IDENTITY {
                    opts.push(format!("to_uv {:?}", b.to_uv));
                }
                let opts: String = opts.iter().map(|o| format!(", {o}")).collect();
                format!("bitmap({}{opts})", b.source.short_name())
            }
            TextureDesc::Checkerboard(c) => format!(
                "checkerboard({} | {})",
                c.color0.describe(),
                c.color1.describe()
            ),
            TextureDesc::MeshAttribute(m) => format!("mesh_attribute({} x {})", m.name, m.scale),
            TextureDesc::RawConstant(r) => format!("rawconstant({:?})", r.value),
            TextureDesc::Scaled(s) => {
                let ch = s.channel.map(|c| format!(".{c:?}")).unwrap_or_default();
                format!("{:?} x {}{ch} + {}", s.scale, s.inner.describe(), s.offset)
            }
        }
    }
}

/// Prints [`TextureDesc::describe`] (`pt info` prints materials with `{:?}`).
impl std::fmt::Debug for TextureDesc {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.describe())
    }
}

/// `<texture type="rawconstant">`: `value`, a float or a 3-vector.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RawConstant {
    /// The value per channel (a float is stored in all three).
    pub value: [f32; 3],
    /// Whether it was given as one number (usable as a scalar and in spectral mode).
    pub scalar: bool,
}

/// `scale * channel(inner) + offset` (see [`TextureDesc::Scaled`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ScaledTexture {
    /// The texture that is scaled.
    pub inner: TextureDesc,
    /// Which channel of `inner` to read, if only one (its value stands in all three).
    pub channel: Option<TextureChannel>,
    /// Factor per channel.
    pub scale: [f32; 3],
    /// Added after scaling, to every channel.
    pub offset: f32,
}

/// How texels between texel centres are reconstructed (Mitsuba's `filter_type`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum BitmapFilter {
    /// Bilinear interpolation between the four nearest texel centres (the default).
    #[default]
    Bilinear,
    /// The texel the point falls in.
    Nearest,
}

/// How texture coordinates outside [0, 1] are mapped back (Mitsuba's `wrap_mode`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum WrapMode {
    /// The image tiles the plane (the default).
    #[default]
    Repeat,
    /// Every other tile is mirrored (period two images, edge texels repeated).
    Mirror,
    /// The edge texels extend outwards.
    Clamp,
}

/// An affine map of texture coordinates, rows `[a, b, c, d, e, f]`: `u' = a u + b v + c`,
/// `v' = d u + e v + f` (Mitsuba's `to_uv`, glTF's KHR_texture_transform).
pub type UvTransform = [f32; 6];

/// The identity [`UvTransform`].
pub const UV_IDENTITY: UvTransform = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0];

/// A `<texture type="bitmap">` (or a glTF texture): an image looked up at the hit's texture
/// coordinates. Row 0 of the image (its top row) is at v = 0; texel centres are at
/// `((i + 0.5) / width, (j + 0.5) / height)`.
#[derive(Clone, Debug, PartialEq)]
pub struct BitmapDesc {
    /// Where it was defined.
    pub loc: SourceLoc,
    /// The image: a file (PNG, JPEG, BMP, TGA, EXR, HDR/RGBE) or embedded bytes.
    pub source: ImageSource,
    /// Use the stored values as they are (Mitsuba's `raw`): otherwise 8- and 16-bit images are
    /// sRGB-decoded to linear values, and, in spectral mode, colour images are upsampled to
    /// spectra. EXR and HDR images are linear either way.
    pub raw: bool,
    /// Reconstruction between texels.
    pub filter: BitmapFilter,
    /// Wrapping outside [0, 1].
    pub wrap: WrapMode,
    /// Applied to the hit's texture coordinates before the lookup.
    pub to_uv: UvTransform,
}

/// `<texture type="checkerboard">`: `color0` where the fractional parts of u and v are both at
/// most 1/2 or both above it, `color1` elsewhere (Mitsuba's `eval`; its scalar `eval_1`
/// swaps the two, which the renderer reproduces for scalar parameters).
#[derive(Clone, Debug, PartialEq)]
pub struct CheckerboardDesc {
    /// Where it was defined.
    pub loc: SourceLoc,
    /// The first value (Mitsuba default 0.4).
    pub color0: TextureDesc,
    /// The second value (Mitsuba default 0.2).
    pub color1: TextureDesc,
    /// Applied to the hit's texture coordinates first.
    pub to_uv: UvTransform,
}

/// `<texture type="mesh_attribute">`: the value of a mesh attribute at the hit.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshAttributeDesc {
    /// Where it was defined.
    pub loc: SourceLoc,
    /// The attribute's name, starting with `vertex_` (interpolated over each triangle) or
    /// `face_` (constant per triangle), e.g. `vertex_color`.
    pub name: String,
    /// Multiplies the value.
    pub scale: f32,
}

/// Which value of a texel a scalar reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TextureChannel {
    /// Red.
    Red,
    /// Green.
    Green,
    /// Blue.
    Blue,
    /// The alpha channel, stored linearly (1 where the image has none). Mitsuba's bitmap
    /// drops alpha; glTF stores opacity there.
    Alpha,
}

/// Image data of a texture: a file, or bytes embedded in the scene file (a glTF buffer view or
/// `data:` URI).
#[derive(Clone, PartialEq)]
pub enum ImageSource {
    /// An image file, resolved.
    File(PathBuf),
    /// Encoded image bytes (PNG or JPEG) and a name for messages.
    Embedded {
        /// Where the bytes came from, e.g. `images[0]`.
        name: String,
        /// The encoded image.
        bytes: Arc<Vec<u8>>,
    },
}

impl ImageSource {
    /// The file name (without its folder) or the embedded image's name, for messages.
    pub fn short_name(&self) -> String {
        match self {
            ImageSource::File(p) => p.file_name().map_or_else(
                || p.display().to_string(),
                |n| n.to_string_lossy().into_owned(),
            ),
            ImageSource::Embedded { name, .. } => name.clone(),
        }
    }
}

/// Names the image instead of listing its bytes (`pt info` prints materials with `{:?}`).
impl std::fmt::Debug for ImageSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ImageSource::File(p) => write!(f, "File({p:?})"),
            ImageSource::Embedded { name, bytes } => {
                write!(f, "Embedded({name}, {} bytes)", bytes.len())
            }
        }
    }
}
