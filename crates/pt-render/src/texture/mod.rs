//! Textures: the value of a texturable parameter at a point of a surface, in the scene's
//! colour mode (Mitsuba 3's `Texture::eval` and `eval_1`).
//!
//! A [`Texture`] is built once per parameter from the scene description ([`build`]) for the
//! role the parameter plays, which decides how RGB becomes a spectrum in spectral mode
//! (DESIGN.md, Colour; Jakob & Hanika 2019):
//! - a reflectance (`reflectance`, `base_color`, ...) is upsampled as a bounded reflectance;
//! - an unbounded quantity (conductor `eta`, `k`, factors) keeps its scale (`2 max(rgb)`);
//! - an emission is upsampled and multiplied by D65 (Mitsuba's `d65`);
//! - a scalar (`alpha`, `sigma`, `opacity`, `weight`, `thickness`, ...) is read with
//!   [`Texture::eval_1`]: a number is itself, an RGB colour its mean (Mitsuba's `srgb`), an RGB
//!   bitmap its Rec. 709 luminance (Mitsuba's `bitmap`);
//! - data (normal maps) are RGB triples read as they are, in either mode.
//!
//! Images are upsampled once per texel at load; at a hit the four texels' spectra are
//! evaluated at the path's wavelengths and interpolated (Mitsuba's `interpolate_spectral`),
//! so nothing is fitted per sample.

pub mod bitmap;
mod build;
pub mod spectral;

pub use bitmap::{Bitmap, Image, Lookup};
pub use build::{
    constant_spectrum, rgb_of, spectrum_for_role, AttributeSlots, Role, TextureBuilder,
};
pub use spectral::{DisplayPrimaries, SpectralBitmap};

use pt_math::Vec2;
use pt_scene::AttributeKind;
use pt_spectrum::{SampledSpectrum, SampledWavelengths, Spectrum};
use std::sync::Arc;

/// Rec. 709 luminance of linear RGB (Mitsuba's `luminance`), the scalar value of an RGB texel.
#[inline(always)]
pub fn luminance(c: [f32; 3]) -> f32 {
    0.212_671 * c[0] + 0.715_160 * c[1] + 0.072_169 * c[2]
}

/// A value that is the same everywhere, in the scene's colour mode: RGB lanes (RGB mode), or a
/// spectrum sampled at the path's wavelengths (spectral mode).
#[derive(Clone, Debug)]
pub enum ConstantSpectrum {
    /// RGB mode: the lanes R, G, B (fourth lane 0).
    Rgb(SampledSpectrum),
    /// Spectral mode: evaluated at the path's wavelengths.
    Spectrum(Spectrum),
}

impl ConstantSpectrum {
    /// The value at the path's wavelengths (RGB mode: the colour).
    #[inline(always)]
    pub fn at(&self, lambda: &SampledWavelengths) -> SampledSpectrum {
        match self {
            ConstantSpectrum::Rgb(c) => *c,
            ConstantSpectrum::Spectrum(s) => s.sample(lambda),
        }
    }

    /// Luminance Y (RGB: Rec. 709; a spectrum: its CIE Y as emitted radiance), for light power.
    pub fn luminance(&self) -> f32 {
        match self {
            ConstantSpectrum::Rgb(c) => c.luminance_rgb(),
            ConstantSpectrum::Spectrum(s) => s.emission_xyz()[1],
        }
    }
}

/// A mesh attribute as textures read it (see [`pt_scene::MeshAttribute`]).
#[derive(Clone, Debug)]
pub struct Attribute {
    /// Per vertex or per triangle.
    pub kind: AttributeKind,
    /// Values per element: 1 or 3.
    pub dims: u32,
    /// `dims` values per element.
    pub values: Vec<f32>,
    /// Spectral mode, 3 values per element: each element upsampled as a reflectance.
    pub spectra: Option<Vec<spectral::TexelSpectrum>>,
}

impl Attribute {
    /// The element indices and weights at a point: three corners with barycentric weights
    /// for vertex attributes, the triangle with weight 1 for face attributes.
    #[inline]
    fn footprint(&self, at: &TexturePoint) -> ([usize; 3], [f32; 3]) {
        match self.kind {
            AttributeKind::Vertex => (at.vertices.map(|v| v as usize), at.weights),
            AttributeKind::Face => ([at.face as usize; 3], [1.0, 0.0, 0.0]),
        }
    }

    /// The value as RGB (one value: in all three channels).
    fn rgb(&self, at: &TexturePoint) -> [f32; 3] {
        let (idx, w) = self.footprint(at);
        let d = self.dims as usize;
        let get = |e: usize, c: usize| {
            self.values
                .get(e * d + c.min(d - 1))
                .copied()
                .unwrap_or(0.0)
        };
        std::array::from_fn(|c| {
            get(idx[0], c) * w[0] + get(idx[1], c) * w[1] + get(idx[2], c) * w[2]
        })
    }

    /// The value at the path's wavelengths: spectra interpolated (spectral mode, colours) or
    /// the RGB interpolation.
    fn eval(&self, at: &TexturePoint, lambda: &SampledWavelengths) -> SampledSpectrum {
        match &self.spectra {
            Some(s) => {
                let (idx, w) = self.footprint(at);
                let get = |e: usize| s.get(e).map_or(SampledSpectrum::ZERO, |t| t.eval(lambda));
                get(idx[0]) * w[0] + get(idx[1]) * w[1] + get(idx[2]) * w[2]
            }
            None if self.dims == 1 => SampledSpectrum::splat(self.rgb(at)[0]),
            None => SampledSpectrum::from_rgb(self.rgb(at)),
        }
    }
}

/// Where a texture is evaluated: the surface's texture coordinates and, for mesh attributes,
/// the hit shape's attributes and the hit's place on its triangle.
#[derive(Clone, Copy, Debug)]
pub struct TexturePoint<'a> {
    /// Texture coordinates (Mitsuba's `si.uv`).
    pub uv: Vec2,
    /// The hit shape's attributes by slot ([`AttributeSlots`]); empty for shapes without any.
    pub attributes: &'a [Option<Attribute>],
    /// Vertex indices of the hit triangle.
    pub vertices: [u32; 3],
    /// Barycentric weights of the three vertices at the hit.
    pub weights: [f32; 3],
    /// Index of the hit triangle in its mesh.
    pub face: u32,
}

impl TexturePoint<'static> {
    /// A point known by its texture coordinates only (no mesh attributes).
    pub fn uv(uv: Vec2) -> Self {
        TexturePoint {
            uv,
            attributes: &[],
            vertices: [0; 3],
            weights: [1.0, 0.0, 0.0],
            face: 0,
        }
    }
}

/// A checkerboard of two textures (Mitsuba's `checkerboard`).
#[derive(Clone, Debug)]
pub struct Checkerboard {
    /// `color0` and `color1`.
    pub colors: [Texture; 2],
    /// Applied to the uv before the pattern (not to the colours' own lookups).
    pub to_uv: pt_scene::UvTransform,
}

impl Checkerboard {
    /// Which colour `eval` shows at `uv`: 0 where the fractional parts of u and v are both at
    /// most 1/2 or both above it (Mitsuba's `checkerboard.cpp`).
    #[inline(always)]
    fn index(&self, uv: Vec2) -> usize {
        let m = self.to_uv;
        let (u, v) = (
            m[0] * uv.x + m[1] * uv.y + m[2],
            m[3] * uv.x + m[4] * uv.y + m[5],
        );
        let (mu, mv) = (u - u.floor() > 0.5, v - v.floor() > 0.5);
        usize::from(mu != mv)
    }
}

/// A texture at a surface point, built for one role ([`Role`]).
#[derive(Clone, Debug)]
pub enum Texture {
    /// The same value everywhere; `scalar` is its scalar value (Mitsuba's `eval_1`).
    Constant {
        /// The value in the scene's colour mode.
        value: ConstantSpectrum,
        /// The value as one number.
        scalar: f32,
    },
    /// An RGB bitmap (RGB mode, scalar and data roles).
    Bitmap(Arc<Bitmap>),
    /// Spectral mode: a bitmap's upsampled texels, with the RGB bitmap for scalar reads.
    SpectralBitmap(Arc<(Bitmap, SpectralBitmap)>),
    /// Two textures in a checkerboard pattern.
    Checkerboard(Box<Checkerboard>),
    /// A mesh attribute of the hit shape, by slot, times `scale`.
    Attribute {
        /// Index into the shape's attributes ([`AttributeSlots`]).
        slot: u32,
        /// Factor.
        scale: f32,
    },
    /// Spectral mode: `inner` times a spectrum (D65 for RGB emission; DESIGN.md).
    Illuminated(Box<(Texture, Spectrum)>),
    /// Spectral mode: display primaries driven by a bitmap's linear RGB (pt extension; see
    /// [`DisplayPrimaries`]).
    Primaries(Arc<(Bitmap, DisplayPrimaries)>),
}

impl Texture {
    /// A constant colour in RGB mode (for tests and tools).
    pub fn rgb(c: [f32; 3]) -> Self {
        Texture::Constant {
            value: ConstantSpectrum::Rgb(SampledSpectrum::from_rgb(c)),
            scalar: (c[0] + c[1] + c[2]) / 3.0,
        }
    }

    /// A constant number (any mode).
    pub fn scalar(v: f32) -> Self {
        Texture::Constant {
            value: ConstantSpectrum::Spectrum(Spectrum::Constant(v)),
            scalar: v,
        }
    }

    /// The value at `at` and the path's wavelengths: RGB lanes in RGB mode, the wavelengths'
    /// values in spectral mode.
    #[inline(always)]
    pub fn eval(&self, at: &TexturePoint, lambda: &SampledWavelengths) -> SampledSpectrum {
        // Constants and checkerboards of two constants inline, so that they run compiled for
        // the render loop's instruction sets (`crate::isa`; outlined, the checkerboard's
        // `floor` was a library call: `film-tent` 0.95 of the time); the rest through a call,
        // since the recursive variants cannot inline. (Bitmaps inline too made the release
        // build take 12.7 minutes instead of 8.8, and `texture-bitmap` no faster: 1.01.)
        match self {
            Texture::Constant { value, .. } => value.at(lambda),
            Texture::Checkerboard(c) => match &c.colors[c.index(at.uv)] {
                Texture::Constant { value, .. } => value.at(lambda),
                nested => nested.eval_varying(at, lambda),
            },
            _ => self.eval_varying(at, lambda),
        }
    }

    /// [`Texture::eval`] of a texture that is not a constant.
    #[inline(never)]
    fn eval_varying(&self, at: &TexturePoint, lambda: &SampledWavelengths) -> SampledSpectrum {
        match self {
            Texture::Constant { value, .. } => value.at(lambda),
            Texture::Bitmap(b) => SampledSpectrum::from_rgb(b.eval(at.uv)),
            Texture::SpectralBitmap(b) => b.1.eval(at.uv, lambda),
            Texture::Checkerboard(c) => c.colors[c.index(at.uv)].eval(at, lambda),
            Texture::Attribute { slot, scale } => match at.attributes.get(*slot as usize) {
                Some(Some(a)) => a.eval(at, lambda) * *scale,
                _ => SampledSpectrum::ZERO,
            },
            Texture::Illuminated(b) => b.0.eval(at, lambda) * b.1.sample(lambda),
            Texture::Primaries(p) => p.1.eval(p.0.eval(at.uv), lambda),
        }
    }

    /// The value as one number (Mitsuba's `eval_1`): a constant's scalar, an RGB bitmap's
    /// luminance, a one-value attribute (three values: their luminance). A checkerboard shows
    /// its colours swapped here, as Mitsuba's `eval_1` does.
    #[inline(always)]
    pub fn eval_1(&self, at: &TexturePoint) -> f32 {
        match self {
            Texture::Constant { scalar, .. } => *scalar,
            Texture::Bitmap(b) => luminance(b.eval(at.uv)),
            Texture::SpectralBitmap(b) => luminance(b.0.eval(at.uv)),
            Texture::Checkerboard(c) => c.colors[1 - c.index(at.uv)].eval_1(at),
            Texture::Attribute { slot, scale } => match at.attributes.get(*slot as usize) {
                Some(Some(a)) if a.dims == 1 => a.rgb(at)[0] * *scale,
                Some(Some(a)) => luminance(a.rgb(at)) * *scale,
                _ => 0.0,
            },
            Texture::Illuminated(b) => b.0.eval_1(at),
            Texture::Primaries(p) => luminance(p.0.eval(at.uv)),
        }
    }

    /// The RGB value at `at` (data textures such as normal maps; RGB mode values).
    #[inline]
    pub fn eval_rgb(&self, at: &TexturePoint) -> [f32; 3] {
        match self {
            Texture::Bitmap(b) => b.eval(at.uv),
            Texture::SpectralBitmap(b) => b.0.eval(at.uv),
            Texture::Primaries(p) => p.0.eval(at.uv),
            Texture::Illuminated(b) => b.0.eval_rgb(at),
            Texture::Checkerboard(c) => c.colors[c.index(at.uv)].eval_rgb(at),
            Texture::Attribute { slot, scale } => match at.attributes.get(*slot as usize) {
                Some(Some(a)) => a.rgb(at).map(|v| v * scale),
                _ => [0.0; 3],
            },
            Texture::Constant { value, scalar } => match value {
                ConstantSpectrum::Rgb(c) => c.rgb(),
                ConstantSpectrum::Spectrum(_) => [*scalar; 3],
            },
        }
    }

    /// The value at the path's wavelengths `lambda` if it is the same everywhere.
    #[inline(always)]
    pub fn constant_at(&self, lambda: &SampledWavelengths) -> Option<SampledSpectrum> {
        match self {
            Texture::Constant { value, .. } => Some(value.at(lambda)),
            _ => None,
        }
    }

    /// The uv gradient of its scalar value at `at` (a bump map's height), for bitmaps
    /// ([`Bitmap::gradient_1`]); `None` for textures that cannot be differentiated (Mitsuba
    /// refuses those in a bump map).
    pub fn gradient_1(&self, at: &TexturePoint) -> Option<Vec2> {
        match self {
            Texture::Bitmap(b) => Some(b.gradient_1(at.uv)),
            Texture::SpectralBitmap(b) => Some(b.0.gradient_1(at.uv)),
            _ => None,
        }
    }

    /// Its resolution in texels (width, height): a bitmap's size, (1, 1) for everything
    /// else (Mitsuba's `Texture::resolution`; a projector's aspect ratio comes from it).
    pub fn resolution(&self) -> (usize, usize) {
        let of = |b: &Bitmap| (b.lookup.width, b.lookup.height);
        match self {
            Texture::Bitmap(b) => of(b),
            Texture::SpectralBitmap(b) => of(&b.0),
            Texture::Primaries(p) => of(&p.0),
            Texture::Illuminated(b) => b.0.resolution(),
            _ => (1, 1),
        }
    }

    /// Whether it is the same everywhere.
    pub fn is_constant(&self) -> bool {
        matches!(self, Texture::Constant { .. })
    }

    /// Whether it reads mesh attribute `slot` (itself or through a checkerboard's colours).
    pub fn reads_attribute(&self, slot: u32) -> bool {
        match self {
            Texture::Attribute { slot: s, .. } => *s == slot,
            Texture::Checkerboard(c) => c.colors.iter().any(|t| t.reads_attribute(slot)),
            Texture::Illuminated(b) => b.0.reads_attribute(slot),
            _ => false,
        }
    }

    /// The mean RGB over the texture's domain (bitmaps: over the texels; a checkerboard: the
    /// mean of its colours; attributes: 1), for light power and sampling weights.
    pub fn mean_rgb(&self) -> [f32; 3] {
        match self {
            Texture::Constant { value, scalar } => match value {
                ConstantSpectrum::Rgb(c) => c.rgb(),
                ConstantSpectrum::Spectrum(s) => {
                    let y = s.emission_xyz()[1];
                    if y.is_finite() {
                        [y; 3]
                    } else {
                        [*scalar; 3]
                    }
                }
            },
            Texture::Bitmap(b) => b.mean(),
            Texture::SpectralBitmap(b) => b.0.mean(),
            Texture::Primaries(p) => p.0.mean(),
            Texture::Illuminated(b) => b.0.mean_rgb(),
            Texture::Checkerboard(c) => {
                let (a, b) = (c.colors[0].mean_rgb(), c.colors[1].mean_rgb());
                std::array::from_fn(|k| 0.5 * (a[k] + b[k]))
            }
            Texture::Attribute { scale, .. } => [*scale; 3],
        }
    }
}
